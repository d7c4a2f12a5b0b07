//! Volumetric path tracing, the reference in scenes with participating media, step for step
//! Mitsuba 3's `volpath`: free-flight sampling in the ray's medium ([`crate::media::tracking`]),
//! next-event estimation at medium and surface vertices with transmittance through `null`
//! boundaries, MIS (power heuristic) between light samples and phase or BSDF samples, Russian
//! roulette from `rr_depth`. `max_depth` counts scattering vertices in the medium and on
//! surfaces alike (1: emitters seen directly, 2: direct light); crossing a `null` boundary does
//! not count. Medium emission (an ircache extension) is gathered along every segment.

use super::equiangular::Segment;
use super::light_sampling::BsdfStrategy;
use super::path_continuation::{
    count_and_roulette, cross_see_through, Arrival, Crossing, PathSettings,
};
use super::{mis_weight, RayCounts};
use crate::irradiance_cache::gather::ShadingPoint;
use crate::media::tracking::{
    across_boundary, medium_after, sample_flight, transmittance_along, Flight,
};
use crate::media::Phase;
use crate::sampler::{dims, Sampler};
use crate::scene::{Interaction, Scene};
use ircache_embree::Hit;
use ircache_math::{Ray, Rgb, Rng, Vec2, Vec3};

/// Parameters of the volumetric path tracer.
#[derive(Clone, Debug)]
pub struct VolPathIntegrator {
    /// Longest path (−1: unbounded).
    pub max_depth: i32,
    /// Depth from which Russian roulette runs.
    pub rr_depth: u32,
    /// Hide emitters seen directly by the camera.
    pub hide_emitters: bool,
    /// Records serving the first surface's diffuse indirect light (the `ic` integrator in a
    /// media scene; see [`crate::media_cache::cache`]).
    pub cache: Option<std::sync::Arc<crate::media_cache::cache::MediaCache>>,
    /// Camera rays marched through media instead of tracked (the cache's pixel pass; see
    /// [`super::media_march`]); `None`: Mitsuba's `volpath`.
    pub camera_march: Option<super::media_march::CameraMarch>,
    /// Light samples at a first surface the media cache serves (`--direct-samples`).
    pub first_light_samples: u32,
    /// Volumetric records serving the in-scattered indirect light at the march's points.
    pub volume_records: Option<std::sync::Arc<crate::media_cache::volume_records::VolumeCache>>,
    /// Caustics at the paths' Lambertian surfaces from photons (see [`Self::trace`]).
    pub caustics: Option<std::sync::Arc<crate::photon_map::ServingMap>>,
    /// The light after a bounce at the paths' Lambertian surfaces from photons (the records'
    /// paths, behind a gather; see [`Self::trace`]). Never for camera paths: a density
    /// estimate seen directly shows its blotches.
    pub global: Option<std::sync::Arc<crate::photon_map::ServingMap>>,
}

/// Where a light sample is taken.
pub(crate) enum Vertex<'a> {
    /// A surface point with its BSDF, outgoing direction in the local frame.
    Surface(&'a Interaction, &'a crate::bsdf::Bsdf, Vec3),
    /// A point in a medium, reached along `d`, with the medium's phase function and, where its
    /// distance was drawn on a segment that also takes equiangular samples, that segment.
    Medium(Vec3, Vec3, Phase, Option<&'a Segment>),
}

/// A path about to find its next vertex.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PathState {
    /// The ray.
    pub ray: Ray,
    /// The medium the ray starts in.
    pub medium: Option<usize>,
    /// Throughput so far.
    pub beta: Rgb,
    /// Depth of the vertex it will find.
    pub depth: u32,
    /// How it arrives there (the weight of emission found).
    pub arrival: Arrival,
    /// It left a Lambertian vertex whose caustics a caustic map served, through delta lobes
    /// alone since, and has not scattered in a medium: the emission it finds is left out.
    pub caustic_chain: bool,
}

impl VolPathIntegrator {
    /// Mitsuba 3's `volpath` at `max_depth` (−1: unbounded), Russian roulette from depth 5:
    /// camera rays tracked, no cache.
    #[must_use]
    pub fn plain(max_depth: i32) -> Self {
        VolPathIntegrator {
            max_depth,
            rr_depth: 5,
            hide_emitters: false,
            cache: None,
            camera_march: None,
            first_light_samples: 1,
            volume_records: None,
            caustics: None,
            global: None,
        }
    }

