//! Radiance's `BSDF` material with Klems matrices ([`ircache_scene::klems`]): a tabulated BSDF,
//! constant over each pair of incident and outgoing patches, on both sides of a thin surface,
//! plus the Lambertian reflection and transmission the material adds.
//!
//! As Radiance's `m_bsdf.c` calls the BSDF library, the direction towards the viewer (`wo`) is
//! the matrix's *incident* direction and the one towards the light (`wi`) its *outgoing* one
//! (reverse ray tracing; the two agree for reciprocal data), and a direction pair no matrix
//! holds on its side is looked up with the roles swapped (`bsdf_m.c`'s reciprocity fallback).
//! The matrices are not split into a diffuse minimum and the rest as `bsdf_m.c` does for its
//! ambient calculation: the sum is the same function.
//!
//! Radiance fuzzes the cells: before each lookup it moves the view direction by a random offset
//! in a square of side √Ω in the local x, y plane (Ω the projected solid angle of the smallest
//! patch holding the view direction in the file's bases) (`m_bsdf.c`'s `bsdf_jitter`, at the default `-ss 1`), so what it renders is the
//! matrix averaged over that square. Here the average is taken over a fixed 4 × 4 grid of
//! offsets, in evaluation, density and sampling alike (a grid point chosen first).
//!
//! The azimuth is measured from `up × n` (`bsdf.c`'s `SDcompXform`): [`Klems::axis`] holds that
//! axis in the local shading frame, set per hit by [`crate::bsdf::Material::at_hit`].
//!
//! Sampling is exact in luminance: a part (either matrix of `wo`'s side, or a Lambertian term)
//! by its share of the directional albedo `A(wo)`, a patch by `f · Ω` along the matrix's row
//! (`make_cdist`), a direction uniform in projected solid angle over the patch (`fo_getvec`);
//! the density is `Y(f(wo, wi)) |cos θᵢ| / A(wo)`.

use super::BsdfSample;
use ircache_math::{sampling, Rgb, Vec2, Vec3};
use ircache_scene::klems::{matrix_entry, KlemsBsdf, KlemsComponent, KlemsMatrix};
use std::collections::HashMap;
use std::f32::consts::FRAC_1_PI;
use std::sync::{Arc, Mutex, OnceLock};

/// Cumulative `Y(f) · Ω` along each row of a matrix, for sampling.
struct Rows {
    /// Entries per row.
    width: usize,
    /// Running sums, row after row.
    cumulative: Vec<f32>,
}

impl Rows {
    fn new(rows: usize, width: usize, weight: impl Fn(usize, usize) -> f32) -> Rows {
        let mut cumulative = Vec::with_capacity(rows * width);
        for r in 0..rows {
            let mut sum = 0.0f32;
            for c in 0..width {
                sum += weight(r, c).max(0.0);
                cumulative.push(sum);
            }
        }
        Rows { width, cumulative }
    }

    fn row(&self, r: usize) -> &[f32] {
        &self.cumulative[r * self.width..(r + 1) * self.width]
    }

    fn total(&self, r: usize) -> f32 {
        self.cumulative[(r + 1) * self.width - 1]
    }
}

/// One component's sampling tables: along incident patches (each row over the outgoing
/// patches) and, for the reciprocity fallback, along outgoing patches.
struct ComponentTables {
    forward: Rows,
    reverse: Rows,
}

/// A Klems BSDF with its sampling tables, interned for the process's lifetime (one per file
/// read), so that the `Copy` [`Klems`] lobe can refer to it.
pub struct KlemsTables {
    /// The matrices.
    pub data: Arc<KlemsBsdf>,
    components: [Option<ComponentTables>; 4],
    /// The distinct bases of the matrices (the view direction's patches are looked up in each).
    bases: Vec<Arc<ircache_scene::klems::AngleBasis>>,
}

/// Offsets on a side of the grid the view direction is averaged over.
const JITTER_GRID: usize = 4;

impl std::fmt::Debug for KlemsTables {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "KlemsTables({})", self.data.source.display())
    }
}

