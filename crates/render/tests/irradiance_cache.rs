//! The irradiance cache against analytic results: an ambient-value furnace (every record density
//! returns the exact irradiance), gradients against central finite differences of the exact
//! irradiance in a box with an opening and a black occluder near the query point (Lambert's
//! polygon form factor gives it in closed form), records against the exact value at their
//! positions, record count against accuracy, determinism and finiteness.

mod common;
use common::*;
use ircache_math::{Rgb, Vec3};
use ircache_render::integrators::Integrator;
use ircache_render::irradiance_cache::points::{irradiance_at_points, PointMethod};
use ircache_render::irradiance_cache::IcParams;
use ircache_render::scene::Scene;
use ircache_scene::*;
use std::f32::consts::PI;
use std::sync::Arc;

/// A quad from four corners in order, two-sided diffuse of albedo `rho`.
fn quad(c: [Vec3; 4], rho: f32) -> ShapeDesc {
    two_sided_quad(c, diffuse(Rgb::splat(rho)))
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// Hole in the ceiling (z = 1) of the unit box, and the black occluder, as polygons.
const HOLE: [[f32; 2]; 2] = [[0.55, 0.75], [0.4, 0.6]];
const OCCLUDER: [[f32; 2]; 2] = [[0.05, 0.2], [0.4, 0.6]];
const OCCLUDER_Z: f32 = 0.2;

fn rect_z(xr: [f32; 2], yr: [f32; 2], z: f32) -> [Vec3; 4] {
    [
        v(xr[0], yr[0], z),
        v(xr[1], yr[0], z),
        v(xr[1], yr[1], z),
        v(xr[0], yr[1], z),
    ]
}

/// The unit box (walls of albedo `rho`), with the hole and occluder when `open`, scaled by
/// `scale` (the cache must not care about units).
fn box_scene(rho: f32, open: bool, scale: f32, ic: IntegratorDesc, size: u32) -> SceneDesc {
    let mut shapes = vec![
        quad(rect_z([0.0, 1.0], [0.0, 1.0], 0.0), rho),
        quad(
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)],
            rho,
        ),
        quad(
            [v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)],
            rho,
        ),
        quad(
            [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
            rho,
        ),
        quad(
            [v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)],
            rho,
        ),
    ];
    if open {
        let [xr, yr] = HOLE;
        // Ceiling around the hole, in four pieces.
        shapes.push(quad(rect_z([0.0, xr[0]], [0.0, 1.0], 1.0), rho));
        shapes.push(quad(rect_z([xr[1], 1.0], [0.0, 1.0], 1.0), rho));
        shapes.push(quad(rect_z(xr, [0.0, yr[0]], 1.0), rho));
        shapes.push(quad(rect_z(xr, [yr[1], 1.0], 1.0), rho));
        let [ox, oy] = OCCLUDER;
        shapes.push(quad(rect_z(ox, oy, OCCLUDER_Z), 0.0));
    } else {
        shapes.push(quad(rect_z([0.0, 1.0], [0.0, 1.0], 1.0), rho));
    }
    for s in &mut shapes {
        if let Geometry::Mesh(m) = &mut s.geometry {
            for p in &mut m.positions {
                *p *= scale;
            }
        }
    }
    scene(
        sensor(
            v(0.5, 0.05, 0.5) * scale,
            v(0.5, 0.9, 0.3) * scale,
            80.0,
            size,
            1,
        ),
        ic,
        shapes,
        vec![],
    )
}

/// The open box (white, scale 1) under a uniform sky of radiance 1, one bounce, with `params`
/// more, seen at `size` pixels.
fn open_box_under_sky(params: &[(&str, &str)], size: u32) -> SceneDesc {
    let mut all = vec![("ambient_value", "1"), ("bounces", "1")];
    all.extend_from_slice(params);
    box_scene(1.0, true, 1.0, ic_desc(&all), size)
}

fn ic_desc(params: &[(&str, &str)]) -> IntegratorDesc {
    IntegratorDesc {
        kind: "ic".into(),
        // One bounce unless `bounces` is given.
        max_depth: 3,
        extra: params
            .iter()
            .map(|(k, v)| (k.to_string(), ParamValue::String(v.to_string()), here()))
            .collect(),
        ..IntegratorDesc::default()
    }
}

