//! Volumetric records: the in-scattered indirect light of a medium cached at points inside it
//! (NOTES-002 §2.8, stage 2; 002 itself caches nothing in the medium and cites JDZJ08 for it).
//!
//! A record at x holds the indirect radiance arriving there, L_ind(x, ω) (everything but the
//! emitters seen directly, which the pixel pass samples), projected onto real spherical
//! harmonics of bands 0–2 (nine coefficients a colour) by a stratified gather over the sphere
//! whose paths are `volpath`'s own. The phase function's in-scattering then follows by
//! Funk–Hecke: with Henyey–Greenstein's Legendre coefficients gˡ, the light scattered towards a
//! camera ray travelling along d is Σ_lm gˡ L_lm Y_lm(d) (isotropic: the l = 0 term alone).
//! Bands above 2 are not small where the light arrives from a narrow region (a spot's beam in
//! the fog) and the phase function is forward (Henyey–Greenstein's series Σ gˡ (2l + 1) P_l
//! converges slowly: at g = 0.5 bands 0–2 hold 0.625 of its forward peak): in open fog at g = 0.5
//! the bands alone read 19 % low beside the beam and 7 % high elsewhere (at g = 0.8 negative).
//! So a record also holds what they miss towards the camera ray that placed it (d₀: the light
//! scattered towards it, from half the paths stratified over the sphere and half in the phase
//! function's lobe about d₀ by the balance heuristic, less the bands' value), added to lookups
//! from directions near d₀ (the camera's rays through a record's neighbourhood arrive from about
//! there; the share fades out by 30° away).
//!
//! A record also holds bands 0–2 of its light one and two bounces shorter, the light of its
//! paths with one or two vertices fewer allowed (each path's last two vertices' parts kept
//! apart: [`VolPathIntegrator::trace`]): a point on a surface record's gather ray is one vertex
//! deeper than the camera ray's points, so that is what it receives
//! ([`VolumeCache::in_scattered_shorter`], [`crate::media_cache::scene_medium`]), and so is fog
//! seen in a mirror; fog seen through a glass sphere is two deeper
//! ([`crate::integrators::media_march`]).
//!
//! Records are placed by a pre-pass along camera rays at the pixel pass's own quadrature points
//! (one row at a time, gathered in parallel, inserted in row order: the same cache at any
//! thread count), with Ward's radius R = the harmonic mean of the gather directions' reaches
//! (the first hit, or in a grid nearer, where its optical depth reaches 4: [`optical_reach`]),
//! at most the distance to the nearest point or spot light, bounded to [scene size/64, scene
//! size/4]. Records are placed where none lies within a·R
//! (ε = distance/(a·R) ≤ 1) and serve out to ε ≤ [`LOOKUP_REACH`] through a local linear fit
//! with weights 1 − ε/[`LOOKUP_REACH`] (they carry no gradients); a record serves only its own
//! medium. Bands 0–2 hold the light's direction well enough: band 3 moved the image by 0.03 % in
//! the fog box; the bias that remains is the interpolation's (BENCHMARKS.md).

use crate::integrators::media_march::{indirect_arrival, quadrature_points};
use crate::integrators::volpath::{PathState, VolPathIntegrator, SHORTER};
use crate::integrators::RayCounts;
use crate::irradiance_cache::record::{CachedRecord, ErrorMetric};
use crate::irradiance_cache::store::RecordStore;
use crate::media::tracking::first_opaque;
use crate::media::{Medium, Phase};
use crate::scene::Scene;
use ircache_math::harmonics::sh::bands_0_to_2;
use ircache_math::{Ray, Rgb, Rng, Vec2, Vec3, PI};
use rayon::prelude::*;
use std::time::Instant;

/// Coefficients a colour: bands 0, 1 and 2.
pub const COEFFICIENTS: usize = 9;

/// A record of the in-scattered indirect light at a point of a medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeRecord {
    /// Position.
    pub p: Vec3,
    /// Ward's radius (the harmonic mean of the gather directions' reaches, bounded).
    pub r: f32,
    /// The medium it lies in.
    pub medium: usize,
    /// L_ind's spherical-harmonic coefficients, index l² + l + m.
    pub radiance: [Rgb; COEFFICIENTS],
    /// The same of L_ind one and two bounces shorter: the in-scattered indirect light of a
    /// point one or two vertices deeper on a path (a surface record's gather ray, fog seen in
    /// a mirror or through glass), whose bounces are as many fewer.
    pub shorter: [[Rgb; COEFFICIENTS]; SHORTER],
    /// The direction d₀ of the camera ray that placed it (unit).
    pub towards: Vec3,
    /// The light scattered towards −d₀ that bands above 2 hold: the gather's estimate of it
    /// (both halves, balance heuristic) less the bands' value there.
    pub high_bands: Rgb,
}

impl CachedRecord for VolumeRecord {
    fn position(&self) -> Vec3 {
        self.p
    }
    fn normal(&self) -> Vec3 {
        Vec3::Z
    }
    fn radius(&self) -> f32 {
        self.r
    }
    fn set_radius(&mut self, r: f32) {
        self.r = r;
    }
}

/// The weights gˡ Y_lm(d) that turn a record's coefficients into the light scattered towards −`d`
/// (a camera ray travelling along `d`): one evaluation of the basis serves every record of a
/// lookup.
#[must_use]
pub fn scattering_weights(d: Vec3, phase: Phase) -> [f32; COEFFICIENTS] {
    let y = bands_0_to_2(d);
    let g = phase.mean_cosine();
    // Band l of index i = l² + l + m is weighted gˡ.
    let power = [1.0, g, g * g];
    std::array::from_fn(|i| power[ircache_math::harmonics::band_and_degree(i).0] * y[i])
}

