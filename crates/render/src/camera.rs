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

impl Camera {
    /// The film rectangle `(min, max)` that holds the projection of the sphere (`centre`,
    /// `radius`), given the world-to-camera transform `to_camera` (the inverse of `to_world`,
    /// made once by the caller). Per film axis, the tangent lines from the eye to the sphere's
    /// circle in that axis's plane bound it (NOTES-001 §C.2 step 2); an axis runs over the
    /// whole film where the circle holds the eye or reaches the eye's plane. `None` when the
    /// sphere lies wholly behind the camera.
    #[must_use]
    pub fn sphere_bounds(
        &self,
        to_camera: &Mat4,
        centre: Vec3,
        radius: f32,
    ) -> Option<(Vec2, Vec2)> {
        let q = to_camera.transform_point3(centre);
        if q.z + radius <= 0.0 {
            return None;
        }
        // Range of x/z (or y/z) over the circle, as tangents of angles from the optical axis.
        let range = |c: f32, z: f32| -> Option<(f32, f32)> {
            let d = (c * c + z * z).sqrt();
            if d <= radius {
                return Some((f32::NEG_INFINITY, f32::INFINITY));
            }
            let centre = c.atan2(z);
            let half = (radius / d).asin();
            let (lo, hi) = (centre - half, centre + half);
            let quarter = std::f32::consts::FRAC_PI_2;
            if lo >= quarter || hi <= -quarter {
                return None;
            }
            let lo = if lo <= -quarter {
                f32::NEG_INFINITY
            } else {
                lo.tan()
            };
            let hi = if hi >= quarter {
                f32::INFINITY
            } else {
                hi.tan()
            };
            Some((lo, hi))
        };
        let (x_lo, x_hi) = range(q.x, q.z)?;
        let (y_lo, y_hi) = range(q.y, q.z)?;
        // Film coordinates fall as camera x and y grow (see `generate_ray`).
        let film = |t: f32, tan_half: f32| 0.5 * (1.0 - t / tan_half);
        Some((
            Vec2::new(film(x_hi, self.tan_half_x), film(y_hi, self.tan_half_y)),
            Vec2::new(film(x_lo, self.tan_half_x), film(y_lo, self.tan_half_y)),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_scene::{FilmDesc, FilterDesc};

    fn sensor(fov: f32, axis: FovAxis, to_world: Mat4) -> SensorDesc {
        SensorDesc {
            medium: None,
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

    /// The film bounds of a sphere hold the projection of every point on it that lies in front
    /// of the camera, and are tight (within 2 % of the extent) for spheres well in front (random
    /// points rarely find the extremes of one that nearly touches the eye's plane); at
    /// millimetre, metre and kilometre scales.
    #[test]
    fn sphere_bounds_hold_the_projected_sphere_tightly() {
        let mut rng = ircache_math::Rng::new(7, 0);
        for scale in [1e-3f32, 1.0, 1e3] {
            let m = Mat4::from_translation(Vec3::new(1.0, -2.0, 0.5) * scale)
                * Mat4::from_rotation_y(0.4)
                * Mat4::from_rotation_x(-0.2);
            let c = Camera::new(&sensor(50.0, FovAxis::X, m), 200, 100);
            let to_camera = c.to_world.inverse();
            for case in 0..200 {
                // Centres around and behind the eye; radii up to past the eye.
                let local = Vec3::new(
                    rng.next_f32() * 4.0 - 2.0,
                    rng.next_f32() * 4.0 - 2.0,
                    rng.next_f32() * 6.0 - 1.0,
                );
                let radius = 0.05 + rng.next_f32() * if case % 4 == 0 { 3.0 } else { 0.6 };
                let centre = c.to_world.transform_point3(local * scale);
                let bounds = c.sphere_bounds(&to_camera, centre, radius * scale);
                let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
                for _ in 0..2000 {
                    let z = rng.next_f32() * 2.0 - 1.0;
                    let phi = rng.next_f32() * std::f32::consts::TAU;
                    let s = (1.0 - z * z).max(0.0).sqrt();
                    let p = centre + Vec3::new(s * phi.cos(), s * phi.sin(), z) * (radius * scale);
                    if let Some(f) = c.project(p) {
                        let (bl, bh) = bounds.expect("a visible point on a sphere called behind");
                        let slack = 1e-4 * (1.0 + f.abs().max_element());
                        assert!(
                            f.x >= bl.x - slack
                                && f.x <= bh.x + slack
                                && f.y >= bl.y - slack
                                && f.y <= bh.y + slack,
                            "{f:?} outside {bl:?}..{bh:?}"
                        );
                        lo = lo.min(f);
                        hi = hi.max(f);
                    }
                }
                let in_front = local.z > 2.0 * radius;
                if let (true, Some((bl, bh))) = (in_front, bounds) {
                    let extent = bh - bl;
                    assert!(
                        (lo - bl).max_element() < 0.02 * extent.max_element(),
                        "{lo} {bl} {hi} {bh} scale {scale} local {local} r {radius}"
                    );
                    assert!((bh - hi).max_element() < 0.02 * extent.max_element());
                }
            }
        }
    }
}
