//! `ircache bench`: figures, never pass/fail.
//!
//! - Ray throughput on Sponza (camera, cosine-hemisphere and shadow rays), 1 and 2 threads: raw
//!   Embree calls on precomputed rays next to the renderer's own hemisphere loop (sample a
//!   direction, spawn an offset ray, intersect, build the surface interaction), and 16-wide packets.
//! - Path tracing time for the Cornell box at 64 spp, next to Mitsuba 3 (`llvm_ad_rgb`) on the same
//!   machine in the same run when `python3 -c "import mitsuba"` works.
//! - Irradiance cache gather rays on Sponza: raw Embree on the records' stratified rays next to
//!   the cache's own gather loop, 1 and 2 threads.
//! - The irradiance cache (`ic`, one bounce) on the Cornell box and Sponza: time, records and
//!   relMSE_trim against the references, with gradient variants, next to Mitsuba 3's path
//!   tracer run at the spp its error law says reaches the same error (and checked).
//! - `splat`: radiance cache splatting against the lookup (see [`splat`]).
//! - `peers`: ircache's `path` and `ic` against Mitsuba 3 with `independent` and `multijitter`,
//!   Mitsuba rendered at more samples until it reaches `ic`'s error (see [`peers`]).
//! - `temporal`: animations, the cache kept over time, flicker measured (see [`temporal`]).

mod adaptive;
mod cache_vs_path;
mod gpu;
mod media;
mod peers;
mod photons;
mod plane;
mod radiance;
mod splat;
mod temporal;

