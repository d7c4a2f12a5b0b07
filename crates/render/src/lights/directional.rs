//! Directional (distant) lights (Mitsuba 3's `directional`): light travelling along `direction`
//! with `irradiance` on a surface perpendicular to it; a receiver with normal `n` gets
//! `E = irradiance · max(0, n · −direction)`. A delta distribution in direction, at infinite
//! distance.

use ircache_math::{Rgb, Vec3};

/// A directional light.
#[derive(Clone, Copy, Debug)]
pub struct DirectionalLight {
    /// Unit direction towards the light (−direction of travel).
    pub wi: Vec3,
    /// Irradiance on a perpendicular surface.
    pub irradiance: Rgb,
}

impl DirectionalLight {
    /// A directional light travelling along `direction` (normalised here); `None` for a zero or
    /// non-finite direction.
    #[must_use]
    pub fn new(direction: Vec3, irradiance: Rgb) -> Option<DirectionalLight> {
        let wi = -direction.try_normalize()?;
        Some(DirectionalLight { wi, irradiance })
    }
}
