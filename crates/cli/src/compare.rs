//! `ircache compare A B`: the error measures of `shared/references/README.md`.

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `ircache compare`.
#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The image to judge.
    pub image: PathBuf,
    /// The reference.
    pub reference: PathBuf,
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
    let a = ircache_image::read_image(&args.image)?;
    let b = ircache_image::read_image(&args.reference)?;
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
            "b": args.reference.display().to_string(),
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
