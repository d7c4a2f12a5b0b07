//! Emitters with importance sampling, for next-event estimation and multiple importance sampling,
//! with Mitsuba 3's conventions.
//!
//! One file per kind: [`area`] (emitting triangle meshes), [`sphere`] (emitting analytic spheres),
//! [`point`], [`spot`], [`directional`], [`environment`] (`constant` and `envmap`). [`LightSet`]
//! gathers them, selects one per sample and converts every density to solid angle at the
//! reference point, including the selection probability.
//!
//! Conventions (Mitsuba 3):
//! - Area emitters are one-sided: they emit on the side of the shading normal only
//!   ([`LightSet::area_radiance`]); a sphere with `flip_normals` emits inwards.
//! - Each emitting shape is one emitter, as is each point, spot, directional, constant and envmap
//!   emitter. One is selected per sample in proportion to an estimate of its contribution at the
//!   reference point ([`selection`]), not uniformly as Mitsuba 3's `Scene::sample_emitter` does.
//! - All environment emitters (normally at most one) are treated as a single environment: a sample
//!   drawn from any of them reports the *total* environment radiance along its direction and the
//!   mixture density [`LightSet::pdf_environment`] (each weighted by its selection probability),
//!   which is exactly what a BSDF-sampled escaping
//!   ray sees, so MIS weights agree on both sides.
//! - Samples that cannot contribute (back side of a one-sided emitter, outside a spot's cone,
//!   black environment direction, degenerate geometry) are reported as `None` rather than as a
//!   zero-radiance sample, so no shadow ray is wasted on them.
//!
//! Per-sample methods do not allocate.

pub mod area;
pub mod directional;
pub mod emission;
pub mod environment;
pub mod point;
pub mod rectangle;
pub mod selection;
pub mod sphere;
pub mod spot;

use area::MeshLight;
use directional::DirectionalLight;
use emission::{distant_origin, EmissionSample, Targets};
use environment::{ConstantLight, EnvmapLight};
use ircache_math::sampling::{
    square_to_cosine_hemisphere, square_to_uniform_sphere, Distribution1D,
};
use ircache_math::{Frame, Rgb, Vec2, Vec3};
use ircache_scene::{EmitterDesc, Geometry, SceneDesc, SurfacePattern};
use point::PointLight;
use selection::LightBound;
use sphere::SphereLight;
use spot::SpotLight;
use std::sync::Arc;

/// Converts an area density to a solid-angle density at a reference point (PBRT 3rd ed. eq. 5.6):
/// `p_ω = p_A · d² / |cos θ_light|`, infinite when the emitter is seen edge-on.
#[inline]
#[must_use]
pub fn solid_angle_pdf(pdf_area: f32, dist2: f32, cos_light: f32) -> f32 {
    pdf_area * dist2 / cos_light.abs()
}

/// True for a finite, strictly positive value (false for NaN).
#[inline]
#[must_use]
pub fn is_positive_finite(x: f32) -> bool {
    x > 0.0 && x.is_finite()
}

/// A light sample for next-event estimation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit world direction from the reference point towards the light.
    pub wi: Vec3,
    /// Distance to the sampled point on the light; `f32::INFINITY` for distant lights.
    pub distance: f32,
    /// Arriving radiance for area and environment lights, `I/d²` (times the spot falloff) for
    /// point and spot lights, irradiance for directional lights; *not* divided by `pdf`.
    pub radiance: Rgb,
    /// Solid-angle density including the light selection probability; for delta lights, the
    /// selection probability alone.
    pub pdf: f32,
    /// Point, spot or directional light (no MIS with BSDF sampling possible).
    pub is_delta: bool,
    /// Index of the light in the set.
    pub light: u32,
    /// The emitter's unit geometric normal at the sampled point, on either side; zero for
    /// point, spot and distant lights (what differentiating the sample with its point held
    /// needs: `media_cache::scene_medium`).
    pub normal: Vec3,
}

/// One emitter.
#[derive(Clone, Debug)]
enum Light {
    Mesh(MeshLight),
    Sphere(SphereLight),
    Point(PointLight),
    Spot(SpotLight),
    Directional(DirectionalLight),
    Constant(ConstantLight),
    Envmap(EnvmapLight),
}

impl Light {
    /// The position of a point or spot light (a delta in position).
    fn delta_position(&self) -> Option<Vec3> {
        match self {
            Light::Point(l) => Some(l.position),
            Light::Spot(l) => Some(l.position_and_intensity().0),
            _ => None,
        }
    }

