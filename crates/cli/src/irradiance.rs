//! `ircache irradiance SCENE`: irradiance at points, like Radiance's `rtrace -I`.
//!
//! Input: lines `x y z nx ny nz` (file or standard input; blank lines and `#` comments are
//! skipped). Output, one line per point: irradiance `R G B` in W/m² (or with `--lux` the
//! illuminance 179 · (0.265 R + 0.670 G + 0.065 B) lm/m²); with `--print-gradients`, then the
//! world-space translational gradient of the indirect part (x y z for R, then G, then B: 9
//! numbers) and its rotational gradient (9 numbers).
//!
//! In scenes with participating media the indirect part is what a media record holds (one
//! bounce through the media, 002's gradients of `--media-gradient`), or with `--integrator path`
//! a gather of `--samples` rays with gradients by central differences; the direct part is
//! attenuated by the media.

use crate::cache_args::CacheArgs;
use crate::render::parse_defines;
use anyhow::{bail, Context, Result};
use clap::Args;
use ircache_math::Vec3;
use ircache_render::irradiance_cache::points::{irradiance_at_points, PointMethod};
use ircache_render::irradiance_cache::IcParams;
use ircache_render::scene::Scene;
use ircache_scene::obj_scene::ObjCamera;
use std::io::{BufRead, Write};
use std::path::PathBuf;

/// Arguments of `ircache irradiance`.
#[derive(Args, Debug, Clone)]
pub struct IrradianceArgs {
    /// Scene file (Mitsuba 3 XML, OBJ or Radiance .rad). Default: the built-in Cornell box.
    pub scene: Option<PathBuf>,
    /// Points file (default: standard input).
    #[arg(long, short = 'i')]
    pub input: Option<PathBuf>,
    /// Set a scene parameter (`-D name=value`).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// ic (the irradiance cache, default) or path (brute force: one gather of --samples rays).
    #[arg(long, default_value = "ic")]
    pub integrator: String,
    /// Hemisphere samples per point for --integrator path.
    #[arg(long, default_value_t = 4096)]
    pub samples: usize,
    /// Print only the indirect part (what the cache holds).
    #[arg(long)]
    pub indirect_only: bool,
    /// Print illuminance (lux, 179 lm/W) instead of RGB irradiance.
    #[arg(long)]
    pub lux: bool,
    /// Append the translational and rotational gradients of the indirect part (18 numbers).
    #[arg(long)]
    pub print_gradients: bool,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, short = 't')]
    pub threads: Option<usize>,
    /// Irradiance cache settings (`--direct-samples` here: light samples per point for the
    /// direct part, default 256, or 4096 where the scene has a sky or another environment).
    #[command(flatten)]
    pub cache: CacheArgs,
}

/// Lines of six numbers, a point and a direction (`layout` names them for messages, `vector`
/// the direction): blank lines and `#` comments skipped, the direction normalised.
pub(crate) fn parse_points(
    text: &str,
    name: &str,
    layout: &str,
    vector: &str,
) -> Result<Vec<(Vec3, Vec3)>> {
    let mut points = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let v: Vec<f32> = line
            .split_whitespace()
            .map(|t| t.parse::<f32>().ok().filter(|x| x.is_finite()))
            .collect::<Option<Vec<_>>>()
            .filter(|v| v.len() == 6)
            .with_context(|| {
                format!(
                    "{name}:{}: expected six finite numbers \"{layout}\", found \"{line}\"",
                    i + 1
                )
            })?;
        let n = Vec3::new(v[3], v[4], v[5]);
        let len = n.length();
        if len.is_nan() || len <= 0.0 || len.is_infinite() {
            bail!(
                "{name}:{}: {vector} ({} {} {}) has no direction",
                i + 1,
                v[3],
                v[4],
                v[5]
            );
        }
        points.push((Vec3::new(v[0], v[1], v[2]), n.normalize()));
    }
    Ok(points)
}

