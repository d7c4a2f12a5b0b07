//! Real spherical harmonics Y_l^m (001 eqs. 3.7–3.8, Condon–Shortley phase) and their rotations.
//!
//! A rotation of a band-limited function keeps each band, so its matrix is block-diagonal, one
//! (2l+1)² block per band. The blocks are computed here by projection,
//! R_{mm'} = ∫_S Y_l^m(ω) Y_l^{m'}(R⁻¹ω) dω, with a rule that integrates those products exactly
//! ([`super::quadrature::sphere`]), so they are exact to rounding without the Ivanic–Ruedenberg
//! recurrence (its 1998 erratum is a known trap); rotations about z have a closed form
//! ([`super::rotate_about_z`]).

use super::basis::{Basis, Sphere};
use super::{coefficient_count, quadrature};
use glam::{DMat3, DVec3};

/// Evaluates every Y_l^m, l < order, at a direction.
pub type ShBasis = Basis<Sphere>;

/// Projection f_i = ∫_S f Y_i dω (3.9) by `rule`.
#[must_use]
pub fn project(order: usize, rule: &quadrature::Rule, f: impl FnMut(DVec3) -> f64) -> Vec<f64> {
    ShBasis::new(order).project(rule, f)
}

/// Y_l^m for bands 0–2 at the unit direction `w` in closed form (single precision, Condon–Shortley
/// phase, index l² + l + m): the same values as [`ShBasis`] of order 3 without its tables, for
/// callers that evaluate them once per lookup or gather ray (the volumetric records).
#[must_use]
pub fn bands_0_to_2(w: glam::Vec3) -> [f32; 9] {
    // √(1/4π), √(3/4π), √(15/4π), √(5/16π), √(15/16π).
    const K0: f32 = 0.282_094_8;
    const K1: f32 = 0.488_602_5;
    const K2: f32 = 1.092_548_5;
    const K20: f32 = 0.315_391_57;
    const K22: f32 = 0.546_274_2;
    let (x, y, z) = (w.x, w.y, w.z);
    [
        K0,
        -K1 * y,
        K1 * z,
        -K1 * x,
        K2 * x * y,
        -K2 * y * z,
        K20 * (3.0 * z * z - 1.0),
        -K2 * x * z,
        K22 * (x * x - y * y),
    ]
}

/// The rotation of spherical-harmonic coefficients by a rotation matrix: block-diagonal, one
/// (2l+1)² block per band, row-major over m, m' = −l … l.
#[derive(Clone, Debug)]
pub struct ShRotation {
    order: usize,
    blocks: Vec<Vec<f64>>,
}

impl ShRotation {
    /// The matrix taking the coefficients of f to those of (R f)(ω) = f(R⁻¹ω).
    #[must_use]
    pub fn new(order: usize, rotation: DMat3) -> ShRotation {
        let rule = quadrature::sphere(order);
        let inverse = rotation.transpose();
        let mut basis = ShBasis::new(order);
        let n = coefficient_count(order);
        let (mut y, mut y_rotated) = (vec![0.0; n], vec![0.0; n]);
        let mut blocks: Vec<Vec<f64>> = (0..order)
            .map(|l| vec![0.0; (2 * l + 1) * (2 * l + 1)])
            .collect();
        for (&d, &w) in rule.directions.iter().zip(&rule.weights) {
            basis.eval(d, &mut y);
            basis.eval(inverse * d, &mut y_rotated);
            for (l, block) in blocks.iter_mut().enumerate() {
                let base = l * l;
                let width = 2 * l + 1;
                for r in 0..width {
                    let wy = w * y[base + r];
                    let row = &mut block[r * width..(r + 1) * width];
                    for (e, yr) in row.iter_mut().zip(&y_rotated[base..base + width]) {
                        *e += wy * yr;
                    }
                }
            }
        }
        ShRotation { order, blocks }
    }

    /// The order it rotates.
    #[must_use]
    pub fn order(&self) -> usize {
        self.order
    }

    /// Band l's block, row-major.
    #[must_use]
    pub fn block(&self, l: usize) -> &[f64] {
        &self.blocks[l]
    }

    /// The rotated coefficients.
    #[must_use]
    pub fn apply(&self, coefficients: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; coefficients.len()];
        for (l, block) in self.blocks.iter().enumerate() {
            let base = l * l;
            let width = 2 * l + 1;
            if base + width > coefficients.len() {
                break;
            }
            let input = &coefficients[base..base + width];
            for r in 0..width {
                out[base + r] = block[r * width..(r + 1) * width]
                    .iter()
                    .zip(input)
                    .map(|(a, b)| a * b)
                    .sum();
            }
        }
        out
    }

    /// The dense matrix (order² × order²).
    #[must_use]
    pub fn dense(&self) -> Vec<f64> {
        let n = coefficient_count(self.order);
        let mut out = vec![0.0; n * n];
        for (l, block) in self.blocks.iter().enumerate() {
            let (base, width) = (l * l, 2 * l + 1);
            for r in 0..width {
                for c in 0..width {
                    out[(base + r) * n + base + c] = block[r * width + c];
                }
            }
        }
        out
    }
}

