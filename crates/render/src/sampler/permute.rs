//! Hashes and permutations the pixel samplers are built from: Kensler's hashed permutation of
//! `[0, n)` (Correlated Multi-Jittered Sampling, Pixar tech. memo 13-01, 2013, §3), Burley's
//! hash-based Owen scrambling (Practical Hash-based Owen Scrambling, JCGT 9(4), 2020), and the
//! first two Sobol' dimensions as generator matrices over 32 bits.

use ircache_math::rng::mix64;

/// Division and remainder by a fixed `u32` as multiplications (Lemire, Kaser & Kurz, "Faster
/// remainder by direct computation", 2019): exact for every `u32` dividend. The samplers divide
/// by their sample count and grid sides in every sample; where these are not powers of two (35
/// samples for 32 asked, a 7 × 5 grid) hardware division was a quarter of a path-traced render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Divisor {
    d: u32,
    /// ⌈2⁶⁴ / d⌉ (0 for d = 1, whose quotient is the dividend).
    m: u64,
}

impl Default for Divisor {
    fn default() -> Self {
        Divisor::new(1)
    }
}

impl Divisor {
    /// Dividing by `d` (at least 1).
    #[must_use]
    pub fn new(d: u32) -> Self {
        assert!(d > 0, "division by zero");
        let m = if d == 1 {
            0
        } else {
            u64::MAX / u64::from(d) + 1
        };
        Divisor { d, m }
    }

    /// The divisor.
    #[inline]
    #[must_use]
    pub fn get(self) -> u32 {
        self.d
    }

    /// `a / d`.
    #[inline]
    #[must_use]
    pub fn quotient(self, a: u32) -> u32 {
        if self.d == 1 {
            a
        } else {
            ((u128::from(self.m) * u128::from(a)) >> 64) as u32
        }
    }

    /// `a % d`.
    #[inline]
    #[must_use]
    pub fn remainder(self, a: u32) -> u32 {
        let low = self.m.wrapping_mul(u64::from(a));
        ((u128::from(low) * u128::from(self.d)) >> 64) as u32
    }

    /// `(a / d, a % d)`.
    #[inline]
    #[must_use]
    pub fn div_rem(self, a: u32) -> (u32, u32) {
        (self.quotient(a), self.remainder(a))
    }
}

/// A random permutation of `[0, n)` chosen by `seed`, evaluated at `i` (Kensler's `permute`:
/// invertible operations on the bits under the smallest all-ones mask ≥ n − 1, with cycle
/// walking until the value falls in range).
#[inline]
#[must_use]
pub fn permute(mut i: u32, n: Divisor, seed: u32) -> u32 {
    let count = n.get();
    debug_assert!(i < count);
    if count <= 1 {
        return 0;
    }
    let w = u32::MAX >> (count - 1).leading_zeros();
    loop {
        i = kensler_round(i, w, seed);
        if i < count {
            break;
        }
    }
    n.remainder(i.wrapping_add(seed))
}

/// Lanes of [`permute_lanes`] and [`div_rem_lanes`]: a batch of samples.
pub const LANES: usize = 16;

/// [`permute`] of `LANES` indices at once, the same values: every lane takes each round and keeps
/// it while it still walks its cycle, so that the loop runs in vector lanes instead of one chain
/// of a dozen dependent multiplications after another. Every index must be below `n`.
#[inline]
#[must_use]
pub fn permute_lanes(i: &[u32; LANES], n: Divisor, seed: u32) -> [u32; LANES] {
    let count = n.get();
    if count <= 1 {
        return [0; LANES];
    }
    let w = u32::MAX >> (count - 1).leading_zeros();
    let mut x = i.map(|v| kensler_round(v, w, seed));
    // A lane leaves [0, n) with probability below 1/2 a round (n > (w + 1) / 2).
    while x.iter().fold(false, |any, &v| any | (v >= count)) {
        for v in &mut x {
            let next = kensler_round(*v, w, seed);
            *v = if *v >= count { next } else { *v };
        }
    }
    div_rem_lanes(&x.map(|v| v.wrapping_add(seed)), count).1
}

/// `(a / d, a % d)` for `LANES` dividends at once, exact: the quotient's estimate
/// ⌊a·⌊(2³² − 1)/d⌋ / 2³²⌋ is short by at most two, which two corrections of the remainder
/// make good; 32 × 32-bit products, unlike [`Divisor`]'s 128-bit ones, run in vector lanes.
#[inline]
#[must_use]
pub fn div_rem_lanes(a: &[u32; LANES], d: u32) -> ([u32; LANES], [u32; LANES]) {
    let (d, m) = (u64::from(d), u64::from(u32::MAX / d));
    let mut q = [0u32; LANES];
    let mut r = [0u32; LANES];
    for ((&a, q), r) in a.iter().zip(&mut q).zip(&mut r) {
        let a = u64::from(a);
        let mut qe = (a * m) >> 32;
        let mut re = a - qe * d;
        for _ in 0..2 {
            let over = re >= d;
            re -= if over { d } else { 0 };
            qe += u64::from(over);
        }
        (*q, *r) = (qe as u32, re as u32);
    }
    (q, r)
}