    /// A point, spot or directional light: no path can hit it, only light samples reach it.
    fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point(_) | Light::Spot(_) | Light::Directional(_)
        )
    }

    /// What selection knows of the light (see [`selection`]); `point_radius2` floors the
    /// distance of point and spot lights.
    fn bound(&self, point_radius2: f32) -> LightBound {
        let local = |center: Vec3, radius: f32, intensity: f32| LightBound::Local {
            center,
            radius2: (radius * radius).max(point_radius2),
            intensity,
        };
        match self {
            Light::Mesh(m) => {
                let (center, radius) = m.bounding_sphere();
                local(center, radius, m.radiance().mean().luminance() * m.area())
            }
            Light::Sphere(s) => {
                let (center, radius) = s.sphere();
                local(
                    center,
                    radius,
                    s.radiance().mean().luminance() * std::f32::consts::PI * radius * radius,
                )
            }
            Light::Point(l) => local(l.position, 0.0, l.intensity.luminance()),
            Light::Spot(l) => {
                let (position, intensity) = l.position_and_intensity();
                local(position, 0.0, intensity.luminance())
            }
            Light::Directional(l) => LightBound::Distant {
                irradiance: l.irradiance.luminance(),
            },
            Light::Constant(c) => LightBound::Distant {
                irradiance: std::f32::consts::PI * c.radiance.luminance(),
            },
            Light::Envmap(e) => LightBound::Distant {
                irradiance: 0.25 * e.total_luminance(),
            },
        }
    }
}

impl Light {
    /// For a distant light: a direction of travel drawn with `u` and the radiance (irradiance
    /// for a directional light) over its density; `None` for other lights or a direction that
    /// carries nothing.
    fn sample_distant(&self, u: Vec2) -> Option<(Vec3, Rgb)> {
        match self {
            Light::Directional(l) => Some((-l.wi, l.irradiance)),
            Light::Constant(c) => Some((-c.sample(u), c.radiance / c.pdf())),
            Light::Envmap(e) => {
                let towards = e.sample(u)?;
                let pdf = e.pdf(towards);
                is_positive_finite(pdf).then(|| (-towards, e.eval(towards) / pdf))
            }
            _ => None,
        }
    }

    /// Emitted power (see [`emission`]); distant lights through the bounding sphere's disc of
    /// radius `scene_radius`.
    fn power(&self, scene_radius: f32) -> Rgb {
        let disc = std::f32::consts::PI * scene_radius * scene_radius;
        let pi = std::f32::consts::PI;
        match self {
            Light::Mesh(m) => m.radiance().mean() * (pi * m.area()),
            Light::Sphere(s) => s.radiance().mean() * (pi * s.area()),
            Light::Point(l) => l.intensity * (4.0 * pi),
            Light::Spot(l) => l.power(),
            Light::Directional(l) => l.irradiance * disc,
            Light::Constant(c) => c.radiance * (4.0 * pi * disc),
            Light::Envmap(e) => e.integral() * disc,
        }
    }
}

/// All emitters of a scene, with their selection.
#[derive(Clone, Debug)]
pub struct LightSet {
    lights: Vec<Light>,
    /// What selection knows of each light.
    bounds: Vec<LightBound>,
    /// For each shape of the description, its area light.
    shape_light: Vec<Option<u32>>,
    /// Indices of the constant and envmap lights.
    env_lights: Vec<u32>,
    scene_center: Vec3,
    scene_radius: f32,
    /// Emitters chosen for photons in proportion to their power's luminance.
    by_power: Distribution1D,
    /// Every light is sampled within a bounded factor of what a Lambertian surface receives
    /// from it (see [`LightSet::samples_diffuse_well`]).
    diffuse_well: bool,
    /// A point or spot light is among the lights.
    delta_positions: bool,
    /// The index of the one point or spot light, where there is exactly one.
    single_delta_position: Option<u32>,
}

/// What an area light emits: one radiance, or a texture looked up at the surface's uv (Mitsuba's
/// `area` emitter with a texture as its `radiance`), times a factor by the direction it is seen
/// from where it has a pattern (Radiance's luminaire tables and spotlights). Its mean, the
/// radiance of a uniform emitter of the same power, stands for the light where power is
/// estimated.
#[derive(Clone, Debug)]
pub struct EmittedRadiance {
    /// The radiance, or the texture's mean.
    radiance: Rgb,
    texture: Option<crate::texture::Texture>,
    pattern: Option<Arc<dyn SurfacePattern>>,
    /// The pattern's mean over the light's surface and its cosine-weighted hemisphere.
    pattern_mean: Rgb,
}

/// Samples (positions × directions) over which a pattern's mean is taken.
const PATTERN_MEAN_SAMPLES: u32 = 4096;

impl EmittedRadiance {
    /// `radiance` everywhere, or `texture` (whose mean `radiance` is), times `pattern` where
    /// given; see [`Self::with_pattern_mean`].
    #[must_use]
    pub fn new(
        radiance: Rgb,
        texture: Option<&ircache_scene::TextureDesc>,
        pattern: Option<&Arc<dyn SurfacePattern>>,
    ) -> EmittedRadiance {
        EmittedRadiance {
            radiance,
            texture: texture.map(crate::texture::Texture::from_desc),
            pattern: pattern.cloned(),
            pattern_mean: Rgb::ONE,
        }
    }

