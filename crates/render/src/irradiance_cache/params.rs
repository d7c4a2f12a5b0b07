//! Parameters of the irradiance cache, named for users, with Radiance's names accepted too
//! (`-aa`, `-ad`, `-ar`, `-ab`, `-av`).

use super::record::{ErrorMetric, GradientMode};
use ircache_math::Rgb;

/// The settings `ircache bench` times on the Cornell box (at 16 spp), and the reference test
/// checks: they reach Radiance's "high" error there.
pub const CORNELL_BOX_BENCH: &[(&str, &str)] = &[
    ("error_metric", "tabellion"),
    ("accuracy", "0.5"),
    ("divisions", "512"),
    ("resolution", "0"),
    ("direct_samples", "4"),
];

/// The settings `ircache bench` times on Sponza (at 8 spp).
pub const SPONZA_BENCH: &[(&str, &str)] = &[
    ("error_metric", "tabellion"),
    ("accuracy", "0.5"),
    ("divisions", "1024"),
    ("supersamples", "512"),
    ("resolution", "0"),
];

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
    /// Indirect bounces (`-ab`): one cache per bounce level; equals path tracing with
    /// `max_depth` = bounces + 2.
    pub bounces: u32,
    /// Radiance assumed beyond the last bounce (`-av`).
    pub ambient_value: Rgb,
    /// Gradients used in interpolation.
    pub gradients: GradientMode,
    /// Translational gradient formula.
    pub formula: TranslationalFormula,
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
    /// Where the bounces beyond a record's own level come from (`--deeper-bounces`).
    pub deeper: Deeper,
    /// Light samples per pixel sample for the direct term (stratified over the light when a
    /// square number): shadow rays are cheaper than pixel samples.
    pub direct_samples: u32,
}

impl Default for IcParams {
    fn default() -> Self {
        IcParams {
            accuracy: 0.4,
            divisions: 512,
            // Radiance's 128 would floor Tabellion's footprint radii at size/256 (4× Sponza's
            // error, measured); the floor stays for records the camera does not see.
            resolution: 1024.0,
            bounces: 1,
            ambient_value: Rgb::ZERO,
            gradients: GradientMode::Full,
            formula: TranslationalFormula::WardHeckbert,
            direct_samples: 4,
            supersamples: 1536,
            record_error: 0.1,
            ambient_weight: 0,
            // Chosen by measurement (BENCHMARKS.md): at equal time Tabellion–Lamorlette's metric
            // reaches about half Ward's error on Sponza and two thirds on the Cornell box.
            error_metric: ErrorMetric::Tabellion,
            overture: Overture::Full,
            spatial_order: false,
            neighbour_clamp: false,
            deeper: Deeper::PathTraced,
        }
    }
}

