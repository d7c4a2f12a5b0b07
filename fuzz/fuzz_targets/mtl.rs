//! Fuzzes the MTL parser: no input may panic.
#![no_main]

use ircache_scene::mesh::parse_mtl;
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let _ = parse_mtl(&text, Arc::new(PathBuf::from("fuzz.mtl")));
});
