//! `ircache render`: load, render, write, report.

use crate::cache_args::CacheArgs;
use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use ircache_math::Vec3;
use ircache_render::integrators::ic::PixelPass;
use ircache_render::integrators::Integrator;
use ircache_render::irradiance_cache::params::RadianceCaching;
use ircache_render::render::{render, Adaptive, RenderOutput, RenderSettings};
use ircache_render::scene::Scene;
use ircache_scene::obj_scene::ObjCamera;
use ircache_scene::SceneDesc;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The built-in scene: Bitterli's Cornell box (CC0), as in `shared/scenes/cornell-box`.
pub const BUILTIN_CORNELL_BOX: &str = include_str!("../assets/cornell-box.xml");

/// Arguments of `ircache render`.
#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// Scene file: Mitsuba 3 XML (.xml), Wavefront OBJ (.obj) or Radiance (.rad). Default: a
    /// built-in Cornell box.
    pub scene: Option<PathBuf>,
    /// Set a scene parameter: `-D name=value` overrides `<default name=...>` (Mitsuba's -D).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Output image (.exr float, .hdr Radiance, .png sRGB). Default: the scene's name with .exr.
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    /// Samples per pixel (overrides the scene's sampler).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Worker threads (default: all cores).
    #[arg(long, short = 't')]
    pub threads: Option<usize>,
    /// Seed of the samples (overrides the sampler's `seed`): the same seed gives the same
    /// image, bit for bit, whatever the thread count.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Sampler (overrides the scene's): independent, stratified, multijitter, orthogonal,
    /// ldsampler (Mitsuba 3's), sobol (Owen-scrambled Sobol' along a Morton curve: lowest error
    /// after a blur) or lattice (a shifted rank-1 lattice sequence along the same curve: lowest
    /// per-pixel error at the first bounce of the Cornell box; with --adaptive, its prefixes
    /// instead of sobol's).
    #[arg(long)]
    pub sampler: Option<String>,
    /// Adaptive pixel sampling to this root-mean-square relative error over the image (e.g.
    /// 0.02; with `ic`, 0.01 and a pilot of --spp 4): every pixel takes --spp samples (a
    /// power of two, the pilot), then rounds double the pixels whose error, estimated from the
    /// two halves of their neighbours' samples, is above their share, up to --max-spp; no
    /// pixel decides from its own samples.
    #[arg(long, value_name = "REL_ERROR")]
    pub adaptive: Option<f32>,
    /// Most samples a pixel takes under --adaptive (default: 8 × --spp).
    #[arg(long, requires = "adaptive")]
    pub max_spp: Option<u32>,
    /// Integrator (overrides the scene's): path, direct, ic (the irradiance cache; also
    /// irrcache), or splat (the same cache, its first-bounce records splatted over the image).
    #[arg(long)]
    pub integrator: Option<String>,
    /// Maximum path depth (overrides the scene's; Mitsuba's meaning: 2 = direct light only).
    #[arg(long)]
    pub max_depth: Option<i32>,
    /// Image width (overrides the film's; without --height, the height follows at the film's
    /// aspect ratio).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (overrides the film's; without --width, the width follows at the film's
    /// aspect ratio).
    #[arg(long)]
    pub height: Option<u32>,
    /// Exposure in stops for PNG output.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// No progress bar and no summary.
    #[arg(long, short = 'q')]
    pub quiet: bool,
    /// Write run statistics as JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// OBJ and Radiance scenes (without --view): eye position `x,y,z`.
    #[arg(long, value_parser = parse_vec3)]
    pub eye: Option<Vec3>,
    /// OBJ and Radiance scenes (without --view): point looked at `x,y,z`.
    #[arg(long, value_parser = parse_vec3)]
    pub target: Option<Vec3>,
    /// OBJ and Radiance scenes (without --view): up vector `x,y,z`.
    #[arg(long, value_parser = parse_vec3)]
    pub up: Option<Vec3>,
    /// OBJ and Radiance scenes (without --view): vertical field of view in degrees.
    #[arg(long)]
    pub fov: Option<f32>,
    /// Radiance scenes: the view, as rpict's options (`"-vp 2 1 1.5 -vd 0 1 0 -vu 0 0 1 -vh 60
    /// -vv 45"`, `-vtv` or `-vtl`) or a view file (`-vf` inside the options also reads one); the
    /// picture fits --width × --height (512 × 512) with square pixels, as rpict's -x, -y.
    #[arg(long, allow_hyphen_values = true)]
    pub view: Option<String>,
    /// Extra images (ic integrator): `irradiance` (interpolated indirect irradiance, written to
    /// NAME-irradiance.exr), `records` (level-0 record positions as red dots over the image, cyan
    /// for records that also hold radiance, NAME-records.exr) and `glossy` (with radiance
    /// records: the indirect light the first surface's cached glossy lobe reflects
    /// towards the camera, from the radiance records, NAME-glossy.exr) and `photons` (with
    /// --photons or --caustic-photons: the indirect irradiance the photon maps give at the first
    /// diffuse surface, the global map's and the caustic map's, NAME-photons.exr). Repeat or
    /// separate with commas.
    #[arg(long, value_delimiter = ',')]
    pub aov: Vec<String>,
    /// Render only band i of n equal bands of rows (0-based, `--tile 2/4`), the rest black: n
    /// processes, one per band, sharing one `--cache` file, and `ircache merge` sums their images.
    #[arg(long, value_parser = parse_tile, value_name = "i/n")]
    pub tile: Option<(usize, usize)>,
    /// Splat on the GPU (`--integrator splat`): wgpu's first adapter, a hardware GPU before a
    /// software one (Mesa's lavapipe); irradiance records only so far (radiance records splat on
    /// the CPU). A clear error without a device or without the `gpu` feature.
    #[arg(long)]
    pub gpu: bool,
    /// Irradiance cache settings.
    #[command(flatten)]
    pub cache: CacheArgs,
}

