//! Closed-form checks of the emitters: irradiance estimated by Monte Carlo with
//! `LightSet::sample` (`E ≈ mean(radiance · cos θ / pdf)`) against analytic values, exact values of
//! the delta lights, `pdf_area` consistency with `sample`, one-sidedness, and Mitsuba 3's envmap
//! lat-long mapping.

mod common;
use common::{emitting_shape, light_scene};
use ircache_image::Image;
use ircache_math::{Frame, Mat4, Rgb, Rng, Vec2, Vec3, PI};
use ircache_render::lights::{LightSample, LightSet, Receiver};
use ircache_scene::*;
use std::path::PathBuf;
use std::sync::Arc;

fn sphere(center: Vec3, radius: f32, flip_normals: bool, radiance: f32) -> ShapeDesc {
    emitting_shape(
        Geometry::Sphere {
            center,
            radius,
            flip_normals,
            orientation: ircache_math::Mat3::IDENTITY,
        },
        Rgb::splat(radiance),
    )
}

/// Rectangle `corner + [0, w]·s + [0, l]·t` with its normal facing `towards`.
fn rectangle(corner: Vec3, s: Vec3, t: Vec3, w: f32, l: f32, towards: Vec3) -> TriangleMesh {
    let p = [
        corner,
        corner + w * s,
        corner + w * s + l * t,
        corner + l * t,
    ];
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    let indices = if n.dot(towards - p[0]) > 0.0 {
        vec![[0, 1, 2], [0, 2, 3]]
    } else {
        vec![[0, 2, 1], [0, 3, 2]]
    };
    TriangleMesh {
        positions: p.to_vec(),
        normals: None,
        uvs: None,
        indices,
    }
}

/// Monte Carlo irradiance at `p` with normal `n` (green channel): (mean, standard error).
fn irradiance(lights: &LightSet, p: Vec3, n: Vec3, samples: usize, seed: u64) -> (f64, f64) {
    let mut rng = Rng::new(seed, 3);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..samples {
        let u_sel = rng.next_f32();
        let u = rng.next_2d();
        if let Some(ls) = lights.sample(p, u_sel, u) {
            assert!(
                ls.pdf > 0.0 && ls.pdf.is_finite() && ls.radiance.is_valid_radiance(),
                "{ls:?}"
            );
            let e = f64::from(ls.radiance.g) * f64::from(n.dot(ls.wi).max(0.0)) / f64::from(ls.pdf);
            sum += e;
            sum2 += e * e;
        }
    }
    let m = sum / samples as f64;
    let var = (sum2 / samples as f64 - m * m).max(0.0);
    (m, (var / samples as f64).sqrt())
}

/// Asserts a Monte Carlo estimate: standard error below 0.5 %, within 4σ (or 1e-5 relative, the
/// f32 round-off, for near-zero-variance cases) and within 1 %.
fn assert_estimate(label: &str, (m, se): (f64, f64), expect: f64) {
    assert!(
        se < 5e-3 * expect,
        "{label}: standard error {se} too large for {expect}"
    );
    assert!(
        (m - expect).abs() < (4.0 * se).max(1e-5 * expect),
        "{label}: {m} vs {expect} (σ {se})"
    );
    assert!(
        (m - expect).abs() < 1e-2 * expect,
        "{label}: {m} vs {expect}"
    );
}

/// `E = π L (r/h)²` for a sphere of radius r whose centre is at height h on the normal.
fn sphere_irradiance(l: f64, r: f64, h: f64) -> f64 {
    std::f64::consts::PI * l * (r / h).powi(2)
}

/// `E = π L F`, F the form factor from a plane element to a parallel w × l rectangle at height h
/// with the element below a corner (Howell's catalogue, B-3):
/// `F = (1/2π)[a/√(1+a²) atan(b/√(1+a²)) + b/√(1+b²) atan(a/√(1+b²))]`, a = w/h, b = l/h.
fn rectangle_irradiance(l: f64, w: f64, len: f64, h: f64) -> f64 {
    let (a, b) = (w / h, len / h);
    let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
    let f = (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * std::f64::consts::PI);
    std::f64::consts::PI * l * f
}

/// A receiver frame that is not axis-aligned.
fn receiver() -> (Vec3, Frame) {
    (
        Vec3::new(0.2, -0.1, 0.3),
        Frame::from_z(Vec3::new(0.3, -0.5, 0.8).normalize()),
    )
}

#[test]
fn spherical_emitter_irradiance_is_pi_l_r2_over_h2() {
    let (p, f) = receiver();
    for (r, h) in [(0.5f32, 2.0f32), (0.9, 1.0), (0.01, 3.0)] {
        let lights = LightSet::new(
            &light_scene(vec![sphere(p + h * f.n, r, false, 3.0)], vec![]),
            p,
            5.0,
        );
        let est = irradiance(&lights, p, f.n, 400_000, 1);
        assert_estimate(
            &format!("sphere r {r} h {h}"),
            est,
            sphere_irradiance(3.0, f64::from(r), f64::from(h)),
        );
    }
}

#[test]
fn rectangular_emitter_irradiance_matches_the_form_factor() {
    let (p, f) = receiver();
    for (w, l, h) in [(1.5f32, 0.8f32, 1.2f32), (4.0, 4.0, 0.5), (0.3, 2.0, 1.0)] {
        let mesh = rectangle(p + h * f.n, f.s, f.t, w, l, p);
        let lights = LightSet::new(
            &light_scene(
                vec![emitting_shape(Geometry::Mesh(mesh), Rgb::splat(2.0))],
                vec![],
            ),
            p,
            5.0,
        );
        let est = irradiance(&lights, p, f.n, 2_000_000, 2);
        let expect = rectangle_irradiance(2.0, f64::from(w), f64::from(l), f64::from(h));
        assert_estimate(&format!("rectangle {w}×{l} at {h}"), est, expect);
    }
}

