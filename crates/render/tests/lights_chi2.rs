//! χ² goodness-of-fit tests of `LightSet::sample` against `LightSet::pdf_area` /
//! `LightSet::pdf_environment`, with the shared harness in `ircache_render::testing`.
//!
//! Directions are sampled from a fixed reference point. The claimed density of a direction is the
//! one the sampler should have: for meshes, the sum of `pdf_area` over every front-facing triangle
//! the ray crosses (the sampler ignores occlusion); for spheres, `pdf_area` at the sphere point the
//! sampler would produce (first hit from outside, the only hit from inside); for the environment,
//! `pdf_environment`. Delta-light samples (point lights added to check the selection probability)
//! and back-facing samples count as "no sample", whose expected share is `1 − ∫ pdf`.
//!
//! Small emitters would fall into one bin of the harness's `(cos θ, φ)` grid, so directions are
//! first rotated into a frame around the emitter and "zoomed": `1 − cos θ' = (1 − cos θ)/ε`, with
//! the density multiplied by the Jacobian `ε` (`dω = ε dω'`).

mod common;
use common::{emitting_shape, light_scene};
use ircache_math::{Frame, Mat4, Rgb, Vec2, Vec3};
use ircache_render::lights::{LightSet, Receiver};
use ircache_render::testing::ChiSquareTest;
use ircache_scene::*;
use std::path::PathBuf;
use std::sync::Arc;

/// Overall significance level and the number of χ² tests in this file (Šidák correction).
const ALPHA: f64 = 0.01;
const TESTS: usize = 8;

/// A triangle soup whose triangles are wound so that their normals face `towards`.
fn soup_facing(tris: &[[Vec3; 3]], towards: Vec3) -> TriangleMesh {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for t in tris {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        let c = (t[0] + t[1] + t[2]) / 3.0;
        let k = positions.len() as u32;
        positions.extend_from_slice(t);
        indices.push(if n.dot(towards - c) > 0.0 {
            [k, k + 1, k + 2]
        } else {
            [k, k + 2, k + 1]
        });
    }
    TriangleMesh {
        positions,
        normals: None,
        uvs: None,
        indices,
    }
}

/// Ray–triangle intersection (Möller–Trumbore, f64): distance along unit `d`, if any.
fn hit_triangle(o: Vec3, d: Vec3, p0: Vec3, p1: Vec3, p2: Vec3) -> Option<f64> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let (p0, e1, e2) = (p0.as_dvec3(), (p1 - p0).as_dvec3(), (p2 - p0).as_dvec3());
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() < 1e-14 {
        return None;
    }
    let tv = o - p0;
    let u = tv.dot(pv) / det;
    let qv = tv.cross(e1);
    let v = d.dot(qv) / det;
    let t = e2.dot(qv) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
}

/// Rotation to a frame around `axis` plus the zoom `ε` of the module documentation.
struct View {
    frame: Frame,
    eps: f64,
}

impl View {
    fn new(axis: Vec3, eps: f64) -> View {
        View {
            frame: Frame::from_z(axis.normalize()),
            eps,
        }
    }

    /// World direction → test direction (NaN when outside the zoomed range: counted as invalid).
    fn world_to_test(&self, w: Vec3) -> Vec3 {
        let l = self.frame.to_local(w).as_dvec3().normalize();
        let s2 = l.x * l.x + l.y * l.y;
        let omc = if l.z > 0.0 {
            s2 / (1.0 + l.z)
        } else {
            1.0 - l.z
        };
        let omc2 = omc / self.eps;
        if omc2 > 2.0 {
            return Vec3::NAN;
        }
        let sin2 = (omc2 * (2.0 - omc2)).max(0.0).sqrt();
        let phi = l.y.atan2(l.x);
        Vec3::new(
            (sin2 * phi.cos()) as f32,
            (sin2 * phi.sin()) as f32,
            (1.0 - omc2) as f32,
        )
    }

    /// Test direction → world direction.
    fn test_to_world(&self, w: Vec3) -> Vec3 {
        let w = w.as_dvec3();
        let s2 = w.x * w.x + w.y * w.y;
        let omc2 = if w.z > 0.0 {
            s2 / (1.0 + w.z)
        } else {
            1.0 - w.z
        };
        let omc = omc2 * self.eps;
        let sin = (omc * (2.0 - omc)).max(0.0).sqrt();
        let phi = w.y.atan2(w.x);
        let l = Vec3::new(
            (sin * phi.cos()) as f32,
            (sin * phi.sin()) as f32,
            (1.0 - omc) as f32,
        );
        self.frame.from_local(l).normalize()
    }

    /// `ε` such that directions within `max_angle` of the axis fill most of the test sphere.
    fn eps_for(max_omc: f64) -> f64 {
        (0.6 * max_omc).min(1.0)
    }
}

