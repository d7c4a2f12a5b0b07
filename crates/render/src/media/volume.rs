//! Spatially varying medium quantities (Mitsuba 3's `constvolume` and `gridvolume`): a constant,
//! or a voxel grid over the unit cube mapped by `to_world`, sampled at cell centres (texel
//! coordinate `p·res − ½`, as Dr.Jit's textures) and interpolated trilinearly or by nearest
//! sample, with clamp, repeat or mirror outside.

use ircache_math::{Mat4, Rgb, Vec3};
use ircache_scene::{GridVolumeDesc, TextureFilter, VolumeDesc, WrapMode};
use std::sync::Arc;

/// A volume ready for lookups at world points.
#[derive(Clone, Debug)]
pub enum Volume {
    /// The same value everywhere.
    Constant(Rgb),
    /// A voxel grid.
    Grid(Grid),
}

/// A voxel grid with its world-to-unit-cube transform.
#[derive(Clone, Debug)]
pub struct Grid {
    desc: Arc<GridVolumeDesc>,
    to_unit: Mat4,
    /// Largest sample per channel.
    pub max: Rgb,
}

impl Volume {
    /// From the description.
    #[must_use]
    pub fn from_desc(desc: &VolumeDesc) -> Volume {
        match desc {
            VolumeDesc::Constant { value, .. } => Volume::Constant(*value),
            VolumeDesc::Grid(g) => {
                let mut max = [0.0f32; 3];
                for (i, v) in g.data.iter().enumerate() {
                    let c = if g.channels == 1 { 0 } else { i % g.channels };
                    max[c] = max[c].max(*v);
                }
                if g.channels == 1 {
                    max = [max[0]; 3];
                }
                Volume::Grid(Grid {
                    to_unit: g.to_world.inverse(),
                    desc: g.clone(),
                    max: Rgb::new(max[0], max[1], max[2]),
                })
            }
        }
    }

    /// The value at world point `p`.
    #[inline]
    #[must_use]
    pub fn eval(&self, p: Vec3) -> Rgb {
        match self {
            Volume::Constant(v) => *v,
            Volume::Grid(g) => g.eval(p),
        }
    }

    /// The value at world point `p` and its gradient per channel (r, g, b), exact for the
    /// interpolant: zero for a constant and for nearest-sample lookups.
    #[inline]
    #[must_use]
    pub fn eval_with_gradient(&self, p: Vec3) -> (Rgb, [Vec3; 3]) {
        match self {
            Volume::Constant(v) => (*v, [Vec3::ZERO; 3]),
            Volume::Grid(g) => g.eval_with_gradient(p),
        }
    }

    /// The largest value per channel anywhere.
    #[must_use]
    pub fn max(&self) -> Rgb {
        match self {
            Volume::Constant(v) => *v,
            Volume::Grid(g) => g.max,
        }
    }

    /// True when the value is the same everywhere.
    #[must_use]
    pub fn is_constant(&self) -> bool {
        matches!(self, Volume::Constant(_))
    }
}

/// An integer sample index brought inside `[0, n)` by the wrap mode.
#[inline]
fn wrap(i: i64, n: usize, mode: WrapMode) -> usize {
    let n = n as i64;
    let r = match mode {
        WrapMode::Clamp => i.clamp(0, n - 1),
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::Mirror => {
            let m = i.rem_euclid(2 * n);
            if m < n {
                m
            } else {
                2 * n - 1 - m
            }
        }
    };
    r as usize
}

/// The trilinear interpolant of the corner values `c[z][y][x]` at fractions `f` and its
/// derivatives along x, y and z: lerps along x, then y, then z, each derivative lerping the
/// differences along its own axis over the other two.
#[inline]
fn trilinear_with_derivatives(c: &[[[f32; 2]; 2]; 2], f: Vec3) -> (f32, Vec3) {
    let lerp = |a: f32, b: f32, s: f32| a * (1.0 - s) + b * s;
    let ax = |dy: usize, dz: usize| lerp(c[dz][dy][0], c[dz][dy][1], f.x);
    let dx = |dy: usize, dz: usize| c[dz][dy][1] - c[dz][dy][0];
    let (a00, a10, a01, a11) = (ax(0, 0), ax(1, 0), ax(0, 1), ax(1, 1));
    let (b0, b1) = (lerp(a00, a10, f.y), lerp(a01, a11, f.y));
    let d_x = lerp(
        lerp(dx(0, 0), dx(1, 0), f.y),
        lerp(dx(0, 1), dx(1, 1), f.y),
        f.z,
    );
    let d_y = lerp(a10 - a00, a11 - a01, f.z);
    (lerp(b0, b1, f.z), Vec3::new(d_x, d_y, b1 - b0))
}

