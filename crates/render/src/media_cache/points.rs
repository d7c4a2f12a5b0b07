//! Irradiance and its gradients at given points in scenes with media (`ircache irradiance`):
//! by one record's gather with 002's gradients (the cache's own computation), or by brute force:
//! the value from `volpath`'s paths over the hemisphere, which share nothing with the records'
//! march (its steps, transmittance quadrature and light streams), and the translational
//! gradient by central differences of the march's gather with common random numbers (NOTES-002
//! §3.3; paths would need far more rays for a difference). The direct part is light sampling
//! with transmittance.

use super::cache::{make_record, RecordSite};
use super::gradient::{gather, March};
use super::scene_medium::SceneMedium;
use crate::integrators::path_continuation::Arrival;
use crate::integrators::volpath::{PathState, VolPathIntegrator};
use crate::integrators::RayCounts;
use crate::irradiance_cache::hemisphere::{to_world, Stratification};
use crate::irradiance_cache::points::{PointIrradiance, PointMethod};
use crate::irradiance_cache::IcParams;
use crate::media::tracking::medium_at;
use crate::media::tracking::transmittance_along;
use crate::scene::Scene;
use ircache_math::{offset_ray_origin, Frame, Ray, Rgb, Rng, Vec3, PI};
use rayon::prelude::*;

/// Direct irradiance at `p` (normal `n`, in `medium`) from `samples` light samples with
/// transmittance.
#[must_use]
pub fn direct_irradiance(
    scene: &Scene,
    p: Vec3,
    n: Vec3,
    medium: Option<usize>,
    samples: u32,
    rng: &mut Rng,
) -> Rgb {
    let mut sum = Rgb::ZERO;
    let mut rays = RayCounts::default();
    for _ in 0..samples {
        let (u_sel, u) = (rng.next_f32(), rng.next_2d());
        let Some(ls) = scene.lights.sample(p, u_sel, u) else {
            continue;
        };
        let cos = ls.wi.dot(n);
        if cos <= 0.0 || ls.pdf <= 0.0 {
            continue;
        }
        let ray = scene.shadow_ray_at(p, Some(n), ls.wi, ls.distance);
        let tr = transmittance_along(scene, ray, medium, rng, &mut rays);
        sum += tr * ls.radiance * (cos / ls.pdf);
    }
    sum / samples.max(1) as f32
}

/// Irradiance at each `(point, normal)`.
#[must_use]
pub fn media_irradiance_at_points(
    scene: &Scene,
    params: &IcParams,
    queries: &[(Vec3, Vec3)],
    method: PointMethod,
    direct_samples: u32,
    seed: u64,
) -> Vec<PointIrradiance> {
    queries
        .par_iter()
        .enumerate()
        .map(|(i, &(p, n))| {
            let medium = medium_at(scene, offset_ray_origin(p, n, n, scene.scale), n);
            let mut rng = Rng::keyed(seed, &[0x006d_6564_6961, i as u64]);
            let direct = if direct_samples > 0 {
                direct_irradiance(scene, p, n, medium, direct_samples, &mut rng)
            } else {
                Rgb::ZERO
            };
            let site = RecordSite {
                p,
                ng: n,
                n,
                medium,
                footprint: 0.0,
            };
            let (indirect, grad_t, grad_r) = match method {
                // No bounce (`-ab 0`): direct light alone.
                _ if params.bounces == 0 => (Rgb::ZERO, [Vec3::ZERO; 3], [Vec3::ZERO; 3]),
                PointMethod::Cache => {
                    let (r, _) = make_record(
                        scene,
                        params,
                        &site,
                        rng.next_u32().into(),
                        Default::default(),
                    );
                    (r.e, r.grad_t, r.grad_r)
                }
                PointMethod::BruteForce { samples } => {
                    brute_force(scene, &site, samples, params, seed ^ i as u64)
                }
            };
            PointIrradiance {
                direct,
                indirect,
                grad_t,
                grad_r,
            }
        })
        .collect()
}