/// Runs the χ² test of the set's sampling at `p` (a point or a [`Receiver`]) against
/// `pdf(world dir)`, in `view`.
fn run(
    lights: &LightSet,
    p: impl Into<Receiver> + Copy,
    view: &View,
    test: ChiSquareTest,
    pdf: impl Fn(Vec3) -> f32,
) -> ircache_render::testing::ChiSquareReport {
    let eps = view.eps as f32;
    test.run(
        |u: Vec2, u_sel: f32| {
            let ls = lights.sample(p, u_sel, u)?;
            if ls.is_delta {
                return None;
            }
            Some((view.world_to_test(ls.wi), ls.pdf * eps))
        },
        |w: Vec3| eps * pdf(view.test_to_world(w)),
    )
}

/// Density of mesh light `light` in direction `w` from `p`: all front-facing crossings.
fn mesh_pdf(lights: &LightSet, light: u32, mesh: &TriangleMesh, p: Vec3, w: Vec3) -> f32 {
    let mut sum = 0.0;
    for (prim, &[a, b, c]) in mesh.indices.iter().enumerate() {
        let (p0, p1, p2) = (
            mesh.positions[a as usize],
            mesh.positions[b as usize],
            mesh.positions[c as usize],
        );
        if let Some(t) = hit_triangle(p, w, p0, p1, p2) {
            let ng = (p1 - p0).cross(p2 - p0).normalize();
            if lights
                .area_radiance(light, Vec3::ZERO, ng, Vec2::ZERO, -w, 1.0)
                .is_black()
            {
                continue;
            }
            let pl = (p.as_dvec3() + w.as_dvec3() * t).as_vec3();
            sum += lights.pdf_area(light, prim as u32, p, pl, ng);
        }
    }
    sum
}

/// Density of sphere light `light` in direction `w` from `p` (first hit from outside, the exit
/// point from inside), zero where the hit point does not emit towards `p`.
fn sphere_pdf(lights: &LightSet, light: u32, c: Vec3, r: f32, flip: bool, p: Vec3, w: Vec3) -> f32 {
    let (o, d, c64) = (p.as_dvec3(), w.as_dvec3().normalize(), c.as_dvec3());
    let oc = o - c64;
    let b = oc.dot(d);
    let cc = oc.length_squared() - f64::from(r) * f64::from(r);
    let disc = b * b - cc;
    if disc < 0.0 {
        return 0.0;
    }
    let sq = disc.sqrt();
    let t = if cc > 0.0 { -b - sq } else { -b + sq };
    if t <= 0.0 {
        return 0.0;
    }
    let pl = o + d * t;
    let outward = ((pl - c64) / f64::from(r)).as_vec3();
    let ns = if flip { -outward } else { outward };
    if lights
        .area_radiance(light, Vec3::ZERO, ns, Vec2::ZERO, -w, 1.0)
        .is_black()
    {
        return 0.0;
    }
    lights.pdf_area(light, 0, p, pl.as_vec3(), ns)
}

/// `1 − cos` of the angle between `axis` and the direction from `p` to `q`.
fn omc(axis: Vec3, p: Vec3, q: Vec3) -> f64 {
    1.0 - f64::from(axis.normalize().dot((q - p).normalize()))
}

fn rectangle(lo: Vec2, hi: Vec2, z: f32, towards: Vec3) -> TriangleMesh {
    let v = |x: f32, y: f32| Vec3::new(x, y, z);
    soup_facing(
        &[
            [v(lo.x, lo.y), v(hi.x, lo.y), v(hi.x, hi.y)],
            [v(lo.x, lo.y), v(hi.x, hi.y), v(lo.x, hi.y)],
        ],
        towards,
    )
}

fn mesh_case(
    mesh: TriangleMesh,
    p: Vec3,
    extra_point_light: bool,
) -> (LightSet, View, TriangleMesh) {
    let emitters = if extra_point_light {
        vec![EmitterDesc::Point {
            position: Vec3::new(5.0, 0.0, 0.0),
            intensity: Rgb::ONE,
        }]
    } else {
        vec![]
    };
    let d = light_scene(
        vec![emitting_shape(
            Geometry::Mesh(mesh.clone()),
            Rgb::new(1.0, 2.0, 3.0),
        )],
        emitters,
    );
    let lights = LightSet::new(&d, Vec3::ZERO, 10.0);
    let centroid = mesh.positions.iter().copied().sum::<Vec3>() / mesh.positions.len() as f32;
    let axis = centroid - p;
    let max_omc = mesh
        .positions
        .iter()
        .map(|&q| omc(axis, p, q))
        .fold(0.0, f64::max);
    (lights, View::new(axis, View::eps_for(max_omc)), mesh)
}

