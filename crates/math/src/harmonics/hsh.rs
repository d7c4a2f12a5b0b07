//! Hemispherical harmonics H_l^m (001 eqs. 3.15–3.19): the spherical harmonics' three-case form
//! with the shifted Legendre functions P̃_l^m(cos θ) = P_l^m(2 cos θ − 1) and K̃ = √2 K, orthonormal
//! on the upper hemisphere. The shift maps the horizon to the sphere's pole, so every H_l^m with
//! m ≠ 0 vanishes there (NOTES-001 §A.8-1).

use super::basis::{Basis, Hemisphere};
use super::quadrature;
use glam::DVec3;

/// Evaluates every H_l^m, l < order, at a direction of the upper hemisphere (below the horizon
/// the basis is not defined: a negative ω_z is taken as the horizon).
pub type HshBasis = Basis<Hemisphere>;

/// Projection λ_i = ∫_H f H_i dω (NOTES-001 §A.3) by a hemisphere `rule`.
#[must_use]
pub fn project(order: usize, rule: &quadrature::Rule, f: impl FnMut(DVec3) -> f64) -> Vec<f64> {
    HshBasis::new(order).project(rule, f)
}

/// The expansion's value Σ λ_i H_i(ω).
#[must_use]
pub fn evaluate(basis: &mut HshBasis, coefficients: &[f64], w: DVec3) -> f64 {
    let h = basis.values(w);
    h.iter().zip(coefficients).map(|(a, b)| a * b).sum()
}

/// Irradiance from the coefficients of incoming radiance: E = ∫ L cos θ dω = √(π/2) λ₀₀ + √(π/6) λ₁₀,
/// since cos θ = √(π/2) H₀₀ + √(π/6) H₁₀ pointwise (NOTES-001 A-T4).
#[must_use]
pub fn irradiance(coefficients: &[f64]) -> f64 {
    use std::f64::consts::PI;
    let l00 = coefficients.first().copied().unwrap_or(0.0);
    let l10 = coefficients.get(2).copied().unwrap_or(0.0);
    (PI / 2.0).sqrt() * l00 + (PI / 6.0).sqrt() * l10
}

#[cfg(test)]
mod tests {
    use super::super::basis::{gram_deviation, Hemisphere};
    use super::super::{index, rotate_about_z};
    use super::*;
    use std::f64::consts::PI;

    /// A-T1: orthonormal on the hemisphere to 1e-10 at orders 1 … 16, by the exact rule.
    #[test]
    fn orthonormal_on_the_hemisphere() {
        for order in 1..=16usize {
            let deviation = gram_deviation::<Hemisphere>(order, &quadrature::hemisphere(order));
            assert!(deviation < 1e-10, "order {order}: {deviation}");
        }
    }

    #[test]
    fn projections_of_powers_of_the_cosine() {
        let order = 8;
        let rule = quadrature::hemisphere(order);
        let cases: [(i32, &[f64]); 4] = [
            (0, &[(2.0 * PI).sqrt()]),
            (1, &[(PI / 2.0).sqrt(), (PI / 6.0).sqrt()]),
            (2, &[0.835543, 0.723601, 0.186833]),
            (
                5,
                &[0.417771, 0.516858, 0.333630, 0.131586, 0.029841, 0.002999],
            ),
        ];
        for (k, want) in cases {
            let got = project(order, &rule, |d| d.z.powi(k));
            for (i, g) in got.iter().enumerate() {
                let (l, m) = super::super::band_and_degree(i);
                let w = if m == 0 {
                    want.get(l).copied().unwrap_or(0.0)
                } else {
                    0.0
                };
                // The notes print six decimals.
                assert!((g - w).abs() < 1e-6, "cos^{k}: ({l},{m}) {g} vs {w}");
            }
        }
        assert!((project(1, &rule, |_| 1.0)[0] - (2.0 * PI).sqrt()).abs() < 1e-13);
    }

    /// A-T4: E = √(π/2) λ₀₀ + √(π/6) λ₁₀ for any radiance: here a lobe, a sky-like gradient and
    /// an azimuthal pattern, against ∫ L cos θ dω by a fine rule.
    #[test]
    fn irradiance_from_two_coefficients() {
        let fine = quadrature::hemisphere_fine(64);
        let radiances: [&dyn Fn(DVec3) -> f64; 3] = [
            &|d| (8.0 * (d.dot(DVec3::new(0.5, 0.1, 0.6).normalize()) - 1.0)).exp(),
            &|d| 1.0 + 2.0 * d.z + d.x,
            &|d| (3.0 * d.y.atan2(d.x)).cos().powi(2) + 0.2,
        ];
        for l in radiances {
            let e: f64 = fine.integrate(|d| l(d) * d.z);
            let coefficients = project(3, &fine, l);
            assert!((irradiance(&coefficients) - e).abs() < 1e-12 * e.abs().max(1.0));
        }
    }

    /// A-T7: rotation about the normal keeps the norm, composes, and equals re-projecting the
    /// function with its azimuth shifted (which fixes the sign convention).
    #[test]
    fn rotation_about_the_normal_is_exact() {
        let order = 6;
        let rule = quadrature::hemisphere_fine(40);
        let lobe = |d: DVec3| (6.0 * (d.dot(DVec3::new(0.6, 0.3, 0.7).normalize()) - 1.0)).exp();
        let h = project(order, &rule, lobe);
        let mut a = h.clone();
        rotate_about_z(order, &mut a, 0.4);
        rotate_about_z(order, &mut a, 0.7);
        let mut b = h.clone();
        rotate_about_z(order, &mut b, 1.1);
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm(&a) - norm(&h)).abs() < 1e-13);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-13);
        }
        // (R f)(ω) = f(R⁻¹ω): the lobe turned by 1.1 about the normal.
        let r = glam::DMat3::from_rotation_z(1.1);
        let turned = project(order, &rule, |d| lobe(r.transpose() * d));
        for (x, y) in b.iter().zip(&turned) {
            assert!((x - y).abs() < 1e-9, "{x} vs {y}");
        }
        assert_eq!(index(0, 0), 0);
    }

    #[test]
    fn every_degree_vanishes_on_the_horizon_but_zero() {
        let mut basis = HshBasis::new(7);
        let h = basis.values(DVec3::new(0.6, 0.8, 0.0));
        for (i, v) in h.iter().enumerate() {
            let (_, m) = super::super::band_and_degree(i);
            if m != 0 {
                assert!(v.abs() < 1e-15);
            }
        }
    }
}
