//! Pixel reconstruction by filter importance sampling.
//!
//! Mitsuba splats each sample into every pixel its filter covers and divides by the summed filter
//! weights. Sampling the sub-pixel offset from the filter itself instead (pbrt-v4's approach)
//! converges to the same filtered image, keeps every pixel independent of its neighbours (so tiles
//! need no shared borders), and gives the same image for any thread count.
//!
//! Filters with negative lobes (Mitchell–Netravali, Catmull–Rom, Lanczos) cannot be sampled as
//! densities: their offsets come from a proposal (piecewise constant over 64 bins of the support,
//! each bin's density in proportion to the largest |f| in it) and each sample carries the weight
//! `f(x) f(y) / (p(x) p(y) (∫f)²)`, signed and bounded, whose mean is 1; the others' weight is
//! exactly 1.

use ircache_math::{sampling, Vec2};
use ircache_scene::FilterDesc;

/// A pixel filter that can be sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Filter {
    /// Box, radius 0.5.
    Box,
    /// Tent of the given radius.
    Tent(f32),
    /// Gaussian with the given standard deviation, truncated at 4 σ.
    Gaussian(f32),
    /// Mitchell–Netravali cubic of radius 2.
    Mitchell {
        /// B.
        b: f32,
        /// C.
        c: f32,
        /// Its proposal and integral.
        proposal: Proposal,
    },
    /// Lanczos-windowed sinc with its radius (the number of lobes).
    Lanczos {
        /// Radius in pixels.
        lobes: f32,
        /// Its proposal and integral.
        proposal: Proposal,
    },
}

/// Bins of a [`Proposal`].
const BINS: usize = 64;

/// The density offsets of a filter with negative lobes are drawn from along one axis (module
/// doc), with the filter's integral.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proposal {
    radius: f32,
    /// Cumulative probabilities at the bins' edges.
    cdf: [f32; BINS + 1],
    /// Density in each bin.
    density: [f32; BINS],
    /// `∫f` over the support.
    norm: f32,
}

impl Proposal {
    fn new(radius: f32, f: impl Fn(f32) -> f32) -> Proposal {
        let h = 2.0 * radius / BINS as f32;
        // The largest |f| in each bin (at 9 points), floored so no bin is left out.
        let mut mass = [0.0f32; BINS];
        for (i, m) in mass.iter_mut().enumerate() {
            let x0 = -radius + i as f32 * h;
            *m = (0..=8)
                .map(|k| f(x0 + h * k as f32 / 8.0).abs())
                .fold(0.0, f32::max)
                .max(1e-3);
        }
        let total: f32 = mass.iter().sum();
        let mut cdf = [0.0f32; BINS + 1];
        let mut density = [0.0f32; BINS];
        for i in 0..BINS {
            cdf[i + 1] = cdf[i] + mass[i] / total;
            density[i] = mass[i] / (total * h);
        }
        cdf[BINS] = 1.0;
        Proposal {
            radius,
            cdf,
            density,
            norm: integral(radius, &f),
        }
    }

    /// An offset along one axis and its weight `f(x) / (p(x) ∫f)`.
    fn sample(&self, u: f32, f: impl Fn(f32) -> f32) -> (f32, f32) {
        let i = self.cdf[1..].partition_point(|&c| c <= u).min(BINS - 1);
        let span = (self.cdf[i + 1] - self.cdf[i]).max(f32::MIN_POSITIVE);
        let t = ((u - self.cdf[i]) / span).clamp(0.0, 1.0);
        let h = 2.0 * self.radius / BINS as f32;
        let x = -self.radius + (i as f32 + t) * h;
        (x, f(x) / (self.density[i] * self.norm))
    }
}

/// Mitsuba's Mitchell–Netravali cubic at `x`.
fn mitchell(x: f32, b: f32, c: f32) -> f32 {
    let x = x.abs();
    let (x2, x3) = (x * x, x * x * x);
    let value = if x < 1.0 {
        (12.0 - 9.0 * b - 6.0 * c) * x3 + (-18.0 + 12.0 * b + 6.0 * c) * x2 + (6.0 - 2.0 * b)
    } else if x < 2.0 {
        (-b - 6.0 * c) * x3
            + (6.0 * b + 30.0 * c) * x2
            + (-12.0 * b - 48.0 * c) * x
            + (8.0 * b + 24.0 * c)
    } else {
        0.0
    };
    value / 6.0
}

/// Mitsuba's Lanczos sinc of radius `a` at `x`.
fn lanczos(x: f32, a: f32) -> f32 {
    let x = x.abs();
    if x < f32::EPSILON {
        return 1.0;
    }
    if x > a {
        return 0.0;
    }
    let (x1, x2) = (std::f32::consts::PI * x, std::f32::consts::PI * x / a);
    x1.sin() * x2.sin() / (x1 * x2)
}

/// `∫ f` over [−radius, radius] by the midpoint rule (4096 points).
fn integral(radius: f32, f: &impl Fn(f32) -> f32) -> f32 {
    let n = 4096;
    let h = 2.0 * radius / n as f32;
    (0..n)
        .map(|i| f(-radius + (i as f32 + 0.5) * h))
        .sum::<f32>()
        * h
}

impl Filter {
    /// The filter of a film description.
    #[must_use]
    pub fn from_desc(desc: &FilterDesc) -> Filter {
        match *desc {
            FilterDesc::Box => Filter::Box,
            FilterDesc::Tent { radius } => Filter::Tent(radius),
            FilterDesc::Gaussian { stddev } => Filter::Gaussian(stddev),
            FilterDesc::Mitchell { b, c } => Filter::Mitchell {
                b,
                c,
                proposal: Proposal::new(2.0, |x| mitchell(x, b, c)),
            },
            FilterDesc::Lanczos { lobes } => {
                let a = lobes as f32;
                Filter::Lanczos {
                    lobes: a,
                    proposal: Proposal::new(a, |x| lanczos(x, a)),
                }
            }
        }
    }

