//! The pixel samplers. Each turns (pixel, sample index, dimension) into a coordinate:
//! - `independent`: hashed uniform numbers;
//! - `stratified`: N = n² samples; each 1-D dimension in N strata, each 2-D pair on an n × n grid,
//!   the strata shuffled independently per dimension (Mitsuba 3's `stratified`);
//! - `multijitter`: correlated multi-jittered sampling (Kensler 2013): each 2-D pair is jittered
//!   on an m × n grid and a Latin hypercube at once;
//! - `orthogonal`: orthogonal-array Latin hypercubes (Jarosz et al. 2019), Bush's construction of
//!   strength 2 with N = s², s prime: every 1-D projection is a Latin hypercube and every 2-D
//!   projection of two dimensions is stratified on an s × s grid;
//! - `ldsampler`: Kollig and Keller's (0, 2)-sequence (first two Sobol' dimensions) with random
//!   digit scrambling, the sample order shuffled per dimension (Mitsuba 3's `ldsampler`);
//! - `sobol`: Owen-scrambled Sobol' points indexed along a Morton curve over the image with
//!   hashed base-4 digit permutations (pbrt-v4's `ZSobolSampler`, Ahmed and Wonka 2020), so that
//!   neighbouring pixels' samples are stratified together; each 2-D pair is a (0, 2)-sequence;
//! - `lattice`: the same Morton-ordered, digit-permuted indices into an extensible rank-1
//!   lattice sequence (Hickernell, Hong, L'Écuyer and Lemieux 2000) instead: point i of a 2-D
//!   pair is φ₂(i)·(1, g) mod 1, φ₂ the radical inverse in base 2, so that the first 2ᵏ points of
//!   any aligned block are the rank-1 lattice of 2ᵏ points with generator g, randomly shifted
//!   (Cranley–Patterson) and mirrored per dimension. Its points lie on a sheared lattice, as
//!   correlated multi-jitter's nearly do, and every power-of-two prefix keeps that.

use super::permute::{
    div_rem_lanes, hash32, hash64, lattice_point, owen_scramble, permute, permute_lanes, sobol_0,
    sobol_1, to_unit, Divisor, LANES,
};
use super::Sampler;
use ircache_math::sampling::ONE_MINUS_EPSILON;
use ircache_math::Vec2;

/// A sampler plugin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplerKind {
    /// Independent uniform numbers.
    Independent,
    /// Jittered strata, shuffled per dimension.
    Stratified,
    /// Correlated multi-jittered.
    MultiJitter,
    /// Orthogonal-array Latin hypercubes.
    Orthogonal,
    /// Scrambled (0, 2)-sequence.
    LowDiscrepancy,
    /// Owen-scrambled Sobol' along a Morton curve.
    Sobol,
    /// A shifted extensible rank-1 lattice sequence along a Morton curve.
    Lattice,
}

impl SamplerKind {
    /// Every kind with its plugin name.
    pub const ALL: [(SamplerKind, &'static str); 7] = [
        (SamplerKind::Independent, "independent"),
        (SamplerKind::Stratified, "stratified"),
        (SamplerKind::MultiJitter, "multijitter"),
        (SamplerKind::Orthogonal, "orthogonal"),
        (SamplerKind::LowDiscrepancy, "ldsampler"),
        (SamplerKind::Sobol, "sobol"),
        (SamplerKind::Lattice, "lattice"),
    ];

    /// The kind named `name` (Mitsuba's plugin names, and `sobol`).
    #[must_use]
    pub fn from_name(name: &str) -> Option<SamplerKind> {
        SamplerKind::ALL
            .iter()
            .find(|(_, n)| *n == name)
            .map(|(k, _)| *k)
    }

    /// The plugin name.
    #[must_use]
    pub fn name(self) -> &'static str {
        SamplerKind::ALL
            .iter()
            .find(|(k, _)| *k == self)
            .map_or("independent", |(_, n)| n)
    }

