//! Statistical test helpers for sampling routines: a χ² goodness-of-fit test of a direction
//! sampler against its claimed density, in the manner of Mitsuba 3's `ChiSquareTest`
//! (`mitsuba/python/chi2.py`) and pbrt-v3's `chi2test`.
//!
//! This module is compiled in normal builds (not only under `#[cfg(test)]`) so that unit tests of
//! every module and the integration tests in `crates/render/tests/` can use it. It is not part of
//! the renderer proper and is hidden from the documentation.
//!
//! # How the test works
//!
//! 1. The domain (the hemisphere `z ≥ 0` or the whole sphere) is cut into bins that are uniform in
//!    `(cos θ, φ)` (`cos θ = z`, `φ = atan2(y, x)`); since `dω = d(cos θ) dφ`, every bin of a
//!    hemisphere grid has the same solid angle.
//! 2. The claimed density `pdf(ω)` (per unit solid angle) is integrated over each bin with nested
//!    adaptive Simpson quadrature in `(cos θ, φ)` (no Jacobian needed), giving the expected
//!    probability of each bin. One extra "no sample" cell receives `1 − ∫ pdf`: the probability that
//!    the sampler returns `None` (a failed sample or a delta lobe that the test does not bin).
//! 3. `samples` draws are made with a deterministic [`Rng`]; each lands in a bin or in the
//!    "no sample" cell.
//! 4. Cells with an expected count below `min_expected` (5) are pooled, in increasing order of
//!    expected count, until the pool reaches `min_expected`; then Pearson's χ² statistic and its
//!    p-value (upper regularised incomplete gamma function, `dof = cells − 1`) are computed.
//! 5. The null hypothesis ("the sampler draws from `pdf`") is rejected when the p-value is below
//!    the Šidák-corrected significance level `1 − (1 − α)^(1/n)` for `n` tests run together
//!    ([`sidak_level`]). A sample that lands in a bin whose expected count is (numerically) zero
//!    fails the test outright, as in Mitsuba.
//!
//! Besides the distribution, [`ChiSquareTest::run`] also checks every sample's *own* pdf (the
//! second element returned by the sampler) against `pdf(ω)`: they must agree to a relative
//! tolerance, otherwise MIS weights would be wrong. Return a pdf of `0.0` (or negative) to skip
//! this check for a sample. Samples that leave the domain (for example `z < 0` in a hemisphere
//! test) are counted as errors.
//!
//! # Example
//!
//! ```
//! use ircache_math::{sampling, Vec3};
//! use ircache_render::testing::ChiSquareTest;
//!
//! let report = ChiSquareTest::hemisphere().with_samples(200_000).run(
//!     |u, _u_lobe| {
//!         let w = sampling::square_to_cosine_hemisphere(u);
//!         Some((w, sampling::cosine_hemisphere_pdf(w)))
//!     },
//!     |w: Vec3| sampling::cosine_hemisphere_pdf(w),
//! );
//! report.assert_ok(0.01, 1, "cosine hemisphere");
//! ```
//!
//! For a light, sample directions as seen from a fixed reference point and pass the solid-angle
//! pdf of a direction (0 for directions that miss the light), with [`ChiSquareTest::sphere`].

#![doc(hidden)]

use ircache_math::{Rng, Vec2, Vec3};
use std::f64::consts::PI;
use std::fmt::Write as _;

/// Which set of directions is binned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// `z ≥ 0` (reflection-only BSDFs). `cos θ` bins cover `[0, 1]`.
    Hemisphere,
    /// All directions (transmission, lights). `cos θ` bins cover `[−1, 1]`.
    Sphere,
}

