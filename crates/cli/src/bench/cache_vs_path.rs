//! `ircache bench --only cache`: the cache against the path tracer on each scene, by rendering.
//!
//! For each scene and depth: `ic` at its defaults (16 spp), then `path` at 4, 16, 64, … spp ([`super::next_sample_count`]) until
//! it reaches the cache's error both unblurred and blurred (σ = 2 px, the low-frequency error:
//! blotches, leaks, bias), or runs 30 times as long. Times to equal error are interpolated
//! between the two renders that bracket it (log error against log time); nothing is extrapolated
//! from an error law. Then the cost of depth: `-ab 8` against `-ab 1` with the deeper bounces
//! path-traced (the default) and with one cache per bounce level.

use anyhow::{Context, Result};
use ircache_image::blur::gaussian_blur;
use ircache_image::compare::compare;
use ircache_image::Image;
use ircache_render::integrators::Integrator;
use ircache_render::render::{render, RenderOutput, RenderSettings, Sampling};
use ircache_render::scene::Scene;
use ircache_scene::obj_scene::ObjCamera;
use std::path::Path;

/// One render's figures.
#[derive(Clone, Copy, Debug)]
pub(super) struct Point {
    pub(super) seconds: f64,
    pub(super) error: f64,
    pub(super) blurred: f64,
    pub(super) lum: f64,
}

pub(super) fn measure(out: &RenderOutput, reference: &Image) -> Result<Point> {
    measure_image(&out.image, out.seconds, reference)
}

/// An image made in `seconds`, against `reference`.
pub(super) fn measure_image(image: &Image, seconds: f64, reference: &Image) -> Result<Point> {
    let m = compare(image, reference)?;
    let b = compare(&gaussian_blur(image, 2.0), &gaussian_blur(reference, 2.0))?;
    Ok(Point {
        seconds,
        error: m.rel_mse_trim,
        blurred: b.rel_mse_trim,
        lum: m.lum_ratio,
    })
}

/// Renders `scene` with `integrator` at `spp` (cache parameters `params`), seed 0.
pub(super) fn run(
    scene: &Scene,
    desc: &ircache_scene::SceneDesc,
    integrator: &str,
    spp: u32,
    params: &[(&str, &str)],
) -> Result<RenderOutput> {
    run_seeded(scene, desc, integrator, spp, params, 0)
}

/// [`run`] on seed `seed` (a reference made in the run takes another seed than the series
/// measured against it, or the series' render at its sample count would reproduce it).
pub(super) fn run_seeded(
    scene: &Scene,
    desc: &ircache_scene::SceneDesc,
    integrator: &str,
    spp: u32,
    params: &[(&str, &str)],
    seed: u64,
) -> Result<RenderOutput> {
    let mut d = desc.integrator.clone();
    d.kind = integrator.into();
    let mut integ = Integrator::from_desc(&d).map_err(anyhow::Error::msg)?;
    if let Integrator::Ic(ic) = &mut integ {
        for (k, v) in params {
            ic.params.set(k, v).map_err(anyhow::Error::msg)?;
        }
    }
    let settings = RenderSettings {
        spp,
        sampling: Sampling::default(),
        ..RenderSettings::from_desc(desc, seed, 0).map_err(anyhow::Error::msg)?
    };
    Ok(render(scene, &integ, &settings, &|_| {})?)
}

/// The time at which the path-tracing series reaches `target` (by `key`), interpolated in
/// log–log between the bracketing renders; `None` when no render reached it.
pub(super) fn time_to(series: &[Point], target: f64, key: fn(&Point) -> f64) -> Option<f64> {
    let first = series.first()?;
    if key(first) <= target {
        return Some(first.seconds);
    }
    series.windows(2).find_map(|w| {
        let (a, b) = (&w[0], &w[1]);
        (key(b) <= target).then(|| {
            let (la, lb, lt) = (key(a).ln(), key(b).ln(), target.ln());
            let f = if (la - lb).abs() > 0.0 {
                (la - lt) / (la - lb)
            } else {
                1.0
            };
            (a.seconds.ln() + f * (b.seconds.ln() - a.seconds.ln())).exp()
        })
    })
}

/// The path tracer's error at `seconds`, interpolated in log–log.
pub(super) fn error_at(series: &[Point], seconds: f64, key: fn(&Point) -> f64) -> Option<f64> {
    series.windows(2).find_map(|w| {
        let (a, b) = (&w[0], &w[1]);
        (a.seconds <= seconds && seconds <= b.seconds).then(|| {
            let f = (seconds.ln() - a.seconds.ln()) / (b.seconds.ln() - a.seconds.ln());
            (key(a).ln() + f * (key(b).ln() - key(a).ln())).exp()
        })
    })
}

pub(super) fn fmt_time(t: Option<f64>, cap: f64) -> String {
    t.map_or(format!("> {cap:.0} s"), |t| format!("{t:.1} s"))
}

/// Prints the times `series` needs to reach `best`'s error and its blurred error (interpolated
/// by [`time_to`]), each as a multiple of `best`'s time (below 1: `best` loses).
pub(super) fn print_time_to_error(label: &str, series: &[Point], best: &Point) {
    let last = series.last().map_or(0.0, |p| p.seconds);
    // Past the series' last point, the ratio at its time is a lower bound.
    let ratio = |t: Option<f64>| {
        t.map_or(format!("> {:.2}", last / best.seconds), |t| {
            format!("{:.2}", t / best.seconds)
        })
    };
    let (t, tb) = (
        time_to(series, best.error, |p| p.error),
        time_to(series, best.blurred, |p| p.blurred),
    );
    println!(
        "  {label}: {} ({}× {:.2} s); blurred: {} ({}×)",
        fmt_time(t, last),
        ratio(t),
        best.seconds,
        fmt_time(tb, last),
        ratio(tb)
    );
}

