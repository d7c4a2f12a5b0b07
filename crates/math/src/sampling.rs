//! Sampling routines. Each warp maps `[0,1)²` to a domain and comes with its density and, where it
//! is a bijection, its inverse. Local hemisphere directions have the normal along +z.

use crate::{INV_PI, PI};
use glam::{Vec2, Vec3};

/// The largest `f32` below 1: where a sample in `[0, 1)` is built by arithmetic that can round
/// up to 1, clamping to this keeps it in its stratum.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Concentric (Shirley–Chiu) map from the unit square to the unit disk.
#[must_use]
pub fn square_to_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    // Both angles stay within ±π/4 of an axis, where short polynomials give sin and cos to
    // float precision (cheaper than libm's range-reducing sincos in the gather loop).
    if o.x.abs() > o.y.abs() {
        let (s, c) = sin_cos_quarter((PI / 4.0) * (o.y / o.x));
        Vec2::new(o.x * c, o.x * s)
    } else {
        // θ = π/2 − φ: cos θ = sin φ, sin θ = cos φ.
        let (s, c) = sin_cos_quarter((PI / 4.0) * (o.x / o.y));
        Vec2::new(o.y * s, o.y * c)
    }
}

/// `(sin x, cos x)` for |x| ≤ π/4 by Taylor polynomials (truncation error below 2e-9).
#[inline]
#[must_use]
pub fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let s = x
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))));
    let c = 1.0
        + x2 * (-0.5
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40320.0 + x2 * (-1.0 / 3_628_800.0)))));
    (s, c)
}

/// `(sin 2πt, cos 2πt)` for the turn fraction `t` (finite; the warps pass `[0, 1)`): reduced
/// exactly to the nearest quarter turn, then [`sin_cos_quarter`] and a branch-free swap of signs.
/// libm's `sincosf` is an out-of-line call that LLVM hoisted above the light-type branches, so
/// every light sample paid for the sphere and cone lights' azimuth (4 % of the Cornell box).
#[inline]
#[must_use]
pub fn sin_cos_turn(t: f32) -> (f32, f32) {
    let t = t - t.floor();
    let quarter = (t * 4.0 + 0.5).floor();
    // t − quarter/4 is exact (Sterbenz, or t itself at quarter 0): |x| ≤ π/4.
    let (s, c) = sin_cos_quarter((t - 0.25 * quarter) * (2.0 * PI));
    let q = quarter as i32;
    let (a, b) = if q & 1 == 0 { (s, c) } else { (c, s) };
    let sin_sign = if q & 2 == 0 { 1.0 } else { -1.0 };
    let cos_sign = if (q + 1) & 2 == 0 { 1.0 } else { -1.0 };
    (a * sin_sign, b * cos_sign)
}

/// Inverse of [`square_to_disk_concentric`].
#[must_use]
pub fn disk_concentric_to_square(p: Vec2) -> Vec2 {
    let r = p.length();
    if r == 0.0 {
        return Vec2::splat(0.5);
    }
    let mut phi = p.y.atan2(p.x);
    if phi < -PI / 4.0 {
        phi += 2.0 * PI;
    }
    let (a, b) = if phi < PI / 4.0 {
        (r, phi * a_over(r))
    } else if phi < 3.0 * PI / 4.0 {
        (-(phi - PI / 2.0) * a_over(r), r)
    } else if phi < 5.0 * PI / 4.0 {
        (-r, -(phi - PI) * a_over(r))
    } else {
        ((phi - 3.0 * PI / 2.0) * a_over(r), -r)
    };
    fn a_over(r: f32) -> f32 {
        4.0 * r / PI
    }
    Vec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0))
}

/// Cosine-weighted hemisphere direction (Malley's method).
#[must_use]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = square_to_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Density of [`square_to_cosine_hemisphere`] per unit solid angle.
#[must_use]
pub fn cosine_hemisphere_pdf(w: Vec3) -> f32 {
    w.z.max(0.0) * INV_PI
}

/// Inverse of [`square_to_cosine_hemisphere`].
#[must_use]
pub fn cosine_hemisphere_to_square(w: Vec3) -> Vec2 {
    disk_concentric_to_square(Vec2::new(w.x, w.y))
}

