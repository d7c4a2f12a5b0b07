//! `ircache bench --only peers`: ircache against Mitsuba 3 at its best, by rendering, in the
//! same run.
//!
//! For each scene: Mitsuba 3 (`llvm_ad_rgb`, 2 threads) with its `independent` and
//! `multijitter` samplers at 64 spp; ircache's path tracer (its default sampler) at 16 and 64
//! spp; `ic` at its defaults. Then Mitsuba `multijitter` at 16, 64, 256, … spp ([`super::next_sample_count`]) until it reaches
//! `ic`'s error (or 20 times `ic`'s time), each in a process of its own; the time to equal
//! error is interpolated between the two renders that bracket it (log error against log time),
//! never taken from an error law.
//! Mitsuba renders more than 64 spp in passes of 64 with different seeds (its memory grows
//! with the samples of one pass), as the references were made.

use super::cache_vs_path::{error_at, measure, measure_image, print_time_to_error, run, Point};
use super::mitsuba_render;
use anyhow::{Context, Result};
use ircache_image::Image;
use ircache_render::scene::Scene;
use ircache_scene::obj_scene::ObjCamera;
use std::path::{Path, PathBuf};

/// Mitsuba 3 at `spp` with `sampler` (a process of its own, kernels compiled by a warm-up
/// render first): the time and the image's figures against `reference`.
fn mitsuba(
    scene: &Path,
    depth: u32,
    sampler: &str,
    spp: u32,
    reference: &Image,
    defines: &[(&str, &str)],
) -> Result<Point> {
    let tmp = std::env::temp_dir().join(format!("ircache-peers-{}.exr", std::process::id()));
    let seconds = mitsuba_render(scene, spp, Some(&tmp), depth, Some(sampler), defines)?;
    let img =
        ircache_image::read_image(&tmp).with_context(|| format!("reading {}", tmp.display()))?;
    let _ = std::fs::remove_file(&tmp);
    measure_image(&img, seconds, reference)
}

/// Mitsuba 3 `multijitter` at 16, 64, 256, … spp until a render reaches `error` (and `blurred`,
/// when given) or takes longer than `cap` seconds, each printed by `show`; `defines` set the
/// scene's defaults (`resx`, `resy`).
#[allow(clippy::too_many_arguments)]
pub(super) fn multijitter_series(
    scene: &Path,
    depth: u32,
    defines: &[(&str, &str)],
    reference: &Image,
    error: f64,
    blurred: Option<f64>,
    cap: f64,
    show: &dyn Fn(&str, &Point),
) -> Result<Vec<Point>> {
    let mut series = Vec::new();
    let mut spp = 16;
    loop {
        let p = mitsuba(scene, depth, "multijitter", spp, reference, defines)?;
        show(&format!("Mitsuba multijitter, {spp} spp"), &p);
        series.push(p);
        if (p.error <= error && blurred.is_none_or(|b| p.blurred <= b))
            || p.seconds > cap
            || spp >= 8192
        {
            return Ok(series);
        }
        spp = super::next_sample_count(spp);
    }
}

/// One scene of the comparison: its name, the `max_depth` of its reference and of `ic`, the
/// scene file, the reference, and the scene's defines (for Mitsuba too).
type PeerCase<'a> = (&'a str, u32, PathBuf, PathBuf, Vec<(&'a str, &'a str)>);

/// Runs the comparison.
pub fn run_all(shared: &Path, only: Option<&str>) -> Result<()> {
    // (scene, max_depth of the reference and of `ic`, scene file, reference, defines): the
    // shared scenes, and ours standing in for the kept-back cathedral lit by two small lamps
    // (the shared Sponza meshes, found wherever the shared folder is).
    let meshes = shared
        .join("scenes/sponza-sun/meshes")
        .display()
        .to_string();
    let own = super::radiance::own_scenes();
    let cases: Vec<PeerCase> = vec![
        (
            "cornell-box",
            3,
            shared.join("scenes/cornell-box/scene.xml"),
            shared.join("references/cornell-box-d3.exr"),
            vec![],
        ),
        (
            "sponza-sun",
            3,
            shared.join("scenes/sponza-sun/scene.xml"),
            shared.join("references/sponza-sun-d3.exr"),
            vec![],
        ),
        (
            "cornell-glossy",
            5,
            shared.join("scenes/cornell-glossy/scene.xml"),
            shared.join("references/cornell-glossy-d5.exr"),
            vec![],
        ),
        (
            "sponza-lamps",
            3,
            own.join("sponza-lamps/scene.xml"),
            own.join("sponza-lamps/reference-d3.exr"),
            vec![("meshes", meshes.as_str())],
        ),
    ];
    println!("\nircache against Mitsuba 3 at its best (2 threads, same run; relMSE_trim, blurred σ = 2 px)");
    for (name, depth, scene_path, reference, mi_defines) in cases {
        if !super::selected(only, name) {
            continue;
        }
        let reference = ircache_image::read_image(&reference)
            .with_context(|| format!("reading {}", reference.display()))?;
        let mut defines = vec![("max_depth".to_string(), depth.to_string())];
        defines.extend(
            mi_defines
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string())),
        );
        let desc = ircache_scene::load_scene(&scene_path, &defines, &ObjCamera::default())?;
        let scene = Scene::build(&desc)?;
        println!("\n{name}, max_depth {depth} (ic -ab {})", depth - 2);
        let show = |label: &str, p: &Point| {
            println!(
                "  {label:<40} {:>8.2} s  relMSE_trim {:.3e}  blurred {:.3e}  lum {:.4}",
                p.seconds, p.error, p.blurred, p.lum
            );
        };
        let mut path = Vec::new();
        for spp in [16, 64] {
            let p = measure(&run(&scene, &desc, "path", spp, &[])?, &reference)?;
            show(&format!("ircache path, {spp} spp"), &p);
            path.push(p);
        }
        let ic = measure(&run(&scene, &desc, "ic", 16, &[])?, &reference)?;
        show("ircache ic, defaults, 16 spp", &ic);
        let mut mi_series = Vec::new();
        match mitsuba(
            &scene_path,
            depth,
            "independent",
            64,
            &reference,
            &mi_defines,
        ) {
            Ok(p) => show("Mitsuba independent, 64 spp", &p),
            Err(e) => {
                println!("  Mitsuba 3 not measured: {e:#}");
                continue;
            }
        }
        mi_series.extend(multijitter_series(
            &scene_path,
            depth,
            &mi_defines,
            &reference,
            ic.error,
            Some(ic.blurred),
            20.0 * ic.seconds,
            &show,
        )?);
        let path64 = *path.last().context("the 64-spp path render")?;
        match error_at(&mi_series, path64.seconds, |p| p.error) {
            Some(e) => println!(
                "  path at equal time: ircache 64 spp {:.3e} against Mitsuba multijitter {e:.3e} at {:.2} s ({})",
                path64.error,
                path64.seconds,
                if path64.error <= e { "ircache lower" } else { "Mitsuba lower" }
            ),
            None => println!("  path at equal time: ircache's 64-spp time lies outside Mitsuba's series"),
        }
        print_time_to_error("Mitsuba multijitter to ic's error", &mi_series, &ic);
    }
    Ok(())
}