/// Exact indirect irradiance on the open box's floor (walls radiate ρ·av = 1, hole and occluder
/// nothing).
fn exact(x: Vec3, n: Vec3) -> f32 {
    let [hx, hy] = HOLE;
    let [ox, oy] = OCCLUDER;
    PI * (1.0
        - form_factor(x, n, &rect_z(hx, hy, 1.0))
        - form_factor(x, n, &rect_z(ox, oy, OCCLUDER_Z)))
}

fn params(list: &[(&str, &str)]) -> IcParams {
    let mut p = IcParams::default();
    for (k, val) in list {
        p.set(k, val).unwrap();
    }
    p
}

#[test]
fn furnace_any_record_density_is_exact() {
    // Closed box of albedo ρ lit only by the ambient value: every gather sample sees ρ·av, so
    // E = π ρ av at level 0 for one bounce and π ρ² av for two, at any accuracy. With one cache
    // per bounce this is exact up to f32 rounding (a few ulps per level: 1e-6 allows 8 at three
    // bounces; a gather ray that f32 rounding put on the horizon once cost 1.1e-5 here); with
    // the deeper bounces path-traced, Russian roulette makes each gather path's weight random,
    // so only the mean over the points is (nearly) exact.
    let rho = 0.7;
    let desc = box_scene(rho, false, 3.0, ic_desc(&[]), 8);
    let scene = Scene::build(&desc).unwrap();
    let queries: Vec<(Vec3, Vec3)> = (0..200)
        .map(|i| {
            let t = i as f32 / 200.0;
            (
                v(0.1 + 0.8 * t, 0.5 + 0.3 * (7.0 * t).sin(), 0.0) * 3.0,
                Vec3::Z,
            )
        })
        .collect();
    for deeper in ["cache", "traced"] {
        for bounces in ["1", "2", "3"] {
            for a in ["0.05", "0.2", "0.6", "1.5"] {
                let exact = deeper == "cache" || bounces == "1";
                // Random path weights: more rays, so that the few records of a coarse cache
                // average to within the tolerance.
                let divisions = if exact { "64" } else { "1024" };
                let p = params(&[
                    ("accuracy", a),
                    ("bounces", bounces),
                    ("ambient_value", "0.25"),
                    ("divisions", divisions),
                    ("deeper_bounces", deeper),
                ]);
                let (res, stats) =
                    irradiance_at_points(&scene, &p, &queries, PointMethod::Cache, 0, 1);
                let expect = PI * 0.25 * rho.powi(bounces.parse().unwrap());
                assert!(stats.unwrap().records() > 0);
                let mut mean = 0.0f64;
                for r in &res {
                    for c in 0..3 {
                        mean += f64::from(r.indirect[c]) / (3 * res.len()) as f64;
                        assert!(
                            !exact || (r.indirect[c] - expect).abs() <= 1e-6 * expect,
                            "a {a}, bounces {bounces}, {deeper}: {} vs {expect}",
                            r.indirect[c]
                        );
                    }
                }
                let tol = if exact { 1e-6 } else { 0.02 };
                assert!(
                    (mean / f64::from(expect) - 1.0).abs() <= tol,
                    "a {a}, bounces {bounces}, {deeper}: mean {mean} vs {expect}"
                );
            }
        }
    }
}

#[test]
fn furnace_render_is_exact() {
    // The rendered closed box: ρ/π · E = ρ² av at every pixel, whatever the scale.
    let rho = 0.6;
    for scale in [1e-3, 1.0, 1e3] {
        let desc = box_scene(
            rho,
            false,
            scale,
            ic_desc(&[
                ("ambient_value", "0.5"),
                ("bounces", "1"),
                ("divisions", "64"),
            ]),
            24,
        );
        let out = render_desc(&desc, 2, 3);
        let expect = rho * rho * 0.5;
        for p in &out.image.pixels {
            assert!(
                (p.g - expect).abs() <= 1e-5 * expect,
                "scale {scale}: {p:?}"
            );
        }
        assert!(out.cache.unwrap().stats.records() > 0);
    }
}

