//! Adaptive pixel sampling in rounds: every pixel takes a pilot of samples, then rounds double
//! the samples of the pixels where one more sample buys the most error, until the image's
//! estimated root-mean-square relative error reaches the target.
//!
//! A pixel's error is estimated from the two halves of its samples: the samples are prefixes of
//! one Owen-scrambled Sobol' sequence per pixel, and both halves of a prefix of 2^k samples are
//! nets of 2^(k−1), so the squared difference of the halves' means measures the error of the
//! pixel's estimate *with its stratification* (a per-sample variance overstates the error of
//! smooth pixels, which stratification serves far better than 1/n, and misjudges edges). With
//! `--sampler lattice` the prefixes are a rank-1 lattice sequence's; its halves are lattices too,
//! but translates of each other, so their difference sees the integrand's change along one vector
//! only (with the cache's small pilots it misled the rounds: BENCHMARKS.md).
//!
//! To spend a budget of samples with the least mean squared error Σ mᵢ(nᵢ), each pixel's
//! marginal gain −∂mᵢ/∂nᵢ must be equal; with mᵢ = wᵢ/nᵢ (wᵢ the error of one sample) that is
//! nᵢ ∝ √wᵢ, scaled so that the mean of mᵢ is the target². Each round estimates wᵢ, doubles the
//! pixels below their share, and measures again; so the counts approach the optimum through
//! measurements taken at growing sample counts, not one guess from a small pilot (whose
//! estimate of a heavy-tailed pixel's error is low).
//!
//! A pixel's error is pooled from its neighbours (a 5 × 5 window without the pixel), never its
//! own samples: a pixel whose first samples happen to miss a small bright source would look
//! converged and stop dark (a bias measured on Sponza). Its count still depends on its own
//! samples at second hand (through its neighbours' counts); the luminance ratio against the
//! references is measured in BENCHMARKS.md. Deterministic: every decision is a function of
//! samples that are.

/// Adaptive pixel sampling: every pixel first takes `spp` samples (rounded up to a power of two,
/// the pilot), then rounds of doubling up to `max_spp`, until the image's estimated
/// root-mean-square relative error is `target` (see the module's documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// Target root-mean-square relative error over the image.
    pub target: f32,
    /// Most samples a pixel takes.
    pub max_spp: u32,
}

/// The luminance sums of a pixel's samples that its error estimate needs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampleSums {
    /// Samples taken (the prefix `0..samples` of the pixel's sequence).
    pub samples: u32,
    /// Sum of all samples' luminance.
    pub luminance: f64,
    /// Sum of the luminance of samples `0..samples / 2`.
    pub first_half: f64,
}

impl SampleSums {
    /// Prepares the sums for taking samples up to `to`: all samples taken so far fall in the
    /// first half of `0..to` (the count at least doubles; otherwise the half cannot be redone).
    pub fn extend_to(&mut self, to: u32) {
        debug_assert!(self.samples <= to / 2 || self.samples == 0);
        if self.samples > 0 {
            self.first_half = self.luminance;
        }
    }

    /// Adds sample `index` of `0..to`'s luminance (`None`: an invalid sample, counted as zero).
    pub fn add(&mut self, index: u32, to: u32, luminance: Option<f64>) {
        if let Some(l) = luminance {
            self.luminance += l;
            if index < to / 2 {
                self.first_half += l;
            }
        }
    }

    /// The squared error of the pixel's mean relative to `mean² + floor`, from its halves:
    /// E[((a − b)/2)²] is half the variance of one half's mean.
    fn relative_error(&self, floor: f64) -> Option<f64> {
        if self.samples < 2 {
            return None;
        }
        let half = f64::from(self.samples / 2);
        let (a, b) = (
            self.first_half / half,
            (self.luminance - self.first_half) / half,
        );
        let mean = self.luminance / f64::from(self.samples);
        Some(((a - b) / 2.0).powi(2) / (mean * mean + floor))
    }
}

/// Radius of the window a pixel's error is pooled from.
const POOL_RADIUS: usize = 2;

/// The floor of the relative error's denominator, as a share of the image's mean luminance:
/// black pixels do not ask for infinitely many samples, whatever the scene's units.
const FLOOR_SHARE: f64 = 0.1;

/// The pilot's sample count: `spp` rounded up to a power of two (the halves stay nets).
#[must_use]
pub fn pilot_samples(spp: u32) -> u32 {
    spp.max(2).next_power_of_two()
}

