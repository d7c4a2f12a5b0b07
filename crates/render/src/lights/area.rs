//! Area lights on triangle meshes (Mitsuba 3's `area` emitter attached to a mesh).
//!
//! The emitter is one-sided: a surface point emits radiance `L` towards `wo` only when `wo` lies on
//! the side of its *shading* normal (the interpolated vertex normal when the mesh has normals,
//! otherwise the geometric normal `(p1 − p0) × (p2 − p0)`), as Mitsuba's `area` emitter does.
//!
//! Sampling picks a point uniformly by area over the whole mesh: a triangle with probability
//! proportional to its area (a [`Distribution1D`] over the triangle areas), then a uniform point in
//! it with Heitz's low-distortion map ([`square_to_uniform_triangle`]). The area density is `1/A`
//! (A the total area), converted to solid angle at the reference point with the *geometric* normal
//! (the true Jacobian of the surface, PBRT 3rd ed. §14.2.2):
//!
//! `p_ω = p_A · d² / |cos θ_light|`, `cos θ_light = n_g · ω`.
//!
//! A mesh that is one flat rectangle (Mitsuba's `rectangle` shape) is sampled uniformly by solid
//! angle instead, where its solid angle allows ([`super::rectangle`]); the density is then `1/Ω`.
//!
//! A textured emitter (Mitsuba's `area` with a texture as its `radiance`) emits the texture's
//! value at the surface's uv (the mesh's texture coordinates, else the barycentric (b1, b2), as a
//! hit's). It is sampled by area, rectangles too, and the sample carries the radiance at its
//! point; Mitsuba samples the texture's luminance in uv instead: the same expectation, another
//! noise. Its mean radiance stands for it where power is estimated (light selection, photons'
//! choice of light).

use super::rectangle::{Rectangle, Seen};
use super::{is_positive_finite, solid_angle_pdf, EmittedRadiance};
use ircache_math::sampling::{
    square_to_cosine_hemisphere, square_to_uniform_hemisphere, square_to_uniform_triangle,
    Distribution1D,
};
use ircache_math::{Frame, Rgb, Vec2, Vec3, PI};
use ircache_scene::TriangleMesh;

/// A uniformly sampled point on an emitting surface with its normals.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Position.
    pub p: Vec3,
    /// Unit geometric normal (for the area → solid-angle Jacobian).
    pub ng: Vec3,
    /// Unit shading normal (decides the emitting side).
    pub ns: Vec3,
    /// Texture coordinates, on textured emitters (zero elsewhere).
    pub uv: Vec2,
}

impl SurfacePoint {
    /// The geometric normal turned to the emitting side (the shading normal's).
    #[must_use]
    pub fn emitting_normal(&self) -> Vec3 {
        if self.ng.dot(self.ns) < 0.0 {
            -self.ng
        } else {
            self.ng
        }
    }
}

/// An emitting triangle mesh.
#[derive(Clone, Debug)]
pub struct MeshLight {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    indices: Vec<[u32; 3]>,
    /// Unit geometric normal of each triangle (`(p1 − p0) × (p2 − p0)`; zero where degenerate).
    triangle_normals: Vec<Vec3>,
    /// Triangle selection proportional to area.
    tri_dist: Distribution1D,
    /// Total surface area.
    area: f32,
    /// Emitted radiance (front side only).
    radiance: EmittedRadiance,
    /// The mesh's texture coordinates, where the radiance is textured and the mesh has them.
    uvs: Option<Vec<Vec2>>,
    /// The mesh as one flat rectangle, with the normal of its emitting side, when it is one:
    /// sampled by solid angle ([`super::rectangle`]).
    rectangle: Option<(Rectangle, Vec3)>,
}

