//! Computing records: the stratified hemisphere gather (000 eqs. 3.4–3.5) from a surface point,
//! shading what each gather ray finds, and turning the samples into a record with its radius
//! limits (003 items 3–4) and gradients.
//!
//! A gather ray that hits an emitter gets no emission (the direct term samples lights), nor does
//! one that escapes to an environment; every surface it finds is shaded with one light sample
//! plus, below the last bounce, the next level's cached irradiance (004's per-bounce caches), or
//! at the last bounce the ambient value. Records needed at deeper levels during a batch go to a
//! private overlay of the work item, so the batch's result does not depend on thread timing.

use super::environment::{decide, HeldEnvironment};
use super::hemisphere::{largest_eigenvalue, to_world, HemisphereSamples, Stratification};
pub use super::params::Deeper;
use super::params::RecordSource;
use super::params::{IcParams, TranslationalFormula};
use super::plane::{HemispherePlane, PlaneMeasure, PlaneSource};
use super::record::{ErrorMetric, Record, NO_RADIANCE};
use super::store::RecordStore;
use crate::integrators::path_continuation::{
    trace_path, Arrival, FirstVertex, IndirectSource, PathSettings, PathStart,
};
use crate::integrators::RayCounts;
use crate::photon_map::PhotonMaps;
use crate::radiance_cache::brdf::BrdfCoefficients;
use crate::radiance_cache::gather::RadianceCoefficients;
use crate::radiance_cache::record::RadianceRecord;
use crate::radiance_cache::RadianceCache;
use crate::scene::{Interaction, Scene};
use ircache_math::{Frame, Ray, Rgb, Rng, Vec2, Vec3};
use std::sync::Arc;

/// The records of every bounce level, and the settings they were made with.
#[derive(Clone, Debug)]
pub struct IrradianceCache {
    /// Settings.
    pub params: IcParams,
    /// One store per bounce level.
    pub levels: Vec<RecordStore>,
    /// Smallest record radius.
    pub r_min: f32,
    /// Largest record radius.
    pub r_max: f32,
    /// Cell size of the stores' finest grid level.
    pub base_cell: f32,
    /// The radiance beyond the last bounce now: the ambient value, or with an ambient weight
    /// its running average with what the cache has computed.
    pub ambient: Rgb,
    /// Area-weighted mean diffuse albedo (luminance) of the scene's surfaces.
    pub mean_albedo: f32,
    /// How a pixel's footprint grows from the camera: Tabellion's radius limits are
    /// `footprint_limits` pixel footprints at a level-0 record; none without a camera view.
    pub pixel_spread: crate::camera::PixelSpread,
    /// Shapes excluded from the cache (003 item 6), by shape index: they get the ambient value
    /// as their indirect light instead of records.
    pub excluded: Vec<bool>,
    /// Radiance caching's tables (`--radiance-cache auto|on`).
    pub radiance: Option<Arc<RadianceCache>>,
    /// The radiance records' coefficients, indexed by [`Record::radiance`].
    pub radiance_records: Vec<RadianceRecord>,
    /// Which records hold the environment's light ([`super::environment`]).
    pub environment: HeldEnvironment,
    /// The share of the environment's light reaching the surfaces in view, where `auto`
    /// measured it to choose [`Self::environment`] (for its note).
    pub environment_visibility: Option<f64>,
    /// The photon maps (`--photons`, `--caustic-photons`): the global map serves the vertices
    /// beyond a record's gather hits, the caustic map adds caustics where records serve.
    pub photons: Option<Arc<PhotonMaps>>,
    /// The plane above first-level records with `--record-source plane` or `gpu-plane`.
    pub plane: Option<Arc<HemispherePlane>>,
    /// Where `--record-source gpu-plane` has its planes made (the caller attaches it).
    pub plane_source: Option<Arc<dyn PlaneSource>>,
}

/// Pixels per side of a record's plane (`--record-source plane`): the thesis's 64.
pub const PLANE_PIXELS: usize = 64;
/// Half-size of the plane at distance 1: 143° across. NOTES-001 infers 2 (127°) from Table
/// 4.1; by that table's protocol 3 errs less on Sponza, the Cornell box and the lamp room (RMS
/// 22.8, 5.0, 20.3 % against 26.1, 8.3, 26.5 %; BENCHMARKS.md), 4 no better.
pub const PLANE_HALF_SIZE: f64 = 3.0;

/// A ray shorter than this many photon-disc radii goes on past the photon map (see
/// [`IrradianceCache::photon_irradiance`]).
pub(crate) const SHORT_RAY: f32 = 1.0;

impl IrradianceCache {
    /// An empty cache for `scene`.
    #[must_use]
    pub fn new(scene: &Scene, params: &IcParams) -> IrradianceCache {
        let mut cache = IrradianceCache::for_size(scene_size(scene), params);
        // Only the ambient running average needs it.
        if params.ambient_weight > 0 {
            cache.mean_albedo = mean_albedo(scene);
        }
        cache.excluded = vec![false; scene.shapes.len()];
        (cache.environment, cache.environment_visibility) =
            decide(scene, params.cached_environment);
        cache
    }

    /// Adds a record read from a file or made by another process to its level's store, its
    /// radiance coefficients (if any) to the cache's list; false when it has no level here.
    pub fn insert_stored(
        &mut self,
        (mut record, radiance): crate::irradiance_cache::file::Stored,
    ) -> bool {
        if record.level as usize >= self.levels.len() {
            return false;
        }
        record.radiance = match radiance {
            Some(c) if self.radiance.is_some() => {
                self.radiance_records
                    .push(RadianceRecord::new(record.p, record.n, c));
                (self.radiance_records.len() - 1) as u32
            }
            _ => NO_RADIANCE,
        };
        self.levels[record.level as usize].insert(record);
        true
    }

    /// A record of this cache as a file holds it (the inverse of [`Self::insert_stored`]).
    #[must_use]
    pub fn stored(&self, record: &Record) -> crate::irradiance_cache::file::Stored {
        let radiance = self
            .radiance_records
            .get(record.radiance as usize)
            .map(|r| r.radiance.clone());
        (
            Record {
                radiance: NO_RADIANCE,
                ..*record
            },
            radiance,
        )
    }

    /// The normalised error at which records cover `sp`: 1, or on a radiance-cached surface the
    /// radiance accuracy over the accuracy (finer).
    #[must_use]
    pub fn coverage_threshold(&self, sp: &ShadingPoint) -> f32 {
        match &self.radiance {
            Some(r) if r.brdf_at(sp).is_some() => {
                (self.params.radiance_accuracy / self.params.accuracy).min(1.0)
            }
            _ => 1.0,
        }
    }

