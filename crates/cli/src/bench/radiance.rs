//! `ircache bench --only radiance`: radiance caching (issue 10) by rendering, in the same run.
//!
//! For cornell-glossy and ircache's own moderately glossy `scenes/cornell-rough` (`-ab 3`, against
//! `max_depth` 5 references): `ic --radiance-cache on` at its defaults (16 spp), and `auto` (the
//! default: metals' lobes only); `ic` with the same lobes traced (`off`) at 16, 64, 256, … spp
//! until it reaches `on`'s error; ircache's path tracer at 16
//! and 64 spp; Mitsuba 3 `multijitter` at 16, 64, … spp until it reaches the error. Times to
//! equal error are interpolated between the bracketing renders (log–log), never extrapolated.
//! Then environment light in the records (`--cached-environment`, `irradiance_cache::environment`)
//! on `scenes/sky-glossy`, under its smooth sky and under the same sky with a sun; and the
//! thesis's setting: the glossy Cornell box at 1000 × 1000 (001 §4.7.1: 12.2 s with 3,023
//! irradiance and 869 radiance records on a 2006 GPU).

use super::cache_vs_path::{fmt_time, measure, print_time_to_error, run, time_to, Point};
use super::peers::multijitter_series;
use anyhow::{Context, Result};
use ircache_render::scene::Scene;
use ircache_scene::obj_scene::ObjCamera;
use std::path::{Path, PathBuf};

/// ircache's own scenes: `scenes/` beside the workspace.
pub(super) fn own_scenes() -> PathBuf {
    let here = PathBuf::from("scenes");
    if here.join("cornell-rough").is_dir() {
        here
    } else {
        PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes"))
    }
}

fn show(label: &str, p: &Point) {
    println!(
        "  {label:<44} {:>8.2} s  relMSE_trim {:.3e}  blurred {:.3e}  lum {:.4}",
        p.seconds, p.error, p.blurred, p.lum
    );
}

