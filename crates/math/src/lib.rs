//! Math shared by every ircache crate: vectors (re-exported from `glam`), RGB colours, orthonormal
//! frames, rays with scale-free origin offsets, sampling routines and a deterministic random number
//! generator.
//!
//! Conventions: single precision (`f32`) as in Embree; directions in a [`Frame`]'s local space have
//! the normal along +z, so `cos θ = w.z`. Every sampling routine in [`sampling`] comes as a triple
//! (sample, pdf, inverse) so round trips can be tested.

pub mod frame;
pub mod harmonics;
pub mod ray;
pub mod rgb;
pub mod rng;
pub mod sampling;

pub use frame::Frame;
pub use glam::{DMat3, DMat4, DVec3, DVec4, Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
pub use ray::{offset_ray_origin, Ray};
pub use rgb::Rgb;
pub use rng::Rng;

/// π as `f32`.
pub const PI: f32 = std::f32::consts::PI;
/// 1/π as `f32`.
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;

/// Length of the bounding-box diagonal of a set of points: the scene scale against which
/// scale-free tolerances are set.
#[must_use]
pub fn bounds_diagonal(points: impl IntoIterator<Item = Vec3>) -> f32 {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if lo.x > hi.x {
        0.0
    } else {
        (hi - lo).length()
    }
}
