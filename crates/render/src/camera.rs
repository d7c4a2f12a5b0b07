//! Mitsuba 3's projective sensors (`src/sensors/perspective.cpp`, `thinlens.cpp`,
//! `orthographic.cpp`): a camera looking along its local +z axis, through a pinhole, a thin lens
//! or parallel rays.
//!
//! Film coordinates run from (0, 0) at the top-left corner to (1, 1) at the bottom-right; the
//! image's x axis maps to camera −x and its y axis to camera −y, as in Mitsuba (whose `lookat`
//! makes camera +x the viewer's left).
//!
//! What projects records onto the film (splatting, the GPU frame, [`Camera::sphere_bounds`])
//! needs a pinhole; the pre-pass and the record placement use the lens's centre.

use ircache_math::{sampling::square_to_disk_concentric, Mat4, Ray, Vec2, Vec3};
pub use ircache_scene::Projection;
use ircache_scene::{FovAxis, PanoramicMapping, SensorDesc};

/// A camera.
#[derive(Clone, Debug)]
pub struct Camera {
    /// Camera-to-world transform.
    pub to_world: Mat4,
    /// Eye position in world space (the lens's centre; for an orthographic camera the centre of
    /// the film rectangle).
    pub origin: Vec3,
    /// tan of half the horizontal field of view; for an orthographic camera, the film
    /// rectangle's half width in camera space (1).
    pub tan_half_x: f32,
    /// tan of half the vertical field of view; orthographic: the half height (1/aspect).
    pub tan_half_y: f32,
    /// Near clip distance along the optical axis.
    pub near_clip: f32,
    /// Far clip distance along the optical axis.
    pub far_clip: f32,
    /// Pinhole, thin lens or orthographic.
    pub projection: Projection,
}

/// How a pixel's footprint grows along a camera path (000 eq. 3.60): `width + angle · distance`,
/// world units. A pinhole or a thin lens spreads by an angle (the lens's blur is left out: the
/// records where the camera focuses are those it sees sharply), parallel rays keep a width.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelSpread {
    /// The footprint at the camera.
    pub width: f32,
    /// Its growth per unit of distance travelled.
    pub angle: f32,
}

impl PixelSpread {
    /// The footprint `travelled` from the camera.
    #[inline]
    #[must_use]
    pub fn at(&self, travelled: f32) -> f32 {
        self.width + self.angle * travelled
    }

    /// Whether the camera gives a footprint at all (not for the cache's own test points).
    #[must_use]
    pub fn is_known(&self) -> bool {
        self.width > 0.0 || self.angle > 0.0
    }
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
        let (tan_half_x, tan_half_y) = match (sensor.projection, axis) {
            // Mitsuba's orthographic_projection: x in [−1, 1], y in [−1/aspect, 1/aspect].
            (Projection::Orthographic, _) => (1.0, h / w),
            (_, FovAxis::Y) => (t * w / h, t),
            (_, FovAxis::Diagonal) => {
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
            projection: sensor.projection,
        }
    }

    /// True for a pinhole (what projects records onto the film needs one).
    #[must_use]
    pub fn is_pinhole(&self) -> bool {
        self.projection == Projection::Pinhole
    }

    /// True when [`Self::generate_ray_through_lens`] uses its lens sample.
    #[must_use]
    pub fn needs_lens_sample(&self) -> bool {
        matches!(self.projection, Projection::ThinLens { aperture_radius, .. } if aperture_radius > 0.0)
    }

    /// How a pixel's footprint grows along a path, for a film `width` pixels wide.
    #[must_use]
    pub fn pixel_spread(&self, width: usize) -> PixelSpread {
        let across = 2.0 * self.tan_half_x / width.max(1) as f32;
        match self.projection {
            // About the angle a pixel spans across the view.
            Projection::Panoramic { horizontal, .. } => PixelSpread {
                width: 0.0,
                angle: horizontal.to_radians() / width.max(1) as f32,
            },
            Projection::Orthographic => PixelSpread {
                width: across * self.to_world.x_axis.truncate().length(),
                angle: 0.0,
            },
            _ => PixelSpread {
                width: 0.0,
                angle: across,
            },
        }
    }

    /// The ray through film position `film` (each coordinate in [0, 1], top-left origin) and
    /// the lens's centre, with a unit direction, starting at the near clip plane.
    #[inline]
    #[must_use]
    pub fn generate_ray(&self, film: Vec2) -> Ray {
        self.generate_ray_through_lens(film, Vec2::splat(0.5))
    }