impl KlemsTables {
    /// The tables of `data`, built once per distinct matrix set. The entry keeps `data` alive,
    /// so its address cannot be taken by another.
    #[must_use]
    pub fn interned(data: &Arc<KlemsBsdf>) -> &'static KlemsTables {
        static CACHE: OnceLock<Mutex<HashMap<usize, &'static KlemsTables>>> = OnceLock::new();
        let key = Arc::as_ptr(data) as usize;
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        if let Some(t) = cache.lock().ok().and_then(|c| c.get(&key).copied()) {
            return t;
        }
        let t: &'static KlemsTables = Box::leak(Box::new(Self::new(data.clone())));
        match cache.lock() {
            Ok(mut c) => c.entry(key).or_insert(t),
            Err(_) => t,
        }
    }

    fn new(data: Arc<KlemsBsdf>) -> KlemsTables {
        let tables = |m: &KlemsMatrix| {
            let (ni, no) = (m.incident.len(), m.outgoing.len());
            ComponentTables {
                forward: Rows::new(ni, no, |i, o| {
                    m.value(o, i).luminance() * m.outgoing.projected_solid_angle(o)
                }),
                reverse: Rows::new(no, ni, |o, i| {
                    m.value(o, i).luminance() * m.incident.projected_solid_angle(i)
                }),
            }
        };
        let components = KlemsComponent::ALL.map(|c| data.component(c).map(tables));
        let mut bases: Vec<Arc<ircache_scene::klems::AngleBasis>> = Vec::new();
        for m in KlemsComponent::ALL
            .iter()
            .filter_map(|&c| data.component(c))
        {
            for b in [&m.incident, &m.outgoing] {
                if !bases.iter().any(|x| x == b) {
                    bases.push(b.clone());
                }
            }
        }
        KlemsTables {
            data,
            components,
            bases,
        }
    }
}

/// The Klems BSDF at one hit.
#[derive(Clone, Copy, Debug)]
pub struct Klems {
    /// The matrices and their tables.
    pub tables: &'static KlemsTables,
    /// The matrices' x axis in the local shading frame, as (cos, sin) of its angle from the
    /// frame's first tangent.
    pub axis: [f32; 2],
    /// Lambertian reflectance added on the front.
    pub reflect_front: Rgb,
    /// Lambertian reflectance added on the back.
    pub reflect_back: Rgb,
    /// Lambertian transmittance added both ways.
    pub transmit: Rgb,
}

impl PartialEq for Klems {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self.tables, other.tables)
            && self.axis == other.axis
            && self.reflect_front == other.reflect_front
            && self.reflect_back == other.reflect_back
            && self.transmit == other.transmit
    }
}

/// A part of the BSDF seen from one side: a matrix row, or a Lambertian term.
enum Part<'a> {
    Row {
        component: KlemsComponent,
        matrix: &'a KlemsMatrix,
        rows: &'a Rows,
        row: usize,
        /// Whether the row runs over incident patches (the reciprocity fallback).
        reverse: bool,
    },
    Lambertian {
        albedo: Rgb,
        /// Whether light comes from the side `wo` is on.
        reflect: bool,
    },
}

impl Part<'_> {
    fn albedo(&self) -> f32 {
        match self {
            Part::Row { rows, row, .. } => rows.total(*row),
            Part::Lambertian { albedo, .. } => albedo.luminance().max(0.0),
        }
    }
}

impl Klems {
    /// `v` (local frame) in the matrices' frame.
    #[inline]
    fn in_matrix_frame(&self, v: Vec3) -> Vec3 {
        let [c, s] = self.axis;
        Vec3::new(v.x * c + v.y * s, v.y * c - v.x * s, v.z)
    }

    #[inline]
    fn in_local_frame(&self, v: Vec3) -> Vec3 {
        let [c, s] = self.axis;
        Vec3::new(v.x * c - v.y * s, v.x * s + v.y * c, v.z)
    }

    /// `f(wo, wi)` in the matrices' frame, without the cosine.
    fn value(&self, a: Vec3, b: Vec3) -> Rgb {
        if a.z == 0.0 || b.z == 0.0 {
            return Rgb::ZERO;
        }
        let (in_front, out_front) = (a.z > 0.0, b.z > 0.0);
        let lambertian = match (in_front, out_front) {
            (true, true) => self.reflect_front,
            (false, false) => self.reflect_back,
            _ => self.transmit,
        } * FRAC_1_PI;
        let tabulated = self
            .tables
            .data
            .component_for(in_front, out_front)
            .and_then(|(c, m)| matrix_entry(c, m, a, b).map(|(o, i)| m.value(o, i)))
            .unwrap_or(Rgb::ZERO);
        tabulated + lambertian
    }

