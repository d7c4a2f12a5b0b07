//! The stratified cosine-weighted hemisphere gather of one record and what is computed from it:
//! irradiance (000 eq. 3.4), harmonic mean distance (3.8), rotational gradient (3.29) and the
//! occlusion-aware translational gradient in both formulations, 3.47 (Křivánek et al. as
//! corrected by Jarosz) and 3.48 (Ward–Heckbert), which 000 §3.6.3 proves equal.
//!
//! Cells: `M` polar rings (j) × `N` azimuthal sectors (k) of equal projected solid angle,
//! sin²θ ∈ [j/M, (j+1)/M), φ ∈ [2πk/N, 2π(k+1)/N) (3.5). By default N ≈ πM (ERRATA 1).
//! Gradients are returned in the local frame (x, y tangent, z the normal) with the conventions of
//! 3.15: E(x, n) ≈ E + (n_i × n)·∇_r E + (x − x_i)·∇_t E (absolute gradients, ERRATA 5).

use ircache_math::sampling::ONE_MINUS_EPSILON;
use ircache_math::{Rgb, Rng, Vec2, Vec3};
use std::f64::consts::PI;

/// The hemisphere's division into cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stratification {
    /// Polar divisions M.
    pub polar: usize,
    /// Azimuthal divisions N.
    pub azimuthal: usize,
}

impl Stratification {
    /// About `divisions` cells with azimuthal ≈ π × polar (Radiance's `-ad`).
    #[must_use]
    pub fn from_divisions(divisions: usize) -> Stratification {
        let d = divisions.max(4) as f64;
        let polar = (d / PI).sqrt().round().max(1.0) as usize;
        let azimuthal = (d / polar as f64).round().max(3.0) as usize;
        Stratification { polar, azimuthal }
    }

    /// Number of cells.
    #[must_use]
    pub fn cells(&self) -> usize {
        self.polar * self.azimuthal
    }

    /// Calls `f(j, k, jitter, direction)` for every cell with the jitter `jitter(j, k)` (3.5), sector
    /// by sector (k outer, j inner: the order `jitter` is called in): each sector's edge angle is
    /// computed once and the jitter within it (at most π/4 for N ≥ 8) by polynomials.
    #[inline]
    pub fn for_each_direction(
        &self,
        mut jitter: impl FnMut(usize, usize) -> Vec2,
        mut f: impl FnMut(usize, usize, Vec2, Vec3),
    ) {
        let two_pi = 2.0 * std::f32::consts::PI;
        let sector = two_pi / self.azimuthal as f32;
        let fast = self.azimuthal >= 8;
        let inv_m = 1.0 / self.polar as f32;
        for k in 0..self.azimuthal {
            let (s0, c0) = ircache_math::sampling::sin_cos_turn(k as f32 / self.azimuthal as f32);
            for j in 0..self.polar {
                let u = jitter(j, k);
                let (sin_t, cos_t) = polar_sin_cos(j, u.x, self.polar, inv_m);
                let (sd, cd) = if fast {
                    ircache_math::sampling::sin_cos_quarter(u.y * sector)
                } else {
                    (u.y * sector).sin_cos()
                };
                let (sp, cp) = (s0 * cd + c0 * sd, c0 * cd - s0 * sd);
                f(j, k, u, Vec3::new(cp * sin_t, sp * sin_t, cos_t));
            }
        }
    }

    /// A multi-jittered pattern (Chiu, Shirley and Wang 1994) drawn from `rng`: within polar
    /// ring j the N cells take distinct ones of N fine sub-rings, and within sector k the M cells
    /// distinct ones of M fine sub-sectors, by random permutations; so the M·N samples are
    /// jittered in their cells and Latin in both angles.
    #[must_use]
    pub fn multijitter(&self, rng: &mut Rng) -> CellJitter {
        let (m, n) = (self.polar, self.azimuthal);
        // Fisher–Yates per ring and per sector (tables: a hashed permutation per cell cost 5 %
        // of a Sponza render). u16 holds them: at the largest divisions (10⁶, times a radiance
        // record's factor 8) N ≈ √(8π·10⁶) ≈ 5000.
        debug_assert!(m.max(n) <= usize::from(u16::MAX));
        let shuffled = |rows: usize, len: usize, rng: &mut Rng| {
            let mut v: Vec<u16> = (0..rows).flat_map(|_| 0..len as u16).collect();
            for row in v.chunks_mut(len) {
                for i in (1..len).rev() {
                    // Multiply-shift (Lemire): no division; its bias, below 2⁻²⁰ here, is
                    // far under the gather's noise.
                    let pick = (u64::from(rng.next_u32()) * (i as u64 + 1)) >> 32;
                    row.swap(i, pick as usize);
                }
            }
            v
        };
        CellJitter {
            strata: *self,
            fine: Some((shuffled(m, n, rng), shuffled(n, m, rng))),
        }
    }

