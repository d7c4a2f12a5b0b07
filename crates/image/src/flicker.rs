//! Flicker and temporal error of frame sequences (`NOTES-001.md` D.8; the thesis has no
//! numerical measure, only videos and one probe's accuracy, Fig. 5.10). All on luminance.
//!
//! - [`flicker_index`]: FI = mean_t RMS_px(I_t − I_{t−1}) / mean(I), no reference needed; for a
//!   still scene and camera, every change between frames is flicker.
//! - [`high_pass_error`]: FHP = √(mean_{t,px}[(Δ²I_t − Δ²A_t)(Δ²I_t − Δ²B_t)]) / mean(R), with
//!   Δ²X_t = X_{t+1} − 2X_t + X_{t−1} and A, B two independent halves of the reference R: smooth
//!   (linear in time) changes cancel, pops from record replacement do not, and the reference's
//!   noise cancels in expectation (the product of two independent errors has mean zero).
//!   Emitters in view are left out ([`emitter_mask`]): their edges' coverage noise at a few
//!   samples per pixel would be all it measures where a light moves.
//! - [`ghost_mask`] and [`masked_rel_mse`]: relMSE_trim per frame, and near what moves.
//! - [`probe_tracks`]: per probe, the largest |I_t/R_t − 1| and the largest step of that ratio
//!   between frames, on small box-filtered windows (Fig. 5.10's "temporal accuracy"), and
//!   whether the probe stays on still surfaces (the reference's window never changes by more
//!   than 10 % between frames: no moving silhouette crosses it).

use crate::compare::{luminance, pixel_rel_mse, trim_keep};
use crate::Image;

/// Why a sequence cannot be measured.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum FlickerError {
    /// Fewer frames than the measure needs.
    #[error("{found} frames: this measure needs at least {needed}")]
    TooFewFrames {
        /// Frames given.
        found: usize,
        /// Frames needed.
        needed: usize,
    },
    /// Frames or references of different sizes.
    #[error("frame {frame} is {width}×{height}, the first frame {first_width}×{first_height}")]
    SizeMismatch {
        /// The frame's index in the sequence.
        frame: usize,
        /// Its width.
        width: usize,
        /// Its height.
        height: usize,
        /// The first frame's width.
        first_width: usize,
        /// The first frame's height.
        first_height: usize,
    },
    /// Sequences of different lengths.
    #[error("{a} frames against {b} reference frames")]
    LengthMismatch {
        /// Frames.
        a: usize,
        /// Reference frames.
        b: usize,
    },
}

fn same_size(seqs: &[&[Image]]) -> Result<(), FlickerError> {
    let first = &seqs[0][0];
    for s in seqs {
        if s.len() != seqs[0].len() {
            return Err(FlickerError::LengthMismatch {
                a: seqs[0].len(),
                b: s.len(),
            });
        }
        for (i, f) in s.iter().enumerate() {
            if (f.width, f.height) != (first.width, first.height) {
                return Err(FlickerError::SizeMismatch {
                    frame: i,
                    width: f.width,
                    height: f.height,
                    first_width: first.width,
                    first_height: first.height,
                });
            }
        }
    }
    Ok(())
}

/// An error unless `seq` has at least `needed` frames.
fn at_least(seq: &[Image], needed: usize) -> Result<(), FlickerError> {
    if seq.len() < needed {
        return Err(FlickerError::TooFewFrames {
            found: seq.len(),
            needed,
        });
    }
    Ok(())
}