/// Mean of `n` brute-force gathers (gradients of the indirect part) at (x, n).
fn mean_gradients(scene: &Scene, x: Vec3, n: Vec3, seeds: u64, formula: &str) -> (f32, Vec3, Vec3) {
    let p = params(&[
        ("ambient_value", "1"),
        ("bounces", "1"),
        ("gradient_formula", formula),
    ]);
    let (mut e, mut gt, mut gr) = (0.0, Vec3::ZERO, Vec3::ZERO);
    for seed in 0..seeds {
        let (r, _) = irradiance_at_points(
            scene,
            &p,
            &[(x, n)],
            PointMethod::BruteForce { samples: 65536 },
            0,
            seed,
        );
        e += r[0].indirect.g;
        gt += r[0].grad_t[1];
        gr += r[0].grad_r[1];
    }
    let k = seeds as f32;
    (e / k, gt / k, gr / k)
}

#[test]
fn gradients_match_finite_differences_with_occluders() {
    // Each translational formula on its own (3.48 and 3.47 share their loop and differ in the
    // azimuthal walls' weights), and the rotational gradient.
    let desc = box_scene(1.0, true, 1.0, ic_desc(&[]), 8);
    let scene = Scene::build(&desc).unwrap();
    for (x, formula) in [
        (v(0.3, 0.5, 0.0), "ward-heckbert"),
        (v(0.35, 0.35, 0.0), "ward-heckbert"),
        (v(0.6, 0.3, 0.0), "ward-heckbert"),
        (v(0.3, 0.5, 0.0), "krivanek"),
        (v(0.35, 0.35, 0.0), "krivanek"),
        (v(0.6, 0.3, 0.0), "krivanek"),
    ] {
        let n = Vec3::Z;
        let (e, gt, gr) = mean_gradients(&scene, x, n, 8, formula);
        // The gather converges to the closed form.
        let e_exact = exact(x, n);
        assert!((e - e_exact).abs() < 0.005 * e_exact, "E {e} vs {e_exact}");
        // Translational: central differences of the exact irradiance along x and y.
        let h = 1e-3;
        let fd_t = v(
            (exact(x + v(h, 0., 0.), n) - exact(x - v(h, 0., 0.), n)) / (2.0 * h),
            (exact(x + v(0., h, 0.), n) - exact(x - v(0., h, 0.), n)) / (2.0 * h),
            0.0,
        );
        assert!(
            (gt - fd_t).length() <= 0.05 * fd_t.length(),
            "{formula} translational gradient at {x}: {gt} vs finite differences {fd_t}"
        );
        // Rotational: turn the normal about x and y; (n_i × n)·∇_r E = δ a·∇_r E.
        let d = 1e-3f32;
        let rot = |axis: Vec3, ang: f32| -> Vec3 { (n + axis.cross(n) * ang.tan()).normalize() };
        let fd_r = v(
            (exact(x, rot(Vec3::X, d)) - exact(x, rot(Vec3::X, -d))) / (2.0 * d),
            (exact(x, rot(Vec3::Y, d)) - exact(x, rot(Vec3::Y, -d))) / (2.0 * d),
            0.0,
        );
        assert!(
            (gr - fd_r).length() <= 0.05 * fd_r.length(),
            "rotational gradient at {x}: {gr} vs finite differences {fd_r}"
        );
    }
}

