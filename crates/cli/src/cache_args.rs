//! Irradiance cache options shared by `render` and `irradiance`, under users' names and
//! Radiance's (`-aa`, `-ad`, `-as`, `-ar`, `-ab`, `-av r g b`, rewritten to long options before
//! parsing).

use anyhow::{bail, Result};
use clap::Args;
use ircache_render::irradiance_cache::IcParams;

/// Irradiance cache settings from the command line.
#[derive(Args, Debug, Clone, Default)]
pub struct CacheArgs {
    /// Accuracy a (Radiance -aa; default 0.4): with --error-metric ward a record serves where
    /// its split-sphere error ε ≤ a; with tabellion (the default) κ = 0.2/a.
    #[arg(long, visible_alias = "aa", help_heading = "Irradiance cache")]
    pub accuracy: Option<String>,
    /// Hemisphere divisions per record (Radiance -ad; default 512).
    #[arg(long, visible_alias = "ad", help_heading = "Irradiance cache")]
    pub divisions: Option<String>,
    /// Resolution (Radiance -ar; default 1024): smallest record radius = scene size / resolution;
    /// 0: none.
    #[arg(long, visible_alias = "ar", help_heading = "Irradiance cache")]
    pub resolution: Option<String>,
    /// Indirect bounces (Radiance -ab; default max_depth − 2); equals path tracing with
    /// max_depth N + 2.
    #[arg(long, visible_alias = "ab", help_heading = "Irradiance cache")]
    pub bounces: Option<String>,
    /// Radiance beyond the last bounce, "v" or "r,g,b" (Radiance -av r g b; default 0).
    #[arg(
        long = "ambient-value",
        visible_alias = "av",
        help_heading = "Irradiance cache"
    )]
    pub ambient_value: Option<String>,
    /// Adaptive super-samples per record (Radiance -as; default 256): extra rays where
    /// neighbours differ most.
    #[arg(long, visible_alias = "as", help_heading = "Irradiance cache")]
    pub supersamples: Option<String>,
    /// Light samples per pixel sample for the direct term (default 4).
    #[arg(long = "direct-samples", help_heading = "Irradiance cache")]
    pub direct_samples: Option<String>,
    /// Weight of the ambient value in a running average with computed irradiance (Radiance -aw).
    #[arg(
        long = "ambient-weight",
        visible_alias = "aw",
        help_heading = "Irradiance cache"
    )]
    pub ambient_weight: Option<String>,
    /// The pre-pass that fills the cache before the pixels: full (every pixel centre), coarse
    /// (every fourth), off.
    #[arg(long, help_heading = "Irradiance cache")]
    pub overture: Option<String>,
    /// Record order in memory after the pre-pass: insertion or spatial (Morton order).
    #[arg(long = "record-order", help_heading = "Irradiance cache")]
    pub record_order: Option<String>,
    /// Record error metric: ward (split sphere), tabellion (Tabellion–Lamorlette, default) or
    /// hessian (second-order radius from the gather's Hessian).
    #[arg(long = "error-metric", help_heading = "Irradiance cache")]
    pub error_metric: Option<String>,
    /// Neighbour clamping (on/off): a record's radius never exceeds a neighbour's plus their distance.
    #[arg(long = "neighbour-clamp", help_heading = "Irradiance cache")]
    pub neighbour_clamp: Option<String>,
    /// Gradients used in interpolation: none, rotation, full (default).
    #[arg(long, help_heading = "Irradiance cache")]
    pub gradients: Option<String>,
    /// Persistent cache file (Radiance -af): records are read from it first and new ones appended.
    #[arg(
        long,
        visible_alias = "af",
        value_name = "FILE",
        help_heading = "Irradiance cache"
    )]
    pub cache: Option<std::path::PathBuf>,
    /// A cache file made for another scene or other settings: check (refuse it) or force (use it).
    #[arg(
        long = "cache-reuse",
        value_name = "check|force",
        help_heading = "Irradiance cache"
    )]
    pub cache_reuse: Option<String>,
    /// Surfaces (shape id in XML, material in OBJ) that take no records but the ambient value
    /// instead (Radiance -ae); repeatable.
    #[arg(
        long = "ambient-exclude",
        visible_alias = "ae",
        value_name = "NAME",
        help_heading = "Irradiance cache"
    )]
    pub ambient_exclude: Vec<String>,
    /// A file of names to exclude, one per line (Radiance -aE).
    #[arg(
        long = "ambient-exclude-file",
        visible_alias = "aE",
        value_name = "FILE",
        help_heading = "Irradiance cache"
    )]
    pub ambient_exclude_file: Vec<std::path::PathBuf>,
    /// Only these surfaces take records (Radiance -ai); repeatable.
    #[arg(
        long = "ambient-include",
        visible_alias = "ai",
        value_name = "NAME",
        help_heading = "Irradiance cache"
    )]
    pub ambient_include: Vec<String>,
    /// A file of names to include, one per line (Radiance -aI).
    #[arg(
        long = "ambient-include-file",
        visible_alias = "aI",
        value_name = "FILE",
        help_heading = "Irradiance cache"
    )]
    pub ambient_include_file: Vec<std::path::PathBuf>,
    /// Translational gradient formula: ward-heckbert (000 eq. 3.48) or krivanek (3.47).
    #[arg(long = "gradient-formula", help_heading = "Irradiance cache")]
    pub gradient_formula: Option<String>,
}

