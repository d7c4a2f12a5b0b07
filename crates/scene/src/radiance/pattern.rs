//! Radiance's patterns (`src/rt/p_func.c`, `p_data.c`): `brightfunc`, `colorfunc`,
//! `brightdata`, `colordata` and `colorpict`, with the function files, data files and pictures
//! they name, and `spotlight`'s cone (`srcsupp.c`'s `spotout`). `ies2rad`'s luminaires are
//! these: `brightdata` over a candela table with `source.cal`'s coordinates and `flatcorr`.
//!
//! A pattern multiplies the radiance of the light, or the colour of the material, it modifies by
//! its value for the ray that meets the surface: its direction `D`, the point `P`, the normal `N`,
//! `Rdot = −D·N` and the distance `T`, all in the pattern's own coordinates: the transform written
//! after its variables, followed by those of the `!xform` commands around it (as `xform` appends
//! them), inverted as `func.c`'s `setfunc` does. Patterns on patterns multiply. A value that is
//! not a number (Radiance's "compute error", e.g. an exact grazing view under `flatcorr`) counts
//! as zero, and a negative one as zero; the loader probes each patterned surface and reports
//! either.

use super::cal::{self, Channels, Function, Node, Program};
use super::data::DataArray;
use super::parse::Primitive;
use super::sky::SkyBrightness;
use crate::SceneError;
use ircache_math::{DMat4, DVec3, Rgb, Vec2, Vec3};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// What a function pattern computes.
#[derive(Debug)]
enum Kind {
    /// `brightfunc`: one expression.
    Bright(Node),
    /// `colorfunc`: three.
    Color([Node; 3]),
    /// `brightdata`: `function(table(x₁ … xₙ))`.
    BrightData {
        table: Arc<DataArray>,
        function: Function,
        coordinates: Vec<Node>,
    },
    /// `colordata` and `texdata`: a table and a function per channel, each function taking
    /// the values its [`Take`] says.
    ColorData {
        tables: [Arc<DataArray>; 3],
        functions: [(Function, Take); 3],
        coordinates: Vec<Node>,
    },
    /// `colorpict`: a picture's channels at (u, v), each through its function, which takes the
    /// three channels (or its own alone, for the green and blue ones of fewer parameters).
    Picture {
        tables: Arc<[DataArray; 3]>,
        functions: [(Function, bool); 3],
        coordinates: [Node; 2],
    },
}

/// One `brightfunc`, `colorfunc`, `brightdata` or `colordata` with its files.
#[derive(Debug)]
pub struct FunctionPattern {
    /// `type 'id'`, for messages.
    name: String,
    program: Arc<Program>,
    kind: Kind,
    /// The modifier's real arguments (`arg(n)`, `A1` …).
    args: Vec<f64>,
    /// World to the pattern's coordinates.
    to_pattern: DMat4,
    /// The pattern's coordinates to world (a texture's displacement goes back through it).
    from_pattern: DMat4,
    /// The scale of the pattern's transform (object to world).
    scale: f64,
    /// It reads `Lu` or `Lv` (only meshes with (u, v) give them).
    reads_uv: bool,
}

/// What a data pattern's channel function is called with (`p_data.c`, `t_data.c`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Take {
    /// The three tables' values (a function of three parameters).
    All,
    /// The first table's value: Radiance passes all three to a function of one parameter,
    /// which reads the first (`texdata`'s functions, and `colordata`'s red one).
    First,
    /// Its own table's value (`colordata`'s green and blue functions of fewer parameters).
    Own,
}

/// Files read while patterns are made (each read once per scene).
pub struct PatternFiles {
    pub(super) functions: cal::Loader,
    tables: HashMap<PathBuf, Arc<DataArray>>,
    pictures: HashMap<PathBuf, Arc<[DataArray; 3]>>,
    klems: HashMap<PathBuf, Arc<crate::klems::KlemsBsdf>>,
}

impl PatternFiles {
    /// Readers for the scene in `scene_dir`.
    #[must_use]
    pub fn new(scene_dir: &std::path::Path) -> PatternFiles {
        PatternFiles {
            functions: cal::Loader::new(scene_dir),
            tables: HashMap::new(),
            pictures: HashMap::new(),
            klems: HashMap::new(),
        }
    }

