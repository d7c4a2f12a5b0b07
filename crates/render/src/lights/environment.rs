//! Environment lights: Mitsuba 3's `constant` and `envmap` emitters (infinitely distant).
//!
//! # `constant`
//! The same radiance from every direction. From a point without a surface (in a medium, or for
//! photons) it is sampled uniformly on the sphere (density `1/(4π)`), as Mitsuba's `constant`
//! emitter does. For a surface that only reflects ([`super::Receiver`]) half the sphere lies
//! behind it and the rest arrives weighted by its cosine, so there the samples are
//! cosine-weighted over the hemisphere facing the viewer (density `cos θ/π`): a Lambertian
//! surface under an open sky then gets its exact irradiance from each sample, where uniform
//! samples of the sphere leave half their samples black and the rest spread by `4 cos θ`.
//!
//! # `envmap`: Mitsuba 3's latitude–longitude mapping (src/emitters/envmap.cpp, 3.6+ with the
//! half-texel shift; the references are rendered with Mitsuba 3.9.1)
//! A world direction `ω` is taken to the emitter's frame, `d = normalize(to_world⁻¹ ω)` (linear
//! part; Mitsuba does not normalise, which only differs for non-rigid `to_world`), and mapped to
//!
//! ```text
//! u = atan2(d.x, −d.z) / 2π,   v = acos(d.y) / π        (inverse: d = (sin φ sin θ, cos θ, −cos φ sin θ),
//!                                                         φ = 2π u, θ = π v)
//! ```
//!
//! so +y (local) is the top row of the image and the image centre (u = ½) looks along +z. The
//! radiance is the **bilinear** interpolation of the `W × H` image (times `scale`) at
//!
//! ```text
//! x = frac(u − ½/W) · W,   y = v · (H − 1)
//! ```
//!
//! with columns wrapping around (Mitsuba appends a copy of column 0) and rows *not* wrapping: row 0
//! sits exactly at the north pole and row `H − 1` at the south pole (texel centres at
//! `u = (i + ½)/W`, `v = j/(H − 1)`).
//!
//! # Importance sampling
//! The bilinear patches between texel centres form a `W × (H − 1)` grid of cells, cell `(i, j)`
//! spanning `φ ∈ 2π[(i + ½)/W, (i + 3/2)/W]` and `θ ∈ π[j/(H−1), (j+1)/(H−1)]`. Each cell gets the
//! weight `w_ij = L̄_ij · Ω_ij`, the mean luminance of its four corner texels (the exact uv-integral
//! of the bilinear luminance) times its solid angle `Ω_ij = (2π/W)(cos θ_j − cos θ_{j+1})`: the
//! sin θ-weighted luminance. A cell is chosen from a marginal (row) and conditional (column)
//! piecewise-constant [`Distribution1D`], then a direction uniform in solid angle inside it (uniform
//! in φ and in cos θ). The density is therefore piecewise constant in solid angle,
//! `p(ω) = P(cell) / Ω_cell`, bounded at the poles, and positive wherever the radiance is (a cell's
//! corner luminances are all zero only when its bilinear radiance is zero). This differs from
//! Mitsuba's bilinear `Hierarchical2D` warp only in variance, not in the rendered expectation.

use super::{is_positive_finite, Receiver};
use ircache_image::Image;
use ircache_math::sampling::{
    square_to_cosine_hemisphere, square_to_uniform_sphere, Distribution1D, UNIFORM_SPHERE_PDF,
};
use ircache_math::{Frame, Mat3, Mat4, Rgb, Vec2, Vec3, INV_PI, PI};

/// Mitsuba's `constant` emitter.
#[derive(Clone, Copy, Debug)]
pub struct ConstantLight {
    /// Radiance from every direction.
    pub radiance: Rgb,
}

impl ConstantLight {
    /// A uniform direction on the sphere.
    #[inline]
    #[must_use]
    pub fn sample(&self, u: Vec2) -> Vec3 {
        square_to_uniform_sphere(u)
    }

    /// Solid-angle density of [`ConstantLight::sample`]: `1/(4π)`.
    #[inline]
    #[must_use]
    pub fn pdf(&self) -> f32 {
        UNIFORM_SPHERE_PDF
    }

    /// A direction for the light arriving at `receiver`: cosine-weighted over the hemisphere of
    /// its normal where it has one, else uniform on the sphere.
    #[inline]
    #[must_use]
    pub fn sample_at(&self, receiver: &Receiver, u: Vec2) -> Vec3 {
        match receiver.normal {
            Some(n) => Frame::from_z(n).from_local(square_to_cosine_hemisphere(u)),
            None => self.sample(u),
        }
    }

