//! The render-time scene: the Embree acceleration structure, one material per shape, the lights,
//! the camera, and the surface interaction (hit point, normals, texture coordinates) recovered
//! from an Embree hit.
//!
//! Shape `i` of the description is Embree geometry `i`, so a hit's geometry id indexes
//! [`Scene::shapes`] directly.

use crate::bsdf::Material;
use crate::camera::Camera;
use crate::lights::LightSet;
use ircache_math::{offset_ray_origin, Frame, Ray, Rgb, Vec2, Vec3};
use ircache_scene::{Geometry, SceneDesc, TriangleMesh};

/// Errors building a scene for rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Embree refused the geometry.
    #[error("ray tracing core: {0}")]
    Embree(#[from] ircache_embree::EmbreeError),
    /// The scene has no geometry.
    #[error("{}: the scene has no shapes", .0.display())]
    EmptyScene(std::path::PathBuf),
    /// A parameter has a value the renderer cannot use.
    #[error("{0}")]
    Invalid(String),
    /// The worker threads could not be started.
    #[error("starting worker threads: {0}")]
    Threads(#[from] rayon::ThreadPoolBuildError),
    /// The irradiance cache file could not be used.
    #[error(transparent)]
    CacheFile(#[from] crate::irradiance_cache::file::CacheFileError),
}

/// Geometry kept for shading after the acceleration structure is built.
#[derive(Clone, Debug)]
pub enum ShapeGeometry {
    /// A triangle mesh.
    Mesh(TriangleMesh),
    /// An analytic sphere.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
        /// Normals point inwards.
        flip_normals: bool,
        /// World to object rotation (the inverse of the description's `orientation`), for the
        /// uv parametrisation.
        to_object: ircache_math::Mat3,
    },
}

/// Mitsuba 3's uv on a sphere at the unit direction `o` from its centre in its own frame: the
/// azimuth from its x axis over 2π (in [0, 1)), the polar angle from its z axis over π.
#[inline]
#[must_use]
pub fn sphere_uv(o: Vec3) -> Vec2 {
    let tau = 2.0 * ircache_math::PI;
    let phi = o.y.atan2(o.x);
    let phi = if phi < 0.0 { phi + tau } else { phi };
    Vec2::new(phi / tau, o.z.clamp(-1.0, 1.0).acos() / ircache_math::PI)
}

/// The rest of a ray along `d` from `o` (just beyond a surface it crossed) to the same `end`
/// (none: to infinity), aimed from `o` at the end itself: a ray kept parallel would pass the end
/// at the offset's distance and, after a grazing crossing, reach a light's own surface before
/// it. `None` where nothing is left of it.
#[must_use]
pub fn ray_on_to(o: Vec3, d: Vec3, end: Option<Vec3>) -> Option<Ray> {
    let Some(end) = end else {
        return Some(Ray::new(o, d));
    };
    let to_end = end - o;
    let length = to_end.length();
    if length.is_nan() || length <= 0.0 || to_end.dot(d) <= 0.0 {
        return None;
    }
    Some(Ray {
        o,
        d: to_end / length,
        t_min: 0.0,
        t_max: length,
    })
}

/// Most thin sheets a ray or a path meets before it is taken as blocked (double glazing is two).
pub const MAX_SHEET_CROSSINGS: u32 = 64;

/// Where a ray goes on past a window pane or a mask's open part ([`Scene::see_through`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Passage {
    /// The direction it goes on in (straight on, or mirrored by a pane).
    pub d: Vec3,
    /// The throughput of the choice over its probability.
    pub weight: Rgb,
    /// A pane mirrored it (a delta bounce).
    pub reflected: bool,
    /// The probability of the choice (a mask's crossing: 1, its weight unscaled).
    pub prob: f32,
}

