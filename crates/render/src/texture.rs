//! Textures: constant colours and bitmaps, looked up by surface uv coordinates with Mitsuba 3's
//! conventions (`src/textures/bitmap.cpp` and Dr.Jit's `Texture`):
//!
//! - uv is first mapped by the `to_uv` affine transform;
//! - `u` runs along the image's columns and `v` along its rows, with `v = 0` at the image's first
//!   (top) row: Mitsuba stores the bitmap as a `height × width` tensor and indexes it by `(v, u)`
//!   (mesh loaders flip OBJ/PLY `v` instead);
//! - texel `(i, j)` has its centre at `((i + 0.5)/w, (j + 0.5)/h)`; bilinear lookups interpolate the
//!   four texels around `uv·(w, h) − 0.5`, nearest lookups take texel `⌊uv·(w, h)⌋`;
//! - indices outside the image are wrapped by `repeat` (modulo), `mirror` (reflected every other
//!   tile) or `clamp` (edge texel).

use ircache_image::Image;
use ircache_math::{Mat3, Rgb, Vec2, Vec3};
use ircache_scene::{TextureDesc, TextureFilter, WrapMode};
use std::sync::Arc;

/// A texture ready for lookups.
#[derive(Clone, Debug)]
pub enum Texture {
    /// The same value everywhere.
    Constant(Rgb),
    /// An image.
    Bitmap(Bitmap),
    /// Mitsuba's `checkerboard` ([`TextureDesc::Checkerboard`]).
    Checkerboard {
        /// Where both fractional parts of (u, v) lie on the same side of ½.
        color0: Rgb,
        /// Elsewhere.
        color1: Rgb,
        /// Texture-coordinate transform.
        to_uv: Mat3,
    },
}

/// An image texture.
#[derive(Clone, Debug)]
pub struct Bitmap {
    image: Arc<Image>,
    filter: TextureFilter,
    wrap: WrapMode,
    /// `None` when `to_uv` is the identity.
    to_uv: Option<Mat3>,
    mean: Rgb,
}

impl Texture {
    /// Builds a texture from its description.
    #[must_use]
    pub fn from_desc(desc: &TextureDesc) -> Texture {
        match desc {
            TextureDesc::Constant(c) => Texture::Constant(*c),
            TextureDesc::Checkerboard {
                color0,
                color1,
                to_uv,
            } => Texture::Checkerboard {
                color0: *color0,
                color1: *color1,
                to_uv: *to_uv,
            },
            TextureDesc::Bitmap(b) => {
                let image = Arc::clone(&b.image);
                if image.width == 0
                    || image.height == 0
                    || image.pixels.len() < image.width * image.height
                {
                    return Texture::Constant(Rgb::ZERO);
                }
                let n = (image.width * image.height) as f64;
                let (mut r, mut g, mut bl) = (0.0f64, 0.0f64, 0.0f64);
                for p in &image.pixels[..image.width * image.height] {
                    r += f64::from(p.r);
                    g += f64::from(p.g);
                    bl += f64::from(p.b);
                }
                let mean = Rgb::new((r / n) as f32, (g / n) as f32, (bl / n) as f32);
                let to_uv = if b.to_uv == Mat3::IDENTITY {
                    None
                } else {
                    Some(b.to_uv)
                };
                Texture::Bitmap(Bitmap {
                    image,
                    filter: b.filter,
                    wrap: b.wrap,
                    to_uv,
                    mean,
                })
            }
        }
    }

    /// One texel's size in uv (u, v); 1/1024 for constants.
    #[must_use]
    pub fn texel_size(&self) -> (f32, f32) {
        match self {
            Texture::Constant(_) | Texture::Checkerboard { .. } => (1.0 / 1024.0, 1.0 / 1024.0),
            Texture::Bitmap(b) => (
                1.0 / b.image.width.max(1) as f32,
                1.0 / b.image.height.max(1) as f32,
            ),
        }
    }

    /// The value at texture coordinates `uv`.
    #[must_use]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        match self {
            Texture::Constant(c) => *c,
            Texture::Bitmap(b) => b.eval(uv),
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                let q = to_uv.transform_point2(uv);
                let high = |x: f32| x - x.floor() > 0.5;
                if high(q.x) == high(q.y) {
                    *color0
                } else {
                    *color1
                }
            }
        }
    }

    /// The average value over the texture (per channel): the texel mean for bitmaps.
    #[must_use]
    pub fn mean(&self) -> Rgb {
        match self {
            Texture::Constant(c) => *c,
            Texture::Bitmap(b) => b.mean,
            // Half of any whole number of squares is each colour.
            Texture::Checkerboard { color0, color1, .. } => (*color0 + *color1) * 0.5,
        }
    }

    /// The scalar mean Mitsuba 3 uses for sampling weights: the channel average of a constant,
    /// the mean luminance of a bitmap.
    #[must_use]
    pub fn mean_scalar(&self) -> f32 {
        match self {
            Texture::Constant(c) => c.mean(),
            Texture::Bitmap(b) => b.mean.luminance(),
            Texture::Checkerboard { .. } => self.mean().luminance(),
        }
    }

    /// True for a constant texture.
    #[must_use]
    pub fn is_constant(&self) -> bool {
        matches!(self, Texture::Constant(_))
    }
}

