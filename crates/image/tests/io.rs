//! OpenEXR, PNG and 8/16-bit input; extension dispatch; atomic writes; the shared references.

mod common;

use common::{names, shared, test_image, unit, Scratch};
use exr::prelude as x;
use exr::prelude::WritableImage;
use ircache_image::{
    read_exr, read_image, read_texture, write_exr, write_image, write_png, Image, ImageError,
};
use ircache_math::Rgb;

#[test]
fn exr_round_trip_is_bit_exact() {
    let s = Scratch::new("exr-round-trip");
    let mut img = test_image(61, 37);
    // Negative, subnormal, huge and non-finite values survive too.
    let specials = [
        -1.5,
        1e-40,
        3.0e38,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -0.0,
        f32::MIN_POSITIVE,
        1.0 / 3.0,
    ];
    for (i, &v) in specials.iter().enumerate() {
        img.pixels[i] = Rgb::new(v, -v, v * 0.5);
    }
    img.pixels[20] = Rgb::new(f32::NAN, 0.0, 1.0);
    let path = s.path("a.exr");
    write_exr(&path, &img).unwrap();
    let back = read_exr(&path).unwrap();
    assert_eq!((back.width, back.height), (61, 37));
    for (i, (a, b)) in img.pixels.iter().zip(&back.pixels).enumerate() {
        let (a, b) = (
            a.to_array().map(f32::to_bits),
            b.to_array().map(f32::to_bits),
        );
        assert_eq!(a, b, "pixel {i}");
    }
    // Through the dispatcher as well, upper-case extension included.
    let p2 = s.path("b.EXR");
    write_image(&p2, &img, 5.0).unwrap();
    let back2 = read_image(&p2).unwrap();
    assert_eq!(back2.pixels[100], img.pixels[100]);
    assert_eq!(std::fs::read(&path).unwrap(), std::fs::read(&p2).unwrap());
}

#[test]
fn exr_is_zip_scanline_float_rgb() {
    let s = Scratch::new("exr-format");
    let path = s.path("a.exr");
    write_exr(&path, &test_image(40, 40)).unwrap();
    let meta = x::MetaData::read_from_file(&path, true).unwrap();
    assert_eq!(meta.headers.len(), 1);
    let h = &meta.headers[0];
    assert_eq!(h.compression, x::Compression::ZIP16);
    assert_eq!(h.blocks, exr::meta::BlockDescription::ScanLines);
    let names: Vec<String> = h.channels.list.iter().map(|c| c.name.to_string()).collect();
    assert_eq!(names, ["B", "G", "R"]);
    assert!(h
        .channels
        .list
        .iter()
        .all(|c| c.sample_type == x::SampleType::F32));
}

/// An RGBA half-float file (as many tools write) reads with alpha dropped.
#[test]
fn reads_half_rgba_exr() {
    let s = Scratch::new("exr-half");
    let path = s.path("half.exr");
    let (w, h) = (13, 7);
    let value = |p: x::Vec2<usize>| (p.x() as f32 * 0.25, p.y() as f32 * 0.5, 2.0, 0.5);
    let channels = x::SpecificChannels::rgba(|p: x::Vec2<usize>| {
        let (r, g, b, a) = value(p);
        (
            x::f16::from_f32(r),
            x::f16::from_f32(g),
            x::f16::from_f32(b),
            x::f16::from_f32(a),
        )
    });
    x::Image::from_channels((w, h), channels)
        .write()
        .to_file(&path)
        .unwrap();
    let img = read_image(&path).unwrap();
    assert_eq!((img.width, img.height), (w, h));
    for yy in 0..h {
        for xx in 0..w {
            let (r, g, b, _) = value(x::Vec2(xx, yy));
            assert_eq!(img.get(xx, yy), Rgb::new(r, g, b));
        }
    }
}

#[test]
fn exr_without_rgb_is_an_error_naming_the_file() {
    let s = Scratch::new("exr-y");
    let path = s.path("luminance.exr");
    let y = x::AnyChannels::sort(smallvec_of(x::AnyChannel::new(
        "Y",
        x::FlatSamples::F32(vec![0.5; 12]),
    )));
    x::Image::from_channels((4, 3), y)
        .write()
        .to_file(&path)
        .unwrap();
    let e = read_exr(&path).unwrap_err();
    assert!(names(&e, &path), "{e}");
    assert!(e.to_string().contains("R, G and B"), "{e}");
}

fn smallvec_of(
    c: x::AnyChannel<x::FlatSamples>,
) -> x::SmallVec<[x::AnyChannel<x::FlatSamples>; 4]> {
    let mut v = x::SmallVec::new();
    v.push(c);
    v
}