/// Σ cᵢ wᵢ: coefficients turned into light by [`scattering_weights`].
fn weighed(coefficients: &[Rgb; COEFFICIENTS], weights: &[f32; COEFFICIENTS]) -> Rgb {
    let mut sum = Rgb::ZERO;
    for (&c, &w) in coefficients.iter().zip(weights) {
        sum += c * w;
    }
    sum
}

/// Directions within this angle of a record's d₀ take its high bands in full…
const HIGH_BANDS_FULL: f32 = 5.0;
/// …and none beyond this one (degrees).
const HIGH_BANDS_NONE: f32 = 30.0;

impl VolumeRecord {
    /// The light the record's medium scatters per unit scattering coefficient towards a camera
    /// ray travelling along unit `d`, with `d`'s [`scattering_weights`]: Σ_lm gˡ L_lm Y_lm(d),
    /// plus the high bands near d₀ (see the module).
    #[must_use]
    pub fn in_scattered(&self, weights: &[f32; COEFFICIENTS], d: Vec3) -> Rgb {
        let mut sum = self.bands(weights);
        let (full, none) = (
            HIGH_BANDS_FULL.to_radians().cos(),
            HIGH_BANDS_NONE.to_radians().cos(),
        );
        let share = ((d.dot(self.towards) - none) / (full - none)).clamp(0.0, 1.0);
        if share > 0.0 {
            sum += self.high_bands * share;
        }
        sum
    }

    /// Bands 0–2 alone: Σ_lm gˡ L_lm Y_lm(d).
    fn bands(&self, weights: &[f32; COEFFICIENTS]) -> Rgb {
        weighed(&self.radiance, weights)
    }
}

/// What building the records did.
#[derive(Clone, Copy, Debug, Default)]
pub struct VolumeCacheStats {
    /// Records made.
    pub records: usize,
    /// Records read from a cache file before the pre-pass.
    pub loaded: usize,
    /// Rays traced by their gathers (every kind).
    pub rays: u64,
    /// Seconds of the pre-pass.
    pub seconds: f64,
}

/// How far past the radius a·R that places records a record serves the pixel pass's lookups:
/// at 1 most lookups found one to three records (62 % of them in the fog box), too few for the
/// local linear fit, and their weighted mean showed each record's noise as a patch. Out to 1.5
/// a lookup averages more records at no cost in bias to first order (the fit): fog box relMSE_trim
/// −11 to −17 %, blurred −18 to −25 %, glass-in-fog −7 % and −16 %; the smoke plume, whose
/// records' light changes faster, within ±5 %, and 2 loses there (BENCHMARKS.md).
pub const LOOKUP_REACH: f32 = 1.5;

/// Volumetric records and their index.
#[derive(Debug)]
pub struct VolumeCache {
    store: RecordStore<VolumeRecord>,
    accuracy: f32,
    /// What building it did.
    pub stats: VolumeCacheStats,
}

/// Gathers a record at `p` in `medium` with `divisions` paths (deterministic for `key`) for a
/// camera ray along `towards`: half with directions stratified over the sphere (θ by equal
/// cos θ, φ twice as finely), which the harmonics and the radius take, half stratified in the
/// phase function's lobe about `towards`; each path `volpath`'s from depth 1, its directly seen
/// emitters left out. The light scattered towards −`towards` takes both halves, weighed by the
/// balance heuristic (so a forward phase function's lobe is sampled where it is large, and an
/// isotropic one's by every path alike).
#[must_use]
pub fn gather(
    integrator: &VolPathIntegrator,
    scene: &Scene,
    p: Vec3,
    medium: usize,
    divisions: u32,
    key: u64,
    towards: Vec3,
) -> (VolumeRecord, u64) {
    let polar = ((divisions as f32 / 4.0).sqrt().round() as u32).max(2);
    let azimuthal = 2 * polar;
    let count = polar * azimuthal;
    let sample_emitters = scene.samples_lights_in(medium);
    let phase = scene.media[medium].phase;
    let mut rays = RayCounts::default();
    // The path along `w` from `p` on stream `index`, and its first hit's distance.
    let mut path = |w: Vec3, index: u32| {
        let mut stream = Rng::keyed(key, &[u64::from(index)]);
        let ray = Ray::new(p, w);
        rays.bounce += 1;
        let hit = scene.accel.intersect(&ray);
        let t_hit = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
        let start = PathState {
            ray,
            medium: Some(medium),
            beta: Rgb::ONE,
            depth: 1,
            arrival: indirect_arrival(p, 0.25 / PI, sample_emitters),
            caustic_chain: false,
        };
        let mut rng = Rng::new(u64::from(stream.next_u32()), 0x766f_6c75);
        let l = integrator.trace(
            scene,
            start,
            Some(hit),
            false,
            &mut stream,
            &mut rng,
            &mut rays,
        );
        (l, t_hit)
    };
    let mut sum = [Rgb::ZERO; COEFFICIENTS];
    let mut shorter = [[Rgb::ZERO; COEFFICIENTS]; SHORTER];
    let mut inverse_distances = 0.0f64;
    // Σ f_p L / (n p_sphere + n f_p) over both halves: the light scattered towards −`towards`.
    let n = count as f32;
    let sphere_density = 0.25 / PI;
    let balance = |l: Rgb, w: Vec3| {
        let f = phase.eval(towards, w);
        l * (f / (n * sphere_density + n * f))
    };
    let mut scattered = Rgb::ZERO;
    let stratum = |j: u32, k: u32, u: Vec2| {
        Vec2::new(
            (j as f32 + u.x) / polar as f32,
            (k as f32 + u.y) / azimuthal as f32,
        )
    };
    for j in 0..polar {
        for k in 0..azimuthal {
            let index = j * azimuthal + k;
            let u = stratum(j, k, Rng::keyed(key, &[u64::from(index), 1]).next_2d());
            let cos = 1.0 - 2.0 * u.x;
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            let phi = 2.0 * PI * u.y;
            let w = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
            let (light, t_hit) = path(w, index);
            let l = light.all;
            let reach = optical_reach(&scene.media[medium], p, w, t_hit);
            if reach.is_finite() {
                inverse_distances += 1.0 / f64::from(reach.max(f32::MIN_POSITIVE));
            }
            let bands = bands_0_to_2(w);
            for (s, &b) in sum.iter_mut().zip(&bands) {
                *s += l * b;
            }
            for (k, coefficients) in shorter.iter_mut().enumerate() {
                let l = light.shorter(k + 1);
                for (h, &b) in coefficients.iter_mut().zip(&bands) {
                    *h += l * b;
                }
            }
            scattered += balance(l, w);
        }
    }
    for j in 0..polar {
        for k in 0..azimuthal {
            let index = count + j * azimuthal + k;
            let u = stratum(j, k, Rng::keyed(key, &[u64::from(index), 1]).next_2d());
            let (w, _) = phase.sample(towards, u);
            scattered += balance(path(w, index).0.all, w);
        }
    }
    let solid_angle = 4.0 * PI / count as f32;
    let size = 2.0 * scene.radius;
    let harmonic = if inverse_distances > 0.0 {
        (f64::from(count) / inverse_distances) as f32
    } else {
        f32::INFINITY
    };
    // The light of a point or spot lamp, scattered, changes on the scale of the distance to it,
    // which no gather hit holds (open fog).
    let lamp = scene
        .lights
        .delta_positions()
        .map(|q| (q - p).length())
        .fold(f32::INFINITY, f32::min);
    let mut record = VolumeRecord {
        p,
        r: harmonic.min(lamp).clamp(size / 64.0, size / 4.0),
        medium,
        radiance: sum.map(|s| s * solid_angle),
        shorter: shorter.map(|c| c.map(|s| s * solid_angle)),
        towards,
        high_bands: Rgb::ZERO,
    };
    record.high_bands = scattered - record.bands(&scattering_weights(towards, phase));
    (record, rays.bounce + rays.shadow + rays.gather)
}

