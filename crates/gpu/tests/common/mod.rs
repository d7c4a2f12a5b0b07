//! What the GPU tests share: the device, and scenes loaded at one bounce (`max_depth` 3).
//! Each test crate uses part of it.
#![allow(dead_code)]

use ircache_gpu::{Gpu, GpuError};
use ircache_scene::SceneDesc;
use std::sync::Arc;

/// The first device wgpu finds (Mesa's lavapipe where there is no GPU). With none the test
/// fails and says so, unless `IRCACHE_GPU_TESTS=skip`: then `None`, and the test returns.
pub fn gpu() -> Option<Arc<Gpu>> {
    match Gpu::new() {
        Ok(g) => {
            eprintln!("GPU: {}", g.describe());
            Some(Arc::new(g))
        }
        Err(e @ GpuError::NoDevice(_))
            if std::env::var("IRCACHE_GPU_TESTS").as_deref() == Ok("skip") =>
        {
            eprintln!("SKIPPED (IRCACHE_GPU_TESTS=skip): {e}");
            None
        }
        Err(e) => panic!("{e} (set IRCACHE_GPU_TESTS=skip to skip the GPU tests)"),
    }
}

/// The scene at `path`, one bounce.
pub fn load(path: &str) -> SceneDesc {
    ircache_scene::load_scene(
        std::path::Path::new(path),
        &[("max_depth".into(), "3".into())],
        &ircache_scene::obj_scene::ObjCamera::default(),
    )
    .unwrap_or_else(|e| panic!("{path} loads: {e}"))
}

/// The shared scene `name` (`../shared/scenes/NAME/scene.xml`), one bounce.
pub fn shared(name: &str) -> SceneDesc {
    load(&format!(
        "{}/../../../shared/scenes/{name}/scene.xml",
        env!("CARGO_MANIFEST_DIR")
    ))
}