    /// Moves a new record's radiance coefficients from its work state's list `made` into the
    /// cache's, pointing the record at their new place (a no-op for records without): into the
    /// place `replacing` (the coefficients of the record it replaces) when that is one, else at
    /// the end.
    pub fn adopt_radiance(
        &mut self,
        record: &mut Record,
        made: &mut [RadianceRecord],
        replacing: u32,
    ) {
        if record.radiance == NO_RADIANCE {
            return;
        }
        let Some(slot) = made.get_mut(record.radiance as usize) else {
            record.radiance = NO_RADIANCE;
            return;
        };
        let coefficients = std::mem::take(slot);
        match self.radiance_records.get_mut(replacing as usize) {
            Some(old) => {
                *old = coefficients;
                record.radiance = replacing;
            }
            None => {
                record.radiance = self.radiance_records.len() as u32;
                self.radiance_records.push(coefficients);
            }
        }
    }

    /// An empty cache for a scene of size `size` (no shape excluded, no mean albedo): what
    /// records need besides the light they gather.
    #[must_use]
    pub fn for_size(size: f32, params: &IcParams) -> IrradianceCache {
        let (r_min, r_max) = params.radius_limits(size);
        let mut cache = IrradianceCache {
            params: params.clone(),
            levels: Vec::new(),
            r_min,
            r_max,
            // Finest grid cell: the smallest validity radius (a fraction of the scene without
            // a minimum spacing).
            base_cell: if r_min > 0.0 {
                params.accuracy * r_min
            } else {
                size * 1e-4
            },
            ambient: params.ambient_value,
            mean_albedo: 0.0,
            excluded: Vec::new(),
            radiance: None,
            radiance_records: Vec::new(),
            pixel_spread: crate::camera::PixelSpread::default(),
            environment: HeldEnvironment::None,
            environment_visibility: None,
            photons: None,
            plane: (params.record_source != RecordSource::Gather)
                .then(|| Arc::new(HemispherePlane::new(PLANE_PIXELS, PLANE_HALF_SIZE))),
            plane_source: None,
        };
        cache.levels = (0..params.bounces.clamp(1, super::params::MAX_STORED_LEVELS))
            .map(|_| cache.empty_store())
            .collect();
        cache
    }

    /// Irradiance from the global photon map at a vertex at `depth` of a path, from photons that
    /// can end there within the bounces (001 §2.4's final gather); `None` without a global map, and where the ray that
    /// found the vertex is shorter than the estimate's disc is wide (Jensen's rule for short
    /// gather rays: near a corner the disc averages light the vertex does not get, −4 to −6 %
    /// measured 2 cm below a Cornell box's ceiling), so the path goes on there.
    #[must_use]
    pub fn photon_irradiance(&self, sp: &ShadingPoint, depth: u32) -> Option<Rgb> {
        let maps = self
            .photons
            .as_ref()
            .filter(|_| self.params.global_photons() > 0)?;
        let bounces = self.photon_bounces(depth);
        let (e, radius) =
            maps.global
                .irradiance_and_radius(sp.it.p, sp.n, bounces, &maps.global_lookup);
        (sp.it.t >= SHORT_RAY * radius).then_some(e)
    }

    /// Irradiance of caustics from the caustic map at a vertex at `depth` where records serve
    /// (zero without a caustic map).
    #[must_use]
    pub fn caustic_irradiance(&self, sp: &ShadingPoint, depth: u32) -> Rgb {
        let Some((map, lookup)) = self
            .photons
            .as_ref()
            .and_then(|m| m.caustic.as_ref().map(|c| (c, &m.caustic_lookup)))
        else {
            return Rgb::ZERO;
        };
        map.irradiance(sp.it.p, sp.n, self.photon_bounces(depth), lookup)
    }

    /// The most bounces a photon landing at a vertex at `depth` may have taken: one of b
    /// bounces ends a path of depth + b + 2 vertices, which `max_depth` bounds.
    fn photon_bounces(&self, depth: u32) -> u16 {
        crate::photon_map::bounce_limit(self.params.max_depth().saturating_sub(depth + 2))
    }

    /// True when a caustic map serves the caustics at records' vertices: their gathers leave
    /// out emitters reached through delta lobes alone.
    #[must_use]
    pub fn caustics_served(&self) -> bool {
        self.photons.as_ref().is_some_and(|m| m.caustic.is_some())
    }

    /// Which records serving `sp` hold the environment's light (none on excluded surfaces).
    #[inline]
    #[must_use]
    pub fn held_environment_at(&self, sp: &ShadingPoint) -> HeldEnvironment {
        if self.is_excluded(sp.it.shape) {
            HeldEnvironment::None
        } else {
            self.environment
        }
    }

    /// True when shape `shape` takes no records.
    #[inline]
    #[must_use]
    pub fn is_excluded(&self, shape: u32) -> bool {
        self.excluded.get(shape as usize).copied().unwrap_or(false)
    }

    /// With an ambient weight w > 0 (003 item 1), the radiance beyond the last bounce becomes
    /// (w · av + n · ρ̄ Ē/π) / (w + n) over the n last-level records: Ē/π is the mean radiance
    /// arriving at the last level's points, and ρ̄ times it is the first term of what follows
    /// (the rest of the series is left out, so the estimate stays low: over-estimating the
    /// ambient term is worse than under-estimating it).
    pub fn update_ambient(&mut self) {
        let w = self.params.ambient_weight;
        if w == 0 {
            return;
        }
        let last = &self.levels[self.levels.len() - 1];
        let n = last.len();
        if n == 0 {
            return;
        }
        // Weighted by the area each record serves (r²): records crowd into dark corners.
        let (mut sum, mut wsum) = (Rgb::ZERO, 0.0f64);
        for r in last.records() {
            let w = f64::from(r.r) * f64::from(r.r);
            sum += r.e * w as f32;
            wsum += w;
        }
        let mean_e = if wsum > 0.0 {
            sum / wsum as f32
        } else {
            Rgb::ZERO
        };
        let tail = mean_e * (self.mean_albedo * ircache_math::INV_PI);
        self.ambient =
            (self.params.ambient_value * w as f32 + tail * n as f32) / (w as f32 + n as f32);
    }

    /// An empty store shaped like this cache's stores.
    #[must_use]
    pub fn empty_store(&self) -> RecordStore {
        RecordStore::new(
            self.base_cell,
            self.params.accuracy,
            self.params.error_metric,
            self.params.neighbour_clamp,
        )
    }

    /// Makes level `level` hold `records`, indexed anew in their order at the cache's current
    /// settings (after radii or the accuracy changed).
    pub fn reindex(&mut self, level: usize, records: Vec<Record>) {
        let mut store = self.empty_store();
        for r in records {
            store.insert(r);
        }
        self.levels[level] = store;
    }
}

/// Area-weighted mean luminance of the diffuse albedo over the scene's triangles (spheres by
/// their area).
fn mean_albedo(scene: &Scene) -> f32 {
    let (mut sum, mut area) = (0.0f64, 0.0f64);
    for s in &scene.shapes {
        let a = match &s.geometry {
            crate::scene::ShapeGeometry::Mesh(m) => ircache_scene::shapes::mesh_area(m),
            crate::scene::ShapeGeometry::Sphere { radius, .. } => {
                4.0 * std::f64::consts::PI * f64::from(*radius).powi(2)
            }
        };
        let rho = scene.materials[s.material]
            .mean_diffuse_reflectance()
            .luminance();
        sum += a * f64::from(rho);
        area += a;
    }
    if area > 0.0 {
        (sum / area).clamp(0.0, 1.0) as f32
    } else {
        0.0
    }
}