fn parse_tile(s: &str) -> Result<(usize, usize), String> {
    let err = || format!("expected i/n with 0 ≤ i < n (for example 0/4), found \"{s}\"");
    let (i, n) = s.split_once('/').ok_or_else(err)?;
    let (i, n) = (
        i.trim().parse::<usize>().map_err(|_| err())?,
        n.trim().parse::<usize>().map_err(|_| err())?,
    );
    if n == 0 || i >= n {
        return Err(err());
    }
    Ok((i, n))
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.parse::<f32>()
                .map_err(|_| format!("expected three numbers x,y,z, found \"{s}\""))
        })
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(Vec3::new(x, y, z)),
        _ => Err(format!(
            "expected three finite numbers x,y,z, found \"{s}\""
        )),
    }
}

/// Parses `-D name=value` pairs.
pub fn parse_defines(defines: &[String]) -> Result<Vec<(String, String)>> {
    defines
        .iter()
        .map(|d| match d.split_once('=') {
            Some((k, v)) if !k.trim().is_empty() => {
                Ok((k.trim().to_string(), v.trim().to_string()))
            }
            _ => bail!("-D {d}: expected NAME=VALUE"),
        })
        .collect()
}

/// Loads the scene named by the arguments (or the built-in one), with command-line overrides
/// applied to the description.
pub fn load(args: &RenderArgs) -> Result<SceneDesc> {
    let defines = parse_defines(&args.define)?;
    let obj_camera = ObjCamera {
        eye: args.eye,
        target: args.target,
        up: args.up,
        fov: args.fov,
        width: args.width,
        height: args.height,
        radiance_view: args.view.clone(),
    };
    let desc = match &args.scene {
        Some(path) => ircache_scene::load_scene(path, &defines, &obj_camera)?,
        None => load_builtin(&defines)?,
    };
    apply_overrides(args, desc)
}

