//! Parameters of the irradiance cache: the settings ([`IcParams`]) and the one table
//! ([`PARAMS`]) that names, documents, parses and prints each of them, with Radiance's names
//! (`-aa`, `-ad`, `-as`, `-ar`, `-ab`, `-av`, `-aw`) as aliases.

use super::hemisphere::{CellJitter, Stratification};
use super::record::{ErrorMetric, GradientMode};
use ircache_math::{Rgb, Rng};

/// How far the pre-pass (the overture: 002, Mitsuba's irrcache) fills the cache before the
/// pixels are rendered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Overture {
    /// Down to every pixel centre: the pixel pass interpolates.
    #[default]
    Full,
    /// Down to every fourth pixel: the pixel pass extrapolates more (relaxed lookups).
    Coarse,
    /// No pre-pass: every pixel sample outside all records gathers a small record of its own.
    Off,
}

impl Overture {
    /// The finest pixel stride the pre-pass visits (0: none).
    #[must_use]
    pub fn finest_stride(self) -> usize {
        match self {
            Overture::Full => 1,
            Overture::Coarse => 4,
            Overture::Off => 0,
        }
    }
}

/// How the surfaces that a record's gather rays find get their own indirect light (the bounces
/// beyond the record's level).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Deeper {
    /// From the next level's cache (Ward's per-bounce caches, 004): one cache per bounce.
    Cache,
    /// By path tracing on from the gather hit (one path per gather ray, Russian roulette):
    /// only surfaces the camera reaches take records. Chosen by measurement (ARCHITECTURE.md):
    /// the per-level caches multiply records with depth.
    #[default]
    PathTraced,
}

/// Whether the cache's records hold the environment's light (`--cached-environment`): the
/// light of gather rays that escape to a `constant` or `envmap` emitter (see
/// [`super::environment`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CachedEnvironment {
    /// `glossy` where the environment is smooth enough for a record's gather, else `off`
    /// ([`super::environment::held_environment`]).
    #[default]
    Auto,
    /// Radiance records hold it: the glossy part of radiance-cached surfaces takes it from them.
    Glossy,
    /// Irradiance and radiance records hold it, as Radiance's ambient calculation holds a sky:
    /// noise-free, but the records' interpolation error now lies on all of it.
    All,
    /// Never: light samples estimate all of the environment's light.
    Off,
}

/// Which glossy lobes radiance records serve (`--radiance-cache`, 001 ch. 3); the others are
/// traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RadianceCaching {
    /// Lobes that reflect much of the light: hemispherical glossy albedo at least
    /// [`AUTO_GLOSSY_ALBEDO`] (rough metals), where the traced lobe's noise is most of a pixel's.
    /// A plastic's thin coating stays traced: its records cost more rays than its noise.
    #[default]
    Auto,
    /// Every glossy lobe that an order up to `--radiance-order` represents.
    On,
    /// None.
    Off,
}

/// The least hemispherical glossy albedo of a lobe that `--radiance-cache auto` caches. Measured
/// (BENCHMARKS.md, "Radiance records for rough metals by default"): rough metals reflect 0.6–0.8
/// of uniform light through their lobe, rough plastics' coatings 0.07; caching the coatings
/// took cornell-glossy 1.2–1.3× the time for the same error.
pub const AUTO_GLOSSY_ALBEDO: f64 = 0.25;

impl RadianceCaching {
    /// The least hemispherical glossy albedo of a cached lobe; `None`: no radiance records.
    #[must_use]
    pub fn min_glossy_albedo(self) -> Option<f64> {
        match self {
            RadianceCaching::Auto => Some(AUTO_GLOSSY_ALBEDO),
            RadianceCaching::On => Some(0.0),
            RadianceCaching::Off => None,
        }
    }
}

impl Deeper {
    /// Parses `cache` or `traced`.
    pub fn parse(s: &str) -> Result<Deeper, String> {
        match s {
            "cache" | "cached" => Ok(Deeper::Cache),
            "traced" | "path" => Ok(Deeper::PathTraced),
            v => Err(format!("expected cache or traced, found \"{v}\"")),
        }
    }

    /// The name [`Self::parse`] reads.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Deeper::Cache => "cache",
            Deeper::PathTraced => "traced",
        }
    }
}

/// Which translational-gradient formula records use (they are equal, 000 §3.6.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TranslationalFormula {
    /// Ward and Heckbert's projected-boundary form (000 eq. 3.48).
    #[default]
    WardHeckbert,
    /// Křivánek et al.'s unprojected form, corrected (000 eq. 3.47).
    Krivanek,
}

/// Where a gather puts its sample within each cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GatherPattern {
    /// Multi-jittered (Chiu, Shirley and Wang 1994): one sample per cell, and across all cells
    /// one per fine polar and one per fine azimuthal stratum (the N-rooks property over M·N
    /// rows and columns). Measured against `Jittered` at the defaults, four seeds each, blurred
    /// relMSE_trim: the records' noise −8 % on Sponza, −6 % on the Cornell box, −7 % on
    /// cornell-glossy, for 0.6 % more time (BENCHMARKS.md, "Multi-jittered gathers").
    #[default]
    Multijittered,
    /// One uniformly jittered sample per cell (000 eq. 3.5; Radiance's).
    Jittered,
}

impl GatherPattern {
    /// The cell jitter of a gather over `strata`, its pattern drawn from `rng`.
    #[must_use]
    pub fn layout(self, strata: Stratification, rng: &mut Rng) -> CellJitter {
        match self {
            GatherPattern::Multijittered => strata.multijitter(rng),
            GatherPattern::Jittered => CellJitter::plain(strata),
        }
    }
}

/// How the first bounce level's records are computed (`--record-source`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RecordSource {
    /// The stratified hemisphere gather (000 eqs. 3.4–3.5) with its super-samples.
    #[default]
    Gather,
    /// A 64 × 64 plane at half-size 3 (143°) above the record, one ray per pixel centre, border
    /// compensated, with the plane's gradients (001 §4.4.2; [`super::plane`]): the GPU's
    /// record on the CPU, to measure it in images.
    Plane,
    /// The same planes rasterised and shaded on the GPU (the scenes the GPU frame serves),
    /// through the source the caller attaches ([`super::plane::PlaneSource`]).
    GpuPlane,
}

