//! `ircache compare A B`: the error measures of `shared/references/README.md`; with
//! `--sequence`, the flicker and temporal error of frame sequences (`ircache_image::flicker`).

use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `ircache compare`.
#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The image to judge (with --sequence, a file name whose run of `#` is the frame number).
    pub image: PathBuf,
    /// The reference (with --sequence, a name pattern as for the image; optional there: without
    /// it only the flicker index is measured).
    pub reference: Option<PathBuf>,
    /// Measure frames A..B (both included) of a sequence: the flicker index; with a reference,
    /// the high-pass temporal error, the mean relMSE, the relMSE near what moves, and probe
    /// tracks (`NOTES-001.md` D.8).
    #[arg(long, value_name = "A..B", value_parser = crate::animate::parse_frames)]
    pub sequence: Option<(u32, u32)>,
    /// With --sequence: a second, independent half of the reference (its noise then cancels
    /// in the high-pass error; the relMSE is measured against the halves' mean).
    #[arg(long, value_name = "PATTERN", requires = "sequence")]
    pub reference_b: Option<PathBuf>,
    /// Write a false-colour PNG of the relative luminance error (red: brighter, blue: darker).
    #[arg(long, value_name = "FILE.png")]
    pub falsecolor: Option<PathBuf>,
    /// Relative error at which the false colour saturates.
    #[arg(long, default_value_t = 0.5)]
    pub range: f64,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Blur both images with a Gaussian of this standard deviation (pixels) before measuring:
    /// the low-frequency error (blotches, leaks, bias) that survives while pixel noise fades.
    #[arg(long, value_name = "SIGMA", default_value_t = 0.0)]
    pub blur: f64,
}

/// Runs `ircache compare`.
pub fn run(args: &CompareArgs) -> Result<()> {
    if !(args.blur >= 0.0 && args.blur.is_finite()) {
        anyhow::bail!(
            "--blur: expected a standard deviation ≥ 0 in pixels, found {}",
            args.blur
        );
    }
    if let Some(frames) = args.sequence {
        return sequence(args, frames);
    }
    let Some(reference) = &args.reference else {
        anyhow::bail!("compare needs a reference image (or --sequence A..B for the flicker index)");
    };
    let a = ircache_image::read_image(&args.image)?;
    let b = ircache_image::read_image(reference)?;
    let (a, b) = if args.blur > 0.0 {
        use ircache_image::blur::gaussian_blur;
        (gaussian_blur(&a, args.blur), gaussian_blur(&b, args.blur))
    } else {
        (a, b)
    };
    let m = ircache_image::compare::compare(&a, &b)?;
    if let Some(fc) = &args.falsecolor {
        let img = ircache_image::falsecolor::false_colour(&a, &b, args.range);
        ircache_image::write_png(fc, &img, 0.0)?;
    }
    if args.json {
        let j = serde_json::json!({
            "a": args.image.display().to_string(),
            "b": reference.display().to_string(),
            "relMSE": m.rel_mse,
            "relMSE_trim": m.rel_mse_trim,
            "RMSE": m.rmse,
            "MRE_lum": m.mre_lum,
            "lum_ratio": m.lum_ratio,
            "mean_lum_a": m.mean_lum_a,
            "mean_lum_b": m.mean_lum_b,
            "nonfinite_a": m.nonfinite_a,
            "blur": args.blur,
        });
        println!("{j}");
    } else {
        println!(
            "relMSE={:.6e}  relMSE_trim={:.6e}  RMSE={:.6e}  MRE_lum={:.6e}  lum_ratio={:.6}  mean_lum_a={:.6}  mean_lum_b={:.6}  nonfinite_a={}",
            m.rel_mse, m.rel_mse_trim, m.rmse, m.mre_lum, m.lum_ratio, m.mean_lum_a, m.mean_lum_b, m.nonfinite_a
        );
    }
    Ok(())
}

/// Reads frames `first..=last` of the sequence named by `pattern`.
pub fn read_sequence(
    pattern: &std::path::Path,
    (first, last): (u32, u32),
) -> Result<Vec<ircache_image::Image>> {
    (first..=last)
        .map(|f| {
            let path = crate::animate::frame_path(pattern, f)?;
            ircache_image::read_image(&path)
                .with_context(|| format!("reading frame {f}: {}", path.display()))
        })
        .collect()
}

/// `ircache compare --sequence`: the measures of `ircache_image::flicker`.
fn sequence(args: &CompareArgs, frames: (u32, u32)) -> Result<()> {
    use ircache_image::flicker::{flicker_index, report, ReferenceSequence};
    let blur = |seq: Vec<ircache_image::Image>| -> Vec<ircache_image::Image> {
        if args.blur > 0.0 {
            seq.iter()
                .map(|f| ircache_image::blur::gaussian_blur(f, args.blur))
                .collect()
        } else {
            seq
        }
    };
    let images = blur(read_sequence(&args.image, frames)?);
    let mut j = serde_json::json!({
        "frames": [frames.0, frames.1],
        "blur": args.blur,
        "flicker_index": flicker_index(&images)?,
    });
    if let Some(reference) = &args.reference {
        let a = blur(read_sequence(reference, frames)?);
        let b = match &args.reference_b {
            Some(p) => blur(read_sequence(p, frames)?),
            None => a.clone(),
        };
        let r = report(&images, &ReferenceSequence::new(a, b)?)?;
        let ext = serde_json::json!({
            "reference_flicker_index": r.reference_flicker_index,
            "high_pass_error": r.high_pass_error,
            "rel_mse_trim": r.rel_mse_trim,
            "rel_mse_trim_near_motion": r.rel_mse_trim_near_motion,
            "pixels_near_motion": r.pixels_near_motion,
            "probe_max_error": r.probe_max_error,
            "probe_max_step": r.probe_max_step,
        });
        if let (Some(o), Some(e)) = (j.as_object_mut(), ext.as_object()) {
            o.extend(e.clone());
        }
    }
    if args.json {
        println!("{j}");
    } else if let Some(o) = j.as_object() {
        let line: Vec<String> = o.iter().map(|(k, v)| format!("{k}={v}")).collect();
        println!("{}", line.join("  "));
    }
    Ok(())
}

/// Arguments of `ircache merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// Images to sum (the same size).
    #[arg(required = true, num_args = 1..)]
    pub images: Vec<std::path::PathBuf>,
    /// The sum.
    #[arg(short = 'o', long = "output")]
    pub output: std::path::PathBuf,
}

/// Runs `ircache merge`: the pixelwise sum of the images.
pub fn merge(args: &MergeArgs) -> anyhow::Result<()> {
    use anyhow::Context;
    let mut sum: Option<ircache_image::Image> = None;
    for p in &args.images {
        let img =
            ircache_image::read_image(p).with_context(|| format!("reading {}", p.display()))?;
        match &mut sum {
            None => sum = Some(img),
            Some(s) => {
                if (s.width, s.height) != (img.width, img.height) {
                    anyhow::bail!(
                        "{}: {}×{}, but the first image is {}×{}",
                        p.display(),
                        img.width,
                        img.height,
                        s.width,
                        s.height
                    );
                }
                for (a, b) in s.pixels.iter_mut().zip(&img.pixels) {
                    *a += *b;
                }
            }
        }
    }
    let sum = sum.context("no images")?;
    ircache_image::write_image(&args.output, &sum, 0.0)?;
    Ok(())
}
