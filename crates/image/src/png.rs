//! 8-bit sRGB PNG output through the `image` crate: each channel is multiplied by 2^exposure,
//! clamped to [0, 1], sRGB-encoded and rounded, as `shared/tools/relmse.py --tonemap` does.

use crate::{srgb, write::write_atomically, Image, ImageError};
use image::{codecs::png::PngEncoder, ExtendedColorType, ImageEncoder};
use std::path::Path;

/// The 8-bit sRGB bytes (RGB, row-major, top row first) of `image` scaled by 2^`exposure`.
#[must_use]
pub fn to_srgb8(image: &Image, exposure: f32) -> Vec<u8> {
    let scale = 2f64.powf(f64::from(exposure));
    let mut out = Vec::with_capacity(image.pixels.len() * 3);
    for c in &image.pixels {
        for v in [c.r, c.g, c.b] {
            out.push(srgb::encode8(f64::from(v) * scale));
        }
    }
    out
}

/// Encodes `image` as an 8-bit sRGB PNG in memory.
pub fn encode(image: &Image, exposure: f32) -> Result<Vec<u8>, String> {
    let (w, h) = (u32::try_from(image.width), u32::try_from(image.height));
    let (Ok(w), Ok(h)) = (w, h) else {
        return Err(format!(
            "{}×{} is too large for PNG",
            image.width, image.height
        ));
    };
    if w == 0 || h == 0 || image.width * image.height != image.pixels.len() {
        return Err(format!(
            "cannot encode a {w}×{h} image with {} pixels",
            image.pixels.len()
        ));
    }
    let bytes = to_srgb8(image, exposure);
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(&bytes, w, h, ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())?;
    Ok(out)
}

/// Writes `image` as an 8-bit sRGB PNG: linear values × 2^`exposure`, clamped to [0, 1], sRGB OETF,
/// rounded to the nearest code (atomically: temporary file, then rename).
pub fn write_png(path: &Path, image: &Image, exposure: f32) -> Result<(), ImageError> {
    crate::check_writable(path, image)?;
    let bytes = encode(image, exposure).map_err(|m| ImageError::write(path, m))?;
    write_atomically(path, &bytes)
}
