//! `ircache view SCENE`: the progressive walkthrough (001 §4.7.2) in the browser.
//!
//! A local HTTP server (`tiny_http`) serves one page; the page asks for frames one after the
//! other (`GET /frame?after=N` waits for frame N + 1 and answers a PNG with the frame's figures
//! in `X-Stats`, or 204 at once when the view has converged and no frame is coming) and sends the controls as `POST /control?key=value&...`. The main thread renders:
//! each frame splats the cache, adds at most a budget of records, and refines the running mean
//! (see [`ircache_render::splatting::walkthrough`]); it idles once the view has converged.
//!
//! Each frame takes one light sample per pixel (frames are averaged) unless `--direct-samples`
//! or the scene says otherwise.
//!
//! Controls: `accuracy=A` (0 < A ≤ 1), `turn=RIGHT,DOWN` (radians), `move=LEFT,UP,FORWARD` (in
//! steps of a twentieth of the distance to the surface at the image centre), `overlay=0|1`
//! (records over the image), `view=image|irradiance`, `budget=N`. `POST /save` appends the
//! records made so far to the `--cache` file. Bad requests get 400 with the reason, unknown paths
//! 404, wrong methods 405; nothing a request says can stop the server.

use crate::render::{self, RenderArgs};
use anyhow::{bail, Context, Result};
use clap::Args;
use ircache_math::Vec3;
use ircache_render::integrators::{Integrator, RayCounts};
use ircache_render::irradiance_cache::aov;
use ircache_render::scene::Scene;
use ircache_render::splatting::walkthrough::{
    moved, Walkthrough, MAX_LAYERS, WALKTHROUGH_LIGHT_SAMPLES,
};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

/// Arguments of `ircache view`.
#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// The scene and the cache, as for `ircache render` (options that only make sense for an
    /// image file are refused).
    #[command(flatten)]
    pub render: RenderArgs,
    /// Port to listen on (0: any free port; the address is printed).
    #[arg(long, default_value_t = 8000)]
    pub port: u16,
    /// Address to bind: 127.0.0.1 (only this machine) unless told otherwise.
    #[arg(long, default_value = "127.0.0.1")]
    pub bind: String,
    /// Most records a frame adds (the thesis's 100).
    #[arg(long, default_value_t = 100)]
    pub budget: usize,
}

const PAGE: &str = include_str!("view.html");

/// A change the page asked for.
#[derive(Clone, Debug, PartialEq)]
enum Control {
    Accuracy(f32),
    Turn(f32, f32),
    Move(Vec3),
    Overlay(bool),
    Irradiance(bool),
    Budget(usize),
}

/// Parses a control query (`key=value&...`); the error names the part that is wrong.
fn parse_controls(query: &str) -> Result<Vec<Control>, String> {
    let number = |key: &str, v: &str| -> Result<f32, String> {
        v.parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{key}={v}: expected a finite number"))
    };
    let pair = |key: &str, v: &str, n: usize| -> Result<Vec<f32>, String> {
        let parts: Vec<&str> = v.split(',').collect();
        if parts.len() != n {
            return Err(format!(
                "{key}={v}: expected {n} numbers separated by commas"
            ));
        }
        parts.iter().map(|p| number(key, p)).collect()
    };
    let mut out = Vec::new();
    for part in query.split('&').filter(|p| !p.is_empty()) {
        let Some((key, value)) = part.split_once('=') else {
            return Err(format!("{part}: expected key=value"));
        };
        out.push(match key {
            "accuracy" => {
                let a = number(key, value)?;
                if !(a > 0.0 && a <= 1.0) {
                    return Err(format!("accuracy={value}: expected a value in (0, 1]"));
                }
                Control::Accuracy(a)
            }
            "turn" => {
                let t = pair(key, value, 2)?;
                if t.iter().any(|x| x.abs() > std::f32::consts::PI) {
                    return Err(format!("turn={value}: at most π radians at a time"));
                }
                Control::Turn(t[0], t[1])
            }
            "move" => {
                let m = pair(key, value, 3)?;
                if m.iter().any(|x| x.abs() > 100.0) {
                    return Err(format!("move={value}: at most 100 steps at a time"));
                }
                Control::Move(Vec3::new(m[0], m[1], m[2]))
            }
            "overlay" | "irradiance" if matches!(value, "0" | "1") => {
                if key == "overlay" {
                    Control::Overlay(value == "1")
                } else {
                    Control::Irradiance(value == "1")
                }
            }
            "view" if matches!(value, "image" | "irradiance") => {
                Control::Irradiance(value == "irradiance")
            }
            "budget" => Control::Budget(
                value
                    .parse::<usize>()
                    .ok()
                    .filter(|&b| b <= 100_000)
                    .ok_or_else(|| format!("budget={value}: expected 0 to 100000"))?,
            ),
            "overlay" | "irradiance" => return Err(format!("{part}: expected 0 or 1")),
            "view" => return Err(format!("{part}: expected image or irradiance")),
            _ => {
                return Err(format!(
                    "unknown control \"{key}\" (known: accuracy, turn, move, overlay, view, budget)"
                ))
            }
        });
    }
    if out.is_empty() {
        return Err("no control given".into());
    }
    Ok(out)
}