/// Majorant optical depth at which a gather direction's reach ends (see [`optical_reach`]).
const REACH_DEPTH: f32 = 4.0;

/// How far a record's gather direction `w` from `p` reaches for Ward's radius: to its first
/// hit at `t_hit`, or, in a grid, sooner, where the optical depth of its local majorants
/// reaches [`REACH_DEPTH`]. Inside a dense plume the in-scattered light changes with the
/// density's structure within a few mean free paths, as it does near a wall (smoke box: blurred
/// relMSE_trim 3.5e-4 → 8.3e-5 with 2.0× the records; depths 2 / 3 / 6 read 7.5e-5 / 7.9e-5 /
/// 1.2e-4 with 6.1× / 2.9× / 1.4× the records). In a homogeneous medium the light varies with
/// the geometry alone, which the hits hold (its boundaries among them): the same cap raised a
/// fog four times the fog box's density by 30 % in blurred error over six seeds.
fn optical_reach(medium: &Medium, p: Vec3, w: Vec3, t_hit: f32) -> f32 {
    if medium.homogeneous {
        return t_hit;
    }
    medium
        .clip(p, w, t_hit)
        .and_then(|(a, b)| medium.majorant_depth_reached(p, w, a, b, f64::from(REACH_DEPTH)))
        .map_or(t_hit, |reach| (reach as f32).min(t_hit))
}

impl VolumeCache {
    /// An empty cache placing records `accuracy` · R apart and serving out to
    /// [`LOOKUP_REACH`] times that.
    #[must_use]
    pub fn new(scene: &Scene, accuracy: f32) -> VolumeCache {
        let min_validity = accuracy * 2.0 * scene.radius / 64.0;
        // The store's radii are the lookups' reach, so that they take its one-cell path; the
        // placement's test (ε ≤ 1) lies inside them.
        VolumeCache {
            store: RecordStore::new(
                min_validity * LOOKUP_REACH,
                accuracy * LOOKUP_REACH,
                ErrorMetric::Ward,
                false,
            ),
            accuracy,
            stats: VolumeCacheStats::default(),
        }
    }

    /// Calls `f(record, ε)` for the records of `medium` whose ε = ‖p − xᵢ‖/(a Rᵢ) ≤ `threshold`.
    fn for_each_serving(
        &self,
        p: Vec3,
        medium: usize,
        threshold: f32,
        mut f: impl FnMut(&VolumeRecord, f32),
    ) {
        self.store
            .for_each_near_within(p, threshold / LOOKUP_REACH, |id| {
                let rec = &self.store.records()[id as usize];
                if rec.medium != medium {
                    return;
                }
                let e = (p - rec.p).length() / (self.accuracy * rec.r);
                if e <= threshold {
                    f(rec, e);
                }
            });
    }

    /// True when a record of `medium` lies within a·R of `p` (the placement's test; lookups reach
    /// further).
    #[must_use]
    pub fn covers(&self, p: Vec3, medium: usize) -> bool {
        let mut found = false;
        self.for_each_serving(p, medium, 1.0, |_, _| found = true);
        found
    }