#[test]
fn interpolated_values_and_gradients_between_records_match_the_closed_form() {
    // Records on a coarse grid of floor points; queries halfway between them, so every value
    // is an interpolation (000 eq. 3.15) of several records, with their gradients.
    use ircache_render::irradiance_cache::build::fill_for_points;
    use ircache_render::irradiance_cache::points::{interpolate_with_gradients, query_point};
    use ircache_render::irradiance_cache::IrradianceCache;
    let desc = box_scene(1.0, true, 1.0, ic_desc(&[]), 8);
    let scene = Scene::build(&desc).unwrap();
    let p = params(&[
        ("ambient_value", "1"),
        ("bounces", "1"),
        ("divisions", "4096"),
        ("accuracy", "0.2"),
        ("error_metric", "ward"),
        ("resolution", "0"),
    ]);
    let grid = |offset: f32, n: usize| -> Vec<Vec3> {
        (0..n * n)
            .map(|i| {
                let (a, b) = ((i % n) as f32, (i / n) as f32);
                v(
                    0.1 + (a + offset) * 0.8 / n as f32,
                    0.1 + (b + offset) * 0.8 / n as f32,
                    0.0,
                )
            })
            .collect()
    };
    let fill: Vec<_> = grid(0.0, 8)
        .into_iter()
        .map(|x| query_point(x, Vec3::Z))
        .collect();
    let mut cache = IrradianceCache::new(&scene, &p);
    fill_for_points(&scene, &mut cache, &fill, 3);
    let records = cache.levels[0].records().to_vec();
    assert!(records.len() >= 8, "{} records", records.len());
    let (mut worst_e, mut worst_g, mut mean_g, mut checked) = (0.0f32, 0.0f32, 0.0f32, 0);
    for x in grid(0.5, 8).into_iter().take(7 * 8) {
        let sp = query_point(x, Vec3::Z);
        let near = records
            .iter()
            .map(|r| r.p.distance(x))
            .fold(f32::INFINITY, f32::min);
        assert!(near > 0.04, "queries lie between records");
        let mut serving = 0;
        cache.levels[0].for_each_serving(x, Vec3::Z, 4.0, |_, _| serving += 1);
        let (e, gt, _) = interpolate_with_gradients(&cache, &sp);
        if serving < 2 || e.g <= 0.0 {
            continue;
        }
        checked += 1;
        let exact_e = exact(x, Vec3::Z);
        worst_e = worst_e.max((e.g - exact_e).abs() / exact_e);
        let h = 1e-3;
        let fd = v(
            (exact(x + v(h, 0., 0.), Vec3::Z) - exact(x - v(h, 0., 0.), Vec3::Z)) / (2.0 * h),
            (exact(x + v(0., h, 0.), Vec3::Z) - exact(x - v(0., h, 0.), Vec3::Z)) / (2.0 * h),
            0.0,
        );
        // Relative to the irradiance: a gradient error of 1 % of E per unit length.
        let g_err = (gt[1] - fd).length() / exact_e;
        worst_g = worst_g.max(g_err);
        mean_g += g_err;
    }
    mean_g /= checked.max(1) as f32;
    eprintln!(
        "{checked} queries: worst value error {worst_e:.4}; gradient error (relative to E, per \
         unit length) worst {worst_g:.3}, mean {mean_g:.3}"
    );
    assert!(checked >= 30, "{checked} queries were interpolated");
    // Measured 0.020, 0.49 and 0.066; the gradient reaches 0.9 E per unit near the occluder.
    assert!(worst_e < 0.03, "value {worst_e}");
    assert!(
        worst_g < 0.75 && mean_g < 0.15,
        "gradient {worst_g} {mean_g}"
    );
}

#[test]
fn records_match_the_exact_irradiance_at_their_positions() {
    let desc = open_box_under_sky(&[("accuracy", "0.2")], 48);
    let scene = Scene::build(&desc).unwrap();
    let integrator = Integrator::from_desc(&desc.integrator).unwrap();
    let out = ircache_render::render::render(
        &scene,
        &integrator,
        &ircache_render::render::RenderSettings {
            width: 48,
            height: 48,
            spp: 1,
            seed: 5,
            threads: 2,
            filter: ircache_render::film::Filter::Box,
            band: None,
            sampling: ircache_render::render::Sampling::default(),
        },
        &|_| {},
    )
    .unwrap();
    let cache = out.cache.unwrap().cache;
    let mut checked = 0;
    for rec in cache.levels[0].records() {
        // Floor records (the exact form holds there).
        if rec.p.z.abs() < 1e-4 && rec.n.z > 0.999 {
            let e = exact(rec.p, rec.n);
            assert!(
                (rec.e.g - e).abs() < 0.03 * e,
                "record at {}: {} vs exact {e}",
                rec.p,
                rec.e.g
            );
            checked += 1;
        }
    }
    assert!(checked > 10, "only {checked} floor records");
}