use anyhow::{bail, Context, Result};
use clap::Args;
use ircache_math::{sampling, Frame, Ray, Rng, Vec2};
use ircache_render::film::Filter;
use ircache_render::integrators::Integrator;
use ircache_render::render::{render, RenderSettings, Sampling};
use ircache_render::scene::{Interaction, Scene};
use ircache_scene::obj_scene::ObjCamera;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `ircache bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Folder holding `scenes/` (default: `$IRCACHE_SHARED`, else `shared` or `../shared` upwards).
    #[arg(long)]
    pub shared: Option<PathBuf>,
    /// Hemisphere rays per first hit.
    #[arg(long, default_value_t = 4)]
    pub hemisphere_rays: usize,
    /// Samples per pixel of the Cornell box path-tracing run.
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Skip the Mitsuba 3 comparison.
    #[arg(long)]
    pub no_mitsuba: bool,
    /// Folder for the images of the parts that make some (gpu: the GPU frame and the same frame
    /// ray traced, PNG).
    #[arg(long)]
    pub images: Option<PathBuf>,
    /// Which parts: all, rays, path, gather, ic, peers (ircache against Mitsuba 3 with
    /// multijitter, by rendering), cache (the cache against path tracing by rendering, and the
    /// cost of depth), radiance (radiance caching against tracing the same lobes and against
    /// Mitsuba 3, by rendering), splat (splatting against the lookup: per record, per frame),
    /// plane (records from a rasterised plane against the stratified gather, Table 4.1), gpu
    /// (the GPU passes' own speed: splat kernel, rasterised views and planes),
    /// temporal (animations: the cache kept over time against a cache per frame and against
    /// Mitsuba 3 per frame, flicker measured), photons (the final gather, caustic map and
    /// photon records against the cache without photons and Mitsuba 3, by rendering), media
    /// (the cache in fog against volpath, volpath against Mitsuba 3's volpath), adaptive
    /// (adaptive pixel sampling against uniform sampling, by rendering).
    #[arg(long, default_value = "all")]
    pub only: String,
    /// temporal: only the animations whose name contains this (still, cube, light, lamp);
    /// adaptive: only the cases of this integrator (path, ic) or whose name begins with it
    /// (e.g. "cornell-glossy d5 ic"); cache: only the scenes whose name begins with it
    /// (e.g. "sponza-sun d3"); peers: only the scenes whose name begins with it
    /// ("cornell-glossy"); gpu: splat, views (the camera's view, planes, records from planes), frame or
    /// walkthrough alone; media: the fog box's side in pixels (128 unless given).
    #[arg(long)]
    pub case: Option<String>,
}

/// Finds the shared folder with the scenes and references.
pub fn find_shared(explicit: Option<&Path>) -> Result<PathBuf> {
    if let Some(p) = explicit {
        return Ok(p.to_path_buf());
    }
    if let Ok(p) = std::env::var("IRCACHE_SHARED") {
        return Ok(PathBuf::from(p));
    }
    let mut dir = std::env::current_dir()?;
    loop {
        for cand in [dir.join("shared"), dir.join("../shared")] {
            if cand.join("scenes").is_dir() {
                return Ok(cand);
            }
        }
        if !dir.pop() {
            bail!(
                "cannot find the shared folder with scenes/ (set IRCACHE_SHARED or pass --shared)"
            );
        }
    }
}

/// The sample count after `spp` in a series that renders a Monte Carlo integrator at rising
/// counts until it reaches a target: four times as many. Multi-jittered sampling (the default,
/// and Mitsuba's best) sizes its grid ⌊√n⌋ rows by ⌈n/rows⌉ columns, so only powers of four
/// give square grids with power-of-two sides; 32 spp becomes 7 × 5 = 35 samples and 128 becomes
/// 132, each 15–20 % dearer per sample (cycle-walking permutations, integer division). A
/// doubling series put those counts into its interpolations and understated what a path tracer
/// reaches in a given time (Sponza `max_depth` 3, blurred: 35 samples in 7.42 s reach 1.09e-3,
/// while between 16 and 64 spp the curve passes 8.6e-4 there, and 42 spp in 7.68 s reach 8.7e-4).
pub(super) fn next_sample_count(spp: u32) -> u32 {
    spp * 4
}

/// The sample count after `spp` in a finer series for a cache, whose error flattens at its
/// records' bias: a series by fours would interpolate along a chord above that curve and
/// overstate the time to an error between its renders. Square grids (and 8 = 2 × 4) about
/// doubling: 4, 8, 16, 36, 64, 144, 256, then by fours.
pub(super) fn next_square_count(spp: u32) -> u32 {
    match spp {
        4 => 8,
        8 => 16,
        16 => 36,
        36 => 64,
        64 => 144,
        144 => 256,
        n => next_sample_count(n),
    }
}

/// Whether `--case` (`only`) selects the case named `name` ("sponza-sun d3 …"): no filter, or
/// a beginning of the name.
pub(super) fn selected(only: Option<&str>, name: &str) -> bool {
    only.is_none_or(|o| name.starts_with(o))
}

fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    Ok(rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?)
}

/// Runs `ircache bench`.
pub fn run(args: &BenchArgs) -> Result<()> {
    let shared = find_shared(args.shared.as_deref())?;
    println!(
        "ircache bench on {} ({} cores)",
        std::env::consts::ARCH,
        std::thread::available_parallelism()?.get()
    );
    if args.only == "all" || args.only == "rays" {
        rays(&shared, args)?;
    }
    if args.only == "all" || args.only == "path" {
        path(&shared, args)?;
    }
    if args.only == "all" || args.only == "gather" {
        gather(&shared)?;
    }
    if args.only == "all" || args.only == "ic" {
        ic(&shared, args)?;
    }
    if args.only == "all" || args.only == "peers" {
        if args.no_mitsuba {
            println!("\nircache against Mitsuba 3: skipped (--no-mitsuba)");
        } else {
            peers::run_all(&shared, args.case.as_deref())?;
        }
    }
    if args.only == "all" || args.only == "cache" {
        cache_vs_path::run_all(&shared, args.case.as_deref())?;
    }
    if args.only == "all" || args.only == "radiance" {
        radiance::run_all(&shared, !args.no_mitsuba)?;
    }
    if args.only == "all" || args.only == "splat" {
        splat::run_all(&shared)?;
    }
    if args.only == "all" || args.only == "gpu" {
        gpu::run_all(&shared, args.images.as_deref(), args.case.as_deref())?;
    }
    if args.only == "all" || args.only == "plane" {
        plane::run_all(&shared)?;
    }
    if args.only == "all" || args.only == "photons" {
        photons::run_all(!args.no_mitsuba)?;
    }
    if args.only == "all" || args.only == "media" {
        media::run_all(!args.no_mitsuba, args.case.as_deref())?;
    }
    if args.only == "all" || args.only == "adaptive" {
        adaptive::run_all(&shared, args.case.as_deref())?;
    }
    if args.only == "all" || args.only == "temporal" {
        temporal::run_all(!args.no_mitsuba, args.case.as_deref())?;
    }
    Ok(())
}

fn load(path: &Path, defines: &[(String, String)]) -> Result<Scene> {
    let desc = ircache_scene::load_scene(path, defines, &ObjCamera::default())?;
    Scene::build(&desc).with_context(|| format!("building {}", path.display()))
}

/// Mrays/s of `f` over `n` rays, best of three.
fn measure(n: usize, mut f: impl FnMut() -> usize) -> f64 {
    let mut best = f64::INFINITY;
    let mut check = 0;
    for _ in 0..3 {
        let t = Instant::now();
        check += f();
        best = best.min(t.elapsed().as_secs_f64());
    }
    std::hint::black_box(check);
    n as f64 / best * 1e-6
}

fn rays(shared: &Path, args: &BenchArgs) -> Result<()> {
    let path = shared.join("scenes/sponza-sun/scene.xml");
    let scene = load(&path, &[])?;
    let (w, h) = (640usize, 480usize);
    // Camera rays, one per pixel centre.
    let camera: Vec<Ray> = (0..w * h)
        .map(|i| {
            scene.camera.generate_ray(Vec2::new(
                ((i % w) as f32 + 0.5) / w as f32,
                ((i / w) as f32 + 0.5) / h as f32,
            ))
        })
        .collect();
    let hits: Vec<Interaction> = camera.iter().filter_map(|r| scene.intersect(r)).collect();
    // Cosine-hemisphere gather rays from the first hits (the same rays for every measurement).
    let k = args.hemisphere_rays;
    let mut hemisphere = Vec::with_capacity(hits.len() * k);
    // Every (k / 64)th hit when k is large, so the set stays near 20 M rays.
    for (i, it) in hits.iter().enumerate().step_by((k / 64).max(1)) {
        gather_rays(&scene, it, i, k, |r| hemisphere.push(r));
    }
    // Shadow rays towards a fixed direction (the sun's reverse) from the first hits.
    let sun = ircache_math::Vec3::new(0.328889, 0.939682, 0.0939682).normalize();
    let shadow: Vec<Ray> = hits
        .iter()
        .map(|it| scene.shadow_ray(it, sun, f32::INFINITY))
        .collect();
    println!(
        "\nSponza ({} triangles): {} camera rays, {} hemisphere rays ({} per hit), {} shadow rays",
        scene.triangles,
        camera.len(),
        hemisphere.len(),
        gather_grid(k).0 * gather_grid(k).1,
        shadow.len()
    );
    println!(
        "{:<44} {:>10} {:>10} {:>8}",
        "Mrays/s", "1 thread", "2 threads", "2t/1t"
    );
    let chunk = 1024;
    let row = |name: &str, f: &(dyn Fn(&[Ray]) -> usize + Sync), rays: &[Ray]| -> Result<()> {
        let mut r = [0.0; 2];
        for (j, t) in [1usize, 2].iter().enumerate() {
            let p = pool(*t)?;
            r[j] = measure(rays.len(), || {
                p.install(|| rays.par_chunks(chunk).map(f).sum())
            });
        }
        print_throughput(name, r);
        Ok(())
    };
    let raw_intersect = |rs: &[Ray]| {
        rs.iter()
            .filter(|r| scene.accel.intersect(r).is_some())
            .count()
    };
    let raw_occluded = |rs: &[Ray]| rs.iter().filter(|r| scene.accel.occluded(r)).count();
    let accel = &scene.accel;
    let packets_with = |coherence: ircache_embree::Coherence| {
        move |rs: &[Ray]| {
            let mut hits = [None; 16];
            let mut n = 0;
            for p in rs.chunks(16) {
                accel.intersect16_with(p, &mut hits[..p.len()], coherence);
                n += hits[..p.len()].iter().filter(|h| h.is_some()).count();
            }
            n
        }
    };
    let packets = packets_with(ircache_embree::Coherence::Coherent);
    row("camera rays, Embree rtcIntersect1", &raw_intersect, &camera)?;
    row(
        "camera rays, Embree rtcIntersect16 packets",
        &packets,
        &camera,
    )?;
    row(
        "hemisphere rays, Embree rtcIntersect1 (raw)",
        &raw_intersect,
        &hemisphere,
    )?;
    row(
        "hemisphere rays, Embree rtcIntersect16 packets",
        &packets,
        &hemisphere,
    )?;
    // Embree told the packet is incoherent (it then traces its rays one by one, in one call).
    let incoherent = packets_with(ircache_embree::Coherence::Incoherent);
    row(
        "hemisphere rays, rtcIntersect16, incoherent",
        &incoherent,
        &hemisphere,
    )?;
    row("shadow rays, Embree rtcOccluded1", &raw_occluded, &shadow)?;
    // The renderer's own gather loop over the same origins and directions.
    let renderer_loop = |rs: &[Ray]| {
        // Rays come in groups of k from one hit: regenerate them as the renderer would.
        rs.iter().filter(|r| scene.intersect(r).is_some()).count()
    };
    row(
        "hemisphere rays, renderer (hit + interaction)",
        &renderer_loop,
        &hemisphere,
    )?;
    // The renderer's own gather loop: sample a cosine direction, spawn an offset ray, trace it;
    // then the same with the surface interaction built at each hit.
    let per_chunk = chunk / k;
    let gather = |(c, hits): (usize, &[Interaction]), interaction: bool| -> usize {
        let mut count = 0;
        for (i, it) in hits.iter().enumerate() {
            gather_rays(&scene, it, c * per_chunk + i, k, |ray| {
                let hit = if interaction {
                    scene.intersect(&ray).is_some()
                } else {
                    scene.accel.intersect(&ray).is_some()
                };
                count += usize::from(hit);
            });
        }
        count
    };
    for (name, interaction) in [
        ("hemisphere gather, renderer (sample+spawn+trace)", false),
        ("  ... and build the surface interaction", true),
    ] {
        let mut r = [0.0; 2];
        for (j, t) in [1usize, 2].iter().enumerate() {
            let p = pool(*t)?;
            // A gather's grid rounds k up to whole 4 × 4 blocks: count the rays it traces.
            let (polar, azimuthal) = gather_grid(k);
            r[j] = measure(hits.len() * polar * azimuthal, || {
                p.install(|| {
                    hits.par_chunks(per_chunk)
                        .enumerate()
                        .map(|h| gather(h, interaction))
                        .sum()
                })
            });
        }
        print_throughput(name, r);
    }
    Ok(())
}

/// The polar × azimuthal cells of [`gather_rays`] for about `k` rays: stratified as a record's
/// gather, in whole 4 × 4 blocks (at least one: 16 rays).
fn gather_grid(k: usize) -> (usize, usize) {
    let polar = ((k as f32 / std::f32::consts::PI).sqrt().round() as usize).max(4) / 4 * 4;
    let azimuthal = (k / polar).max(4) / 4 * 4;
    (polar, azimuthal)
}

/// The cosine-weighted gather rays (about `k`, see [`gather_grid`]) of first hit number
/// `index`, on the camera's side of the surface, always the same for the same index.
fn gather_rays(scene: &Scene, it: &Interaction, index: usize, k: usize, mut f: impl FnMut(Ray)) {
    let mut rng = Rng::keyed(1, &[index as u64]);
    let n = if it.ng.dot(scene.camera.origin - it.p) < 0.0 {
        -it.ng
    } else {
        it.ng
    };
    let frame = Frame::from_z(n);
    let (polar, azimuthal) = gather_grid(k);
    for block in 0..(polar / 4) * (azimuthal / 4) {
        let (bj, bi) = (block / (azimuthal / 4), block % (azimuthal / 4));
        for c in 0..16 {
            let (j, i) = (bj * 4 + c / 4, bi * 4 + c % 4);
            let u = rng.next_2d();
            let cell = ircache_math::Vec2::new(
                (j as f32 + u.x) / polar as f32,
                (i as f32 + u.y) / azimuthal as f32,
            );
            f(scene.spawn_ray(
                it,
                frame.from_local(sampling::square_to_cosine_hemisphere(cell)),
            ));
        }
    }
}

fn path(shared: &Path, args: &BenchArgs) -> Result<()> {
    for scene in ["cornell-box", "sponza-sun"] {
        path_scene(&shared.join(format!("scenes/{scene}/scene.xml")), args)?;
    }
    Ok(())
}

fn path_scene(scene_path: &Path, args: &BenchArgs) -> Result<()> {
    let defines = vec![("max_depth".to_string(), "3".to_string())];
    let desc = ircache_scene::load_scene(scene_path, &defines, &ObjCamera::default())?;
    let scene = Scene::build(&desc)?;
    let integrator = Integrator::from_desc(&desc.integrator).map_err(anyhow::Error::msg)?;
    println!(
        "\nPath tracing, {} {}×{}, max_depth 3, {} spp",
        scene_path.display(),
        desc.sensor.film.width,
        desc.sensor.film.height,
        args.spp
    );
    let mut ours = 0.0;
    for threads in [1usize, 2] {
        let settings = RenderSettings {
            width: desc.sensor.film.width as usize,
            height: desc.sensor.film.height as usize,
            spp: args.spp,
            seed: 0,
            threads,
            filter: Filter::from_desc(&desc.sensor.film.filter),
            band: None,
            sampling: Sampling::default(),
        };
        let out = render(&scene, &integrator, &settings, &|_| {})?;
        println!(
            "  ircache path, {threads} thread(s): {:.2} s ({:.4} s per spp, {:.1} Mrays/s)",
            out.seconds,
            out.seconds / args.spp as f64,
            out.rays.total() as f64 * 1e-6 / out.seconds
        );
        ours = out.seconds;
    }
    if args.no_mitsuba {
        return Ok(());
    }
    match mitsuba_time(scene_path, args.spp) {
        Ok(t) => println!(
            "  Mitsuba 3 llvm_ad_rgb, 2 threads: {t:.2} s ({:.4} s per spp); ircache / Mitsuba time = {:.2}",
            t / args.spp as f64,
            ours / t
        ),
        Err(e) => println!("  Mitsuba 3 not measured: {e:#}"),
    }
    Ok(())
}

/// A throughput row: rays per second with 1 and 2 threads and their ratio.
fn print_throughput(name: &str, r: [f64; 2]) {
    println!(
        "{:<44} {:>10.2} {:>10.2} {:>8.2}",
        name,
        r[0],
        r[1],
        r[1] / r[0]
    );
}

/// Mitsuba's LLVM variants need libLLVM; Debian's packages put it here.
pub(super) fn llvm_path() -> Option<String> {
    ["19", "18", "17", "16", "15", "14"]
        .iter()
        .map(|v| format!("/usr/lib/x86_64-linux-gnu/libLLVM-{v}.so"))
        .find(|p| Path::new(p).exists())
        .or_else(|| std::env::var("DRJIT_LIBLLVM_PATH").ok())
}

/// Times Mitsuba 3's render of the same scene (kernels compiled by a warm-up run first).
fn mitsuba_time(scene: &Path, spp: u32) -> Result<f64> {
    mitsuba_render(scene, spp, None, 3, None, &[])
}

/// Renders the scene with Mitsuba 3 at `spp` (in passes of at most 64 spp with different
/// seeds, averaged, as the references were made), writing the image to `out` if given; returns
/// the render time (kernels compiled by a warm-up run first).
/// `sampler` overrides the scene's `$sampler` default, `defines` others (`resx`, `resy`); a
/// define `seed0` is not the scene's: it offsets the passes' seeds (for an image independent of a
/// reference made with the first seeds).
pub(super) fn mitsuba_render(
    scene: &Path,
    spp: u32,
    out: Option<&Path>,
    max_depth: u32,
    sampler: Option<&str>,
    defines: &[(&str, &str)],
) -> Result<f64> {
    let mut sampler = sampler.map_or(String::new(), |s| format!(", sampler={s:?}"));
    let mut seed0 = "0";
    for (name, value) in defines {
        if *name == "seed0" {
            seed0 = value;
        } else {
            sampler += &format!(", {name}={value:?}");
        }
    }
    let save = match out {
        Some(p) => format!("mi.Bitmap(acc).write({:?})", p.display().to_string()),
        None => String::new(),
    };
    let script = format!(
        r#"
import os, time, mitsuba as mi
mi.set_variant('llvm_ad_rgb')
import drjit as dr
s = mi.load_file({scene:?}, spp={spp}, max_depth={max_depth}{sampler})
img = mi.render(s, spp=4); dr.eval(img); dr.sync_thread()
left, passes, acc = {spp}, 0, None
t = time.time()
while left > 0:
    n = min(64, left)
    img = mi.render(s, spp=n, seed={seed0} + passes) * (n / {spp})
    acc = img if acc is None else acc + img
    dr.eval(acc); dr.sync_thread()
    left -= n; passes += 1
print("ircache-mitsuba-seconds", time.time() - t)
{save}
"#,
        scene = scene.display().to_string()
    );
    run_mitsuba_script(&script, &[])
}

/// Runs a Python script driving Mitsuba 3 with `args`; returns the seconds it prints on its
/// `ircache-mitsuba-seconds` line.
fn run_mitsuba_script(script: &str, args: &[&std::ffi::OsStr]) -> Result<f64> {
    let out = std::process::Command::new("python3")
        .arg("-c")
        .arg(script)
        .args(args)
        .envs(llvm_path().map(|p| ("DRJIT_LIBLLVM_PATH", p)))
        .output()
        .context("running python3")?;
    if !out.status.success() {
        bail!(
            "{}",
            String::from_utf8_lossy(&out.stderr)
                .lines()
                .last()
                .unwrap_or("python3 failed")
        );
    }
    // Mitsuba's log shares stdout (its warnings end in colour codes): find our line.
    let s = String::from_utf8_lossy(&out.stdout);
    s.lines()
        .filter_map(|l| l.split_once("ircache-mitsuba-seconds "))
        .next_back()
        .map(|(_, t)| t.trim())
        .unwrap_or("")
        .parse::<f64>()
        .with_context(|| format!("parsing Mitsuba's time from {s:?}"))
}

/// Renders frames `frames` of an animation with Mitsuba 3 (`multijitter` at `spp`, in passes
/// of at most 64, seeds from `seed`, the same for every frame as `ircache animate`'s pixel
/// samples and Mitsuba's default seed are), each frame's shapes moved by `motions` (per
/// frame, (shape id, row-major world-to-world matrix)) through `mi.traverse`: meshes' vertices
/// (and normals), spheres' `to_world`. Writes each frame to `pattern`'s name for it; returns
/// the seconds of the frames' updates and renders (kernels compiled by a warm-up render first).
pub(super) fn mitsuba_render_frames(
    scene: &Path,
    (width, height): (u32, u32),
    (first, _): (u32, u32),
    motions: &[Vec<(String, [f32; 16])>],
    spp: u32,
    seed: u32,
    pattern: &Path,
) -> Result<f64> {
    let frames: Vec<serde_json::Value> = motions
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let f = first + i as u32;
            Ok(serde_json::json!({
                "frame": f,
                "out": crate::animate::frame_path(pattern, f)?.display().to_string(),
                "motions": m.iter().map(|(id, mat)| (id.clone(), mat.to_vec())).collect::<std::collections::BTreeMap<_, _>>(),
            }))
        })
        .collect::<Result<_>>()?;
    // Scenes name their sampler either as a `$sampler` default or literally (multijitter).
    let text = std::fs::read_to_string(scene)?;
    let mut defines = serde_json::json!({
        "resx": width.to_string(), "resy": height.to_string(), "integrator": "path",
    });
    if text.contains("<default name=\"sampler\"") {
        defines["sampler"] = "multijitter".into();
    } else if !text.contains("<sampler type=\"multijitter\"") {
        bail!(
            "{}: its sampler is not multijitter and not a $sampler default",
            scene.display()
        );
    }
    let job = serde_json::json!({
        "scene": scene.display().to_string(),
        "defines": defines,
        "spp": spp,
        "seed": seed,
        "frames": frames,
    });
    let job_file = std::env::temp_dir().join(format!("ircache-frames-{}.json", std::process::id()));
    std::fs::write(&job_file, serde_json::to_string(&job)?)?;
    let script = r#"
import json, sys, time, numpy as np, mitsuba as mi
mi.set_variant('llvm_ad_rgb')
import drjit as dr
job = json.load(open(sys.argv[1]))
d = job['defines']
s = mi.load_file(job['scene'], **d)
params = mi.traverse(s)
ids = sorted({k for f in job['frames'] for k in f['motions']})
base = {}
for sid in ids:
    vp = sid + '.vertex_positions'
    if vp in params:
        n = sid + '.vertex_normals'
        normals = np.array(params[n]).reshape(-1, 3) if n in params and dr.width(params[n]) > 0 else None
        base[sid] = ('mesh', np.array(params[vp]).reshape(-1, 3), normals)
    elif sid + '.to_world' in params:
        t = params[sid + '.to_world']
        base[sid] = ('to_world', np.array(t.matrix).reshape(4, 4), type(t))
    else:
        raise SystemExit('no parameters for shape ' + sid)
img = mi.render(s, spp=4); dr.eval(img); dr.sync_thread()
spp, total = job['spp'], 0.0
for f in job['frames']:
    t = time.time()
    for sid, m in f['motions'].items():
        M = np.array(m, dtype=np.float64).reshape(4, 4)
        kind = base[sid]
        if kind[0] == 'mesh':
            p = kind[1] @ M[:3, :3].T + M[:3, 3]
            params[sid + '.vertex_positions'] = mi.Float(p.astype(np.float32).ravel())
            if kind[2] is not None:
                n = kind[2] @ np.linalg.inv(M[:3, :3])
                n /= np.linalg.norm(n, axis=1, keepdims=True)
                params[sid + '.vertex_normals'] = mi.Float(n.astype(np.float32).ravel())
        else:
            params[sid + '.to_world'] = kind[2](mi.Matrix4f(M @ kind[1]))
    params.update()
    left, passes, acc = spp, 0, None
    while left > 0:
        n = min(64, left)
        img = mi.render(s, spp=n, seed=job['seed'] * 1009 + passes) * (n / spp)
        acc = img if acc is None else acc + img
        dr.eval(acc); dr.sync_thread()
        left -= n; passes += 1
    total += time.time() - t
    mi.Bitmap(acc).write(f['out'])
print("ircache-mitsuba-seconds", total)
"#;
    let seconds = run_mitsuba_script(script, &[job_file.as_os_str()]);
    let _ = std::fs::remove_file(&job_file);
    seconds
}

/// Gather-ray throughput of the irradiance cache on Sponza.
fn gather(shared: &Path) -> Result<()> {
    use ircache_render::irradiance_cache::hemisphere::Stratification;
    let scene = load(&shared.join("scenes/sponza-sun/scene.xml"), &[])?;
    let strata = Stratification::from_divisions(1024);
    // Record positions: first hits of a 48×36 grid of camera rays.
    let (gw, gh) = (48usize, 36usize);
    let points: Vec<Interaction> = (0..gw * gh)
        .filter_map(|i| {
            let film = Vec2::new(
                ((i % gw) as f32 + 0.5) / gw as f32,
                ((i / gw) as f32 + 0.5) / gh as f32,
            );
            scene.intersect(&scene.camera.generate_ray(film))
        })
        .collect();
    let mut all = Vec::new();
    for (i, it) in points.iter().enumerate() {
        stratified_rays(&scene, strata, i, it, |r| all.push(r));
    }
    println!(
        "\nIrradiance cache gather rays on Sponza: {} records × {} stratified rays ({} × {})",
        points.len(),
        strata.cells(),
        strata.polar,
        strata.azimuthal
    );
    println!(
        "{:<52} {:>9} {:>9} {:>7}",
        "Mrays/s", "1 thread", "2 threads", "2t/1t"
    );
    let per = 16usize;
    let raw = |rs: &[Ray]| {
        rs.iter()
            .filter(|r| scene.accel.intersect(r).is_some())
            .count()
    };
    let ours = |(c, its): (usize, &[Interaction])| {
        let mut n = 0;
        for (i, it) in its.iter().enumerate() {
            stratified_rays(&scene, strata, c * per + i, it, |r| {
                n += usize::from(scene.intersect(&r).is_some());
            });
        }
        n
    };
    let mut rows = Vec::new();
    for (name, which) in [
        ("raw Embree rtcIntersect1 on the same rays", 0),
        ("cache gather loop (stratify+spawn+trace+interaction)", 1),
    ] {
        let mut r = [0.0; 2];
        for (j, t) in [1usize, 2].iter().enumerate() {
            let p = pool(*t)?;
            r[j] = measure(all.len(), || {
                p.install(|| {
                    if which == 0 {
                        all.par_chunks(per * strata.cells()).map(raw).sum()
                    } else {
                        points.par_chunks(per).enumerate().map(ours).sum()
                    }
                })
            });
        }
        println!(
            "{name:<52} {:>9.2} {:>9.2} {:>7.2}",
            r[0],
            r[1],
            r[1] / r[0]
        );
        rows.push(r);
    }
    println!(
        "  gather loop / raw: {:.0} % on 1 thread, {:.0} % on 2",
        100.0 * rows[1][0] / rows[0][0],
        100.0 * rows[1][1] / rows[0][1]
    );
    Ok(())
}

/// The stratified gather rays of record number `i` at `it`, on the camera's side (the same for
/// the same `i`).
fn stratified_rays(
    scene: &Scene,
    strata: ircache_render::irradiance_cache::hemisphere::Stratification,
    i: usize,
    it: &Interaction,
    mut f: impl FnMut(Ray),
) {
    let mut rng = Rng::keyed(7, &[i as u64]);
    let n = if it.ng.dot(scene.camera.origin - it.p) < 0.0 {
        -it.ng
    } else {
        it.ng
    };
    let frame = Frame::from_z(n);
    strata.for_each_direction(
        |_, _| rng.next_2d(),
        |_, _, _, d| f(scene.spawn_ray(it, frame.from_local(d))),
    );
}

/// Named cache parameters.
type Settings = &'static [(&'static str, &'static str)];
/// (scene, spp, settings, Mitsuba's error law c0 + c1/spp, Radiance high: error, seconds).
type IcCase = (&'static str, u32, Settings, (f64, f64), (f64, f64));
/// (label, settings added, thread counts).
type IcVariant = (&'static str, Settings, &'static [usize]);

/// The irradiance cache against the references, Mitsuba 3 and Radiance's published figures.
fn ic(shared: &Path, args: &BenchArgs) -> Result<()> {
    // (scene, spp, settings beyond the defaults, Mitsuba's error law c0 + c1/spp, Radiance high:
    // error, seconds)
    let cases: [IcCase; 2] = [
        ("cornell-box", 16, &[], (2.8e-5, 0.114), (3.7e-4, 77.6)),
        ("sponza-sun", 8, &[], (1e-3, 4.0), (1.04e-2, 141.2)),
    ];
    for (name, spp, preset, law, radiance) in cases {
        let scene_path = shared.join(format!("scenes/{name}/scene.xml"));
        let reference =
            ircache_image::read_image(&shared.join(format!("references/{name}-d3.exr")))?;
        let defines = vec![("max_depth".to_string(), "3".to_string())];
        let mut desc = ircache_scene::load_scene(&scene_path, &defines, &ObjCamera::default())?;
        desc.integrator.kind = "ic".into();
        let scene = Scene::build(&desc)?;
        let settings_text: Vec<String> = preset.iter().map(|(k, v)| format!("{k} {v}")).collect();
        println!(
            "\nIrradiance cache, {name} {}×{}, one bounce, {spp} spp, {}",
            desc.sensor.film.width,
            desc.sensor.film.height,
            settings_text.join(", ")
        );
        println!(
            "  {:<34} {:>7} {:>8} {:>9} {:>9} {:>9} {:>11}",
            "variant", "threads", "seconds", "pre-pass", "pixels", "records", "relMSE_trim"
        );
        let mut best = (f64::INFINITY, 0.0);
        let variants: [IcVariant; 12] = [
            ("gradients full (3.48)", &[], &[1, 2]),
            (
                "gradients full (3.47)",
                &[("gradient_formula", "krivanek")],
                &[2],
            ),
            ("gradients rotation", &[("gradients", "rotation")], &[2]),
            ("gradients none", &[("gradients", "none")], &[2]),
            // Equal rays: 1.5 N stratified against N + 0.5 N adaptive super-samples.
            (
                "1.5× divisions, no super-samples",
                &[("divisions", "1.5x"), ("supersamples", "0")],
                &[2],
            ),
            (
                "1× divisions + 0.5× super-samples",
                &[("supersamples", "0.5x")],
                &[2],
            ),
            ("+ neighbour clamping", &[("neighbour_clamp", "on")], &[2]),
            (
                "overture coarse (every 4th pixel)",
                &[("overture", "coarse")],
                &[2],
            ),
            (
                "record order spatial (Morton)",
                &[("record_order", "spatial")],
                &[2],
            ),
            (
                "error metric ward, a 0.25",
                &[("error_metric", "ward"), ("accuracy", "0.25")],
                &[2],
            ),
            (
                "error metric hessian, a 0.05",
                &[("error_metric", "hessian"), ("accuracy", "0.05")],
                &[2],
            ),
            (
                "ward, a 0.4, neighbour clamping",
                &[
                    ("error_metric", "ward"),
                    ("accuracy", "0.4"),
                    ("neighbour_clamp", "on"),
                ],
                &[2],
            ),
        ];
        let mut one_thread = 0.0;
        for (label, extra, threads) in variants {
            for &t in threads {
                let mut integrator =
                    Integrator::from_desc(&desc.integrator).map_err(anyhow::Error::msg)?;
                if let Integrator::Ic(ic) = &mut integrator {
                    for (k, v) in preset.iter().chain(extra) {
                        // "1.5x": relative to the preset's divisions (equal rays for the
                        // super-sampling comparison).
                        let v = match v.strip_suffix('x') {
                            Some(f) => format!(
                                "{}",
                                (f.parse::<f64>()? * ic.params.divisions as f64).round()
                            ),
                            None => v.to_string(),
                        };
                        ic.params.set(k, &v).map_err(anyhow::Error::msg)?;
                    }
                }
                let settings = RenderSettings {
                    width: desc.sensor.film.width as usize,
                    height: desc.sensor.film.height as usize,
                    spp,
                    seed: 0,
                    threads: t,
                    filter: Filter::from_desc(&desc.sensor.film.filter),
                    band: None,
                    sampling: Sampling::default(),
                };
                let out = render(&scene, &integrator, &settings, &|_| {})?;
                let m = ircache_image::compare::compare(&out.image, &reference)?;
                let c = out.cache.as_ref().context("cache report")?;
                println!(
                    "  {label:<34} {t:>7} {:>8.2} {:>9.2} {:>9.2} {:>9} {:>11.3e}",
                    out.seconds,
                    c.stats.gather_seconds,
                    c.pixel_seconds,
                    c.stats.records(),
                    m.rel_mse_trim
                );
                if t == 1 {
                    one_thread = out.seconds;
                }
                if label.starts_with("gradients full (3.48)") && t == 2 {
                    best = (m.rel_mse_trim, out.seconds);
                    println!(
                        "  {:<34} 2 threads / 1 thread: {:.2}×; {:.1} M gather rays, {:.1} M rays in all",
                        "",
                        one_thread / out.seconds,
                        c.stats.gather_rays as f64 * 1e-6,
                        out.rays.total() as f64 * 1e-6
                    );
                }
            }
        }
        let (err, secs) = best;
        println!(
            "  Radiance 6.0a rpict \"high\" (references README, not run here): {:.1} s for {:.2e}: \
             ircache {:.0}× faster at {}",
            radiance.1,
            radiance.0,
            radiance.1 / secs,
            if err <= radiance.0 { "lower error" } else { "HIGHER error" }
        );
        if args.no_mitsuba {
            continue;
        }
        // Mitsuba at the spp its error law gives for our error, then checked.
        let (c0, c1) = law;
        if err <= c0 {
            println!("  Mitsuba 3: error {err:.2e} is below its floor {c0:.1e}; not run");
            continue;
        }
        let m_spp = (c1 / (err - c0)).ceil() as u32;
        let tmp =
            std::env::temp_dir().join(format!("ircache-bench-{}-{name}.exr", std::process::id()));
        match mitsuba_render(&scene_path, m_spp, Some(&tmp), 3, None, &[]) {
            Ok(t) => {
                let m = ircache_image::read_image(&tmp)
                    .map_err(anyhow::Error::from)
                    .and_then(|img| Ok(ircache_image::compare::compare(&img, &reference)?));
                let _ = std::fs::remove_file(&tmp);
                let m_err = m.map(|m| m.rel_mse_trim).unwrap_or(f64::NAN);
                // Path tracing's error above its floor falls as 1/spp: the time at which
                // Mitsuba would reach ircache's error, from this measured point.
                let equal = t * (m_err - c0) / (err - c0);
                println!(
                    "  Mitsuba 3 llvm_ad_rgb path, 2 threads, {m_spp} spp: {t:.1} s for relMSE_trim {m_err:.3e}"
                );
                println!(
                    "  Mitsuba at ircache's error ({err:.3e}, error above {c0:.1e} ∝ 1/spp): {equal:.1} s; \
                     ircache is {:.1}× faster",
                    equal / secs
                );
            }
            Err(e) => println!("  Mitsuba 3 not measured: {e:#}"),
        }
    }
    Ok(())
}