/// `bounces` without a bound: paths end by Russian roulette alone.
pub const UNBOUNDED: u32 = u32::MAX;

/// Most bounce levels that keep a record store (records sit at the depth where camera paths
/// meet a surface; deeper, the pixel pass traces).
pub const MAX_STORED_LEVELS: u32 = 16;

/// Photons in the global map with `--photons auto` where they serve. Chosen by measurement
/// (BENCHMARKS.md, "The photon final gather by default"): on the Cornell box and Sponza at
/// `max_depth` 10, cornell-glossy at 5 and the lamp room at 7, 300 000 and 1 000 000 photons
/// lowered the blurred error by under 10 % more than 100 000 for 1–11 s more.
pub const AUTO_PHOTONS: u64 = 100_000;

/// Photons in the caustic map with `--caustic-photons auto`, in scenes with surfaces that make
/// caustics (delta lobes). Chosen by measurement (BENCHMARKS.md, "The caustic map by
/// default"): on cornell-glass and the lamp room, 30 000 to 300 000 gave the same error within
/// 3 %; what pays is that the gathers leave those heavy-tailed paths to the map.
pub const AUTO_CAUSTIC_PHOTONS: u64 = 100_000;

/// Irradiance cache settings.
#[derive(Clone, Debug, PartialEq)]
pub struct IcParams {
    /// Accuracy `a` (`-aa`): with Ward's metric a record serves where its split-sphere error
    /// ε ≤ a (Radiance's meaning); with Tabellion's, κ = 0.2/a.
    pub accuracy: f32,
    /// Hemisphere divisions per record (`-ad`), split as polar × azimuthal ≈ π × polar.
    pub divisions: usize,
    /// Resolution (`-ar`): the smallest record radius is the scene size / resolution (the
    /// smallest spacing that times `a`), the largest 64× that; 0 means no minimum.
    pub resolution: f32,
    /// Tabellion–Lamorlette's limits on the radius of a record the camera sees, in pixel
    /// footprints (000 eq. 3.60): smallest and largest.
    pub footprint_limits: (f32, f32),
    /// Indirect bounces (`-ab`): one cache per bounce level; equals path tracing with
    /// `max_depth` = bounces + 2.
    pub bounces: u32,
    /// Radiance assumed beyond the last bounce (`-av`).
    pub ambient_value: Rgb,
    /// Gradients used in interpolation.
    pub gradients: GradientMode,
    /// Translational gradient formula.
    pub formula: TranslationalFormula,
    /// Where each cell's gather sample lies (`--gather-pattern`).
    pub gather_pattern: GatherPattern,
    /// How the first level's records are computed (`--record-source`).
    pub record_source: RecordSource,
    /// Reorder records spatially after the pre-pass (003 item 8, `--record-order spatial`).
    pub spatial_order: bool,
    /// How far the pre-pass fills the cache (`--overture`).
    pub overture: Overture,
    /// How a record's error is measured (`--error-metric`).
    pub error_metric: ErrorMetric,
    /// Neighbour clamping: a record's radius never exceeds a neighbour's plus their distance.
    pub neighbour_clamp: bool,
    /// Weight of `ambient_value` in a running average with the irradiance the cache computes
    /// (`-aw`, 003 item 1); 0 keeps the ambient value fixed.
    pub ambient_weight: u32,
    /// Most adaptive super-samples per record (`-as`): extra gather rays for the cells whose
    /// neighbours differ most (003 item 2), as many as the record needs to reach
    /// `record_error`; 0: none.
    pub supersamples: usize,
    /// Target relative standard error of a record's irradiance, as a fraction of the accuracy:
    /// super-sampling stops once the gather's own error estimate is below
    /// `record_error × accuracy`; 0 spends every super-sample.
    pub record_error: f32,
    /// Gather a record again, with up to `divisions + supersamples` rays, where its neighbours'
    /// gathers say the neighbourhood needs at least this many times the divisions
    /// ([`super::build::regather_noisy`]); 0: never.
    pub regather_at: f32,
    /// Where the bounces beyond a record's own level come from (`--deeper-bounces`).
    pub deeper: Deeper,
    /// Light samples per pixel sample for the direct term (stratified over the light when a
    /// square number): shadow rays are cheaper than pixel samples.
    pub direct_samples: u32,
    /// Radiance records for moderately glossy lobes (`--radiance-cache`, 001 ch. 3): records on
    /// the surfaces of the lobes it names also hold their incoming radiance in hemispherical
    /// harmonics.
    pub radiance_cache: RadianceCaching,
    /// Highest order of radiance records (`--radiance-order`): a glossy lobe is cached when an
    /// order up to this keeps 95 % of its energy, traced otherwise.
    pub radiance_order: usize,
    /// Accuracy of the radiance records' placement and lookups (`--radiance-accuracy`), at most
    /// `accuracy`: glossy lobes show a record's error more than irradiance does (001 §4.7.1 uses
    /// 0.2 against 0.25).
    pub radiance_accuracy: f32,
    /// Whether records hold the environment's light (`--cached-environment`).
    pub cached_environment: CachedEnvironment,
    /// Photons in the global map for the cached final gather (`--photons`); 0: off; `None`:
    /// automatic ([`IcParams::global_photons`]).
    pub photons: Option<u64>,
    /// Photons in the caustic map, read at the pixel (`--caustic-photons`); 0: off; `None`:
    /// automatic ([`IcParams::caustic_photons`]).
    pub caustic_photons: Option<u64>,
    /// Photons per global-map estimate (`--photon-lookup`).
    pub photon_lookup: usize,
    /// Largest lookup radius as a fraction of the scene size (`--photon-radius`).
    pub photon_radius: f32,
    /// Records made from photons before the pre-pass (`--photon-records`, 001 ch. 6).
    pub photon_records: bool,
    /// The translational gradient of records in participating media (002, NOTES-002 §2.7).
    pub media_gradient: crate::media_cache::gradient::MediaGradient,
    /// Light samples per surface hit and per march step of a gather through media.
    pub media_light_samples: u32,
    /// In media: quadrature points per camera-ray segment of the pixel pass (0: delta tracking).
    pub media_march: u32,
    /// In media: volumetric records serve the in-scattered indirect light at the march's points.
    pub media_volume_records: bool,
    /// In media: paths a volumetric record gathers.
    pub media_volume_divisions: u32,
    /// In media: gather rays per surface record (`divisions` is the clear scenes').
    pub media_divisions: usize,
    /// In media: paths per gather ray for the bounces beyond a record's first.
    pub media_deeper_paths: u32,
}