    /// Sets the pattern's mean from points `position(u)` (point, front normal) uniform over the
    /// light's surface: the mean factor over them and cosine-distributed directions, so that
    /// [`Self::mean`] times π times the area is the light's power.
    #[must_use]
    pub fn with_pattern_mean(mut self, position: impl Fn(Vec2) -> (Vec3, Vec3)) -> Self {
        let Some(pattern) = &self.pattern else {
            return self;
        };
        // A grid of 4 × 4 positions, each with 256 cosine-distributed directions from a
        // Hammersley set (i/N, bit-reversed i).
        const POSITIONS: u32 = 16;
        const DIRECTIONS: u32 = PATTERN_MEAN_SAMPLES / POSITIONS;
        let mut sum = [0f64; 3];
        for i in 0..POSITIONS {
            let u = Vec2::new(((i % 4) as f32 + 0.5) / 4.0, ((i / 4) as f32 + 0.5) / 4.0);
            let (p, n) = position(u);
            let frame = Frame::from_z(n);
            for j in 0..DIRECTIONS {
                let v = Vec2::new(
                    (j as f32 + 0.5) / DIRECTIONS as f32,
                    (f64::from(j.reverse_bits()) / 4_294_967_296.0) as f32,
                );
                let leaving = frame.from_local(square_to_cosine_hemisphere(v));
                // (At uv 0: the mean is an estimate of the power, for choosing lights.)
                let f = pattern.factor(p, n, -leaving, f32::INFINITY, Vec2::ZERO);
                for (s, v) in sum.iter_mut().zip(f.to_array()) {
                    *s += f64::from(v);
                }
            }
        }
        let k = 1.0 / f64::from(PATTERN_MEAN_SAMPLES);
        self.pattern_mean = Rgb::new(
            (sum[0] * k) as f32,
            (sum[1] * k) as f32,
            (sum[2] * k) as f32,
        );
        self
    }

    /// The radiance of a uniform emitter of the same power (the texture's mean times the
    /// pattern's).
    #[inline]
    #[must_use]
    pub fn mean(&self) -> Rgb {
        self.radiance * self.pattern_mean
    }

    /// The radiance at texture coordinates `uv`, before any pattern.
    #[inline]
    #[must_use]
    pub fn at(&self, uv: Vec2) -> Rgb {
        match &self.texture {
            None => self.radiance,
            Some(t) => t.eval(uv),
        }
    }

    /// The radiance leaving the point `p` (texture coordinates `uv`, unit front normal `n`)
    /// along the unit `wo`, towards a viewer `distance` away.
    #[inline]
    #[must_use]
    pub fn seen(&self, uv: Vec2, p: Vec3, n: Vec3, wo: Vec3, distance: f32) -> Rgb {
        match &self.pattern {
            None => self.at(uv),
            Some(f) => self.at(uv) * f.factor(p, n, -wo, distance, uv),
        }
    }

    /// True where it varies with the direction it is seen from.
    #[inline]
    #[must_use]
    pub fn is_patterned(&self) -> bool {
        self.pattern.is_some()
    }

    /// True where what it emits may read the surface's texture coordinates (a texture, or a
    /// pattern that may read a mesh's (u, v)): samples then carry their point's.
    #[inline]
    #[must_use]
    pub fn reads_uv(&self) -> bool {
        self.texture.is_some() || self.pattern.is_some()
    }

    /// True where it varies over the surface.
    #[inline]
    #[must_use]
    pub fn is_textured(&self) -> bool {
        self.texture.is_some()
    }
}

/// The point whose incident light the samples estimate: a point in space (in a medium, a
/// photon's), or a surface that only reflects, with its unit normal on the viewer's side. A
/// `constant` environment's samples then keep to that hemisphere, cosine-weighted (see
/// [`environment`]); the density of a direction ([`LightSet::pdf_environment`]) depends on the
/// receiver as the samples do, so MIS weights agree on both sides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    /// Position.
    pub p: Vec3,
    /// Unit normal on the side light is reflected to, for a surface that transmits nothing.
    pub normal: Option<Vec3>,
}

impl Receiver {
    /// A point without a surface.
    #[inline]
    #[must_use]
    pub fn point(p: Vec3) -> Receiver {
        Receiver { p, normal: None }
    }

    /// A surface at `p` that reflects only to the side of the unit normal `n`.
    #[inline]
    #[must_use]
    pub fn reflecting(p: Vec3, n: Vec3) -> Receiver {
        Receiver { p, normal: Some(n) }
    }
}

impl From<Vec3> for Receiver {
    #[inline]
    fn from(p: Vec3) -> Receiver {
        Receiver::point(p)
    }
}