    /// The sample count this kind uses for a requested one (rounded up to what its construction
    /// needs: a square, a product of two near-equal factors, the square of a prime, a power of two).
    #[must_use]
    pub fn sample_count(self, requested: u32) -> u32 {
        let n = requested.max(1);
        match self {
            SamplerKind::Independent => n,
            SamplerKind::Stratified => {
                let r = ceil_sqrt(n);
                r * r
            }
            SamplerKind::MultiJitter => {
                let (m, k) = multijitter_grid(n);
                m * k
            }
            SamplerKind::Orthogonal => {
                let s = orthogonal_base(n);
                s * s
            }
            SamplerKind::LowDiscrepancy | SamplerKind::Sobol | SamplerKind::Lattice => {
                n.next_power_of_two()
            }
        }
    }
}

fn ceil_sqrt(n: u32) -> u32 {
    let mut r = (f64::from(n)).sqrt() as u32;
    while r * r < n {
        r += 1;
    }
    while r > 1 && (r - 1) * (r - 1) >= n {
        r -= 1;
    }
    r.max(1)
}

/// The m × k grid of multi-jittered sampling as Mitsuba 3 sizes it: k = ⌊√n⌋ rows, m = ⌈n/k⌉
/// columns (32 asked: 7 × 5 = 35; 8: 4 × 2).
pub(super) fn multijitter_grid(n: u32) -> (u32, u32) {
    let k = f64::from(n.max(1)).sqrt().floor().max(1.0) as u32;
    (n.max(1).div_ceil(k), k)
}

/// The smallest prime s with s² ≥ n.
pub(super) fn orthogonal_base(n: u32) -> u32 {
    let mut s = ceil_sqrt(n).max(2);
    while !(2..s)
        .take_while(|d| d * d <= s)
        .all(|d| !s.is_multiple_of(d))
    {
        s += 1;
    }
    s
}

/// A sampler for a whole image: its kind, sample count, seed and image size.
#[derive(Clone, Debug)]
pub struct SamplerSettings {
    /// Which construction.
    pub kind: SamplerKind,
    /// Samples per pixel after rounding ([`SamplerKind::sample_count`]).
    pub spp: u32,
    /// Seed of every pixel's samples.
    pub seed: u64,
    /// Jitter within strata (`false`: stratum centres), for the stratified kinds.
    pub jitter: bool,
    /// `sobol`: every prefix of a pixel's samples of a power-of-two length is a net (for adaptive
    /// sampling, which takes prefixes); `false`: only all `spp` are, and the pixels' sample sets
    /// together are blue noise (see `PixelSampler::sobol_index`).
    pub progressive: bool,
    /// Image width (the Sobol' sampler's Morton curve).
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The construction's grid, from `kind` and `spp`.
    grid: Grid,
}

/// Constants of a construction, computed once.
#[derive(Clone, Copy, Debug, Default)]
struct Grid {
    /// `stratified`: n of the n × n grid; `multijitter`: columns m; `orthogonal`: the prime s.
    a: u32,
    /// `multijitter`: rows k.
    b: u32,
    /// `sobol`: log₂ spp.
    log2_spp: u32,
    /// `sobol`: base-4 digits of the Morton-ordered sample index.
    digits: u32,
    /// Dividing by the sample count.
    by_spp: Divisor,
    /// Dividing by `a`.
    by_a: Divisor,
    /// Dividing by `b`.
    by_b: Divisor,
}

impl SamplerSettings {
    /// Settings for `kind` at `requested` samples per pixel (rounded up as the kind needs).
    #[must_use]
    pub fn new(kind: SamplerKind, requested: u32, seed: u64, width: u32, height: u32) -> Self {
        let spp = kind.sample_count(requested);
        let grid = match kind {
            SamplerKind::Independent | SamplerKind::LowDiscrepancy => Grid::default(),
            SamplerKind::Stratified => Grid {
                a: ceil_sqrt(spp),
                ..Grid::default()
            },
            SamplerKind::MultiJitter => {
                let (m, k) = multijitter_grid(spp);
                Grid {
                    a: m,
                    b: k,
                    ..Grid::default()
                }
            }
            SamplerKind::Orthogonal => Grid {
                a: orthogonal_base(spp),
                ..Grid::default()
            },
            SamplerKind::Sobol | SamplerKind::Lattice => {
                let log2_spp = spp.trailing_zeros();
                let log2_res = width
                    .max(height)
                    .max(1)
                    .next_power_of_two()
                    .trailing_zeros();
                Grid {
                    log2_spp,
                    digits: log2_res + log2_spp.div_ceil(2),
                    ..Grid::default()
                }
            }
        };
        let grid = Grid {
            by_spp: Divisor::new(spp.max(1)),
            by_a: Divisor::new(grid.a.max(1)),
            by_b: Divisor::new(grid.b.max(1)),
            ..grid
        };
        SamplerSettings {
            kind,
            spp,
            seed,
            jitter: true,
            progressive: false,
            width,
            height,
            grid,
        }
    }