fn lum(img: &Image) -> Vec<f64> {
    img.pixels.iter().map(|&c| luminance(c)).collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// The static flicker index FI (see the module documentation).
///
/// # Errors
/// Fewer than two frames, or frames of different sizes.
pub fn flicker_index(frames: &[Image]) -> Result<f64, FlickerError> {
    at_least(frames, 2)?;
    same_size(&[frames])?;
    let l: Vec<Vec<f64>> = frames.iter().map(lum).collect();
    let level = mean(&l.iter().map(|f| mean(f)).collect::<Vec<_>>());
    let rms: Vec<f64> = l
        .windows(2)
        .map(|w| {
            let sq: Vec<f64> = w[1]
                .iter()
                .zip(&w[0])
                .map(|(a, b)| (a - b) * (a - b))
                .collect();
            mean(&sq).sqrt()
        })
        .collect();
    Ok(mean(&rms) / level.max(f64::MIN_POSITIVE))
}

/// Second differences in time of each pixel's luminance, frames 1 … n−2.
fn second_differences(l: &[Vec<f64>]) -> Vec<Vec<f64>> {
    l.windows(3)
        .map(|w| {
            w[0].iter()
                .zip(&w[1])
                .zip(&w[2])
                .map(|((a, b), c)| c - 2.0 * b + a)
                .collect()
        })
        .collect()
}

/// The high-pass temporal error FHP against the reference halves `a` and `b` (the same
/// sequence twice for a reference without halves: then the reference's noise is not
/// cancelled), over the pixels `exclude` does not mark. The mean product can come out negative
/// where the error is below the reference's noise; FHP is then 0.
///
/// # Errors
/// Fewer than three frames, or sequences of different lengths or sizes.
pub fn high_pass_error(
    frames: &[Image],
    a: &[Image],
    b: &[Image],
    exclude: Option<&[bool]>,
) -> Result<f64, FlickerError> {
    at_least(frames, 3)?;
    same_size(&[frames, a, b])?;
    let li: Vec<Vec<f64>> = frames.iter().map(lum).collect();
    let la: Vec<Vec<f64>> = a.iter().map(lum).collect();
    let lb: Vec<Vec<f64>> = b.iter().map(lum).collect();
    let (di, da, db) = (
        second_differences(&li),
        second_differences(&la),
        second_differences(&lb),
    );
    let mut sum = 0.0;
    let mut count = 0usize;
    for ((i, a), b) in di.iter().zip(&da).zip(&db) {
        for (px, ((x, y), z)) in i.iter().zip(a).zip(b).enumerate() {
            if exclude.is_some_and(|m| m[px]) {
                continue;
            }
            sum += (x - y) * (x - z);
            count += 1;
        }
    }
    let level = mean(
        &la.iter()
            .zip(&lb)
            .map(|(a, b)| 0.5 * (mean(a) + mean(b)))
            .collect::<Vec<_>>(),
    );
    Ok((sum / count.max(1) as f64).max(0.0).sqrt() / level.max(f64::MIN_POSITIVE))
}

/// Emitters in view: pixels brighter than 20 times their frame's median luminance in any
/// reference frame, dilated by one pixel (their edges).
///
/// # Errors
/// No frames, or frames of different sizes.
pub fn emitter_mask(reference: &[Image]) -> Result<Vec<bool>, FlickerError> {
    at_least(reference, 1)?;
    same_size(&[reference])?;
    let (w, h) = (reference[0].width, reference[0].height);
    let mut bright = vec![false; w * h];
    for f in reference {
        let l = lum(f);
        let mut sorted = l.clone();
        sorted.sort_unstable_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        for (b, v) in bright.iter_mut().zip(&l) {
            *b |= *v > 20.0 * median.max(f64::MIN_POSITIVE);
        }
    }
    Ok(dilate(&bright, w, h, 1))
}

/// Marks every pixel within `d` pixels (a square) of a marked one.
fn dilate(marked: &[bool], w: usize, h: usize, d: usize) -> Vec<bool> {
    let d = d as isize;
    let mut out = vec![false; w * h];
    for y in 0..h as isize {
        for x in 0..w as isize {
            if !marked[(y * w as isize + x) as usize] {
                continue;
            }
            for yy in (y - d).max(0)..=(y + d).min(h as isize - 1) {
                for xx in (x - d).max(0)..=(x + d).min(w as isize - 1) {
                    out[(yy * w as isize + xx) as usize] = true;
                }
            }
        }
    }
    out
}

/// The pixels near what moves: where the reference's luminance ranges over more than
/// `threshold` of its mean across the sequence (after a 3×3 box filter against its noise),
/// dilated by `dilate` pixels.
///
/// # Errors
/// No frames, or frames of different sizes.
pub fn ghost_mask(
    reference: &[Image],
    threshold: f64,
    dilate_by: usize,
) -> Result<Vec<bool>, FlickerError> {
    at_least(reference, 1)?;
    same_size(&[reference])?;
    let (w, h) = (reference[0].width, reference[0].height);
    let boxed: Vec<Vec<f64>> = reference
        .iter()
        .map(|f| box_filter(&lum(f), w, h, 1))
        .collect();
    let mut changing = vec![false; w * h];
    for (i, c) in changing.iter_mut().enumerate() {
        let (lo, hi, sum) = boxed
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY, 0.0), |(lo, hi, s), f| {
                (lo.min(f[i]), hi.max(f[i]), s + f[i])
            });
        let m = sum / boxed.len() as f64;
        *c = hi - lo > threshold * m.max(1e-12);
    }
    Ok(dilate(&changing, w, h, dilate_by))
}

