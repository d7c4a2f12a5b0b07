//! Mitsuba 3's built-in analytic shapes as triangle meshes, and the mesh operations the loaders
//! share (transforming to world space, flipping, areas).
//!
//! Object-space conventions follow Mitsuba 3 exactly:
//! - [`rectangle`]: the square [−1, 1]² at z = 0, normal +z, uv = (x/2 + ½, y/2 + ½).
//! - [`cube`]: [−1, 1]³, 24 vertices (4 per face), 12 triangles with outward normals and
//!   Mitsuba's per-face uv layout (its `cube.cpp` vertex, normal, uv and index tables).
//! - [`disk`]: the unit disk at z = 0, normal +z. Mitsuba intersects the exact disk; here it is a
//!   fan of `segments` triangles whose polygon radius is enlarged so that the polygon's area equals
//!   π (the disk's), keeping emitted power and irradiance from a disk light exact. uv = (r, φ/2π)
//!   as in Mitsuba (r = 1 on the rim); every triangle has its own three vertices so that the seam
//!   at φ = 0 interpolates correctly.

use crate::desc::TriangleMesh;
use ircache_math::{Mat3, Mat4, Vec2, Vec3};

/// Segments used when a Mitsuba `disk` is tessellated.
pub const DISK_SEGMENTS: u32 = 256;