#[test]
fn bad_exr_is_an_error_naming_the_file() {
    let s = Scratch::new("exr-bad");
    let good = s.path("good.exr");
    write_exr(&good, &test_image(50, 30)).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let mut cuts: Vec<usize> = (0..60).map(|i| i * bytes.len() / 60).collect();
    cuts.extend([1, 3, 4, 7, 8, 100, bytes.len() - 1]);
    for n in cuts {
        let path = s.path(&format!("cut{n}.exr"));
        std::fs::write(&path, &bytes[..n]).unwrap();
        match read_exr(&path) {
            Err(e @ ImageError::Read { .. }) => assert!(names(&e, &path), "{e}"),
            other => panic!("truncated at {n} of {}: {other:?}", bytes.len()),
        }
    }
    let path = s.path("magic.exr");
    std::fs::write(&path, b"\x89PNG\r\n\x1a\n not an exr").unwrap();
    let e = read_image(&path).unwrap_err();
    assert!(names(&e, &path) && e.to_string().contains("OpenEXR"), "{e}");
    // Random damage: an error or an image, never a panic.
    for k in 0..200u64 {
        let mut bad = bytes.clone();
        let h = common::hash(k) as usize;
        bad[h % bytes.len()] ^= 1 << (k % 8);
        let _ = ircache_image::exr::decode(&bad);
    }
}

#[test]
fn reads_the_shared_mitsuba_references() {
    let dir = shared().join("references");
    let img = read_image(&dir.join("cornell-box-d3.exr")).unwrap();
    assert_eq!((img.width, img.height), (512, 512));
    // cornell-box-d3.json gives Mitsuba's mean RGB of this image.
    let want = [0.1658275813270828, 0.11145297425372308, 0.03346603200111253];
    for (k, w) in want.iter().enumerate() {
        let mean = img
            .pixels
            .iter()
            .map(|p| f64::from(p.to_array()[k]))
            .sum::<f64>()
            / img.pixels.len() as f64;
        assert!((mean - w).abs() < 1e-6 * w, "channel {k}: {mean} vs {w}");
    }
    for name in [
        "cornell-box-d10.exr",
        "cornell-box-emitters.exr",
        "sponza-sun-d3.exr",
        "sponza-sun-d10.exr",
    ] {
        let img = read_image(&dir.join(name)).unwrap();
        assert!(
            img.width > 0 && img.pixels.len() == img.width * img.height,
            "{name}"
        );
    }
}

/// Decodes a PNG file with the `image` crate: (width, height, RGB8 bytes).
fn png_codes(path: &std::path::Path) -> (u32, u32, Vec<u8>) {
    let img = image::open(path).unwrap();
    assert_eq!(img.color(), image::ColorType::Rgb8);
    let rgb = img.to_rgb8();
    (rgb.width(), rgb.height(), rgb.into_raw())
}

#[test]
fn png_is_8_bit_srgb_with_exposure() {
    let s = Scratch::new("png");
    let values = [0.0, 1.0, 0.5, 0.25, 2.0, -1.0, 0.002, 0.214];
    let img = Image {
        width: 4,
        height: 2,
        pixels: values.iter().map(|&v| Rgb::new(v, v * 0.5, 0.0)).collect(),
    };
    let path = s.path("a.png");
    write_png(&path, &img, 0.0).unwrap();
    let (w, h, codes) = png_codes(&path);
    assert_eq!((w, h), (4, 2));
    let red: Vec<u8> = codes.chunks(3).map(|c| c[0]).collect();
    // 0 → 0, 1 → 255, 0.5 → 188 (0.7354 · 255 = 187.5), 0.25 → 137, clamped above and below,
    // 0.002 on the linear segment → 7, 0.214 → 127 (codes from relmse.py's srgb8).
    assert_eq!(red, [0, 255, 188, 137, 255, 0, 7, 127]);
    let green: Vec<u8> = codes.chunks(3).map(|c| c[1]).collect();
    assert_eq!(green[2], 137); // 0.25
                               // Exposure +1 doubles: 0.25 shows as 0.5.
    let p2 = s.path("b.png");
    write_image(&p2, &img, 1.0).unwrap();
    let (_, _, codes2) = png_codes(&p2);
    assert_eq!(codes2[3 * 3], 188);
    assert_eq!(codes2[2 * 3 + 1], 188); // green 0.25 · 2
    assert_eq!(codes2[3], 255);
    // Exposure −1 halves: 1.0 shows as 0.5.
    write_png(&p2, &img, -1.0).unwrap();
    assert_eq!(png_codes(&p2).2[3], 188);
}