/// Mean over frames of relmse.py's relMSE_trim against `reference` (the per-pixel relMSE
/// without each frame's worst 0.1 % of pixels: a path tracer's rare hits of a small bright
/// emitter would otherwise decide it), over the pixels of `mask` (all pixels when `None`).
///
/// # Errors
/// Sequences of different lengths or sizes, or an empty sequence.
pub fn masked_rel_mse(
    frames: &[Image],
    reference: &[Image],
    mask: Option<&[bool]>,
) -> Result<f64, FlickerError> {
    at_least(frames, 1)?;
    same_size(&[frames, reference])?;
    let mut per_frame = Vec::with_capacity(frames.len());
    for (f, r) in frames.iter().zip(reference) {
        let mut e: Vec<f64> = f
            .pixels
            .iter()
            .zip(&r.pixels)
            .enumerate()
            .filter(|(i, _)| mask.is_none_or(|m| m[*i]))
            .map(|(_, (&a, &b))| pixel_rel_mse(a, b))
            .collect();
        e.sort_unstable_by(f64::total_cmp);
        let keep = trim_keep(e.len()).max(1).min(e.len());
        per_frame.push(e[..keep].iter().sum::<f64>() / keep.max(1) as f64);
    }
    Ok(mean(&per_frame))
}

/// One probe's track against the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeTrack {
    /// Pixel column.
    pub x: usize,
    /// Pixel row.
    pub y: usize,
    /// Largest |I_t/R_t − 1| over the frames.
    pub max_error: f64,
    /// Largest |I_t/R_t − I_{t−1}/R_{t−1}|: a jump.
    pub max_step: f64,
    /// The reference's window never changes by more than 10 % from one frame to the next: the
    /// probe watches a still surface (a moving object's silhouette would make the ratio's
    /// steps the reference's noise at an edge, not the cache's).
    pub still: bool,
}

/// Tracks of the probes at `points`, each the mean over a (2r+1)² window.
///
/// # Errors
/// Sequences of different lengths or sizes, or fewer than two frames.
pub fn probe_tracks(
    frames: &[Image],
    reference: &[Image],
    points: &[(usize, usize)],
    r: usize,
) -> Result<Vec<ProbeTrack>, FlickerError> {
    at_least(frames, 2)?;
    same_size(&[frames, reference])?;
    let (w, h) = (frames[0].width, frames[0].height);
    let (lf, lr): (Vec<Vec<f64>>, Vec<Vec<f64>>) = (
        frames.iter().map(lum).collect(),
        reference.iter().map(lum).collect(),
    );
    Ok(points
        .iter()
        .map(|&(x, y)| {
            let (x, y) = (x.min(w - 1), y.min(h - 1));
            let refs: Vec<f64> = lr
                .iter()
                .map(|l| window_mean(l, w, h, x, y, r).max(1e-12))
                .collect();
            let ratios: Vec<f64> = lf
                .iter()
                .zip(&refs)
                .map(|(l, r_mean)| window_mean(l, w, h, x, y, r) / r_mean)
                .collect();
            ProbeTrack {
                x,
                y,
                max_error: ratios.iter().map(|q| (q - 1.0).abs()).fold(0.0, f64::max),
                max_step: ratios
                    .windows(2)
                    .map(|q| (q[1] - q[0]).abs())
                    .fold(0.0, f64::max),
                still: refs.windows(2).all(|q| (q[1] / q[0] - 1.0).abs() <= 0.1),
            }
        })
        .collect())
}

