//! Radiance's transforms (`src/common/xf.c`): `-t x y z`, `-rx/-ry/-rz degrees`, `-s scale`,
//! `-mx/-my/-mz` mirrors, applied in the order written; `-i n` repeats what follows it `n`
//! times and `-a n` makes `n` copies, copy `k` with what follows applied `k` times.
//!
//! Radiance multiplies row vectors, `p' = p · M`; here the same transform is a column-vector
//! matrix, `p' = M p`, so "A then B" is `B · A`.

use ircache_math::{DMat4, DVec3};

/// An affine transform with Radiance's bookkeeping: the uniform scale (radii scale by it) and
/// whether it mirrors (polygon vertex order is then reversed to keep the front side).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Object to world, column vectors.
    pub matrix: DMat4,
    /// The product of the scales (`-s`), always positive.
    pub scale: f64,
    /// An odd number of mirrors (or `-I`).
    pub reverse: bool,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            matrix: DMat4::IDENTITY,
            scale: 1.0,
            reverse: false,
        }
    }
}

impl Transform {
    /// This transform, then `outer`.
    #[must_use]
    pub fn then(&self, outer: &Transform) -> Transform {
        Transform {
            matrix: outer.matrix * self.matrix,
            scale: self.scale * outer.scale,
            reverse: self.reverse != outer.reverse,
        }
    }

    /// A point.
    #[must_use]
    pub fn point(&self, p: DVec3) -> DVec3 {
        self.matrix.transform_point3(p)
    }

    /// A direction (not normalised).
    #[must_use]
    pub fn vector(&self, v: DVec3) -> DVec3 {
        self.matrix.transform_vector3(v)
    }
}

/// One step of a transform: a matrix and its scale (negative for a mirror).
fn step(args: &[String], i: &mut usize) -> Result<Option<(DMat4, f64)>, String> {
    let opt = args[*i].as_str();
    let num = |k: usize| -> Result<f64, String> {
        let w = args
            .get(*i + k)
            .ok_or_else(|| format!("{opt} needs {k} number(s)"))?;
        w.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("{opt}: expected a number, found \"{w}\""))
    };
    let (m, s, n) = match opt {
        "-t" => (
            DMat4::from_translation(DVec3::new(num(1)?, num(2)?, num(3)?)),
            1.0,
            3,
        ),
        "-rx" => (DMat4::from_rotation_x(num(1)?.to_radians()), 1.0, 1),
        "-ry" => (DMat4::from_rotation_y(num(1)?.to_radians()), 1.0, 1),
        "-rz" => (DMat4::from_rotation_z(num(1)?.to_radians()), 1.0, 1),
        "-s" => {
            let s = num(1)?;
            if s == 0.0 {
                return Err("-s 0 would collapse the scene".into());
            }
            (DMat4::from_scale(DVec3::splat(s)), s, 1)
        }
        "-mx" => (DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)), -1.0, 0),
        "-my" => (DMat4::from_scale(DVec3::new(1.0, -1.0, 1.0)), -1.0, 0),
        "-mz" => (DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0)), -1.0, 0),
        _ => return Ok(None),
    };
    *i += n + 1;
    Ok(Some((m, s)))
}

/// A transform written after a name (an `instance`'s, a `mesh`'s, a pattern's): options only,
/// no arrays and no files.
pub fn parse_plain(args: &[String]) -> Result<Transform, String> {
    match parse_options(args)? {
        (copies, files) if files.is_empty() && copies.len() == 1 && copies[0].0.is_none() => {
            Ok(copies[0].1)
        }
        _ => Err(format!(
            "expected transform options only, found \"{}\"",
            args.join(" ")
        )),
    }
}

/// Parses a transform's options; returns the copies to make (`Some(k)` for copy `k` of an
/// array, with its transform) and the file names after the options.
#[allow(clippy::type_complexity)]
pub fn parse_options(
    args: &[String],
) -> Result<(Vec<(Option<usize>, Transform)>, Vec<String>), String> {
    // Segments between -a options: each a transform, the ones after an -a repeated per copy.
    let mut copies: Vec<(Option<usize>, Transform)> = vec![(None, Transform::default())];
    let mut block = (DMat4::IDENTITY, 1.0f64);
    let mut repeat = 1usize;
    let mut segment = Transform::default();
    let mut array: Option<usize> = None;
    let mut i = 0;
    // Applies `block` `repeat` times to the segment.
    let flush = |segment: &mut Transform, block: &mut (DMat4, f64), repeat: usize| {
        for _ in 0..repeat {
            *segment = Transform {
                matrix: block.0,
                scale: block.1.abs(),
                reverse: block.1 < 0.0,
            }
            .then_inner(segment);
        }
        *block = (DMat4::IDENTITY, 1.0);
    };
    // Closes a segment: without an array it extends every copy; with `-a n` each copy k takes it
    // k times.
    let close =
        |copies: &mut Vec<(Option<usize>, Transform)>, segment: Transform, array: Option<usize>| {
            match array {
                None => {
                    for (_, t) in copies.iter_mut() {
                        *t = segment.then_inner(t);
                    }
                }
                Some(n) => {
                    let mut next = Vec::with_capacity(copies.len() * n);
                    for (label, t) in copies.iter() {
                        let mut acc = *t;
                        for k in 0..n {
                            let name = match label {
                                Some(l) => Some(l * n + k),
                                None => Some(k),
                            };
                            next.push((name, acc));
                            acc = segment.then_inner(&acc);
                        }
                    }
                    *copies = next;
                }
            }
        };
    while i < args.len() && args[i].starts_with('-') && args[i].len() > 1 {
        match args[i].as_str() {
            "-i" => {
                flush(&mut segment, &mut block, repeat);
                let w = args.get(i + 1).ok_or("-i needs a count")?;
                repeat = w
                    .parse()
                    .map_err(|_| format!("-i: expected a count, found \"{w}\""))?;
                i += 2;
            }
            "-a" => {
                flush(&mut segment, &mut block, repeat);
                repeat = 1;
                close(&mut copies, segment, array);
                segment = Transform::default();
                let w = args.get(i + 1).ok_or("-a needs a count")?;
                let n: usize =
                    w.parse().ok().filter(|&n| n >= 1).ok_or_else(|| {
                        format!("-a: expected a count of at least 1, found \"{w}\"")
                    })?;
                array = Some(n);
                i += 2;
            }
            _ => match step(args, &mut i)? {
                Some((m, s)) => block = (m * block.0, block.1 * s),
                None => return Err(format!("unknown or unsupported option \"{}\"", args[i])),
            },
        }
    }
    flush(&mut segment, &mut block, repeat);
    close(&mut copies, segment, array);
    Ok((copies, args[i..].to_vec()))
}

impl Transform {
    /// `inner`, then this transform.
    fn then_inner(&self, inner: &Transform) -> Transform {
        inner.then(self)
    }
}