#[test]
fn rectangle_area_light_with_a_point_light() {
    let p = Vec3::new(0.3, 0.2, 0.0);
    let (lights, view, mesh) = mesh_case(
        rectangle(Vec2::new(-1.0, -0.5), Vec2::new(1.0, 1.5), 1.0, p),
        p,
        true,
    );
    assert_eq!(lights.len(), 2);
    let r = run(&lights, p, &view, ChiSquareTest::sphere(), |w| {
        mesh_pdf(&lights, 0, &mesh, p, w)
    });
    r.assert_ok(ALPHA, TESTS, "rectangle + point");
    // The delta light's selections carry no density: ∫ pdf = 1 − its selection probability.
    let delta_share = f64::from(lights.selection_probability(p, 1));
    assert!(delta_share > 0.0 && delta_share < 1.0);
    assert!(
        (r.pdf_integral - (1.0 - delta_share)).abs() < 2e-3,
        "∫pdf = {} with the point light selected with probability {delta_share}",
        r.pdf_integral
    );
}

#[test]
fn wrong_density_is_rejected() {
    // Negative control: claiming the area density without the d²/cos conversion must fail.
    let p = Vec3::new(0.3, 0.2, 0.0);
    let (lights, view, mesh) = mesh_case(
        rectangle(Vec2::new(-1.0, -0.5), Vec2::new(1.0, 1.5), 1.0, p),
        p,
        false,
    );
    let r = run(
        &lights,
        p,
        &view,
        ChiSquareTest::sphere().with_samples(200_000),
        |w| {
            let pdf = mesh_pdf(&lights, 0, &mesh, p, w);
            // The area density 1/A (A = 4) in place of the solid-angle density.
            if pdf > 0.0 {
                0.25
            } else {
                0.0
            }
        },
    );
    assert!(
        !r.passes(ALPHA, TESTS),
        "a wrong density passed:\n{}",
        r.table()
    );
}

#[test]
fn uneven_triangle_mesh() {
    let p = Vec3::new(0.1, 0.2, 0.0);
    let v = Vec3::new;
    let tris = [
        // Big (area 2), small (0.005), tiny (0.001: 2000× smaller than the big one), and a tilted,
        // non-coplanar one. (A 0.001-wide sliver would be narrower than the harness's quadrature
        // nodes, which then underestimate its probability.)
        [v(-1.0, -1.0, 1.0), v(1.0, -1.0, 1.0), v(1.0, 1.0, 1.0)],
        [v(-1.0, 1.0, 1.0), v(-0.9, 1.0, 1.0), v(-1.0, 0.9, 1.0)],
        [
            v(-0.9, 0.5, 1.0),
            v(-0.855_279_6, 0.5, 1.0),
            v(-0.9, 0.544_720_4, 1.0),
        ],
        [v(0.5, 1.2, 0.6), v(1.5, 1.2, 1.0), v(1.0, 2.0, 0.8)],
    ];
    let (lights, view, mesh) = mesh_case(soup_facing(&tris, p), p, false);
    let r = run(
        &lights,
        p,
        &view,
        ChiSquareTest::sphere().with_bins(30, 30),
        |w| mesh_pdf(&lights, 0, &mesh, p, w),
    );
    r.assert_ok(ALPHA, TESTS, "uneven mesh");
    assert!(
        (r.pdf_integral - 1.0).abs() < 2e-3,
        "∫pdf = {}",
        r.pdf_integral
    );
}

fn sphere_case(p: Vec3, c: Vec3, radius: f32, flip: bool, label: &str) {
    let d = light_scene(
        vec![emitting_shape(
            Geometry::Sphere {
                center: c,
                radius,
                flip_normals: flip,
                orientation: ircache_math::Mat3::IDENTITY,
            },
            Rgb::splat(4.0),
        )],
        vec![EmitterDesc::Point {
            position: Vec3::new(0.0, 7.0, 0.0),
            intensity: Rgb::ONE,
        }],
    );
    let lights = LightSet::new(&d, c, radius);
    let dc = (c - p).length();
    let view = if dc > radius {
        let sin2 = f64::from(radius / dc).powi(2);
        let max_omc = sin2 / (1.0 + (1.0 - sin2).sqrt());
        View::new(c - p, View::eps_for(max_omc))
    } else {
        View::new(Vec3::Z, 1.0)
    };
    let r = run(&lights, p, &view, ChiSquareTest::sphere(), |w| {
        sphere_pdf(&lights, 0, c, radius, flip, p, w)
    });
    r.assert_ok(ALPHA, TESTS, label);
    // The point light's selections carry no density.
    let sphere_share = f64::from(lights.selection_probability(p, 0));
    assert!(
        (r.pdf_integral - sphere_share).abs() < 2e-3,
        "{label}: ∫pdf = {} with the sphere selected with probability {sphere_share}",
        r.pdf_integral
    );
}

