//! `ircache bench --only temporal`: animations (issue 13) with the cache kept over time, by
//! rendering whole sequences, in the same run.
//!
//! For each animation: per-frame references from Mitsuba 3 (`multijitter`, two independent
//! halves of [`Case::reference_spp`] each, the frames' motions applied to the shapes through
//! `mi.traverse`, the matrices computed by ircache's own animation code); `ircache animate` (a
//! process each, wall time) with the temporal cache (interpolated and extrapolated temporal
//! gradients; next frames estimated by reprojection, the default, and by gathering again; with
//! still pixels' sampled light kept over frames, the default, and without; and with
//! `--adaptive` pixel sampling), the age-based cache and a cache per frame; the measures of
//! `ircache_image::flicker`; then Mitsuba `multijitter` per frame at 4, 16, 64, … spp
//! ([`super::next_sample_count`]) until its mean relMSE reaches both temporal caches' (uniform and
//! adaptive), the equal-error times interpolated between the two sequences that bracket them
//! (log error against log time).

use super::mitsuba_render_frames;
use super::radiance::own_scenes;
use crate::compare::read_sequence as read_frames;
use anyhow::{bail, Context, Result};
use ircache_image::flicker::{report, ReferenceSequence, SequenceReport};
use ircache_image::Image;
use ircache_scene::animation::{load_animation, Target};
use std::path::Path;
use std::time::Instant;

/// Samples per pixel of the cache's renders.
const SPP: u32 = 16;
/// `--adaptive` of the adaptive row (pilot 4 spp; `ic`'s target scale, as `bench --only adaptive`).
const ADAPTIVE_TARGET: &str = "0.01";

/// One animation to measure.
struct Case {
    /// Label.
    name: &'static str,
    /// The `<animation>` file under `scenes/`.
    file: &'static str,
    /// Frames (both included).
    frames: (u32, u32),
    /// Image size.
    size: (u32, u32),
    /// Samples per pixel of each half of the references: enough that their noise stays
    /// below the still pixels' error once the frames have kept their samples for a while.
    reference_spp: u32,
    /// Why Mitsuba's equal-error search is not run, if it is not.
    no_search: Option<&'static str>,
}

/// What a sequence measured, and how long it took.
#[derive(Clone, Copy, Debug)]
struct Measured {
    seconds: f64,
    report: SequenceReport,
}

fn measure(frames: &[Image], seconds: f64, r: &ReferenceSequence) -> Result<Measured> {
    Ok(Measured {
        seconds,
        report: report(frames, r)?,
    })
}

fn show(label: &str, m: &Measured, extra: &str) {
    let r = &m.report;
    println!(
        "  {label:<34} {:>8.1} s  FI {:.2e}  FHP {:.2e}  relMSE_trim {:.3e}  near motion {:.3e}  probe step {:.3} err {:.3}  {extra}",
        m.seconds,
        r.flicker_index,
        r.high_pass_error.unwrap_or(f64::NAN),
        r.rel_mse_trim,
        r.rel_mse_trim_near_motion.unwrap_or(f64::NAN),
        r.probe_max_step,
        r.probe_max_error
    );
}