/// Mitsuba's `rectangle`: two triangles covering [−1, 1]² at z = 0, normal +z.
#[must_use]
pub fn rectangle() -> TriangleMesh {
    let positions = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let uvs = positions
        .iter()
        .map(|p| Vec2::new(0.5 * p.x + 0.5, 0.5 * p.y + 0.5))
        .collect();
    TriangleMesh {
        positions,
        normals: None,
        uvs: Some(uvs),
        indices: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// Mitsuba's `cube`: [−1, 1]³ with per-face vertices, outward per-vertex normals and uvs.
#[must_use]
pub fn cube() -> TriangleMesh {
    // Mitsuba 3 cube.cpp tables.
    const P: [[f32; 3]; 24] = [
        [1., -1., -1.],
        [1., -1., 1.],
        [-1., -1., 1.],
        [-1., -1., -1.],
        [1., 1., -1.],
        [-1., 1., -1.],
        [-1., 1., 1.],
        [1., 1., 1.],
        [1., -1., -1.],
        [1., 1., -1.],
        [1., 1., 1.],
        [1., -1., 1.],
        [1., -1., 1.],
        [1., 1., 1.],
        [-1., 1., 1.],
        [-1., -1., 1.],
        [-1., -1., 1.],
        [-1., 1., 1.],
        [-1., 1., -1.],
        [-1., -1., -1.],
        [1., 1., -1.],
        [1., -1., -1.],
        [-1., -1., -1.],
        [-1., 1., -1.],
    ];
    const N: [[f32; 3]; 6] = [
        [0., -1., 0.],
        [0., 1., 0.],
        [1., 0., 0.],
        [0., 0., 1.],
        [-1., 0., 0.],
        [0., 0., -1.],
    ];
    const UV: [[f32; 2]; 4] = [[0., 1.], [1., 1.], [1., 0.], [0., 0.]];
    let positions = P.iter().map(|&p| Vec3::from_array(p)).collect();
    let normals = (0..24).map(|i| Vec3::from_array(N[i / 4])).collect();
    let uvs = (0..24).map(|i| Vec2::from_array(UV[i % 4])).collect();
    let indices = (0..6u32)
        .flat_map(|f| [[4 * f, 4 * f + 1, 4 * f + 2], [4 * f + 3, 4 * f, 4 * f + 2]])
        .collect();
    TriangleMesh {
        positions,
        normals: Some(normals),
        uvs: Some(uvs),
        indices,
    }
}

/// Polygon radius that gives a regular `segments`-gon the area of the unit disk, π.
#[must_use]
pub fn disk_polygon_radius(segments: u32) -> f32 {
    let n = f64::from(segments.max(3));
    let area_unit = 0.5 * n * (2.0 * std::f64::consts::PI / n).sin();
    (std::f64::consts::PI / area_unit).sqrt() as f32
}

/// Mitsuba's `disk` tessellated as a fan of `segments` (≥ 3) triangles of total area π, normal +z.
#[must_use]
pub fn disk(segments: u32) -> TriangleMesh {
    let n = segments.max(3);
    let r = disk_polygon_radius(n);
    let mut positions = Vec::with_capacity(3 * n as usize);
    let mut uvs = Vec::with_capacity(3 * n as usize);
    let mut indices = Vec::with_capacity(n as usize);
    for i in 0..n {
        let a0 = i as f32 / n as f32;
        let a1 = (i + 1) as f32 / n as f32;
        let (phi0, phi1) = (a0 * std::f32::consts::TAU, a1 * std::f32::consts::TAU);
        let base = positions.len() as u32;
        positions.push(Vec3::ZERO);
        positions.push(Vec3::new(r * phi0.cos(), r * phi0.sin(), 0.0));
        positions.push(Vec3::new(r * phi1.cos(), r * phi1.sin(), 0.0));
        uvs.push(Vec2::new(0.0, 0.5 * (a0 + a1)));
        uvs.push(Vec2::new(1.0, a0));
        uvs.push(Vec2::new(1.0, a1));
        indices.push([base, base + 1, base + 2]);
    }
    TriangleMesh {
        positions,
        normals: None,
        uvs: Some(uvs),
        indices,
    }
}

/// Mitsuba's `cylinder` (radius 1, from z = 0 to z = 1, open at both ends, normals outward)
/// tessellated into `segments` (≥ 3) strips whose polygon has the circle's perimeter, so the
/// lateral area is 2π; smooth normals (the circle's), uv = (φ/2π, z) as Mitsuba's.
#[must_use]
pub fn cylinder(segments: u32) -> TriangleMesh {
    let n = segments.max(3);
    let nf = f64::from(n);
    let r = (std::f64::consts::PI / (nf * (std::f64::consts::PI / nf).sin())) as f32;
    let mut positions = Vec::with_capacity(2 * (n as usize + 1));
    let mut normals = Vec::with_capacity(2 * (n as usize + 1));
    let mut uvs = Vec::with_capacity(2 * (n as usize + 1));
    for i in 0..=n {
        let a = i as f32 / n as f32;
        let phi = a * std::f32::consts::TAU;
        let (s, c) = if i == n { (0.0, 1.0) } else { phi.sin_cos() };
        for z in [0.0, 1.0] {
            positions.push(Vec3::new(r * c, r * s, z));
            normals.push(Vec3::new(c, s, 0.0));
            uvs.push(Vec2::new(a, z));
        }
    }
    let indices = (0..n)
        .flat_map(|i| {
            let (a, d, b, c) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            [[a, b, c], [a, c, d]]
        })
        .collect();
    TriangleMesh {
        positions,
        normals: Some(normals),
        uvs: Some(uvs),
        indices,
    }
}

/// Transforms a mesh in place: positions by `m` (affine part), normals by the inverse transpose
/// of its linear part, renormalised. Returns `false` when the linear part is singular (the mesh
/// is then left unchanged).
pub fn transform_mesh(mesh: &mut TriangleMesh, m: &Mat4) -> bool {
    let lin = Mat3::from_mat4(*m);
    let det = lin.determinant();
    if !det.is_finite() || det == 0.0 {
        return false;
    }
    let nm = lin.inverse().transpose();
    for p in &mut mesh.positions {
        *p = m.transform_point3(*p);
    }
    if let Some(normals) = &mut mesh.normals {
        for n in normals {
            *n = (nm * *n).normalize_or_zero();
        }
    }
    true
}

/// Reverses the winding of every triangle and negates the shading normals (`flip_normals`).
pub fn flip_mesh(mesh: &mut TriangleMesh) {
    for t in &mut mesh.indices {
        t.swap(1, 2);
    }
    if let Some(normals) = &mut mesh.normals {
        for n in normals {
            *n = -*n;
        }
    }
}

/// Reverses the winding of every triangle, leaving normals alone.
pub fn reverse_winding(mesh: &mut TriangleMesh) {
    for t in &mut mesh.indices {
        t.swap(1, 2);
    }
}

/// The area of triangle `t` of `mesh`.
#[must_use]
pub fn triangle_area(mesh: &TriangleMesh, t: usize) -> f32 {
    let [a, b, c] = mesh.indices[t].map(|i| mesh.positions[i as usize]);
    0.5 * (b - a).cross(c - a).length()
}

/// Total surface area of a mesh (summed in double precision).
#[must_use]
pub fn mesh_area(mesh: &TriangleMesh) -> f64 {
    (0..mesh.indices.len())
        .map(|t| f64::from(triangle_area(mesh, t)))
        .sum()
}

/// The first triangle whose area is zero (or not finite, or negligible against its edge
/// lengths), if any.
#[must_use]
pub fn find_degenerate_triangle(mesh: &TriangleMesh) -> Option<usize> {
    mesh.indices.iter().position(|t| {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let (e1, e2) = (b - a, c - a);
        let cross = e1.cross(e2).length();
        !cross.is_finite() || cross <= 1e-7 * e1.length() * e2.length() || cross == 0.0
    })
}

/// Unit geometric normal of triangle `t`, from its winding.
#[must_use]
pub fn triangle_normal(mesh: &TriangleMesh, t: usize) -> Vec3 {
    let [a, b, c] = mesh.indices[t].map(|i| mesh.positions[i as usize]);
    (b - a).cross(c - a).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1.0)
    }

    #[test]
    fn rectangle_area_normal_uv() {
        let m = rectangle();
        assert!(close(mesh_area(&m), 4.0, 1e-6));
        for t in 0..2 {
            assert!((triangle_normal(&m, t) - Vec3::Z).length() < 1e-6);
        }
        let uvs = m.uvs.as_ref().unwrap();
        assert_eq!(uvs[0], Vec2::new(0.0, 0.0));
        assert_eq!(uvs[2], Vec2::new(1.0, 1.0));
    }

    #[test]
    fn cube_area_outward_normals() {
        let m = cube();
        assert_eq!(m.indices.len(), 12);
        assert!(close(mesh_area(&m), 24.0, 1e-6));
        let normals = m.normals.as_ref().unwrap();
        for t in 0..12 {
            let ng = triangle_normal(&m, t);
            let [a, b, c] = m.indices[t].map(|i| i as usize);
            let centroid = (m.positions[a] + m.positions[b] + m.positions[c]) / 3.0;
            // Outward: the normal points away from the centre.
            assert!(ng.dot(centroid) > 0.0, "triangle {t} faces inwards");
            for i in [a, b, c] {
                assert!(
                    (normals[i] - ng).length() < 1e-6,
                    "vertex normal disagrees on {t}"
                );
            }
        }
        assert!(find_degenerate_triangle(&m).is_none());
    }

    #[test]
    fn flat_shading_is_found_from_the_normals() {
        assert!(rectangle().shades_flat(), "no normals");
        assert!(cube().shades_flat(), "a normal per face");
        let mut turned = cube();
        // One vertex normal tilted by about 0.01 rad, or all of them reversed: both shade smooth.
        let n = turned.normals.as_mut().unwrap();
        n[0] = (n[0] + Vec3::new(0.01, 0.0, 0.01)).normalize();
        assert!(!turned.shades_flat());
        let mut flipped = cube();
        for n in flipped.normals.as_mut().unwrap() {
            *n = -*n;
        }
        assert!(!flipped.shades_flat());
    }

    #[test]
    fn disk_area_is_exact() {
        for n in [3, 16, DISK_SEGMENTS] {
            let m = disk(n);
            assert_eq!(m.indices.len(), n as usize);
            assert!(close(mesh_area(&m), std::f64::consts::PI, 1e-5), "n = {n}");
            for t in 0..m.indices.len() {
                assert!((triangle_normal(&m, t) - Vec3::Z).length() < 1e-5);
            }
        }
    }

    #[test]
    fn transform_scales_area_and_normals() {
        let mut m = cube();
        let xf = Mat4::from_scale(Vec3::new(2.0, 3.0, 0.5));
        assert!(transform_mesh(&mut m, &xf));
        // Faces: 2 × (4·1.5 + 4·1 + 6·... ) computed directly: extents 4 × 6 × 1.
        let expected = 2.0 * (4.0 * 6.0 + 4.0 * 1.0 + 6.0 * 1.0);
        assert!(close(mesh_area(&m), expected, 1e-6));
        for n in m.normals.as_ref().unwrap() {
            assert!((n.length() - 1.0).abs() < 1e-6);
        }
        let mut f = rectangle();
        flip_mesh(&mut f);
        assert!((triangle_normal(&f, 0) + Vec3::Z).length() < 1e-6);
        assert!(!transform_mesh(
            &mut f,
            &Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0))
        ));
    }
}
