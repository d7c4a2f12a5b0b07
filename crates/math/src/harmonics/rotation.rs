//! Rotating hemispherical-harmonic expansions (001 §3.4, NOTES-001 §A.5).
//!
//! A rotation R = F_pᵀ F_k is split as R = R_z(α) R_y(β) R_z(γ) ([`ZyzAngles`]) and applied as
//! h' = Z(α) · Y(β) · Z(γ) · h. Rotations about the normal are exact ([`super::rotate_about_z`]).
//! The tilt Y(β) is lossy: the lune of solid angle 2β that the tilt takes below the horizon is
//! lost. Its matrix is the precomputed rotation of 3.31, oriented so that it rotates the function
//! as (R f)(ω) = f(R⁻¹ω) (3.31 writes H_j(R_β ω), the other way round):
//! MR(β)_ij = ∫_{ω ∈ H, R_y(β)⁻¹ω ∈ H} H_i(ω) H_j(R_y(β)⁻¹ω) dω,
//! integrated here over the lune by a rule with smooth edges ([`super::quadrature::lune`]), and
//! tabulated over β ([`TiltTable`], lerped). The reference it is checked against is the SH route
//! C R^SH_y(β) Cᵀ with many more SH bands ([`tilt_by_sh`]): exact in the limit, slow.
//! The thesis's third way (digon deletion and eq. 3.30's angle) is not a rigid rotation and is
//! not built (NOTES-001 §A.5).

use super::conversion::Conversion;
use super::hsh::HshBasis;
use super::sh::{rotation_y, ShRotation};
use super::{coefficient_count, quadrature, rotate_about_z};
use glam::DMat3;
use rayon::prelude::*;

/// Euler angles of R = R_z(α) R_y(β) R_z(γ) (NOTES-001 §0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZyzAngles {
    /// The last rotation about z.
    pub alpha: f64,
    /// The tilt about y, β = acos(R₂₂) ∈ [0, π]: the angle between the two normals.
    pub beta: f64,
    /// The first rotation about z.
    pub gamma: f64,
}

impl ZyzAngles {
    /// The angles of a rotation matrix. Where the tilt is below [`NEGLIGIBLE_TILT`] it is taken
    /// as a turn about z alone (β = 0, γ = 0, α from the top-left block): α and γ alone are then
    /// ill-conditioned (each the angle of a vector of length sin β, which frames built in `f32` on
    /// one plane make of rounding noise), their sum is not.
    #[must_use]
    pub fn from_matrix(r: DMat3) -> ZyzAngles {
        // glam is column-major: r.col(j)[i] is R_ij.
        let at = |i: usize, j: usize| r.col(j)[i];
        let sin_beta = at(0, 2).hypot(at(1, 2));
        if sin_beta < NEGLIGIBLE_TILT && at(2, 2) > 0.0 {
            return ZyzAngles {
                alpha: (at(1, 0) - at(0, 1)).atan2(at(0, 0) + at(1, 1)),
                beta: 0.0,
                gamma: 0.0,
            };
        }
        let beta = at(2, 2).clamp(-1.0, 1.0).acos();
        if sin_beta < 1e-12 {
            // R_z(α) R_y(π) R_z(0): α from the top-left block.
            return ZyzAngles {
                alpha: at(1, 0).atan2(at(0, 0)),
                beta,
                gamma: 0.0,
            };
        }
        ZyzAngles {
            alpha: at(1, 2).atan2(at(0, 2)),
            beta,
            gamma: at(2, 1).atan2(-at(2, 0)),
        }
    }

    /// The matrix R_z(α) R_y(β) R_z(γ).
    #[must_use]
    pub fn matrix(&self) -> DMat3 {
        DMat3::from_rotation_z(self.alpha)
            * rotation_y(self.beta)
            * DMat3::from_rotation_z(self.gamma)
    }
}

/// Lune nodes (per coordinate) for an order: measured, MR(0) = I to 1e-14 at orders 3 … 12 with
/// 6n + 16 (the error falls exponentially: order 10 gives 3e-10 at 50 nodes, 4e-15 at 60).
fn lune_nodes(order: usize) -> usize {
    6 * order + 16
}

/// Calls `f` with each node's weight w, H(ω) and H(R_y(β)⁻¹ ω) of the lune rule that projects
/// MR(β): MR(β)_ij = Σ w H_i(ω) H_j(R_y(β)⁻¹ ω).
fn for_each_lune_node(order: usize, beta: f64, mut f: impl FnMut(f64, &[f64], &[f64])) {
    let rule = quadrature::lune(beta, lune_nodes(order));
    let n = coefficient_count(order);
    let inverse = rotation_y(beta).transpose();
    let mut basis = HshBasis::new(order);
    let (mut h, mut h_back) = (vec![0.0; n], vec![0.0; n]);
    for (&d, &w) in rule.directions.iter().zip(&rule.weights) {
        basis.eval(d, &mut h);
        basis.eval(inverse * d, &mut h_back);
        f(w, &h, &h_back);
    }
}

