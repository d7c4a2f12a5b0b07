//! Samplers: where every random number of a pixel sample comes from. Mitsuba 3's sampler plugins
//! (`independent`, `stratified`, `multijitter`, `orthogonal`, `ldsampler`) and an Owen-scrambled
//! Sobol' sampler decorrelated between pixels along a Morton curve (`sobol`, as pbrt-v4's
//! `ZSobolSampler`).
//!
//! A pixel sample is a point in a high-dimensional cube; integrators draw its coordinates in a
//! fixed order ([`dims`]: the film position, then a block of dimensions per path vertex), so that
//! the same dimension serves the same purpose in every sample of a pixel and the samplers'
//! stratification reaches the direct light. Every value is a pure function of (seed, pixel,
//! sample index, dimension): the image does not depend on the thread count or the order of work.
//!
//! [`Sampler`] is the narrow interface the integrators draw through; a plain [`Rng`] stream
//! implements it too (the caches' gathers, which stratify their own hemisphere).

pub mod dims;
mod kinds;
pub mod permute;

pub use kinds::{PixelSampler, SamplerKind, SamplerSettings};

use ircache_math::{Rng, Vec2};

/// A source of sample coordinates in `[0, 1)`.
pub trait Sampler {
    /// The next coordinate.
    fn next_1d(&mut self) -> f32;
    /// The next two coordinates (stratified jointly where the sampler promises it).
    fn next_2d(&mut self) -> Vec2;
    /// 64 random bits for seeding a computation of its own (a private record's gather).
    fn next_key(&mut self) -> u64;
    /// Jumps to dimension `dim` of the current sample (see [`dims`]); a plain stream ignores it.
    fn set_dimension(&mut self, _dim: u32) {}

    /// Passes over the next coordinate, which the caller does not need (a light choice among
    /// one light, a lobe choice in a one-lobe BSDF): the coordinates after it stay the same.
    fn skip_1d(&mut self) {
        let _ = self.next_1d();
    }

    /// Itself as a trait object: code generic over the sampler (the path loop, monomorphised
    /// for the pixel pass's sampler so that its draws inline) hands it on to interfaces that
    /// take any sampler.
    fn as_dyn(&mut self) -> &mut dyn Sampler;
}

impl Sampler for Rng {
    #[inline]
    fn as_dyn(&mut self) -> &mut dyn Sampler {
        self
    }

    #[inline]
    fn next_1d(&mut self) -> f32 {
        self.next_f32()
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        Rng::next_2d(self)
    }

    #[inline]
    fn next_key(&mut self) -> u64 {
        u64::from(self.next_u32()) << 32 | u64::from(self.next_u32())
    }
}

#[cfg(test)]
mod tests;