    /// The in-scattered indirect light at `p` towards a camera ray along `d` per unit
    /// scattering coefficient from the records serving it (ε ≤ [`LOOKUP_REACH`]): the value at
    /// `p` of a weighted least-squares plane through them (weights 1 − ε/[`LOOKUP_REACH`]), or
    /// their weighted mean where fewer than four span the space; `None` where none serves. No
    /// relaxed second try (a wider reach where none serves): a record
    /// stretched past its radius near a dark wall overstates the light (measured: the
    /// in-scattered light 3.7 % high with one and weighted means, 2.2–2.5 % without and with
    /// the fit), and the caller then traces a path.
    #[must_use]
    pub fn in_scattered(&self, p: Vec3, medium: usize, d: Vec3, phase: Phase) -> Option<Rgb> {
        let weights = scattering_weights(d, phase);
        self.fit(p, medium, |rec| rec.in_scattered(&weights, d))
    }

    /// The in-scattered indirect light `bounces` (1 or 2) bounces shorter
    /// ([`VolumeRecord::shorter`]) at `p` towards a ray along `d` per unit scattering
    /// coefficient, bands 0–2 alone, as [`Self::in_scattered`] reads the whole.
    #[must_use]
    pub fn in_scattered_shorter(
        &self,
        p: Vec3,
        medium: usize,
        d: Vec3,
        phase: Phase,
        bounces: usize,
    ) -> Option<Rgb> {
        let weights = scattering_weights(d, phase);
        self.fit(p, medium, |rec| {
            weighed(&rec.shorter[bounces - 1], &weights)
        })
    }

    /// The value at `p` of the weighted least-squares plane through `value` of the records of
    /// `medium` serving it (weights 1 − ε/[`LOOKUP_REACH`]), clamped at zero; `None` where none
    /// serves.
    fn fit(&self, p: Vec3, medium: usize, value: impl Fn(&VolumeRecord) -> Rgb) -> Option<Rgb> {
        let mut fit = LocalLinear::default();
        self.for_each_serving(p, medium, LOOKUP_REACH, |rec, e| {
            fit.add(rec.p - p, (1.0 - e / LOOKUP_REACH).max(1e-6), value(rec));
        });
        fit.value().map(|v| v.max(Rgb::ZERO))
    }

    /// The records.
    #[must_use]
    pub fn records(&self) -> &[VolumeRecord] {
        self.store.records()
    }

    /// Fills the cache at the quadrature points (`points` a segment, each at its stratum's
    /// middle) of camera rays through the centres of a `width` × `height` image, gathering
    /// with `divisions` paths of `integrator` (run inside a rayon pool), after the records
    /// `loaded` (from a cache file), which come first in [`Self::records`].
    #[allow(clippy::too_many_arguments)]
    #[must_use]
    pub fn build(
        integrator: &VolPathIntegrator,
        scene: &Scene,
        accuracy: f32,
        divisions: u32,
        points: u32,
        width: usize,
        height: usize,
        seed: u64,
        loaded: Vec<VolumeRecord>,
    ) -> VolumeCache {
        let start = Instant::now();
        let mut cache = VolumeCache::new(scene, accuracy);
        cache.stats.loaded = loaded.len();
        for record in loaded {
            cache.store.insert(record);
        }
        // A point closer than this to one already wanted in its row waits for that record.
        let spacing = accuracy * 2.0 * scene.radius / 64.0;
        for y in 0..height {
            let mut wanted: Vec<(u64, Vec3, usize, Vec3)> = Vec::new();
            for x in 0..width {
                let film = Vec2::new(
                    (x as f32 + 0.5) / width as f32,
                    (y as f32 + 0.5) / height as f32,
                );
                let ray = scene.camera.generate_ray(film);
                // Each record's stream: its pixel and its place among the pixel's points.
                let pixel = ((y * width + x) as u64) << 16;
                let mut index = 0u64;
                for_each_quadrature_point(scene, ray, points, |p, m| {
                    index += 1;
                    if cache.covers(p, m) {
                        return;
                    }
                    if wanted
                        .iter()
                        .any(|&(_, q, n, _)| n == m && (q - p).length() < spacing)
                    {
                        return;
                    }
                    wanted.push((pixel | index, p, m, ray.d));
                });
            }
            let made: Vec<(VolumeRecord, u64)> = wanted
                .par_iter()
                .map(|&(key, p, m, towards)| {
                    let key =
                        ircache_math::rng::mix64(seed ^ key.wrapping_mul(0x9E37_79B9_7F4A_7C15));
                    gather(integrator, scene, p, m, divisions, key, towards)
                })
                .collect();
            for (record, rays) in made {
                if cache.covers(record.p, record.medium) {
                    continue;
                }
                cache.store.insert(record);
                cache.stats.records += 1;
                cache.stats.rays += rays;
            }
        }
        cache.stats.seconds = start.elapsed().as_secs_f64();
        cache
    }
}

/// The value at the origin of a weighted least-squares plane through `(offset, weight, value)`
/// (local linear regression: no first-order bias where the records lie to one side, the
/// volumetric records having no gradients of their own), accumulated record by record; their
/// weighted mean where the offsets do not span three dimensions well.
#[derive(Clone, Copy, Debug, Default)]
struct LocalLinear {
    /// Records added.
    count: usize,
    /// Σ w v vᵀ over the design rows v = (1, offset), unscaled: its upper triangle, row by row
    /// (00, 01, 02, 03, 11, 12, 13, 22, 23, 33).
    moments: [f64; 10],
    /// Σ w v valueᵀ, a column per channel.
    values: [[f64; 4]; 3],
    /// The largest offset's length: the fit's scale.
    scale: f32,
}