/// What the light samples from one point share ([`LightSet::sample_sharing`]): how it sees the
/// rectangle light last sampled from it. Made afresh for each point.
#[derive(Clone, Copy, Debug, Default)]
pub struct SharedSetUp {
    rectangle: Option<(usize, Option<rectangle::Seen>)>,
}

impl LightSet {
    /// Builds the lights of `desc`: one area light per emitting shape (in shape order), then the
    /// other emitters in description order. `scene_center` and `scene_radius` describe the scene's
    /// bounding sphere (kept for distant lights, see [`LightSet::scene_bounds`]). Emitting shapes
    /// without area and directional lights without a direction are skipped.
    #[must_use]
    pub fn new(desc: &SceneDesc, scene_center: Vec3, scene_radius: f32) -> LightSet {
        let mut lights = Vec::new();
        let mut shape_light = vec![None; desc.shapes.len()];
        for (i, shape) in desc.shapes.iter().enumerate() {
            let Some(radiance) = shape.emitter else {
                continue;
            };
            let light = match &shape.geometry {
                Geometry::Mesh(mesh) => MeshLight::new(
                    mesh,
                    EmittedRadiance::new(
                        radiance,
                        shape.emitter_texture.as_ref(),
                        shape.emitter_pattern.as_ref(),
                    ),
                )
                .map(Light::Mesh),
                &Geometry::Sphere {
                    center,
                    radius,
                    flip_normals,
                    orientation,
                } => {
                    let emitted = EmittedRadiance::new(
                        radiance,
                        shape.emitter_texture.as_ref(),
                        shape.emitter_pattern.as_ref(),
                    );
                    SphereLight::new(center, radius, flip_normals, emitted, orientation.inverse())
                        .map(Light::Sphere)
                }
            };
            if let Some(light) = light {
                shape_light[i] = Some(lights.len() as u32);
                lights.push(light);
            }
        }
        let mut env_lights = Vec::new();
        for e in &desc.emitters {
            let light = match e {
                &EmitterDesc::Point {
                    position,
                    intensity,
                } => Some(Light::Point(PointLight {
                    position,
                    intensity,
                })),
                &EmitterDesc::Spot {
                    to_world,
                    intensity,
                    cutoff_angle,
                    beam_width,
                } => Some(Light::Spot(SpotLight::new(
                    to_world,
                    intensity,
                    cutoff_angle,
                    beam_width,
                ))),
                &EmitterDesc::Directional {
                    direction,
                    irradiance,
                } => DirectionalLight::new(direction, irradiance).map(Light::Directional),
                &EmitterDesc::Constant { radiance } => {
                    Some(Light::Constant(ConstantLight { radiance }))
                }
                EmitterDesc::Envmap {
                    image,
                    to_world,
                    scale,
                    ..
                } => EnvmapLight::new(image, *to_world, *scale).map(Light::Envmap),
            };
            if let Some(light) = light {
                if matches!(light, Light::Constant(_) | Light::Envmap(_)) {
                    env_lights.push(lights.len() as u32);
                }
                lights.push(light);
            }
        }
        // Point lights get a bound of a millionth of the scene's size (scale-free).
        let point_radius2 = (scene_radius * 1e-6).powi(2).max(f32::MIN_POSITIVE);
        let bounds = lights.iter().map(|l| l.bound(point_radius2)).collect();
        let powers: Vec<f32> = lights
            .iter()
            .map(|l| l.power(scene_radius).luminance())
            .collect();
        let diffuse_well = lights.iter().all(|l| match l {
            Light::Mesh(m) => m.is_rectangle(),
            Light::Sphere(_) | Light::Point(_) | Light::Spot(_) | Light::Directional(_) => true,
            Light::Constant(_) | Light::Envmap(_) => false,
        });
        let positioned: Vec<u32> = (0u32..)
            .zip(&lights)
            .filter_map(|(i, l)| l.delta_position().map(|_| i))
            .collect();
        LightSet {
            delta_positions: !positioned.is_empty(),
            single_delta_position: (positioned.len() == 1).then(|| positioned[0]),
            diffuse_well,
            by_power: Distribution1D::new(&powers),
            lights,
            bounds,
            shape_light,
            env_lights,
            scene_center,
            scene_radius,
        }
    }

    /// True when every light's samples have a density within a bounded factor of the light a
    /// Lambertian surface receives from it, wherever the surface is: rectangles (by solid angle
    /// near, by area far), spheres (their cone), points, spots and distant directions. Not for
    /// other meshes (by area, unbounded next to them) nor environments (a sphere's worth of
    /// samples for a hemisphere's light, against a cosine-weighted BSDF sample that sees it
    /// all): there a BSDF sample combined by MIS pays.
    #[must_use]
    pub fn samples_diffuse_well(&self) -> bool {
        self.diffuse_well
    }