    /// Side of the jitter square for the view direction `a` (`m_bsdf.c`'s `sr_vpsa[0]`): √Ω of
    /// the smallest patch holding it (a patch's size depends on its ring alone, so the side
    /// `a` is on does not matter).
    fn jitter(&self, a: Vec3) -> f32 {
        let up = Vec3::new(a.x, a.y, a.z.abs());
        self.tables
            .bases
            .iter()
            .filter_map(|b| b.patch(up).map(|p| b.projected_solid_angle(p)))
            .fold(f32::INFINITY, f32::min)
            .sqrt()
    }

    /// The view direction `a` (matrices' frame) moved to grid point `k` of a jitter square of
    /// side `side`.
    #[inline]
    fn jittered(a: Vec3, side: f32, k: usize) -> Vec3 {
        if !side.is_finite() {
            return a;
        }
        let step = side / JITTER_GRID as f32;
        let offset = |i: usize| side * 0.5 - (i as f32 + 0.5) * step;
        let (i, j) = (k % JITTER_GRID, k / JITTER_GRID);
        Vec3::new(a.x + offset(i), a.y + offset(j), a.z).normalize()
    }

    /// The BSDF averaged over the jitter grid, `f(wo, wi)` without the cosine.
    fn blurred(&self, a: Vec3, b: Vec3) -> Rgb {
        let (n, side) = (JITTER_GRID * JITTER_GRID, self.jitter(a));
        let mut sum = Rgb::ZERO;
        for k in 0..n {
            sum += self.value(Self::jittered(a, side, k), b);
        }
        sum / n as f32
    }