/// The scene size used for record spacing: the largest extent of the bounding box (Radiance's
/// octree cube).
#[must_use]
pub fn scene_size(scene: &Scene) -> f32 {
    // The bounding sphere's diameter over √3 is the cube edge of a cubic box; good enough and
    // scale-free.
    (2.0 * scene.radius / 3f32.sqrt()).max(f32::MIN_POSITIVE)
}

/// Counters of one work item or pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GatherCounts {
    /// Hemisphere rays traced.
    pub gather_rays: u64,
    /// Shadow rays traced for the surfaces gather rays found.
    pub shadow_rays: u64,
    /// Records computed.
    pub records: u64,
    /// Cells adaptive super-sampling refined (three more rays each).
    pub supersampled_cells: u64,
}

impl GatherCounts {
    /// Adds another count.
    pub fn add(&mut self, o: &GatherCounts) {
        self.gather_rays += o.gather_rays;
        self.shadow_rays += o.shadow_rays;
        self.records += o.records;
        self.supersampled_cells += o.supersampled_cells;
    }
}

/// Private state of one work item: records it made at deeper levels (visible to itself only
/// until the batch is merged), in the order they were made.
#[derive(Debug)]
pub struct WorkState {
    overlay: Vec<Option<RecordStore>>,
    /// Records made, in order, with the points they were gathered at and their gathers' keys.
    pub new_records: Vec<(Record, ShadingPoint, u64)>,
    /// Radiance coefficients of the records made (their [`Record::radiance`] indexes this
    /// until they are inserted into the cache, which moves these to its own list).
    pub radiance: Vec<RadianceRecord>,
    /// Counters.
    pub counts: GatherCounts,
    /// With a [`NextFrameEstimator`], the estimates of the records the work item's gatherer made
    /// itself, in order (records its paths made at deeper levels have none).
    pub estimates: Vec<NextEstimate>,
}

impl WorkState {
    /// An empty state for a cache with `levels` levels.
    #[must_use]
    pub fn new(levels: usize) -> WorkState {
        WorkState {
            overlay: vec![None; levels],
            new_records: Vec::new(),
            radiance: Vec::new(),
            counts: GatherCounts::default(),
            estimates: Vec::new(),
        }
    }
}

/// One gather ray as the gather traced it: enough to carry it to another frame (temporal
/// caching's reprojection, 001 §5.2.4).
#[derive(Clone, Copy, Debug)]
pub struct TracedSample {
    /// Its cell, `j * N + k`.
    pub cell: u32,
    /// The key of its own random stream ([`sample_rng`]).
    pub key: u64,
    /// Its direction in the record's frame, as the cell's stratum drew it.
    pub local: Vec3,
    /// The ray (world space, unit direction).
    pub ray: Ray,
    /// What it found.
    pub found: TracedHit,
}

/// What a traced gather ray found.
#[derive(Clone, Copy, Debug)]
pub enum TracedHit {
    /// A surface, where the light source reported it.
    Surface(Interaction),
    /// A surface a light source without a scene found (a closed form): it cannot be carried.
    Opaque(Rgb, f32),
    /// Nothing: the environment's radiance, into the cell's radiance and kept apart.
    Escaped(Rgb, Rgb),
    /// A direction below the geometric surface.
    Below,
}

/// A record's value in the next frame, estimated while the record is made.
#[derive(Clone, Debug)]
pub struct NextEstimate {
    /// The record as it would be gathered in the next frame (at its moved place).
    pub record: Record,
    /// Its incoming radiance in HSH where the record holds it.
    pub radiance: Option<RadianceRecord>,
    /// Rays the estimate traced.
    pub counts: GatherCounts,
}

/// Estimates each record's next-frame value from its gather's traced samples as the record is
/// made (temporal caching; [`crate::temporal::reprojection`]).
pub trait NextFrameEstimator: Sync {
    /// The next frame's record at the place of the record gathered at `sp` for `level` with
    /// `strata` on `seed`, whose samples were `samples`.
    fn estimate(
        &self,
        seed: u64,
        sp: &ShadingPoint,
        level: u32,
        strata: Stratification,
        samples: &[TracedSample],
    ) -> NextEstimate;
}

/// The random stream of the gather sample keyed `key` for `level` on `seed`: what it draws
/// never shifts another sample's numbers.
#[must_use]
pub fn sample_rng(seed: u64, key: u64, level: u32) -> Rng {
    Rng::keyed(seed, &[SAMPLE_SALT, key, u64::from(level)])
}

/// What a gather ray finds: the radiance arriving along it, the distance to the surface it
/// comes from and that surface's geometric normal (world space).
#[derive(Clone, Copy, Debug)]
pub struct Incident {
    /// Radiance arriving (emission of the surface found left out: direct terms sample lights).
    pub radiance: Rgb,
    /// Distance to the surface.
    pub distance: f32,
    /// Its geometric normal.
    pub normal: Vec3,
    /// The ray and the surface it met, where a scene was traced (a closed form has none).
    pub hit: Option<(Ray, Interaction)>,
    /// `Some((d, τ))` where the ray crossed window panes or masks' open parts with throughput τ
    /// and then escaped along `d`: it brings what an escaping ray brings, the environment's
    /// radiance along `d`, times τ (`radiance` is then zero).
    pub escaped: Option<(Vec3, Rgb)>,
}

impl Incident {
    /// `radiance` arriving along `ray` from the surface `hit` it met.
    #[inline]
    #[must_use]
    pub fn found(radiance: Rgb, ray: Ray, hit: Interaction) -> Incident {
        Incident {
            radiance,
            distance: hit.t,
            normal: hit.ng,
            hit: Some((ray, hit)),
            escaped: None,
        }
    }

    /// What arrives along a gather ray in direction `d` whose trace gave `found` (`None`: it
    /// escaped): a surface's light, or `Err` with the escaped light's direction and throughput.
    #[inline]
    pub fn or_escaped(found: Option<Incident>, d: Vec3) -> Result<Incident, (Vec3, Rgb)> {
        match found {
            None => Err((d, Rgb::ONE)),
            Some(Incident {
                escaped: Some(e), ..
            }) => Err(e),
            Some(inc) => Ok(inc),
        }
    }
}

/// The narrow interface through which a cache's gather asks for light: the radiance arriving at
/// a point from a direction. [`SceneRadiance`] traces the scene; a test can answer in closed
/// form, so records are checked without a ray tracer.
pub trait IncidentRadiance: Sync {
    /// What arrives at `sp` from the unit world direction `d` (above the surface), for a record
    /// at bounce `level` of `cache` (`key` keys the random streams of records made on the way);
    /// `None` when the ray escapes (no radiance, infinitely far).
    #[allow(clippy::too_many_arguments)]
    fn incident(
        &self,
        cache: &IrradianceCache,
        seed: u64,
        st: &mut WorkState,
        sp: &ShadingPoint,
        d: Vec3,
        level: u32,
        key: u64,
        rng: &mut Rng,
    ) -> Option<Incident>;