    /// True when the scene has no emitter.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// Number of emitters.
    #[must_use]
    pub fn len(&self) -> usize {
        self.lights.len()
    }

    /// If light `light` is a point or a spot light (a delta in position, whose 1/r² a distance
    /// along a ray through a medium is sampled against: [`crate::integrators::equiangular`]),
    /// its position and the part of `[t0, t1]` along `o + t d` it lights (a spot's cone).
    #[must_use]
    pub fn delta_position_along(
        &self,
        light: u32,
        o: Vec3,
        d: Vec3,
        interval: (f32, f32),
    ) -> Option<(Vec3, (f32, f32))> {
        let light = self.lights.get(light as usize)?;
        let position = light.delta_position()?;
        match light {
            Light::Spot(l) => Some((position, l.cone_interval(o, d, interval)?)),
            _ => Some((position, interval)),
        }
    }

    /// ∇ln of a spot light's falloff at the receiver `x` ([`SpotLight::falloff_log_gradient`]);
    /// zero for any other light.
    #[must_use]
    pub fn falloff_log_gradient(&self, light: u32, x: Vec3) -> Vec3 {
        match self.lights.get(light as usize) {
            Some(Light::Spot(l)) => l.falloff_log_gradient(x),
            _ => Vec3::ZERO,
        }
    }

    /// The position of light `light` if it is a point or a spot light.
    #[must_use]
    pub fn delta_position(&self, light: u32) -> Option<Vec3> {
        self.lights.get(light as usize)?.delta_position()
    }

    /// The positions of the point and spot lights.
    pub fn delta_positions(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.lights.iter().filter_map(Light::delta_position)
    }

    /// The index of the scene's one point or spot light, where it has exactly one.
    #[must_use]
    pub fn single_delta_position(&self) -> Option<u32> {
        self.single_delta_position
    }

    /// True when a point or spot light is among the emitters.
    #[must_use]
    pub fn has_delta_positions(&self) -> bool {
        self.delta_positions
    }

    /// When the scene's only emitter is a directional light: the unit direction towards it and
    /// its irradiance (the light a rasteriser's shadow map serves).
    #[must_use]
    pub fn only_directional(&self) -> Option<(Vec3, Rgb)> {
        match self.lights.as_slice() {
            [Light::Directional(l)] => Some((l.wi, l.irradiance)),
            _ => None,
        }
    }

    /// The scene's bounding sphere `(centre, radius)` given at construction.
    #[must_use]
    pub fn scene_bounds(&self) -> (Vec3, f32) {
        (self.scene_center, self.scene_radius)
    }

    /// Next-event estimation at the receiver `at` (a point, or a [`Receiver`]): selects a light
    /// with `u_select` and samples it with `u`. `None` when the sample cannot contribute (see
    /// the module documentation) or the set is empty.
    #[inline]
    #[must_use]
    pub fn sample(&self, at: impl Into<Receiver>, u_select: f32, u: Vec2) -> Option<LightSample> {
        self.sample_sharing(at, u_select, u, &mut SharedSetUp::default())
    }

    /// [`Self::sample`] for one of several samples from the same `p`, which share `shared`: a
    /// rectangle light's spherical set-up (Ureña's four angles) is made once for them all.
    #[inline]
    #[must_use]
    pub fn sample_sharing(
        &self,
        at: impl Into<Receiver>,
        u_select: f32,
        u: Vec2,
        shared: &mut SharedSetUp,
    ) -> Option<LightSample> {
        if self.lights.is_empty() {
            return None;
        }
        let at = at.into();
        let (idx, sel) = self.select(at.p, u_select);
        self.sample_chosen(idx, sel, at, u, true, shared)
    }

    /// Samples light `idx` alone with `u`, its densities scaled by `sel` (1 where every light is
    /// sampled in turn): an environment light's sample carries its own radiance and density,
    /// not the whole environment's.
    #[inline]
    #[must_use]
    pub fn sample_light(
        &self,
        idx: usize,
        sel: f32,
        at: impl Into<Receiver>,
        u: Vec2,
    ) -> Option<LightSample> {
        self.sample_chosen(idx, sel, at.into(), u, false, &mut SharedSetUp::default())
    }

