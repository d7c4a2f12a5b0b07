//! Radiance views (`src/common/image.c`, `rpict(1)`): `-vtv` (perspective) and `-vtl`
//! (parallel) with `-vp`, `-vd`, `-vu`, `-vh`, `-vv`; `-vf file` reads a view file (`rvu` or
//! `rpict` lines, or `VIEW=` lines of a picture header). Radiance's defaults: `-vtv -vp 0 0 0
//! -vd 0 1 0 -vu 0 0 1 -vh 45 -vv 45`. Shifts, lifts, fore and aft clipping, and the fisheye and
//! panoramic types are refused rather than rendered as something else.
//!
//! rpict fits the picture into `-x` × `-y` keeping square pixels: the picture's aspect is the
//! view's, `tan(vh/2) / tan(vv/2)` (for parallel views `vh / vv`), and the larger of the two
//! sizes that fits is used ([`View::fit`]).

use ircache_math::DVec3;
use std::path::Path;

/// A Radiance view.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// Parallel (`-vtl`) rather than perspective (`-vtv`).
    pub parallel: bool,
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
            parallel: false,
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
                "-vtv" => {
                    self.parallel = false;
                    0
                }
                "-vtl" => {
                    self.parallel = true;
                    0
                }
                "-vth" | "-vta" | "-vts" | "-vtc" => {
                    return Err(format!(
                        "{w}: fisheye and panoramic views are not supported (only -vtv and -vtl)"
                    ))
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
        let ok = if self.parallel {
            h > 0.0 && v > 0.0
        } else {
            h > 0.0 && h < 180.0 && v > 0.0 && v < 180.0
        };
        if !ok {
            return Err(format!(
                "view size -vh {h} -vv {v} out of range (perspective: between 0 and 180 degrees)"
            ));
        }
        Ok(())
    }

    /// The view's aspect, width over height.
    #[must_use]
    pub fn aspect(&self) -> f64 {
        if self.parallel {
            self.horizontal / self.vertical
        } else {
            (self.horizontal.to_radians() * 0.5).tan() / (self.vertical.to_radians() * 0.5).tan()
        }
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