    /// The sampler of pixel (x, y), positioned at sample 0, dimension 0.
    #[must_use]
    pub fn pixel(&self, x: u32, y: u32) -> PixelSampler<'_> {
        let pixel_seed = hash64(self.seed, u64::from(y) << 32 | u64::from(x));
        let morton = if matches!(self.kind, SamplerKind::Sobol | SamplerKind::Lattice) {
            morton2(x, y)
        } else {
            0
        };
        let row_seed = hash32(pixel_seed, 0x0a7e_0a7e);
        PixelSampler {
            s: self,
            pixel_seed,
            morton,
            row_seed,
            index: 0,
            dim: 0,
            sobol_dims: [None; CACHED_DIMS],
            dim_hashes: [0; CACHED_DIMS],
            batch: Batch::default(),
        }
    }
}

/// Interleaves the bits of x and y (x in the even bits).
fn morton2(x: u32, y: u32) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut v = u64::from(v);
        v = (v | v << 16) & 0x0000_ffff_0000_ffff;
        v = (v | v << 8) & 0x00ff_00ff_00ff_00ff;
        v = (v | v << 4) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | v << 2) & 0x3333_3333_3333_3333;
        (v | v << 1) & 0x5555_5555_5555_5555
    }
    spread(x) | spread(y) << 1
}

/// The 24 permutations of four base-4 digits.
const DIGIT_PERMUTATIONS: [[u8; 4]; 24] = [
    [0, 1, 2, 3],
    [0, 1, 3, 2],
    [0, 2, 1, 3],
    [0, 2, 3, 1],
    [0, 3, 2, 1],
    [0, 3, 1, 2],
    [1, 0, 2, 3],
    [1, 0, 3, 2],
    [1, 2, 0, 3],
    [1, 2, 3, 0],
    [1, 3, 2, 0],
    [1, 3, 0, 2],
    [2, 1, 0, 3],
    [2, 1, 3, 0],
    [2, 0, 1, 3],
    [2, 0, 3, 1],
    [2, 3, 0, 1],
    [2, 3, 1, 0],
    [3, 1, 2, 0],
    [3, 1, 0, 2],
    [3, 2, 1, 0],
    [3, 2, 0, 1],
    [3, 0, 2, 1],
    [3, 0, 1, 2],
];

/// The first base-4 digit of a `sobol` (or `lattice`) sample index that lies wholly in the pixel's Morton code
/// (those below hold the sample's own bits; with an odd log₂ spp, the lowest bit alone).
#[inline]
fn first_pixel_digit(log2_spp: u32) -> u32 {
    log2_spp.div_ceil(2).max(log2_spp & 1)
}

/// The base-4 digits `digits` of the Morton-ordered index `morton` (shifted down one bit when
/// `odd`), each permuted by a hash of the digits above it and `salt` (pbrt-v4's
/// `ZSobolSampler::GetSampleIndex`); the other bits zero.
#[inline]
fn permuted_digits(morton: u64, salt: u64, odd: bool, digits: std::ops::Range<u32>) -> u64 {
    let mut index = 0u64;
    for i in digits {
        let shift = 2 * i - u32::from(odd);
        let digit = (morton >> shift) & 3;
        let higher = morton >> (shift + 2);
        let p = (hash64(higher, salt) >> 40) % 24;
        index |= u64::from(DIGIT_PERMUTATIONS[p as usize][digit as usize]) << shift;
    }
    index
}