/// One shape at render time.
#[derive(Clone, Debug)]
pub struct Shape {
    /// The shape's `id` in XML, its material's name in OBJ.
    pub name: Option<String>,
    /// Its geometry.
    pub geometry: ShapeGeometry,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Its area light in [`Scene::lights`], if it emits.
    pub area_light: Option<u32>,
    /// A flat-shaded mesh whose material and emitter have no image texture and whose material
    /// ignores tangents: its interactions need no vertex data (position from the ray, normal
    /// from Embree).
    pub flat: bool,
    /// A `null` BSDF: the invisible boundary of a medium, passed through by rays.
    pub null: bool,
    /// A thin dielectric sheet (a window pane, [`Material::thin_sheet`]): paths cross it
    /// without a bounce and shadow rays through it carry its transmittance.
    pub thin_sheet: bool,
    /// A `mask` around its material: paths pass through it where it is not opaque
    /// ([`Material::opacity`]), shadow rays carry 1 − opacity.
    pub masked: bool,
    /// A smooth Radiance `trans`: light samples of lights no path can hit (distant, point and
    /// spot lights) pass through it with its straight transmittance, as Radiance's shadow rays
    /// do; paths take that part as the material's straight lobe, as ever.
    pub straight_trans: bool,
    /// The media on its two sides (indices into [`Scene::media`]).
    pub media: ircache_scene::MediumInterface,
    /// A bump or normal map ([`Scene::perturbed_shadowing`]).
    pub perturbed: bool,
}

/// A ray–surface intersection.
#[derive(Clone, Copy, Debug)]
pub struct Interaction {
    /// Hit point.
    pub p: Vec3,
    /// Unit geometric normal (triangle winding, or outward for spheres unless flipped).
    pub ng: Vec3,
    /// Shading frame around the unit shading normal (after a normal or bump map).
    pub frame: Frame,
    /// The shading normal before a normal or bump map (irradiance cache records use it).
    pub base_n: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// Shape index.
    pub shape: u32,
    /// Triangle (or sphere) index within the shape.
    pub prim: u32,
    /// Ray distance.
    pub t: f32,
}

impl Interaction {
    /// The BSDF of `material` here, for a ray arriving along the unit `d` (Radiance's patterns
    /// on a material's colour need the point, normal, direction and distance).
    #[inline]
    #[must_use]
    pub fn bsdf(&self, material: &crate::bsdf::Material, d: Vec3) -> crate::bsdf::Bsdf {
        material.at_hit(self.uv, self.p, self.ng, d, self.t, &self.frame)
    }
}

/// The scene as the integrators see it.
pub struct Scene {
    /// Embree scene.
    pub accel: ircache_embree::Scene,
    /// Shapes, indexed by Embree geometry id.
    pub shapes: Vec<Shape>,
    /// Materials, one per shape.
    pub materials: Vec<Material>,
    /// All emitters.
    pub lights: LightSet,
    /// The camera.
    pub camera: Camera,
    /// Largest coordinate magnitude: the scale for ray-origin offsets.
    pub scale: f32,
    /// Centre of the bounding sphere.
    pub center: Vec3,
    /// Radius of the bounding sphere.
    pub radius: f32,
    /// Total triangle count.
    pub triangles: usize,
    /// Some emitter can be found by a ray (an area light or an environment); when false, a path's
    /// last segment, which could only pick up emission, need not be traced.
    pub has_hittable_emitters: bool,
    /// Some shape is a thin sheet or masked ([`Shape::thin_sheet`], [`Shape::masked`]): rays
    /// and shadow rays pass through them.
    pub has_see_through: bool,
    /// Some shape is a smooth `trans` ([`Shape::straight_trans`]): the light samples of delta
    /// lights pass through it ([`Scene::delta_shadow_transmittance`]).
    pub has_straight_trans: bool,
    /// Some surface has a bump or normal map: without one, [`Scene::perturbed_shadowing`]
    /// answers 1 without looking at the shape.
    pub has_perturbed: bool,
    /// Content hash of what light transport depends on (geometry, materials, emitters; not the
    /// camera, not where the files are): a cache file records it.
    pub content_hash: u64,
    /// Participating media.
    pub media: Vec<crate::media::Medium>,
    /// The medium the camera sits in.
    pub camera_medium: Option<usize>,
    /// Where the first medium or `null` surface was declared, for integrators without media.
    media_location: Option<String>,
}

/// Radiance's `raynormal`: the shading normal `n` displaced by a texture, normalised, and
/// mirrored about the ray's direction `d` where the displacement would turn it to the other side
/// of the ray (Radiance's "fix orientation").
fn radiance_normal(n: Vec3, displacement: Vec3, d: Vec3) -> Vec3 {
    let m = (n + displacement).normalize_or(n);
    let (before, after) = (-d.dot(n), -d.dot(m));
    if (after > 0.0) != (before > 0.0) {
        (m + d * (2.0 * after)).normalize_or(n)
    } else {
        m
    }
}