    /// `f(wo, wi) · |cos θᵢ|` (local frame).
    #[must_use]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let (a, b) = (self.in_matrix_frame(wo), self.in_matrix_frame(wi));
        if a.z == 0.0 || b.z == 0.0 {
            return Rgb::ZERO;
        }
        self.blurred(a, b) * b.z.abs()
    }

    /// The parts seen from `a` (matrices' frame): the two matrix rows and two Lambertian terms.
    fn parts(&self, a: Vec3) -> [Option<Part<'_>>; 4] {
        let front = a.z > 0.0;
        let row = |out_front: bool| -> Option<Part<'_>> {
            let (component, matrix) = self.tables.data.component_for(front, out_front)?;
            let tables = self.tables.components[component as usize].as_ref()?;
            let (map_in, map_out) = component.maps();
            if let Some(row) = matrix.incident.patch(map_in.apply(a)) {
                return Some(Part::Row {
                    component,
                    matrix,
                    rows: &tables.forward,
                    row,
                    reverse: false,
                });
            }
            let row = matrix.outgoing.patch(map_out.apply(a))?;
            Some(Part::Row {
                component,
                matrix,
                rows: &tables.reverse,
                row,
                reverse: true,
            })
        };
        [
            row(front),
            row(!front),
            Some(Part::Lambertian {
                albedo: if front {
                    self.reflect_front
                } else {
                    self.reflect_back
                },
                reflect: true,
            }),
            Some(Part::Lambertian {
                albedo: self.transmit,
                reflect: false,
            }),
        ]
    }

    /// The directional albedo in luminance, `A(wo)`, in the matrices' frame.
    fn albedo(&self, a: Vec3) -> f32 {
        self.parts(a).iter().flatten().map(Part::albedo).sum()
    }

    /// Solid-angle density of [`Self::sample`]: the mean over the jitter grid of
    /// `Y(f(a_k, wi)) |cos θᵢ| / A(a_k)`.
    #[must_use]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (a, b) = (self.in_matrix_frame(wo), self.in_matrix_frame(wi));
        if a.z == 0.0 || b.z == 0.0 {
            return 0.0;
        }
        self.blurred_and_density(a, b).1
    }

    /// The BSDF averaged over the jitter grid (as [`Self::blurred`]) and the sampling density
    /// of `b` (`Y(f(a_k, b)) |cos θᵢ| / A(a_k)` averaged), from one pass over the grid.
    fn blurred_and_density(&self, a: Vec3, b: Vec3) -> (Rgb, f32) {
        let (n, side) = (JITTER_GRID * JITTER_GRID, self.jitter(a));
        let (mut sum, mut density) = (Rgb::ZERO, 0.0);
        for k in 0..n {
            let ak = Self::jittered(a, side, k);
            let v = self.value(ak, b);
            sum += v;
            let total = self.albedo(ak);
            if total > 0.0 {
                density += v.luminance().max(0.0) / total;
            }
        }
        (sum / n as f32, density * b.z.abs() / n as f32)
    }

    /// Samples `wi`: a grid point, then a part by its albedo (`u_lobe`, remapped for each
    /// choice), then a patch along the part's row, then a direction in the patch by `u`.
    #[must_use]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let a = self.in_matrix_frame(wo);
        if a.z == 0.0 {
            return None;
        }
        let n = JITTER_GRID * JITTER_GRID;
        let scaled = u_lobe * n as f32;
        let k = (scaled as usize).min(n - 1);
        let u_lobe = scaled - k as f32;
        let ak = Self::jittered(a, self.jitter(a), k);
        let parts = self.parts(ak);
        let total: f32 = parts.iter().flatten().map(Part::albedo).sum();
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let mut target = u_lobe * total;
        let mut chosen = None;
        for part in parts.iter().flatten() {
            let w = part.albedo();
            if w > 0.0 {
                chosen = Some(part);
                if target < w {
                    break;
                }
                target -= w;
            }
        }
        let b = match chosen? {
            Part::Row {
                component,
                matrix,
                rows,
                row,
                reverse,
            } => {
                let cumulative = rows.row(*row);
                let target = target.min(rows.total(*row));
                let k = cumulative
                    .partition_point(|&c| c <= target)
                    .min(cumulative.len() - 1);
                let (map_in, map_out) = component.maps();
                let uv = [u.x, u.y];
                if *reverse {
                    map_in.apply(matrix.incident.direction(k, uv))
                } else {
                    map_out.apply(matrix.outgoing.direction(k, uv))
                }
            }
            Part::Lambertian { reflect, .. } => {
                let d = sampling::square_to_cosine_hemisphere(u);
                let up = (a.z > 0.0) == *reflect;
                Vec3::new(d.x, d.y, if up { d.z } else { -d.z })
            }
        };
        if b.z == 0.0 {
            return None;
        }
        let wi = self.in_local_frame(b);
        let (f, pdf) = self.blurred_and_density(a, b);
        let eval = f * b.z.abs();
        BsdfSample::smooth(wi, pdf, || eval, 1.0)
    }

    /// Samples the direction a photon arriving from `wl` (local frame, towards where it came
    /// from) leaves in: the matrices are not reciprocal, so the photon's new direction is the
    /// BSDF's *view* direction and `wl` its light direction, weight `f(wo, wl) |cos θₒ| / pdf`.
    /// The direction is cosine-distributed on the side `u_lobe` picks (either with probability
    /// ½): plain, unbiased, and only used by the photon passes.
    #[must_use]
    pub fn sample_adjoint(&self, wl: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let b = self.in_matrix_frame(wl);
        if b.z == 0.0 {
            return None;
        }
        let d = sampling::square_to_cosine_hemisphere(u);
        let same_side = u_lobe < 0.5;
        let a = Vec3::new(d.x, d.y, if same_side == (b.z > 0.0) { d.z } else { -d.z });
        if a.z == 0.0 {
            return None;
        }
        let pdf = 0.5 * a.z.abs() * FRAC_1_PI;
        let eval = self.blurred(a, b) * a.z.abs();
        BsdfSample::smooth(self.in_local_frame(a), pdf, || eval, 1.0)
    }

    /// True when light passes through (a transmission matrix or a Lambertian transmittance).
    #[must_use]
    pub fn transmits(&self) -> bool {
        let data = &self.tables.data;
        data.component(KlemsComponent::TransmitFront).is_some()
            || data.component(KlemsComponent::TransmitBack).is_some()
            || !self.transmit.is_black()
    }
}