/// What the render loop publishes and the requests leave for it.
#[derive(Default)]
struct Shared {
    /// Frames rendered.
    frame: u64,
    /// The latest frame as a PNG.
    png: Arc<Vec<u8>>,
    /// The latest frame's figures (JSON).
    stats: String,
    /// Controls not yet applied.
    pending: Vec<Control>,
    /// A save asked for: its answer goes here.
    save: Option<Option<Result<String, String>>>,
    /// The view has converged and the renderer waits for a control: no frame is coming.
    idle: bool,
}

struct State {
    shared: Mutex<Shared>,
    changed: Condvar,
}

impl State {
    fn lock(&self) -> std::sync::MutexGuard<'_, Shared> {
        // A panicking request thread cannot leave the figures half-written in a way that
        // matters: take the data either way.
        self.shared.lock().unwrap_or_else(|e| e.into_inner())
    }
}

fn header(name: &str, value: &str) -> tiny_http::Header {
    tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes()).unwrap_or_else(|()| {
        tiny_http::Header::from_bytes(&b"X-Invalid"[..], &b"1"[..]).expect("valid")
    })
}

fn text(code: u16, body: impl Into<String>) -> tiny_http::Response<std::io::Cursor<Vec<u8>>> {
    tiny_http::Response::from_string(body.into())
        .with_status_code(code)
        .with_header(header("Content-Type", "text/plain; charset=utf-8"))
}

/// Answers one request.
fn handle(request: tiny_http::Request, state: &State) {
    let url = request.url().to_string();
    let (path, query) = url.split_once('?').unwrap_or((&url, ""));
    let method = request.method().clone();
    use tiny_http::Method::{Get, Post};
    let response = match (path, &method) {
        ("/", Get) | ("/index.html", Get) => tiny_http::Response::from_string(PAGE)
            .with_header(header("Content-Type", "text/html; charset=utf-8")),
        ("/frame", Get) => {
            let after = query
                .split('&')
                .find_map(|p| p.strip_prefix("after="))
                .map(str::parse::<u64>);
            let after = match after {
                None => 0,
                Some(Ok(n)) => n,
                Some(Err(_)) => {
                    let _ = request.respond(text(400, "after=N: expected a frame number"));
                    return;
                }
            };
            let deadline = Instant::now() + Duration::from_secs(10);
            let mut shared = state.lock();
            while shared.frame <= after && !shared.idle {
                let left = deadline.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    break;
                }
                shared = state
                    .changed
                    .wait_timeout(shared, left)
                    .unwrap_or_else(|e| e.into_inner())
                    .0;
            }
            if shared.frame <= after {
                drop(shared);
                let _ = request.respond(text(204, ""));
                return;
            }
            let (png, stats, frame) = (shared.png.clone(), shared.stats.clone(), shared.frame);
            drop(shared);
            let r = tiny_http::Response::from_data(png.as_slice().to_vec())
                .with_header(header("Content-Type", "image/png"))
                .with_header(header("Cache-Control", "no-store"))
                .with_header(header("X-Frame", &frame.to_string()))
                .with_header(header("X-Stats", &stats));
            let _ = request.respond(r);
            return;
        }
        ("/stats", Get) => {
            let stats = state.lock().stats.clone();
            tiny_http::Response::from_string(stats)
                .with_header(header("Content-Type", "application/json"))
        }
        ("/control", Post) => match parse_controls(query) {
            Ok(controls) => {
                state.lock().pending.extend(controls);
                state.changed.notify_all();
                text(200, "ok")
            }
            Err(e) => text(400, e),
        },
        ("/save", Post) => {
            let mut shared = state.lock();
            shared.save = Some(None);
            state.changed.notify_all();
            let deadline = Instant::now() + Duration::from_secs(30);
            while matches!(shared.save, Some(None)) && Instant::now() < deadline {
                shared = state
                    .changed
                    .wait_timeout(shared, Duration::from_millis(100))
                    .unwrap_or_else(|e| e.into_inner())
                    .0;
            }
            match shared.save.take() {
                Some(Some(Ok(m))) => text(200, m),
                Some(Some(Err(e))) => text(400, e),
                _ => text(503, "the renderer did not answer in time"),
            }
        }
        ("/" | "/index.html" | "/frame" | "/stats" | "/control" | "/save", _) => {
            text(405, format!("{method} is not allowed on {path}"))
        }
        _ => text(404, format!("{path}: no such page")),
    };
    let _ = request.respond(response);
}

