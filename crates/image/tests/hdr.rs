//! Radiance RGBE pictures: round trips, hand-made flat and RLE files, Radiance's exact RLE bytes,
//! orientations, exposure, and bad input.

mod common;

use common::{names, test_image, Scratch};
use ircache_image::hdr::{decode, encode, encode_flat, encode_scanline, from_rgbe, to_rgbe};
use ircache_image::{read_hdr, read_image, write_hdr, write_image, Image};
use ircache_math::Rgb;

/// |a − b| within RGBE precision: half a mantissa step of the largest channel, ≤ max / 256.
fn within_rgbe(a: Rgb, b: Rgb) -> bool {
    let m = a.max_channel().max(0.0);
    let tol = m / 256.0 * (1.0 + 1e-6) + 1e-30;
    (a.r.max(0.0) - b.r).abs() <= tol
        && (a.g.max(0.0) - b.g).abs() <= tol
        && (a.b.max(0.0) - b.b).abs() <= tol
}

#[test]
fn round_trip_within_rgbe_precision() {
    let s = Scratch::new("hdr-round-trip");
    for (w, h) in [(37, 23), (5, 3), (8, 1), (300, 2)] {
        let img = test_image(w, h);
        let path = s.path("a.hdr");
        write_hdr(&path, &img).unwrap();
        let back = read_hdr(&path).unwrap();
        assert_eq!((back.width, back.height), (w, h));
        for (i, (&a, &b)) in img.pixels.iter().zip(&back.pixels).enumerate() {
            assert!(within_rgbe(a, b), "{w}×{h} pixel {i}: {a:?} vs {b:?}");
        }
        // Not trivially exact: the RGBE quantisation shows.
        assert_ne!(img, back);
    }
}

#[test]
fn rle_and_flat_agree() {
    let img = test_image(64, 17);
    let rle = encode(&img).unwrap();
    let flat = encode_flat(&img).unwrap();
    assert!(
        rle.len() < flat.len(),
        "RLE {} bytes vs flat {}",
        rle.len(),
        flat.len()
    );
    let (a, b) = (decode(&rle).unwrap(), decode(&flat).unwrap());
    assert_eq!(a, b);
    // And the RGBE bytes survive exactly: re-encoding what was read gives the same file.
    assert_eq!(encode(&a).unwrap(), rle);
}

#[test]
fn header_is_radiance_standard() {
    let img = test_image(10, 4);
    let bytes = encode(&img).unwrap();
    let text = String::from_utf8_lossy(&bytes[..70]);
    assert!(text.starts_with("#?RADIANCE\n"), "{text}");
    assert!(
        text.contains("\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 10\n"),
        "{text}"
    );
    let body = bytes
        .windows(11)
        .position(|w| w == b"-Y 4 +X 10\n")
        .unwrap()
        + 11;
    // A new-style scanline starts 2, 2, width high, width low.
    assert_eq!(&bytes[body..body + 4], &[2, 2, 0, 10]);
}

#[test]
fn rle_bytes_are_radiance_fwritecolrs() {
    // One 12-pixel scanline, every component equal to v, worked through Radiance's fwritecolrs by
    // hand: a run of 5, a literal of 1, a run of 4, and a short run of 2 (written as a run).
    let v = [5u8, 5, 5, 5, 5, 7, 8, 8, 8, 8, 9, 9];
    let pixels: Vec<[u8; 4]> = v.iter().map(|&m| [m, m, m, m]).collect();
    let component = [133u8, 5, 1, 7, 132, 8, 130, 9];
    let mut want = vec![2u8, 2, 0, 12];
    for _ in 0..4 {
        want.extend_from_slice(&component);
    }
    let mut out = Vec::new();
    encode_scanline(&mut out, &pixels);
    assert_eq!(out, want);
    // Literal chunks are at most 128 long, runs at most 127.
    let ramp: Vec<[u8; 4]> = (0..300).map(|i| [(i % 251) as u8, 7, 7, 130]).collect();
    let mut out = Vec::new();
    encode_scanline(&mut out, &ramp);
    let mut red = vec![128u8];
    red.extend((0..128).map(|i| i as u8));
    red.push(128);
    red.extend((128..251).chain(0..5).map(|i| i as u8));
    red.push(44);
    red.extend((5..49).map(|i| i as u8));
    assert_eq!(&out[4..4 + red.len()], &red[..]);
    assert_eq!(
        &out[4 + red.len()..4 + red.len() + 6],
        &[255, 7, 255, 7, 128 + 46, 7]
    );
    // Decoding gives the pixels back.
    let mut file = b"#?RADIANCE\n\n-Y 1 +X 300\n".to_vec();
    file.extend_from_slice(&out);
    let img = decode(&file).unwrap();
    for (p, q) in img.pixels.iter().zip(&ramp) {
        assert_eq!(p.to_array(), from_rgbe(*q).map(|x| x as f32));
    }
}

