//! Tests of the safe Embree wrapper: conventions (t, barycentrics, normal orientation), ray
//! segment limits, spheres, packet/single agreement, scale invariance, input validation and
//! thread safety.

use ircache_embree::{Coherence, Device, EmbreeError, Hit, Scene, SceneBuilder};
use ircache_math::sampling::square_to_uniform_sphere;
use ircache_math::{Ray, Rng, Vec3};

fn device() -> Device {
    Device::new().expect("Embree device")
}

fn scene_of(positions: &[Vec3], indices: &[[u32; 3]]) -> Scene {
    let mut b = SceneBuilder::new(&device()).unwrap();
    assert_eq!(b.add_triangle_mesh(positions, indices).unwrap(), 0);
    b.build().unwrap()
}

fn ray(o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Ray {
    Ray { o, d, t_min, t_max }
}

/// The triangle (0,0,0), (1,0,0), (0,1,0).
fn unit_triangle() -> Scene {
    scene_of(
        &[
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        &[[0, 1, 2]],
    )
}

fn rand_vec(rng: &mut Rng, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(
        lo + (hi - lo) * rng.next_f32(),
        lo + (hi - lo) * rng.next_f32(),
        lo + (hi - lo) * rng.next_f32(),
    )
}

/// `n` random triangles of edge length ~0.2 in [-1, 1]^3, vertices not shared.
fn soup(rng: &mut Rng, n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::with_capacity(3 * n);
    let mut idx = Vec::with_capacity(n);
    for i in 0..n as u32 {
        let c = rand_vec(rng, -1.0, 1.0);
        for _ in 0..3 {
            p.push(c + rand_vec(rng, -0.1, 0.1));
        }
        idx.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    (p, idx)
}

/// Random rays of varying direction length, some with finite or shifted segments.
fn random_rays(rng: &mut Rng, n: usize) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let o = rand_vec(rng, -1.5, 1.5);
            let d = square_to_uniform_sphere(rng.next_2d()) * (0.5 + 1.5 * rng.next_f32());
            let (t_min, t_max) = match i % 4 {
                0 => (0.0, f32::INFINITY),
                1 => (0.0, 0.3 + rng.next_f32()),
                2 => (0.2 * rng.next_f32(), f32::INFINITY),
                _ => (0.1, 2.0),
            };
            ray(o, d, t_min, t_max)
        })
        .collect()
}

fn near_edge(h: &Hit) -> bool {
    h.u.min(h.v).min(1.0 - h.u - h.v) < 1e-4
}

/// Compares two query results; a disagreement about which triangle is hit is tolerated only
/// when one of the hits lies within 1e-4 (barycentric) of an edge, and is counted.
fn compare(a: Option<Hit>, b: Option<Hit>, t_scale: f32, tolerated: &mut usize, what: &str) {
    match (a, b) {
        (None, None) => {}
        (Some(a), Some(b)) if a.geom_id == b.geom_id && a.prim_id == b.prim_id => {
            let rel = (b.t - a.t * t_scale).abs() / (a.t * t_scale).abs().max(1e-30);
            assert!(rel < 1e-4, "{what}: t {} vs {} (scale {t_scale})", a.t, b.t);
            assert!(
                (a.u - b.u).abs() < 1e-3 && (a.v - b.v).abs() < 1e-3,
                "{what}: uv {a:?} vs {b:?}"
            );
            assert!(
                a.ng.normalize().dot(b.ng.normalize()) > 0.9999,
                "{what}: ng {a:?} vs {b:?}"
            );
        }
        (a, b) => {
            assert!(
                a.iter().chain(b.iter()).any(near_edge),
                "{what}: results differ away from an edge: {a:?} vs {b:?}"
            );
            *tolerated += 1;
        }
    }
}