    /// The `max_depth` of `bounces` indirect bounces (`-ab` N: N + 2; unbounded: −1).
    #[must_use]
    pub fn depth_of_bounces(bounces: u32) -> i32 {
        i32::try_from(bounces.saturating_add(2)).unwrap_or(-1)
    }

    /// Radiance arriving along the camera ray `ray`, whose closest hit `first_hit` the caller
    /// traced.
    pub fn li(
        &self,
        scene: &Scene,
        ray: &Ray,
        first_hit: Option<&Hit>,
        sampler: &mut dyn Sampler,
        rays: &mut RayCounts,
    ) -> Rgb {
        sampler.set_dimension(dims::vertex(0, dims::CACHE));
        let mut rng = Rng::new(sampler.next_key(), 0x766f_6c70);
        let arrival = Arrival::Camera {
            hide_emitters: self.hide_emitters,
        };
        if let Some(march) = self.camera_march {
            return super::media_march::li(
                self, march, scene, ray, first_hit, arrival, sampler, &mut rng, rays,
            );
        }
        let start = PathState {
            ray: *ray,
            medium: scene.camera_medium,
            beta: Rgb::ONE,
            depth: 0,
            arrival,
            caustic_chain: false,
        };
        self.trace(
            scene,
            start,
            Some(first_hit.copied()),
            false,
            sampler,
            &mut rng,
            rays,
        )
        .all
    }

    /// Caustic irradiance at the surface `it` on the side of `n` from photons that a path
    /// whose vertex there has depth `depth` may take (b bounces end a path of depth + b + 2
    /// vertices); zero without a caustic map.
    fn caustic_irradiance(&self, it: &Interaction, n: Vec3, depth: u32) -> Rgb {
        let bounces = self.depth_limit().saturating_sub(depth + 2);
        match &self.caustics {
            Some(c) if bounces > 0 => {
                c.irradiance(it.p, n, crate::photon_map::bounce_limit(bounces))
            }
            _ => Rgb::ZERO,
        }
    }

    /// The largest depth as a count (−1: unbounded).
    pub(crate) fn depth_limit(&self) -> u32 {
        u32::try_from(self.max_depth).unwrap_or(u32::MAX)
    }