/// `--record-source plane`: first-level records from a border-compensated 64 × 64 plane with
/// its gradients, against the open box's exact irradiance at their positions: the plane's own
/// estimator error (001 Table 4.1: the directions outside its 143° take the border's radiance),
/// within a few percent; the translational gradients along the floor against central
/// differences of the exact irradiance.
#[test]
fn plane_records_match_the_exact_irradiance_at_their_positions() {
    let desc = open_box_under_sky(&[("accuracy", "0.3"), ("record_source", "plane")], 32);
    let out = render_desc(&desc, 2, 5);
    let cache = out.cache.unwrap().cache;
    let (mut squared, mut worst, mut checked) = (0.0f64, 0.0f32, 0);
    let (mut gradient_error, mut gradient_size) = (0.0f64, 0.0f64);
    for rec in cache.levels[0].records() {
        if rec.p.z.abs() < 1e-4 && rec.n.z > 0.999 {
            let e = exact(rec.p, rec.n);
            let relative = (rec.e.g - e) / e;
            squared += f64::from(relative * relative);
            worst = worst.max(relative.abs());
            checked += 1;
            // The record's gradient may be scaled down by Ward's limit: compare where it was not.
            let h = 1e-3;
            let fd = Vec3::new(
                (exact(rec.p + Vec3::X * h, rec.n) - exact(rec.p - Vec3::X * h, rec.n)) / (2.0 * h),
                (exact(rec.p + Vec3::Y * h, rec.n) - exact(rec.p - Vec3::Y * h, rec.n)) / (2.0 * h),
                0.0,
            );
            gradient_error += f64::from((rec.grad_t[1] - fd).length_squared());
            gradient_size += f64::from(fd.length_squared());
        }
    }
    let rms = (squared / f64::from(checked.max(1))).sqrt();
    let gradient = (gradient_error / gradient_size).sqrt();
    eprintln!("{checked} floor records: RMS {rms}, worst {worst}; gradient {gradient}");
    assert!(checked > 10, "only {checked} floor records");
    // Measured: RMS 0.3 %, worst 0.9 %, gradients 9 % (0.6, 1.7, 7 % with a 127° plane).
    assert!(rms < 0.02 && worst < 0.05, "RMS {rms}, worst {worst}");
    assert!(
        gradient < 0.2,
        "translational gradient: relative RMS error {gradient}"
    );
}

#[test]
fn records_grow_as_accuracy_falls() {
    let count = |a: &str| {
        let desc = box_scene(
            0.8,
            true,
            1.0,
            ic_desc(&[
                ("ambient_value", "1"),
                ("error_metric", "ward"),
                ("accuracy", a),
                ("divisions", "128"),
                ("resolution", "32"),
            ]),
            96,
        );
        render_desc(&desc, 2, 1).cache.unwrap().stats.records() as f64
    };
    let (n4, n2, n1) = (count("0.4"), count("0.2"), count("0.1"));
    // Roughly 1/a²: about 4× per halving of a.
    for (hi, lo) in [(n2, n4), (n1, n2)] {
        let ratio = hi / lo;
        assert!((2.5..6.5).contains(&ratio), "{n4} {n2} {n1}: ratio {ratio}");
    }
}

#[test]
fn cache_render_is_deterministic_and_finite() {
    let desc = box_scene(
        0.8,
        true,
        1.0,
        ic_desc(&[
            ("ambient_value", "1"),
            ("bounces", "2"),
            ("divisions", "64"),
            ("deeper_bounces", "cache"),
        ]),
        40,
    );
    let a = render_desc(&desc, 2, 9);
    let b = render_desc(&desc, 2, 9);
    let c = render_desc(&desc, 1, 9);
    assert_eq!(a.image.pixels, b.image.pixels);
    assert_eq!(
        a.image.pixels, c.image.pixels,
        "thread count changed the image"
    );
    assert!(a.image.pixels.iter().all(|p| p.is_valid_radiance()));
    let d = render_desc(&desc, 2, 10);
    assert_ne!(a.image.pixels, d.image.pixels, "the seed changed nothing");
    let st = a.cache.unwrap().stats;
    assert_eq!(st.records_per_level.len(), 2);
    assert!(st.records_per_level[1] > 0);
}