/// Rotation about the y axis by β, as in NOTES-001 §0: [[cos β, 0, sin β], [0, 1, 0], [−sin β, 0, cos β]].
#[must_use]
pub fn rotation_y(beta: f64) -> DMat3 {
    let (s, c) = beta.sin_cos();
    DMat3::from_cols(DVec3::new(c, 0.0, -s), DVec3::Y, DVec3::new(s, 0.0, c))
}

/// Rotation about the z axis by α.
#[must_use]
pub fn rotation_z(alpha: f64) -> DMat3 {
    DMat3::from_rotation_z(alpha)
}

#[cfg(test)]
mod tests {
    use super::super::basis::{gram_deviation, Sphere};
    use super::super::rotate_about_z;
    use super::*;
    use std::f64::consts::PI;

    fn norm(v: &[f64]) -> f64 {
        v.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    #[test]
    fn orthonormal_on_the_sphere() {
        for order in [1usize, 3, 6, 10, 16] {
            let deviation = gram_deviation::<Sphere>(order, &quadrature::sphere(order));
            assert!(deviation < 1e-10, "order {order}: {deviation}");
        }
    }

    #[test]
    fn low_bands_in_closed_form() {
        // Y_1^{-1} = −√(3/4π) y, Y_1^0 = √(3/4π) z, Y_1^1 = −√(3/4π) x (Condon–Shortley).
        let w = DVec3::new(0.3, -0.5, 0.6).normalize();
        let y = ShBasis::new(2).values(w);
        let k = (3.0 / (4.0 * PI)).sqrt();
        assert!((y[0] - 0.5 / PI.sqrt()).abs() < 1e-15);
        assert!((y[1] + k * w.y).abs() < 1e-15);
        assert!((y[2] - k * w.z).abs() < 1e-15);
        assert!((y[3] + k * w.x).abs() < 1e-15);
    }

    /// The closed form of bands 0–2 against the general evaluator, over directions of every
    /// octant and the poles.
    #[test]
    fn bands_0_to_2_equal_the_basis() {
        let mut basis = ShBasis::new(3);
        let mut y = [0.0f64; 9];
        let mut directions = vec![DVec3::Z, -DVec3::Z, DVec3::X, -DVec3::Y];
        for i in 0..200 {
            let (a, b) = (
                f64::from(i) * 0.618_034 % 1.0,
                f64::from(i) * 0.754_877 % 1.0,
            );
            let z = 1.0 - 2.0 * a;
            let r = (1.0 - z * z).sqrt();
            directions.push(DVec3::new(
                r * (2.0 * PI * b).cos(),
                r * (2.0 * PI * b).sin(),
                z,
            ));
        }
        for w in directions {
            basis.eval(w, &mut y);
            let closed = bands_0_to_2(w.as_vec3());
            for (i, (&c, &e)) in closed.iter().zip(&y).enumerate() {
                assert!(
                    (f64::from(c) - e).abs() < 2e-6,
                    "{w:?} index {i}: {c} against {e}"
                );
            }
        }
    }

    /// A-T6: rotations keep the norm, compose, and R(2π) = I; agree with projecting the rotated
    /// function; about z they equal the closed form.
    #[test]
    fn rotations_are_orthogonal_and_compose() {
        let order = 8;
        let lobe = |d: DVec3| (5.0 * (d.dot(DVec3::new(0.4, 0.2, 0.9).normalize()) - 1.0)).exp();
        let s = project(order, &quadrature::sphere(40), lobe);
        let r1 = ShRotation::new(order, rotation_y(0.3));
        let r2 = ShRotation::new(order, rotation_y(0.5));
        let r12 = ShRotation::new(order, rotation_y(0.8));
        let a = r2.apply(&r1.apply(&s));
        let b = r12.apply(&s);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-12);
        }
        assert!((norm(&r1.apply(&s)) - norm(&s)).abs() < 1e-12);
        let full = ShRotation::new(order, rotation_y(2.0 * PI)).apply(&s);
        for (x, y) in full.iter().zip(&s) {
            assert!((x - y).abs() < 1e-12);
        }
        // A general rotation against the projection of the rotated function (whose own
        // truncation error is the lobe's energy beyond order 8: compare the low bands).
        let rot = DMat3::from_euler(glam::EulerRot::ZYZ, 0.7, 1.1, -0.4);
        let rotated =
            ShRotation::new(order, rot).apply(&project(order, &quadrature::sphere(40), lobe));
        let projected = project(order, &quadrature::sphere(40), |d| {
            lobe(rot.transpose() * d)
        });
        for (x, y) in rotated.iter().zip(&projected) {
            assert!((x - y).abs() < 1e-10, "{x} vs {y}");
        }
        let z = ShRotation::new(order, rotation_z(0.9)).apply(&s);
        let mut closed = s.clone();
        rotate_about_z(order, &mut closed, 0.9);
        for (x, y) in z.iter().zip(&closed) {
            assert!((x - y).abs() < 1e-12);
        }
    }
}
