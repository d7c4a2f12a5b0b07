//! Gaussian blur of an image, the low-pass filter of `ircache compare --blur`: after a small blur
//! a path tracer's pixel noise fades while a cache's low-frequency error (blotches, leaks, bias)
//! stays, so the blurred relMSE measures the latter.

use crate::Image;
use ircache_math::Rgb;

/// The image convolved with a normalised Gaussian of standard deviation `sigma` pixels,
/// separably, truncated at 3σ; at the borders the kernel is renormalised over the pixels inside
/// the image (no darkening at the edges). `sigma` ≤ 0 returns a copy.
#[must_use]
pub fn gaussian_blur(img: &Image, sigma: f64) -> Image {
    if sigma.is_nan() || sigma <= 0.0 || img.width == 0 || img.height == 0 {
        return img.clone();
    }
    let radius = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f64> = (-radius..=radius)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let pass = |src: &Image, horizontal: bool| -> Image {
        let mut out = Image::new(src.width, src.height);
        let (w, h) = (src.width as isize, src.height as isize);
        for y in 0..h {
            for x in 0..w {
                let (mut acc, mut wsum) = ([0.0f64; 3], 0.0f64);
                for (k, &kw) in kernel.iter().enumerate() {
                    let o = k as isize - radius;
                    let (sx, sy) = if horizontal { (x + o, y) } else { (x, y + o) };
                    if sx < 0 || sy < 0 || sx >= w || sy >= h {
                        continue;
                    }
                    let c = src.get(sx as usize, sy as usize);
                    for (a, v) in acc.iter_mut().zip([c.r, c.g, c.b]) {
                        *a += kw * f64::from(v);
                    }
                    wsum += kw;
                }
                out.set(
                    x as usize,
                    y as usize,
                    Rgb::new(
                        (acc[0] / wsum) as f32,
                        (acc[1] / wsum) as f32,
                        (acc[2] / wsum) as f32,
                    ),
                );
            }
        }
        out
    };
    pass(&pass(img, true), false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_stays_and_an_impulse_spreads_as_a_gaussian() {
        let mut img = Image::new(31, 21);
        for p in &mut img.pixels {
            *p = Rgb::splat(2.5);
        }
        let b = gaussian_blur(&img, 2.0);
        assert!(b.pixels.iter().all(|p| (p.r - 2.5).abs() < 1e-5));
        // An impulse far from the borders: total kept, profile exp(−d²/2σ²) up to normalisation.
        let mut img = Image::new(41, 41);
        img.set(20, 20, Rgb::splat(1.0));
        let b = gaussian_blur(&img, 2.0);
        let total: f64 = b.pixels.iter().map(|p| f64::from(p.g)).sum();
        assert!((total - 1.0).abs() < 1e-5, "{total}");
        let ratio = f64::from(b.get(23, 20).g / b.get(20, 20).g);
        assert!((ratio - (-9.0f64 / 8.0).exp()).abs() < 1e-4, "{ratio}");
        let diag = f64::from(b.get(22, 22).g / b.get(20, 20).g);
        assert!((diag - (-1.0f64).exp()).abs() < 1e-4, "{diag}");
    }

    #[test]
    fn blur_removes_pixel_noise_but_not_a_step() {
        // Alternating ±0.5 noise around 1 averages out; a left/right step of 1 → 2 keeps its
        // plateaus away from the edge.
        let mut img = Image::new(64, 32);
        for y in 0..32 {
            for x in 0..64 {
                let noise = if (x + y) % 2 == 0 { 0.5 } else { -0.5 };
                let base = if x < 32 { 1.0 } else { 2.0 };
                img.set(x, y, Rgb::splat(base + noise));
            }
        }
        let b = gaussian_blur(&img, 2.0);
        assert!((b.get(8, 16).r - 1.0).abs() < 0.01, "{:?}", b.get(8, 16));
        assert!((b.get(56, 16).r - 2.0).abs() < 0.01, "{:?}", b.get(56, 16));
    }
}