/// Uniform direction on the hemisphere z ≥ 0.
#[must_use]
pub fn square_to_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = sin_cos_turn(u.y);
    Vec3::new(r * cos, r * sin, z)
}

/// Density of [`square_to_uniform_hemisphere`].
#[must_use]
pub fn uniform_hemisphere_pdf(w: Vec3) -> f32 {
    if w.z >= 0.0 {
        0.5 * INV_PI
    } else {
        0.0
    }
}

/// Uniform direction on the unit sphere.
#[must_use]
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = sin_cos_turn(u.y);
    Vec3::new(r * cos, r * sin, z)
}

/// Density of [`square_to_uniform_sphere`].
pub const UNIFORM_SPHERE_PDF: f32 = 0.25 * INV_PI;

/// Inverse of [`square_to_uniform_sphere`].
#[must_use]
pub fn uniform_sphere_to_square(w: Vec3) -> Vec2 {
    let mut phi = w.y.atan2(w.x) / (2.0 * PI);
    if phi < 0.0 {
        phi += 1.0;
    }
    Vec2::new((1.0 - w.z) * 0.5, phi)
}

/// Uniform direction in the cone of directions within angle acos(`cos_max`) of +z.
#[must_use]
pub fn square_to_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_t = 1.0 - u.x * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let (sin, cos) = sin_cos_turn(u.y);
    Vec3::new(sin_t * cos, sin_t * sin, cos_t)
}

/// Density of [`square_to_uniform_cone`].
#[must_use]
pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Uniform barycentric coordinates `(b1, b2)` on a triangle (Heitz's low-distortion map).
#[must_use]
pub fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
    if u.y > u.x {
        let b0 = u.x / 2.0;
        let b1 = u.y - b0;
        Vec2::new(b0, b1)
    } else {
        let b1 = u.y / 2.0;
        let b0 = u.x - b1;
        Vec2::new(b0, b1)
    }
}

/// Sample of the tent filter of radius `radius` (density (r − |x|)/r² on [−r, r]).
#[must_use]
pub fn sample_tent(u: f32, radius: f32) -> f32 {
    if u < 0.5 {
        let v = 2.0 * u;
        radius * (v.sqrt() - 1.0)
    } else {
        let v = 2.0 * u - 1.0;
        radius * (1.0 - (1.0 - v).sqrt())
    }
}