/// A point a thousandth of the light's size below a rectangle's middle, where it covers all but
/// 1 % of the hemisphere and is sampled over it (`lights::rectangle`'s `Seen::Nearly`): the four
/// quarters' form factors, and a bounded sample weight (area sampling's would reach A/h² = 10⁶).
#[test]
fn rectangle_just_above_the_receiver() {
    let (p, f) = receiver();
    let (w, h) = (1.0f32, 1e-3f32);
    let corner = p + h * f.n - 0.5 * w * (f.s + f.t);
    let mesh = rectangle(corner, f.s, f.t, w, w, p);
    let lights = LightSet::new(
        &light_scene(
            vec![emitting_shape(Geometry::Mesh(mesh), Rgb::splat(2.0))],
            vec![],
        ),
        p,
        5.0,
    );
    let mut rng = Rng::new(3, 9);
    for _ in 0..10_000 {
        if let Some(ls) = lights.sample(p, rng.next_f32(), rng.next_2d()) {
            let weight = ls.radiance.g * ls.wi.dot(f.n) / ls.pdf;
            assert!(
                weight <= 2.0 * 2.0 * std::f32::consts::PI,
                "weight {weight}"
            );
        }
    }
    let est = irradiance(&lights, p, f.n, 2_000_000, 2);
    let half = f64::from(0.5 * w);
    let expect = 4.0 * rectangle_irradiance(2.0, half, half, f64::from(h));
    assert_estimate("rectangle 1×1 at 0.001 over its middle", est, expect);
    assert_pdf_consistent("rectangle just above", &lights, p, |_| 0);
}

/// Mitsuba's `lookat` to_world: +z from `origin` towards `target`.
fn lookat(origin: Vec3, target: Vec3) -> Mat4 {
    let dir = (target - origin).normalize();
    let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    )
}

fn only(lights: &LightSet, p: Vec3) -> LightSample {
    lights
        .sample(p, 0.5, Vec2::new(0.3, 0.7))
        .expect("a sample")
}

#[test]
fn point_light_gives_i_cos_over_d2() {
    let (p, f) = receiver();
    let q = p + Vec3::new(1.0, -2.0, 3.0);
    let lights = LightSet::new(
        &light_scene(
            vec![],
            vec![EmitterDesc::Point {
                position: q,
                intensity: Rgb::new(5.0, 6.0, 7.0),
            }],
        ),
        p,
        5.0,
    );
    let ls = only(&lights, p);
    let d = (q - p).length();
    let cos = f.n.dot((q - p) / d);
    assert!(ls.is_delta && ls.pdf == 1.0 && (ls.distance - d).abs() < 1e-5 * d);
    let e = ls.radiance.g * f.n.dot(ls.wi) / ls.pdf;
    let expect = 6.0 * cos / (d * d);
    assert!((e - expect).abs() < 1e-5 * expect, "{e} vs {expect}");
}

#[test]
fn directional_light_gives_irradiance_times_cos() {
    let (p, f) = receiver();
    let dir = Vec3::new(0.2, 0.4, -1.0);
    let lights = LightSet::new(
        &light_scene(
            vec![],
            vec![EmitterDesc::Directional {
                direction: dir,
                irradiance: Rgb::splat(3.0),
            }],
        ),
        p,
        5.0,
    );
    let ls = only(&lights, p);
    assert!(ls.is_delta && ls.distance == f32::INFINITY && ls.pdf == 1.0);
    let e = ls.radiance.g * f.n.dot(ls.wi);
    let expect = 3.0 * f.n.dot(-dir.normalize());
    assert!(
        expect > 0.0 && (e - expect).abs() < 1e-5 * expect,
        "{e} vs {expect}"
    );
}

#[test]
fn spot_light_on_axis_in_the_ramp_and_outside() {
    let (p, f) = receiver();
    let pos = p + 2.5 * f.n;
    let (cutoff, beam) = (30.0f32, 10.0f32);
    let lights = LightSet::new(
        &light_scene(
            vec![],
            vec![EmitterDesc::Spot {
                to_world: lookat(pos, p),
                intensity: Rgb::splat(4.0),
                cutoff_angle: cutoff,
                beam_width: beam,
            }],
        ),
        p,
        5.0,
    );
    // On the axis: I / d².
    let ls = only(&lights, p);
    assert!(ls.is_delta);
    let e = ls.radiance.g * f.n.dot(ls.wi) / ls.pdf;
    assert!((e - 4.0 / 6.25).abs() < 1e-5, "{e}");
    // Mitsuba's falloff_curve: linear in angle between beam_width and cutoff_angle.
    for theta_deg in [5.0f32, 12.0, 20.0, 29.0, 31.0, 60.0] {
        let theta = theta_deg.to_radians();
        let q = pos + 2.0 * (-f.n * theta.cos() + f.s * theta.sin());
        let falloff = if theta_deg <= beam {
            1.0
        } else if theta_deg >= cutoff {
            0.0
        } else {
            (cutoff - theta_deg) / (cutoff - beam)
        };
        // I · falloff / d² with I = 4, d = 2.
        let expect = 4.0 * falloff / 4.0;
        match lights.sample(q, 0.5, Vec2::ZERO) {
            Some(ls) => {
                assert!(expect > 0.0, "θ = {theta_deg}: light outside the cone");
                assert!(
                    (ls.radiance.g - expect).abs() < 1e-4,
                    "θ = {theta_deg}: {} vs {expect}",
                    ls.radiance.g
                );
            }
            None => assert_eq!(expect, 0.0, "θ = {theta_deg}: no sample"),
        }
    }
}

