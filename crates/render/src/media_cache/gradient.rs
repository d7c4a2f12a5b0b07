//! Surface and medium irradiance at a receiver, and their translational gradients, from one
//! stratified cosine-weighted hemisphere gather through a participating medium (002 §§3–6 with
//! the corrections of NOTES-002 §2).
//!
//! Per cell (j, k) with direction ω: the first opaque hit at distance s and the radiance L leaving
//! it; the medium between, marched in steps that integrate T_r exactly for the step's σ_t (exact
//! in homogeneous media); the source q = σ_s L_i + σ_a L_e per unit length (no cosine; the cell
//! weight A(n·ω) = π/(MN) holds it, NOTES-002 §2.2). Then
//! - E_s = A Σ T_r(s) L, E_m = A Σ ∫_0^s T_r q dt (eqs. 7, 19);
//! - ∇E_s = eq. 11 on the attenuated radiance + A Σ ∇T_r L with the hit point fixed (eqs. 17–18,
//!   the "pivot" gradient ∇τ = −ω τ/s + ∫(1 − t/s)∇σ_t dt, §2.4);
//! - ∇E_m, consistent form (§2.7): A Σ [∫(T_r ∇q + ∇T_r^{rigid} q) dt − ω T_r(s) q(s⁻) plus
//!   Σ_interfaces T_r (q₂ − q₁) n̂/(ω·n̂)], plus eq. 24 per wall (§2.5 item 3: the farther
//!   cell's medium integral between the two hit distances, at the nearer distance's rate).
//!
//! Gradients are absolute, per channel, in the receiver's tangent frame, as the cache's records
//! (ERRATA 5). Walls are the irradiance cache's own ([`wall_sum`]), so eq. 11 and eq. 24 cannot
//! drift apart.

use crate::irradiance_cache::hemisphere::{
    wall_sum, ward_heckbert_azimuthal, HemisphereSamples, LocalGradient, Stratification,
};
use ircache_math::{Vec2, Vec3};
use std::f64::consts::PI;

pub use ircache_math::DVec3;

/// Which translational gradient (the tests show each; NOTES-002 §2.7).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MediaGradient {
    /// Ward–Heckbert's walls (eq. 11) on the total cell radiance: media-blind.
    None,
    /// The absorption terms alone, pivot transmittance gradient, no walls (Jarosz et al. 2008a).
    Jdzj08,
    /// 002's Algorithm 1 read literally: walls of eqs. 11 and 24, pivot transmittance gradient
    /// along the march, no endpoint or interface terms.
    Paper,
    /// The notes' consistent form (the default).
    Corrected,
}

/// What the estimator needs of the scene along a gather ray from `o` along unit `w` (world
/// space). Sources and coefficients are per RGB channel.
pub trait GatherMedium {
    /// The first opaque surface: its distance (∞ when the ray escapes) and the radiance leaving
    /// it towards `o` (for an escaped ray, the environment's).
    fn surface(&self, o: DVec3, w: DVec3) -> (f64, [f64; 3]);
    /// Medium boundaries crossed before `t_max`: distances in increasing order with a normal of
    /// each (either orientation).
    fn boundaries(&self, o: DVec3, w: DVec3, t_max: f64) -> Vec<(f64, DVec3)>;
    /// Extinction at distance `t` along the ray (in the medium the ray is in there).
    fn sigma_t(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3];
    /// Its spatial gradient, per channel.
    fn sigma_t_gradient(&self, o: DVec3, w: DVec3, t: f64) -> [DVec3; 3];
    /// The extinction (largest channel) that sizes a march step begun at distance `t`, and the
    /// distance up to which that step may go: in a grid, where the optical depth of its local
    /// majorants from `t` reaches `budget`, so that a step begun in thin or empty smoke does
    /// not stride over a dense part and read it at one midpoint (the smoke box's ceiling read
    /// 1–4 % dark). By default σ_t at `t`, unbounded.
    fn step_extent(&self, o: DVec3, w: DVec3, t: f64, _budget: f64) -> (f64, f64) {
        let sigma = self.sigma_t(o, w, t);
        (sigma.iter().copied().fold(0.0f64, f64::max), f64::INFINITY)
    }

