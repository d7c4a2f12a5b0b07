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
}
