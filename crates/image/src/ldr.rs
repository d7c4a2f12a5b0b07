//! 8-bit and 16-bit image input (PNG, JPEG, TGA, BMP) through the `image` crate, decoded to linear
//! RGB: sRGB codes through the sRGB EOTF, or as code / 255 (code / 65535) when `raw`. Grey is
//! replicated to RGB and alpha dropped; float images the `image` crate decodes are taken as stored.

use crate::{guard, read_bytes, srgb, Image, ImageError};
use image::{DynamicImage, ImageFormat, ImageReader};
use ircache_math::Rgb;
use std::io::Cursor;
use std::path::Path;

/// Decodes an 8/16-bit image held in memory; `format_hint` is used when the content does not
/// identify the format (TGA has no signature).
pub fn decode(bytes: &[u8], format_hint: Option<ImageFormat>, raw: bool) -> Result<Image, String> {
    guard(|| {
        let mut reader = ImageReader::new(Cursor::new(bytes));
        if let Some(f) = format_hint {
            reader.set_format(f);
        }
        let reader = reader.with_guessed_format().map_err(|e| e.to_string())?;
        if reader.format().is_none() {
            return Err("unknown image format".into());
        }
        let img = reader.decode().map_err(|e| format!("cannot decode: {e}"))?;
        Ok(convert(&img, raw))
    })
}

/// A decoded image as linear RGB.
fn convert(img: &DynamicImage, raw: bool) -> Image {
    let (width, height) = (img.width() as usize, img.height() as usize);
    let pixels: Vec<Rgb> = match img {
        DynamicImage::ImageRgb32F(_) | DynamicImage::ImageRgba32F(_) => img
            .to_rgb32f()
            .pixels()
            .map(|p| Rgb::from_array(p.0))
            .collect(),
        DynamicImage::ImageLuma16(_)
        | DynamicImage::ImageLumaA16(_)
        | DynamicImage::ImageRgb16(_)
        | DynamicImage::ImageRgba16(_) => {
            let f = |v: u16| {
                let x = f64::from(v) / 65535.0;
                (if raw { x } else { srgb::eotf(x) }) as f32
            };
            img.to_rgb16()
                .pixels()
                .map(|p| Rgb::new(f(p.0[0]), f(p.0[1]), f(p.0[2])))
                .collect()
        }
        _ => {
            let table: [f32; 256] = if raw {
                std::array::from_fn(|i| (i as f64 / 255.0) as f32)
            } else {
                srgb::decode8_table()
            };
            let f = |v: u8| table[usize::from(v)];
            img.to_rgb8()
                .pixels()
                .map(|p| Rgb::new(f(p.0[0]), f(p.0[1]), f(p.0[2])))
                .collect()
        }
    };
    Image {
        width,
        height,
        pixels,
    }
}

/// Reads an 8/16-bit image file as linear RGB (see the module documentation).
pub fn read_ldr(path: &Path, raw: bool) -> Result<Image, ImageError> {
    let bytes = read_bytes(path)?;
    decode(&bytes, ImageFormat::from_path(path).ok(), raw).map_err(|m| ImageError::read(path, m))
}
