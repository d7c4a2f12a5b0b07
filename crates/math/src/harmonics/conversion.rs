//! The SH ↔ HSH conversion matrix (001 eqs. 3.20–3.26, NOTES-001 §A.4):
//! C[i(l,m), j(l',m')] = ∫_H H_l^m Y_l'^m' dω, rows HSH (eq. 3.20's order), columns SH. It is zero
//! unless m = m' (3.26), where the φ integral gives 2π for every m:
//! C = 2π √2 ∫₀¹ N_l^|m|(2x − 1) N_l'^|m|(x) dx, N the normalised Legendre functions.
//!
//! Directions: h = C s restricts an SH expansion to the upper hemisphere; s = Cᵀ h extends an HSH
//! expansion by zero below the horizon (§3.4.1 states them for C indexed the other way).
//! For odd m the integrand holds √x at x = 0; the substitution x = t² makes it analytic, so
//! Gauss–Legendre reaches machine precision.

use super::legendre::{normalized_legendre, table_len, triangle_index};
use super::{coefficient_count, index, quadrature::gauss_legendre};
use std::f64::consts::{PI, SQRT_2};

/// C for an HSH order and an SH order (dense, row-major: HSH rows, SH columns).
#[derive(Clone, Debug)]
pub struct Conversion {
    hsh_order: usize,
    sh_order: usize,
    matrix: Vec<f64>,
}

impl Conversion {
    /// The matrix between HSH of `hsh_order` and SH of `sh_order`.
    #[must_use]
    pub fn new(hsh_order: usize, sh_order: usize) -> Conversion {
        let (rows, cols) = (coefficient_count(hsh_order), coefficient_count(sh_order));
        let mut matrix = vec![0.0; rows * cols];
        let nodes = 2 * (hsh_order + sh_order) + 32;
        let (mut p_h, mut p_s) = (
            vec![0.0; table_len(hsh_order)],
            vec![0.0; table_len(sh_order)],
        );
        for (t, wt) in gauss_legendre(nodes, 0.0, 1.0) {
            // x = t², dx = 2t dt.
            let x = t * t;
            let weight = wt * 2.0 * t * 2.0 * PI * SQRT_2;
            normalized_legendre(
                hsh_order,
                2.0 * x - 1.0,
                2.0 * t * (1.0 - x).sqrt(),
                &mut p_h,
            );
            normalized_legendre(sh_order, x, (1.0 - x * x).sqrt(), &mut p_s);
            for l in 0..hsh_order {
                for lp in 0..sh_order {
                    for m in 0..=l.min(lp) {
                        let v = weight * p_h[triangle_index(l, m)] * p_s[triangle_index(lp, m)];
                        let mi = m as i64;
                        matrix[index(l, mi) * cols + index(lp, mi)] += v;
                        if m > 0 {
                            matrix[index(l, -mi) * cols + index(lp, -mi)] += v;
                        }
                    }
                }
            }
        }
        Conversion {
            hsh_order,
            sh_order,
            matrix,
        }
    }

    /// The HSH order (rows).
    #[must_use]
    pub fn hsh_order(&self) -> usize {
        self.hsh_order
    }

    /// The SH order (columns).
    #[must_use]
    pub fn sh_order(&self) -> usize {
        self.sh_order
    }

