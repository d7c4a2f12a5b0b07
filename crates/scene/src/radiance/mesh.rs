//! Radiance's compiled meshes (`obj2mesh`'s `.rtm`; `src/common/readmesh.c`, `mesh.c`,
//! `dircode.c`), read for the `mesh` primitive.
//!
//! After a text header (`FORMAT=Radiance_tmesh`) come, in Radiance's portable binary: the object
//! size (minus 319), the bounding cube (four strings), the (u, v) limits (four reals), the mesh's
//! octree (skipped), its materials (as an octree's scene data) and its patches. A patch holds up
//! to 256 vertices, quantised to 32 bits across the cube (normals in a 32-bit direction code,
//! (u, v) across their limits), its local triangles (three vertex bytes and a material), and
//! triangles joining it to other patches (one or two vertices given as patch · 256 + vertex).

use super::octree::{at_object, header_end, Reader};
use super::parse::Primitive;
use super::xform::Transform;
use crate::desc::TriangleMesh;
use crate::SceneError;
use ircache_math::{DVec3, Vec2};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// Radiance's `MESHMAGIC`: `1 · MAXOBJSIZ + 311`.
const MESHMAGIC: i64 = 8 + 311;

/// A mesh's materials (its own scene data, in order) and its triangles grouped by material:
/// `(index into the materials, or None for void; the triangles in world space)`.
pub struct Mesh {
    /// The material primitives the mesh carries.
    pub materials: Vec<Primitive>,
    /// The triangles of each material.
    pub groups: Vec<(Option<usize>, TriangleMesh)>,
}

/// One patch's vertices and triangles (vertex ids are patch · 256 + index).
struct Patch {
    xyz: Vec<[u32; 3]>,
    normals: Option<Vec<i32>>,
    uvs: Option<Vec<[u32; 2]>>,
    /// `(three vertex ids, material)`, local and joining triangles alike.
    triangles: Vec<([u32; 3], i64)>,
}

