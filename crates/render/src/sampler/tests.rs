//! Each sampler keeps the stratification it promises in every projection it promises, is uniform
//! (χ²) where it promises nothing more, and is a pure function of (seed, pixel, sample, dimension).

use super::kinds::{multijitter_grid, orthogonal_base};
use super::*;

fn settings(kind: SamplerKind, spp: u32) -> SamplerSettings {
    SamplerSettings::new(kind, spp, 17, 64, 48)
}

/// What `draw` takes from dimension `dim` of each of one pixel's samples.
fn points<T>(
    s: &SamplerSettings,
    x: u32,
    y: u32,
    dim: u32,
    draw: impl Fn(&mut PixelSampler<'_>) -> T,
) -> Vec<T> {
    let mut p = s.pixel(x, y);
    (0..s.spp)
        .map(|i| {
            p.set_sample(i, dim);
            draw(&mut p)
        })
        .collect()
}

/// The points of one pixel in the 2-D pair starting at `dim`.
fn points_2d(s: &SamplerSettings, x: u32, y: u32, dim: u32) -> Vec<Vec2> {
    points(s, x, y, dim, |p| p.next_2d())
}

fn points_1d(s: &SamplerSettings, x: u32, y: u32, dim: u32) -> Vec<f32> {
    points(s, x, y, dim, |p| p.next_1d())
}

/// True when every cell of an nx × ny grid holds exactly one point.
fn one_per_cell(pts: &[Vec2], nx: u32, ny: u32) -> bool {
    let mut count = vec![0u32; (nx * ny) as usize];
    for p in pts {
        assert!(
            (0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y),
            "{p}"
        );
        let (cx, cy) = ((p.x * nx as f32) as u32, (p.y * ny as f32) as u32);
        count[(cy * nx + cx) as usize] += 1;
    }
    count.iter().all(|&c| c == 1)
}

fn latin(xs: &[f32]) -> bool {
    let pts: Vec<Vec2> = xs.iter().map(|&x| Vec2::new(x, 0.5)).collect();
    one_per_cell(&pts, xs.len() as u32, 1)
}

/// Pearson's χ² of `values` in `bins` equal bins against uniform.
fn chi2(values: &[f32], bins: usize) -> f64 {
    let mut count = vec![0f64; bins];
    for &v in values {
        count[((v * bins as f32) as usize).min(bins - 1)] += 1.0;
    }
    let e = values.len() as f64 / bins as f64;
    count.iter().map(|c| (c - e) * (c - e) / e).sum()
}

const PIXELS: [(u32, u32); 4] = [(0, 0), (1, 0), (13, 7), (63, 47)];
/// Dimensions used as 2-D pairs: the film, vertex 0's light and BSDF samples, a deep vertex's.
const PAIRS: [u32; 4] = [0, 3, 6, 2 + 8 * 5 + 1];

#[test]
fn sample_counts_round_up_as_each_construction_needs() {
    use SamplerKind::*;
    assert_eq!(Independent.sample_count(10), 10);
    assert_eq!(Stratified.sample_count(10), 16);
    assert_eq!(MultiJitter.sample_count(10), 12);
    assert_eq!(MultiJitter.sample_count(64), 64);
    // Mitsuba 3's rounding: ⌊√n⌋ rows.
    assert_eq!(MultiJitter.sample_count(32), 35);
    assert_eq!(MultiJitter.sample_count(8), 8);
    assert_eq!(Orthogonal.sample_count(10), 25);
    assert_eq!(Orthogonal.sample_count(64), 121);
    assert_eq!(LowDiscrepancy.sample_count(10), 16);
    assert_eq!(Sobol.sample_count(64), 64);
    for (k, name) in SamplerKind::ALL {
        assert_eq!(SamplerKind::from_name(name), Some(k));
        assert_eq!(k.name(), name);
    }
}

#[test]
fn stratified_fills_every_stratum_in_1d_and_2d() {
    for spp in [4, 16, 64] {
        let s = settings(SamplerKind::Stratified, spp);
        let r = (spp as f32).sqrt() as u32;
        for (x, y) in PIXELS {
            for d in PAIRS {
                assert!(
                    one_per_cell(&points_2d(&s, x, y, d), r, r),
                    "spp {spp} dim {d}"
                );
                assert!(latin(&points_1d(&s, x, y, d)), "spp {spp} dim {d}");
            }
        }
    }
}

#[test]
fn multijitter_is_jittered_and_latin_at_once() {
    for spp in [12, 16, 64] {
        let s = settings(SamplerKind::MultiJitter, spp);
        let (m, k) = multijitter_grid(spp);
        for (x, y) in PIXELS {
            for d in PAIRS {
                let pts = points_2d(&s, x, y, d);
                assert!(one_per_cell(&pts, m, k), "grid, spp {spp} dim {d}");
                let xs: Vec<f32> = pts.iter().map(|p| p.x).collect();
                let ys: Vec<f32> = pts.iter().map(|p| p.y).collect();
                assert!(latin(&xs) && latin(&ys), "latin, spp {spp} dim {d}");
                assert!(latin(&points_1d(&s, x, y, d)));
            }
        }
    }
}

#[test]
fn orthogonal_stratifies_every_pair_of_dimensions() {
    for spp in [9, 25, 49] {
        let s = settings(SamplerKind::Orthogonal, spp);
        let base = orthogonal_base(spp);
        for (x, y) in PIXELS {
            let cols: Vec<Vec<f32>> = (0..base).map(|d| points_1d(&s, x, y, d)).collect();
            for c in &cols {
                assert!(latin(c), "spp {spp}");
            }
            for a in 0..base as usize {
                for b in a + 1..base as usize {
                    let pts: Vec<Vec2> = (0..spp as usize)
                        .map(|i| Vec2::new(cols[a][i], cols[b][i]))
                        .collect();
                    assert!(one_per_cell(&pts, base, base), "spp {spp} dims {a} {b}");
                }
            }
        }
    }
}

/// Every elementary interval of area 1/n of the unit square holds one point: a (0, m, 2)-net.
fn is_net(pts: &[Vec2]) -> bool {
    let m = pts.len().trailing_zeros();
    (0..=m).all(|a| one_per_cell(pts, 1 << a, 1 << (m - a)))
}

#[test]
fn ldsampler_and_sobol_are_0_2_nets_in_each_pair() {
    for kind in [SamplerKind::LowDiscrepancy, SamplerKind::Sobol] {
        for spp in [1, 2, 8, 32, 256] {
            let s = settings(kind, spp);
            for (x, y) in PIXELS {
                for d in PAIRS {
                    assert!(
                        is_net(&points_2d(&s, x, y, d)),
                        "{kind:?} spp {spp} dim {d}"
                    );
                    assert!(latin(&points_1d(&s, x, y, d)), "{kind:?} spp {spp} dim {d}");
                }
            }
        }
    }
}

#[test]
fn sobol_prefixes_of_a_pixel_are_nets_too() {
    // The first 4^k samples of a pixel form a (0, 2k, 2)-net (progressive rendering stays
    // stratified; the base-4 digit shuffling keeps only blocks of powers of 4 aligned).
    let s = settings(SamplerKind::Sobol, 64);
    for d in PAIRS {
        let pts = points_2d(&s, 5, 9, d);
        for k in [0, 2, 4, 6] {
            assert!(is_net(&pts[..1 << k]), "dim {d}, first {}", 1 << k);
        }
    }
}

#[test]
fn every_sampler_is_uniform_across_pixels_and_dimensions_are_independent() {
    for (kind, _) in SamplerKind::ALL {
        let s = SamplerSettings::new(kind, 16, 3, 64, 64);
        let (mut a, mut b, mut joint) = (Vec::new(), Vec::new(), Vec::new());
        for y in 0..32 {
            for x in 0..32 {
                let mut p = s.pixel(x, y);
                for i in 0..s.spp {
                    p.set_sample(i, 2);
                    let u = p.next_1d();
                    p.set_dimension(11);
                    let v = p.next_2d();
                    a.push(u);
                    b.push(v.y);
                    // 8 × 8 bins of (dimension 2, dimension 12) as one index in [0, 1).
                    joint.push(((u * 8.0).floor() * 8.0 + (v.y * 8.0).floor()) / 64.0);
                }
            }
        }
        // χ² with 63 degrees of freedom: 99.99 % quantile ≈ 115.
        for (what, vals) in [("dim 2", &a), ("dim 12", &b), ("joint", &joint)] {
            let c = chi2(vals, 64);
            assert!(c < 115.0, "{kind:?} {what}: χ² {c}");
        }
    }
}

#[test]
fn independent_sampler_passes_chi2_within_a_pixel() {
    let s = settings(SamplerKind::Independent, 4096);
    let pts = points_2d(&s, 3, 4, 2);
    let xs: Vec<f32> = pts.iter().map(|p| p.x).collect();
    let ys: Vec<f32> = pts.iter().map(|p| p.y).collect();
    assert!(chi2(&xs, 64) < 115.0 && chi2(&ys, 64) < 115.0);
}

#[test]
fn values_are_a_function_of_seed_pixel_sample_and_dimension() {
    for (kind, _) in SamplerKind::ALL {
        let s = settings(kind, 16);
        let mut t = s.clone();
        t.seed = 18;
        let seq = |s: &SamplerSettings, x, y| {
            let mut p = s.pixel(x, y);
            let mut v = Vec::new();
            for i in (0..s.spp).rev() {
                p.set_sample(i, 0);
                v.extend([p.next_1d(), p.next_2d().x, p.next_1d()]);
            }
            v
        };
        assert_eq!(seq(&s, 2, 3), seq(&s, 2, 3), "{kind:?}");
        assert_ne!(seq(&s, 2, 3), seq(&s, 3, 2), "{kind:?}: pixels must differ");
        assert_ne!(seq(&s, 2, 3), seq(&t, 2, 3), "{kind:?}: seeds must differ");
    }
}

#[test]
fn unjittered_strata_sit_at_their_centres() {
    let mut s = settings(SamplerKind::Stratified, 16);
    s.jitter = false;
    for p in points_2d(&s, 1, 1, 0) {
        let f = (p * 4.0).fract();
        assert!((f - Vec2::splat(0.5)).abs().max_element() < 1e-6);
    }
}

#[test]
fn progressive_sobol_prefixes_of_every_power_of_two_are_nets_and_pairs_independent() {
    // Adaptive sampling takes prefixes 8, 16, 32, … of a pixel's sequence: each must be a net,
    // odd powers of two too (the base-4 digit shuffling of the plain sampler splits those).
    let mut s = settings(SamplerKind::Sobol, 256);
    s.progressive = true;
    for (x, y) in PIXELS {
        for d in PAIRS {
            let pts = points_2d(&s, x, y, d);
            for k in 0..=8 {
                assert!(
                    is_net(&pts[..1 << k]),
                    "({x}, {y}) dim {d}, first {}",
                    1 << k
                );
            }
        }
    }
    let mut plain = settings(SamplerKind::Sobol, 256);
    plain.progressive = false;
    let split = PIXELS.iter().any(|&(x, y)| {
        PAIRS.iter().any(|&d| {
            let pts = points_2d(&plain, x, y, d);
            [1, 3, 5, 7].iter().any(|&k| !is_net(&pts[..1 << k]))
        })
    });
    assert!(
        split,
        "the plain sampler's odd prefixes were all nets: the test shows nothing"
    );
    // Different pairs do not pair the same points: dimension 3 against dimension 6 over the
    // pixels of a 32 × 32 block, 64 samples each, fills 8 × 8 bins uniformly.
    let mut s = SamplerSettings::new(SamplerKind::Sobol, 64, 3, 64, 64);
    s.progressive = true;
    let mut joint = Vec::new();
    for y in 0..32 {
        for x in 0..32 {
            let (a, b) = (points_2d(&s, x, y, 3), points_2d(&s, x, y, 6));
            for (u, v) in a.iter().zip(&b) {
                joint.push(((u.x * 8.0).floor() * 8.0 + (v.x * 8.0).floor()) / 64.0);
            }
        }
    }
    // 63 degrees of freedom: the 1e-6 tail lies near 130.
    let c = chi2(&joint, 64);
    assert!(c < 130.0, "χ² {c:.1}");
}

/// A batch (the pixel pass draws 16 samples interleaved) gives every draw the value the sampler
/// gives one sample at a time, bit for bit: each kind, power-of-two and other counts, batches
/// cut short, a dimension drawn as 1-D by one sample and 2-D by another, dimensions past the
/// batch's, the first vertex's extra samples' (held in slots of their own) and those past them.
#[test]
fn batched_draws_equal_single_draws_bit_for_bit() {
    for (kind, _) in SamplerKind::ALL {
        for spp in [1, 4, 16, 35, 64, 100, 128, 512] {
            let s = settings(kind, spp);
            let plan = |i: u32, d: u32| (i * 7 + d * 3).is_multiple_of(5);
            let single = |x: u32, y: u32, i: u32, d: u32| {
                let mut p = s.pixel(x, y);
                p.set_sample(i, d);
                if plan(i, d) {
                    Vec2::new(p.next_1d(), -1.0)
                } else {
                    p.next_2d()
                }
            };
            for (x, y) in [(0, 0), (5, 3), (63, 47)] {
                let mut p = s.pixel(x, y);
                let mut first = 0;
                while first < s.spp {
                    let len = (s.spp - first).min(16).min(3 + first % 16);
                    p.begin_batch(first, len);
                    // Interleaved as the pixel pass draws: every sample's dimension d, then d + 1.
                    let extra = crate::sampler::dims::EXTRA;
                    for d in (0..40).step_by(3).chain((extra - 3..extra + 30).step_by(3)) {
                        for i in first..first + len {
                            p.set_sample(i, d);
                            let v = if plan(i, d) {
                                Vec2::new(p.next_1d(), -1.0)
                            } else {
                                p.next_2d()
                            };
                            let w = single(x, y, i, d);
                            assert_eq!(
                                (v.x.to_bits(), v.y.to_bits()),
                                (w.x.to_bits(), w.y.to_bits()),
                                "{} spp {spp} pixel ({x}, {y}) sample {i} dim {d}",
                                kind.name()
                            );
                        }
                    }
                    first += len;
                }
            }
        }
    }
}

/// Whether `pts` (a power-of-two count N) is a rank-1 lattice with generator (1, g) (`Some(true)`)
/// or its mirror image (1, −g) (`Some(false)`), shifted: sorted by x, the points step by 1/N in x
/// and, in y, by ±g/N modulo 1, each to 24-bit precision. Random or merely stratified points are
/// neither (`None`).
fn lattice_sign(pts: &[Vec2], g: u32) -> Option<bool> {
    let n = pts.len() as f64;
    let mut sorted = pts.to_vec();
    sorted.sort_by(|a, b| a.x.total_cmp(&b.x));
    let close = |d: f64| (d - d.round()).abs() < 1e-5;
    let steps = |step: f64| {
        sorted.windows(2).all(|w| {
            close(f64::from(w[1].x - w[0].x) - 1.0 / n)
                && close(f64::from(w[1].y - w[0].y) - step / n)
        })
    };
    let g = f64::from(g);
    [true, false]
        .into_iter()
        .find(|&up| steps(if up { g } else { -g }))
}

#[test]
fn lattice_prefixes_of_every_power_of_two_are_shifted_lattices() {
    use super::permute::LATTICE_GENERATOR;
    let g = LATTICE_GENERATOR;
    for progressive in [false, true] {
        let mut s = settings(SamplerKind::Lattice, 256);
        s.progressive = progressive;
        let mut signs = [0u32; 2];
        for (x, y) in PIXELS {
            for d in PAIRS {
                let pts = points_2d(&s, x, y, d);
                let Some(up) = lattice_sign(&pts, g) else {
                    panic!("({x}, {y}) dim {d} progressive {progressive}: no lattice");
                };
                signs[usize::from(up)] += 1;
                assert!(latin(&points_1d(&s, x, y, d)), "({x}, {y}) dim {d}");
                // Progressive: every prefix; plain: the blocks of powers of 4 (base-4 digits).
                // (Two points cannot tell g from −g.)
                let step = if progressive { 1 } else { 2 };
                for k in (2..8).step_by(step) {
                    assert_eq!(
                        lattice_sign(&pts[..1 << k], g),
                        Some(up),
                        "({x}, {y}) dim {d} progressive {progressive}: first {}",
                        1 << k
                    );
                }
            }
        }
        // The mirror image is chosen per dimension: both occur over 32 pairs.
        for d in (0..64).step_by(2) {
            let up = lattice_sign(&points_2d(&s, 1, 0, d), g).expect("a lattice");
            signs[usize::from(up)] += 1;
        }
        assert!(signs.iter().all(|&c| c > 4), "{signs:?}");
    }
    // Not every point set passes: Sobol' nets are stratified but no lattice.
    let sobol = settings(SamplerKind::Sobol, 64);
    assert_eq!(lattice_sign(&points_2d(&sobol, 1, 0, 0), g), None);
}