/// FNV-1a of what light transport depends on: the geometry (positions, indices, normals, uvs),
/// materials and emitters (their descriptions, with every image's texels, each image once), the
/// media and which shapes and camera they fill, not where the files lie.
fn content_hash(desc: &SceneDesc) -> u64 {
    use crate::irradiance_cache::file::Fnv;
    use std::fmt::Write;
    let mut h = Fnv::default();
    let floats = |h: &mut Fnv, v: &mut dyn Iterator<Item = f32>| {
        for c in v {
            h.bytes(&c.to_le_bytes());
        }
    };
    let mut images: Vec<*const ircache_scene::BitmapDesc> = Vec::new();
    for s in &desc.shapes {
        match &s.geometry {
            Geometry::Mesh(m) => {
                h.bytes(b"mesh");
                floats(&mut h, &mut m.positions.iter().flat_map(|p| p.to_array()));
                for t in &m.indices {
                    for i in t {
                        h.bytes(&i.to_le_bytes());
                    }
                }
                h.bytes(b"normals");
                if let Some(n) = &m.normals {
                    floats(&mut h, &mut n.iter().flat_map(|p| p.to_array()));
                }
                h.bytes(b"uvs");
                if let Some(uv) = &m.uvs {
                    floats(&mut h, &mut uv.iter().flat_map(|p| p.to_array()));
                }
            }
            g => {
                let _ = write!(h, "{g:?}");
            }
        }
        let _ = write!(
            h,
            "{:?}{:?}{:?}{:?}{:?}",
            s.bsdf, s.emitter, s.emitter_texture, s.emitter_pattern, s.media
        );
        let mut hash_image = |b: &std::sync::Arc<ircache_scene::BitmapDesc>| {
            if !images.contains(&std::sync::Arc::as_ptr(b)) {
                images.push(std::sync::Arc::as_ptr(b));
                h.words(
                    b.image
                        .pixels
                        .iter()
                        .flat_map(|p| [p.r, p.g, p.b])
                        .map(f32::to_bits),
                );
            }
        };
        s.bsdf.for_each_bitmap(&mut hash_image);
        if let Some(ircache_scene::TextureDesc::Bitmap(b)) = &s.emitter_texture {
            hash_image(b);
        }
    }
    let _ = write!(h, "{:?}{:?}", desc.emitters, desc.sensor.medium);
    for m in &desc.media {
        let _ = write!(
            h,
            "{:?}{:?}{:?}{}{:?}",
            m.kind, m.phase, m.scale, m.sample_emitters, m.id
        );
        for v in [Some(&m.sigma_t), Some(&m.albedo), m.emission.as_ref()]
            .into_iter()
            .flatten()
        {
            match v {
                ircache_scene::VolumeDesc::Grid(g) => {
                    let _ = write!(h, "{g:?}");
                    h.words(g.data.iter().map(|x| x.to_bits()));
                }
                c => {
                    let _ = write!(h, "{c:?}");
                }
            }
        }
    }
    for s in &desc.shapes {
        let _ = write!(h, "{:?}", s.media);
    }
    h.0
}