/// One pixel's samples.
#[derive(Clone, Debug)]
pub struct PixelSampler<'a> {
    s: &'a SamplerSettings,
    pixel_seed: u64,
    morton: u64,
    row_seed: u32,
    index: u32,
    dim: u32,
    /// `sobol` and `lattice`: per dimension, what all the pixel's samples share (`None` until
    /// computed).
    sobol_dims: [Option<SobolDim>; CACHED_DIMS],
    /// Per dimension, the pixel's hash of it (0 until computed).
    dim_hashes: [u64; CACHED_DIMS],
    /// The values of a batch of consecutive samples, each dimension's filled at its first draw.
    batch: Batch,
}

/// Dimensions a batch holds: the film position and the first three path vertices' blocks.
const BATCH_DIMS: usize = 2 + 3 * super::dims::PER_VERTEX as usize;
/// Dimensions of the first vertex's extra samples a batch holds after those (the `ic` pixel
/// pass's light samples beyond the first: four a vertex by default).
const BATCH_EXTRA_DIMS: usize = 3 * 8;
/// Slots of a batch: [`BATCH_DIMS`], then [`BATCH_EXTRA_DIMS`].
const BATCH_SLOTS: usize = BATCH_DIMS + BATCH_EXTRA_DIMS;

/// The batch slot of dimension `dim`, if a batch holds it.
#[inline]
fn batch_slot(dim: u32) -> Option<usize> {
    let d = dim as usize;
    if d < BATCH_DIMS {
        return Some(d);
    }
    let extra = dim.checked_sub(super::dims::EXTRA)? as usize;
    (extra < BATCH_EXTRA_DIMS).then_some(BATCH_DIMS + extra)
}
/// Samples a batch holds (the pixel pass's packet width).
pub const BATCH_SAMPLES: usize = LANES;

/// One draw's form, as a batch holds it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Form {
    Empty,
    One,
    Two,
}

/// A batch of consecutive samples' values, per dimension, in the form first drawn there. A
/// sample's draw is a chain of dependent hashes and permutations (Kensler's is a dozen
/// dependent multiplications); drawn one at a time as the path needs it, it costs the chain's
/// latency each time, while filling the batch's samples in one loop overlaps them (they are
/// independent). The values are the sampler's own, computed by the same function.
#[derive(Clone, Debug)]
struct Batch {
    first: u32,
    len: u32,
    forms: [Form; BATCH_SLOTS],
    values: [[Vec2; BATCH_SAMPLES]; BATCH_SLOTS],
}

impl Default for Batch {
    fn default() -> Self {
        Batch {
            first: 0,
            len: 0,
            forms: [Form::Empty; BATCH_SLOTS],
            values: [[Vec2::ZERO; BATCH_SAMPLES]; BATCH_SLOTS],
        }
    }
}

/// Dimensions whose per-pixel values (Sobol' pixel digits, dimension hashes) a pixel sampler
/// keeps.
const CACHED_DIMS: usize = 48;

/// `sobol` and `lattice`: what a pixel's draws of one dimension share, computed once per pixel
/// and dimension instead of at every draw.
#[derive(Clone, Copy, Debug)]
struct SobolDim {
    /// The permuted digits of the pixel's part of the sample index.
    high: u64,
    /// Progressive: the pixel's shuffle of its own samples (the octave shuffle's seed in the low
    /// word, the XOR in the high one).
    shuffle: u64,
    /// The Owen scrambles' seeds (`lattice`: the shifts): the first coordinate's in the low
    /// word, the second's (and a 1-D draw's) in the high one.
    scramble: u64,
}

/// A permutation of `0..2^32` that maps every octave `[2^t, 2^(t+1))` (and 0, 1) to itself: the
/// bits below `j`'s highest are nested-scrambled (each flipped by a hash of the bits above it),
/// so that every prefix `0..2^k` maps to itself.
#[inline]
fn octave_shuffle(j: u32, seed: u32) -> u32 {
    if j < 2 {
        return j;
    }
    // With the highest bit at the top, Burley's scramble flips each bit by a hash of those
    // above; an even seed leaves the top bit itself.
    let shift = j.leading_zeros();
    owen_scramble(j << shift, seed & !1) >> shift
}

