//! The one path-continuation routine: every integrator (`path`, `ic`) and every cache's gather
//! follows a path with it. At each vertex: emission found by the previous sample (with MIS),
//! light samples (see [`super::light_sampling`]), and the continuation through the BSDF, as
//! Mitsuba 3's `path` integrator does, with `max_depth` counting vertices the same way (so a
//! cached render with N bounces is path tracing at `max_depth` N + 2 with parts looked up); at
//! the last vertex, where they suffice, light samples stand alone
//! ([`super::light_sampling::light_samples_suffice`]).
//!
//! A cache plugs in through [`IndirectSource`]: at a vertex whose BSDF has a Lambertian part, it
//! may serve that part's indirect light as `k(wo) E / π` (E the cached irradiance); the path then
//! continues through the glossy part alone, and light samples are weighted against that part
//! only. Where it declines, the whole BSDF is sampled, as in path tracing.

use super::light_sampling::{
    light_samples_suffice, receiver, sample_lights, BsdfStrategy, DeferredShadows,
    EnvironmentServed, Selection, Shadows,
};
use super::{mis_weight, RayCounts};
use crate::irradiance_cache::environment::HeldEnvironment;
use crate::irradiance_cache::gather::ShadingPoint;
use crate::lights::Receiver;
use crate::sampler::{dims, Sampler};
use crate::scene::{Interaction, Scene};
use ircache_math::{Ray, Rgb, Vec3, INV_PI};

/// Where the Lambertian part of a vertex's indirect light may come from.
pub trait IndirectSource {
    /// Irradiance arriving at `sp` by indirect paths, for a vertex at `depth` (0: the first
    /// surface of a camera path), or `None` to trace it. Only asked where indirect light exists
    /// (`depth + 2 < max_depth`).
    fn irradiance(
        &mut self,
        scene: &Scene,
        sp: &ShadingPoint,
        depth: u32,
        sampler: &mut dyn Sampler,
        rays: &mut RayCounts,
    ) -> Option<Rgb>;

    /// Indirect light the glossy part of the BSDF at `sp` reflects towards `wo` (world, unit),
    /// from cached incoming radiance (radiance caching), or `None` to trace it. Only asked where
    /// indirect light exists and the Lambertian part needs nothing traced (served, or absent).
    fn glossy(&mut self, scene: &Scene, sp: &ShadingPoint, depth: u32, wo: Vec3) -> Option<Rgb> {
        let _ = (scene, sp, depth, wo);
        None
    }

    /// Which of what it serves at `sp` holds the environment's light too (records that hold
    /// it, `irradiance_cache::environment`): light samples of the environment then leave out
    /// the parts served.
    fn held_environment(&self, sp: &ShadingPoint) -> HeldEnvironment {
        let _ = sp;
        HeldEnvironment::None
    }

    /// Whether the irradiance [`Self::irradiance`] just gave at `sp` holds the environment's
    /// light (its direct light included): where records hold all of it, unless the source
    /// answered from something that holds only light after a bounce (a photon map).
    fn irradiance_holds_environment(&self, sp: &ShadingPoint) -> bool {
        self.held_environment(sp) == HeldEnvironment::All
    }

    /// Radiance assumed beyond the last bounce (Radiance's ambient value): what the Lambertian
    /// part reflects at a vertex where the depth runs out.
    fn ambient(&self) -> Rgb {
        Rgb::ZERO
    }

    /// True when caustics at the vertices it serves come from elsewhere (a caustic map): a
    /// gather's paths then leave out emitters reached through delta lobes alone. The map gives
    /// irradiance, so where [`Self::glossy`] serves a glossy lobe from such gathers, the path
    /// goes on through that lobe to trace the caustics it reflects (delta lobes alone onwards,
    /// counting only the emission they reach).
    fn caustics_served(&self) -> bool {
        false
    }

    /// False when it never serves anything (plain path tracing skips the Lambertian split).
    fn serves(&self) -> bool {
        true
    }

    /// False when the caller wants only what it serves ([`Self::took`]): the light samples,
    /// which add nothing to that, are left out.
    fn samples_lights(&self) -> bool {
        true
    }

    /// Told of each part of the path's radiance that came from what it served (irradiance,
    /// glossy light or the ambient value, with the path's throughput): the rest was traced.
    fn took(&mut self, light: Rgb) {
        let _ = light;
    }
}