    /// The ray through film position `film` and the point of the aperture that `lens` (in
    /// [0, 1]²) maps to by the concentric disc map, as Mitsuba's thin lens; other projections
    /// ignore `lens`. Unit direction, starting at the near clip plane. Inlined: a ray returned
    /// through memory stalled the pixel loop on store forwarding.
    #[inline]
    #[must_use]
    pub fn generate_ray_through_lens(&self, film: Vec2, lens: Vec2) -> Ray {
        let x = (1.0 - 2.0 * film.x) * self.tan_half_x;
        let y = (1.0 - 2.0 * film.y) * self.tan_half_y;
        match self.projection {
            Projection::Pinhole => self.ray_from_aperture(Vec3::ZERO, Vec3::new(x, y, 1.0)),
            Projection::ThinLens {
                aperture_radius,
                focus_distance,
            } => {
                let a = aperture_radius * square_to_disk_concentric(lens);
                let aperture = Vec3::new(a.x, a.y, 0.0);
                let focus = Vec3::new(x, y, 1.0) * focus_distance;
                self.ray_from_aperture(aperture, focus - aperture)
            }
            Projection::Orthographic => {
                let near = Vec3::new(x, y, self.near_clip);
                Ray {
                    o: self.to_world.transform_point3(near),
                    d: self.to_world.transform_vector3(Vec3::Z).normalize(),
                    t_min: 0.0,
                    t_max: self.far_clip - self.near_clip,
                }
            }
            Projection::Panoramic {
                mapping,
                horizontal,
                vertical,
            } => match panoramic_direction(mapping, horizontal, vertical, film) {
                Some(d) => Ray {
                    o: self.origin,
                    d: self.to_world.transform_vector3(d).normalize(),
                    t_min: self.near_clip,
                    t_max: self.far_clip,
                },
                // Outside the fisheye's circle: a ray that meets nothing ([`Self::sees`]).
                None => Ray {
                    o: self.origin,
                    d: self.to_world.transform_vector3(Vec3::Z).normalize(),
                    t_min: 0.0,
                    t_max: 0.0,
                },
            },
        }
    }

    /// False where the film sees nothing (outside a fisheye's circle): the pixel pass gives
    /// such samples no weight.
    #[inline]
    #[must_use]
    pub fn sees(&self, film: Vec2) -> bool {
        match self.projection {
            Projection::Panoramic {
                mapping,
                horizontal,
                vertical,
            } => panoramic_direction(mapping, horizontal, vertical, film).is_some(),
            _ => true,
        }
    }

    /// The ray from camera-space point `aperture` along camera-space `towards`, clipped to the
    /// near and far planes.
    #[inline]
    fn ray_from_aperture(&self, aperture: Vec3, towards: Vec3) -> Ray {
        // `to_world` is linear here, so `towards` need not be normalised before it: the
        // direction's chain has one square root and one division, and the clip distances'
        // (1 / the unit direction's z) run beside it.
        let d = self.to_world.transform_vector3(towards).normalize();
        let inv_z = towards.length() / towards.z;
        Ray {
            o: if aperture == Vec3::ZERO {
                self.origin
            } else {
                self.to_world.transform_point3(aperture)
            },
            d,
            t_min: self.near_clip * inv_z,
            t_max: self.far_clip * inv_z,
        }
    }

    /// Film position of a world-space point seen through the lens's centre, or `None` when it
    /// lies behind the camera (behind the film rectangle's plane, orthographic).
    #[must_use]
    pub fn project(&self, p: Vec3) -> Option<Vec2> {
        let q = self.to_world.inverse().transform_point3(p);
        if let Projection::Panoramic {
            mapping,
            horizontal,
            vertical,
        } = self.projection
        {
            return panoramic_film(mapping, horizontal, vertical, q.normalize());
        }
        if q.z <= 0.0 {
            return None;
        }
        let z = match self.projection {
            Projection::Orthographic => 1.0,
            _ => q.z,
        };
        Some(Vec2::new(
            0.5 * (1.0 - q.x / (z * self.tan_half_x)),
            0.5 * (1.0 - q.y / (z * self.tan_half_y)),
        ))
    }

    /// The ray from the camera to world-space point `p` that [`Self::project`] images (from the
    /// eye for a pinhole or the lens's centre, along the axis for parallel rays), unit
    /// direction, and the distance to `p` along it.
    #[must_use]
    pub fn ray_to(&self, p: Vec3) -> (Ray, f32) {
        let from = match self.projection {
            Projection::Orthographic => {
                let q = self.to_world.inverse().transform_point3(p);
                self.to_world.transform_point3(Vec3::new(q.x, q.y, 0.0))
            }
            _ => self.origin,
        };
        let to = p - from;
        let dist = to.length();
        (Ray::new(from, to / dist), dist)
    }
}