impl Scene {
    /// Builds the render-time scene from a description.
    pub fn build(desc: &SceneDesc) -> Result<Scene, RenderError> {
        if desc.shapes.is_empty() {
            return Err(RenderError::EmptyScene(desc.source.clone()));
        }
        let device = ircache_embree::Device::new()?;
        let mut builder = ircache_embree::SceneBuilder::new(&device)?;
        let mut shapes = Vec::with_capacity(desc.shapes.len());
        let mut materials = Vec::with_capacity(desc.shapes.len());
        let mut triangles = 0;
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for (i, s) in desc.shapes.iter().enumerate() {
            let geometry = match &s.geometry {
                Geometry::Mesh(m) => {
                    let id = builder.add_triangle_mesh(&m.positions, &m.indices)?;
                    debug_assert_eq!(id as usize, i);
                    triangles += m.indices.len();
                    for &p in &m.positions {
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                    ShapeGeometry::Mesh(m.clone())
                }
                &Geometry::Sphere {
                    center,
                    radius,
                    flip_normals,
                    orientation,
                } => {
                    let id = builder.add_spheres(&[(center, radius)])?;
                    debug_assert_eq!(id as usize, i);
                    lo = lo.min(center - Vec3::splat(radius));
                    hi = hi.max(center + Vec3::splat(radius));
                    ShapeGeometry::Sphere {
                        center,
                        radius,
                        flip_normals,
                        to_object: orientation.inverse(),
                    }
                }
            };
            let material = Material::from_desc(&s.bsdf);
            let flat = matches!(&geometry, ShapeGeometry::Mesh(m) if m.shades_flat())
                && material.is_tangent_free()
                && !material.is_textured()
                && s.emitter_texture.is_none();
            materials.push(material);
            shapes.push(Shape {
                name: s.id.clone(),
                geometry,
                material: i,
                area_light: None,
                flat,
                null: matches!(*s.bsdf, ircache_scene::BsdfDesc::Null),
                thin_sheet: materials[i].thin_sheet().is_some(),
                masked: materials[i].is_masked(),
                straight_trans: materials[i].has_straight_transmission(),
                media: s.media,
                perturbed: materials[i].perturbation().is_some(),
            });
        }
        let accel = builder.build()?;
        let center = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(f32::MIN_POSITIVE);
        let lights = LightSet::new(desc, center, radius);
        for (i, shape) in shapes.iter_mut().enumerate() {
            shape.area_light = lights.area_light_of_shape(i);
        }
        let camera = Camera::new(
            &desc.sensor,
            desc.sensor.film.width,
            desc.sensor.film.height,
        );
        let scale = lo.abs().max(hi.abs()).max_element().max(f32::MIN_POSITIVE);
        let has_hittable_emitters =
            lights.has_environment() || shapes.iter().any(|s| s.area_light.is_some());
        let media_location = desc
            .media
            .first()
            .map(|m| m.location.to_string())
            .or_else(|| {
                desc.shapes
                    .iter()
                    .find(|s| matches!(*s.bsdf, ircache_scene::BsdfDesc::Null))
                    .map(|s| s.location.to_string())
            });
        Ok(Scene {
            media: desc
                .media
                .iter()
                .map(crate::media::Medium::from_desc)
                .collect(),
            camera_medium: desc.sensor.medium,
            media_location,
            content_hash: content_hash(desc),
            has_hittable_emitters,
            has_see_through: shapes.iter().any(|s| s.thin_sheet || s.masked),
            has_straight_trans: shapes.iter().any(|s| s.straight_trans),
            has_perturbed: shapes.iter().any(|s| s.perturbed),
            accel,
            shapes,
            materials,
            lights,
            camera,
            scale,
            center,
            radius,
            triangles,
        })
    }

    /// True when scattering in `medium` takes light samples (Mitsuba's `sample_emitters`, and
    /// lights to sample).
    #[must_use]
    pub fn samples_lights_in(&self, medium: usize) -> bool {
        self.media[medium].sample_emitters && !self.lights.is_empty()
    }

    /// True when the scene has participating media or `null` surfaces.
    #[must_use]
    pub fn has_media(&self) -> bool {
        self.media_location.is_some()
    }

    /// Errors when the scene has media or `null` surfaces, which only `volpath` renders: `what`
    /// names the method that cannot.
    pub fn require_no_media(&self, what: &str) -> Result<(), RenderError> {
        match &self.media_location {
            None => Ok(()),
            Some(at) => Err(RenderError::Invalid(format!(
                "the scene has participating media or null surfaces (the first at {at}), which \
                 {what} does not handle: render it with --integrator volpath"
            ))),
        }
    }

    /// The closest surface along `ray`.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray) -> Option<Interaction> {
        let hit = self.accel.intersect(ray)?;
        Some(self.interaction(ray, &hit))
    }

    /// The sheet met at `it` by a ray along the unit `d`, when its shape is a thin sheet
    /// ([`Shape::thin_sheet`]; a Radiance pane's patterns evaluated there).
    #[inline]
    #[must_use]
    pub fn thin_sheet(&self, it: &Interaction, d: Vec3) -> Option<crate::bsdf::ThinDielectric> {
        let shape = &self.shapes[it.shape as usize];
        if shape.thin_sheet {
            self.materials[shape.material].thin_sheet_at(it.uv, it.p, it.ng, d, it.t)
        } else {
            None
        }
    }

