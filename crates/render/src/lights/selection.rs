//! Light selection in proportion to an estimate of each light's contribution at the reference
//! point (issue 9), instead of uniformly (Mitsuba 3's default) or by power alone.
//!
//! Each light keeps a [`LightBound`]: enough to estimate, in one division, the irradiance it can
//! give a point without occlusion and without the receiver's cosine: `I / max(d², r²)` for a
//! light of "intensity" `I` (luminance × area for meshes, `L π r²` for spheres, the intensity of
//! point and spot lights) at distance `d` from its centre, `r` its bounding radius (so a point
//! inside the bound gets the light's whole weight, not an infinite one); the irradiance of a
//! directional light; `∫ L dω / 4` for the environment (π L for a constant one). A light is
//! chosen with probability `(1 − s) wᵢ / Σ w + s / N`: the uniform share `s` keeps every light
//! reachable where the estimate errs (occlusion, orientation). Up to [`MAX_ESTIMATED`] lights;
//! beyond that, the estimate would cost more than it saves and selection is uniform.

use ircache_math::Vec3;

/// Most lights whose contributions are estimated per point.
pub const MAX_ESTIMATED: usize = 64;

/// Share of the selection probability spread uniformly over all lights.
pub const UNIFORM_SHARE: f32 = 0.1;

/// What selection knows of a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightBound {
    /// A light in the scene: weight `intensity / max(|p − center|², radius²)`.
    Local {
        /// Centre of the light's bounding sphere.
        center: Vec3,
        /// Squared radius of the bounding sphere (a small positive floor for point lights).
        radius2: f32,
        /// Luminance times area (meshes), `L π r²` (spheres), intensity (point, spot).
        intensity: f32,
    },
    /// A light at infinity: the same weight everywhere.
    Distant {
        /// Irradiance-like weight.
        irradiance: f32,
    },
}

impl LightBound {
    /// The light's estimated unoccluded contribution at `p` (non-negative, finite).
    #[inline]
    #[must_use]
    pub fn weight(&self, p: Vec3) -> f32 {
        let w = match *self {
            LightBound::Local {
                center,
                radius2,
                intensity,
            } => intensity / (center - p).length_squared().max(radius2),
            LightBound::Distant { irradiance } => irradiance,
        };
        if w.is_finite() {
            w.max(0.0)
        } else {
            0.0
        }
    }
}

/// `P(light | p)` from its weight, the weights' total and the number of lights: uniform when no
/// light has a weight. The one formula both [`select`] and [`probability`] use, so that the
/// probability a sample reports and the one MIS recomputes are the same number.
#[inline]
fn mixed(weight: f32, total: f32, n: usize) -> f32 {
    let uniform = 1.0 / n as f32;
    if total > 0.0 && total.is_finite() {
        (1.0 - UNIFORM_SHARE) * weight / total + UNIFORM_SHARE * uniform
    } else {
        uniform
    }
}

/// The light `u` in `[0, 1)` chooses at `p` among `bounds` (not empty) and its probability:
/// one light is certain; beyond [`MAX_ESTIMATED`] lights the choice is uniform.
#[inline]
#[must_use]
pub fn select(bounds: &[LightBound], p: Vec3, u: f32) -> (usize, f32) {
    let n = bounds.len();
    if n <= 1 {
        return (0, 1.0);
    }
    if n > MAX_ESTIMATED {
        return (((u * n as f32) as usize).min(n - 1), 1.0 / n as f32);
    }
    let mut weights = [0.0f32; MAX_ESTIMATED];
    let mut total = 0.0f32;
    for (w, b) in weights.iter_mut().zip(bounds) {
        *w = b.weight(p);
        total += *w;
    }
    let (mut cumulative, mut last) = (0.0, (0, 0.0));
    for (i, &w) in weights[..n].iter().enumerate() {
        let q = mixed(w, total, n);
        if q > 0.0 {
            cumulative += q;
            last = (i, q);
            if u < cumulative {
                return last;
            }
        }
    }
    // Rounding left u beyond the sum: the last light that can be chosen.
    last
}

/// The probability with which [`select`] at `p` chooses `light`.
#[inline]
#[must_use]
pub fn probability(bounds: &[LightBound], p: Vec3, light: usize) -> f32 {
    let n = bounds.len();
    match n {
        0 => 0.0,
        1 => 1.0,
        _ if n > MAX_ESTIMATED => 1.0 / n as f32,
        _ => {
            let total: f32 = bounds.iter().map(|b| b.weight(p)).sum();
            mixed(bounds[light].weight(p), total, n)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(center: Vec3, r: f32, l: f32) -> LightBound {
        LightBound::Local {
            center,
            radius2: r * r,
            intensity: l * std::f32::consts::PI * r * r,
        }
    }

    #[test]
    fn probabilities_sum_to_one_agree_with_the_single_light_form_and_favour_the_near_light() {
        let bounds = [
            sphere(Vec3::new(0.0, 0.0, 1.0), 0.1, 1.0),
            sphere(Vec3::new(0.0, 0.0, 10.0), 0.1, 1.0),
            LightBound::Distant { irradiance: 0.0 },
        ];
        let p = Vec3::ZERO;
        let pmf: Vec<f32> = (0..3).map(|i| probability(&bounds, p, i)).collect();
        assert!((pmf.iter().sum::<f32>() - 1.0).abs() < 1e-6, "{pmf:?}");
        // Each light is chosen on an interval of u as long as its probability, reported as such.
        let n = 100_000;
        let mut counts = [0u32; 3];
        for k in 0..n {
            let (i, q) = select(&bounds, p, (k as f32 + 0.5) / n as f32);
            assert_eq!(q, pmf[i]);
            counts[i] += 1;
        }
        for (i, &c) in counts.iter().enumerate() {
            assert!(
                (c as f32 / n as f32 - pmf[i]).abs() < 1e-4,
                "{counts:?} {pmf:?}"
            );
        }
        // Weights 100 : 1 : 0, and every light keeps its uniform share.
        let expect = 0.9 * 100.0 / 101.0 + 0.1 / 3.0;
        assert!((pmf[0] - expect).abs() < 1e-5, "{pmf:?}");
        assert!((pmf[2] - 0.1 / 3.0).abs() < 1e-7, "{pmf:?}");
    }

    #[test]
    fn a_point_inside_a_bound_gets_a_finite_weight_and_no_weight_is_uniform() {
        let b = sphere(Vec3::ZERO, 0.5, 2.0);
        assert!((b.weight(Vec3::ZERO) - 2.0 * std::f32::consts::PI).abs() < 1e-5);
        let none = [LightBound::Distant { irradiance: 0.0 }; 4];
        let pmf: Vec<f32> = (0..4).map(|i| probability(&none, Vec3::ONE, i)).collect();
        assert_eq!(pmf, [0.25; 4]);
    }
}
