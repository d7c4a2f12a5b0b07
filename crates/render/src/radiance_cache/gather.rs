//! Incoming radiance in HSH from the irradiance cache's stratified gather (NOTES-001 §B.2): the
//! coefficients λ_i = Σ_cells L_c ∫_cell H_i dω (§A.3: a cell's radiance times the integral of the
//! basis over it, so the cosine-weighted strata need no 1/cos θ weights), and their translational
//! gradients by Ward and Heckbert's wall motion (000 eq. 3.48 with ERRATA 2–4) with each wall's
//! cosine replaced by the basis function there: polar walls weigh (2π/N) sin θ cos θ H_i(θ_j, φ_c),
//! azimuthal walls (sin θ_{j+1} − sin θ_j) H_i(θ_c, φ_k) / cos θ_c, each over the nearer of its two
//! cells' distances. Where H_i is cos θ's expansion the sums are the irradiance gradient's
//! exactly, so √(π/2) ∂λ₀₀ + √(π/6) ∂λ₁₀ = ∇_t E (NOTES-001 B-T1).

use crate::irradiance_cache::hemisphere::{HemisphereSamples, Stratification};
use ircache_math::harmonics::coefficient_count;
use ircache_math::harmonics::hsh::HshBasis;
use ircache_math::harmonics::quadrature::gauss_legendre;
use ircache_math::DVec3;
use std::f64::consts::PI;

/// Gauss–Legendre nodes per cell and coordinate for the cell integrals of the basis.
const CELL_NODES: usize = 10;

/// The basis integrated over each cell of a stratification, and its values on the cell walls:
/// computed once per (stratification, order).
#[derive(Clone, Debug)]
pub struct CellBasis {
    strata: Stratification,
    order: usize,
    /// `[cell][i]`: ∫_cell H_i dω, cell = j·N + k.
    cells: Vec<f64>,
    /// `[cell][i]`: the polar wall's weight at the top of ring j, (2π/N) sin θ_j cos θ_j H_i(θ_j, φ_c).
    polar: Vec<f64>,
    /// `[cell][i]`: the azimuthal wall's weight at the start of sector k,
    /// (sin θ_{j+1} − sin θ_j) H_i(θ_c, φ_k) / cos θ_c.
    azimuthal: Vec<f64>,
}

impl CellBasis {
    /// The tables for `strata` at `order`.
    #[must_use]
    pub fn new(strata: Stratification, order: usize) -> CellBasis {
        let (m, n) = (strata.polar, strata.azimuthal);
        let count = coefficient_count(order);
        let mut basis = HshBasis::new(order);
        let mut h = vec![0.0; count];
        let theta_wall = |j: usize| (j as f64 / m as f64).sqrt().min(1.0).asin();
        let dphi = 2.0 * PI / n as f64;
        let direction = |theta: f64, phi: f64| {
            let (st, ct) = theta.sin_cos();
            DVec3::new(st * phi.cos(), st * phi.sin(), ct)
        };
        let mut cells = vec![0.0; m * n * count];
        let mut polar = vec![0.0; m * n * count];
        let mut azimuthal = vec![0.0; m * n * count];
        for j in 0..m {
            let (t0, t1) = (theta_wall(j), theta_wall(j + 1));
            let theta_c = 0.5 * (t0 + t1);
            let thetas = gauss_legendre(CELL_NODES, t0, t1);
            for k in 0..n {
                let cell = j * n + k;
                let out = &mut cells[cell * count..(cell + 1) * count];
                for (phi, wp) in gauss_legendre(CELL_NODES, k as f64 * dphi, (k + 1) as f64 * dphi)
                {
                    for &(theta, wt) in &thetas {
                        basis.eval(direction(theta, phi), &mut h);
                        let w = wt * wp * theta.sin();
                        for (o, hi) in out.iter_mut().zip(&h) {
                            *o += w * hi;
                        }
                    }
                }
                let phi_c = (k as f64 + 0.5) * dphi;
                basis.eval(direction(t0, phi_c), &mut h);
                let w = dphi * t0.sin() * t0.cos();
                for (o, hi) in polar[cell * count..(cell + 1) * count].iter_mut().zip(&h) {
                    *o = w * hi;
                }
                basis.eval(direction(theta_c, k as f64 * dphi), &mut h);
                let w = (t1.sin() - t0.sin()) / theta_c.cos();
                for (o, hi) in azimuthal[cell * count..(cell + 1) * count]
                    .iter_mut()
                    .zip(&h)
                {
                    *o = w * hi;
                }
            }
        }
        CellBasis {
            strata,
            order,
            cells,
            polar,
            azimuthal,
        }
    }