    /// Entry C[i, j] (i an HSH index, j an SH index).
    #[must_use]
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.matrix[i * coefficient_count(self.sh_order) + j]
    }

    /// h = C s: an SH expansion restricted to the upper hemisphere, in HSH.
    #[must_use]
    pub fn hsh_from_sh(&self, sh: &[f64]) -> Vec<f64> {
        let cols = coefficient_count(self.sh_order);
        (0..coefficient_count(self.hsh_order))
            .map(|i| {
                self.matrix[i * cols..(i + 1) * cols]
                    .iter()
                    .zip(sh)
                    .map(|(a, b)| a * b)
                    .sum()
            })
            .collect()
    }

    /// s = Cᵀ h: an HSH expansion extended by zero below the horizon, in SH.
    #[must_use]
    pub fn sh_from_hsh(&self, hsh: &[f64]) -> Vec<f64> {
        let cols = coefficient_count(self.sh_order);
        let mut out = vec![0.0; cols];
        for (i, &h) in hsh
            .iter()
            .enumerate()
            .take(coefficient_count(self.hsh_order))
        {
            for (o, c) in out.iter_mut().zip(&self.matrix[i * cols..(i + 1) * cols]) {
                *o += c * h;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::{hsh, quadrature, sh};
    use super::*;
    use glam::DVec3;

    fn relative(a: &[f64], b: &[f64]) -> f64 {
        let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
        (d / b.iter().map(|y| y * y).sum::<f64>()).sqrt()
    }

    /// The closed forms of NOTES-001 §A.4 and its order-3 matrix (four decimals).
    #[test]
    fn closed_form_entries() {
        let c = Conversion::new(3, 3);
        let s = SQRT_2;
        let exact = [
            ((0, 0), 1.0 / s),
            ((0, 2), 6f64.sqrt() / 4.0),
            ((2, 2), 1.0 / (2.0 * s)),
            ((2, 6), 30f64.sqrt() / 8.0),
            ((6, 6), 1.0 / (4.0 * s)),
            ((0, 6), 0.0),
            ((6, 0), 0.0),
            ((6, 2), 0.0),
        ];
        for ((i, j), want) in exact {
            assert!(
                (c.at(i, j) - want).abs() < 1e-13,
                "C[{i},{j}] {} vs {want}",
                c.at(i, j)
            );
        }
        // The notes' matrix as printed, four decimals.
        #[rustfmt::skip]
        #[allow(clippy::approx_constant)]
        let printed = [
            0.7071, 0.0, 0.6124, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            0.0, 0.6739, 0.0, 0.0, 0.0, 0.6745, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.3536, 0.0, 0.0, 0.0, 0.6847, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.6739, 0.0, 0.0, 0.0, 0.6745, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.6187, 0.0, 0.0, 0.0, 0.0,
            0.0, -0.1578, 0.0, 0.0, 0.0, 0.2117, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1768, 0.0, 0.0,
            0.0, 0.0, 0.0, -0.1578, 0.0, 0.0, 0.0, 0.2117, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.6187,
        ];
        for i in 0..9 {
            for j in 0..9 {
                assert!((c.at(i, j) - printed[i * 9 + j]).abs() < 6e-5, "C[{i},{j}]");
            }
        }
    }

    /// Against brute-force ∫_H H_i Y_j dω on a fine rule (odd m included).
    #[test]
    fn equals_the_defining_integral() {
        let (nh, ns) = (4, 6);
        let c = Conversion::new(nh, ns);
        let rule = quadrature::hemisphere_fine(400);
        let (mut hb, mut sb) = (hsh::HshBasis::new(nh), sh::ShBasis::new(ns));
        let mut brute = vec![0.0; coefficient_count(nh) * coefficient_count(ns)];
        for (&d, &w) in rule.directions.iter().zip(&rule.weights) {
            let (h, y) = (hb.values(d), sb.values(d));
            for (i, hi) in h.iter().enumerate() {
                for (j, yj) in y.iter().enumerate() {
                    brute[i * y.len() + j] += w * hi * yj;
                }
            }
        }
        let cols = coefficient_count(ns);
        for i in 0..coefficient_count(nh) {
            for j in 0..cols {
                // The fine rule itself converges slowly at odd m (the √x edge).
                assert!(
                    (c.at(i, j) - brute[i * cols + j]).abs() < 2e-6,
                    "C[{i},{j}]"
                );
            }
        }
    }

    /// A constant in SH becomes (√(2π), 0, …) in HSH; a round trip HSH → SH → HSH (C Cᵀ) of a
    /// cos⁵ lobe at 30° loses what the notes computed (A-T9), decreasing with the SH order.
    #[test]
    fn round_trips() {
        let c = Conversion::new(3, 4);
        let mut s = vec![0.0; 16];
        s[0] = (4.0 * PI).sqrt();
        let h = c.hsh_from_sh(&s);
        assert!((h[0] - (2.0 * PI).sqrt()).abs() < 1e-13);
        assert!(h[1..].iter().all(|v| v.abs() < 1e-13));

        let axis = DVec3::new(0.5, 0.0, 3f64.sqrt() / 2.0);
        let h = hsh::project(5, &quadrature::hemisphere_fine(64), |d| {
            d.dot(axis).max(0.0).powi(5)
        });
        let expected = [(5, 0.072), (10, 0.0021), (20, 0.00096), (40, 0.00051)];
        for (ns, want) in expected {
            let c = Conversion::new(5, ns);
            let back = c.hsh_from_sh(&c.sh_from_hsh(&h));
            let err = relative(&back, &h);
            assert!(
                (err - want).abs() < 0.05 * want,
                "n_S {ns}: {err} vs {want}"
            );
        }
    }
}