    /// Radiance arriving from infinitely far along `d` when a gather ray escapes: the
    /// environment's, which records hold where the cache says so ([`super::environment`]). None
    /// by default.
    fn escaped(&self, d: Vec3) -> Rgb {
        let _ = d;
        Rgb::ZERO
    }
}

/// Computes records for one cache from the light an [`IncidentRadiance`] reports.
pub struct Gatherer<'a> {
    /// Where the light comes from.
    pub light: &'a dyn IncidentRadiance,
    /// The cache (read-only during a batch).
    pub cache: &'a IrradianceCache,
    /// Seed of all random streams.
    pub seed: u64,
    /// Who estimates each record's next frame as it is made (temporal caching), if anyone.
    pub next: Option<&'a dyn NextFrameEstimator>,
}

/// The share of the accuracy the second-order error may reach at a record's serving distance
/// (½ λ ρ² = CURVATURE_SHARE · a · E). Measured, three seeds each at the defaults, as blurred
/// relMSE_trim × time^1.25 (the path tracer's trade), against the rule before it: 0.25: Sponza
/// d3 −28 %, the lamp room −13 %; 0.1: −32 %, −26 %, the Cornell box −5 %, cornell-glossy d5
/// +1 %; 0.04 ties with 0.1 (−30 %, −27 %, −9 %, −4 %, for 5 % more time); 0.02 loses on three
/// of the four (BENCHMARKS.md).
const CURVATURE_SHARE: f32 = 0.1;

/// The distance at which a record gathered as `h` with irradiance `e` reaches the second-order
/// error `error·E` (½ λ ρ² = error · E, λ the largest eigenvalue of the translational Hessian of
/// E's luminance by reprojection of the hits, as the Hessian metric's radius; Radiance's
/// ambHessian): infinite where E does not curve.
fn hessian_reach(h: &HemisphereSamples, e: Rgb, error: f32) -> f32 {
    let lambda = largest_eigenvalue(h.translational_hessian());
    let y = f64::from(e.luminance());
    if lambda > 0.0 && y > 0.0 {
        (2.0 * f64::from(error) * y / lambda).sqrt() as f32
    } else {
        f32::INFINITY
    }
}

/// Incident radiance by tracing the scene: a gather ray's path is continued by [`trace_path`]
/// to the cache's depth, the Lambertian parts of deeper vertices served by the next levels'
/// caches or traced ([`Deeper`]).
pub struct SceneRadiance<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Where deeper indirect light comes from.
    pub deeper: Deeper,
}

/// A surface point with the normal of the side being shaded.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint {
    /// The interaction (for spawning rays).
    pub it: Interaction,
    /// Shading normal before any normal or bump map, turned towards the viewer: records are
    /// gathered around it and weighted by it (003 item 5).
    pub n: Vec3,
    /// Shading normal after the normal or bump map, on the same side: interpolation turns the
    /// records' irradiance towards it through the rotational gradient.
    pub n_bump: Vec3,
    /// Cosine between the viewing direction and `n` (1 for query points).
    pub cos_view: f32,
    /// Length of the whole path from the camera to this point (0 when not reached from the
    /// camera): with the viewing angle, it gives the pixel footprint (000 eq. 3.60).
    pub travelled: f32,
}

impl ShadingPoint {
    /// The interaction seen from direction `wo` (unit, pointing away from the surface).
    #[must_use]
    pub fn facing(it: Interaction, wo: Vec3) -> ShadingPoint {
        let flip = it.base_n.dot(wo) < 0.0;
        let s = if flip { -1.0 } else { 1.0 };
        ShadingPoint {
            it,
            n: it.base_n * s,
            n_bump: it.frame.n * s,
            cos_view: it.base_n.dot(wo).abs(),
            travelled: it.t,
        }
    }
}

const GATHER_SALT: u64 = 0x6761_7468_6572;
/// Salt of each gather sample's own stream.
const SAMPLE_SALT: u64 = 0x7361_6d70_6c65;

/// Where the environment's light that a gather's escaping rays bring goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Escapes {
    /// Into the cells' radiance: the irradiance and the radiance record hold it.
    Irradiance,
    /// Into [`HemisphereSamples::escaped`]: the radiance record alone holds it.
    Apart,
    /// Nowhere: light samples estimate it.
    Dropped,
}

/// What one gather ray finds.
enum Found {
    /// A surface: the radiance arriving from it, its distance, its normal (local frame) and
    /// the surface where a scene was traced.
    Surface(Rgb, f32, Vec3, Option<(Ray, Interaction)>),
    /// Nothing: it escaped; the environment's radiance along it, into the cell's radiance and
    /// kept apart ([`Escapes`]).
    Escaped(Rgb, Rgb),
    /// The direction is below the geometric surface: nothing arrives.
    Below,
}

/// What the sample of cell `cell` along the local direction `local` (in `frame`) found, kept as
/// a [`TracedSample`].
fn traced_sample(
    sp: &ShadingPoint,
    frame: &Frame,
    cell: usize,
    key: u64,
    local: Vec3,
    found: &Found,
) -> TracedSample {
    let ray = |hit: Option<(Ray, Interaction)>| {
        hit.map_or(Ray::new(sp.it.p, frame.from_local(local)), |(ray, _)| ray)
    };
    let (ray, found) = match *found {
        Found::Surface(_, _, _, Some(hit)) => (ray(Some(hit)), TracedHit::Surface(hit.1)),
        Found::Surface(l, t, _, None) => (ray(None), TracedHit::Opaque(l, t)),
        Found::Escaped(into, apart) => (ray(None), TracedHit::Escaped(into, apart)),
        Found::Below => (ray(None), TracedHit::Below),
    };
    TracedSample {
        cell: cell as u32,
        key,
        local,
        ray,
        found,
    }
}

impl<'a> Gatherer<'a> {
    /// A gatherer of `light` for `cache` on seed `seed`, estimating no next frame.
    #[must_use]
    pub fn new(light: &'a dyn IncidentRadiance, cache: &'a IrradianceCache, seed: u64) -> Self {
        Gatherer {
            light,
            cache,
            seed,
            next: None,
        }
    }