    /// The order.
    #[must_use]
    pub fn order(&self) -> usize {
        self.order
    }

    /// Each cell's weight in the light a lobe with coefficients `c` (one channel) reflects from
    /// one sample per cell, g_c = Σ_i c_i ∫_cell H_i (at least 0), scaled to a mean of 1.
    #[must_use]
    pub fn lobe_weights(&self, c: &[f64]) -> Vec<f64> {
        let count = coefficient_count(self.order);
        let mut g: Vec<f64> = self
            .cells
            .chunks(count)
            .map(|b| b.iter().zip(c).map(|(x, y)| x * y).sum::<f64>().max(0.0))
            .collect();
        let mean = g.iter().sum::<f64>() / g.len().max(1) as f64;
        if mean > 0.0 {
            g.iter_mut().for_each(|v| *v /= mean);
        }
        g
    }

    /// The stratification it was made for.
    #[must_use]
    pub fn strata(&self) -> Stratification {
        self.strata
    }
}

/// A gather's incoming radiance in HSH: coefficients and their translational gradients along
/// the local x and y axes, each `[channel][coefficient]` (3 × order²).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RadianceCoefficients {
    /// The order.
    pub order: usize,
    /// λ per channel.
    pub coefficients: Vec<f64>,
    /// ∂λ/∂x per channel.
    pub gradient_x: Vec<f64>,
    /// ∂λ/∂y per channel.
    pub gradient_y: Vec<f64>,
}

impl RadianceCoefficients {
    /// From a gather's samples (one per cell) and the tables for their stratification.
    ///
    /// # Panics
    /// When the tables were made for another stratification.
    #[must_use]
    pub fn from_samples(samples: &HemisphereSamples, basis: &CellBasis) -> RadianceCoefficients {
        assert_eq!(
            samples.strata, basis.strata,
            "cell tables of another stratification"
        );
        let (m, n) = (samples.strata.polar, samples.strata.azimuthal);
        let count = coefficient_count(basis.order);
        let mut coefficients = vec![0.0; 3 * count];
        let mut gradient_x = vec![0.0; 3 * count];
        let mut gradient_y = vec![0.0; 3 * count];
        let radiance = |cell: usize| {
            let c = samples.radiance[cell];
            [f64::from(c.r), f64::from(c.g), f64::from(c.b)]
        };
        let distance = |cell: usize| f64::from(samples.distance[cell]);
        let dphi = 2.0 * PI / n as f64;
        let add = |target: &mut [f64], weights: &[f64], l: [f64; 3], scale: f64| {
            for ch in 0..3 {
                let s = scale * l[ch];
                if s != 0.0 {
                    for (t, w) in target[ch * count..(ch + 1) * count].iter_mut().zip(weights) {
                        *t += s * w;
                    }
                }
            }
        };
        for j in 0..m {
            for k in 0..n {
                let cell = j * n + k;
                let l = radiance(cell);
                add(
                    &mut coefficients,
                    &basis.cells[cell * count..(cell + 1) * count],
                    l,
                    1.0,
                );
                let phi_c = (k as f64 + 0.5) * dphi;
                let phi_w = k as f64 * dphi;
                // The polar wall between rings j − 1 and j moves along the sector's mid
                // direction u; the azimuthal wall between sectors k − 1 and k along v.
                if j > 0 {
                    let below = cell - n;
                    let r = distance(cell).min(distance(below));
                    let lb = radiance(below);
                    let d = [l[0] - lb[0], l[1] - lb[1], l[2] - lb[2]];
                    let w = &basis.polar[cell * count..(cell + 1) * count];
                    add(&mut gradient_x, w, d, phi_c.cos() / r);
                    add(&mut gradient_y, w, d, phi_c.sin() / r);
                }
                let before = j * n + (k + n - 1) % n;
                let r = distance(cell).min(distance(before));
                let lb = radiance(before);
                let d = [l[0] - lb[0], l[1] - lb[1], l[2] - lb[2]];
                let w = &basis.azimuthal[cell * count..(cell + 1) * count];
                add(&mut gradient_x, w, d, -phi_w.sin() / r);
                add(&mut gradient_y, w, d, phi_w.cos() / r);
            }
        }
        RadianceCoefficients {
            order: basis.order,
            coefficients,
            gradient_x,
            gradient_y,
        }
    }