    /// Where the `what` file `name` that `p` names is, or an error saying where it was looked
    /// for.
    pub(super) fn locate(
        &self,
        name: &str,
        what: &str,
        p: &Primitive,
    ) -> Result<PathBuf, SceneError> {
        self.functions.find(name, &p.location).ok_or_else(|| {
            SceneError::at(
                p.location.clone(),
                format!(
                    "{} '{}': cannot find {what} \"{name}\" (looked beside the file naming it, \
                     beside the scene and along RAYPATH)",
                    p.kind, p.id
                ),
            )
        })
    }

    /// The Klems BSDF at `path`, read once.
    pub(super) fn klems(
        &mut self,
        path: &std::path::Path,
    ) -> Result<Arc<crate::klems::KlemsBsdf>, String> {
        if let Some(k) = self.klems.get(path) {
            return Ok(k.clone());
        }
        let k = Arc::new(super::bsdf_xml::read(path)?);
        self.klems.insert(path.to_path_buf(), k.clone());
        Ok(k)
    }

    fn picture(&mut self, name: &str, p: &Primitive) -> Result<Arc<[DataArray; 3]>, SceneError> {
        let path = self.locate(name, "picture", p)?;
        if let Some(t) = self.pictures.get(&path) {
            return Ok(t.clone());
        }
        let image = ircache_image::read_image(&path).map_err(|e| SceneError::Referenced {
            location: p.location.clone(),
            path: path.clone(),
            message: e.to_string(),
        })?;
        if image.width < 2 || image.height < 2 {
            return Err(SceneError::at(
                p.location.clone(),
                format!(
                    "{} '{}': picture \"{name}\" needs at least 2 × 2 pixels",
                    p.kind, p.id
                ),
            ));
        }
        let t = Arc::new(DataArray::from_picture(&image));
        self.pictures.insert(path, t.clone());
        Ok(t)
    }

    fn table(&mut self, name: &str, p: &Primitive) -> Result<Arc<DataArray>, SceneError> {
        let path = self.locate(name, "data file", p)?;
        if let Some(t) = self.tables.get(&path) {
            return Ok(t.clone());
        }
        let t = Arc::new(DataArray::read(&path).map_err(|e| e.referenced_from(&p.location))?);
        self.tables.insert(path, t.clone());
        Ok(t)
    }
}

/// True for the string arguments that start a transform.
fn is_transform_option(s: &str) -> bool {
    matches!(
        s,
        "-t" | "-rx" | "-ry" | "-rz" | "-s" | "-mx" | "-my" | "-mz" | "-i"
    )
}

impl FunctionPattern {
    /// True for the types this reads.
    #[must_use]
    pub fn is_function_pattern(kind: &str) -> bool {
        matches!(
            kind,
            "brightfunc" | "colorfunc" | "brightdata" | "colordata" | "colorpict"
        )
    }

