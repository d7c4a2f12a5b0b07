//! `ircache view` end to end: the server over plain HTTP (frames, controls, bad requests), and
//! the page in headless Chromium (the page loads, shows frames that converge to `ircache render`
//! of the same view, and sends the controls it is given). The built-in Cornell box, small.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn temp_dir(name: &str) -> ircache_testing::ScratchDir {
    ircache_testing::ScratchDir::new(&format!("view-{name}"))
}

/// A running `ircache view`, stopped when dropped.
struct Server {
    child: Child,
    port: u16,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn serve(size: u32) -> Server {
    serve_with(size, &[])
}

/// `ircache view` of the built-in scene at `size × size` with more options.
fn serve_with(size: u32, extra: &[&str]) -> Server {
    let mut child = Command::new(env!("CARGO_BIN_EXE_ircache"))
        .args([
            "view",
            "--port",
            "0",
            "--width",
            &size.to_string(),
            "--height",
        ])
        .arg(size.to_string())
        .args(extra)
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .expect("ircache view starts");
    let mut lines = BufReader::new(child.stderr.take().expect("stderr")).lines();
    let port = loop {
        let line = lines
            .next()
            .expect("ircache view printed its address")
            .expect("stderr");
        if let Some(rest) = line.split("http://127.0.0.1:").nth(1) {
            break rest
                .split('/')
                .next()
                .and_then(|p| p.parse().ok())
                .expect("port");
        }
    };
    // Keep draining stderr so the server never blocks on it.
    std::thread::spawn(move || for _ in lines {});
    Server { child, port }
}

struct Reply {
    status: u16,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Reply {
    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }
    fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
}

fn raw(port: u16, request: &[u8]) -> Reply {
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("connects");
    s.set_read_timeout(Some(Duration::from_secs(60)))
        .expect("timeout");
    s.write_all(request).expect("sends");
    let mut buf = Vec::new();
    let _ = s.read_to_end(&mut buf);
    let split = buf
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("an HTTP reply");
    let head = String::from_utf8_lossy(&buf[..split]).into_owned();
    let mut lines = head.lines();
    let status = lines
        .next()
        .and_then(|l| l.split(' ').nth(1))
        .and_then(|c| c.parse().ok())
        .expect("status");
    let headers = lines
        .filter_map(|l| l.split_once(": "))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    Reply {
        status,
        headers,
        body: buf[split + 4..].to_vec(),
    }
}

fn http(port: u16, method: &str, path: &str) -> Reply {
    raw(
        port,
        format!(
            "{method} {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\nContent-Length: 0\r\n\r\n"
        )
        .as_bytes(),
    )
}

/// A frame after `after` with its figures.
fn frame(port: u16, after: u64) -> (u64, serde_json::Value, Vec<u8>) {
    let r = http(port, "GET", &format!("/frame?after={after}"));
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.header("Content-Type"), Some("image/png"));
    let n = r
        .header("X-Frame")
        .and_then(|f| f.parse().ok())
        .expect("X-Frame");
    let stats = serde_json::from_str(r.header("X-Stats").expect("X-Stats")).expect("JSON");
    (n, stats, r.body)
}

/// Frames until the running mean holds `layers` layers; the last frame's figures and PNG.
fn settle(port: u16, layers: u64) -> (u64, serde_json::Value, Vec<u8>) {
    let start = Instant::now();
    let mut last = frame(port, 0);
    while last.1["layers"].as_u64().unwrap_or(0) < layers {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "never settled: {}",
            last.1
        );
        last = frame(port, last.0);
    }
    last
}

fn decode(png: &[u8], dir: &Path, name: &str) -> ircache_image::Image {
    let path = dir.join(name);
    std::fs::write(&path, png).expect("write");
    ircache_image::read_image(&path).expect("a PNG")
}