impl PixelSampler<'_> {
    /// Moves to sample `index` (< the sample count), dimension `dim`.
    #[inline]
    pub fn set_sample(&mut self, index: u32, dim: u32) {
        debug_assert!(index < self.s.spp);
        self.index = index;
        self.dim = dim;
    }

    /// Announces that samples `first..first + len` (`len` ≤ [`BATCH_SAMPLES`]) are drawn
    /// next, interleaved: each dimension's values for all of them are then computed together at
    /// its first draw. The values do not change.
    pub fn begin_batch(&mut self, first: u32, len: u32) {
        debug_assert!(len as usize <= BATCH_SAMPLES && first + len <= self.s.spp);
        self.batch.first = first;
        self.batch.len = len;
        self.batch.forms = [Form::Empty; BATCH_SLOTS];
    }

    /// Where the current sample's value of dimension `dim` in `form` lies in the batch: the
    /// dimension and the sample's place; filled first where empty. `None` where the batch does
    /// not hold it.
    #[inline]
    fn batched(&mut self, dim: u32, form: Form) -> Option<(usize, usize)> {
        let lane = self.index.wrapping_sub(self.batch.first);
        if lane >= self.batch.len {
            return None;
        }
        let d = batch_slot(dim)?;
        match self.batch.forms[d] {
            f if f == form => {}
            Form::Empty => self.fill(d, dim, form),
            _ => return None,
        }
        Some((d, lane as usize))
    }

    /// Computes dimension `dim` in `form` for every sample of the batch, into slot `d`.
    #[cold]
    fn fill(&mut self, d: usize, dim: u32, form: Form) {
        let s = self.s;
        if matches!(s.kind, SamplerKind::MultiJitter | SamplerKind::Stratified) {
            self.fill_permuted(d, dim, form);
            self.batch.forms[d] = form;
            return;
        }
        let index = self.index;
        let (first, len) = (self.batch.first, self.batch.len);
        for lane in 0..len {
            self.index = first + lane;
            self.batch.values[d][lane as usize] = match form {
                Form::Two => self.sample_2d(dim),
                _ => Vec2::new(self.sample_1d(dim), 0.0),
            };
        }
        self.batch.forms[d] = form;
        self.index = index;
    }

    /// [`Self::sample_1d`] and [`Self::sample_2d`] of `multijitter` and `stratified` for the
    /// whole batch, on any grid: the permutations with their cycle walking, the divisions and
    /// the jitter hashes in vector lanes
    /// ([`permute_lanes`], [`div_rem_lanes`]); the same values (a test compares the two). Drawn
    /// one sample at a time they were a fifth of a path-traced render at sample counts whose
    /// grids are not powers of two (35, 132, 506 samples for 32, 128, 512 asked).
    fn fill_permuted(&mut self, d: usize, dim: u32, form: Form) {
        let s = self.s;
        let seed = self.dim_seed(dim, 0);
        let (first, len, pixel_seed) = (self.batch.first, self.batch.len, self.pixel_seed);
        // Lanes past the batch repeat its first sample (their values are not read).
        let index: [u32; LANES] = std::array::from_fn(|l| {
            if (l as u32) < len {
                first + l as u32
            } else {
                first
            }
        });
        let p = permute_lanes(&index, s.grid.by_spp, seed);
        let jitter: [(f32, f32); LANES] = if s.jitter {
            index.map(|i| unit_pair(sample_bits(pixel_seed, i, dim)))
        } else {
            [(0.5, 0.5); LANES]
        };
        let values = &mut self.batch.values[d];
        if form != Form::Two {
            let n = s.spp as f32;
            for ((v, &p), &(jx, _)) in values.iter_mut().zip(&p).zip(&jitter) {
                *v = Vec2::new((p as f32 + jx) / n, 0.0);
            }
            return;
        }
        let (p_div_m, p_mod_m) = div_rem_lanes(&p, s.grid.a);
        if s.kind == SamplerKind::Stratified {
            for (l, v) in values.iter_mut().enumerate() {
                *v = stratified_point(s.grid.a, (p_mod_m[l], p_div_m[l]), jitter[l]);
            }
            return;
        }
        let (seed_x, seed_y) = sub_stratum_seeds(seed);
        let sx = permute_lanes(&p_mod_m, s.grid.by_a, seed_x);
        let sy = permute_lanes(&p_div_m, s.grid.by_b, seed_y);
        for (l, v) in values.iter_mut().enumerate() {
            *v = multijitter_point(s.grid, (p_mod_m[l], p_div_m[l]), (sx[l], sy[l]), jitter[l]);
        }
    }

    #[inline]
    fn dim_seed(&mut self, dim: u32, salt: u64) -> u32 {
        // The pixel's hash of the dimension is the same for all its samples: kept.
        let hash = || hash64(self.pixel_seed, u64::from(dim)) | 1;
        let h = match self.dim_hashes.get(dim as usize) {
            Some(&h) if h != 0 => h,
            Some(_) => {
                let h = hash();
                self.dim_hashes[dim as usize] = h;
                h
            }
            None => hash(),
        };
        // Salts pick independent 32-bit words of the hash (salt ≥ 2 rehashes).
        match salt {
            0 => h as u32,
            1 => (h >> 32) as u32,
            _ => hash32(h, salt),
        }
    }

    /// 64 random bits of the current sample's dimension `dim`.
    #[inline]
    fn sample_hash(&self, dim: u32) -> u64 {
        sample_bits(self.pixel_seed, self.index, dim)
    }

    /// Two jitter offsets from one hash.
    #[inline]
    fn jitter2(&self, dim: u32) -> (f32, f32) {
        if self.s.jitter {
            unit_pair(self.sample_hash(dim))
        } else {
            (0.5, 0.5)
        }
    }

    #[inline]
    fn random(&self, dim: u32, salt: u64) -> u32 {
        hash32(
            self.pixel_seed ^ (u64::from(self.index) << 32 | u64::from(dim)),
            salt,
        )
    }

    /// The Sobol' sample index of this pixel's current sample for dimension `dim`: the Morton
    /// index with each base-4 digit permuted by a hash of the digits above it (pbrt-v4's
    /// `ZSobolSampler::GetSampleIndex`), so that the pixels' blocks of indices, and the points
    /// they give, are shuffled independently per dimension.
    ///
    /// The digits above the sample's own depend on the pixel alone; they are computed once per
    /// dimension and pixel.
    ///
    /// Progressive: the sample's own bits are not permuted digit by digit (a permuted digit
    /// above the prefix's would take the prefix out of its aligned block, and the block's net
    /// property with it) but shuffled within each octave `[2^t, 2^(t+1))` of the sample index,
    /// which every prefix of a power-of-two length keeps, then XORed with a constant (which maps
    /// aligned blocks to aligned blocks); both differ per dimension and pixel, so that dimension
    /// pairs do not pair the same points.
    fn sobol_index(&mut self, dim: u32) -> (u64, u64) {
        let log2_spp = self.s.grid.log2_spp;
        let sd = self.sobol_dim(dim);
        if self.s.progressive {
            // Seeded by pixel and dimension: a shuffle shared by the pixels would give every
            // pixel the same pairing of one dimension's points with another's, and without the
            // XOR (which moves each aligned prefix block to another) sample 0 would be the same
            // point of every pixel's block.
            let mask = (1u64 << log2_spp) - 1;
            let own = u64::from(octave_shuffle(self.index, sd.shuffle as u32))
                ^ ((sd.shuffle >> 32) & mask);
            return (sd.high | own, sd.scramble);
        }
        let odd = log2_spp & 1 == 1;
        let morton = self.morton << log2_spp | u64::from(self.index);
        let salt = Self::sobol_salt(self.s.seed, dim);
        let last = u32::from(odd);
        let mut index =
            sd.high | permuted_digits(morton, salt, odd, last..first_pixel_digit(log2_spp));
        if odd {
            index |= (morton & 1) ^ (hash64(morton >> 1, salt) & 1);
        }
        (index, sd.scramble)
    }

    /// The salt of dimension `dim`'s digit permutations.
    #[inline]
    fn sobol_salt(seed: u64, dim: u32) -> u64 {
        (0x5555_5555u64).wrapping_mul(u64::from(dim)) ^ seed
    }

    /// What the pixel's draws of dimension `dim` share (kept for the first [`CACHED_DIMS`]).
    #[inline]
    fn sobol_dim(&mut self, dim: u32) -> SobolDim {
        if let Some(Some(sd)) = self.sobol_dims.get(dim as usize) {
            return *sd;
        }
        let Grid {
            log2_spp, digits, ..
        } = self.s.grid;
        let salt = Self::sobol_salt(self.s.seed, dim);
        let morton = self.morton << log2_spp;
        let sd = SobolDim {
            high: permuted_digits(
                morton,
                salt,
                log2_spp & 1 == 1,
                first_pixel_digit(log2_spp)..digits,
            ),
            shuffle: hash64(self.morton, salt ^ 0x0c7a),
            scramble: hash64(self.s.seed, u64::from(dim)),
        };
        if let Some(slot) = self.sobol_dims.get_mut(dim as usize) {
            *slot = Some(sd);
        }
        sd
    }

    fn sample_1d(&mut self, dim: u32) -> f32 {
        let s = self.s;
        let n = s.spp;
        match s.kind {
            SamplerKind::Independent => to_unit(self.random(dim, 1)),
            SamplerKind::Stratified | SamplerKind::MultiJitter => {
                let p = permute(self.index, s.grid.by_spp, self.dim_seed(dim, 0));
                (p as f32 + self.jitter2(dim).0) / n as f32
            }
            SamplerKind::Orthogonal => self.orthogonal(dim),
            SamplerKind::LowDiscrepancy => {
                let p = permute(self.index, s.grid.by_spp, self.dim_seed(dim, 0));
                to_unit(sobol_0(p) ^ self.dim_seed(dim, 1))
            }
            SamplerKind::Sobol => {
                let (i, scramble) = self.sobol_index(dim);
                to_unit(owen_scramble(sobol_0(i as u32), (scramble >> 32) as u32))
            }
            SamplerKind::Lattice => {
                let (i, shift) = self.sobol_index(dim);
                to_unit(sobol_0(i as u32).wrapping_add((shift >> 32) as u32))
            }
        }
    }

    fn sample_2d(&mut self, dim: u32) -> Vec2 {
        let s = self.s;
        match s.kind {
            SamplerKind::Independent => {
                let (x, y) = unit_pair(self.sample_hash(dim));
                Vec2::new(x, y)
            }
            SamplerKind::Stratified => {
                let p = permute(self.index, s.grid.by_spp, self.dim_seed(dim, 0));
                let (y_stratum, x_stratum) = s.grid.by_a.div_rem(p);
                stratified_point(s.grid.a, (x_stratum, y_stratum), self.jitter2(dim))
            }
            SamplerKind::MultiJitter => {
                // Kensler 2013, listing 5: stratum (p mod m, p div m), sub-strata from the
                // permuted other coordinate.
                let seed = self.dim_seed(dim, 0);
                let p = permute(self.index, s.grid.by_spp, seed);
                let (p_div_m, p_mod_m) = s.grid.by_a.div_rem(p);
                let (seed_x, seed_y) = sub_stratum_seeds(seed);
                let sx = permute(p_mod_m, s.grid.by_a, seed_x);
                let sy = permute(p_div_m, s.grid.by_b, seed_y);
                multijitter_point(s.grid, (p_mod_m, p_div_m), (sx, sy), self.jitter2(dim))
            }
            SamplerKind::Orthogonal => Vec2::new(self.orthogonal(dim), self.orthogonal(dim + 1)),
            SamplerKind::LowDiscrepancy => {
                let p = permute(self.index, s.grid.by_spp, self.dim_seed(dim, 0));
                Vec2::new(
                    to_unit(sobol_0(p) ^ self.dim_seed(dim, 1)),
                    to_unit(sobol_1(p) ^ self.dim_seed(dim, 2)),
                )
            }
            SamplerKind::Sobol => {
                let (i, h) = self.sobol_index(dim);
                let i = i as u32;
                Vec2::new(
                    to_unit(owen_scramble(sobol_0(i), h as u32)),
                    to_unit(owen_scramble(sobol_1(i), (h >> 32) as u32)),
                )
            }
            SamplerKind::Lattice => {
                let (i, shift) = self.sobol_index(dim);
                let (x, y) = lattice_point(i as u32, shift);
                Vec2::new(to_unit(x), to_unit(y))
            }
        }
    }

    /// Bush's orthogonal array of strength 2 over GF(s): row i = a₀ + a₁·s has in column j the
    /// value a₀ + a₁·j mod s; any two columns take every pair of values once. The value picks
    /// the stratum, a₁ the sub-stratum (distinct among the rows sharing a value), both shuffled
    /// per column, so every column is also a Latin hypercube.
    fn orthogonal(&mut self, dim: u32) -> f32 {
        let grid = self.s.grid;
        let by_s = grid.by_a;
        let row = permute(self.index, grid.by_spp, self.row_seed);
        let (a1, a0) = by_s.div_rem(row);
        let column = by_s.remainder(dim);
        let value = by_s.remainder(a0 + a1 * column);
        let stratum = permute(value, by_s, self.dim_seed(dim, 0));
        let sub = permute(a1, by_s, self.dim_seed(dim, 1));
        let s = grid.a as f32;
        (stratum as f32 + (sub as f32 + self.jitter2(dim).0) / s) / s
    }
}