/// A reference sequence as two independent halves, and what the measures take from it.
pub struct ReferenceSequence {
    /// First half.
    pub a: Vec<Image>,
    /// Second half (the first again for a reference without halves).
    pub b: Vec<Image>,
    /// The halves' mean.
    pub mean: Vec<Image>,
    /// Pixels near what moves ([`ghost_mask`]: a change over 10 %, dilated by 1/32 of the width).
    pub near_motion: Vec<bool>,
    /// Emitters in view ([`emitter_mask`]).
    pub emitters: Vec<bool>,
}

impl ReferenceSequence {
    /// The reference from its halves.
    ///
    /// # Errors
    /// No frames, or halves of different lengths or sizes.
    pub fn new(a: Vec<Image>, b: Vec<Image>) -> Result<ReferenceSequence, FlickerError> {
        at_least(&a, 1)?;
        same_size(&[&a, &b])?;
        let mean: Vec<Image> = a
            .iter()
            .zip(&b)
            .map(|(x, y)| {
                let mut m = x.clone();
                for (p, q) in m.pixels.iter_mut().zip(&y.pixels) {
                    *p = (*p + *q) * 0.5;
                }
                m
            })
            .collect();
        let near_motion = ghost_mask(&mean, 0.1, (mean[0].width / 32).max(1))?;
        let emitters = emitter_mask(&mean)?;
        Ok(ReferenceSequence {
            a,
            b,
            mean,
            near_motion,
            emitters,
        })
    }
}

/// Every measure of a sequence against a reference (`NOTES-001.md` D.8).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SequenceReport {
    /// [`flicker_index`] of the frames.
    pub flicker_index: f64,
    /// [`flicker_index`] of the reference's mean.
    pub reference_flicker_index: f64,
    /// [`high_pass_error`] with emitters left out (`None` below three frames).
    pub high_pass_error: Option<f64>,
    /// [`masked_rel_mse`] over the whole frames.
    pub rel_mse_trim: f64,
    /// [`masked_rel_mse`] near what moves (`None` where nothing moves).
    pub rel_mse_trim_near_motion: Option<f64>,
    /// Pixels near what moves.
    pub pixels_near_motion: usize,
    /// The largest step of the still probes of a 4×4 grid ([`probe_tracks`], 5×5 windows).
    pub probe_max_step: f64,
    /// Their largest error.
    pub probe_max_error: f64,
}

/// Measures `frames` against `reference`.
///
/// # Errors
/// Fewer than two frames, or sequences of different lengths or sizes.
pub fn report(
    frames: &[Image],
    reference: &ReferenceSequence,
) -> Result<SequenceReport, FlickerError> {
    at_least(frames, 2)?;
    same_size(&[frames, &reference.mean])?;
    let (w, h) = (frames[0].width, frames[0].height);
    let probes: Vec<(usize, usize)> = (0..16)
        .map(|i| ((2 * (i % 4) + 1) * w / 8, (2 * (i / 4) + 1) * h / 8))
        .collect();
    let tracks = probe_tracks(frames, &reference.mean, &probes, 2)?;
    let still = || tracks.iter().filter(|t| t.still);
    let near = reference.near_motion.iter().filter(|&&m| m).count();
    Ok(SequenceReport {
        flicker_index: flicker_index(frames)?,
        reference_flicker_index: flicker_index(&reference.mean)?,
        high_pass_error: (frames.len() >= 3)
            .then(|| {
                high_pass_error(
                    frames,
                    &reference.a,
                    &reference.b,
                    Some(&reference.emitters),
                )
            })
            .transpose()?,
        rel_mse_trim: masked_rel_mse(frames, &reference.mean, None)?,
        rel_mse_trim_near_motion: (near > 0)
            .then(|| masked_rel_mse(frames, &reference.mean, Some(&reference.near_motion)))
            .transpose()?,
        pixels_near_motion: near,
        probe_max_step: still().map(|t| t.max_step).fold(0.0, f64::max),
        probe_max_error: still().map(|t| t.max_error).fold(0.0, f64::max),
    })
}

