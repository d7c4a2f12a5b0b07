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

use super::gather::{Gatherer, ShadingPoint, WorkState};
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
        let mut plane = vec![0.0; n * n];
        for j in 0..n {
            for i in 0..n {
                let (x0, x1, y0, y1) = (edge(i), edge(i + 1), edge(j), edge(j + 1));
                plane[j * n + i] = g(x1, y1) - g(x0, y1) - g(x1, y0) + g(x0, y0);
            }
        }
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
            border[pixel(v) * n + pixel(u)] += 0.5 * cos2 * dphi;
        }
        // The exact total outside the frustum.
        let outside = PI * (1.0 - coverage(s));
        let sum: f64 = border.iter().sum();
        if sum > 0.0 {
            border.iter_mut().for_each(|w| *w *= outside / sum);
        }
        HemispherePlane {
            pixels,
            half_size,
            plane,
            border,
        }
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

    /// The radiance through each pixel's centre above `sp`, one ray each through the
    /// gatherer's light (what a rasteriser would write), for a record at bounce `level`.
    pub fn sample(
        &self,
        g: &Gatherer,
        st: &mut WorkState,
        sp: &ShadingPoint,
        level: u32,
        key: u64,
    ) -> Vec<Rgb> {
        self.sample_with(g.seed, sp, level, key, |_, d, key, rng| {
            st.counts.gather_rays += 1;
            match g
                .light
                .incident(g.cache, g.seed, st, sp, d, level, key, rng)
            {
                Some(inc) => inc.radiance,
                None => g.light.escaped(d),
            }
        })
    }

    /// The radiance `radiance(pixel, d, key, rng)` gives for each pixel above `sp` (row-major;
    /// black below the geometric surface), `d` the world direction through the pixel's centre,
    /// `key` the pixel's key in the record's streams and `rng` the record's stream: the one
    /// pixel loop of [`HemispherePlane::sample`] and of a rasteriser's plane, so both draw the
    /// same random numbers.
    pub fn sample_with(
        &self,
        seed: u64,
        sp: &ShadingPoint,
        level: u32,
        key: u64,
        mut radiance: impl FnMut(usize, Vec3, u64, &mut Rng) -> Rgb,
    ) -> Vec<Rgb> {
        let frame = Frame::from_z(sp.n);
        let mut rng = Rng::keyed(seed, &[0x0070_6c61_6e65, key, u64::from(level)]);
        let n = self.pixels;
        let mut out = vec![Rgb::ZERO; n * n];
        for j in 0..n {
            for i in 0..n {
                let d = frame.from_local(self.direction(i, j));
                if d.dot(sp.it.ng) * sp.n.dot(sp.it.ng).signum() <= 0.0 {
                    continue; // below the geometric surface
                }
                let k = j * n + i;
                out[k] = radiance(k, d, super::gather::mix(key, k as u64), &mut rng);
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
}
