//! Evaluating a basis at a direction, shared by the spherical (3.7) and hemispherical (3.18)
//! harmonics: both are N_l^|m|(x) times √2 cos mφ, √2 sin |m|φ or 1, and differ only in the
//! Legendre argument (cos θ, or 2 cos θ − 1 for the hemisphere, 3.15) and a factor √2 (K̃ = √2 K,
//! 3.19). A [`Domain`] says which.

use super::legendre::{normalized_legendre, table_len, triangle_index};
use super::{azimuthal, coefficient_count, index, quadrature};
use glam::DVec3;
use std::f64::consts::SQRT_2;
use std::marker::PhantomData;

/// The domain of a basis: its Legendre argument at a direction and its normalisation.
pub trait Domain {
    /// Factor on every function (1 for SH, √2 for HSH).
    const SCALE: f64;

    /// (x, √(1 − x²)) of the Legendre functions at the unit direction `w`.
    fn legendre_argument(w: DVec3) -> (f64, f64);
}

/// The sphere: x = cos θ.
#[derive(Clone, Copy, Debug)]
pub struct Sphere;

impl Domain for Sphere {
    const SCALE: f64 = 1.0;

    fn legendre_argument(w: DVec3) -> (f64, f64) {
        (w.z, w.x.hypot(w.y))
    }
}

/// The upper hemisphere: x = 2 cos θ − 1, its sine formed as 2√(cos θ (1 − cos θ)) without the
/// cancellation of 1 − x² near the pole (NOTES-001 §A.2); below the horizon is taken as the
/// horizon.
#[derive(Clone, Copy, Debug)]
pub struct Hemisphere;

impl Domain for Hemisphere {
    const SCALE: f64 = SQRT_2;

    fn legendre_argument(w: DVec3) -> (f64, f64) {
        let x = w.z.clamp(0.0, 1.0);
        (2.0 * x - 1.0, 2.0 * (x * (1.0 - x)).sqrt())
    }
}

/// Evaluates every function of bands l < order at a direction, with its scratch space.
#[derive(Clone, Debug)]
pub struct Basis<D> {
    order: usize,
    legendre: Vec<f64>,
    cos: Vec<f64>,
    sin: Vec<f64>,
    domain: PhantomData<D>,
}

impl<D: Domain> Basis<D> {
    /// An evaluator for `order` bands.
    #[must_use]
    pub fn new(order: usize) -> Basis<D> {
        Basis {
            order,
            legendre: vec![0.0; table_len(order)],
            cos: vec![0.0; order.max(1)],
            sin: vec![0.0; order.max(1)],
            domain: PhantomData,
        }
    }

    /// The order it evaluates.
    #[must_use]
    pub fn order(&self) -> usize {
        self.order
    }

    /// The function values for every index i < order² into `out` (`w` a unit vector).
    pub fn eval(&mut self, w: DVec3, out: &mut [f64]) {
        assert!(
            out.len() >= coefficient_count(self.order),
            "basis output too short"
        );
        let (x, s) = D::legendre_argument(w);
        let rho = w.x.hypot(w.y);
        let (c, sn) = if rho > 0.0 {
            (w.x / rho, w.y / rho)
        } else {
            (1.0, 0.0)
        };
        normalized_legendre(self.order, x, s, &mut self.legendre);
        azimuthal(c, sn, &mut self.cos, &mut self.sin);
        for l in 0..self.order {
            out[index(l, 0)] = D::SCALE * self.legendre[triangle_index(l, 0)];
            for m in 1..=l {
                let n = D::SCALE * SQRT_2 * self.legendre[triangle_index(l, m)];
                out[index(l, m as i64)] = n * self.cos[m];
                out[index(l, -(m as i64))] = n * self.sin[m];
            }
        }
    }

    /// The function values as a new vector.
    #[must_use]
    pub fn values(&mut self, w: DVec3) -> Vec<f64> {
        let mut out = vec![0.0; coefficient_count(self.order)];
        self.eval(w, &mut out);
        out
    }

    /// Projection c_i = ∫ f B_i dω by `rule` (over the domain).
    #[must_use]
    pub fn project(
        &mut self,
        rule: &quadrature::Rule,
        mut f: impl FnMut(DVec3) -> f64,
    ) -> Vec<f64> {
        let n = coefficient_count(self.order);
        let (mut b, mut out) = (vec![0.0; n], vec![0.0; n]);
        for (&d, &w) in rule.directions.iter().zip(&rule.weights) {
            let v = w * f(d);
            if v != 0.0 {
                self.eval(d, &mut b);
                for (o, bi) in out.iter_mut().zip(&b) {
                    *o += v * bi;
                }
            }
        }
        out
    }
}

/// The largest deviation of the Gram matrix ∫ B_i B_j dω (by `rule`) from the identity.
#[cfg(test)]
pub(crate) fn gram_deviation<D: Domain>(order: usize, rule: &quadrature::Rule) -> f64 {
    let n = coefficient_count(order);
    let mut basis = Basis::<D>::new(order);
    let (mut b, mut gram) = (vec![0.0; n], vec![0.0; n * n]);
    for (&d, &w) in rule.directions.iter().zip(&rule.weights) {
        basis.eval(d, &mut b);
        for i in 0..n {
            for j in 0..n {
                gram[i * n + j] += w * b[i] * b[j];
            }
        }
    }
    (0..n * n)
        .map(|k| (gram[k] - if k / n == k % n { 1.0 } else { 0.0 }).abs())
        .fold(0.0, f64::max)
}
