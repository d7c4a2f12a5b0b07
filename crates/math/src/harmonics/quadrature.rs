//! Quadrature rules over the sphere, the hemisphere and the lune two hemispheres share, with
//! which the harmonic tables are built and tested (NOTES-001 §A.3).
//!
//! Gauss–Legendre in cos θ times uniform φ integrates exactly the product of two expansions of
//! order n (at equal m a polynomial of degree ≤ 2n − 2 in cos θ, NOTES-001 §A.3) once it has n
//! nodes in cos θ and 2n in φ. The lune's rule substitutes a smoothstep at its ends, where the
//! hemispherical basis has a square-root edge (the horizon), so Gauss–Legendre converges
//! exponentially there too.

use gauss_quad::GaussLegendre;
use glam::DVec3;
use std::f64::consts::PI;

/// Directions and weights: ∫ f dω ≈ Σ wᵢ f(ωᵢ).
#[derive(Clone, Debug, Default)]
pub struct Rule {
    /// The directions (unit vectors).
    pub directions: Vec<DVec3>,
    /// Their weights (solid angle).
    pub weights: Vec<f64>,
}

impl Rule {
    /// ∫ f dω by the rule.
    pub fn integrate(&self, mut f: impl FnMut(DVec3) -> f64) -> f64 {
        self.directions
            .iter()
            .zip(&self.weights)
            .map(|(&d, &w)| w * f(d))
            .sum()
    }

    /// Number of nodes.
    #[must_use]
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// True when it has no nodes.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }
}

/// Gauss–Legendre nodes and weights on `[a, b]` (`n` ≥ 1 nodes; one node is the midpoint).
#[must_use]
pub fn gauss_legendre(n: usize, a: f64, b: f64) -> Vec<(f64, f64)> {
    let half = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    if n <= 1 {
        return vec![(mid, b - a)];
    }
    let rule = GaussLegendre::new(n).expect("two or more Gauss–Legendre nodes");
    rule.iter()
        .map(|(x, w)| (mid + half * x, half * w))
        .collect()
}

/// Gauss–Legendre in cos θ over `[z0, z1]` times `azimuths` uniform φ (offset by half a step).
fn product_rule(cos_nodes: usize, azimuths: usize, z0: f64, z1: f64) -> Rule {
    product_rule_over(cos_nodes, azimuths, azimuths.max(1), z0, z1)
}

/// The first `kept` of `azimuths` azimuths of the product rule, each weighted
/// `azimuths / kept` times.
fn product_rule_over(cos_nodes: usize, azimuths: usize, kept: usize, z0: f64, z1: f64) -> Rule {
    let azimuths = azimuths.max(1);
    let step = 2.0 * PI / azimuths as f64;
    let weight = step * azimuths as f64 / kept as f64;
    let mut rule = Rule::default();
    for (z, wz) in gauss_legendre(cos_nodes, z0, z1) {
        let r = (1.0 - z * z).max(0.0).sqrt();
        for k in 0..kept {
            let phi = (k as f64 + 0.5) * step;
            rule.directions
                .push(DVec3::new(r * phi.cos(), r * phi.sin(), z));
            rule.weights.push(wz * weight);
        }
    }
    rule
}

/// A rule over the upper hemisphere (z ≥ 0) exact for the product of two hemispherical
/// expansions of order `order`.
#[must_use]
pub fn hemisphere(order: usize) -> Rule {
    product_rule(order.max(1), 2 * order.max(1), 0.0, 1.0)
}

/// A rule over the whole sphere exact for the product of two spherical expansions of order
/// `order`.
#[must_use]
pub fn sphere(order: usize) -> Rule {
    product_rule(order.max(1), 2 * order.max(1), -1.0, 1.0)
}

/// A finer rule over the upper hemisphere: `nodes` in cos θ and 2 × `nodes` in φ (for projecting
/// functions that are not band-limited).
#[must_use]
pub fn hemisphere_fine(nodes: usize) -> Rule {
    product_rule(nodes.max(1), 2 * nodes.max(1), 0.0, 1.0)
}

