//! Fuzzes the Mitsuba 3 XML loader. It has no string entry point, so each input is written to
//! `scene.xml` in a per-process temporary folder and loaded with `mitsuba::load`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn scene_path() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("ircache-fuzz-xml-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temporary folder");
        dir.join("scene.xml")
    })
}

fuzz_target!(|data: &[u8]| {
    let path = scene_path();
    std::fs::write(path, data).expect("write the input");
    let _ = ircache_scene::mitsuba::load(path, &[]);
});
