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

/// Selection probabilities at `p` for `bounds` (at most [`MAX_ESTIMATED`]), written to `pmf`;
/// uniform when no light has a weight.
#[inline]
pub fn selection_pmf(bounds: &[LightBound], p: Vec3, pmf: &mut [f32]) {
    let n = bounds.len();
    let mut total = 0.0f32;
    for (w, b) in pmf.iter_mut().zip(bounds) {
        *w = b.weight(p);
        total += *w;
    }
    let uniform = 1.0 / n as f32;
    if !(total > 0.0 && total.is_finite()) {
        pmf[..n].fill(uniform);
        return;
    }
    let scale = (1.0 - UNIFORM_SHARE) / total;
    for w in &mut pmf[..n] {
        *w = *w * scale + UNIFORM_SHARE * uniform;
    }
}

/// The probability of light `light` at `p` under [`selection_pmf`], without the others'.
#[inline]
#[must_use]
pub fn light_pmf(bounds: &[LightBound], p: Vec3, light: usize) -> f32 {
    let n = bounds.len();
    let total: f32 = bounds.iter().map(|b| b.weight(p)).sum();
    let uniform = 1.0 / n as f32;
    if !(total > 0.0 && total.is_finite()) {
        return uniform;
    }
    (1.0 - UNIFORM_SHARE) * bounds[light].weight(p) / total + UNIFORM_SHARE * uniform
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
        let mut pmf = [0.0; 3];
        selection_pmf(&bounds, p, &mut pmf);
        assert!((pmf.iter().sum::<f32>() - 1.0).abs() < 1e-6, "{pmf:?}");
        for (i, &q) in pmf.iter().enumerate() {
            assert!((q - light_pmf(&bounds, p, i)).abs() < 1e-7);
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
        let mut pmf = [0.0; 4];
        selection_pmf(&none, Vec3::ONE, &mut pmf);
        assert_eq!(pmf, [0.25; 4]);
    }
}
