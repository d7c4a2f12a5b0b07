//! HDR images: the in-memory linear RGB float [`Image`], reading and writing OpenEXR, Radiance HDR
//! and PNG, loading textures, and the error measures of `../shared/references/README.md`.

use ircache_math::Rgb;

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
        Image { width, height, pixels: vec![Rgb::ZERO; width * height] }
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

/// Reads an image for use as a texture or environment map: OpenEXR and Radiance HDR as stored
/// (linear), 8-bit formats (PNG, JPEG, ...) decoded from sRGB to linear unless `raw`.
pub fn read_texture(path: &std::path::Path, raw: bool) -> Result<Image, ImageError> {
    let _ = raw;
    Err(ImageError::Read { path: path.to_path_buf(), message: "image reading is being written".into() })
}
