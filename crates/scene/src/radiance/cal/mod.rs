//! Radiance's function language (`.cal` files; Ward's `calc`, `src/common/calexpr.c`,
//! `caldefn.c`, `calfunc.c`), which patterns on Radiance's materials are written in:
//! [`parse`] reads definitions and expressions, [`eval`] links and evaluates them,
//! [`library`] holds the standard files a scene may name without Radiance installed.
//!
//! A [`Loader`] finds files as Radiance does (beside the file that names them, beside the scene,
//! then along `RAYPATH`, then ircache's copies of the standard ones) and links each function
//! file once, after the global `rayinit.cal` definitions.

pub mod eval;
pub mod library;
pub mod noise;
pub mod parse;

pub use eval::{Channels, Function, Node, Program};

use crate::error::SourceLocation;
use crate::SceneError;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Finds and links function files; one per scene load.
pub struct Loader {
    /// The directory of the scene file (Radiance's working directory).
    scene_dir: PathBuf,
    rayinit: Vec<parse::Definition>,
    programs: HashMap<PathBuf, Arc<Program>>,
}

impl Loader {
    /// A loader for the scene in `scene_dir`.
    #[must_use]
    pub fn new(scene_dir: &Path) -> Loader {
        let rayinit = parse::parse_definitions(
            library::RAYINIT,
            Arc::new(PathBuf::from("(ircache's rayinit.cal)")),
        )
        .expect("the built-in rayinit.cal parses");
        Loader {
            scene_dir: scene_dir.to_path_buf(),
            rayinit,
            programs: HashMap::new(),
        }
    }

    /// Where the file `name` named at `at` is: beside the naming file, beside the scene, then in
    /// each directory of `RAYPATH`; `None` if nowhere.
    #[must_use]
    pub fn find(&self, name: &str, at: &SourceLocation) -> Option<PathBuf> {
        let p = Path::new(name);
        if p.is_absolute() {
            return p.is_file().then(|| p.to_path_buf());
        }
        let mut dirs = Vec::new();
        if let Some(d) = at.file.parent() {
            dirs.push(d.to_path_buf());
        }
        dirs.push(self.scene_dir.clone());
        if let Some(raypath) = std::env::var_os("RAYPATH") {
            dirs.extend(std::env::split_paths(&raypath));
        }
        dirs.into_iter().map(|d| d.join(p)).find(|f| f.is_file())
    }