    /// Radiance arriving along `start.ray`, whose closest hit the caller may have traced
    /// (`first`); with `skip_first_medium` the medium before that hit is left out (the caller
    /// accounted for it: [`super::media_march`]).
    ///
    /// With a caustic map, a vertex whose BSDF is Lambertian alone (or whose Lambertian part
    /// the media cache serves) takes its caustics from the map, photons that reached it through
    /// delta lobes alone without scattering in a medium (Jensen's split; see
    /// [`crate::photon_map::trace`]), and the path on from it leaves out the emission it finds
    /// in the same way; any other vertex, and a scattering in a medium, ends that rule.
    ///
    /// The parts of the light that the path's last two vertices (depths `max_depth` − 1 and − 2)
    /// emit are also kept apart ([`PathLight::last`]): what the same path brings with one or two
    /// vertices fewer allowed is the difference ([`PathLight::shorter`]). Light from the media cache's records and the caustic map is counted in
    /// full alone: the part is exact for an integrator without them.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn trace(
        &self,
        scene: &Scene,
        start: PathState,
        first: Option<Option<Hit>>,
        skip_first_medium: bool,
        sampler: &mut dyn Sampler,
        rng: &mut Rng,
        rays: &mut RayCounts,
    ) -> PathLight {
        let max_depth = self.depth_limit();
        let mut last = [Rgb::ZERO; SHORTER];
        // Light emitted at vertex `at`: counted in full, and apart where `at` is one of the last.
        let mut add = |l: &mut Rgb, value: Rgb, at: u32| {
            *l += value;
            for (k, part) in last.iter_mut().enumerate() {
                if at.saturating_add(k as u32 + 1) == max_depth {
                    *part += value;
                }
            }
        };
        let PathState {
            mut ray,
            mut medium,
            mut beta,
            mut depth,
            mut arrival,
            mut caustic_chain,
        } = start;
        let mut l = Rgb::ZERO;
        let mut eta = 1.0f32;
        let mut first = first;
        let mut skip_medium = skip_first_medium;
        let mut crossings = 0u32;
        loop {
            if depth >= max_depth {
                break;
            }
            let hit = match first.take() {
                Some(h) => h,
                None => {
                    rays.bounce += 1;
                    scene.accel.intersect(&ray)
                }
            };
            let t_hit = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
            if let Some(m) = medium.filter(|_| !std::mem::take(&mut skip_medium)) {
                let med = &scene.media[m];
                let sample_emitters = scene.samples_lights_in(m);
                // Point and spot lights' single scattering by equiangular sampling, weighed
                // against the light sample at the free flight's scattering.
                let segment = (depth + 1 < max_depth && sample_emitters)
                    .then(|| Segment::for_flight(scene, m, &ray, t_hit))
                    .flatten();
                if let Some(segment) = &segment {
                    sampler.set_dimension(dims::equiangular(depth, crossings));
                    let u = (sampler.next_1d(), sampler.next_1d());
                    add(
                        &mut l,
                        beta * segment.estimate(scene, u, rng, rays),
                        depth + 1,
                    );
                }
                let mut emitted = Rgb::ZERO;
                let flight = sample_flight(med, ray.o, ray.d, t_hit, &mut beta, &mut emitted, rng);
                add(&mut l, emitted, depth);
                match flight {
                    Flight::Absorbed => break,
                    Flight::Passed => {}
                    Flight::Scattered { t, .. } => {
                        caustic_chain = false;
                        let p = ray.at(t);
                        if depth + 1 < max_depth && sample_emitters {
                            let vertex = Vertex::Medium(p, ray.d, med.phase, segment.as_ref());
                            let direct = sample_light(
                                scene,
                                &vertex,
                                medium,
                                depth,
                                Some(Weighing::ONE),
                                sampler,
                                rng,
                                rays,
                            );
                            add(&mut l, beta * direct, depth + 1);
                        }
                        sampler.set_dimension(dims::vertex(depth, dims::BSDF));
                        sampler.skip_1d();
                        let (w, pdf) = med.phase.sample(ray.d, sampler.next_2d());
                        arrival = Arrival::Bsdf {
                            from: p.into(),
                            pdf,
                            delta: false,
                            light_samples: u32::from(sample_emitters),
                        };
                        ray = Ray::new(p, w);
                        if !count_and_roulette(&mut depth, &mut beta, eta, self.rr_depth, sampler) {
                            break;
                        }
                        continue;
                    }
                }
            }
            let Some(hit) = hit else {
                if scene.lights.has_environment() && !caustic_chain {
                    let w = arrival.emission_weight(|p| scene.lights.pdf_environment(p, ray.d));
                    if w > 0.0 {
                        let le = scene.lights.environment_radiance(ray.d);
                        add(&mut l, beta * le * w, depth);
                    }
                }
                break;
            };
            let it = scene.interaction(&ray, &hit);
            let shape = &scene.shapes[it.shape as usize];
            if shape.null {
                // An index-matched boundary: the ray goes on, in the medium beyond.
                let Some(next) = across_boundary(scene, &it, ray.d, medium, &mut crossings) else {
                    break;
                };
                (ray, medium) = next;
                continue;
            }
            if scene.has_see_through && (shape.thin_sheet || shape.masked) {
                // A window pane or a mask, as in `path`.
                let settings = PathSettings {
                    max_depth,
                    rr_depth: self.rr_depth,
                    first_light_samples: 1,
                };
                match cross_see_through(
                    scene,
                    &it,
                    -ray.d,
                    (&mut beta, &mut arrival, &mut depth, &mut crossings),
                    eta,
                    &settings,
                    sampler,
                    rays,
                ) {
                    Crossing::On(next) => {
                        medium = medium_after(shape.media, it.ng, next.d, medium);
                        ray = next;
                        continue;
                    }
                    Crossing::Stay => {}
                    Crossing::End => break,
                }
            }
            let wo = -ray.d;
            if let Some(light) = shape.area_light.filter(|_| !caustic_chain) {
                let le = scene
                    .lights
                    .area_radiance(light, it.p, it.frame.n, it.uv, wo, it.t);
                if !le.is_black() {
                    let w = arrival.emission_weight(|from| {
                        scene
                            .lights
                            .pdf_area(light, it.prim, from.p, it.p, it.frame.n)
                    });
                    add(&mut l, beta * le * w, depth);
                }
            }
            if depth + 1 >= max_depth {
                break;
            }
            let bsdf = it.bsdf(&scene.materials[shape.material], ray.d);
            let wo_local = it.frame.to_local(wo);
            // The first surface's Lambertian indirect light from the media cache, where it
            // serves; a purely Lambertian surface then ends the path with its light samples
            // alone, a glossy part goes on by its own samples, the light samples weighed
            // against them (`path`'s split, [`super::path_continuation`]).
            let mut strategy = BsdfStrategy::All;
            let mut light_samples = 1;
            if let Some(cache) = self.cache.as_ref() {
                let k = bsdf.lambertian_albedo(wo_local);
                let sp = ShadingPoint::facing(it, wo);
                let served = (!k.is_black())
                    .then(|| cache.irradiance(depth, it.p, sp.n, sp.n_bump))
                    .flatten();
                if let Some(e) = served {
                    let vertex = Vertex::Surface(&it, &bsdf, wo_local);
                    let glossy = bsdf.has_glossy();
                    // Several light samples here (`--direct-samples`): the lattice shifted by
                    // the sampler's numbers, so the first stays stratified across the pixel.
                    sampler.set_dimension(dims::vertex(depth, dims::LIGHT));
                    let (u_sel, u) = (sampler.next_1d(), sampler.next_2d());
                    let shift = [u_sel, u.x, u.y];
                    let n = self.first_light_samples.max(1);
                    let weighing = glossy.then_some(Weighing {
                        strategy: BsdfStrategy::Glossy,
                        samples: n,
                    });
                    let mut direct = Rgb::ZERO;
                    for i in 0..n {
                        let u = super::media_march::lattice_point(shift, i);
                        direct += light_sample_with(scene, &vertex, medium, weighing, u, rng, rays);
                    }
                    add(&mut l, beta * direct / n as f32, depth + 1);
                    let caustic = self.caustic_irradiance(&it, sp.n, depth);
                    l += beta * k * (e + caustic) * ircache_math::INV_PI;
                    if !glossy {
                        break;
                    }
                    strategy = BsdfStrategy::Glossy;
                    light_samples = n;
                }
            }
            // With a global map, a Lambertian vertex the cache did not serve takes the light
            // after a bounce from it and ends the path, its light samples alone.
            let photons = self
                .global
                .as_ref()
                .filter(|_| strategy == BsdfStrategy::All)
                .and_then(|map| {
                    let bounces = max_depth.saturating_sub(depth + 2);
                    let b = crate::photon_map::bounce_limit(bounces);
                    (bounces > 0)
                        .then(|| photon_reflected(scene, map, &it, &bsdf, ray.d, it.t, b))
                        .flatten()
                });
            // Caustics from the map at a Lambertian vertex the cache did not serve (the global
            // map's photons hold them where it serves).
            let mut caustics_served = false;
            if strategy == BsdfStrategy::All
                && photons.is_none()
                && self.caustics.is_some()
                && bsdf.is_diffuse_only()
            {
                let k = bsdf.lambertian_albedo(wo_local);
                let n = ShadingPoint::facing(it, wo).n;
                l += beta * k * self.caustic_irradiance(&it, n, depth) * ircache_math::INV_PI;
                caustics_served = true;
            }
            if strategy == BsdfStrategy::All {
                // Without media, the last light samples stand alone where `path`'s do (a medium
                // would emit or scatter along the last ray, which must then be traced); so do
                // those of a vertex the global map serves.
                let alone = photons.is_some()
                    || (!scene.has_media()
                        && super::light_sampling::light_samples_suffice(
                            scene,
                            &bsdf,
                            depth + 2 >= max_depth,
                        ));
                if bsdf.has_smooth() && !scene.lights.is_empty() {
                    let vertex = Vertex::Surface(&it, &bsdf, wo_local);
                    let weighing = (!alone).then_some(Weighing::ONE);
                    let direct =
                        sample_light(scene, &vertex, medium, depth, weighing, sampler, rng, rays);
                    add(&mut l, beta * direct, depth + 1);
                }
                if let Some((all, last_parts)) = photons {
                    l += beta * all;
                    for (part, photons) in last.iter_mut().zip(last_parts) {
                        *part += beta * photons;
                    }
                    break;
                }
                if alone {
                    break;
                }
            }
            let Some((bs, wi)) = super::path_continuation::sample_continuation(
                scene, &it, &bsdf, wo_local, strategy, depth, sampler,
            ) else {
                break;
            };
            beta *= bs.weight;
            eta *= bs.eta;
            caustic_chain = caustics_served || (caustic_chain && bs.delta);
            arrival = Arrival::Bsdf {
                from: it.p.into(),
                pdf: bs.pdf,
                delta: bs.delta,
                light_samples,
            };
            medium = medium_after(shape.media, it.ng, wi, medium);
            ray = scene.spawn_ray(&it, wi);
            if !count_and_roulette(&mut depth, &mut beta, eta, self.rr_depth, sampler) {
                break;
            }
        }
        PathLight { all: l, last }
    }
}