    /// The local direction of the sample in cell (j, k) at jitter `u` (3.5).
    #[inline]
    #[must_use]
    pub fn direction(&self, j: usize, k: usize, u: Vec2) -> Vec3 {
        let (sin_t, cos_t) = polar_sin_cos(j, u.x, self.polar, 1.0 / self.polar as f32);
        let (sp, cp) =
            ircache_math::sampling::sin_cos_turn((k as f32 + u.y) / self.azimuthal as f32);
        Vec3::new(cp * sin_t, sp * sin_t, cos_t)
    }

    /// The cell `j * N + k` holding the local direction `local` (the inverse of
    /// [`Self::direction`]); `None` below the horizon.
    #[must_use]
    pub fn cell_of(&self, local: Vec3) -> Option<usize> {
        let len2 = local.length_squared();
        if !(local.z > 0.0 && len2 > 0.0) {
            return None;
        }
        let s2 = (1.0 - local.z * local.z / len2).max(0.0);
        let j = ((s2 * self.polar as f32) as usize).min(self.polar - 1);
        let phi = local
            .y
            .atan2(local.x)
            .rem_euclid(2.0 * std::f32::consts::PI);
        let k = ((phi * self.azimuthal as f32 / (2.0 * std::f32::consts::PI)) as usize)
            .min(self.azimuthal - 1);
        Some(j * self.azimuthal + k)
    }
}

/// sin θ and cos θ of the sample at jitter `u` < 1 in polar ring `j` of `m` (sin²θ = (j + u)/m).
/// cos²θ is computed as (m − j − u)/m, not 1 − sin²θ: in the last ring j + u rounds to m in
/// f32 when u is within an ulp of 1, which put the ray exactly on the horizon, where the gather
/// drops it (the furnace test's three-bounce deficit of 1.1e-5).
#[inline]
fn polar_sin_cos(j: usize, u: f32, m: usize, inv_m: f32) -> (f32, f32) {
    let sin2 = ((j as f32 + u) * inv_m).min(1.0);
    let cos2 = (((m - j) as f32 - u) * inv_m).max(0.0);
    (sin2.sqrt(), cos2.sqrt())
}

/// Where each cell's sample lies within it: plain jitter, or a multi-jittered pattern
/// ([`Stratification::multijitter`]).
#[derive(Clone, Debug)]
pub struct CellJitter {
    strata: Stratification,
    /// Multi-jittered: per ring j the fine sub-ring of each sector's cell (`[j * N + k]`), and
    /// per sector k the fine sub-sector of each ring's cell (`[k * M + j]`).
    fine: Option<(Vec<u16>, Vec<u16>)>,
}

impl CellJitter {
    /// Plain jitter: the uniform sample is the offset in its cell.
    #[must_use]
    pub fn plain(strata: Stratification) -> CellJitter {
        CellJitter { strata, fine: None }
    }

    /// The offset in cell (j, k) of the sample made from a uniform `u`.
    #[inline]
    #[must_use]
    pub fn jitter(&self, j: usize, k: usize, u: Vec2) -> Vec2 {
        let Some((ring, sector)) = &self.fine else {
            return u;
        };
        let (m, n) = (self.strata.polar, self.strata.azimuthal);
        Vec2::new(
            ((f32::from(ring[j * n + k]) + u.x) / n as f32).min(ONE_MINUS_EPSILON),
            ((f32::from(sector[k * m + j]) + u.y) / m as f32).min(ONE_MINUS_EPSILON),
        )
    }
}

/// The radiance and hit distance found in each cell, `[j * N + k]`. A ray that escaped has
/// distance `f32::INFINITY`.
#[derive(Clone, Debug, PartialEq)]
pub struct HemisphereSamples {
    /// The division into cells.
    pub strata: Stratification,
    /// Incoming radiance per cell.
    pub radiance: Vec<Rgb>,
    /// Distance to the surface seen per cell.
    pub distance: Vec<f32>,
    /// Per cell, the local direction of its sample and the unit normal of the surface it hit
    /// (local frame; zero when it hit nothing), for the Hessian by reprojection.
    pub hits: Vec<(Vec3, Vec3)>,
    /// Per cell, the environment's radiance where its rays escaped, kept apart from
    /// `radiance` where only radiance records hold it (`super::environment`); zero elsewhere.
    pub escaped: Vec<Rgb>,
}

/// Per-channel gradients in the local frame (z components are zero).
pub type LocalGradient = [Vec3; 3];

