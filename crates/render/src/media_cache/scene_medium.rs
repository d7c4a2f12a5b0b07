//! The renderer's scene as a [`GatherMedium`]: gather rays pass through `null` boundaries (they
//! are not occluders: only opaque hits end a cell, NOTES-002 §1.3), the medium along each ray is
//! tracked across them, surfaces are lit by direct light with transmittance, and the medium's
//! source is single scattering from the lights plus emission (stage 1, §2.8).
//!
//! Everything is deterministic for a given ray: light samples are a stratified set rotated by a
//! hash of the gather direction (so they differ between cells, and an area light is sampled all
//! over, but not between two receivers gathering along the same direction), and the ratio
//! tracking of their shadow rays draws on streams keyed by that direction and the march step,
//! so that central differences with common random numbers (§3.3) compare like with like. (One
//! fixed stream for every shadow ray put the tracking's collisions at the same distances on
//! every ray: a quadrature rule, not an estimate, and in the smoke grid it read the ceiling's
//! light 3–5 % low.)
//!
//! A march step's source ([`GatherMedium::step_source`]) takes point and spot lights at a
//! distance drawn on the step towards the light (equiangular, as the pixel pass's march and
//! `volpath` do: [`crate::integrators::equiangular`]), not at the step's middle, whose 1/r²
//! made the records that a gather ray passing near the lamp reached spikes and the rest low.
//!
//! Deeper bounces (`max_depth` above 3, [`SceneMedium::with_deeper_bounces`]) are in two parts.
//! The light they scatter along the gather ray in a medium, ∫ T σ_s L_ind dt, comes from the
//! volumetric records' light one bounce shorter (a point on a gather ray is one vertex deeper
//! than the camera ray's points they were gathered for: [`VolumeCache::in_scattered_shorter`]) at
//! [`RECORD_POINTS`] quadrature points per segment, or a phase-sampled path at a point no record
//! serves; the rest is `volpath`'s paths on from the opaque hit through the transmittance, a
//! BSDF sample first. Where a medium on the ray scatters too far forward for bands 0–2, or
//! without records, each path finds its first vertex by a free flight along the ray instead (a
//! collision in the medium or the opaque hit), then a phase or BSDF sample. The emitters these
//! samples meet directly are left out (the march's light samples hold them).
//! `--media-deeper-paths` paths per cell, on streams keyed by the cell's direction, as the light
//! samples are, their first BSDF or phase samples stratified among them ([`first_stratum`]:
//! smoke box relMSE_trim −3 %, blurred −8 % over six seeds). The records' part is the same
//! light with less noise (the fog box: relMSE_trim −13 %, blurred −17 %, BENCHMARKS.md).
//!
//! The source's gradient comes from the same light samples in closed form, each sample's point
//! on the light held and its visibility too (§2.7): the phase function's and the geometry's
//! derivatives, and the optical depth's by the pivot form through homogeneous media, boundaries
//! and grids ([`transmittance_with_depth_gradient`]), and a spot light's falloff, linear in the
//! angle from its axis; no extra shadow rays.

use super::gradient::{interface_offset, DVec3, GatherMedium, StepExtent};
use super::volume_records::VolumeCache;
use crate::integrators::light_sampling::BsdfStrategy;
use crate::integrators::media_march::{in_scattered_by_path, quadrature_points, MarchPoint};
use crate::integrators::path_continuation::{count_and_roulette, sample_continuation, Arrival};
use crate::integrators::volpath::{photon_reflected, PathState, VolPathIntegrator};
use crate::integrators::RayCounts;
use crate::lights::LightSample;
use crate::media::tracking::{
    first_opaque, medium_after, sample_flight, transmittance_along,
    transmittance_with_depth_gradient, Flight, OpaqueHit,
};
use crate::media::{CoefficientGradients, Coefficients};
use crate::photon_map::{bounce_limit, ServingMap};
use crate::scene::Scene;
use ircache_math::sampling::Equiangular;
use ircache_math::{Ray, Rgb, Rng, Vec2, Vec3};
use std::cell::RefCell;

/// The key of the deeper bounces' streams (beside the gather direction's bits).
const DEEPER_KEY: u64 = 0x6465_6570_6572;

/// The key of the jitter of [`SceneMedium::in_scattered_by_records`]'s points.
const RECORDS_KEY: u64 = 0x7265_636f_7264;

/// Quadrature points per medium segment of a gather ray at which the volumetric records serve.
const RECORD_POINTS: u32 = 4;

/// The largest |g| of a Henyey–Greenstein phase function whose in-scattered light the records'
/// bands 0–2 serve along gather rays.
const BANDS_HOLD_PHASE: f32 = 0.5;

/// The step key of light samples at a gather ray's opaque hit.
const SURFACE_STEP: u32 = u32::MAX;

/// The keys of a light sample's tracking streams: its transmittance, its optical depth.
const TRANSMITTANCE_STREAM: u64 = 0x006d_6564_6961;
const DEPTH_STREAM: u64 = 0x0064_6570_7468;
/// The key of the stream of a point or spot light sample's distance on its march step.
const DISTANCE_STREAM: u64 = 0x0065_7175_6961;
/// The key of the stream choosing a light sample's visibility shift (axis and sign).
const VISIBILITY_STREAM: u64 = 0x0076_6973_6962;

/// The shift of a light sample's visibility difference, as a fraction of its distance to the
/// light (of the scene's scale for distant lights): small beside a penumbra, and its noise
/// grows as its inverse.
const VISIBILITY_SHIFT: f32 = 0.03;

/// Coordinates `u` moved into stratum `k` of `n`: a √n × √n grid where `n` is a square, else
/// `n` strata of the first coordinate.
fn first_stratum(u: Vec2, k: u32, n: u32) -> Vec2 {
    let side = (n as f32).sqrt().round() as u32;
    if side * side == n {
        Vec2::new(
            ((k % side) as f32 + u.x) / side as f32,
            ((k / side) as f32 + u.y) / side as f32,
        )
    } else {
        Vec2::new((k as f32 + u.x) / n as f32, u.y)
    }
}

/// A stream whose first 2-D draw falls in its path's stratum ([`first_stratum`]): the deeper
/// paths of one gather ray leave its vertex in stratified directions.
struct FirstStratum<'a> {
    stream: &'a mut Rng,
    /// The path's stratum and the paths, until the first 2-D draw.
    stratum: Option<(u32, u32)>,
}