/// What the surface `it`, whose BSDF `bsdf` is Lambertian alone, reflects towards `-d` of the
/// light that reaches it after a bounce or more, from the global map's photons of up to
/// `bounces` bounces: `k E/π` (Jensen's cached final gather), and apart the parts of the photons
/// of exactly `bounces` and `bounces` − 1 bounces, whose paths end at the last and the last but
/// one vertex a path may take ([`PathLight::last`]). `None` for any other BSDF, and where `it` lies nearer to the vertex
/// before it (`distance`) than the estimate's disc is wide (Jensen's rule for short gather rays,
/// as [`crate::irradiance_cache::IrradianceCache::photon_irradiance`]).
pub(crate) fn photon_reflected(
    scene: &Scene,
    map: &crate::photon_map::ServingMap,
    it: &Interaction,
    bsdf: &crate::bsdf::Bsdf,
    d: Vec3,
    distance: f32,
    bounces: u16,
) -> Option<(Rgb, [Rgb; SHORTER])> {
    if !bsdf.is_diffuse_only() {
        return None;
    }
    // The side the ray arrives on, as photons keep theirs.
    let n = if it.frame.n.dot(d) < 0.0 {
        it.frame.n
    } else {
        -it.frame.n
    };
    let ([e, fewer, fewer_2], radius) = map.irradiance_by_last_bounces(it.p, n, bounces);
    if distance < crate::irradiance_cache::gather::SHORT_RAY * radius {
        return None;
    }
    let k = bsdf.lambertian_albedo(it.frame.to_local(-d))
        * (ircache_math::INV_PI * scene.perturbed_lambertian_share(it));
    Some((k * e, [k * (e - fewer), k * (fewer - fewer_2)]))
}

