//! The error measures against hand-computed values and against relmse.py on a real reference.

mod common;

use common::{perturb, shared};
use ircache_image::compare::{compare, trim_keep, CompareError, Metrics};
use ircache_image::Image;
use ircache_math::Rgb;

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

#[test]
fn hand_computed_2x2() {
    let b = Image {
        width: 2,
        height: 2,
        pixels: vec![
            Rgb::new(1.0, 0.0, 0.5),
            Rgb::new(0.0, 0.0, 0.0),
            Rgb::new(2.0, 1.0, 0.0),
            Rgb::new(0.1, 0.2, 0.3),
        ],
    };
    let a = Image {
        width: 2,
        height: 2,
        pixels: vec![
            Rgb::new(1.5, 0.0, 0.5),
            Rgb::new(0.1, 0.0, 0.0),
            Rgb::new(2.0, 1.0, 0.0),
            Rgb::new(0.1, 0.2, 0.3),
        ],
    };
    let m = compare(&a, &b).unwrap();
    // Per channel (a − b)² / (b² + 0.01): pixel 0: 0.25 / 1.01, 0, 0; pixel 1: 0.01 / 0.01 = 1, 0, 0
    // (0.1 as f32 differs from 0.1 slightly, so use the f32 value); pixels 2 and 3: 0.
    let d1 = f64::from(0.1f32);
    let want_rel = (0.25 / 1.01 + d1 * d1 / 0.01) / 12.0;
    assert!(
        close(m.rel_mse, want_rel, 1e-12),
        "{} vs {want_rel}",
        m.rel_mse
    );
    // 4 pixels: round(3.996) = 4, nothing dropped.
    assert!(close(m.rel_mse_trim, want_rel, 1e-12));
    let want_rmse = ((0.25 + d1 * d1) / 12.0f64).sqrt();
    assert!(close(m.rmse, want_rmse, 1e-12));
    let lum = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let lb = [
        lum([1.0, 0.0, 0.5]),
        0.0,
        lum([2.0, 1.0, 0.0]),
        lum(b.pixels[3].to_array().map(f64::from)),
    ];
    let la = [lum([1.5, 0.0, 0.5]), lum([d1, 0.0, 0.0]), lb[2], lb[3]];
    let want_mre = ((la[0] - lb[0]).abs() / (lb[0] + 0.01) + la[1] / 0.01) / 4.0;
    assert!(
        close(m.mre_lum, want_mre, 1e-12),
        "{} vs {want_mre}",
        m.mre_lum
    );
    let (ma, mb) = (la.iter().sum::<f64>() / 4.0, lb.iter().sum::<f64>() / 4.0);
    assert!(close(m.mean_lum_a, ma, 1e-12) && close(m.mean_lum_b, mb, 1e-12));
    assert!(close(m.lum_ratio, ma / mb, 1e-12));
    assert_eq!(m.nonfinite_a, 0);
    // Identical images: all errors zero, ratio one.
    let z = compare(&b, &b).unwrap();
    assert_eq!(
        (z.rel_mse, z.rel_mse_trim, z.rmse, z.mre_lum, z.lum_ratio),
        (0.0, 0.0, 0.0, 0.0, 1.0)
    );
}

#[test]
fn relative_error_is_relative_to_b() {
    // (a − b)² / (b² + 0.01) is not symmetric: swapping A and B changes it.
    let a = Image {
        width: 1,
        height: 1,
        pixels: vec![Rgb::splat(2.0)],
    };
    let b = Image {
        width: 1,
        height: 1,
        pixels: vec![Rgb::splat(1.0)],
    };
    assert!(close(compare(&a, &b).unwrap().rel_mse, 1.0 / 1.01, 1e-12));
    assert!(close(compare(&b, &a).unwrap().rel_mse, 1.0 / 4.01, 1e-12));
}

#[test]
fn trim_drops_exactly_the_worst_pixel_from_1000() {
    assert_eq!(trim_keep(1000), 999);
    assert_eq!(trim_keep(1499), 1498);
    assert_eq!(trim_keep(999), 998);
    assert_eq!(trim_keep(500), 500); // round(499.5) = 500, half to even
    assert_eq!(trim_keep(1), 1);
    assert_eq!(trim_keep(512 * 512), 261_882);
    for n in [1000usize, 1200, 1499] {
        let b = Image {
            width: n,
            height: 1,
            pixels: vec![Rgb::splat(1.0); n],
        };
        let mut a = b.clone();
        // Pixel i has a small error growing with i; pixel 7 is the worst by far.
        for (i, p) in a.pixels.iter_mut().enumerate() {
            *p = Rgb::splat(1.0 + 1e-3 * (i % 10) as f32);
        }
        a.pixels[7] = Rgb::splat(50.0);
        let m = compare(&a, &b).unwrap();
        let e = |i: usize| {
            let d = f64::from(a.pixels[i].r) - 1.0;
            d * d / 1.01
        };
        let all: f64 = (0..n).map(e).sum();
        let want_trim = (0..n).filter(|&i| i != 7).map(e).sum::<f64>() / (n - 1) as f64;
        assert!(close(m.rel_mse, all / n as f64, 1e-12));
        assert!(
            close(m.rel_mse_trim, want_trim, 1e-12),
            "n = {n}: {} vs {want_trim}",
            m.rel_mse_trim
        );
        assert!(m.rel_mse_trim < m.rel_mse / 10.0);
    }
}