    /// What a window pane or a mask's open part does to a ray that meets it at `it` arriving
    /// from `wo` (world, unit, back along the ray), with `u` uniform in [0, 1): `None` where the
    /// ray meets the surface (a mask's opaque share, any other surface); else where it goes on.
    /// A mask is crossed with probability 1 − opacity; a pane transmits straight on or mirrors,
    /// as [`crate::bsdf::ThinDielectric::choose`] decides. The one rule paths, gathers and
    /// photons follow.
    #[must_use]
    pub fn see_through(&self, it: &Interaction, wo: Vec3, u: f32) -> Option<Passage> {
        let shape = &self.shapes[it.shape as usize];
        if shape.masked {
            return (u >= self.materials[shape.material].opacity(it.uv)).then_some(Passage {
                d: -wo,
                weight: Rgb::ONE,
                reflected: false,
                prob: 1.0,
            });
        }
        let sheet = self.thin_sheet(it, -wo)?;
        let cos = it.frame.n.dot(wo);
        let c = sheet.choose(cos, u);
        Some(Passage {
            d: if c.reflected {
                2.0 * cos * it.frame.n - wo
            } else {
                -wo
            },
            weight: c.weight,
            reflected: c.reflected,
            prob: c.prob,
        })
    }

    /// What reaches the end of a shadow ray: nothing where a surface blocks it, all where none
    /// does, and where it only crosses thin sheets (window panes) their transmittance at the
    /// angle it crosses them, `τ (1 − R')` each (Radiance's glass passes source rays the same
    /// way; Mitsuba 3 blocks them, so a sun behind a window never lights a room there), and
    /// masks what their opacity leaves.
    #[inline]
    #[must_use]
    pub fn shadow_transmittance(&self, ray: &Ray) -> Rgb {
        if !self.has_see_through {
            return if self.accel.occluded(ray) {
                Rgb::ZERO
            } else {
                Rgb::ONE
            };
        }
        self.transmittance_through(ray)
    }

    /// [`Scene::shadow_transmittance`] for the light sample of a light no path can hit (a
    /// distant, point or spot light): smooth `trans` surfaces pass it too, with their straight
    /// transmittance at the angle crossed (Radiance's `normal.c` lets shadow rays through them);
    /// a path that crosses them that way is the material's straight lobe, and cannot reach such
    /// a light, so nothing is counted twice.
    #[must_use]
    pub fn delta_shadow_transmittance(&self, ray: &Ray) -> Rgb {
        if !self.has_straight_trans {
            return self.shadow_transmittance(ray);
        }
        let passes = |it: &Interaction, d: Vec3| {
            let shape = &self.shapes[it.shape as usize];
            if shape.straight_trans {
                it.bsdf(&self.materials[shape.material], d)
                    .straight_transmittance(it.ng.dot(d))
            } else {
                self.passed_by(it, d)
            }
        };
        match self.cross(ray, passes) {
            (None, tr) => tr,
            (Some(_), _) => Rgb::ZERO,
        }
    }

    #[inline(never)]
    fn transmittance_through(&self, ray: &Ray) -> Rgb {
        match self.intersect_opaque(ray) {
            (None, tr) => tr,
            (Some(_), _) => Rgb::ZERO,
        }
    }

    /// The first opaque surface along `ray`, with the transmittance of what it crossed before:
    /// thin sheets, `τ (1 − R')` each at the angle crossed, and masks, 1 − their opacity there.
    /// What a BSDF sample that sees through panes and cut-outs finds (as light samples do).
    /// Past [`MAX_SHEET_CROSSINGS`] crossings, nothing with zero transmittance.
    #[must_use]
    pub fn intersect_opaque(&self, ray: &Ray) -> (Option<Interaction>, Rgb) {
        if !self.has_see_through {
            return (self.intersect(ray), Rgb::ONE);
        }
        self.cross(ray, |it, d| self.passed_by(it, d))
    }

