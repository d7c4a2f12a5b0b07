//! `ircache bench --only media`: participating media (issue 15) by rendering, in the same run.
//!
//! On `scenes/cornell-fog` at 128 pixels across (`--case N`: N): (1) the irradiance cache in the fog (one
//! bounce, `max_depth` 3) at 16 spp — camera rays tracked (stage 1), marched without
//! volumetric records, 512 gather rays a record, the consistent media gradient, the defaults —
//! against `volpath` at 16, 64, 256, … spp until it reaches the defaults' error (unblurred and
//! blurred, σ = 2 px); the reference is `volpath` at 4096 spp made here on a seed of its own;
//! the records' pre-pass times and rays are printed, so the gradient's overhead over the
//! media-blind default reads off the table. (2) The cache at its defaults on `cornell-fog`,
//! `smoke-box`, `glass-in-fog` (glass and gold spheres in the fog) and `spot-fog` (a spot light's
//! beam) at their own `max_depth` 6
//! (the bounces beyond the first traced from the gathers) against `volpath` the same way, each
//! against a reference of its own. (3) `volpath` at `max_depth` 6 (`multijitter`) against Mitsuba
//! 3's `volpath` (`multijitter`) at equal spp, both against a Mitsuba reference of 4096 spp made
//! here (seeds 0–63; the compared Mitsuba images from seed 5000). Times to equal error are
//! interpolated between the bracketing renders, never extrapolated.

use super::cache_vs_path::{measure, measure_image, print_time_to_error, run, run_seeded, Point};
use super::mitsuba_render;
use super::radiance::own_scenes;
use anyhow::{Context, Result};
use ircache_render::scene::Scene;
use ircache_scene::obj_scene::ObjCamera;

fn show(label: &str, p: &Point) {
    println!(
        "  {label:<44} {:>8.2} s  relMSE_trim {:.3e}  blurred {:.3e}  lum {:.4}",
        p.seconds, p.error, p.blurred, p.lum
    );
}