/// Parameters of a χ² test. Build with [`ChiSquareTest::hemisphere`] or
/// [`ChiSquareTest::sphere`] and adjust with the `with_*` methods.
#[derive(Clone, Debug)]
pub struct ChiSquareTest {
    /// The binned domain.
    pub domain: Domain,
    /// Bins along `cos θ` (over `[0, 1]` or `[−1, 1]`).
    pub theta_bins: usize,
    /// Bins along `φ ∈ [0, 2π)`.
    pub phi_bins: usize,
    /// Number of samples drawn.
    pub samples: usize,
    /// Seed of the [`Rng`] that draws `(u, u_lobe)`.
    pub seed: u64,
    /// Cells with fewer expected samples than this are pooled (5, the usual rule).
    pub min_expected: f64,
    /// Absolute error target of the quadrature of each bin, in units of probability.
    pub integration_tol: f64,
    /// Relative tolerance of the sampler's pdf against `pdf(ω)`.
    pub pdf_rel_tol: f32,
}

impl ChiSquareTest {
    /// 10 × 20 bins over the hemisphere, 10⁶ samples.
    #[must_use]
    pub fn hemisphere() -> Self {
        ChiSquareTest {
            domain: Domain::Hemisphere,
            theta_bins: 10,
            phi_bins: 20,
            samples: 1_000_000,
            seed: 0x5eed,
            min_expected: 5.0,
            integration_tol: 1e-8,
            pdf_rel_tol: 2e-3,
        }
    }

    /// 20 × 20 bins over the whole sphere, 10⁶ samples.
    #[must_use]
    pub fn sphere() -> Self {
        ChiSquareTest {
            domain: Domain::Sphere,
            theta_bins: 20,
            ..Self::hemisphere()
        }
    }

    /// Sets the number of samples.
    #[must_use]
    pub fn with_samples(mut self, n: usize) -> Self {
        self.samples = n;
        self
    }

    /// Sets the bin counts along `cos θ` and `φ`.
    #[must_use]
    pub fn with_bins(mut self, theta_bins: usize, phi_bins: usize) -> Self {
        self.theta_bins = theta_bins;
        self.phi_bins = phi_bins;
        self
    }

    /// Sets the seed.
    #[must_use]
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    fn z_range(&self) -> (f64, f64) {
        match self.domain {
            Domain::Hemisphere => (0.0, 1.0),
            Domain::Sphere => (-1.0, 1.0),
        }
    }

    /// The bin index of a unit direction, or `None` when it lies outside the domain.
    fn bin_of(&self, w: Vec3) -> Option<usize> {
        let (z0, z1) = self.z_range();
        let z = f64::from(w.z).clamp(-1.0, 1.0);
        if z < z0 {
            return None;
        }
        let zi = (((z - z0) / (z1 - z0)) * self.theta_bins as f64) as usize;
        let zi = zi.min(self.theta_bins - 1);
        let mut phi = f64::from(w.y).atan2(f64::from(w.x));
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let pi = ((phi / (2.0 * PI)) * self.phi_bins as f64) as usize;
        let pi = pi.min(self.phi_bins - 1);
        Some(zi * self.phi_bins + pi)
    }

    /// Integrates `pdf` over every bin (row-major: `cos θ` bin, then `φ` bin).
    #[must_use]
    pub fn integrate_bins(&self, pdf: &impl Fn(Vec3) -> f32) -> Vec<f64> {
        let (z0, z1) = self.z_range();
        let dz = (z1 - z0) / self.theta_bins as f64;
        let dphi = 2.0 * PI / self.phi_bins as f64;
        let tol = self.integration_tol;
        let f = |z: f64, phi: f64| -> f64 {
            let r = (1.0 - z * z).max(0.0).sqrt();
            let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            let p = f64::from(pdf(w));
            if p.is_finite() {
                p.max(0.0)
            } else {
                0.0
            }
        };
        let mut out = Vec::with_capacity(self.theta_bins * self.phi_bins);
        for i in 0..self.theta_bins {
            let (za, zb) = (z0 + i as f64 * dz, z0 + (i + 1) as f64 * dz);
            for j in 0..self.phi_bins {
                let (pa, pb) = (j as f64 * dphi, (j + 1) as f64 * dphi);
                let inner = |z: f64| adaptive_simpson(&|phi| f(z, phi), pa, pb, tol / dz, 12);
                out.push(adaptive_simpson(&inner, za, zb, tol, 12).max(0.0));
            }
        }
        out
    }

