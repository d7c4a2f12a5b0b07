//! `ircache animate`: a frame sequence of an animated scene (`ircache_scene::animation`), its
//! cache kept over time (`ircache_render::temporal`) or, for the `path` and `direct`
//! integrators, each frame rendered on its own.

use crate::render::{
    apply_overrides, check_writable, integrator, parse_defines, settings, RenderArgs,
};
use anyhow::{bail, Context, Result};
use clap::Args;
use ircache_image::Image;
use ircache_render::integrators::Integrator;
use ircache_render::irradiance_cache::params::on_off;
use ircache_render::render::{render, render_runs};
use ircache_render::scene::Scene;
use ircache_render::temporal::pixel_reuse::{still_pixels, Change, StillRuns};
use ircache_render::temporal::record::SlopeKind;
use ircache_render::temporal::{CacheMode, FrameStats, NextFrame, SequenceCache, TemporalParams};
use ircache_scene::animation::{is_animation, load_animation, Animation};
use ircache_scene::SceneDesc;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `ircache animate`.
#[derive(Args, Debug, Clone)]
pub struct AnimateArgs {
    /// Frames to render, `A..B` with both ends included (default: all the animation's frames).
    #[arg(long, value_parser = parse_frames, value_name = "A..B")]
    pub frames: Option<(u32, u32)>,
    /// How the cache is kept over time: `temporal` (temporal radiance caching, 001 ch. 5:
    /// lifespans from each record's change, temporal gradients, renewal at the same place),
    /// `age` (000 §3.7.3: the oldest 1/--max-lifespan of the records gathered again each frame,
    /// those that may see moving things first) or `per-frame` (a new cache each frame).
    #[arg(long, default_value = "temporal", value_parser = CacheMode::parse)]
    pub cache_mode: CacheMode,
    /// Temporal accuracy a_t (001 eq. 5.6): the relative change of irradiance a record may
    /// take over its life.
    #[arg(long, default_value_t = 0.05)]
    pub temporal_accuracy: f32,
    /// Longest life of a record in frames (δt_max, 001 eq. 5.8).
    #[arg(long, default_value_t = 10)]
    pub max_lifespan: u32,
    /// Temporal gradients: `interpolated` (towards the record's successor, 5.15–5.17: the
    /// sequence is filled before the first frame is written), `extrapolated` (from the next
    /// frame's estimate, 5.12–5.14) or `off`.
    #[arg(long, default_value = "interpolated", value_parser = parse_gradients)]
    pub temporal_gradients: SlopeKind,
    /// How `temporal` estimates a new record's next frame for its lifespan: `reproject` (001
    /// §5.2.4: the record's gather rays carried to the next frame and their hits shaded again,
    /// no hemisphere rays) or `regather` (the hemisphere gathered again in the next frame with
    /// the same random numbers: no holes, about twice the rays; BENCHMARKS.md).
    #[arg(long, default_value = NextFrame::default().name(), value_parser = NextFrame::parse)]
    pub next_frame: NextFrame,
    /// `on`: where nothing that moved between two frames can reach a pixel's sampled light
    /// (emission, direct light: a still camera and lights, Lambertian surfaces out of the moving
    /// shapes' views and shadows), the frames are one still run for the pixel: each draws new
    /// samples, and each is written with its own cached light plus the mean sampled light of
    /// the whole run (frames are written as they render with the run so far, then again at the
    /// end; with --adaptive each frame weighs by its samples); `off`: every frame's pixels on
    /// their own. Not with the splat integrator.
    #[arg(long, default_value = "on", value_parser = on_off, action = clap::ArgAction::Set)]
    pub accumulate: bool,
    /// Everything `ircache render` takes; SCENE is an `<animation>` file or a still scene
    /// (which then needs --frames; none: the built-in Cornell box), and -o a file name whose
    /// run of `#` is the frame number (default: the scene's name, `-####.exr`).
    #[command(flatten)]
    pub render: RenderArgs,
}