    /// Reads the pattern primitive `p`.
    pub fn from_primitive(
        p: &Primitive,
        files: &mut PatternFiles,
    ) -> Result<FunctionPattern, SceneError> {
        let err =
            |m: String| SceneError::at(p.location.clone(), format!("{} '{}': {m}", p.kind, p.id));
        let s = &p.strings;
        if !p.integers.is_empty() {
            return Err(err("expected no integer arguments".into()));
        }
        // Index of the function file and how many strings before it are expressions or names.
        let (file_index, needed) = match p.kind.as_str() {
            "brightfunc" => (1, 2),
            "colorfunc" => (3, 4),
            "brightdata" => (2, 4),
            "colordata" | "texdata" => (6, 8),
            "texfunc" => (3, 4),
            "colorpict" => (4, 7),
            // The mixture's coefficient of its foreground.
            "mixfunc" => (3, 4),
            other => return Err(err(format!("{other} is not a function pattern"))),
        };
        if s.len() < needed {
            return Err(err(format!(
                "expected at least {needed} string arguments, found {}",
                s.len()
            )));
        }
        // The file's program with this modifier's real arguments folded in.
        let program = Arc::new(
            files
                .functions
                .program(&s[file_index], &p.location)?
                .specialized(&p.reals),
        );
        let expr = |text: &str| -> Result<Node, SceneError> {
            let e = cal::parse::parse_expression(text, &p.location)?;
            program
                .compile(&e, &p.location)
                .map(|n| program.fold(n, &p.reals))
                .map_err(|e| err(format!("in \"{text}\": {e}")))
        };
        let tables_first = match p.kind.as_str() {
            "brightdata" => Some((1, 1)),
            "colordata" | "texdata" => Some((3, 3)),
            _ => None,
        };
        let (kind, first_transform) = match p.kind.as_str() {
            "brightfunc" => (Kind::Bright(expr(&s[0])?), 2),
            "mixfunc" => (Kind::Bright(expr(&s[2])?), 4),
            "colorfunc" | "texfunc" => (Kind::Color([expr(&s[0])?, expr(&s[1])?, expr(&s[2])?]), 4),
            "colorpict" => {
                let tables = files.picture(&s[3], p)?;
                let mut functions = Vec::new();
                for (i, name) in s[..3].iter().enumerate() {
                    // p_pdata: the red function takes the three channels; green and blue
                    // take them too unless defined with fewer parameters (then their own).
                    // (A red function of one parameter reads the red channel, as the extra
                    // arguments Radiance passes it go unread.)
                    let f = match program.function(name, 3, &p.location) {
                        Ok(f) => (f, false),
                        Err(_) => (
                            program
                                .function(name, 1, &p.location)
                                .map_err(|e| err(format!("colour function of channel {i}: {e}")))?,
                            true,
                        ),
                    };
                    functions.push(f);
                }
                (
                    Kind::Picture {
                        tables,
                        functions: [functions[0], functions[1], functions[2]],
                        coordinates: [expr(&s[5])?, expr(&s[6])?],
                    },
                    7,
                )
            }
            _ => {
                let (first, count) = tables_first.expect("data patterns");
                let mut tables = Vec::new();
                for name in &s[first..first + count] {
                    tables.push(files.table(name, p)?);
                }
                let n = tables[0].dimensions();
                if tables.iter().any(|t| t.dimensions() != n) {
                    return Err(err("its three data files differ in dimensions".into()));
                }
                let start = file_index + 1;
                if s.len() < start + n {
                    return Err(err(format!(
                        "the data has {n} dimension(s), so {n} coordinate expression(s) must \
                         follow the function file"
                    )));
                }
                let coordinates = s[start..start + n]
                    .iter()
                    .map(|t| expr(t))
                    .collect::<Result<Vec<_>, _>>()?;
                let function = |name: &str| {
                    program
                        .function(name, 1, &p.location)
                        .map_err(|e| err(e.to_string()))
                };
                // A channel function of three parameters takes the three values; one of fewer
                // takes the first (texdata passes all three to each, as colordata to its red
                // one) or its own (colordata's green and blue).
                let channel = |i: usize| -> Result<(Function, Take), SceneError> {
                    if let Ok(f) = program.function(&s[i], 3, &p.location) {
                        return Ok((f, Take::All));
                    }
                    let own = p.kind == "colordata" && i > 0;
                    Ok((function(&s[i])?, if own { Take::Own } else { Take::First }))
                };
                let kind = if count == 1 {
                    Kind::BrightData {
                        table: tables[0].clone(),
                        function: function(&s[0])?,
                        coordinates,
                    }
                } else {
                    Kind::ColorData {
                        tables: [tables[0].clone(), tables[1].clone(), tables[2].clone()],
                        functions: [channel(0)?, channel(1)?, channel(2)?],
                        coordinates,
                    }
                };
                (kind, start + n)
            }
        };
        let rest = &s[first_transform..];
        if let Some(w) = rest.first().filter(|w| !is_transform_option(w)) {
            return Err(err(format!(
                "unexpected string argument \"{w}\" (a transform such as -rz 90 -t 0 0 1 may \
                 follow the pattern's variables)"
            )));
        }
        let own = super::xform::parse_plain(rest).map_err(|e| err(format!("transform: {e}")))?;
        let total = own.then(&p.transform);
        let to_pattern = total.matrix.inverse();
        if !to_pattern.is_finite() {
            return Err(err("its transform cannot be inverted".into()));
        }
        let nodes: Vec<&Node> = match &kind {
            Kind::Bright(e) => vec![e],
            Kind::Color(e) => e.iter().collect(),
            Kind::BrightData { coordinates, .. } | Kind::ColorData { coordinates, .. } => {
                coordinates.iter().collect()
            }
            Kind::Picture { coordinates, .. } => coordinates.iter().collect(),
        };
        let functions: Vec<Function> = match &kind {
            Kind::BrightData { function, .. } => vec![*function],
            Kind::ColorData { functions, .. } => functions.iter().map(|f| f.0).collect(),
            Kind::Picture { functions, .. } => functions.iter().map(|f| f.0).collect(),
            _ => Vec::new(),
        };
        let reads_uv = nodes.iter().any(|n| program.reads_channels(n, &[25, 26]))
            || functions
                .iter()
                .any(|&f| program.function_reads_channels(f, &[25, 26]));
        Ok(FunctionPattern {
            name: format!("{} '{}'", p.kind, p.id),
            program,
            kind,
            args: p.reals.clone(),
            to_pattern,
            from_pattern: total.matrix,
            scale: total.scale,
            reads_uv,
        })
    }

