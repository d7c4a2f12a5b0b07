//! Fuzzes the PLY parser (ASCII and binary): no input may panic or allocate without bound, and
//! every mesh produced must satisfy `TriangleMesh`'s contract.
#![no_main]

use ircache_scene::mesh::parse_ply;
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = parse_ply(data, Arc::new(PathBuf::from("fuzz.ply"))) {
        let n = m.positions.len();
        for t in &m.indices {
            assert!(t.iter().all(|&i| (i as usize) < n));
        }
        if let Some(ns) = &m.normals {
            assert_eq!(ns.len(), n);
        }
        if let Some(uv) = &m.uvs {
            assert_eq!(uv.len(), n);
        }
    }
});