/// One round of Kensler's hash of `i` under the mask `w` (seed `p`): invertible on `[0, w]`.
#[inline(always)]
fn kensler_round(mut i: u32, w: u32, p: u32) -> u32 {
    i ^= p;
    i = i.wrapping_mul(0xe170_893d);
    i ^= p >> 16;
    i ^= (i & w) >> 4;
    i ^= p >> 8;
    i = i.wrapping_mul(0x0929_eb3f);
    i ^= p >> 23;
    i ^= (i & w) >> 1;
    i = i.wrapping_mul(1 | p >> 27);
    i = i.wrapping_mul(0x6935_fa69);
    i ^= (i & w) >> 11;
    i = i.wrapping_mul(0x74dc_b303);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0x9e50_1cc3);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0xc860_a3df);
    i &= w;
    i ^= i >> 5;
    i
}

/// 32 well-mixed bits from a key and a salt.
#[inline]
#[must_use]
pub fn hash32(key: u64, salt: u64) -> u32 {
    (mix64(key ^ salt.wrapping_mul(0x9E37_79B9_7F4A_7C15)) >> 32) as u32
}

/// 64 well-mixed bits from a key and a salt.
#[inline]
#[must_use]
pub fn hash64(key: u64, salt: u64) -> u64 {
    mix64(key ^ salt.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// A float in `[0, 1)` from the top 24 bits of `bits`.
#[inline]
#[must_use]
pub fn to_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Burley's nested uniform scramble: an Owen scramble of the 32-bit fixed-point value `x` (each
/// bit flipped by a hash of the bits above it), so every elementary interval of a net maps to one
/// of the same size and a (t, m, s)-net stays one.
#[inline]
#[must_use]
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    let mut v = x.reverse_bits();
    // Laine–Karras-style permutation: each operation only carries from low to high bits of the
    // reversed value, that is from the high bits of x to its lower ones.
    v = v.wrapping_add(seed);
    v ^= v.wrapping_mul(0x6c50_b47c);
    v ^= v.wrapping_mul(0xb82f_1e52);
    v ^= v.wrapping_mul(0xc7af_e638);
    v ^= v.wrapping_mul(0x8d22_f6e6);
    v.reverse_bits()
}

/// The first Sobol' dimension (van der Corput in base 2) of point `i`, as 32-bit fixed point.
#[inline]
#[must_use]
pub fn sobol_0(i: u32) -> u32 {
    i.reverse_bits()
}

/// The second Sobol' dimension (primitive polynomial x + 1, direction numbers all 1: the generator
/// matrix is Pascal's triangle mod 2) of point `i`, as 32-bit fixed point. Read as a polynomial
/// a(x) over GF(2) (bit k the coefficient of xᵏ), i maps to a(1 + x), whose bits, reversed,
/// are the point's. On halves of 2s bits, a(1 + x) = a_lo(1 + x) + (1 + xˢ)·a_hi(1 + x), so
/// five shift-and-XOR steps, smallest halves first, compute it without a loop over i's bits.
#[inline]
#[must_use]
pub fn sobol_1(i: u32) -> u32 {
    let mut v = i;
    v ^= (v >> 1) & 0x5555_5555;
    v ^= (v >> 2) & 0x3333_3333;
    v ^= (v >> 4) & 0x0f0f_0f0f;
    v ^= (v >> 8) & 0x00ff_00ff;
    v ^= (v >> 16) & 0x0000_ffff;
    v.reverse_bits()
}

/// The generator g of the `lattice` sampler's rank-1 lattice sequence φ₂(i)·(1, g): of the odd
/// g < 2¹², the one whose lattices of 4 to 4 096 points have the longest shortest vector relative
/// to a hexagonal lattice's of the same density, at its worst over those sizes (0.71 at 4 points,
/// where no lattice does better; 0.90 at 16, 0.95 at 64, 0.99 at 256).
pub const LATTICE_GENERATOR: u32 = 3045;

/// Point `i` of the `lattice` sampler's sequence (32-bit fixed point): φ₂(i)·(1, ±g) mod 1 plus a
/// shift, from `shift`'s two words (its lowest bit of the second picks the sign, a mirror image:
/// which of the two a scene prefers depends on how its integrands lie, so neither is fixed).
/// Since φ₂(2ᵏq + j) = φ₂(j) + φ₂(q)/2ᵏ, every aligned block of 2ᵏ indices is the 2ᵏ-point
/// rank-1 lattice, shifted.
#[inline]
#[must_use]
pub fn lattice_point(i: u32, shift: u64) -> (u32, u32) {
    let g = if shift >> 32 & 1 == 1 {
        LATTICE_GENERATOR.wrapping_neg()
    } else {
        LATTICE_GENERATOR
    };
    let v = i.reverse_bits();
    (
        v.wrapping_add(shift as u32),
        v.wrapping_mul(g).wrapping_add((shift >> 32) as u32),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permute_is_a_permutation_and_depends_on_the_seed() {
        for n in [1u32, 2, 3, 7, 16, 17, 64, 100, 121, 1000] {
            for seed in [0u32, 1, 0xdead_beef, 12345] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let j = permute(i, Divisor::new(n), seed);
                    assert!(j < n && !seen[j as usize], "n {n} seed {seed}");
                    seen[j as usize] = true;
                }
            }
        }
        let a: Vec<u32> = (0..64).map(|i| permute(i, Divisor::new(64), 1)).collect();
        let b: Vec<u32> = (0..64).map(|i| permute(i, Divisor::new(64), 2)).collect();
        assert_ne!(a, b);
    }

    #[test]
    fn divisor_agrees_with_hardware_division() {
        let mut rng = ircache_math::Rng::keyed(7, &[1]);
        let mut dividends = vec![
            0u32,
            1,
            2,
            3,
            u32::MAX,
            u32::MAX - 1,
            1 << 31,
            (1 << 31) - 1,
        ];
        dividends.extend((0..2000).map(|_| rng.next_u32()));
        let mut divisors: Vec<u32> = (1..=300).collect();
        divisors.extend([
            1 << 16,
            65_537,
            1 << 31,
            (1 << 31) + 1,
            u32::MAX - 1,
            u32::MAX,
        ]);
        divisors.extend((0..200).map(|_| rng.next_u32().max(1)));
        for &d in &divisors {
            let by = Divisor::new(d);
            for &a in &dividends {
                assert_eq!(by.div_rem(a), (a / d, a % d), "{a} by {d}");
            }
            // The lanes' division too, sixteen dividends at a time.
            for chunk in dividends.chunks_exact(LANES) {
                let a: [u32; LANES] = chunk.try_into().unwrap();
                let (q, r) = div_rem_lanes(&a, d);
                for l in 0..LANES {
                    assert_eq!((q[l], r[l]), (a[l] / d, a[l] % d), "{} by {d}", a[l]);
                }
            }
        }
    }

    /// The lanes' permutation is the permutation, cycle walking and all: every n to 300 and
    /// some larger ones, several seeds, indices from every part of [0, n).
    #[test]
    fn permute_lanes_equals_permute() {
        let mut rng = ircache_math::Rng::keyed(9, &[2]);
        for n in (1..=300).chain([506, 1024, 4099, 65_537]) {
            let by = Divisor::new(n);
            for _ in 0..4 {
                let seed = rng.next_u32();
                let i: [u32; LANES] = std::array::from_fn(|_| rng.next_u32() % n);
                let lanes = permute_lanes(&i, by, seed);
                for l in 0..LANES {
                    let want = permute(i[l], by, seed);
                    assert_eq!(lanes[l], want, "n {n} seed {seed} i {}", i[l]);
                }
            }
        }
    }

    #[test]
    fn sobol_matches_its_definition() {
        // Direction numbers of dimension 1: v_k = v_{k-1} ^ (v_{k-1} >> 1), v_0 = 1/2; the point is
        // the XOR of the v_k for the set bits of i (Bratley & Fox 1988).
        let mut v = [0u32; 32];
        v[0] = 1 << 31;
        for k in 1..32 {
            v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        }
        let mut rng = ircache_math::Rng::new(7, 1);
        let some = (0..1000).map(|_| rng.next_u32());
        for i in [0u32, 1, 2, 3, 5, 77, 1023, 0xffff_ffff]
            .into_iter()
            .chain(some)
        {
            let want = (0..32)
                .filter(|k| i >> k & 1 == 1)
                .fold(0, |acc, k| acc ^ v[k]);
            assert_eq!(sobol_1(i), want);
        }
        // First points of the 2-D sequence in index order: (0,0), (½,½), (¼,¾), (¾,¼).
        let f = |x: u32| f64::from(x) / 4_294_967_296.0;
        let pts: Vec<(f64, f64)> = (0..4).map(|i| (f(sobol_0(i)), f(sobol_1(i)))).collect();
        assert_eq!(
            pts,
            vec![(0.0, 0.0), (0.5, 0.5), (0.25, 0.75), (0.75, 0.25)]
        );
    }

    #[test]
    fn owen_scramble_is_a_bijection_preserving_prefixes() {
        // Values sharing their top k bits still share them after scrambling.
        for seed in [0u32, 7, 0x1234_5678] {
            for x in [0u32, 1 << 31, 0xffff_0000, 0x8000_1234] {
                for k in 1..16 {
                    let y = x ^ (1 << (31 - k)); // differs from x first at bit k (from the top)
                    let (sx, sy) = (owen_scramble(x, seed), owen_scramble(y, seed));
                    assert_eq!(sx >> (32 - k), sy >> (32 - k), "top {k} bits");
                    assert_ne!(sx >> (31 - k), sy >> (31 - k), "bit {k} must differ");
                }
            }
        }
        let mut seen = std::collections::HashSet::new();
        for x in 0..4096u32 {
            assert!(seen.insert(owen_scramble(x << 20, 99) >> 20));
        }
    }
}
