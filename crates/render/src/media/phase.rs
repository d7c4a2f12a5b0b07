//! Phase functions: isotropic and Henyey–Greenstein (Mitsuba 3's `isotropic` and `hg`), each
//! sampled exactly (the sample's weight is 1).
//!
//! Convention: `d` is the direction the light travels *into* the scattering point (the ray's
//! direction), `w` the direction it leaves along; cos θ = d·w, so g > 0 scatters forward.
//! p(θ) = (1 − g²) / (4π (1 + g² − 2g cos θ)^{3/2}).

use ircache_math::sampling::sin_cos_turn;
use ircache_math::{Frame, Vec2, Vec3, PI};
use ircache_scene::PhaseDesc;

/// A phase function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    /// 1/4π.
    Isotropic,
    /// Henyey–Greenstein with mean cosine `g`.
    HenyeyGreenstein {
        /// Mean cosine of the scattering angle, in (−1, 1).
        g: f32,
    },
}

/// Below this |g| Henyey–Greenstein is sampled as isotropic (the inversion divides by g).
const ISOTROPIC_G: f32 = 1e-3;

impl Phase {
    /// From the scene description.
    #[must_use]
    pub fn from_desc(desc: &PhaseDesc) -> Phase {
        match *desc {
            PhaseDesc::Isotropic => Phase::Isotropic,
            PhaseDesc::HenyeyGreenstein { g } => Phase::HenyeyGreenstein { g },
        }
    }

    /// Density per steradian of leaving along `w` after arriving along `d` (both unit).
    #[inline]
    #[must_use]
    pub fn eval(&self, d: Vec3, w: Vec3) -> f32 {
        match *self {
            Phase::Isotropic => 0.25 / PI,
            Phase::HenyeyGreenstein { g } => henyey_greenstein(g, d.dot(w)),
        }
    }

    /// The derivative of [`Phase::eval`] with respect to cos θ = `d`·`w`:
    /// 3g p(θ) / (1 + g² − 2g cos θ) for Henyey–Greenstein.
    #[inline]
    #[must_use]
    pub fn eval_derivative(&self, d: Vec3, w: Vec3) -> f32 {
        match *self {
            Phase::Isotropic => 0.0,
            Phase::HenyeyGreenstein { g } => {
                let cos_theta = d.dot(w);
                3.0 * g * henyey_greenstein(g, cos_theta) / (1.0 + g * g - 2.0 * g * cos_theta)
            }
        }
    }

    /// A direction drawn with density [`Phase::eval`], and that density.
    #[inline]
    #[must_use]
    pub fn sample(&self, d: Vec3, u: Vec2) -> (Vec3, f32) {
        let cos_theta = match *self {
            Phase::HenyeyGreenstein { g } if g.abs() >= ISOTROPIC_G => {
                let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
                ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
            }
            _ => 1.0 - 2.0 * u.x,
        };
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let (sin, cos) = sin_cos_turn(u.y);
        let local = Vec3::new(sin_theta * cos, sin_theta * sin, cos_theta);
        let w = Frame::from_z(d).from_local(local).normalize();
        (w, self.eval(d, w))
    }

    /// The mean cosine (0 for isotropic).
    #[must_use]
    pub fn mean_cosine(&self) -> f32 {
        match *self {
            Phase::Isotropic => 0.0,
            Phase::HenyeyGreenstein { g } => g,
        }
    }
}

/// Henyey–Greenstein's density at cos θ.
#[inline]
#[must_use]
pub fn henyey_greenstein(g: f32, cos_theta: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_math::Rng;

    /// ∫ p dω = 1 and ∫ p cos θ dω = g by quadrature over θ.
    #[test]
    fn normalised_with_mean_cosine_g() {
        for g in [-0.8f32, -0.3, 0.0, 0.5, 0.8, 0.95] {
            let n = 200_000;
            let (mut total, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let mu = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                let p = f64::from(henyey_greenstein(g, mu as f32)) * 2.0 * std::f64::consts::PI;
                total += p * 2.0 / n as f64;
                mean += p * mu * 2.0 / n as f64;
            }
            assert!((total - 1.0).abs() < 2e-3, "g {g}: ∫p = {total}");
            assert!((mean - f64::from(g)).abs() < 2e-3, "g {g}: mean cos {mean}");
        }
    }

    /// Sampled cosines follow the density: a χ²-style histogram check on cos θ and the sample's
    /// reported density equals `eval`.
    #[test]
    fn sampling_matches_density() {
        let d = Vec3::new(0.3, -0.5, 0.8).normalize();
        for phase in [
            Phase::Isotropic,
            Phase::HenyeyGreenstein { g: 0.8 },
            Phase::HenyeyGreenstein { g: -0.5 },
        ] {
            let bins = 40;
            let n = 400_000;
            let mut hist = vec![0u32; bins];
            let mut rng = Rng::new(7, 1);
            for _ in 0..n {
                let (w, pdf) = phase.sample(d, rng.next_2d());
                assert!((w.length() - 1.0).abs() < 1e-4);
                let e = phase.eval(d, w);
                assert!((pdf - e).abs() <= 1e-5 * e.max(1.0), "{pdf} vs {e}");
                let mu = d.dot(w).clamp(-1.0, 1.0 - 1e-7);
                hist[((mu + 1.0) * 0.5 * bins as f32) as usize] += 1;
            }
            let mut chi2 = 0.0f64;
            for (b, &count) in hist.iter().enumerate() {
                // Expected: ∫ over the bin of 2π p(μ) dμ by a fine midpoint rule.
                let (lo, hi) = (
                    -1.0 + 2.0 * b as f64 / bins as f64,
                    -1.0 + 2.0 * (b + 1) as f64 / bins as f64,
                );
                let steps = 200;
                let mut prob = 0.0;
                for s in 0..steps {
                    let mu = lo + (hi - lo) * (s as f64 + 0.5) / steps as f64;
                    let p = match phase {
                        Phase::Isotropic => 0.25 / std::f64::consts::PI,
                        Phase::HenyeyGreenstein { g } => f64::from(henyey_greenstein(g, mu as f32)),
                    };
                    prob += p * 2.0 * std::f64::consts::PI * (hi - lo) / steps as f64;
                }
                let expected = prob * n as f64;
                chi2 += (f64::from(count) - expected).powi(2) / expected;
            }
            // 39 degrees of freedom: the 99.9 % quantile is about 72.
            assert!(chi2 < 72.0, "{phase:?}: χ² = {chi2}");
        }
    }

    /// The derivative in cos θ against central differences of the density.
    #[test]
    fn derivative_matches_differences() {
        let d = Vec3::Z;
        for g in [0.0f32, 0.3, -0.6, 0.85] {
            let phase = Phase::HenyeyGreenstein { g };
            for mu in [-0.9f32, -0.2, 0.4, 0.95] {
                let at = |m: f32| Vec3::new((1.0 - m * m).sqrt(), 0.0, m);
                let h = 1e-3;
                let fd = (f64::from(phase.eval(d, at(mu + h)))
                    - f64::from(phase.eval(d, at(mu - h))))
                    / (2.0 * f64::from(h));
                let got = f64::from(phase.eval_derivative(d, at(mu)));
                assert!(
                    (got - fd).abs() <= 1e-3 * fd.abs().max(1e-3),
                    "g {g}, cos {mu}: {got} against {fd}"
                );
            }
        }
        assert_eq!(Phase::Isotropic.eval_derivative(d, Vec3::X), 0.0);
    }
}
