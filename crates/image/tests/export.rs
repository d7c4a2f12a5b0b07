//! Not a check: writes files for checking this crate against outside tools. Run with
//! `IRCACHE_IMAGE_EXPORT=DIR cargo test -p ircache-image --test export -- --ignored`, then e.g.
//! `python3 shared/tools/relmse.py --json DIR/cornell-box-d3-perturbed.exr
//! shared/references/cornell-box-d3.exr` (the figures in tests/compare.rs came from that), or
//! Radiance's `getinfo` / `pvalue -o -h -H -d DIR/test.hdr` (compare with DIR/test.txt).

mod common;

use common::{perturb, shared, test_image};
use std::io::Write;

#[test]
#[ignore = "writes files for outside tools; needs IRCACHE_IMAGE_EXPORT"]
fn export_for_outside_tools() {
    let dir = std::path::PathBuf::from(
        std::env::var("IRCACHE_IMAGE_EXPORT").expect("IRCACHE_IMAGE_EXPORT=DIR"),
    );
    std::fs::create_dir_all(&dir).unwrap();
    let b = ircache_image::read_image(&shared().join("references/cornell-box-d3.exr")).unwrap();
    ircache_image::write_exr(&dir.join("cornell-box-d3-perturbed.exr"), &perturb(&b)).unwrap();
    let m = ircache_image::compare::compare(&perturb(&b), &b).unwrap();
    std::fs::write(dir.join("cornell-box-d3-perturbed.txt"), format!("{m:?}\n")).unwrap();
    let fc = ircache_image::falsecolor::false_colour(&perturb(&b), &b, 0.5);
    ircache_image::write_png(&dir.join("cornell-box-d3-falsecolour.png"), &fc, 0.0).unwrap();
    // A picture for Radiance's tools, with the values this crate reads back from it.
    let img = test_image(300, 7);
    ircache_image::write_hdr(&dir.join("test.hdr"), &img).unwrap();
    ircache_image::write_exr(&dir.join("test.exr"), &img).unwrap();
    ircache_image::write_png(&dir.join("test.png"), &img, 0.0).unwrap();
    let back = ircache_image::read_hdr(&dir.join("test.hdr")).unwrap();
    let mut f = std::fs::File::create(dir.join("test.txt")).unwrap();
    for p in &back.pixels {
        writeln!(f, "{:e}\t{:e}\t{:e}", p.r, p.g, p.b).unwrap();
    }
}