/// The film's size with the command line's width and height: one of them alone keeps the
/// film's aspect ratio (rounded, at least a pixel), as a smaller preview of the same view.
fn resized((w, h): (u32, u32), width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let follow = |given: u32, this: u32, other: u32| -> u32 {
        if this == 0 {
            return other;
        }
        let scaled = (f64::from(given) * f64::from(other) / f64::from(this)).round();
        (scaled as u32).max(1)
    };
    match (width, height) {
        (Some(width), Some(height)) => (width, height),
        (Some(width), None) => (width, follow(width, w, h)),
        (None, Some(height)) => (follow(height, h, w), height),
        (None, None) => (w, h),
    }
}

/// Applies the command line's overrides (size, samples, sampler, integrator, depth) to a
/// loaded scene.
pub fn apply_overrides(args: &RenderArgs, mut desc: SceneDesc) -> Result<SceneDesc> {
    // The Radiance loader has fitted the picture into --width × --height as rpict does.
    let fitted = desc
        .source
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("rad") || e.eq_ignore_ascii_case("oct"));
    if !fitted {
        let film = &mut desc.sensor.film;
        (film.width, film.height) = resized((film.width, film.height), args.width, args.height);
    }
    if desc.sensor.film.width == 0 || desc.sensor.film.height == 0 {
        bail!(
            "image size {}×{} is empty",
            desc.sensor.film.width,
            desc.sensor.film.height
        );
    }
    if let Some(spp) = args.spp {
        desc.sensor.spp = spp;
    }
    if let Some(s) = &args.sampler {
        desc.sensor.sampler = s.clone();
    }
    if desc.sensor.spp == 0 {
        bail!("--spp must be at least 1");
    }
    if let Some(i) = &args.integrator {
        desc.integrator.kind = i.clone();
        desc.integrator.unusable = None;
    }
    if let Some(d) = args.max_depth {
        desc.integrator.max_depth = d;
    }
    Ok(desc)
}