/// A gather of `samples` rays (`params`' light samples per hit and march step, its bounces) and
/// central differences of it along the tangents, with the same cells' jitter at both points, at
/// a step of 1 % of the nearest opaque hit.
fn brute_force(
    scene: &Scene,
    site: &RecordSite,
    samples: usize,
    params: &IcParams,
    seed: u64,
) -> (Rgb, [Vec3; 3], [Vec3; 3]) {
    let strata = Stratification::from_divisions(samples);
    let frame = Frame::from_z(site.n);
    let axes = [frame.s.as_dvec3(), frame.t.as_dvec3(), frame.n.as_dvec3()];
    let origin = offset_ray_origin(site.p, site.ng, site.n, scene.scale).as_dvec3();
    let n = strata.azimuthal;
    let at = |x| {
        let view = SceneMedium::new(scene, site.medium, false, params.media_light_samples)
            .with_gradients(false)
            .with_deeper_bounces(params.bounces, params.media_deeper_paths, None, None);
        let march = March {
            gradients: false,
            ..March::default()
        };
        gather(&view, x, axes, strata, &march, |j, k| {
            Rng::keyed(seed, &[(j * n + k) as u64]).next_2d()
        })
    };
    let here = at(origin);
    let samples_here = here.hemisphere_samples();
    let nearest = samples_here
        .distance
        .iter()
        .copied()
        .fold(f32::INFINITY, f32::min);
    let h = if nearest.is_finite() {
        0.01 * f64::from(nearest)
    } else {
        1e-3 * f64::from(scene.radius)
    };
    let mut grad = [Vec3::ZERO; 3];
    for axis in [axes[0], axes[1]] {
        let (plus, minus) = (
            at(origin + axis * h).total_irradiance(),
            at(origin - axis * h).total_irradiance(),
        );
        for c in 0..3 {
            grad[c] += axis.as_vec3() * ((plus[c] - minus[c]) / (2.0 * h)) as f32;
        }
    }
    let grad_r = to_world(&samples_here.rotational_gradient(), frame.s, frame.t);
    let e = volpath_irradiance(
        scene,
        site.medium,
        origin.as_vec3(),
        frame,
        strata,
        params.bounces,
        seed,
    );
    (e, grad, grad_r)
}

/// E at `origin` (in `medium`, around `frame`'s normal) by `volpath`: a path along a
/// cosine-weighted direction in each cell of `strata` (jittered), through `bounces` bounces, the
/// emitters it meets directly left out as the records' gathers leave them (the medium's
/// emission along it counts, as theirs does).
fn volpath_irradiance(
    scene: &Scene,
    medium: Option<usize>,
    origin: Vec3,
    frame: Frame,
    strata: Stratification,
    bounces: u32,
    seed: u64,
) -> Rgb {
    const KEY: u64 = 0x0076_6f6c_7061_7468;
    let integrator = VolPathIntegrator::plain(VolPathIntegrator::depth_of_bounces(bounces));
    let mut rays = RayCounts::default();
    let mut sum = Rgb::ZERO;
    for j in 0..strata.polar {
        for k in 0..strata.azimuthal {
            let mut stream = Rng::keyed(seed ^ KEY, &[(j * strata.azimuthal + k) as u64]);
            let w = frame.from_local(strata.direction(j, k, stream.next_2d()));
            let mut rng = Rng::new(u64::from(stream.next_u32()), KEY);
            let start = PathState {
                ray: Ray::new(origin, w),
                medium,
                beta: Rgb::ONE,
                depth: 1,
                arrival: Arrival::Gather,
                caustic_chain: false,
            };
            sum += integrator
                .trace(scene, start, None, false, &mut stream, &mut rng, &mut rays)
                .all;
        }
    }
    sum * (PI / strata.cells() as f32)
}

#[cfg(test)]
mod diag {
    use super::*;
    use crate::media_cache::gradient::{GatherMedium, StepExtent};