impl crate::sampler::Sampler for FirstStratum<'_> {
    fn next_1d(&mut self) -> f32 {
        self.stream.next_f32()
    }
    fn next_2d(&mut self) -> Vec2 {
        let u = self.stream.next_2d();
        match self.stratum.take() {
            Some((k, n)) => first_stratum(u, k, n),
            None => u,
        }
    }
    fn next_key(&mut self) -> u64 {
        crate::sampler::Sampler::next_key(self.stream)
    }
    fn as_dyn(&mut self) -> &mut dyn crate::sampler::Sampler {
        self
    }
}

/// A ray traced up to its first opaque hit.
#[derive(Clone, Debug)]
struct Traced {
    o: DVec3,
    w: DVec3,
    s: f64,
    radiance: [f64; 3],
    /// Crossings of null boundaries: distance, geometric normal.
    crossings: Vec<(f64, DVec3)>,
    /// The medium after each crossing (`media[0]` before the first).
    media: Vec<Option<usize>>,
    /// The opaque hit, if any.
    opaque: Option<OpaqueHit>,
}

impl Traced {
    /// The ray's pieces between crossings: start, end (the opaque hit's distance, ∞ for an
    /// escaping ray, at the last) and the medium along it.
    fn segments(&self) -> impl Iterator<Item = (f64, f64, Option<usize>)> + '_ {
        self.media.iter().enumerate().map(|(i, &medium)| {
            let t0 = if i == 0 { 0.0 } else { self.crossings[i - 1].0 };
            let t1 = self.crossings.get(i).map_or(self.s, |c| c.0);
            (t0, t1, medium)
        })
    }
}

/// A source evaluated at a point towards a direction: its value and its gradient.
#[derive(Clone, Copy, Debug)]
struct Source {
    p: DVec3,
    w: DVec3,
    q: [f64; 3],
    gradient: [DVec3; 3],
}

/// A scene seen by a gather from one receiver.
pub struct SceneMedium<'a> {
    scene: &'a Scene,
    /// The medium on the side of the receiver's hemisphere.
    medium: Option<usize>,
    /// Emitters seen by gather rays count (validation against closed forms).
    include_emitters: bool,
    /// Light samples per surface hit and per medium point.
    light_samples: u32,
    /// The receiver's tangents, when only the tangential gradients are wanted (the estimator
    /// projects onto them): differences along two axes instead of three.
    tangents: Option<[DVec3; 2]>,
    /// The light samples' rotation for the last gather direction asked.
    rotation: std::cell::Cell<Option<(DVec3, Vec2, f32)>>,
    /// The march step along the last gather direction whose source was asked (each `source`
    /// call is one), which keys its light samples' tracking streams.
    march_step: std::cell::Cell<Option<(DVec3, u32)>>,
    /// Sources are evaluated with their gradients (off: values alone, their gradients asked for
    /// computed anew).
    gradients: bool,
    /// The sources' gradients take in where a volumetric shadow's edge moves
    /// ([`Self::shadow_edge`]); off, each light sample's visibility is held.
    shadow_edges: bool,
    /// The paths of the bounces beyond a gather ray's first vertex (`None`: one bounce).
    deeper: Option<VolPathIntegrator>,
    /// Such paths per gather ray.
    deeper_paths: u32,
    /// Volumetric records serving the deeper paths' light in-scattered along the gather ray.
    volume: Option<std::sync::Arc<VolumeCache>>,
    /// A caustic map serves the receiver's caustics: its deeper paths leave out the emission
    /// they reach through delta lobes alone, unscattered ([`VolPathIntegrator::trace`]).
    caustics_served: bool,
    /// The global map, with the most bounces of the photons that may serve a gather ray's
    /// opaque hit: the deeper bounces' light there ([`Self::with_deeper_bounces`]).
    global: Option<(std::sync::Arc<ServingMap>, u16)>,
    /// The last source evaluated: point, direction, value and gradient.
    last_source: RefCell<Option<Source>>,
    /// The last coefficients taken with their gradients (a march step's source and its σ_t
    /// gradient ask at the same point).
    last_gradients: std::cell::Cell<Option<(usize, DVec3, Coefficients, CoefficientGradients)>>,
    last: RefCell<Option<Traced>>,
    rays: RefCell<RayCounts>,
}

impl<'a> SceneMedium<'a> {
    /// A view of `scene` from a receiver in `medium`.
    #[must_use]
    pub fn new(
        scene: &'a Scene,
        medium: Option<usize>,
        include_emitters: bool,
        light_samples: u32,
    ) -> Self {
        SceneMedium {
            scene,
            medium,
            include_emitters,
            light_samples: light_samples.max(1),
            tangents: None,
            gradients: true,
            shadow_edges: true,
            deeper: None,
            deeper_paths: 1,
            volume: None,
            caustics_served: false,
            global: None,
            rotation: std::cell::Cell::new(None),
            march_step: std::cell::Cell::new(None),
            last_source: RefCell::new(None),
            last_gradients: std::cell::Cell::new(None),
            last: RefCell::new(None),
            rays: RefCell::new(RayCounts::default()),
        }
    }

    /// Keeps the gradients' parts along the receiver's tangents `[s, t]` only (the estimator
    /// drops the normal components anyway).
    #[must_use]
    pub fn with_tangents(mut self, tangents: [DVec3; 2]) -> Self {
        self.tangents = Some(tangents);
        self
    }

    /// Whether the sources' gradients take in the light's visibility changing at volumetric
    /// shadows' edges (on by default; off holds each light sample's visibility, as NOTES-002
    /// §2.7's first form).
    #[must_use]
    pub fn with_shadow_edges(mut self, shadow_edges: bool) -> Self {
        self.shadow_edges = shadow_edges;
        self
    }

    /// Evaluates the source's gradient with its value (the default) or not (a gather that asks
    /// for no per-cell gradients).
    #[must_use]
    pub fn with_gradients(mut self, gradients: bool) -> Self {
        self.gradients = gradients;
        self
    }

    /// Gathers `bounces` indirect bounces (`-ab`; unbounded: Russian roulette alone): the
    /// ones beyond the first by the mean of `paths` `volpath` paths per gather ray (see the
    /// module). With `caustics`, the receiver's caustics are the map's, left out of the
    /// gather, and the paths take those of their own Lambertian vertices from it. With
    /// `global`, a gather ray's diffuse opaque hit reflects the map's irradiance instead of
    /// its paths (Jensen's cached final gather, through media).
    #[must_use]
    pub fn with_deeper_bounces(
        mut self,
        bounces: u32,
        paths: u32,
        caustics: Option<&std::sync::Arc<ServingMap>>,
        global: Option<&std::sync::Arc<ServingMap>>,
    ) -> Self {
        self.deeper_paths = paths.max(1);
        self.caustics_served = caustics.is_some();
        self.global = global
            .filter(|_| bounces > 1)
            .map(|g| (g.clone(), bounce_limit(bounces.saturating_sub(1))));
        self.deeper = (bounces > 1).then(|| VolPathIntegrator {
            caustics: caustics.cloned(),
            global: global.cloned(),
            ..VolPathIntegrator::plain(VolPathIntegrator::depth_of_bounces(bounces))
        });
        self
    }