impl CacheArgs {
    fn pairs(&self) -> Vec<(&'static str, &String)> {
        [
            ("accuracy", &self.accuracy),
            ("divisions", &self.divisions),
            ("resolution", &self.resolution),
            ("bounces", &self.bounces),
            ("ambient_value", &self.ambient_value),
            ("gradients", &self.gradients),
            ("direct_samples", &self.direct_samples),
            ("supersamples", &self.supersamples),
            ("ambient_weight", &self.ambient_weight),
            ("error_metric", &self.error_metric),
            ("overture", &self.overture),
            ("record_order", &self.record_order),
            ("neighbour_clamp", &self.neighbour_clamp),
            ("gradient_formula", &self.gradient_formula),
        ]
        .into_iter()
        .filter_map(|(n, v)| v.as_ref().map(|v| (n, v)))
        .collect()
    }

    /// True when any option was given.
    #[must_use]
    pub fn any(&self) -> bool {
        !self.pairs().is_empty()
            || self.cache.is_some()
            || self.cache_reuse.is_some()
            || !self.ambient_exclude.is_empty()
            || !self.ambient_include.is_empty()
            || !self.ambient_exclude_file.is_empty()
            || !self.ambient_include_file.is_empty()
    }

    /// The exclusion or inclusion list (names and names read from files).
    pub fn exclusions(&self) -> Result<ircache_render::integrators::ic::Exclusions> {
        use ircache_render::integrators::ic::Exclusions;
        let read = |names: &[String], files: &[std::path::PathBuf]| -> Result<Vec<String>> {
            let mut all = names.to_vec();
            for f in files {
                let text = std::fs::read_to_string(f)
                    .map_err(|e| anyhow::anyhow!("{}: {e}", f.display()))?;
                all.extend(
                    text.lines()
                        .map(str::trim)
                        .filter(|l| !l.is_empty() && !l.starts_with('#'))
                        .map(String::from),
                );
            }
            Ok(all)
        };
        let ex = read(&self.ambient_exclude, &self.ambient_exclude_file)?;
        let inc = read(&self.ambient_include, &self.ambient_include_file)?;
        match (ex.is_empty(), inc.is_empty()) {
            (true, true) => Ok(Exclusions::None),
            (false, true) => Ok(Exclusions::Exclude(ex)),
            (true, false) => Ok(Exclusions::Include(inc)),
            (false, false) => bail!(
                "--ambient-exclude and --ambient-include cannot be combined (Radiance's -ae/-ai either)"
            ),
        }
    }

    /// The cache file and whether a stale one may be used.
    pub fn cache_file(&self) -> Result<(Option<std::path::PathBuf>, bool)> {
        let force = match self.cache_reuse.as_deref() {
            None | Some("check") => false,
            Some("force") => true,
            Some(o) => bail!("--cache-reuse {o}: expected check or force"),
        };
        if force && self.cache.is_none() {
            bail!("--cache-reuse needs --cache FILE");
        }
        Ok((self.cache.clone(), force))
    }

    /// Applies the options given to `params`.
    pub fn apply(&self, params: &mut IcParams) -> Result<()> {
        for (name, value) in self.pairs() {
            if let Err(e) = params.set(name, value) {
                bail!("--{}: {e}", name.replace('_', "-"));
            }
        }
        Ok(())
    }
}

/// Rewrites Radiance-style options (`-aa 0.1`, `-av 0.1 0.1 0.1`) into the long forms clap
/// parses.
#[must_use]
pub fn rewrite_radiance_options(args: Vec<String>) -> Vec<String> {
    let mut out = Vec::with_capacity(args.len());
    let mut i = 0;
    while i < args.len() {
        let a = &args[i];
        match a.as_str() {
            "-aa" | "-ad" | "-ar" | "-ab" | "-as" | "-af" | "-aw" | "-ae" | "-aE" | "-ai"
            | "-aI" => out.push(format!("-{a}")),
            "-av" => {
                out.push("--av".into());
                let three: Vec<&String> = args.iter().skip(i + 1).take(3).collect();
                if three.len() == 3 && three.iter().all(|v| v.parse::<f32>().is_ok()) {
                    out.push(format!("{},{},{}", three[0], three[1], three[2]));
                    i += 4;
                    continue;
                }
            }
            _ => out.push(a.clone()),
        }
        i += 1;
    }
    out
}