/// MR(β), dense, row-major, order² × order².
#[must_use]
pub fn tilt_matrix(order: usize, beta: f64) -> Vec<f64> {
    let n = coefficient_count(order);
    let mut out = vec![0.0; n * n];
    for_each_lune_node(order, beta, |w, h, h_back| {
        for i in 0..n {
            let wh = w * h[i];
            for (o, hb) in out[i * n..(i + 1) * n].iter_mut().zip(h_back) {
                *o += wh * hb;
            }
        }
    });
    out
}

/// [`tilt_matrix`] restricted to each of the parity `sets` (row-major, set × set), computed
/// alone: the entries between the sets vanish, and half the products are saved.
fn tilt_blocks(order: usize, beta: f64, sets: &[Vec<usize>; 2]) -> [Vec<f64>; 2] {
    let mut blocks = sets.clone().map(|set| vec![0.0; set.len() * set.len()]);
    let mut back = Vec::with_capacity(coefficient_count(order));
    for_each_lune_node(order, beta, |w, h, h_back| {
        for (set, block) in sets.iter().zip(&mut blocks) {
            let m = set.len();
            back.clear();
            back.extend(set.iter().map(|&j| h_back[j]));
            for (r, &i) in set.iter().enumerate() {
                let wh = w * h[i];
                for (o, hb) in block[r * m..(r + 1) * m].iter_mut().zip(&back) {
                    *o += wh * hb;
                }
            }
        }
    });
    blocks
}

/// The SH route to the same tilt: C R^SH_y(β) Cᵀ with `sh_order` SH bands (NOTES-001 §A.5
/// method 1): exact as `sh_order` grows, the reference for [`tilt_matrix`].
#[must_use]
pub fn tilt_by_sh(order: usize, sh_order: usize, beta: f64) -> Vec<f64> {
    let c = Conversion::new(order, sh_order);
    let r = ShRotation::new(sh_order, rotation_y(beta));
    let n = coefficient_count(order);
    let mut out = vec![0.0; n * n];
    let mut unit = vec![0.0; n];
    for j in 0..n {
        unit.iter_mut().for_each(|u| *u = 0.0);
        unit[j] = 1.0;
        let column = c.hsh_from_sh(&r.apply(&c.sh_from_hsh(&unit)));
        for i in 0..n {
            out[i * n + j] = column[i];
        }
    }
    out
}

/// Dense matrix times vector.
#[cfg(test)]
fn multiply(matrix: &[f64], v: &[f64]) -> Vec<f64> {
    let n = v.len();
    (0..n)
        .map(|i| {
            matrix[i * n..(i + 1) * n]
                .iter()
                .zip(v)
                .map(|(a, b)| a * b)
                .sum()
        })
        .collect()
}

/// The tilt (sin β) below which a rotation is taken as a turn about the normal alone: MR(β) =
/// I + O(β), so the error is about 1e-4 of the coefficients, while frames built in `f32` make
/// the normals of one plane differ by about 1e-7.
pub const NEGLIGIBLE_TILT: f64 = 1e-4;

/// The coefficients a tilt about y keeps among themselves: those even under φ → −φ (m ≥ 0,
/// cos mφ) and those odd (m < 0, sin |m|φ), by index l² + l + m. MR(β) has no entry between the
/// two sets, since the tilt and the lune it loses are both symmetric under y → −y; applied as two
/// blocks it takes about half the products of the dense matrix.
fn parity_sets(order: usize) -> [Vec<usize>; 2] {
    let (mut even, mut odd) = (Vec::new(), Vec::new());
    for l in 0..order as i64 {
        for m in -l..=l {
            let i = (l * l + l + m) as usize;
            if m >= 0 {
                even.push(i);
            } else {
                odd.push(i);
            }
        }
    }
    [even, odd]
}

/// MR(β) at steps of `step` from 0 to at least `max_beta`, lerped between (NOTES-001 §A.5: the
/// error is quadratic in the step, 1.7e-4 at 1°), each stored as its two parity blocks
/// ([`parity_sets`]).
#[derive(Clone, Debug)]
pub struct TiltTable {
    order: usize,
    step: f64,
    /// The even and the odd coefficients' indices.
    sets: [Vec<usize>; 2],
    /// Per tabulated angle, MR(β) restricted to each set (row-major, set × set).
    blocks: Vec<[Vec<f64>; 2]>,
}