#[test]
fn non_finite_values_are_counted_and_trimmed_first() {
    let n = 1000;
    let b = Image {
        width: 100,
        height: 10,
        pixels: vec![Rgb::splat(1.0); n],
    };
    let mut a = b.clone();
    a.pixels[3] = Rgb::new(f32::NAN, 1.0, f32::INFINITY);
    let m = compare(&a, &b).unwrap();
    assert_eq!(m.nonfinite_a, 2);
    assert!(m.rel_mse.is_nan());
    // numpy sorts NaN last, so the trim drops it: the rest is exact.
    assert_eq!(m.rel_mse_trim, 0.0);
    a.pixels[3] = Rgb::new(1.0, 1.0, f32::INFINITY);
    let m = compare(&a, &b).unwrap();
    assert_eq!(m.rel_mse, f64::INFINITY);
    assert_eq!(m.rel_mse_trim, 0.0);
}

#[test]
fn size_mismatch_names_both_sizes() {
    let e = compare(&Image::new(3, 2), &Image::new(2, 3)).unwrap_err();
    assert_eq!(
        e,
        CompareError::SizeMismatch {
            a_width: 3,
            a_height: 2,
            b_width: 2,
            b_height: 3
        }
    );
    let s = e.to_string();
    assert!(s.contains("3×2") && s.contains("2×3"), "{s}");
    assert!(matches!(
        compare(&Image::new(0, 4), &Image::new(0, 4)),
        Err(CompareError::Empty { .. })
    ));
    let bad = Image {
        width: 2,
        height: 2,
        pixels: vec![Rgb::ZERO; 3],
    };
    assert!(matches!(
        compare(&bad, &Image::new(2, 2)),
        Err(CompareError::Malformed { .. })
    ));
}

/// The reference against a deterministic perturbation of itself ([`common::perturb`]). The
/// expected figures were printed by relmse.py itself, reading the same perturbed image written by
/// this crate (`tests/export.rs`):
///   python3 shared/tools/relmse.py --json cornell-box-d3-perturbed.exr references/cornell-box-d3.exr
/// with mitsuba 3 and numpy from PyPI. Its false-colour PNG (`--falsecolor`) and the one
/// `false_colour` + `write_png` write from the same images had identical codes in every pixel.
#[test]
fn agrees_with_relmse_py_on_the_cornell_box_reference() {
    let b = ircache_image::read_image(&shared().join("references/cornell-box-d3.exr")).unwrap();
    let a = perturb(&b);
    let m = compare(&a, &b).unwrap();
    let want = Metrics {
        rel_mse: 0.14022799966054442,
        rel_mse_trim: 0.005940810138433638,
        rmse: 0.10761904222541886,
        mre_lum: 0.17059653202135674,
        lum_ratio: 1.0547701445651854,
        mean_lum_a: 0.1238114072311523,
        mean_lum_b: 0.11738235848739526,
        nonfinite_a: 0,
    };
    let pairs = [
        ("relMSE", m.rel_mse, want.rel_mse),
        ("relMSE_trim", m.rel_mse_trim, want.rel_mse_trim),
        ("RMSE", m.rmse, want.rmse),
        ("MRE_lum", m.mre_lum, want.mre_lum),
        ("lum_ratio", m.lum_ratio, want.lum_ratio),
        ("mean_lum_a", m.mean_lum_a, want.mean_lum_a),
        ("mean_lum_b", m.mean_lum_b, want.mean_lum_b),
    ];
    for (name, got, expected) in pairs {
        assert!(
            close(got, expected, 1e-9),
            "{name}: {got} vs relmse.py's {expected}"
        );
    }
    assert_eq!(m.nonfinite_a, want.nonfinite_a);
    // The trim matters here: the outliers dominate plain relMSE.
    assert!(m.rel_mse_trim < m.rel_mse / 10.0);
}