    /// The first surface along `ray` that `passes` lets no light through (`None`), with the
    /// product of what the surfaces before it let through; past [`MAX_SHEET_CROSSINGS`]
    /// crossings, nothing with zero transmittance.
    fn cross(
        &self,
        ray: &Ray,
        passes: impl Fn(&Interaction, Vec3) -> Option<Rgb>,
    ) -> (Option<Interaction>, Rgb) {
        let end = ray.t_max.is_finite().then(|| ray.o + ray.d * ray.t_max);
        let mut ray = *ray;
        let mut tr = Rgb::ONE;
        for _ in 0..MAX_SHEET_CROSSINGS {
            let Some(it) = self.intersect(&ray) else {
                return (None, tr);
            };
            let Some(passed) = passes(&it, ray.d) else {
                return (Some(it), tr);
            };
            tr *= passed;
            // On from just beyond the sheet, to the same end.
            let o = offset_ray_origin(it.p, it.ng, ray.d, self.scale);
            let Some(next) = ray_on_to(o, ray.d, end) else {
                return (None, tr);
            };
            ray = next;
        }
        (None, Rgb::ZERO)
    }

    /// What a shadow ray along `d` keeps crossing the surface at `it`: a thin sheet's
    /// transmittance at that angle, what a mask's opacity leaves open there; `None` where the
    /// surface is opaque.
    #[must_use]
    pub fn passed_by(&self, it: &Interaction, d: Vec3) -> Option<Rgb> {
        let shape = &self.shapes[it.shape as usize];
        if shape.masked {
            let open = 1.0 - self.materials[shape.material].opacity(it.uv);
            return (open > 0.0).then(|| Rgb::splat(open));
        }
        self.thin_sheet(it, d)
            .map(|sheet| sheet.transmittance(it.frame.n.dot(d)))
    }

    /// The interaction where `ray` meets triangle `prim` of mesh shape `shape` (Möller and
    /// Trumbore), as Embree would report it; `None` when it misses that triangle or the shape
    /// is not a mesh. For hits found another way (a rasteriser's visibility).
    #[must_use]
    pub fn hit_triangle(&self, ray: &Ray, shape: u32, prim: u32) -> Option<Interaction> {
        let ShapeGeometry::Mesh(mesh) = &self.shapes.get(shape as usize)?.geometry else {
            return None;
        };
        let [i0, i1, i2] = *mesh.indices.get(prim as usize)?;
        let p = |i: u32| mesh.positions[i as usize];
        let (p0, p1, p2) = (p(i0), p(i1), p(i2));
        let (e1, e2) = (p1 - p0, p2 - p0);
        let q = ray.d.cross(e2);
        let det = e1.dot(q);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let s = ray.o - p0;
        let u = s.dot(q) / det;
        let r = s.cross(e1);
        let v = ray.d.dot(r) / det;
        let t = e2.dot(r) / det;
        if !(0.0..=1.0).contains(&u)
            || v < 0.0
            || u + v > 1.0
            || !(ray.t_min..=ray.t_max).contains(&t)
        {
            return None;
        }
        let hit = ircache_embree::Hit {
            t,
            geom_id: shape,
            prim_id: prim,
            u,
            v,
            ng: e1.cross(e2),
        };
        Some(self.interaction(ray, &hit))
    }

