//! Mitsuba 3's `perspective` sensor: a pinhole camera looking along its local +z axis.
//!
//! Film coordinates run from (0, 0) at the top-left corner to (1, 1) at the bottom-right; the
//! image's x axis maps to camera −x and its y axis to camera −y, as in Mitsuba (whose `lookat`
//! makes camera +x the viewer's left).

use ircache_math::{Mat4, Ray, Vec2, Vec3};
use ircache_scene::{FovAxis, SensorDesc};

/// A pinhole camera.
#[derive(Clone, Debug)]
pub struct Camera {
    /// Camera-to-world transform.
    pub to_world: Mat4,
    /// Eye position in world space.
    pub origin: Vec3,
    /// tan of half the horizontal field of view.
    pub tan_half_x: f32,
    /// tan of half the vertical field of view.
    pub tan_half_y: f32,
    /// Near clip distance along the optical axis.
    pub near_clip: f32,
    /// Far clip distance along the optical axis.
    pub far_clip: f32,
}

impl Camera {
    /// The camera of a sensor description, for a film of `width × height` pixels.
    #[must_use]
    pub fn new(sensor: &SensorDesc, width: u32, height: u32) -> Camera {
        let (w, h) = (width as f32, height as f32);
        let t = (sensor.fov_degrees.to_radians() * 0.5).tan();
        let axis = match sensor.fov_axis {
            FovAxis::Smaller if w <= h => FovAxis::X,
            FovAxis::Smaller => FovAxis::Y,
            FovAxis::Larger if w >= h => FovAxis::X,
            FovAxis::Larger => FovAxis::Y,
            a => a,
        };
        let (tan_half_x, tan_half_y) = match axis {
            FovAxis::Y => (t * w / h, t),
            FovAxis::Diagonal => {
                let d = (w * w + h * h).sqrt();
                (t * w / d, t * h / d)
            }
            _ => (t, t * h / w),
        };
        Camera {
            to_world: sensor.to_world,
            origin: sensor.to_world.transform_point3(Vec3::ZERO),
            tan_half_x,
            tan_half_y,
            near_clip: sensor.near_clip,
            far_clip: sensor.far_clip,
        }
    }

    /// The primary ray through film position `film` (each coordinate in [0, 1], top-left origin),
    /// with a unit direction, starting at the near clip plane.
    #[must_use]
    pub fn generate_ray(&self, film: Vec2) -> Ray {
        let d_cam = Vec3::new(
            (1.0 - 2.0 * film.x) * self.tan_half_x,
            (1.0 - 2.0 * film.y) * self.tan_half_y,
            1.0,
        )
        .normalize();
        let d = self.to_world.transform_vector3(d_cam).normalize();
        let inv_z = 1.0 / d_cam.z;
        Ray {
            o: self.origin,
            d,
            t_min: self.near_clip * inv_z,
            t_max: self.far_clip * inv_z,
        }
    }

    /// Film position of a world-space point, or `None` when it lies behind the camera.
    #[must_use]
    pub fn project(&self, p: Vec3) -> Option<Vec2> {
        let q = self.to_world.inverse().transform_point3(p);
        if q.z <= 0.0 {
            return None;
        }
        Some(Vec2::new(
            0.5 * (1.0 - q.x / (q.z * self.tan_half_x)),
            0.5 * (1.0 - q.y / (q.z * self.tan_half_y)),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_scene::{FilmDesc, FilterDesc};

    fn sensor(fov: f32, axis: FovAxis, to_world: Mat4) -> SensorDesc {
        SensorDesc {
            to_world,
            fov_degrees: fov,
            fov_axis: axis,
            near_clip: 0.01,
            far_clip: 1e4,
            film: FilmDesc {
                width: 200,
                height: 100,
                filter: FilterDesc::Box,
            },
            spp: 1,
            sampler: "independent".into(),
            sampler_seed: 0,
            jitter: true,
        }
    }

    #[test]
    fn fov_axes_and_image_orientation() {
        let c = Camera::new(&sensor(90.0, FovAxis::X, Mat4::IDENTITY), 200, 100);
        assert!((c.tan_half_x - 1.0).abs() < 1e-6 && (c.tan_half_y - 0.5).abs() < 1e-6);
        // The left edge of the image looks towards camera +x (Mitsuba's convention).
        let left = c.generate_ray(Vec2::new(0.0, 0.5));
        assert!(left.d.x > 0.0 && (left.d.x - left.d.z).abs() < 1e-6);
        let top = c.generate_ray(Vec2::new(0.5, 0.0));
        assert!(top.d.y > 0.0);
        let cy = Camera::new(&sensor(90.0, FovAxis::Y, Mat4::IDENTITY), 200, 100);
        assert!((cy.tan_half_y - 1.0).abs() < 1e-6 && (cy.tan_half_x - 2.0).abs() < 1e-6);
    }

    #[test]
    fn project_inverts_generate_ray() {
        let m = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)) * Mat4::from_rotation_y(0.7);
        let c = Camera::new(&sensor(40.0, FovAxis::Y, m), 200, 100);
        let f = Vec2::new(0.3, 0.8);
        let r = c.generate_ray(f);
        let back = c.project(r.at(5.0)).unwrap();
        assert!((back - f).length() < 1e-4);
    }
}