#[test]
fn rgbe_conversion_is_radiance_setcolr() {
    assert_eq!(to_rgbe(Rgb::new(1.0, 0.5, 0.0)), [128, 64, 0, 129]);
    assert_eq!(to_rgbe(Rgb::new(0.75, 0.0, 0.0)), [192, 0, 0, 128]);
    assert_eq!(to_rgbe(Rgb::ZERO), [0; 4]);
    assert_eq!(to_rgbe(Rgb::new(-1.0, f32::NAN, 1e-33)), [0; 4]);
    assert_eq!(to_rgbe(Rgb::new(f32::INFINITY, 0.0, 0.0)), [255, 0, 0, 255]);
    assert_eq!(to_rgbe(Rgb::new(f32::MAX, 1.0, 0.0)), [255, 0, 0, 255]);
    // Truncation, as setcolr: 0.3 · 2^8 · 2^1 = 153.6 → 153; 1e-3 → 0.512 → 0.
    assert_eq!(to_rgbe(Rgb::new(0.3, 0.2, 1e-3)), [153, 102, 0, 127]);
    assert_eq!(
        from_rgbe([128, 64, 0, 129]),
        [128.5 / 128.0, 64.5 / 128.0, 0.5 / 128.0]
    );
    assert_eq!(from_rgbe([9, 9, 9, 0]), [0.0; 3]);
}

/// A hand-made picture: flat RGBE (widths below 8 are always flat), two EXPOSURE lines, a comment.
#[test]
fn reads_hand_made_flat_file_with_exposure() {
    let mut file = b"#?RADIANCE\n# a comment\nEXPOSURE=2\nFORMAT=32-bit_rle_rgbe\nEXPOSURE= 0.5e1\n\n-Y 2 +X 3\n".to_vec();
    let colrs: [[u8; 4]; 6] = [
        [128, 64, 0, 129],
        [0, 0, 0, 0],
        [200, 100, 50, 130],
        [255, 255, 255, 120],
        [128, 128, 128, 129],
        [1, 2, 3, 140],
    ];
    for c in &colrs {
        file.extend_from_slice(c);
    }
    let s = Scratch::new("hdr-flat");
    let path = s.path("flat.pic");
    std::fs::write(&path, &file).unwrap();
    let img = read_image(&path).unwrap();
    assert_eq!((img.width, img.height), (3, 2));
    for (i, c) in colrs.iter().enumerate() {
        let want = from_rgbe(*c).map(|v| (v / 10.0) as f32);
        assert_eq!(img.pixels[i].to_array(), want, "pixel {i}");
    }
    assert_eq!(
        img.get(0, 0),
        Rgb::new(128.5 / 1280.0, 64.5 / 1280.0, 0.5 / 1280.0)
    );
}

