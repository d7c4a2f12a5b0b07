//! A coarse grid of local majorants over a voxel grid's unit cube (pbrt-v4's `MajorantGrid`):
//! each cell holds the largest extinction any lookup inside it can return, so delta and ratio
//! tracking draw their tentative collisions against that cell's bound instead of the whole
//! medium's, stepping from cell to cell along the ray (Amanatides and Woo's traversal). The
//! exponential distribution is memoryless, so restarting the draw at each cell boundary keeps
//! the estimators unbiased.

use super::volume::Grid;
use ircache_math::{Mat4, Vec3};

/// Majorant cells per axis (at most; never more than the voxels).
const CELLS: usize = 16;

/// Local majorants of a grid's extinction.
#[derive(Clone, Debug)]
pub struct MajorantGrid {
    res: [usize; 3],
    /// Largest extinction (scaled, over channels) per cell, `(z·ny + y)·nx + x`.
    max: Vec<f32>,
    to_unit: Mat4,
}

impl MajorantGrid {
    /// The majorants of `grid` × `scale`. A cell covers the unit-cube box [i/n, (i+1)/n] per
    /// axis; every sample that trilinear (or nearest) lookups inside it can weigh is included.
    #[must_use]
    pub fn new(grid: &Grid, scale: f32, to_unit: Mat4) -> MajorantGrid {
        let voxels = grid.resolution();
        let res = voxels.map(|v| v.clamp(1, CELLS));
        let mut max = vec![0.0f32; res[0] * res[1] * res[2]];
        for z in 0..res[2] {
            for y in 0..res[1] {
                for x in 0..res[0] {
                    let range = |i: usize, a: usize| {
                        // Texel coordinates p·v − ½ over the cell and the next sample up; the
                        // lookup's wrap mode brings indices outside the grid back in.
                        let (lo, hi) = (i as f32 / res[a] as f32, (i + 1) as f32 / res[a] as f32);
                        let v = voxels[a] as f32;
                        (
                            (lo * v - 0.5).floor() as i64,
                            (hi * v - 0.5).floor() as i64 + 1,
                        )
                    };
                    let (rx, ry, rz) = (range(x, 0), range(y, 1), range(z, 2));
                    max[(z * res[1] + y) * res[0] + x] = scale * grid.max_over([rx, ry, rz]);
                }
            }
        }
        MajorantGrid { res, max, to_unit }
    }

    /// Calls `f(t0, t1, majorant)` for the cells the segment `o + t d`, t ∈ [t0, t1], crosses,
    /// in order, until `f` returns false.
    pub fn for_each_segment(
        &self,
        o: Vec3,
        d: Vec3,
        t0: f32,
        t1: f32,
        mut f: impl FnMut(f32, f32, f32) -> bool,
    ) {
        // The ray in unit-cube space has the same parameter t.
        let ou = self.to_unit.transform_point3(o);
        let du = self.to_unit.transform_vector3(d);
        let res = Vec3::new(self.res[0] as f32, self.res[1] as f32, self.res[2] as f32);
        let start = ((ou + du * t0) * res).clamp(Vec3::ZERO, res - Vec3::splat(1e-4));
        let mut cell = [start.x as i64, start.y as i64, start.z as i64];
        let mut next = [0.0f32; 3];
        let mut delta = [0.0f32; 3];
        let mut step = [0i64; 3];
        for a in 0..3 {
            if du[a] == 0.0 {
                next[a] = f32::INFINITY;
                delta[a] = f32::INFINITY;
                continue;
            }
            // Grid-space position p(t)·res; the next boundary crossed along d.
            let dir = du[a] * res[a];
            let pos = (ou[a] + du[a] * t0) * res[a];
            let boundary = if dir > 0.0 {
                cell[a] as f32 + 1.0
            } else {
                cell[a] as f32
            };
            next[a] = t0 + ((boundary - pos) / dir).max(0.0);
            delta[a] = 1.0 / dir.abs();
            step[a] = if dir > 0.0 { 1 } else { -1 };
        }
        let mut t = t0;
        loop {
            let a = if next[0] <= next[1] && next[0] <= next[2] {
                0
            } else if next[1] <= next[2] {
                1
            } else {
                2
            };
            let end = next[a].min(t1);
            let index = (cell[2] as usize * self.res[1] + cell[1] as usize) * self.res[0]
                + cell[0] as usize;
            if end > t && !f(t, end, self.max[index]) {
                return;
            }
            if end >= t1 {
                return;
            }
            t = end;
            cell[a] += step[a];
            if cell[a] < 0 || cell[a] >= self.res[a] as i64 {
                return;
            }
            next[a] += delta[a];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::volume::Volume;
    use ircache_math::Rng;
    use ircache_scene::{GridVolumeDesc, TextureFilter, VolumeDesc, WrapMode};
    use std::sync::Arc;

    fn grid(wrap: WrapMode, filter: TextureFilter) -> (Grid, Mat4) {
        let res = [37usize, 20, 9];
        let mut rng = Rng::new(3, 4);
        let data = (0..res[0] * res[1] * res[2])
            .map(|_| rng.next_f32().powi(4) * 5.0)
            .collect();
        let to_world = Mat4::from_translation(Vec3::new(-1.0, 0.5, 2.0))
            * Mat4::from_scale(Vec3::new(3.0, 1.5, 0.7));
        let desc = VolumeDesc::Grid(Arc::new(GridVolumeDesc {
            path: "<test>".into(),
            resolution: res,
            channels: 1,
            data,
            to_world,
            filter,
            wrap,
        }));
        let Volume::Grid(g) = Volume::from_desc(&desc) else {
            unreachable!()
        };
        let to_unit = g.to_unit();
        (g, to_unit)
    }

    /// Along random rays through the grid's box, the segments tile [t0, t1] in order, and the
    /// extinction at any point of a segment stays under its majorant, for every filter and wrap.
    #[test]
    fn segments_tile_the_ray_and_bound_the_extinction() {
        for wrap in [WrapMode::Clamp, WrapMode::Repeat, WrapMode::Mirror] {
            for filter in [TextureFilter::Bilinear, TextureFilter::Nearest] {
                let (g, to_unit) = grid(wrap, filter);
                let majorants = MajorantGrid::new(&g, 2.0, to_unit);
                let to_world = to_unit.inverse();
                let mut rng = Rng::new(9, 1);
                for _ in 0..300 {
                    let a = to_world.transform_point3(Vec3::new(
                        rng.next_f32(),
                        rng.next_f32(),
                        rng.next_f32(),
                    ));
                    let b = to_world.transform_point3(Vec3::new(
                        rng.next_f32(),
                        rng.next_f32(),
                        rng.next_f32(),
                    ));
                    let d = (b - a).normalize();
                    let len = (b - a).length();
                    let mut covered = 0.0f32;
                    majorants.for_each_segment(a, d, 0.0, len, |s0, s1, m| {
                        assert!(
                            (s0 - covered).abs() <= 1e-4 * len.max(1.0),
                            "gap at {s0} (covered {covered})"
                        );
                        for k in 0..8 {
                            let t = s0 + (s1 - s0) * (k as f32 + 0.5) / 8.0;
                            let sigma = 2.0 * g.eval(a + d * t).max_channel();
                            assert!(
                                sigma <= m * (1.0 + 1e-5) + 1e-6,
                                "{wrap:?} {filter:?}: σ {sigma} > majorant {m}"
                            );
                        }
                        covered = s1;
                        true
                    });
                    assert!(
                        (covered - len).abs() <= 1e-4 * len.max(1.0),
                        "ended at {covered} of {len}"
                    );
                }
            }
        }
    }
}