/// Loads the built-in Cornell box. It references no other file, so it is written to a private
/// temporary file and read by the ordinary XML loader.
pub(crate) fn load_builtin(defines: &[(String, String)]) -> Result<SceneDesc> {
    let dir = std::env::temp_dir().join(format!("ircache-builtin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join("cornell-box.xml");
    std::fs::write(&path, BUILTIN_CORNELL_BOX)
        .with_context(|| format!("writing {}", path.display()))?;
    let result = ircache_scene::mitsuba::load(&path, defines);
    let _ = std::fs::remove_dir_all(&dir);
    let mut desc = result?;
    // Named as what it is, not by the temporary file it was read from.
    desc.source = PathBuf::from("built-in Cornell box");
    Ok(desc)
}

pub fn default_output(args: &RenderArgs) -> PathBuf {
    let stem = args
        .scene
        .as_ref()
        .and_then(|p| {
            // `scene.xml` in a folder is better named after the folder.
            let s = p.file_stem()?.to_string_lossy().into_owned();
            if s == "scene" {
                p.canonicalize()
                    .ok()?
                    .parent()?
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
            } else {
                Some(s)
            }
        })
        .unwrap_or_else(|| "cornell-box".into());
    PathBuf::from(format!("{stem}.exr"))
}

/// The adaptive sampling asked for, checked.
fn adaptive(args: &RenderArgs, spp: u32) -> Result<Option<Adaptive>> {
    let Some(target) = args.adaptive else {
        return Ok(None);
    };
    if !(target > 0.0 && target.is_finite()) {
        bail!("--adaptive {target}: expected a relative error above 0 (e.g. 0.02)");
    }
    let max_spp = args.max_spp.unwrap_or(spp.saturating_mul(8));
    if max_spp < spp {
        bail!("--max-spp {max_spp} is below --spp {spp}");
    }
    Ok(Some(Adaptive { target, max_spp }))
}

/// The integrator the scene and the command line ask for, with the cache options applied.
pub fn integrator(args: &RenderArgs, desc: &SceneDesc) -> Result<Integrator> {
    let mut integrator = Integrator::from_desc(&desc.integrator).map_err(anyhow::Error::msg)?;
    match &mut integrator {
        Integrator::Ic(ic) => {
            args.cache.apply(&mut ic.params)?;
            (ic.cache_file, ic.force_reuse) = args.cache.cache_file()?;
            ic.exclusions = args.cache.exclusions()?;
        }
        _ if args.cache.any() => bail!(
            "irradiance cache options apply to the ic integrator only (this scene uses \"{}\"; \
             add --integrator ic)",
            desc.integrator.kind
        ),
        _ => {}
    }
    Ok(integrator)
}

/// The render settings the scene and the command line ask for.
pub fn settings(args: &RenderArgs, desc: &SceneDesc) -> Result<RenderSettings> {
    let mut s = RenderSettings::from_desc(
        desc,
        args.seed.unwrap_or(desc.sensor.sampler_seed),
        args.threads.unwrap_or(0),
    )
    .map_err(anyhow::Error::msg)?;
    s.band = args.tile;
    s.sampling.adaptive = adaptive(args, desc.sensor.spp)?;
    Ok(s)
}

/// Runs `ircache render`.
pub fn run(args: &RenderArgs) -> Result<()> {
    let t0 = Instant::now();
    let output = args.output.clone().unwrap_or_else(|| default_output(args));
    check_writable(&output)?;
    let desc = load(args)?;
    let mut integrator = integrator(args, &desc)?;
    for aov in &args.aov {
        if !matches!(
            aov.as_str(),
            "irradiance" | "records" | "glossy" | "photons"
        ) {
            bail!("--aov {aov}: expected irradiance, records, glossy or photons");
        }
        if aov == "photons"
            && !matches!(&integrator, Integrator::Ic(ic)
                if ic.params.global_photons() > 0
                    || ic.params.caustic_photons.is_some_and(|n| n > 0))
        {
            // (Asked before the render: whether `auto` makes a caustic map depends on the
            // scene's surfaces, known only once it is built.)
            bail!("--aov photons needs photon maps: give --photons N or --caustic-photons N");
        }
        if !matches!(integrator, Integrator::Ic(_)) {
            bail!("--aov {aov} needs the ic integrator");
        }
        if aov == "glossy"
            && matches!(&integrator, Integrator::Ic(ic) if ic.params.radiance_cache == RadianceCaching::Off)
        {
            bail!("--aov glossy needs --radiance-cache auto or on (it shows the radiance records)");
        }
    }
    let gpu = if args.gpu {
        let Integrator::Ic(ic) = &mut integrator else {
            bail!("--gpu splats records: it needs --integrator splat");
        };
        if ic.pixel_pass != PixelPass::Splat {
            bail!("--gpu splats records: it needs --integrator splat");
        }
        let gpu = crate::gpu::splatter()?;
        ic.splatter = Some(gpu.splatter.clone());
        Some(gpu)
    } else {
        None
    };
    let scene = Scene::build(&desc).context("building the scene")?;
    if scene.has_media() && matches!(integrator, Integrator::Ic(_)) {
        if let Some(aov) = args.aov.first() {
            bail!(
                "--aov {aov}: the cache in media (`ic` in a scene with media) makes no extra \
                 images yet"
            );
        }
    }
    if let Integrator::Ic(ic) = &mut integrator {
        crate::gpu::attach_plane_source(ic, &scene)?;
    }
    let load_seconds = t0.elapsed().as_secs_f64();
    let settings = settings(args, &desc)?;
    // Under --adaptive the sampler is the progressive one `RenderSettings::sampler` picks.
    let drawn = settings.sampler();
    if drawn.kind != settings.sampling.sampler {
        eprintln!(
            "note: --adaptive draws its samples from the {} sampler (its prefixes stay \
             stratified as samples are added; --sampler lattice is the other that does), not {}",
            drawn.kind.name(),
            settings.sampling.sampler.name()
        );
    }
    let rounded = drawn.spp;
    if rounded != settings.spp && settings.sampling.adaptive.is_none() {
        // Said even with --quiet: the render costs more than asked.
        eprintln!(
            "note: the {} sampler takes {rounded} samples per pixel for the {} asked",
            settings.sampling.sampler.name(),
            settings.spp
        );
    }
    // The thesis's pipeline whole on the GPU where the scene and the options allow it.
    if let Some(gpu) = &gpu {
        if crate::gpu::whole_frame(gpu, args, &scene, &integrator, &settings, &output)? {
            for note in &desc.notes {
                eprintln!("note: {note}");
            }
            return Ok(());
        }
    }
    let show = !args.quiet && std::io::stderr().is_terminal();
    let bar = if show {
        let b = ProgressBar::new((settings.width * settings.height) as u64);
        b.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b
    } else {
        ProgressBar::hidden()
    };
    let out = render(&scene, &integrator, &settings, &|n| bar.set_position(n))?;
    // What the loaders and the cache changed is said even with --quiet.
    let cache_notes = out
        .cache
        .iter()
        .flat_map(|c| c.stats.notes.iter())
        .chain(out.media_cache.iter().flat_map(|st| st.notes.iter()));
    for note in desc.notes.iter().chain(cache_notes) {
        eprintln!("note: {note}");
    }
    bar.finish_and_clear();
    ircache_image::write_image(&output, &out.image, args.exposure)?;
    if let Some(report) = &out.cache {
        write_aovs(args, &scene, report, &out.image, &settings, &output)?;
    }
    let wall = t0.elapsed().as_secs_f64();
    if !args.quiet {
        summary(&desc, &settings, &out, &output, wall);
        if let Some(gpu) = &gpu {
            eprintln!("{}", (gpu.summary)());
        }
    }
    if let Some(stats) = &args.stats {
        write_stats(stats, &desc, &settings, &out, wall, load_seconds)?;
    }
    Ok(())
}

/// Fails early, before any rendering, if the output file cannot be created.
pub fn check_writable(path: &Path) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        bail!(
            "{}: cannot write: directory {} does not exist",
            path.display(),
            dir.display()
        );
    }
    let probe = dir.join(format!(".ircache-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .with_context(|| format!("{}: cannot write to {}", path.display(), dir.display()))?;
    let _ = std::fs::remove_file(probe);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if !matches!(ext.as_str(), "exr" | "hdr" | "pic" | "png") {
        bail!(
            "{}: unknown image format \"{ext}\" (expected .exr, .hdr, .pic or .png)",
            path.display()
        );
    }
    Ok(())
}

fn summary(desc: &SceneDesc, s: &RenderSettings, out: &RenderOutput, output: &Path, wall: f64) {
    let rays = out.rays.total();
    eprintln!(
        "{}: {}×{} at {:.1} spp ({}, {}) in {:.2} s (render {:.2} s): {:.1} M rays, {:.2} Mrays/s -> {}",
        desc.source.display(),
        s.width,
        s.height,
        out.samples as f64 / (s.width * s.rows().len()).max(1) as f64,
        s.sampling.sampler.name(),
        desc.integrator.kind,
        wall,
        out.seconds,
        rays as f64 * 1e-6,
        rays as f64 * 1e-6 / out.seconds.max(1e-9),
        output.display()
    );
    if let Some(st) = &out.media_cache {
        eprintln!(
            "media cache: {} records (per level: {:?}; {} from the cache file), {:.1} M gather rays, {:.1} M shadow rays, {:.1} M march steps; pre-pass {:.2} s",
            st.records,
            st.per_level,
            st.loaded,
            st.gather_rays as f64 * 1e-6,
            st.shadow_rays as f64 * 1e-6,
            st.march_steps as f64 * 1e-6,
            st.seconds
        );
        if st.metric_replaced {
            eprintln!("note: {}", ircache_render::media_cache::cache::METRIC_NOTE);
        }
        for map in st.global_map.iter().chain(&st.caustic_map) {
            eprintln!("{map}");
        }
    }
    if let Some(st) = &out.volume_records {
        eprintln!(
            "volumetric records: {} records ({} from the cache file), {:.1} M rays; pre-pass {:.2} s",
            st.records,
            st.loaded,
            st.rays as f64 * 1e-6,
            st.seconds
        );
    }
    if let Some(c) = &out.cache {
        let st = &c.stats;
        eprintln!(
            "irradiance cache: {} records (per bounce level: {:?}), {} computed ({} overlapping another of their batch), \
             {:.1} M gather rays; pre-pass {:.2} s, pixel pass {:.2} s; \
             {} samples outside every record",
            st.records(),
            st.records_per_level,
            st.records_computed,
            st.records_overlapping,
            st.gather_rays as f64 * 1e-6,
            st.gather_seconds,
            c.pixel_seconds,
            c.uncached_samples
        );
        if let Some(maps) = &c.cache.photons {
            for map in maps.maps() {
                eprintln!("{map}");
            }
            if st.photon_records > 0 {
                eprintln!(
                    "photon records: {} in {:.2} s ({:.2} ms each)",
                    st.photon_records,
                    st.photon_record_seconds,
                    1e3 * st.photon_record_seconds / st.photon_records as f64
                );
            }
        }
        if let Some(sp) = &c.splat {
            eprintln!(
                "splatting: {} layers, {} record splats, {} records gathered at misses; \
                 G-buffers {:.2} s, splats {:.2} s, misses {:.2} s, shading {:.2} s",
                sp.layers,
                sp.splats,
                sp.miss_records,
                sp.gbuffer_seconds,
                sp.splat_seconds,
                sp.miss_seconds,
                sp.shade_seconds
            );
        }
    }
    if out.invalid_samples > 0 {
        eprintln!(
            "warning: {} samples were NaN, infinite or negative and were dropped",
            out.invalid_samples
        );
    }
}

/// A photon map's figures in the statistics file.
fn map_json(m: ircache_render::photon_map::MapSummary) -> serde_json::Value {
    serde_json::json!({
        "kind": format!("{:?}", m.kind).to_lowercase(),
        "stored": m.stats.stored,
        "emitted": m.stats.emitted,
        "rays": m.stats.rays,
        "seconds": m.seconds,
    })
}

fn write_stats(
    path: &Path,
    desc: &SceneDesc,
    s: &RenderSettings,
    out: &RenderOutput,
    wall: f64,
    load_seconds: f64,
) -> Result<()> {
    let mut json = serde_json::json!({
        "scene": desc.source.display().to_string(),
        "integrator": desc.integrator.kind,
        "max_depth": desc.integrator.max_depth,
        "wall_seconds": wall,
        "load_seconds": load_seconds,
        "render_seconds": out.seconds,
        "rays": out.rays.total(),
        "camera_rays": out.rays.camera,
        "bounce_rays": out.rays.bounce,
        "shadow_rays": out.rays.shadow,
        "mrays_per_second": out.rays.total() as f64 * 1e-6 / out.seconds.max(1e-9),
        "width": s.width,
        "height": s.height,
        "spp": s.first_samples(),
        "mean_spp": out.samples as f64 / (s.width * s.rows().len()).max(1) as f64,
        "adaptive": s.sampling.adaptive.map(|a| a.target),
        "sampler": s.sampling.sampler.name(),
        "seed": s.seed,
        "threads": if s.threads == 0 { std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1) } else { s.threads },
        "invalid_samples": out.invalid_samples,
    });
    if let Some(c) = &out.cache {
        let st = &c.stats;
        let p = &c.cache.params;
        let extra = serde_json::json!({
            "records": st.records(),
            "records_per_level": st.records_per_level,
            "records_computed": st.records_computed,
            "records_overlapping": st.records_overlapping,
            "records_loaded": st.records_loaded,
            "records_from_others": st.records_from_others,
            "records_regathered": st.records_regathered,
            "radiance_records": st.radiance_records,
            "radiance_table_seconds": st.radiance_table_seconds,
            "gather_rays": out.rays.gather,
            "prepass_gather_rays": st.gather_rays,
            "gather_seconds": st.gather_seconds,
            "pixel_seconds": c.pixel_seconds,
            "uncached_samples": c.uncached_samples,
            "supersampled_cells": st.supersampled_cells,
            "photon_records": st.photon_records,
            "photon_record_seconds": st.photon_record_seconds,
            "photon_maps": c.cache.photons.as_ref().map(|m| {
                m.maps().map(|map| map_json(map.summary())).collect::<Vec<_>>()
            }),
            // Every cache parameter, from the parameter table.
            "cache_params": p
                .to_pairs()
                .into_iter()
                .map(|(n, v)| (n.to_string(), serde_json::Value::String(v)))
                .collect::<serde_json::Map<_, _>>(),
        });
        if let (Some(a), Some(b)) = (json.as_object_mut(), extra.as_object()) {
            a.extend(b.clone());
        }
        if let (Some(a), Some(sp)) = (json.as_object_mut(), &c.splat) {
            a.insert(
                "splat".into(),
                serde_json::json!({
                    "layers": sp.layers,
                    "splats": sp.splats,
                    "miss_records": sp.miss_records,
                    "gbuffer_seconds": sp.gbuffer_seconds,
                    "splat_seconds": sp.splat_seconds,
                    "miss_seconds": sp.miss_seconds,
                    "shade_seconds": sp.shade_seconds,
                }),
            );
        }
    }
    if let (Some(a), Some(st)) = (json.as_object_mut(), &out.media_cache) {
        a.insert(
            "media_cache".into(),
            serde_json::json!({
                "records_computed": st.records,
                "records_per_level": st.per_level,
                "records_loaded": st.loaded,
                "gather_rays": st.gather_rays,
                "shadow_rays": st.shadow_rays,
                "march_steps": st.march_steps,
                "seconds": st.seconds,
                "caustic_map": st.caustic_map.map(map_json),
                "global_map": st.global_map.map(map_json),
            }),
        );
    }
    if let (Some(a), Some(st)) = (json.as_object_mut(), &out.volume_records) {
        a.insert(
            "volume_records".into(),
            serde_json::json!({
                "records_computed": st.records,
                "records_loaded": st.loaded,
                "rays": st.rays,
                "seconds": st.seconds,
            }),
        );
    }
    std::fs::write(path, serde_json::to_string_pretty(&json)? + "\n")
        .with_context(|| format!("{}: cannot write statistics", path.display()))
}

/// Writes the images `--aov` asked for next to `output`.
fn write_aovs(
    args: &RenderArgs,
    scene: &Scene,
    report: &ircache_render::render::CacheReport,
    image: &ircache_image::Image,
    settings: &RenderSettings,
    output: &Path,
) -> Result<()> {
    use ircache_render::irradiance_cache::aov;
    for kind in &args.aov {
        let img = match kind.as_str() {
            "irradiance" => {
                aov::irradiance_image(scene, &report.cache, settings.width, settings.height)
            }
            "glossy" => {
                if report.cache.radiance.is_none() {
                    bail!(
                        "--aov glossy: this render cached no glossy lobe (--radiance-cache auto \
                         caches only lobes that reflect a quarter or more of uniform light, rough \
                         metals): give --radiance-cache on"
                    );
                }
                aov::glossy_image(scene, &report.cache, settings.width, settings.height)
            }
            "photons" => {
                if report.cache.photons.is_none() {
                    bail!(
                        "--aov photons: this render made no photon maps (no global photons at \
                         this depth, and no surface in the scene makes caustics): give --photons N"
                    );
                }
                aov::photon_image(scene, &report.cache, settings.width, settings.height)
            }
            _ => aov::record_overlay(scene, &report.cache, image),
        };
        let stem = output
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let path = output.with_file_name(format!("{stem}-{kind}.exr"));
        ircache_image::write_image(&path, &img, 0.0)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::resized;

    #[test]
    fn one_side_given_keeps_the_films_aspect_ratio() {
        assert_eq!(resized((640, 480), Some(320), None), (320, 240));
        assert_eq!(resized((640, 480), None, Some(96)), (128, 96));
        assert_eq!(resized((1280, 720), Some(96), None), (96, 54));
        assert_eq!(resized((640, 480), Some(100), Some(100)), (100, 100));
        assert_eq!(resized((640, 480), None, None), (640, 480));
        // Never below a pixel on the side that follows.
        assert_eq!(resized((1000, 1), Some(10), None), (10, 1));
    }
}