/// A (2r+1)² box filter of a luminance plane, clamped at the borders.
fn box_filter(l: &[f64], w: usize, h: usize, r: usize) -> Vec<f64> {
    (0..w * h)
        .map(|i| window_mean(l, w, h, i % w, i / w, r))
        .collect()
}

/// The mean of a luminance plane over the (2r+1)² window at (x, y), clamped at the borders.
fn window_mean(l: &[f64], w: usize, h: usize, x: usize, y: usize, r: usize) -> f64 {
    let (mut s, mut n) = (0.0, 0);
    for yy in y.saturating_sub(r)..=(y + r).min(h - 1) {
        for xx in x.saturating_sub(r)..=(x + r).min(w - 1) {
            s += l[yy * w + xx];
            n += 1;
        }
    }
    s / f64::from(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_math::Rgb;

    fn frame(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Image {
        let mut img = Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                img.set(x, y, Rgb::splat(f(x, y)));
            }
        }
        img
    }

    #[test]
    fn flicker_index_of_alternating_frames() {
        // Frames alternating between 0.9 and 1.1: every step is 0.2 over a mean of 1.
        let seq: Vec<Image> = (0..6)
            .map(|t| frame(4, 4, |_, _| if t % 2 == 0 { 0.9 } else { 1.1 }))
            .collect();
        assert!((flicker_index(&seq).unwrap() - 0.2).abs() < 1e-6);
        let still: Vec<Image> = (0..6).map(|_| frame(4, 4, |x, _| x as f32)).collect();
        assert_eq!(flicker_index(&still).unwrap(), 0.0);
    }

    #[test]
    fn high_pass_error_ignores_linear_change_and_sees_a_pop() {
        let reference: Vec<Image> = (0..8)
            .map(|t| frame(4, 4, |_, _| 1.0 + 0.1 * t as f32))
            .collect();
        // Off by a constant and a linear drift: no high-pass error.
        let drifting: Vec<Image> = (0..8)
            .map(|t| frame(4, 4, |_, _| 1.2 + 0.12 * t as f32))
            .collect();
        assert!(high_pass_error(&drifting, &reference, &reference, None).unwrap() < 1e-6);
        // A jump of 0.1 at frame 4 gives second differences +0.1 and −0.1.
        let popping: Vec<Image> = (0..8)
            .map(|t| {
                frame(4, 4, |_, _| {
                    1.0 + 0.1 * t as f32 + if t >= 4 { 0.1 } else { 0.0 }
                })
            })
            .collect();
        let fhp = high_pass_error(&popping, &reference, &reference, None).unwrap();
        // mean of d² over 6 second differences, two of them ±0.1: √(0.02/6) / mean(R) (1.35).
        let want = (0.02f64 / 6.0).sqrt() / 1.35;
        assert!((fhp - want).abs() < 1e-5 * want, "{fhp} vs {want}");
    }

    #[test]
    fn independent_reference_noise_cancels() {
        // Two halves with independent ±0.05 noise around the truth, the frames exact: the mean
        // product is near zero where the squared error against one half is not.
        let mut state = 1u64;
        let mut noise = || {
            state = ircache_math::rng::mix64(state);
            if state & 1 == 0 {
                0.05
            } else {
                -0.05
            }
        };
        let truth: Vec<Image> = (0..10).map(|_| frame(16, 16, |_, _| 1.0)).collect();
        let mut half = || -> Vec<Image> {
            (0..10)
                .map(|_| {
                    let mut f = frame(16, 16, |_, _| 1.0);
                    for p in &mut f.pixels {
                        *p = Rgb::splat(1.0 + noise());
                    }
                    f
                })
                .collect()
        };
        let (a, b) = (half(), half());
        let cancelled = high_pass_error(&truth, &a, &b, None).unwrap();
        let plain = high_pass_error(&truth, &a, &a, None).unwrap();
        assert!(plain > 0.1, "{plain}");
        assert!(cancelled < 0.3 * plain, "{cancelled} vs {plain}");
    }

    #[test]
    fn ghost_mask_covers_the_moving_square_and_its_border() {
        // A bright 2×2 square moving one pixel a frame along row 5.
        let seq: Vec<Image> = (0..4)
            .map(|t| {
                frame(16, 12, move |x, y| {
                    if (4..6).contains(&y) && (t + 2..t + 4).contains(&x) {
                        5.0
                    } else {
                        1.0
                    }
                })
            })
            .collect();
        let mask = ghost_mask(&seq, 0.1, 2).unwrap();
        assert!(mask[5 * 16 + 4]);
        assert!(mask[16 + 4], "dilated upwards (row 1)");
        assert!(!mask[11 * 16 + 15], "far corner");
    }

    #[test]
    fn masked_rel_mse_is_compare_s_rel_mse_trim_without_a_mask() {
        let mut state = 7u64;
        let mut noise = || {
            state = ircache_math::rng::mix64(state);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut noisy = || {
            let mut f = frame(40, 30, |_, _| 0.0);
            for p in &mut f.pixels {
                *p = Rgb::splat(0.5 + noise());
            }
            f
        };
        let a: Vec<Image> = (0..3).map(|_| noisy()).collect();
        let b: Vec<Image> = (0..3).map(|_| noisy()).collect();
        let want = a
            .iter()
            .zip(&b)
            .map(|(x, y)| crate::compare::compare(x, y).unwrap().rel_mse_trim)
            .sum::<f64>()
            / 3.0;
        let got = masked_rel_mse(&a, &b, None).unwrap();
        assert!((got - want).abs() < 1e-12 * want, "{got} vs {want}");
    }

    #[test]
    fn emitter_mask_leaves_out_a_moving_light_from_the_high_pass_error() {
        // A light (100) moving a pixel a frame over a dim wall (0.1); the frames get the wall
        // right and the light's position wrong by a pixel on odd frames.
        let light_at =
            |t: usize| move |x: usize, y: usize| if y == 4 && x == t + 2 { 100.0 } else { 0.1 };
        let reference: Vec<Image> = (0..6).map(|t| frame(12, 8, light_at(t))).collect();
        let frames: Vec<Image> = (0..6).map(|t| frame(12, 8, light_at(t + t % 2))).collect();
        let mask = emitter_mask(&reference).unwrap();
        assert!(mask[4 * 12 + 2] && mask[3 * 12 + 3] && !mask[0]);
        assert!(high_pass_error(&frames, &reference, &reference, None).unwrap() > 1.0);
        assert_eq!(
            high_pass_error(&frames, &reference, &reference, Some(&mask)).unwrap(),
            0.0
        );
    }

    #[test]
    fn probe_tracks_find_the_jump() {
        let reference: Vec<Image> = (0..5).map(|_| frame(8, 8, |_, _| 2.0)).collect();
        let seq: Vec<Image> = (0..5)
            .map(|t| frame(8, 8, |_, _| if t == 3 { 2.1 } else { 2.0 }))
            .collect();
        let tracks = probe_tracks(&seq, &reference, &[(3, 3)], 1).unwrap();
        assert!((tracks[0].max_error - 0.05).abs() < 1e-6);
        assert!((tracks[0].max_step - 0.05).abs() < 1e-6);
        assert!(tracks[0].still);
        // A reference that jumps by 20 % makes the probe not still.
        let mut moving = reference.clone();
        moving[2] = frame(8, 8, |_, _| 2.4);
        assert!(!probe_tracks(&seq, &moving, &[(3, 3)], 1).unwrap()[0].still);
    }
}