    /// Builds the surface interaction of an Embree hit. Inlined: returned through memory, the
    /// interaction was copied whole out of its fields' separate stores (a store-forwarding stall
    /// at every vertex).
    #[inline(always)]
    pub fn interaction(&self, ray: &Ray, hit: &ircache_embree::Hit) -> Interaction {
        let shape = &self.shapes[hit.geom_id as usize];
        match &shape.geometry {
            ShapeGeometry::Mesh(_) if shape.flat => {
                // Embree's Ng is (p1 − p0) × (p2 − p0), the same winding as below.
                let ng = hit.ng.normalize_or(Vec3::Z);
                Interaction {
                    p: ray.at(hit.t),
                    ng,
                    frame: Frame::from_z(ng),
                    base_n: ng,
                    uv: Vec2::new(hit.u, hit.v),
                    shape: hit.geom_id,
                    prim: hit.prim_id,
                    t: hit.t,
                }
            }
            ShapeGeometry::Mesh(m) => {
                let [i0, i1, i2] = m.indices[hit.prim_id as usize].map(|i| i as usize);
                let (b1, b2) = (hit.u, hit.v);
                let b0 = 1.0 - b1 - b2;
                let (p0, p1, p2) = (m.positions[i0], m.positions[i1], m.positions[i2]);
                let p = b0 * p0 + b1 * p1 + b2 * p2;
                let ng = (p1 - p0)
                    .cross(p2 - p0)
                    .normalize_or(hit.ng.normalize_or(Vec3::Z));
                let ns = match &m.normals {
                    Some(n) => (b0 * n[i0] + b1 * n[i1] + b2 * n[i2]).normalize_or(ng),
                    None => ng,
                };
                let uv = match &m.uvs {
                    Some(t) => b0 * t[i0] + b1 * t[i1] + b2 * t[i2],
                    None => Vec2::new(b1, b2),
                };
                let mut dpdu = p1 - p0;
                let material = &self.materials[shape.material];
                let mut frame = match material.radiance_texture() {
                    Some(t) => Frame::from_normal_tangent(
                        radiance_normal(ns, t.displacement(p, ns, ray.d, hit.t, uv), ray.d),
                        dpdu,
                    ),
                    None => Frame::from_normal_tangent(ns, dpdu),
                };
                if let (Some(perturb), Some(t)) = (material.perturbation(), &m.uvs) {
                    // dp/du and dp/dv from the triangle's texture coordinates.
                    let (d1, d2) = (t[i0] - t[i2], t[i1] - t[i2]);
                    let (e1, e2) = (p0 - p2, p1 - p2);
                    let det = d1.x * d2.y - d1.y * d2.x;
                    if det.abs() > f32::MIN_POSITIVE {
                        dpdu = (e1 * d2.y - e2 * d1.y) / det;
                        let dpdv = (e2 * d1.x - e1 * d2.x) / det;
                        let n = perturb.normal(uv, ns, ng, dpdu, dpdv, -ray.d);
                        frame = Frame::from_normal_tangent(n, dpdu);
                    }
                }
                Interaction {
                    p,
                    ng,
                    frame,
                    base_n: ns,
                    uv,
                    shape: hit.geom_id,
                    prim: hit.prim_id,
                    t: hit.t,
                }
            }
            &ShapeGeometry::Sphere {
                center,
                radius,
                flip_normals,
                to_object,
            } => {
                let p_raw = ray.at(hit.t);
                let local = (p_raw - center).normalize_or(Vec3::Z);
                // Re-project onto the sphere: the analytic hit is more accurate than o + t d.
                let p = center + local * radius;
                let n = if flip_normals { -local } else { local };
                // Mitsuba's parametrisation, in the sphere's own frame: u the azimuth from its
                // x axis, v the polar angle from its z axis.
                let o = to_object * local;
                let tau = 2.0 * ircache_math::PI;
                let uv = sphere_uv(o);
                let material = &self.materials[shape.material];
                let perturbation = material.perturbation();
                let textured = material
                    .radiance_texture()
                    .map(|t| radiance_normal(n, t.displacement(p, n, ray.d, hit.t, uv), ray.d));
                let mut frame = Frame::from_z(textured.unwrap_or(n));
                if perturbation.is_some() || !material.is_tangent_free() {
                    // dp/du = 2πR (−y, x, 0) and dp/dv = πR (z cos φ, z sin φ, −sin θ) in the
                    // sphere's frame (Mitsuba's), turned to the world's.
                    let to_world = to_object.transpose();
                    let dpdu = to_world * (Vec3::new(-o.y, o.x, 0.0) * (tau * radius));
                    let sin_t = (o.x * o.x + o.y * o.y).sqrt();
                    let (cos_p, sin_p) = if sin_t > 0.0 {
                        (o.x / sin_t, o.y / sin_t)
                    } else {
                        (1.0, 0.0)
                    };
                    let dpdv = to_world
                        * (Vec3::new(o.z * cos_p, o.z * sin_p, -sin_t) * (0.5 * tau * radius));
                    if dpdu.length_squared() > 0.0 {
                        let shading = match perturbation {
                            Some(perturb) => perturb.normal(uv, n, n, dpdu, dpdv, -ray.d),
                            None => textured.unwrap_or(n),
                        };
                        frame = Frame::from_normal_tangent(shading, dpdu);
                    }
                }
                Interaction {
                    p,
                    ng: n,
                    frame,
                    base_n: n,
                    uv,
                    shape: hit.geom_id,
                    prim: hit.prim_id,
                    t: hit.t,
                }
            }
        }
    }