    /// Samples light `idx`, chosen with probability `sel`; with `whole_environment`, an
    /// environment direction is weighed as every environment light's (one-sample MIS over them,
    /// [`Self::pdf_environment`]): [`Self::sample`] once [`Self::select`] has chosen, for a
    /// caller that looks at the choice first.
    #[inline]
    pub(crate) fn sample_chosen(
        &self,
        idx: usize,
        sel: f32,
        at: Receiver,
        u: Vec2,
        whole_environment: bool,
        shared: &mut SharedSetUp,
    ) -> Option<LightSample> {
        let light = idx as u32;
        let p = at.p;
        let own_environment = |wi: Vec3, pdf: f32, radiance: Rgb| {
            (is_positive_finite(pdf * sel) && !radiance.is_black()).then_some(LightSample {
                wi,
                distance: f32::INFINITY,
                radiance,
                pdf: pdf * sel,
                is_delta: false,
                light,
                normal: Vec3::ZERO,
            })
        };
        let area =
            |(wi, distance, radiance, pdf, normal): (Vec3, f32, Rgb, f32, Vec3)| LightSample {
                wi,
                distance,
                radiance,
                pdf: pdf * sel,
                is_delta: false,
                light,
                normal,
            };
        let delta = |(wi, distance, radiance): (Vec3, f32, Rgb)| LightSample {
            wi,
            distance,
            radiance,
            pdf: sel,
            is_delta: true,
            light,
            normal: Vec3::ZERO,
        };
        match &self.lights[idx] {
            Light::Mesh(m) => {
                let seen = match shared.rectangle {
                    Some((light, seen)) if light == idx => seen,
                    _ => {
                        let seen = m.rectangle_seen_from(p);
                        shared.rectangle = Some((idx, seen));
                        seen
                    }
                };
                m.sample_seen(p, u, seen).map(area)
            }
            Light::Sphere(s) => s.sample(p, u).map(area),
            Light::Point(l) => l.sample(p).map(delta),
            Light::Spot(l) => l.sample(p).map(delta),
            Light::Directional(l) => {
                (!l.irradiance.is_black()).then(|| delta((l.wi, f32::INFINITY, l.irradiance)))
            }
            Light::Constant(c) if whole_environment => {
                self.environment_sample(at, c.sample_at(&at, u), light)
            }
            Light::Envmap(e) if whole_environment => {
                self.environment_sample(at, e.sample(u)?, light)
            }
            Light::Constant(c) => {
                let wi = c.sample_at(&at, u);
                own_environment(wi, c.pdf_at(&at, wi), c.radiance)
            }
            Light::Envmap(e) => {
                let wi = e.sample(u)?;
                own_environment(wi, e.pdf(wi), e.eval(wi))
            }
        }
    }

    /// Emitted power of light `light` (distant lights: through the disc of the scene's bounding
    /// sphere, see [`emission`]).
    #[must_use]
    pub fn power(&self, light: u32) -> Rgb {
        self.lights
            .get(light as usize)
            .map_or(Rgb::ZERO, |l| l.power(self.scene_radius))
    }

    /// A photon's start (see [`emission`]): an emitter chosen by `u_select` in proportion to its
    /// power, a point on it by `u_position`, a direction by `u_direction`; the flux weight is
    /// divided by the selection probability, so its mean is the total power. `None` for a sample
    /// that carries nothing, or when no emitter emits.
    #[must_use]
    pub fn sample_emission(
        &self,
        u_select: f32,
        u_position: Vec2,
        u_direction: Vec2,
    ) -> Option<EmissionSample> {
        let (center, radius) = (self.scene_center, self.scene_radius);
        let distant = |direction: Vec3, flux: Rgb| {
            let (origin, area) = distant_origin(direction, center, radius, u_position);
            EmissionSample {
                origin,
                direction,
                normal: None,
                flux: flux * area,
                from_delta_light: false,
            }
        };
        self.emit(u_select, |light| match light {
            Light::Mesh(m) => {
                let (origin, n, direction, flux) = m.sample_emission(u_position, u_direction)?;
                Some(EmissionSample {
                    origin,
                    direction,
                    normal: Some(n),
                    flux,
                    from_delta_light: false,
                })
            }
            Light::Sphere(s) => {
                let (origin, n, direction, flux) = s.sample_emission(u_position, u_direction);
                Some(EmissionSample {
                    origin,
                    direction,
                    normal: Some(n),
                    flux,
                    from_delta_light: false,
                })
            }
            Light::Point(l) => Some(EmissionSample {
                origin: l.position,
                direction: square_to_uniform_sphere(u_direction),
                normal: None,
                flux: l.intensity * (4.0 * std::f32::consts::PI),
                from_delta_light: false,
            }),
            Light::Spot(l) => {
                let (origin, direction, flux) = l.sample_emission(u_direction)?;
                Some(EmissionSample {
                    origin,
                    direction,
                    normal: None,
                    flux,
                    from_delta_light: false,
                })
            }
            Light::Directional(_) | Light::Constant(_) | Light::Envmap(_) => {
                let (direction, flux) = light.sample_distant(u_direction)?;
                Some(distant(direction, flux))
            }
        })
    }