    /// Gathers the hemisphere above `sp` with `strata`, shading the hits for `level`; keeps
    /// every ray it traces in `traced` when asked.
    pub fn gather(
        &self,
        st: &mut WorkState,
        sp: &ShadingPoint,
        strata: Stratification,
        level: u32,
        key: u64,
        mut traced: Option<&mut Vec<TracedSample>>,
    ) -> (HemisphereSamples, Frame) {
        let mut rng = Rng::keyed(self.seed, &[GATHER_SALT, key, u64::from(level)]);
        let frame = Frame::from_z(sp.n);
        let ng = if sp.it.ng.dot(sp.n) < 0.0 {
            -sp.it.ng
        } else {
            sp.it.ng
        };
        let mut h = HemisphereSamples::new(strata);
        // What escaped rays bring: into the irradiance (`all`), apart for the radiance record
        // (`glossy`, on radiance-cached surfaces), or nothing.
        let environment = match self.cache.environment {
            HeldEnvironment::All => Escapes::Irradiance,
            HeldEnvironment::Glossy if self.glossy_brdf(sp).is_some() => Escapes::Apart,
            _ => Escapes::Dropped,
        };
        let mut dirs = Vec::with_capacity(strata.cells());
        let mut jitter = vec![Vec2::ZERO; strata.cells()];
        let layout = self.cache.params.gather_pattern.layout(strata, &mut rng);
        strata.for_each_direction(
            |j, k| layout.jitter(j, k, rng.next_2d()),
            |j, k, u, d| {
                jitter[j * strata.azimuthal + k] = u;
                dirs.push((j, k, d));
            },
        );
        for (j, k, local) in dirs {
            let idx = j * strata.azimuthal + k;
            let sample_key = mix(key, idx as u64);
            let found = self.sample(st, sp, &frame, ng, local, level, sample_key, environment);
            if let Some(traced) = traced.as_deref_mut() {
                traced.push(traced_sample(sp, &frame, idx, sample_key, local, &found));
            }
            match found {
                Found::Surface(l, t, n_hit, _) => {
                    h.radiance[idx] = l;
                    h.distance[idx] = t;
                    h.hits[idx] = (local, n_hit);
                }
                Found::Escaped(into, apart) => {
                    h.radiance[idx] = into;
                    h.escaped[idx] = apart;
                }
                Found::Below => {}
            }
        }
        let extra = self.cache.params.supersamples;
        if extra > 0 {
            self.supersample(
                st,
                sp,
                &frame,
                ng,
                &mut h,
                &jitter,
                extra,
                level,
                key,
                environment,
                traced,
            );
        }
        (h, frame)
    }