impl HemisphereSamples {
    /// Empty samples for `strata`.
    #[must_use]
    pub fn new(strata: Stratification) -> HemisphereSamples {
        HemisphereSamples {
            strata,
            radiance: vec![Rgb::ZERO; strata.cells()],
            distance: vec![f32::INFINITY; strata.cells()],
            hits: vec![(Vec3::ZERO, Vec3::ZERO); strata.cells()],
            escaped: vec![Rgb::ZERO; strata.cells()],
        }
    }

    /// The samples with the escaped environment radiance added to each cell's radiance (what
    /// a radiance record holding the environment projects); `None` when none was kept apart.
    #[must_use]
    pub fn with_escaped(&self) -> Option<HemisphereSamples> {
        if self.escaped.iter().all(|e| e.is_black()) {
            return None;
        }
        let mut all = self.clone();
        for (l, e) in all.radiance.iter_mut().zip(&self.escaped) {
            *l += *e;
        }
        Some(all)
    }

    #[inline]
    fn l(&self, j: usize, k: usize) -> [f64; 3] {
        let c = self.radiance[j * self.strata.azimuthal + k];
        [c.r as f64, c.g as f64, c.b as f64]
    }

    #[inline]
    fn r(&self, j: usize, k: usize) -> f64 {
        self.distance[j * self.strata.azimuthal + k] as f64
    }

    /// For each cell, how much its four neighbours (polar ±1, azimuthal ±1 with wrap-around)
    /// differ among themselves: the spread (max − min) of their luminances. Adaptive
    /// super-sampling (003 item 2) spends extra rays where this is large. The cell's own sample
    /// is left out on purpose: a choice made from the cell's own value would bias it (cells
    /// whose sample missed a small bright patch would keep their zero, the others regress to
    /// the mean: −23 % on Sponza, measured).
    #[must_use]
    pub fn neighbour_spread(&self) -> Vec<f32> {
        let (m, n) = (self.strata.polar, self.strata.azimuthal);
        let y: Vec<f32> = self.radiance.iter().map(|c| c.luminance()).collect();
        let mut out = vec![0.0; m * n];
        for j in 0..m {
            for k in 0..n {
                let mut lo = y[j * n + (k + 1) % n].min(y[j * n + (k + n - 1) % n]);
                let mut hi = y[j * n + (k + 1) % n].max(y[j * n + (k + n - 1) % n]);
                for jj in [j.wrapping_sub(1), j + 1] {
                    if jj < m {
                        lo = lo.min(y[jj * n + k]);
                        hi = hi.max(y[jj * n + k]);
                    }
                }
                out[j * n + k] = hi - lo;
            }
        }
        out
    }

    /// The cells to super-sample, largest neighbour spread first: the fewest (at most
    /// `max_cells`) whose refinement with three more rays each brings the irradiance's predicted
    /// relative standard error to `target` or below.
    ///
    /// The error model: E = π/(MN) Σ Lᵢ with one sample per cell, so Var(E)/E² = Σ σᵢ² / (Σ Yᵢ)²
    /// with σᵢ the spread of radiance within cell i, estimated from its neighbours'
    /// ([`Self::neighbour_spread`], a range, taken as σᵢ ≈ range/3 — the standard deviation of
    /// a range's two ends is range/2, of a uniform spread range/√12); four samples divide a
    /// cell's variance by four.
    #[must_use]
    pub fn cells_to_refine(&self, target: f32, max_cells: usize) -> Vec<usize> {
        let spread = self.neighbour_spread();
        let total: f64 = self.radiance.iter().map(|c| f64::from(c.luminance())).sum();
        if total <= 0.0 {
            return Vec::new();
        }
        let var = |i: usize| (f64::from(spread[i]) / 3.0).powi(2);
        let mut v: f64 = (0..spread.len()).map(var).sum();
        let mut order: Vec<usize> = (0..spread.len()).filter(|&i| spread[i] > 0.0).collect();
        // Largest spread first; ties by index, so the choice is deterministic.
        order.sort_by(|&a, &b| spread[b].total_cmp(&spread[a]).then(a.cmp(&b)));
        let goal = (f64::from(target) * total).powi(2);
        let mut n = 0;
        while n < order.len().min(max_cells) && v > goal {
            v -= 0.75 * var(order[n]);
            n += 1;
        }
        order.truncate(n);
        order
    }