impl MeshLight {
    /// A sphere bounding the mesh: `(centre of its bounding box, half its diagonal)`.
    #[must_use]
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        let (lo, hi) = self.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
    }

    /// An area light on `mesh` emitting `radiance`; `None` if the mesh has no area.
    #[must_use]
    pub fn new(mesh: &TriangleMesh, radiance: EmittedRadiance) -> Option<MeshLight> {
        // (p1 − p0) × (p2 − p0) of each triangle: twice its area along its normal.
        let cross: Vec<Vec3> = mesh
            .indices
            .iter()
            .map(|&[a, b, c]| {
                let (p0, p1, p2) = (
                    mesh.positions[a as usize],
                    mesh.positions[b as usize],
                    mesh.positions[c as usize],
                );
                (p1 - p0).cross(p2 - p0)
            })
            .collect();
        let areas: Vec<f32> = cross.iter().map(|c| 0.5 * c.length()).collect();
        let area = areas.iter().map(|&a| f64::from(a)).sum::<f64>() as f32;
        if !is_positive_finite(area) {
            return None;
        }
        let normals = mesh
            .normals
            .as_ref()
            .filter(|n| n.len() == mesh.positions.len())
            .cloned();
        // Solid-angle sampling needs one emitting side: both triangles wound alike and no
        // vertex normal leaning off the plane.
        let triangle_normals: Vec<Vec3> = cross.iter().map(|c| c.normalize_or_zero()).collect();
        let rectangle = Rectangle::from_triangles(&mesh.positions, &mesh.indices)
            .and_then(|r| {
                let n = triangle_normals[0];
                let flat = |v: Vec3| v.dot(n) > 1.0 - 1e-5;
                (flat(triangle_normals[1])
                    && normals
                        .as_ref()
                        .is_none_or(|ns| ns.iter().all(|&v| flat(v))))
                .then_some((r, n))
            })
            // By area where the radiance varies over the surface (a texture, or a pattern that
            // reads the mesh's (u, v)), so that each sample carries its point's.
            .filter(|_| {
                !(radiance.is_textured() || (radiance.is_patterned() && mesh.uvs.is_some()))
            });
        // Texture coordinates where the radiance or its pattern reads them.
        let uvs = mesh
            .uvs
            .as_ref()
            .filter(|t| radiance.reads_uv() && t.len() == mesh.positions.len())
            .cloned();
        let mut light = MeshLight {
            positions: mesh.positions.clone(),
            triangle_normals,
            normals,
            indices: mesh.indices.clone(),
            tri_dist: Distribution1D::new(&areas),
            area,
            radiance,
            uvs,
            rectangle,
        };
        if light.radiance.is_patterned() {
            light.radiance = light.radiance.clone().with_pattern_mean(|u| {
                let s = light.sample_position(u);
                (s.p, s.emitting_normal())
            });
        }
        Some(light)
    }

    /// True when the light is one flat rectangle (sampled by solid angle where it is near).
    #[must_use]
    pub fn is_rectangle(&self) -> bool {
        self.rectangle.is_some()
    }

    /// Emitted radiance on the front side.
    #[must_use]
    pub fn radiance(&self) -> &EmittedRadiance {
        &self.radiance
    }

    /// Total surface area.
    #[must_use]
    pub fn area(&self) -> f32 {
        self.area
    }

    /// Unit geometric normal of triangle `prim`, if it exists.
    #[inline]
    fn geometric_normal(&self, prim: u32) -> Option<Vec3> {
        self.triangle_normals
            .get(prim as usize)
            .copied()
            .filter(|n| *n != Vec3::ZERO)
    }

    /// A point uniformly distributed by area over the mesh (density `1 / area()`): on a
    /// rectangle directly, else a triangle chosen by area and a point in it.
    #[inline(always)]
    #[must_use]
    pub fn sample_position(&self, u: Vec2) -> SurfacePoint {
        // The rectangle's few operations inline, so that the point stays in registers (returned
        // through memory it stalled its caller on store forwarding); triangles apart.
        match &self.rectangle {
            // Its triangles are wound alike and its vertex normals (if any) lie along n.
            Some((rect, n)) => SurfacePoint {
                p: rect.point(u),
                ng: *n,
                ns: *n,
                uv: Vec2::ZERO,
            },
            None => self.sample_triangle_position(u),
        }
    }

    /// [`Self::sample_position`] on a mesh of triangles: one chosen by area, a point in it.
    fn sample_triangle_position(&self, u: Vec2) -> SurfacePoint {
        let (tri, _, ux) = self.tri_dist.sample(u.x);
        let b = square_to_uniform_triangle(Vec2::new(ux, u.y));
        let [i0, i1, i2] = self.indices[tri].map(|i| i as usize);
        let (p0, p1, p2) = (self.positions[i0], self.positions[i1], self.positions[i2]);
        let b0 = 1.0 - b.x - b.y;
        // Same barycentric convention as Embree's hit (u, v) = (b1, b2).
        let p = b0 * p0 + b.x * p1 + b.y * p2;
        let ng = self.geometric_normal(tri as u32).unwrap_or(Vec3::Z);
        let ns = match &self.normals {
            Some(n) => (b0 * n[i0] + b.x * n[i1] + b.y * n[i2]).normalize_or(ng),
            None => ng,
        };
        let uv = match (&self.uvs, self.radiance.reads_uv()) {
            (_, false) => Vec2::ZERO,
            (Some(t), true) => b0 * t[i0] + b.x * t[i1] + b.y * t[i2],
            (None, true) => b,
        };
        SurfacePoint { p, ng, ns, uv }
    }

    /// A photon start: a point uniform by area, a cosine-distributed direction about the
    /// geometric normal turned to the emitting side; `(point, that normal, direction, flux
    /// weight π L A)`, `None` where a bent shading normal leaves the direction unlit.
    #[must_use]
    pub fn sample_emission(&self, u_pos: Vec2, u_dir: Vec2) -> Option<(Vec3, Vec3, Vec3, Rgb)> {
        let s = self.sample_position(u_pos);
        let n = s.emitting_normal();
        let d = Frame::from_z(n).from_local(square_to_cosine_hemisphere(u_dir));
        (d.dot(s.ns) > 0.0).then(|| {
            let l = self.radiance.seen(s.uv, s.p, n, d, f32::INFINITY);
            (s.p, n, d, l * (PI * self.area))
        })
    }

    /// Samples a direction from `p_ref` towards the mesh: `(wi, distance, radiance, solid-angle
    /// pdf, geometric normal at the point)`,
    /// or `None` when the sampled point does not emit towards `p_ref` (back side) or the density is
    /// degenerate (reference point in the emitter's plane).
    #[inline]
    #[must_use]
    pub fn sample(&self, p_ref: Vec3, u: Vec2) -> Option<(Vec3, f32, Rgb, f32, Vec3)> {
        self.sample_seen(p_ref, u, self.rectangle_seen_from(p_ref))
    }

    /// How `p_ref` samples the light when it is one rectangle ([`Rectangle::seen_from`]; `None`
    /// for other meshes, sampled by area): what several light samples from one point share
    /// ([`Self::sample_seen`]).
    #[inline(always)]
    #[must_use]
    pub fn rectangle_seen_from(&self, p_ref: Vec3) -> Option<Seen> {
        let (rect, n) = self.rectangle.as_ref()?;
        // Behind the emitting side nothing arrives, however it is sampled: by area, cheapest.
        Some(if n.dot(p_ref - rect.point(Vec2::ZERO)) > 0.0 {
            rect.seen_from(p_ref)
        } else {
            Seen::Area
        })
    }

    /// [`Self::sample`] with `seen`, [`Self::rectangle_seen_from`] at the same `p_ref`, given.
    #[inline]
    #[must_use]
    pub fn sample_seen(
        &self,
        p_ref: Vec3,
        u: Vec2,
        seen: Option<Seen>,
    ) -> Option<(Vec3, f32, Rgb, f32, Vec3)> {
        if let (Some(seen), Some((rect, n))) = (seen, &self.rectangle) {
            let n = *n;
            let pdf = seen.solid_angle_pdf();
            match seen {
                Seen::Spherical(sph) => {
                    let d = sph.sample(p_ref, u) - p_ref;
                    let dist = d.length();
                    let wi = d / dist;
                    if !is_positive_finite(dist) || n.dot(-wi) <= 0.0 {
                        return None;
                    }
                    let l = self.radiance.seen(Vec2::ZERO, p_ref + d, n, -wi, dist);
                    return Some((wi, dist, l, pdf?, n));
                }
                Seen::Nearly(axis) => {
                    let wi = Frame::from_z(axis).from_local(square_to_uniform_hemisphere(u));
                    let dist = rect.hit(p_ref, wi)?;
                    if n.dot(-wi) <= 0.0 {
                        return None;
                    }
                    let l = self
                        .radiance
                        .seen(Vec2::ZERO, p_ref + wi * dist, n, -wi, dist);
                    return Some((wi, dist, l, pdf?, n));
                }
                Seen::Area => {}
            }
        }
        let sp = self.sample_position(u);
        let d = sp.p - p_ref;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        if !is_positive_finite(dist) {
            return None;
        }
        let wi = d / dist;
        // One-sided emission along the shading normal: the light leaves towards -wi.
        if sp.ns.dot(-wi) <= 0.0 {
            return None;
        }
        let pdf = solid_angle_pdf(1.0 / self.area, dist2, sp.ng.dot(wi));
        if !is_positive_finite(pdf) {
            return None;
        }
        let l = self
            .radiance
            .seen(sp.uv, sp.p, sp.emitting_normal(), -wi, dist);
        Some((wi, dist, l, pdf, sp.ng))
    }

    /// Solid-angle density (without light selection) with which [`MeshLight::sample`] from `p_ref`
    /// produces `p_light` on triangle `prim`; `n_fallback` is used only if `prim` is out of range.
    #[inline]
    #[must_use]
    pub fn pdf(&self, prim: u32, p_ref: Vec3, p_light: Vec3, n_fallback: Vec3) -> f32 {
        if let Some(pdf) = self
            .rectangle_seen_from(p_ref)
            .and_then(|seen| seen.solid_angle_pdf())
        {
            return pdf;
        }
        let ng = self.geometric_normal(prim).unwrap_or(n_fallback);
        let d = p_light - p_ref;
        let dist2 = d.length_squared();
        if !is_positive_finite(dist2) {
            return 0.0;
        }
        let pdf = solid_angle_pdf(1.0 / self.area, dist2, ng.dot(d / dist2.sqrt()));
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }
}