impl IcParams {
    /// Sets a parameter by its user name or Radiance name; `value` is the text given.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), String> {
        let float = |v: &str| -> Result<f32, String> {
            v.trim()
                .parse::<f32>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("{name}: expected a number, found \"{v}\""))
        };
        match name {
            "accuracy" | "aa" => {
                let a = float(value)?;
                if !(a > 0.0 && a <= 2.0) {
                    return Err(format!("{name}: expected 0 < accuracy ≤ 2, found {a}"));
                }
                self.accuracy = a;
            }
            "divisions" | "ad" => {
                let d = value.trim().parse::<usize>().map_err(|_| {
                    format!("{name}: expected a whole number of divisions, found \"{value}\"")
                })?;
                if !(4..=1_000_000).contains(&d) {
                    return Err(format!(
                        "{name}: expected 4 to 1000000 divisions, found {d}"
                    ));
                }
                self.divisions = d;
            }
            "ambient_weight" | "ambient-weight" | "aw" => {
                self.ambient_weight = value
                    .trim()
                    .parse::<u32>()
                    .ok()
                    .filter(|n| *n <= 65535)
                    .ok_or_else(|| {
                        format!("{name}: expected a whole weight 0 to 65535, found \"{value}\"")
                    })?;
            }
            "supersamples" | "as" => {
                self.supersamples = value
                    .trim()
                    .parse::<usize>()
                    .ok()
                    .filter(|n| *n <= 1_000_000)
                    .ok_or_else(|| {
                        format!("{name}: expected 0 to 1000000 super-samples, found \"{value}\"")
                    })?;
            }
            "record_error" | "record-error" => {
                let e = float(value)?;
                if !(0.0..=10.0).contains(&e) {
                    return Err(format!(
                        "{name}: expected 0 to 10 (a fraction of the accuracy), found {e}"
                    ));
                }
                self.record_error = e;
            }
            "resolution" | "ar" => {
                let r = float(value)?;
                if r < 0.0 {
                    return Err(format!("{name}: expected a resolution ≥ 0, found {r}"));
                }
                self.resolution = r;
            }
            "bounces" | "ab" => {
                self.bounces = value
                    .trim()
                    .parse::<u32>()
                    .ok()
                    .filter(|b| *b <= 64)
                    .ok_or_else(|| {
                        format!("{name}: expected 0 to 64 bounces, found \"{value}\"")
                    })?;
            }
            "ambient_value" | "ambient-value" | "av" => {
                let parts: Vec<&str> = value
                    .split(|c: char| c == ',' || c.is_whitespace())
                    .filter(|t| !t.is_empty())
                    .collect();
                let v = match parts[..] {
                    [x] => Rgb::splat(float(x)?),
                    [r, g, b] => Rgb::new(float(r)?, float(g)?, float(b)?),
                    _ => {
                        return Err(format!(
                            "{name}: expected one value or three (r g b), found \"{value}\""
                        ))
                    }
                };
                if !v.is_valid_radiance() {
                    return Err(format!(
                        "{name}: expected a radiance ≥ 0, found \"{value}\""
                    ));
                }
                self.ambient_value = v;
            }
            "direct_samples" | "direct-samples" => {
                self.direct_samples = value
                    .trim()
                    .parse::<u32>()
                    .ok()
                    .filter(|n| (1..=4096).contains(n))
                    .ok_or_else(|| {
                        format!("{name}: expected 1 to 4096 light samples, found \"{value}\"")
                    })?;
            }
            "record_order" | "record-order" => {
                self.spatial_order = match value.trim() {
                    "spatial" => true,
                    "insertion" => false,
                    v => {
                        return Err(format!(
                            "{name}: expected insertion or spatial, found \"{v}\""
                        ))
                    }
                }
            }
            "overture" => {
                self.overture = match value.trim() {
                    "full" | "on" => Overture::Full,
                    "coarse" => Overture::Coarse,
                    "off" => Overture::Off,
                    v => {
                        return Err(format!(
                            "{name}: expected full, coarse or off, found \"{v}\""
                        ))
                    }
                }
            }
            "error_metric" | "error-metric" => {
                self.error_metric = ErrorMetric::parse(value.trim())?
            }
            "neighbour_clamp" | "neighbour-clamp" | "neighbor_clamp" => {
                self.neighbour_clamp = match value.trim() {
                    "on" | "true" | "1" => true,
                    "off" | "false" | "0" => false,
                    v => return Err(format!("{name}: expected on or off, found \"{v}\"")),
                }
            }
            "deeper_bounces" | "deeper-bounces" => {
                self.deeper = Deeper::parse(value.trim()).map_err(|e| format!("{name}: {e}"))?
            }
            "gradients" => self.gradients = GradientMode::parse(value.trim())?,
            "gradient_formula" | "gradient-formula" => {
                self.formula = match value.trim() {
                    "ward-heckbert" | "3.48" => TranslationalFormula::WardHeckbert,
                    "krivanek" | "3.47" => TranslationalFormula::Krivanek,
                    v => {
                        return Err(format!(
                            "{name}: expected ward-heckbert or krivanek, found \"{v}\""
                        ))
                    }
                }
            }
            _ => return Err(format!("unknown irradiance cache parameter \"{name}\"")),
        }
        Ok(())
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