    /// The relative variance of the irradiance estimate times the number of cells (so per
    /// ray), own samples included (a lone bright cell counts). Each cell's variance is taken
    /// from second differences with its neighbours, Yᵢ − (Yₗ + Yᵣ)/2 along the azimuth and,
    /// where both exist, along the polar angle: for independent cells of equal variance σ² its
    /// expected square is 1.5 σ², and the radiance's linear variation over the hemisphere
    /// cancels (plain differences would count it as noise). Var(E)/E² = Σ σᵢ² / (Σ Yᵢ)².
    #[must_use]
    pub fn relative_variance(&self) -> f32 {
        self.weighted_relative_variance(None)
    }

    /// [`Self::relative_variance`] of a weighted estimate Σ w_c Y_c (weights of mean 1, one per
    /// cell; `None`: all 1): Σ w_c² σ_c² / (Σ w_c Y_c)² times the number of cells. A radiance
    /// record's glossy estimate weighs its cells by the lobe.
    #[must_use]
    pub fn weighted_relative_variance(&self, weights: Option<&[f64]>) -> f32 {
        let (m, n) = (self.strata.polar, self.strata.azimuthal);
        let y: Vec<f64> = self
            .radiance
            .iter()
            .map(|c| f64::from(c.luminance()))
            .collect();
        let w = |i: usize| weights.map_or(1.0, |w| w[i]);
        let total: f64 = y.iter().enumerate().map(|(i, v)| w(i) * v).sum();
        if total <= 0.0 || n < 3 {
            return 0.0;
        }
        let mut v = 0.0f64;
        for j in 0..m {
            for k in 0..n {
                let c = y[j * n + k];
                let az = c - 0.5 * (y[j * n + (k + 1) % n] + y[j * n + (k + n - 1) % n]);
                let (mut sum, mut count) = (az * az, 1.0);
                if j > 0 && j + 1 < m {
                    let po = c - 0.5 * (y[(j - 1) * n + k] + y[(j + 1) * n + k]);
                    sum += po * po;
                    count += 1.0;
                }
                v += w(j * n + k).powi(2) * sum / (1.5 * count);
            }
        }
        (v / (total * total) * (m * n) as f64) as f32
    }

    /// Irradiance, π/(MN) Σ L (3.4).
    #[must_use]
    pub fn irradiance(&self) -> Rgb {
        let mut s = [0.0f64; 3];
        for c in &self.radiance {
            s[0] += c.r as f64;
            s[1] += c.g as f64;
            s[2] += c.b as f64;
        }
        let f = PI / self.strata.cells() as f64;
        Rgb::new((s[0] * f) as f32, (s[1] * f) as f32, (s[2] * f) as f32)
    }

    /// Harmonic mean distance MN / Σ 1/r (3.8); infinite when every ray escaped.
    #[must_use]
    pub fn harmonic_mean_distance(&self) -> f32 {
        let inv: f64 = self
            .distance
            .iter()
            .map(|&r| {
                if r.is_finite() && r > 0.0 {
                    1.0 / r as f64
                } else {
                    0.0
                }
            })
            .sum();
        if inv > 0.0 {
            (self.strata.cells() as f64 / inv) as f32
        } else {
            f32::INFINITY
        }
    }

    /// Rotational gradient (3.29), signed so that E(n) ≈ E + (n_i × n)·∇_r E. Each cell's
    /// weight is the mean of tan θ and of the azimuthal direction over the cell, not their
    /// values at its centre: a cell is uniform in u = sin²θ, where tan θ = √(u/(1−u)) has the
    /// antiderivative asin √u − √(u(1−u)); at the horizon ring the centre value is 1/√2 of
    /// the mean, which took 6 % off the gradient at 512 divisions (a closed-form test found it).
    #[must_use]
    pub fn rotational_gradient(&self) -> LocalGradient {
        let (m, n) = (self.strata.polar, self.strata.azimuthal);
        let anti = |u: f64| u.sqrt().asin() - (u * (1.0 - u)).max(0.0).sqrt();
        let tan_mean: Vec<f64> = (0..m)
            .map(|j| (anti((j + 1) as f64 / m as f64) - anti(j as f64 / m as f64)) * m as f64)
            .collect();
        let dphi = 2.0 * PI / n as f64;
        let mut g = [[0.0f64; 2]; 3];
        for k in 0..n {
            let (p0, p1) = (k as f64 * dphi, (k + 1) as f64 * dphi);
            // Means of −sin φ and cos φ over the sector.
            let v = [(p1.cos() - p0.cos()) / dphi, (p1.sin() - p0.sin()) / dphi];
            let mut sum = [0.0f64; 3];
            for (j, &tan) in tan_mean.iter().enumerate() {
                let l = self.l(j, k);
                for c in 0..3 {
                    sum[c] += l[c] * tan;
                }
            }
            for c in 0..3 {
                g[c][0] += v[0] * sum[c];
                g[c][1] += v[1] * sum[c];
            }
        }
        let f = PI / (m * n) as f64;
        g.map(|gc| Vec3::new((gc[0] * f) as f32, (gc[1] * f) as f32, 0.0))
    }

