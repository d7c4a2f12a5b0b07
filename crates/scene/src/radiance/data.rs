//! Radiance's data files (`src/common/data.c`), the tables of `brightdata` and `colordata`
//! patterns (`ies2rad`'s candela tables among them):
//!
//! ```text
//! N                                 number of dimensions
//! begin_1 end_1 n_1                 evenly spaced coordinates of each dimension …
//! 0 0 n_k  x_1 … x_n                … or the n coordinates themselves, monotonic
//! values, the last dimension changing fastest
//! ```
//!
//! Lookups interpolate linearly in each dimension; outside the table they extrapolate linearly
//! up to one division and then taper harmonically to zero, as `data_interp` does.

use crate::error::SourceLocation;
use crate::SceneError;
use std::path::Path;

/// One dimension's coordinates.
#[derive(Clone, Debug, PartialEq)]
struct Dimension {
    /// First coordinate.
    origin: f64,
    /// Last minus first.
    size: f64,
    /// Number of coordinates (at least 2).
    count: usize,
    /// The coordinates, where they are not evenly spaced.
    points: Option<Vec<f64>>,
}

/// An N-dimensional table.
#[derive(Clone, Debug, PartialEq)]
pub struct DataArray {
    dimensions: Vec<Dimension>,
    values: Vec<f64>,
}

/// Most dimensions (Radiance's `MAXDDIM`).
const MAX_DIMENSIONS: usize = 5;

impl DataArray {
    /// Reads the data file at `path`; errors name the file and line.
    pub fn read(path: &Path) -> Result<DataArray, SceneError> {
        let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        DataArray::parse(&String::from_utf8_lossy(&bytes), path)
    }

    /// Parses a data file's text (`path` for errors).
    pub fn parse(text: &str, path: &Path) -> Result<DataArray, SceneError> {
        let mut words = text
            .lines()
            .enumerate()
            .flat_map(|(i, line)| line.split_whitespace().map(move |w| (i as u32 + 1, w)));
        let mut last_line = 1;
        let mut next = |what: &str| -> Result<(f64, u32), SceneError> {
            match words.next() {
                Some((line, w)) => {
                    last_line = line;
                    w.parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .map(|v| (v, line))
                        .ok_or_else(|| {
                            SceneError::at(
                                location(path, line),
                                format!("expected {what}, found \"{w}\""),
                            )
                        })
                }
                None => Err(SceneError::at(
                    location(path, last_line),
                    format!("the data file ends where {what} was expected"),
                )),
            }
        };
        let (n, line) = next("the number of dimensions")?;
        if n.fract() != 0.0 || !(1.0..=MAX_DIMENSIONS as f64).contains(&n) {
            return Err(SceneError::at(
                location(path, line),
                format!("the number of dimensions must be 1 to {MAX_DIMENSIONS}, found {n}"),
            ));
        }
        let mut dimensions = Vec::new();
        let mut total = 1usize;
        for k in 0..n as usize {
            let (begin, _) = next("a dimension's first coordinate")?;
            let (end, _) = next("a dimension's last coordinate")?;
            let (count, line) = next("a dimension's number of coordinates")?;
            if count.fract() != 0.0 || !(2.0..=1e7).contains(&count) {
                return Err(SceneError::at(
                    location(path, line),
                    format!(
                        "dimension {} needs at least 2 coordinates, found {count}",
                        k + 1
                    ),
                ));
            }
            let count = count as usize;
            total = total
                .checked_mul(count)
                .filter(|&t| t <= 1 << 26)
                .ok_or_else(|| SceneError::at(location(path, line), "the table is too large"))?;
            let dim = if end == begin {
                let mut points = Vec::with_capacity(count);
                for _ in 0..count {
                    points.push(next("a coordinate")?.0);
                }
                let rising = points[1] > points[0];
                if points
                    .windows(2)
                    .any(|w| (w[1] > w[0]) != rising || w[1] == w[0])
                {
                    return Err(SceneError::at(
                        location(path, line),
                        format!("dimension {}'s coordinates are not monotonic", k + 1),
                    ));
                }
                Dimension {
                    origin: points[0],
                    size: points[count - 1] - points[0],
                    count,
                    points: Some(points),
                }
            } else {
                Dimension {
                    origin: begin,
                    size: end - begin,
                    count,
                    points: None,
                }
            };
            dimensions.push(dim);
        }
        let mut values = Vec::with_capacity(total);
        for _ in 0..total {
            values.push(next("a data value")?.0);
        }
        Ok(DataArray { dimensions, values })
    }