impl Grid {
    /// Samples along x, y, z.
    #[must_use]
    pub fn resolution(&self) -> [usize; 3] {
        self.desc.resolution
    }

    /// The largest sample (over channels) with indices in the inclusive ranges `[(lo, hi); 3]`,
    /// indices outside the grid wrapped as lookups wrap them.
    #[must_use]
    pub fn max_over(&self, ranges: [(i64, i64); 3]) -> f32 {
        let mut m = 0.0f32;
        for z in ranges[2].0..=ranges[2].1 {
            for y in ranges[1].0..=ranges[1].1 {
                for x in ranges[0].0..=ranges[0].1 {
                    m = m.max(self.sample([x, y, z]).max_channel());
                }
            }
        }
        m
    }

    /// World to the unit cube.
    #[must_use]
    pub fn to_unit(&self) -> Mat4 {
        self.to_unit
    }

    /// The sample at integer indices (wrapped).
    #[inline]
    fn sample(&self, [x, y, z]: [i64; 3]) -> Rgb {
        let g = &*self.desc;
        let [nx, ny, nz] = g.resolution;
        self.value(self.index(
            wrap(x, nx, g.wrap),
            wrap(y, ny, g.wrap),
            wrap(z, nz, g.wrap),
        ))
    }

    /// Where the sample at indices already inside the grid starts in `data`.
    #[inline]
    fn index(&self, x: usize, y: usize, z: usize) -> usize {
        let g = &*self.desc;
        let [nx, ny, _] = g.resolution;
        ((z * ny + y) * nx + x) * g.channels
    }

    /// The sample starting at `data[i]`.
    #[inline]
    fn value(&self, i: usize) -> Rgb {
        let g = &*self.desc;
        if g.channels == 1 {
            Rgb::splat(g.data[i])
        } else {
            Rgb::new(g.data[i], g.data[i + 1], g.data[i + 2])
        }
    }