    /// True when samples carry weights other than 1 (filters with negative lobes).
    #[must_use]
    pub fn is_weighted(&self) -> bool {
        matches!(self, Filter::Mitchell { .. } | Filter::Lanczos { .. })
    }

    /// The farthest a sampled offset lies from the pixel centre along either axis, in pixels.
    #[must_use]
    pub fn radius(&self) -> f32 {
        match *self {
            Filter::Box => 0.5,
            Filter::Tent(r) => r,
            Filter::Gaussian(s) => 4.0 * s,
            Filter::Mitchell { .. } => 2.0,
            Filter::Lanczos { lobes, .. } => lobes,
        }
    }

    /// An offset from the pixel centre, in pixels, and the sample's weight: distributed like
    /// the filter with weight 1, or for filters with negative lobes like their proposal with
    /// the signed weight (module doc).
    #[must_use]
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let signed = |proposal: &Proposal, f: &dyn Fn(f32) -> f32| {
            let (x, wx) = proposal.sample(u.x, f);
            let (y, wy) = proposal.sample(u.y, f);
            (Vec2::new(x, y), wx * wy)
        };
        let offset = match self {
            Filter::Mitchell { b, c, proposal } => {
                return signed(proposal, &|x| mitchell(x, *b, *c))
            }
            Filter::Lanczos { lobes, proposal } => {
                return signed(proposal, &|x| lanczos(x, *lobes))
            }
            Filter::Box => u - Vec2::splat(0.5),
            Filter::Tent(r) => Vec2::new(
                sampling::sample_tent(u.x, *r),
                sampling::sample_tent(u.y, *r),
            ),
            Filter::Gaussian(s) => Vec2::new(
                sampling::sample_truncated_gaussian(u.x, *s, 4.0 * s),
                sampling::sample_truncated_gaussian(u.y, *s, 4.0 * s),
            ),
        };
        (offset, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_stay_within_the_filter_radius_and_are_centred() {
        for (f, r) in [
            (Filter::Box, 0.5),
            (Filter::Tent(1.0), 1.0),
            (Filter::Gaussian(0.5), 2.0),
        ] {
            let mut mean = Vec2::ZERO;
            let n = 64;
            for i in 0..n {
                for j in 0..n {
                    let (o, w) = f.sample(Vec2::new(
                        (i as f32 + 0.5) / n as f32,
                        (j as f32 + 0.5) / n as f32,
                    ));
                    assert_eq!(w, 1.0, "{f:?}");
                    assert!(o.x.abs() <= r && o.y.abs() <= r, "{f:?} {o}");
                    assert!(o.x.abs() <= f.radius() && o.y.abs() <= f.radius());
                    mean += o;
                }
            }
            assert!((mean / (n * n) as f32).length() < 1e-3, "{f:?} not centred");
        }
    }

    /// The signed filters' weighted samples reproduce the filter: over stratified offsets the
    /// mean of `w g(x, y)` equals `∫∫ f(x) f(y) g / (∫f)²` by quadrature for a smooth `g`
    /// (and the mean weight is 1), within 0.5 %; the weights stay bounded.
    #[test]
    fn signed_filters_reproduce_themselves() {
        use ircache_scene::FilterDesc;
        for desc in [
            FilterDesc::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
            },
            FilterDesc::Mitchell { b: 0.0, c: 0.5 },
            FilterDesc::Lanczos { lobes: 3 },
        ] {
            let filter = Filter::from_desc(&desc);
            let (radius, f): (f32, Box<dyn Fn(f32) -> f32>) = match filter {
                Filter::Mitchell { b, c, .. } => (2.0, Box::new(move |x| mitchell(x, b, c))),
                Filter::Lanczos { lobes, .. } => (lobes, Box::new(move |x| lanczos(x, lobes))),
                _ => unreachable!(),
            };
            let g = |x: f32, y: f32| 1.0 + 0.3 * x + 0.2 * x * x + 0.1 * y * y;
            // Quadrature.
            let n = 400;
            let h = 2.0 * radius / n as f32;
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for i in 0..n {
                for j in 0..n {
                    let (x, y) = (
                        -radius + (i as f32 + 0.5) * h,
                        -radius + (j as f32 + 0.5) * h,
                    );
                    let w = f64::from(f(x) * f(y));
                    num += w * f64::from(g(x, y));
                    den += w;
                }
            }
            let expected = num / den;
            // Stratified samples.
            let m = 2048;
            let (mut sum, mut weights, mut largest) = (0.0f64, 0.0f64, 0.0f32);
            for i in 0..m {
                for j in 0..m {
                    let u = Vec2::new((i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
                    let (o, w) = filter.sample(u);
                    assert!(o.x.abs() <= radius && o.y.abs() <= radius);
                    sum += f64::from(w * g(o.x, o.y));
                    weights += f64::from(w);
                    largest = largest.max(w.abs());
                }
            }
            let samples = f64::from(m * m);
            assert!(
                (weights / samples - 1.0).abs() < 5e-3,
                "{desc:?}: mean weight {}",
                weights / samples
            );
            assert!(
                ((sum / samples) / expected - 1.0).abs() < 5e-3,
                "{desc:?}: {} against {expected}",
                sum / samples
            );
            assert!(largest < 4.0, "{desc:?}: weight {largest}");
        }
    }
}
