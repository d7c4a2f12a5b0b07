//! Isotropic point lights (Mitsuba 3's `point`): radiant intensity `I` (W sr⁻¹) at a position;
//! a point at distance `d` receives `I / d²` (times the cosine at the receiver), a delta
//! distribution in direction.

use super::is_positive_finite;
use ircache_math::{Rgb, Vec3};

/// A point light.
#[derive(Clone, Copy, Debug)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity.
    pub intensity: Rgb,
}

impl PointLight {
    /// The (only) direction from `p_ref`: `(wi, distance, I/d²)`; `None` at the light's position.
    #[inline]
    #[must_use]
    pub fn sample(&self, p_ref: Vec3) -> Option<(Vec3, f32, Rgb)> {
        let d = self.position - p_ref;
        let dist2 = d.length_squared();
        if !is_positive_finite(dist2) {
            return None;
        }
        let dist = dist2.sqrt();
        Some((d / dist, dist, self.intensity / dist2))
    }
}
