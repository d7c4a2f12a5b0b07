//! Irradiance cache options shared by `render` and `irradiance`, under users' names and
//! Radiance's (`-aa`, `-ad`, `-as`, `-ar`, `-ab`, `-av r g b`, rewritten to long options before
//! parsing).

use anyhow::{bail, Result};
use clap::Args;
use ircache_render::irradiance_cache::params::{param, PARAMS};
use ircache_render::irradiance_cache::IcParams;

/// Irradiance cache options: one per entry of the parameter table
/// ([`ircache_render::irradiance_cache::params::PARAMS`]), plus the cache file and the
/// exclusion lists.
#[derive(Args, Debug, Clone, Default)]
pub struct CacheArgs {
    /// The table's options that were given, as (name, value).
    #[command(flatten)]
    pub params: ParamArgs,
    /// Persistent cache file (Radiance -af): records are read from it first and new ones
    /// appended batch by batch; several processes may share it.
    #[arg(
        long,
        visible_alias = "af",
        value_name = "FILE",
        help_heading = "Irradiance cache"
    )]
    pub cache: Option<std::path::PathBuf>,
    /// check (default): a file made for another scene, view or settings is refused with the
    /// reason; force: used anyway.
    #[arg(
        long = "cache-reuse",
        value_name = "check|force",
        help_heading = "Irradiance cache"
    )]
    pub cache_reuse: Option<String>,
    /// Surface (shape id in XML, material name in OBJ) that takes no records and gets the
    /// ambient value as its indirect light (Radiance -ae); repeatable.
    #[arg(
        long = "ambient-exclude",
        visible_alias = "ae",
        value_name = "NAME",
        help_heading = "Irradiance cache"
    )]
    pub ambient_exclude: Vec<String>,
    /// File listing surfaces to exclude, one name per line (Radiance -aE).
    #[arg(
        long = "ambient-exclude-file",
        visible_alias = "aE",
        value_name = "FILE",
        help_heading = "Irradiance cache"
    )]
    pub ambient_exclude_file: Vec<std::path::PathBuf>,
    /// Only this surface takes records (Radiance -ai); repeatable.
    #[arg(
        long = "ambient-include",
        visible_alias = "ai",
        value_name = "NAME",
        help_heading = "Irradiance cache"
    )]
    pub ambient_include: Vec<String>,
    /// File listing the only surfaces that take records (Radiance -aI).
    #[arg(
        long = "ambient-include-file",
        visible_alias = "aI",
        value_name = "FILE",
        help_heading = "Irradiance cache"
    )]
    pub ambient_include_file: Vec<std::path::PathBuf>,
}

/// The options made from the parameter table, in the order given.
#[derive(Debug, Clone, Default)]
pub struct ParamArgs {
    /// (name in the table, value text) for each option given.
    pub given: Vec<(&'static str, String)>,
}

impl clap::FromArgMatches for ParamArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut given = Vec::new();
        for spec in PARAMS {
            if let Some(v) = m.get_one::<String>(spec.name) {
                given.push((spec.name, v.clone()));
            }
        }
        Ok(ParamArgs { given })
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl clap::Args for ParamArgs {
    fn augment_args(mut cmd: clap::Command) -> clap::Command {
        let defaults = IcParams::default();
        for spec in PARAMS {
            let radiance: Vec<&'static str> = spec
                .aliases
                .iter()
                .copied()
                .filter(|a| a.len() == 2)
                .collect();
            let dashed = spec.name.replace('_', "-");
            let mut help = format!("{} [default: {}]", spec.help, (spec.get)(&defaults));
            if let Some(r) = radiance.first() {
                help = format!("(Radiance -{r}) {help}");
            }
            let mut arg = clap::Arg::new(spec.name)
                .long(dashed)
                .value_name(spec.value)
                .help(help)
                .help_heading("Irradiance cache");
            for r in radiance {
                arg = arg.visible_alias(r);
            }
            cmd = cmd.arg(arg);
        }
        cmd
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl CacheArgs {
    /// True when any cache option was given.
    #[must_use]
    pub fn any(&self) -> bool {
        !self.params.given.is_empty()
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
        for (name, value) in &self.params.given {
            if let Some(spec) = param(name) {
                if let Err(e) = (spec.set)(params, value) {
                    bail!("--{}: {e}", name.replace('_', "-"));
                }
            }
        }
        params.check().map_err(anyhow::Error::msg)
    }
}

/// How many values rpict's view option `opt` takes (`-vtv` none, `-vp` three, ...), if it is one.
fn view_option_arity(opt: &str) -> Option<usize> {
    match opt {
        "-vtv" | "-vtl" | "-vth" | "-vta" | "-vts" | "-vtc" => Some(0),
        "-vp" | "-vd" | "-vu" => Some(3),
        "-vh" | "-vv" | "-vo" | "-va" | "-vs" | "-vl" | "-vf" => Some(1),
        _ => None,
    }
}

/// Rewrites Radiance-style options (`-aa 0.1`, `-av 0.1 0.1 0.1`) into the long forms clap
/// parses; rpict's view options (`-vp 1 2 3 -vd 0 1 0 -vth …`, `-vf file`) join into one
/// `--view`, and `-x N`, `-y N` become `--width N`, `--height N`, so that an rpict command line
/// reads as it is.
#[must_use]
pub fn rewrite_radiance_options(args: Vec<String>) -> Vec<String> {
    let mut out = Vec::with_capacity(args.len());
    let mut view: Vec<String> = Vec::new();
    let mut i = 0;
    while i < args.len() {
        let a = &args[i];
        if let Some(n) = view_option_arity(a) {
            view.extend(args[i..(i + 1 + n).min(args.len())].iter().cloned());
            i += 1 + n;
            continue;
        }
        if (a == "-x" || a == "-y") && args.get(i + 1).is_some_and(|v| v.parse::<u32>().is_ok()) {
            out.push(if a == "-x" { "--width" } else { "--height" }.into());
            out.push(args[i + 1].clone());
            i += 2;
            continue;
        }
        match a.as_str() {
            "-af" | "-ae" | "-aE" | "-ai" | "-aI" => out.push(format!("-{a}")),
            "-av" => {
                out.push("--av".into());
                let three: Vec<&String> = args.iter().skip(i + 1).take(3).collect();
                if three.len() == 3 && three.iter().all(|v| v.parse::<f32>().is_ok()) {
                    out.push(format!("{},{},{}", three[0], three[1], three[2]));
                    i += 4;
                    continue;
                }
            }
            r if r.len() == 3 && r.starts_with("-a") && param(&r[1..]).is_some() => {
                out.push(format!("-{a}"))
            }
            _ => out.push(a.clone()),
        }
        i += 1;
    }
    if !view.is_empty() {
        out.push("--view".into());
        out.push(view.join(" "));
    }
    out
}
