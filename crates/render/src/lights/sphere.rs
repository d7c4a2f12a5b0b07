//! Area lights on analytic spheres (Mitsuba 3's `area` emitter on a `sphere` shape).
//!
//! The emitting side follows the shading normal: outward, or inward with `flip_normals` (a sphere
//! lighting its interior). Sampling follows Mitsuba 3's `Sphere::sample_direction`:
//!
//! - reference point **outside** (`|p − c| > r`): a direction uniform in the cone subtended by the
//!   sphere, `cos θ_max = √(1 − r²/d_c²)`, density `1 / (2π (1 − cos θ_max))` (PBRT 3rd ed.
//!   §14.2.2). `1 − cos θ_max` is evaluated as `sin²θ_max / (1 + cos θ_max)` so that small, distant
//!   spheres keep their precision. The point on the sphere is the first intersection of the
//!   sampled ray, `t = d_c cos θ − √(r² − d_c² sin²θ)`.
//! - reference point **inside**: a point uniform by area (density `1/(4πr²)`), converted to solid
//!   angle with `d² / |cos θ_light|`.
//!
//! A textured emitter emits the texture at each point's uv (Mitsuba's parametrisation in the
//! sphere's frame, [`crate::scene::sphere_uv`]); the sampling stays the same and the sample
//! carries the radiance at its point.

use super::EmittedRadiance;
use super::{is_positive_finite, solid_angle_pdf};
use ircache_math::sampling::{sin_cos_turn, square_to_cosine_hemisphere, square_to_uniform_sphere};
use ircache_math::{Frame, Mat3, Rgb, Vec2, Vec3, PI};

/// An emitting sphere.
#[derive(Clone, Debug)]
pub struct SphereLight {
    center: Vec3,
    radius: f32,
    flip_normals: bool,
    /// The radiance.
    radiance: EmittedRadiance,
    /// World to object rotation, for the uv of a textured radiance.
    to_object: Mat3,
}

impl SphereLight {
    /// `(centre, radius)`.
    #[must_use]
    pub fn sphere(&self) -> (Vec3, f32) {
        (self.center, self.radius)
    }

    /// A sphere light emitting `radiance` (a texture's uv measured in the frame `to_object`
    /// turns world directions into); `None` for a non-positive or non-finite radius.
    #[must_use]
    pub fn new(
        center: Vec3,
        radius: f32,
        flip_normals: bool,
        radiance: EmittedRadiance,
        to_object: Mat3,
    ) -> Option<SphereLight> {
        if !(radius > 0.0 && radius.is_finite()) {
            return None;
        }
        let mut light = SphereLight {
            center,
            radius,
            flip_normals,
            radiance,
            to_object,
        };
        if light.radiance.is_patterned() {
            light.radiance = light
                .radiance
                .clone()
                .with_pattern_mean(|u| light.sample_position(u));
        }
        Some(light)
    }

    /// Emitted radiance on the emitting side.
    #[must_use]
    pub fn radiance(&self) -> &EmittedRadiance {
        &self.radiance
    }

    /// Emitted radiance at the point whose outward unit normal is `outward`, leaving along the
    /// unit `wo` towards a viewer `distance` away.
    #[inline]
    pub(crate) fn radiance_seen(&self, outward: Vec3, wo: Vec3, distance: f32) -> Rgb {
        let uv = if self.radiance.is_textured() {
            crate::scene::sphere_uv(self.to_object * outward)
        } else {
            Vec2::ZERO
        };
        if self.radiance.is_patterned() {
            let p = self.center + outward * self.radius;
            self.radiance
                .seen(uv, p, self.shading_normal(outward), wo, distance)
        } else {
            self.radiance.at(uv)
        }
    }

    /// A photon start: a point uniform by area, a cosine-distributed direction about the
    /// emitting side's normal; `(point, normal, direction, flux weight π L A)`.
    #[must_use]
    pub fn sample_emission(&self, u_pos: Vec2, u_dir: Vec2) -> (Vec3, Vec3, Vec3, Rgb) {
        let (p, n) = self.sample_position(u_pos);
        let d = Frame::from_z(n).from_local(square_to_cosine_hemisphere(u_dir));
        let outward = (p - self.center) / self.radius;
        (
            p,
            n,
            d,
            self.radiance_seen(outward, d, f32::INFINITY) * (PI * self.area()),
        )
    }

    /// A point uniform by area (density `1 / area()`) with the normal of the emitting side.
    #[must_use]
    pub fn sample_position(&self, u: Vec2) -> (Vec3, Vec3) {
        let outward = square_to_uniform_sphere(u);
        (
            self.center + outward * self.radius,
            self.shading_normal(outward),
        )
    }