impl Default for IcParams {
    fn default() -> Self {
        IcParams {
            // Both by measurement (BENCHMARKS.md, "Where a record's rays pay"): at 16 spp the
            // pixel pass costs the same whatever the cache does, so rays spent on records pay
            // until their noise stops being the error that is left. Against 0.35 and 512 (with
            // re-gathering at 16), blurred relMSE_trim × time: Cornell box d3 0.52×, Sponza d3
            // 0.78×, cornell-glossy d5 0.78×, the lamp room d7 1.14× (its median 0.92×, its
            // mean luminance 0.9924 → 0.9958).
            accuracy: 0.3,
            divisions: 1024,
            // Radiance's 128 would floor Tabellion's footprint radii at size/256 (4× Sponza's
            // error, measured); the floor stays for records the camera does not see.
            resolution: 1024.0,
            // Tabellion–Lamorlette's 1.5 and 10, the largest halved by measurement (BENCHMARKS.md,
            // "Records no larger than five pixels"): where nothing nearby bounds a record it grew
            // to 10 footprints, and its gather noise showed as blotches 20 pixels across; at 5,
            // blurred relMSE_trim × time 0.83–0.99× on 10 of 13 scene-depth pairs (Sponza d3
            // 0.91×), the same error on the lamp room and the bump maps, 1.07× on cornell-rough.
            footprint_limits: (1.5, 5.0),
            bounces: 1,
            ambient_value: Rgb::ZERO,
            gradients: GradientMode::Full,
            formula: TranslationalFormula::WardHeckbert,
            gather_pattern: GatherPattern::Multijittered,
            record_source: RecordSource::Gather,
            direct_samples: 4,
            supersamples: 1536,
            record_error: 0.1,
            // Off by measurement (BENCHMARKS.md, "Where a record's rays pay"): at 16 it doubled
            // Sponza's gather rays at -ab 1 for 19 % less blurred error (blurred error × time
            // 1.47× that without it at 4 spp) and tied on the lamp room, the Cornell box and
            // cornell-glossy (also with radiance records).
            regather_at: 0.0,
            ambient_weight: 0,
            // Chosen by measurement (BENCHMARKS.md): at equal time Tabellion–Lamorlette's metric
            // reaches about half Ward's error on Sponza and two thirds on the Cornell box.
            error_metric: ErrorMetric::default(),
            overture: Overture::Full,
            spatial_order: false,
            neighbour_clamp: false,
            deeper: Deeper::PathTraced,
            radiance_cache: RadianceCaching::Auto,
            radiance_order: 10,
            radiance_accuracy: 0.3,
            cached_environment: CachedEnvironment::Auto,
            photons: None,
            caustic_photons: None,
            // Mitsuba 0.6's photonmapper takes 120 for its global map, Radiance 50.
            photon_lookup: 100,
            photon_radius: 0.05,
            photon_records: false,
            // Measured (BENCHMARKS.md, "Media gradients in the image", 2026-12-04): on the fog
            // box, the same fog four times denser and the smoke plume, the media-aware forms
            // left the image's error as it was and took 1.6-2.6x the time (their source
            // gradients difference the light samples); `corrected` stays one flag away.
            media_gradient: crate::media_cache::gradient::MediaGradient::None,
            media_light_samples: 1,
            media_march: 16,
            media_volume_records: true,
            media_volume_divisions: 256,
            media_deeper_paths: 4,
            // Measured (BENCHMARKS.md, "Media gradients in the image"): on the fog box, a fog
            // four times denser and the smoke plume, 128 rays gave the blurred error of 512
            // within 0-11 % in 0.47-0.69x the time (64: +22 % on the fog box); a record's
            // rays march through the medium, and the image's error there is not their noise.
            media_divisions: 128,
        }
    }
}

/// One cache parameter. Every place a parameter appears is made from its entry here: the
/// `render` and `irradiance` command-line options (`--name`, and Radiance's `-xx` where it has
/// one), the XML `<integrator type="irrcache">` parameters, the cache file's header and its
/// staleness check (entries that shape records), and the `--stats` JSON.
pub struct ParamSpec {
    /// Name in XML and the stats (snake case); the command-line option is `--` + the name with
    /// dashes.
    pub name: &'static str,
    /// Radiance's option without its dash (`aa` for `-aa`), or other accepted names.
    pub aliases: &'static [&'static str],
    /// What the value looks like, for the help (`A`, `none|rotation|full`).
    pub value: &'static str,
    /// What it means (the default is added from [`IcParams::default`]).
    pub help: &'static str,
    /// Records made under other values cannot serve (part of a cache file's identity).
    pub shapes_records: bool,
    /// The value as text that [`ParamSpec::set`] reads back.
    pub get: fn(&IcParams) -> String,
    /// Sets the value from text (the error names what was expected).
    pub set: fn(&mut IcParams, &str) -> Result<(), String>,
}

impl std::fmt::Debug for ParamSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

fn number<T: std::str::FromStr + PartialOrd + std::fmt::Display>(
    v: &str,
    lo: T,
    hi: T,
    what: &str,
) -> Result<T, String> {
    v.trim()
        .parse::<T>()
        .ok()
        .filter(|x| *x >= lo && *x <= hi)
        .ok_or_else(|| format!("expected {what} from {lo} to {hi}, found \"{}\"", v.trim()))
}

/// The items of a list value, separated by commas or spaces (`1,2,3`, `1 2 3`).
fn list(v: &str) -> Vec<&str> {
    v.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .collect()
}

/// A photon count or `auto` (`None`).
fn photons_or_auto(v: &str) -> Result<Option<u64>, String> {
    if v.trim() == "auto" {
        Ok(None)
    } else {
        number(v, 0, 1_000_000_000, "a number of photons or auto").map(Some)
    }
}