    /// A texture's (`texfunc`, `texdata`) displacement of the normal, in world coordinates:
    /// its three values turned back from its coordinates and divided by their scale
    /// (`t_func.c`).
    #[must_use]
    pub fn displacement(&self, p: DVec3, n: DVec3, d: DVec3, t: f64, uv: [f64; 2]) -> DVec3 {
        let v = DVec3::from(self.value(p, n, d, t, uv));
        self.from_pattern.transform_vector3(v) / self.scale
    }

    /// The pattern's value (per channel) for a ray along the unit world direction `d` meeting
    /// the surface at `p` with unit front normal `n`, `t` from where it started.
    #[must_use]
    pub fn value(&self, p: DVec3, n: DVec3, d: DVec3, t: f64, uv: [f64; 2]) -> [f64; 3] {
        let w = &self.to_pattern;
        let s = self.scale;
        let v = |x: DVec3| (w.transform_vector3(x) * s).to_array();
        let c = Channels {
            direction: v(d),
            normal: v(n),
            point: w.transform_point3(p).to_array(),
            distance: t / s,
            rdot: -d.dot(n),
            scale: 1.0 / s,
            origin: w.transform_point3(DVec3::ZERO).to_array(),
            axes: [v(DVec3::X), v(DVec3::Y), v(DVec3::Z)],
            shadow_distance: t / s,
            uv,
        };
        let args = &self.args;
        let prog = &self.program;
        let table = |table: &DataArray, f: Function, coordinates: &[Node]| {
            let mut x = [0.0; 5];
            for (x, e) in x.iter_mut().zip(coordinates) {
                *x = prog.eval(e, &c, args);
            }
            let v = table.value(&x[..coordinates.len()]);
            prog.call(f, &[v], &c, args)
        };
        match &self.kind {
            Kind::Bright(e) => [prog.eval(e, &c, args); 3],
            Kind::Color(e) => e.each_ref().map(|e| prog.eval(e, &c, args)),
            Kind::BrightData {
                table: t,
                function,
                coordinates,
            } => [table(t, *function, coordinates); 3],
            Kind::ColorData {
                tables,
                functions,
                coordinates,
            } => {
                let mut x = [0.0; 5];
                for (x, e) in x.iter_mut().zip(coordinates) {
                    *x = prog.eval(e, &c, args);
                }
                let x = &x[..coordinates.len()];
                let v = [0, 1, 2].map(|i| tables[i].value(x));
                [0, 1, 2].map(|i| match functions[i] {
                    (f, Take::All) => prog.call(f, &v, &c, args),
                    (f, Take::First) => prog.call(f, &v[..1], &c, args),
                    (f, Take::Own) => prog.call(f, &v[i..=i], &c, args),
                })
            }
            Kind::Picture {
                tables,
                functions,
                coordinates,
            } => {
                // y major: (v, u).
                let at = [
                    prog.eval(&coordinates[1], &c, args),
                    prog.eval(&coordinates[0], &c, args),
                ];
                let rgb = [0, 1, 2].map(|i| tables[i].value(&at));
                [0, 1, 2].map(|i| match functions[i] {
                    (f, false) => prog.call(f, &rgb, &c, args),
                    (f, true) => prog.call(f, &rgb[i..=i], &c, args),
                })
            }
        }
    }

    /// `type 'id'`.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }
}

/// One link of a light's chain of patterns.
#[derive(Clone, Debug)]
pub enum Pattern {
    /// gensky's or gendaylit's sky, evaluated natively.
    Sky(SkyBrightness),
    /// A function pattern.
    Function(Arc<FunctionPattern>),
    /// A texture (`texfunc`, `texdata`): it displaces the normal and leaves the colour.
    Texture(Arc<FunctionPattern>),
}

impl Pattern {
    fn value(&self, p: DVec3, n: DVec3, d: DVec3, t: f64, uv: [f64; 2]) -> [f64; 3] {
        match self {
            Pattern::Sky(s) => [s.brightness(d); 3],
            Pattern::Function(f) => f.value(p, n, d, t, uv),
            Pattern::Texture(_) => [1.0; 3],
        }
    }