#[test]
fn hessian_by_reprojection_matches_second_differences() {
    use ircache_render::irradiance_cache::gather::{
        Gatherer, IrradianceCache, SceneRadiance, WorkState,
    };
    use ircache_render::irradiance_cache::hemisphere::Stratification;
    use ircache_render::irradiance_cache::points::query_point;
    // The box with the opening, without the occluder (whose silhouette would uncover surfaces
    // the gather never saw): E = π (1 − F_hole).
    let mut desc = box_scene(1.0, true, 1.0, ic_desc(&[]), 8);
    desc.shapes.pop();
    let scene = Scene::build(&desc).unwrap();
    let exact_hole = |x: Vec3| -> f64 {
        let [hx, hy] = HOLE;
        f64::from(PI * (1.0 - form_factor(x, Vec3::Z, &rect_z(hx, hy, 1.0))))
    };
    let p = params(&[
        ("ambient_value", "1"),
        ("bounces", "1"),
        ("supersamples", "0"),
    ]);
    let cache = IrradianceCache::new(&scene, &p);
    for x in [v(0.3, 0.5, 0.0), v(0.6, 0.3, 0.0), v(0.5, 0.45, 0.0)] {
        let sp = query_point(x, Vec3::Z);
        let mut hsum = [0.0f64; 3];
        let seeds = 8;
        let mut frame = None;
        for seed in 0..seeds {
            let light = SceneRadiance::path_traced(&scene);
            let g = Gatherer::new(&light, &cache, seed);
            let mut st = WorkState::new(1);
            let (h, f) = g.gather(
                &mut st,
                &sp,
                Stratification::from_divisions(16384),
                0,
                1,
                None,
            );
            let hh = h.translational_hessian();
            for c in 0..3 {
                hsum[c] += hh[c] / seeds as f64;
            }
            frame = Some(f);
        }
        let f = frame.unwrap();
        let (s, t) = (f.s, f.t);
        let d = 1e-2f32;
        let e = |a: f32, b: f32| exact_hole(x + s * a + t * b);
        let dd = f64::from(d * d);
        let exact = [
            (e(d, 0.0) - 2.0 * e(0.0, 0.0) + e(-d, 0.0)) / dd,
            (e(d, d) - e(d, -d) - e(-d, d) + e(-d, -d)) / (4.0 * dd),
            (e(0.0, d) - 2.0 * e(0.0, 0.0) + e(0.0, -d)) / dd,
        ];
        let norm = |m: [f64; 3]| (m[0] * m[0] + 2.0 * m[1] * m[1] + m[2] * m[2]).sqrt();
        let diff = [hsum[0] - exact[0], hsum[1] - exact[1], hsum[2] - exact[2]];
        eprintln!("at {x}: reprojected {hsum:?}, second differences {exact:?}");
        assert!(
            norm(diff) <= 0.15 * norm(exact),
            "Hessian at {x}: {hsum:?} vs {exact:?}"
        );
    }
}

/// Exact one-bounce irradiance at floor point `x` (normal +z) from the underside of a square
/// reflector `[-s, s]² × {h}` of albedo `rho`, lit by a point light of intensity `i` at `l`
/// just below it: a 256² midpoint rule over the reflector (nothing blocks floor and underside).
fn hot_spot_exact(x: Vec3, s: f32, h: f32, rho: f32, i: f32, l: Vec3) -> f32 {
    let n = 256;
    let cell = 2.0 * s / n as f32;
    let mut e = 0.0f64;
    for a in 0..n {
        for b in 0..n {
            let y = v(
                -s + (a as f32 + 0.5) * cell,
                -s + (b as f32 + 0.5) * cell,
                h,
            );
            // Irradiance on the underside (normal −z) from the light below it.
            let to_l = l - y;
            let e_y = i * (-to_l.z).max(0.0).abs() / to_l.length().powi(3);
            let e_y = if to_l.z < 0.0 { e_y } else { 0.0 };
            let radiance = rho / PI * e_y;
            let d = y - x;
            let d2 = d.length_squared();
            let cos_x = d.z / d2.sqrt();
            let cos_y = d.z / d2.sqrt();
            e += f64::from(radiance * cos_x * cos_y / d2 * cell * cell);
        }
    }
    e as f32
}

