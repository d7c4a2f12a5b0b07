//! Triangle-mesh file formats: Wavefront OBJ ([`obj`]) with its MTL material libraries ([`mtl`]),
//! Stanford PLY ([`ply`]) and Mitsuba's serialized meshes ([`serialized`]), plus the geometry helpers they share (polygon triangulation,
//! degenerate-triangle tests, vertex-normal estimation).
//!
//! Every reader is hand-written so that each error names its place: `file:line:column` for the
//! text formats, the header line or the element index and byte offset for PLY bodies. Readers never
//! panic on malformed input, and never allocate more than a bounded multiple of the input's size
//! (the `fuzz/` directory at the workspace root exercises that).
//!
//! Conventions shared by the readers:
//! - Polygons are triangulated as a fan from their first vertex when convex (what Mitsuba 3's OBJ
//!   loader does); non-convex simple polygons of up to [`EAR_CLIPPING_MAX_VERTICES`] vertices are
//!   ear-clipped instead. Winding is preserved.
//! - Degenerate (zero-area) triangles are dropped and counted, since [`TriangleMesh`] promises
//!   none; a file in which *every* triangle is degenerate is an error.
//! - Normals read from files are normalised; a zero-length or non-finite normal is an error.

#![deny(missing_docs)]

pub mod mtl;
pub mod obj;
pub mod ply;
pub mod serialized;

pub use mtl::{parse_mtl, read_mtl, MtlMaterial, MtlTexture};
pub use obj::{obj_to_mesh, parse_obj, read_obj, ObjData, ObjGroup};
pub use ply::{parse_ply, read_ply};
pub use serialized::{parse_serialized, read_serialized, write_serialized, SerializedMesh};

use crate::desc::TriangleMesh;
use ircache_math::{Vec2, Vec3};

/// Polygons with more vertices than this are fan-triangulated even when non-convex (ear clipping
/// is quadratic to cubic in the vertex count).
pub const EAR_CLIPPING_MAX_VERTICES: usize = 64;

/// True when the triangle `(a, b, c)` has exactly zero area (or a non-finite normal), judged in
/// double precision so that small but valid triangles are kept.
#[must_use]
pub fn is_degenerate(a: Vec3, b: Vec3, c: Vec3) -> bool {
    let a = a.as_dvec3();
    let e1 = b.as_dvec3() - a;
    let e2 = c.as_dvec3() - a;
    let n = e1.cross(e2);
    let len2 = n.length_squared();
    !(len2 > 0.0 && len2.is_finite())
}

/// Triangulates a planar-ish polygon given by its vertex positions, returning index triples into
/// `points` with the polygon's winding. Triangles (3 points) are returned as is; convex polygons are
/// fan-triangulated from point 0; simple non-convex polygons of at most
/// [`EAR_CLIPPING_MAX_VERTICES`] points are ear-clipped; anything else (self-intersecting, larger,
/// or without a defined plane) falls back to the fan. Fewer than 3 points give no triangles.
#[must_use]
pub fn triangulate_polygon(points: &[Vec3]) -> Vec<[usize; 3]> {
    let n = points.len();
    if n < 3 {
        return Vec::new();
    }
    let fan = || (1..n - 1).map(|i| [0, i, i + 1]).collect::<Vec<_>>();
    if n == 3 || n > EAR_CLIPPING_MAX_VERTICES {
        return fan();
    }
    // Newell normal: robust plane normal of a polygon, oriented by its winding.
    let mut normal = glam::DVec3::ZERO;
    for i in 0..n {
        let p = points[i].as_dvec3();
        let q = points[(i + 1) % n].as_dvec3();
        normal += glam::DVec3::new(
            (p.y - q.y) * (p.z + q.z),
            (p.z - q.z) * (p.x + q.x),
            (p.x - q.x) * (p.y + q.y),
        );
    }
    if !(normal.length_squared() > 0.0 && normal.is_finite()) {
        return fan();
    }
    // Project onto the plane of the two axes other than the normal's dominant one, keeping the
    // orientation so that the polygon is counter-clockwise in 2D.
    let abs = normal.abs();
    let (ax, ay, sign) = if abs.x >= abs.y && abs.x >= abs.z {
        (1, 2, normal.x.signum())
    } else if abs.y >= abs.z {
        (2, 0, normal.y.signum())
    } else {
        (0, 1, normal.z.signum())
    };
    let p2: Vec<glam::DVec2> = points
        .iter()
        .map(|p| {
            let p = p.as_dvec3().to_array();
            glam::DVec2::new(p[ax], p[ay] * sign)
        })
        .collect();
    let cross = |o: glam::DVec2, a: glam::DVec2, b: glam::DVec2| (a - o).perp_dot(b - o);
    let convex = (0..n).all(|i| cross(p2[i], p2[(i + 1) % n], p2[(i + 2) % n]) >= 0.0);
    if convex {
        return fan();
    }
    ear_clip(&p2).unwrap_or_else(fan)
}