    /// With `volume`, the light the deeper bounces scatter along a gather ray through a medium
    /// comes from its records, one bounce shorter, at the ray's quadrature points (see the
    /// module); the deeper paths then go on from the opaque hit alone.
    #[must_use]
    pub fn with_volume_records(mut self, volume: Option<&std::sync::Arc<VolumeCache>>) -> Self {
        self.volume = volume.cloned();
        self
    }

    /// Rays traced so far.
    #[must_use]
    pub fn rays(&self) -> RayCounts {
        *self.rays.borrow()
    }

    /// The `i`-th light sample (light choice, position) for gather direction `w`: a stratified
    /// set shifted by a hash of `w` (Cranley–Patterson rotation).
    fn light_sample(&self, w: DVec3, i: u32) -> (f32, Vec2) {
        let n = self.light_samples;
        let side = (n as f32).sqrt().ceil() as u32;
        let (a, b) = (i % side, i / side);
        // The rotation of direction `w` (a cell's every march step asks for the same one).
        let (shift, select) = match self.rotation.get() {
            Some((known, shift, select)) if known == w => (shift, select),
            _ => {
                let mut rng = Rng::keyed(
                    0x6c69_6768_7473,
                    &[w.x.to_bits(), w.y.to_bits(), w.z.to_bits()],
                );
                let (shift, select) = (rng.next_2d(), rng.next_f32());
                self.rotation.set(Some((w, shift, select)));
                (shift, select)
            }
        };
        let wrap = |x: f32| if x >= 1.0 { x - 1.0 } else { x };
        let u = Vec2::new(
            wrap((a as f32 + shift.x) / side as f32),
            wrap((b as f32 + shift.y) / side as f32),
        );
        (wrap((i as f32 + select) / n as f32), u)
    }

    /// Calls `f(i, sample, at, weight)` for each of the light samples of gather direction `w`
    /// at `p` that can contribute (the stream both [`Self::direct`] and
    /// [`Self::scattered_with_gradient`] walk, so the two agree sample by sample); the sample is
    /// taken at `at` and its value counts `weight` times.
    ///
    /// With `step`, the march step about `p` (its middle), a point or spot light is sampled
    /// not at `p` but at a distance drawn on the step towards it ([`Equiangular`], Kulla and
    /// Fajardo 2012), weighed to estimate the step's source ([`StepExtent::sample_weight`]): at
    /// the middle alone its 1/r² made a gather ray that passes near the lamp a spike, and the
    /// records that met none read low (spot-fog over six seeds: relMSE_trim 4.0e-4 → 2.2e-4).
    fn for_each_light_sample(
        &self,
        p: Vec3,
        w: DVec3,
        step: Option<&StepExtent>,
        mut f: impl FnMut(u32, LightSample, Vec3, Rgb),
    ) {
        let lights = &self.scene.lights;
        if lights.is_empty() {
            return;
        }
        let step = step.filter(|_| lights.has_delta_positions());
        for i in 0..self.light_samples {
            let (u_sel, u) = self.light_sample(w, i);
            let Some(step) = step else {
                if let Some(ls) = lights.sample(p, u_sel, u).filter(|ls| ls.pdf > 0.0) {
                    f(i, ls, p, Rgb::ONE);
                }
                continue;
            };
            let (light, selection) = lights.select(p, u_sel);
            let (at, weight) = if lights.delta_position(light as u32).is_some() {
                // Nothing where the light misses the step (a spot's cone) or the ray meets it.
                let Some(moved) = self.step_distance(p, w, step, light as u32, i) else {
                    continue;
                };
                moved
            } else {
                (p, Rgb::ONE)
            };
            let shared = &mut crate::lights::SharedSetUp::default();
            if let Some(ls) = lights
                .sample_chosen(light, selection, at.into(), u, true, shared)
                .filter(|ls| ls.pdf > 0.0)
            {
                f(i, ls, at, weight);
            }
        }
    }

    /// For point or spot light `light` and march step `step` about `p` along `w`: a distance on
    /// the step drawn uniformly in the angle the light subtends (within a spot's cone), as the
    /// point there and the sample's weight. `None` where the light misses the step or the ray
    /// passes through it.
    fn step_distance(
        &self,
        p: Vec3,
        w: DVec3,
        step: &StepExtent,
        light: u32,
        i: u32,
    ) -> Option<(Vec3, Rgb)> {
        let middle = step.middle();
        let d = w.as_vec3();
        let interval = ((step.t0 - middle) as f32, (step.t1 - middle) as f32);
        let (position, interval) = self
            .scene
            .lights
            .delta_position_along(light, p, d, interval)?;
        let equiangular = Equiangular::new(p, d, position, interval)?;
        let mut rng = Self::sample_stream(DISTANCE_STREAM, w, self.step_key(w, false), i);
        let (t, pdf) = equiangular.sample(rng.next_f32());
        let weight = step.sample_weight(middle + f64::from(t), f64::from(pdf));
        let weight = Rgb::new(weight[0] as f32, weight[1] as f32, weight[2] as f32);
        Some((p + d * t, weight))
    }

    /// Counts a march step along `w` (see `march_step`).
    fn begin_march_step(&self, w: DVec3) {
        let n = match self.march_step.get() {
            Some((known, n)) if known == w => n + 1,
            _ => 0,
        };
        self.march_step.set(Some((w, n)));
    }

    /// The key of the streams of light samples taken along `w` now: the march step's, or
    /// [`SURFACE_STEP`] at the opaque hit (traced before the march).
    fn step_key(&self, w: DVec3, at_surface: bool) -> u32 {
        match self.march_step.get() {
            Some((known, n)) if known == w && !at_surface => n,
            _ => SURFACE_STEP,
        }
    }

    /// The stream of light sample `i` along gather direction `w` at step `step`, for its
    /// transmittance ([`TRANSMITTANCE_STREAM`]) or, apart, its optical depth's gradient in grids
    /// ([`DEPTH_STREAM`]): common random numbers between receivers gathering along `w`.
    fn sample_stream(purpose: u64, w: DVec3, step: u32, i: u32) -> Rng {
        let key = [w.x, w.y, w.z].map(f64::to_bits);
        Rng::keyed(
            purpose,
            &[key[0], key[1], key[2], u64::from(step), u64::from(i)],
        )
    }