#[test]
fn sphere_light_seen_from_near() {
    let c = Vec3::new(0.5, -0.2, 1.0);
    sphere_case(
        c + 1.5 * 0.8 * Vec3::new(0.6, 0.0, -0.8),
        c,
        0.8,
        false,
        "sphere near",
    );
}

#[test]
fn sphere_light_seen_from_far() {
    let c = Vec3::new(0.5, -0.2, 1.0);
    sphere_case(
        c + 40.0 * 0.8 * Vec3::new(0.0, 0.6, -0.8),
        c,
        0.8,
        false,
        "sphere far",
    );
}

#[test]
fn inward_sphere_light_seen_from_inside() {
    let c = Vec3::new(0.5, -0.2, 1.0);
    sphere_case(
        c + 0.6 * 2.0 * Vec3::new(0.48, 0.6, -0.64),
        c,
        2.0,
        true,
        "sphere inside",
    );
}

/// A 48 × 24 lat-long map: a dim gradient, a black band and a very bright 2 × 2 spot.
fn spot_envmap() -> Arc<ircache_image::Image> {
    let (w, h) = (48, 24);
    let mut img = ircache_image::Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let g = 0.05 + 0.2 * x as f32 / w as f32 + 0.1 * y as f32 / h as f32;
            img.set(x, y, Rgb::new(g, 0.5 * g, 2.0 * g));
        }
    }
    for x in 0..w {
        img.set(x, 17, Rgb::ZERO);
    }
    for (x, y) in [(30, 7), (31, 7), (30, 8), (31, 8)] {
        img.set(x, y, Rgb::new(2000.0, 1500.0, 1000.0));
    }
    Arc::new(img)
}

fn env_rotation() -> Mat4 {
    Mat4::from_rotation_x(0.4) * Mat4::from_rotation_y(1.1)
}

/// `delta`: the index of a delta light among the emitters, whose selections carry no density.
/// From a point, and from a reflecting surface there (the constant emitter's samples then
/// cosine-weighted over its hemisphere).
fn env_case(emitters: Vec<EmitterDesc>, label: &str, delta: Option<u32>) {
    let p = Vec3::new(0.3, 0.1, -0.2);
    env_case_at(emitters.clone(), Receiver::point(p), label, delta);
    let n = Vec3::new(0.3, -0.8, 0.5).normalize();
    env_case_at(
        emitters,
        Receiver::reflecting(p, n),
        &format!("{label}, at a reflecting surface"),
        delta,
    );
}

fn env_case_at(emitters: Vec<EmitterDesc>, at: Receiver, label: &str, delta: Option<u32>) {
    let d = light_scene(vec![], emitters);
    let lights = LightSet::new(&d, Vec3::ZERO, 1.0);
    assert!(lights.has_environment());
    let p = at.p;
    let r = run(
        &lights,
        at,
        &View::new(Vec3::Z, 1.0),
        ChiSquareTest::sphere().with_bins(36, 48),
        |w| lights.pdf_environment(at, w),
    );
    r.assert_ok(ALPHA, TESTS, label);
    let delta_share = delta.map_or(0.0, |i| f64::from(lights.selection_probability(p, i)));
    assert!(
        (r.pdf_integral - (1.0 - delta_share)).abs() < 2e-3,
        "{label}: ∫pdf = {}",
        r.pdf_integral
    );
}

#[test]
fn envmap_with_a_bright_spot() {
    env_case(
        vec![EmitterDesc::Envmap {
            path: PathBuf::from("<test>"),
            image: spot_envmap(),
            to_world: env_rotation(),
            scale: 1.5,
        }],
        "envmap",
        None,
    );
}

#[test]
fn constant_environment() {
    env_case(
        vec![EmitterDesc::Constant {
            radiance: Rgb::new(0.2, 0.3, 0.4),
        }],
        "constant",
        None,
    );
}

#[test]
fn constant_plus_envmap_plus_directional_mixture() {
    // Environment samples from either emitter report the mixture density; the directional light
    // takes its share of the selections.
    env_case(
        vec![
            EmitterDesc::Constant {
                radiance: Rgb::splat(0.1),
            },
            EmitterDesc::Directional {
                direction: Vec3::new(0.0, -1.0, 0.2),
                irradiance: Rgb::ONE,
            },
            EmitterDesc::Envmap {
                path: PathBuf::from("<test>"),
                image: spot_envmap(),
                to_world: env_rotation(),
                scale: 1.0,
            },
        ],
        "constant + envmap",
        Some(1),
    );
}
