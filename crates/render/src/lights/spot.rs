//! Spot lights (Mitsuba 3's `spot`): a point light at the origin of `to_world` emitting along its
//! local +z, with intensity `I · falloff(θ) / d²`.
//!
//! The falloff is Mitsuba 3's `falloff_curve` (src/emitters/spot.cpp), *linear in angle*:
//!
//! ```text
//! falloff(θ) = 1                                       if cos θ ≥ cos(beam_width)
//!            = (cutoff_angle − θ) / (cutoff_angle − beam_width)   if cos(cutoff) < cos θ < cos(beam)
//!            = 0                                       if cos θ ≤ cos(cutoff_angle)
//! ```
//!
//! with θ the angle between the emitted direction (light → receiver, in the light's local frame,
//! normalised) and +z. Angles are given in degrees in the scene description.

use super::is_positive_finite;
use ircache_math::sampling::{square_to_uniform_cone, uniform_cone_pdf};
use ircache_math::{Mat3, Mat4, Rgb, Vec2, Vec3};

/// A spot light.
#[derive(Clone, Copy, Debug)]
pub struct SpotLight {
    position: Vec3,
    /// World → light-local linear map (inverse of `to_world`'s linear part).
    world_to_local: Mat3,
    intensity: Rgb,
    cutoff: f32,
    cos_cutoff: f32,
    beam: f32,
    cos_beam: f32,
}

impl SpotLight {
    /// Position and intensity on the axis.
    #[must_use]
    pub fn position_and_intensity(&self) -> (Vec3, Rgb) {
        (self.position, self.intensity)
    }

    /// A spot light from Mitsuba's parameters (angles in degrees).
    #[must_use]
    pub fn new(
        to_world: Mat4,
        intensity: Rgb,
        cutoff_angle_deg: f32,
        beam_width_deg: f32,
    ) -> SpotLight {
        let cutoff = cutoff_angle_deg.to_radians();
        // Mitsuba asserts beam_width ≤ cutoff_angle; clamp instead.
        let beam = beam_width_deg.to_radians().min(cutoff);
        SpotLight {
            position: to_world.transform_point3(Vec3::ZERO),
            world_to_local: Mat3::from_mat4(to_world).inverse(),
            intensity,
            cutoff,
            cos_cutoff: cutoff.cos(),
            beam,
            cos_beam: beam.cos(),
        }
    }

    /// Mitsuba 3's `falloff_curve` for the light-local direction `local` (need not be unit).
    #[inline]
    #[must_use]
    pub fn falloff(&self, local: Vec3) -> f32 {
        let cos_t = local.normalize_or_zero().z;
        if cos_t <= self.cos_cutoff {
            0.0
        } else if cos_t >= self.cos_beam {
            1.0
        } else {
            ((self.cutoff - cos_t.clamp(-1.0, 1.0).acos()) / (self.cutoff - self.beam))
                .clamp(0.0, 1.0)
        }
    }

    /// The direction from `p_ref` towards the light: `(wi, distance, I·falloff/d²)`; `None` outside
    /// the cone or at the light's position.
    /// Emitted power (see [`super::emission::spot_power`]).
    #[must_use]
    pub fn power(&self) -> Rgb {
        super::emission::spot_power(self.intensity, self.beam, self.cutoff)
    }

    /// Intensity towards the unit world direction `w` (falloff included).
    #[must_use]
    pub fn intensity_towards(&self, w: Vec3) -> Rgb {
        self.intensity * self.falloff(self.world_to_local * w)
    }

    /// A photon direction uniform in the cutoff cone with its flux weight `I falloff / p_ω`.
    #[must_use]
    pub fn sample_emission(&self, u: Vec2) -> Option<(Vec3, Vec3, Rgb)> {
        let local = square_to_uniform_cone(u, self.cos_cutoff);
        let falloff = self.falloff(local);
        if falloff <= 0.0 {
            return None;
        }
        let direction = (self.world_to_local.inverse() * local).normalize();
        let weight = self.intensity * (falloff / uniform_cone_pdf(self.cos_cutoff));
        Some((self.position, direction, weight))
    }

    #[inline]
    #[must_use]
    pub fn sample(&self, p_ref: Vec3) -> Option<(Vec3, f32, Rgb)> {
        let d = self.position - p_ref;
        let dist2 = d.length_squared();
        if !is_positive_finite(dist2) {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = d / dist;
        let falloff = self.falloff(self.world_to_local * -wi);
        if falloff <= 0.0 {
            return None;
        }
        Some((wi, dist, self.intensity * (falloff / dist2)))
    }
}