    /// Light arriving at `p` (in `medium`) along the light samples of gather direction `w`, with
    /// transmittance: `f(direction towards the light)` weighs each; the mean over the samples.
    /// With `march_step` (a source's), point and spot lights are sampled over the step
    /// ([`Self::for_each_light_sample`]).
    fn direct(
        &self,
        p: Vec3,
        w: DVec3,
        offset_normal: Option<Vec3>,
        medium: Option<usize>,
        march_step: Option<&StepExtent>,
        f: impl Fn(Vec3) -> Rgb,
    ) -> Rgb {
        let mut sum = Rgb::ZERO;
        let step = self.step_key(w, offset_normal.is_some());
        self.for_each_light_sample(p, w, march_step, |i, ls, at, count| {
            let weight = f(ls.wi);
            if weight.is_black() {
                return;
            }
            let ray = self
                .scene
                .shadow_ray_at(at, offset_normal, ls.wi, ls.distance);
            let mut rng = Self::sample_stream(TRANSMITTANCE_STREAM, w, step, i);
            let mut rays = self.rays.borrow_mut();
            let tr = transmittance_along(self.scene, ray, medium, &mut rng, &mut rays);
            sum += weight * tr * ls.radiance * count / ls.pdf;
        });
        sum / self.light_samples as f32
    }