/// [`hemisphere_fine`]'s nodes with φ in (0, π), each weighing twice: the same integral of a
/// function even in φ (f(x, −y, z) = f(x, y, z)), whose nodes at ±φ agree, at half the cost.
#[must_use]
pub fn hemisphere_fine_mirrored(nodes: usize) -> Rule {
    product_rule_over(nodes.max(1), 2 * nodes.max(1), nodes.max(1), 0.0, 1.0)
}

/// Smoothstep 3u² − 2u³ and its derivative: flattens a rule at both ends of `[0, 1]`.
fn smoothstep(u: f64) -> (f64, f64) {
    (u * u * (3.0 - 2.0 * u), 6.0 * u * (1.0 - u))
}

/// A rule over the lune {ω : ω_z ≥ 0 and (R_y(β)⁻¹ ω)_z ≥ 0}, the part of the upper hemisphere
/// that stays above the horizon when rotated back by β about the tangent axis y (β ∈ [0, π]).
/// Coordinates about the y axis, which both horizons contain: ω = (sin ψ cos χ, cos ψ,
/// sin ψ sin χ), where the lune is χ ∈ [0, π − β], ψ ∈ [0, π]; `nodes` Gauss–Legendre nodes in each,
/// after a smoothstep in each so the basis's √ω_z edges become smooth.
#[must_use]
pub fn lune(beta: f64, nodes: usize) -> Rule {
    let width = (PI - beta).max(0.0);
    let mut rule = Rule::default();
    if width == 0.0 {
        return rule;
    }
    let gl = gauss_legendre(nodes, 0.0, 1.0);
    for &(v, wv) in &gl {
        let (sv, dv) = smoothstep(v);
        let psi = PI * sv;
        let (sin_psi, cos_psi) = psi.sin_cos();
        for &(u, wu) in &gl {
            let (su, du) = smoothstep(u);
            let chi = width * su;
            let (sin_chi, cos_chi) = chi.sin_cos();
            rule.directions
                .push(DVec3::new(sin_psi * cos_chi, cos_psi, sin_psi * sin_chi));
            rule.weights.push(wu * wv * PI * dv * width * du * sin_psi);
        }
    }
    rule
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_measure_their_domains() {
        assert!((hemisphere(5).integrate(|_| 1.0) - 2.0 * PI).abs() < 1e-12);
        assert!((sphere(5).integrate(|_| 1.0) - 4.0 * PI).abs() < 1e-12);
        // ∫_H cos θ dω = π.
        assert!((hemisphere(3).integrate(|d| d.z) - PI).abs() < 1e-12);
        for beta in [0.0, 0.1, 0.7, 2.0] {
            // The lune has solid angle 2π − 2β and lies above both horizons.
            let rule = lune(beta, 24);
            assert!((rule.integrate(|_| 1.0) - (2.0 * PI - 2.0 * beta)).abs() < 1e-12);
            let (s, c) = f64::sin_cos(beta);
            for d in &rule.directions {
                assert!(d.z >= -1e-15 && s * d.x + c * d.z >= -1e-12);
            }
        }
    }

    #[test]
    fn the_mirrored_rule_integrates_even_functions_as_the_whole() {
        let (whole, half) = (hemisphere_fine(12), hemisphere_fine_mirrored(12));
        assert_eq!(half.directions.len() * 2, whole.directions.len());
        assert!(half.directions.iter().all(|d| d.y > 0.0));
        // Even in φ: equal; odd (y): zero over the whole, not over the half.
        let even = |d: DVec3| (1.0 + d.x).powi(3) * d.z + d.y * d.y;
        assert!((half.integrate(even) - whole.integrate(even)).abs() < 1e-12);
        assert!(whole.integrate(|d| d.y).abs() < 1e-12);
        assert!(half.integrate(|d| d.y) > 1.0);
    }
}