/// Ear clipping of a counter-clockwise simple polygon in 2D; `None` when no ear can be found (the
/// polygon is not simple).
fn ear_clip(p: &[glam::DVec2]) -> Option<Vec<[usize; 3]>> {
    let cross = |o: glam::DVec2, a: glam::DVec2, b: glam::DVec2| (a - o).perp_dot(b - o);
    let mut remaining: Vec<usize> = (0..p.len()).collect();
    let mut out = Vec::with_capacity(p.len() - 2);
    while remaining.len() > 3 {
        let m = remaining.len();
        let mut clipped = false;
        for i in 0..m {
            let (ia, ib, ic) = (
                remaining[(i + m - 1) % m],
                remaining[i],
                remaining[(i + 1) % m],
            );
            let (a, b, c) = (p[ia], p[ib], p[ic]);
            if cross(a, b, c) <= 0.0 {
                continue; // reflex or flat corner
            }
            let inside = remaining.iter().any(|&j| {
                j != ia
                    && j != ib
                    && j != ic
                    && cross(a, b, p[j]) >= 0.0
                    && cross(b, c, p[j]) >= 0.0
                    && cross(c, a, p[j]) >= 0.0
            });
            if inside {
                continue;
            }
            out.push([ia, ib, ic]);
            remaining.remove(i);
            clipped = true;
            break;
        }
        if !clipped {
            return None;
        }
    }
    out.push([remaining[0], remaining[1], remaining[2]]);
    Some(out)
}

/// Angle-weighted vertex normals of a mesh (each triangle contributes its unit normal times the
/// angle at the vertex, as Mitsuba 3's `recompute_vertex_normals` does). A vertex whose
/// contributions cancel gets the normal of the first triangle using it, and an unused vertex +z, so
/// that every returned normal has unit length.
#[must_use]
pub fn compute_vertex_normals(mesh: &TriangleMesh) -> Vec<Vec3> {
    let mut acc = vec![glam::DVec3::ZERO; mesh.positions.len()];
    let mut fallback = vec![None; mesh.positions.len()];
    for tri in &mesh.indices {
        let [i0, i1, i2] = tri.map(|i| i as usize);
        let (Some(&p0), Some(&p1), Some(&p2)) = (
            mesh.positions.get(i0),
            mesh.positions.get(i1),
            mesh.positions.get(i2),
        ) else {
            continue;
        };
        let (p0, p1, p2) = (p0.as_dvec3(), p1.as_dvec3(), p2.as_dvec3());
        let n = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        if n == glam::DVec3::ZERO {
            continue;
        }
        for (i, (a, b, c)) in [(i0, (p0, p1, p2)), (i1, (p1, p2, p0)), (i2, (p2, p0, p1))] {
            let angle = (b - a)
                .normalize_or_zero()
                .dot((c - a).normalize_or_zero())
                .clamp(-1.0, 1.0)
                .acos();
            acc[i] += n * angle;
            fallback[i].get_or_insert(n);
        }
    }
    acc.iter()
        .zip(&fallback)
        .map(|(a, f)| {
            let n = a.normalize_or_zero();
            if n != glam::DVec3::ZERO {
                n.as_vec3()
            } else {
                f.map_or(Vec3::Z, |f| f.as_vec3())
            }
        })
        .collect()
}