/// `ircache render --integrator splat` of the built-in scene at `size`, as a PNG image.
fn rendered(dir: &Path, size: u32) -> ircache_image::Image {
    let out = dir.join("render.png");
    let o = Command::new(env!("CARGO_BIN_EXE_ircache"))
        .args([
            "render",
            "--integrator",
            "splat",
            "--spp",
            "256",
            "-q",
            "--width",
        ])
        .args([
            size.to_string(),
            "--height".into(),
            size.to_string(),
            "-o".into(),
        ])
        .arg(&out)
        .output()
        .expect("render runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    ircache_image::read_image(&out).expect("render.png")
}

/// relMSE_trim after a 1-pixel blur and the luminance ratio of `a` against `b`.
fn against(a: &ircache_image::Image, b: &ircache_image::Image) -> (f64, f64) {
    use ircache_image::blur::gaussian_blur;
    let m = ircache_image::compare::compare(&gaussian_blur(a, 1.0), &gaussian_blur(b, 1.0))
        .expect("same size");
    (m.rel_mse_trim, m.lum_ratio)
}

/// The top-left `size × size` pixels of a screenshot: where the page shows the frame.
fn frame_in_screenshot(path: &Path, size: usize) -> ircache_image::Image {
    let full = ircache_image::read_image(path).expect("a screenshot");
    let mut image = ircache_image::Image::new(size, size);
    for y in 0..size {
        for x in 0..size {
            image.set(x, y, full.get(x, y));
        }
    }
    image
}

fn mean_abs_difference(a: &ircache_image::Image, b: &ircache_image::Image) -> f64 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| f64::from((x.r - y.r).abs() + (x.g - y.g).abs() + (x.b - y.b).abs()))
        .sum::<f64>()
        / a.pixels.len() as f64
}

#[test]
fn view_serves_converging_frames_follows_controls_and_refuses_bad_requests() {
    let dir = temp_dir("http");
    let size = 40;
    let server = serve(size);
    let port = server.port;

    let page = http(port, "GET", "/");
    assert_eq!(page.status, 200);
    assert!(page.text().contains("<img id=\"frame\""));

    // The first frame spends its budget; the mean then converges to the renderer's image.
    let (_, first, _) = frame(port, 0);
    assert_eq!(first["width"].as_u64(), Some(u64::from(size)));
    let (n, settled, png) = settle(port, 256);
    assert_eq!(settled["uncovered"].as_u64(), Some(0), "{settled}");
    let image = decode(&png, &dir, "settled.png");
    let reference = rendered(&dir, size);
    let (error, lum) = against(&image, &reference);
    assert!(
        error < 2e-3 && (lum - 1.0).abs() < 0.02,
        "blurred relMSE_trim {error}, lum {lum}"
    );

    // A finer accuracy restarts the mean and opens holes that new records fill.
    let accuracy = http(port, "POST", "/control?accuracy=0.15");
    assert_eq!(accuracy.status, 200, "{}", accuracy.text());
    let mut finer = frame(port, n);
    while finer.1["accuracy"].as_f64() != Some(0.15) {
        finer = frame(port, finer.0);
    }
    assert!(finer.1["layers"].as_u64() < Some(10), "{}", finer.1);
    assert!(
        finer.1["records"].as_u64() > settled["records"].as_u64(),
        "{}",
        finer.1
    );

    // A turn of the camera shows another image.
    let (n, settled, png) = settle(port, 16);
    let before = decode(&png, &dir, "before.png");
    assert_eq!(http(port, "POST", "/control?turn=0.4,0").status, 200);
    let view = settled["view_number"].as_u64().expect("view number");
    let mut turned = frame(port, n);
    while turned.1["view_number"].as_u64() == Some(view) || turned.1["layers"].as_u64() < Some(4) {
        turned = frame(port, turned.0);
    }
    let after = decode(&turned.2, &dir, "after.png");
    assert!(
        mean_abs_difference(&before, &after) > 0.05,
        "the view did not change"
    );

    // Bad requests: a reason, the right status, and the server carries on.
    for (method, path, status, says) in [
        ("POST", "/control?accuracy=7", 400, "(0, 1]"),
        ("POST", "/control?zoom=2", 400, "unknown control"),
        ("GET", "/control?accuracy=0.2", 405, "not allowed"),
        ("GET", "/frame?after=x", 400, "frame number"),
        ("POST", "/save", 400, "--cache"),
        ("GET", "/nothing-here", 404, "no such page"),
    ] {
        let r = http(port, method, path);
        assert_eq!(r.status, status, "{method} {path}: {}", r.text());
        assert!(r.text().contains(says), "{method} {path}: {}", r.text());
    }
    let _ = raw(port, b"\x00\x01 garbage that is not HTTP\r\n\r\n");
    assert_eq!(http(port, "GET", "/stats").status, 200);
}

