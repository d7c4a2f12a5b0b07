//! Fuzzes the OBJ parser and the merge into one mesh: no input may panic, and every mesh produced
//! must satisfy `TriangleMesh`'s contract.
#![no_main]

use ircache_scene::mesh::{obj_to_mesh, parse_obj};
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(obj) = parse_obj(&text, Arc::new(PathBuf::from("fuzz.obj"))) {
        for g in &obj.groups {
            check(&g.mesh);
            assert_eq!(g.vertex_keys.len(), g.mesh.positions.len());
        }
        check(&obj_to_mesh(&obj));
    }
});

fn check(m: &ircache_scene::TriangleMesh) {
    let n = m.positions.len();
    for t in &m.indices {
        assert!(t.iter().all(|&i| (i as usize) < n));
    }
    if let Some(ns) = &m.normals {
        assert_eq!(ns.len(), n);
        assert!(
            ns.iter().all(|v| (v.length() - 1.0).abs() < 1e-3),
            "non-unit normal"
        );
    }
    if let Some(uv) = &m.uvs {
        assert_eq!(uv.len(), n);
    }
}