    /// [`LightSet::sample_emission`] aimed at `targets` (caustic photons): the light chosen by
    /// power, a point on it, a direction towards one target (`u_pick`), the flux weight divided
    /// by the densities of all three.
    #[must_use]
    pub fn sample_emission_towards(
        &self,
        targets: &Targets,
        (u_select, u_pick): (f32, f32),
        u_position: Vec2,
        u_direction: Vec2,
    ) -> Option<EmissionSample> {
        if targets.is_empty() {
            return None;
        }
        let from_surface =
            |p: Vec3, n: Vec3, ns: Vec3, radiance: &dyn Fn(Vec3) -> Rgb, area: f32| {
                let w = targets.sample_direction(p, u_pick, u_direction);
                let cos = n.dot(w);
                let pdf = targets.direction_pdf(p, w);
                (cos > 0.0 && ns.dot(w) > 0.0 && is_positive_finite(pdf)).then(|| EmissionSample {
                    origin: p,
                    direction: w,
                    normal: Some(n),
                    flux: radiance(w) * (cos * area / pdf),
                    from_delta_light: false,
                })
            };
        let from_point = |p: Vec3, intensity: &dyn Fn(Vec3) -> Rgb| {
            let w = targets.sample_direction(p, u_pick, u_direction);
            let pdf = targets.direction_pdf(p, w);
            is_positive_finite(pdf).then(|| EmissionSample {
                origin: p,
                direction: w,
                normal: None,
                flux: intensity(w) / pdf,
                from_delta_light: false,
            })
        };
        let distant = |direction: Vec3, radiance_over_pdf: Rgb| {
            let (origin, density) = targets.sample_disc(direction, u_pick, u_position);
            is_positive_finite(density).then(|| EmissionSample {
                origin,
                direction,
                normal: None,
                flux: radiance_over_pdf / density,
                from_delta_light: false,
            })
        };
        self.emit(u_select, |light| match light {
            Light::Mesh(m) => {
                let s = m.sample_position(u_position);
                let n = s.emitting_normal();
                from_surface(
                    s.p,
                    n,
                    s.ns,
                    &|w| m.radiance().seen(s.uv, s.p, n, w, f32::INFINITY),
                    m.area(),
                )
            }
            Light::Sphere(s) => {
                let (p, n) = s.sample_position(u_position);
                let outward = (p - s.sphere().0) / s.sphere().1;
                from_surface(
                    p,
                    n,
                    n,
                    &|w| s.radiance_seen(outward, w, f32::INFINITY),
                    s.area(),
                )
            }
            Light::Point(l) => from_point(l.position, &|_| l.intensity),
            Light::Spot(l) => {
                let (p, _) = l.position_and_intensity();
                from_point(p, &|w| l.intensity_towards(w))
            }
            Light::Directional(_) | Light::Constant(_) | Light::Envmap(_) => {
                let (direction, flux) = light.sample_distant(u_direction)?;
                distant(direction, flux)
            }
        })
    }

    /// Picks an emitter in proportion to its power with `u_select` and lets `sample` start a
    /// photon from it; divides the flux by the selection probability. `None` when no emitter
    /// emits or the sample carries nothing finite.
    fn emit(
        &self,
        u_select: f32,
        sample: impl FnOnce(&Light) -> Option<EmissionSample>,
    ) -> Option<EmissionSample> {
        if self.lights.is_empty() || self.by_power.integral <= 0.0 {
            return None;
        }
        let (index, probability, _) = self.by_power.sample(u_select);
        if probability <= 0.0 {
            return None;
        }
        let light = &self.lights[index];
        let sample = sample(light)?;
        let flux = sample.flux / probability;
        (!flux.is_black() && flux.to_array().iter().all(|c| c.is_finite())).then_some(
            EmissionSample {
                flux,
                from_delta_light: light.is_delta(),
                ..sample
            },
        )
    }

    /// The light chosen by `u_select` at `p` and its selection probability.
    #[inline]
    pub(crate) fn select(&self, p: Vec3, u_select: f32) -> (usize, f32) {
        selection::select(&self.bounds, p, u_select)
    }

    /// The probability that [`LightSet::sample`] at `p` selects `light`.
    #[inline]
    #[must_use]
    pub fn selection_probability(&self, p: Vec3, light: u32) -> f32 {
        selection::probability(&self.bounds, p, light as usize)
    }

    /// A sample of the environment along `wi` with the total radiance and mixture density.
    #[inline]
    fn environment_sample(&self, at: Receiver, wi: Vec3, light: u32) -> Option<LightSample> {
        let pdf = self.pdf_environment(at, wi);
        let radiance = self.environment_radiance(wi);
        if !is_positive_finite(pdf) || radiance.is_black() {
            return None;
        }
        Some(LightSample {
            wi,
            distance: f32::INFINITY,
            radiance,
            pdf,
            is_delta: false,
            light,
            normal: Vec3::ZERO,
        })
    }

    /// Area light id of shape `shape` (index into `desc.shapes`), if that shape emits.
    #[must_use]
    pub fn area_light_of_shape(&self, shape: usize) -> Option<u32> {
        self.shape_light.get(shape).copied().flatten()
    }