/// Runs the comparison.
pub fn run_all(with_mitsuba: bool, only: Option<&str>) -> Result<()> {
    if !with_mitsuba {
        println!("\nanimations: skipped (they need Mitsuba 3 for the references)");
        return Ok(());
    }
    let own = own_scenes();
    let cases = [
        Case {
            name: "still box",
            file: "cube-in-box/still.xml",
            frames: (0, 29),
            size: (128, 128),
            reference_spp: 2048,
            no_search: None,
        },
        Case {
            name: "cube in a box",
            file: "cube-in-box/animation.xml",
            frames: (0, 47),
            size: (128, 128),
            reference_spp: 2048,
            no_search: None,
        },
        Case {
            name: "moving light",
            file: "cube-in-box/moving-light.xml",
            frames: (0, 47),
            size: (128, 128),
            reference_spp: 2048,
            no_search: None,
        },
        Case {
            name: "lamp room, rolling sphere",
            file: "lamp-room/animation.xml",
            frames: (0, 23),
            size: (128, 96),
            reference_spp: 512,
            no_search: Some(
                "its references (2 × 512 spp) are too noisy: Mitsuba's own relMSE_trim at 32 spp \
                 is 0.32, and the cache's 1.7e-2 is near the references' own noise",
            ),
        },
    ];
    let work = std::env::temp_dir().join("ircache-bench-temporal");
    std::fs::create_dir_all(&work)?;
    let exe = std::env::current_exe()?;
    println!(
        "\nanimations ({SPP} spp; references Mitsuba multijitter, two halves per frame; \
         FI flicker index, FHP high-pass temporal error (emitters in view left out), relMSE_trim per frame, near motion: pixels \
         within 1/32 width of a >10 % change; probe: the largest step and error of 16 probes on a 4×4 grid, those no moving silhouette crosses)"
    );
    for case in cases {
        if only.is_some_and(|o| !case.name.contains(o)) {
            continue;
        }
        let file = own.join(case.file);
        let (desc, animation) = load_animation(&file, &[])?;
        let dir = work.join(case.name.replace([' ', ','], "-"));
        std::fs::create_dir_all(&dir)?;
        let (w, h) = case.size;
        println!(
            "\n{} ({}, frames {}..{}, {w}×{h}, max_depth {})",
            case.name, case.file, case.frames.0, case.frames.1, desc.integrator.max_depth
        );
        if animation.tracks.iter().any(|t| t.target == Target::Camera) {
            bail!(
                "{}: the Mitsuba frames move shapes only, not the camera",
                file.display()
            );
        }
        // The frames' motions, from ircache's own animation code.
        let motions: Vec<Vec<(String, [f32; 16])>> = (case.frames.0..=case.frames.1)
            .map(|f| {
                animation
                    .tracks
                    .iter()
                    .filter_map(|t| match t.target {
                        Target::Shape(i) => Some((
                            desc.shapes[i].id.clone().unwrap_or_default(),
                            t.motion(f as f32).transpose().to_cols_array(),
                        )),
                        Target::Camera => None,
                    })
                    .collect()
            })
            .collect();
        let scene_file = desc.source.clone();
        let mitsuba = |spp: u32, seed: u32, pattern: &Path| -> Result<f64> {
            mitsuba_render_frames(
                &scene_file,
                case.size,
                case.frames,
                &motions,
                spp,
                seed,
                pattern,
            )
        };
        // References: reused when a run with the same settings made them.
        let spp = case.reference_spp;
        let (ra, rb) = (
            dir.join(format!("ref-a-{spp}-###.exr")),
            dir.join(format!("ref-b-{spp}-###.exr")),
        );
        let last = crate::animate::frame_path(&rb, case.frames.1)?;
        if !last.exists() {
            let t = Instant::now();
            mitsuba(spp, 1, &ra)?;
            mitsuba(spp, 2, &rb)?;
            println!(
                "  references (2 × {spp} spp) made in {:.0} s",
                t.elapsed().as_secs_f64()
            );
        }
        let reference = ReferenceSequence::new(
            read_frames(&ra, case.frames)?,
            read_frames(&rb, case.frames)?,
        )?;
        let frames_arg = format!("{}..{}", case.frames.0, case.frames.1);
        let mut temporal = None;
        let mut adaptive = None;
        // (label, mode, temporal gradients, next frame, pixel sampling: spp and more arguments)
        let adaptive_args = ["--adaptive", ADAPTIVE_TARGET, "--max-spp", "128"];
        let per_frame_pixels = ["--accumulate", "off"];
        for (label, mode, gradients, next_frame, (spp, more)) in [
            (
                "temporal, interpolated",
                "temporal",
                "interpolated",
                "reproject",
                (SPP, &[][..]),
            ),
            (
                "  … --accumulate off (every frame's pixels on their own)",
                "temporal",
                "interpolated",
                "reproject",
                (SPP, &per_frame_pixels[..]),
            ),
            (
                "  … next frames gathered again",
                "temporal",
                "interpolated",
                "regather",
                (SPP, &[][..]),
            ),
            (
                "  … --adaptive (pilot 4, at most 128)",
                "temporal",
                "interpolated",
                "reproject",
                (4, &adaptive_args[..]),
            ),
            (
                "temporal, extrapolated",
                "temporal",
                "extrapolated",
                "reproject",
                (SPP, &[][..]),
            ),
            ("age-based", "age", "off", "regather", (SPP, &[][..])),
            (
                "cache per frame",
                "per-frame",
                "off",
                "regather",
                (SPP, &[][..]),
            ),
        ] {
            let tag = match more.first() {
                None => "",
                Some(&"--accumulate") => "-own-pixels",
                Some(_) => "-adaptive",
            };
            let pattern = dir.join(format!("{mode}-{gradients}-{next_frame}{tag}-###.exr"));
            let stats = dir.join(format!("{mode}-{gradients}-{next_frame}{tag}.json"));
            let t = Instant::now();
            let out = std::process::Command::new(&exe)
                .args([
                    "animate",
                    &file.display().to_string(),
                    "--frames",
                    &frames_arg,
                ])
                .args(["--width", &w.to_string(), "--height", &h.to_string()])
                .args(["--spp", &spp.to_string(), "--integrator", "ic", "-q"])
                .args(["--cache-mode", mode, "--temporal-gradients", gradients])
                .args(["--next-frame", next_frame])
                .args(more)
                .arg("-o")
                .arg(&pattern)
                .arg("--stats")
                .arg(&stats)
                .output()?;
            let seconds = t.elapsed().as_secs_f64();
            if !out.status.success() {
                bail!("ircache animate: {}", String::from_utf8_lossy(&out.stderr));
            }
            let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats)?)?;
            let m = measure(&read_frames(&pattern, case.frames)?, seconds, &reference)?;
            show(
                label,
                &m,
                &format!(
                    "records {} (+{} estimates, {:.1} M rays), cache {:.1} s",
                    s["records_gathered"],
                    s["estimates"],
                    s["estimate_rays"].as_f64().unwrap_or(0.0) / 1e6,
                    s["cache_seconds"].as_f64().unwrap_or(0.0)
                ),
            );
            if tag == "-adaptive" {
                adaptive = Some(m);
            } else if mode == "temporal" && temporal.is_none() && tag.is_empty() {
                temporal = Some(m);
            }
        }
        let temporal = temporal.context("the temporal run")?;
        if let Some(why) = case.no_search {
            println!("  Mitsuba's equal-error search not run: {why}");
            continue;
        }
        // Mitsuba at more samples until it reaches both temporal caches' relMSE.
        let compared: Vec<(&str, Measured)> = [
            ("temporal cache", Some(temporal)),
            ("adaptive one", adaptive),
        ]
        .into_iter()
        .filter_map(|(name, m)| m.map(|m| (name, m)))
        .collect();
        let target = compared
            .iter()
            .map(|(_, m)| m.report.rel_mse_trim)
            .fold(f64::INFINITY, f64::min);
        let mut series: Vec<Measured> = Vec::new();
        let mut spp = 4;
        loop {
            let pattern = dir.join(format!("mitsuba-{spp}-###.exr"));
            let seconds = mitsuba(spp, 3, &pattern)?;
            let m = measure(&read_frames(&pattern, case.frames)?, seconds, &reference)?;
            show(&format!("Mitsuba multijitter, {spp} spp"), &m, "");
            series.push(m);
            if m.report.rel_mse_trim <= target || seconds > 30.0 * temporal.seconds || spp >= 4096 {
                break;
            }
            spp = super::next_sample_count(spp);
        }
        for (name, m) in compared {
            match equal_error_seconds(&series, m.report.rel_mse_trim) {
                Some(t) => println!(
                    "  Mitsuba multijitter at the {name}'s relMSE: {t:.1} s, {:.2}× the {name}'s {:.1} s",
                    t / m.seconds,
                    m.seconds
                ),
                None => println!("  Mitsuba multijitter did not reach the {name}'s relMSE within the cap"),
            }
        }
    }
    Ok(())
}

/// The time at which the series reaches `error`, interpolated between the two sequences that
/// bracket it in log error against log time; `None` when none reaches it.
fn equal_error_seconds(series: &[Measured], error: f64) -> Option<f64> {
    let hit = series.iter().position(|m| m.report.rel_mse_trim <= error)?;
    if hit == 0 {
        return Some(series[0].seconds);
    }
    let (p, q) = (&series[hit - 1], &series[hit]);
    let (pe, qe) = (p.report.rel_mse_trim, q.report.rel_mse_trim);
    let s = (error.ln() - pe.ln()) / (qe.ln() - pe.ln());
    Some((p.seconds.ln() + s * (q.seconds.ln() - p.seconds.ln())).exp())
}