/// Parses `A..B` (both included).
pub fn parse_frames(s: &str) -> Result<(u32, u32), String> {
    let err = || format!("expected A..B with 0 ≤ A ≤ B (both included), found \"{s}\"");
    let (a, b) = s.split_once("..").ok_or_else(err)?;
    let (a, b) = (
        a.trim().parse::<u32>().map_err(|_| err())?,
        b.trim().parse::<u32>().map_err(|_| err())?,
    );
    if a > b {
        return Err(err());
    }
    Ok((a, b))
}

fn parse_gradients(s: &str) -> Result<SlopeKind, String> {
    match s {
        "interpolated" => Ok(SlopeKind::Interpolated),
        "extrapolated" => Ok(SlopeKind::Extrapolated),
        "off" => Ok(SlopeKind::Constant),
        _ => Err(format!(
            "unknown temporal gradients \"{s}\" (expected interpolated, extrapolated or off)"
        )),
    }
}

/// `pattern` with its last run of `#` replaced by `frame`, zero-padded to the run's length.
pub fn frame_path(pattern: &Path, frame: u32) -> Result<PathBuf> {
    let s = pattern.to_string_lossy();
    let Some(end) = s.rfind('#') else {
        bail!(
            "{}: the output name needs a run of # for the frame number (e.g. frame-####.exr)",
            pattern.display()
        );
    };
    let start = s[..end].rfind(|c| c != '#').map_or(0, |i| i + 1);
    let width = end + 1 - start;
    Ok(PathBuf::from(format!(
        "{}{:0width$}{}",
        &s[..start],
        frame,
        &s[end + 1..]
    )))
}

/// Bytes of frames' parts `--accumulate` holds in memory; more go to a temporary folder.
const PARTS_IN_MEMORY: usize = 512 << 20;

/// Each frame's image and cached light until its pixels' still runs are whole: in memory
/// while they take under [`PARTS_IN_MEMORY`], else in a temporary folder, removed however the
/// command ends.
enum FrameParts {
    /// Nothing kept (no `--accumulate`).
    None,
    /// By frame.
    Memory(std::collections::HashMap<u32, (Image, Image)>),
    /// Two OpenEXR files a frame.
    Folder(PathBuf),
}

impl FrameParts {
    /// Where the parts of frames of `pixels` pixels in all will go: memory up to `budget`
    /// bytes.
    fn new(accumulate: bool, pixels: usize, budget: usize) -> Result<FrameParts> {
        if !accumulate {
            return Ok(FrameParts::None);
        }
        if pixels.saturating_mul(2 * std::mem::size_of::<ircache_math::Rgb>()) <= budget {
            return Ok(FrameParts::Memory(std::collections::HashMap::new()));
        }
        let folder = std::env::temp_dir().join(format!(
            "ircache-animate-{}-{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos())
        ));
        std::fs::create_dir_all(&folder).with_context(|| {
            format!(
                "{}: cannot make a folder for the frames' parts",
                folder.display()
            )
        })?;
        Ok(FrameParts::Folder(folder))
    }

    fn path(folder: &Path, frame: u32, part: &str) -> PathBuf {
        folder.join(format!("{part}-{frame}.exr"))
    }

    /// Keeps frame `frame`'s image and cached part.
    fn put(&mut self, frame: u32, image: Image, cached: Image) -> Result<()> {
        match self {
            FrameParts::None => {}
            FrameParts::Memory(m) => {
                m.insert(frame, (image, cached));
            }
            FrameParts::Folder(f) => {
                ircache_image::write_image(&Self::path(f, frame, "image"), &image, 0.0)?;
                ircache_image::write_image(&Self::path(f, frame, "cached"), &cached, 0.0)?;
            }
        }
        Ok(())
    }

    /// Frame `frame`'s image and cached part, given up.
    fn take(&mut self, frame: u32) -> Result<(Image, Image)> {
        match self {
            FrameParts::None => bail!("frame {frame}'s parts were not kept"),
            FrameParts::Memory(m) => m
                .remove(&frame)
                .with_context(|| format!("frame {frame}'s parts were not kept")),
            FrameParts::Folder(f) => Ok((
                ircache_image::read_image(&Self::path(f, frame, "image"))?,
                ircache_image::read_image(&Self::path(f, frame, "cached"))?,
            )),
        }
    }
}