#[test]
fn mixed_set_sums_the_closed_forms() {
    let (p, f) = receiver();
    let (r, h) = (0.4f32, 1.5f32);
    let (w, l, hr) = (1.0f32, 2.0f32, 0.8f32);
    let mesh = rectangle(p + hr * f.n, f.s, f.t, w, l, p);
    let q = p + Vec3::new(0.5, -1.0, 2.0);
    let dir = -(f.n + 0.3 * f.s).normalize();
    let spot_pos = p + 2.0 * (f.n - 0.5 * f.t).normalize();
    let lights = LightSet::new(
        &light_scene(
            vec![
                sphere(p + h * f.n, r, false, 2.0),
                emitting_shape(Geometry::Mesh(mesh), Rgb::splat(1.5)),
            ],
            vec![
                EmitterDesc::Point {
                    position: q,
                    intensity: Rgb::splat(0.7),
                },
                EmitterDesc::Directional {
                    direction: dir,
                    irradiance: Rgb::splat(0.4),
                },
                EmitterDesc::Spot {
                    to_world: lookat(spot_pos, p),
                    intensity: Rgb::splat(0.9),
                    cutoff_angle: 20.0,
                    beam_width: 15.0,
                },
            ],
        ),
        p,
        5.0,
    );
    assert_eq!(lights.len(), 5);
    let dq = f64::from((q - p).length());
    let expect = sphere_irradiance(2.0, f64::from(r), f64::from(h))
        + rectangle_irradiance(1.5, f64::from(w), f64::from(l), f64::from(hr))
        + 0.7 * f64::from(f.n.dot((q - p).normalize())) / (dq * dq)
        + 0.4 * f64::from(f.n.dot(-dir))
        + 0.9 * f64::from(f.n.dot((spot_pos - p).normalize())) / 4.0;
    assert_estimate(
        "mixed set",
        irradiance(&lights, p, f.n, 4_000_000, 3),
        expect,
    );
}

/// Two equal spheres, one near the receiver and one ten times farther: selection by estimated
/// contribution picks the near one almost always, so one sample's relative standard deviation is
/// far below uniform selection's (≈ 1: half the samples carry twice the near light, half next
/// to nothing), and the estimate is still the closed-form sum.
#[test]
fn selection_follows_the_lights_contributions() {
    let (p, f) = receiver();
    let (r, near, far) = (0.1f32, 1.0f32, 10.0f32);
    let lights = LightSet::new(
        &light_scene(
            vec![
                sphere(p + near * f.n, r, false, 1.0),
                sphere(p + far * (f.n + 0.2 * f.s).normalize(), r, false, 1.0),
            ],
            vec![],
        ),
        p,
        20.0,
    );
    let near_share = lights.selection_probability(p, 0);
    assert!(near_share > 0.9, "near light selected with {near_share}");
    let total = lights.selection_probability(p, 0) + lights.selection_probability(p, 1);
    assert!((total - 1.0).abs() < 1e-6, "{total}");
    let far_e = sphere_irradiance(1.0, f64::from(r), f64::from(far))
        * f64::from(f.n.dot((f.n + 0.2 * f.s).normalize()));
    let expect = sphere_irradiance(1.0, f64::from(r), f64::from(near)) + far_e;
    let samples = 200_000;
    let (m, se) = irradiance(&lights, p, f.n, samples, 5);
    assert_estimate("two spheres", (m, se), expect);
    let relative_sd = se * (samples as f64).sqrt() / expect;
    assert!(
        relative_sd < 0.4,
        "one sample's relative deviation {relative_sd}"
    );
}

/// Ray–triangle intersection distance (Möller–Trumbore, f64).
fn hit_triangle(o: Vec3, d: Vec3, p0: Vec3, p1: Vec3, p2: Vec3) -> Option<f64> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let (p0, e1, e2) = (p0.as_dvec3(), (p1 - p0).as_dvec3(), (p2 - p0).as_dvec3());
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() < 1e-14 {
        return None;
    }
    let tv = o - p0;
    let (u, qv) = (tv.dot(pv) / det, tv.cross(e1));
    let (v, t) = (d.dot(qv) / det, e2.dot(qv) / det);
    (u >= -1e-6 && v >= -1e-6 && u + v <= 1.0 + 1e-6 && t > 0.0).then_some(t)
}

/// The triangle of `mesh` on which a sample from `p` landed.
fn prim_of(mesh: &TriangleMesh, p: Vec3, ls: &LightSample) -> u32 {
    let mut best = (f64::INFINITY, 0);
    for (i, &[a, b, c]) in mesh.indices.iter().enumerate() {
        let [p0, p1, p2] = [a, b, c].map(|k| mesh.positions[k as usize]);
        if let Some(t) = hit_triangle(p, ls.wi, p0, p1, p2) {
            let err = (t - f64::from(ls.distance)).abs();
            if err < best.0 {
                best = (err, i as u32);
            }
        }
    }
    assert!(
        best.0 < 1e-4 * f64::from(ls.distance).max(1.0),
        "sample not on the mesh: {ls:?}"
    );
    best.1
}

fn assert_pdf_consistent(
    label: &str,
    lights: &LightSet,
    p: Vec3,
    prim: impl Fn(&LightSample) -> u32,
) {
    let mut rng = Rng::new(11, 5);
    let mut count = 0;
    for _ in 0..20_000 {
        let Some(ls) = lights.sample(p, rng.next_f32(), rng.next_2d()) else {
            continue;
        };
        if ls.is_delta || ls.distance == f32::INFINITY {
            continue;
        }
        count += 1;
        let pl = p + ls.wi * ls.distance;
        // The normal argument is only a fallback; pass a wrong one to make sure it is not used.
        let pdf = lights.pdf_area(ls.light, prim(&ls), p, pl, Vec3::X);
        assert!(
            (pdf - ls.pdf).abs() <= 1e-4 * ls.pdf,
            "{label}: pdf_area {pdf} vs sample {}",
            ls.pdf
        );
    }
    assert!(count > 1000, "{label}: only {count} area samples");
}

