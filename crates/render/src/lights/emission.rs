//! Emission sampling: where light leaves each emitter and in which direction, for tracing
//! photons (001 §2.4; Jensen, *Realistic Image Synthesis Using Photon Mapping*, §5.1).
//!
//! A sample carries its flux weight `L_e cos θ / (p_A p_ω)` (or its delta-light analogue), so that
//! the mean weight over many samples is the emitter's power. [`LightSet::sample_emission`](
//! super::LightSet::sample_emission) selects an emitter in proportion to its power's luminance
//! and divides by that probability, so the mean over the set is the scene's total power.
//!
//! Per kind (`Φ` the power the mean weight converges to):
//! - surfaces (meshes, spheres): a point uniform by area, a cosine-distributed direction about
//!   the geometric normal on the emitting side; `Φ = π L A`;
//! - point lights: a uniform direction, `Φ = 4π I`;
//! - spot lights: a direction uniform in the cutoff cone, weighted by the falloff;
//!   `Φ = 2π I (1 − (sin θ_c − sin θ_b)/(θ_c − θ_b))` with Mitsuba's falloff linear in angle;
//! - distant lights (directional, constant, envmap): a direction, then a point uniform on the
//!   disc of the scene's bounding sphere perpendicular to it, started outside the sphere;
//!   `Φ = E π R²` for a directional light, `π R² ∫ L dω` for an environment.

use ircache_math::sampling::{
    square_to_disk_concentric, square_to_uniform_cone, square_to_uniform_sphere,
};
use ircache_math::{Frame, Rgb, Vec2, Vec3};

/// A photon's start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionSample {
    /// Where it leaves the emitter.
    pub origin: Vec3,
    /// Unit direction of travel.
    pub direction: Vec3,
    /// The emitter surface's geometric normal on the emitting side, for offsetting the first ray
    /// (`None` for point, spot and distant lights).
    pub normal: Option<Vec3>,
    /// Flux weight: the emitted flux this one sample stands for (before dividing by the number
    /// of photons).
    pub flux: Rgb,
    /// From a light no path can hit (point, spot or directional): its light reaches surfaces
    /// through smooth `trans` by light samples ([`crate::scene::Scene::delta_shadow_transmittance`]).
    /// Set from the light chosen, where the set picks one; each light's own sampler leaves it
    /// false.
    pub from_delta_light: bool,
}

/// Power of a spot light of intensity `intensity` with Mitsuba's falloff, linear in angle from 1
/// at `beam` to 0 at `cutoff` (radians): `2π I (1 − (sin θ_c − sin θ_b)/(θ_c − θ_b))`, which is
/// `2π I (1 − cos θ_c)` when the two are equal.
#[must_use]
pub fn spot_power(intensity: Rgb, beam: f32, cutoff: f32) -> Rgb {
    let (b, c) = (f64::from(beam), f64::from(cutoff));
    let cone = if c - b > 1e-6 {
        1.0 - (c.sin() - b.sin()) / (c - b)
    } else {
        1.0 - c.cos()
    };
    intensity * (2.0 * std::f64::consts::PI * cone) as f32
}

/// A photon from a distant light arriving along the unit direction of travel `direction`: a point
/// uniform on the disc of the bounding sphere `(center, radius)` perpendicular to it, started a
/// radius outside the sphere. Returns the origin and the disc's area (the position density's
/// inverse).
#[must_use]
pub fn distant_origin(direction: Vec3, center: Vec3, radius: f32, u: Vec2) -> (Vec3, f32) {
    let origin = point_on_disc(direction, center, radius, u) - direction * (2.0 * radius);
    (origin, std::f32::consts::PI * radius * radius)
}

/// A point uniform on the disc of `(center, radius)` across the unit direction `direction`.
fn point_on_disc(direction: Vec3, center: Vec3, radius: f32, u: Vec2) -> Vec3 {
    let d = square_to_disk_concentric(u) * radius;
    center + Frame::from_z(direction).from_local(Vec3::new(d.x, d.y, 0.0))
}

/// Spheres photons are aimed at: the bounding spheres of the surfaces with delta lobes, for
/// caustic photons (Jensen's projection maps, §5.1.6, with spheres for maps). A direction is
/// drawn uniformly in the cone of one sphere, chosen uniformly; its density is the mixture over
/// all the cones that hold it, so overlapping targets are counted right. Distant light is
/// aimed through one target's cross-section disc, with the mixture's density over the plane.
#[derive(Clone, Debug, Default)]
pub struct Targets {
    spheres: Vec<(Vec3, f32)>,
    /// Distant light starts this far behind a target (outside the scene).
    back: f32,
}

impl Targets {
    /// Targets `spheres` in a scene of bounding sphere `(center, radius)`.
    #[must_use]
    pub fn new(spheres: Vec<(Vec3, f32)>, center: Vec3, radius: f32) -> Targets {
        let back = spheres
            .iter()
            .map(|(c, r)| (*c - center).length() + r)
            .fold(0.0f32, f32::max)
            + 2.0 * radius;
        Targets { spheres, back }
    }