/// `ircache view --gpu` splats on the GPU (lavapipe where there is no GPU): its frames converge
/// to the CPU walkthrough's image.
#[cfg(feature = "gpu")]
#[test]
fn view_on_the_gpu_converges_to_the_cpu_image() {
    let dir = temp_dir("gpu");
    let on_gpu = serve_with(24, &["--gpu"]);
    let on_cpu = serve(24);
    // The two run at their own pace: compare the images once both hold 256 layers.
    let (_, a, png_a) = settle(on_gpu.port, 256);
    let (_, _, png_b) = settle(on_cpu.port, 256);
    assert!(a["records"].as_u64() > Some(0), "{a}");
    let (error, lum) = against(
        &decode(&png_a, &dir, "a.png"),
        &decode(&png_b, &dir, "b.png"),
    );
    assert!(
        error < 2e-3 && (lum - 1.0).abs() < 0.02,
        "GPU against CPU walkthrough: blurred relMSE_trim {error}, lum {lum}"
    );
}

/// With `--cache FILE`, "save cache" appends the walkthrough's records to the file, and a
/// later walkthrough starts from them.
#[test]
fn view_saves_its_records_and_a_later_view_starts_from_them() {
    let dir = temp_dir("save");
    let file = dir.join("walk.icc");
    let file = file.to_str().expect("a UTF-8 path");
    let first = serve_with(24, &["--cache", file]);
    // Frames make records at their misses in the background: wait until sixteen frames in a
    // row made none, so that nothing is added between the count and the save.
    let (mut n, mut settled, _) = settle(first.port, 32);
    let (mut quiet, start) = (0, Instant::now());
    while quiet < 16 {
        let next = frame(first.port, n);
        quiet = if next.1["new_records"].as_u64() == Some(0)
            && next.1["records"] == settled["records"]
        {
            quiet + 1
        } else {
            0
        };
        (n, settled) = (next.0, next.1);
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "never quiet: {settled}"
        );
    }
    let made = settled["records"].as_u64().expect("records");
    let saved = http(first.port, "POST", "/save");
    assert_eq!(saved.status, 200, "{}", saved.text());
    assert_eq!(saved.text(), format!("saved {made} records"));
    // Nothing new to save the second time.
    assert_eq!(http(first.port, "POST", "/save").text(), "saved 0 records");
    drop(first);

    let second = serve_with(24, &["--cache", file]);
    let (_, stats, _) = frame(second.port, 0);
    assert!(
        stats["records"].as_u64() >= Some(made) && stats["new_records"].as_u64() == Some(0),
        "the second walkthrough did not start from the saved records: {stats}"
    );
}

fn chromium() -> Option<PathBuf> {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .find_map(|name| {
            std::env::var_os("PATH").and_then(|paths| {
                std::env::split_paths(&paths)
                    .map(|p| p.join(name))
                    .find(|p| p.is_file())
            })
        })
}

/// Why a browser run gave no page: it did not exit within its wall-clock limit.
struct BrowserHung(String);

/// Loads `url` in headless Chromium for `budget_ms` of virtual time; `what` is `--dump-dom` or
/// `--screenshot=FILE`. Returns its standard output.
///
/// Chromium runs in its own process group with a fresh profile, its output in files rather than
/// pipes (a helper process that outlives the browser, such as the crash handler, would otherwise
/// hold a pipe open forever), without the background networking a closed network refuses or
/// drops, and under a wall-clock limit after which the whole group is killed; a run that hangs
/// is tried again, twice.
fn browse(
    browser: &Path,
    dir: &Path,
    url: &str,
    what: &str,
    budget_ms: u32,
) -> Result<String, BrowserHung> {
    // Now and then (a few per cent of runs here) a headless Chromium never ends its virtual
    // time; a fresh one goes through.
    let mut hung = Vec::new();
    for _ in 0..3 {
        match browse_once(browser, dir, url, what, budget_ms) {
            Ok(out) => return Ok(out),
            Err(BrowserHung(why)) => hung.push(why),
        }
    }
    Err(BrowserHung(hung.join("\n")))
}