impl LocalLinear {
    /// Adds a record at `offset` from the point with weight `w` and value `value`.
    #[inline]
    fn add(&mut self, offset: Vec3, w: f32, value: Rgb) {
        let (x, y, z) = (
            f64::from(offset.x),
            f64::from(offset.y),
            f64::from(offset.z),
        );
        let w = f64::from(w);
        let (wx, wy, wz) = (w * x, w * y, w * z);
        let m = &mut self.moments;
        m[0] += w;
        m[1] += wx;
        m[2] += wy;
        m[3] += wz;
        m[4] += wx * x;
        m[5] += wx * y;
        m[6] += wx * z;
        m[7] += wy * y;
        m[8] += wy * z;
        m[9] += wz * z;
        for (sum, c) in self.values.iter_mut().zip([value.r, value.g, value.b]) {
            let c = f64::from(c);
            sum[0] += w * c;
            sum[1] += wx * c;
            sum[2] += wy * c;
            sum[3] += wz * c;
        }
        self.count += 1;
        self.scale = self.scale.max(offset.length());
    }

    /// The plane's value at the point, or the weighted mean where fewer than four records span
    /// the space; `None` without records.
    fn value(&self) -> Option<Rgb> {
        if self.count == 0 {
            return None;
        }
        let m = &self.moments;
        let mean = || {
            Rgb::new(
                (self.values[0][0] / m[0]) as f32,
                (self.values[1][0] / m[0]) as f32,
                (self.values[2][0] / m[0]) as f32,
            )
        };
        if self.count < 4 {
            return Some(mean());
        }
        // In offsets over the scale (conditioning, and a scale-free singularity test): M becomes
        // S M S and each right-hand side S b with S = diag(1, 1/s, 1/s, 1/s).
        let s = 1.0 / f64::from(self.scale.max(f32::MIN_POSITIVE));
        let s2 = s * s;
        let scaled = ircache_math::DMat4::from_cols_array(&[
            m[0],
            m[1] * s,
            m[2] * s,
            m[3] * s,
            m[1] * s,
            m[4] * s2,
            m[5] * s2,
            m[6] * s2,
            m[2] * s,
            m[5] * s2,
            m[7] * s2,
            m[8] * s2,
            m[3] * s,
            m[6] * s2,
            m[8] * s2,
            m[9] * s2,
        ]);
        let det = scaled.determinant();
        if det.is_nan() || det.abs() <= 1e-6 * m[0].powi(4) {
            return Some(mean());
        }
        // The plane's value at the point: e₁ᵀ M⁻¹ b.
        let row = scaled.inverse().row(0);
        let at = |b: [f64; 4]| {
            row.dot(ircache_math::DVec4::new(b[0], b[1] * s, b[2] * s, b[3] * s)) as f32
        };
        Some(Rgb::new(
            at(self.values[0]),
            at(self.values[1]),
            at(self.values[2]),
        ))
    }
}