    /// The program of function file `name` (`.` for none: `rayinit.cal`'s definitions alone),
    /// named at `at`.
    pub fn program(&mut self, name: &str, at: &SourceLocation) -> Result<Arc<Program>, SceneError> {
        let (key, text) = if name == "." {
            (PathBuf::from("."), None)
        } else {
            match self.find(name, at) {
                Some(path) => {
                    if let Some(p) = self.programs.get(&path) {
                        return Ok(p.clone());
                    }
                    let bytes = std::fs::read(&path).map_err(|e| SceneError::Referenced {
                        location: at.clone(),
                        path: path.clone(),
                        message: e.to_string(),
                    })?;
                    let text = String::from_utf8_lossy(&bytes).into_owned();
                    (path, Some(text))
                }
                None => {
                    let file = Path::new(name).file_name().and_then(|f| f.to_str());
                    match file.and_then(library::standard_file) {
                        Some(text) => (
                            PathBuf::from(format!("(ircache's {name})")),
                            Some(text.to_string()),
                        ),
                        None => {
                            return Err(SceneError::at(
                                at.clone(),
                                format!(
                                    "cannot find function file \"{name}\" (looked beside the \
                                     file naming it, beside the scene and along RAYPATH)"
                                ),
                            ))
                        }
                    }
                }
            }
        };
        if let Some(p) = self.programs.get(&key) {
            return Ok(p.clone());
        }
        let files = match text {
            Some(t) => vec![parse::parse_definitions(&t, Arc::new(key.clone()))?],
            None => Vec::new(),
        };
        let program = Arc::new(Program::link(&self.rayinit, &files)?);
        self.programs.insert(key, program.clone());
        Ok(program)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at() -> SourceLocation {
        SourceLocation::start_of(Path::new("/nonexistent/scene.rad"))
    }

    fn value(program: &Program, expr: &str, channels: &Channels, args: &[f64]) -> f64 {
        let e = parse::parse_expression(expr, &at()).unwrap();
        let node = program.compile(&e, &at()).unwrap();
        program.eval(&node, channels, args)
    }

    fn program_of(text: &str) -> Program {
        let rayinit =
            parse::parse_definitions(library::RAYINIT, Arc::new(PathBuf::from("r"))).unwrap();
        let file = parse::parse_definitions(text, Arc::new(PathBuf::from("f.cal"))).unwrap();
        Program::link(&rayinit, &[file]).unwrap()
    }

    #[test]
    fn arithmetic_library_and_rayinit() {
        let p = program_of("");
        let c = Channels::default();
        let v = |e: &str| value(&p, e, &c, &[2.0, 5.0]);
        assert_eq!(v("-2^2"), 4.0);
        assert_eq!(v("2^3^2"), 512.0);
        assert_eq!(v("10-4-3"), 3.0);
        assert_eq!(v("12/4/3"), 1.0);
        assert_eq!(v("if(0, 1, 2)"), 2.0);
        assert_eq!(v("if(-1, 1, 2)"), 2.0);
        assert_eq!(v("if(1e-9, 1, 2)"), 1.0);
        assert_eq!(v("select(2, 7, 8, 9)"), 8.0);
        assert_eq!(v("select(0, 7, 8, 9)"), 3.0);
        assert!(v("select(4, 7, 8, 9)").is_nan());
        assert_eq!(v("min(3, 1, 2) + max(3, 1, 2)"), 4.0);
        assert_eq!(v("abs(-3) + sgn(-2) + sq(3)"), 11.0);
        assert_eq!(v("mod(-1, 360)"), 359.0);
        assert_eq!(v("tri(100, 90)"), 80.0);
        assert_eq!(v("tri(190, 90)"), 10.0);
        assert_eq!(v("Acos(2)"), 0.0);
        assert!((v("DEGREE") - std::f64::consts::PI / 180.0).abs() < 1e-15);
        assert_eq!(v("AC + A1 * 10 + A2"), 2.0 + 20.0 + 5.0);
        assert!(v("A3").is_nan());
        assert!((v("erf(0.5)") - 0.520_499_877_813_046_5).abs() < 2e-7);
        assert_eq!(v("rand(3)"), v("rand(3)"));
        assert!((0.0..1.0).contains(&v("rand(3)")));
    }

    #[test]
    fn channels_functions_as_arguments_and_recursion() {
        let p = program_of(
            "fact(n) = if(n - 1.5, n * fact(n - 1), 1);\n\
             twice(f, x) = f(f(x));\n\
             inc(x) = x + 1;\n\
             forever(x) = forever(x);",
        );
        let c = Channels {
            direction: [0.0, 0.6, 0.8],
            normal: [0.0, 0.0, -1.0],
            point: [1.0, 2.0, 3.0],
            rdot: 0.8,
            ..Channels::default()
        };
        let v = |e: &str| value(&p, e, &c, &[]);
        assert_eq!(v("fact(5)"), 120.0);
        assert_eq!(v("twice(inc, 1)"), 3.0);
        assert_eq!(v("twice(sqrt, 16)"), 2.0);
        assert!((v("dot(D, N)") + 0.8).abs() < 1e-15);
        // (D × N)_x = Dy Nz − Dz Ny.
        assert!((v("cross(1, D, N)") + 0.6).abs() < 1e-15);
        assert_eq!(v("Px + Py * Pz + Rdot"), 7.8);
        assert!(v("forever(1)").is_nan());
    }

    #[test]
    fn source_cal_angles() {
        let mut loader = Loader::new(Path::new("/nonexistent"));
        let p = loader.program("source.cal", &at()).unwrap();
        // Light leaving straight down: the ray towards the luminaire looks up.
        let up = Channels {
            direction: [0.0, 0.0, 1.0],
            ..Channels::default()
        };
        assert_eq!(value(&p, "src_theta", &up, &[]), 0.0);
        // Leaving towards +x and slightly down (θ = 60°, φ = 0); seen looking along −x.
        let (s, c) = (60f64.to_radians().sin(), 60f64.to_radians().cos());
        let side = Channels {
            direction: [-s, 0.0, c],
            rdot: c,
            ..Channels::default()
        };
        assert!((value(&p, "src_theta", &side, &[]) - 60.0).abs() < 1e-9);
        assert!(value(&p, "src_phi", &side, &[]).abs() < 1e-9);
        // φ = 250° folds to 70° (two planes of symmetry) and 110° (one).
        let a = 250f64.to_radians();
        let skew = Channels {
            direction: [-s * a.cos(), -s * a.sin(), c],
            rdot: c,
            ..Channels::default()
        };
        assert!((value(&p, "src_phi", &skew, &[]) - 250.0).abs() < 1e-9);
        assert!((value(&p, "src_phi4", &skew, &[]) - 70.0).abs() < 1e-9);
        assert!((value(&p, "src_phi2", &skew, &[]) - 110.0).abs() < 1e-9);
        // flatcorr divides by Rdot and applies the multiplier.
        let f = p.function("flatcorr", 1, &at()).unwrap();
        assert!((p.call(f, &[3.0], &side, &[2.0]) - 2.0 * 3.0 / c).abs() < 1e-12);
    }

    #[test]
    fn specialized_programs_give_the_general_values() {
        // Folding and inlining change no value: source.cal's coordinates and corrections,
        // rayinit's vector functions and recursive definitions at many rays, against the
        // program as linked.
        let general = program_of(&format!(
            "{}\nfact(n) = if(n - 1.5, n * fact(n - 1), 1);\n\
             twice(f, x) = f(f(x));\ninc(x) = x + 1;\n\
             sum(n) = if(n, Px + sum(n - 1), 0);",
            library::SOURCE_CAL
        ));
        let args = [0.7, 0.2, 0.3, 0.4];
        let fast = general.specialized(&args);
        let exprs = [
            "src_theta",
            "src_phi",
            "src_phi2",
            "src_phi4",
            "srcB_vert2 + srcB_horiz2",
            "flatcorr(Dz + 2)",
            "boxcorr(3) + cylcorr(2)",
            "lboxcorr(1)",
            "dot(D, N) + cross(2, D, N) + linterp(.3, Px, Py)",
            "bezier(1, Px, 3, 4, .25) * fade(1, 2, Pz)",
            "fact(4) + twice(inc, 2) + fact(Dz + 3)",
            "sum(3) + sum(A1 * 4)",
        ];
        let mut rng = 0x1234_5678u64;
        let mut next = || {
            rng = rng.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            ((rng >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        for e in exprs {
            let parsed = parse::parse_expression(e, &at()).unwrap();
            let slow = general.compile(&parsed, &at()).unwrap();
            let quick = fast.fold(fast.compile(&parsed, &at()).unwrap(), &args);
            for _ in 0..200 {
                let d = [next(), next(), next()];
                let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let c = Channels {
                    direction: d.map(|v| v / l),
                    normal: [0.0, 0.0, -1.0],
                    point: [next(), next(), next()],
                    rdot: d[2] / l,
                    shadow_distance: 2.0 + next(),
                    ..Channels::default()
                };
                let (a, b) = (general.eval(&slow, &c, &args), fast.eval(&quick, &c, &args));
                assert!(
                    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                    "{e}: {a} against {b}"
                );
            }
        }
    }

    #[test]
    fn link_errors_name_the_place() {
        let rayinit =
            parse::parse_definitions(library::RAYINIT, Arc::new(PathBuf::from("r"))).unwrap();
        let bad = |text: &str| {
            let file = parse::parse_definitions(text, Arc::new(PathBuf::from("f.cal"))).unwrap();
            Program::link(&rayinit, &[file]).unwrap_err().to_string()
        };
        assert!(bad("a = 1;\nb = c + 1;").contains("f.cal:2:1: undefined variable 'c'"));
        assert!(bad("f(x) = x;\nb = f(1, 2);").contains("'f' takes 1 argument(s)"));
        assert!(bad("b = noise4(1, 2, 3);").contains("undefined function 'noise4'"));
        assert!(bad("b = noise3(1, 2);").contains("'noise3' called with 2 argument(s)"));
        assert!(bad("b = NxP;").contains("textures"));
        let mut loader = Loader::new(Path::new("/nonexistent"));
        let e = loader
            .program("missing.cal", &at())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("cannot find function file \"missing.cal\""),
            "{e}"
        );
    }
}