    /// Runs the test. `sample(u, u_lobe)` maps uniform numbers to a unit direction and the
    /// sampler's own pdf for it (≤ 0 to skip the pdf check), or `None` for no (binned) sample;
    /// `pdf(ω)` is the claimed solid-angle density.
    pub fn run<S, P>(&self, mut sample: S, pdf: P) -> ChiSquareReport
    where
        S: FnMut(Vec2, f32) -> Option<(Vec3, f32)>,
        P: Fn(Vec3) -> f32,
    {
        let nbins = self.theta_bins * self.phi_bins;
        let probs = self.integrate_bins(&pdf);
        let pdf_integral: f64 = probs.iter().sum();
        let n = self.samples as f64;
        // Cell `nbins` is "no sample".
        let mut expected: Vec<f64> = probs.iter().map(|p| p * n).collect();
        expected.push(((1.0 - pdf_integral) * n).max(0.0));
        let mut observed = vec![0.0f64; nbins + 1];

        let mut rng = Rng::new(self.seed, 0xC41_5E7);
        let mut outside = 0usize;
        let mut non_finite = 0usize;
        let mut pdf_mismatches = 0usize;
        let mut worst_pdf_mismatch: Option<(Vec3, f32, f32)> = None;
        for _ in 0..self.samples {
            let u_lobe = rng.next_f32();
            let u = rng.next_2d();
            match sample(u, u_lobe) {
                None => observed[nbins] += 1.0,
                Some((w, p)) => {
                    if !w.is_finite() || !p.is_finite() || (w.length() - 1.0).abs() > 1e-3 {
                        non_finite += 1;
                        continue;
                    }
                    let Some(b) = self.bin_of(w) else {
                        outside += 1;
                        continue;
                    };
                    observed[b] += 1.0;
                    if p > 0.0 {
                        let q = pdf(w);
                        let err = (p - q).abs();
                        if err > self.pdf_rel_tol * p.max(q) + 1e-6 {
                            pdf_mismatches += 1;
                            let worse = match worst_pdf_mismatch {
                                None => true,
                                Some((_, a, b)) => err > (a - b).abs(),
                            };
                            if worse {
                                worst_pdf_mismatch = Some((w, p, q));
                            }
                        }
                    }
                }
            }
        }

        // A sample in a cell that should receive (essentially) none is a failure by itself.
        let zero_expected_hits: f64 = observed
            .iter()
            .zip(&expected)
            .filter(|(_, &e)| e < 1e-6)
            .map(|(&o, _)| o)
            .sum();

        let (chi2, dof) = pooled_chi2(&observed, &expected, self.min_expected);
        let p_value = if dof == 0 {
            1.0
        } else {
            chi2_sf(chi2, dof as f64)
        };
        ChiSquareReport {
            theta_bins: self.theta_bins,
            phi_bins: self.phi_bins,
            samples: self.samples,
            chi2,
            dof,
            p_value,
            pdf_integral,
            observed,
            expected,
            outside,
            non_finite,
            zero_expected_hits: zero_expected_hits as usize,
            pdf_mismatches,
            worst_pdf_mismatch,
        }
    }
}