/// Runs the comparison.
pub fn run_all(shared: &Path, with_mitsuba: bool) -> Result<()> {
    let own = own_scenes();
    let cases = [
        (
            "cornell-glossy",
            shared.join("scenes/cornell-glossy/scene.xml"),
            shared.join("references/cornell-glossy-d5.exr"),
        ),
        (
            "cornell-rough",
            own.join("cornell-rough/scene.xml"),
            own.join("cornell-rough/reference-d5.exr"),
        ),
    ];
    println!("\nRadiance caching (ic -ab 3 against max_depth 5 references; 2 threads, same run)");
    let on = [("radiance_cache", "on")];
    let off = [("radiance_cache", "off")];
    for (name, scene_path, reference_path) in &cases {
        let reference = ircache_image::read_image(reference_path)
            .with_context(|| format!("reading {}", reference_path.display()))?;
        let defines = vec![("max_depth".to_string(), "5".to_string())];
        let desc = ircache_scene::load_scene(scene_path, &defines, &ObjCamera::default())?;
        let scene = Scene::build(&desc)?;
        println!("\n{name}");
        let out = run(&scene, &desc, "ic", 16, &on)?;
        let cached = measure(&out, &reference)?;
        let radiance_records = out.cache.as_ref().map_or(0, |c| c.stats.radiance_records);
        show(
            &format!("ic, radiance cache on, 16 spp ({radiance_records} radiance records)"),
            &cached,
        );
        let auto = run(&scene, &desc, "ic", 16, &[("radiance_cache", "auto")])?;
        let auto_records = auto.cache.as_ref().map_or(0, |c| c.stats.radiance_records);
        show(
            &format!("ic, radiance cache auto, 16 spp ({auto_records} radiance records)"),
            &measure(&auto, &reference)?,
        );
        let cap = 20.0 * cached.seconds;
        let mut traced = Vec::new();
        let mut spp = 16;
        loop {
            let p = measure(&run(&scene, &desc, "ic", spp, &off)?, &reference)?;
            show(&format!("ic, glossy lobes traced, {spp} spp"), &p);
            traced.push(p);
            if p.error <= cached.error || p.seconds > cap || spp >= 1024 {
                break;
            }
            spp = super::next_sample_count(spp);
        }
        for spp in [16, 64] {
            show(
                &format!("ircache path, {spp} spp"),
                &measure(&run(&scene, &desc, "path", spp, &[])?, &reference)?,
            );
        }
        let last = traced.last().map_or(0.0, |p| p.seconds);
        let t = time_to(&traced, cached.error, |p| p.error);
        println!(
            "  tracing the lobes to the radiance cache's error: {} ({}×)",
            fmt_time(t, last),
            t.map_or("?".into(), |t| format!("{:.1}", t / cached.seconds))
        );
        if !with_mitsuba {
            continue;
        }
        let mi = match multijitter_series(
            scene_path,
            5,
            &[],
            &reference,
            cached.error,
            None,
            cap,
            &show,
        ) {
            Ok(mi) => mi,
            Err(e) => {
                println!("  Mitsuba 3 not measured: {e:#}");
                Vec::new()
            }
        };
        if !mi.is_empty() {
            print_time_to_error(
                "Mitsuba multijitter to the radiance cache's error",
                &mi,
                &cached,
            );
        }
    }
    environment(&own)?;
    // The thesis's setting: 1000 × 1000, one bounce.
    let scene_path = own.join("cornell-rough/scene.xml");
    let defines = vec![
        ("max_depth".to_string(), "3".to_string()),
        ("resx".to_string(), "1000".to_string()),
        ("resy".to_string(), "1000".to_string()),
    ];
    let desc = ircache_scene::load_scene(&scene_path, &defines, &ObjCamera::default())?;
    let scene = Scene::build(&desc)?;
    let out = run(&scene, &desc, "ic", 4, &on)?;
    let (records, radiance) = out
        .cache
        .as_ref()
        .map_or((0, 0), |c| (c.stats.records(), c.stats.radiance_records));
    println!(
        "\ncornell-rough at 1000 × 1000, -ab 1, 4 spp: {:.2} s, {} records of which {} radiance records \
         (the thesis: 12.2 s, 3,023 irradiance and 869 radiance records, on a 2006 GPU)",
        out.seconds, records, radiance
    );
    Ok(())
}

/// `--cached-environment` on `scenes/sky-glossy` (`-ab 1`, 16 spp, radiance cache on): each
/// choice, under the smooth sky and under the sky with a sun, against the path tracer.
fn environment(own: &Path) -> Result<()> {
    println!(
        "\nEnvironment light in the records (sky-glossy, 256 × 256, -ab 1, radiance cache on, 16 spp)"
    );
    let scene_path = own.join("sky-glossy/scene.xml");
    for (sky, reference) in [
        ("sky.exr", "reference-d3.exr"),
        ("sky-sun.exr", "reference-sun-d3.exr"),
    ] {
        let reference_path = own.join("sky-glossy").join(reference);
        let reference = ircache_image::read_image(&reference_path)
            .with_context(|| format!("reading {}", reference_path.display()))?;
        let defines = vec![
            ("max_depth".to_string(), "3".to_string()),
            ("sky".to_string(), sky.to_string()),
        ];
        let desc = ircache_scene::load_scene(&scene_path, &defines, &ObjCamera::default())?;
        let scene = Scene::build(&desc)?;
        println!(
            "\n{sky} (relative variance {:.2})",
            scene.lights.environment_relative_variance()
        );
        for choice in ["auto", "off", "glossy", "all"] {
            let params = [("radiance_cache", "on"), ("cached_environment", choice)];
            let p = measure(&run(&scene, &desc, "ic", 16, &params)?, &reference)?;
            show(&format!("ic --cached-environment {choice}"), &p);
        }
        for spp in [16, 64] {
            let p = measure(&run(&scene, &desc, "path", spp, &[])?, &reference)?;
            show(&format!("ircache path, {spp} spp"), &p);
        }
    }
    Ok(())
}
