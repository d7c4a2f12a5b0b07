//! The fixed order in which a pixel sample's dimensions are used: the film position first, then
//! a block of [`PER_VERTEX`] dimensions for each path vertex (the cache's work, the light sample,
//! the BSDF sample, Russian roulette), so that a dimension means the same in every sample of a
//! pixel whatever the path did before. Extra samples at a vertex (several light samples) use
//! dimensions far beyond the blocks.

/// The film position (2-D).
pub const FILM: u32 = 0;
/// The position on a thin lens (2-D), among the extra dimensions so that a lens leaves the
/// vertex blocks (and a pinhole's images) as they are.
pub const LENS: u32 = EXTRA + EXTRA_LENS * 3;
/// First dimension of vertex 0's block.
const FIRST_VERTEX: u32 = 2;
/// Dimensions per vertex.
pub const PER_VERTEX: u32 = 8;
/// Offset in a vertex block: the cache's per-sample work (a key).
pub const CACHE: u32 = 0;
/// Offset: the first light sample (light choice 1-D, position on the light 2-D).
pub const LIGHT: u32 = 1;
/// Offset: the BSDF sample (lobe choice 1-D, direction 2-D).
pub const BSDF: u32 = 4;
/// Offset: Russian roulette (1-D).
pub const ROULETTE: u32 = 7;
/// Where the dimensions of extra samples at a vertex start (vertex 0's first).
pub const EXTRA: u32 = 1 << 24;

/// Dimension `offset` of the block of path vertex `depth`.
#[inline]
#[must_use]
pub fn vertex(depth: u32, offset: u32) -> u32 {
    FIRST_VERTEX
        .saturating_add(depth.saturating_mul(PER_VERTEX))
        .saturating_add(offset)
        .min(EXTRA - PER_VERTEX)
}

/// First dimension of extra sample `i` ≥ 1 at vertex `depth` (3 dimensions each): light
/// samples beyond the first take `i` in [1, 2048), BSDF samples beyond the first 2048 + `i`.
#[inline]
#[must_use]
pub fn extra(depth: u32, i: u32) -> u32 {
    EXTRA + (depth.min(1023) * 4096 + i.min(4095)) * 3
}

/// Index in [`extra`] at vertex 0 that holds the lens position (beyond the sheets' choices).
const EXTRA_LENS: u32 = 4095;

/// Index of extra BSDF sample `i` in [`extra`].
pub const EXTRA_BSDF: u32 = 2048;

/// Index in [`extra`] of the choice at the `i`-th thin sheet a path crosses after vertex
/// `depth` (reflect or pass), which takes no vertex block of its own.
pub const EXTRA_SHEET: u32 = 3072;

/// Index in [`extra`] of the equiangular light sample on the `i`-th medium segment after
/// vertex `depth` ([`crate::integrators::equiangular`]).
pub const EXTRA_EQUIANGULAR: u32 = 3584;

/// The dimensions (light choice, distance) of the equiangular sample on the medium segment
/// that follows `crossings` null boundaries crossed since the path began, after vertex `depth`.
#[inline]
#[must_use]
pub fn equiangular(depth: u32, crossings: u32) -> u32 {
    extra(depth, EXTRA_EQUIANGULAR + crossings.min(255))
}

/// The dimension of the choice at the `crossing`-th thin sheet (from 1) met after vertex `depth`.
#[inline]
#[must_use]
pub fn sheet(depth: u32, crossing: u32) -> u32 {
    extra(depth, EXTRA_SHEET + crossing)
}