/// No cache: plain path tracing.
pub struct Traced;

impl IndirectSource for Traced {
    fn irradiance(
        &mut self,
        _: &Scene,
        _: &ShadingPoint,
        _: u32,
        _: &mut dyn Sampler,
        _: &mut RayCounts,
    ) -> Option<Rgb> {
        None
    }

    fn serves(&self) -> bool {
        false
    }
}

/// Path settings.
#[derive(Clone, Copy, Debug)]
pub struct PathSettings {
    /// Longest path in vertices as Mitsuba counts them (1: emitters seen directly, 2: direct
    /// light, 3: one indirect bounce); `u32::MAX` for unbounded.
    pub max_depth: u32,
    /// Depth from which Russian roulette runs.
    pub rr_depth: u32,
    /// Light samples at the first vertex (one at later vertices).
    pub first_light_samples: u32,
}

/// How the path arrived at the vertex it is about to find: this decides the weight of the
/// emission found there.
#[derive(Clone, Copy, Debug)]
pub enum Arrival {
    /// A camera ray: emission counts fully, or not at all when emitters are hidden.
    Camera {
        /// Hide emitters seen directly.
        hide_emitters: bool,
    },
    /// A cache's gather ray: emission is left out (the direct term samples the lights).
    Gather,
    /// A BSDF sample from `from` with density `pdf` (`delta` for a delta lobe), made beside
    /// `light_samples` light samples: emission is weighted by MIS.
    Bsdf {
        /// The vertex the sample left, as its light samples saw it.
        from: Receiver,
        /// Its density.
        pdf: f32,
        /// From a delta lobe.
        delta: bool,
        /// Light samples taken at that vertex.
        light_samples: u32,
    },
}

impl Arrival {
    /// After a delta lobe's sample.
    #[inline]
    fn is_delta(&self) -> bool {
        matches!(self, Arrival::Bsdf { delta: true, .. })
    }

    /// The weight of emission found by this arrival: 1 or 0 for camera rays (emitters shown or
    /// hidden), 0 for gather rays, 1 after a delta lobe, else the power heuristic against the
    /// light samples taken at the vertex left, `light_pdf(that vertex)` being their density.
    #[inline]
    pub(crate) fn emission_weight(&self, light_pdf: impl FnOnce(Receiver) -> f32) -> f32 {
        match *self {
            Arrival::Camera { hide_emitters } => f32::from(u8::from(!hide_emitters)),
            Arrival::Gather => 0.0,
            Arrival::Bsdf { delta: true, .. } => 1.0,
            Arrival::Bsdf {
                from,
                pdf,
                light_samples,
                ..
            } => mis_weight(pdf, light_samples as f32 * light_pdf(from)),
        }
    }
}

/// A path about to find its next vertex.
#[derive(Clone, Copy, Debug)]
pub struct PathStart {
    /// The ray.
    pub ray: Ray,
    /// Depth of the vertex it will find (0 for a camera ray).
    pub depth: u32,
    /// Throughput so far.
    pub beta: Rgb,
    /// How it arrives.
    pub arrival: Arrival,
}

impl PathStart {
    /// A camera ray, about to find the path's first vertex.
    #[must_use]
    pub fn camera(ray: Ray, hide_emitters: bool) -> PathStart {
        PathStart {
            ray,
            depth: 0,
            beta: Rgb::ONE,
            arrival: Arrival::Camera { hide_emitters },
        }
    }
}