#[test]
fn triangle_hit_t_uv_and_normal() {
    let (p0, p1, p2) = (
        Vec3::new(1.0, 0.0, 2.0),
        Vec3::new(3.0, 0.0, 2.0),
        Vec3::new(1.0, 4.0, 2.0),
    );
    let scene = scene_of(&[p0, p1, p2], &[[0, 1, 2]]);
    // Target (1 − u − v)·p0 + u·p1 + v·p2 with u = 0.2, v = 0.3 → (1.4, 1.2, 2).
    let r = ray(
        Vec3::new(1.4, 1.2, -1.0),
        Vec3::new(0.0, 0.0, 2.0),
        0.0,
        f32::INFINITY,
    );
    let h = scene.intersect(&r).expect("hit");
    assert_eq!((h.geom_id, h.prim_id), (0, 0));
    assert!((h.t - 1.5).abs() < 1e-6, "t = {}", h.t); // non-unit direction: t = 3 / 2
    assert!(
        (h.u - 0.2).abs() < 1e-6 && (h.v - 0.3).abs() < 1e-6,
        "{h:?}"
    );
    let n = h.ng.normalize();
    assert!(
        (n - Vec3::Z).length() < 1e-6,
        "ng {} must follow (p1-p0)x(p2-p0) = +z",
        h.ng
    );
    // Reversed winding flips the normal: it follows the vertex order, not the ray.
    let flipped = scene_of(&[p0, p2, p1], &[[0, 1, 2]]);
    let hf = flipped.intersect(&r).unwrap();
    assert!((hf.ng.normalize() + Vec3::Z).length() < 1e-6, "{hf:?}");
    assert!(
        (hf.u - 0.3).abs() < 1e-6 && (hf.v - 0.2).abs() < 1e-6,
        "{hf:?}"
    );
}

#[test]
fn triangle_convention_on_random_triangles() {
    let mut rng = Rng::new(11, 0);
    for _ in 0..200 {
        let (p0, p1, p2) = (
            rand_vec(&mut rng, -3.0, 3.0),
            rand_vec(&mut rng, -3.0, 3.0),
            rand_vec(&mut rng, -3.0, 3.0),
        );
        let cross = (p1 - p0).cross(p2 - p0);
        if cross.length() < 0.1 {
            continue;
        }
        let (u, v) = (0.05 + 0.4 * rng.next_f32(), 0.05 + 0.4 * rng.next_f32());
        let target = (1.0 - u - v) * p0 + u * p1 + v * p2;
        let d = square_to_uniform_sphere(rng.next_2d()) * (0.1 + 3.0 * rng.next_f32());
        if d.normalize().dot(cross.normalize()).abs() < 0.1 {
            continue; // grazing
        }
        let t0 = 0.5 + rng.next_f32();
        let scene = scene_of(&[p0, p1, p2], &[[0, 1, 2]]);
        let h = scene
            .intersect(&ray(target - t0 * d, d, 0.0, f32::INFINITY))
            .expect("hit");
        assert!((h.t - t0).abs() < 1e-4 * t0, "t {} vs {t0}", h.t);
        assert!(
            (h.u - u).abs() < 1e-4 && (h.v - v).abs() < 1e-4,
            "{h:?} vs {u} {v}"
        );
        assert!(h.ng.length() > 0.0);
        assert!(
            h.ng.normalize().dot(cross.normalize()) > 0.9999,
            "{h:?} vs {cross}"
        );
    }
}

#[test]
fn triangle_miss_segment_limits_and_occlusion() {
    let scene = unit_triangle();
    let o = Vec3::new(0.25, 0.25, 1.0);
    let down = Vec3::new(0.0, 0.0, -1.0);
    // Miss: pointing away, and passing beside the triangle.
    assert!(scene
        .intersect(&ray(o, -down, 0.0, f32::INFINITY))
        .is_none());
    assert!(scene
        .intersect(&ray(Vec3::new(0.8, 0.8, 1.0), down, 0.0, f32::INFINITY))
        .is_none());
    assert!(!scene.occluded(&ray(Vec3::new(0.8, 0.8, 1.0), down, 0.0, f32::INFINITY)));
    // The hit is at t = 1: t_max just below cuts it off, just above keeps it.
    assert!(scene.intersect(&ray(o, down, 0.0, 0.999)).is_none());
    assert!((scene.intersect(&ray(o, down, 0.0, 1.001)).unwrap().t - 1.0).abs() < 1e-6);
    // t_min beyond the hit also removes it.
    assert!(scene
        .intersect(&ray(o, down, 1.001, f32::INFINITY))
        .is_none());
    assert!(scene.occluded(&ray(o, down, 0.0, f32::INFINITY)));
    assert!(scene.occluded(&ray(o, down, 0.0, 1.001)));
    assert!(!scene.occluded(&ray(o, down, 0.0, 0.999)));
    assert!(!scene.occluded(&ray(o, down, 1.001, f32::INFINITY)));
}