    /// Translational gradient, Křivánek et al.'s formulation corrected (000 eq. 3.47 with
    /// ERRATA 2–4): polar walls weighted by the cosine at the wall, azimuthal walls by the
    /// cosine at the cell's mid angle, each wall moving with the closer of its two cells.
    #[must_use]
    pub fn translational_gradient_krivanek(&self) -> LocalGradient {
        self.translational_gradient_with(|w, j| {
            let theta_c = 0.5 * (w.theta[j] + w.theta[j + 1]);
            (w.cos[j] - w.cos[j + 1]) * theta_c.cos() / theta_c.sin()
        })
    }

    /// Translational gradient in Ward and Heckbert's original form (000 eq. 3.48): the motion of
    /// the projected cell boundaries.
    #[must_use]
    pub fn translational_gradient_ward_heckbert(&self) -> LocalGradient {
        self.translational_gradient_with(ward_heckbert_azimuthal)
    }

    /// The wall sum of both formulations on the cells' radiance differences.
    fn translational_gradient_with(
        &self,
        azimuthal: impl Fn(&PolarWalls, usize) -> f64,
    ) -> LocalGradient {
        let n = self.strata.azimuthal;
        wall_sum(
            self.strata,
            |c| self.r(c / n, c % n),
            azimuthal,
            |hi, lo| {
                let (a, b) = (self.l(hi / n, hi % n), self.l(lo / n, lo % n));
                [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
            },
        )
    }
}

/// Ward and Heckbert's azimuthal wall weight (000 eq. 3.48): sin θ_{j+} − sin θ_{j−}.
pub(crate) fn ward_heckbert_azimuthal(w: &PolarWalls, j: usize) -> f64 {
    w.sin[j + 1] - w.sin[j]
}

/// The sum over cell walls that both formulations share. Polar walls (between rings j−1 and j,
/// at θ_{j−}: 3.42, ERRATA 3) weigh (2π/N) sin θ cos² θ in both; azimuthal walls (between
/// sectors k−1 and k: 3.46, ERRATA 2 and 4) weigh `azimuthal(walls, j)`, which is where 3.47 and
/// 3.48 differ in form. Each wall moves with the closer of its two cells (`distance` of cell
/// `j·N + k`); `difference(hi, lo)` is what changes across the wall from cell `lo` to cell `hi`
/// (the higher index): the radiance difference for surfaces (002 eq. 11), the medium's
/// visible-shell integral for the visibility gradient (002 eq. 24).
pub(crate) fn wall_sum(
    strata: Stratification,
    distance: impl Fn(usize) -> f64,
    azimuthal: impl Fn(&PolarWalls, usize) -> f64,
    difference: impl Fn(usize, usize) -> [f64; 3],
) -> LocalGradient {
    let (m, n) = (strata.polar, strata.azimuthal);
    let walls = PolarWalls::new(m);
    let dphi = 2.0 * PI / n as f64;
    let mut g = [[0.0f64; 2]; 3];
    for k in 0..n {
        let phi_c = (k as f64 + 0.5) * dphi;
        let u = [phi_c.cos(), phi_c.sin()];
        let phi_w = k as f64 * dphi;
        let v = [-phi_w.sin(), phi_w.cos()];
        let km = (k + n - 1) % n;
        let (mut su, mut sv) = ([0.0f64; 3], [0.0f64; 3]);
        for j in 0..m {
            let cell = j * n + k;
            if j > 0 {
                let (s, c) = (walls.sin[j], walls.cos[j]);
                let below = (j - 1) * n + k;
                let w = dphi * s * c * c / distance(cell).min(distance(below));
                if w.is_finite() && w != 0.0 {
                    let d = difference(cell, below);
                    for ch in 0..3 {
                        su[ch] += w * d[ch];
                    }
                }
            }
            let beside = j * n + km;
            let w = azimuthal(&walls, j) / distance(cell).min(distance(beside));
            if w.is_finite() && w != 0.0 {
                let d = difference(cell, beside);
                for ch in 0..3 {
                    sv[ch] += w * d[ch];
                }
            }
        }
        for ch in 0..3 {
            g[ch][0] += u[0] * su[ch] + v[0] * sv[ch];
            g[ch][1] += u[1] * su[ch] + v[1] * sv[ch];
        }
    }
    g.map(|gc| Vec3::new(gc[0] as f32, gc[1] as f32, 0.0))
}

impl HemisphereSamples {
    /// Irradiance (luminance) at the point moved by `(dx, dy)` in the tangent plane with the
    /// surfaces the samples hit held fixed: each sample keeps its radiance, and its cell's
    /// projected solid angle π/(MN) scales by (cos θ′/cos θ)(r/r′)²(cos α′/cos α), α the angle
    /// at the surface hit. Visibility changes are not modelled (as in Radiance's ambHessian).
    #[must_use]
    pub fn reprojected_irradiance(&self, dx: f64, dy: f64) -> f64 {
        let mut e = 0.0f64;
        for (i, &(w, n)) in self.hits.iter().enumerate() {
            let r = f64::from(self.distance[i]);
            if !r.is_finite() || n == Vec3::ZERO {
                continue;
            }
            let (w, n) = (w.as_dvec3(), n.as_dvec3());
            let p = w * r; // the hit point, relative to the original position
            let q = p - Vec3::new(dx as f32, dy as f32, 0.0).as_dvec3();
            let r2 = q.length();
            if r2 <= 0.0 {
                continue;
            }
            let w2 = q / r2;
            if w2.z <= 0.0 || w.z <= 0.0 {
                continue;
            }
            let cos_a = n.dot(w).abs().max(0.05);
            let cos_a2 = n.dot(w2).abs();
            e += f64::from(self.radiance[i].luminance())
                * (w2.z / w.z)
                * (r / r2).powi(2)
                * (cos_a2 / cos_a);
        }
        e * PI / self.strata.cells() as f64
    }