#[test]
fn an_indirect_hot_spot_is_interpolated_within_the_accuracy() {
    // A lamp's shade reflecting its bulb onto a desk, reduced to its bones: a small bright
    // reflector above a floor makes a peak of indirect irradiance about as wide as its height.
    // Records are spaced by the nearest hit distance (Tabellion's metric, the default), which
    // the reflector sets, too far apart for the peak: the record at its top, with no gradient
    // to speak of, served its flanks. The curvature bound (the second-order error at the
    // serving distance) and the gradient limit on the serving distance (003 item 4) bring
    // records closer there; in the lamp room the peak under the desk lamp was 30 % low.
    use ircache_render::irradiance_cache::build::fill_for_points;
    use ircache_render::irradiance_cache::points::{interpolate_with_gradients, query_point};
    use ircache_render::irradiance_cache::IrradianceCache;
    let (s, h, rho, intensity) = (0.15f32, 0.3f32, 0.8f32, 1.0f32);
    let light = v(0.0, 0.0, h - 0.02);
    let floor = quad(rect_z([-2.0, 2.0], [-2.0, 2.0], 0.0), 0.5);
    let reflector = quad(rect_z([-s, s], [-s, s], h), rho);
    let desc = scene(
        sensor(v(0.0, -1.5, 1.0), v(0.0, 0.0, 0.0), 60.0, 8, 1),
        ic_desc(&[]),
        vec![floor, reflector],
        vec![EmitterDesc::Point {
            position: light,
            intensity: Rgb::splat(intensity),
        }],
    );
    let built = Scene::build(&desc).unwrap();
    let p = params(&[
        ("bounces", "1"),
        ("divisions", "2048"),
        ("supersamples", "0"),
        ("resolution", "0"),
    ]);
    let n = 48;
    let at = |i: usize, j: usize, offset: f32| {
        v(
            -0.6 + 1.2 * (i as f32 + offset) / n as f32,
            -0.6 + 1.2 * (j as f32 + offset) / n as f32,
            0.0,
        )
    };
    let fill: Vec<_> = (0..n * n)
        .map(|k| query_point(at(k % n, k / n, 0.0), Vec3::Z))
        .collect();
    let mut cache = IrradianceCache::new(&built, &p);
    fill_for_points(&built, &mut cache, &fill, 5);
    // Queries between the fill points, along the line through the peak and over the square.
    let (mut sum, mut exact_sum, mut worst) = (0.0f64, 0.0f64, 0.0f32);
    for j in (0..n - 1).step_by(3) {
        for i in 0..n - 1 {
            let x = at(i, j, 0.5);
            let (e, _, _) = interpolate_with_gradients(&cache, &query_point(x, Vec3::Z));
            let exact = hot_spot_exact(x, s, h, rho, intensity, light);
            sum += f64::from(e.g);
            exact_sum += f64::from(exact);
            if exact > 0.5 * hot_spot_exact(Vec3::ZERO, s, h, rho, intensity, light) {
                worst = worst.max((e.g - exact).abs() / exact);
            }
        }
    }
    let ratio = sum / exact_sum;
    eprintln!(
        "{} records; interpolated over exact {ratio:.4}; worst near the peak {worst:.3}",
        cache.levels[0].len()
    );
    // Measured 1.002 and 0.11 (the peak's record is a few per cent off by its own noise); the
    // gradient limit on R alone gave 1.24 and 0.90 (the peak's record served its flanks), and
    // with the curvature bound at a·E instead of a tenth of it 1.027 and 0.24.
    assert!((ratio - 1.0).abs() < 0.02, "mean {ratio}");
    assert!(worst < 0.15, "near the peak {worst}");
}