    /// The factor by which a bump or normal map scales the BSDF at `it` for light along the
    /// world direction `wi`, as Mitsuba's perturbed BSDFs: 0 where `wi` and the perturbed
    /// frame lie on different sides of the unperturbed surface, else the shadowing function
    /// (Mitsuba's default, [`crate::bsdf::Perturbation::shadowing`]); 1 on other surfaces.
    /// Applied to BSDF values and sample weights, never to densities. Light samples lacked the
    /// side test that BSDF samples had: on `scenes/bumps` under a sky, `path` read 3.6 %
    /// and light samples alone 8 % above Mitsuba on the bumped ground.
    #[inline]
    #[must_use]
    pub fn perturbed_shadowing(&self, it: &Interaction, wi: Vec3) -> f32 {
        if !self.has_perturbed {
            return 1.0;
        }
        self.perturbed_shadowing_at(it, wi)
    }

    /// [`Scene::perturbed_shadowing`] in a scene with bump or normal maps: out of line, for
    /// inlined, LLVM computed its terminator term (a division) on every light sample of every
    /// scene, ahead of the flag's check.
    #[cold]
    #[inline(never)]
    fn perturbed_shadowing_at(&self, it: &Interaction, wi: Vec3) -> f32 {
        let Some(p) = self.perturbation_at(it) else {
            return 1.0;
        };
        // Mitsuba's perturbed BSDFs answer 0 where the light and the perturbed frame lie on
        // different sides of the unperturbed surface.
        if wi.dot(it.base_n) * wi.dot(it.frame.n) <= 0.0 {
            return 0.0;
        }
        p.shadowing(it.base_n, it.frame.n, wi)
    }

    /// The factor for a Lambertian part served by a cache's irradiance at a perturbed `it`
    /// ([`crate::bsdf::Perturbation::lambertian_share`]); 1 on other surfaces.
    #[inline]
    #[must_use]
    pub fn perturbed_lambertian_share(&self, it: &Interaction) -> f32 {
        self.perturbation_at(it)
            .map_or(1.0, |p| p.lambertian_share(it.base_n, it.frame.n))
    }

    /// The bump or normal map at `it`; scenes without one answer from a flag, without looking
    /// at the shape.
    #[inline]
    fn perturbation_at(&self, it: &Interaction) -> Option<&crate::bsdf::Perturbation> {
        if !self.has_perturbed {
            return None;
        }
        let shape = &self.shapes[it.shape as usize];
        if !shape.perturbed {
            return None;
        }
        self.materials[shape.material].perturbation()
    }

    /// A ray leaving surface point `it` along `d`, offset against self-intersection.
    #[inline]
    #[must_use]
    pub fn spawn_ray(&self, it: &Interaction, d: Vec3) -> Ray {
        Ray::new(offset_ray_origin(it.p, it.ng, d, self.scale), d)
    }

    /// A shadow ray from `it` towards unit direction `wi` for a light at `distance` (may be
    /// infinite), shortened relatively so that it does not reach the light's own surface. A ray
    /// to a point is aimed from the offset origin at the point itself: kept parallel to `wi`, it
    /// would pass the point at the offset's distance, and near a curved light's silhouette hit
    /// the light before it.
    #[inline]
    #[must_use]
    pub fn shadow_ray(&self, it: &Interaction, wi: Vec3, distance: f32) -> Ray {
        self.shadow_ray_at(it.p, Some(it.ng), wi, distance)
    }

    /// [`Scene::shadow_ray`] from any point: offset along the geometric normal `ng` of the
    /// surface it lies on, or not at all for a point in a medium.
    #[inline]
    #[must_use]
    pub fn shadow_ray_at(&self, p: Vec3, ng: Option<Vec3>, wi: Vec3, distance: f32) -> Ray {
        let o = ng.map_or(p, |ng| offset_ray_origin(p, ng, wi, self.scale));
        if !distance.is_finite() {
            return Ray {
                o,
                d: wi,
                t_min: 0.0,
                t_max: f32::INFINITY,
            };
        }
        let to_light = p + wi * distance - o;
        let length = to_light.length();
        let d = if length > 0.0 { to_light / length } else { wi };
        Ray {
            o,
            d,
            t_min: 0.0,
            t_max: length * (1.0 - ircache_math::ray::SHADOW_EPSILON),
        }
    }
}