/// Calls `f(point, medium)` at the middle of each quadrature stratum of `ray`'s medium segments
/// (through null boundaries, up to the first opaque surface), as the pixel pass places them.
fn for_each_quadrature_point(scene: &Scene, ray: Ray, points: u32, mut f: impl FnMut(Vec3, usize)) {
    let mut visit = |o: Vec3, t_end: f32, medium: Option<usize>| {
        let Some(m) = medium else {
            return;
        };
        let segment = Ray::new(o, ray.d);
        let (quadrature, _, _) =
            quadrature_points(&scene.media[m], &segment, t_end, points, || 0.5);
        // Points where nothing scatters need no record (the march adds no in-scattering there).
        for (t, _) in quadrature {
            let p = segment.at(t);
            if !scene.media[m].at(p).sigma_s.is_black() {
                f(p, m);
            }
        }
    };
    let mut medium = scene.camera_medium;
    let mut last_origin = ray.o;
    let opaque = first_opaque(scene, ray, medium, &mut 0, |origin, it, beyond| {
        visit(origin, it.t, medium);
        medium = beyond;
        last_origin = it.p;
    });
    match opaque {
        Some(hit) => visit(hit.segment_origin, hit.it.t, hit.medium),
        None => visit(last_origin, f32::INFINITY, medium),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::phase::henyey_greenstein;
    use crate::testing::{project_scene, project_scene_desc};
    use ircache_math::harmonics::quadrature;
    use ircache_math::harmonics::sh::ShBasis;

    /// A gather direction's reach for the radius ([`optical_reach`]): the first hit in the
    /// homogeneous fog; in the smoke grid never past the hit, never short of [`REACH_DEPTH`] over
    /// the grid's largest extinction, with the density integrated up to it (fine midpoints)
    /// at most [`REACH_DEPTH`] (the majorants bound it), and from inside the plume short of
    /// the walls in some directions.
    #[test]
    fn reaches_end_at_hits_or_at_an_optical_depth_in_grids() {
        let directions = [
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(0.0, -0.6, 0.8),
        ];
        let fog = project_scene("cornell-fog", &[]);
        for w in directions {
            let p = Vec3::new(0.1, 1.0, 0.0);
            let t_hit = fog
                .accel
                .intersect(&Ray::new(p, w))
                .expect("the room is closed")
                .t;
            assert_eq!(optical_reach(&fog.media[0], p, w, t_hit), t_hit);
        }
        let smoke = project_scene("smoke-box", &[]);
        let medium = &smoke.media[0];
        let p = Vec3::new(0.1, 1.0, 0.05);
        let mut short = 0;
        for w in directions {
            let t_hit = smoke.accel.intersect(&Ray::new(p, w)).expect("closed").t;
            let reach = optical_reach(medium, p, w, t_hit);
            assert!(reach <= t_hit, "{w}: reach {reach} past the hit {t_hit}");
            assert!(
                reach >= (REACH_DEPTH / medium.majorant).min(t_hit) * (1.0 - 1e-4),
                "{w}: reach {reach} short of depth {REACH_DEPTH} at the largest extinction"
            );
            let n = 20_000;
            let depth: f32 = (0..n)
                .map(|i| {
                    let x = p + w * (reach * (i as f32 + 0.5) / n as f32);
                    let inside = medium
                        .bounds
                        .is_some_and(|(lo, hi)| x.cmpge(lo).all() && x.cmple(hi).all());
                    if inside {
                        medium.at(x).sigma_t.max_channel()
                    } else {
                        0.0
                    }
                })
                .sum::<f32>()
                * reach
                / n as f32;
            assert!(
                depth <= REACH_DEPTH * 1.01,
                "{w}: optical depth {depth} to the reach"
            );
            if reach < 0.99 * t_hit {
                short += 1;
            }
        }
        assert!(short >= 2, "only {short} reaches end in the smoke");
    }

    /// The mean of `n` phase-sampled paths' in-scattered light (green) at `at` (the pixel
    /// pass's estimator where no record serves) and its standard error.
    fn mean_of_paths(
        integrator: &VolPathIntegrator,
        scene: &Scene,
        at: &crate::integrators::media_march::MarchPoint,
        n: u32,
    ) -> (f64, f64) {
        use crate::integrators::media_march::in_scattered_by_path;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        let mut rng = Rng::new(11, 12);
        let mut rays = RayCounts::default();
        for k in 0..n {
            let at_k =
                in_scattered_by_path(integrator, scene, at, u64::from(k), &mut rng, &mut rays);
            let v = f64::from(at_k.g);
            sum += v;
            sum2 += v * v;
        }
        let mean = sum / f64::from(n);
        (
            mean,
            ((sum2 / f64::from(n) - mean * mean) / f64::from(n)).sqrt(),
        )
    }

    /// A record gathered in the fog Cornell box predicts the in-scattered indirect light at its
    /// own position: against the mean of phase-sampled paths from there (the pixel pass's
    /// estimator where no record serves), within 2 % or three standard errors (the record's,
    /// 32 768 paths, and 40 000 paths'), for camera directions along three axes.
    #[test]
    fn a_record_predicts_the_in_scattered_light_of_paths() {
        use crate::integrators::media_march::MarchPoint;
        let scene = project_scene("cornell-fog", &[("max_depth".to_string(), "3".to_string())]);
        let integrator = VolPathIntegrator::plain(3);
        let medium = 0;
        let phase = scene.media[medium].phase;
        for p in [
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(-0.7, 0.3, 0.5),
            Vec3::new(0.5, 1.7, -0.5),
        ] {
            for d in [Vec3::X, Vec3::NEG_Y, Vec3::Z] {
                let divisions = 32_768;
                let (record, _) = gather(&integrator, &scene, p, medium, divisions, 7, d);
                let predicted = record.in_scattered(&scattering_weights(d, phase), d).g;
                let at = MarchPoint {
                    p,
                    d,
                    medium,
                    depth: 0,
                };
                let n = 40_000;
                let (mean, error) = mean_of_paths(&integrator, &scene, &at, n);
                // The record's own noise at most as the paths' per path.
                let both = error * (1.0 + f64::from(n) / f64::from(divisions)).sqrt();
                assert!(
                    (f64::from(predicted) - mean).abs() < (3.0 * both).max(0.02 * mean),
                    "at {p:?} towards {d:?}: record {predicted}, paths {mean} ± {error}"
                );
            }
        }
    }

    /// In open fog (Henyey–Greenstein g = 0.5, and 0.8) beside and behind a spot light's beam, where the
    /// in-scattered indirect light arrives from a narrow region, a record gathered for a camera
    /// ray (65 536 paths) predicts the light scattered towards it within three standard errors
    /// (its own and 100 000 phase-sampled paths'; at g = 0.8 a million, within 25 %), while bands 0–2
    /// alone miss it by more than 10 % at some of these points (measured at g = 0.5 with 8192
    /// paths: −19 %, −19 %, −7 %, −6 %, −19 %, +7 %), and at g = 0.8 by more than half (beside
    /// the beam they turn negative).
    #[test]
    fn a_record_beside_a_beam_holds_the_light_bands_0_to_2_miss() {
        use crate::integrators::media_march::MarchPoint;
        // The scene's g = 0.5, and Mitsuba's default for `hg`, 0.8.
        // (tolerance floor, least miss of the bands alone somewhere): at 0.8 paths near the
        // lamp have heavy tails (single values 30 000 times the mean; 250 000 paths' means
        // spread ±8 %).
        for (g, floor, miss) in [(0.5, 0.0, 0.1), (0.8, 0.25, 0.5)] {
            let mut desc = project_scene_desc("open-fog", &[]);
            desc.media[0].phase = ircache_scene::PhaseDesc::HenyeyGreenstein { g };
            let scene = Scene::build(&desc).expect("the scene builds");
            let integrator = VolPathIntegrator::plain(5);
            let medium = 0;
            let phase = scene.media[medium].phase;
            let lamp = Vec3::new(-4.0, 5.0, 2.0);
            let axis = (Vec3::new(-3.0, 0.0, 0.0) - lamp).normalize();
            let side = axis.cross(Vec3::Z).normalize();
            let camera = Vec3::new(0.0, 2.0, 10.0);
            let mut worst_bands = 0.0f64;
            let divisions = 65_536;
            for p in [
                lamp + axis * 2.0 + side * 0.8,
                lamp + axis * 2.0 + side * 2.0,
                lamp + axis - side,
                lamp + axis * 3.0,
                lamp - axis,
                Vec3::new(-3.0, 4.0, 4.0),
            ] {
                let d = (p - camera).normalize();
                let (record, _) = gather(&integrator, &scene, p, medium, divisions, 7, d);
                let weights = scattering_weights(d, phase);
                let at = MarchPoint {
                    p,
                    d,
                    medium,
                    depth: 0,
                };
                let n: u32 = if g > 0.6 { 1_000_000 } else { 100_000 };
                let (mean, error) = mean_of_paths(&integrator, &scene, &at, n);
                let predicted = f64::from(record.in_scattered(&weights, d).g);
                // The record's own noise at most as the paths' per path (its directions stratified).
                let both = error * (1.0 + f64::from(n) / f64::from(divisions)).sqrt();
                assert!(
                    (predicted - mean).abs() < (3.0 * both).max(floor * mean),
                    "g = {g}, at {p:?}: record {predicted}, paths {mean} ± {error}"
                );
                worst_bands =
                    worst_bands.max((f64::from(record.bands(&weights).g) / mean - 1.0).abs());
            }
            assert!(
                worst_bands > miss,
                "g = {g}: bands 0–2 alone within {worst_bands}"
            );
        }
    }

    /// A record's light one and two bounces shorter ([`VolumeRecord::shorter`], from the parts
    /// of each path's light its last two vertices emit) is the light of the same paths with one
    /// or two vertices fewer allowed: records gathered on the same streams by `volpath` at
    /// `max_depth` − 1 and − 2 hold it (to rounding), in the fog box and in the smoke grid, at
    /// depths 4 and 6, where each of the last two bounces is more than 1 % of the light;
    /// unbounded paths have no last vertex. (Scenes with
    /// point or spot lights draw the last vertex's equiangular sample before the free flight
    /// that finds it, so there the two gathers' paths part.)
    #[test]
    fn a_records_short_light_is_that_of_paths_one_vertex_shorter() {
        for (name, p) in [
            ("cornell-fog", Vec3::new(0.1, 1.0, 0.0)),
            ("smoke-box", Vec3::new(0.1, 1.0, 0.05)),
        ] {
            let scene = project_scene(name, &[]);
            let band_0 = |c: &[Rgb; COEFFICIENTS]| c[0].luminance();
            for depth in [4, 6] {
                let at = |max_depth: i32| {
                    let integrator = VolPathIntegrator::plain(max_depth);
                    gather(&integrator, &scene, p, 0, 64, 0x5eed, Vec3::Z).0
                };
                let whole = at(depth);
                let scale = band_0(&whole.radiance);
                for k in 1..=SHORTER {
                    let shorter = at(depth - k as i32);
                    let ours = &whole.shorter[k - 1];
                    for (i, (a, b)) in ours.iter().zip(&shorter.radiance).enumerate() {
                        let off = (*a - *b).map(f32::abs).max_channel();
                        assert!(
                            off <= 1e-4 * scale,
                            "{name}, depth {depth} less {k}, coefficient {i}: {a:?} against {b:?}"
                        );
                    }
                }
                assert!(
                    band_0(&whole.radiance) > 1.01 * band_0(&whole.shorter[0]),
                    "{name}, depth {depth}: the last bounce holds no light"
                );
                assert!(
                    band_0(&whole.shorter[0]) > 1.01 * band_0(&whole.shorter[1]),
                    "{name}, depth {depth}: the last bounce but one holds no light"
                );
            }
            let unbounded = gather(&VolPathIntegrator::plain(-1), &scene, p, 0, 64, 7, Vec3::Z).0;
            assert_eq!(
                unbounded.shorter, [unbounded.radiance; 2],
                "{name}: unbounded"
            );
        }
    }

    /// With a global map ending the paths at their Lambertian vertices, a record's shorter
    /// light keeps its meaning: the parts of the photons of exactly the last allowed bounces are
    /// left out ([`crate::photon_map::PhotonMap::irradiance_by_last_bounces`]), so it matches
    /// records gathered at `max_depth` − 1 and − 2 with the same map within 1 % in band 0 (512
    /// paths; they part at the vertex where only the longer one may read the map, so not to
    /// rounding: one shorter read 1.000002). Taking the photons' whole light as the last
    /// vertex's read 0.70.
    #[test]
    fn a_records_short_light_with_a_global_map() {
        use crate::irradiance_cache::prepare::media_global_map;
        use crate::irradiance_cache::IcParams;
        let scene = project_scene("cornell-fog", &[]);
        let p = Vec3::new(0.1, 1.0, 0.0);
        let params = IcParams {
            bounces: 4,
            photons: Some(100_000),
            ..IcParams::default()
        };
        let map = std::sync::Arc::new(media_global_map(&scene, &params, 1).expect("a map"));
        let at = |max_depth: i32| {
            let integrator = VolPathIntegrator {
                global: Some(map.clone()),
                ..VolPathIntegrator::plain(max_depth)
            };
            gather(&integrator, &scene, p, 0, 512, 0x5eed, Vec3::Z).0
        };
        let whole = at(6);
        let band_0 = |c: &[Rgb; COEFFICIENTS]| f64::from(c[0].luminance());
        for k in 1..=SHORTER {
            let (a, b) = (
                band_0(&whole.shorter[k - 1]),
                band_0(&at(6 - k as i32).radiance),
            );
            assert!((a / b - 1.0).abs() < 0.01, "{k} shorter {a} against {b}");
        }
        let a = band_0(&whole.shorter[0]);
        assert!(
            band_0(&whole.radiance) > 1.05 * a,
            "the last bounce holds no light"
        );
    }

    /// In the smoke plume's box, most of which is empty, records sit only where the smoke
    /// scatters: the pixel pass adds no in-scattering elsewhere, so a record there is wasted
    /// (before: 15 128 records at 128², 606 after, the image unchanged in the plume).
    #[test]
    fn records_sit_only_where_the_medium_scatters() {
        let scene = project_scene("smoke-box", &[]);
        let integrator = VolPathIntegrator::plain(3);
        let cache = VolumeCache::build(&integrator, &scene, 0.3, 8, 8, 24, 24, 1, Vec::new());
        let records = cache.records();
        assert!(records.len() > 5, "{} records", records.len());
        for r in records {
            let c = scene.media[r.medium].at(r.p);
            assert!(
                !c.sigma_s.is_black(),
                "a record at {} where nothing scatters",
                r.p
            );
        }
    }

    /// The local linear fit reproduces a plane exactly from records all to one side of the
    /// point (where a weighted mean is off by the slope times their mean offset), and declines
    /// coplanar records.
    #[test]
    fn local_linear_fit_has_no_first_order_bias() {
        let plane = |o: Vec3| {
            Rgb::new(
                1.0 + 0.5 * o.x - 0.2 * o.y + 0.3 * o.z,
                2.0 + o.y,
                0.5 - 0.1 * o.z,
            )
        };
        let mut rng = Rng::new(1, 2);
        let serving: Vec<(Vec3, f32, Rgb)> = (0..7)
            .map(|_| {
                let o = Vec3::new(
                    0.1 + rng.next_f32(),
                    rng.next_f32() - 0.5,
                    rng.next_f32() - 0.5,
                );
                (o, 0.1 + rng.next_f32(), plane(o))
            })
            .collect();
        let local_linear = |serving: &[(Vec3, f32, Rgb)]| {
            let mut fit = LocalLinear::default();
            for &(o, w, v) in serving {
                fit.add(o, w, v);
            }
            fit.value().expect("records were added")
        };
        let fit = local_linear(&serving);
        let exact = plane(Vec3::ZERO);
        for c in 0..3 {
            assert!(
                (fit[c] - exact[c]).abs() < 1e-4,
                "channel {c}: {} against {}",
                fit[c],
                exact[c]
            );
        }
        let weighted_mean = |serving: &[(Vec3, f32, Rgb)]| {
            let (sum, weights) = serving
                .iter()
                .fold((Rgb::ZERO, 0.0), |(s, w), &(_, wi, v)| (s + v * wi, w + wi));
            sum / weights
        };
        let mean = weighted_mean(&serving);
        assert!(
            (mean[0] - exact[0]).abs() > 0.1,
            "the weighted mean is biased here"
        );
        // Coplanar records (and fewer than four) take the weighted mean.
        let flat: Vec<(Vec3, f32, Rgb)> = serving
            .iter()
            .map(|&(o, w, v)| (Vec3::new(o.x, o.y, 0.0), w, v))
            .collect();
        for part in [&flat[..], &serving[..3]] {
            let (fit, mean) = (local_linear(part), weighted_mean(part));
            for c in 0..3 {
                assert!(
                    (fit[c] - mean[c]).abs() < 1e-5 * mean[c].abs(),
                    "{fit:?} against {mean:?}"
                );
            }
        }
    }

    /// A record's in-scattered light equals the integral ∫ f_p(d·ω) L(ω) dω by a fine product
    /// rule, for incident light of bands 0–2 (exact there whatever g) and Henyey–Greenstein
    /// phases forward, backward and isotropic.
    #[test]
    fn in_scattering_is_the_phase_integral() {
        let light = |w: ircache_math::DVec3| {
            [
                1.0 + 0.6 * w.z + 0.3 * w.x * w.y,
                0.5 + 0.4 * w.x * w.x - 0.2 * w.y,
                0.8 - 0.3 * w.z * w.z + 0.1 * w.x,
            ]
        };
        let rule = quadrature::sphere(24);
        let bands: Vec<Vec<f64>> = (0..3)
            .map(|c| ShBasis::new(3).project(&rule, |w| light(w)[c]))
            .collect();
        let radiance: [Rgb; COEFFICIENTS] = std::array::from_fn(|i| {
            Rgb::new(bands[0][i] as f32, bands[1][i] as f32, bands[2][i] as f32)
        });
        let record = VolumeRecord {
            p: Vec3::ZERO,
            r: 1.0,
            medium: 0,
            radiance,
            towards: Vec3::X,
            high_bands: Rgb::splat(1.0),
            shorter: [[Rgb::ZERO; COEFFICIENTS]; SHORTER],
        };
        let fine = quadrature::sphere(200);
        for phase in [
            Phase::Isotropic,
            Phase::HenyeyGreenstein { g: 0.3 },
            Phase::HenyeyGreenstein { g: -0.5 },
        ] {
            for d in [
                Vec3::Z,
                Vec3::new(0.6, 0.0, -0.8),
                Vec3::new(-0.48, 0.6, 0.64),
            ] {
                // (Directions over 30° from d₀ take none of its high bands.)
                let got = record.in_scattered(&scattering_weights(d, phase), d);
                let mut exact = [0.0f64; 3];
                for (w, &weight) in fine.directions.iter().zip(&fine.weights) {
                    let f = match phase {
                        Phase::Isotropic => 0.25 / std::f64::consts::PI,
                        Phase::HenyeyGreenstein { g } => {
                            f64::from(henyey_greenstein(g, d.as_dvec3().dot(*w) as f32))
                        }
                    };
                    let l = light(*w);
                    for c in 0..3 {
                        exact[c] += weight * f * l[c];
                    }
                }
                for c in 0..3 {
                    assert!(
                        (f64::from(got[c]) - exact[c]).abs() < 2e-3 * exact[c].abs().max(0.1),
                        "{phase:?} {d:?} channel {c}: {} against {}",
                        got[c],
                        exact[c]
                    );
                }
            }
        }
    }
}
