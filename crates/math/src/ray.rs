//! Rays and scale-free self-intersection avoidance.
//!
//! Secondary rays start on a surface; floating-point error in the hit point would make them hit the
//! surface they leave. Instead of an absolute epsilon (which breaks for scenes in millimetres or
//! kilometres) the origin is moved off the surface by a few units in the last place of its own
//! coordinates, following Wächter and Binder, "A Fast and Robust Method for Avoiding
//! Self-Intersection" (Ray Tracing Gems, ch. 6).

use glam::Vec3;

/// A ray `o + t d` for `t` in `[t_min, t_max]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub o: Vec3,
    /// Direction (not necessarily unit length; callers document when it is).
    pub d: Vec3,
    /// Nearest accepted distance.
    pub t_min: f32,
    /// Farthest accepted distance.
    pub t_max: f32,
}

impl Ray {
    /// An unbounded ray from `o` along `d`.
    #[must_use]
    pub fn new(o: Vec3, d: Vec3) -> Ray {
        Ray {
            o,
            d,
            t_min: 0.0,
            t_max: f32::INFINITY,
        }
    }
    /// The point at distance `t`.
    #[must_use]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// Moves a surface point `p` with geometric normal `ng` off the surface, to the side that `w`
/// points to, by an offset that scales with the magnitude of `p` (integer ULP steps). Near the
/// coordinate origin, where ULPs become tiny but the rounding error of the hit point does not, the
/// offset is a fixed fraction of `scene_scale` (the largest coordinate magnitude in the scene), so the
/// method stays scale-free.
#[must_use]
pub fn offset_ray_origin(p: Vec3, ng: Vec3, w: Vec3, scene_scale: f32) -> Vec3 {
    let origin = scene_scale * (1.0 / 32.0);
    let float_scale = scene_scale * (1.0 / 65536.0);
    const INT_SCALE: f32 = 256.0;
    let n = if ng.dot(w) < 0.0 { -ng } else { ng };
    let of_i = n * INT_SCALE;
    let step = |x: f32, o: f32| -> f32 {
        let oi = o as i32;
        let bits = x.to_bits() as i32;
        f32::from_bits(bits.wrapping_add(if x < 0.0 { -oi } else { oi }) as u32)
    };
    let p_i = Vec3::new(step(p.x, of_i.x), step(p.y, of_i.y), step(p.z, of_i.z));
    Vec3::new(
        if p.x.abs() < origin {
            p.x + float_scale * n.x
        } else {
            p_i.x
        },
        if p.y.abs() < origin {
            p.y + float_scale * n.y
        } else {
            p_i.y
        },
        if p.z.abs() < origin {
            p.z + float_scale * n.z
        } else {
            p_i.z
        },
    )
}

/// Shadow-ray length factor: a shadow ray towards a point at distance `d` stops at `d × (1 − this)`
/// so that it does not hit the light's own surface. Relative, hence scale-free.
pub const SHADOW_EPSILON: f32 = 1e-4;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_to_the_requested_side_at_every_scale() {
        let n = Vec3::new(0.0, 1.0, 0.0);
        for scale in [1e-3f32, 1.0, 1e3, 1e6] {
            let p = Vec3::new(0.37, 0.51, -0.23) * scale;
            let up = offset_ray_origin(p, n, n, scale);
            let down = offset_ray_origin(p, n, -n, scale);
            assert!(up.y > p.y && down.y < p.y, "scale {scale}");
            // Relative offset is tiny: well under 1e-3 of the coordinate magnitude.
            assert!((up - p).length() < 1e-3 * p.length());
        }
    }
}