/// Pearson's χ² with pooling of cells whose expected count is below `min_expected`.
/// Returns `(χ², degrees of freedom)`.
#[must_use]
pub fn pooled_chi2(observed: &[f64], expected: &[f64], min_expected: f64) -> (f64, usize) {
    let mut idx: Vec<usize> = (0..expected.len()).collect();
    idx.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let mut chi2 = 0.0;
    let mut cells = 0usize;
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for &i in &idx {
        let (o, e) = (observed[i], expected[i]);
        if e <= 0.0 && o == 0.0 {
            continue;
        }
        if pool_e > 0.0 || pool_o > 0.0 || e < min_expected {
            pool_o += o;
            pool_e += e;
            if pool_e >= min_expected {
                chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
                cells += 1;
                pool_o = 0.0;
                pool_e = 0.0;
            }
        } else {
            chi2 += (o - e) * (o - e) / e;
            cells += 1;
        }
    }
    if pool_e > 0.0 || pool_o > 0.0 {
        // A pool that never reached `min_expected` (everything else is tiny): keep it as a cell.
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e.max(1e-300);
        cells += 1;
    }
    (chi2, cells.saturating_sub(1))
}

/// The outcome of [`ChiSquareTest::run`].
#[derive(Clone, Debug)]
pub struct ChiSquareReport {
    /// Bins along `cos θ`.
    pub theta_bins: usize,
    /// Bins along `φ`.
    pub phi_bins: usize,
    /// Samples drawn.
    pub samples: usize,
    /// Pearson's statistic after pooling.
    pub chi2: f64,
    /// Degrees of freedom (pooled cells − 1).
    pub dof: usize,
    /// Probability of a statistic at least this large under the null hypothesis.
    pub p_value: f64,
    /// `∫ pdf` over the domain (numerical).
    pub pdf_integral: f64,
    /// Observed counts per bin; the last entry counts `None` samples.
    pub observed: Vec<f64>,
    /// Expected counts per bin; the last entry is `(1 − ∫ pdf) · samples`.
    pub expected: Vec<f64>,
    /// Samples outside the domain.
    pub outside: usize,
    /// Samples with a non-finite or non-unit direction or a non-finite pdf.
    pub non_finite: usize,
    /// Samples that landed in cells with (numerically) zero expected count.
    pub zero_expected_hits: usize,
    /// Samples whose own pdf disagreed with `pdf(ω)`.
    pub pdf_mismatches: usize,
    /// The worst such disagreement: `(ω, sampler's pdf, pdf(ω))`.
    pub worst_pdf_mismatch: Option<(Vec3, f32, f32)>,
}

impl ChiSquareReport {
    /// Whether the sampler passes at significance `alpha` corrected for `num_tests` tests, and
    /// every sample was valid and had a consistent pdf.
    #[must_use]
    pub fn passes(&self, alpha: f64, num_tests: usize) -> bool {
        self.failure(alpha, num_tests).is_none()
    }

    /// Why the test fails, or `None`.
    #[must_use]
    pub fn failure(&self, alpha: f64, num_tests: usize) -> Option<String> {
        let level = sidak_level(alpha, num_tests);
        if self.outside > 0 {
            return Some(format!("{} samples outside the domain", self.outside));
        }
        if self.non_finite > 0 {
            return Some(format!(
                "{} non-finite or non-unit samples",
                self.non_finite
            ));
        }
        if self.zero_expected_hits > 0 {
            return Some(format!(
                "{} samples in cells of zero expected count",
                self.zero_expected_hits
            ));
        }
        // A handful of f32 round-off disagreements at grazing angles are tolerated.
        if self.pdf_mismatches as f64 > 1e-4 * self.samples as f64 {
            return Some(format!(
                "{} samples whose pdf disagrees with pdf(ω); worst (ω, sampled, pdf(ω)) = {:?}",
                self.pdf_mismatches, self.worst_pdf_mismatch
            ));
        }
        if self.p_value.is_nan() || self.p_value < level {
            return Some(format!(
                "χ² = {:.2} with {} dof: p = {:.3e} < {:.3e}",
                self.chi2, self.dof, self.p_value, level
            ));
        }
        None
    }

    /// Panics with a readable table of observed and expected counts unless [`Self::passes`].
    pub fn assert_ok(&self, alpha: f64, num_tests: usize, label: &str) {
        if let Some(why) = self.failure(alpha, num_tests) {
            panic!("χ² test '{label}' failed: {why}\n{}", self.table());
        }
    }

