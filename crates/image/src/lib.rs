//! HDR images: the in-memory linear RGB float [`Image`], reading and writing OpenEXR, Radiance HDR
//! and PNG, loading textures, and the error measures of `../shared/references/README.md`.
//!
//! Layout:
//! - [`exr`]: OpenEXR (32-bit float RGB out; RGB/RGBA, half or float in), via the `exr` crate.
//! - [`hdr`]: Radiance RGBE pictures (`.hdr`, `.pic`), hand-written to match Radiance byte for byte.
//! - [`png`]: 8-bit sRGB PNG output with an exposure in stops.
//! - [`ldr`]: 8/16-bit formats (PNG, JPEG, TGA, BMP) in, via the `image` crate.
//! - [`srgb`]: the sRGB transfer functions.
//! - [`compare`]: the error measures of `shared/tools/relmse.py` (relMSE, relMSE_trim, ...).
//! - [`falsecolor`]: relmse.py's false-colour picture of the relative luminance error.
//!
//! Writers are atomic: they write a temporary file beside the target and rename it over the target,
//! so a failed write never destroys an existing file. Readers never panic on bad input: every
//! malformed, truncated or unsupported file gives [`ImageError::Read`] naming the file.

#![deny(missing_docs)]

use ircache_math::Rgb;
use std::path::Path;

pub mod blur;
pub mod compare;
pub mod exr;
pub mod falsecolor;
pub mod flicker;
pub mod hdr;
pub mod ldr;
pub mod png;
pub mod srgb;
mod write;

pub use crate::exr::{read_exr, write_exr};
pub use crate::hdr::{read_hdr, write_hdr};
pub use crate::png::write_png;

/// The most pixels a reader accepts (16384 × 16384), so that a corrupt header cannot make a reader
/// allocate without bound.
pub const MAX_PIXELS: usize = 1 << 28;

/// A linear RGB float image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width × height` pixels, row-major, top row first.
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// A black image.
    #[must_use]
    pub fn new(width: usize, height: usize) -> Image {
        Image {
            width,
            height,
            pixels: vec![Rgb::ZERO; width * height],
        }
    }
    /// The pixel at column `x`, row `y` (row 0 is the top).
    #[must_use]
    pub fn get(&self, x: usize, y: usize) -> Rgb {
        self.pixels[y * self.width + x]
    }
    /// Sets the pixel at column `x`, row `y`.
    pub fn set(&mut self, x: usize, y: usize, c: Rgb) {
        self.pixels[y * self.width + x] = c;
    }
}

/// Errors reading or writing images.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The file could not be read or decoded; `message` says why.
    #[error("{}: {message}", path.display())]
    Read {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        message: String,
    },
    /// The file could not be written.
    #[error("{}: cannot write: {message}", path.display())]
    Write {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        message: String,
    },
}

impl ImageError {
    pub(crate) fn read(path: &Path, message: impl Into<String>) -> ImageError {
        ImageError::Read {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
    pub(crate) fn write(path: &Path, message: impl Into<String>) -> ImageError {
        ImageError::Write {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// The file formats this crate tells apart by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Exr,
    Hdr,
    Png,
    Other,
}

fn kind(path: &Path) -> Kind {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("exr") => Kind::Exr,
        Some("hdr" | "pic") => Kind::Hdr,
        Some("png") => Kind::Png,
        _ => Kind::Other,
    }
}

/// Writes `image` in the format its extension names: `.exr` (32-bit float OpenEXR), `.hdr` or
/// `.pic` (Radiance RGBE), or `.png` (8-bit sRGB, scaled by 2^`exposure`; `exposure` is ignored by
/// the HDR formats, which store radiance as it is). Any other extension is an [`ImageError::Write`].
pub fn write_image(path: &Path, image: &Image, exposure: f32) -> Result<(), ImageError> {
    match kind(path) {
        Kind::Exr => write_exr(path, image),
        Kind::Hdr => write_hdr(path, image),
        Kind::Png => write_png(path, image, exposure),
        Kind::Other => Err(ImageError::write(
            path,
            "unknown image extension (known: .exr, .hdr, .pic, .png)",
        )),
    }
}

/// Reads an image as linear RGB: `.exr` and `.hdr`/`.pic` as stored, anything else through the
/// `image` crate (PNG, JPEG, TGA, BMP) decoded from sRGB to linear.
pub fn read_image(path: &Path) -> Result<Image, ImageError> {
    read_texture(path, false)
}

/// Reads an image for use as a texture or environment map: OpenEXR and Radiance HDR as stored
/// (linear), 8-bit and 16-bit formats (PNG, JPEG, TGA, BMP) decoded from sRGB to linear unless
/// `raw` (then value / 255, or / 65535, as is). Grey images are replicated to RGB; alpha is dropped.
pub fn read_texture(path: &Path, raw: bool) -> Result<Image, ImageError> {
    match kind(path) {
        Kind::Exr => read_exr(path),
        Kind::Hdr => read_hdr(path),
        Kind::Png | Kind::Other => ldr::read_ldr(path, raw),
    }
}

/// Checks that `image` can be written: non-empty, with as many pixels as its size says.
pub(crate) fn check_writable(path: &Path, image: &Image) -> Result<(), ImageError> {
    if image.width == 0 || image.height == 0 {
        return Err(ImageError::write(
            path,
            format!("empty image ({}×{})", image.width, image.height),
        ));
    }
    if image.width.checked_mul(image.height) != Some(image.pixels.len()) {
        return Err(ImageError::write(
            path,
            format!(
                "malformed image: {} pixels for a size of {}×{}",
                image.pixels.len(),
                image.width,
                image.height
            ),
        ));
    }
    Ok(())
}

/// Reads a whole file, mapping failure to [`ImageError::Read`].
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>, ImageError> {
    std::fs::read(path).map_err(|e| ImageError::read(path, e.to_string()))
}

/// Runs a third-party decoder, turning a panic inside it into an error message.
pub(crate) fn guard<T>(f: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(_) => Err("the decoder failed on malformed data".into()),
    }
}
