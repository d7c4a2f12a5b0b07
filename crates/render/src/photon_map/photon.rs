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

/// A unit vector in three signed 16-bit components (each within 2⁻¹⁵ of the original): a
/// photon's directions as its kd-tree node keeps them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PackedUnit([i16; 3]);

impl PackedUnit {
    const SCALE: f32 = i16::MAX as f32;

    /// Packs `v` (components in [−1, 1]).
    #[inline]
    #[must_use]
    pub fn new(v: Vec3) -> Self {
        let q = |c: f32| (c.clamp(-1.0, 1.0) * Self::SCALE).round() as i16;
        PackedUnit([q(v.x), q(v.y), q(v.z)])
    }

    /// Its dot product with `v`.
    #[inline]
    #[must_use]
    pub fn dot(self, v: Vec3) -> f32 {
        let [x, y, z] = self.0;
        (f32::from(x) * v.x + f32::from(y) * v.y + f32::from(z) * v.z) / Self::SCALE
    }
}

/// What photon queries filter on (see `kd_tree`): the normal, the incoming direction, the
/// bounce count and whether it is a caustic photon, in 16 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PhotonTag {
    /// [`Photon::normal`].
    pub normal: PackedUnit,
    /// [`Photon::incoming`].
    pub incoming: PackedUnit,
    bounces: u16,
    caustic: bool,
}

impl PhotonTag {
    /// The tag of `photon`.
    #[inline]
    #[must_use]
    pub fn of(photon: &Photon) -> Self {
        PhotonTag {
            normal: PackedUnit::new(photon.normal),
            incoming: PackedUnit::new(photon.incoming),
            bounces: photon.bounces,
            caustic: photon.caustic,
        }
    }

    /// [`Photon::bounces`].
    #[inline]
    #[must_use]
    pub fn bounces(&self) -> u16 {
        self.bounces
    }

    /// [`Photon::caustic`].
    #[inline]
    #[must_use]
    pub fn caustic(&self) -> bool {
        self.caustic
    }
}
