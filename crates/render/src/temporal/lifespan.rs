//! A record's lifespan from its change over one frame (001 eqs. 5.1–5.8, with the fixes of
//! `ERRATA.md` item 8 and `NOTES-001.md` D.2).
//!
//! The change over time is δE ≈ ∂E/∂t (t − t₀) (5.1) with ∂E/∂t ≈ E₀(τ − 1) per frame, τ =
//! E₁/E₀ (5.2–5.4). The record is usable at frame t while its temporal weight w_t = 1/(|τ − 1|
//! (t − t₀)) (5.5, with |τ − 1|: the printed τ − 1 is negative for falling light) is at least
//! 1/a_t (5.6), and for at most δt_max frames (5.8). So it lives
//! L = min(⌊a_t / |τ − 1|⌋, δt_max − 1) frames after t₀, its own frame always included.

use ircache_math::Rgb;

/// |τ − 1| of an irradiance: the largest relative change of a channel over the frame,
/// |E₁ − E₀| / max(E₀, `floor`). `floor` (a small share of the scene's typical irradiance) keeps
/// nearly black records from expiring on changes no one can see (NOTES-001 D.2's ε·E_ambient).
#[must_use]
pub fn relative_change(e0: Rgb, e1: Rgb, floor: f32) -> f32 {
    let floor = floor.max(f32::MIN_POSITIVE);
    [(e0.r, e1.r), (e0.g, e1.g), (e0.b, e1.b)]
        .into_iter()
        .map(|(a, b)| (b - a).abs() / a.max(floor))
        .fold(0.0, f32::max)
}

/// |τ − 1| of radiance coefficients (001 eq. 5.7 as `NOTES-001.md` D.2 fixes it: a ratio of
/// coefficients is undefined where they are zero or negative): per channel
/// ‖Λ¹ − Λ⁰‖₂ / ‖Λ⁰‖₂, the largest; `a` and `b` hold `channels` equal runs (`[channel][i]`).
#[must_use]
pub fn coefficient_change(a: &[f64], b: &[f64], channels: usize) -> f32 {
    let n = a.len() / channels.max(1);
    if n == 0 || a.len() != b.len() {
        return 0.0;
    }
    a.chunks(n)
        .zip(b.chunks(n))
        .map(|(x, y)| {
            let d: f64 = x.iter().zip(y).map(|(p, q)| (q - p) * (q - p)).sum();
            let norm: f64 = x.iter().map(|p| p * p).sum();
            if norm > 0.0 {
                (d / norm).sqrt()
            } else if d > 0.0 {
                f64::INFINITY
            } else {
                0.0
            }
        })
        .fold(0.0, f64::max) as f32
}

/// The frames a record lives after its own (L of D.2): the last frame it serves is t₀ + L.
/// `accuracy` is a_t; `max_lifespan` is δt_max ≥ 1 (1: every record lives one frame).
#[must_use]
pub fn lifespan(change: f32, accuracy: f32, max_lifespan: u32) -> u32 {
    let cap = max_lifespan.max(1) - 1;
    if change.is_nan() {
        // Never trusted to extend a life.
        return 0;
    }
    if change <= 0.0 {
        // No change: only δt_max bounds it.
        return cap;
    }
    let frames = (accuracy / change).floor();
    if frames >= cap as f32 {
        cap
    } else {
        frames.max(0.0) as u32
    }
}

/// The temporal weight of 5.5 with |τ − 1| (infinite in the record's own frame).
#[must_use]
pub fn temporal_weight(change: f32, age: u32) -> f32 {
    1.0 / (change * age as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worked_examples_of_the_notes() {
        // a_t = 0.05 and a 1 %/frame change give 5 frames.
        assert_eq!(lifespan(0.01, 0.05, 20), 5);
        // 0.25 %/frame gives 20, capped by δt_max = 20 to 19.
        assert_eq!(lifespan(0.0025, 0.05, 20), 19);
        // A static record lives δt_max − 1 frames after its own; δt_max = 1 renews every frame.
        assert_eq!(lifespan(0.0, 0.05, 10), 9);
        assert_eq!(lifespan(0.0, 0.05, 1), 0);
        assert_eq!(lifespan(f32::NAN, 0.05, 10), 0);
    }

    #[test]
    fn the_gate_of_5_6_agrees_with_the_lifespan() {
        // w_t ≥ 1/a_t exactly on the frames 1..=L (below δt_max).
        for &change in &[0.003f32, 0.007, 0.012, 0.02, 0.049, 0.2] {
            let a_t = 0.05;
            let l = lifespan(change, a_t, 1000);
            for age in 1..=l {
                assert!(temporal_weight(change, age) >= 1.0 / a_t * (1.0 - 1e-6));
            }
            assert!(temporal_weight(change, l + 1) < 1.0 / a_t);
        }
    }

    #[test]
    fn coefficient_change_is_a_norm_ratio_per_channel() {
        // Channel 0: (3, 4) → (3, 4.5): 0.5/5; channel 1 unchanged.
        let a = [3.0, 4.0, 1.0, 0.0];
        let b = [3.0, 4.5, 1.0, 0.0];
        assert!((coefficient_change(&a, &b, 2) - 0.1).abs() < 1e-7);
        // Negative coefficients count by their size: (−3, −4) → (−3, −3.5) is also 0.1.
        assert!((coefficient_change(&[-3.0, -4.0], &[-3.0, -3.5], 1) - 0.1).abs() < 1e-7);
        assert_eq!(coefficient_change(&[0.0, 0.0], &[0.0, 0.0], 1), 0.0);
    }

    #[test]
    fn change_is_relative_per_channel_and_sign_free() {
        let e0 = Rgb::new(1.0, 2.0, 4.0);
        assert!((relative_change(e0, Rgb::new(1.0, 2.0, 3.8), 0.0) - 0.05).abs() < 1e-6);
        assert!((relative_change(e0, Rgb::new(1.1, 2.0, 4.0), 0.0) - 0.1).abs() < 1e-6);
        // The floor: a black record changing by 0.01 against a floor of 1.
        let black = Rgb::ZERO;
        assert!((relative_change(black, Rgb::splat(0.01), 1.0) - 0.01).abs() < 1e-7);
    }
}
