//! Raw single-thread Embree throughput through the safe wrapper: a random soup of ~100k
//! triangles, diffuse-bounce-like rays (origin on a random triangle, cosine-distributed
//! direction about its normal), measured for `intersect`, `occluded` and the 16-wide packets
//! (with both coherence hints), plus coherent camera-ray packets (4×4 pixel tiles) for contrast.
//!
//! Run with `cargo run --release -p ircache-embree --example raw_throughput [triangles] [rays]`.

use std::hint::black_box;
use std::time::Instant;

use ircache_embree::{Coherence, Device, Scene, SceneBuilder};
use ircache_math::sampling::square_to_cosine_hemisphere;
use ircache_math::{offset_ray_origin, Frame, Ray, Rng, Vec3};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n_tris: usize = args
        .next()
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(100_000);
    let n_rays: usize = args
        .next()
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(2_000_000);

    let mut rng = Rng::new(1234, 0);
    let mut rv = |s: f32| {
        Vec3::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
        ) * s
    };
    let mut positions = Vec::with_capacity(3 * n_tris);
    for _ in 0..n_tris {
        let c = rv(2.0);
        positions.extend([c + rv(0.05), c + rv(0.05), c + rv(0.05)]);
    }
    let indices: Vec<[u32; 3]> = (0..n_tris as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();

    let t0 = Instant::now();
    let device = Device::new()?;
    let mut builder = SceneBuilder::new(&device)?;
    builder.add_triangle_mesh(&positions, &indices)?;
    let scene = builder.build()?;
    println!(
        "{n_tris} triangles: build {:.1} ms (RTC_BUILD_QUALITY_HIGH)",
        t0.elapsed().as_secs_f64() * 1e3
    );

    // Rays leaving random points on random triangles, cosine-distributed about the normal on a
    // random side, with scale-free origin offsets as the renderer does.
    let mut rng = Rng::new(99, 1);
    let rays: Vec<Ray> = (0..n_rays)
        .map(|_| {
            let t = rng.next_below(n_tris as u32) as usize;
            let [p0, p1, p2] = [positions[3 * t], positions[3 * t + 1], positions[3 * t + 2]];
            let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let p = (1.0 - u - v) * p0 + u * p1 + v * p2;
            let mut n = (p1 - p0).cross(p2 - p0).normalize();
            if rng.next_f32() < 0.5 {
                n = -n;
            }
            let d = Frame::from_z(n).from_local(square_to_cosine_hemisphere(rng.next_2d()));
            Ray::new(offset_ray_origin(p, n, d, 1.0), d)
        })
        .collect();

    // Camera rays from outside the soup, in 4x4 pixel tiles (one packet per tile).
    let res = ((n_rays / 16) as f64).sqrt() as usize * 4;
    let eye = Vec3::new(0.0, 0.0, -3.0);
    let mut camera = Vec::with_capacity(res * res);
    for ty in (0..res).step_by(4) {
        for tx in (0..res).step_by(4) {
            for y in ty..ty + 4 {
                for x in tx..tx + 4 {
                    let px = (x as f32 + 0.5) / res as f32 * 2.0 - 1.0;
                    let py = (y as f32 + 0.5) / res as f32 * 2.0 - 1.0;
                    camera.push(Ray::new(eye, Vec3::new(px * 0.5, py * 0.5, 1.0)));
                }
            }
        }
    }

    println!("single thread, {n_rays} diffuse-bounce rays:");
    for _round in 0..2 {
        bench_all(&scene, &rays);
    }
    println!("single thread, {} camera rays in 4x4 tiles:", camera.len());
    bench_all(&scene, &camera);
    Ok(())
}

fn report(name: &str, secs: f64, n: usize, count: usize) {
    println!(
        "  {name:<26} {:7.2} Mrays/s  ({count} of {n} hit/occluded)",
        n as f64 / secs / 1e6
    );
}

fn bench_all(scene: &Scene, rays: &[Ray]) {
    let n = rays.len();
    let t = Instant::now();
    let hits = rays
        .iter()
        .filter(|r| black_box(scene.intersect(r)).is_some())
        .count();
    report("intersect", t.elapsed().as_secs_f64(), n, hits);

    let t = Instant::now();
    let occ = rays.iter().filter(|r| black_box(scene.occluded(r))).count();
    report("occluded", t.elapsed().as_secs_f64(), n, occ);

    for (name, coherence) in [
        ("coherent", Coherence::Coherent),
        ("incoherent", Coherence::Incoherent),
    ] {
        let t = Instant::now();
        let mut hits16 = [None; 16];
        let mut hits = 0;
        for chunk in rays.chunks(16) {
            scene.intersect16_with(chunk, &mut hits16, coherence);
            hits += black_box(&hits16[..chunk.len()])
                .iter()
                .filter(|h| h.is_some())
                .count();
        }
        report(
            &format!("intersect16 ({name})"),
            t.elapsed().as_secs_f64(),
            n,
            hits,
        );

        let t = Instant::now();
        let mut occ16 = [false; 16];
        let mut occ = 0;
        for chunk in rays.chunks(16) {
            scene.occluded16_with(chunk, &mut occ16, coherence);
            occ += black_box(&occ16[..chunk.len()])
                .iter()
                .filter(|&&o| o)
                .count();
        }
        report(
            &format!("occluded16 ({name})"),
            t.elapsed().as_secs_f64(),
            n,
            occ,
        );
    }
}
