//! Radiance views (`src/common/image.c`, `rpict(1)`): `-vtv` (perspective), `-vtl` (parallel),
//! `-vth` (hemispherical fisheye), `-vta` (angular fisheye), `-vts` (planisphere) and `-vtc`
//! (cylindrical panorama) with `-vp`, `-vd`, `-vu`, `-vh`, `-vv`; `-vf file` reads a view file
//! (`rvu` or `rpict` lines, or `VIEW=` lines of a picture header). Radiance's defaults: `-vtv
//! -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 45 -vv 45`. Shifts, lifts, fore and aft clipping are
//! refused rather than rendered as something else.
//!
//! rpict fits the picture into `-x` × `-y` keeping square pixels: the picture's aspect is the
//! view's (`setview`'s `√(hn2/vn2)`: `tan(vh/2) / tan(vv/2)` for perspective views, `vh / vv`
//! for parallel and angular ones), and the larger of the two sizes that fits is used
//! ([`View::fit`]).

use ircache_math::DVec3;
use std::path::Path;

/// A Radiance view's type (`-vt?`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewType {
    /// `-vtv`.
    Perspective,
    /// `-vtl`.
    Parallel,
    /// `-vth`.
    Hemispherical,
    /// `-vta`.
    Angular,
    /// `-vts`.
    Planispheric,
    /// `-vtc`.
    Cylindrical,
}

/// A Radiance view.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// Its type.
    pub kind: ViewType,
    /// Eye point.
    pub position: DVec3,
    /// View direction.
    pub direction: DVec3,
    /// Up vector.
    pub up: DVec3,
    /// Horizontal size: full angle in degrees (perspective) or width in scene units (parallel).
    pub horizontal: f64,
    /// Vertical size, as `horizontal`.
    pub vertical: f64,
}

impl Default for View {
    fn default() -> Self {
        View {
            kind: ViewType::Perspective,
            position: DVec3::ZERO,
            direction: DVec3::Y,
            up: DVec3::Z,
            horizontal: 45.0,
            vertical: 45.0,
        }
    }
}

