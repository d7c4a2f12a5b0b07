//! `ircache bench --only photons`: photon mapping (issue 14) by rendering, in the same run.
//!
//! On ircache's `scenes/cornell-glass` (cornell-glossy with a glass sphere: a caustic; `-ab 3`
//! against a `max_depth` 5 reference) and `scenes/lamp-room` (lamps in shades: most light
//! arrives off a rough-metal bowl and a gold cone; `max_depth` 7), at 256 pixels across: `ic`
//! without photons, at its defaults, with the cached final gather (`--photons`) without and
//! with the caustic map, and with photon-mapped records (`--photon-records on`), all at 16 spp;
//! then `ic` without photons
//! at 64, 256, … spp and Mitsuba 3 `multijitter` at 16, 64, … spp until each reaches the best
//! photon variant's error (unblurred and blurred, σ = 2 px), or 20 times its time. Times to
//! equal error are interpolated between the bracketing renders, never extrapolated. Last, the
//! time per record: photon records against gathered ones (001 §6.3: 3.71 ms against 2.6 ms).

use super::cache_vs_path::{measure, print_time_to_error, run, Point};
use super::peers::multijitter_series;
use super::radiance::own_scenes;
use anyhow::{Context, Result};
use ircache_render::render::RenderOutput;
use ircache_render::scene::Scene;
use ircache_scene::obj_scene::ObjCamera;

fn show(label: &str, p: &Point) {
    println!(
        "  {label:<52} {:>8.2} s  relMSE_trim {:.3e}  blurred {:.3e}  lum {:.4}",
        p.seconds, p.error, p.blurred, p.lum
    );
}

/// One photon-mapping variant: its label and cache parameters.
type Variant = (&'static str, Vec<(&'static str, &'static str)>);

/// What the cache did: photon maps, records from photons, gathered records.
fn cache_line(out: &RenderOutput) -> String {
    let Some(c) = out.cache.as_ref() else {
        return String::new();
    };
    let st = &c.stats;
    let mut line = format!(
        "    records {} ({} gathered in {:.2} s",
        st.records(),
        st.records_computed,
        st.gather_seconds
    );
    if st.records_computed > 0 {
        line += &format!(
            ", {:.2} ms each",
            1e3 * st.gather_seconds / st.records_computed as f64
        );
    }
    line += ")";
    if st.photon_records > 0 {
        line += &format!(
            "; {} from photons in {:.2} s, {:.2} ms each",
            st.photon_records,
            st.photon_record_seconds,
            1e3 * st.photon_record_seconds / st.photon_records as f64
        );
    }
    if let Some(maps) = &c.cache.photons {
        for map in maps.maps() {
            line += &format!("; {map}");
        }
    }
    line
}

/// Runs the comparison.
pub fn run_all(with_mitsuba: bool) -> Result<()> {
    let own = own_scenes();
    let global = ("photons", "200000");
    let no_caustics = ("caustic_photons", "0");
    let cases: [(&str, u32, &str, &str, Vec<Variant>); 2] = [
        (
            "cornell-glass",
            5,
            "256",
            "256",
            vec![
                ("ic, defaults (100000 photons in each map)", vec![]),
                (
                    "ic, final gather (--photons 200000), no caustic map",
                    vec![global, no_caustics],
                ),
                (
                    "ic, final gather and caustic map (200000 each)",
                    vec![global, ("caustic_photons", "200000")],
                ),
                (
                    "ic, photon records and caustic map",
                    vec![
                        global,
                        ("caustic_photons", "200000"),
                        ("photon_records", "on"),
                    ],
                ),
            ],
        ),
        (
            "lamp-room",
            7,
            "256",
            "192",
            vec![
                ("ic, defaults (100000 photons in each map)", vec![]),
                (
                    "ic, final gather (--photons 300000), no caustic map",
                    vec![("photons", "300000"), no_caustics],
                ),
                (
                    "ic, final gather (--photons 300000), caustic map",
                    vec![("photons", "300000")],
                ),
                (
                    "ic, photon records (--photons 300000), caustic map",
                    vec![("photons", "300000"), ("photon_records", "on")],
                ),
            ],
        ),
    ];
    println!("\nPhoton mapping (2 threads, same run; 16 spp unless said)");
    for (name, depth, resx, resy, variants) in &cases {
        let scene_path = own.join(name).join("scene.xml");
        let reference_path = own.join(name).join(format!("reference-d{depth}.exr"));
        let reference = ircache_image::read_image(&reference_path)
            .with_context(|| format!("reading {}", reference_path.display()))?;
        let defines = vec![
            ("max_depth".to_string(), depth.to_string()),
            ("resx".to_string(), resx.to_string()),
            ("resy".to_string(), resy.to_string()),
        ];
        let desc = ircache_scene::load_scene(&scene_path, &defines, &ObjCamera::default())?;
        let scene = Scene::build(&desc)?;
        println!("\n{name} ({resx} × {resy}, max_depth {depth})");
        let no_photons = [("photons", "0"), no_caustics];
        let out = run(&scene, &desc, "ic", 16, &no_photons)?;
        let plain = measure(&out, &reference)?;
        show("ic, no photons", &plain);
        println!("{}", cache_line(&out));
        let mut best: Option<(String, Point)> = None;
        for (label, params) in variants {
            let out = run(&scene, &desc, "ic", 16, params)?;
            let p = measure(&out, &reference)?;
            show(label, &p);
            println!("{}", cache_line(&out));
            if best.as_ref().is_none_or(|(_, b)| p.error < b.error) {
                best = Some((label.to_string(), p));
            }
        }
        for spp in [16, 64] {
            show(
                &format!("ircache path, {spp} spp"),
                &measure(&run(&scene, &desc, "path", spp, &[])?, &reference)?,
            );
        }
        let Some((label, best)) = best else {
            continue;
        };
        let cap = 20.0 * best.seconds;
        println!("  the best photon variant: {label}");
        let mut series = vec![plain];
        let mut spp = 64;
        while !(series
            .last()
            .is_some_and(|p| p.error <= best.error && p.blurred <= best.blurred))
            && series.last().is_some_and(|p| p.seconds < cap)
            && spp <= 1024
        {
            let p = measure(&run(&scene, &desc, "ic", spp, &no_photons)?, &reference)?;
            show(&format!("ic, no photons, {spp} spp"), &p);
            series.push(p);
            spp = super::next_sample_count(spp);
        }
        print_time_to_error("ic without photons to that error", &series, &best);
        if !with_mitsuba {
            continue;
        }
        let mi_defines = [("resx", *resx), ("resy", *resy)];
        match multijitter_series(
            &scene_path,
            *depth,
            &mi_defines,
            &reference,
            best.error,
            Some(best.blurred),
            cap,
            &show,
        ) {
            Ok(mi) => print_time_to_error("Mitsuba multijitter to that error", &mi, &best),
            Err(e) => println!("  Mitsuba 3 not measured: {e:#}"),
        }
    }
    Ok(())
}