/// Rays Embree would refuse (an origin at infinity or beyond 1.844e18, a NaN direction or
/// distance: numerical failures upstream) miss and are occluded, alone and in packets beside
/// good rays, which keep their answers; without the check Debian's Embree aborts the process
/// in its `ray.valid()` assertion (open fog's march once put a point at infinity).
#[test]
fn rays_embree_would_refuse_miss_instead_of_aborting() {
    let scene = unit_triangle();
    let down = Vec3::new(0.0, 0.0, -1.0);
    let good = ray(Vec3::new(0.25, 0.25, 1.0), down, 0.0, f32::INFINITY);
    let bad = [
        ray(
            Vec3::new(0.25, f32::INFINITY, 1.0),
            down,
            0.0,
            f32::INFINITY,
        ),
        ray(Vec3::new(0.25, 0.25, 1e19), down, 0.0, f32::INFINITY),
        ray(
            Vec3::new(0.25, 0.25, 1.0),
            Vec3::new(f32::NAN, 0.0, -1.0),
            0.0,
            1.0,
        ),
        ray(Vec3::new(0.25, 0.25, 1.0), down, f32::NAN, f32::INFINITY),
        ray(Vec3::new(0.25, 0.25, 1.0), down, 0.0, f32::NAN),
    ];
    for r in &bad {
        assert!(!ircache_embree::traceable(r), "{r:?}");
        assert!(scene.intersect(r).is_none(), "{r:?}");
        assert!(scene.occluded(r), "{r:?}");
    }
    assert!(ircache_embree::traceable(&good));
    let mut rays = vec![good];
    rays.extend_from_slice(&bad);
    rays.push(good);
    let mut hits = vec![None; rays.len()];
    scene.intersect16(&rays, &mut hits);
    let mut occluded = vec![false; rays.len()];
    scene.occluded16(&rays, &mut occluded);
    for (i, (h, o)) in hits.iter().zip(&occluded).enumerate() {
        let is_good = i == 0 || i == rays.len() - 1;
        assert_eq!(h.is_some(), is_good, "ray {i}: {h:?}");
        assert!(*o, "ray {i}");
    }
}