/// The half-extents of a panoramic film in its mapping's units (`image.c`'s `setview`).
fn panoramic_extents(mapping: PanoramicMapping, horizontal: f32, vertical: f32) -> (f32, f32) {
    let half = |a: f32| (a * 0.5).to_radians();
    match mapping {
        PanoramicMapping::Hemispherical => {
            (2.0 * half(horizontal).sin(), 2.0 * half(vertical).sin())
        }
        PanoramicMapping::Angular => (horizontal / 180.0, vertical / 180.0),
        PanoramicMapping::Planispheric => (
            2.0 * half(horizontal).sin() / (1.0 + half(horizontal).cos()),
            2.0 * half(vertical).sin() / (1.0 + half(vertical).cos()),
        ),
        PanoramicMapping::Cylindrical => (horizontal.to_radians(), 2.0 * half(vertical).tan()),
    }
}

/// The camera-space unit direction (+z forward, +x the viewer's left, +y up) of film point
/// `film` in a panoramic view (`image.c`'s `viewray`), `None` outside a fisheye's circle.
fn panoramic_direction(
    mapping: PanoramicMapping,
    horizontal: f32,
    vertical: f32,
    film: Vec2,
) -> Option<Vec3> {
    let (h, v) = panoramic_extents(mapping, horizontal, vertical);
    // Radiance's image coordinates: right and up from the centre, in [−½, ½].
    let (x, y) = (film.x - 0.5, 0.5 - film.y);
    let (right, up, forward) = match mapping {
        PanoramicMapping::Hemispherical => {
            let (x, y) = (x * h, y * v);
            let z = 1.0 - x * x - y * y;
            if z < 0.0 {
                return None;
            }
            (x, y, z.sqrt())
        }
        PanoramicMapping::Angular => {
            let (x, y) = (x * h, y * v);
            let d2 = x * x + y * y;
            if d2 > 1.0 {
                return None;
            }
            let d = d2.sqrt();
            let z = (std::f32::consts::PI * d).cos();
            let s = if d <= 1e-7 {
                std::f32::consts::PI
            } else {
                (1.0 - z * z).max(0.0).sqrt() / d
            };
            (x * s, y * s, z)
        }
        PanoramicMapping::Planispheric => {
            let (x, y) = (x * h, y * v);
            let d = x * x + y * y;
            let z = (1.0 - d) / (1.0 + d);
            (x * (1.0 + z), y * (1.0 + z), z)
        }
        PanoramicMapping::Cylindrical => {
            let a = x * h;
            let d = Vec3::new(a.sin(), y * v, a.cos());
            let d = d / d.length();
            (d.x, d.y, d.z)
        }
    };
    Some(Vec3::new(-right, up, forward))
}

/// The film point of the camera-space unit direction `d` in a panoramic view (the inverse of
/// [`panoramic_direction`]); `None` where the mapping has none (behind a hemispherical view,
/// the direction straight back for an angular one).
fn panoramic_film(
    mapping: PanoramicMapping,
    horizontal: f32,
    vertical: f32,
    d: Vec3,
) -> Option<Vec2> {
    let (h, v) = panoramic_extents(mapping, horizontal, vertical);
    let (right, up, forward) = (-d.x, d.y, d.z);
    let (x, y) = match mapping {
        PanoramicMapping::Hemispherical => {
            if forward < 0.0 {
                return None;
            }
            (right / h, up / v)
        }
        PanoramicMapping::Angular => {
            let s = (right * right + up * up).sqrt();
            let d = forward.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
            if s <= 0.0 {
                if forward > 0.0 {
                    (0.0, 0.0)
                } else {
                    return None;
                }
            } else {
                (right / s * d / h, up / s * d / v)
            }
        }
        PanoramicMapping::Planispheric => {
            if forward <= -1.0 {
                return None;
            }
            (right / (1.0 + forward) / h, up / (1.0 + forward) / v)
        }
        PanoramicMapping::Cylindrical => {
            let across = (right * right + forward * forward).sqrt();
            if across <= 0.0 {
                return None;
            }
            (right.atan2(forward) / h, up / across / v)
        }
    };
    Some(Vec2::new(x + 0.5, 0.5 - y))
}

impl Camera {
    /// The film rectangle `(min, max)` that holds the projection of the sphere (`centre`,
    /// `radius`), given the world-to-camera transform `to_camera` (the inverse of `to_world`,
    /// made once by the caller). Per film axis, the tangent lines from the eye to the sphere's
    /// circle in that axis's plane bound it (NOTES-001 §C.2 step 2); an axis runs over the
    /// whole film where the circle holds the eye or reaches the eye's plane. `None` when the
    /// sphere lies wholly behind the camera. For a pinhole ([`Self::is_pinhole`]).
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
            projection: ircache_scene::Projection::Pinhole,
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