    struct Probe<'a> {
        inner: &'a SceneMedium<'a>,
        base: DVec3,
        freeze_sigma: bool,
        freeze_q: bool,
        zero_gq: bool,
        zero_gs: bool,
    }
    use ircache_math::DVec3;
    impl GatherMedium for Probe<'_> {
        fn surface(&self, _o: DVec3, w: DVec3) -> (f64, [f64; 3]) {
            self.inner.surface(self.base, w)
        }
        fn boundaries(&self, _o: DVec3, w: DVec3, t: f64) -> Vec<(f64, DVec3)> {
            self.inner.boundaries(self.base, w, t)
        }
        fn sigma_t(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
            self.inner
                .sigma_t(if self.freeze_sigma { self.base } else { o }, w, t)
        }
        fn sigma_t_gradient(&self, o: DVec3, w: DVec3, t: f64) -> [DVec3; 3] {
            if self.zero_gs {
                [DVec3::ZERO; 3]
            } else {
                self.inner.sigma_t_gradient(o, w, t)
            }
        }
        fn step_extent(&self, _o: DVec3, w: DVec3, t: f64, b: f64) -> (f64, f64) {
            self.inner.step_extent(self.base, w, t, b)
        }
        fn source(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
            self.inner
                .source(if self.freeze_q { self.base } else { o }, w, t)
        }
        fn source_gradient(&self, o: DVec3, w: DVec3, t: f64) -> [DVec3; 3] {
            if self.zero_gq {
                [DVec3::ZERO; 3]
            } else {
                self.inner.source_gradient(o, w, t)
            }
        }
        fn step_source(&self, o: DVec3, w: DVec3, st: &StepExtent) -> [f64; 3] {
            self.inner
                .step_source(if self.freeze_q { self.base } else { o }, w, st)
        }
        fn step_source_gradient(&self, o: DVec3, w: DVec3, st: &StepExtent) -> [DVec3; 3] {
            if self.zero_gq {
                [DVec3::ZERO; 3]
            } else {
                self.inner.step_source_gradient(o, w, st)
            }
        }
    }

    fn scene(no_boxes: bool) -> Scene {
        let name = std::env::var("DIAG_SCENE").unwrap_or("smoke-box".into());
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("../../scenes/{name}/scene.xml"));
        let mut desc = ircache_scene::mitsuba::load(&path, &[]).unwrap();
        if no_boxes {
            desc.shapes
                .retain(|s| !matches!(s.id.as_deref(), Some("ShortBox" | "TallBox")));
        }
        if std::env::var("DIAG_HOMOG").is_ok() {
            desc.media[0].kind = ircache_scene::desc::MediumKind::Homogeneous;
            desc.media[0].sigma_t = ircache_scene::desc::VolumeDesc::constant(Rgb::splat(3.0));
            desc.media[0].scale = 1.0;
        }
        Scene::build(&desc).unwrap()
    }

    #[test]
    #[ignore]
    fn parts() {
        let scene = scene(std::env::var("DIAG_BOXES").is_err());
        let (p, nrm) = match std::env::var("DIAG_POINT").as_deref() {
            Ok("left") => (Vec3::new(-0.99, 1.0, 0.0), Vec3::X),
            Ok("floor") => (Vec3::new(-0.5, 0.001, 0.5), Vec3::Y),
            _ => (Vec3::new(0.0, 1.0, -0.99), Vec3::Z),
        };
        let frame = Frame::from_z(nrm);
        let axes = [frame.s.as_dvec3(), frame.t.as_dvec3(), frame.n.as_dvec3()];
        eprintln!("axes {:?}", axes);
        let origin = offset_ray_origin(p, nrm, nrm, scene.scale).as_dvec3();
        let medium = medium_at(&scene, offset_ray_origin(p, nrm, nrm, scene.scale), nrm);
        let ls: u32 = std::env::var("DIAG_LS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(4);
        let div: usize = std::env::var("DIAG_DIV")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(20000);
        let hfrac: f64 = std::env::var("DIAG_H")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(0.01);
        let strata = Stratification::from_divisions(div);
        let n = strata.azimuthal;
        let seeds = 8u64;
        let c = 1;
        let ostep: f64 = std::env::var("DIAG_STEP")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(0.1);
        let rows: Vec<Vec<(&'static str, [f64; 2])>> = (0..seeds)
            .into_par_iter()
            .map(|seed| {
                let mut out = Vec::new();
                let view = SceneMedium::new(&scene, medium, false, ls)
                    .with_tangents([axes[0], axes[1]])
                    .with_gradients(true)
                    .with_deeper_bounces(1, 0, None, None);
                let v = |l: crate::irradiance_cache::hemisphere::LocalGradient| {
                    [f64::from(l[c].x), f64::from(l[c].y)]
                };
                {
                    let g = gather(
                        &view,
                        origin,
                        axes,
                        strata,
                        &March {
                            optical_step: ostep,
                            max_steps: 4096,
                            ..March::default()
                        },
                        |j, k| Rng::keyed(seed, &[(j * n + k) as u64]).next_2d(),
                    );
                    let parts = g.gradient_parts();
                    out.push(("p surface_walls", v(parts.surface_walls)));
                    out.push(("p absorption", v(parts.absorption)));
                    out.push(("p medium_walls", v(parts.medium_walls)));
                    out.push(("p interior_rigid", v(parts.interior_rigid)));
                    out.push(("p radial", v(parts.radial)));
                    out.push(("p interfaces", v(parts.interfaces)));
                    let (a, b) = (v(parts.surface_walls), v(parts.absorption));
                    out.push(("q analytic surface", [a[0] + b[0], a[1] + b[1]]));
                    let m = [
                        parts.medium_walls,
                        parts.interior_rigid,
                        parts.radial,
                        parts.interfaces,
                    ]
                    .map(v);
                    out.push((
                        "q analytic medium",
                        [m.iter().map(|x| x[0]).sum(), m.iter().map(|x| x[1]).sum()],
                    ));
                }
                for (name, zq, zs) in [
                    ("a rigid: gq only", false, true),
                    ("b rigid: gs only", true, false),
                ] {
                    let probe = Probe {
                        inner: &view,
                        base: origin,
                        freeze_sigma: false,
                        freeze_q: false,
                        zero_gq: zq,
                        zero_gs: zs,
                    };
                    let g = gather(
                        &probe,
                        origin,
                        axes,
                        strata,
                        &March {
                            optical_step: ostep,
                            max_steps: 4096,
                            ..March::default()
                        },
                        |j, k| Rng::keyed(seed, &[(j * n + k) as u64]).next_2d(),
                    );
                    out.push((name, v(g.gradient_parts().interior_rigid)));
                }
                let fstrata = Stratification::from_divisions(100_000);
                let fnn = fstrata.azimuthal;
                let fview = SceneMedium::new(&scene, medium, false, ls)
                    .with_gradients(false)
                    .with_deeper_bounces(1, 0, None, None);
                let at = |x: DVec3, fs: bool, fq: bool| {
                    let probe = Probe {
                        inner: &fview,
                        base: origin,
                        freeze_sigma: fs,
                        freeze_q: fq,
                        zero_gq: true,
                        zero_gs: true,
                    };
                    let march = March {
                        gradients: false,
                        optical_step: ostep,
                        max_steps: 4096,
                        ..March::default()
                    };
                    gather(&probe, x, axes, fstrata, &march, |j, k| {
                        Rng::keyed(seed + 100, &[(j * fnn + k) as u64]).next_2d()
                    })
                };
                let h = hfrac;
                {
                    let full = |x: DVec3| {
                        let march = March {
                            gradients: false,
                            optical_step: ostep,
                            max_steps: 4096,
                            ..March::default()
                        };
                        gather(&fview, x, axes, fstrata, &march, |j, k| {
                            Rng::keyed(seed + 100, &[(j * fnn + k) as u64]).next_2d()
                        })
                        .irradiance()
                    };
                    let (mut fs, mut fm) = ([0.0; 2], [0.0; 2]);
                    for (i, axis) in [axes[0], axes[1]].into_iter().enumerate() {
                        let (pl, mi) = (full(origin + axis * h), full(origin - axis * h));
                        fs[i] = (pl.0[c] - mi.0[c]) / (2.0 * h);
                        fm[i] = (pl.1[c] - mi.1[c]) / (2.0 * h);
                    }
                    out.push(("r fd surface", fs));
                    out.push(("r fd medium", fm));
                }
                for (name, fs, fq) in [
                    ("c fd q only", true, false),
                    ("d fd sigma only", false, true),
                ] {
                    let mut fm = [0.0; 2];
                    for (i, axis) in [axes[0], axes[1]].into_iter().enumerate() {
                        let (pl, mi) = (
                            at(origin + axis * h, fs, fq).irradiance(),
                            at(origin - axis * h, fs, fq).irradiance(),
                        );
                        fm[i] = (pl.1[c] - mi.1[c]) / (2.0 * h);
                    }
                    out.push((name, fm));
                }
                out
            })
            .collect();
        let mut acc = std::collections::BTreeMap::<&str, [f64; 4]>::new();
        for r in rows {
            for (k, v) in r {
                let e = acc.entry(k).or_insert([0.0; 4]);
                e[0] += v[0];
                e[1] += v[1];
                e[2] += v[0] * v[0];
                e[3] += v[1] * v[1];
            }
        }
        let ns = seeds as f64;
        for (k, v) in &acc {
            let (m0, m1) = (v[0] / ns, v[1] / ns);
            let se = |sq: f64, m: f64| ((sq / ns - m * m).max(0.0) / (ns - 1.0)).sqrt();
            eprintln!(
                "{k:20} {:+.5} ± {:.5}  {:+.5} ± {:.5}",
                m0,
                se(v[2], m0),
                m1,
                se(v[3], m1)
            );
        }
    }

    #[test]
    #[ignore]
    fn sigma_grad() {
        let scene = scene(true);
        let p = Vec3::new(0.0, 1.0, -0.99);
        let nrm = Vec3::Z;
        let frame = Frame::from_z(nrm);
        let axes = [frame.s.as_dvec3(), frame.t.as_dvec3(), frame.n.as_dvec3()];
        let origin = offset_ray_origin(p, nrm, nrm, scene.scale).as_dvec3();
        let medium = medium_at(&scene, offset_ray_origin(p, nrm, nrm, scene.scale), nrm);
        let view = SceneMedium::new(&scene, medium, false, 4).with_tangents([axes[0], axes[1]]);
        let mut rng = Rng::new(3, 4);
        let h = 1e-4;
        let (mut sa, mut sf) = (DVec3::ZERO, DVec3::ZERO);
        for _ in 0..2000 {
            let u = rng.next_2d();
            let w = (axes[2]
                + axes[0] * (f64::from(u.x) - 0.5) * 1.5
                + axes[1] * (f64::from(u.y) - 0.5) * 1.5)
                .normalize();
            let t = 0.5 + 1.8 * f64::from(rng.next_f32());
            let g = view.sigma_t_gradient(origin, w, t)[1];
            let mut f = DVec3::ZERO;
            for a in [axes[0], axes[1]] {
                let d = (view.sigma_t(origin + a * h, w, t)[1]
                    - view.sigma_t(origin - a * h, w, t)[1])
                    / (2.0 * h);
                f += a * d;
            }
            sa += g.abs();
            sf += f.abs();
            if (g - f).length() > 0.05 * f.length().max(1.0) {
                eprintln!(
                    "t {t:.3} w {w:?}: analytic {g:?} fd {f:?} sigma {:?}",
                    view.sigma_t(origin, w, t)
                );
            }
        }
        eprintln!("sum |analytic| {sa:?} sum |fd| {sf:?}");
    }

    #[test]
    #[ignore]
    fn single_rays() {
        let scene = scene(true);
        let p = Vec3::new(0.0, 1.0, -0.99);
        let nrm = Vec3::Z;
        let frame = Frame::from_z(nrm);
        let axes = [frame.s.as_dvec3(), frame.t.as_dvec3(), frame.n.as_dvec3()];
        let origin = offset_ray_origin(p, nrm, nrm, scene.scale).as_dvec3();
        let medium = medium_at(&scene, offset_ray_origin(p, nrm, nrm, scene.scale), nrm);
        let strata = Stratification::from_divisions(1);
        let h: f64 = std::env::var("DIAG_H")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(1e-4);
        let mut rng = Rng::new(7, 1);
        let (mut sa, mut sf) = (0.0, 0.0);
        for i in 0..400 {
            let u = rng.next_2d();
            if std::env::var("DIAG_ONLY").is_ok() && i != 0 {
                continue;
            }
            let view = SceneMedium::new(&scene, medium, false, 4)
                .with_tangents([axes[0], axes[1]])
                .with_gradients(true);
            let probe = Probe {
                inner: &view,
                base: origin,
                freeze_sigma: false,
                freeze_q: true,
                zero_gq: true,
                zero_gs: false,
            };
            let key = 1000 + i as u64;
            let g = gather(&probe, origin, axes, strata, &March::default(), |_, _| u);
            let a = g.gradient_parts().interior_rigid[1].x as f64;
            let fview = SceneMedium::new(&scene, medium, false, 4).with_gradients(false);
            let fprobe = Probe {
                inner: &fview,
                base: origin,
                freeze_sigma: false,
                freeze_q: true,
                zero_gq: true,
                zero_gs: true,
            };
            let march = March {
                gradients: false,
                ..March::default()
            };
            let e = |x: DVec3| {
                gather(&fprobe, x, axes, strata, &march, |_, _| u)
                    .irradiance()
                    .1[1]
            };
            let f = (e(origin + axes[0] * h) - e(origin - axes[0] * h)) / (2.0 * h);
            let _ = key;
            sa += a;
            sf += f;
            if (a - f).abs() > 0.02 * f.abs().max(0.01) {
                eprintln!(
                    "{i} u {u:?}: analytic {a:.5} fd {f:.5} steps {}",
                    g.march_steps
                );
            }
        }
        eprintln!("sum analytic {sa:.4} fd {sf:.4}");
    }

    #[test]
    #[ignore]
    fn outlier() {
        let scene = scene(std::env::var("DIAG_BOXES").is_err());
        let (p, nrm) = (Vec3::new(-0.5, 0.001, 0.5), Vec3::Y);
        let medium = medium_at(&scene, offset_ray_origin(p, nrm, nrm, scene.scale), nrm);
        let frame = Frame::from_z(nrm);
        let axes = [frame.s.as_dvec3(), frame.t.as_dvec3(), frame.n.as_dvec3()];
        let origin = offset_ray_origin(p, nrm, nrm, scene.scale).as_dvec3();
        let seed: u64 = std::env::var("DIAG_SEED")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(3);
        let div: usize = std::env::var("DIAG_DIV")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(80000);
        let mut rng = Rng::keyed(seed, &[0x006d_6564_6961, 0]);
        let key: u64 = rng.next_u32().into();
        let strata = Stratification::from_divisions(div);
        let n = strata.azimuthal;
        let view = SceneMedium::new(&scene, medium, false, 4)
            .with_tangents([axes[0], axes[1]])
            .with_gradients(true)
            .with_deeper_bounces(1, 0, None, None);
        let g = gather(&view, origin, axes, strata, &March::default(), |j, k| {
            Rng::keyed(key, &[(j * n + k) as u64]).next_2d()
        });
        let parts = g.gradient_parts();
        eprintln!("{parts:#?}");
        let (j, k) = (16561 / n, 16561 % n);
        let local = strata
            .direction(j, k, Rng::keyed(key, &[(j * n + k) as u64]).next_2d())
            .as_dvec3();
        let w = (axes[0] * local.x + axes[1] * local.y + axes[2] * local.z).normalize();
        for i in 0..40 {
            let t = 1.9 + 0.0088 * f64::from(i);
            let q = view.source(origin, w, t)[1];
            let gq = view.source_gradient(origin, w, t)[1];
            eprintln!("t {t:.4} x {:?} q {q:.4} gq {gq:.2?}", (origin + w * t));
        }
    }
}