/// Standard normal quantile (Acklam's rational approximation refined by one Halley step on the erf
/// approximation is unnecessary here: filter sampling tolerates 1e-9 relative error).
#[must_use]
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let p = p.clamp(1e-300, 1.0 - 1e-16);
    let pl = 0.02425;
    if p < pl {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - pl {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        let q = (-2.0 * (1.0 - p).ln()).sqrt();
        -(((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    }
}

/// Standard normal CDF.
#[must_use]
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * erfc(-x / std::f64::consts::SQRT_2)
}

/// Complementary error function (Numerical Recipes' Chebyshev fit, relative error < 1.2e-7).
#[must_use]
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Sample of a Gaussian of standard deviation `sigma` truncated to `[−radius, radius]`.
#[must_use]
pub fn sample_truncated_gaussian(u: f32, sigma: f32, radius: f32) -> f32 {
    let lo = normal_cdf(-(radius / sigma) as f64);
    let hi = 1.0 - lo;
    let p = lo + u as f64 * (hi - lo);
    ((normal_quantile(p) * sigma as f64) as f32).clamp(-radius, radius)
}

/// Equiangular sampling of a distance along a ray towards a point (Kulla and Fajardo 2012,
/// "Importance sampling techniques for path tracing in participating media", §4): t drawn on
/// `[t0, t1]` with density h / ((θ_b − θ_a)(h² + (t − Δ)²)), which is uniform in the angle the
/// point subtends, so that a point light's 1/r² along the ray is cancelled up to the
/// transmittance and the phase function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equiangular {
    /// The distance along the ray of its closest approach to the point.
    delta: f32,
    /// The closest approach's distance from the point.
    h: f32,
    /// The angles, seen from the point, of `t0` and `t1` (from the closest approach).
    theta_a: f32,
    theta_b: f32,
    /// The interval.
    t0: f32,
    t1: f32,
}

impl Equiangular {
    /// Towards `point` along `o + t d` (`d` unit), `t` in `[t0, t1]` (`t1` may be infinite);
    /// `None` where the ray passes through the point (h = 0 to the precision of the distances
    /// involved) or the interval is empty.
    #[must_use]
    pub fn new(o: Vec3, d: Vec3, point: Vec3, (t0, t1): (f32, f32)) -> Option<Equiangular> {
        let to = point - o;
        let delta = to.dot(d);
        let h = (to - d * delta).length();
        // h is only known to about an ulp of ‖to‖ (scale-free).
        let apart = h > 4.0 * f32::EPSILON * to.length();
        let nonempty = t1 > t0;
        if !apart || !nonempty {
            return None;
        }
        let theta_a = (t0 - delta).atan2(h);
        let theta_b = (t1 - delta).atan2(h);
        (theta_b > theta_a).then_some(Equiangular {
            delta,
            h,
            theta_a,
            theta_b,
            t0,
            t1,
        })
    }

    /// A distance from `u` in `[0, 1)` and its density.
    #[must_use]
    pub fn sample(&self, u: f32) -> (f32, f32) {
        // f32's π/2 lies above the true one, where the tangent turns negative: keep below it.
        let right = f32::from_bits(std::f32::consts::FRAC_PI_2.to_bits() - 1);
        let theta = (self.theta_a + u * (self.theta_b - self.theta_a)).clamp(-right, right);
        let t = (self.delta + self.h * theta.tan()).clamp(self.t0, self.t1);
        (t, self.pdf(t))
    }

    /// The density of distance `t` (zero outside the interval).
    #[must_use]
    pub fn pdf(&self, t: f32) -> f32 {
        if !(self.t0..=self.t1).contains(&t) {
            return 0.0;
        }
        let x = t - self.delta;
        self.h / ((self.theta_b - self.theta_a) * (self.h * self.h + x * x))
    }
}

/// A piecewise-constant 1D distribution over `n` bins (for light selection and environment maps).
#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// Unnormalised bin weights.
    pub func: Vec<f32>,
    /// Cumulative distribution, `n + 1` entries from 0 to 1.
    pub cdf: Vec<f32>,
    /// Sum of the weights (0 when all are zero).
    pub integral: f32,
    /// Per interval `[g/n, (g+1)/n)` of `u`, the last bin whose `cdf` lies at or below its
    /// start (Chen and Asau's guide table): a sample walks from there, a load or two where a
    /// binary search over an environment map's row waited on ten.
    guide: Vec<u32>,
}

