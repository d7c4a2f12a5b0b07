//! OpenEXR input and output through the `exr` crate.
//!
//! Output is one layer of 32-bit float `R`, `G`, `B` channels in ZIP-compressed scanline blocks
//! (16 lines), increasing line order: the plainest kind of EXR, which OpenEXR, Mitsuba 3's
//! `mi.Bitmap` and the Python tools read. Input accepts the first layer that has `R`, `G` and `B`
//! channels (half, float or uint; any other channel, alpha included, is ignored), scanline or tiled
//! (largest resolution level); a file without them is an error naming the file.

use crate::{guard, read_bytes, write::write_atomically, Image, ImageError, MAX_PIXELS};
use ::exr::prelude::{self as x, ReadChannels, ReadLayers, WritableImage};
use ircache_math::Rgb;
use std::io::Cursor;
use std::path::Path;

/// Encodes `image` as an OpenEXR file in memory (32-bit float RGB, ZIP scanlines).
pub fn encode(image: &Image) -> Result<Vec<u8>, String> {
    if image.width == 0 || image.height == 0 || image.width * image.height != image.pixels.len() {
        return Err(format!(
            "cannot encode a {}×{} image with {} pixels",
            image.width,
            image.height,
            image.pixels.len()
        ));
    }
    let channels = x::SpecificChannels::rgb(|p: x::Vec2<usize>| {
        let c = image.pixels[p.y() * image.width + p.x()];
        (c.r, c.g, c.b)
    });
    let layer = x::Layer::new(
        (image.width, image.height),
        x::LayerAttributes::default(),
        x::Encoding::SMALL_LOSSLESS,
        channels,
    );
    let mut out = Cursor::new(Vec::new());
    x::Image::from_layer(layer)
        .write()
        .to_buffered(&mut out)
        .map_err(|e| e.to_string())?;
    Ok(out.into_inner())
}

/// Decodes an OpenEXR file held in memory: the first layer with `R`, `G` and `B` channels.
pub fn decode(bytes: &[u8]) -> Result<Image, String> {
    guard(|| {
        // Check the size in the header first, so that a corrupt header cannot ask for terabytes.
        let meta = x::MetaData::read_from_buffered(Cursor::new(bytes), false)
            .map_err(|e| format!("not a valid OpenEXR file: {e}"))?;
        for h in &meta.headers {
            let (w, hgt) = (h.layer_size.width(), h.layer_size.height());
            if !matches!(w.checked_mul(hgt), Some(n) if n <= MAX_PIXELS) {
                return Err(format!(
                    "layer size {w}×{hgt} exceeds the limit of {MAX_PIXELS} pixels"
                ));
            }
        }
        let image = x::read()
            .no_deep_data()
            .largest_resolution_level()
            .rgb_channels(
                |size, _| Image::new(size.width(), size.height()),
                |img: &mut Image, p, (r, g, b): (f32, f32, f32)| {
                    if p.x() < img.width && p.y() < img.height {
                        img.set(p.x(), p.y(), Rgb::new(r, g, b));
                    }
                },
            )
            .first_valid_layer()
            .all_attributes()
            .non_parallel()
            .from_buffered(Cursor::new(bytes))
            .map_err(|e| match e {
                x::Error::Invalid(m) if m.contains("no layer in the image matched") => {
                    "no layer with R, G and B channels".to_string()
                }
                e => format!("cannot decode OpenEXR: {e}"),
            })?;
        Ok(image.layer_data.channel_data.pixels)
    })
}

/// Writes `image` as a 32-bit float RGB OpenEXR file (atomically: temporary file, then rename).
pub fn write_exr(path: &Path, image: &Image) -> Result<(), ImageError> {
    crate::check_writable(path, image)?;
    let bytes = encode(image).map_err(|m| ImageError::write(path, m))?;
    write_atomically(path, &bytes)
}

/// Reads an OpenEXR file (RGB or RGBA, half or float) as linear RGB, alpha dropped.
pub fn read_exr(path: &Path) -> Result<Image, ImageError> {
    let bytes = read_bytes(path)?;
    decode(&bytes).map_err(|m| ImageError::read(path, m))
}
