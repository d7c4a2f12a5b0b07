//! Equiangular sampling of point and spot lights along rays through media (Kulla and Fajardo
//! 2012, §4 and §5), the single scattering's distance drawn towards the light instead of by
//! the medium's free flight, weighed against free-flight sampling by the power heuristic.
//!
//! Free-flight sampling puts a scattering vertex anywhere along the ray; its light sample
//! carries the light's I/r², which a vertex drawn close to a point light makes arbitrarily
//! large (near a lamp in fog, `volpath`'s fireflies and the march's spikes). Equiangular
//! sampling draws the distance uniformly in the angle the light subtends, which cancels the
//! 1/r², so a ray that passes close to the light is sampled where its light is. The two are
//! combined by multiple importance sampling over (light, distance) pairs:
//!
//! - the distance strategy: the first scattering at t of free-flight sampling (`volpath`:
//!   density r e^{−r (t − t₀)} with r the rate of real scatterings; the march: its quadrature's
//!   n points) with the light chosen at x(t) by the light set's selection;
//! - the equiangular strategy: the light chosen by the selection at the segment's middle, then
//!   t from [`Equiangular`] towards it, on the part of the segment a spot's cone covers (only
//!   point and spot lights; for other lights the distance strategy alone).
//!
//! In media with constant coefficients (fog) the free flight's density is a closed form; in
//! grids the weights take a homogeneous medium's at the grid's majorant in its place, which
//! keeps them a partition of unity (so the sum stays unbiased, if less well weighed), and the
//! equiangular sample's transmittance back to the segment's start is ratio tracked.

use super::RayCounts;
use crate::lights::{is_positive_finite, LightSample};
use crate::media::tracking::{transmittance, transmittance_along};
use crate::media::Coefficients;
use crate::scene::Scene;
use ircache_math::sampling::Equiangular;
use ircache_math::{Ray, Rgb, Rng, Vec3};

/// How the distance strategy of a segment draws its distances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum DistanceDensity {
    /// Free-flight sampling's first real scattering, at rate r per unit length.
    Flight { rate: f32 },
    /// `count` points stratified by the transmittance under the mean extinction `mean`, whose
    /// probabilities sum to `mass` over the segment (the march's quadrature).
    Quadrature { count: u32, mean: f32, mass: f32 },
}

/// A segment of a ray through a medium, with what both strategies' densities need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Segment {
    /// The ray's origin and unit direction.
    pub o: Vec3,
    pub d: Vec3,
    /// The segment, `t1` possibly infinite.
    pub t0: f32,
    pub t1: f32,
    /// The medium.
    pub medium: usize,
    /// Its extinction and scattering coefficients where they are constant (closed-form
    /// transmittance); `None` in a grid (ratio tracking, lookups).
    pub constant: Option<(Rgb, Rgb)>,
    /// The distance strategy.
    pub distance: DistanceDensity,
    /// Equiangular samples taken on the segment.
    pub samples: u32,
    /// Where the scene has one point or spot light: its index and [`Self::towards`] it, made
    /// once (the march asks for it at each of its points).
    single: Option<(u32, Option<(Equiangular, f32)>)>,
}

impl Segment {
    /// The segment of `ray` up to `t_hit` in `medium` for free-flight sampling (`volpath`), or
    /// `None` where the medium scatters nothing or no point or spot light exists. In a grid the
    /// free flight's density has no closed form; the weights then take the density of a
    /// homogeneous medium at the grid's majorant in its place, which keeps them a partition of
    /// unity (both strategies compute the same weights), so the sum stays unbiased.
    #[must_use]
    pub fn for_flight(scene: &Scene, medium: usize, ray: &Ray, t_hit: f32) -> Option<Segment> {
        if !scene.lights.has_delta_positions() {
            return None;
        }
        let med = &scene.media[medium];
        let majorant = med.majorant;
        let coefficients = med.constant_coefficients();
        let rate = match coefficients {
            Some(c) => {
                // `sample_flight`'s choice at a tentative collision (rate: the majorant):
                // scattering with probability mean σ_s over mean σ_s + mean σ_n.
                let ps = c.sigma_s.mean();
                let pn = (Rgb::splat(majorant) - c.sigma_t).max(Rgb::ZERO).mean();
                if !is_positive_finite(ps) {
                    return None;
                }
                majorant * ps / (ps + pn)
            }
            None => majorant,
        };
        let density = DistanceDensity::Flight { rate };
        Segment::with_coefficients(scene, medium, ray, t_hit, coefficients, density, 1)
    }

    /// The segment of `ray` up to `t_hit` in `medium` whose distances are drawn with `density`
    /// (or weighed as if they were: see [`Self::for_flight`]), beside `samples` equiangular
    /// samples; `None` as [`Self::for_flight`].
    #[must_use]
    pub fn for_density(
        scene: &Scene,
        medium: usize,
        ray: &Ray,
        t_hit: f32,
        density: DistanceDensity,
        samples: u32,
    ) -> Option<Segment> {
        if !scene.lights.has_delta_positions() || samples == 0 {
            return None;
        }
        let coefficients = scene.media[medium].constant_coefficients();
        Segment::with_coefficients(scene, medium, ray, t_hit, coefficients, density, samples)
    }