impl TiltTable {
    /// Tables for `order` at steps of `step` radians up to `max_beta` (≤ π).
    #[must_use]
    pub fn new(order: usize, step: f64, max_beta: f64) -> TiltTable {
        let max_beta = max_beta.clamp(0.0, std::f64::consts::PI);
        let count = (max_beta / step).ceil() as usize + 1;
        let sets = parity_sets(order);
        // One angle per task (the caller's thread pool): the same blocks, in order.
        let blocks = (0..count)
            .into_par_iter()
            .map(|k| tilt_blocks(order, (k as f64 * step).min(std::f64::consts::PI), &sets))
            .collect();
        TiltTable {
            order,
            step,
            sets,
            blocks,
        }
    }

    /// The order it rotates.
    #[must_use]
    pub fn order(&self) -> usize {
        self.order
    }

    /// The largest tilt it holds.
    #[must_use]
    pub fn max_beta(&self) -> f64 {
        (self.blocks.len() - 1) as f64 * self.step
    }

    /// MR(β) h, lerped between the two tabulated angles around β; `None` beyond the table.
    #[must_use]
    pub fn tilt(&self, beta: f64, h: &[f64]) -> Option<Vec<f64>> {
        let mut out = h.to_vec();
        let mut scratch = Vec::new();
        self.tilt_in_place(beta, &mut out, &mut scratch)
            .then_some(out)
    }

    /// [`Self::tilt`] in place for each of the consecutive expansions of this order in `h` (one,
    /// or a channel each), `scratch` its working space; false (and `h` unspecified) beyond the
    /// table. Each row of MR(β) is lerped once and applied to every channel: the table's rows
    /// are read once per lookup, not once per channel.
    fn tilt_in_place(&self, beta: f64, h: &mut [f64], scratch: &mut Vec<f64>) -> bool {
        let position = beta / self.step;
        let k = position.floor() as usize;
        if beta < 0.0 || k >= self.blocks.len() {
            return false;
        }
        let t = position - k as f64;
        let next = if t == 0.0 {
            None
        } else if k + 1 < self.blocks.len() {
            Some(&self.blocks[k + 1])
        } else {
            return false;
        };
        let n = coefficient_count(self.order);
        let channels = h.len() / n;
        for (s, set) in self.sets.iter().enumerate() {
            let m = set.len();
            // The set's coefficients, channel by channel, then room for one lerped row.
            scratch.clear();
            for channel in h.chunks(n) {
                scratch.extend(set.iter().map(|&i| channel[i]));
            }
            scratch.resize(channels * m + m, 0.0);
            let (x, lerped) = scratch.split_at_mut(channels * m);
            let a = &self.blocks[k][s];
            for (r, &i) in set.iter().enumerate() {
                let ra = &a[r * m..(r + 1) * m];
                let row: &[f64] = match next {
                    Some(b) => {
                        let rb = &b[s][r * m..(r + 1) * m];
                        for ((o, &va), &vb) in lerped.iter_mut().zip(ra).zip(rb) {
                            *o = va + t * (vb - va);
                        }
                        &*lerped
                    }
                    None => ra,
                };
                for (channel, xc) in h.chunks_mut(n).zip(x.chunks(m)) {
                    channel[i] = row.iter().zip(xc).map(|(p, q)| p * q).sum();
                }
            }
        }
        true
    }

    /// The coefficients h in a frame F_k seen from a frame F_p: R = F_pᵀ F_k applied as
    /// Z(α) MR(β) Z(γ) h; `None` when the normals are further apart than the table reaches.
    /// Coplanar frames (tilt below [`NEGLIGIBLE_TILT`], [`ZyzAngles::from_matrix`]) cost one turn
    /// about the normal, not a dense product.
    #[must_use]
    pub fn rotate(&self, rotation: DMat3, h: &[f64]) -> Option<Vec<f64>> {
        let mut v = h.to_vec();
        self.rotate_in_place(rotation, &mut v).then_some(v)
    }

    /// [`Self::rotate`] in place, for each of the consecutive expansions of this order in `h`
    /// (one, or a channel each), the angles found once; false (and `h` unspecified) beyond the
    /// table.
    pub fn rotate_in_place(&self, rotation: DMat3, h: &mut [f64]) -> bool {
        let n = coefficient_count(self.order);
        let angles = ZyzAngles::from_matrix(rotation);
        if angles.beta == 0.0 {
            h.chunks_mut(n)
                .for_each(|channel| rotate_about_z(self.order, channel, angles.alpha));
            return true;
        }
        h.chunks_mut(n)
            .for_each(|channel| rotate_about_z(self.order, channel, angles.gamma));
        let mut scratch = Vec::with_capacity(h.len() + n);
        if !self.tilt_in_place(angles.beta, h, &mut scratch) {
            return false;
        }
        h.chunks_mut(n)
            .for_each(|channel| rotate_about_z(self.order, channel, angles.alpha));
        true
    }
}