    /// True when there is nothing to aim at.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.spheres.is_empty()
    }

    fn pick(&self, u: f32) -> (Vec3, f32) {
        let i = ((u * self.spheres.len() as f32) as usize).min(self.spheres.len() - 1);
        self.spheres[i]
    }

    /// `(cos θ_max, 1 − cos θ_max)` of the cone of `(c, r)` from `o`; `None` from inside.
    fn cone(o: Vec3, (c, r): (Vec3, f32)) -> Option<(f32, f32)> {
        let d2 = (c - o).length_squared();
        let r2 = r * r;
        if d2 <= r2 {
            return None;
        }
        let sin2 = r2 / d2;
        let cos = (1.0 - sin2).max(0.0).sqrt();
        Some((cos, sin2 / (1.0 + cos)))
    }

    /// A direction from `o` towards one target (`u_pick` chooses it), uniform in its cone.
    #[must_use]
    pub fn sample_direction(&self, o: Vec3, u_pick: f32, u: Vec2) -> Vec3 {
        let target = self.pick(u_pick);
        match Self::cone(o, target) {
            Some((cos_max, _)) => Frame::from_z((target.0 - o).normalize())
                .from_local(square_to_uniform_cone(u, cos_max)),
            None => square_to_uniform_sphere(u),
        }
    }

    /// The density of [`Targets::sample_direction`] at the unit direction `w` from `o`.
    #[must_use]
    pub fn direction_pdf(&self, o: Vec3, w: Vec3) -> f32 {
        let mut sum = 0.0;
        for &target in &self.spheres {
            sum += match Self::cone(o, target) {
                Some((cos_max, one_minus)) => {
                    if w.dot((target.0 - o).normalize()) >= cos_max {
                        1.0 / (2.0 * std::f32::consts::PI * one_minus)
                    } else {
                        0.0
                    }
                }
                None => 1.0 / (4.0 * std::f32::consts::PI),
            };
        }
        sum / self.spheres.len() as f32
    }

    /// A start for distant light travelling along `d`: a point uniform on one target's
    /// cross-section disc, moved back outside the scene; with the mixture's density over the
    /// plane across `d` there.
    #[must_use]
    pub fn sample_disc(&self, d: Vec3, u_pick: f32, u: Vec2) -> (Vec3, f32) {
        let (c, r) = self.pick(u_pick);
        let on_disc = point_on_disc(d, c, r, u);
        let mut density = 0.0;
        for &(ci, ri) in &self.spheres {
            let to = ci - on_disc;
            let across = (to - d * to.dot(d)).length_squared();
            if across <= ri * ri * (1.0 + 1e-5) {
                density += 1.0 / (std::f32::consts::PI * ri * ri);
            }
        }
        (on_disc - d * self.back, density / self.spheres.len() as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_math::Rng;

    #[test]
    fn spot_power_integrates_the_falloff() {
        // Midpoint rule over θ of 2π I falloff(θ) sin θ.
        let (beam, cutoff) = (0.2f64, 0.9f64);
        let n = 100_000;
        let mut sum = 0.0;
        for i in 0..n {
            let t = (f64::from(i) + 0.5) / f64::from(n) * cutoff;
            let falloff = if t < beam {
                1.0
            } else {
                (cutoff - t) / (cutoff - beam)
            };
            sum += falloff * t.sin() * cutoff / f64::from(n);
        }
        let expect = 2.0 * std::f64::consts::PI * sum;
        let got = spot_power(Rgb::ONE, beam as f32, cutoff as f32).r;
        assert!(
            (f64::from(got) / expect - 1.0).abs() < 1e-5,
            "{got} {expect}"
        );
        // Equal angles: a uniform cone.
        let cone = spot_power(Rgb::ONE, 0.5, 0.5).r;
        assert!((cone - 2.0 * std::f32::consts::PI * (1.0 - 0.5f32.cos())).abs() < 1e-5);
    }

    #[test]
    fn distant_origins_cover_the_bounding_disc_from_outside() {
        let (c, r) = (Vec3::new(1.0, 2.0, 3.0), 2.0);
        let d = Vec3::new(1.0, -1.0, 0.5).normalize();
        let mut rng = Rng::new(1, 1);
        let mut far = 0.0f32;
        for _ in 0..1000 {
            let (o, area) = distant_origin(d, c, r, rng.next_2d());
            assert!((area - std::f32::consts::PI * 4.0).abs() < 1e-5);
            // Outside the sphere, behind it along the direction of travel, within the disc.
            let along = (o - c).dot(d);
            assert!((along + 2.0 * r).abs() < 1e-4);
            let off = (o - c - d * along).length();
            assert!(off <= r * (1.0 + 1e-5));
            far = far.max(off);
        }
        assert!(far > 0.95 * r);
    }
}
