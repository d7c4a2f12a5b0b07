//! The false-colour picture of `shared/tools/relmse.py --falsecolor`: per pixel the relative
//! luminance error e = (La − Lb) / (Lb + 0.01) / range, clipped to [−1, 1], shown as white for 0,
//! towards red (1, 0, 0) where A is brighter and towards blue (0, 0, 1) where A is darker.

use crate::compare::{luminance, EPS};
use crate::{srgb, Image};
use ircache_math::Rgb;

/// The display colour (sRGB-encoded, in [0, 1]) of a clipped error `e ∈ [−1, 1]`.
#[must_use]
pub fn colour_of(e: f64) -> [f64; 3] {
    let (pos, neg) = (e.max(0.0), (-e).max(0.0));
    [1.0 - neg, 1.0 - pos - neg, 1.0 - pos].map(|v| v.clamp(0.0, 1.0))
}

/// The relative luminance error of A against B, divided by `range` and clipped to [−1, 1]
/// (a `range` that is not positive makes every non-zero error saturate; NaN stays NaN).
#[must_use]
pub fn clipped_error(a: Rgb, b: Rgb, range: f64) -> f64 {
    let (la, lb) = (luminance(a), luminance(b));
    let rel = (la - lb) / (lb + EPS);
    let e = if range > 0.0 {
        rel / range
    } else {
        rel * f64::INFINITY
    };
    if e.is_nan() && !rel.is_nan() {
        0.0 // 0 · ∞ when rel = 0 and range ≤ 0
    } else {
        e.clamp(-1.0, 1.0)
    }
}

/// relmse.py's false-colour image of A against B, saturating at a relative error of ±`range`.
///
/// The pixels are *linear* values: the display colours of relmse.py put through the sRGB EOTF, so
/// that [`crate::write_png`] at exposure 0 (which applies the sRGB OETF) writes relmse.py's PNG
/// codes (to within one code where a value falls on a rounding boundary). Pixels whose error is
/// NaN come out black. If the sizes differ (which [`crate::compare::compare`] reports as an error),
/// the result is black, of A's size.
#[must_use]
pub fn false_colour(a: &Image, b: &Image, range: f64) -> Image {
    let mut out = Image::new(a.width, a.height);
    if a.width != b.width || a.height != b.height || a.pixels.len() != b.pixels.len() {
        return out;
    }
    for (o, (&pa, &pb)) in out.pixels.iter_mut().zip(a.pixels.iter().zip(&b.pixels)) {
        let e = clipped_error(pa, pb, range);
        if e.is_nan() {
            continue;
        }
        let [r, g, bl] = colour_of(e).map(|v| srgb::eotf(v) as f32);
        *o = Rgb::new(r, g, bl);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// relmse.py's 8-bit code of a display value: `(clip(v, 0, 1) * 255 + 0.5).astype(uint8)`.
    fn code(v: f64) -> u8 {
        (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
    }

    #[test]
    fn colours_match_relmse_py() {
        assert_eq!(colour_of(0.0), [1.0, 1.0, 1.0]);
        assert_eq!(colour_of(1.0), [1.0, 0.0, 0.0]);
        assert_eq!(colour_of(-1.0), [0.0, 0.0, 1.0]);
        assert_eq!(colour_of(0.5), [1.0, 0.5, 0.5]);
        let b = Rgb::splat(1.0);
        // A 10 % brighter with range 0.5: e = 0.1 / 1.01 / 0.5.
        let e = clipped_error(Rgb::splat(1.1), b, 0.5);
        assert!((e - 0.1 / 1.01 / 0.5).abs() < 1e-6, "{e}");
        assert_eq!(clipped_error(Rgb::splat(3.0), b, 0.5), 1.0);
        assert_eq!(clipped_error(Rgb::ZERO, b, 0.5), -1.0);
        assert_eq!(clipped_error(b, b, 0.0), 0.0);
        assert_eq!(clipped_error(Rgb::splat(1.01), b, 0.0), 1.0);
    }

    #[test]
    fn png_codes_match_relmse_py() {
        // Every error on a fine grid: write_png's codes of the linear pixels equal relmse.py's.
        let n = 2001;
        let b = Image {
            width: n,
            height: 1,
            pixels: vec![Rgb::splat(1.0); n],
        };
        let mut a = b.clone();
        for (i, p) in a.pixels.iter_mut().enumerate() {
            *p = Rgb::splat(0.4 + 1.2 * i as f32 / (n - 1) as f32);
        }
        let fc = false_colour(&a, &b, 0.5);
        let codes = crate::png::to_srgb8(&fc, 0.0);
        let mut off = 0;
        for (i, (&pa, &pb)) in a.pixels.iter().zip(&b.pixels).enumerate() {
            let want = colour_of(clipped_error(pa, pb, 0.5)).map(code);
            let got = [codes[3 * i], codes[3 * i + 1], codes[3 * i + 2]];
            for k in 0..3 {
                let d = (i32::from(want[k]) - i32::from(got[k])).abs();
                assert!(d <= 1, "pixel {i}: {got:?} vs {want:?}");
                off += usize::from(d != 0);
            }
        }
        assert!(off <= n / 100, "{off} codes off by one");
        assert_eq!(&codes[..3], &[0, 0, 255]);
        assert_eq!(&codes[3 * (n - 1)..], &[255, 0, 0]);
    }

    #[test]
    fn size_mismatch_gives_black() {
        let a = Image::new(3, 2);
        let b = Image::new(2, 3);
        let fc = false_colour(&a, &b, 0.5);
        assert_eq!((fc.width, fc.height), (3, 2));
        assert!(fc.pixels.iter().all(|p| p.is_black()));
    }
}