    /// True when it reads a mesh's (u, v) (`Lu`, `Lv`).
    #[must_use]
    pub fn reads_uv(&self) -> bool {
        match self {
            Pattern::Sky(_) => false,
            Pattern::Function(f) | Pattern::Texture(f) => f.reads_uv,
        }
    }
}

/// The patterns on a light (outermost first) and its spotlight cone: the factor on its radiance.
#[derive(Clone, Debug, Default)]
pub struct PatternChain {
    /// Patterns, multiplied.
    pub chain: Vec<Pattern>,
    /// A spotlight.
    pub spot: Option<Spot>,
}

/// A `spotlight`'s cone and focus (`srcsupp.c`, `source.c`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    /// The unit direction light leaves along.
    pub aim: DVec3,
    /// The cosine of half the cone's angle.
    pub cos_half: f64,
    /// The length of the orientation vector: the focus lies this far behind the source, and
    /// the light reaching a point `d` away is that of a source `d + focus` away, so its
    /// radiance is scaled by `(d / (d + focus))²` (Radiance adjusts the solid angle alike).
    pub focus: f64,
}

impl PatternChain {
    /// True when nothing modifies the light.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.chain.is_empty() && self.spot.is_none()
    }

    /// The factor (per channel; non-negative, finite) for a ray along the unit `d` seeing the
    /// light at `p` with front normal `n`, `t` from its start.
    #[must_use]
    pub fn factor_f64(&self, p: DVec3, n: DVec3, d: DVec3, t: f64, uv: [f64; 2]) -> [f64; 3] {
        let mut focus = 1.0;
        if let Some(spot) = self.spot {
            // srcsupp.c's spotout: outside when the light's direction −D leaves the cone.
            if -d.dot(spot.aim) < spot.cos_half {
                return [0.0; 3];
            }
            if spot.focus > 0.0 {
                // An infinite distance (photons leaving) sees the far field, 1.
                focus = if t.is_finite() {
                    (t / (t + spot.focus)).powi(2)
                } else {
                    1.0
                };
            }
        }
        self.raw(p, n, d, t, uv).map(|v| {
            if v.is_finite() && v > 0.0 {
                v * focus
            } else {
                0.0
            }
        })
    }

    /// The chain's values before non-numbers and negatives are zeroed (for the loader's probe).
    #[must_use]
    pub fn raw(&self, p: DVec3, n: DVec3, d: DVec3, t: f64, uv: [f64; 2]) -> [f64; 3] {
        let mut f = [1.0; 3];
        for link in &self.chain {
            let v = link.value(p, n, d, t, uv);
            for (f, v) in f.iter_mut().zip(v) {
                *f *= v;
            }
        }
        f
    }
}

impl PatternChain {
    /// The sum of its textures' displacements of the normal (Radiance's `r->pert`).
    #[must_use]
    pub fn displacement_f64(&self, p: DVec3, n: DVec3, d: DVec3, t: f64, uv: [f64; 2]) -> DVec3 {
        self.chain
            .iter()
            .filter_map(|link| match link {
                Pattern::Texture(f) => Some(f.displacement(p, n, d, t, uv)),
                _ => None,
            })
            .filter(|v| v.is_finite())
            .sum()
    }
}

impl crate::desc::SurfacePattern for PatternChain {
    fn factor(&self, point: Vec3, normal: Vec3, direction: Vec3, distance: f32, uv: Vec2) -> Rgb {
        let [r, g, b] = self.factor_f64(
            point.as_dvec3(),
            normal.as_dvec3(),
            direction.as_dvec3(),
            f64::from(distance),
            [f64::from(uv.x), f64::from(uv.y)],
        );
        Rgb::new(r as f32, g as f32, b as f32)
    }

    fn reads_uv(&self) -> bool {
        self.chain.iter().any(Pattern::reads_uv)
    }

    fn displacement(
        &self,
        point: Vec3,
        normal: Vec3,
        direction: Vec3,
        distance: f32,
        uv: Vec2,
    ) -> Vec3 {
        self.displacement_f64(
            point.as_dvec3(),
            normal.as_dvec3(),
            direction.as_dvec3(),
            f64::from(distance),
            [f64::from(uv.x), f64::from(uv.y)],
        )
        .as_vec3()
    }

    fn perturbs(&self) -> bool {
        self.chain.iter().any(|l| matches!(l, Pattern::Texture(_)))
    }
}