/// A hand-made old-style file with run counts (1, 1, 1, n), one multi-byte count, width ≥ 8.
#[test]
fn reads_old_style_runs() {
    let a = [200u8, 10, 10, 128];
    let b = [10u8, 200, 10, 128];
    let mut file = b"#?RGBE\n\n-Y 1 +X 300\n".to_vec();
    file.extend_from_slice(&a);
    file.extend_from_slice(&[1, 1, 1, 9]); // 9 more a
    file.extend_from_slice(&b);
    file.extend_from_slice(&[1, 1, 1, 0x1f]); // then 0x1f + (1 << 8) more b = 287
    file.extend_from_slice(&[1, 1, 1, 1]);
    file.extend_from_slice(&[1, 1, 1, 50]); // overrun past the width is ignored, as Radiance does
    let img = decode(&file).unwrap();
    let (fa, fb) = (
        from_rgbe(a).map(|v| v as f32),
        from_rgbe(b).map(|v| v as f32),
    );
    for x in 0..300 {
        assert_eq!(
            img.get(x, 0).to_array(),
            if x < 10 { fa } else { fb },
            "x = {x}"
        );
    }
}

#[test]
fn reads_all_orientations() {
    // A 3 × 2 picture stored in each of Radiance's eight orientations decodes the same.
    let img = Image {
        width: 3,
        height: 2,
        pixels: (1..=6).map(|i| Rgb::splat(i as f32)).collect(),
    };
    let colr = |x: usize, y: usize| to_rgbe(img.get(x, y));
    let cases: [(&str, bool, bool, bool); 8] = [
        ("-Y 2 +X 3", true, false, false),
        ("-Y 2 -X 3", true, false, true),
        ("+Y 2 +X 3", true, true, false),
        ("+Y 2 -X 3", true, true, true),
        ("+X 3 -Y 2", false, false, false),
        ("+X 3 +Y 2", false, true, false),
        ("-X 3 -Y 2", false, false, true),
        ("-X 3 +Y 2", false, true, true),
    ];
    for (res, y_major, flip_y, flip_x) in cases {
        let mut file = format!("#?RADIANCE\n\n{res}\n").into_bytes();
        let fx = |x: usize| if flip_x { 2 - x } else { x };
        let fy = |y: usize| if flip_y { 1 - y } else { y };
        if y_major {
            for y in 0..2 {
                for x in 0..3 {
                    file.extend_from_slice(&colr(fx(x), fy(y)));
                }
            }
        } else {
            for x in 0..3 {
                for y in 0..2 {
                    file.extend_from_slice(&colr(fx(x), fy(y)));
                }
            }
        }
        let back = decode(&file).unwrap_or_else(|e| panic!("{res}: {e}"));
        assert_eq!((back.width, back.height), (3, 2), "{res}");
        for (p, q) in back.pixels.iter().zip(&img.pixels) {
            assert!(
                within_rgbe(*q, *p),
                "{res}: {:?} vs {:?}",
                back.pixels,
                img.pixels
            );
        }
    }
}

#[test]
fn every_truncation_is_an_error() {
    for img in [test_image(40, 6), test_image(5, 4)] {
        let full = encode(&img).unwrap();
        assert!(decode(&full).is_ok());
        for n in 0..full.len() {
            let r = decode(&full[..n]);
            assert!(
                r.is_err(),
                "{}×{}: a prefix of {n} of {} bytes decoded",
                img.width,
                img.height,
                full.len()
            );
        }
        let flat = encode_flat(&img).unwrap();
        for n in 0..flat.len() {
            assert!(decode(&flat[..n]).is_err(), "flat prefix {n}");
        }
    }
}

#[test]
fn corrupt_bytes_never_panic() {
    let full = encode(&test_image(40, 6)).unwrap();
    for k in 0..3000u64 {
        let mut bad = full.clone();
        for j in 0..1 + k % 4 {
            let h = common::hash(k * 8 + j) as usize;
            let at = h % bad.len();
            bad[at] = (h >> 16) as u8;
        }
        // Either decodes (damage that is still valid data) or is reported; never a panic.
        if let Ok(img) = decode(&bad) {
            assert_eq!(img.width * img.height, img.pixels.len());
        }
    }
}