/// Runs the comparison.
pub fn run_all(with_mitsuba: bool, case: Option<&str>) -> Result<()> {
    let scene_path = own_scenes().join("cornell-fog").join("scene.xml");
    let size = case.unwrap_or("128");
    if !size.parse::<u32>().is_ok_and(|s| (8..=4096).contains(&s)) {
        anyhow::bail!(
            "bench --only media --case {size}: expected the image's side, 8 to 4096 pixels"
        );
    }
    let load = |depth: u32| -> Result<(ircache_scene::SceneDesc, Scene)> {
        let defines = vec![
            ("max_depth".to_string(), depth.to_string()),
            ("resx".to_string(), size.to_string()),
            ("resy".to_string(), size.to_string()),
        ];
        let desc = ircache_scene::load_scene(&scene_path, &defines, &ObjCamera::default())?;
        let scene = Scene::build(&desc)?;
        Ok((desc, scene))
    };
    println!("\nParticipating media (2 threads, same run; cornell-fog at {size} × {size})");
    let (desc, scene) = load(3)?;
    // Another seed than the volpath series below, which would otherwise meet it at 4096 spp.
    let reference = run_seeded(&scene, &desc, "volpath", 4096, &[], 1 << 20)?.image;
    println!(
        "\nThe cache in the fog, one bounce (max_depth 3), 16 spp; reference: volpath at 4096 spp"
    );
    let variants: [(&str, Vec<(&str, &str)>); 5] = [
        ("stage 1: camera rays tracked", vec![("media_march", "0")]),
        (
            "marched, no volumetric records",
            vec![("media_volume_records", "off")],
        ),
        ("--media-divisions 512", vec![("media_divisions", "512")]),
        (
            "--media-gradient corrected",
            vec![("media_gradient", "corrected")],
        ),
        ("defaults (marched, volumetric records)", vec![]),
    ];
    let mut forms = Vec::new();
    for (label, params) in &variants {
        let out = run(&scene, &desc, "ic", 16, params)?;
        let p = measure(&out, &reference)?;
        show(label, &p);
        if let Some(st) = &out.media_cache {
            println!(
                "    {} surface records, pre-pass {:.2} s, {:.1} M gather rays, {:.1} M shadow rays, {:.1} M march steps",
                st.records,
                st.seconds,
                st.gather_rays as f64 * 1e-6,
                st.shadow_rays as f64 * 1e-6,
                st.march_steps as f64 * 1e-6
            );
        }
        if let Some(st) = &out.volume_records {
            println!(
                "    {} volumetric records, pre-pass {:.2} s, {:.1} M rays",
                st.records,
                st.seconds,
                st.rays as f64 * 1e-6
            );
        }
        forms.push(p);
    }
    let best = forms.last().copied().context("no cache render")?; // the defaults
    race(&scene, &desc, &reference, &best)?;
    println!(
        "\nThe cache at the scenes' own depth (max_depth 6), defaults, 16 spp; reference: volpath at 4096 spp"
    );
    for name in ["cornell-fog", "smoke-box", "glass-in-fog", "spot-fog"] {
        let path = own_scenes().join(name).join("scene.xml");
        let defines = vec![
            ("resx".to_string(), size.to_string()),
            ("resy".to_string(), size.to_string()),
        ];
        let desc = ircache_scene::load_scene(&path, &defines, &ObjCamera::default())?;
        let scene = Scene::build(&desc)?;
        let reference = run_seeded(&scene, &desc, "volpath", 4096, &[], 1 << 20)?.image;
        let out = run(&scene, &desc, "ic", 16, &[])?;
        let best = measure(&out, &reference)?;
        show(&format!("{name}: ic"), &best);
        let (surface, volume) = (
            out.media_cache.as_ref().map_or(0.0, |st| st.seconds),
            out.volume_records.map_or(0.0, |st| st.seconds),
        );
        let photons = out
            .media_cache
            .and_then(|st| st.global_map)
            .map_or(String::new(), |m| {
                format!(", global map {:.2} s", m.seconds)
            });
        println!(
            "    pre-passes: surface records {surface:.2} s, volumetric records {volume:.2} s{photons}"
        );
        race(&scene, &desc, &reference, &best)?;
    }
    if !with_mitsuba {
        return Ok(());
    }
    println!("\nvolpath against Mitsuba 3 volpath (max_depth 6, multijitter, equal spp; reference: Mitsuba 4096 spp)");
    let (desc, scene) = load(6)?;
    let defines = [("resx", size), ("resy", size)];
    let tmp = std::env::temp_dir().join(format!("ircache-media-{}.exr", std::process::id()));
    mitsuba_render(
        &scene_path,
        4096,
        Some(&tmp),
        6,
        Some("multijitter"),
        &defines,
    )
    .context("Mitsuba 3 reference")?;
    let reference = ircache_image::read_image(&tmp)?;
    for spp in [64, 256] {
        let mut d = defines.to_vec();
        d.push(("seed0", "5000"));
        let seconds = mitsuba_render(&scene_path, spp, Some(&tmp), 6, Some("multijitter"), &d)?;
        let mi = measure_image(&ircache_image::read_image(&tmp)?, seconds, &reference)?;
        show(&format!("Mitsuba volpath, {spp} spp"), &mi);
        let ours = measure(&run(&scene, &desc, "volpath", spp, &[])?, &reference)?;
        show(&format!("ircache volpath, {spp} spp"), &ours);
    }
    let _ = std::fs::remove_file(&tmp);
    Ok(())
}

/// `volpath` at 16, 64, 256, … spp until it reaches `best`'s error and blurred error (or 4096
/// spp), then the times it needs for each, interpolated between the renders that bracket them.
fn race(
    scene: &Scene,
    desc: &ircache_scene::SceneDesc,
    reference: &ircache_image::Image,
    best: &Point,
) -> Result<()> {
    let mut series = Vec::new();
    let mut spp = 16;
    while spp <= 4096 {
        let p = measure(&run(scene, desc, "volpath", spp, &[])?, reference)?;
        show(&format!("volpath, {spp} spp"), &p);
        series.push(p);
        if p.error <= best.error && p.blurred <= best.blurred {
            break;
        }
        spp = super::next_sample_count(spp);
    }
    print_time_to_error("volpath to the cache's error", &series, best);
    Ok(())
}