/// `ircache irradiance` where light arrives off a mirror (a caustic): a small panel faces up
/// under a perfect mirror, so at one bounce the floor, and a workplane in the air above it,
/// receive only the panel's mirror image, whose irradiance Lambert's form factor gives. Points
/// need not lie on surfaces, so no caustic map serves them even where renders make one: the
/// gathers keep that light, by default and when a map is asked for.
#[test]
fn irradiance_at_points_keeps_the_light_a_mirror_sends() {
    let (h, le) = (0.15, 10.0);
    let mirror = Arc::new(BsdfDesc::Conductor {
        eta: Rgb::splat(0.0),
        k: Rgb::splat(1.0),
        specular_reflectance: Rgb::ONE,
    });
    let shapes = vec![
        // Floor (y = 0, up) and mirror (y = 1, down), both 4 × 4.
        quad(
            [
                v(-2., 0., -2.),
                v(-2., 0., 2.),
                v(2., 0., 2.),
                v(2., 0., -2.),
            ],
            0.5,
        ),
        common::quad(
            [
                v(-2., 1., -2.),
                v(2., 1., -2.),
                v(2., 1., 2.),
                v(-2., 1., 2.),
            ],
            mirror,
            None,
        ),
        // The panel at y = 0.5, shining up only.
        common::quad(
            [v(-h, 0.5, -h), v(-h, 0.5, h), v(h, 0.5, h), v(h, 0.5, -h)],
            diffuse(Rgb::ZERO),
            Some(Rgb::splat(le)),
        ),
    ];
    let desc = scene(
        sensor(v(0.0, 0.9, 3.0), v(0.0, 0.3, 0.0), 50.0, 8, 1),
        ic_desc(&[]),
        shapes,
        vec![],
    );
    let scene = Scene::build(&desc).unwrap();
    // The panel's image in the mirror, at y = 1.5.
    let image = [v(-h, 1.5, -h), v(h, 1.5, -h), v(h, 1.5, h), v(-h, 1.5, h)];
    let queries: Vec<(Vec3, Vec3)> = (0..24)
        .map(|i| {
            let t = i as f32 / 24.0 * std::f32::consts::TAU;
            let r = 0.6 + 0.3 * (i % 3) as f32;
            let y = if i % 2 == 0 { 0.0 } else { 0.3 };
            (v(r * t.cos(), y, r * t.sin()), Vec3::Y)
        })
        .collect();
    let exact: Vec<f32> = queries
        .iter()
        .map(|&(x, n)| le * PI * form_factor(x, n, &image))
        .collect();
    // Tolerances about three standard deviations over seeds: the records' mean spreads 1.8 %,
    // the brute-force gathers' 0.7 %.
    for (what, method, p, tolerance) in [
        ("defaults", PointMethod::Cache, params(&[]), 0.06),
        (
            "caustic map asked",
            PointMethod::Cache,
            params(&[("caustic_photons", "100000")]),
            0.06,
        ),
        (
            "brute force",
            PointMethod::BruteForce { samples: 16384 },
            params(&[]),
            0.03,
        ),
    ] {
        let (res, stats) = irradiance_at_points(&scene, &p, &queries, method, 0, 5);
        // A count asked for and not used is said.
        let noted = stats.is_some_and(|s| s.notes.iter().any(|n| n.contains("not used at points")));
        assert_eq!(noted, what == "caustic map asked", "{what}: notes");
        let ratio = res
            .iter()
            .zip(&exact)
            .map(|(r, &e)| f64::from(r.indirect.g / e))
            .sum::<f64>()
            / exact.len() as f64;
        assert!(
            (ratio - 1.0).abs() < tolerance,
            "{what}: {ratio} of the exact"
        );
    }
}

/// Records on the edges where surfaces meet: in the cube-in-box at 128², pixel centres along
/// the floor's edges with the side walls hit the floor a rounding error beyond the wall, where
/// the record's hemisphere sees the outside of the room (irradiance 0). Raised to Tabellion's
/// footprint floor such a record darkened a patch of pixels along the edge by up to 25 %
/// (5 × 5 windows down to 0.89 of the path tracer's); with the contact rule
/// ([`ircache_render::irradiance_cache::record::CONTACT_SHARE`]) it serves only its own spot.
/// Every 5 × 5 window below the light must keep at least 0.93 of `path`'s luminance at 512 spp
/// (the least found after the fix: 0.96, at the cube's anti-aliased edges).
#[test]
fn records_on_the_edges_of_a_room_do_not_darken_it() {
    let defines = |integrator: &str, spp: u32| {
        [
            ("integrator", integrator.to_string()),
            ("resx", "128".to_string()),
            ("resy", "128".to_string()),
            ("spp", spp.to_string()),
        ]
        .map(|(k, v)| (k.to_string(), v))
    };
    let luminance = |desc: &SceneDesc, seed: u64| -> Vec<f64> {
        render_desc(desc, 2, seed)
            .image
            .pixels
            .iter()
            .map(|&p| ircache_image::compare::luminance(p))
            .collect()
    };
    let cache = luminance(&project_scene("cube-in-box", &defines("irrcache", 16)), 1);
    let path = luminance(&project_scene("cube-in-box", &defines("path", 512)), 2);
    let window = |img: &[f64], x: usize, y: usize| -> f64 {
        (y - 2..=y + 2)
            .flat_map(|yy| (x - 2..=x + 2).map(move |xx| img[yy * 128 + xx]))
            .sum::<f64>()
    };
    let mut worst = (f64::INFINITY, 0, 0);
    // Rows from 16 down: the light's edges (rows 8–12) are the emitter's coverage noise.
    for y in (16..124).step_by(2) {
        for x in (2..126).step_by(2) {
            let q = window(&cache, x, y) / window(&path, x, y);
            if q < worst.0 {
                worst = (q, x, y);
            }
        }
    }
    assert!(
        worst.0 >= 0.93,
        "the window at ({}, {}) reads {:.3} of the path tracer's",
        worst.1,
        worst.2,
        worst.0
    );
}