    /// Surface area.
    #[must_use]
    pub fn area(&self) -> f32 {
        4.0 * PI * self.radius * self.radius
    }

    /// `(sin²θ_max, 1 − cos θ_max)` of the cone subtended from a point at squared distance
    /// `dc2 > r²` from the centre.
    #[inline]
    fn cone(&self, dc2: f32) -> (f32, f32) {
        let sin2_max = (self.radius * self.radius / dc2).min(1.0);
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        (sin2_max, sin2_max / (1.0 + cos_max))
    }

    #[inline]
    fn is_outside(&self, dc2: f32) -> bool {
        // A reference point on the sphere itself (a hit on it, up to rounding) counts as being on
        // the emitting side: inside for an inward-facing sphere. The tolerance is relative.
        let r2 = self.radius * self.radius;
        if self.flip_normals {
            dc2 > r2 * (1.0 + 1e-4)
        } else {
            dc2 > r2
        }
    }

    /// The shading normal (emitting side) at the point with outward unit normal `outward`.
    #[inline]
    fn shading_normal(&self, outward: Vec3) -> Vec3 {
        if self.flip_normals {
            -outward
        } else {
            outward
        }
    }

    /// Samples a direction from `p_ref` towards the sphere: `(wi, distance, radiance, solid-angle
    /// pdf, outward normal at the point)`, or `None` when the sampled point does not emit towards `p_ref`.
    #[inline]
    #[must_use]
    pub fn sample(&self, p_ref: Vec3, u: Vec2) -> Option<(Vec3, f32, Rgb, f32, Vec3)> {
        let to_c = self.center - p_ref;
        let dc2 = to_c.length_squared();
        let (wi, dist, outward, pdf) = if self.is_outside(dc2) {
            let dc = dc2.sqrt();
            let (sin2_max, one_minus_cos_max) = self.cone(dc2);
            // Uniform in the cone: 1 − cos θ = u·(1 − cos θ_max).
            let omc = u.x * one_minus_cos_max;
            let cos_t = 1.0 - omc;
            let sin2_t = (omc * (2.0 - omc)).min(sin2_max);
            let sin_t = sin2_t.sqrt();
            let (sin, cos) = sin_cos_turn(u.y);
            let frame = Frame::from_z(to_c / dc);
            let wi = frame
                .from_local(Vec3::new(sin_t * cos, sin_t * sin, cos_t))
                .normalize();
            let t = dc * cos_t - (self.radius * self.radius - dc2 * sin2_t).max(0.0).sqrt();
            let p_light = p_ref + wi * t;
            let outward = (p_light - self.center).normalize_or(-wi);
            (wi, t, outward, 1.0 / (2.0 * PI * one_minus_cos_max))
        } else {
            let outward = square_to_uniform_sphere(u);
            let p_light = self.center + outward * self.radius;
            let d = p_light - p_ref;
            let dist2 = d.length_squared();
            let dist = dist2.sqrt();
            if !is_positive_finite(dist) {
                return None;
            }
            let wi = d / dist;
            let pdf = solid_angle_pdf(
                1.0 / (4.0 * PI * self.radius * self.radius),
                dist2,
                outward.dot(wi),
            );
            (wi, dist, outward, pdf)
        };
        if self.shading_normal(outward).dot(-wi) <= 0.0 || !is_positive_finite(pdf) {
            return None;
        }
        Some((
            wi,
            dist,
            self.radiance_seen(outward, -wi, dist),
            pdf,
            outward,
        ))
    }

    /// Solid-angle density (without light selection) with which [`SphereLight::sample`] from
    /// `p_ref` produces the point `p_light` on the sphere.
    #[inline]
    #[must_use]
    pub fn pdf(&self, p_ref: Vec3, p_light: Vec3) -> f32 {
        let dc2 = (self.center - p_ref).length_squared();
        let pdf = if self.is_outside(dc2) {
            1.0 / (2.0 * PI * self.cone(dc2).1)
        } else {
            let d = p_light - p_ref;
            let dist2 = d.length_squared();
            if !is_positive_finite(dist2) {
                return 0.0;
            }
            let outward = (p_light - self.center).normalize_or(Vec3::Z);
            solid_angle_pdf(
                1.0 / (4.0 * PI * self.radius * self.radius),
                dist2,
                outward.dot(d / dist2.sqrt()),
            )
        };
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }
}