#[cfg(test)]
mod tests {
    use super::super::hsh;
    use super::*;
    use glam::DVec3;
    use std::f64::consts::PI;

    fn norm(v: &[f64]) -> f64 {
        v.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    fn relative(a: &[f64], b: &[f64]) -> f64 {
        let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
        norm(&d) / norm(b)
    }

    /// A cos⁵ lobe with its axis at θ = 30° (NOTES-001 §A.5), in HSH of order 5.
    fn lobe() -> Vec<f64> {
        let axis = DVec3::new(0.5, 0.0, 3f64.sqrt() / 2.0);
        hsh::project(5, &quadrature::hemisphere_fine(64), |d| {
            d.dot(axis).max(0.0).powi(5)
        })
    }

    /// Frames built in `f32` around normals of one plane that differ by rounding: the rotation
    /// between them is their turn about the normal, not two ill-conditioned angles' noise.
    #[test]
    fn nearly_coplanar_frames_turn_about_the_normal() {
        let order = 6;
        let h = hsh::project(order, &quadrature::hemisphere_fine(40), |d| {
            (4.0 * (d.dot(DVec3::new(0.5, 0.2, 0.8).normalize()) - 1.0)).exp()
        });
        let frame = |n: glam::Vec3, turn: f32| {
            let helper = glam::Vec3::X;
            let t0 = (helper - n * n.dot(helper)).normalize();
            let b0 = n.cross(t0);
            let t = t0 * turn.cos() + b0 * turn.sin();
            DMat3::from_cols(t.as_dvec3(), n.cross(t).as_dvec3(), n.as_dvec3())
        };
        let n1 = glam::Vec3::new(0.3, -0.2, 0.9).normalize();
        // The same plane's normal through a different rounding.
        let n2 = (glam::Vec3::new(0.3, -0.2, 0.9) * 1.000_001).normalize();
        let table = TiltTable::new(order, 1f64.to_radians(), 5f64.to_radians());
        let rotated = table
            .rotate(frame(n1, 0.3).transpose() * frame(n2, 1.0), &h)
            .unwrap();
        let mut turned = h.clone();
        // The record's tangent is 0.7 further round than the shading point's: R = R_z(0.7).
        rotate_about_z(order, &mut turned, 0.7);
        assert!(
            relative(&rotated, &turned) < 1e-4,
            "{}",
            relative(&rotated, &turned)
        );
    }

    #[test]
    fn euler_angles_round_trip() {
        for (a, b, g) in [
            (0.3, 0.9, -1.2),
            (2.0, 0.1, 0.5),
            (-2.5, 2.9, 3.0),
            (0.7, 0.0, 0.0),
        ] {
            let r = ZyzAngles {
                alpha: a,
                beta: b,
                gamma: g,
            }
            .matrix();
            let back = ZyzAngles::from_matrix(r).matrix();
            assert!((r - back).abs().to_cols_array().iter().all(|e| *e < 1e-12));
        }
        let angles = ZyzAngles::from_matrix(rotation_y(0.4));
        assert!((angles.beta - 0.4).abs() < 1e-14 && angles.alpha.abs() < 1e-14);
    }

    /// A-T8: MR(0) = I; a constant loses the lune, h'₀₀ = √(2π)(1 − β/π); the norm never grows.
    #[test]
    fn tilt_loses_the_lune_and_nothing_else() {
        let order = 5;
        let n = coefficient_count(order);
        let identity = tilt_matrix(order, 0.0);
        for i in 0..n {
            for j in 0..n {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((identity[i * n + j] - want).abs() < 1e-10, "MR(0)[{i},{j}]");
            }
        }
        for beta in [0.1f64, 0.35, 0.8, 1.2] {
            let m = tilt_matrix(order, beta);
            let mut constant = vec![0.0; n];
            constant[0] = (2.0 * PI).sqrt();
            let h = multiply(&m, &constant);
            assert!((h[0] - (2.0 * PI).sqrt() * (1.0 - beta / PI)).abs() < 1e-10);
            let l = lobe();
            assert!(norm(&multiply(&m, &l)) <= norm(&l) * (1.0 + 1e-12));
        }
    }

    /// MR(β) equals projecting the tilted, clipped function, and the SH route converges to it
    /// (NOTES-001 §A.5: 0.02 % at n_S = 20, under 0.01 % at n_S = 40 for the cos⁵ lobe; measured
    /// 1.5e-4 and 8e-6 at 20°, 5e-5 and 5e-6 at 45°).
    #[test]
    fn tilt_equals_projection_and_the_sh_route() {
        let order = 5;
        let h = lobe();
        let mut basis = HshBasis::new(order);
        for beta in [20f64.to_radians(), 45f64.to_radians()] {
            let tilted = multiply(&tilt_matrix(order, beta), &h);
            let inverse = rotation_y(beta).transpose();
            let truth = hsh::project(order, &quadrature::lune(beta, 80), |d| {
                hsh::evaluate(&mut basis, &h, inverse * d)
            });
            assert!(relative(&tilted, &truth) < 1e-10);
            let sh20 = multiply(&tilt_by_sh(order, 20, beta), &h);
            let sh40 = multiply(&tilt_by_sh(order, 40, beta), &h);
            let (e20, e40) = (relative(&sh20, &tilted), relative(&sh40, &tilted));
            assert!(e20 < 3e-4 && e40 < 2e-5, "β {beta}: {e20} {e40}");
        }
    }

    /// MR(β) keeps the coefficients even under φ → −φ and the odd ones apart (what lets the
    /// table store two blocks): its entries between the two sets are rounding noise beside the
    /// others, at orders and tilts across the table's range, and the table at a tabulated angle
    /// equals the dense matrix.
    #[test]
    fn the_tilt_keeps_even_and_odd_coefficients_apart() {
        for order in [3, 7, 10] {
            let n = coefficient_count(order);
            let [even, odd] = parity_sets(order);
            assert_eq!(even.len() + odd.len(), n);
            for degrees in [1.0f64, 13.0, 30.0] {
                let m = tilt_matrix(order, degrees.to_radians());
                let largest = m.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                let across = even
                    .iter()
                    .flat_map(|&i| odd.iter().map(move |&j| (i, j)))
                    .map(|(i, j)| m[i * n + j].abs().max(m[j * n + i].abs()))
                    .fold(0.0f64, f64::max);
                assert!(
                    across < 1e-12 * largest,
                    "order {order}, {degrees}°: {across} across against {largest}"
                );
            }
        }
        let order = 6;
        let h = hsh::project(order, &quadrature::hemisphere_fine(40), |d| {
            (3.0 * (d.dot(DVec3::new(0.3, -0.4, 0.85).normalize()) - 1.0)).exp()
        });
        let table = TiltTable::new(order, 1f64.to_radians(), 20f64.to_radians());
        let beta = 17f64.to_radians();
        let blocks = table.tilt(beta, &h).unwrap();
        let dense = multiply(&tilt_matrix(order, beta), &h);
        assert!(
            relative(&blocks, &dense) < 1e-12,
            "{}",
            relative(&blocks, &dense)
        );
    }

    /// The table at 1° steps, read halfway between two entries, against the SH route at
    /// n_S = 40 (the bound: 2e-4), and a whole rotation of frames against tilting
    /// after turning by hand.
    #[test]
    fn table_reads_within_bounds() {
        let order = 5;
        let h = lobe();
        let table = TiltTable::new(order, 1f64.to_radians(), 25f64.to_radians());
        for degrees in [4.5f64, 12.5, 20.5] {
            let beta = degrees.to_radians();
            let lerped = table.tilt(beta, &h).unwrap();
            let exact = multiply(&tilt_matrix(order, beta), &h);
            let sh = multiply(&tilt_by_sh(order, 40, beta), &h);
            assert!(
                relative(&lerped, &exact) < 2e-4,
                "{degrees}°: {}",
                relative(&lerped, &exact)
            );
            assert!(
                relative(&lerped, &sh) < 2e-4,
                "{degrees}° SH: {}",
                relative(&lerped, &sh)
            );
        }
        assert!(table.tilt(30f64.to_radians(), &h).is_none());
        let angles = ZyzAngles {
            alpha: 0.4,
            beta: 10f64.to_radians(),
            gamma: -1.3,
        };
        let rotated = table.rotate(angles.matrix(), &h).unwrap();
        let mut by_hand = h.clone();
        rotate_about_z(order, &mut by_hand, -1.3);
        let mut by_hand = multiply(&tilt_matrix(order, angles.beta), &by_hand);
        rotate_about_z(order, &mut by_hand, 0.4);
        assert!(relative(&rotated, &by_hand) < 1e-12);
    }
}