/// Runs `ircache view`.
pub fn run(args: &ViewArgs) -> Result<()> {
    let r = &args.render;
    for (given, name) in [
        (r.output.is_some(), "-o"),
        (r.spp.is_some(), "--spp"),
        (r.sampler.is_some(), "--sampler"),
        (r.adaptive.is_some(), "--adaptive"),
        (r.stats.is_some(), "--stats"),
        (!r.aov.is_empty(), "--aov"),
        (r.tile.is_some(), "--tile"),
    ] {
        if given {
            bail!("{name} does not apply to ircache view (it shows the image in the browser; use ircache render)");
        }
    }
    if let Some(i) = r.integrator.as_deref() {
        if !matches!(i, "ic" | "irrcache" | "splat") {
            bail!(
                "--integrator {i}: the walkthrough splats the irradiance cache (ic or splat only)"
            );
        }
    }
    let mut desc = render::load(r)?;
    if !matches!(desc.integrator.kind.as_str(), "ic" | "irrcache" | "splat") {
        // The scene names another integrator: the walkthrough is the cache's, with its defaults.
        desc.integrator.kind = "ic".into();
        desc.integrator.unusable = None;
        desc.integrator.extra.clear();
    }
    let mut integrator = Integrator::from_desc(&desc.integrator).map_err(anyhow::Error::msg)?;
    let Integrator::Ic(ic) = &mut integrator else {
        bail!("the walkthrough needs the cache's integrator");
    };
    // Frames are averaged: one light sample a frame unless asked otherwise (2.3× the frame rate
    // of the default 4 on the Cornell box at 512×512, the same converged image).
    let asked = |name: &str| {
        r.cache.params.given.iter().any(|(n, _)| *n == name)
            || desc.integrator.extra.iter().any(|(n, _, _)| n == name)
    };
    if !asked("direct_samples") {
        ic.params.direct_samples = WALKTHROUGH_LIGHT_SAMPLES;
    }
    r.cache.apply(&mut ic.params)?;
    (ic.cache_file, ic.force_reuse) = r.cache.cache_file()?;
    ic.exclusions = r.cache.exclusions()?;
    if r.gpu {
        let gpu = crate::gpu::splatter()?;
        eprintln!("splatting on the GPU: {}", gpu.device);
        ic.splatter = Some(gpu.splatter);
    }
    let scene = Scene::build(&desc).context("building the scene")?;
    scene.require_no_media("the walkthrough viewer")?;
    crate::gpu::attach_plane_source(ic, &scene)?;
    let (w, h) = (
        desc.sensor.film.width as usize,
        desc.sensor.film.height as usize,
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(r.threads.unwrap_or(0))
        .build()?;
    let seed = r.seed.unwrap_or(desc.sensor.sampler_seed);
    let mut walk = Walkthrough::new(scene, ic, w, h, seed, &pool)?;
    walk.budget = args.budget;

    let server = tiny_http::Server::http((args.bind.as_str(), args.port))
        .map_err(|e| anyhow::anyhow!("listening on {}:{}: {e}", args.bind, args.port))?;
    let address = server
        .server_addr()
        .to_ip()
        .context("the server has no IP address")?;
    eprintln!("ircache view: http://{address}/ ({w}×{h}; Ctrl-C to stop)");
    let state = Arc::new(State {
        shared: Mutex::new(Shared::default()),
        changed: Condvar::new(),
    });
    let server = Arc::new(server);
    for _ in 0..4 {
        let (server, state) = (server.clone(), state.clone());
        std::thread::spawn(move || {
            while let Ok(request) = server.recv() {
                handle(request, &state);
            }
        });
    }

    let (mut overlay, mut irradiance) = (false, false);
    let mut rays = RayCounts::default();
    let mut recent: std::collections::VecDeque<Instant> = Default::default();
    let mut frame_no = 0u64;
    // Views shown so far: one more at each camera move or accuracy change (the mean restarts).
    let mut views = 1u64;
    loop {
        let (controls, save) = {
            let mut shared = state.lock();
            if shared.pending.is_empty() && shared.save.is_none() && walk.layers() >= MAX_LAYERS {
                // Converged: say so (frame requests are answered at once) and wait for a control.
                if !shared.idle {
                    shared.idle = true;
                    state.changed.notify_all();
                }
                let _ = state
                    .changed
                    .wait_timeout(shared, Duration::from_millis(200));
                continue;
            }
            shared.idle = false;
            let save = matches!(shared.save, Some(None));
            (std::mem::take(&mut shared.pending), save)
        };
        if save {
            let answer = walk.save().map(|n| format!("saved {n} records"));
            state.lock().save = Some(Some(answer));
            state.changed.notify_all();
        }
        for c in controls {
            match c {
                Control::Accuracy(a) => {
                    // Validated when parsed.
                    let _ = walk.set_accuracy(a);
                    views += 1;
                }
                Control::Turn(right, down) => {
                    let to_world = moved(&walk.scene().camera, -right, down, Vec3::ZERO);
                    walk.set_camera(to_world);
                    views += 1;
                }
                Control::Move(step) => {
                    let camera = &walk.scene().camera;
                    let centre = camera.generate_ray(ircache_math::Vec2::splat(0.5));
                    let distance = walk
                        .scene()
                        .intersect(&centre)
                        .map_or(1.0, |it| it.t)
                        .max(1e-6);
                    let to_world = moved(camera, 0.0, 0.0, step * (distance / 20.0));
                    walk.set_camera(to_world);
                    views += 1;
                }
                Control::Overlay(on) => overlay = on,
                Control::Irradiance(on) => irradiance = on,
                Control::Budget(b) => walk.budget = b,
            }
        }
        let report = pool.install(|| walk.frame(&mut rays));
        let image = walk.image(irradiance);
        let image = if overlay {
            aov::record_overlay(walk.scene(), walk.cache(), &image)
        } else {
            image
        };
        let png = ircache_image::png::encode(&image, r.exposure).map_err(anyhow::Error::msg)?;
        let now = Instant::now();
        recent.push_back(now);
        while recent
            .front()
            .is_some_and(|t| now - *t > Duration::from_secs(1))
        {
            recent.pop_front();
        }
        frame_no += 1;
        let stats = serde_json::json!({
            "frame": frame_no,
            "view_number": views,
            "layers": report.layers,
            "records": report.records,
            "new_records": report.new_records,
            "uncovered": report.uncovered,
            "ms": report.seconds * 1e3,
            "fps": recent.len() as f64,
            // Three decimals: the f32 slider value, not its binary expansion.
            "accuracy": (f64::from(walk.accuracy()) * 1e3).round() / 1e3,
            "budget": walk.budget,
            "overlay": overlay,
            "view": if irradiance { "irradiance" } else { "image" },
            "width": w,
            "height": h,
        })
        .to_string();
        let mut shared = state.lock();
        shared.frame = frame_no;
        shared.png = Arc::new(png);
        shared.stats = stats;
        drop(shared);
        state.changed.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controls_parse_and_bad_ones_say_why() {
        assert_eq!(
            parse_controls(
                "accuracy=0.2&turn=0.1,-0.2&move=0,1,0&overlay=1&view=irradiance&budget=5"
            ),
            Ok(vec![
                Control::Accuracy(0.2),
                Control::Turn(0.1, -0.2),
                Control::Move(Vec3::new(0.0, 1.0, 0.0)),
                Control::Overlay(true),
                Control::Irradiance(true),
                Control::Budget(5),
            ])
        );
        for (bad, says) in [
            ("accuracy=0", "(0, 1]"),
            ("accuracy=nan", "finite"),
            ("turn=1", "2 numbers"),
            ("move=1,2,x", "finite"),
            ("overlay=yes", "0 or 1"),
            ("view=x", "image or irradiance"),
            ("zoom=2", "unknown control"),
            ("budget=-1", "0 to 100000"),
            ("", "no control"),
            ("accuracy", "key=value"),
        ] {
            let e = parse_controls(bad).expect_err(bad);
            assert!(e.contains(says), "{bad}: {e}");
        }
    }
}