/// The sample counts of the next round, or `None` when sampling is done: the estimated image
/// error is at the target, or no pixel may double within `max_spp`. `sums` holds every pixel
/// of a `w`-wide image (pixels with no samples are not rendered and stay at 0).
#[must_use]
pub fn next_round(sums: &[SampleSums], w: usize, adaptive: &Adaptive) -> Option<Vec<u32>> {
    let h = sums.len() / w.max(1);
    let rendered: Vec<&SampleSums> = sums.iter().filter(|s| s.samples > 0).collect();
    if rendered.is_empty() {
        return None;
    }
    let mean = rendered
        .iter()
        .map(|s| s.luminance / f64::from(s.samples))
        .sum::<f64>()
        / rendered.len() as f64;
    let floor = (FLOOR_SHARE * mean).powi(2).max(f64::MIN_POSITIVE);
    // Each pixel's relative squared error times its samples: the error of one sample, so that
    // neighbours with other counts pool.
    let per_sample: Vec<Option<f64>> = sums
        .iter()
        .map(|s| s.relative_error(floor).map(|e| e * f64::from(s.samples)))
        .collect();
    // Summed-area table of the per-sample errors and of the counts of pixels that have one.
    let mut table = vec![(0.0f64, 0u32); (w + 1) * (h + 1)];
    for y in 0..h {
        for x in 0..w {
            let (e, n) = per_sample[y * w + x].map_or((0.0, 0), |e| (e, 1));
            let up = table[y * (w + 1) + x + 1];
            let left = table[(y + 1) * (w + 1) + x];
            let diag = table[y * (w + 1) + x];
            table[(y + 1) * (w + 1) + x + 1] =
                (e + up.0 + left.0 - diag.0, n + up.1 + left.1 - diag.1);
        }
    }
    let window = |x: usize, y: usize| {
        let (x0, y0) = (x.saturating_sub(POOL_RADIUS), y.saturating_sub(POOL_RADIUS));
        let (x1, y1) = ((x + POOL_RADIUS + 1).min(w), (y + POOL_RADIUS + 1).min(h));
        let at = |x: usize, y: usize| table[y * (w + 1) + x];
        let (a, b, c, d) = (at(x1, y1), at(x0, y1), at(x1, y0), at(x0, y0));
        (a.0 - b.0 - c.0 + d.0, a.1 + d.1 - b.1 - c.1)
    };
    // Each rendered pixel's one-sample error wᵢ, pooled from its window without it.
    let one_sample: Vec<Option<f64>> = (0..sums.len())
        .map(|i| {
            if sums[i].samples == 0 {
                return None;
            }
            let (mut e, mut n) = window(i % w, i / w);
            if let Some(own) = per_sample[i] {
                e -= own;
                n -= 1;
            }
            Some(if n > 0 {
                (e / f64::from(n)).max(0.0)
            } else {
                0.0
            })
        })
        .collect();
    let target = f64::from(adaptive.target).powi(2) * rendered.len() as f64;
    // The image's estimated error now, Σ mᵢ = Σ wᵢ/nᵢ.
    let total: f64 = one_sample
        .iter()
        .zip(sums)
        .filter_map(|(w, s)| w.map(|w| w / f64::from(s.samples)))
        .sum();
    if total <= target {
        return None;
    }
    // The counts that bring Σ wᵢ/nᵢ to the target with the fewest samples are nᵢ ∝ √wᵢ,
    // nᵢ = √wᵢ · Σ√w / (P t²); pixels whose count is below its share (nearest power of two in
    // ratio) double, and are measured again before they double again.
    let scale = one_sample.iter().flatten().map(|w| w.sqrt()).sum::<f64>() / target;
    let mut counts: Vec<u32> = sums.iter().map(|s| s.samples).collect();
    let mut doubled = false;
    for (i, w) in one_sample.iter().enumerate() {
        let (Some(w), n) = (*w, sums[i].samples) else {
            continue;
        };
        let share = w.sqrt() * scale;
        if share > std::f64::consts::SQRT_2 * f64::from(n) && 2 * n <= adaptive.max_spp {
            counts[i] = 2 * n;
            doubled = true;
        }
    }
    doubled.then_some(counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pixel(samples: u32, first: f64, second: f64) -> SampleSums {
        SampleSums {
            samples,
            luminance: first + second,
            first_half: first,
        }
    }

    #[test]
    fn a_converged_image_takes_no_round() {
        // Halves that agree: no error, nothing to add.
        let sums = vec![pixel(8, 4.0, 4.0); 16];
        let a = Adaptive {
            target: 0.01,
            max_spp: 64,
        };
        assert_eq!(next_round(&sums, 4, &a), None);
    }

    #[test]
    fn the_noisy_region_doubles_first_and_the_pixel_is_judged_by_its_neighbours() {
        // An 8 × 8 image: the left half's halves disagree by 50 %, the right half's agree.
        let mut sums = Vec::new();
        for _y in 0..8 {
            for x in 0..8 {
                sums.push(if x < 4 {
                    pixel(8, 3.0, 5.0)
                } else {
                    pixel(8, 4.0, 4.0)
                });
            }
        }
        // A right-half pixel whose own halves disagree wildly is not doubled for it.
        sums[5 * 8 + 7] = pixel(8, 0.0, 8.0);
        let a = Adaptive {
            target: 1e-3,
            max_spp: 64,
        };
        let counts = next_round(&sums, 8, &a).expect("a round");
        for y in 0..8 {
            assert_eq!(counts[y * 8], 16, "row {y}");
        }
        assert_eq!(counts[5 * 8 + 7], 8);
        // Far from it, the right half stays.
        assert_eq!(counts[7], 8);
        assert_eq!(counts[8 + 6], 8);
        // The cap holds.
        let capped = Adaptive {
            target: 1e-3,
            max_spp: 8,
        };
        assert_eq!(next_round(&sums, 8, &capped), None);
    }
}
