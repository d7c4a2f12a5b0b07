//! Fuzzes the Radiance octree and compiled-mesh readers: each input is written to `scene.oct`
//! in a per-process temporary folder and read as both. An octree may name scene files (`oconv` without `-f`), which are
//! read as scene text and may hold `!` commands: inputs with a `/` (a name outside the folder)
//! or a `!` (the input itself named as scene text) are skipped, so that no command ever runs.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn scene_path() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("ircache-fuzz-oct-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temporary folder");
        dir.join("scene.oct")
    })
}

fuzz_target!(|data: &[u8]| {
    if data.contains(&b'!') || data.contains(&b'/') {
        return;
    }
    let path = scene_path();
    std::fs::write(path, data).expect("write the input");
    let _ = ircache_scene::radiance::octree::read(path, &Default::default(), 0);
    let _ = ircache_scene::radiance::mesh::read(path, &Default::default());
});
