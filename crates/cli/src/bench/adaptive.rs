//! `ircache bench --only adaptive`: adaptive pixel sampling against uniform sampling, by
//! rendering (issue 9).
//!
//! For each scene: uniform series with the default sampler (`multijitter`) and with the sequence
//! adaptive sampling takes prefixes of (`lattice` for `path`, `sobol` for `ic`) at 4, 16, 64, …
//! spp (`ic`: the square grids of [`super::next_square_count`]), and adaptive renders
//! (pilot 8 spp; `ic` 4) at two or three targets (estimated root-mean-square relative error, chosen per
//! scene to span about 16 to 150 samples a pixel); for each adaptive render, the time each uniform series needs
//! to reach its relMSE_trim, interpolated between the two renders that bracket it (log–log).
//! Scenes without a Mitsuba reference are measured on a smaller film against our own path
//! tracer at 512 spp (`multijitter`; its own error lies below a tenth of the compared ones).

use super::cache_vs_path::{fmt_time, measure_image, time_to, Point};
use anyhow::{Context, Result};
use ircache_image::Image;
use ircache_render::integrators::Integrator;
use ircache_render::render::{render, Adaptive, RenderSettings, Sampling};
use ircache_render::sampler::SamplerKind;
use ircache_render::scene::Scene;
use ircache_scene::obj_scene::ObjCamera;
use std::path::Path;

/// Renders `desc` with `integrator` at `spp` with `sampling`, at `scale` of its film's sides.
fn render_with(
    scene: &Scene,
    desc: &ircache_scene::SceneDesc,
    integrator: &str,
    spp: u32,
    sampling: Sampling,
    scale: usize,
    seed: u64,
) -> Result<(Image, f64, f64)> {
    let mut d = desc.integrator.clone();
    d.kind = integrator.into();
    let integ = Integrator::from_desc(&d).map_err(anyhow::Error::msg)?;
    let scene_settings = RenderSettings::from_desc(desc, seed, 0).map_err(anyhow::Error::msg)?;
    let settings = RenderSettings {
        width: scene_settings.width / scale,
        height: scene_settings.height / scale,
        spp,
        sampling,
        ..scene_settings
    };
    let out = render(scene, &integ, &settings, &|_| {})?;
    let pixels = (settings.width * settings.height) as f64;
    Ok((out.image, out.seconds, out.samples as f64 / pixels))
}

/// Scene file, `max_depth`, integrator, Mitsuba reference (none: our own), film scale, targets.
type Case = (
    &'static str,
    u32,
    &'static str,
    Option<&'static str>,
    usize,
    &'static [f32],
);

fn uniform(sampler: SamplerKind) -> Sampling {
    Sampling {
        sampler,
        ..Sampling::default()
    }
}