impl Distribution1D {
    /// Builds the distribution; all-zero weights give a uniform distribution with `integral == 0`.
    #[must_use]
    pub fn new(func: &[f32]) -> Distribution1D {
        let n = func.len().max(1);
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0f32);
        let mut acc = 0.0f64;
        for &f in func {
            acc += f.max(0.0) as f64;
            cdf.push(acc as f32);
        }
        let integral = acc as f32;
        if acc > 0.0 {
            for c in cdf.iter_mut() {
                *c = (*c as f64 / acc) as f32;
            }
        } else {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f32 / n as f32;
            }
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        // No weights at all leave no bin (`cdf` is [1]).
        let bins = cdf.len() - 1;
        let mut guide = Vec::with_capacity(bins);
        let mut i = 0;
        for g in 0..bins {
            let start = g as f32 / bins as f32;
            while i < bins && cdf[i + 1] <= start {
                i += 1;
            }
            guide.push(i as u32);
        }
        Distribution1D {
            func: func.to_vec(),
            cdf,
            integral,
            guide,
        }
    }

    /// Number of bins.
    #[must_use]
    pub fn len(&self) -> usize {
        self.cdf.len() - 1
    }

    /// True when there are no bins.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// Probability of bin `i`.
    #[must_use]
    pub fn pmf(&self, i: usize) -> f32 {
        self.cdf[i + 1] - self.cdf[i]
    }

    /// Samples a bin: returns (bin, probability, `u` rescaled to [0,1) within the bin).
    #[must_use]
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        let i = self.bin(u);
        let p = self.pmf(i);
        let ur = if p > 0.0 {
            ((u - self.cdf[i]) / p).clamp(0.0, 1.0 - f32::EPSILON)
        } else {
            0.5
        };
        (i, p, ur)
    }

    /// The last bin `i` with `cdf[i] <= u` (the first for `u` below 0 or NaN, the last for `u`
    /// at or above 1): from the guide table's entry, walked back past rounding and on past the
    /// bins that start at or below `u`.
    #[inline]
    fn bin(&self, u: f32) -> usize {
        let n = self.len();
        if n == 0 || u.is_nan() {
            return 0;
        }
        let g = ((u * n as f32) as usize).min(n - 1);
        let mut i = self.guide[g] as usize;
        while i > 0 && self.cdf[i] > u {
            i -= 1;
        }
        while i < n && self.cdf[i + 1] <= u {
            i += 1;
        }
        i.min(n - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_guide_table_finds_the_bins_a_binary_search_finds() {
        let mut rng = crate::Rng::new(7, 0);
        assert_eq!(Distribution1D::new(&[]).len(), 0);
        let weights: [&[f32]; 5] = [
            &[1.0],
            &[0.0, 0.0, 3.0, 0.0, 1.0, 0.0],
            &[0.0; 4],
            &[1e-30, 1.0, 1e-30, 0.0, 5.0, 1e-3, 0.0, 0.0],
            &[2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 7.0],
        ];
        for func in weights {
            let d = Distribution1D::new(func);
            let n = d.len();
            let search = |u: f32| {
                d.cdf
                    .partition_point(|&c| c <= u)
                    .saturating_sub(1)
                    .min(n - 1)
            };
            let mut us: Vec<f32> = d.cdf.clone();
            us.extend(d.cdf.iter().map(|&c| c.next_down()));
            us.extend((0..2000).map(|_| rng.next_f32()));
            us.extend([-1.0, -0.0, 1.0, 2.0, f32::NAN, 1.0f32.next_down()]);
            for u in us {
                assert_eq!(d.bin(u), search(u), "u {u} in {func:?}");
            }
        }
    }

    #[test]
    fn concentric_round_trip() {
        for i in 0..50 {
            for j in 0..50 {
                let u = Vec2::new((i as f32 + 0.37) / 50.0, (j as f32 + 0.61) / 50.0);
                let back = disk_concentric_to_square(square_to_disk_concentric(u));
                assert!((back - u).length() < 1e-4, "{u} -> {back}");
            }
        }
    }

    #[test]
    fn turn_sin_cos_matches_libm() {
        // Every quarter, both sides of each reduction boundary, and values outside [0, 1).
        let mut worst = 0.0f64;
        for i in 0..=40_000 {
            let t = i as f32 / 40_000.0;
            for t in [t, t - 3.0, t + 7.0, t.next_up(), t.next_down()] {
                let (s, c) = sin_cos_turn(t);
                let (sd, cd) = (2.0 * std::f64::consts::PI * f64::from(t)).sin_cos();
                worst = worst
                    .max((f64::from(s) - sd).abs())
                    .max((f64::from(c) - cd).abs());
            }
        }
        assert!(worst < 2e-6, "largest error {worst}");
    }

    #[test]
    fn quarter_sin_cos_matches_libm() {
        for i in -1000..=1000 {
            let x = (PI / 4.0) * (i as f32 / 1000.0);
            let (s, c) = sin_cos_quarter(x);
            let (sd, cd) = (x as f64).sin_cos();
            assert!((s as f64 - sd).abs() < 2e-7, "sin {x}: {s} vs {sd}");
            assert!((c as f64 - cd).abs() < 2e-7, "cos {x}: {c} vs {cd}");
        }
    }

    #[test]
    fn sphere_round_trip() {
        let u = Vec2::new(0.3, 0.8);
        let back = uniform_sphere_to_square(square_to_uniform_sphere(u));
        assert!((back - u).length() < 1e-5);
    }

    #[test]
    fn quantile_inverts_cdf() {
        for &x in &[-3.0, -1.0, -0.1, 0.0, 0.5, 2.0] {
            assert!((normal_quantile(normal_cdf(x)) - x).abs() < 1e-5);
        }
    }

    #[test]
    fn tent_density_matches_histogram() {
        let n = 200_000;
        let bins = 20;
        let mut h = vec![0u32; bins];
        for i in 0..n {
            let x = sample_tent((i as f32 + 0.5) / n as f32, 1.0);
            h[(((x + 1.0) / 2.0 * bins as f32) as usize).min(bins - 1)] += 1;
        }
        for (b, &c) in h.iter().enumerate() {
            let x0 = -1.0 + 2.0 * b as f32 / bins as f32;
            let x1 = x0 + 2.0 / bins as f32;
            let f = |x: f32| {
                if x < 0.0 {
                    0.5 * (1.0 + x).powi(2)
                } else {
                    1.0 - 0.5 * (1.0 - x).powi(2)
                }
            };
            let expect = (f(x1) - f(x0)) * n as f32;
            assert!((c as f32 - expect).abs() < 2.0, "bin {b}: {c} vs {expect}");
        }
    }

    #[test]
    fn distribution_samples_proportionally() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        assert_eq!(d.sample(0.1).0, 0);
        assert_eq!(d.sample(0.3).0, 2);
        assert!((d.pmf(2) - 0.75).abs() < 1e-6);
        assert_eq!(d.pmf(1), 0.0);
    }

    /// Equiangular sampling: the density integrates to 1 over the interval (finite and
    /// infinite), samples land in it, and their histogram follows the density.
    #[test]
    fn equiangular_density_integrates_to_one_and_matches_its_samples() {
        let o = Vec3::new(0.3, -1.0, 2.0);
        let d = Vec3::new(1.0, 2.0, -0.5).normalize();
        let light = Vec3::new(1.5, 0.7, 1.0);
        for (t0, t1) in [
            (0.0f32, 4.0f32),
            (1.2, 1.9),
            (2.5, 40.0),
            (0.0, f32::INFINITY),
        ] {
            let eq = Equiangular::new(o, d, light, (t0, t1)).expect("a proper interval");
            // ∫ pdf over [t0, min(t1, 1e4)] by the midpoint rule in the angle's substitution
            // would be circular; integrate in t on a fine grid instead.
            let end = t1.min(1.0e4);
            let n = 400_000;
            let step = (end - t0) as f64 / n as f64;
            let integral: f64 = (0..n)
                .map(|i| f64::from(eq.pdf((f64::from(t0) + (i as f64 + 0.5) * step) as f32)) * step)
                .sum();
            let tail = if t1.is_finite() {
                0.0
            } else {
                // Beyond 1e4 the density is h/(Δθ t²): its integral is h/(Δθ · 1e4).
                f64::from(eq.h / (eq.theta_b - eq.theta_a)) / 1.0e4
            };
            assert!(
                (integral + tail - 1.0).abs() < 2e-3,
                "[{t0}, {t1}]: ∫ pdf = {}",
                integral + tail
            );
            // Histogram of 20 000 samples over 10 bins of the finite part against the density.
            let hi = t1.min(t0 + 10.0);
            let mut bins = [0u32; 10];
            let count = 20_000;
            for i in 0..count {
                let (t, pdf) = eq.sample((i as f32 + 0.5) / count as f32);
                assert!(t >= t0 && t <= t1, "sample {t} outside [{t0}, {t1}]");
                assert!(
                    (pdf - eq.pdf(t)).abs() <= 1e-4 * pdf,
                    "pdf {pdf} vs {}",
                    eq.pdf(t)
                );
                if t < hi {
                    bins[(((t - t0) / (hi - t0)) * 10.0).min(9.0) as usize] += 1;
                }
            }
            for (b, &c) in bins.iter().enumerate() {
                let (a, z) = (
                    t0 + (hi - t0) * b as f32 / 10.0,
                    t0 + (hi - t0) * (b + 1) as f32 / 10.0,
                );
                let expected: f64 = (0..1000)
                    .map(|k| {
                        let t = a + (z - a) * (k as f32 + 0.5) / 1000.0;
                        f64::from(eq.pdf(t)) * f64::from(z - a) / 1000.0
                    })
                    .sum::<f64>()
                    * f64::from(count);
                assert!(
                    (f64::from(c) - expected).abs() <= 3.0 + 0.01 * expected,
                    "[{t0}, {t1}] bin {b}: {c} samples, {expected:.1} expected"
                );
            }
        }
        // A ray through the point has no equiangular density; neither has an empty interval.
        assert!(Equiangular::new(o, d, o + d * 2.0, (0.0, 4.0)).is_none());
        assert!(Equiangular::new(o, d, light, (3.0, 3.0)).is_none());
    }
}
