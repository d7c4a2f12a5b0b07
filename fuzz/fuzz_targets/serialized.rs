//! Fuzzes the reader of Mitsuba's serialized meshes: no input may panic or allocate without
//! bound, and every mesh produced must satisfy `TriangleMesh`'s contract.
#![no_main]

use ircache_scene::mesh::parse_serialized;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for index in 0..2 {
        if let Ok(m) = parse_serialized(data, index) {
            let m = m.mesh;
            let n = m.positions.len();
            for t in &m.indices {
                assert!(t.iter().all(|&i| (i as usize) < n));
            }
            if let Some(ns) = &m.normals {
                assert_eq!(ns.len(), n);
                assert!(ns.iter().all(|v| (v.length() - 1.0).abs() < 1e-4));
            }
            if let Some(uv) = &m.uvs {
                assert_eq!(uv.len(), n);
            }
        }
    }
});