/// [`photons_or_auto`]'s text.
fn photons_text(count: Option<u64>) -> String {
    count.map_or("auto".into(), |n| n.to_string())
}

/// Parses a switch: `on` or `off` (or `true`/`1`, `false`/`0`).
pub fn on_off(v: &str) -> Result<bool, String> {
    match v.trim() {
        "on" | "true" | "1" => Ok(true),
        "off" | "false" | "0" => Ok(false),
        v => Err(format!("expected on or off, found \"{v}\"")),
    }
}

const RADIANCE_CACHINGS: &[(&str, RadianceCaching)] = &[
    ("auto", RadianceCaching::Auto),
    ("on", RadianceCaching::On),
    ("off", RadianceCaching::Off),
];

const CACHED_ENVIRONMENTS: &[(&str, CachedEnvironment)] = &[
    ("auto", CachedEnvironment::Auto),
    ("glossy", CachedEnvironment::Glossy),
    ("all", CachedEnvironment::All),
    ("off", CachedEnvironment::Off),
];

fn choice<T: Copy>(v: &str, options: &[(&str, T)]) -> Result<T, String> {
    options
        .iter()
        .find(|(n, _)| *n == v.trim())
        .map(|(_, t)| *t)
        .ok_or_else(|| {
            let names: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
            format!("expected {}, found \"{}\"", names.join(" or "), v.trim())
        })
}