    /// Source per unit length at distance `t`, towards the receiver (`w` leaves it).
    fn source(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3];
    /// Its spatial gradient with `w` fixed, per channel.
    fn source_gradient(&self, o: DVec3, w: DVec3, t: f64) -> [DVec3; 3];
    /// The source of a whole march step, q̄ with q̄ ∫ T_r dt = ∫ T_r q dt over the step (T_r
    /// from its start at its extinction), an estimate where q peaks inside the step (a point
    /// light's 1/r²). By default q at the step's middle.
    fn step_source(&self, o: DVec3, w: DVec3, step: &StepExtent) -> [f64; 3] {
        self.source(o, w, step.middle())
    }
    /// Its gradient, as [`Self::source_gradient`] is `source`'s.
    fn step_source_gradient(&self, o: DVec3, w: DVec3, step: &StepExtent) -> [DVec3; 3] {
        self.source_gradient(o, w, step.middle())
    }
    /// Radiance towards `o` from the bounces beyond the ray's first vertex (a collision in the
    /// medium or the opaque hit), an unbiased estimate; `None` where the gather sees one bounce.
    /// It joins the cell's surface radiance: eq. 11's walls differentiate it as the surface's,
    /// and no transmittance gradient is taken of it.
    fn deeper(&self, _o: DVec3, _w: DVec3) -> Option<[f64; 3]> {
        None
    }
}

/// A march step `[t0, t1]` along a gather ray and its extinction (constant over it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepExtent {
    pub t0: f64,
    pub t1: f64,
    pub sigma: [f64; 3],
}

impl StepExtent {
    /// The step's middle, where its coefficients are read.
    #[must_use]
    pub fn middle(&self) -> f64 {
        0.5 * (self.t0 + self.t1)
    }

    /// The weight that turns a sample of the source at distance `t` drawn with density `pdf` on
    /// the step into an estimate of the step's source q̄ ([`GatherMedium::step_source`]):
    /// e^{−σ (t − t0)}/(pdf ∫ e^{−σ (t' − t0)} dt'), per channel.
    #[must_use]
    pub fn sample_weight(&self, t: f64, pdf: f64) -> [f64; 3] {
        let len = self.t1 - self.t0;
        std::array::from_fn(|c| {
            let integral = exp_integral(self.sigma[c], len);
            if pdf > 0.0 && integral > 0.0 {
                (-self.sigma[c] * (t - self.t0)).exp() / (pdf * integral)
            } else {
                0.0
            }
        })
    }
}

/// A march step may straddle this many optical steps of a grid's local majorants (they bound
/// σ_t loosely: sizing every step by them cost 1.6× the time for the same image).
const MAJORANT_STEPS: f64 = 3.0;

/// March settings (NOTES-002 §2.6).
#[derive(Clone, Copy, Debug)]
pub struct March {
    /// Optical depth per step (the step is at most this over σ_t).
    pub optical_step: f64,
    /// Most steps per cell ray.
    pub max_steps: usize,
    /// Transmittance below which an escaping ray stops.
    pub cutoff: f64,
    /// Compute the gradients' per-cell parts (off: irradiance only, for finite differences).
    pub gradients: bool,
}

impl Default for March {
    fn default() -> Self {
        March {
            optical_step: 0.1,
            max_steps: 256,
            cutoff: 1e-6,
            gradients: true,
        }
    }
}

/// One march step `[t0, t1]` of a cell ray: transmittance at its start, the step's extinction
/// and source (at its midpoint).
#[derive(Clone, Copy, Debug)]
struct Step {
    t0: f64,
    t1: f64,
    tr0: [f64; 3],
    sigma: [f64; 3],
    q: [f64; 3],
}

