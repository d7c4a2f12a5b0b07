//! `ircache rays SCENE`: radiance along rays, like Radiance's `rtrace -ov`.
//!
//! Input: lines `ox oy oz dx dy dz` (file or standard input; blank lines and `#` comments are
//! skipped). Output, one line per ray: the radiance arriving along it, `R G B` in W sr⁻¹ m⁻²
//! (or with `--lum` the luminance 179 · (0.265 R + 0.670 G + 0.065 B) cd/m²): the mean of
//! `--samples` path-traced estimates (`volpath` where the scene has media) at the scene's
//! `max_depth` or `--max-depth`, unbiased; samples the integrator returns as non-finite count as
//! zero and are reported. Same seed, same numbers, for any thread count.

use crate::irradiance::{load_desc, parse_points, read_input};
use anyhow::{bail, Context, Result};
use clap::Args;
use ircache_math::{Ray, Rgb};
use ircache_render::integrators::Integrator;
use ircache_render::integrators::RayCounts;
use ircache_render::sampler::{dims, SamplerKind, SamplerSettings};
use ircache_render::scene::Scene;
use rayon::prelude::*;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `ircache rays`.
#[derive(Args, Debug, Clone)]
pub struct RaysArgs {
    /// Scene file (Mitsuba 3 XML, OBJ or Radiance .rad/.oct). Default: the built-in Cornell box.
    pub scene: Option<PathBuf>,
    /// Rays file (default: standard input).
    #[arg(long, short = 'i')]
    pub input: Option<PathBuf>,
    /// Set a scene parameter (`-D name=value`).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Path-traced samples per ray.
    #[arg(long, default_value_t = 1024)]
    pub samples: u32,
    /// Longest path (Mitsuba's max_depth: 1 sees emitters only, 2 direct light; -1 unbounded).
    /// Default: the scene's.
    #[arg(long, allow_negative_numbers = true)]
    pub max_depth: Option<i32>,
    /// Print luminance (cd/m², 179 lm/W) instead of RGB radiance.
    #[arg(long)]
    pub lum: bool,
    /// Seed of the samples.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, short = 't')]
    pub threads: Option<usize>,
}

/// Runs `ircache rays`.
pub fn run(args: &RaysArgs) -> Result<()> {
    if args.samples == 0 {
        bail!("--samples must be at least 1");
    }
    let (text, name) = read_input(args.input.as_deref())?;
    let rays = parse_points(&text, &name, "ox oy oz dx dy dz", "the direction")?;
    let desc = load_desc(args.scene.as_deref(), &args.define)?;
    let scene = Scene::build(&desc).context("building the scene")?;
    let mut integrator = desc.integrator.clone();
    integrator.kind = if scene.has_media() { "volpath" } else { "path" }.into();
    if let Some(d) = args.max_depth {
        integrator.max_depth = d;
    }
    let integrator = Integrator::from_desc(&integrator).map_err(anyhow::Error::msg)?;
    // One "pixel" per ray: its samples are the sampler's of that pixel.
    let samplers = SamplerSettings::new(
        SamplerKind::Sobol,
        args.samples,
        args.seed,
        rays.len().max(1) as u32,
        1,
    );
    let spp = samplers.spp;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()?;
    let results: Vec<(Rgb, u64)> = pool.install(|| {
        rays.par_iter()
            .enumerate()
            .map(|(i, &(o, d))| {
                let mut sampler = samplers.pixel(i as u32, 0);
                let mut counts = RayCounts::default();
                let ray = Ray::new(o, d);
                let (mut sum, mut invalid) = (Rgb::ZERO, 0u64);
                for k in 0..spp {
                    sampler.set_sample(k, dims::vertex(0, 0));
                    let l = integrator.li_ray(&scene, &ray, &mut sampler, &mut counts);
                    if l.is_valid_radiance() {
                        sum += l;
                    } else {
                        invalid += 1;
                    }
                }
                (sum / spp as f32, invalid)
            })
            .collect()
    });
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let mut invalid = 0;
    for (l, bad) in &results {
        invalid += bad;
        if args.lum {
            writeln!(
                out,
                "{:e}",
                179.0 * (0.265 * l.r + 0.670 * l.g + 0.065 * l.b)
            )?;
        } else {
            writeln!(out, "{:e} {:e} {:e}", l.r, l.g, l.b)?;
        }
    }
    out.flush()?;
    if invalid > 0 {
        eprintln!("note: {invalid} sample(s) were not finite and counted as zero");
    }
    Ok(())
}