    /// One gather ray along the local direction `local`: what it finds. The sample's shading
    /// draws on a stream of its own, keyed by `key`: what one sample draws never shifts
    /// another's numbers, so two gathers with the same key differ only in the samples whose
    /// scene differs (temporal caching's next-frame estimate relies on it).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn sample(
        &self,
        st: &mut WorkState,
        sp: &ShadingPoint,
        frame: &Frame,
        ng: Vec3,
        local: Vec3,
        level: u32,
        key: u64,
        environment: Escapes,
    ) -> Found {
        let d = frame.from_local(local);
        if d.dot(ng) <= 0.0 {
            return Found::Below;
        }
        st.counts.gather_rays += 1;
        let mut rng = sample_rng(self.seed, key, level);
        let found = self
            .light
            .incident(self.cache, self.seed, st, sp, d, level, key, &mut rng);
        match Incident::or_escaped(found, d) {
            Ok(inc) => Found::Surface(
                inc.radiance,
                inc.distance,
                frame.to_local(inc.normal),
                inc.hit,
            ),
            Err((out, tau)) => match environment {
                Escapes::Irradiance => Found::Escaped(self.light.escaped(out) * tau, Rgb::ZERO),
                Escapes::Apart => Found::Escaped(Rgb::ZERO, self.light.escaped(out) * tau),
                Escapes::Dropped => Found::Escaped(Rgb::ZERO, Rgb::ZERO),
            },
        }
    }

    /// Adaptive super-sampling (003 item 2): the cells whose neighbours differ most among
    /// themselves get three more rays each, as many cells as the record needs to bring its
    /// predicted relative error to the target ([`HemisphereSamples::cells_to_refine`]; every
    /// cell up to `extra` / 3 when the target is 0), placed with the first sample on a 2×2
    /// lattice shifted by that sample's jitter, so the cell stays stratified; it keeps the mean
    /// of its four samples and the nearest of their distances. The choice of cells never looks
    /// at a cell's own sample, which keeps the estimate unbiased (see
    /// [`HemisphereSamples::neighbour_spread`]).
    #[allow(clippy::too_many_arguments)]
    fn supersample(
        &self,
        st: &mut WorkState,
        sp: &ShadingPoint,
        frame: &Frame,
        ng: Vec3,
        h: &mut HemisphereSamples,
        jitter: &[Vec2],
        extra: usize,
        level: u32,
        key: u64,
        environment: Escapes,
        mut traced: Option<&mut Vec<TracedSample>>,
    ) {
        let strata = h.strata;
        let target = self.cache.params.record_error * self.cache.params.accuracy;
        let cells = h.cells_to_refine(target, extra / 3);
        const LATTICE: [(f32, f32); 3] = [(0.5, 0.5), (0.5, 0.0), (0.0, 0.5)];
        for &idx in &cells {
            let (j, k) = (idx / strata.azimuthal, idx % strata.azimuthal);
            let v = jitter[idx];
            let mut sum = h.radiance[idx];
            let mut escaped = h.escaped[idx];
            for (q, (dx, dy)) in LATTICE.iter().enumerate() {
                let u = Vec2::new((v.x + dx).fract(), (v.y + dy).fract());
                let local = strata.direction(j, k, u);
                let sample_key = mix(key, (strata.cells() + 3 * idx + q) as u64);
                let found = self.sample(st, sp, frame, ng, local, level, sample_key, environment);
                if let Some(traced) = traced.as_deref_mut() {
                    traced.push(traced_sample(sp, frame, idx, sample_key, local, &found));
                }
                match found {
                    Found::Surface(l, t, n_hit, _) => {
                        sum += l;
                        // The nearest surface in the cell moves its walls (3.42, 3.46).
                        if t < h.distance[idx] {
                            h.distance[idx] = t;
                            h.hits[idx] = (local, n_hit);
                        }
                    }
                    Found::Escaped(into, apart) => {
                        sum += into;
                        escaped += apart;
                    }
                    Found::Below => {}
                }
            }
            h.radiance[idx] = sum * 0.25;
            h.escaped[idx] = escaped * 0.25;
        }
        st.counts.supersampled_cells += cells.len() as u64;
    }

    /// A record at `sp` for bounce `level`: gather, then limit the radius.
    pub fn record_at(&self, st: &mut WorkState, sp: &ShadingPoint, level: u32, key: u64) -> Record {
        if let (0, Some(plane)) = (level, self.cache.plane.as_deref()) {
            // A record from its plane: the GPU's (one point at a time here; the pre-pass asks
            // for a batch's at once), else ray cast on the CPU, the same estimator.
            let from_gpu = match (self.cache.params.record_source, &self.cache.plane_source) {
                (RecordSource::GpuPlane, Some(source)) => source.measure(&[*sp]).ok(),
                _ => None,
            };
            let measure = from_gpu
                .and_then(|m| m.first().copied())
                .unwrap_or_else(|| {
                    let pixels = plane.sample(self, st, sp, level, key);
                    plane.measure(sp, &pixels)
                });
            return self.record_from_plane(st, sp, level, &measure);
        }
        // A radiance record weighs its cells by the glossy lobe: it needs as many more rays as
        // the lobe is narrower than the cosine.
        let factor = self.glossy_brdf(sp).map_or(1.0, |b| b.ray_factor());
        let divisions = (self.cache.params.divisions as f64 * factor).round() as usize;
        let strata = Stratification::from_divisions(divisions);
        self.record_with(st, sp, level, key, strata)
    }

    /// A record gathered with `strata` instead of the cache's divisions.
    pub fn record_with(
        &self,
        st: &mut WorkState,
        sp: &ShadingPoint,
        level: u32,
        key: u64,
        strata: Stratification,
    ) -> Record {
        let mut traced = self.next.map(|_| Vec::new());
        let (h, frame) = self.gather(st, sp, strata, level, key, traced.as_mut());
        st.counts.records += 1;
        let record = self.record_from(st, sp, level, &h, &frame);
        if let (Some(next), Some(traced)) = (self.next, traced) {
            let estimate = next.estimate(self.seed, sp, level, strata, &traced);
            st.estimates.push(estimate);
        }
        record
    }

    /// The record at `sp` for bounce `level` that the samples `h` (gathered in `frame`, its
    /// z axis the normal) give: irradiance, gradients, radius within its limits; its HSH
    /// coefficients, where it holds them, go to `st`.
    pub fn record_from(
        &self,
        st: &mut WorkState,
        sp: &ShadingPoint,
        level: u32,
        h: &HemisphereSamples,
        frame: &Frame,
    ) -> Record {
        let params = &self.cache.params;
        let e = h.irradiance();
        let grad_t_local = match params.formula {
            TranslationalFormula::WardHeckbert => h.translational_gradient_ward_heckbert(),
            TranslationalFormula::Krivanek => h.translational_gradient_krivanek(),
        };
        let grad_t = to_world(&grad_t_local, frame.s, frame.t);
        let grad_r = to_world(&h.rotational_gradient(), frame.s, frame.t);
        let nearest = h.distance.iter().copied().fold(f32::INFINITY, f32::min);
        let hessian = match params.error_metric {
            ErrorMetric::Hessian => Some(hessian_reach(h, e, params.accuracy)),
            // Where the irradiance curves faster than the nearest surface suggests (a peak of
            // indirect light under a lamp's shade, which the gradient does not see at its top),
            // no record serves beyond the distance at which the second-order error, which
            // gradients do not correct, reaches CURVATURE_SHARE · a · E.
            _ => Some(hessian_reach(h, e, CURVATURE_SHARE * params.accuracy)),
        };
        let (ray_variance, radiance) = self.variance_and_radiance(st, sp, h);
        let record = self.finish_record(
            sp,
            level,
            (e, grad_t, grad_r),
            (nearest, h.harmonic_mean_distance(), hessian),
            (ray_variance, radiance),
        );
        if let Some(r) = st.radiance.get_mut(radiance as usize) {
            // Over the distance it serves to at the fallback's twice the accuracy.
            let reach = record.r
                * params
                    .error_metric
                    .reach_per_radius(params.radiance_accuracy);
            r.radiance
                .limit_gradients(f64::from(2.0 * reach), f64::from(params.radiance_accuracy));
        }
        record
    }

    /// The record a plane's `measure` gives at `sp` (no radiance coefficients; no curvature
    /// bound: a plane gives no Hessian).
    pub fn record_from_plane(
        &self,
        st: &mut WorkState,
        sp: &ShadingPoint,
        level: u32,
        m: &PlaneMeasure,
    ) -> Record {
        st.counts.records += 1;
        self.finish_record(
            sp,
            level,
            (m.e, m.grad_t, m.grad_r),
            (m.nearest, m.harmonic, None),
            (0.0, NO_RADIANCE),
        )
    }

    /// A record at `sp` for bounce `level` from its irradiance and gradients (world space), the
    /// distances its hemisphere saw (the nearest, the harmonic mean, and where known the
    /// Hessian's reach: at the accuracy under the Hessian metric, at CURVATURE_SHARE of it
    /// otherwise) and what else it holds: its radius within the limits (the resolution's, or
    /// for Tabellion's metric `--footprint-limits` pixel footprints at a record the camera sees,
    /// 000 eq. 3.60; 003 items 3–4) and Ward's gradient limit. Shared by gathered records and
    /// records from planes.
    pub fn finish_record(
        &self,
        sp: &ShadingPoint,
        level: u32,
        (e, mut grad_t, grad_r): (Rgb, [Vec3; 3], [Vec3; 3]),
        (nearest, harmonic, hessian): (f32, f32, Option<f32>),
        (ray_variance, radiance): (f32, u32),
    ) -> Record {
        let params = &self.cache.params;
        let limits = (self.cache.r_min, self.cache.r_max);
        let (r, (r_min, r_max)) = match params.error_metric {
            ErrorMetric::Ward => (harmonic, limits),
            ErrorMetric::Tabellion => {
                let footprint =
                    (self.cache.pixel_spread.is_known() && sp.travelled > 0.0).then(|| {
                        super::record::pixel_footprint(
                            self.cache.pixel_spread,
                            sp.travelled,
                            sp.cos_view,
                        )
                    });
                super::record::tabellion_radius(
                    &[nearest],
                    limits,
                    footprint,
                    params.footprint_limits,
                )
            }
            // ½ λ R² = a E: the second-order error reaches a E at R. The reprojection cannot
            // see visibility change behind nearby occluders: the harmonic mean distance bounds
            // the radius there (Radiance's corral plays this part).
            ErrorMetric::Hessian => (hessian.unwrap_or(harmonic).min(harmonic), limits),
        };
        let r = match (params.error_metric, hessian) {
            (ErrorMetric::Hessian, _) | (_, None) => r,
            (metric, Some(reach)) => r.min(reach / metric.reach_per_radius(params.accuracy)),
        };
        let r = super::record::limit_radius_by_gradient(
            e,
            &mut grad_t,
            r.min(r_max),
            r_min,
            params.error_metric.gradient_limit_scale(params.accuracy),
        );
        Record {
            p: sp.it.p,
            n: sp.n,
            e,
            r: r.max(f32::MIN_POSITIVE),
            grad_t,
            grad_r,
            level: level as u8,
            ray_variance,
            radiance,
        }
    }

    /// The radiance-cached glossy lobe's table at `sp`, if radiance caching serves it there.
    fn glossy_brdf(&self, sp: &ShadingPoint) -> Option<&BrdfCoefficients> {
        self.cache.radiance.as_deref()?.brdf_at(sp)
    }

    /// What a record gathered as `h` at `sp` holds beyond irradiance: its relative variance per
    /// ray, and where the surface's glossy lobe is radiance-cached, its incoming radiance in HSH
    /// (kept in the work state, whose index is returned; [`NO_RADIANCE`] elsewhere). A radiance
    /// record's variance is the larger of its irradiance's and its glossy estimate's at normal
    /// view (the cells weighed by the lobe), so that noisy radiance records are gathered again
    /// with the rays they need ([`super::build::regather_noisy`]).
    fn variance_and_radiance(
        &self,
        st: &mut WorkState,
        sp: &ShadingPoint,
        h: &HemisphereSamples,
    ) -> (f32, u32) {
        let irradiance = h.relative_variance();
        let (Some(tables), Some(brdf)) = (self.cache.radiance.as_deref(), self.glossy_brdf(sp))
        else {
            return (irradiance, NO_RADIANCE);
        };
        let with_environment = h.with_escaped();
        let h = with_environment.as_ref().unwrap_or(h);
        let basis = tables.cell_basis(h.strata, brdf.order());
        let weights = basis.lobe_weights(&brdf.normal_view());
        let variance = irradiance.max(h.weighted_relative_variance(Some(&weights)));
        let coefficients = RadianceCoefficients::from_samples(h, &basis);
        st.radiance
            .push(RadianceRecord::new(sp.it.p, sp.n, coefficients));
        (variance, (st.radiance.len() - 1) as u32)
    }

    /// Indirect irradiance at `sp` for bounce `level`: interpolated from the cache and this work
    /// item's own records, or from a new record made here.
    pub fn irradiance(&self, st: &mut WorkState, sp: &ShadingPoint, level: u32, key: u64) -> Rgb {
        let lvl = level as usize;
        let params = &self.cache.params;
        let (mut sum, mut wsum) = (Rgb::ZERO, 0.0f32);
        let mut found = false;
        for store in [Some(&self.cache.levels[lvl]), st.overlay[lvl].as_ref()]
            .into_iter()
            .flatten()
        {
            if let Some(i) = store.interpolate(sp.it.p, sp.n, sp.n_bump, 1.0, params.gradients) {
                sum += i.e * i.weight_sum;
                wsum += i.weight_sum;
                found = true;
            }
        }
        if found {
            return sum / wsum;
        }
        let rec = self.record_at(st, sp, level, key);
        let store = st.overlay[lvl].get_or_insert_with(|| self.cache.empty_store());
        store.insert(rec);
        st.new_records.push((rec, *sp, key));
        rec.e
    }
}

