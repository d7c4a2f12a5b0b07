//! The error measures of `shared/tools/relmse.py` (its `metrics`), computed in `f64` exactly as
//! the script computes them, so that `ircache compare` and the script print the same figures.
//!
//! With A the image under test, B the reference, d = a − b per channel and L the Rec. 709 luminance:
//! - `rel_mse`: mean over pixels and channels of d² / (b² + 0.01);
//! - `rel_mse_trim`: the same over the `round(n · 0.999)` pixels (Python's round, half to even)
//!   with the smallest per-pixel value (the mean over the 3 channels), i.e. without the worst 0.1 %;
//! - `rmse`: √(mean over pixels and channels of d²);
//! - `mre_lum`: mean over pixels of |La − Lb| / (Lb + 0.01);
//! - `lum_ratio`: mean La / mean Lb; `mean_lum_a`, `mean_lum_b`;
//! - `nonfinite_a`: how many channel values of A are NaN or infinite.
//!
//! Sums are compensated (Neumaier), so the results agree with numpy's pairwise sums to about 1e-15.

use crate::Image;
use ircache_math::Rgb;

/// The constant in the denominators of the relative measures (relmse.py's `1e-2`).
pub const EPS: f64 = 1e-2;

/// Rec. 709 luminance weights, as relmse.py's `LUM`.
pub const LUM: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Rec. 709 luminance in `f64` (as relmse.py's `a @ LUM`).
#[must_use]
pub fn luminance(c: Rgb) -> f64 {
    LUM[0] * f64::from(c.r) + LUM[1] * f64::from(c.g) + LUM[2] * f64::from(c.b)
}

/// The measures of one comparison (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    /// Mean over pixels and channels of (a − b)² / (b² + 0.01).
    pub rel_mse: f64,
    /// `rel_mse` without the worst 0.1 % of pixels.
    pub rel_mse_trim: f64,
    /// Root mean square error over pixels and channels.
    pub rmse: f64,
    /// Mean over pixels of |La − Lb| / (Lb + 0.01).
    pub mre_lum: f64,
    /// Mean luminance of A over mean luminance of B.
    pub lum_ratio: f64,
    /// Mean luminance of A.
    pub mean_lum_a: f64,
    /// Mean luminance of B.
    pub mean_lum_b: f64,
    /// Channel values of A that are NaN or infinite.
    pub nonfinite_a: usize,
}

/// Why two images cannot be compared.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum CompareError {
    /// The images differ in size.
    #[error(
        "image sizes differ: {a_width}×{a_height} (image) vs {b_width}×{b_height} (reference)"
    )]
    SizeMismatch {
        /// Width of A.
        a_width: usize,
        /// Height of A.
        a_height: usize,
        /// Width of B.
        b_width: usize,
        /// Height of B.
        b_height: usize,
    },
    /// The images have no pixels.
    #[error("the images are empty ({width}×{height})")]
    Empty {
        /// Width.
        width: usize,
        /// Height.
        height: usize,
    },
    /// An image's pixel buffer does not hold width × height pixels.
    #[error("malformed image: {len} pixels for a size of {width}×{height}")]
    Malformed {
        /// Width.
        width: usize,
        /// Height.
        height: usize,
        /// Pixels held.
        len: usize,
    },
}

/// A compensated (Neumaier) sum.
#[derive(Clone, Copy, Default)]
struct Sum {
    s: f64,
    c: f64,
}

impl Sum {
    fn add(&mut self, x: f64) {
        let t = self.s + x;
        if self.s.abs() >= x.abs() {
            self.c += (self.s - t) + x;
        } else {
            self.c += (x - t) + self.s;
        }
        self.s = t;
    }
    fn get(self) -> f64 {
        // With an infinite term the compensation is NaN; numpy's sum is then ±∞ (or NaN), as `s`.
        if self.s.is_finite() {
            self.s + self.c
        } else {
            self.s
        }
    }
}

/// relmse.py's per-pixel relMSE: the mean over the channels of (a − b)² / (b² + 0.01).
#[must_use]
pub fn pixel_rel_mse(a: Rgb, b: Rgb) -> f64 {
    let e = |x: f32, y: f32| {
        let (x, y) = (f64::from(x), f64::from(y));
        let d = x - y;
        d * d / (y * y + EPS)
    };
    (e(a.r, b.r) + e(a.g, b.g) + e(a.b, b.b)) / 3.0
}

/// How many of `n` per-pixel values relMSE_trim keeps: Python's `int(round(n * 0.999))`.
#[must_use]
pub fn trim_keep(n: usize) -> usize {
    (n as f64 * 0.999).round_ties_even() as usize
}

fn check(img: &Image) -> Result<(), CompareError> {
    if img.width.checked_mul(img.height) != Some(img.pixels.len()) {
        return Err(CompareError::Malformed {
            width: img.width,
            height: img.height,
            len: img.pixels.len(),
        });
    }
    Ok(())
}

/// Compares A (`a`, the image under test) against the reference B (`b`): relmse.py's measures.
pub fn compare(a: &Image, b: &Image) -> Result<Metrics, CompareError> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(CompareError::SizeMismatch {
            a_width: a.width,
            a_height: a.height,
            b_width: b.width,
            b_height: b.height,
        });
    }
    check(a)?;
    check(b)?;
    let n = a.pixels.len();
    if n == 0 {
        return Err(CompareError::Empty {
            width: a.width,
            height: a.height,
        });
    }
    let mut per_pixel = Vec::with_capacity(n);
    let (mut rel, mut sq, mut mre, mut la_sum, mut lb_sum) = (
        Sum::default(),
        Sum::default(),
        Sum::default(),
        Sum::default(),
        Sum::default(),
    );
    let mut nonfinite_a = 0;
    for (&pa, &pb) in a.pixels.iter().zip(&b.pixels) {
        let e = pixel_rel_mse(pa, pb);
        per_pixel.push(e);
        rel.add(e);
        for (x, y) in pa.to_array().into_iter().zip(pb.to_array()) {
            let d = f64::from(x) - f64::from(y);
            sq.add(d * d);
            nonfinite_a += usize::from(!x.is_finite());
        }
        let (la, lb) = (luminance(pa), luminance(pb));
        mre.add((la - lb).abs() / (lb + EPS));
        la_sum.add(la);
        lb_sum.add(lb);
    }
    // numpy's sort puts NaN last; so does this order, so the trim drops NaN pixels first.
    per_pixel.sort_unstable_by(|x, y| match (x.is_nan(), y.is_nan()) {
        (false, false) => x.partial_cmp(y).unwrap_or(std::cmp::Ordering::Equal),
        (nan_x, nan_y) => nan_x.cmp(&nan_y),
    });
    let keep = trim_keep(n);
    let mut trim = Sum::default();
    for &e in &per_pixel[..keep] {
        trim.add(e);
    }
    let nf = n as f64;
    let (mean_lum_a, mean_lum_b) = (la_sum.get() / nf, lb_sum.get() / nf);
    Ok(Metrics {
        rel_mse: rel.get() / nf,
        rel_mse_trim: trim.get() / keep as f64,
        rmse: (sq.get() / (3.0 * nf)).sqrt(),
        mre_lum: mre.get() / nf,
        lum_ratio: mean_lum_a / mean_lum_b,
        mean_lum_a,
        mean_lum_b,
        nonfinite_a,
    })
}