/// The text of `input` (standard input when `None`) and its name for messages.
pub(crate) fn read_input(input: Option<&std::path::Path>) -> Result<(String, String)> {
    Ok(match input {
        Some(p) => (
            std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?,
            p.display().to_string(),
        ),
        None => {
            let mut s = String::new();
            for line in std::io::stdin().lock().lines() {
                s.push_str(&line.context("reading standard input")?);
                s.push('\n');
            }
            (s, "<stdin>".to_string())
        }
    })
}

/// The scene at `scene` (the built-in Cornell box when `None`) with the `-D` definitions
/// `define`, its camera the loaders' default.
pub(crate) fn load_desc(
    scene: Option<&std::path::Path>,
    define: &[String],
) -> Result<ircache_scene::SceneDesc> {
    let defines = parse_defines(define)?;
    Ok(match scene {
        Some(p) => ircache_scene::load_scene(p, &defines, &ObjCamera::default())?,
        None => crate::render::load_builtin(&defines)?,
    })
}

/// Runs `ircache irradiance`.
pub fn run(args: &IrradianceArgs) -> Result<()> {
    let method = match args.integrator.as_str() {
        "ic" | "irrcache" => PointMethod::Cache,
        "path" => {
            if args.samples < 4 {
                bail!("--samples must be at least 4");
            }
            PointMethod::BruteForce {
                samples: args.samples,
            }
        }
        other => bail!("--integrator {other}: expected ic or path"),
    };
    let (text, name) = read_input(args.input.as_deref())?;
    let queries = parse_points(&text, &name, "x y z nx ny nz", "the normal")?;
    let desc = load_desc(args.scene.as_deref(), &args.define)?;
    let scene = Scene::build(&desc).context("building the scene")?;
    let mut params = IcParams::default();
    if args.cache.cache.is_some() || args.cache.exclusions()? != Default::default() {
        bail!("--cache and the exclusion lists apply to `ircache render` only");
    }
    // Light samples per point: many, unless given (points are few; pixels are many). A sky
    // spreads its light over the whole hemisphere: 256 samples leave 1–2 % noise on a
    // point's daylight, 4096 about 0.1 % (BENCHMARKS).
    params.direct_samples = if scene.lights.has_environment() {
        4096
    } else {
        256
    };
    args.cache.apply(&mut params)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()?;
    let direct_samples = if args.indirect_only {
        0
    } else {
        params.direct_samples.max(1)
    };
    let (results, stats) = if scene.has_media() {
        // Through participating media: each point's own gather with 002's gradients (the
        // records' computation), or brute force with finite-difference gradients.
        params.check().map_err(anyhow::Error::msg)?;
        ircache_render::media_cache::cache::available(&params).map_err(anyhow::Error::msg)?;
        let results = pool.install(|| {
            ircache_render::media_cache::points::media_irradiance_at_points(
                &scene,
                &params,
                &queries,
                method,
                direct_samples,
                args.seed,
            )
        });
        (results, None)
    } else {
        params.check_without_media().map_err(anyhow::Error::msg)?;
        pool.install(|| {
            irradiance_at_points(&scene, &params, &queries, method, direct_samples, args.seed)
        })
    };
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for r in &results {
        let e = r.direct + r.indirect;
        let mut line = if args.lux {
            format!("{:e}", 179.0 * (0.265 * e.r + 0.670 * e.g + 0.065 * e.b))
        } else {
            format!("{:e} {:e} {:e}", e.r, e.g, e.b)
        };
        if args.print_gradients {
            for g in r.grad_t.iter().chain(&r.grad_r) {
                line.push_str(&format!(" {:e} {:e} {:e}", g.x, g.y, g.z));
            }
        }
        writeln!(out, "{line}")?;
    }
    out.flush()?;
    if let Some(st) = stats {
        for note in &st.notes {
            eprintln!("note: {note}");
        }
        eprintln!(
            "irradiance cache: {} records for {} points ({} computed, {:.1} M gather rays, {:.2} s)",
            st.records(),
            queries.len(),
            st.records_computed,
            st.gather_rays as f64 * 1e-6,
            st.gather_seconds
        );
    }
    Ok(())
}