    /// Radiance leaving the point `p` of area light `light` with shading normal `n_shading` and
    /// texture coordinates `uv` towards the world direction `wo`, seen from `distance` away:
    /// the emitter's radiance there when `n_shading · wo > 0`, zero on the back side (one-sided,
    /// as Mitsuba's `area` emitter) and for ids that are not area lights.
    #[inline]
    #[must_use]
    pub fn area_radiance(
        &self,
        light: u32,
        p: Vec3,
        n_shading: Vec3,
        uv: Vec2,
        wo: Vec3,
        distance: f32,
    ) -> Rgb {
        if n_shading.dot(wo) <= 0.0 {
            return Rgb::ZERO;
        }
        match self.lights.get(light as usize) {
            Some(Light::Mesh(m)) => m.radiance().seen(uv, p, n_shading, wo, distance),
            Some(Light::Sphere(s)) => s.radiance().seen(uv, p, n_shading, wo, distance),
            _ => Rgb::ZERO,
        }
    }

    /// Solid-angle density (including selection) with which [`LightSet::sample`] from `p` produces
    /// the point `p_light` on area light `light`, triangle `prim` (ignored for spheres). Meshes use
    /// the triangle's geometric normal for the Jacobian (`n_light` only if `prim` is invalid);
    /// spheres use their analytic normal. Zero for ids that are not area lights.
    #[inline]
    #[must_use]
    pub fn pdf_area(&self, light: u32, prim: u32, p: Vec3, p_light: Vec3, n_light: Vec3) -> f32 {
        let pdf = match self.lights.get(light as usize) {
            Some(Light::Mesh(m)) => m.pdf(prim, p, p_light, n_light),
            Some(Light::Sphere(s)) => s.pdf(p, p_light),
            _ => return 0.0,
        };
        pdf * self.selection_probability(p, light)
    }

    /// Radiance from the environment (sum of the constant and envmap emitters) along the escaping
    /// ray direction `dir` (world; from the scene towards the environment).
    #[inline]
    #[must_use]
    pub fn environment_radiance(&self, dir: Vec3) -> Rgb {
        let mut l = Rgb::ZERO;
        for &i in &self.env_lights {
            match &self.lights[i as usize] {
                Light::Constant(c) => l += c.radiance,
                Light::Envmap(e) => l += e.eval(dir),
                _ => {}
            }
        }
        l
    }

    /// Solid-angle density (including selection) with which [`LightSet::sample`] at the
    /// receiver `at` produces the environment direction `dir`: `Σ_env P(env | p) p_env(dir)`.
    #[inline]
    #[must_use]
    pub fn pdf_environment(&self, at: impl Into<Receiver>, dir: Vec3) -> f32 {
        let at = at.into();
        let mut pdf = 0.0;
        for &i in &self.env_lights {
            let own = match &self.lights[i as usize] {
                Light::Constant(c) => c.pdf_at(&at, dir),
                Light::Envmap(e) => e.pdf(dir),
                _ => 0.0,
            };
            pdf += own * self.selection_probability(at.p, i);
        }
        pdf
    }

    /// Relative variance `E[Y²]/E[Y]² − 1` of the environment's luminance `Y` over the sphere
    /// (uniform directions): 0 for a `constant` emitter, large for a map whose power is in a
    /// small sun. Several maps are taken as uncorrelated. 0 without an environment.
    #[must_use]
    pub fn environment_relative_variance(&self) -> f64 {
        let four_pi = 4.0 * std::f64::consts::PI;
        let (mut mean, mut square) = (0.0f64, 0.0f64);
        for &i in &self.env_lights {
            let (m, s) = match &self.lights[i as usize] {
                Light::Constant(c) => {
                    let y = f64::from(c.radiance.luminance());
                    (y, y * y)
                }
                Light::Envmap(e) => {
                    let (m1, m2) = e.luminance_moments();
                    (m1 / four_pi, m2 / four_pi)
                }
                _ => continue,
            };
            square += s + 2.0 * mean * m;
            mean += m;
        }
        if mean > 0.0 {
            (square / (mean * mean) - 1.0).max(0.0)
        } else {
            0.0
        }
    }

    /// True when light `light` is a `constant` or `envmap` emitter.
    #[inline]
    #[must_use]
    pub fn is_environment(&self, light: u32) -> bool {
        self.env_lights.contains(&light)
    }

    /// True when the scene has a constant or envmap emitter.
    #[must_use]
    pub fn has_environment(&self) -> bool {
        !self.env_lights.is_empty()
    }

    /// True when every light is a point, spot or directional light (a light sample is then the
    /// same whatever the random numbers, up to the choice of light).
    #[must_use]
    pub fn all_delta(&self) -> bool {
        self.lights.iter().all(Light::is_delta)
    }
}