/// How many of a path's last vertices [`PathLight`] keeps apart.
pub(crate) const SHORTER: usize = 2;

/// A path's light, and the parts of it its last allowed vertices emit.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PathLight {
    /// All of it.
    pub all: Rgb,
    /// What the vertices at depth `max_depth` − 1 and `max_depth` − 2 emit (or the light
    /// samples before them take).
    pub last: [Rgb; SHORTER],
}

impl PathLight {
    /// The light of the same path with `k` ≤ [`SHORTER`] vertices fewer allowed.
    #[must_use]
    pub fn shorter(&self, k: usize) -> Rgb {
        self.last[..k].iter().fold(self.all, |l, &part| l - part)
    }
}

/// How a light sample is weighed against the vertex's own phase or BSDF sample (power
/// heuristic): the part of the BSDF that sample draws from (a phase function's is the whole)
/// and the light samples taken beside it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Weighing {
    /// The part the vertex's sample draws.
    pub strategy: BsdfStrategy,
    /// Light samples at the vertex.
    pub samples: u32,
}

impl Weighing {
    /// One light sample beside a sample of the whole BSDF or phase function.
    pub const ONE: Weighing = Weighing {
        strategy: BsdfStrategy::All,
        samples: 1,
    };
}

/// One light sample at `vertex` from the sampler's dimensions of vertex `depth`; see
/// [`light_sample_with`].
#[allow(clippy::too_many_arguments)]
fn sample_light(
    scene: &Scene,
    vertex: &Vertex,
    medium: Option<usize>,
    depth: u32,
    weighing: Option<Weighing>,
    sampler: &mut dyn Sampler,
    rng: &mut Rng,
    rays: &mut RayCounts,
) -> Rgb {
    sampler.set_dimension(dims::vertex(depth, dims::LIGHT));
    let u_sel = sampler.next_1d();
    let u = sampler.next_2d();
    light_sample_with(scene, vertex, medium, weighing, (u_sel, u), rng, rays)
}