/// ∫_0^len e^{−σ t} dt.
#[inline]
fn exp_integral(sigma: f64, len: f64) -> f64 {
    if sigma * len < 1e-6 {
        len * (1.0 - 0.5 * sigma * len)
    } else {
        -(-sigma * len).exp_m1() / sigma
    }
}

impl Step {
    /// ∫_{t0}^{min(t, t1)} T_r q dt.
    fn partial(&self, t: f64) -> [f64; 3] {
        let len = (t.min(self.t1) - self.t0).max(0.0);
        std::array::from_fn(|c| self.tr0[c] * self.q[c] * exp_integral(self.sigma[c], len))
    }
}

/// What one cell's ray found.
#[derive(Clone, Debug, Default)]
struct Cell {
    /// Opaque hit distance (∞: escaped).
    s: f64,
    /// T_r(s) L.
    surface: [f64; 3],
    /// Medium radiance ∫ T_r q dt.
    medium: [f64; 3],
    steps: Vec<Step>,
    /// ∇T_r(x↔x_s) L, hit point fixed (world space).
    absorption: [DVec3; 3],
    /// ∫ (T_r ∇q + ∇T_r^{rigid} q) dt.
    interior_rigid: [DVec3; 3],
    /// ∫ (T_r ∇q + ∇T_r^{pivot} q) dt.
    interior_pivot: [DVec3; 3],
    /// −ω T_r(s) q(s⁻) for a ray ending at an opaque hit.
    radial: [DVec3; 3],
    /// Σ T_r(t_b) (q₂ − q₁) n̂/(ω·n̂).
    interfaces: [DVec3; 3],
}

impl Cell {
    /// ∫_0^t T_r q dt along this cell's ray.
    fn cumulative(&self, t: f64) -> [f64; 3] {
        let mut out = [0.0; 3];
        for st in self.steps.iter().take_while(|st| st.t0 < t) {
            let p = st.partial(t);
            for c in 0..3 {
                out[c] += p[c];
            }
        }
        out
    }
}

/// The gather's result.
#[derive(Clone, Debug)]
pub struct MediaGather {
    /// The cells.
    pub strata: Stratification,
    cells: Vec<Cell>,
    /// The receiver's tangent frame (world).
    frame: [DVec3; 3],
    /// Steps marched in all.
    pub march_steps: usize,
}

/// The parts of a translational gradient (local frame, per channel), to check each against the
/// notes' values.
#[derive(Clone, Copy, Debug, Default)]
pub struct GradientParts {
    /// Eq. 11 on the attenuated surface radiance.
    pub surface_walls: LocalGradient,
    /// A Σ ∇T_r L (eqs. 17–18, pivot).
    pub absorption: LocalGradient,
    /// Eq. 24 per wall.
    pub medium_walls: LocalGradient,
    /// A Σ ∫(T_r ∇q + ∇T_r^{rigid} q) dt.
    pub interior_rigid: LocalGradient,
    /// A Σ ∫(T_r ∇q + ∇T_r^{pivot} q) dt.
    pub interior_pivot: LocalGradient,
    /// A Σ −ω T_r(s) q(s⁻).
    pub radial: LocalGradient,
    /// A Σ interface terms.
    pub interfaces: LocalGradient,
    /// Eq. 11 on the total cell radiance (media-blind).
    pub blind_walls: LocalGradient,
}