#[test]
fn sphere_hits_from_outside_and_inside_with_outward_normal() {
    let c = Vec3::new(1.0, 2.0, 3.0);
    let mut b = SceneBuilder::new(&device()).unwrap();
    let mesh = b
        .add_triangle_mesh(
            &[
                Vec3::new(50.0, 0.0, 0.0),
                Vec3::new(51.0, 0.0, 0.0),
                Vec3::new(50.0, 1.0, 0.0),
            ],
            &[[0, 1, 2]],
        )
        .unwrap();
    let spheres = b
        .add_spheres(&[(Vec3::new(-10.0, 0.0, 0.0), 1.0), (c, 0.5)])
        .unwrap();
    assert_eq!((mesh, spheres), (0, 1));
    let scene = b.build().unwrap();

    // From outside along +z with |d| = 2: surface at z = 2.5, t = 1.25.
    let h = scene
        .intersect(&ray(
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(0.0, 0.0, 2.0),
            0.0,
            f32::INFINITY,
        ))
        .unwrap();
    assert_eq!((h.geom_id, h.prim_id), (1, 1));
    assert!((h.t - 1.25).abs() < 1e-5, "t = {}", h.t);
    assert!(
        (h.ng.normalize() - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-4,
        "{h:?}"
    );

    // From the centre: exit at z = 3.5, t = 0.25, normal still outward (+z).
    let h = scene
        .intersect(&ray(c, Vec3::new(0.0, 0.0, 2.0), 0.0, f32::INFINITY))
        .unwrap();
    assert!((h.t - 0.25).abs() < 1e-5, "t = {}", h.t);
    assert!((h.ng.normalize() - Vec3::Z).length() < 1e-4, "{h:?}");

    // Generic directions from outside and inside against the analytic solution.
    let mut rng = Rng::new(5, 5);
    for i in 0..200 {
        let d = square_to_uniform_sphere(rng.next_2d()) * (0.3 + rng.next_f32());
        let inside = i % 2 == 0;
        let o = if inside {
            c + rand_vec(&mut rng, -0.2, 0.2)
        } else {
            c - d.normalize() * 2.0 + rand_vec(&mut rng, -0.2, 0.2)
        };
        // Solve |o + t d − c|² = r².
        let oc = o - c;
        let (a, bq, cq) = (d.dot(d), oc.dot(d), oc.dot(oc) - 0.25);
        let disc = bq * bq - a * cq;
        let h = scene.intersect(&ray(o, d, 0.0, f32::INFINITY));
        if disc <= 0.0 {
            assert!(h.is_none());
            continue;
        }
        let t = if inside {
            (-bq + disc.sqrt()) / a
        } else {
            (-bq - disc.sqrt()) / a
        };
        let h = h.expect("analytic hit");
        assert_eq!((h.geom_id, h.prim_id), (1, 1));
        assert!((h.t - t).abs() < 1e-4 * t.max(1.0), "t {} vs {t}", h.t);
        let outward = (o + t * d - c).normalize();
        assert!(
            h.ng.normalize().dot(outward) > 0.999,
            "{h:?} vs outward {outward}"
        );
    }
    assert!(scene.occluded(&ray(c, Vec3::X, 0.0, 0.6)));
    assert!(!scene.occluded(&ray(c, Vec3::X, 0.0, 0.4)));
}

#[test]
fn packets_match_single_rays_including_partial_packets() {
    let mut rng = Rng::new(42, 1);
    let (p, idx) = soup(&mut rng, 3000);
    let mut b = SceneBuilder::new(&device()).unwrap();
    b.add_triangle_mesh(&p, &idx).unwrap();
    b.add_spheres(&[
        (Vec3::new(0.3, -0.2, 0.1), 0.3),
        (Vec3::new(-0.5, 0.5, -0.5), 0.2),
    ])
    .unwrap();
    let scene = b.build().unwrap();
    let rays = random_rays(&mut rng, 16 * 64 + 9);
    let mut tolerated = 0;
    let mut hits_found = 0;
    let mut occ_found = 0;
    // Full packets, partial packets (1, 7, 15 rays) and a long slice that is split internally.
    let mut start = 0;
    for (k, len) in [16usize, 1, 7, 15, 16, 3].iter().cycle().enumerate() {
        if start >= rays.len() {
            break;
        }
        let end = (start + len).min(rays.len());
        let chunk = &rays[start..end];
        let mut hits = [None; 16];
        // Poison the slots beyond the chunk: they must be left alone.
        let poison = Some(Hit {
            t: -7.0,
            geom_id: 99,
            prim_id: 99,
            u: 0.0,
            v: 0.0,
            ng: Vec3::ONE,
        });
        hits.fill(poison);
        let mut occ = [true; 16];
        scene.intersect16(chunk, &mut hits);
        scene.occluded16(chunk, &mut occ[..chunk.len()]);
        // The incoherent traversal hint must not change results.
        let mut hits_inc = [None; 16];
        let mut occ_inc = [false; 16];
        scene.intersect16_with(chunk, &mut hits_inc, Coherence::Incoherent);
        scene.occluded16_with(chunk, &mut occ_inc, Coherence::Incoherent);
        for i in 0..chunk.len() {
            compare(
                hits[i],
                hits_inc[i],
                1.0,
                &mut tolerated,
                &format!("incoherent packet {k} lane {i}"),
            );
            assert!(
                occ_inc[i] == occ[i] || hits[i].is_some_and(|h| near_edge(&h)),
                "incoherent occluded16 lane {i}"
            );
        }
        for (i, r) in chunk.iter().enumerate() {
            let single = scene.intersect(r);
            compare(
                single,
                hits[i],
                1.0,
                &mut tolerated,
                &format!("packet {k} lane {i}"),
            );
            let so = scene.occluded(r);
            if so != occ[i] {
                assert!(
                    single.is_some_and(|h| near_edge(&h)),
                    "occluded16 lane {i}: {} vs {so}",
                    occ[i]
                );
                tolerated += 1;
            }
            assert_eq!(so, single.is_some(), "occluded vs intersect");
            hits_found += single.is_some() as usize;
            occ_found += so as usize;
        }
        assert!(
            hits[chunk.len()..].iter().all(|h| *h == poison),
            "slots past the rays were written"
        );
        start = end;
    }
    // The long slice path (more than 16 rays at once).
    let mut all = vec![None; rays.len()];
    scene.intersect16(&rays, &mut all);
    let mut all_occ = vec![false; rays.len()];
    scene.occluded16(&rays, &mut all_occ);
    for (i, r) in rays.iter().enumerate() {
        compare(
            scene.intersect(r),
            all[i],
            1.0,
            &mut tolerated,
            &format!("long slice ray {i}"),
        );
        assert_eq!(all_occ[i], all[i].is_some() || scene.occluded(r));
    }
    assert!(
        hits_found > rays.len() / 10 && hits_found < rays.len(),
        "degenerate test: {hits_found} hits"
    );
    assert_eq!(hits_found, occ_found);
    assert!(
        tolerated <= rays.len() / 200,
        "{tolerated} edge disagreements"
    );
}

#[test]
fn scaled_scenes_give_the_same_hits() {
    let mut rng = Rng::new(7, 3);
    let (p, idx) = soup(&mut rng, 2000);
    let rays = random_rays(&mut rng, 4000);
    let base = scene_of(&p, &idx);
    let base_hits: Vec<_> = rays.iter().map(|r| base.intersect(r)).collect();
    assert!(base_hits.iter().filter(|h| h.is_some()).count() > 400);
    for s in [1e-3f32, 1e3] {
        let ps: Vec<Vec3> = p.iter().map(|&v| v * s).collect();
        let scene = scene_of(&ps, &idx);
        let (lo, hi) = scene.bounds();
        let (blo, bhi) = base.bounds();
        assert!(
            (lo - blo * s).abs().max_element() < 1e-5 * s
                && (hi - bhi * s).abs().max_element() < 1e-5 * s
        );
        let mut tolerated = 0;
        for (r, bh) in rays.iter().zip(&base_hits) {
            // Origin and segment scale, direction is kept: t scales by s.
            let rs = ray(r.o * s, r.d, r.t_min * s, r.t_max * s);
            compare(
                *bh,
                scene.intersect(&rs),
                s,
                &mut tolerated,
                &format!("scale {s}"),
            );
            if !bh.is_some_and(|h| near_edge(&h)) {
                assert_eq!(scene.occluded(&rs), bh.is_some(), "occluded at scale {s}");
            }
        }
        assert!(
            tolerated <= rays.len() / 200,
            "scale {s}: {tolerated} edge disagreements"
        );
    }
}

#[test]
fn invalid_input_is_rejected_and_the_builder_stays_usable() {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let mut b = SceneBuilder::new(&device()).unwrap();
    let nan = b.add_triangle_mesh(
        &[Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Y],
        &[[0, 1, 2]],
    );
    assert!(matches!(nan, Err(EmbreeError::InvalidInput(_))), "{nan:?}");
    let inf = b.add_triangle_mesh(
        &[Vec3::ZERO, Vec3::X, Vec3::new(0.0, f32::INFINITY, 0.0)],
        &[[0, 1, 2]],
    );
    assert!(matches!(inf, Err(EmbreeError::InvalidInput(_))), "{inf:?}");
    let oob = b.add_triangle_mesh(&tri, &[[0, 1, 3]]);
    assert!(matches!(oob, Err(EmbreeError::InvalidInput(_))), "{oob:?}");
    for bad in [
        (Vec3::ZERO, -1.0),
        (Vec3::ZERO, 0.0),
        (Vec3::ZERO, f32::NAN),
        (Vec3::splat(f32::NAN), 1.0),
    ] {
        let r = b.add_spheres(&[(Vec3::ONE, 1.0), bad]);
        assert!(
            matches!(r, Err(EmbreeError::InvalidInput(_))),
            "{bad:?}: {r:?}"
        );
    }
    // Rejected calls consume no id, and the builder still works.
    assert_eq!(b.add_triangle_mesh(&tri, &[[0, 1, 2]]).unwrap(), 0);
    let scene = b.build().unwrap();
    assert!(scene.occluded(&ray(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, 0.0, f32::INFINITY)));
}

#[test]
fn empty_scenes_and_empty_geometry() {
    let empty = SceneBuilder::new(&device()).unwrap().build().unwrap();
    let r = ray(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY);
    assert!(empty.intersect(&r).is_none());
    assert!(!empty.occluded(&r));
    let mut hits = [Some(Hit {
        t: 1.0,
        geom_id: 0,
        prim_id: 0,
        u: 0.0,
        v: 0.0,
        ng: Vec3::X,
    }); 3];
    empty.intersect16(&[r; 3], &mut hits);
    assert!(hits.iter().all(Option::is_none));
    let mut occ = [true; 3];
    empty.occluded16(&[r; 3], &mut occ);
    assert!(occ.iter().all(|o| !o));
    let (lo, hi) = empty.bounds();
    assert!(lo.x > hi.x, "empty bounds {lo} {hi}");

    let mut b = SceneBuilder::new(&device()).unwrap();
    assert_eq!(b.add_triangle_mesh(&[], &[]).unwrap(), 0);
    assert_eq!(b.add_spheres(&[]).unwrap(), 1);
    assert_eq!(
        b.add_spheres(&[(Vec3::new(5.0, 0.0, 0.0), 1.0)]).unwrap(),
        2
    );
    let scene = b.build().unwrap();
    let h = scene.intersect(&r).unwrap();
    assert_eq!((h.geom_id, h.prim_id), (2, 0));
    assert!((h.t - 4.0).abs() < 1e-5);
    let (lo, hi) = scene.bounds();
    assert!(
        (lo - Vec3::new(4.0, -1.0, -1.0)).length() < 1e-5
            && (hi - Vec3::new(6.0, 1.0, 1.0)).length() < 1e-5,
        "{lo} {hi}"
    );
}

#[test]
fn geometry_ids_follow_call_order() {
    let mut b = SceneBuilder::new(&device()).unwrap();
    let quad = |z: f32| {
        (
            [
                Vec3::new(-1.0, -1.0, z),
                Vec3::new(1.0, -1.0, z),
                Vec3::new(1.0, 1.0, z),
                Vec3::new(-1.0, 1.0, z),
            ],
            [[0u32, 1, 2], [0, 2, 3]],
        )
    };
    let (p, i) = quad(1.0);
    assert_eq!(b.add_triangle_mesh(&p, &i).unwrap(), 0);
    assert_eq!(
        b.add_spheres(&[(Vec3::new(0.0, 0.0, 5.0), 0.5)]).unwrap(),
        1
    );
    let (p, i) = quad(3.0);
    assert_eq!(b.add_triangle_mesh(&p, &i).unwrap(), 2);
    let scene = b.build().unwrap();
    let up = |x: f32, y: f32, t_min: f32| {
        scene
            .intersect(&ray(Vec3::new(x, y, 0.0), Vec3::Z, t_min, f32::INFINITY))
            .map(|h| (h.geom_id, h.prim_id))
    };
    assert_eq!(up(0.5, -0.5, 0.0), Some((0, 0)));
    assert_eq!(up(-0.5, 0.5, 0.0), Some((0, 1)));
    assert_eq!(up(-0.5, 0.5, 2.0), Some((2, 1)));
    assert_eq!(up(0.0, 0.0, 3.5), Some((1, 0)));
}

#[test]
fn scene_is_send_sync_and_usable_from_two_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Scene>();
    assert_send_sync::<Device>();
    fn assert_send<T: Send>() {}
    assert_send::<SceneBuilder>();

    let mut rng = Rng::new(3, 9);
    let (p, idx) = soup(&mut rng, 1000);
    let scene = {
        // The scene keeps its device alive after the caller's handle is gone.
        let dev = device();
        let mut b = SceneBuilder::new(&dev).unwrap();
        b.add_triangle_mesh(&p, &idx).unwrap();
        b.build().unwrap()
    };
    let rays = random_rays(&mut rng, 2000);
    let expected: Vec<_> = rays.iter().map(|r| scene.intersect(r)).collect();
    let (a, b) = rays.split_at(1000);
    let (ra, rb) = std::thread::scope(|s| {
        let ta = s.spawn(|| a.iter().map(|r| scene.intersect(r)).collect::<Vec<_>>());
        let tb = s.spawn(|| {
            let mut hits = vec![None; b.len()];
            scene.intersect16(b, &mut hits);
            hits
        });
        (ta.join().unwrap(), tb.join().unwrap())
    });
    assert_eq!(ra, expected[..1000]);
    let mut tolerated = 0;
    for (e, h) in expected[1000..].iter().zip(rb) {
        compare(*e, h, 1.0, &mut tolerated, "thread packets");
    }
    assert!(expected.iter().any(Option::is_some));
}