/// Builds one [`TriangleMesh`] from corner tuples, de-duplicating vertices by their source index
/// triple. Shared by the OBJ reader (per group) and [`obj_to_mesh`].
#[derive(Default)]
pub(crate) struct MeshBuilder {
    pub(crate) mesh: TriangleMesh,
    /// Source (position, uv, normal) index triple of each mesh vertex (`u32::MAX` = absent).
    pub(crate) keys: Vec<[u32; 3]>,
    map: std::collections::HashMap<[u32; 3], u32>,
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    any_uv: bool,
    all_normals: bool,
}

/// The "absent" marker in a vertex key.
pub(crate) const NO_INDEX: u32 = u32::MAX;

impl MeshBuilder {
    pub(crate) fn new() -> MeshBuilder {
        MeshBuilder {
            all_normals: true,
            ..MeshBuilder::default()
        }
    }

    /// The mesh vertex for a source key, creating it from the source arrays if new.
    /// `key[0]` must index `positions`, `key[1]`/`key[2]` `uvs`/`normals` or be [`NO_INDEX`].
    pub(crate) fn vertex(
        &mut self,
        key: [u32; 3],
        positions: &[Vec3],
        uvs: &[Vec2],
        normals: &[Vec3],
    ) -> u32 {
        if let Some(&id) = self.map.get(&key) {
            return id;
        }
        let id = self.positions.len() as u32;
        self.positions.push(positions[key[0] as usize]);
        if key[1] != NO_INDEX {
            self.any_uv = true;
            self.uvs.push(uvs[key[1] as usize]);
        } else {
            self.uvs.push(Vec2::ZERO);
        }
        if key[2] != NO_INDEX {
            self.normals.push(normals[key[2] as usize]);
        } else {
            self.all_normals = false;
            self.normals.push(Vec3::ZERO);
        }
        self.keys.push(key);
        self.map.insert(key, id);
        id
    }

    pub(crate) fn triangle(&mut self, tri: [u32; 3]) {
        self.mesh.indices.push(tri);
    }

    /// Number of triangles so far.
    pub(crate) fn triangle_count(&self) -> usize {
        self.mesh.indices.len()
    }

    /// The finished mesh and the source key of each vertex. Texture coordinates are kept when any
    /// vertex has one (the others get (0, 0)); normals are kept when any vertex has one, vertices
    /// without one getting the angle-weighted normal of the mesh.
    pub(crate) fn finish(mut self) -> (TriangleMesh, Vec<[u32; 3]>) {
        let any_normal = self.keys.iter().any(|k| k[2] != NO_INDEX);
        self.mesh.positions = self.positions;
        self.mesh.uvs = self.any_uv.then_some(self.uvs);
        if any_normal {
            if !self.all_normals {
                let computed = compute_vertex_normals(&self.mesh);
                for ((n, c), k) in self.normals.iter_mut().zip(computed).zip(&self.keys) {
                    if k[2] == NO_INDEX {
                        *n = c;
                    }
                }
            }
            self.mesh.normals = Some(self.normals);
        }
        (self.mesh, self.keys)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fan_for_convex_quad() {
        let q = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        assert_eq!(triangulate_polygon(&q), vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn ear_clipping_for_concave_polygon() {
        // An arrow-head: vertex 0 is reflex, so a fan from 0 would leave the polygon.
        let p = [
            Vec3::new(0.5, 0.4, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.5, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 0.0),
        ];
        let tris = triangulate_polygon(&p);
        assert_eq!(tris.len(), 2);
        // Total area equals the polygon's area, and every triangle keeps the winding (+z).
        let mut area = 0.0;
        for t in &tris {
            let n = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
            assert!(n.z > 0.0, "{tris:?}");
            area += n.z / 2.0;
        }
        let expected = 0.5 * (1.0 * 1.0) - 0.5 * (1.0 * 0.4);
        assert!((area - expected).abs() < 1e-6, "{area} vs {expected}");
    }

    #[test]
    fn degenerate_detection() {
        assert!(is_degenerate(Vec3::ZERO, Vec3::X, Vec3::X * 2.0));
        assert!(!is_degenerate(Vec3::ZERO, Vec3::X * 1e-20, Vec3::Y * 1e-20));
    }
}
