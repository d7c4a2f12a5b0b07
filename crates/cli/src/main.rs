//! `ircache`: the command-line tool.
//!
//! - `ircache render [SCENE]` renders a Mitsuba 3 XML or Wavefront OBJ scene (a built-in Cornell
//!   box when none is given) to OpenEXR, Radiance HDR or PNG.
//! - `ircache animate ANIMATION` renders an animation's frames, its cache kept over time
//!   (temporal radiance caching, age-based invalidation or a cache per frame).
//! - `ircache compare A B` prints relMSE, relMSE_trim, RMSE and the mean-luminance ratio of A
//!   against the reference B (the measures of `shared/tools/relmse.py`).
//! - `ircache irradiance SCENE` prints irradiance at points (by the cache or by brute force).
//! - `ircache rays SCENE` prints the radiance arriving along rays (path traced).
//! - `ircache cache info FILE` prints what an irradiance cache file holds.
//! - `ircache bench` measures ray throughput and rendering speed.
//! - `ircache view [SCENE]` serves the progressive walkthrough to a browser.

mod animate;
mod bench;
mod cache_args;
mod cache_info;
mod compare;
mod gpu;
mod irradiance;
mod rays;
mod render;
mod view;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Global illumination by irradiance caching and path tracing.
#[derive(Parser, Debug)]
#[command(name = "ircache", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to an image.
    Render(Box<render::RenderArgs>),
    /// Render an animation's frames with a cache kept over time.
    Animate(Box<animate::AnimateArgs>),
    /// Compare an image against a reference.
    Compare(compare::CompareArgs),
    /// Irradiance at points read as lines "x y z nx ny nz" (Radiance's rtrace -I).
    Irradiance(Box<irradiance::IrradianceArgs>),
    /// Radiance arriving along rays read as lines "ox oy oz dx dy dz" (Radiance's rtrace -ov).
    Rays(Box<rays::RaysArgs>),
    /// Sum images of the same size (the bands of `render --tile i/n` make the whole image).
    Merge(compare::MergeArgs),
    /// Inspect an irradiance cache file (`ircache cache info FILE`).
    #[command(subcommand)]
    Cache(cache_info::CacheCommand),
    /// Measure ray throughput and rendering speed (prints figures).
    Bench(bench::BenchArgs),
    /// Walk through a scene in the browser: the cache splatted progressively (a local server).
    View(Box<view::ViewArgs>),
}

fn main() -> ExitCode {
    let cli = Cli::parse_from(cache_args::rewrite_radiance_options(
        std::env::args().collect(),
    ));
    let result = match cli.command {
        Command::Render(a) => render::run(&a),
        Command::Animate(a) => animate::run(&a),
        Command::Compare(a) => compare::run(&a),
        Command::Irradiance(a) => irradiance::run(&a),
        Command::Rays(a) => rays::run(&a),
        Command::Cache(c) => cache_info::run(&c),
        Command::Merge(a) => compare::merge(&a),
        Command::Bench(a) => bench::run(&a),
        Command::View(a) => view::run(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