/// Reads the mesh at `path`, moved by `transform`.
pub fn read(path: &Path, transform: &Transform) -> Result<Mesh, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let file = Arc::new(path.to_path_buf());
    let err = |m: String| at_object(&file, 1, m);
    let start = header_end(&bytes, "Radiance_tmesh").ok_or_else(|| {
        err("not a Radiance mesh (its header does not say FORMAT=Radiance_tmesh)".into())
    })?;
    let mut r = Reader::new(&bytes, start);
    let truncated = |r: &Reader| err(format!("the mesh is truncated at byte {}", r.pos()));
    let size = r.int(2).ok_or_else(|| truncated(&r))? - MESHMAGIC;
    if !(1..=8).contains(&size) {
        return Err(err("incompatible mesh format".into()));
    }
    let size = size as usize;
    let mut cube = [0.0f64; 4];
    for c in &mut cube {
        let s = r.string().ok_or_else(|| truncated(&r))?;
        *c = s
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| err(format!("the mesh's bounds \"{s}\" are not a number")))?;
    }
    // Written as (u min, u max, v min, v max): uv_limits[0] the minima, [1] the maxima.
    let mut uv_limits = [[0.0f64; 2]; 2];
    for axis in 0..2 {
        for limit in &mut uv_limits {
            limit[axis] = r.real().ok_or_else(|| truncated(&r))?;
        }
    }
    r.skip_tree(size).ok_or_else(|| truncated(&r))?;
    let materials = super::octree::read_scene(&mut r, size, &file)?;
    let count = r.int(4).ok_or_else(|| truncated(&r))?;
    if count < 0 {
        return Err(err(format!("{count} patches")));
    }
    let mut patches = Vec::new();
    for k in 0..count {
        patches
            .push(patch(&mut r).ok_or_else(|| err(format!("patch {k} is damaged or truncated")))?);
    }
    // Vertices from their ids, in world space.
    let scale = cube[3] / 4_294_967_296.0;
    let origin = DVec3::new(cube[0], cube[1], cube[2]);
    let linear = transform.matrix;
    let normal_matrix = linear.inverse().transpose();
    let vertex = |id: u32| -> Option<(DVec3, Option<DVec3>, Option<Vec2>)> {
        let p = patches.get((id >> 8) as usize)?;
        let v = (id & 0xff) as usize;
        let xyz = p.xyz.get(v)?;
        let q = |i: usize| (f64::from(xyz[i]) + 0.5) * scale;
        let local = origin + DVec3::new(q(0), q(1), q(2));
        let n = p
            .normals
            .as_ref()
            .and_then(|n| n.get(v))
            .filter(|&&code| code != 0)
            .map(|&code| {
                normal_matrix
                    .transform_vector3(decode_direction(code))
                    .normalize()
            });
        let uv = p
            .uvs
            .as_ref()
            .and_then(|uv| uv.get(v))
            .filter(|uv| uv[0] != 0)
            .map(|uv| {
                let at = |i: usize| {
                    uv_limits[0][i]
                        + (uv_limits[1][i] - uv_limits[0][i]) * (f64::from(uv[i]) + 0.5)
                            / 4_294_967_296.0
                };
                Vec2::new(at(0) as f32, at(1) as f32)
            });
        Some((transform.point(local), n, uv))
    };
    // Triangles grouped by material, vertices shared within a group.
    let mut groups: Vec<(Option<usize>, Vec<[u32; 3]>)> = Vec::new();
    let mut group_of: HashMap<i64, usize> = HashMap::new();
    for (k, p) in patches.iter().enumerate() {
        for (ids, material) in &p.triangles {
            let material = match *material {
                -1 => None,
                m if (0..materials.len() as i64).contains(&m) => Some(m as usize),
                m => {
                    return Err(err(format!(
                        "patch {k}: a triangle's material {m} is not among the mesh's {}",
                        materials.len()
                    )))
                }
            };
            let g = *group_of
                .entry(material.map_or(-1, |m| m as i64))
                .or_insert_with(|| {
                    groups.push((material, Vec::new()));
                    groups.len() - 1
                });
            // Ids local to this patch get its number.
            let tri = ids.map(|id| {
                if id & LOCAL != 0 {
                    (k as u32) << 8 | (id & 0xff)
                } else {
                    id
                }
            });
            groups[g].1.push(tri);
        }
    }
    let mut out = Vec::new();
    for (material, triangles) in groups {
        let mut local: HashMap<u32, u32> = HashMap::new();
        let (mut positions, mut normals, mut uvs) = (Vec::new(), Vec::new(), Vec::new());
        let (mut all_normals, mut all_uvs) = (true, true);
        let mut indices = Vec::with_capacity(triangles.len());
        for tri in triangles {
            let mut idx = [0u32; 3];
            for (i, &id) in idx.iter_mut().zip(&tri) {
                *i = match local.get(&id) {
                    Some(&i) => i,
                    None => {
                        let (p, n, uv) = vertex(id).ok_or_else(|| {
                            err(format!(
                                "a triangle names vertex {id}, which no patch holds"
                            ))
                        })?;
                        all_normals &= n.is_some();
                        all_uvs &= uv.is_some();
                        positions.push(p.as_vec3());
                        normals.push(n.unwrap_or(DVec3::Z).as_vec3());
                        uvs.push(uv.unwrap_or(Vec2::ZERO));
                        local.insert(id, positions.len() as u32 - 1);
                        positions.len() as u32 - 1
                    }
                };
            }
            indices.push(idx);
        }
        if transform.reverse {
            for t in &mut indices {
                t.swap(1, 2);
            }
        }
        out.push((
            material,
            TriangleMesh {
                positions,
                normals: all_normals.then_some(normals),
                uvs: all_uvs.then_some(uvs),
                indices,
            },
        ));
    }
    Ok(Mesh {
        materials,
        groups: out,
    })
}