impl View {
    /// Applies the view options among `words` (other words are skipped, as Radiance skips the
    /// program name and its other options in a view file); `base` is the directory `-vf` files
    /// are relative to.
    pub fn apply(&mut self, words: &[String], base: &Path) -> Result<(), String> {
        let mut i = 0;
        while i < words.len() {
            let w = words[i].as_str();
            let num = |k: usize| -> Result<f64, String> {
                let s = words
                    .get(i + k)
                    .ok_or_else(|| format!("{w} needs more numbers"))?;
                s.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| format!("{w}: expected a number, found \"{s}\""))
            };
            let used = match w {
                "-vtv" | "-vtl" | "-vth" | "-vta" | "-vts" | "-vtc" => {
                    self.kind = match w {
                        "-vtv" => ViewType::Perspective,
                        "-vtl" => ViewType::Parallel,
                        "-vth" => ViewType::Hemispherical,
                        "-vta" => ViewType::Angular,
                        "-vts" => ViewType::Planispheric,
                        _ => ViewType::Cylindrical,
                    };
                    0
                }
                "-vp" | "-vd" | "-vu" => {
                    let v = DVec3::new(num(1)?, num(2)?, num(3)?);
                    match w {
                        "-vp" => self.position = v,
                        "-vd" => self.direction = v,
                        _ => self.up = v,
                    }
                    3
                }
                "-vh" => {
                    self.horizontal = num(1)?;
                    1
                }
                "-vv" => {
                    self.vertical = num(1)?;
                    1
                }
                "-vs" | "-vl" | "-vo" | "-va" => {
                    if num(1)? != 0.0 {
                        return Err(format!(
                            "{w} (view shift, lift or clipping) is not supported"
                        ));
                    }
                    1
                }
                "-vf" => {
                    let f = words.get(i + 1).ok_or("-vf needs a file")?;
                    self.read_file(&base.join(f))?;
                    1
                }
                _ if w.starts_with("-v") => return Err(format!("unknown view option \"{w}\"")),
                _ => 0,
            };
            i += used + 1;
        }
        self.check()
    }

    /// Reads a view file: every line's view options, in order.
    pub fn read_file(&mut self, path: &Path) -> Result<(), String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read view file {}: {e}", path.display()))?;
        let base = path.parent().unwrap_or(Path::new(""));
        for line in text.lines() {
            let line = line.strip_prefix("VIEW=").unwrap_or(line);
            let words: Vec<String> = line.split_whitespace().map(str::to_string).collect();
            self.apply(&words, base)
                .map_err(|e| format!("{}: {e}", path.display()))?;
        }
        Ok(())
    }

    /// Parses view options from one string (a file name alone is read as a view file).
    pub fn parse(text: &str, base: &Path) -> Result<View, String> {
        let mut view = View::default();
        let words: Vec<String> = text.split_whitespace().map(str::to_string).collect();
        if words.len() == 1 && !words[0].starts_with('-') {
            view.read_file(&base.join(&words[0]))?;
        } else {
            view.apply(&words, base)?;
        }
        Ok(view)
    }

    fn check(&self) -> Result<(), String> {
        if self.direction.length() == 0.0 {
            return Err("-vd is the zero vector".into());
        }
        if self.up.cross(self.direction).length()
            <= 1e-9 * self.up.length() * self.direction.length()
        {
            return Err("-vu is parallel to -vd".into());
        }
        let (h, v) = (self.horizontal, self.vertical);
        // setview's limits per type: (largest -vh, largest -vv, whether the largest is allowed).
        let (max_h, max_v, closed) = match self.kind {
            ViewType::Parallel => (f64::INFINITY, f64::INFINITY, false),
            ViewType::Perspective => (180.0, 180.0, false),
            ViewType::Hemispherical => (180.0, 180.0, true),
            ViewType::Angular => (360.0, 360.0, true),
            ViewType::Planispheric => (360.0, 360.0, false),
            ViewType::Cylindrical => (360.0, 180.0, false),
        };
        let within = |x: f64, max: f64| x > 0.0 && (x < max || (closed && x == max));
        let horizontal_ok = within(h, max_h) || (self.kind == ViewType::Cylindrical && h == 360.0);
        if !horizontal_ok || !within(v, max_v) {
            return Err(format!(
                "view size -vh {h} -vv {v} out of range for this view type (at most {max_h} and \
                 {max_v} degrees)"
            ));
        }
        Ok(())
    }

    /// `setview`'s half-extents of the film in its own units, horizontal and vertical (their
    /// ratio is the picture's aspect).
    #[must_use]
    pub fn extents(&self) -> (f64, f64) {
        let (h, v) = (self.horizontal, self.vertical);
        let half = |a: f64| (a * 0.5).to_radians();
        match self.kind {
            ViewType::Parallel | ViewType::Angular => (h, v),
            ViewType::Perspective => (2.0 * half(h).tan(), 2.0 * half(v).tan()),
            ViewType::Hemispherical => (2.0 * half(h).sin(), 2.0 * half(v).sin()),
            ViewType::Planispheric => (
                2.0 * half(h).sin() / (1.0 + half(h).cos()),
                2.0 * half(v).sin() / (1.0 + half(v).cos()),
            ),
            ViewType::Cylindrical => (h.to_radians(), 2.0 * half(v).tan()),
        }
    }

    /// The view's aspect, width over height.
    #[must_use]
    pub fn aspect(&self) -> f64 {
        let (h, v) = self.extents();
        h / v
    }

    /// rpict's picture size within `x` × `y` with square pixels.
    #[must_use]
    pub fn fit(&self, x: u32, y: u32) -> (u32, u32) {
        let aspect = self.aspect();
        let (xf, yf) = (f64::from(x), f64::from(y));
        if xf / yf > aspect {
            (((yf * aspect).round() as u32).max(1), y)
        } else {
            (x, ((xf / aspect).round() as u32).max(1))
        }
    }
}