fn name_of<T: Copy + PartialEq>(t: T, options: &[(&'static str, T)]) -> String {
    options
        .iter()
        .find(|(_, o)| *o == t)
        .map_or("?", |(n, _)| *n)
        .to_string()
}

const OVERTURES: &[(&str, Overture)] = &[
    ("full", Overture::Full),
    ("coarse", Overture::Coarse),
    ("off", Overture::Off),
];
const FORMULAS: &[(&str, TranslationalFormula)] = &[
    ("ward-heckbert", TranslationalFormula::WardHeckbert),
    ("krivanek", TranslationalFormula::Krivanek),
];
const PATTERNS: &[(&str, GatherPattern)] = &[
    ("multijittered", GatherPattern::Multijittered),
    ("jittered", GatherPattern::Jittered),
];
const ORDERS: &[(&str, bool)] = &[("insertion", false), ("spatial", true)];
const SOURCES: &[(&str, RecordSource)] = &[
    ("gather", RecordSource::Gather),
    ("plane", RecordSource::Plane),
    ("gpu-plane", RecordSource::GpuPlane),
];

/// Every cache parameter, in the order the help lists them.
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "accuracy",
        aliases: &["aa"],
        value: "A",
        help: "with --error-metric ward a record serves where its split-sphere error \
               ‖x − xᵢ‖/Rᵢ + √(1 − n·nᵢ) ≤ A (Radiance's meaning); with tabellion κ = 0.2/A",
        shapes_records: true,
        get: |p| p.accuracy.to_string(),
        set: |p, v| {
            let a: f32 = number(v, 0.0, 2.0, "an accuracy")?;
            if a <= 0.0 {
                return Err(format!("expected an accuracy above 0, found {a}"));
            }
            p.accuracy = a;
            Ok(())
        },
    },
    ParamSpec {
        name: "divisions",
        aliases: &["ad"],
        value: "N",
        help: "gather rays per record, split polar × azimuthal ≈ π × polar",
        shapes_records: true,
        get: |p| p.divisions.to_string(),
        set: |p, v| {
            p.divisions = number(v, 4, 1_000_000, "a whole number of divisions")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "gather_pattern",
        aliases: &[],
        value: "multijittered|jittered",
        help: "where a record's gather puts each cell's ray: multi-jittered (one per cell and \
               one per fine polar and azimuthal stratum) or jittered within its cell alone",
        shapes_records: true,
        get: |p| name_of(p.gather_pattern, PATTERNS),
        set: |p, v| {
            p.gather_pattern = choice(v, PATTERNS)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "record_source",
        aliases: &[],
        value: "gather|plane|gpu-plane",
        help: "how the first bounce's records are computed: the stratified gather, or a 64 × 64 \
               border-compensated plane above each record with the plane's gradients (001 \
               §4.4.2), ray cast on the CPU (plane) or rasterised and shaded on the GPU \
               (gpu-plane, for the scenes the GPU frame serves; --gpu is not needed); plane \
               records hold irradiance only (radiance-cached lobes are traced)",
        shapes_records: true,
        get: |p| name_of(p.record_source, SOURCES),
        set: |p, v| {
            p.record_source = choice(v, SOURCES)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "supersamples",
        aliases: &["as"],
        value: "N",
        help: "most extra gather rays per record, three to a cell, in the cells whose \
               neighbours differ most, until the record's estimated error reaches --record-error",
        shapes_records: true,
        get: |p| p.supersamples.to_string(),
        set: |p, v| {
            p.supersamples = number(v, 0, 1_000_000, "super-samples")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "record_error",
        aliases: &[],
        value: "F",
        help: "target relative standard error of a record's irradiance as a fraction of the \
               accuracy (estimated from the spread of the gather's strata); 0 spends every \
               super-sample",
        shapes_records: true,
        get: |p| p.record_error.to_string(),
        set: |p, v| {
            p.record_error = number(v, 0.0, 10.0, "a fraction of the accuracy")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "regather_at",
        aliases: &[],
        value: "K",
        help: "gather a record again, with up to divisions + supersamples rays, where the \
               records serving around it estimate that their neighbourhood needs at least K \
               times the divisions to reach --record-error (small bright patches seen from \
               afar; the choice never looks at the record's own samples); 0: never",
        shapes_records: true,
        get: |p| p.regather_at.to_string(),
        set: |p, v| {
            p.regather_at = number(v, 0.0, 1.0e6, "a multiple of the divisions (0: never)")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "resolution",
        aliases: &["ar"],
        value: "R",
        help: "smallest record radius = scene size / R, largest 64× that (with tabellion they \
               bound the nearest distance: R/2 ≥ size/2R, inside the pixel-footprint limits); \
               0: no minimum",
        shapes_records: true,
        get: |p| p.resolution.to_string(),
        set: |p, v| {
            p.resolution = number(v, 0.0, f32::MAX, "a resolution")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "footprint_limits",
        aliases: &[],
        value: "MIN,MAX",
        help: "with tabellion, the smallest and largest radius of a record the camera sees, in \
               pixel footprints (000 eq. 3.60; Tabellion–Lamorlette's 1.5,10)",
        shapes_records: true,
        get: |p| format!("{},{}", p.footprint_limits.0, p.footprint_limits.1),
        set: |p, v| {
            let parts = list(v);
            let [lo, hi] = parts[..] else {
                return Err(format!(
                    "expected two pixel-footprint multiples MIN,MAX, found \"{v}\""
                ));
            };
            let lo = number(lo, 0.0, 1.0e6, "a multiple of the pixel footprint")?;
            let hi = number(
                hi,
                lo,
                1.0e6,
                "a multiple of the pixel footprint at least MIN",
            )?;
            p.footprint_limits = (lo, hi);
            Ok(())
        },
    },
    ParamSpec {
        name: "bounces",
        aliases: &["ab"],
        value: "N|-1",
        help: "indirect bounces: the image equals path tracing at max_depth N + 2; -1: unbounded \
               (Russian roulette ends the paths; needs --deeper-bounces traced) \
               (default: the scene's max_depth − 2)",
        shapes_records: true,
        get: |p| {
            if p.bounces == UNBOUNDED {
                "-1".to_string()
            } else {
                p.bounces.to_string()
            }
        },
        set: |p, v| {
            p.bounces = if v.trim() == "-1" {
                UNBOUNDED
            } else {
                number(v, 0, 64, "bounces (or -1: unbounded)")?
            };
            Ok(())
        },
    },
    ParamSpec {
        name: "deeper_bounces",
        aliases: &[],
        value: "traced|cache",
        help: "the bounces beyond a record's own: path-traced from its gather hits, or from \
               one cache per bounce level (Ward's)",
        shapes_records: true,
        get: |p| p.deeper.name().to_string(),
        set: |p, v| {
            p.deeper = Deeper::parse(v.trim())?;
            Ok(())
        },
    },
    ParamSpec {
        name: "ambient_value",
        aliases: &["av"],
        value: "V|r,g,b",
        help: "radiance assumed beyond the last bounce",
        shapes_records: true,
        get: |p| {
            let c = p.ambient_value;
            format!("{},{},{}", c.r, c.g, c.b)
        },
        set: |p, v| {
            let parts = list(v);
            let f = |x: &str| number(x, 0.0, f32::MAX, "a radiance");
            p.ambient_value = match parts[..] {
                [x] => Rgb::splat(f(x)?),
                [r, g, b] => Rgb::new(f(r)?, f(g)?, f(b)?),
                _ => {
                    return Err(format!(
                        "expected one value or three (r g b), found \"{v}\""
                    ))
                }
            };
            Ok(())
        },
    },
    ParamSpec {
        name: "ambient_weight",
        aliases: &["aw"],
        value: "N",
        help: "replace the ambient value by the running average (N·av + n·ρ̄Ē/π)/(N + n) over \
               the last level's n records; 0: fixed",
        shapes_records: true,
        get: |p| p.ambient_weight.to_string(),
        set: |p, v| {
            p.ambient_weight = number(v, 0, 65535, "a whole weight")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "error_metric",
        aliases: &[],
        value: "tabellion|ward|hessian",
        help: "how a record's error is measured: Tabellion–Lamorlette (000 eqs. 3.59–3.62, \
               radii within --footprint-limits pixel footprints), Ward's split sphere (3.10), or \
               a Hessian radius (½λR² = aE)",
        shapes_records: true,
        get: |p| p.error_metric.name().to_string(),
        set: |p, v| {
            p.error_metric = ErrorMetric::parse(v.trim())?;
            Ok(())
        },
    },
    ParamSpec {
        name: "neighbour_clamp",
        aliases: &["neighbor_clamp"],
        value: "on|off",
        help: "a record's radius never exceeds a neighbour's radius plus their distance",
        shapes_records: true,
        get: |p| if p.neighbour_clamp { "on" } else { "off" }.to_string(),
        set: |p, v| {
            p.neighbour_clamp = on_off(v)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "gradients",
        aliases: &[],
        value: "full|rotation|none",
        help: "gradients used in interpolation (000 eq. 3.15)",
        shapes_records: true,
        get: |p| p.gradients.name().to_string(),
        set: |p, v| {
            p.gradients = GradientMode::parse(v.trim())?;
            Ok(())
        },
    },
    ParamSpec {
        name: "gradient_formula",
        aliases: &[],
        value: "ward-heckbert|krivanek",
        help: "translational gradient as 000 eq. 3.48 or 3.47 (equal)",
        shapes_records: true,
        get: |p| name_of(p.formula, FORMULAS),
        set: |p, v| {
            p.formula = choice(v, FORMULAS)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "overture",
        aliases: &[],
        value: "full|coarse|off",
        help: "how far the pre-pass fills the cache before the pixels: every pixel centre, \
               every fourth, or not at all",
        shapes_records: false,
        get: |p| name_of(p.overture, OVERTURES),
        set: |p, v| {
            p.overture = choice(v, OVERTURES)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "record_order",
        aliases: &[],
        value: "insertion|spatial",
        help: "reorder records along a Morton curve after the pre-pass (003 item 8)",
        shapes_records: false,
        get: |p| name_of(p.spatial_order, ORDERS),
        set: |p, v| {
            p.spatial_order = choice(v, ORDERS)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "direct_samples",
        aliases: &[],
        value: "N",
        help: "light samples per pixel sample at the first surface (one when the only light \
               is a delta light; a quarter, rounded up, in the later frames of an animation's \
               still runs in a scene of one light, unless --adaptive)",
        shapes_records: false,
        get: |p| p.direct_samples.to_string(),
        set: |p, v| {
            p.direct_samples = number(v, 1, 4096, "light samples")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "radiance_cache",
        aliases: &[],
        value: "auto|on|off",
        help: "radiance caching (001 ch. 3): records on glossy surfaces also hold their \
               incoming radiance in hemispherical harmonics, and glossy lobes that an order up \
               to --radiance-order represents (95 % of their energy) are shaded from them \
               instead of traced; auto: only lobes that reflect a quarter or more of uniform \
               light (rough metals, not plastics' coatings)",
        shapes_records: true,
        get: |p| name_of(p.radiance_cache, RADIANCE_CACHINGS),
        set: |p, v| {
            p.radiance_cache = choice(v, RADIANCE_CACHINGS)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "radiance_order",
        aliases: &[],
        value: "N",
        help: "highest order of radiance records (bands 0 … N − 1, N² coefficients per colour)",
        shapes_records: true,
        get: |p| p.radiance_order.to_string(),
        set: |p, v| {
            p.radiance_order = number(v, 1, 16, "an order")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "radiance_accuracy",
        aliases: &[],
        value: "A",
        help: "accuracy of radiance records, at most --accuracy (the irradiance records'): on \
               radiance-cached surfaces records are placed and read as if the accuracy were this",
        shapes_records: true,
        get: |p| p.radiance_accuracy.to_string(),
        set: |p, v| {
            p.radiance_accuracy = number(v, 0.001, 10.0, "an accuracy")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "cached_environment",
        aliases: &[],
        value: "auto|glossy|all|off",
        help: "which records hold the light of a constant or envmap emitter (light samples of \
               it then estimate only the rest of the BSDF): glossy, radiance records (the \
               radiance-cached glossy lobes take it from them); all, irradiance records too, as \
               Radiance's ambient calculation holds a sky (noise-free, with the cache's \
               interpolation error; gathers cross window panes); auto: off for an environment \
               with a sun in it, all where less than half of its light reaches the surfaces in \
               view (rooms lit through windows, where its light samples speckle), else glossy",
        shapes_records: true,
        get: |p| name_of(p.cached_environment, CACHED_ENVIRONMENTS),
        set: |p, v| {
            p.cached_environment = choice(v, CACHED_ENVIRONMENTS)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "photons",
        aliases: &[],
        value: "N|auto",
        help: "photons in the global map (stored, after at least one bounce): a record's gather \
               rays read the indirect light of the surfaces they hit from it instead of tracing \
               on (Jensen's cached final gather, Radiance's -ap); 0: off; auto: 100000 where \
               the surfaces gather rays hit have indirect light of their own (-ab 2 or more \
               with the deeper bounces traced) or with --photon-records on, else none; in \
               participating media the photons scatter in the medium too, and auto makes the \
               map only where 4 photons emitted per photon asked store half (not where a \
               medium emits, whose light photons do not carry)",
        shapes_records: true,
        get: |p| photons_text(p.photons),
        set: |p, v| {
            p.photons = photons_or_auto(v)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "caustic_photons",
        aliases: &[],
        value: "N|auto",
        help: "photons in the caustic map (light through glass and off mirrors onto Lambertian \
               surfaces), read at the pixel; the gathers then leave those paths out (where \
               radiance records serve a glossy lobe, the pixel traces them through it); 0: \
               caustics come from the gathers; auto: 100000 in scenes with such surfaces",
        shapes_records: true,
        get: |p| photons_text(p.caustic_photons),
        set: |p, v| {
            p.caustic_photons = photons_or_auto(v)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "photon_lookup",
        aliases: &[],
        value: "N",
        help: "photons per estimate in the global map (the caustic map takes half as many)",
        shapes_records: true,
        get: |p| p.photon_lookup.to_string(),
        set: |p, v| {
            p.photon_lookup = number(v, 1, 100_000, "a number of photons")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "photon_radius",
        aliases: &[],
        value: "F",
        help: "largest photon lookup radius as a fraction of the scene size (the caustic \
               map's a quarter of it)",
        shapes_records: true,
        get: |p| p.photon_radius.to_string(),
        set: |p, v| {
            let r: f32 = number(v, 0.0, 1.0, "a fraction of the scene size")?;
            if r <= 0.0 {
                return Err(format!("expected a fraction above 0, found {r}"));
            }
            p.photon_radius = r;
            Ok(())
        },
    },
    ParamSpec {
        name: "photon_records",
        aliases: &[],
        value: "on|off",
        help: "make first-bounce records from the global map's photons before the pre-pass \
               (001 ch. 6: a record wherever no record reaches a photon, its irradiance and \
               gradients from the photons of its zone); the pre-pass then gathers records only \
               where photons left holes. Needs --photons",
        shapes_records: true,
        get: |p| if p.photon_records { "on" } else { "off" }.to_string(),
        set: |p, v| {
            p.photon_records = on_off(v)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "media_gradient",
        aliases: &[],
        value: "none|corrected|paper|jdzj08",
        help: "in scenes with participating media, the records' translational gradient (002): \
               none (Ward–Heckbert's walls, media-blind: the default, as fast and as accurate \
               in the image at the records' radii), corrected (NOTES-002 §2.7's consistent \
               form: absorption, visibility of the medium's light, the radial and interface \
               terms; for studying gradients), paper (002's Algorithm 1 read literally), \
               jdzj08 (absorption terms only)",
        shapes_records: true,
        get: |p| name_of(p.media_gradient, MEDIA_GRADIENTS),
        set: |p, v| {
            p.media_gradient = choice(v, MEDIA_GRADIENTS)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "media_light_samples",
        aliases: &[],
        value: "N",
        help: "in scenes with participating media, light samples per surface hit and per march \
               step of a record's gather (its single scattering, whose samples the gradient's \
               source term differentiates): more cost more, and steady the gradients near \
               lights",
        shapes_records: true,
        get: |p| p.media_light_samples.to_string(),
        set: |p, v| {
            p.media_light_samples = number(v, 1u32, 1024, "a number of light samples")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "media_march",
        aliases: &[],
        value: "N",
        help: "in scenes with participating media, the pixel pass marches camera rays: the \
               medium's single scattering and emission by N stratified points per segment (fewer \
               where it scatters little), each with a light sample, and the surface behind \
               weighted by its transmittance; 0 tracks them as volpath does (one collision or \
               none)",
        shapes_records: false,
        get: |p| p.media_march.to_string(),
        set: |p, v| {
            p.media_march = number(v, 0u32, 1024, "a number of points")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "media_volume_records",
        aliases: &[],
        value: "on|off",
        help: "in scenes with participating media, with --media-march: records inside the \
               medium hold its in-scattered indirect light (spherical harmonics of bands 0–2, \
               gathered with --media-volume-divisions paths) and serve the march's points; off: a \
               phase-sampled path from one collision per camera sample",
        shapes_records: false,
        get: |p| if p.media_volume_records { "on" } else { "off" }.to_string(),
        set: |p, v| {
            p.media_volume_records = on_off(v)?;
            Ok(())
        },
    },
    ParamSpec {
        name: "media_volume_divisions",
        aliases: &[],
        value: "N",
        help: "in scenes with participating media, paths a volumetric record gathers over the \
               sphere (their noise is the fog's low-frequency error; they cost a tenth of a \
               surface record's rays through fog)",
        shapes_records: true,
        get: |p| p.media_volume_divisions.to_string(),
        set: |p, v| {
            p.media_volume_divisions = number(v, 8u32, 1 << 20, "a number of paths")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "media_deeper_paths",
        aliases: &[],
        value: "N",
        help: "in scenes with participating media, paths per gather ray of a surface record for \
               the bounces beyond its first (max_depth above 3): their noise is the fog's \
               blotches; at max_depth 6, 4 paths against 1 took 1.17x the time for 0.6x the \
               error in the fog box at 256x256, and 1.6x the time for 0.87x in a dense smoke",
        shapes_records: true,
        get: |p| p.media_deeper_paths.to_string(),
        set: |p, v| {
            p.media_deeper_paths = number(v, 1u32, 1 << 16, "a number of paths")?;
            Ok(())
        },
    },
    ParamSpec {
        name: "media_divisions",
        aliases: &[],
        value: "N",
        help: "in scenes with participating media, gather rays per surface record, split as \
               --divisions (which stays the clear scenes'): each ray marches through the medium",
        shapes_records: true,
        get: |p| p.media_divisions.to_string(),
        set: |p, v| {
            p.media_divisions = number(v, 4, 1_000_000, "a whole number of divisions")?;
            Ok(())
        },
    },
];

const MEDIA_GRADIENTS: &[(&str, crate::media_cache::gradient::MediaGradient)] = &[
    (
        "corrected",
        crate::media_cache::gradient::MediaGradient::Corrected,
    ),
    ("paper", crate::media_cache::gradient::MediaGradient::Paper),
    (
        "jdzj08",
        crate::media_cache::gradient::MediaGradient::Jdzj08,
    ),
    ("none", crate::media_cache::gradient::MediaGradient::None),
];

/// The entry named `name` (its name, with dashes or underscores, or an alias).
#[must_use]
pub fn param(name: &str) -> Option<&'static ParamSpec> {
    let n = name.replace('-', "_");
    PARAMS
        .iter()
        .find(|s| s.name == n || s.aliases.contains(&n.as_str()))
}

impl IcParams {
    /// Sets a parameter by its name or an alias (Radiance's); `value` is the text given.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), String> {
        let spec = param(name).ok_or_else(|| {
            let names: Vec<&str> = PARAMS.iter().map(|s| s.name).collect();
            format!(
                "unknown irradiance cache parameter \"{name}\" (known: {})",
                names.join(", ")
            )
        })?;
        (spec.set)(self, value).map_err(|e| format!("{name}: {e}"))
    }

    /// Every parameter as (name, value text), in table order.
    #[must_use]
    pub fn to_pairs(&self) -> Vec<(&'static str, String)> {
        PARAMS.iter().map(|s| (s.name, (s.get)(self))).collect()
    }

    /// The command-line names (`--media-divisions`) of the settings among `names` (the
    /// parameter table's) that differ from their defaults: what a user gave.
    #[must_use]
    pub fn given_among(&self, names: &[&str]) -> Vec<String> {
        let defaults = IcParams::default();
        PARAMS
            .iter()
            .filter(|s| names.contains(&s.name) && (s.get)(self) != (s.get)(&defaults))
            .map(|s| format!("--{}", s.name.replace('_', "-")))
            .collect()
    }

    /// The settings only records in participating media read.
    pub const MEDIA_ONLY: [&'static str; 7] = [
        "media_gradient",
        "media_light_samples",
        "media_march",
        "media_volume_records",
        "media_volume_divisions",
        "media_deeper_paths",
        "media_divisions",
    ];

    /// Refuses the settings only records in media read ([`Self::MEDIA_ONLY`]) when given for a
    /// scene without media.
    pub fn check_without_media(&self) -> Result<(), String> {
        let given = self.given_among(&Self::MEDIA_ONLY);
        if given.is_empty() {
            return Ok(());
        }
        Err(format!(
            "{} for scenes with participating media; this one has none",
            Self::named(&given)
        ))
    }

    /// Settings' names as the subject of a sentence: `--a is`, `--a, --b are`.
    #[must_use]
    pub fn named(given: &[String]) -> String {
        let verb = if given.len() == 1 { "is" } else { "are" };
        format!("{} {verb}", given.join(", "))
    }

    /// Settings that cannot go together: unbounded bounces need the deeper bounces traced (one
    /// cache per bounce level would be endless).
    pub fn check(&self) -> Result<(), String> {
        if self.bounces == UNBOUNDED && self.deeper == Deeper::Cache {
            return Err(
                "unbounded bounces (max_depth -1) need --deeper-bounces traced: give \
                 max_depth ≥ 2 or bounces for one cache per bounce level"
                    .into(),
            );
        }
        if self.photons.is_some_and(|n| n > 0) && self.deeper == Deeper::Cache {
            return Err(
                "--photons serves the bounces beyond the records from the photon map: \
                        it does not go with --deeper-bounces cache"
                    .into(),
            );
        }
        if self.photons.is_some_and(|n| n > 0) && self.uses_ambient() {
            return Err(
                "--photons ends the gather paths in the photon map, so they never reach the \
                 ambient value: give --ambient-value 0 and --ambient-weight 0, or --photons 0"
                    .into(),
            );
        }
        if self.photon_records && self.global_photons() == 0 {
            return Err("--photon-records on needs photons: give --photons N".into());
        }
        Ok(())
    }

    /// Photons in the global map: the count asked for, or with `auto`
    /// [`AUTO_PHOTONS`] where they serve (gather hits with indirect light of their own: two or
    /// more bounces, the deeper ones traced; or photon records) and none elsewhere, nor with an
    /// ambient value (paths that end in photons never reach it).
    #[must_use]
    pub fn global_photons(&self) -> u64 {
        self.photons.unwrap_or({
            let serve = self.bounces >= 2 && self.deeper == Deeper::PathTraced;
            if (serve || self.photon_records) && !self.uses_ambient() {
                AUTO_PHOTONS
            } else {
                0
            }
        })
    }

    /// Photons asked of the caustic map: the count given, or [`AUTO_CAUSTIC_PHOTONS`] with
    /// `auto`. A scene with no surface that makes caustics gets no map either way
    /// ([`crate::irradiance_cache::prepare::photon_maps`]).
    #[must_use]
    pub fn caustic_photons(&self) -> u64 {
        self.caustic_photons.unwrap_or(AUTO_CAUSTIC_PHOTONS)
    }

    /// Whether light beyond the last bounce is an ambient value (`-av` or `-aw`).
    #[must_use]
    pub fn uses_ambient(&self) -> bool {
        self.ambient_value != Rgb::ZERO || self.ambient_weight > 0
    }

    /// The path's `max_depth` (Mitsuba's count: bounces + 2; `u32::MAX` when unbounded).
    #[must_use]
    pub fn max_depth(&self) -> u32 {
        self.bounces.saturating_add(2)
    }

    /// The smallest and largest record radius R for a scene of size `scene_size` (Radiance's
    /// octree cube size): R_min = size / resolution, R_max = 64 R_min (003 items 3–4).
    #[must_use]
    pub fn radius_limits(&self, scene_size: f32) -> (f32, f32) {
        if self.resolution > 0.0 {
            let r_min = scene_size / self.resolution;
            (r_min, 64.0 * r_min)
        } else {
            (0.0, scene_size * 0.5)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn automatic_photons_serve_only_where_gather_hits_have_indirect_light() {
        let with = |pairs: &[(&str, &str)]| {
            let mut p = IcParams::default();
            for (k, v) in pairs {
                p.set(k, v).unwrap();
            }
            p
        };
        assert_eq!(with(&[("bounces", "1")]).global_photons(), 0);
        assert_eq!(with(&[("bounces", "2")]).global_photons(), AUTO_PHOTONS);
        assert_eq!(with(&[("bounces", "-1")]).global_photons(), AUTO_PHOTONS);
        let records = with(&[("bounces", "1"), ("photon_records", "on")]);
        assert_eq!(records.global_photons(), AUTO_PHOTONS);
        assert!(records.check().is_ok());
        // The caustic map: on, radiance records or not.
        assert_eq!(with(&[]).caustic_photons(), AUTO_CAUSTIC_PHOTONS);
        let radiance = with(&[("radiance_cache", "on")]);
        assert_eq!(radiance.caustic_photons(), AUTO_CAUSTIC_PHOTONS);
        assert!(radiance.check().is_ok());
        let asked = with(&[("radiance_cache", "on"), ("caustic_photons", "1000")]);
        assert!(asked.check().is_ok());
        assert_eq!(with(&[("caustic_photons", "0")]).caustic_photons(), 0);
        let per_level = with(&[("bounces", "3"), ("deeper_bounces", "cache")]);
        assert_eq!(per_level.global_photons(), 0);
        assert!(per_level.check().is_ok());
        for ambient in [("ambient_value", "0.1"), ("ambient_weight", "8")] {
            let p = with(&[("bounces", "3"), ambient]);
            assert_eq!(p.global_photons(), 0, "{ambient:?}");
            assert!(p.check().is_ok());
            let asked = with(&[("bounces", "3"), ambient, ("photons", "1000")]);
            assert!(
                asked.check().unwrap_err().contains("ambient"),
                "{ambient:?}"
            );
        }
        let off = with(&[("bounces", "3"), ("photons", "0")]);
        assert_eq!(off.global_photons(), 0);
        assert_eq!(
            with(&[("bounces", "1"), ("photons", "7")]).global_photons(),
            7
        );
        // The text round-trips, so a cache file's header tells auto from a count.
        assert_eq!(
            with(&[])
                .to_pairs()
                .iter()
                .find(|(k, _)| *k == "photons")
                .unwrap()
                .1,
            "auto"
        );
        assert!(IcParams::default().set("photons", "many").is_err());
    }

    #[test]
    fn every_parameter_reads_back_what_it_prints_and_names_its_errors() {
        // Defaults and a changed value of each survive get → set → get; bad text is refused
        // with the parameter's name; names with dashes and Radiance's aliases find the entry.
        let mut p = IcParams::default();
        for spec in PARAMS {
            let text = (spec.get)(&p);
            (spec.set)(&mut p, &text).unwrap_or_else(|e| panic!("{}: {e}", spec.name));
            assert_eq!((spec.get)(&p), text, "{}", spec.name);
            let e = p.set(spec.name, "nonsense").unwrap_err();
            assert!(e.starts_with(spec.name), "{e}");
            assert!(param(&spec.name.replace('_', "-")).is_some());
            for a in spec.aliases {
                assert_eq!(param(a).map(|s| s.name), Some(spec.name));
            }
        }
        assert_eq!(p, IcParams::default());
        assert!(p
            .set("acuracy", "0.3")
            .unwrap_err()
            .contains("known: accuracy"));
        // Names are unique.
        for (i, a) in PARAMS.iter().enumerate() {
            for b in &PARAMS[i + 1..] {
                assert_ne!(a.name, b.name);
                assert!(!b.aliases.contains(&a.name) && !a.aliases.contains(&b.name));
            }
        }
    }

    #[test]
    fn the_readme_documents_every_parameter() {
        let readme =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md"))
                .expect("README.md beside the workspace");
        for spec in PARAMS {
            let option = format!("`--{} ", spec.name.replace('_', "-"));
            assert!(readme.contains(&option), "README lacks {option}");
        }
    }
}