impl Drop for FrameParts {
    fn drop(&mut self) {
        if let FrameParts::Folder(f) = self {
            // A temporary folder: nothing to report if it is gone already.
            let _ = std::fs::remove_dir_all(f);
        }
    }
}

/// Loads the animation (or a still scene as one that does not move) with the overrides.
fn load(args: &RenderArgs) -> Result<(SceneDesc, Animation)> {
    let defines = parse_defines(&args.define)?;
    let Some(path) = &args.scene else {
        // The built-in Cornell box, still.
        return Ok((crate::render::load(args)?, Animation::default()));
    };
    if !is_animation(path)? {
        return Ok((crate::render::load(args)?, Animation::default()));
    }
    let (desc, animation) = load_animation(path, &defines)?;
    Ok((apply_overrides(args, desc)?, animation))
}

/// Runs `ircache animate`.
pub fn run(args: &AnimateArgs) -> Result<()> {
    let r = &args.render;
    if r.tile.is_some() || r.gpu || !r.aov.is_empty() {
        bail!("ircache animate does not take --tile, --gpu or --aov");
    }
    let t0 = Instant::now();
    let (base, animation) = load(r)?;
    let (first, last) = match (args.frames, animation.frames) {
        (Some(f), _) => f,
        (None, n) if n > 0 => (0, n - 1),
        (None, _) => bail!("a still scene needs --frames A..B"),
    };
    // By default the scene's name (as `render` names its image) and the frame number.
    let pattern = r.output.clone().unwrap_or_else(|| {
        let name = crate::render::default_output(r);
        let stem = name.file_stem().unwrap_or_default().to_string_lossy();
        PathBuf::from(format!("{stem}-####.exr"))
    });
    check_writable(&frame_path(&pattern, first)?)?;
    let integrator = integrator(r, &base)?;
    let settings = settings(r, &base)?;
    for note in &base.notes {
        eprintln!("note: {note}");
    }
    let scene_at = |frame: u32| -> Result<Scene> {
        Scene::build(&animation.scene_at(&base, frame as f32))
            .with_context(|| format!("building the scene of frame {frame}"))
    };
    let write = |frame: u32, image: &ircache_image::Image| -> Result<PathBuf> {
        let path = frame_path(&pattern, frame)?;
        ircache_image::write_image(&path, image, r.exposure)?;
        Ok(path)
    };
    let say = |line: String| {
        if !r.quiet {
            eprintln!("{line}");
        }
    };

    let Integrator::Ic(ic) = &integrator else {
        // No cache: every frame on its own.
        for frame in first..=last {
            let scene = scene_at(frame)?;
            let out = render(&scene, &integrator, &settings, &|_| {})?;
            let path = write(frame, &out.image)?;
            say(format!(
                "frame {frame}: {:.2} s -> {}",
                out.seconds,
                path.display()
            ));
        }
        return Ok(());
    };
    let params = TemporalParams {
        mode: args.cache_mode,
        accuracy: args.temporal_accuracy,
        max_lifespan: args.max_lifespan,
        gradients: args.temporal_gradients,
        next_frame: args.next_frame,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()?;
    let mut cache =
        SequenceCache::new(ic, params, (settings.width, settings.height), settings.seed)?;
    let accumulate =
        args.accumulate && ic.pixel_pass != ircache_render::integrators::ic::PixelPass::Splat;
    if args.accumulate && !accumulate {
        eprintln!("note: --accumulate is off with the splat integrator");
    }
    let mut runs = StillRuns::new(settings.width * settings.height);
    // The frame the runs end at so far.
    let mut last_rendered: Option<u32> = None;
    let mut parts = FrameParts::new(
        accumulate,
        settings.width * settings.height * (last - first + 1) as usize,
        PARTS_IN_MEMORY,
    )?;
    let mut fills: Vec<FrameStats> = Vec::new();
    // Each frame's pixel pass: seconds, pixel samples taken and pixels still since the frame
    // before (`--accumulate`).
    let mut pixel_passes: Vec<(f64, u64, usize)> = Vec::new();
    let mut render_frame = |cache: &SequenceCache, frame: u32, scene: &Scene| -> Result<()> {
        let mut ic = ic.clone();
        ic.seed = settings.seed;
        ic.cache = Some(std::sync::Arc::new(
            cache.cache_at(frame, scene, &animation, &pool)?,
        ));
        let integrator = Integrator::Ic(ic);
        if !accumulate {
            let out = render(scene, &integrator, &settings, &|_| {})?;
            let path = write(frame, &out.image)?;
            pixel_passes.push((out.seconds, out.samples, 0));
            say(format!(
                "frame {frame}: pixels {:.2} s -> {}",
                out.seconds,
                path.display()
            ));
            return Ok(());
        }
        let t = Instant::now();
        let still = match last_rendered {
            Some(f) if f + 1 == frame => {
                let change = Change::between(&animation, &base, f as f32, frame as f32);
                still_pixels(
                    scene,
                    &change,
                    (settings.width, settings.height),
                    settings.filter.radius(),
                )
            }
            _ => vec![false; settings.width * settings.height],
        };
        let drawn = runs.drawn(&still);
        let out = render_runs(scene, &integrator, &settings, &|_| {}, Some(&drawn))?;
        let cached = out.cached.context("the frame's cached light")?;
        let samples = out
            .samples_per_pixel
            .as_ref()
            .context("the frame's samples per pixel")?;
        let parts_of_frame = (&out.image, &cached);
        runs.add(frame, &still, parts_of_frame, samples);
        last_rendered = Some(frame);
        let path = write(frame, &runs.so_far(parts_of_frame))?;
        parts.put(frame, out.image, cached)?;
        let seconds = t.elapsed().as_secs_f64();
        let kept = still.iter().filter(|&&s| s).count();
        pixel_passes.push((seconds, out.samples, kept));
        say(format!(
            "frame {frame}: pixels {seconds:.2} s, {:.1} % kept -> {}",
            100.0 * kept as f64 / still.len().max(1) as f64,
            path.display()
        ));
        Ok(())
    };
    let mut next = Some(scene_at(first)?);
    for frame in first..=last {
        let scene = next.take().context("the frame's scene")?;
        next = if frame < last {
            Some(scene_at(frame + 1)?)
        } else {
            None
        };
        let st = cache.fill_frame(frame, &scene, next.as_ref(), &animation, &pool)?;
        say(format!(
            "frame {frame}: {} records ({} carried, {} renewed, {} new, {} dropped), {} estimates, cache {:.2} s",
            st.live, st.carried, st.renewed, st.new, st.dropped, st.estimates, st.seconds
        ));
        fills.push(st);
        if !params.two_passes() {
            render_frame(&cache, frame, &scene)?;
        }
    }
    if params.two_passes() {
        for frame in first..=last {
            render_frame(&cache, frame, &scene_at(frame)?)?;
        }
    }
    if accumulate && runs.any_kept() {
        // Each frame again with its pixels' whole still runs.
        for frame in first..=last {
            let (image, cached) = parts.take(frame)?;
            write(frame, &runs.whole(frame, (&image, &cached)))?;
        }
        say(format!(
            "frames {first}..{last} written again with their pixels' whole still runs"
        ));
    }
    let wall = t0.elapsed().as_secs_f64();
    let gathers: usize = fills.iter().map(FrameStats::gathers).sum();
    let records: usize = fills.iter().map(|f| f.renewed + f.new).sum();
    say(format!(
        "{} frames ({} cache): {records} records gathered, {} estimates, {:.1} M gather rays; \
         cache {:.2} s, pixels {:.2} s, wall {wall:.2} s",
        last - first + 1,
        params.mode.name(),
        gathers - records,
        fills.iter().map(|f| f.gather_rays).sum::<u64>() as f64 * 1e-6,
        fills.iter().map(|f| f.seconds).sum::<f64>(),
        pixel_passes.iter().map(|p| p.0).sum::<f64>(),
    ));
    if let Some(path) = &r.stats {
        write_stats(path, args, &fills, &pixel_passes, wall)?;
    }
    Ok(())
}

fn write_stats(
    path: &Path,
    args: &AnimateArgs,
    fills: &[FrameStats],
    pixel_passes: &[(f64, u64, usize)],
    wall: f64,
) -> Result<()> {
    let frames: Vec<serde_json::Value> = fills
        .iter()
        .zip(pixel_passes)
        .map(|(f, &(px, samples, still))| {
            serde_json::json!({
                "frame": f.frame, "live": f.live, "carried": f.carried, "renewed": f.renewed,
                "new": f.new, "dropped": f.dropped, "estimates": f.estimates,
                "estimate_rays": f.estimate_rays,
                "gather_rays": f.gather_rays, "cache_seconds": f.seconds, "pixel_seconds": px,
                "pixel_samples": samples, "still_pixels": still,
            })
        })
        .collect();
    let json = serde_json::json!({
        "cache_mode": args.cache_mode.name(),
        "temporal_accuracy": args.temporal_accuracy,
        "max_lifespan": args.max_lifespan,
        "records_gathered": fills.iter().map(|f| f.renewed + f.new).sum::<usize>(),
        "estimates": fills.iter().map(|f| f.estimates).sum::<usize>(),
        "next_frame": args.next_frame.name(),
        "accumulate": args.accumulate,
        "estimate_rays": fills.iter().map(|f| f.estimate_rays).sum::<u64>(),
        "gather_rays": fills.iter().map(|f| f.gather_rays).sum::<u64>(),
        "cache_seconds": fills.iter().map(|f| f.seconds).sum::<f64>(),
        "pixel_seconds": pixel_passes.iter().map(|p| p.0).sum::<f64>(),
        "wall_seconds": wall,
        "frames": frames,
    });
    std::fs::write(path, serde_json::to_string_pretty(&json)? + "\n")
        .with_context(|| format!("{}: cannot write statistics", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_paths() {
        let p = |s: &str, f| frame_path(Path::new(s), f).map(|p| p.display().to_string());
        assert_eq!(p("out/frame-####.exr", 7).unwrap(), "out/frame-0007.exr");
        assert_eq!(p("a#b-##.png", 123).unwrap(), "a#b-123.png");
        assert_eq!(p("x-#.exr", 42).unwrap(), "x-42.exr");
        assert!(p("frame.exr", 1).is_err());
    }

    /// The parts come back as they were put, from memory or from the temporary folder, which
    /// goes with them.
    #[test]
    fn frame_parts_round_trip() {
        let mut a = Image::new(3, 2);
        a.set(2, 1, ircache_math::Rgb::new(0.25, 1.5e-7, 3e4));
        let mut b = Image::new(3, 2);
        b.set(0, 0, ircache_math::Rgb::splat(0.1));
        for budget in [PARTS_IN_MEMORY, 0] {
            let mut parts = FrameParts::new(true, 12, budget).unwrap();
            parts.put(4, a.clone(), b.clone()).unwrap();
            let (c, s) = parts.take(4).unwrap();
            assert!(
                c.pixels == a.pixels && s.pixels == b.pixels,
                "budget {budget}"
            );
            if let FrameParts::Folder(f) = &parts {
                let f = f.clone();
                assert!(f.is_dir());
                drop(parts);
                assert!(!f.exists());
            }
        }
        assert!(FrameParts::new(false, 12, 0).unwrap().take(0).is_err());
    }

    #[test]
    fn frame_ranges() {
        assert_eq!(parse_frames("0..29"), Ok((0, 29)));
        assert!(parse_frames("5..2").is_err());
        assert!(parse_frames("5").is_err());
    }
}