    /// Solid-angle density with which [`ConstantLight::sample_at`] draws `dir` at `receiver`.
    #[inline]
    #[must_use]
    pub fn pdf_at(&self, receiver: &Receiver, dir: Vec3) -> f32 {
        match receiver.normal {
            Some(n) => n.dot(dir).max(0.0) * INV_PI,
            None => UNIFORM_SPHERE_PDF,
        }
    }
}

/// Mitsuba's `envmap` emitter (see the module documentation for the mapping).
#[derive(Clone, Debug)]
pub struct EnvmapLight {
    width: usize,
    /// Rows stored (≥ 2: a one-row image is duplicated).
    height: usize,
    /// `width × height` texels, row 0 at the north pole (local +y), times `scale`, channels ≥ 0.
    texels: Vec<Rgb>,
    to_world: Mat3,
    to_local: Mat3,
    /// Marginal over the `height − 1` cell rows.
    rows: Distribution1D,
    /// Conditional over the `width` cells of each cell row.
    cols: Vec<Distribution1D>,
    /// `cos θ_j` at the `height` texel rows.
    cos_theta: Vec<f32>,
    /// Solid angle of one cell of each cell row.
    cell_solid_angle: Vec<f32>,
    /// False when the whole map is black (nothing to sample).
    samplable: bool,
}

impl EnvmapLight {
    /// `∫ L dω` of the luminance over the sphere (as its sampling tabulates it).
    #[must_use]
    pub fn total_luminance(&self) -> f32 {
        self.rows.integral
    }

    /// `(∫ Y dω, ∫ Y² dω)` of the luminance `Y` over the sphere, each cell at the mean of its four
    /// corner texels (as its sampling tabulates it).
    #[must_use]
    pub fn luminance_moments(&self) -> (f64, f64) {
        let w = self.width;
        let y = |i: usize, j: usize| f64::from(self.texels[j * w + i % w].luminance());
        let (mut m1, mut m2) = (0.0, 0.0);
        for (j, omega) in self.cell_solid_angle.iter().enumerate() {
            for i in 0..w {
                let mean = 0.25 * (y(i, j) + y(i + 1, j) + y(i, j + 1) + y(i + 1, j + 1));
                m1 += mean * f64::from(*omega);
                m2 += mean * mean * f64::from(*omega);
            }
        }
        (m1, m2)
    }

    /// `∫ L dω` over the sphere per channel, each cell at the mean of its four corner texels.
    #[must_use]
    pub fn integral(&self) -> Rgb {
        let w = self.width;
        let l = |i: usize, j: usize| self.texels[j * w + i % w];
        let mut sum = Rgb::ZERO;
        for (j, omega) in self.cell_solid_angle.iter().enumerate() {
            for i in 0..w {
                let mean = (l(i, j) + l(i + 1, j) + l(i, j + 1) + l(i + 1, j + 1)) * 0.25;
                sum += mean * *omega;
            }
        }
        sum
    }

    /// Builds the emitter and its sampling distributions from the radiance image.
    #[must_use]
    pub fn new(image: &Image, to_world: Mat4, scale: f32) -> Option<EnvmapLight> {
        let width = image.width;
        if width == 0 || image.height == 0 || image.pixels.len() < width * image.height {
            return None;
        }
        let src_h = image.height;
        let height = src_h.max(2);
        let mut texels = Vec::with_capacity(width * height);
        for y in 0..height {
            let sy = y.min(src_h - 1);
            texels.extend(image.pixels[sy * width..(sy + 1) * width].iter().map(|&c| {
                (c * scale)
                    .max(Rgb::ZERO)
                    .map(|v| if v.is_finite() { v } else { 0.0 })
            }));
        }
        let lum: Vec<f32> = texels.iter().map(|c| c.luminance()).collect();
        let cos_theta: Vec<f32> = (0..height)
            .map(|j| (PI * j as f32 / (height - 1) as f32).cos())
            .collect();
        // Exact end values (cos(π) in f32 is not exactly −1).
        let mut cos_theta = cos_theta;
        cos_theta[0] = 1.0;
        cos_theta[height - 1] = -1.0;
        let dphi = 2.0 * PI / width as f32;
        let cell_solid_angle: Vec<f32> = (0..height - 1)
            .map(|j| dphi * (cos_theta[j] - cos_theta[j + 1]).max(0.0))
            .collect();
        let mut cols = Vec::with_capacity(height - 1);
        let mut row_weights = Vec::with_capacity(height - 1);
        let mut w = vec![0.0f32; width];
        for j in 0..height - 1 {
            for (i, wi) in w.iter_mut().enumerate() {
                let i1 = (i + 1) % width;
                let mean = 0.25
                    * (lum[j * width + i]
                        + lum[j * width + i1]
                        + lum[(j + 1) * width + i]
                        + lum[(j + 1) * width + i1]);
                *wi = mean * cell_solid_angle[j];
            }
            let d = Distribution1D::new(&w);
            row_weights.push(d.integral);
            cols.push(d);
        }
        let rows = Distribution1D::new(&row_weights);
        let samplable = rows.integral > 0.0 && rows.integral.is_finite();
        Some(EnvmapLight {
            width,
            height,
            texels,
            to_world: Mat3::from_mat4(to_world),
            to_local: Mat3::from_mat4(to_world).inverse(),
            rows,
            cols,
            cos_theta,
            cell_solid_angle,
            samplable,
        })
    }