#[test]
fn bad_files_are_errors_naming_the_file() {
    let s = Scratch::new("hdr-bad");
    let full = encode(&test_image(40, 6)).unwrap();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("magic.hdr", b"P6\n3 2\n255\n".to_vec(), "#?"),
        (
            "truncated.hdr",
            full[..full.len() - 7].to_vec(),
            "truncated",
        ),
        ("header.hdr", full[..20].to_vec(), "truncated header"),
        (
            "xyze.hdr",
            b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\x80\x80\x80\x80".to_vec(),
            "xyze",
        ),
        (
            "resolution.hdr",
            b"#?RADIANCE\n\n-Y 1 -Y 1\n\x80\x80\x80\x80".to_vec(),
            "resolution",
        ),
        (
            "huge.hdr",
            b"#?RADIANCE\n\n-Y 100000 +X 100000\n".to_vec(),
            "exceeds",
        ),
        (
            "exposure.hdr",
            b"#?RADIANCE\nEXPOSURE=-1\n\n-Y 1 +X 1\n\x80\x80\x80\x80".to_vec(),
            "exposure",
        ),
        ("empty.hdr", Vec::new(), "#?"),
    ];
    for (name, bytes, says) in cases {
        let path = s.path(name);
        std::fs::write(&path, bytes).unwrap();
        let e = read_hdr(&path).expect_err(name);
        assert!(names(&e, &path), "{e}");
        assert!(e.to_string().contains(says), "{name}: {e}");
    }
    let missing = s.path("missing.hdr");
    assert!(names(&read_hdr(&missing).unwrap_err(), &missing));
}

#[test]
fn writes_through_write_image_with_both_extensions() {
    let s = Scratch::new("hdr-ext");
    let img = test_image(9, 9);
    for name in ["a.hdr", "b.PIC"] {
        let path = s.path(name);
        write_image(&path, &img, 3.0).unwrap(); // exposure is for PNG only
        let back = read_image(&path).unwrap();
        for (a, b) in img.pixels.iter().zip(&back.pixels) {
            assert!(within_rgbe(*a, *b));
        }
    }
    assert_eq!(s.files(), vec!["a.hdr", "b.PIC"]);
}

/// Pictures written by Radiance itself (see tests/data/README.md): RLE and flat read the same,
/// within RGBE precision of the values Radiance was given; EXPOSURE is divided out; and this
/// crate's encoder reproduces Radiance's RLE bytes exactly.
#[test]
fn reads_pictures_written_by_radiance() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let values: Vec<Rgb> = std::fs::read_to_string(dir.join("radiance-values.txt"))
        .unwrap()
        .lines()
        .map(|l| {
            let v: Vec<f32> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
            Rgb::new(v[0], v[1], v[2])
        })
        .collect();
    let rle = read_hdr(&dir.join("radiance-rle.hdr")).unwrap();
    let flat = read_hdr(&dir.join("radiance-flat.hdr")).unwrap();
    let exposed = read_hdr(&dir.join("radiance-exposure.hdr")).unwrap();
    assert_eq!((rle.width, rle.height), (40, 3));
    assert_eq!(rle, flat);
    assert_eq!(rle, exposed);
    for (i, (v, p)) in values.iter().zip(&rle.pixels).enumerate() {
        assert!(within_rgbe(*v, *p), "pixel {i}: {v:?} vs {p:?}");
    }
    let radiance = std::fs::read(dir.join("radiance-rle.hdr")).unwrap();
    let ours = encode(&rle).unwrap();
    let body = |b: &[u8]| b[b.windows(2).position(|w| w == b"\n\n").unwrap() + 2..].to_vec();
    let skip_resolution =
        |b: Vec<u8>| b[b.iter().position(|&c| c == b'\n').unwrap() + 1..].to_vec();
    assert_eq!(
        skip_resolution(body(&ours)),
        skip_resolution(body(&radiance))
    );
}