    /// The three channels of a picture as `colorpict` sees it (`data.c`'s `getpict`): two
    /// dimensions, y (rows from the bottom) then x, the shorter side spanning [0, 1] and the
    /// longer its aspect ratio, pixel centres from one end to the other.
    #[must_use]
    pub fn from_picture(image: &ircache_image::Image) -> [DataArray; 3] {
        let (w, h) = (image.width, image.height);
        let (ysize, xsize) = if w <= h {
            (h as f64 / w as f64, 1.0)
        } else {
            (1.0, w as f64 / h as f64)
        };
        let dims = vec![
            Dimension {
                origin: 0.0,
                size: ysize,
                count: h,
                points: None,
            },
            Dimension {
                origin: 0.0,
                size: xsize,
                count: w,
                points: None,
            },
        ];
        [0, 1, 2].map(|c| {
            let mut values = Vec::with_capacity(w * h);
            for row in 0..h {
                let y = h - 1 - row;
                values.extend(
                    image.pixels[y * w..(y + 1) * w]
                        .iter()
                        .map(|p| f64::from(p.to_array()[c])),
                );
            }
            DataArray {
                dimensions: dims.clone(),
                values,
            }
        })
    }

    /// The number of dimensions.
    #[must_use]
    pub fn dimensions(&self) -> usize {
        self.dimensions.len()
    }

    /// The interpolated value at `point` (one coordinate per dimension).
    #[must_use]
    pub fn value(&self, point: &[f64]) -> f64 {
        self.interpolate(0, 0, point)
    }

    /// Interpolates dimensions `k..` of the block of values starting at `offset`.
    fn interpolate(&self, k: usize, offset: usize, point: &[f64]) -> f64 {
        let d = &self.dimensions[k];
        let stride: usize = self.dimensions[k + 1..].iter().map(|d| d.count).product();
        let x = point[k];
        // The cell i and the position x in units of cells.
        let (i, x) = match &d.points {
            None => {
                let x = (x - d.origin) / d.size * (d.count - 1) as f64;
                (((x as i64).max(0) as usize).min(d.count - 2), x)
            }
            Some(p) => {
                let rising = d.size > 0.0;
                // The last coordinate not beyond x (in the table's order), within [0, n − 2].
                let i = p.partition_point(|&v| if rising { v <= x } else { v >= x });
                let i = i.saturating_sub(1).min(d.count - 2);
                (i, i as f64 + (x - p[i]) / (p[i + 1] - p[i]))
            }
        };
        let i_f = i as f64;
        // Linear, extrapolated up to one division, then tapering harmonically.
        let (c0, c1) = if x > i_f + 2.0 {
            let c0 = 1.0 / (i_f - 1.0 - x);
            (c0, -2.0 * c0)
        } else if x < i_f - 1.0 {
            let c1 = 1.0 / (x - i_f);
            (-2.0 * c1, c1)
        } else {
            (i_f + 1.0 - x, x - i_f)
        };
        let at = |j: usize| {
            let o = offset + j * stride;
            if k + 1 == self.dimensions.len() {
                self.values[o]
            } else {
                self.interpolate(k + 1, o, point)
            }
        };
        c0 * at(i) + c1 * at(i + 1)
    }
}

fn location(path: &Path, line: u32) -> SourceLocation {
    SourceLocation {
        line,
        ..SourceLocation::start_of(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_on_even_and_listed_coordinates() {
        // 2 × 3: x in {0, 10} evenly, y at 0, 1, 4 listed.
        let d =
            DataArray::parse("2\n0 10 2\n0 0 3 0 1 4\n1 2 3\n5 6 9\n", Path::new("t.dat")).unwrap();
        assert_eq!(d.value(&[0.0, 0.0]), 1.0);
        assert_eq!(d.value(&[10.0, 4.0]), 9.0);
        assert!((d.value(&[5.0, 2.5]) - 0.5 * (2.5 + 7.5)).abs() < 1e-12);
        // Extrapolated up to one division beyond, linearly.
        assert!((d.value(&[15.0, 0.0]) - 7.0).abs() < 1e-12);
        // Decreasing listed coordinates work alike.
        let r = DataArray::parse("1\n0 0 3 4 1 0\n3 2 1\n", Path::new("t.dat")).unwrap();
        assert!((r.value(&[2.5]) - 2.5).abs() < 1e-12);
    }

    #[test]
    fn errors_name_the_line() {
        let e = DataArray::parse("1\n0 1 2\n1 x\n", Path::new("t.dat")).unwrap_err();
        assert!(e.to_string().contains("t.dat:3:"), "{e}");
        let e = DataArray::parse("1\n0 1 3\n1 2\n", Path::new("t.dat")).unwrap_err();
        assert!(e.to_string().contains("ends where a data value"), "{e}");
        let e = DataArray::parse("1\n0 0 3 0 2 1\n1 2 3\n", Path::new("t.dat")).unwrap_err();
        assert!(e.to_string().contains("monotonic"), "{e}");
    }
}