/// One light sample at `vertex` (in `medium`, on the side the light lies for a surface) drawn
/// with `u` (light choice, position), with transmittance through media and `null` boundaries,
/// weighted against the vertex's phase or BSDF sample by the power heuristic (`weighing`: where
/// that sample draws the glossy part alone, the Lambertian part's light counts in full), or
/// alone where no such sample follows (`None`).
pub(crate) fn light_sample_with(
    scene: &Scene,
    vertex: &Vertex,
    medium: Option<usize>,
    weighing: Option<Weighing>,
    (u_sel, u): (f32, Vec2),
    rng: &mut Rng,
    rays: &mut RayCounts,
) -> Rgb {
    let p = match vertex {
        Vertex::Surface(it, ..) => it.p,
        Vertex::Medium(p, ..) => *p,
    };
    let Some(ls) = scene.lights.sample(p, u_sel, u) else {
        return Rgb::ZERO;
    };
    if ls.pdf <= 0.0 {
        return Rgb::ZERO;
    }
    let strategy = weighing.map_or(BsdfStrategy::All, |w| w.strategy);
    // The value, the part of it the vertex's own sample also reaches, and that sample's density.
    let (f, traced, pdf, ray, medium) = match *vertex {
        Vertex::Surface(it, bsdf, wo) => {
            let wi = it.frame.to_local(ls.wi);
            let shadowing = scene.perturbed_shadowing(it, ls.wi);
            let f = bsdf.eval(wo, wi) * shadowing;
            if f.is_black() {
                return Rgb::ZERO;
            }
            let traced = match strategy {
                BsdfStrategy::All => f,
                BsdfStrategy::Glossy => bsdf.eval_glossy(wo, wi) * shadowing,
            };
            let shape = &scene.shapes[it.shape as usize];
            let medium = medium_after(shape.media, it.ng, ls.wi, medium);
            (
                f,
                traced,
                strategy.pdf(bsdf, wo, wi),
                scene.shadow_ray(it, ls.wi, ls.distance),
                medium,
            )
        }
        Vertex::Medium(p, d, phase, _) => {
            let value = phase.eval(d, ls.wi);
            let ray = scene.shadow_ray_at(p, None, ls.wi, ls.distance);
            (Rgb::splat(value), Rgb::splat(value), value, ray, medium)
        }
    };
    let tr = transmittance_along(scene, ray, medium, rng, rays);
    if tr.is_black() {
        return Rgb::ZERO;
    }
    let (weighted, w) = match weighing {
        Some(Weighing { samples, .. }) if !ls.is_delta => {
            let w = mis_weight(samples as f32 * ls.pdf, pdf);
            match strategy {
                BsdfStrategy::All => (f, w),
                BsdfStrategy::Glossy => ((f - traced * (1.0 - w)).max(Rgb::ZERO), 1.0),
            }
        }
        _ => (f, 1.0),
    };
    // A point or spot light's sample at a distance drawn on a segment that also takes
    // equiangular samples of it.
    let w = match vertex {
        Vertex::Medium(.., Some(segment)) if ls.is_delta => {
            w * segment.distance_weight(scene, (p - segment.o).dot(segment.d), &ls)
        }
        _ => w,
    };
    weighted * tr * ls.radiance * (w / ls.pdf)
}