    /// The 2×2 translational Hessian (xx, xy, yy) of the irradiance's luminance in the local
    /// frame: the second derivatives of [`Self::reprojected_irradiance`] at the record, in one
    /// pass. A sample at unit direction w, distance r, hit normal n contributes
    /// L q_z |n·q| / (cos α |q|⁴) r² / w_z with q = r w − δ; twice differentiated at δ = 0,
    /// L sgn(n·w) / (r² cos α) · (24 (n·w) w_a w_b − 4 (n_a w_b + n_b w_a) − 4 (n·w) δ_ab)
    /// (tested against central differences of the reprojection).
    #[must_use]
    pub fn translational_hessian(&self) -> [f64; 3] {
        let mut h = [0.0f64; 3];
        for (i, &(w, n)) in self.hits.iter().enumerate() {
            let r = f64::from(self.distance[i]);
            if !r.is_finite() || n == Vec3::ZERO || w.z <= 0.0 || r <= 0.0 {
                continue;
            }
            let (w, n) = (w.as_dvec3(), n.as_dvec3());
            let nw = n.dot(w);
            let cos_a = nw.abs().max(0.05);
            let l = f64::from(self.radiance[i].luminance()) * nw.signum() / (r * r * cos_a);
            h[0] += l * (24.0 * nw * w.x * w.x - 8.0 * n.x * w.x - 4.0 * nw);
            h[1] += l * (24.0 * nw * w.x * w.y - 4.0 * (n.x * w.y + n.y * w.x));
            h[2] += l * (24.0 * nw * w.y * w.y - 8.0 * n.y * w.y - 4.0 * nw);
        }
        h.map(|v| v * PI / self.strata.cells() as f64)
    }
}

/// The largest eigenvalue magnitude of the symmetric 2×2 matrix (xx, xy, yy).
#[must_use]
pub fn largest_eigenvalue(h: [f64; 3]) -> f64 {
    let [a, b, c] = h;
    let mean = 0.5 * (a + c);
    let d = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    (mean + d).abs().max((mean - d).abs())
}

/// Angles of the polar cell boundaries: sin²θ_j = j/M for j = 0..=M.
pub(crate) struct PolarWalls {
    theta: Vec<f64>,
    sin: Vec<f64>,
    cos: Vec<f64>,
}

impl PolarWalls {
    fn new(m: usize) -> PolarWalls {
        let sin: Vec<f64> = (0..=m).map(|j| (j as f64 / m as f64).sqrt()).collect();
        let cos: Vec<f64> = (0..=m)
            .map(|j| (1.0 - j as f64 / m as f64).max(0.0).sqrt())
            .collect();
        let theta = sin.iter().zip(&cos).map(|(s, c)| s.atan2(*c)).collect();
        PolarWalls { theta, sin, cos }
    }
}

/// A local-frame gradient expressed in world space with tangents `s` and `t`.
#[must_use]
pub fn to_world(g: &LocalGradient, s: Vec3, t: Vec3) -> [Vec3; 3] {
    g.map(|v| s * v.x + t * v.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_gather_direction_lies_on_the_horizon() {
        // The largest jitter below 1 in the last ring: sin²θ = (M − 1 + u)/M rounds to 1 in f32,
        // which put the ray on the horizon before cos²θ was computed as (M − j − u)/M. Both
        // routes to a direction must stay above it, and keep unit length.
        let u = Vec2::new(ircache_math::sampling::ONE_MINUS_EPSILON, 0.5);
        for divisions in [64, 300, 1024, 4096, 100_000] {
            let strata = Stratification::from_divisions(divisions);
            let (m, n) = (strata.polar, strata.azimuthal);
            let d = strata.direction(m - 1, 0, u);
            assert!(d.z > 0.0, "{divisions} divisions: {d:?}");
            assert!((d.length() - 1.0).abs() < 1e-6);
            let mut lowest = f32::INFINITY;
            strata.for_each_direction(|_, _| u, |_, _, _, d| lowest = lowest.min(d.z));
            assert!(lowest > 0.0, "{divisions} divisions ({m} × {n})");
            assert_eq!(strata.cell_of(d), Some((m - 1) * n));
        }
    }

    #[test]
    fn multijittered_gathers_are_jittered_in_cells_and_latin_in_both_angles() {
        // Each sample in its own cell, and over all cells exactly one in each of the M·N fine
        // sub-rings (sin²θ) and each of the M·N fine sub-sectors (φ); for several seeds and a
        // non-square grid.
        for (divisions, seed) in [(1024, 1u64), (300, 7), (64, 11)] {
            let strata = Stratification::from_divisions(divisions);
            let (m, n) = (strata.polar, strata.azimuthal);
            let mut rng = Rng::keyed(seed, &[]);
            let layout = strata.multijitter(&mut rng);
            // The fine sub-ring (sin²θ) and sub-sector (φ) of M·N each holding `d`.
            let fine = |x: f64| ((x * (m * n) as f64) as usize).min(m * n - 1);
            let sub_ring = |d: Vec3| fine(f64::from(1.0 - d.z * d.z));
            let sub_sector = |d: Vec3| {
                fine(f64::from(d.y).atan2(f64::from(d.x)).rem_euclid(2.0 * PI) / (2.0 * PI))
            };
            let (mut rings, mut sectors) = (vec![0u32; m * n], vec![0u32; m * n]);
            strata.for_each_direction(
                |j, k| layout.jitter(j, k, rng.next_2d()),
                |j, k, _, d| {
                    assert_eq!(strata.cell_of(d), Some(j * n + k), "cell ({j}, {k})");
                    rings[sub_ring(d)] += 1;
                    sectors[sub_sector(d)] += 1;
                },
            );
            // f32 directions may land a hair across a fine boundary: allow a handful.
            let off = |v: &[u32]| v.iter().filter(|&&c| c != 1).count();
            assert!(
                off(&rings) <= 4,
                "{divisions}: {} sub-rings not hit once",
                off(&rings)
            );
            assert!(
                off(&sectors) <= 4,
                "{divisions}: {} sub-sectors not hit once",
                off(&sectors)
            );
            // Plain jitter breaks the Latin property (so the check above can fail).
            let (mut plain, mut rng) = (vec![0u32; m * n], Rng::keyed(seed, &[]));
            strata.for_each_direction(|_, _| rng.next_2d(), |_, _, _, d| plain[sub_ring(d)] += 1);
            assert!(
                off(&plain) > m * n / 8,
                "{divisions}: plain jitter looked Latin"
            );
        }
    }

    #[test]
    fn the_hessian_is_the_second_difference_of_the_reprojection() {
        // Hits on a tilted plane above the record and a wall to one side, with radiance varying
        // by cell: the analytic second derivatives against central differences of the
        // reprojected irradiance.
        let strata = Stratification::from_divisions(256);
        let mut h = HemisphereSamples::new(strata);
        let mut rng = Rng::keyed(9, &[]);
        strata.for_each_direction(
            |_, _| rng.next_2d(),
            |j, k, _, w| {
                let i = j * strata.azimuthal + k;
                let (n, r) = if w.x > 0.6 {
                    (Vec3::new(-1.0, 0.0, 0.0), 0.8 / w.x)
                } else {
                    let n = Vec3::new(0.2, -0.1, -1.0).normalize();
                    (n, 1.5 / -n.dot(w))
                };
                h.radiance[i] = Rgb::splat(0.5 + (i % 7) as f32 * 0.3);
                h.distance[i] = r;
                h.hits[i] = (w, n);
            },
        );
        let a = h.translational_hessian();
        let step = 1e-3;
        let e = |x, y| h.reprojected_irradiance(x, y);
        let e0 = e(0.0, 0.0);
        let fd = [
            (e(step, 0.0) - 2.0 * e0 + e(-step, 0.0)) / (step * step),
            (e(step, step) - e(step, -step) - e(-step, step) + e(-step, -step))
                / (4.0 * step * step),
            (e(0.0, step) - 2.0 * e0 + e(0.0, -step)) / (step * step),
        ];
        let scale = fd.iter().map(|v| v.abs()).fold(0.0, f64::max);
        for c in 0..3 {
            assert!((a[c] - fd[c]).abs() < 1e-3 * scale, "{c}: {a:?} vs {fd:?}");
        }
    }

    fn random_samples(strata: Stratification, seed: u64) -> HemisphereSamples {
        let mut rng = Rng::keyed(seed, &[]);
        let mut h = HemisphereSamples::new(strata);
        for i in 0..strata.cells() {
            h.radiance[i] = Rgb::new(rng.next_f32(), 2.0 * rng.next_f32(), 0.5 * rng.next_f32());
            h.distance[i] = if rng.next_f32() < 0.1 {
                f32::INFINITY
            } else {
                0.01 + 10.0 * rng.next_f32()
            };
        }
        h
    }

    /// iid cell noise: the variance per ray of an estimate weighing a quarter of the cells
    /// (weights 4 there, 0 elsewhere: mean 1) is four times the plain one's, and uniform weights
    /// give the plain figure.
    #[test]
    fn every_cell_holds_the_directions_drawn_in_it() {
        for strata in [
            Stratification::from_divisions(512),
            Stratification::from_divisions(37),
        ] {
            for j in 0..strata.polar {
                for k in 0..strata.azimuthal {
                    for u in [
                        Vec2::new(0.01, 0.02),
                        Vec2::new(0.5, 0.5),
                        Vec2::new(0.98, 0.97),
                    ] {
                        let d = strata.direction(j, k, u);
                        assert_eq!(strata.cell_of(d * 3.0), Some(j * strata.azimuthal + k));
                    }
                }
            }
            assert_eq!(strata.cell_of(Vec3::new(0.3, 0.2, -0.1)), None);
        }
    }

    #[test]
    fn weighted_variance_grows_as_the_weights_narrow() {
        let strata = Stratification::from_divisions(4096);
        let h = random_samples(strata, 17);
        let plain = h.relative_variance();
        let ones = vec![1.0; strata.cells()];
        assert!((h.weighted_relative_variance(Some(&ones)) - plain).abs() < 1e-6 * plain);
        // A quarter of the sectors, all rings.
        let quarter: Vec<f64> = (0..strata.cells())
            .map(|i| {
                if (i % strata.azimuthal) * 4 < strata.azimuthal {
                    4.0
                } else {
                    0.0
                }
            })
            .collect();
        let mean = quarter.iter().sum::<f64>() / quarter.len() as f64;
        let quarter: Vec<f64> = quarter.iter().map(|w| w / mean).collect();
        let ratio = h.weighted_relative_variance(Some(&quarter)) / plain;
        assert!((ratio - 4.0).abs() < 0.6, "ratio {ratio}");
    }

    #[test]
    fn divisions_give_azimuthal_about_pi_times_polar() {
        let s = Stratification::from_divisions(1024);
        assert_eq!((s.polar, s.azimuthal), (18, 57));
        let s = Stratification::from_divisions(512);
        assert!((s.azimuthal as f64 / s.polar as f64 - PI).abs() < 0.5);
    }

    #[test]
    fn krivanek_equals_ward_heckbert() {
        // 000 §3.6.3: eqs. 3.47 and 3.48 are analytically equal.
        for (d, seed) in [(64, 1), (512, 2), (1024, 3), (4096, 4)] {
            let h = random_samples(Stratification::from_divisions(d), seed);
            let a = h.translational_gradient_krivanek();
            let b = h.translational_gradient_ward_heckbert();
            for c in 0..3 {
                let scale = a[c].length().max(b[c].length());
                assert!(scale > 0.0);
                assert!(
                    (a[c] - b[c]).length() <= 1e-6 * scale,
                    "{d} divisions, channel {c}: {} vs {}",
                    a[c],
                    b[c]
                );
            }
        }
    }

    #[test]
    fn uniform_radiance_has_no_gradient() {
        let strata = Stratification::from_divisions(512);
        let mut h = HemisphereSamples::new(strata);
        h.radiance.fill(Rgb::splat(2.0));
        h.distance.fill(3.0);
        let e = h.irradiance();
        assert!((e.r - 2.0 * std::f32::consts::PI).abs() < 1e-5);
        assert!((h.harmonic_mean_distance() - 3.0).abs() < 1e-5);
        for g in h
            .rotational_gradient()
            .iter()
            .chain(&h.translational_gradient_krivanek())
        {
            assert!(g.length() < 1e-5, "{g}");
        }
    }
}