fn add(a: LocalGradient, b: LocalGradient) -> LocalGradient {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

impl GradientParts {
    /// The translational gradient of `variant`.
    #[must_use]
    pub fn total(&self, variant: MediaGradient) -> LocalGradient {
        match variant {
            MediaGradient::None => self.blind_walls,
            MediaGradient::Jdzj08 => add(self.absorption, self.interior_pivot),
            MediaGradient::Paper => add(
                add(self.surface_walls, self.absorption),
                add(self.medium_walls, self.interior_pivot),
            ),
            MediaGradient::Corrected => add(
                add(add(self.surface_walls, self.absorption), self.medium_walls),
                add(add(self.interior_rigid, self.radial), self.interfaces),
            ),
        }
    }
}

/// Gathers at `x` with normal `frame[2]` and tangents `frame[0]`, `frame[1]` (world, unit), one
/// ray per cell at offset `jitter(j, k)` in the cell.
pub fn gather(
    scene: &dyn GatherMedium,
    x: DVec3,
    frame: [DVec3; 3],
    strata: Stratification,
    march: &March,
    mut jitter: impl FnMut(usize, usize) -> Vec2,
) -> MediaGather {
    let mut cells = Vec::with_capacity(strata.cells());
    let mut march_steps = 0;
    for j in 0..strata.polar {
        for k in 0..strata.azimuthal {
            let local = strata.direction(j, k, jitter(j, k)).as_dvec3();
            let w = (frame[0] * local.x + frame[1] * local.y + frame[2] * local.z).normalize();
            let cell = trace_cell(scene, x, w, march);
            march_steps += cell.steps.len();
            cells.push(cell);
        }
    }
    MediaGather {
        strata,
        cells,
        frame,
        march_steps,
    }
}

/// How far from a medium boundary at distance `t` along a ray from `origin` its two sides are
/// told apart: 1e-5 of the distance and the coordinates' size, some 100 single-precision ulps
/// (the scene is traced in single precision; within a few ulps of a face, rays miss it).
pub(crate) fn interface_offset(t: f64, origin: DVec3) -> f64 {
    1e-5 * (t + origin.abs().max_element()).max(f64::MIN_POSITIVE)
}

/// One cell's ray: the opaque hit, then the march through the medium up to it.
fn trace_cell(scene: &dyn GatherMedium, x: DVec3, w: DVec3, march: &March) -> Cell {
    let (s, radiance) = scene.surface(x, w);
    let mut cell = Cell {
        s,
        ..Cell::default()
    };
    let boundaries = scene.boundaries(x, w, s);
    // Running state: transmittance, optical depth, ∫∇σ dt (G0) and ∫ t ∇σ dt (G1), each with the
    // interfaces' jumps (σ₂ − σ₁) n̂/(ω·n̂) (at t_b in G1).
    let mut tr = [1.0f64; 3];
    let mut tau = [0.0f64; 3];
    let mut g0 = [DVec3::ZERO; 3];
    let mut g1 = [DVec3::ZERO; 3];
    let mut t = 0.0f64;
    let mut next_boundary = 0;
    let mut q_last = [0.0f64; 3];
    let mut steps = 0usize;
    // Segments between boundaries; the last ends at s (or where an escaping ray is dark).
    loop {
        let segment_end = boundaries.get(next_boundary).map_or(s, |b| b.0);
        while t < segment_end && steps < march.max_steps {
            let (sigma_max, extent) =
                scene.step_extent(x, w, t, MAJORANT_STEPS * march.optical_step);
            let mut dt = if sigma_max > 0.0 {
                march.optical_step / sigma_max
            } else {
                f64::INFINITY
            };
            dt = dt.min(extent - t);
            if !segment_end.is_finite() && !dt.is_finite() {
                break; // an empty medium to infinity
            }
            // Spread what is left over the steps still allowed.
            let left = march.max_steps - steps;
            if segment_end.is_finite() {
                dt = dt.min(segment_end - t).max((segment_end - t) / left as f64);
            }
            let t1 = (t + dt).min(segment_end);
            let mid = 0.5 * (t + t1);
            let sigma = scene.sigma_t(x, w, mid);
            let span = StepExtent { t0: t, t1, sigma };
            let q = scene.step_source(x, w, &span);
            let (gq, gs) = if march.gradients {
                (
                    scene.step_source_gradient(x, w, &span),
                    scene.sigma_t_gradient(x, w, mid),
                )
            } else {
                ([DVec3::ZERO; 3], [DVec3::ZERO; 3])
            };
            let step = Step {
                t0: t,
                t1,
                tr0: tr,
                sigma,
                q,
            };
            let len = t1 - t;
            let tm = 0.5 * (t + t1);
            for c in 0..3 {
                let int_tr = tr[c] * exp_integral(sigma[c], len);
                cell.medium[c] += q[c] * int_tr;
                // Running gradients at the step's midpoint.
                let g0m = g0[c] + gs[c] * (0.5 * len);
                let g1m = g1[c] + gs[c] * (0.5 * len * tm);
                let tau_m = tau[c] + sigma[c] * 0.5 * len;
                let rigid = -g0m;
                let pivot = if tm > 0.0 {
                    w * (tau_m / tm) - g0m + g1m / tm
                } else {
                    DVec3::ZERO
                };
                cell.interior_rigid[c] += (gq[c] + rigid * q[c]) * int_tr;
                cell.interior_pivot[c] += (gq[c] + pivot * q[c]) * int_tr;
                tr[c] *= (-sigma[c] * len).exp();
                tau[c] += sigma[c] * len;
                g0[c] += gs[c] * len;
                g1[c] += gs[c] * (len * tm);
            }
            q_last = q;
            cell.steps.push(step);
            steps += 1;
            t = t1;
            if !s.is_finite() && tr.iter().all(|&v| v < march.cutoff) {
                break;
            }
        }
        let Some(&(tb, n)) = boundaries.get(next_boundary) else {
            break;
        };
        if tb >= s || tb.is_nan() || steps >= march.max_steps {
            break;
        }
        // Crossing a boundary: the jumps of σ and q, just before and after it. Far enough
        // from it for the single-precision scene: a point within a few ulps of a null face
        // sends its light samples' shadow rays through the face unseen, as if the medium went
        // on to the light (the smoke box's q read a third of its value at its top face, and
        // the records' vertical gradients twice the finite differences).
        let eps = interface_offset(tb, x);
        let (before, after) = (tb - eps, tb + eps);
        let (s1, s2) = (scene.sigma_t(x, w, before), scene.sigma_t(x, w, after));
        let (q1, q2) = (scene.source(x, w, before), scene.source(x, w, after));
        let cos = w.dot(n);
        if cos.abs() > 1e-12 {
            let dir = n / cos;
            for c in 0..3 {
                cell.interfaces[c] += dir * (tr[c] * (q2[c] - q1[c]));
                g0[c] += dir * (s2[c] - s1[c]);
                g1[c] += dir * ((s2[c] - s1[c]) * tb);
            }
        }
        t = tb;
        next_boundary += 1;
    }
    if s.is_finite() {
        for c in 0..3 {
            cell.surface[c] = tr[c] * radiance[c];
            // Pivot about the fixed hit point: ∇τ = −ω τ/s + G0 − G1/s; ∇T_r = −T_r ∇τ.
            let grad_tau = -w * (tau[c] / s) + g0[c] - g1[c] / s;
            cell.absorption[c] = -grad_tau * (tr[c] * radiance[c]);
            cell.radial[c] = -w * (tr[c] * q_last[c]);
        }
    } else {
        // Escaped: the environment, attenuated (its gradient is zero: nothing moves).
        for c in 0..3 {
            cell.surface[c] = tr[c] * radiance[c];
        }
    }
    if let Some(deeper) = scene.deeper(x, w) {
        for (l, d) in cell.surface.iter_mut().zip(deeper) {
            *l += d;
        }
    }
    cell
}

impl MediaGather {
    /// Cell weight A(n·ω) = π/(MN).
    fn weight(&self) -> f64 {
        PI / self.strata.cells() as f64
    }

    /// Surface irradiance E_s (attenuated) and medium irradiance E_m.
    #[must_use]
    pub fn irradiance(&self) -> ([f64; 3], [f64; 3]) {
        let a = self.weight();
        let (mut es, mut em) = ([0.0; 3], [0.0; 3]);
        for cell in &self.cells {
            for c in 0..3 {
                es[c] += a * cell.surface[c];
                em[c] += a * cell.medium[c];
            }
        }
        (es, em)
    }

    /// The whole irradiance E = E_s + E_m.
    #[must_use]
    pub fn total_irradiance(&self) -> [f64; 3] {
        let (es, em) = self.irradiance();
        std::array::from_fn(|c| es[c] + em[c])
    }

    /// The samples as the irradiance cache keeps them: the total cell radiance L_s + L_m and
    /// the opaque hit distance (for E, R and the rotational gradient, unchanged by media: 002 §3).
    #[must_use]
    pub fn hemisphere_samples(&self) -> HemisphereSamples {
        let mut h = HemisphereSamples::new(self.strata);
        for (i, cell) in self.cells.iter().enumerate() {
            let l: [f64; 3] = std::array::from_fn(|c| cell.surface[c] + cell.medium[c]);
            h.radiance[i] = ircache_math::Rgb::new(l[0] as f32, l[1] as f32, l[2] as f32);
            h.distance[i] = cell.s as f32;
        }
        h
    }

    /// A world-space vector per channel, summed over cells by `f` and weighted by A, in the
    /// local frame.
    fn cell_sum(&self, f: impl Fn(&Cell) -> [DVec3; 3]) -> LocalGradient {
        let a = self.weight();
        let mut g = [DVec3::ZERO; 3];
        for cell in &self.cells {
            let v = f(cell);
            for c in 0..3 {
                g[c] += v[c];
            }
        }
        g.map(|v| {
            Vec3::new(
                (a * v.dot(self.frame[0])) as f32,
                (a * v.dot(self.frame[1])) as f32,
                0.0,
            )
        })
    }

    /// Every part of the translational gradient.
    #[must_use]
    pub fn gradient_parts(&self) -> GradientParts {
        let distance = |i: usize| self.cells[i].s;
        let surface_walls = wall_sum(self.strata, distance, ward_heckbert_azimuthal, |hi, lo| {
            let (a, b) = (&self.cells[hi], &self.cells[lo]);
            std::array::from_fn(|c| a.surface[c] - b.surface[c])
        });
        let blind_walls = wall_sum(self.strata, distance, ward_heckbert_azimuthal, |hi, lo| {
            let (a, b) = (&self.cells[hi], &self.cells[lo]);
            std::array::from_fn(|c| a.surface[c] + a.medium[c] - b.surface[c] - b.medium[c])
        });
        // Eq. 24 per wall: at shells between the two hit distances only the farther cell is
        // visible; V_hi − V_lo is +1 when that is the higher-index cell.
        let medium_walls = wall_sum(self.strata, distance, ward_heckbert_azimuthal, |hi, lo| {
            let (sh, sl) = (self.cells[hi].s, self.cells[lo].s);
            if sh == sl {
                return [0.0; 3];
            }
            let (near, far, sign) = if sh > sl {
                (sl, hi, 1.0)
            } else {
                (sh, lo, -1.0)
            };
            let cell = &self.cells[far];
            let upto = cell.medium;
            let before = cell.cumulative(near);
            std::array::from_fn(|c| sign * (upto[c] - before[c]))
        });
        GradientParts {
            surface_walls,
            absorption: self.cell_sum(|c| c.absorption),
            medium_walls,
            interior_rigid: self.cell_sum(|c| c.interior_rigid),
            interior_pivot: self.cell_sum(|c| c.interior_pivot),
            radial: self.cell_sum(|c| c.radial),
            interfaces: self.cell_sum(|c| c.interfaces),
            blind_walls,
        }
    }
}