/// One Chromium run of [`browse`], killed after 45 s of wall time (a normal one takes 1–7 s).
fn browse_once(
    browser: &Path,
    dir: &Path,
    url: &str,
    what: &str,
    budget_ms: u32,
) -> Result<String, BrowserHung> {
    use std::os::unix::process::CommandExt;
    let profile = dir.join("chromium-profile");
    let _ = std::fs::remove_dir_all(&profile);
    let out_path = dir.join("chromium.out");
    let err_path = dir.join("chromium.err");
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-dev-shm-usage",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-crash-reporter",
            "--disable-breakpad",
            "--hide-scrollbars",
            "--window-size=400,300",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--virtual-time-budget={budget_ms}"))
        .arg(what)
        .arg(url)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out_path).expect("chromium.out"))
        .stderr(std::fs::File::create(&err_path).expect("chromium.err"))
        .process_group(0)
        .spawn()
        .expect("chromium runs");
    let limit = Duration::from_secs(45);
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("chromium's status") {
            break Some(status);
        }
        if start.elapsed() > limit {
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    // Whatever the browser left running goes with it.
    let _ = Command::new("kill")
        .args(["-KILL", "--", &format!("-{}", child.id())])
        .stderr(Stdio::null())
        .status();
    let _ = child.wait();
    let stderr = std::fs::read_to_string(&err_path).unwrap_or_default();
    let Some(status) = status else {
        let tail: String = stderr.lines().rev().take(20).collect::<Vec<_>>().join("\n");
        return Err(BrowserHung(format!(
            "chromium did not exit within {limit:?} on {url}; the last of its stderr, newest first:\n{tail}"
        )));
    };
    assert!(status.success(), "chromium: {stderr}");
    Ok(std::fs::read_to_string(&out_path).unwrap_or_default())
}

#[test]
fn view_in_headless_chromium_shows_the_converged_image_and_applies_controls() {
    let Some(browser) = chromium() else {
        eprintln!(
            "SKIPPED view_in_headless_chromium: no chromium on PATH (scripts/setup.sh installs \
             Debian's chromium)"
        );
        return;
    };
    match page_in_chromium(&browser) {
        Ok(()) => {}
        // A browser that hangs says nothing about the page; where the environment lets Chromium
        // hang, the test reports it and passes unless IRCACHE_REQUIRE_BROWSER is set (sessions set
        // it; what hangs is shown either way).
        Err(BrowserHung(why)) if std::env::var_os("IRCACHE_REQUIRE_BROWSER").is_none() => {
            eprintln!("SKIPPED view_in_headless_chromium: {why}");
        }
        Err(BrowserHung(why)) => panic!("{why}"),
    }
}

fn page_in_chromium(browser: &Path) -> Result<(), BrowserHung> {
    let dir = temp_dir("browser");
    let size = 48;
    let server = serve(size);
    let base = format!("http://127.0.0.1:{}/", server.port);

    // The page shows frames and their figures; controls in the fragment go through the page's
    // own control path (the slider's and the keys').
    let dom = browse(
        browser,
        &dir,
        &format!("{base}#accuracy=0.2&overlay=0"),
        "--dump-dom",
        4000,
    )?;
    assert!(
        dom.contains("accuracy 0.2 "),
        "the page never showed accuracy 0.2:\n{dom}"
    );
    let layers: u64 = dom
        .split("layers ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .expect("the page shows its layers");
    assert!(layers > 0);

    // Back to the default accuracy, converged: the screenshot's image is the renderer's.
    assert_eq!(
        http(server.port, "POST", "/control?accuracy=0.35").status,
        200
    );
    let start = Instant::now();
    let mut last = frame(server.port, 0);
    while last.1["accuracy"].as_f64() != Some(0.35) || last.1["layers"].as_u64() < Some(256) {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "never settled: {}",
            last.1
        );
        last = frame(server.port, last.0);
    }
    let shot = dir.join("shot.png");
    browse(
        browser,
        &dir,
        &base,
        &format!("--screenshot={}", shot.display()),
        3000,
    )?;
    let image = frame_in_screenshot(&shot, size as usize);
    let (error, lum) = against(&image, &rendered(&dir, size));
    assert!(
        error < 2e-3 && (lum - 1.0).abs() < 0.02,
        "screenshot: blurred relMSE_trim {error}, lum {lum}"
    );

    // A camera turn sent by the page changes what it shows.
    browse(
        browser,
        &dir,
        &format!("{base}#turn=0.5,0"),
        "--dump-dom",
        2000,
    )?;
    let turned = dir.join("turned.png");
    browse(
        browser,
        &dir,
        &base,
        &format!("--screenshot={}", turned.display()),
        2000,
    )?;
    let moved = frame_in_screenshot(&turned, size as usize);
    assert!(
        mean_abs_difference(&image, &moved) > 0.05,
        "the turn did not show"
    );
    Ok(())
}

/// Options that do not apply to a walkthrough are refused with the reason, before any server
/// starts.
#[test]
fn view_refuses_options_it_cannot_honour() {
    for (args, says) in [
        (&["--spp", "4"][..], "--spp does not apply"),
        (&["-o", "x.exr"][..], "-o does not apply"),
        (&["--integrator", "path"][..], "ic or splat only"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_ircache"))
            .arg("view")
            .args(["--port", "0"])
            .args(args)
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{args:?}: {err}");
    }
}
