//! The sRGB transfer functions (IEC 61966-2-1), in `f64`, and the 8-bit encoding used by
//! `shared/tools/relmse.py` (clamp to [0, 1], OETF, `× 255 + 0.5`, truncate).

/// sRGB OETF: linear [0, 1] to encoded [0, 1].
#[must_use]
pub fn oetf(linear: f64) -> f64 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB EOTF: encoded [0, 1] to linear [0, 1] (the inverse of [`oetf`]).
#[must_use]
pub fn eotf(encoded: f64) -> f64 {
    if encoded <= 0.040_45 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// A linear value as an 8-bit sRGB code: clamped to [0, 1] (NaN → 0), encoded, rounded half up.
#[must_use]
pub fn encode8(linear: f64) -> u8 {
    let x = if linear.is_nan() {
        0.0
    } else {
        linear.clamp(0.0, 1.0)
    };
    // In [0.5, 255.5]: the cast truncates, i.e. rounds half up, as relmse.py's `astype(uint8)`.
    (oetf(x) * 255.0 + 0.5) as u8
}

/// The 256 linear values of the 8-bit sRGB codes.
#[must_use]
pub fn decode8_table() -> [f32; 256] {
    let mut t = [0.0; 256];
    for (i, v) in t.iter_mut().enumerate() {
        *v = eotf(i as f64 / 255.0) as f32;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_codes() {
        assert_eq!(encode8(0.0), 0);
        assert_eq!(encode8(1.0), 255);
        assert_eq!(encode8(0.5), 188);
        assert_eq!(encode8(-3.0), 0);
        assert_eq!(encode8(7.0), 255);
        assert_eq!(encode8(f64::NAN), 0);
        assert_eq!(encode8(0.002), 7); // linear segment: 12.92 · 0.002 · 255 = 6.59
    }

    #[test]
    fn eotf_inverts_oetf_and_codes_round_trip() {
        for i in 0..=1000 {
            let x = f64::from(i) / 1000.0;
            assert!((eotf(oetf(x)) - x).abs() < 1e-12, "{x}");
        }
        let t = decode8_table();
        for (i, v) in t.iter().enumerate() {
            assert_eq!(usize::from(encode8(f64::from(*v))), i);
        }
    }
}