/// The seeds of a multi-jittered dimension's column and row shuffles (Kensler's `sx`, `sy`) from
/// the dimension's seed.
#[inline]
fn sub_stratum_seeds(seed: u32) -> (u32, u32) {
    (
        seed.wrapping_mul(0xa511_e9b3),
        seed.wrapping_mul(0x63d8_3595),
    )
}

/// 64 random bits of sample `index`'s dimension `dim` in the pixel `pixel_seed`.
#[inline]
fn sample_bits(pixel_seed: u64, index: u32, dim: u32) -> u64 {
    hash64(pixel_seed, u64::from(index) << 32 | u64::from(dim))
}

/// Two offsets in [0, 1) from a sample's 64 random bits.
#[inline]
fn unit_pair(bits: u64) -> (f32, f32) {
    (to_unit(bits as u32), to_unit((bits >> 32) as u32))
}

/// `stratified`'s 2-D point: cell (x, y) of the r × r grid, jittered within.
#[inline]
fn stratified_point(r: u32, (x, y): (u32, u32), (jx, jy): (f32, f32)) -> Vec2 {
    Vec2::new((x as f32 + jx) / r as f32, (y as f32 + jy) / r as f32)
}

/// Kensler's multi-jittered point (2013, listing 5): stratum (p mod m, p div m), the sub-strata
/// `(sx, sy)` of the permuted other coordinate, jittered within. The divisions by m and k are
/// multiplications by their reciprocals, exact on power-of-two grids (the reciprocals are
/// loop-invariant in a batch; no speed change was measured, BENCHMARKS.md).
#[inline]
fn multijitter_point(
    grid: Grid,
    (p_mod_m, p_div_m): (u32, u32),
    (sx, sy): (u32, u32),
    (jx, jy): (f32, f32),
) -> Vec2 {
    let (inv_m, inv_k) = (1.0 / grid.a as f32, 1.0 / grid.b as f32);
    Vec2::new(
        (p_mod_m as f32 + (sy as f32 + jx) * inv_k) * inv_m,
        (p_div_m as f32 + (sx as f32 + jy) * inv_m) * inv_k,
    )
    .min(Vec2::splat(ONE_MINUS_EPSILON))
}

impl Sampler for PixelSampler<'_> {
    #[inline]
    fn as_dyn(&mut self) -> &mut dyn Sampler {
        self
    }

    #[inline]
    fn next_1d(&mut self) -> f32 {
        let u = match self.batched(self.dim, Form::One) {
            Some((d, lane)) => self.batch.values[d][lane].x,
            None => self.sample_1d(self.dim),
        };
        self.dim += 1;
        u.min(ONE_MINUS_EPSILON)
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let u = match self.batched(self.dim, Form::Two) {
            Some((d, lane)) => self.batch.values[d][lane],
            None => self.sample_2d(self.dim),
        };
        self.dim += 2;
        u.min(Vec2::splat(ONE_MINUS_EPSILON))
    }

    #[inline]
    fn next_key(&mut self) -> u64 {
        let k = self.sample_hash(self.dim);
        self.dim += 1;
        k
    }

    #[inline]
    fn set_dimension(&mut self, dim: u32) {
        self.dim = dim;
    }

    #[inline]
    fn skip_1d(&mut self) {
        self.dim += 1;
    }
}
