//! Fuzzes the Radiance scene loader. Each input is written to `scene.rad` in a per-process
//! temporary folder and loaded with `radiance::load`. Inputs with a `!` are skipped: a command
//! line other than `!xform` runs through the shell, as oconv runs it, and a fuzzer must not.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn scene_path() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("ircache-fuzz-rad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temporary folder");
        dir.join("scene.rad")
    })
}

fuzz_target!(|data: &[u8]| {
    if data.contains(&b'!') {
        return;
    }
    let path = scene_path();
    std::fs::write(path, data).expect("write the input");
    let _ = ircache_scene::radiance::load(path, &Default::default());
});