/// Wraps a texel index into `[0, n)`.
fn wrap_index(i: i64, n: usize, mode: WrapMode) -> usize {
    let n = n as i64;
    let j = match mode {
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::Clamp => i.clamp(0, n - 1),
        WrapMode::Mirror => {
            let m = i.rem_euclid(2 * n);
            if m >= n {
                2 * n - 1 - m
            } else {
                m
            }
        }
    };
    j as usize
}

impl Bitmap {
    fn texel(&self, x: i64, y: i64) -> Rgb {
        let w = self.image.width;
        let xi = wrap_index(x, w, self.wrap);
        let yi = wrap_index(y, self.image.height, self.wrap);
        self.image.pixels[yi * w + xi]
    }

    /// The value at `uv` (before `to_uv`).
    #[must_use]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        let uv = match &self.to_uv {
            None => uv,
            Some(m) => {
                let p = *m * Vec3::new(uv.x, uv.y, 1.0);
                Vec2::new(p.x, p.y)
            }
        };
        if !uv.is_finite() {
            return Rgb::ZERO;
        }
        let (w, h) = (self.image.width as f64, self.image.height as f64);
        // Double precision keeps texel positions exact for large uv (tiling).
        let (x, y) = (f64::from(uv.x) * w, f64::from(uv.y) * h);
        match self.filter {
            TextureFilter::Nearest => self.texel(x.floor() as i64, y.floor() as i64),
            TextureFilter::Bilinear => {
                let (x, y) = (x - 0.5, y - 0.5);
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let c00 = self.texel(x0, y0);
                let c10 = self.texel(x0 + 1, y0);
                let c01 = self.texel(x0, y0 + 1);
                let c11 = self.texel(x0 + 1, y0 + 1);
                let top = c00 * (1.0 - fx) + c10 * fx;
                let bottom = c01 * (1.0 - fx) + c11 * fx;
                top * (1.0 - fy) + bottom * fy
            }
        }
    }

    /// The image.
    #[must_use]
    pub fn image(&self) -> &Image {
        &self.image
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_scene::BitmapDesc;
    use std::path::PathBuf;

    /// 2×2 image: top row (v < 0.5) 0 and 1, bottom row 2 and 3 (red channel), green = 10·red.
    fn tex(filter: TextureFilter, wrap: WrapMode, to_uv: Mat3) -> Texture {
        let mut img = Image::new(2, 2);
        for (i, v) in [0.0f32, 1.0, 2.0, 3.0].into_iter().enumerate() {
            img.set(i % 2, i / 2, Rgb::new(v, 10.0 * v, 0.5));
        }
        Texture::from_desc(&TextureDesc::Bitmap(Arc::new(BitmapDesc {
            path: PathBuf::from("test.exr"),
            image: Arc::new(img),
            filter,
            wrap,
            to_uv,
        })))
    }

    fn red(t: &Texture, u: f32, v: f32) -> f32 {
        t.eval(Vec2::new(u, v)).r
    }

    #[test]
    fn bilinear_at_centres_and_between() {
        let t = tex(TextureFilter::Bilinear, WrapMode::Clamp, Mat3::IDENTITY);
        // Texel centres.
        assert!((red(&t, 0.25, 0.25) - 0.0).abs() < 1e-6);
        assert!((red(&t, 0.75, 0.25) - 1.0).abs() < 1e-6);
        assert!((red(&t, 0.25, 0.75) - 2.0).abs() < 1e-6);
        assert!((red(&t, 0.75, 0.75) - 3.0).abs() < 1e-6);
        // Between them.
        assert!((red(&t, 0.5, 0.5) - 1.5).abs() < 1e-6);
        assert!((red(&t, 0.5, 0.25) - 0.5).abs() < 1e-6);
        assert!((red(&t, 0.25, 0.5) - 1.0).abs() < 1e-6);
        assert!((red(&t, 0.375, 0.25) - 0.25).abs() < 1e-6);
        assert!((t.eval(Vec2::new(0.5, 0.5)).g - 15.0).abs() < 1e-5);
        // Clamp: outside the centres the edge texels are held.
        assert!((red(&t, 0.0, 0.0) - 0.0).abs() < 1e-6);
        assert!((red(&t, 1.0, 1.0) - 3.0).abs() < 1e-6);
        assert!((red(&t, 7.0, -3.0) - 1.0).abs() < 1e-6);
        assert_eq!(t.mean(), Rgb::new(1.5, 15.0, 0.5));
    }

    #[test]
    fn wrap_modes() {
        let rep = tex(TextureFilter::Bilinear, WrapMode::Repeat, Mat3::IDENTITY);
        // At u = 0 the repeat mode blends the last and first columns.
        assert!((red(&rep, 0.0, 0.25) - 0.5).abs() < 1e-6);
        assert!((red(&rep, 1.25, 0.25) - 0.0).abs() < 1e-6);
        assert!((red(&rep, -0.25, 0.25) - 1.0).abs() < 1e-6);
        assert!((red(&rep, 0.75, -1.25) - 3.0).abs() < 1e-6);
        let mir = tex(TextureFilter::Bilinear, WrapMode::Mirror, Mat3::IDENTITY);
        // Mirror: the tile to the left is reversed, so u = −0.25 is texel 0 again, u = 0 too.
        assert!((red(&mir, 0.0, 0.25) - 0.0).abs() < 1e-6);
        assert!((red(&mir, -0.25, 0.25) - 0.0).abs() < 1e-6);
        assert!((red(&mir, -0.75, 0.25) - 1.0).abs() < 1e-6);
        assert!((red(&mir, 1.25, 0.25) - 1.0).abs() < 1e-6);
        assert!((red(&mir, 2.25, 0.25) - 0.0).abs() < 1e-6);
        let near = tex(TextureFilter::Nearest, WrapMode::Repeat, Mat3::IDENTITY);
        assert_eq!(red(&near, 0.49, 0.1), 0.0);
        assert_eq!(red(&near, 0.51, 0.1), 1.0);
        assert_eq!(red(&near, 0.51, 0.6), 3.0);
        assert_eq!(red(&near, 1.51, -0.4), 3.0);
        let near_mirror = tex(TextureFilter::Nearest, WrapMode::Mirror, Mat3::IDENTITY);
        assert_eq!(red(&near_mirror, -0.1, 0.1), 0.0);
        assert_eq!(red(&near_mirror, -0.6, 0.1), 1.0);
    }

    #[test]
    fn to_uv_transform_applies_first() {
        // Scale uv by 2 (tiles twice): u = 0.375 → 0.75, the centre of column 1.
        let m = Mat3::from_cols(
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        );
        let t = tex(TextureFilter::Bilinear, WrapMode::Repeat, m);
        assert!((red(&t, 0.375, 0.125) - 1.0).abs() < 1e-6);
        // Translation by (0.5, 0).
        let m = Mat3::from_cols(Vec3::X, Vec3::Y, Vec3::new(0.5, 0.0, 1.0));
        let t = tex(TextureFilter::Bilinear, WrapMode::Repeat, m);
        assert!((red(&t, 0.25, 0.25) - 1.0).abs() < 1e-6);
        assert!(
            (Texture::Constant(Rgb::splat(0.3))
                .eval(Vec2::new(5.0, -2.0))
                .g
                - 0.3)
                .abs()
                < 1e-7
        );
    }

    /// Mitsuba's `checkerboard` read from XML (a `to_uv` of translate then scale) and looked
    /// up: the colours Mitsuba 3.9.1's own `eval` gives at six points (`scalar_rgb`).
    #[test]
    fn checkerboard_matches_mitsuba() {
        let dir = ircache_testing::ScratchDir::new("checkerboard");
        let path = dir.join("scene.xml");
        std::fs::write(
            &path,
            r#"<scene version="3.0.0"><sensor type="perspective"/>
<shape type="cube"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
<rgb name="color0" value="0.9, 0.1, 0.1"/><float name="color1" value="0.25"/>
<transform name="to_uv"><translate x="0.1" y="0.3"/><scale x="3" y="2"/></transform>
</texture></bsdf></shape></scene>"#,
        )
        .unwrap();
        let desc = ircache_scene::mitsuba::load(&path, &[]).unwrap();
        let material = crate::bsdf::Material::from_desc(&desc.shapes[0].bsdf);
        let (red, grey) = (Rgb::new(0.9, 0.1, 0.1), Rgb::splat(0.25));
        for (uv, expected) in [
            ((0.05, 0.05), grey),
            ((0.2, 0.1), red),
            ((0.2, 0.4), grey),
            ((0.45, 0.8), grey),
            ((0.7, 0.3), red),
            ((0.95, 0.95), red),
        ] {
            let got = material.at(Vec2::new(uv.0, uv.1)).diffuse_reflectance();
            assert_eq!(got, expected, "at {uv:?}");
        }
        assert!(material.is_textured());
    }
}
