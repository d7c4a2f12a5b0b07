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

    /// ∇ln falloff at the receiver `x` (world space): zero in the fully lit core and outside the
    /// cone; in between the falloff is linear in the angle θ from the axis, so ∇ln f =
    /// −∇θ/(cutoff − θ), with ∇cos θ = Mᵀ(ẑ/|u| − u_z u/|u|³) for u = M (x − position).
    #[must_use]
    pub fn falloff_log_gradient(&self, x: Vec3) -> Vec3 {
        let u = self.world_to_local * (x - self.position);
        let length = u.length();
        if !is_positive_finite(length) {
            return Vec3::ZERO;
        }
        let cos_t = u.z / length;
        if cos_t <= self.cos_cutoff || cos_t >= self.cos_beam {
            return Vec3::ZERO;
        }
        let theta = cos_t.clamp(-1.0, 1.0).acos();
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        if !is_positive_finite(self.cutoff - theta) || !is_positive_finite(sin_t) {
            return Vec3::ZERO;
        }
        let d_cos =
            self.world_to_local.transpose() * (Vec3::Z / length - u * (u.z / length.powi(3)));
        // ∇θ = −∇cos θ / sin θ.
        d_cos / (sin_t * (self.cutoff - theta))
    }

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

    /// The part of `[t0, t1]` along `o + t d` inside the cutoff cone (where the light reaches),
    /// a single interval for cutoffs below 90° (the cone is convex); the whole of it for wider
    /// cones; `None` where the ray misses the cone.
    #[must_use]
    pub fn cone_interval(&self, o: Vec3, d: Vec3, (t0, t1): (f32, f32)) -> Option<(f32, f32)> {
        if self.cos_cutoff <= 0.0 {
            return Some((t0, t1));
        }
        // In the light's frame (an affine map keeps t): v + t w inside when v_z + t w_z ≥ 0 and
        // (v_z + t w_z)² ≥ cos²α |v + t w|².
        let v = self.world_to_local * (o - self.position);
        let w = self.world_to_local * d;
        let c2 = self.cos_cutoff * self.cos_cutoff;
        let (v, w) = (v.as_dvec3(), w.as_dvec3());
        let c2 = f64::from(c2);
        let a = w.z * w.z - c2 * w.length_squared();
        let b = 2.0 * (w.z * v.z - c2 * w.dot(v));
        let c = v.z * v.z - c2 * v.length_squared();
        // {f ≥ 0} (f = a t² + b t + c) is the double cone: for a < 0 the piece between the roots,
        // for a > 0 the two pieces outside them (one in each nappe), for a = 0 a half-line.
        // The lit nappe is where also v_z + t w_z ≥ 0; it is convex, so what it keeps of
        // [t0, t1] is one interval.
        let (lo, hi) = (f64::from(t0), f64::from(t1));
        let (z_lo, z_hi) = if w.z > 0.0 {
            (-v.z / w.z, f64::INFINITY)
        } else if w.z < 0.0 {
            (f64::NEG_INFINITY, -v.z / w.z)
        } else if v.z >= 0.0 {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            return None;
        };
        let clip = |(p, q): (f64, f64)| {
            let (p, q) = (p.max(lo).max(z_lo), q.min(hi).min(z_hi));
            (q > p).then_some((p, q))
        };
        let disc = b * b - 4.0 * a * c;
        let found = if a == 0.0 {
            if b > 0.0 {
                clip((-c / b, f64::INFINITY))
            } else if b < 0.0 {
                clip((f64::NEG_INFINITY, -c / b))
            } else if c >= 0.0 {
                clip((f64::NEG_INFINITY, f64::INFINITY))
            } else {
                None
            }
        } else if disc < 0.0 {
            // No root: the whole line lies inside (a > 0) or outside (a < 0).
            (a > 0.0)
                .then(|| clip((f64::NEG_INFINITY, f64::INFINITY)))
                .flatten()
        } else {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            let (r1, r2) = {
                let x = q / a;
                let y = if q != 0.0 { c / q } else { x };
                (x.min(y), x.max(y))
            };
            if a < 0.0 {
                clip((r1, r2))
            } else {
                // One piece lies in each nappe; the z half-line keeps the lit one's (of the
                // other, at most a rounding's sliver at the apex).
                let length = |i: &Option<(f64, f64)>| i.map_or(-1.0, |(p, q)| q - p);
                let (before, after) = (clip((f64::NEG_INFINITY, r1)), clip((r2, f64::INFINITY)));
                if length(&before) >= length(&after) {
                    before
                } else {
                    after
                }
            }
        };
        found.map(|(a, b)| (a as f32, b as f32))
    }

    /// The direction from `p_ref` towards the light: `(wi, distance, I·falloff/d²)`; `None` outside
    /// the cone or at the light's position.
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

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_math::Rng;

    /// Along random rays, a distance lies in `cone_interval` exactly where the light reaches it
    /// (falloff above zero), to a hair at the interval's ends, for narrow cones and a light
    /// frame that scales its axes unevenly, and from near the apex, where the line meets both
    /// nappes; past 90° the interval holds every lit distance.
    #[test]
    fn cone_interval_is_where_the_light_reaches() {
        let mut rng = Rng::new(17, 3);
        for (cutoff, beam, to_world) in [
            (
                20.0,
                15.0,
                Mat4::from_translation(Vec3::new(0.3, 1.0, -0.2)),
            ),
            (
                60.0,
                10.0,
                Mat4::from_translation(Vec3::new(-1.0, 0.5, 2.0))
                    * Mat4::from_rotation_x(0.7)
                    * Mat4::from_scale(Vec3::new(1.0, 2.0, 0.5)),
            ),
            (89.0, 30.0, Mat4::from_rotation_y(2.0)),
            (120.0, 30.0, Mat4::IDENTITY),
        ] {
            let light = SpotLight::new(to_world, Rgb::ONE, cutoff, beam);
            let mut hits = 0;
            let apex = to_world.transform_point3(Vec3::ZERO);
            for ray in 0..3000 {
                // A third of the rays start near the apex (both nappes, the roots close).
                let near = if ray % 3 == 0 { 0.05 } else { 3.0 };
                let o = (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0)
                    * near
                    + if near < 1.0 { apex } else { Vec3::ZERO };
                let d =
                    (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5).normalize();
                let (t0, t1) = if near < 1.0 {
                    (-1.0f32, 1.0f32)
                } else {
                    (0.1, 8.0)
                };
                let interval = light.cone_interval(o, d, (t0, t1));
                for k in 0..400 {
                    let t = t0 + (t1 - t0) * (k as f32 + 0.5) / 400.0;
                    let lit = light.sample(o + d * t).is_some();
                    let within = interval.is_some_and(|(a, b)| t >= a && t <= b);
                    // Past 90° the whole segment is kept (it need only hold the lit part).
                    if lit != within && (lit || cutoff < 90.0) {
                        let (a, b) = interval.unwrap_or((f32::NAN, f32::NAN));
                        let margin = 1e-3 * (1.0 + t.abs());
                        assert!(
                            (t - a).abs() < margin || (t - b).abs() < margin,
                            "cutoff {cutoff}: t {t} lit {lit}, interval {interval:?}"
                        );
                    }
                    hits += usize::from(lit);
                }
            }
            assert!(
                hits > 1000,
                "cutoff {cutoff}: too few rays through the cone ({hits})"
            );
        }
    }
}