#[test]
fn pdf_area_matches_the_sampled_pdf() {
    let (p, f) = receiver();
    // A rectangle, a mesh with very uneven triangles and smooth normals, spheres from outside and
    // inside, with a point light in the set (selection probability 1/4).
    let rect = rectangle(p + 0.7 * f.n, f.s, f.t, 1.2, 0.6, p);
    let mut uneven = rectangle(p + 1.0 * f.n - 0.5 * f.s, f.s, f.t, 3.0, 0.01, p);
    let k = uneven.positions.len() as u32;
    uneven.positions.extend([
        p + 0.9 * f.n,
        p + 0.9 * f.n + 0.05 * f.s,
        p + 1.2 * f.n + 0.02 * f.t,
    ]);
    uneven.indices.push([k, k + 1, k + 2]);
    uneven.normals = Some(
        uneven
            .positions
            .iter()
            .map(|&q| (p - q).normalize())
            .collect(),
    );
    let meshes = [rect, uneven];
    let lights = LightSet::new(
        &light_scene(
            vec![
                emitting_shape(Geometry::Mesh(meshes[0].clone()), Rgb::ONE),
                emitting_shape(Geometry::Mesh(meshes[1].clone()), Rgb::ONE),
                sphere(p + 2.0 * f.n + f.s, 0.5, false, 1.0),
            ],
            vec![EmitterDesc::Point {
                position: p + f.n,
                intensity: Rgb::ONE,
            }],
        ),
        p,
        5.0,
    );
    assert_eq!(lights.len(), 4);
    assert_pdf_consistent(
        "meshes and sphere from outside",
        &lights,
        p,
        |ls| match ls.light {
            0 | 1 => prim_of(&meshes[ls.light as usize], p, ls),
            _ => 0,
        },
    );
    let inside = LightSet::new(
        &light_scene(vec![sphere(p + 0.3 * f.s, 1.0, true, 1.0)], vec![]),
        p,
        5.0,
    );
    assert_pdf_consistent("sphere from inside", &inside, p, |_| 0);
}

#[test]
fn area_emitters_are_one_sided() {
    let (p, f) = receiver();
    let mesh = rectangle(p + f.n, f.s, f.t, 1.0, 1.0, p);
    let lights = LightSet::new(
        &light_scene(
            vec![
                emitting_shape(Geometry::Mesh(mesh), Rgb::splat(2.0)),
                sphere(p + 10.0 * f.s, 1.0, true, 1.0),
                sphere(p - 10.0 * f.s, 1.0, false, 1.0),
            ],
            vec![],
        ),
        p,
        20.0,
    );
    assert_eq!(lights.area_light_of_shape(0), Some(0));
    assert_eq!(lights.area_light_of_shape(3), None);
    // The rectangle faces p: its normal is −n.
    assert_eq!(
        lights.area_radiance(0, Vec3::ZERO, -f.n, Vec2::ZERO, -f.n, 1.0),
        Rgb::splat(2.0)
    );
    assert_eq!(
        lights.area_radiance(0, Vec3::ZERO, -f.n, Vec2::ZERO, f.n, 1.0),
        Rgb::ZERO
    );
    let behind = p + 2.0 * f.n;
    let inside_outward = p - 10.0 * f.s + 0.2 * f.t;
    let mut rng = Rng::new(3, 3);
    for _ in 0..2000 {
        let (u_sel, u) = (rng.next_f32(), rng.next_2d());
        // Behind the rectangle, outside the inward-facing sphere, inside the outward-facing one.
        if let Some(ls) = lights.sample(behind, u_sel, u) {
            assert_eq!(ls.light, 2, "{ls:?}");
        }
        assert!(!matches!(lights.sample(p, u_sel, u), Some(ls) if ls.light == 1));
        assert!(!matches!(lights.sample(inside_outward, u_sel, u), Some(ls) if ls.light == 2));
    }
}

/// Mitsuba's `uv_to_direction` (local frame).
fn uv_to_direction(u: f32, v: f32) -> Vec3 {
    let (theta, phi) = (v * PI, u * 2.0 * PI);
    Vec3::new(
        phi.sin() * theta.sin(),
        theta.cos(),
        -phi.cos() * theta.sin(),
    )
}

#[test]
fn envmap_uses_mitsubas_lat_long_mapping() {
    let (w, h) = (8usize, 5usize);
    let mut img = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            img.set(x, y, Rgb::new(1.0 + x as f32 + 10.0 * y as f32, 1.0, 0.5));
        }
    }
    let to_world = Mat4::from_rotation_y(0.7) * Mat4::from_rotation_z(-0.3);
    let lights = LightSet::new(
        &light_scene(
            vec![],
            vec![EmitterDesc::Envmap {
                path: PathBuf::from("<test>"),
                image: Arc::new(img.clone()),
                to_world,
                scale: 2.0,
            }],
        ),
        Vec3::ZERO,
        1.0,
    );
    let world = |d: Vec3| to_world.transform_vector3(d);
    let r = |d: Vec3| lights.environment_radiance(world(d)).r;
    // Texel centres: u = (x + ½)/W, v = y/(H − 1) (rows at the poles excluded: φ is undefined).
    for y in 1..h - 1 {
        for x in 0..w {
            let d = uv_to_direction((x as f32 + 0.5) / w as f32, y as f32 / (h - 1) as f32);
            let expect = 2.0 * img.get(x, y).r;
            assert!(
                (r(d) - expect).abs() < 1e-3 * expect,
                "texel ({x}, {y}): {} vs {expect}",
                r(d)
            );
        }
    }
    // Local −z is u = 0: halfway between the last and the first column (wrap-around); +x is
    // u = ¼ (between columns 1 and 2 of 8); the equator is row 2 of 5.
    let (c0, c7) = (img.get(0, 2).r, img.get(7, 2).r);
    assert!((r(-Vec3::Z) - (c0 + c7)).abs() < 1e-3, "{}", r(-Vec3::Z));
    assert!(
        (r(Vec3::X) - (img.get(1, 2).r + img.get(2, 2).r)).abs() < 1e-3,
        "{}",
        r(Vec3::X)
    );
    // The north pole (local +y) is the top row, the south pole the bottom row (φ is arbitrary
    // there, so only the row's range is checked).
    let range = |y: usize| {
        (
            2.0 * img.get(0, y).r - 1e-3,
            2.0 * img.get(w - 1, y).r + 1e-3,
        )
    };
    let (lo, hi) = range(0);
    assert!(
        (lo..=hi).contains(&r(Vec3::Y)),
        "north pole {} not in row 0 {lo}..{hi}",
        r(Vec3::Y)
    );
    let (lo, hi) = range(h - 1);
    assert!(
        (lo..=hi).contains(&r(-Vec3::Y)),
        "south pole {} not in row {} {lo}..{hi}",
        r(-Vec3::Y),
        h - 1
    );
    // Samples come with the environment's radiance and pdf, at infinite distance.
    let mut rng = Rng::new(9, 9);
    for _ in 0..1000 {
        let ls = lights
            .sample(Vec3::ZERO, rng.next_f32(), rng.next_2d())
            .expect("envmap sample");
        assert_eq!(ls.distance, f32::INFINITY);
        assert!(!ls.is_delta);
        assert_eq!(ls.radiance, lights.environment_radiance(ls.wi));
        assert_eq!(ls.pdf, lights.pdf_environment(Vec3::ZERO, ls.wi));
    }
}