    /// The segment, given the medium's constant coefficients (`None` in a grid).
    fn with_coefficients(
        scene: &Scene,
        medium: usize,
        ray: &Ray,
        t_hit: f32,
        coefficients: Option<Coefficients>,
        density: DistanceDensity,
        samples: u32,
    ) -> Option<Segment> {
        let constant = match coefficients {
            Some(c) if c.sigma_s.is_black() => return None,
            Some(c) => Some((c.sigma_t, c.sigma_s)),
            None => None,
        };
        let (t0, t1) = scene.media[medium].clip(ray.o, ray.d, t_hit)?;
        let mut segment = Segment {
            o: ray.o,
            d: ray.d,
            t0,
            t1,
            medium,
            constant,
            distance: density,
            samples,
            single: None,
        };
        segment.single = scene
            .lights
            .single_delta_position()
            .map(|light| (light, segment.towards_anew(scene, light)));
        Some(segment)
    }

    /// The density of the distance strategy at `t`.
    #[must_use]
    pub fn distance_pdf(&self, t: f32) -> f32 {
        let s = (t - self.t0).max(0.0);
        match self.distance {
            DistanceDensity::Flight { rate } => rate * (-rate * s).exp(),
            DistanceDensity::Quadrature { count, mean, mass } => {
                count as f32 * mean * (-mean * s).exp() / mass
            }
        }
    }

    /// Where the equiangular strategy selects its light.
    fn selection_point(&self) -> Vec3 {
        let span = self.t1 - self.t0;
        let t = if span.is_finite() {
            self.t0 + 0.5 * span
        } else {
            self.t0
        };
        self.o + self.d * t
    }

    /// The equiangular distribution towards `light` and the probability of selecting it there.
    fn towards(&self, scene: &Scene, light: u32) -> Option<(Equiangular, f32)> {
        match self.single {
            Some((only, towards)) if only == light => towards,
            _ => self.towards_anew(scene, light),
        }
    }

    /// [`Self::towards`], computed.
    fn towards_anew(&self, scene: &Scene, light: u32) -> Option<(Equiangular, f32)> {
        let (position, interval) =
            scene
                .lights
                .delta_position_along(light, self.o, self.d, (self.t0, self.t1))?;
        let eq = Equiangular::new(self.o, self.d, position, interval)?;
        let selection = scene
            .lights
            .selection_probability(self.selection_point(), light);
        (selection > 0.0).then_some((eq, selection))
    }

    /// The power heuristic's weight of the distance strategy's light sample `ls`, taken at
    /// distance `t` (its density: the distance's times `ls.pdf`, the selection there).
    #[must_use]
    pub fn distance_weight(&self, scene: &Scene, t: f32, ls: &LightSample) -> f32 {
        if !ls.is_delta {
            return 1.0;
        }
        let Some((eq, selection)) = self.towards(scene, ls.light) else {
            return 1.0;
        };
        let own = self.distance_pdf(t) * ls.pdf;
        super::mis_weight(own, self.samples as f32 * selection * eq.pdf(t))
    }

    /// The equiangular strategy's estimate of the single scattering along the segment, per unit
    /// of the transmittance before `t0`: a light chosen by `u_select`, a distance by `u`, the
    /// light sample's transmittance from `rng`; zero where the light chosen is not a point or
    /// spot light.
    #[must_use]
    pub fn estimate(
        &self,
        scene: &Scene,
        (u_select, u): (f32, f32),
        rng: &mut Rng,
        rays: &mut RayCounts,
    ) -> Rgb {
        let (medium, phase) = (self.medium, scene.media[self.medium].phase);
        if scene.lights.is_empty() {
            return Rgb::ZERO;
        }
        let light = scene.lights.select(self.selection_point(), u_select).0 as u32;
        let Some((eq, selection)) = self.towards(scene, light) else {
            return Rgb::ZERO;
        };
        let (t, pdf) = eq.sample(u);
        if !is_positive_finite(pdf) {
            return Rgb::ZERO;
        }
        let x = self.o + self.d * t;
        let Some(at_x) =
            scene
                .lights
                .sample_light(light as usize, 1.0, x, ircache_math::Vec2::ZERO)
        else {
            return Rgb::ZERO;
        };
        let f = phase.eval(self.d, at_x.wi);
        if !is_positive_finite(f) || at_x.radiance.is_black() {
            return Rgb::ZERO;
        }
        let own = self.samples as f32 * selection * pdf;
        let other = self.distance_pdf(t) * scene.lights.selection_probability(x, light);
        let w = super::mis_weight(own, other);
        if !is_positive_finite(w) {
            return Rgb::ZERO;
        }
        // The light reaching x and the way back to the segment's start.
        let (before, sigma_s) = match self.constant {
            Some((sigma_t, sigma_s)) => ((sigma_t * -(t - self.t0)).exp(), sigma_s),
            None => {
                let sigma_s = scene.media[medium].at(x).sigma_s;
                if sigma_s.is_black() {
                    return Rgb::ZERO;
                }
                let before = transmittance(&scene.media[medium], self.o, self.d, t, rng);
                (before, sigma_s)
            }
        };
        if before.is_black() {
            return Rgb::ZERO;
        }
        let shadow = scene.shadow_ray_at(x, None, at_x.wi, at_x.distance);
        let tr = transmittance_along(scene, shadow, Some(medium), rng, rays);
        before * sigma_s * at_x.radiance * tr * (f * w / own)
    }
}