    /// Ward's gradient limit carried to the coefficients (as
    /// [`crate::irradiance_cache::record::limit_radius_by_gradient`] does for irradiance, here
    /// by scaling the gradients, since the record's radius is shared): over `reach`, the
    /// distance the record serves to, per channel, the gradients may not predict a change of
    /// the coefficient vector larger than `share` of its norm, ‖d·∇λ‖ ≤ share·‖λ‖ (by
    /// orthonormality the norms of the radiance over the hemisphere). Near a wall the
    /// high-order coefficients' gradients can be many times the coefficients, and extrapolated
    /// over a record's reach they made bright streaks of glossy light.
    pub fn limit_gradients(&mut self, reach: f64, share: f64) {
        let count = coefficient_count(self.order);
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
        for ch in 0..3 {
            let span = ch * count..(ch + 1) * count;
            let c = norm(&self.coefficients[span.clone()]).sqrt();
            let g = (norm(&self.gradient_x[span.clone()]) + norm(&self.gradient_y[span.clone()]))
                .sqrt();
            if g * reach > share * c {
                // g · reach > 0 here.
                let f = share * c / (g * reach);
                self.gradient_x[span.clone()]
                    .iter_mut()
                    .for_each(|v| *v *= f);
                self.gradient_y[span].iter_mut().for_each(|v| *v *= f);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_room::{gather, room};
    use super::*;
    use ircache_math::harmonics::hsh::{self, irradiance};
    use ircache_math::harmonics::quadrature;
    use ircache_math::{Rgb, Rng};

    /// B-T1: the coefficients combine to the gather's irradiance, their gradients to its
    /// Ward–Heckbert translational gradient, to rounding, on any samples.
    #[test]
    fn two_coefficients_give_the_irradiance_record() {
        let strata = Stratification::from_divisions(512);
        let basis = CellBasis::new(strata, 4);
        let mut rng = Rng::new(5, 0);
        let mut s = HemisphereSamples::new(strata);
        for (l, r) in s.radiance.iter_mut().zip(s.distance.iter_mut()) {
            *l = Rgb::new(
                rng.next_f32(),
                2.0 * rng.next_f32(),
                rng.next_f32().powi(4) * 9.0,
            );
            *r = 0.1 + 3.0 * rng.next_f32();
        }
        let rc = RadianceCoefficients::from_samples(&s, &basis);
        let n = coefficient_count(4);
        let e = s.irradiance();
        let g = s.translational_gradient_ward_heckbert();
        let (a, b) = ((PI / 2.0).sqrt(), (PI / 6.0).sqrt());
        for (ch, (e, g)) in [(e.r, g[0]), (e.g, g[1]), (e.b, g[2])]
            .into_iter()
            .enumerate()
        {
            let c = &rc.coefficients[ch * n..];
            assert!(
                (irradiance(c) - f64::from(e)).abs() < 1e-6 * f64::from(e),
                "E {ch}"
            );
            let gx = a * rc.gradient_x[ch * n] + b * rc.gradient_x[ch * n + 2];
            let gy = a * rc.gradient_y[ch * n] + b * rc.gradient_y[ch * n + 2];
            let scale = f64::from(g.length());
            assert!(
                (gx - f64::from(g.x)).abs() < 1e-6 * scale,
                "∂x {ch}: {gx} vs {}",
                g.x
            );
            assert!(
                (gy - f64::from(g.y)).abs() < 1e-6 * scale,
                "∂y {ch}: {gy} vs {}",
                g.y
            );
        }
    }

    /// B-T3: every coefficient's gradient against central differences of converged
    /// coefficients, in a room with an occluder (within 5 % of the gradient's largest
    /// coefficient).
    #[test]
    fn gradients_match_finite_differences() {
        let order = 4;
        let n = coefficient_count(order);
        let strata = Stratification::from_divisions(8192);
        let basis = CellBasis::new(strata, order);
        let fine = quadrature::hemisphere_fine(500);
        let converged = |p: DVec3| hsh::project(order, &fine, |d| room(p, d).0);
        let p = DVec3::new(0.1, 0.05, 0.0);
        let samples = gather(p, ircache_math::DMat3::IDENTITY, strata, 11);
        let rc = RadianceCoefficients::from_samples(&samples, &basis);
        let h = 0.01;
        for (axis, gradient) in [(DVec3::X, &rc.gradient_x), (DVec3::Y, &rc.gradient_y)] {
            let plus = converged(p + axis * h);
            let minus = converged(p - axis * h);
            let fd: Vec<f64> = plus
                .iter()
                .zip(&minus)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect();
            let scale = fd.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for i in 0..n {
                // Red channel: radiance × 1.
                assert!(
                    (gradient[i] - fd[i]).abs() < 0.05 * scale,
                    "axis {axis}, coefficient {i}: {} vs {}",
                    gradient[i],
                    fd[i]
                );
            }
        }
    }
}