    /// Mitsuba's `direction_to_uv` of a unit local direction.
    #[inline]
    fn direction_to_uv(d: Vec3) -> Vec2 {
        let mut u = d.x.atan2(-d.z) * (0.5 / PI);
        if u < 0.0 {
            u += 1.0;
        }
        Vec2::new(u, d.y.clamp(-1.0, 1.0).acos() * (1.0 / PI))
    }

    /// Continuous texel coordinates `(x, y)` (x in `[0, W)`, y in `[0, H−1]`) of a world direction.
    #[inline]
    fn texel_coords(&self, dir: Vec3) -> Option<Vec2> {
        let d = (self.to_local * dir).try_normalize()?;
        let uv = Self::direction_to_uv(d);
        let w = self.width as f32;
        let mut x = uv.x * w - 0.5;
        x -= (x / w).floor() * w;
        if x.is_nan() || x >= w {
            x = 0.0;
        }
        Some(Vec2::new(x.max(0.0), uv.y * (self.height - 1) as f32))
    }

    /// Cell indices `(i, j)` of continuous texel coordinates.
    #[inline]
    fn cell(&self, xy: Vec2) -> (usize, usize) {
        (
            (xy.x as usize).min(self.width - 1),
            (xy.y as usize).min(self.height - 2),
        )
    }

    /// Radiance arriving along the escaping ray direction `dir` (world, need not be unit):
    /// Mitsuba's bilinear lookup (module documentation).
    #[inline]
    #[must_use]
    pub fn eval(&self, dir: Vec3) -> Rgb {
        let Some(xy) = self.texel_coords(dir) else {
            return Rgb::ZERO;
        };
        let (i, j) = self.cell(xy);
        let (fx, fy) = (
            (xy.x - i as f32).clamp(0.0, 1.0),
            (xy.y - j as f32).clamp(0.0, 1.0),
        );
        let i1 = if i + 1 == self.width { 0 } else { i + 1 };
        let w = self.width;
        let v00 = self.texels[j * w + i];
        let v10 = self.texels[j * w + i1];
        let v01 = self.texels[(j + 1) * w + i];
        let v11 = self.texels[(j + 1) * w + i1];
        let v0 = v00 * (1.0 - fx) + v10 * fx;
        let v1 = v01 * (1.0 - fx) + v11 * fx;
        v0 * (1.0 - fy) + v1 * fy
    }

    /// Samples a world direction proportionally to the cell weights (module documentation);
    /// `None` when the map is black.
    #[inline]
    #[must_use]
    pub fn sample(&self, u: Vec2) -> Option<Vec3> {
        if !self.samplable {
            return None;
        }
        let (j, pj, uy) = self.rows.sample(u.y);
        if pj <= 0.0 {
            return None;
        }
        let (i, pi, ux) = self.cols[j].sample(u.x);
        if pi <= 0.0 {
            return None;
        }
        let (c0, c1) = (self.cos_theta[j], self.cos_theta[j + 1]);
        let cos_t = (c0 + (c1 - c0) * uy).clamp(-1.0, 1.0);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = 2.0 * PI * (i as f32 + 0.5 + ux) / self.width as f32;
        let (sin_p, cos_p) = phi.sin_cos();
        let local = Vec3::new(sin_p * sin_t, cos_t, -cos_p * sin_t);
        (self.to_world * local).try_normalize()
    }

    /// Solid-angle density with which [`EnvmapLight::sample`] produces the world direction `dir`.
    #[inline]
    #[must_use]
    pub fn pdf(&self, dir: Vec3) -> f32 {
        if !self.samplable {
            return 0.0;
        }
        let Some(xy) = self.texel_coords(dir) else {
            return 0.0;
        };
        let (i, j) = self.cell(xy);
        let omega = self.cell_solid_angle[j];
        if !is_positive_finite(omega) {
            return 0.0;
        }
        self.rows.pmf(j) * self.cols[j].pmf(i) / omega
    }
}