/// At a surface that only reflects, a constant sky's samples are cosine-weighted over the
/// hemisphere it faces, so each one alone estimates its irradiance E = πL exactly: a Lambertian
/// surface under an open sky has no noise from them. From a point (uniform on the sphere, as
/// Mitsuba samples it) the same estimates spread from 0 to 4πL.
#[test]
fn constant_sky_samples_at_a_reflecting_surface_are_exact() {
    let radiance = 0.8;
    let lights = LightSet::new(
        &light_scene(
            vec![],
            vec![EmitterDesc::Constant {
                radiance: Rgb::splat(radiance),
            }],
        ),
        Vec3::ZERO,
        1.0,
    );
    let p = Vec3::new(0.2, -0.1, 0.4);
    let n = Vec3::new(-0.6, 0.3, 0.7).normalize();
    let estimate = |ls: &LightSample| ls.radiance.g * n.dot(ls.wi).max(0.0) / ls.pdf;
    let mut rng = Rng::new(5, 1);
    let (mut low, mut high) = (f32::INFINITY, 0.0f32);
    for _ in 0..10_000 {
        let (u_sel, u) = (rng.next_f32(), rng.next_2d());
        let ls = lights
            .sample(Receiver::reflecting(p, n), u_sel, u)
            .expect("a sample of the sky");
        let e = estimate(&ls);
        assert!(
            (e - PI * radiance).abs() <= 1e-4 * PI * radiance,
            "{e} against πL = {}",
            PI * radiance
        );
        assert_eq!(
            ls.pdf,
            lights.pdf_environment(Receiver::reflecting(p, n), ls.wi)
        );
        if let Some(ls) = lights.sample(p, u_sel, u) {
            low = low.min(estimate(&ls));
            high = high.max(estimate(&ls));
        }
    }
    assert!(
        low == 0.0 && high > 3.9 * PI * radiance,
        "from a point: {low} to {high}"
    );
}

#[test]
fn envmap_and_constant_irradiance() {
    // A constant environment of radiance L gives E = π L on any plane. For an envmap with a bright
    // spot the reference is a fine quadrature of its own radiance (this checks the importance
    // sampling weights; the mapping is checked by `envmap_uses_mitsubas_lat_long_mapping`).
    let (p, f) = receiver();
    let lights = LightSet::new(
        &light_scene(
            vec![],
            vec![EmitterDesc::Constant {
                radiance: Rgb::splat(0.8),
            }],
        ),
        p,
        1.0,
    );
    assert_estimate(
        "constant",
        irradiance(&lights, p, f.n, 1_000_000, 4),
        std::f64::consts::PI * 0.8,
    );

    let mut img = Image::new(16, 9);
    for y in 0..9 {
        for x in 0..16 {
            img.set(
                x,
                y,
                Rgb::splat(if y == 2 && (5..8).contains(&x) {
                    200.0
                } else {
                    0.2 + 0.1 * x as f32
                }),
            );
        }
    }
    let lights = LightSet::new(
        &light_scene(
            vec![],
            vec![EmitterDesc::Envmap {
                path: PathBuf::from("<test>"),
                image: Arc::new(img),
                to_world: Mat4::from_rotation_x(0.3),
                scale: 1.0,
            }],
        ),
        p,
        1.0,
    );
    // Reference: midpoint quadrature of ∫ L(ω) max(0, n·ω) dω on a fine (cos θ, φ) grid.
    let n_grid = 1200;
    let mut expect = 0.0f64;
    for i in 0..n_grid {
        let z = -1.0 + 2.0 * (i as f64 + 0.5) / n_grid as f64;
        let s = (1.0 - z * z).sqrt();
        for j in 0..2 * n_grid {
            let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / (2 * n_grid) as f64;
            let w = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
            let cos = f64::from(f.n.dot(w).max(0.0));
            expect += f64::from(lights.environment_radiance(w).g) * cos;
        }
    }
    expect *= 4.0 * std::f64::consts::PI / (2 * n_grid * n_grid) as f64;
    assert_estimate("envmap", irradiance(&lights, p, f.n, 1_000_000, 5), expect);
}