    /// Traces (or recalls) the ray from `o` along `w`.
    fn traced(&self, o: DVec3, w: DVec3) -> std::cell::Ref<'_, Traced> {
        let known = self
            .last
            .borrow()
            .as_ref()
            .is_some_and(|t| t.o == o && t.w == w);
        if !known {
            let t = self.trace(o, w);
            *self.last.borrow_mut() = Some(t);
        }
        std::cell::Ref::map(self.last.borrow(), |t| t.as_ref().expect("just traced"))
    }

    /// Traces the ray from `o` along `w` to its first opaque hit.
    fn trace(&self, o: DVec3, w: DVec3) -> Traced {
        let scene = self.scene;
        let d = w.as_vec3();
        let mut crossings = Vec::new();
        let mut media = vec![self.medium];
        // Distances from `o`, in double precision, of each segment's start plus its hit.
        let along =
            |segment_origin: Vec3, t: f32| (segment_origin.as_dvec3() - o).dot(w) + f64::from(t);
        let opaque = first_opaque(
            scene,
            Ray::new(o.as_vec3(), d),
            self.medium,
            &mut self.rays.borrow_mut().gather,
            |segment_origin, it, beyond| {
                crossings.push((along(segment_origin, it.t), it.ng.as_dvec3()));
                media.push(beyond);
            },
        );
        let (s, radiance) = match opaque {
            None => {
                let mut l = [0.0; 3];
                if scene.lights.has_environment() && self.include_emitters {
                    let e = scene.lights.environment_radiance(d);
                    l = [e.r, e.g, e.b].map(f64::from);
                }
                (f64::INFINITY, l)
            }
            Some(OpaqueHit {
                it,
                segment_origin,
                medium,
            }) => {
                // Its emission (when counted) and direct light reflected towards o.
                let shape = &scene.shapes[it.shape as usize];
                let wo = -d;
                let mut l = Rgb::ZERO;
                if self.include_emitters {
                    if let Some(light) = shape.area_light {
                        l += scene
                            .lights
                            .area_radiance(light, it.p, it.frame.n, it.uv, wo, it.t);
                    }
                }
                let bsdf = it.bsdf(&scene.materials[shape.material], -wo);
                if bsdf.has_smooth() {
                    let wo_local = it.frame.to_local(wo);
                    let side = medium_after(shape.media, it.ng, wo, medium);
                    l += self.direct(it.p, w, Some(it.ng), side, None, |wi| {
                        bsdf.eval(wo_local, it.frame.to_local(wi))
                            * scene.perturbed_shadowing(&it, wi)
                    });
                }
                (along(segment_origin, it.t), [l.r, l.g, l.b].map(f64::from))
            }
        };
        Traced {
            o,
            w,
            s,
            radiance,
            crossings,
            media,
            opaque,
        }
    }

    /// The light of the bounces beyond the first vertex of the ray from `o` along `w`: what they
    /// scatter along it from the volumetric records plus the mean of `deeper_paths` `volpath`
    /// paths from its opaque hit, or without records the mean of as many paths from a free
    /// flight along the ray (see the module); `None` with one bounce.
    fn deeper_radiance(&self, o: DVec3, w: DVec3) -> Option<Rgb> {
        let integrator = self.deeper.as_ref()?;
        let traced = self.traced(o, w);
        let served = self
            .volume
            .as_ref()
            .and_then(|records| self.in_scattered_by_records(integrator, records, &traced));
        if let Some((l, through)) = served {
            if let Some(reflected) = self.reflected_photon_light(&traced) {
                return Some(l + through * reflected);
            }
        }
        let (mut sum, through) = match served {
            Some((l, through)) => (l * self.deeper_paths as f32, Some(through)),
            None => (Rgb::ZERO, None),
        };
        for k in 0..self.deeper_paths {
            sum += self.deeper_path(integrator, &traced, k, through);
        }
        Some(sum / self.deeper_paths as f32)
    }

    /// The light of the bounces beyond the first that the opaque hit of `traced` reflects
    /// towards its origin, from the global map ([`photon_reflected`]); `None` without a map,
    /// and where that does not serve (the paths go on).
    fn reflected_photon_light(&self, traced: &Traced) -> Option<Rgb> {
        let (map, bounces) = self.global.as_ref()?;
        let it = &traced.opaque.as_ref()?.it;
        let d = traced.w.as_vec3();
        let bsdf = it.bsdf(
            &self.scene.materials[self.scene.shapes[it.shape as usize].material],
            d,
        );
        photon_reflected(self.scene, map, it, &bsdf, d, traced.s as f32, *bounces).map(|l| l.0)
    }

    /// The light of the bounces beyond the first scattered along the ray `traced` towards its
    /// origin, from the volumetric records' light one bounce shorter at [`RECORD_POINTS`]
    /// quadrature points per medium segment (where none serves a point, from a phase-sampled
    /// path there), and the transmittance to the ray's end; `None` where a medium on the way
    /// scatters too far forward for bands 0–2 ([`BANDS_HOLD_PHASE`]).
    fn in_scattered_by_records(
        &self,
        integrator: &VolPathIntegrator,
        records: &VolumeCache,
        traced: &Traced,
    ) -> Option<(Rgb, Rgb)> {
        let scene = self.scene;
        let forward = |m: &Option<usize>| {
            m.is_some_and(|m| scene.media[m].phase.mean_cosine().abs() > BANDS_HOLD_PHASE)
        };
        if traced.media.iter().any(forward) {
            return None;
        }
        let d = traced.w.as_vec3();
        let mut jitter = Rng::keyed(
            RECORDS_KEY,
            &[
                traced.w.x.to_bits(),
                traced.w.y.to_bits(),
                traced.w.z.to_bits(),
            ],
        );
        let (mut sum, mut through) = (Rgb::ZERO, Rgb::ONE);
        for (t0, t1, medium) in traced.segments() {
            let Some(m) = medium else {
                continue;
            };
            let med = &scene.media[m];
            let ray = Ray::new((traced.o + traced.w * t0).as_vec3(), d);
            let (points, segment, _) =
                quadrature_points(med, &ray, (t1 - t0) as f32, RECORD_POINTS, || {
                    jitter.next_f32()
                });
            for (t, weight) in points {
                let p = ray.at(t);
                let sigma_s = med.at(p).sigma_s;
                if sigma_s.is_black() {
                    continue;
                }
                let l = records
                    .in_scattered_shorter(p, m, d, med.phase, 1)
                    .unwrap_or_else(|| {
                        let at = MarchPoint {
                            p,
                            d,
                            medium: m,
                            depth: 1,
                        };
                        let key = u64::from(jitter.next_u32());
                        let mut rng = Rng::new(key, RECORDS_KEY);
                        let mut rays = RayCounts::default();
                        let l =
                            in_scattered_by_path(integrator, scene, &at, key, &mut rng, &mut rays);
                        self.count_gather_rays(rays);
                        l
                    });
                sum += through * weight * sigma_s * l;
            }
            through *= segment;
        }
        Some((sum, through))
    }

    /// One path of [`Self::deeper_radiance`] along the ray `traced`, on stream `k` of its
    /// direction: from the opaque hit through the transmittance `through` where the records
    /// hold the medium's part, else from a free flight along the ray.
    fn deeper_path(
        &self,
        integrator: &VolPathIntegrator,
        traced: &Traced,
        k: u32,
        through: Option<Rgb>,
    ) -> Rgb {
        let scene = self.scene;
        let Traced { o, w, opaque, .. } = *traced;
        let mut stream = Rng::keyed(
            DEEPER_KEY,
            &[w.x.to_bits(), w.y.to_bits(), w.z.to_bits(), u64::from(k)],
        );
        let mut rng = Rng::new(u64::from(stream.next_u32()), DEEPER_KEY);
        let mut rays = RayCounts::default();
        let d = w.as_vec3();
        let mut beta = through.unwrap_or(Rgb::ONE);
        let mut depth = 1;
        let mut start = None;
        // Where the records hold the medium's part, the path leaves from the opaque hit.
        for (t0, t1, medium) in traced.segments().filter(|_| through.is_none()) {
            if let Some(m) = medium {
                let med = &scene.media[m];
                let origin = (o + w * t0).as_vec3();
                // The march holds the medium's emission along the ray.
                let mut emitted = Rgb::ZERO;
                let flight = sample_flight(
                    med,
                    origin,
                    d,
                    (t1 - t0) as f32,
                    &mut beta,
                    &mut emitted,
                    &mut rng,
                );
                match flight {
                    Flight::Absorbed => return Rgb::ZERO,
                    Flight::Passed => {}
                    Flight::Scattered { t, .. } => {
                        let p = origin + d * t;
                        let u = first_stratum(stream.next_2d(), k, self.deeper_paths);
                        let (wi, _) = med.phase.sample(d, u);
                        start = Some((Ray::new(p, wi), Some(m), 1.0));
                        break;
                    }
                }
            }
        }
        let mut arrival = Arrival::Gather;
        let mut caustic_chain = false;
        let (ray, medium, eta) = match start {
            Some(found) => found,
            None => {
                let Some(hit) = opaque else {
                    return Rgb::ZERO;
                };
                let it = hit.it;
                let shape = &scene.shapes[it.shape as usize];
                let bsdf = it.bsdf(&scene.materials[shape.material], d);
                let wo_local = it.frame.to_local(-d);
                let mut first = FirstStratum {
                    stream: &mut stream,
                    stratum: Some((k, self.deeper_paths)),
                };
                let Some((bs, wi)) = sample_continuation(
                    scene,
                    &it,
                    &bsdf,
                    wo_local,
                    BsdfStrategy::All,
                    depth,
                    &mut first,
                ) else {
                    return Rgb::ZERO;
                };
                beta *= bs.weight;
                // Light samples cannot take what a delta lobe reaches: it counts in full, or
                // is the receiver's caustic, which the map serves.
                caustic_chain = self.caustics_served && bs.delta;
                if bs.delta {
                    arrival = Arrival::Bsdf {
                        from: it.p.into(),
                        pdf: bs.pdf,
                        delta: true,
                        light_samples: 0,
                    };
                }
                let beyond = medium_after(shape.media, it.ng, wi, hit.medium);
                (scene.spawn_ray(&it, wi), beyond, bs.eta)
            }
        };
        if !count_and_roulette(&mut depth, &mut beta, eta, integrator.rr_depth, &mut stream) {
            return Rgb::ZERO;
        }
        let state = PathState {
            ray,
            medium,
            beta,
            depth,
            arrival,
            caustic_chain,
        };
        let l = integrator
            .trace(scene, state, None, false, &mut stream, &mut rng, &mut rays)
            .all;
        self.count_gather_rays(rays);
        l
    }

    /// Adds the rays of a path traced for a gather ray to the gather's counts.
    fn count_gather_rays(&self, rays: RayCounts) {
        let mut counts = self.rays.borrow_mut();
        counts.gather += rays.bounce + rays.camera;
        counts.shadow += rays.shadow;
    }

    /// The medium at distance `t` along the ray.
    fn medium_along(&self, o: DVec3, w: DVec3, t: f64) -> Option<usize> {
        let traced = self.traced(o, w);
        let i = traced.crossings.iter().take_while(|c| c.0 <= t).count();
        traced.media[i]
    }

    /// σ_t, σ_s, L_e at `p` in `medium`.
    fn coefficients(&self, medium: Option<usize>, p: DVec3) -> Option<crate::media::Coefficients> {
        let m = &self.scene.media[medium?];
        let p = p.as_vec3();
        m.contains(p).then(|| m.at(p))
    }

    /// [`Self::coefficients`] with their gradients in a grid (`None` in a homogeneous medium).
    fn coefficients_with_gradients(
        &self,
        medium: Option<usize>,
        p: DVec3,
    ) -> Option<(Coefficients, Option<CoefficientGradients>)> {
        let index = medium?;
        let m = &self.scene.media[index];
        if m.homogeneous {
            return self.coefficients(medium, p).map(|c| (c, None));
        }
        if let Some((i, q, c, g)) = self.last_gradients.get() {
            if i == index && q == p {
                return Some((c, Some(g)));
            }
        }
        let x = p.as_vec3();
        if !m.contains(x) {
            return None;
        }
        let (c, g) = m.at_with_gradient(x);
        self.last_gradients.set(Some((index, p, c, g)));
        Some((c, Some(g)))
    }

    /// The source q at `p` towards direction `-w` (the receiver) in `medium`; with
    /// `march_step`, the step's about `p` ([`GatherMedium::step_source`]).
    fn q(
        &self,
        medium: Option<usize>,
        p: DVec3,
        w: DVec3,
        march_step: Option<&StepExtent>,
    ) -> [f64; 3] {
        let Some(c) = self.coefficients(medium, p) else {
            return [0.0; 3];
        };
        let mut q = c.sigma_a() * c.emission;
        if !c.sigma_s.is_black() {
            let m = &self.scene.media[medium.unwrap_or(0)];
            let towards = (-w).as_vec3();
            let phase = m.phase;
            let li = self.direct(p.as_vec3(), w, None, medium, march_step, |wi| {
                Rgb::splat(phase.eval(-wi, towards))
            });
            q += c.sigma_s * li;
        }
        [q.r, q.g, q.b].map(f64::from)
    }

    /// The source q at `p` towards `-w` in `medium` and its spatial gradient (`w` fixed), from
    /// the same light samples: q = σ_a L_e + σ_s L_s with the coefficients' gradients by
    /// central differences (no rays) and L_s's in closed form per light sample, its point on the
    /// light held (NOTES-002 §2.7: "for an area light with its sample points frozen"; visibility
    /// held). A sample's integrand in area measure, f = L_e p(−ωᵢ·ω) T cos θ_y / r², moves with
    /// p as ∇ln f = ∇ln p − ∇τ + 2ωᵢ/r + (n_y/cos θ_y + ωᵢ)/r (the last two for points at a
    /// distance; a distant light's direction is held, leaving −∇τ), plus a spot light's
    /// ∇ln falloff ([`crate::lights::LightSet::falloff_log_gradient`]). With `march_step`, the
    /// step's source about `p` and its gradient ([`GatherMedium::step_source`]).
    fn q_with_gradient(
        &self,
        medium: Option<usize>,
        p: DVec3,
        w: DVec3,
        march_step: Option<&StepExtent>,
    ) -> Source {
        let mut out = Source {
            p,
            w,
            q: [0.0; 3],
            gradient: [DVec3::ZERO; 3],
        };
        // The coefficients with their own gradients, exact for the grids' interpolants.
        let Some((c, coefficient_gradients)) = self.coefficients_with_gradients(medium, p) else {
            return out;
        };
        let m = &self.scene.media[medium.unwrap_or(0)];
        let emitted = c.sigma_a() * c.emission;
        let mut q = emitted;
        let mut gradient = [DVec3::ZERO; 3];
        let rgb = |v: Rgb| [v.r, v.g, v.b].map(f64::from);
        if let Some(cg) = coefficient_gradients.filter(|_| !emitted.is_black()) {
            // ∇(σ_a L_e) = ∇σ_a L_e + σ_a ∇L_e.
            let (sigma_a, ga) = (rgb(c.sigma_a()), cg.sigma_a(&c));
            let le = rgb(c.emission);
            gradient = [0, 1, 2].map(|k| {
                self.along_axes(ga[k] * le[k] as f32 + cg.emission[k] * sigma_a[k] as f32)
            });
        }
        if !c.sigma_s.is_black() {
            let (li, li_gradient) = self.scattered_with_gradient(p, w, medium, m.phase, march_step);
            q += c.sigma_s * li;
            let sigma_s = rgb(c.sigma_s);
            let li = rgb(li);
            let sigma_s_gradient = coefficient_gradients.map_or([DVec3::ZERO; 3], |cg| {
                cg.sigma_s.map(|g| self.along_axes(g))
            });
            for k in 0..3 {
                gradient[k] += sigma_s_gradient[k] * li[k] + li_gradient[k] * sigma_s[k];
            }
        }
        out.q = rgb(q);
        out.gradient = gradient;
        out
    }

    /// Light single-scattered at `p` towards `-w` per unit σ_s (the phase function times the
    /// light arriving with transmittance, over the light samples of `w`, as [`Self::direct`])
    /// and its gradient with each sample's point on the light held (see [`Self::q_with_gradient`];
    /// the optical depth's gradient from [`transmittance_with_depth_gradient`]).
    fn scattered_with_gradient(
        &self,
        p: DVec3,
        w: DVec3,
        medium: Option<usize>,
        phase: crate::media::Phase,
        march_step: Option<&StepExtent>,
    ) -> (Rgb, [DVec3; 3]) {
        let (mut sum, mut gradient) = (Rgb::ZERO, [DVec3::ZERO; 3]);
        let towards = (-w).as_vec3();
        let mut rays = self.rays.borrow_mut();
        let step = self.step_key(w, false);
        self.for_each_light_sample(p.as_vec3(), w, march_step, |i, ls, x, count| {
            let weight = phase.eval(-ls.wi, towards);
            if weight <= 0.0 {
                return;
            }
            let ray = self.scene.shadow_ray_at(x, None, ls.wi, ls.distance);
            let mut rng = Self::sample_stream(TRANSMITTANCE_STREAM, w, step, i);
            let mut depth_rng = Self::sample_stream(DEPTH_STREAM, w, step, i);
            let (tr, depth_gradient) = transmittance_with_depth_gradient(
                self.scene,
                ray,
                medium,
                &mut rng,
                &mut depth_rng,
                &mut rays,
            );
            if tr.is_black() {
                return;
            }
            let value = ls.radiance * tr * count * (weight / ls.pdf);
            sum += value;
            // ∇ln of the sample's integrand, less −∇τ (per channel, below).
            let wi = ls.wi.as_dvec3();
            let mut log = DVec3::ZERO;
            let r = f64::from(ls.distance);
            if r.is_finite() {
                // ∇(−ωᵢ·ω) = (ω − (ωᵢ·ω) ωᵢ)/r with ω = `towards`.
                let t = towards.as_dvec3();
                let d_cos = (t - wi * wi.dot(t)) / r;
                log += d_cos * f64::from(phase.eval_derivative(-ls.wi, towards) / weight);
                log += wi * (2.0 / r);
                log += self
                    .scene
                    .lights
                    .falloff_log_gradient(ls.light, x)
                    .as_dvec3();
                let n = ls.normal.as_dvec3();
                let cos_y = -n.dot(wi);
                if cos_y != 0.0 {
                    log += (n / cos_y + wi) / r;
                }
            }
            let depth = depth_gradient.map(|v| v.as_dvec3());
            let shadow_edge = self.shadow_edge(x, &ls, medium, w, step, i, &mut rays);
            let value = [value.r, value.g, value.b].map(f64::from);
            for c in 0..3 {
                gradient[c] += (log - depth[c] + shadow_edge) * value[c];
            }
        });
        let n = f64::from(self.light_samples);
        (sum / self.light_samples as f32, gradient.map(|g| g / n))
    }

    /// The part of a visible light sample's ∇ln f that held visibility misses: near a volumetric
    /// shadow's edge, moving `x` hides the light (NOTES-002 §2.7 leaves this open; the fog box's
    /// gradients in the boxes' shadows were up to 60 % off the finite differences without it).
    /// One more shadow ray, from `x` shifted by h along one axis of the gradient (the receiver's
    /// two tangents, or three world axes) with a sign, both drawn, the light's point held. The
    /// sample being visible, the central difference (V(x + h e) − V(x − h e))/h along e (over h,
    /// not 2h: from the visible side it sees half of the edges' crossings) is the mean of
    /// 2 s (V(x + s h e) − 1)/h over the sign s, and the axis drawn weighs its count. A shift
    /// that itself goes through a surface (a point beside a box's face) is no shadow's edge and
    /// counts as visible; one more ray tells, only where the shifted one was blocked.
    #[allow(clippy::too_many_arguments)]
    fn shadow_edge(
        &self,
        x: Vec3,
        ls: &LightSample,
        medium: Option<usize>,
        w: DVec3,
        step: u32,
        i: u32,
        rays: &mut RayCounts,
    ) -> DVec3 {
        if !self.shadow_edges {
            return DVec3::ZERO;
        }
        let world = [DVec3::X, DVec3::Y, DVec3::Z];
        let axes: &[DVec3] = match &self.tangents {
            Some(t) => t,
            None => &world,
        };
        let mut rng = Self::sample_stream(VISIBILITY_STREAM, w, step, i);
        let pick = rng.next_f32() * axes.len() as f32;
        let axis = axes[(pick as usize).min(axes.len() - 1)];
        let sign = if pick.fract() < 0.5 { -1.0 } else { 1.0 };
        let h = VISIBILITY_SHIFT
            * if ls.distance.is_finite() {
                ls.distance
            } else {
                self.scene.scale
            };
        let moved = x + (axis * sign).as_vec3() * h;
        let ray = if ls.distance.is_finite() {
            let to_light = x + ls.wi * ls.distance - moved;
            let length = to_light.length();
            self.scene
                .shadow_ray_at(moved, None, to_light / length, length)
        } else {
            self.scene.shadow_ray_at(moved, None, ls.wi, ls.distance)
        };
        rays.shadow += 1;
        let mut traced = 0;
        // The light's own surface does not count: the held point, reached from elsewhere, lies
        // off its plane by the sampler's rounding.
        let own =
            |hit: &OpaqueHit| self.scene.shapes[hit.it.shape as usize].area_light == Some(ls.light);
        if first_opaque(self.scene, ray, medium, &mut traced, |_, _, _| {})
            .is_none_or(|hit| own(&hit))
        {
            return DVec3::ZERO;
        }
        // Blocked: by a shadow's edge, unless the shift itself went through a surface.
        rays.shadow += 1;
        let shift = Ray {
            o: x,
            d: (axis * sign).as_vec3(),
            t_min: 0.0,
            t_max: h,
        };
        if first_opaque(self.scene, shift, medium, &mut traced, |_, _, _| {}).is_some() {
            return DVec3::ZERO;
        }
        axis * (-2.0 * axes.len() as f64 * sign / f64::from(h))
    }

    /// [`GatherMedium::source`] at `t`, or with `march_step` [`GatherMedium::step_source`].
    fn source_over(&self, o: DVec3, w: DVec3, t: f64, march_step: Option<&StepExtent>) -> [f64; 3] {
        self.begin_march_step(w);
        let medium = self.medium_along(o, w, t);
        if !self.gradients {
            return self.q(medium, o + w * t, w, march_step);
        }
        let source = self.q_with_gradient(medium, o + w * t, w, march_step);
        *self.last_source.borrow_mut() = Some(source);
        source.q
    }

    /// The gradient of [`Self::source_over`].
    fn source_gradient_over(
        &self,
        o: DVec3,
        w: DVec3,
        t: f64,
        march_step: Option<&StepExtent>,
    ) -> [DVec3; 3] {
        let medium = self.medium_along(o, w, t);
        let p = o + w * t;
        let known = *self.last_source.borrow();
        match known {
            Some(s) if s.p == p && s.w == w => s.gradient,
            _ => self.q_with_gradient(medium, p, w, march_step).gradient,
        }
    }

    /// A gradient as the estimator wants it: whole, or its part along the receiver's tangents.
    fn along_axes(&self, g: Vec3) -> DVec3 {
        let g = g.as_dvec3();
        match &self.tangents {
            Some(t) => t.iter().map(|&e| e * e.dot(g)).sum(),
            None => g,
        }
    }
}

