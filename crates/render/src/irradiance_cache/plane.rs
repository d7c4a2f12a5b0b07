//! Records from a rasterised plane (001 §4.4.2, Table 4.1; NOTES-001 §C.4): the GPU computes a
//! record by rasterising the scene onto an N × N plane at distance 1 above it (half-size s), one
//! radiance per pixel, and sums the pixels with weights. The plane misses the directions
//! outside its frustum, the cosine-weighted share 1 − F(s) of the hemisphere, with
//!
//! ```text
//! F(s) = (4/π) · s/√(1+s²) · atan(s/√(1+s²))          (NOTES-001 §C.4, the plane's coverage)
//! ```
//!
//! Three estimators of the irradiance E = ∫ L cos θ dω from the pixels:
//! - **plane only**: each pixel's cos θ dω, Σ = π F(s);
//! - **coverage** ([LC04]): the same divided by F(s), Σ = π;
//! - **border compensation** (the thesis's): a direction outside the frustum takes the value of
//!   the border pixel at the same azimuth, through the radial map (u, v) = (x/z, y/z)·s/max(|x/z|,
//!   |y/z|) (NOTES-001's concrete form), so each border pixel's weight grows by the cos θ dω of the
//!   directions it stands for; Σ = π exactly.
//!
//! A pixel's own cos θ dω over its square [x₀, x₁] × [y₀, y₁] of the plane is exact:
//! ∫∫ dA/(1 + x² + y²)² has the antiderivative
//! G(x, y) = x/(2√(1+x²)) · atan(y/√(1+x²)) + y/(2√(1+y²)) · atan(x/√(1+y²)).
//! The directions outside the frustum at azimuth φ all map to one border point; their
//! cos θ dω is ∫_{θₑ}^{π/2} cos θ sin θ dθ dφ = cos²θₑ/2 dφ with tan θₑ = s/max(|cos φ|, |sin φ|),
//! integrated over φ by a fine midpoint rule and scaled so that the border's total is the exact
//! π(1 − F(s)).
//!
//! Here the pixels are sampled by one ray per pixel centre through the gather's
//! [`IncidentRadiance`], to measure the estimators against the stratified gather (Table 4.1's
//! protocol, `ircache bench --only plane`); the GPU's rasteriser will fill the same pixels.
//!
//! **Gradients** (the thesis only says its records hold them; NOTES-001 §C.4). Rotational:
//! ∇ᵣE = ∫ L (n × ω) dω for any set of directions, each pixel's ∫ ω dω in closed form,
//! ∫∫ x dA/(1+x²+y²)² = −atan(y/√(1+x²))/(2√(1+x²)) over its square, the border's by the
//! azimuthal rule. Translational: Ward and Heckbert's argument (000 eqs. 3.42–3.48) on the
//! pixel grid instead of polar × azimuthal cells. Moving the point by δx (in the tangent plane)
//! moves what a direction sees by δω = −δx⊥/d, so every wall between two pixels k and l moves,
//! at the closer one's distance, and E changes by (L_k − L_l) ∫ cos θ (δω·ν) ds along it (ν the
//! wall's unit normal on the sphere, from k into l). A wall x = x₀ of the plane is a great
//! circle with ν = (1, 0, −x₀)/√(1+x₀²), along which ∫ cos θ ds = [y/(√(1+x₀²)·√(1+x₀²+y²))];
//! so it adds (L_right − L_left)/d · [y/((1+x₀²)√(1+x₀²+y²))] to ∂E/∂x, and a wall y = y₀ the
//! same with x and y exchanged. That is the gradient of the light the frustum sees: outside it
//! border compensation gives each direction its border pixel's value through a map fixed in the
//! record's frame, and letting the border pixels' change (their walls' mean term) hold over
//! those directions too, which a field linear across a ceiling needs (its outside share is
//! 1 − F(s), 17 % at s = 2; a vertical edge's 4 %), tripled the errors on real scenes, where the
//! border pixels see the nearest walls at grazing angles (`ircache bench --only plane`).