/// Every light sample taken from an unoccluded point on a floor reaches its light: the shadow ray
/// towards it is not stopped by the light's own surface (spheres seen from near and far, a
/// rectangle), at millimetre, metre and kilometre scales.
#[test]
fn light_samples_are_not_occluded_by_their_own_light() {
    use ircache_math::ray::Ray;
    use ircache_render::scene::Scene;
    let floor = |s: f32| ShapeDesc {
        media: Default::default(),
        id: None,
        geometry: Geometry::Mesh(rectangle(
            Vec3::new(-10.0 * s, -10.0 * s, 0.0),
            Vec3::X,
            Vec3::Y,
            20.0 * s,
            20.0 * s,
            Vec3::Z,
        )),
        bsdf: common::diffuse(Rgb::splat(0.5)),
        emitter: None,
        emitter_texture: None,
        emitter_pattern: None,
        location: common::here(),
    };
    let mut failures = Vec::new();
    for scale in [1e-3f32, 1.0, 1e3] {
        for (label, light) in [
            (
                "near sphere",
                sphere(Vec3::new(0.1, 0.0, 0.5) * scale, 0.4 * scale, false, 1.0),
            ),
            (
                "far sphere",
                sphere(Vec3::new(2.0, 1.0, 1.5) * scale, 0.4 * scale, false, 1.0),
            ),
            (
                "tiny sphere",
                sphere(Vec3::new(0.0, 0.5, 3.0) * scale, 0.01 * scale, false, 1.0),
            ),
            (
                "rectangle",
                emitting_shape(
                    Geometry::Mesh(rectangle(
                        Vec3::new(-0.5, -0.3, 1.0) * scale,
                        Vec3::new(1.0, 0.0, 0.2).normalize(),
                        Vec3::Y,
                        scale,
                        0.6 * scale,
                        Vec3::ZERO,
                    )),
                    Rgb::splat(1.0),
                ),
            ),
        ] {
            let scene = Scene::build(&light_scene(vec![floor(scale), light], vec![])).unwrap();
            let mut rng = Rng::new(7, 1);
            let (mut samples, mut occluded) = (0u32, 0u32);
            for i in 0..16 {
                let x = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, 0.0) * scale;
                // Looked at from above, from a different side for each point.
                let eye = x + Vec3::new(0.01, 0.02, 0.05) * scale * (i as f32 + 1.0);
                let down = Ray {
                    o: eye,
                    d: (x - eye).normalize(),
                    t_min: 0.0,
                    t_max: f32::INFINITY,
                };
                let it = scene.intersect(&down).expect("the floor");
                for _ in 0..4000 {
                    let Some(ls) = scene.lights.sample(it.p, rng.next_f32(), rng.next_2d()) else {
                        continue;
                    };
                    if ls.wi.dot(it.ng) <= 0.0 {
                        continue;
                    }
                    samples += 1;
                    let shadow = scene.shadow_ray(&it, ls.wi, ls.distance);
                    occluded += u32::from(scene.accel.occluded(&shadow));
                }
            }
            assert!(
                samples > 10_000,
                "{label} at scale {scale}: {samples} samples"
            );
            if occluded != 0 {
                failures.push(format!(
                    "{label} at scale {scale}: {occluded} of {samples} light samples occluded"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The relative variance that decides whether radiance records hold the environment: an
/// envmap bright above the horizon (a) and dim below (b) has ((a − b)/(a + b))², and a constant
/// c added to it ((a − b)/(a + b + 2c))²; a constant alone 0.
#[test]
fn environment_relative_variance_has_its_closed_form() {
    // Rows at texel centres v = y/(H − 1): an odd height puts the horizon on a row, whose cells
    // blend the two values over 1/(H − 1) of the sphere's height.
    let (w, h) = (16usize, 401usize);
    let (a, b, c) = (3.0f32, 0.5f32, 2.0f32);
    let mut img = Image::new(w, h);
    for y in 0..h {
        let v = match (2 * y + 1).cmp(&h) {
            std::cmp::Ordering::Less => a,
            std::cmp::Ordering::Equal => 0.5 * (a + b),
            std::cmp::Ordering::Greater => b,
        };
        for x in 0..w {
            img.set(x, y, Rgb::splat(v));
        }
    }
    let envmap = EmitterDesc::Envmap {
        path: PathBuf::from("<test>"),
        image: Arc::new(img),
        to_world: Mat4::IDENTITY,
        scale: 1.0,
    };
    let constant = EmitterDesc::Constant {
        radiance: Rgb::splat(c),
    };
    let variance = |emitters: Vec<EmitterDesc>| {
        LightSet::new(&light_scene(vec![], emitters), Vec3::ZERO, 1.0)
            .environment_relative_variance()
    };
    let expect = f64::from(((a - b) / (a + b)).powi(2));
    let got = variance(vec![envmap.clone()]);
    assert!((got - expect).abs() < 0.01 * expect, "{got} vs {expect}");
    let expect = f64::from(((a - b) / (a + b + 2.0 * c)).powi(2));
    let got = variance(vec![envmap, constant.clone()]);
    assert!((got - expect).abs() < 0.01 * expect, "{got} vs {expect}");
    assert_eq!(variance(vec![constant]), 0.0);
    assert_eq!(variance(vec![]), 0.0);
}

/// At a path's last vertex on a Lambertian floor under a rectangular light, the path tracer
/// takes light samples alone (no BSDF ray: the one that would only look for emitters) and still
/// converges to ρ/π · E of the form factor; where a light is not sampled in proportion to what
/// the floor receives from it (a triangle emitter, an environment) the BSDF ray is traced.
#[test]
fn light_samples_stand_alone_at_a_lambertian_last_vertex() {
    use ircache_math::ray::Ray;
    use ircache_render::integrators::path_continuation::{
        trace_path, FirstVertex, PathSettings, PathStart, Traced,
    };
    use ircache_render::integrators::RayCounts;
    use ircache_render::scene::Scene;
    let (rho, radiance, w, l, h) = (0.5f64, 2.0f32, 1.0f32, 0.6f32, 0.5f32);
    let floor = ShapeDesc {
        media: Default::default(),
        id: None,
        geometry: Geometry::Mesh(rectangle(
            Vec3::new(-10.0, -10.0, 0.0),
            Vec3::X,
            Vec3::Y,
            20.0,
            20.0,
            Vec3::Z,
        )),
        bsdf: common::diffuse(Rgb::splat(rho as f32)),
        emitter: None,
        emitter_texture: None,
        emitter_pattern: None,
        location: common::here(),
    };
    // The receiver at the origin lies below the light's corner (the form factor's case).
    let light = emitting_shape(
        Geometry::Mesh(rectangle(
            Vec3::new(0.0, 0.0, h),
            Vec3::X,
            Vec3::Y,
            w,
            l,
            Vec3::ZERO,
        )),
        Rgb::splat(radiance),
    );
    let triangle = emitting_shape(
        Geometry::Mesh(TriangleMesh {
            positions: vec![
                Vec3::new(-3.0, -3.0, 2.0),
                Vec3::new(-2.0, -3.0, 2.0),
                Vec3::new(-3.0, -2.0, 2.0),
            ],
            normals: None,
            uvs: None,
            indices: vec![[0, 2, 1]],
        }),
        Rgb::splat(0.01),
    );
    let render = |shapes: Vec<ShapeDesc>, emitters: Vec<EmitterDesc>| {
        let scene = Scene::build(&light_scene(shapes, emitters)).unwrap();
        let eye = Vec3::new(0.002, 0.001, 0.3);
        let ray = Ray::new(eye, (Vec3::ZERO - eye).normalize());
        let settings = PathSettings {
            max_depth: 2,
            rr_depth: 5,
            first_light_samples: 1,
        };
        let mut rays = RayCounts::default();
        let mut rng = Rng::new(11, 5);
        let n = 40_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let start = PathStart::camera(ray, true);
            let v = f64::from(
                trace_path(
                    &scene,
                    start,
                    FirstVertex::Trace,
                    &mut Traced,
                    &settings,
                    &mut rng,
                    &mut rays,
                )
                .g,
            );
            sum += v;
            sum2 += v * v;
        }
        let mean = sum / f64::from(n);
        let se = ((sum2 / f64::from(n) - mean * mean) / f64::from(n)).sqrt();
        (mean, se, rays.bounce)
    };
    let expect = rho / std::f64::consts::PI
        * rectangle_irradiance(
            f64::from(radiance),
            f64::from(w),
            f64::from(l),
            f64::from(h),
        );
    let (mean, se, bounces) = render(vec![floor.clone(), light.clone()], vec![]);
    assert_eq!(bounces, 0, "a BSDF ray was traced at the last vertex");
    assert!(
        (mean - expect).abs() < 4.0 * se + 1e-4 * expect,
        "{mean} ± {se} against {expect}"
    );
    let (_, _, bounces) = render(vec![floor.clone(), light.clone(), triangle], vec![]);
    assert!(bounces > 30_000, "triangle emitter: {bounces} BSDF rays");
    let sky = EmitterDesc::Constant {
        radiance: Rgb::splat(0.01),
    };
    let (_, _, bounces) = render(vec![floor, light], vec![sky]);
    assert!(bounces > 30_000, "environment: {bounces} BSDF rays");
}

/// The form factor from a receiver below corner (0, 0) of a parallel rectangle at height h to
/// its part [s0, s1] × [t0, t1], by inclusion and exclusion of corner rectangles.
fn part_irradiance(l: f64, (s0, s1): (f64, f64), (t0, t1): (f64, f64), h: f64) -> f64 {
    let corner = |a: f64, b: f64| {
        if a <= 0.0 || b <= 0.0 {
            0.0
        } else {
            rectangle_irradiance(l, a, b, h)
        }
    };
    corner(s1, t1) - corner(s0, t1) - corner(s1, t0) + corner(s0, t0)
}

/// A textured area emitter (Mitsuba's `area` with a texture as its radiance): a checkerboard
/// of two radiances over the rectangle's uv quadrants. Light samples carry the radiance at their
/// point, so the irradiance below a corner is the quadrants' form factors weighted by their
/// radiances (the mean radiance alone reads more than 5 % off here); a hit reads the texture at its uv.
#[test]
fn textured_rectangle_emits_its_texture() {
    let (p, f) = receiver();
    let (w, l, h) = (1.2f32, 0.9f32, 0.7f32);
    let mut mesh = rectangle(p + h * f.n, f.s, f.t, w, l, p);
    mesh.uvs = Some(vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ]);
    let (bright, dim) = (3.0f32, 0.5f32);
    let mut shape = emitting_shape(Geometry::Mesh(mesh), Rgb::splat(0.5 * (bright + dim)));
    shape.emitter_texture = Some(TextureDesc::Checkerboard {
        color0: Rgb::splat(bright),
        color1: Rgb::splat(dim),
        to_uv: ircache_math::Mat3::IDENTITY,
    });
    let lights = LightSet::new(&light_scene(vec![shape], vec![]), p, 5.0);
    let (w2, l2, wf, lf, hf) = (
        f64::from(w) / 2.0,
        f64::from(l) / 2.0,
        f64::from(w),
        f64::from(l),
        f64::from(h),
    );
    let expect = part_irradiance(f64::from(bright), (0.0, w2), (0.0, l2), hf)
        + part_irradiance(f64::from(bright), (w2, wf), (l2, lf), hf)
        + part_irradiance(f64::from(dim), (w2, wf), (0.0, l2), hf)
        + part_irradiance(f64::from(dim), (0.0, w2), (l2, lf), hf);
    let mean_only = rectangle_irradiance(0.5 * f64::from(bright + dim), wf, lf, hf);
    assert!(
        (mean_only / expect - 1.0).abs() > 0.05,
        "{mean_only} {expect}"
    );
    let est = irradiance(&lights, p, f.n, 2_000_000, 5);
    assert_estimate("textured rectangle", est, expect);
    // Hits: the texture at the hit's uv, on the emitting side only.
    let n_light = -f.n;
    assert_eq!(
        lights.area_radiance(0, Vec3::ZERO, n_light, Vec2::new(0.2, 0.3), n_light, 1.0),
        Rgb::splat(bright)
    );
    assert_eq!(
        lights.area_radiance(0, Vec3::ZERO, n_light, Vec2::new(0.7, 0.3), n_light, 1.0),
        Rgb::splat(dim)
    );
    assert_eq!(
        lights.area_radiance(0, Vec3::ZERO, n_light, Vec2::new(0.7, 0.3), -n_light, 1.0),
        Rgb::ZERO
    );
}

/// A direction- and position-dependent emission pattern: `2 cos²θ (1 + x/2)`, θ between the
/// light leaving and the emitter's normal, x the point's coordinate. Over a rectangle centred on
/// x = 0 its cosine-weighted mean is 1, so the light's power stays `π L A`.
#[derive(Debug)]
struct Lobe;

impl SurfacePattern for Lobe {
    fn factor(&self, point: Vec3, normal: Vec3, direction: Vec3, _distance: f32, _uv: Vec2) -> Rgb {
        let c = (-direction).dot(normal).max(0.0);
        Rgb::splat(2.0 * c * c * (1.0 + 0.5 * point.x))
    }
}

/// A patterned rectangle light: its samples carry the pattern at their point and direction (the
/// irradiance they estimate equals a quadrature over the rectangle, near where it is sampled by
/// solid angle and far where by area), a ray hitting it sees the same radiance as the sample
/// that chose that point, and its power is the pattern's mean times `π L A`.
#[test]
fn patterned_emitter_samples_hits_and_power_agree() {
    let (w, l) = (1.0f32, 2.0f32);
    let radiance = 3.0f32;
    let corner = Vec3::new(-0.5 * w, -0.5 * l, 1.0);
    let mesh = rectangle(corner, Vec3::X, Vec3::Y, w, l, Vec3::ZERO);
    let mut shape = emitting_shape(Geometry::Mesh(mesh), Rgb::splat(radiance));
    shape.emitter_pattern = Some(Arc::new(Lobe));
    let lights = LightSet::new(&light_scene(vec![shape], vec![]), Vec3::ZERO, 5.0);
    let n_light = -Vec3::Z;
    // Quadrature of L f cosθ_r cosθ_l / r² over the rectangle.
    let quadrature = |p: Vec3, n: Vec3| {
        let k = 600;
        let mut e = 0.0f64;
        for i in 0..k {
            for j in 0..k {
                let x = corner
                    + Vec3::new(
                        w * (i as f32 + 0.5) / k as f32,
                        l * (j as f32 + 0.5) / k as f32,
                        0.0,
                    );
                let d = x - p;
                let r2 = d.length_squared();
                let wi = d / r2.sqrt();
                let (cr, cl) = (n.dot(wi).max(0.0), (-wi).dot(n_light).max(0.0));
                let f = Lobe.factor(x, n_light, wi, r2.sqrt(), Vec2::ZERO).g;
                e += f64::from(radiance * f * cr * cl / r2);
            }
        }
        e * f64::from(w * l) / (k * k) as f64
    };
    for (label, p, n) in [
        ("near, by solid angle", Vec3::new(0.1, 0.2, 0.7), Vec3::Z),
        (
            "tilted",
            Vec3::new(-0.6, 0.4, 0.2),
            Vec3::new(0.3, -0.2, 0.9).normalize(),
        ),
        ("far", Vec3::new(3.0, -2.0, -20.0), Vec3::Z),
    ] {
        assert_estimate(
            label,
            irradiance(&lights, p, n, 400_000, 11),
            quadrature(p, n),
        );
        // What a ray reaching the sampled point sees.
        let mut rng = Rng::new(5, 1);
        for _ in 0..1000 {
            let Some(ls) = lights.sample(p, rng.next_f32(), rng.next_2d()) else {
                continue;
            };
            let seen = lights.area_radiance(
                ls.light,
                p + ls.wi * ls.distance,
                n_light,
                Vec2::ZERO,
                -ls.wi,
                ls.distance,
            );
            assert!(
                (seen.g - ls.radiance.g).abs() <= 1e-4 * ls.radiance.g.max(1e-3),
                "{label}: a hit sees {seen:?}, the sample carried {:?}",
                ls.radiance
            );
        }
    }
    let power = lights.power(0).g;
    let expected = PI * radiance * w * l;
    assert!(
        (power / expected - 1.0).abs() < 0.01,
        "power {power} against {expected}"
    );
}

/// Light samples and BSDF samples see a bump map alike: `scenes/bumps` under its sky alone
/// (the sun taken out), direct light only (`max_depth` 2). The cache's pixel pass takes it by
/// light samples alone at that depth, `path` weighs them against BSDF samples; the mean
/// luminance of the two agree within 0.3 % (4 standard errors). Light samples used to take
/// light from the other side of the unperturbed surface, which Mitsuba's perturbed BSDFs (and
/// our BSDF samples) answer 0: light samples alone then read 0.6–0.75 % above `path`, 4 % on
/// the bumped ground.
#[test]
fn light_samples_and_bsdf_samples_agree_on_bump_maps() {
    let dir = ircache_testing::project_scenes().join("bumps");
    let text = std::fs::read_to_string(dir.join("scene.xml"))
        .unwrap()
        .replace("value=\"3, 2.8, 2.5\"", "value=\"0, 0, 0\"")
        .replace(
            "value=\"height.exr\"",
            &format!("value=\"{}\"", dir.join("height.exr").display()),
        )
        .replace(
            "value=\"normals.exr\"",
            &format!("value=\"{}\"", dir.join("normals.exr").display()),
        );
    assert!(
        text.contains("value=\"0, 0, 0\""),
        "the sun is in the scene file"
    );
    let dir = ircache_testing::ScratchDir::new("bumps-sky");
    let path = dir.join("scene.xml");
    std::fs::write(&path, text).unwrap();
    let mean = |integrator: &str| -> f64 {
        let defines: Vec<(String, String)> = [
            ("integrator", integrator),
            ("max_depth", "2"),
            ("resx", "64"),
            ("resy", "64"),
            ("spp", "64"),
        ]
        .into_iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
        let desc = ircache_scene::mitsuba::load(&path, &defines).unwrap();
        let out = common::render_desc(&desc, 2, 3);
        out.image
            .pixels
            .iter()
            .map(|&p| ircache_image::compare::luminance(p))
            .sum::<f64>()
            / out.image.pixels.len() as f64
    };
    let (direct, path_traced) = (mean("irrcache"), mean("path"));
    assert!(
        (direct / path_traced - 1.0).abs() < 3e-3,
        "direct {direct:.5} against path {path_traced:.5}"
    );
}