impl IncidentRadiance for SceneRadiance<'_> {
    fn incident(
        &self,
        cache: &IrradianceCache,
        seed: u64,
        st: &mut WorkState,
        sp: &ShadingPoint,
        d: Vec3,
        level: u32,
        key: u64,
        rng: &mut Rng,
    ) -> Option<Incident> {
        let ray = self.scene.spawn_ray(&sp.it, d);
        let hit = self.scene.intersect(&ray)?;
        if !self.scene.has_see_through {
            // Built here, in the returned `Option`: `Some(incident_at(…))` copied the 184 bytes.
            let radiance = self.radiance_at(cache, seed, st, &ray, &hit, level, key, rng);
            return Some(Incident::found(radiance, ray, hit));
        }
        Some(self.through_see_through(cache, seed, st, ray, hit, level, key, rng))
    }

    fn escaped(&self, d: Vec3) -> Rgb {
        self.scene.lights.environment_radiance(d)
    }
}

impl<'a> SceneRadiance<'a> {
    /// A gather ray crosses window panes and masks' open parts as paths do (through with the
    /// pane's transmittance, mirrored with its reflectance, chosen at random by their shares),
    /// so that the sky beyond a window is in records that hold the environment, as Radiance's
    /// ambient rays find it through `glass`. What it finds straight through is reported at its
    /// true distance; if it escapes, as escaped with the throughput of the crossings. A pane
    /// that mirrors it is a vertex of the path, one bounce deeper, as `path` counts it; the path
    /// goes on from there and the emitters and sky it finds count in full, as after any delta
    /// lobe (light samples cross panes only straight, so nothing else finds them; where a
    /// caustic map serves, it holds them). It is reported at the first pane's distance.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn through_see_through(
        &self,
        cache: &IrradianceCache,
        seed: u64,
        st: &mut WorkState,
        mut ray: Ray,
        mut hit: Interaction,
        level: u32,
        key: u64,
        rng: &mut Rng,
    ) -> Incident {
        let first = (hit.t, hit.ng);
        let (mut tau, mut travelled) = (Rgb::ONE, 0.0f32);
        for _ in 0..crate::scene::MAX_SHEET_CROSSINGS {
            let shape = &self.scene.shapes[hit.shape as usize];
            let next = if shape.masked || shape.thin_sheet {
                self.scene.see_through(&hit, -ray.d, rng.next_f32())
            } else {
                None
            };
            if let Some(passage) = next.filter(|p| p.reflected) {
                st.counts.gather_rays += 1;
                // The pane is the vertex at depth level + 1; the mirrored path goes on from
                // level + 2, where the path loop's own depth rule ends it at `max_depth`.
                let arrival = if cache.caustics_served() {
                    Arrival::Gather
                } else {
                    Arrival::Bsdf {
                        from: hit.p.into(),
                        pdf: passage.prob,
                        delta: true,
                        light_samples: 0,
                    }
                };
                let start = PathStart {
                    ray: self.scene.spawn_ray(&hit, passage.d),
                    depth: level + 2,
                    beta: tau * passage.weight,
                    arrival,
                };
                let radiance =
                    self.trace_from(cache, seed, st, start, FirstVertex::Trace, level, key, rng);
                return Incident {
                    radiance,
                    distance: first.0,
                    normal: first.1,
                    hit: None,
                    escaped: None,
                };
            }
            let Some((d, w)) = next.map(|p| (p.d, p.weight)) else {
                let mut inc = self.incident_at(cache, seed, st, &ray, hit, level, key, rng);
                inc.radiance *= tau;
                inc.distance += travelled;
                return inc;
            };
            st.counts.gather_rays += 1;
            tau *= w;
            travelled += hit.t;
            ray = self.scene.spawn_ray(&hit, d);
            match self.scene.intersect(&ray) {
                Some(h) => hit = h,
                None => {
                    return Incident {
                        radiance: Rgb::ZERO,
                        distance: f32::INFINITY,
                        normal: -d,
                        hit: None,
                        escaped: Some((d, tau)),
                    }
                }
            }
        }
        Incident {
            radiance: Rgb::ZERO,
            distance: first.0,
            normal: first.1,
            hit: None,
            escaped: None,
        }
    }

    /// The light of `scene`, its deeper bounces path traced.
    #[must_use]
    pub fn path_traced(scene: &'a Scene) -> Self {
        SceneRadiance {
            scene,
            deeper: Deeper::PathTraced,
        }
    }

    /// What arrives along the gather ray `ray` from its first hit `hit` (found by the caller:
    /// Embree, or a rasteriser's visibility), for a record at bounce `level`.
    #[allow(clippy::too_many_arguments)]
    pub fn incident_at(
        &self,
        cache: &IrradianceCache,
        seed: u64,
        st: &mut WorkState,
        ray: &Ray,
        hit: Interaction,
        level: u32,
        key: u64,
        rng: &mut Rng,
    ) -> Incident {
        let radiance = self.radiance_at(cache, seed, st, ray, &hit, level, key, rng);
        Incident::found(radiance, *ray, hit)
    }

    /// The radiance of [`Self::incident_at`].
    #[allow(clippy::too_many_arguments)]
    fn radiance_at(
        &self,
        cache: &IrradianceCache,
        seed: u64,
        st: &mut WorkState,
        ray: &Ray,
        hit: &Interaction,
        level: u32,
        key: u64,
        rng: &mut Rng,
    ) -> Rgb {
        let start = PathStart {
            ray: *ray,
            depth: level + 1,
            beta: Rgb::ONE,
            arrival: Arrival::Gather,
        };
        self.trace_from(
            cache,
            seed,
            st,
            start,
            FirstVertex::Interaction(Some(hit)),
            level,
            key,
            rng,
        )
    }

    /// The light a gather's path from `start` brings (its first hit `first`, as
    /// [`trace_path`] takes it), for a record at bounce `level`.
    #[allow(clippy::too_many_arguments)]
    fn trace_from(
        &self,
        cache: &IrradianceCache,
        seed: u64,
        st: &mut WorkState,
        start: PathStart,
        first: FirstVertex,
        level: u32,
        key: u64,
        rng: &mut Rng,
    ) -> Rgb {
        let params = &cache.params;
        let settings = PathSettings {
            max_depth: params.max_depth(),
            // Roulette from the first continuation beyond the gather hit: gathers are many
            // and each path's throughput is already a reflectance.
            rr_depth: level + 2,
            first_light_samples: 1,
        };
        let mut rays = RayCounts::default();
        let gatherer = Gatherer::new(self, cache, seed);
        let radiance = {
            let mut source = GatherSource {
                gatherer: &gatherer,
                deeper: self.deeper,
                st: &mut *st,
                key,
                photon_served: false,
            };
            trace_path(
                self.scene,
                start,
                first,
                &mut source,
                &settings,
                rng,
                &mut rays,
            )
        };
        st.counts.gather_rays += rays.bounce + rays.gather;
        st.counts.shadow_rays += rays.shadow;
        radiance
    }
}