/// One patch (`getpatch`); `None` when damaged.
fn patch(r: &mut Reader) -> Option<Patch> {
    let flags = r.int(1)?;
    if flags & 1 == 0 || flags & !7 != 0 {
        return None;
    }
    let nverts = r.int(2)?;
    if !(1..=256).contains(&nverts) {
        return None;
    }
    let n = nverts as usize;
    let u32_of = |r: &mut Reader| r.int(4).map(|v| v as u32);
    let mut xyz = Vec::with_capacity(n);
    for _ in 0..n {
        xyz.push([u32_of(r)?, u32_of(r)?, u32_of(r)?]);
    }
    let normals = if flags & 2 != 0 {
        Some(
            (0..n)
                .map(|_| r.int(4).map(|v| v as i32))
                .collect::<Option<Vec<_>>>()?,
        )
    } else {
        None
    };
    let uvs = if flags & 4 != 0 {
        Some(
            (0..n)
                .map(|_| Some([u32_of(r)?, u32_of(r)?]))
                .collect::<Option<Vec<_>>>()?,
        )
    } else {
        None
    };
    let base = |v: i64| -> Option<u32> { u32::try_from(v).ok() };
    let ntris = r.int(2)?;
    if !(0..=512).contains(&ntris) {
        return None;
    }
    let mut local = Vec::with_capacity(ntris as usize);
    for _ in 0..ntris {
        // Vertex bytes are unsigned.
        let v = [r.int(1)? & 0xff, r.int(1)? & 0xff, r.int(1)? & 0xff];
        local.push(v);
    }
    let materials: Vec<i64> = if r.int(2)? > 1 {
        (0..ntris).map(|_| r.int(2)).collect::<Option<Vec<_>>>()?
    } else {
        vec![r.int(2)?; ntris as usize]
    };
    // Local vertex ids get this patch's number when the caller knows it: keep them local here
    // and mark them with the high bit.
    let mut triangles: Vec<([u32; 3], i64)> = local
        .iter()
        .zip(&materials)
        .map(|(v, &m)| (v.map(|x| LOCAL | x as u32), m))
        .collect();
    let nj1 = r.int(2)?;
    if !(0..=256).contains(&nj1) {
        return None;
    }
    for _ in 0..nj1 {
        let v1 = base(r.int(4)?)?;
        let (v2, v3) = (r.int(1)? & 0xff, r.int(1)? & 0xff);
        let m = r.int(2)?;
        triangles.push(([v1, LOCAL | v2 as u32, LOCAL | v3 as u32], m));
    }
    let nj2 = r.int(2)?;
    if !(0..=256).contains(&nj2) {
        return None;
    }
    for _ in 0..nj2 {
        let (v1, v2) = (base(r.int(4)?)?, base(r.int(4)?)?);
        let v3 = r.int(1)? & 0xff;
        let m = r.int(2)?;
        triangles.push(([v1, v2, LOCAL | v3 as u32], m));
    }
    Some(Patch {
        xyz,
        normals,
        uvs,
        triangles,
    })
}

/// Marks a vertex id local to its patch (the patch's number is put in once all are read).
const LOCAL: u32 = 1 << 31;

/// Radiance's 32-bit direction code (`dircode.c`'s `decodedir`).
fn decode_direction(code: i32) -> DVec3 {
    const SCALE: f64 = 11584.5;
    let c = code as u32;
    let d1 = f64::from((c >> 5) & 0x1fff) / SCALE;
    let d2 = f64::from((c >> 18) & 0x1fff) / SCALE;
    let der = (1.0 - d1 * d1 - d2 * d2).max(0.0).sqrt();
    let order = match ((c & 0o20 != 0) as usize) << 1 | (c & 0o10 != 0) as usize {
        0 => [1, 0, 2],
        1 => [0, 1, 2],
        2 => [1, 2, 0],
        _ => [0, 2, 1],
    };
    let mut v = [0.0; 3];
    v[order[0]] = d1;
    v[order[1]] = d2;
    v[order[2]] = der;
    for (i, x) in v.iter_mut().enumerate() {
        if c & (1 << i) != 0 {
            *x = -*x;
        }
    }
    DVec3::from_array(v)
}