/// The first vertex of a path, where the caller has found it already.
#[derive(Clone, Copy, Debug)]
pub enum FirstVertex<'a> {
    /// Not yet: the path traces its ray.
    Trace,
    /// Embree's closest hit along the ray (`None`: it escapes), made an interaction in the
    /// path's own slot: built by the caller and moved in, its fields' separate stores were read
    /// back whole and stalled on store forwarding.
    Hit(Option<&'a ircache_embree::Hit>),
    /// The interaction itself (`None`: the ray escapes).
    Interaction(Option<&'a Interaction>),
}

/// Radiance arriving along `start.ray`, whose first intersection the caller may have traced
/// already (`first`, which is then used as the first vertex).
pub fn trace_path<S: Sampler + ?Sized, I: IndirectSource + ?Sized>(
    scene: &Scene,
    start: PathStart,
    first: FirstVertex,
    source: &mut I,
    settings: &PathSettings,
    sampler: &mut S,
    rays: &mut RayCounts,
) -> Rgb {
    trace_path_deferring(scene, start, first, source, settings, sampler, rays, None)
}

/// [`trace_path`], whose first vertex's light samples, with `deferred`, leave their shadow
/// rays and what they bring to it ([`DeferredShadows::resolve`] adds that later) instead of the
/// result.
#[allow(clippy::too_many_arguments)]
pub fn trace_path_deferring<S: Sampler + ?Sized, I: IndirectSource + ?Sized>(
    scene: &Scene,
    start: PathStart,
    first: FirstVertex,
    source: &mut I,
    settings: &PathSettings,
    sampler: &mut S,
    rays: &mut RayCounts,
    mut deferred: Option<&mut DeferredShadows>,
) -> Rgb {
    let PathStart {
        mut ray,
        mut depth,
        mut beta,
        mut arrival,
    } = start;
    // Distance from the camera along a camera path (caches size records by the pixel
    // footprint at its end); 0 on other paths.
    let from_camera = matches!(arrival, Arrival::Camera { .. });
    let mut travelled = 0.0f32;
    // Several light samples at the path's first vertex only (later vertices weigh less).
    let max_depth = settings.max_depth;
    let mut l = Rgb::ZERO;
    let mut eta = 1.0f32;
    let mut first = first;
    // A gather's path while it has left only through delta lobes: the emission it finds is a
    // caustic, which a caustic map serves instead where the source says so.
    let mut caustic_chain = matches!(arrival, Arrival::Gather) && source.caustics_served();
    // A camera path whose glossy light came from gathers that left the caustics out
    // ([`IndirectSource::caustics_served`]): on through delta lobes alone, counting only the
    // emission reached through them.
    let mut caustics_only = false;
    // Thin sheets met along the path (each crossing draws a dimension of its own).
    let mut crossings = 0u32;
    loop {
        if depth >= max_depth {
            break;
        }
        let traced;
        let hit = match std::mem::replace(&mut first, FirstVertex::Trace) {
            FirstVertex::Interaction(it) => it,
            FirstVertex::Hit(h) => {
                traced = h.map(|h| scene.interaction(&ray, h));
                traced.as_ref()
            }
            FirstVertex::Trace => {
                traced = scene.intersect(&ray);
                traced.as_ref()
            }
        };
        // Emission the path leaves out here: a gather's caustic, or on a caustics-only path
        // what a non-delta sample finds (the light samples beside it counted that in full).
        let left_out = caustic_chain || (caustics_only && !arrival.is_delta());
        // Borrowed, not moved out: a copy of the whole interaction right after `intersect`
        // wrote it field by field stalled on store forwarding (a tenth of this loop's time).
        let Some(it) = hit else {
            if scene.lights.has_environment() && !left_out {
                let w = arrival.emission_weight(|p| scene.lights.pdf_environment(p, ray.d));
                if w > 0.0 {
                    l += beta * scene.lights.environment_radiance(ray.d) * w;
                }
            }
            break;
        };
        let wo = -ray.d;
        let shape = &scene.shapes[it.shape as usize];
        if let Some(light) = shape.area_light.filter(|_| !left_out) {
            let le = scene
                .lights
                .area_radiance(light, it.p, it.frame.n, it.uv, wo, it.t);
            if !le.is_black() {
                let w = arrival.emission_weight(|from| {
                    scene
                        .lights
                        .pdf_area(light, it.prim, from.p, it.p, it.frame.n)
                });
                if w > 0.0 {
                    l += beta * le * w;
                }
            }
        }
        if scene.has_see_through && (shape.thin_sheet || shape.masked) {
            // A window pane or a mask: passed through without a bounce (light samples see
            // through it, `Scene::shadow_transmittance`, so the emission beyond keeps the weight
            // of the vertex before), mirrored by a pane, or a mask's surface met.
            match cross_see_through(
                scene,
                it,
                wo,
                (&mut beta, &mut arrival, &mut depth, &mut crossings),
                eta,
                settings,
                sampler,
                rays,
            ) {
                Crossing::On(next) => {
                    travelled += it.t;
                    ray = next;
                    continue;
                }
                Crossing::Stay => {}
                Crossing::End => break,
            }
        }
        if depth + 1 >= max_depth {
            break;
        }
        travelled += it.t;
        let bsdf = it.bsdf(&scene.materials[shape.material], ray.d);
        let wo_local = it.frame.to_local(wo);

        // The Lambertian part's indirect light from the cache, where it serves; the beyond-last
        // bounce ambient value where the depth runs out. Then the glossy part's, where cached
        // radiance serves it: the path ends here, its direct light left to the light samples.
        let mut strategy = BsdfStrategy::All;
        let mut all_served = false;
        let mut environment_served = EnvironmentServed::default();
        if source.serves() && !caustics_only && bsdf.has_smooth() {
            let k = bsdf.lambertian_albedo(wo_local);
            let indirect = depth + 2 < max_depth;
            let sp = indirect.then(|| {
                let mut sp = ShadingPoint::facing(*it, wo);
                sp.travelled = if from_camera { travelled } else { 0.0 };
                sp
            });
            let mut lambertian_served = k.is_black();
            if !k.is_black() {
                if let Some(sp) = &sp {
                    sampler.set_dimension(dims::vertex(depth, dims::CACHE));
                    if let Some(e) = source.irradiance(scene, sp, depth, sampler.as_dyn(), rays) {
                        // On a bump or normal map, the share of the perturbed lobe that light
                        // from above the surface reaches: the cache holds irradiance, not its
                        // directions.
                        let served = beta * k * e * (INV_PI * scene.perturbed_lambertian_share(it));
                        l += served;
                        source.took(served);
                        strategy = BsdfStrategy::Glossy;
                        lambertian_served = true;
                        if source.irradiance_holds_environment(sp) {
                            environment_served.lambertian = k;
                        }
                    }
                } else {
                    let served = beta * k * source.ambient();
                    l += served;
                    source.took(served);
                }
            }
            if let Some(sp) = sp.filter(|_| lambertian_served && bsdf.has_glossy()) {
                if let Some(glossy) = source.glossy(scene, &sp, depth, wo) {
                    l += beta * glossy;
                    source.took(beta * glossy);
                    all_served = true;
                    environment_served.glossy =
                        source.held_environment(&sp) != HeldEnvironment::None;
                }
            }
        }

        // Light samples.
        let ne = if depth == start.depth {
            settings.first_light_samples.max(1)
        } else {
            1
        };
        let last = depth + 2 >= max_depth;
        // Served glossy light without its caustics: the path goes on through the glossy lobe
        // for them alone, and the light samples here count in full.
        let trace_caustics = all_served && !last && source.caustics_served();
        let continues = caustics_only
            || trace_caustics
            || (!all_served
                && (!last
                    || (scene.has_hittable_emitters
                        && !light_samples_suffice(scene, &bsdf, last))));
        if !caustics_only && source.samples_lights() {
            let shadows = match deferred.as_deref_mut().filter(|_| depth == start.depth) {
                Some(d) => Shadows::Deferred(d, beta),
                None => Shadows::Traced,
            };
            l += beta
                * sample_lights(
                    scene,
                    it,
                    &bsdf,
                    wo_local,
                    (ne, Selection::Chosen),
                    (strategy, u32::from(continues && !trace_caustics)),
                    environment_served,
                    depth,
                    sampler,
                    rays,
                    shadows,
                );
        }
        if !continues || (strategy == BsdfStrategy::Glossy && !bsdf.has_glossy()) {
            break;
        }

        // The BSDF sample that continues the path.
        let Some((bs, wi)) =
            sample_continuation(scene, it, &bsdf, wo_local, strategy, depth, sampler)
        else {
            break;
        };
        if caustics_only && !bs.delta {
            break;
        }
        caustics_only |= trace_caustics;
        beta *= bs.weight;
        eta *= bs.eta;
        caustic_chain &= bs.delta;
        arrival = Arrival::Bsdf {
            from: receiver(it, &bsdf, wo_local),
            pdf: bs.pdf,
            delta: bs.delta,
            light_samples: ne,
        };
        ray = scene.spawn_ray(it, wi);
        rays.bounce += 1;
        if !count_and_roulette(&mut depth, &mut beta, eta, settings.rr_depth, sampler) {
            break;
        }
    }
    l
}

/// What a path does at a surface it may pass through ([`cross_see_through`]).
pub(crate) enum Crossing {
    /// On beyond it (through a pane or a mask's open part, or mirrored by a pane).
    On(Ray),
    /// The surface is met: the vertex is shaded with the mask's nested BSDF.
    Stay,
    /// The path ends here.
    End,
}

/// At the thin sheet or masked surface `it`, met by a path arriving from `wo`: the choice drawn
/// from the sampler's dimension of this crossing. A pane is crossed (no bounce) or mirrors the
/// path (a delta bounce, counted, with Russian roulette) with probability R'; a mask is met
/// with probability its opacity there, else crossed. Out of line: scenes without either run
/// the loop as before (cold: laid out away from the loop, which ran 3 % slower on the Cornell
/// box with this branch inline).
#[allow(clippy::too_many_arguments)]
#[cold]
#[inline(never)]
pub(crate) fn cross_see_through<S: Sampler + ?Sized>(
    scene: &Scene,
    it: &Interaction,
    wo: Vec3,
    (beta, arrival, depth, crossings): (&mut Rgb, &mut Arrival, &mut u32, &mut u32),
    eta: f32,
    settings: &PathSettings,
    sampler: &mut S,
    rays: &mut RayCounts,
) -> Crossing {
    *crossings += 1;
    if *crossings > crate::scene::MAX_SHEET_CROSSINGS {
        return Crossing::End;
    }
    sampler.set_dimension(dims::sheet(*depth, *crossings));
    let u = sampler.next_1d();
    let Some(passage) = scene.see_through(it, wo, u) else {
        return Crossing::Stay;
    };
    if !passage.reflected {
        *beta *= passage.weight;
        return Crossing::On(scene.spawn_ray(it, passage.d));
    }
    if *depth + 1 >= settings.max_depth {
        return Crossing::End;
    }
    *beta *= passage.weight;
    *arrival = Arrival::Bsdf {
        from: it.p.into(),
        pdf: passage.prob,
        delta: true,
        light_samples: 0,
    };
    rays.bounce += 1;
    if count_and_roulette(depth, beta, eta, settings.rr_depth, sampler) {
        Crossing::On(scene.spawn_ray(it, passage.d))
    } else {
        Crossing::End
    }
}

/// The sample of `strategy`'s part of the BSDF that continues a path at vertex `depth` (its
/// dimensions of the sampler), with its world direction; `None` where there is none or where
/// the geometric and shading hemispheres disagree (light leaks). Inlined: its sample returned
/// through memory stalled the caller on store forwarding.
#[inline(always)]
pub(crate) fn sample_continuation<S: Sampler + ?Sized>(
    scene: &Scene,
    it: &Interaction,
    bsdf: &crate::bsdf::Bsdf,
    wo_local: Vec3,
    strategy: BsdfStrategy,
    depth: u32,
    sampler: &mut S,
) -> Option<(crate::bsdf::BsdfSample, Vec3)> {
    sampler.set_dimension(dims::vertex(depth, dims::BSDF));
    let u_lobe = if bsdf.is_diffuse_only() {
        sampler.skip_1d();
        0.0
    } else {
        sampler.next_1d()
    };
    let u = sampler.next_2d();
    let mut bs = strategy.sample(bsdf, wo_local, u_lobe, u)?;
    let wi = it.frame.from_local(bs.wi);
    if (wi.dot(it.ng) > 0.0) != (bs.wi.z > 0.0) && !bs.delta {
        return None;
    }
    bs.weight *= scene.perturbed_shadowing(it, wi);
    Some((bs, wi))
}

/// Counts the vertex a path just left (`depth` + 1) and plays Russian roulette from `rr_depth`
/// on with survival min(max(β)·η², 0.95), as Mitsuba 3; false when the path ends (also when
/// the weight is zero or not finite).
pub(crate) fn count_and_roulette<S: Sampler + ?Sized>(
    depth: &mut u32,
    beta: &mut Rgb,
    eta: f32,
    rr_depth: u32,
    sampler: &mut S,
) -> bool {
    sampler.set_dimension(dims::vertex(*depth, dims::ROULETTE));
    *depth += 1;
    let beta_max = beta.max_channel();
    if beta_max <= 0.0 || !beta_max.is_finite() {
        return false;
    }
    if *depth >= rr_depth {
        let q = (beta_max * eta * eta).min(0.95);
        if sampler.next_1d() >= q {
            return false;
        }
        *beta /= q;
    }
    true
}