    /// Observed / expected counts as text, one row per `cos θ` bin (for failure messages).
    #[must_use]
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "∫pdf = {:.6}; none: observed {} expected {:.1}",
            self.pdf_integral,
            self.observed[self.observed.len() - 1],
            self.expected[self.expected.len() - 1]
        );
        for i in (0..self.theta_bins).rev() {
            let _ = write!(s, "row {i:2} obs:");
            for j in 0..self.phi_bins {
                let _ = write!(s, " {:7.0}", self.observed[i * self.phi_bins + j]);
            }
            let _ = write!(s, "\n       exp:");
            for j in 0..self.phi_bins {
                let _ = write!(s, " {:7.1}", self.expected[i * self.phi_bins + j]);
            }
            s.push('\n');
        }
        s
    }
}

/// The Šidák-corrected per-test significance level for `num_tests` independent tests run at
/// overall level `alpha`: `1 − (1 − α)^(1/n)`.
#[must_use]
pub fn sidak_level(alpha: f64, num_tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / num_tests.max(1) as f64)
}

/// Survival function of the χ² distribution with `dof` degrees of freedom: `P(X ≥ x)`.
#[must_use]
pub fn chi2_sf(x: f64, dof: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    gamma_q(0.5 * dof, 0.5 * x)
}