    /// A thin lens: every lens position's ray through a film position meets the others (and
    /// the pinhole's ray) on the plane in focus, starts on the aperture disc at the near clip
    /// plane, and the lens's centre gives the pinhole's ray; off the focus plane they part by
    /// the circle of confusion's size.
    #[test]
    fn thin_lens_rays_meet_on_the_focus_plane() {
        let m = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)) * Mat4::from_rotation_y(0.7);
        let (radius, focus) = (0.2, 4.0);
        let mut desc = sensor(40.0, FovAxis::Y, m);
        let pinhole = Camera::new(&desc, 200, 100);
        desc.projection = Projection::ThinLens {
            aperture_radius: radius,
            focus_distance: focus,
        };
        let c = Camera::new(&desc, 200, 100);
        assert!(c.needs_lens_sample() && !c.is_pinhole());
        let f = Vec2::new(0.3, 0.8);
        let centre = c.generate_ray(f);
        let p = pinhole.generate_ray(f);
        assert!((centre.d - p.d).length() < 1e-6 && (centre.o - p.o).length() < 1e-6);
        let to_camera = m.inverse();
        // The pinhole ray's point at depth `focus` (camera z).
        let depth_t = |r: &Ray, z: f32| {
            let (o, d) = (
                to_camera.transform_point3(r.o),
                to_camera.transform_vector3(r.d),
            );
            r.at((z - o.z) / d.z)
        };
        let in_focus = depth_t(&p, focus);
        let mut rng = ircache_math::Rng::new(3, 0);
        let mut spread_far: f32 = 0.0;
        for _ in 0..64 {
            let r = c.generate_ray_through_lens(f, Vec2::new(rng.next_f32(), rng.next_f32()));
            assert!((r.d.length() - 1.0).abs() < 1e-5);
            let start = to_camera.transform_point3(r.at(r.t_min));
            assert!((start.z - c.near_clip).abs() < 1e-5);
            let lens = to_camera.transform_point3(r.o);
            assert!(lens.z.abs() < 1e-5 && lens.truncate().length() <= radius * (1.0 + 1e-5));
            assert!((depth_t(&r, focus) - in_focus).length() < 1e-4);
            spread_far =
                spread_far.max((depth_t(&r, 2.0 * focus) - depth_t(&p, 2.0 * focus)).length());
        }
        // At twice the focus distance the rays spread over the aperture's size (radius · 1).
        assert!(
            spread_far > 0.5 * radius && spread_far <= radius * 1.001,
            "{spread_far}"
        );
    }

    /// Orthographic: parallel rays along the optical axis from the film rectangle [−1, 1] ×
    /// [−1/aspect, 1/aspect] scaled by `to_world`, which `project` inverts; the pixel's
    /// footprint is its width, the same at any distance.
    #[test]
    fn orthographic_rays_are_parallel_from_the_film_rectangle() {
        let m = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
            * Mat4::from_rotation_y(0.7)
            * Mat4::from_scale(Vec3::new(3.0, 3.0, 1.0));
        let mut desc = sensor(40.0, FovAxis::Y, m);
        desc.projection = Projection::Orthographic;
        let c = Camera::new(&desc, 200, 100);
        let axis = m.transform_vector3(Vec3::Z).normalize();
        let corner = c.generate_ray(Vec2::ZERO);
        let opposite = c.generate_ray(Vec2::ONE);
        assert!((corner.d - axis).length() < 1e-6 && (opposite.d - axis).length() < 1e-6);
        // The film spans 2 × 3 across and 1 × 3 down (aspect 2).
        let across = corner.o - opposite.o;
        assert!(
            (across.length() - (36.0f32 + 9.0).sqrt()).abs() < 1e-4,
            "{across}"
        );
        assert!(across.dot(axis).abs() < 1e-5);
        let f = Vec2::new(0.3, 0.8);
        let r = c.generate_ray(f);
        for t in [0.5, 7.0] {
            assert!((c.project(r.at(t)).unwrap() - f).length() < 1e-5);
            let (back, dist) = c.ray_to(r.at(t));
            assert!((back.d - axis).length() < 1e-5 && dist > t);
        }
        let spread = c.pixel_spread(200);
        assert!((spread.at(0.0) - 0.03).abs() < 1e-6 && spread.at(100.0) == spread.at(0.0));
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
