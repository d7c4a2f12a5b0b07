//! The photon (001 Fig. 6.1, with the normal and bounce count NOTES-001 E.1 adds): plain data.

use ircache_math::{Rgb, Vec3};

/// A photon stored where it met a surface with a Lambertian part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Where it landed.
    pub position: Vec3,
    /// The surface's geometric normal, turned towards the side the photon came from.
    pub normal: Vec3,
    /// Unit direction towards where it came from (−direction of travel).
    pub incoming: Vec3,
    /// The flux it carries (already divided by the number of photons emitted).
    pub flux: Rgb,
    /// Surfaces it scattered from before landing here (0: straight from the emitter).
    pub bounces: u16,
    /// Length of its last flight: from the surface (or emitter) it left to here.
    pub distance: f32,
    /// It came through delta lobes alone (a caustic photon).
    pub caustic: bool,
}

impl Photon {
    /// Its position as an array (the kd-tree's key).
    #[inline]
    #[must_use]
    pub fn key(&self) -> [f32; 3] {
        self.position.to_array()
    }
}
