//! Fuzzes the reader of LBNL BSDF XML files (Klems matrices, `radiance::bsdf_xml`): any text
//! either reads or gives an error; nothing may panic or allocate beyond what the text holds.
#![no_main]

use ircache_scene::klems::{matrix_entry, KlemsComponent};
use ircache_scene::radiance::bsdf_xml;
use ircache_math::Vec3;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let Ok(bsdf) = bsdf_xml::parse(&text, Path::new("fuzz.xml")) else {
        return;
    };
    // Look up a few direction pairs in every component it has.
    let dirs = [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.3, 0.5, -0.812)];
    for c in KlemsComponent::ALL {
        if let Some(m) = bsdf.component(c) {
            for a in dirs {
                for b in dirs {
                    if let Some((o, i)) = matrix_entry(c, m, a, b) {
                        let _ = m.value(o, i);
                    }
                }
            }
            for p in 0..m.incident.len().min(64) {
                let _ = m.incident.direction(p, [0.5, 0.5]);
            }
        }
    }
});