impl GatherMedium for SceneMedium<'_> {
    fn surface(&self, o: DVec3, w: DVec3) -> (f64, [f64; 3]) {
        let t = self.traced(o, w);
        (t.s, t.radiance)
    }

    fn deeper(&self, o: DVec3, w: DVec3) -> Option<[f64; 3]> {
        let l = self.deeper_radiance(o, w)?;
        Some([l.r, l.g, l.b].map(f64::from))
    }

    fn boundaries(&self, o: DVec3, w: DVec3, t_max: f64) -> Vec<(f64, DVec3)> {
        let traced = self.traced(o, w);
        let mut out: Vec<(f64, DVec3)> = traced
            .crossings
            .iter()
            .copied()
            .filter(|c| c.0 < t_max)
            .collect();
        // A heterogeneous medium also ends at its box.
        for (t0, t1, m) in traced.segments() {
            let Some(m) = m.map(|m| &self.scene.media[m]) else {
                continue;
            };
            if m.bounds.is_none() {
                continue;
            }
            let t1 = t1.min(t_max);
            let Some((a, b)) = m.clip(
                o.as_vec3() + w.as_vec3() * t0 as f32,
                w.as_vec3(),
                (t1 - t0) as f32,
            ) else {
                continue;
            };
            // A box face on the segment's own end (a grid filling its null box) is that end,
            // not a second boundary beside it: its jump would count twice (the smoke box's
            // records read vertical gradients 2.5× their differences).
            let near = interface_offset(t1.max(t0), o);
            for (t, inside) in [(f64::from(a), true), (f64::from(b), false)] {
                let t = t0 + t;
                let is_end = (inside && t <= t0 + near) || (!inside && t >= t1 - near);
                if !is_end {
                    out.push((t, m.box_face_normal((o + w * t).as_vec3()).as_dvec3()));
                }
            }
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        out
    }

    fn sigma_t(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
        let medium = self.medium_along(o, w, t);
        self.coefficients(medium, o + w * t).map_or([0.0; 3], |c| {
            [c.sigma_t.r, c.sigma_t.g, c.sigma_t.b].map(f64::from)
        })
    }

    fn step_extent(&self, o: DVec3, w: DVec3, t: f64, budget: f64) -> (f64, f64) {
        let Some(index) = self.medium_along(o, w, t) else {
            return (0.0, f64::INFINITY);
        };
        let m = &self.scene.media[index];
        let p = o + w * t;
        let here = self
            .coefficients(Some(index), p)
            .map_or(0.0, |c| f64::from(c.sigma_t.max_channel()));
        if m.homogeneous {
            return (here, f64::INFINITY);
        }
        // Up to where the optical depth of the grid's local majorants from p reaches the budget:
        // thin or empty cells are passed in one step, dense ones are not entered far. A step
        // begun on the grid's box (rounding may put p just outside it) is sized by the
        // majorants inside: sized by σ_t = 0 there, it strode the whole grid at one midpoint,
        // and the smoke box's gathers read their gradients 10–60 % off their differences. A
        // step begun well outside the box ends where the box begins.
        let (p32, w32) = (p.as_vec3(), w.as_vec3());
        let Some((a, b)) = m.clip(p32, w32, f32::MAX) else {
            return (here, f64::INFINITY);
        };
        let entry = f64::from(a);
        if entry > interface_offset(t, o) {
            return (here, t + entry);
        }
        let reached = m.majorant_depth_reached(p32, w32, a, b, budget);
        (here, reached.map_or(f64::INFINITY, |s| t + s))
    }

    fn sigma_t_gradient(&self, o: DVec3, w: DVec3, t: f64) -> [DVec3; 3] {
        let medium = self.medium_along(o, w, t);
        if medium.is_none_or(|m| self.scene.media[m].homogeneous) {
            return [DVec3::ZERO; 3];
        }
        match self.coefficients_with_gradients(medium, o + w * t) {
            Some((_, Some(g))) => g.sigma_t.map(|g| self.along_axes(g)),
            _ => [DVec3::ZERO; 3],
        }
    }

    fn source(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
        self.source_over(o, w, t, None)
    }

    fn step_source(&self, o: DVec3, w: DVec3, step: &StepExtent) -> [f64; 3] {
        self.source_over(o, w, step.middle(), Some(step))
    }

    fn source_gradient(&self, o: DVec3, w: DVec3, t: f64) -> [DVec3; 3] {
        self.source_gradient_over(o, w, t, None)
    }

    fn step_source_gradient(&self, o: DVec3, w: DVec3, step: &StepExtent) -> [DVec3; 3] {
        self.source_gradient_over(o, w, step.middle(), Some(step))
    }
}