/// The Lambertian indirect light at the vertices of a gather's paths.
struct GatherSource<'g, 'a> {
    gatherer: &'g Gatherer<'a>,
    deeper: Deeper,
    st: &'g mut WorkState,
    key: u64,
    /// The last vertex's irradiance came from the global photon map, which holds light after
    /// a bounce only: the environment's direct light there is the light samples' whatever the
    /// records hold.
    photon_served: bool,
}

impl IndirectSource for GatherSource<'_, '_> {
    fn irradiance(
        &mut self,
        _: &Scene,
        sp: &ShadingPoint,
        depth: u32,
        _: &mut dyn crate::sampler::Sampler,
        _: &mut RayCounts,
    ) -> Option<Rgb> {
        let g = self.gatherer;
        self.photon_served = false;
        if g.cache.is_excluded(sp.it.shape) {
            return Some(g.cache.ambient * std::f32::consts::PI);
        }
        if depth > 0 {
            if let Some(e) = g.cache.photon_irradiance(sp, depth) {
                self.photon_served = true;
                return Some(e);
            }
        }
        match self.deeper {
            Deeper::Cache if (depth as usize) < g.cache.levels.len() => {
                Some(g.irradiance(self.st, sp, depth, self.key))
            }
            _ => None,
        }
    }

    fn ambient(&self) -> Rgb {
        self.gatherer.cache.ambient
    }

    fn caustics_served(&self) -> bool {
        self.gatherer.cache.caustics_served()
    }

    fn held_environment(&self, sp: &ShadingPoint) -> HeldEnvironment {
        self.gatherer.cache.held_environment_at(sp)
    }

    fn irradiance_holds_environment(&self, sp: &ShadingPoint) -> bool {
        !self.photon_served && self.held_environment(sp) == HeldEnvironment::All
    }
}

/// Mixes a key with an index (splitmix64 finaliser).
#[inline]
#[must_use]
pub fn mix(key: u64, i: u64) -> u64 {
    let mut z = key ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::irradiance_cache::points::query_point;

    /// A dome far away whose radiance is linear in the direction: L(d) = c₀ + a·d.
    struct Dome {
        c0: f32,
        a: Vec3,
    }

    impl IncidentRadiance for Dome {
        fn incident(
            &self,
            _: &IrradianceCache,
            _: u64,
            _: &mut WorkState,
            _: &ShadingPoint,
            d: Vec3,
            _: u32,
            _: u64,
            _: &mut Rng,
        ) -> Option<Incident> {
            Some(Incident {
                radiance: Rgb::splat(self.c0 + self.a.dot(d)),
                distance: 1e6,
                normal: -d,
                hit: None,
                escaped: None,
            })
        }
    }

    #[test]
    fn a_record_of_closed_form_light_has_its_irradiance_and_gradients() {
        // E(n) = π c₀ + (2π/3) a·n; turning n changes it by (2π/3) a·δn, so the rotational
        // gradient is (2π/3) n × a (E(n') ≈ E + (n × n')·∇ᵣE); the dome is at infinity, so the
        // translational gradient vanishes. No ray tracer involved.
        let mut params = IcParams::default();
        params.set("divisions", "4096").unwrap();
        params.set("supersamples", "0").unwrap();
        let cache = IrradianceCache::for_size(10.0, &params);
        let dome = Dome {
            c0: 1.0,
            a: Vec3::new(0.3, -0.2, 0.5),
        };
        let g = Gatherer::new(&dome, &cache, 4);
        for n in [
            Vec3::Z,
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(-0.36, 0.48, 0.8),
        ] {
            let mut st = WorkState::new(1);
            let rec = g.record_at(&mut st, &query_point(Vec3::ONE, n), 0, 7);
            let pi = std::f32::consts::PI;
            let e = pi * dome.c0 + 2.0 * pi / 3.0 * dome.a.dot(n);
            assert!(
                (rec.e.g - e).abs() < 2e-3 * e,
                "n {n}: E {} vs {e}",
                rec.e.g
            );
            let grad_r = n.cross(dome.a) * (2.0 * pi / 3.0);
            assert!(
                (rec.grad_r[1] - grad_r).length() < 0.02 * grad_r.length(),
                "n {n}: rotational gradient {} vs {grad_r}",
                rec.grad_r[1]
            );
            assert!(rec.grad_t[1].length() < 1e-5 * e, "{}", rec.grad_t[1]);
            let cells = super::super::hemisphere::Stratification::from_divisions(4096).cells();
            assert_eq!(st.counts.gather_rays, cells as u64);
        }
    }
}