/// Natural log of Γ(x), x > 0 (Lanczos, g = 7, n = 9; ~15 digits).
#[must_use]
pub fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Upper regularised incomplete gamma function `Q(a, x) = Γ(a, x) / Γ(a)` (series for
/// `x < a + 1`, Lentz continued fraction otherwise; Numerical Recipes §6.2).
#[must_use]
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let gln = ln_gamma(a);
    if x < a + 1.0 {
        let mut ap = a;
        let mut sum = 1.0 / a;
        let mut del = sum;
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        (1.0 - sum * (-x + a * x.ln() - gln).exp()).clamp(0.0, 1.0)
    } else {
        const FPMIN: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / FPMIN;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < FPMIN {
                d = FPMIN;
            }
            c = b + an / c;
            if c.abs() < FPMIN {
                c = FPMIN;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        ((-x + a * x.ln() - gln).exp() * h).clamp(0.0, 1.0)
    }
}

/// Adaptive Simpson quadrature of `f` over `[a, b]` to absolute error about `tol`, recursing at
/// most `max_depth` levels. The interval is first split into 8 panels, each refined at least twice
/// (33 nodes), so that narrow peaks between the initial nodes are unlikely to be missed.
pub fn adaptive_simpson(f: &impl Fn(f64) -> f64, a: f64, b: f64, tol: f64, max_depth: u32) -> f64 {
    const PANELS: usize = 8;
    let h = (b - a) / PANELS as f64;
    let mut total = 0.0;
    for k in 0..PANELS {
        let (lo, hi) = (a + k as f64 * h, a + (k + 1) as f64 * h);
        let (fa, fb) = (f(lo), f(hi));
        let m = 0.5 * (lo + hi);
        let fm = f(m);
        let whole = (hi - lo) / 6.0 * (fa + 4.0 * fm + fb);
        total += simpson_rec(
            f,
            [lo, hi],
            [fa, fm, fb],
            whole,
            tol / PANELS as f64,
            0,
            max_depth,
        );
    }
    total
}

/// Levels of refinement always done before the error estimate may stop the recursion.
const MIN_LEVELS: u32 = 2;
/// Relative accuracy at which a sub-interval is accepted.
const REL_TOL: f64 = 1e-6;

fn simpson_rec(
    f: &impl Fn(f64) -> f64,
    [a, b]: [f64; 2],
    [fa, fm, fb]: [f64; 3],
    whole: f64,
    tol: f64,
    level: u32,
    max_depth: u32,
) -> f64 {
    let m = 0.5 * (a + b);
    let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
    let (flm, frm) = (f(lm), f(rm));
    let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
    let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    let delta = left + right - whole;
    // Absolute target, or a relative one (the integrand is typically evaluated in `f32`, whose
    // round-off would otherwise keep the recursion going to `max_depth`).
    let converged = delta.abs() <= 15.0 * tol || delta.abs() <= REL_TOL * (left + right).abs();
    if level >= max_depth || (level >= MIN_LEVELS && converged) {
        return left + right + delta / 15.0;
    }
    simpson_rec(
        f,
        [a, m],
        [fa, flm, fm],
        left,
        0.5 * tol,
        level + 1,
        max_depth,
    ) + simpson_rec(
        f,
        [m, b],
        [fm, frm, fb],
        right,
        0.5 * tol,
        level + 1,
        max_depth,
    )
}

/// The project's scene `scenes/NAME/scene.xml` with `defines`, as loaded (unit tests).
#[cfg(test)]
pub(crate) fn project_scene_desc(
    name: &str,
    defines: &[(String, String)],
) -> ircache_scene::SceneDesc {
    let path = ircache_testing::project_scenes()
        .join(name)
        .join("scene.xml");
    ircache_scene::mitsuba::load(&path, defines)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// [`project_scene_desc`], built.
#[cfg(test)]
pub(crate) fn project_scene(name: &str, defines: &[(String, String)]) -> crate::scene::Scene {
    crate::scene::Scene::build(&project_scene_desc(name, defines)).expect("the scene builds")
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_math::sampling;

    #[test]
    fn chi2_survival_function_matches_tables() {
        // Critical values of the χ² distribution at p = 0.05 and 0.01.
        assert!((chi2_sf(3.841, 1.0) - 0.05).abs() < 1e-3);
        assert!((chi2_sf(18.307, 10.0) - 0.05).abs() < 1e-3);
        assert!((chi2_sf(23.209, 10.0) - 0.01).abs() < 1e-4);
        assert!((chi2_sf(135.807, 100.0) - 0.01).abs() < 1e-4);
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
        assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-12);
    }

    #[test]
    fn simpson_integrates_peaks() {
        let v = adaptive_simpson(
            &|x| (-(x - 0.3) * (x - 0.3) / 2e-4).exp(),
            0.0,
            1.0,
            1e-10,
            30,
        );
        assert!((v - (2.0 * PI * 1e-4).sqrt()).abs() < 1e-8, "{v}");
    }

    #[test]
    fn cosine_sampling_passes_and_uniform_against_cosine_fails() {
        let t = ChiSquareTest::hemisphere().with_samples(200_000);
        let good = t.run(
            |u, _| {
                let w = sampling::square_to_cosine_hemisphere(u);
                Some((w, sampling::cosine_hemisphere_pdf(w)))
            },
            sampling::cosine_hemisphere_pdf,
        );
        good.assert_ok(0.01, 2, "cosine");
        assert!((good.pdf_integral - 1.0).abs() < 1e-6);
        let bad = t.run(
            |u, _| Some((sampling::square_to_uniform_hemisphere(u), 0.0)),
            sampling::cosine_hemisphere_pdf,
        );
        assert!(!bad.passes(0.01, 2));
    }

    #[test]
    fn missing_mass_is_checked_on_the_sphere() {
        // Half of the samples are "None": consistent with a pdf that integrates to 1/2.
        let t = ChiSquareTest::sphere().with_samples(200_000);
        let half = |w: Vec3| 0.5 * sampling::uniform_hemisphere_pdf(w);
        let r = t.run(
            |u, l| (l < 0.5).then(|| (sampling::square_to_uniform_hemisphere(u), half(Vec3::Z))),
            half,
        );
        r.assert_ok(0.01, 2, "half");
        // Claiming the full density while dropping half of the samples fails.
        let r = t.run(
            |u, l| (l < 0.5).then(|| (sampling::square_to_uniform_hemisphere(u), 0.0)),
            sampling::uniform_hemisphere_pdf,
        );
        assert!(!r.passes(0.01, 2));
    }
}