#[cfg(test)]
mod tests {
    use super::{first_stratum, DVec3, GatherMedium, SceneMedium};
    use crate::testing::project_scene;
    use ircache_math::{Rng, Vec2};

    /// A march step begun where a gather ray enters the smoke's grid (its box is its null box:
    /// the entry lies on the box's face, which rounding may put just outside the grid) is sized
    /// by the grid's majorants ahead: the smoke's optical depth over it stays within the
    /// budget. Sized by σ_t = 0 at the face, such steps strode the whole grid at one midpoint.
    #[test]
    fn a_step_begun_on_a_grids_box_stays_within_its_budget() {
        let scene = project_scene("smoke-box", &[]);
        let view = SceneMedium::new(&scene, None, false, 1);
        let budget = 0.3;
        let mut rng = Rng::new(11, 3);
        let mut entered = 0;
        for _ in 0..400 {
            // From points on the back wall towards the plume, through the box's back face.
            let u = rng.next_2d();
            let o = DVec3::new(
                0.4 * f64::from(u.x) - 0.2,
                0.8 + 0.4 * f64::from(u.y),
                -0.99,
            );
            let u = rng.next_2d();
            let w = DVec3::new(
                0.8 * (f64::from(u.x) - 0.5),
                0.8 * (f64::from(u.y) - 0.5),
                1.0,
            )
            .normalize();
            let (s, _) = view.surface(o, w);
            let crossings = view.boundaries(o, w, s);
            let Some(&(t, _)) = crossings.first() else {
                continue;
            };
            let exit = crossings.get(1).map_or(s, |c| c.0);
            // The step may go on out of the box (or to a box in the smoke) where the majorants
            // ahead stay under the budget.
            let (_, extent) = view.step_extent(o, w, t, budget);
            let end = extent.min(exit);
            assert!(end > t, "{w}: step from {t} to {extent}");
            // The smoke's optical depth over the step, by fine midpoints.
            let n = 1000;
            let depth: f64 = (0..n)
                .map(|i| {
                    let x = t + (end - t) * (i as f64 + 0.5) / n as f64;
                    view.sigma_t(o, w, x)[0] * (end - t) / n as f64
                })
                .sum();
            assert!(
                depth <= budget * 1.001,
                "{w} from {o}: optical depth {depth} over the step {t}..{extent}"
            );
            entered += 1;
        }
        assert!(entered > 300, "{entered} rays entered the smoke");
    }

    /// The deeper paths' first draws: for a square count a grid of cells, else strips of the
    /// first coordinate; every point of the unit square lies in exactly one path's cell, and a
    /// path's draws stay in its own (so the paths of a gather ray are stratified, and one path
    /// draws as before).
    #[test]
    fn first_strata_partition_the_unit_square() {
        let mut rng = Rng::new(5, 9);
        for n in [1u32, 2, 3, 4, 9] {
            let side = (n as f32).sqrt().round() as u32;
            let cell = |v: Vec2| {
                if side * side == n {
                    (v.x * side as f32) as u32 + side * (v.y * side as f32) as u32
                } else {
                    (v.x * n as f32) as u32
                }
            };
            for _ in 0..2000 {
                let u = rng.next_2d();
                for k in 0..n {
                    let v = first_stratum(u, k, n);
                    assert!((0.0..1.0).contains(&v.x) && (0.0..1.0).contains(&v.y));
                    assert_eq!(cell(v), k, "n {n}: path {k} drew {v} from {u}");
                }
            }
            assert_eq!(
                first_stratum(Vec2::new(0.3, 0.7), 0, 1),
                Vec2::new(0.3, 0.7)
            );
        }
    }
}
