//! Pixel reconstruction by filter importance sampling.
//!
//! Mitsuba splats each sample into every pixel its filter covers and divides by the summed filter
//! weights. Sampling the sub-pixel offset from the filter itself instead (pbrt-v4's approach)
//! converges to the same filtered image, keeps every pixel independent of its neighbours (so tiles
//! need no shared borders), and gives the same image for any thread count.

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
}

impl Filter {
    /// The filter of a film description.
    #[must_use]
    pub fn from_desc(desc: &FilterDesc) -> Filter {
        match *desc {
            FilterDesc::Box => Filter::Box,
            FilterDesc::Tent { radius } => Filter::Tent(radius),
            FilterDesc::Gaussian { stddev } => Filter::Gaussian(stddev),
        }
    }

    /// The farthest a sampled offset lies from the pixel centre along either axis, in pixels.
    #[must_use]
    pub fn radius(&self) -> f32 {
        match *self {
            Filter::Box => 0.5,
            Filter::Tent(r) => r,
            Filter::Gaussian(s) => 4.0 * s,
        }
    }

    /// An offset from the pixel centre, in pixels, distributed like the filter.
    #[must_use]
    pub fn sample(&self, u: Vec2) -> Vec2 {
        match *self {
            Filter::Box => u - Vec2::splat(0.5),
            Filter::Tent(r) => {
                Vec2::new(sampling::sample_tent(u.x, r), sampling::sample_tent(u.y, r))
            }
            Filter::Gaussian(s) => Vec2::new(
                sampling::sample_truncated_gaussian(u.x, s, 4.0 * s),
                sampling::sample_truncated_gaussian(u.y, s, 4.0 * s),
            ),
        }
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
                    let o = f.sample(Vec2::new(
                        (i as f32 + 0.5) / n as f32,
                        (j as f32 + 0.5) / n as f32,
                    ));
                    assert!(o.x.abs() <= r && o.y.abs() <= r, "{f:?} {o}");
                    assert!(o.x.abs() <= f.radius() && o.y.abs() <= f.radius());
                    mean += o;
                }
            }
            assert!((mean / (n * n) as f32).length() < 1e-3, "{f:?} not centred");
        }
    }
}