#[test]
fn srgb_and_raw_textures() {
    let s = Scratch::new("textures");
    // An RGBA PNG: alpha dropped; sRGB code 188 decodes near 0.5 linear, raw gives 188/255.
    let rgba = image::RgbaImage::from_raw(2, 1, vec![188, 0, 255, 10, 128, 64, 32, 255]).unwrap();
    let png = s.path("rgba.png");
    rgba.save(&png).unwrap();
    let lin = read_texture(&png, false).unwrap();
    assert_eq!((lin.width, lin.height), (2, 1));
    assert!(
        (lin.get(0, 0).r - 0.502_886_5).abs() < 1e-6,
        "{:?}",
        lin.get(0, 0)
    );
    assert_eq!(lin.get(0, 0).g, 0.0);
    assert_eq!(lin.get(0, 0).b, 1.0);
    assert!((lin.get(1, 0).r - 0.2158605).abs() < 1e-6);
    let raw = read_texture(&png, true).unwrap();
    assert_eq!(raw.get(0, 0), Rgb::new(188.0 / 255.0, 0.0, 1.0));
    // Grey is replicated; 16-bit values keep their precision.
    let grey = image::GrayImage::from_raw(1, 1, vec![128]).unwrap();
    let gp = s.path("grey.bmp");
    grey.save(&gp).unwrap();
    let g = read_texture(&gp, true).unwrap();
    assert_eq!(g.get(0, 0), Rgb::splat(128.0 / 255.0));
    let g16 = image::ImageBuffer::<image::Luma<u16>, _>::from_raw(1, 1, vec![30000u16]).unwrap();
    let g16p = s.path("grey16.png");
    g16.save(&g16p).unwrap();
    assert_eq!(
        read_texture(&g16p, true).unwrap().get(0, 0),
        Rgb::splat((30000.0f64 / 65535.0) as f32)
    );
    // TGA (no signature: known by its extension) and JPEG.
    let rgb = image::RgbImage::from_raw(1, 1, vec![255, 128, 0]).unwrap();
    let tga = s.path("c.tga");
    rgb.save(&tga).unwrap();
    assert_eq!(
        read_texture(&tga, true).unwrap().get(0, 0),
        Rgb::new(1.0, 128.0 / 255.0, 0.0)
    );
    let big = image::RgbImage::from_pixel(16, 16, image::Rgb([200, 200, 200]));
    let jpg = s.path("d.jpg");
    big.save(&jpg).unwrap();
    let j = read_image(&jpg).unwrap();
    assert!((j.get(8, 8).g - 0.5776).abs() < 0.02, "{:?}", j.get(8, 8));
    // HDR formats are read as stored, `raw` or not.
    let hdr = s.path("e.exr");
    let img = Image {
        width: 1,
        height: 1,
        pixels: vec![Rgb::new(0.5, 7.0, 0.0)],
    };
    write_exr(&hdr, &img).unwrap();
    assert_eq!(read_texture(&hdr, false).unwrap(), img);
    // Garbage with an image extension is an error naming the file.
    let bad = s.path("bad.png");
    std::fs::write(&bad, b"\x89PNG\r\n\x1a\n\0\0\0").unwrap();
    let e = read_texture(&bad, false).unwrap_err();
    assert!(names(&e, &bad), "{e}");
    let unknown = s.path("x.unknown");
    std::fs::write(&unknown, b"hello").unwrap();
    assert!(names(&read_image(&unknown).unwrap_err(), &unknown));
}

#[test]
fn writes_are_atomic() {
    let s = Scratch::new("atomic");
    let img = test_image(8, 8);
    // Unknown extension: an error that lists the known ones, and nothing written.
    let e = write_image(&s.path("a.tiff"), &img, 0.0).unwrap_err();
    assert!(matches!(e, ImageError::Write { .. }));
    for ext in [".exr", ".hdr", ".pic", ".png"] {
        assert!(e.to_string().contains(ext), "{e}");
    }
    // An unwritable place: an error naming the path, nothing left behind.
    let nowhere = s.path("no/such/dir/a.exr");
    let e = write_image(&nowhere, &img, 0.0).unwrap_err();
    assert!(
        matches!(e, ImageError::Write { .. }) && names(&e, &nowhere),
        "{e}"
    );
    // A failed write leaves the existing file as it was and no temporary file behind: here the
    // target is a non-empty directory, so the final rename fails.
    let keep = s.path("keep.png");
    std::fs::create_dir(&keep).unwrap();
    std::fs::write(keep.join("inside"), b"precious").unwrap();
    let e = write_png(&keep, &img, 0.0).unwrap_err();
    assert!(names(&e, &keep), "{e}");
    assert_eq!(std::fs::read(keep.join("inside")).unwrap(), b"precious");
    // An invalid image fails before touching an existing file.
    let existing = s.path("old.exr");
    write_exr(&existing, &img).unwrap();
    let before = std::fs::read(&existing).unwrap();
    let bad = Image {
        width: 3,
        height: 3,
        pixels: vec![Rgb::ZERO; 4],
    };
    assert!(write_exr(&existing, &bad).is_err());
    assert!(write_exr(&existing, &Image::new(0, 0)).is_err());
    assert_eq!(std::fs::read(&existing).unwrap(), before);
    // Overwriting works and leaves only the target.
    let mut img2 = img.clone();
    img2.pixels[0] = Rgb::splat(unit(7));
    write_exr(&existing, &img2).unwrap();
    assert_eq!(read_exr(&existing).unwrap(), img2);
    assert_eq!(s.files(), vec!["keep.png", "old.exr"]);
}