use super::gather::{Gatherer, Incident, ShadingPoint, WorkState};
use super::hemisphere::LocalGradient;
use ircache_math::{Frame, Rgb, Rng, Vec3};
use std::f64::consts::PI;

/// How the pixels of the plane are summed into irradiance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlaneEstimator {
    /// The plane's own cos θ dω: misses 1 − F(s) of the hemisphere.
    PlaneOnly,
    /// Divided by the coverage F(s) ([LC04]).
    Coverage,
    /// Border pixels stand for the directions outside the frustum at their azimuth.
    BorderCompensation,
}

/// The plane above a record: N × N pixels at distance 1, half-size s, in the record's frame
/// (z the normal), with each estimator's pixel weights.
#[derive(Clone, Debug)]
pub struct HemispherePlane {
    /// Pixels per side.
    pub pixels: usize,
    /// Half-size s of the plane at distance 1 (field of view 2 atan s).
    pub half_size: f64,
    /// Per pixel (row-major, y then x): the exact cos θ dω of its square.
    plane: Vec<f64>,
    /// Per pixel: the cos θ dω of the directions outside the frustum it stands for.
    border: Vec<f64>,
    /// Per pixel, border compensated: ∫ (ω_x, ω_y) dω over the directions it stands for (the
    /// rotational gradient's weights).
    tilt: Vec<[f64; 2]>,
    /// Per wall x = x₀ between pixels (i − 1, j) and (i, j) (index j·(N − 1) + i − 1): its
    /// weight [y/((1+x₀²)√(1+x₀²+y²))] over the wall; by symmetry the walls y = y₀ between
    /// (i, j − 1) and (i, j) (index i·(N − 1) + j − 1) take the same values.
    wall: Vec<f64>,
}

/// What a record's plane gives: the border-compensated irradiance, its gradients in world space
/// and the nearest and harmonic mean distances of the pixels' hits (infinite where none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneMeasure {
    /// Irradiance.
    pub e: Rgb,
    /// Translational gradient per channel.
    pub grad_t: [Vec3; 3],
    /// Rotational gradient per channel.
    pub grad_r: [Vec3; 3],
    /// Nearest hit.
    pub nearest: f32,
    /// Harmonic mean distance of the hits.
    pub harmonic: f32,
}

/// Planes of first-level records made elsewhere, many at a time (the GPU's rasterised planes,
/// `ircache_gpu`): `--record-source gpu-plane`.
pub trait PlaneSource: Send + Sync + std::fmt::Debug {
    /// The planes above `points`, in their order, or why they could not be made.
    ///
    /// # Errors
    /// When the device fails.
    fn measure(&self, points: &[ShadingPoint]) -> Result<Vec<PlaneMeasure>, String>;
}

/// The pixels of a plane above a record: each pixel centre's radiance and the distance to the
/// surface it sees (infinite where the ray escapes or lies below the surface, as a gather's
/// empty cells).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlanePixels {
    /// Radiance, row-major.
    pub radiance: Vec<Rgb>,
    /// Distance to the surface seen.
    pub distance: Vec<f32>,
}

/// F(s): the share of the cosine-weighted hemisphere a plane of half-size `s` at distance 1
/// covers.
#[must_use]
pub fn coverage(s: f64) -> f64 {
    let a = s / (1.0 + s * s).sqrt();
    4.0 / PI * a * a.atan()
}

/// Midpoint steps per border pixel of the azimuthal rule.
const BORDER_STEPS: usize = 64;