/// Runs the comparison.
pub fn run_all(shared: &Path, only: Option<&str>) -> Result<()> {
    let cases: [Case; 9] = [
        (
            "cornell-box/scene.xml",
            3,
            "path",
            Some("cornell-box-d3"),
            1,
            &[0.2, 0.1, 0.07],
        ),
        (
            "sponza-sun/scene.xml",
            3,
            "path",
            Some("sponza-sun-d3"),
            1,
            &[0.3, 0.2, 0.1],
        ),
        (
            "cornell-glossy/scene.xml",
            5,
            "path",
            Some("cornell-glossy-d5"),
            1,
            &[0.2, 0.1, 0.07],
        ),
        (
            "cornell-box/scene.xml",
            3,
            "ic",
            Some("cornell-box-d3"),
            1,
            &[0.02, 0.01, 0.007],
        ),
        (
            "sponza-sun/scene.xml",
            3,
            "ic",
            Some("sponza-sun-d3"),
            1,
            &[0.03, 0.02, 0.012],
        ),
        (
            "cornell-glossy/scene.xml",
            5,
            "ic",
            Some("cornell-glossy-d5"),
            1,
            &[0.03, 0.015],
        ),
        (
            "bitterli-veach-mis/scene.xml",
            3,
            "path",
            None,
            4,
            &[0.2, 0.1],
        ),
        (
            "cornell-box-mcguire/CornellBox-Original.obj",
            3,
            "path",
            None,
            2,
            &[0.1, 0.05, 0.03],
        ),
        (
            "sponza-dabrovic/sponza.obj",
            3,
            "path",
            None,
            2,
            &[0.1, 0.05, 0.03],
        ),
    ];
    println!("\nAdaptive pixel sampling against uniform (pilot 8 spp, `ic` 4; time of each uniform series to the adaptive render's relMSE_trim)");
    println!(
        "  {:<34} {:>6} {:>7} {:>10} {:>10} | {:>10} {:>6} | {:>10} {:>6}",
        "scene", "target", "mean spp", "s", "relMSE_t", "mj→err", "ratio", "prog.→err", "ratio"
    );
    for (file, depth, integrator, mitsuba, scale, targets) in cases {
        let name = format!(
            "{} d{depth} {integrator}",
            file.split('/').next().unwrap_or(file)
        );
        if !(only == Some(integrator) || super::selected(only, &name)) {
            continue;
        }
        let path = shared.join("scenes").join(file);
        if !path.exists() {
            println!("  {file}: not found, skipped");
            continue;
        }
        let mut defines = Vec::new();
        if file.starts_with("bitterli") {
            // Its default integrator is Tungsten's path guider.
            defines.push(("integrator".into(), "path".into()));
        }
        let mut desc = ircache_scene::load_scene(&path, &defines, &ObjCamera::default())?;
        // On the description, as `--max-depth` sets it: OBJ models have no $max_depth.
        desc.integrator.max_depth = depth as i32;
        let scene = Scene::build(&desc)?;
        let reference = match mitsuba {
            Some(r) => ircache_image::read_image(&shared.join(format!("references/{r}.exr")))
                .with_context(|| format!("reading the {r} reference"))?,
            None => {
                render_with(
                    &scene,
                    &desc,
                    "path",
                    512,
                    uniform(SamplerKind::MultiJitter),
                    scale,
                    // A seed of its own: the uniform series' 512-spp render would be it.
                    1 << 20,
                )?
                .0
            }
        };
        // The cache's pixel pass is cheap beside its pre-pass and mostly converged where the
        // records serve: a pilot of 4 and a cap of 128 (measured: 8 gave rounds no room).
        let cache = integrator == "ic";
        let (pilot, max_spp) = if cache { (4, 128) } else { (8, 512) };
        // The cache's rounds judge pixels by halves of 2 and 4 samples: Sobol' nets there (a
        // lattice's halves are translates of each other; measured on the Cornell box, `ic` took
        // up to 2× the samples to the same error with `lattice`), lattices for `path`.
        let progressive = if cache {
            SamplerKind::Sobol
        } else {
            SamplerKind::Lattice
        };
        let adaptive: Vec<(f32, Point, f64)> = targets
            .iter()
            .map(|&target| {
                let sampling = Sampling {
                    sampler: progressive,
                    adaptive: Some(Adaptive { target, max_spp }),
                    ..Sampling::default()
                };
                let (image, seconds, spp) =
                    render_with(&scene, &desc, integrator, pilot, sampling, scale, 0)?;
                Ok((target, measure_image(&image, seconds, &reference)?, spp))
            })
            .collect::<Result<_>>()?;
        let lowest = adaptive
            .iter()
            .map(|a| a.1.error)
            .fold(f64::INFINITY, f64::min);
        let longest = adaptive.iter().map(|a| a.1.seconds).fold(0.0, f64::max);
        let cap = 8.0 * longest;
        // Each uniform series by time and, free of timing noise, by samples.
        let series = |kind: SamplerKind| -> Result<(Vec<Point>, Vec<Point>)> {
            let (mut points, mut by_samples) = (Vec::new(), Vec::new());
            let mut spp = 4;
            loop {
                let (image, seconds, mean_spp) =
                    render_with(&scene, &desc, integrator, spp, uniform(kind), scale, 0)?;
                let p = measure_image(&image, seconds, &reference)?;
                points.push(p);
                by_samples.push(Point {
                    seconds: mean_spp,
                    ..p
                });
                if p.error <= lowest || p.seconds > cap || spp >= 4096 {
                    return Ok((points, by_samples));
                }
                spp = if cache {
                    super::next_square_count(spp)
                } else {
                    super::next_sample_count(spp)
                };
            }
        };
        let (mj, mj_spp) = series(SamplerKind::MultiJitter)?;
        let (progressive_series, progressive_spp) = series(progressive)?;
        let label = format!(
            "{name}{}",
            if mitsuba.is_some() { "" } else { " (own ref)" }
        );
        for (target, a, spp) in &adaptive {
            let ratio = |t: Option<f64>| t.map_or("-".into(), |t| format!("{:.2}", t / a.seconds));
            let spp_ratio = |s: &[Point]| {
                time_to(s, a.error, |p| p.error).map_or("-".into(), |n| format!("{:.2}", n / spp))
            };
            let (t_mj, t_progressive) = (
                time_to(&mj, a.error, |p| p.error),
                time_to(&progressive_series, a.error, |p| p.error),
            );
            println!(
                "  {:<34} {:>6} {:>7.1} {:>10.2} {:>10.3e} | {:>10} {:>6} | {:>10} {:>6} | spp ratio {:>5} {:>5}   (lum {:.4}, blurred {:.2e})",
                label,
                target,
                spp,
                a.seconds,
                a.error,
                fmt_time(t_mj, cap),
                ratio(t_mj),
                fmt_time(t_progressive, cap),
                ratio(t_progressive),
                spp_ratio(&mj_spp),
                spp_ratio(&progressive_spp),
                a.lum,
                a.blurred,
            );
        }
        let first = |s: &[Point]| s.first().map_or(0.0, |p| p.seconds);
        println!(
            "  {:<34} uniform series from 4 spp: multijitter {:.2} s, the progressive sampler {:.2} s",
            "",
            first(&mj),
            first(&progressive_series)
        );
    }
    println!(
        "  ratio > 1: adaptive sampling reaches the error in less time than that uniform series"
    );
    Ok(())
}