    /// The interpolated value at world point `p`.
    #[must_use]
    pub fn eval(&self, p: Vec3) -> Rgb {
        let u = self.to_unit.transform_point3(p);
        let res = Vec3::new(
            self.desc.resolution[0] as f32,
            self.desc.resolution[1] as f32,
            self.desc.resolution[2] as f32,
        );
        if self.desc.filter == TextureFilter::Nearest {
            let i = (u * res).floor();
            return self.sample([i.x as i64, i.y as i64, i.z as i64]);
        }
        let t = u * res - Vec3::splat(0.5);
        let i0 = t.floor();
        let f = t - i0;
        let [x, y, z] = [i0.x as i64, i0.y as i64, i0.z as i64];
        // Each axis's two indices wrapped once, not once per corner.
        let g = &*self.desc;
        let [nx, ny, nz] = g.resolution;
        let xs = [wrap(x, nx, g.wrap), wrap(x + 1, nx, g.wrap)];
        let ys = [wrap(y, ny, g.wrap), wrap(y + 1, ny, g.wrap)];
        let zs = [wrap(z, nz, g.wrap), wrap(z + 1, nz, g.wrap)];
        let weight = |corner: usize| {
            let (dx, dy, dz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = if dx == 1 { f.x } else { 1.0 - f.x }
                * if dy == 1 { f.y } else { 1.0 - f.y }
                * if dz == 1 { f.z } else { 1.0 - f.z };
            (w, self.index(xs[dx], ys[dy], zs[dz]))
        };
        if g.channels == 1 {
            // One channel: the same sums as three equal ones, a third of the work.
            let mut out = 0.0f32;
            for corner in 0..8 {
                let (w, i) = weight(corner);
                if w != 0.0 {
                    out += g.data[i] * w;
                }
            }
            return Rgb::splat(out);
        }
        let mut out = Rgb::ZERO;
        for corner in 0..8 {
            let (w, i) = weight(corner);
            if w != 0.0 {
                out += self.value(i) * w;
            }
        }
        out
    }

    /// [`Self::eval`] and the interpolant's gradient in world space per channel: the trilinear
    /// weights' derivatives in texel space (t = u·res − ½), taken to the world by the transpose
    /// of `to_unit`'s linear part. Inside a cell it is exact; on a cell face it is the derivative
    /// from the cell above. Nearest-sample lookups are piecewise constant: zero.
    #[must_use]
    pub fn eval_with_gradient(&self, p: Vec3) -> (Rgb, [Vec3; 3]) {
        let g = &*self.desc;
        if g.filter == TextureFilter::Nearest {
            return (self.eval(p), [Vec3::ZERO; 3]);
        }
        let u = self.to_unit.transform_point3(p);
        let [nx, ny, nz] = g.resolution;
        let res = Vec3::new(nx as f32, ny as f32, nz as f32);
        let t = u * res - Vec3::splat(0.5);
        let i0 = t.floor();
        let f = t - i0;
        let [x, y, z] = [i0.x as i64, i0.y as i64, i0.z as i64];
        let xs = [wrap(x, nx, g.wrap), wrap(x + 1, nx, g.wrap)];
        let ys = [wrap(y, ny, g.wrap), wrap(y + 1, ny, g.wrap)];
        let zs = [wrap(z, nz, g.wrap), wrap(z + 1, nz, g.wrap)];
        let corners = |channel: usize| {
            let v = |dx: usize, dy: usize, dz: usize| {
                g.data[self.index(xs[dx], ys[dy], zs[dz]) + channel]
            };
            [
                [[v(0, 0, 0), v(1, 0, 0)], [v(0, 1, 0), v(1, 1, 0)]],
                [[v(0, 0, 1), v(1, 0, 1)], [v(0, 1, 1), v(1, 1, 1)]],
            ]
        };
        // ∂f/∂p = Mᵀ (res ⊙ ∂f/∂t) for u = M p.
        let to_world = self.to_unit.transpose();
        let one = |channel: usize| {
            let (value, d) = trilinear_with_derivatives(&corners(channel), f);
            (value, to_world.transform_vector3(d * res))
        };
        if g.channels == 1 {
            let (value, gradient) = one(0);
            return (Rgb::splat(value), [gradient; 3]);
        }
        let [(r, gr), (gg, gg_), (b, gb)] = [0, 1, 2].map(one);
        (Rgb::new(r, gg, b), [gr, gg_, gb])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_math::{Quat, Rng};
    use std::path::PathBuf;

    fn grid(channels: usize, wrap: WrapMode) -> Volume {
        let mut rng = Rng::new(7, 0);
        let resolution = [5, 4, 6];
        let data = (0..resolution.iter().product::<usize>() * channels)
            .map(|_| rng.next_f32())
            .collect();
        // Rotated, scaled unequally and moved: the gradient's transform is not the identity.
        let to_world = Mat4::from_scale_rotation_translation(
            Vec3::new(2.0, 0.5, 1.25),
            Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7),
            Vec3::new(0.3, -1.0, 2.0),
        );
        Volume::from_desc(&VolumeDesc::Grid(Arc::new(GridVolumeDesc {
            path: PathBuf::from("test.vol"),
            resolution,
            channels,
            data,
            to_world,
            filter: TextureFilter::Bilinear,
            wrap,
        })))
    }

    /// The trilinear interpolant's gradient against central differences of lookups, at random
    /// points inside and outside the grid (the wrap modes), one and three channels; the value
    /// is the lookup's.
    #[test]
    fn a_grids_gradient_is_that_of_its_lookups() {
        let mut rng = Rng::new(3, 1);
        for channels in [1, 3] {
            for wrap in [WrapMode::Clamp, WrapMode::Repeat, WrapMode::Mirror] {
                let volume = grid(channels, wrap);
                let Volume::Grid(g) = &volume else {
                    unreachable!()
                };
                let to_world = g.to_unit.inverse();
                for _ in 0..200 {
                    let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 1.4
                        - Vec3::splat(0.2);
                    let p = to_world.transform_point3(u);
                    let (value, gradient) = volume.eval_with_gradient(p);
                    let expected = volume.eval(p);
                    assert!(
                        (value - expected).map(f32::abs).max_channel() < 1e-5,
                        "{value:?} {expected:?}"
                    );
                    // A step far below a cell (cells are 0.2–0.5 units wide): unless the step
                    // straddles a cell face, the difference is the derivative to rounding.
                    let h = 2e-3;
                    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                        let fd =
                            (volume.eval(p + axis * h) - volume.eval(p - axis * h)) / (2.0 * h);
                        let analytic = Rgb::new(
                            gradient[0].dot(axis),
                            gradient[1].dot(axis),
                            gradient[2].dot(axis),
                        );
                        let scale = gradient.iter().map(|g| g.length()).fold(1.0, f32::max);
                        let off = (fd - analytic).map(f32::abs).max_channel() / scale;
                        // A straddled face changes the slope by at most the neighbours'.
                        assert!(
                            off < 2e-2 || straddles(g, p, axis * h),
                            "{fd:?} {analytic:?}"
                        );
                    }
                }
            }
        }
    }

    /// True when `p ± step` lie in different cells of the interpolant.
    fn straddles(g: &Grid, p: Vec3, step: Vec3) -> bool {
        let [nx, ny, nz] = g.desc.resolution;
        let res = Vec3::new(nx as f32, ny as f32, nz as f32);
        let cell = |q: Vec3| (g.to_unit.transform_point3(q) * res - Vec3::splat(0.5)).floor();
        cell(p + step) != cell(p - step)
    }
}