/// Runs the comparison (`only`: the cases whose name, as "sponza-sun d3", begins with it).
pub fn run_all(shared: &Path, only: Option<&str>) -> Result<()> {
    let cases = [
        ("cornell-box", 3, "cornell-box-d3"),
        ("cornell-box", 10, "cornell-box-d10"),
        ("sponza-sun", 3, "sponza-sun-d3"),
        ("sponza-sun", 10, "sponza-sun-d10"),
        ("cornell-glossy", 3, "cornell-glossy-d3"),
        ("cornell-glossy", 5, "cornell-glossy-d5"),
    ];
    println!("\nThe cache against path tracing (ic defaults at 16 spp; path until it reaches the cache's error)");
    println!(
        "  {:<24} {:>7} {:>10} {:>10} {:>7} | {:>10} {:>10} | {:>11} {:>11}",
        "scene",
        "ic s",
        "ic err",
        "ic blur2",
        "ic lum",
        "path err*",
        "path blur*",
        "path→err",
        "path→blur"
    );
    for (name, depth, reference) in cases {
        if !super::selected(only, &format!("{name} d{depth}")) {
            continue;
        }
        let scene_path = shared.join(format!("scenes/{name}/scene.xml"));
        let reference =
            ircache_image::read_image(&shared.join(format!("references/{reference}.exr")))
                .with_context(|| format!("reading the {reference} reference"))?;
        let defines = vec![("max_depth".to_string(), depth.to_string())];
        let desc = ircache_scene::load_scene(&scene_path, &defines, &ObjCamera::default())?;
        let scene = Scene::build(&desc)?;
        let ic = measure(&run(&scene, &desc, "ic", 16, &[])?, &reference)?;
        // Beyond one bounce the defaults read the gather hits' indirect light from photons
        // (`--photons auto`); the same without them, for the record.
        let without = (depth > 3)
            .then(|| {
                measure(
                    &run(&scene, &desc, "ic", 16, &[("photons", "0")])?,
                    &reference,
                )
            })
            .transpose()?;
        let cap = 30.0 * ic.seconds;
        let mut series = Vec::new();
        let mut spp = 4;
        loop {
            let p = measure(&run(&scene, &desc, "path", spp, &[])?, &reference)?;
            series.push(p);
            if (p.error <= ic.error && p.blurred <= ic.blurred) || p.seconds > cap || spp >= 4096 {
                break;
            }
            spp = super::next_sample_count(spp);
        }
        // A cache render's row: its figures, the path tracer's errors at its time, and (for the
        // defaults) the path tracer's times to its errors.
        let row = |label: String, c: &Point, times: bool| {
            let at = |key: fn(&Point) -> f64| {
                error_at(&series, c.seconds, key).map_or("-".to_string(), |e| format!("{e:.3e}"))
            };
            let to = |target: f64, key: fn(&Point) -> f64| {
                if times {
                    fmt_time(time_to(&series, target, key), cap)
                } else {
                    String::new()
                }
            };
            println!(
                "  {:<24} {:>7.2} {:>10.3e} {:>10.3e} {:>7.4} | {:>10} {:>10} | {:>11} {:>11}",
                label,
                c.seconds,
                c.error,
                c.blurred,
                c.lum,
                at(|p| p.error),
                at(|p| p.blurred),
                to(c.error, |p| p.error),
                to(c.blurred, |p| p.blurred),
            );
        };
        row(format!("{name} d{depth}"), &ic, true);
        if let Some(w) = without {
            row("  … --photons 0".into(), &w, false);
        }
    }
    println!("  * the path tracer's error at the cache's time (interpolated between its renders)");
    if only.is_some() {
        return Ok(());
    }

    println!("\nThe cost of depth: -ab 8 against -ab 1 (16 spp)");
    for name in ["cornell-glossy", "sponza-sun"] {
        let scene_path = shared.join(format!("scenes/{name}/scene.xml"));
        let desc = ircache_scene::load_scene(&scene_path, &[], &ObjCamera::default())?;
        let scene = Scene::build(&desc)?;
        // Ward's per-level caches stop at -ab 2: -ab 3 took 157× -ab 1 on cornell-glossy
        // (BENCHMARKS.md, issue 8).
        for (deeper, bounces) in [("traced", &["1", "8"][..]), ("cache", &["1", "2"][..])] {
            let mut line = format!("  {name:<16} deeper bounces {deeper:<7}");
            let mut first = 0.0;
            for b in bounces {
                let out = run(
                    &scene,
                    &desc,
                    "ic",
                    16,
                    &[("bounces", b), ("deeper_bounces", deeper)],
                )?;
                let c = out.cache.as_ref().context("cache report")?;
                if first == 0.0 {
                    first = out.seconds;
                }
                line += &format!(
                    "  -ab {b}: {:.2} s ({:.2}×, {} records)",
                    out.seconds,
                    out.seconds / first,
                    c.stats.records()
                );
            }
            println!("{line}");
        }
    }
    Ok(())
}
