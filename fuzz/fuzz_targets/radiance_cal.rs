//! Fuzzes Radiance's function language: the input's first line is an expression, the rest a
//! function file; both are parsed, linked after rayinit.cal, specialised and evaluated for a
//! few rays. Nothing may panic or overflow the stack; values may be anything.
#![no_main]

use ircache_scene::radiance::cal::{self, Channels};
use ircache_scene::SourceLocation;
use libfuzzer_sys::fuzz_target;
use std::path::{Path, PathBuf};
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let (expr, file) = text.split_once('\n').unwrap_or((&text, ""));
    let at = SourceLocation::start_of(Path::new("fuzz.cal"));
    let rayinit =
        cal::parse::parse_definitions(cal::library::RAYINIT, Arc::new(PathBuf::from("r")))
            .expect("rayinit parses");
    let Ok(defs) = cal::parse::parse_definitions(file, Arc::new(PathBuf::from("fuzz.cal"))) else {
        return;
    };
    let Ok(program) = cal::Program::link(&rayinit, &[defs]) else {
        return;
    };
    let Ok(e) = cal::parse::parse_expression(expr, &at) else {
        return;
    };
    let Ok(node) = program.compile(&e, &at) else {
        return;
    };
    let args = [0.5, 2.0, -1.0];
    let fast = program.specialized(&args);
    let quick = fast.compile(&e, &at).map(|n| fast.fold(n, &args));
    for d in [[0.0, 0.0, 1.0], [0.6, 0.0, -0.8], [0.0, 1.0, 0.0]] {
        let c = Channels {
            direction: d,
            normal: [0.0, 0.0, 1.0],
            point: [1.0, -2.0, 0.5],
            rdot: -d[2],
            ..Channels::default()
        };
        let a = program.eval(&node, &c, &args);
        if let Ok(q) = &quick {
            let b = fast.eval(q, &c, &args);
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "specialised {b} against {a}"
            );
        }
    }
});