impl HemispherePlane {
    /// The plane of `pixels` × `pixels` at half-size `half_size`.
    ///
    /// # Panics
    /// When `pixels` is 0 or `half_size` is not positive.
    #[must_use]
    pub fn new(pixels: usize, half_size: f64) -> HemispherePlane {
        assert!(pixels > 0 && half_size > 0.0, "an empty plane");
        let (n, s) = (pixels, half_size);
        let edge = |i: usize| -s + 2.0 * s * i as f64 / n as f64;
        let g = |x: f64, y: f64| {
            let (rx, ry) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
            x / (2.0 * rx) * (y / rx).atan() + y / (2.0 * ry) * (x / ry).atan()
        };
        // ∫ ω_x dω over a square of the plane: ∫∫ x dA/(1+x²+y²)².
        let hx = |x: f64, y: f64| {
            let a = (1.0 + x * x).sqrt();
            -(y / a).atan() / (2.0 * a)
        };
        // Each pixel's square: its cos θ dω (G) and its ∫ (ω_x, ω_y) dω.
        let mut plane = vec![0.0; n * n];
        let mut tilt = vec![[0.0; 2]; n * n];
        for j in 0..n {
            for i in 0..n {
                let (x0, x1, y0, y1) = (edge(i), edge(i + 1), edge(j), edge(j + 1));
                let square =
                    |f: &dyn Fn(f64, f64) -> f64| f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0);
                plane[j * n + i] = square(&g);
                tilt[j * n + i] = [square(&hx), square(&|x, y| hx(y, x))];
            }
        }
        // The directions outside the frustum at azimuth φ (from θₑ to π/2) take the border
        // pixel the radial map sends φ to: their cos θ dω = cos²θₑ/2 dφ, and for the tilt
        // ∫ sin θ (cos φ, sin φ) sin θ dθ dφ.
        let mut border = vec![0.0; n * n];
        let steps = 4 * n * BORDER_STEPS;
        let dphi = 2.0 * PI / steps as f64;
        for k in 0..steps {
            let phi = (k as f64 + 0.5) * dphi;
            let (sin, cos) = phi.sin_cos();
            let m = cos.abs().max(sin.abs());
            let cos2 = m * m / (m * m + s * s);
            let (u, v) = (s * cos / m, s * sin / m);
            let pixel = |c: f64| (((c + s) / (2.0 * s) * n as f64) as usize).min(n - 1);
            let at = pixel(v) * n + pixel(u);
            border[at] += 0.5 * cos2 * dphi;
            let theta_e = (s / m).atan();
            let sin2 = 0.25 * PI - 0.5 * theta_e + 0.25 * (2.0 * theta_e).sin();
            tilt[at][0] += cos * sin2 * dphi;
            tilt[at][1] += sin * sin2 * dphi;
        }
        // The exact total outside the frustum.
        let outside = PI * (1.0 - coverage(s));
        let sum: f64 = border.iter().sum();
        if sum > 0.0 {
            border.iter_mut().for_each(|w| *w *= outside / sum);
        }
        // Walls x = x₀ (and by symmetry y = y₀).
        let mut wall = vec![0.0; n * n.saturating_sub(1)];
        for j in 0..n {
            for i in 1..n {
                let x0 = edge(i);
                let c = 1.0 + x0 * x0;
                let f = |y: f64| y / (c * (c + y * y).sqrt());
                wall[j * (n - 1) + i - 1] = f(edge(j + 1)) - f(edge(j));
            }
        }
        HemispherePlane {
            pixels,
            half_size,
            plane,
            border,
            tilt,
            wall,
        }
    }

    /// The translational and rotational gradients of the border-compensated irradiance (local
    /// frame, z the normal; the module's comment derives them) from the plane's `pixels`. The
    /// translational gradient is that of the light the frustum sees.
    #[must_use]
    pub fn gradients(&self, pixels: &PlanePixels) -> (LocalGradient, LocalGradient) {
        let n = self.pixels;
        let (l, d) = (&pixels.radiance, &pixels.distance);
        // Each wall once.
        let mut t = [[0.0f64; 2]; 3];
        for j in 0..n {
            for i in 1..n {
                let w = self.wall[j * (n - 1) + i - 1];
                // x = edge(i) between (i − 1, j) and (i, j); y = edge(i) between (j, i − 1)
                // and (j, i).
                let walls = [
                    (0, j * n + i - 1, j * n + i),
                    (1, (i - 1) * n + j, i * n + j),
                ];
                for (axis, from, to) in walls {
                    let closer = f64::from(d[from].min(d[to]));
                    if !(closer > 0.0 && closer.is_finite()) {
                        continue;
                    }
                    let (a, b) = (l[to], l[from]);
                    for (c, diff) in [a.r - b.r, a.g - b.g, a.b - b.b].into_iter().enumerate() {
                        t[c][axis] += f64::from(diff) * w / closer;
                    }
                }
            }
        }
        let mut r = [[0.0f64; 2]; 3];
        // ∇ᵣE = ∫ L (n × ω) dω = ∫ L (−ω_y, ω_x) dω.
        for (k, w) in self.tilt.iter().enumerate() {
            let lk = l[k];
            for (c, v) in [lk.r, lk.g, lk.b].into_iter().enumerate() {
                r[c][0] -= f64::from(v) * w[1];
                r[c][1] += f64::from(v) * w[0];
            }
        }
        let vec = |g: [[f64; 2]; 3]| g.map(|c| Vec3::new(c[0] as f32, c[1] as f32, 0.0));
        (vec(t), vec(r))
    }

    /// What `pixels`, sampled above `sp` ([`Self::sample_with`]), give a record.
    #[must_use]
    pub fn measure(&self, sp: &ShadingPoint, pixels: &PlanePixels) -> PlaneMeasure {
        let frame = Frame::from_z(sp.n);
        let (t, r) = self.gradients(pixels);
        let (mut nearest, mut inverse, mut hits) = (f32::INFINITY, 0.0f64, 0u32);
        for &d in pixels
            .distance
            .iter()
            .filter(|d| d.is_finite() && **d > 0.0)
        {
            nearest = nearest.min(d);
            inverse += 1.0 / f64::from(d);
            hits += 1;
        }
        let world = |g: &LocalGradient| super::hemisphere::to_world(g, frame.s, frame.t);
        PlaneMeasure {
            e: self.irradiance(&pixels.radiance, PlaneEstimator::BorderCompensation),
            grad_t: world(&t),
            grad_r: world(&r),
            nearest,
            harmonic: if hits > 0 {
                (f64::from(hits) / inverse) as f32
            } else {
                f32::INFINITY
            },
        }
    }

    /// Per pixel (row-major), ∫ (ω_x, ω_y) dω over the directions it stands for, border
    /// compensated: the rotational gradient's weights, for a GPU pass.
    #[must_use]
    pub fn tilt_weights(&self) -> &[[f64; 2]] {
        &self.tilt
    }

    /// Per wall, its weight in the translational gradient: the wall x = edge(i) between pixels
    /// (i − 1, j) and (i, j) at j·(N − 1) + i − 1, the wall y = edge(j) between (i, j − 1) and
    /// (i, j) at i·(N − 1) + j − 1; for a GPU pass.
    #[must_use]
    pub fn wall_weights(&self) -> &[f64] {
        &self.wall
    }

    /// The local direction (z the normal) through the centre of pixel `(i, j)`.
    #[must_use]
    pub fn direction(&self, i: usize, j: usize) -> Vec3 {
        let (n, s) = (self.pixels as f64, self.half_size);
        let x = -s + 2.0 * s * (i as f64 + 0.5) / n;
        let y = -s + 2.0 * s * (j as f64 + 0.5) / n;
        Vec3::new(x as f32, y as f32, 1.0).normalize()
    }

    /// Each pixel's weight under `estimator` (row-major): E = Σ w L.
    #[must_use]
    pub fn weights(&self, estimator: PlaneEstimator) -> Vec<f64> {
        (0..self.plane.len())
            .map(|k| self.weight(k, estimator))
            .collect()
    }

    /// Pixel `k`'s weight under `estimator`.
    #[inline]
    fn weight(&self, k: usize, estimator: PlaneEstimator) -> f64 {
        match estimator {
            PlaneEstimator::PlaneOnly => self.plane[k],
            PlaneEstimator::Coverage => self.plane[k] / coverage(self.half_size),
            PlaneEstimator::BorderCompensation => self.plane[k] + self.border[k],
        }
    }

    /// The irradiance the pixels' radiances `radiance` (row-major) give under `estimator`.
    #[must_use]
    pub fn irradiance(&self, radiance: &[Rgb], estimator: PlaneEstimator) -> Rgb {
        let mut e = [0.0f64; 3];
        for (k, l) in radiance.iter().enumerate().take(self.plane.len()) {
            let w = self.weight(k, estimator);
            e[0] += w * f64::from(l.r);
            e[1] += w * f64::from(l.g);
            e[2] += w * f64::from(l.b);
        }
        Rgb::new(e[0] as f32, e[1] as f32, e[2] as f32)
    }

    /// The radiance through each pixel's centre above `sp` and the distance to what it sees,
    /// one ray each through the gatherer's light (what a rasteriser would write), for a record
    /// at bounce `level`.
    pub fn sample(
        &self,
        g: &Gatherer,
        st: &mut WorkState,
        sp: &ShadingPoint,
        level: u32,
        key: u64,
    ) -> PlanePixels {
        self.sample_with(g.seed, sp, level, key, |_, d, key, rng| {
            st.counts.gather_rays += 1;
            let found = g
                .light
                .incident(g.cache, g.seed, st, sp, d, level, key, rng);
            match Incident::or_escaped(found, d) {
                Ok(inc) => (inc.radiance, inc.distance),
                Err((out, tau)) => (g.light.escaped(out) * tau, f32::INFINITY),
            }
        })
    }

    /// The radiance and distance `radiance(pixel, d, key, rng)` gives for each pixel above `sp`
    /// (row-major; black and infinitely far below the geometric surface), `d` the world
    /// direction through the pixel's centre in the frame [`Frame::from_z`] of `sp.n`, `key` the
    /// pixel's key in the record's streams and `rng` the record's stream: the one pixel loop of
    /// [`HemispherePlane::sample`] and of a rasteriser's plane, so both draw the same random
    /// numbers.
    pub fn sample_with(
        &self,
        seed: u64,
        sp: &ShadingPoint,
        level: u32,
        key: u64,
        mut radiance: impl FnMut(usize, Vec3, u64, &mut Rng) -> (Rgb, f32),
    ) -> PlanePixels {
        let frame = Frame::from_z(sp.n);
        let mut rng = Rng::keyed(seed, &[0x0070_6c61_6e65, key, u64::from(level)]);
        let n = self.pixels;
        let mut out = PlanePixels {
            radiance: vec![Rgb::ZERO; n * n],
            distance: vec![f32::INFINITY; n * n],
        };
        for j in 0..n {
            for i in 0..n {
                let d = frame.from_local(self.direction(i, j));
                if d.dot(sp.it.ng) * sp.n.dot(sp.it.ng).signum() <= 0.0 {
                    continue; // below the geometric surface
                }
                let k = j * n + i;
                let (l, t) = radiance(k, d, super::gather::mix(key, k as u64), &mut rng);
                out.radiance[k] = l;
                out.distance[k] = t;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// C-T4: a constant radiance of 1 gives E = π F(s) on the plane alone, π with the coverage
    /// division and π with border compensation; the plane's exact pixel weights sum to π F(s)
    /// and F(s) is NOTES-001's table.
    #[test]
    fn a_constant_radiance_gives_pi_under_each_estimator_as_the_notes_say() {
        for (s, f) in [(1.0, 0.554), (2.0, 0.831), (3.0, 0.917), (4.0, 0.951)] {
            assert!((coverage(s) - f).abs() < 5e-4, "F({s}) = {}", coverage(s));
        }
        for (n, s) in [(64, 2.0), (16, 1.0), (33, 3.5)] {
            let plane = HemispherePlane::new(n, s);
            let ones = vec![Rgb::ONE; n * n];
            let e = |est| f64::from(plane.irradiance(&ones, est).g);
            let f = coverage(s);
            assert!(
                (e(PlaneEstimator::PlaneOnly) - PI * f).abs() < 1e-5,
                "{n} {s}"
            );
            assert!((e(PlaneEstimator::Coverage) - PI).abs() < 1e-5, "{n} {s}");
            assert!(
                (e(PlaneEstimator::BorderCompensation) - PI).abs() < 1e-5,
                "{n} {s}"
            );
            // The pixel weights against a fine midpoint rule over the plane.
            let fine = 8;
            let m = n * fine;
            let mut sum = 0.0;
            for j in 0..m {
                for i in 0..m {
                    let x = -s + 2.0 * s * (i as f64 + 0.5) / m as f64;
                    let y = -s + 2.0 * s * (j as f64 + 0.5) / m as f64;
                    sum += (2.0 * s / m as f64).powi(2) / (1.0 + x * x + y * y).powi(2);
                }
            }
            assert!((sum - PI * f).abs() < 1e-4, "midpoint {sum} vs {}", PI * f);
        }
    }

    /// Border compensation is exact where the radiance depends on the azimuth alone (the
    /// directions outside the frustum at an azimuth take the border's value there, theirs up
    /// to the pixel's azimuthal width), and the closest of the three where it grows towards the
    /// horizon.
    #[test]
    fn border_compensation_is_exact_in_azimuth_and_closest_towards_the_horizon() {
        let (n, s) = (64, 2.0);
        let plane = HemispherePlane::new(n, s);
        // L = 1 + cos φ: E = ∫ (1 + cos φ) cos θ dω = π.
        let radiance: Vec<Rgb> = (0..n * n)
            .map(|k| {
                let d = plane.direction(k % n, k / n);
                let phi = d.y.atan2(d.x);
                Rgb::splat(1.0 + 0.8 * phi.cos())
            })
            .collect();
        let e = |est| f64::from(plane.irradiance(&radiance, est).g);
        let border = e(PlaneEstimator::BorderCompensation);
        assert!((border - PI).abs() < 2e-3 * PI, "border {border}");
        // L = sin²θ (brighter towards the horizon, as walls around a floor): E = π/2. The
        // border holds the most horizontal values the plane sees, the coverage division the
        // plane's mean: border compensation comes closest (Table 4.1's order).
        let walls: Vec<Rgb> = (0..n * n)
            .map(|k| {
                let d = plane.direction(k % n, k / n);
                Rgb::splat(1.0 - d.z * d.z)
            })
            .collect();
        let exact = PI / 2.0;
        let error = |est| (f64::from(plane.irradiance(&walls, est).g) - exact).abs() / exact;
        let (only, cov, bord) = (
            error(PlaneEstimator::PlaneOnly),
            error(PlaneEstimator::Coverage),
            error(PlaneEstimator::BorderCompensation),
        );
        assert!(bord < 0.5 * cov && cov < only, "{only} {cov} {bord}");
    }

    /// The pixels a field gives, `field(local direction)` = (radiance, distance).
    fn pixels_of(plane: &HemispherePlane, field: impl Fn(Vec3) -> (Rgb, f32)) -> PlanePixels {
        let n = plane.pixels;
        let mut out = PlanePixels::default();
        for k in 0..n * n {
            let (l, d) = field(plane.direction(k % n, k / n));
            out.radiance.push(l);
            out.distance.push(d);
        }
        out
    }

    /// ∇ᵣE of L = 1 + ω·b is (2π/3) n × b (∫ ω ωᵀ dω = (2π/3) I in the tangent plane); the
    /// border's directions take their pixel's value, so the plane comes within a few percent.
    #[test]
    fn rotational_gradient_of_a_linear_field_is_two_thirds_pi_n_cross_b() {
        let plane = HemispherePlane::new(64, 2.0);
        let b = Vec3::new(0.6, -0.3, 0.4);
        let pixels = pixels_of(&plane, |w| (Rgb::splat(1.0 + w.dot(b)), 1.0));
        let (_, r) = plane.gradients(&pixels);
        let exact = Vec3::Z.cross(b) * (2.0 * std::f32::consts::PI / 3.0);
        let error = (r[1] - exact).length() / exact.length();
        assert!(error < 0.05, "{:?} against {exact:?} ({error})", r[1]);
        // Without a tilt the rotational gradient vanishes by symmetry.
        let flat = pixels_of(&plane, |w| (Rgb::splat(1.0 + w.z), 1.0));
        assert!(plane.gradients(&flat).1[0].length() < 1e-5);
    }

    /// Under a ceiling at height h, the gradient of the light the frustum sees: radiance
    /// L₀ + cX linear in the ceiling's X gives ∂E/∂x = c·πF(s) (every direction's radiance grows
    /// by c); a step, L₀ where X > 0 and black beyond, gives the wall x = 0's
    /// L₀/h ∫ dy/(1+y²)² over [−s, s] = L₀ (s/(1+s²) + atan s)/h (cos θ ds/d = dy/(h(1+y²)²)).
    /// The plane's gradient meets both within its discretisation, with no component along y.
    #[test]
    fn translational_gradient_under_a_ceiling_matches_the_closed_forms() {
        let plane = HemispherePlane::new(64, 2.0);
        let (h, l0, c) = (2.0f32, 3.0f32, 0.7f32);
        // A direction (x, y, 1)/r meets the ceiling at X = h·x, distance h·r.
        let hit = |w: Vec3| (h * w.x / w.z, h / w.z);
        let linear = pixels_of(&plane, |w| {
            let (x, t) = hit(w);
            (Rgb::new(l0 + c * x, 2.0 * (l0 + c * x), 0.0), t)
        });
        let (t, _) = plane.gradients(&linear);
        let pi = std::f32::consts::PI;
        for (channel, scale) in [(0, 1.0), (1, 2.0)] {
            let g = t[channel];
            let exact = scale * pi * c * coverage(2.0) as f32;
            assert!(
                (g.x - exact).abs() < 0.02 * exact,
                "linear {g:?} against {exact}"
            );
            assert!(g.y.abs() < 1e-3 * exact, "linear {g:?}");
        }
        let step = pixels_of(&plane, |w| {
            let (x, t) = hit(w);
            (Rgb::splat(if x > 0.0 { l0 } else { 0.0 }), t)
        });
        let (t, _) = plane.gradients(&step);
        let exact = l0 * (2.0 / 5.0 + 2.0f32.atan()) / h;
        assert!(
            (t[0].x - exact).abs() < 0.04 * exact,
            "step {:?} against {exact}",
            t[0]
        );
        assert!(t[0].y.abs() < 1e-3 * exact, "step {:?}", t[0]);
        // Escaped pixels (nothing seen) move nothing.
        let open = pixels_of(&plane, |w| {
            let (x, t) = hit(w);
            if x > 0.0 {
                (Rgb::splat(l0), t)
            } else {
                (Rgb::splat(1.0), f32::INFINITY)
            }
        });
        let (t_open, _) = plane.gradients(&open);
        assert!(
            (t_open[0].x - (l0 - 1.0) / l0 * exact).abs() < 0.05 * exact,
            "{:?}",
            t_open[0]
        );
    }
}
