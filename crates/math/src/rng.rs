//! A small, fast, deterministic random number generator (PCG32, O'Neill 2014) whose streams are
//! derived from (seed, pixel, pass) so that an image does not depend on the thread count.

/// PCG32 (XSH RR variant).
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

const MULT: u64 = 6_364_136_223_846_793_005;

/// SplitMix64 finaliser: a good 64-bit hash for seeding.
#[must_use]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Rng {
    /// A generator for stream `stream` of seed `seed`.
    #[must_use]
    pub fn new(seed: u64, stream: u64) -> Rng {
        let mut r = Rng {
            state: 0,
            inc: (mix64(stream ^ 0x5851_F42D_4C95_7F2D) << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(mix64(seed));
        r.next_u32();
        r
    }

    /// A generator keyed by several integers (seed, pixel index, pass, ...).
    #[must_use]
    pub fn keyed(seed: u64, keys: &[u64]) -> Rng {
        let mut h = mix64(seed);
        for &k in keys {
            h = mix64(h ^ k);
        }
        Rng::new(h, mix64(h ^ 0xD1B5_4A32_D192_ED03))
    }

    /// Next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in `[0, 1)`; never returns 1.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two uniform numbers in `[0, 1)`.
    pub fn next_2d(&mut self) -> glam::Vec2 {
        let x = self.next_f32();
        glam::Vec2::new(x, self.next_f32())
    }

    /// Uniform integer in `[0, n)` (n > 0), unbiased by rejection.
    pub fn next_below(&mut self, n: u32) -> u32 {
        let threshold = n.wrapping_neg() % n;
        loop {
            let r = self.next_u32();
            if r >= threshold {
                return r % n;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_key_same_sequence_different_key_different_sequence() {
        let a: Vec<u32> = (0..8)
            .scan(Rng::keyed(7, &[1, 2]), |r, _| Some(r.next_u32()))
            .collect();
        let b: Vec<u32> = (0..8)
            .scan(Rng::keyed(7, &[1, 2]), |r, _| Some(r.next_u32()))
            .collect();
        let c: Vec<u32> = (0..8)
            .scan(Rng::keyed(7, &[2, 1]), |r, _| Some(r.next_u32()))
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn uniform_mean_and_range() {
        let mut r = Rng::new(1, 2);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let x = r.next_f32();
            assert!((0.0..1.0).contains(&x));
            sum += x as f64;
        }
        assert!((sum / n as f64 - 0.5).abs() < 0.005);
    }
}
