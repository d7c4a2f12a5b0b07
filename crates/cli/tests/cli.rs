//! End-to-end tests of the `ircache` binary: outputs, statistics, determinism, and bad input
//! (clear message with a location, non-zero exit, no panic, nothing written).

use ircache_testing::ScratchDir;
use std::path::Path;
use std::process::{Command, Output};

fn ircache(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ircache"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("runs")
}

/// A test's own folder under the system's temporary folder, removed when the test ends
/// (passed or not).
fn temp_dir(name: &str) -> ScratchDir {
    ScratchDir::new(&format!("cli-{name}"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn builtin_scene_renders_every_format_and_writes_stats() {
    let d = temp_dir("formats");
    for out in ["a.exr", "a.hdr", "a.png"] {
        let o = ircache(
            &[
                "render", "--spp", "1", "--width", "32", "--height", "32", "-o", out, "-q",
            ],
            &d,
        );
        assert!(o.status.success(), "{out}: {}", stderr(&o));
        assert!(std::fs::metadata(d.join(out)).unwrap().len() > 0);
    }
    let o = ircache(
        &[
            "render", "--spp", "2", "--width", "24", "--height", "16", "-o", "s.exr", "--stats",
            "s.json", "-q",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("s.json")).unwrap()).unwrap();
    assert_eq!(s["width"], 24);
    assert_eq!(s["height"], 16);
    assert_eq!(s["spp"], 2);
    assert!(s["wall_seconds"].as_f64().unwrap() > 0.0);
    // Every sample starts with a camera ray.
    assert!(s["rays"].as_u64().unwrap() >= 24 * 16 * 2);
}

#[test]
fn same_seed_same_file_other_seed_other_file() {
    let d = temp_dir("seed");
    let run = |out: &str, seed: &str, threads: &str| {
        let o = ircache(
            &[
                "render",
                "--spp",
                "4",
                "--width",
                "40",
                "--height",
                "40",
                "--seed",
                seed,
                "--threads",
                threads,
                "-o",
                out,
                "-q",
            ],
            &d,
        );
        assert!(o.status.success(), "{}", stderr(&o));
        ircache_image::read_image(&d.join(out)).unwrap()
    };
    let a = run("a.exr", "5", "2");
    let b = run("b.exr", "5", "1");
    let c = run("c.exr", "6", "2");
    assert!(a.pixels == b.pixels);
    assert!(a.pixels != c.pixels);
}

#[test]
fn direct_integrator_equals_path_at_max_depth_2() {
    // Two formulations of direct lighting with MIS draw the same random numbers in the same order:
    // their images agree exactly.
    let d = temp_dir("direct");
    for (out, extra) in [
        ("d.exr", &["--integrator", "direct"][..]),
        ("p.exr", &["--integrator", "path", "--max-depth", "2"][..]),
    ] {
        let mut args = vec![
            "render", "--spp", "4", "--width", "48", "--height", "48", "-o", out, "-q",
        ];
        args.extend(extra);
        let o = ircache(&args, &d);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let a = ircache_image::read_image(&d.join("d.exr")).unwrap();
    let b = ircache_image::read_image(&d.join("p.exr")).unwrap();
    assert!(a.pixels == b.pixels);
    assert!(a.pixels.iter().any(|p| p.g > 0.0));
}

#[test]
fn bad_input_names_the_place_and_exits_non_zero() {
    let d = temp_dir("bad");
    std::fs::write(
        d.join("bad.xml"),
        "<scene version=\"3.0.0\">\n  <shape type=\"sphre\"/>\n</scene>\n",
    )
    .unwrap();
    let o = ircache(&["render", "bad.xml", "-o", "x.exr", "-q"], &d);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("bad.xml:2:") && e.contains("sphre"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
    assert!(
        !d.join("x.exr").exists(),
        "nothing is written for a failed render"
    );

    let o = ircache(&["render", "-o", "no/such/dir/x.exr", "-q"], &d);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("no/such/dir"), "{}", stderr(&o));

    let o = ircache(&["render", "-o", "x.bmp", "-q"], &d);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("x.bmp"), "{}", stderr(&o));

    let o = ircache(&["render", "missing.xml", "-q"], &d);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("missing.xml"), "{}", stderr(&o));

    let o = ircache(&["compare", "missing.exr", "missing2.exr"], &d);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("missing.exr"), "{}", stderr(&o));
}

#[test]
fn compare_reports_zero_error_for_identical_images() {
    let d = temp_dir("compare");
    let o = ircache(
        &[
            "render", "--spp", "1", "--width", "16", "--height", "16", "-o", "a.exr", "-q",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = ircache(
        &[
            "compare",
            "a.exr",
            "a.exr",
            "--json",
            "--falsecolor",
            "e.png",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["relMSE"], 0.0);
    assert_eq!(j["lum_ratio"], 1.0);
    assert!(d.join("e.png").exists());
}

#[test]
fn ic_render_reports_the_cache_and_writes_aovs() {
    let d = temp_dir("ic");
    let o = ircache(
        &[
            "render",
            "--integrator",
            "ic",
            "-ab",
            "1",
            "-aa",
            "0.3",
            "-ad",
            "64",
            "-av",
            "0.01",
            "0.01",
            "0.01",
            "--spp",
            "2",
            "--width",
            "48",
            "--height",
            "48",
            "-o",
            "ic.exr",
            "--stats",
            "ic.json",
            "--aov",
            "irradiance,records",
            "-q",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("ic.json")).unwrap()).unwrap();
    let records = s["records"].as_u64().unwrap();
    assert!(records > 10, "{s}");
    assert!(s["records_computed"].as_u64().unwrap() >= records);
    assert!(s["gather_rays"].as_u64().unwrap() >= records * 60);
    assert_eq!(s["cache_params"]["accuracy"].as_str().unwrap(), "0.3");
    for f in ["ic-irradiance.exr", "ic-records.exr"] {
        assert!(std::fs::metadata(d.join(f)).unwrap().len() > 0, "{f}");
    }
    // The glossy AOV shows radiance records: without them, an error, not a black image.
    let o = ircache(
        &[
            "render",
            "--integrator",
            "ic",
            "--aov",
            "glossy",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "-o",
            "g.exr",
            "-q",
        ],
        &d,
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--radiance-cache on"), "{}", stderr(&o));
    // Cache options with another integrator are an error, not ignored.
    let o = ircache(
        &[
            "render",
            "--integrator",
            "path",
            "-aa",
            "0.1",
            "-o",
            "x.exr",
        ],
        &d,
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("ic integrator"), "{}", stderr(&o));
    // A bad value names the option.
    let o = ircache(
        &[
            "render",
            "--integrator",
            "ic",
            "--accuracy",
            "5",
            "-o",
            "x.exr",
        ],
        &d,
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--accuracy"), "{}", stderr(&o));
}

/// Runs `ircache irradiance` on the built-in Cornell box with `points` on standard input.
fn irradiance(args: &[&str], points: &str) -> Output {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_ircache"))
        .arg("irradiance")
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("runs");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(points.as_bytes())
        .unwrap();
    child.wait_with_output().unwrap()
}

fn numbers(o: &Output) -> Vec<Vec<f64>> {
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| l.split_whitespace().map(|t| t.parse().unwrap()).collect())
        .collect()
}

#[test]
fn irradiance_at_points_cache_agrees_with_brute_force() {
    // Floor (y = 0), a point in mid-air and one on the red wall of the built-in Cornell box.
    let points = "-0.5 0 0.5 0 1 0\n0.5 0 -0.5 0 1 0\n# comment\n\n0 1 0 0 1 0\n-0.99 1 0 1 0 0\n";
    let cache = irradiance(
        &["--indirect-only", "--print-gradients", "-ad", "4096"],
        points,
    );
    assert!(cache.status.success(), "{}", stderr(&cache));
    let brute = irradiance(
        &[
            "--indirect-only",
            "--integrator",
            "path",
            "--samples",
            "16384",
        ],
        points,
    );
    assert!(brute.status.success(), "{}", stderr(&brute));
    let (c, b) = (numbers(&cache), numbers(&brute));
    assert_eq!(c.len(), 4);
    assert!(c.iter().all(|l| l.len() == 3 + 18));
    assert!(b.iter().all(|l| l.len() == 3));
    for (lc, lb) in c.iter().zip(&b) {
        let max = lb[0].max(lb[1]).max(lb[2]);
        for ch in 0..3 {
            assert!(
                (lc[ch] - lb[ch]).abs() <= 0.08 * lb[ch] + 0.02 * max + 1e-5,
                "cache {lc:?} vs brute force {lb:?}"
            );
        }
    }
    // Total irradiance exceeds the indirect part; --lux prints one number per point.
    let total = numbers(&irradiance(&[], points));
    let lux = numbers(&irradiance(&["--lux"], points));
    for ((t, i), l) in total.iter().zip(&c).zip(&lux) {
        assert!(t[0] >= i[0]);
        assert_eq!(l.len(), 1);
        let expect = 179.0 * (0.265 * t[0] + 0.670 * t[1] + 0.065 * t[2]);
        assert!((l[0] - expect).abs() <= 1e-4 * expect.max(1e-6));
    }
    // Bad input names the line.
    let bad = irradiance(&[], "0 0 0 0 1 0\n1 2 3 4 5\n");
    assert!(!bad.status.success());
    assert!(stderr(&bad).contains("<stdin>:2"), "{}", stderr(&bad));
    assert!(!stderr(&bad).contains("panicked"));
}

#[test]
fn irrcache_integrator_in_xml_takes_parameters_and_refuses_unknown_ones() {
    let d = temp_dir("irrcache-xml");
    let scene = |params: &str| {
        format!(
            r#"<scene version="3.0.0">
  <integrator type="irrcache">
    <integer name="max_depth" value="3"/>
    {params}
  </integrator>
  <sensor type="perspective"><float name="fov" value="80"/>
    <transform name="to_world"><lookat origin="0.5,0.05,0.5" target="0.5,0.9,0.3" up="0,0,1"/></transform>
    <sampler type="independent"><integer name="sample_count" value="1"/></sampler>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film>
  </sensor>
  <shape type="cube"><transform name="to_world"><scale value="0.5"/><translate value="0.5,0.5,0.5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
  <emitter type="point"><point name="position" value="0.5,0.5,0.8"/><rgb name="intensity" value="1"/></emitter>
</scene>"#
        )
    };
    std::fs::write(
        d.join("good.xml"),
        scene(r#"<float name="accuracy" value="0.3"/><integer name="divisions" value="64"/>"#),
    )
    .unwrap();
    let o = ircache(
        &[
            "render", "good.xml", "-o", "g.exr", "--stats", "g.json", "-q",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("g.json")).unwrap()).unwrap();
    assert_eq!(s["cache_params"]["divisions"], "64");
    assert_eq!(s["cache_params"]["bounces"], "1");
    std::fs::write(
        d.join("bad.xml"),
        scene(r#"<float name="acuracy" value="0.3"/>"#),
    )
    .unwrap();
    let o = ircache(&["render", "bad.xml", "-o", "b.exr"], &d);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("bad.xml:4:") && e.contains("acuracy"), "{e}");
}

/// A small lit room whose camera and wall colour are scene parameters.
fn room_xml() -> &'static str {
    r#"<scene version="3.0.0">
  <default name="eye" value="0.5,0.1,0.5"/>
  <default name="wall" value="0.6"/>
  <integrator type="irrcache"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><float name="fov" value="70"/>
    <transform name="to_world"><lookat origin="$eye" target="0.5,0.9,0.4" up="0,0,1"/></transform>
    <sampler type="independent"><integer name="sample_count" value="2"/></sampler>
    <film type="hdrfilm"><integer name="width" value="48"/><integer name="height" value="48"/></film>
  </sensor>
  <shape type="cube"><transform name="to_world"><scale value="0.5"/><translate value="0.5,0.5,0.5"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="$wall"/></bsdf></bsdf></shape>
  <shape type="cube"><transform name="to_world"><scale value="0.1"/><translate value="0.3,0.6,0.1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf></shape>
  <emitter type="point"><point name="position" value="0.5,0.5,0.8"/><rgb name="intensity" value="1"/></emitter>
</scene>"#
}

fn stats_of(d: &Path, name: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(d.join(name)).unwrap()).unwrap()
}

#[test]
fn cache_file_is_reused_across_runs_and_views_and_refused_when_stale() {
    let d = temp_dir("cache-file");
    std::fs::write(d.join("room.xml"), room_xml()).unwrap();
    let render = |out: &str, extra: &[&str]| {
        let mut args = vec![
            "render", "room.xml", "--cache", "room.icc", "-ad", "128", "-o", out, "--stats",
        ];
        let stats = format!("{out}.json");
        args.push(&stats);
        args.push("-q");
        args.extend_from_slice(extra);
        ircache(&args, &d)
    };
    let o = render("a.exr", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let first = stats_of(&d, "a.exr.json");
    let made = first["records_computed"].as_u64().unwrap();
    assert!(made > 50);
    assert_eq!(first["records_loaded"], 0);
    // The same view again: everything comes from the file, the same image.
    let o = render("b.exr", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let again = stats_of(&d, "b.exr.json");
    assert_eq!(again["records_loaded"].as_u64().unwrap(), made);
    assert!(again["records_computed"].as_u64().unwrap() * 20 <= made);
    assert_eq!(
        std::fs::read(d.join("a.exr")).unwrap(),
        std::fs::read(d.join("b.exr")).unwrap()
    );
    // Another view of the same room computes far fewer than it would alone.
    let o = render("c.exr", &["-D", "eye=0.2,0.15,0.6"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let reused = stats_of(&d, "c.exr.json")["records_computed"]
        .as_u64()
        .unwrap();
    let o = ircache(
        &[
            "render",
            "room.xml",
            "-ad",
            "128",
            "-D",
            "eye=0.2,0.15,0.6",
            "-o",
            "fresh.exr",
            "--stats",
            "fresh.json",
            "-q",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let alone = stats_of(&d, "fresh.json")["records_computed"]
        .as_u64()
        .unwrap();
    assert!(
        reused * 2 < alone,
        "{reused} with the file vs {alone} alone"
    );
    // Other settings or another scene: refused with the reason, nothing written.
    let o = render("x.exr", &["-aa", "0.25"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("accuracy 0.3 (now 0.25)") && e.contains("--cache-reuse force"),
        "{e}"
    );
    assert!(!d.join("x.exr").exists());
    let o = render("y.exr", &["-D", "wall=0.7"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("another scene"), "{}", stderr(&o));
    // Forced: used anyway.
    let o = render("z.exr", &["-aa", "0.3", "--cache-reuse", "force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stats_of(&d, "z.exr.json")["records_loaded"]
            .as_u64()
            .unwrap()
            >= made
    );
    // What the file holds.
    let o = ircache(&["cache", "info", "room.icc"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let info = String::from_utf8_lossy(&o.stdout);
    assert!(
        info.contains("divisions 128") && info.contains("records"),
        "{info}"
    );
}

/// In media, the surface records and the volumetric records go to the cache file and come
/// back from it: a second render gathers nothing and gives the same image; other media
/// settings are refused.
#[test]
fn cache_file_holds_the_records_of_a_media_scene() {
    let d = temp_dir("cache-file-media");
    let scene = ircache_testing::project_scenes().join("cornell-fog/scene.xml");
    let scene = scene.to_str().unwrap();
    let render = |out: &str, extra: &[&str]| {
        let stats = format!("{out}.json");
        let mut args = vec![
            "render",
            scene,
            "--integrator",
            "ic",
            "--spp",
            "2",
            "--width",
            "24",
            "--height",
            "24",
            "--media-divisions",
            "32",
            "--media-volume-divisions",
            "16",
            "--cache",
            "fog.icc",
            "-o",
            out,
            "--stats",
            &stats,
            "-q",
        ];
        args.extend_from_slice(extra);
        ircache(&args, &d)
    };
    let o = render("a.exr", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let first = stats_of(&d, "a.exr.json");
    let (surface, volume) = (
        first["media_cache"]["records_computed"].as_u64().unwrap(),
        first["volume_records"]["records_computed"]
            .as_u64()
            .unwrap(),
    );
    assert!(surface > 10 && volume > 10, "{surface} {volume}");
    let o = render("b.exr", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let again = stats_of(&d, "b.exr.json");
    assert_eq!(
        again["media_cache"]["records_loaded"].as_u64().unwrap(),
        surface
    );
    assert_eq!(
        again["volume_records"]["records_loaded"].as_u64().unwrap(),
        volume
    );
    assert_eq!(again["media_cache"]["records_computed"], 0);
    assert_eq!(again["volume_records"]["records_computed"], 0);
    assert_eq!(
        std::fs::read(d.join("a.exr")).unwrap(),
        std::fs::read(d.join("b.exr")).unwrap()
    );
    let o = ircache(&["cache", "info", "fog.icc"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let info = String::from_utf8_lossy(&o.stdout);
    assert!(
        info.contains(&format!("volumetric       {volume} records")),
        "{info}"
    );
    let o = render("x.exr", &["--media-deeper-paths", "2"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("media_deeper_paths 4 (now 2)"),
        "{}",
        stderr(&o)
    );
}

/// In media, the cache's settings its records do not read, and extra images, are refused by
/// name rather than ignored, as the media's own settings are in a scene without media; the
/// caustic map is made where asked, and reported.
#[test]
fn media_scenes_refuse_what_their_cache_ignores() {
    let d = temp_dir("media-settings");
    let scene = ircache_testing::project_scenes().join("glass-in-fog/scene.xml");
    let scene = scene.to_str().unwrap();
    let render_in = |scene: &str, extra: &[&str]| {
        let mut args = vec![
            "render",
            scene,
            "--integrator",
            "ic",
            "--spp",
            "1",
            "--width",
            "12",
            "--height",
            "12",
            "--media-divisions",
            "16",
            "--media-volume-divisions",
            "16",
            "-o",
            "x.exr",
            "--stats",
            "x.json",
        ];
        args.extend_from_slice(extra);
        ircache(&args, &d)
    };
    let render = |extra: &[&str]| render_in(scene, extra);
    for (extra, named) in [
        (
            &["--photon-records", "on"][..],
            "--photon-records is not used",
        ),
        (
            &["--divisions", "64", "--supersamples", "8"][..],
            "--divisions, --supersamples are not used",
        ),
        (&["--aov", "irradiance"][..], "--aov irradiance"),
    ] {
        let o = render(extra);
        assert!(!o.status.success(), "{extra:?} was accepted");
        assert!(stderr(&o).contains(named), "{extra:?}: {}", stderr(&o));
    }
    // And the media's own settings in a scene without media (the built-in Cornell box).
    let o = ircache(
        &[
            "render",
            "--integrator",
            "ic",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "--media-march",
            "4",
            "-o",
            "y.exr",
        ],
        &d,
    );
    assert!(!o.status.success(), "--media-march accepted without media");
    assert!(
        stderr(&o).contains("--media-march is for scenes with participating media"),
        "{}",
        stderr(&o)
    );
    let o = render(&["--caustic-photons", "2000", "--photons", "3000"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("Caustic map: "), "{}", stderr(&o));
    assert!(stderr(&o).contains("Global map: "), "{}", stderr(&o));
    let stats = stats_of(&d, "x.json");
    for (map, wanted) in [("caustic_map", 2000), ("global_map", 3000)] {
        assert!(
            stats["media_cache"][map]["stored"]
                .as_u64()
                .is_some_and(|n| n >= wanted),
            "{stats}"
        );
    }
    // Photons leave the lights alone: where a medium emits, a global map is refused.
    let text = std::fs::read_to_string(scene).unwrap().replace(
        "<float name=\"sigma_t\" value=\"1\" />",
        "<float name=\"sigma_t\" value=\"1\" /><rgb name=\"emission\" value=\"0.1\" />",
    );
    assert!(text.contains("emission"));
    std::fs::write(d.join("emitting.xml"), text).unwrap();
    let o = render_in("emitting.xml", &["--photons", "1000"]);
    assert!(
        !o.status.success(),
        "a global map in emitting media was accepted"
    );
    assert!(stderr(&o).contains("whose media emit"), "{}", stderr(&o));
}

#[test]
fn four_processes_share_one_cache_file_on_disjoint_tiles() {
    let d = temp_dir("shared-cache");
    std::fs::write(d.join("room.xml"), room_xml()).unwrap();
    let base = [
        "render",
        "room.xml",
        "-ad",
        "512",
        "--width",
        "64",
        "--height",
        "64",
        "--spp",
        "4",
        "-q",
        "--threads",
        "1",
    ];
    // Four processes at once, one band each, one cache file.
    let children: Vec<_> = (0..4)
        .map(|i| {
            let tile = format!("{i}/4");
            let (out, stats) = (format!("t{i}.exr"), format!("t{i}.json"));
            Command::new(env!("CARGO_BIN_EXE_ircache"))
                .args(base)
                .args([
                    "--tile",
                    &tile,
                    "--cache",
                    "shared.icc",
                    "-o",
                    &out,
                    "--stats",
                    &stats,
                ])
                .current_dir(&d)
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let (mut computed, mut from_others) = (0, 0);
    for (i, c) in children.into_iter().enumerate() {
        let o = c.wait_with_output().unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        let s = stats_of(&d, &format!("t{i}.json"));
        computed += s["records_computed"].as_u64().unwrap();
        from_others += s["records_from_others"].as_u64().unwrap();
    }
    // The processes took in each other's records while they ran.
    assert!(from_others > 0, "no process read another's records");
    // The file holds every record, none torn or corrupt.
    let o = ircache(&["cache", "info", "shared.icc"], &d);
    let info = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        info.contains(&format!("records          {computed} ")),
        "{computed}: {info}"
    );
    assert!(!info.contains("torn"), "{info}");
    // One process alone.
    let o = ircache(
        &[&base[..], &["-o", "single.exr", "--stats", "single.json"]].concat(),
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let single = stats_of(&d, "single.json")["records_computed"]
        .as_u64()
        .unwrap();
    assert!(
        computed as f64 <= 1.3 * single as f64,
        "{computed} records by four processes vs {single} by one"
    );
    // The bands sum to the single-process image.
    let o = ircache(
        &[
            "merge",
            "t0.exr",
            "t1.exr",
            "t2.exr",
            "t3.exr",
            "-o",
            "merged.exr",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = ircache(&["compare", "merged.exr", "single.exr", "--json"], &d);
    let m: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let (e, lum) = (
        m["relMSE_trim"].as_f64().unwrap(),
        m["lum_ratio"].as_f64().unwrap(),
    );
    assert!(
        e < 2e-3 && (lum - 1.0).abs() < 0.01,
        "relMSE_trim {e}, lum ratio {lum}"
    );
}

/// A room whose floor has a bumpy normal map (or none), lit by a point light.
fn bumpy_room_xml(bumpy: bool) -> String {
    let floor_bsdf = r#"<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></bsdf>"#;
    let floor_bsdf = if bumpy {
        format!(
            r#"<bsdf type="normalmap"><texture name="normalmap" type="bitmap"><string name="filename" value="bumps.exr"/><boolean name="raw" value="true"/></texture>{floor_bsdf}</bsdf>"#
        )
    } else {
        floor_bsdf.to_string()
    };
    format!(
        r#"<scene version="3.0.0">
  <integrator type="irrcache"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><float name="fov" value="70"/>
    <transform name="to_world"><lookat origin="0.5,0.05,0.6" target="0.5,0.8,0.0" up="0,0,1"/></transform>
    <sampler type="independent"><integer name="sample_count" value="2"/></sampler>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/></film>
  </sensor>
  <shape type="cube"><transform name="to_world"><scale value="0.5"/><translate value="0.5,0.5,0.5"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.2"/></bsdf></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.499"/><translate value="0.5,0.5,0.001"/></transform>
    {floor_bsdf}</shape>
  <emitter type="point"><point name="position" value="0.3,0.5,0.8"/><rgb name="intensity" value="1"/></emitter>
</scene>"#
    )
}

#[test]
fn normal_maps_reach_the_cache_through_the_rotation_gradient_not_more_records() {
    // 003 item 5: records use the unperturbed normal, so a bumpy floor takes about as many
    // records as a flat one; the bumps still show, through direct light and the rotation
    // gradient.
    let d = temp_dir("bumps");
    // Tangent-space normals tilted up to ~35° in a 16×16 pattern.
    let (w, h) = (64usize, 64usize);
    let mut img = ircache_image::Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
            let t = 0.7 * (u * 16.0 * std::f32::consts::TAU).sin();
            let s = 0.7 * (v * 16.0 * std::f32::consts::TAU).cos();
            let n = ircache_math::Vec3::new(t, s, 1.0).normalize();
            img.set(
                x,
                y,
                ircache_math::Rgb::new(0.5 * n.x + 0.5, 0.5 * n.y + 0.5, 0.5 * n.z + 0.5),
            );
        }
    }
    ircache_image::write_image(&d.join("bumps.exr"), &img, 0.0).unwrap();
    std::fs::write(d.join("flat.xml"), bumpy_room_xml(false)).unwrap();
    std::fs::write(d.join("bumpy.xml"), bumpy_room_xml(true)).unwrap();
    let run = |scene: &str, extra: &[&str]| {
        let stats = format!("{scene}{}.json", extra.len());
        let out = format!("{scene}{}.exr", extra.len());
        let o = ircache(
            &[
                &[
                    "render", scene, "-ad", "128", "-o", &out, "--stats", &stats, "-q",
                ][..],
                extra,
            ]
            .concat(),
            &d,
        );
        assert!(o.status.success(), "{}", stderr(&o));
        (
            stats_of(&d, &stats)["records"].as_u64().unwrap() as f64,
            ircache_image::read_image(&d.join(out)).unwrap(),
        )
    };
    let (flat, flat_img) = run("flat.xml", &[]);
    let (bumpy, bumpy_img) = run("bumpy.xml", &[]);
    assert!(
        (bumpy - flat).abs() <= 0.1 * flat,
        "{bumpy} records on the bumpy floor vs {flat} on the flat one"
    );
    // The bumps show.
    let diff: f32 = flat_img
        .pixels
        .iter()
        .zip(&bumpy_img.pixels)
        .map(|(a, b)| (a.luminance() - b.luminance()).abs())
        .sum::<f32>()
        / flat_img.pixels.len() as f32;
    let mean: f32 =
        flat_img.pixels.iter().map(|p| p.luminance()).sum::<f32>() / flat_img.pixels.len() as f32;
    assert!(diff > 0.02 * mean, "{diff} vs mean {mean}");
    // And through the cache: the indirect irradiance image differs on the floor.
    run("flat.xml", &["--aov", "irradiance"]);
    run("bumpy.xml", &["--aov", "irradiance"]);
    let fe = ircache_image::read_image(&d.join("flat.xml2-irradiance.exr")).unwrap();
    let be = ircache_image::read_image(&d.join("bumpy.xml2-irradiance.exr")).unwrap();
    let ediff: f32 = fe
        .pixels
        .iter()
        .zip(&be.pixels)
        .map(|(a, b)| (a.luminance() - b.luminance()).abs())
        .sum();
    let esum: f32 = fe.pixels.iter().map(|p| p.luminance()).sum();
    assert!(
        ediff > 0.01 * esum,
        "the irradiance did not follow the bumps: {ediff} of {esum}"
    );
}

#[test]
fn unbounded_depth_and_other_renderers_integrators() {
    let d = temp_dir("unbounded");
    let small = [
        "render", "--spp", "2", "--width", "24", "--height", "24", "-q", "-o",
    ];
    // max_depth -1 with the cache: unbounded bounces, the deeper ones path-traced (an OBJ scene
    // has no max_depth either).
    let o = ircache(&[&small[..], &["u.exr", "-D", "max_depth=-1"]].concat(), &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = ircache_image::read_image(&d.join("u.exr")).unwrap();
    assert!(img.pixels.iter().all(|p| p.is_valid_radiance()));
    // … but not with one cache per bounce level: said, not silently one bounce.
    let o = ircache(
        &[
            &small[..],
            &["c.exr", "-D", "max_depth=-1", "--deeper-bounces", "cache"],
        ]
        .concat(),
        &d,
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("unbounded"), "{}", stderr(&o));
    // A scene naming another renderer's integrator loads; rendering with it is the error, with
    // where it was written, and naming ours on the command line renders.
    let o = ircache(
        &[&small[..], &["f.exr", "-D", "integrator=foo"]].concat(),
        &d,
    );
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("\"foo\" not found") && stderr(&o).contains(".xml:"),
        "{}",
        stderr(&o)
    );
    let o = ircache(
        &[
            &small[..],
            &["p.exr", "-D", "integrator=foo", "--integrator", "path"],
        ]
        .concat(),
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
}

/// `--radiance-cache on` on the repository's moderately glossy Cornell box: radiance records are
/// made, reported, written to a cache file and read back from it, and shown by the glossy AOV.
#[test]
fn radiance_cache_renders_reports_and_reuses_its_records() {
    let d = temp_dir("radiance");
    let scene = ircache_testing::project_scenes().join("cornell-rough/scene.xml");
    let scene = scene.to_str().unwrap();
    let args = |out: &str, stats: &str| -> Vec<String> {
        one_bounce_at_32(
            scene,
            &[
                "--radiance-cache",
                "on",
                "--cache",
                "rough.icc",
                "--aov",
                "glossy",
            ],
            out,
            stats,
        )
    };
    let first = args("a.exr", "a.json");
    let o = ircache(&first.iter().map(String::as_str).collect::<Vec<_>>(), &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let read = |f: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join(f)).unwrap()).unwrap()
    };
    let a = read("a.json");
    let radiance = a["radiance_records"].as_u64().unwrap();
    assert!(radiance > 0, "{a}");
    let glossy = ircache_image::read_image(&d.join("a-glossy.exr")).unwrap();
    assert!(glossy.pixels.iter().any(|p| p.g > 0.0));
    let second = args("b.exr", "b.json");
    let o = ircache(&second.iter().map(String::as_str).collect::<Vec<_>>(), &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let b = read("b.json");
    assert_eq!(b["records_computed"].as_u64(), Some(0), "{b}");
    assert!(b["radiance_records"].as_u64().unwrap() >= radiance, "{b}");
}

/// `ircache render scene` with `ic`, one bounce, 1 spp at 32 × 32, writing `out` and `stats`,
/// with `extra` arguments.
fn one_bounce_at_32(scene: &str, extra: &[&str], out: &str, stats: &str) -> Vec<String> {
    [
        "render",
        scene,
        "--integrator",
        "ic",
        "-ab",
        "1",
        "--spp",
        "1",
        "--width",
        "32",
        "--height",
        "32",
        "-o",
        out,
        "--stats",
        stats,
        "-q",
    ]
    .iter()
    .chain(extra)
    .map(|s| s.to_string())
    .collect()
}

/// `--radiance-cache auto`, the default, caches the lobes that reflect much of the light: on
/// cornell-rough its rough metals (aluminium walls, the tall box) get radiance records; on
/// cornell-glossy, whose one cacheable lobe is a plastic's coating, there are none.
#[test]
fn automatic_radiance_caching_takes_metals_and_leaves_coatings() {
    let d = temp_dir("radiance-auto");
    let radiance_records = |scene: &str, stats: &str| -> (u64, String) {
        let args = one_bounce_at_32(scene, &[], "x.exr", stats);
        let o = ircache(&args.iter().map(String::as_str).collect::<Vec<_>>(), &d);
        assert!(o.status.success(), "{}", stderr(&o));
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join(stats)).unwrap()).unwrap();
        (
            s["radiance_records"].as_u64().unwrap(),
            s["cache_params"]["radiance_cache"]
                .as_str()
                .unwrap()
                .to_string(),
        )
    };
    let rough = ircache_testing::project_scenes().join("cornell-rough/scene.xml");
    let rough = rough.to_str().unwrap();
    let (metals, mode) = radiance_records(rough, "rough.json");
    assert_eq!(mode, "auto");
    assert!(metals > 0, "cornell-rough: {metals} radiance records");
    let glossy = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/scenes/cornell-glossy/scene.xml"
    );
    let (coatings, _) = radiance_records(glossy, "glossy.json");
    assert_eq!(coatings, 0, "cornell-glossy: radiance records");
}

/// Whether a `--gpu` run found no device and `IRCACHE_GPU_TESTS=skip` lets the test skip
/// (saying so); otherwise the test goes on and fails on the run's error.
fn skipped_without_gpu(run: &Output) -> bool {
    let skip = !run.status.success()
        && stderr(run).contains("no GPU device")
        && std::env::var("IRCACHE_GPU_TESTS").as_deref() == Ok("skip");
    if skip {
        eprintln!("SKIPPED (IRCACHE_GPU_TESTS=skip): {}", stderr(run));
    }
    skip
}

/// `--gpu` on Sponza under its sun: the whole frame on the GPU (rasterised, splatted, shadow
/// mapped, composed; `ircache_gpu::frame`) gives the CPU splat pass's image, up to its other
/// sampling of the pixels (R₂ offsets against the sampler's) and its records gathered at misses
/// (the GPU frame serves those samples at thresholds 2 and 4), and the loaders' notes.
#[cfg(feature = "gpu")]
#[test]
fn the_whole_frame_on_the_gpu_renders_the_splat_pass_image() {
    let d = temp_dir("gpu-frame");
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/scenes/sponza-sun/scene.xml"
    );
    let base = [
        "render",
        scene,
        "--integrator",
        "splat",
        "--spp",
        "4",
        "--width",
        "96",
        "--height",
        "72",
    ];
    let run = |extra: &[&str]| ircache(&[&base[..], extra].concat(), &d);
    let gpu = run(&["--gpu", "-o", "gpu.exr"]);
    if skipped_without_gpu(&gpu) {
        return;
    }
    assert!(gpu.status.success(), "{}", stderr(&gpu));
    let said = stderr(&gpu);
    assert!(said.contains("the whole frame on the GPU"), "{said}");
    assert!(said.contains("degenerate"), "the loader's note: {said}");
    let cpu = run(&["-q", "-o", "cpu.exr"]);
    assert!(cpu.status.success(), "{}", stderr(&cpu));
    let o = ircache(
        &["compare", "gpu.exr", "cpu.exr", "--blur", "2", "--json"],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let (rel, lum) = (
        j["relMSE_trim"].as_f64().unwrap(),
        j["lum_ratio"].as_f64().unwrap(),
    );
    eprintln!(
        "whole GPU frame against the CPU splat pass: blurred relMSE_trim {rel}, luminance {lum}"
    );
    assert!(rel < 2e-2, "blurred relMSE_trim {rel}");
    assert!((lum - 1.0).abs() < 0.03, "mean luminance ratio {lum}");
}

/// `--gpu` (the `gpu` feature, on by default): the splat integrator's image equals the CPU
/// splatter's to the GPU's rounding (on lavapipe, which `scripts/setup.sh` installs where there
/// is no GPU, bit for bit); it is refused for other integrators; without a device it says so and
/// exits non-zero. With no device at all the test fails, unless `IRCACHE_GPU_TESTS=skip`.
#[cfg(feature = "gpu")]
#[test]
fn gpu_splatting_renders_the_cpu_image_and_says_what_it_cannot_do() {
    let d = temp_dir("gpu");
    let base = [
        "render",
        "--integrator",
        "splat",
        "--spp",
        "2",
        "--width",
        "48",
        "--height",
        "48",
        "-q",
    ];
    let run = |extra: &[&str]| ircache(&[&base[..], extra].concat(), &d);
    let gpu = run(&["--gpu", "-o", "gpu.exr"]);
    if skipped_without_gpu(&gpu) {
        return;
    }
    assert!(gpu.status.success(), "{}", stderr(&gpu));
    // The Cornell box's area light is not the whole GPU frame's: it says so and splats.
    assert!(
        stderr(&gpu).contains("does not serve this scene"),
        "{}",
        stderr(&gpu)
    );
    let cpu = run(&["-o", "cpu.exr"]);
    assert!(cpu.status.success(), "{}", stderr(&cpu));
    let o = ircache(&["compare", "gpu.exr", "cpu.exr", "--json"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rel = j["relMSE"].as_f64().unwrap();
    assert!(rel < 1e-8, "GPU against CPU splatting: relMSE {rel}");

    let o = ircache(
        &[
            "render", "--gpu", "--spp", "1", "--width", "8", "--height", "8", "-o", "ic.exr",
        ],
        &d,
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--integrator splat"), "{}", stderr(&o));
    assert!(!d.join("ic.exr").exists());

    // No Vulkan driver and only Vulkan allowed: no device.
    let o = Command::new(env!("CARGO_BIN_EXE_ircache"))
        .args([&base[..], &["--gpu", "-o", "none.exr"]].concat())
        .env("VK_ICD_FILENAMES", d.join("no-such-driver.json"))
        .env("WGPU_BACKEND", "vulkan")
        .current_dir(&d)
        .output()
        .expect("runs");
    assert!(!o.status.success());
    assert!(stderr(&o).contains("no GPU device found"), "{}", stderr(&o));
    assert!(!d.join("none.exr").exists());
}

/// Under a sky (a `constant` emitter) the irradiance at points is the same whether the records
/// hold the sky (`--cached-environment all`: it is then indirect light, and the direct part
/// leaves it out) or light samples estimate it (`off`); and with `all` the indirect part holds
/// it.
#[test]
fn irradiance_at_points_under_a_sky_is_the_same_whether_the_records_hold_it() {
    let d = temp_dir("sky-points");
    let scene = d.join("sky.xml");
    std::fs::write(
        &scene,
        r#"<scene version="3.0.0">
  <integrator type="irrcache"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><transform name="to_world"><lookat origin="0,3,3" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
  <shape type="cube"><transform name="to_world"><scale value="0.5"/><translate value="0,0.5,0"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></shape>
  <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>
</scene>"#,
    )
    .unwrap();
    let scene = scene.to_str().unwrap();
    // On the floor beside the box, far from it, and on the box's side.
    let points = "0.7 0 0 0 1 0\n3 0 3 0 1 0\n0.5 0.5 0 1 0 0\n";
    let run = |environment: &str, indirect_only: bool| {
        let mut args = vec![
            scene,
            "-ad",
            "2048",
            "--direct-samples",
            "1024",
            "--cached-environment",
            environment,
        ];
        if indirect_only {
            args.push("--indirect-only");
        }
        let o = irradiance(&args, points);
        assert!(o.status.success(), "{}", stderr(&o));
        numbers(&o)
    };
    let (held, sampled) = (run("all", false), run("off", false));
    let (held_indirect, sampled_indirect) = (run("all", true), run("off", true));
    for k in 0..3 {
        let (a, b) = (held[k][1], sampled[k][1]);
        assert!(
            (a - b).abs() <= 0.03 * b,
            "point {k}: held {a} vs sampled {b}"
        );
        // The open floor point sees sky over most of its hemisphere: π·0.5 in all.
        assert!(
            held_indirect[k][1] > sampled_indirect[k][1] + 0.3,
            "point {k}"
        );
    }
    let far = held[1][1];
    assert!(
        (far - std::f64::consts::PI * 0.5).abs() < 0.03 * far,
        "open floor: {far} vs π/2"
    );
}

/// The repository's `scenes/cube-in-box`.
fn cube_in_box(file: &str) -> String {
    ircache_testing::project_scenes()
        .join("cube-in-box")
        .join(file)
        .display()
        .to_string()
}

#[test]
fn animate_writes_numbered_frames_same_seed_same_frames_and_compare_measures_them() {
    let d = temp_dir("animate");
    let anim = cube_in_box("animation.xml");
    let run = |out: &str, mode: &str| {
        ircache(
            &[
                "animate",
                &anim,
                "--frames",
                "2..4",
                "--width",
                "24",
                "--height",
                "24",
                "--spp",
                "1",
                "--cache-mode",
                mode,
                "-o",
                out,
                "-q",
                "--stats",
                "s.json",
            ],
            &d,
        )
    };
    let o = run("a-###.exr", "temporal");
    assert!(o.status.success(), "{}", stderr(&o));
    for f in 2..=4 {
        assert!(d.join(format!("a-{f:03}.exr")).is_file(), "frame {f}");
    }
    assert!(!d.join("a-001.exr").exists() && !d.join("a-005.exr").exists());
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("s.json")).unwrap()).unwrap();
    assert_eq!(s["frames"].as_array().map(Vec::len), Some(3));
    assert_eq!(s["cache_mode"], "temporal");
    assert!(s["records_gathered"].as_u64() > Some(0));
    // The same seed gives the same frames.
    let o = run("b-###.exr", "temporal");
    assert!(o.status.success(), "{}", stderr(&o));
    for f in 2..=4 {
        let a = std::fs::read(d.join(format!("a-{f:03}.exr"))).unwrap();
        let b = std::fs::read(d.join(format!("b-{f:03}.exr"))).unwrap();
        assert!(a == b, "frame {f} differs between two runs");
    }
    for mode in ["age", "per-frame"] {
        let o = run(&format!("{mode}-#.exr"), mode);
        assert!(o.status.success(), "{mode}: {}", stderr(&o));
    }
    // Adaptive sampling frame by frame: more samples than the pilot where the pixels need them,
    // at most the cap, and the same frames from the same seed.
    let adaptive = |out: &str| {
        let o = ircache(
            &[
                "animate",
                &anim,
                "--frames",
                "2..3",
                "--width",
                "24",
                "--height",
                "24",
                "--spp",
                "4",
                "--adaptive",
                "0.01",
                "--max-spp",
                "32",
                "-o",
                out,
                "-q",
                "--stats",
                "adaptive.json",
            ],
            &d,
        );
        assert!(o.status.success(), "{}", stderr(&o));
        stats_of(&d, "adaptive.json")["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["pixel_samples"].as_u64().unwrap() as f64 / (24.0 * 24.0))
            .collect::<Vec<_>>()
    };
    for mean in adaptive("ad-#.exr") {
        assert!(mean > 4.5 && mean <= 32.0, "mean spp {mean}");
    }
    adaptive("ae-#.exr");
    for f in 2..=3 {
        let a = std::fs::read(d.join(format!("ad-{f}.exr"))).unwrap();
        let b = std::fs::read(d.join(format!("ae-{f}.exr"))).unwrap();
        assert!(a == b, "adaptive frame {f} differs between two runs");
    }
    // A sequence against itself: no error, no high-pass error; its flicker index is positive
    // (the cube moves).
    let o = ircache(
        &[
            "compare",
            "--sequence",
            "2..4",
            "a-###.exr",
            "b-###.exr",
            "--json",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["rel_mse_trim"].as_f64(), Some(0.0));
    assert_eq!(j["high_pass_error"].as_f64(), Some(0.0));
    assert!(j["flicker_index"].as_f64() > Some(0.0));
}

#[test]
fn animate_bad_input_names_the_place() {
    let d = temp_dir("animate-bad");
    let scene = cube_in_box("scene.xml");
    let write = |name: &str, body: &str| {
        std::fs::write(d.join(name), body).unwrap();
        d.join(name).display().to_string()
    };
    let cases = [
        (
            write(
                "unknown.xml",
                &format!(
                    "<animation version=\"1\" scene=\"{scene}\" frames=\"4\">\n  <move shape=\"Teapot\">\n    <key frame=\"0\"/>\n  </move>\n</animation>\n"
                ),
            ),
            "unknown.xml:2:3",
            "no shape with id \"Teapot\"",
        ),
        (
            write(
                "order.xml",
                &format!(
                    "<animation version=\"1\" scene=\"{scene}\" frames=\"4\">\n  <move shape=\"Cube\">\n    <key frame=\"3\"/>\n    <key frame=\"1\"/>\n  </move>\n</animation>\n"
                ),
            ),
            "order.xml:4:5",
            "increasing frame order",
        ),
        (
            write(
                "turn.xml",
                &format!(
                    "<animation version=\"1\" scene=\"{scene}\" frames=\"4\">\n  <move shape=\"Cube\">\n    <key frame=\"0\" rotate=\"0 1 0 0\"/>\n    <key frame=\"3\" rotate=\"0 1 0 200\"/>\n  </move>\n</animation>\n"
                ),
            ),
            "turn.xml:4:5",
            "less than 180°",
        ),
        (
            write(
                "missing.xml",
                "<animation version=\"1\" scene=\"nowhere.xml\" frames=\"4\">\n</animation>\n",
            ),
            "missing.xml:1:1",
            "nowhere.xml",
        ),
    ];
    for (file, place, what) in cases {
        let o = ircache(&["animate", &file, "-o", "f-#.exr", "-q"], &d);
        let e = stderr(&o);
        assert!(!o.status.success(), "{file}");
        assert!(e.contains(place) && e.contains(what), "{file}: {e}");
        assert!(!e.contains("panicked"), "{e}");
        assert!(!d.join("f-0.exr").exists());
    }
    // A still scene needs --frames; an output name without # is refused before rendering.
    let o = ircache(&["animate", &scene, "-q"], &d);
    assert!(!o.status.success() && stderr(&o).contains("--frames"));
    // No scene: the built-in Cornell box, still, its frames named after it.
    let o = ircache(
        &[
            "animate", "--frames", "0..1", "--width", "8", "--height", "8", "--spp", "1", "-q",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(d.join("cornell-box-0000.exr").is_file() && d.join("cornell-box-0001.exr").is_file());
    let o = ircache(
        &["animate", &scene, "--frames", "0..1", "-o", "f.exr", "-q"],
        &d,
    );
    assert!(!o.status.success() && stderr(&o).contains("run of #"));
}

#[test]
fn rays_give_the_radiance_along_them() {
    // A light sphere of radius r and radiance L at height h over a Lambertian floor of
    // reflectance ρ: straight below it the floor's radiance is E ρ / π = L ρ r²/h² (direct light,
    // max_depth 2; aimed a hair off the floor's diagonal, an edge Embree's fast, non-robust
    // test may miss); a ray into the sphere sees L; one into empty space nothing. Radiance's units
    // and luminance (179 lm/W) with --lum; a bad line names its place.
    let d = temp_dir("rays");
    std::fs::write(
        d.join("s.rad"),
        "void light lamp\n0\n0\n3 40 20 10\nlamp sphere bulb\n0\n0\n4 0 0 2 0.25\n\
         void plastic floor_mat\n0\n0\n5 .6 .5 .4 0 0\n\
         floor_mat polygon floor\n0\n0\n12 -50 -50 0 50 -50 0 50 50 0 -50 50 0\n",
    )
    .unwrap();
    std::fs::write(
        d.join("r.txt"),
        "# from above the floor, beside the bulb, down at the point below it\n\
         1 0 1 -1 0.0005 -1\n\
         -3 0 2 1 0 0\n\
         0 0 3 0 0 1\n",
    )
    .unwrap();
    let rays = |more: &[&str]| {
        let mut args = vec!["rays", "s.rad", "-i", "r.txt", "--max-depth", "2"];
        args.extend_from_slice(more);
        ircache(&args, &d)
    };
    let o = rays(&["--samples", "256"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = numbers(&o);
    let k = 0.25f64.powi(2) / 4.0;
    for (ch, (l, rho)) in [(40.0, 0.6), (20.0, 0.5), (10.0, 0.4)]
        .into_iter()
        .enumerate()
    {
        let expected = l * rho * k;
        assert!(
            (v[0][ch] / expected - 1.0).abs() < 5e-3,
            "floor {ch}: {} against {expected}",
            v[0][ch]
        );
        assert!((v[1][ch] - l).abs() < 1e-3 * l, "bulb {ch}: {}", v[1][ch]);
        assert_eq!(v[2][ch], 0.0);
    }
    let lum = numbers(&rays(&["--samples", "16", "--lum"]));
    assert!((lum[1][0] - 179.0 * (0.265 * 40.0 + 0.670 * 20.0 + 0.065 * 10.0)).abs() < 0.1);
    std::fs::write(d.join("bad.txt"), "1 0 1 -1 0 -1\n1 2 3 0 0 0\n").unwrap();
    let o = ircache(&["rays", "s.rad", "-i", "bad.txt"], &d);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("bad.txt:2: the direction (0 0 0) has no direction"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn rpict_command_lines_read_as_they_are() {
    // rpict's view options, -x and -y and -ab: the same picture as --view, --width, --height.
    let d = temp_dir("rpict");
    let office = ircache_testing::project_scenes()
        .join("radiance-office/office.rad")
        .canonicalize()
        .unwrap();
    let office = office.to_str().unwrap();
    let a = ircache(
        &[
            "render", office, "-vth", "-vp", "2", "3", "1.2", "-vd", "0", "1", "0", "-vh", "180",
            "-vv", "180", "-x", "40", "-y", "30", "-ab", "1", "--spp", "2", "-o", "a.hdr",
        ],
        &d,
    );
    assert!(a.status.success(), "{}", stderr(&a));
    let b = ircache(
        &[
            "render",
            office,
            "--view",
            "-vth -vp 2 3 1.2 -vd 0 1 0 -vh 180 -vv 180",
            "--width",
            "40",
            "--height",
            "30",
            "--ab",
            "1",
            "--spp",
            "2",
            "-o",
            "b.hdr",
        ],
        &d,
    );
    assert!(b.status.success(), "{}", stderr(&b));
    let (ia, ib) = (
        ircache_image::read_image(&d.join("a.hdr")).unwrap(),
        ircache_image::read_image(&d.join("b.hdr")).unwrap(),
    );
    // A 180° fisheye fits 30 × 30 in 40 × 30.
    assert_eq!((ia.width, ia.height), (30, 30));
    assert_eq!(ia.pixels, ib.pixels);
}

#[test]
fn rays_through_stained_glass_match_radiance() {
    // What a ray sees through a pane whose pattern tints its transmission (Radiance's -ab 0
    // follows the pane's reflection to the lit floor: max_depth 3). Measured within 0.03 %.
    let dir = ircache_testing::project_scenes()
        .join("radiance-patterns")
        .canonicalize()
        .unwrap();
    let text = std::fs::read_to_string(dir.join("reference-stain-rays.txt")).unwrap();
    let rays: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split_whitespace().map(|w| w.parse().unwrap()).collect())
        .collect();
    let input: String = rays
        .iter()
        .map(|r| format!("{} {} {} {} {} {}\n", r[0], r[1], r[2], r[3], r[4], r[5]))
        .collect();
    let d = temp_dir("stain");
    std::fs::write(d.join("r.txt"), input).unwrap();
    let scene = dir.join("stain.rad");
    let o = ircache(
        &[
            "rays",
            scene.to_str().unwrap(),
            "-i",
            "r.txt",
            "--max-depth",
            "3",
            "--samples",
            "2048",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    for (ours, reference) in numbers(&o).iter().zip(&rays) {
        for ch in 0..3 {
            let r = reference[6 + ch];
            assert!(
                (ours[ch] / r - 1.0).abs() < 0.005,
                "{ours:?} against {reference:?}"
            );
        }
    }
}

/// `--accumulate`: in the still box every pixel is still over all eight frames, each frame
/// draws new samples, and every frame gets the mean of all eight frames' sampled light: the
/// error against a path-traced reference falls below half that of the frames rendered on their
/// own, in the first frame as in the last, and the frames flicker no more.
#[test]
fn animate_still_pixels_converge_over_the_frames() {
    let d = temp_dir("animate-accumulate");
    let still = cube_in_box("still.xml");
    let size = ["--width", "32", "--height", "32"];
    // Uniform, and adaptive (each frame's pixels take their own counts).
    let adaptive = ["--adaptive", "0.01", "--max-spp", "32"];
    let run = |out: &str, accumulate: &str, more: &[&str]| {
        let o = ircache(
            &[
                &["animate", &still, "--frames", "0..7", "--spp", "4", "-q"][..],
                &size,
                more,
                &["--accumulate", accumulate, "-o", out],
            ]
            .concat(),
            &d,
        );
        assert!(o.status.success(), "{}", stderr(&o));
    };
    run("on-#.exr", "on", &[]);
    run("off-#.exr", "off", &[]);
    run("adaptive-on-#.exr", "on", &adaptive);
    run("adaptive-off-#.exr", "off", &adaptive);
    let scene = cube_in_box("scene.xml");
    let o = ircache(
        &[
            &[
                "render",
                &scene,
                "--integrator",
                "path",
                "--spp",
                "1024",
                "-q",
            ][..],
            &size,
            &["-o", "ref.exr"],
        ]
        .concat(),
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let read = |name: &str| ircache_image::read_image(&d.join(name)).unwrap();
    let reference = read("ref.exr");
    let error = |name: &str| {
        ircache_image::compare::compare(&read(name), &reference)
            .unwrap()
            .rel_mse
    };
    for f in [0, 7] {
        let (on, off) = (
            error(&format!("on-{f}.exr")),
            error(&format!("off-{f}.exr")),
        );
        assert!(
            on < 0.5 * off,
            "frame {f}: {on} kept against {off} on its own"
        );
    }
    // The frames do not flicker more for it: what the cache gives is taken at the same samples
    // in every frame (with --adaptive, the same count), and the sampled light is the same mean
    // in all. (With --adaptive the frames on their own are near the cache's own error at this
    // size already, and whether a pixel's samples see a sliver of the lamp decides its error.)
    let flicker = |prefix: &str| {
        let frames: Vec<_> = (0..8).map(|f| read(&format!("{prefix}-{f}.exr"))).collect();
        ircache_image::flicker::flicker_index(&frames).unwrap()
    };
    for prefix in ["", "adaptive-"] {
        let (on, off) = (
            flicker(&format!("{prefix}on")),
            flicker(&format!("{prefix}off")),
        );
        assert!(
            on <= 1.2 * off,
            "{prefix}flicker index {on} kept against {off} on their own"
        );
    }
}
