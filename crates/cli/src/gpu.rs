//! `--gpu`: the GPU splatter (the `ircache-gpu` crate) behind the `gpu` feature, on by default.

use anyhow::Result;
use ircache_render::splatting::buffer::Splatter;
use std::sync::Arc;

/// A splatter on the GPU and a line saying where its calls ran.
pub struct GpuSplatting {
    /// The splatter, for the integrator or the walkthrough.
    pub splatter: Arc<dyn Splatter>,
    /// The same, for the whole frame on the GPU.
    #[cfg(feature = "gpu")]
    pub gpu_splatter: Arc<ircache_gpu::splat::GpuSplatter>,
    /// Its device.
    #[cfg(feature = "gpu")]
    pub gpu: Arc<ircache_gpu::Gpu>,
    /// The device: name, kind, backend.
    pub device: String,
    /// "device: N calls on the GPU, M on the CPU (radiance records), K failed".
    pub summary: Box<dyn Fn() -> String + Send + Sync>,
}

/// Opens the GPU and makes its splatter.
///
/// # Errors
/// Without a device, or built without the `gpu` feature.
#[cfg(feature = "gpu")]
pub fn splatter() -> Result<GpuSplatting> {
    use std::sync::atomic::Ordering;
    let gpu = Arc::new(ircache_gpu::Gpu::new()?);
    let device = gpu.describe();
    let splatter = Arc::new(ircache_gpu::splat::GpuSplatter::new(gpu.clone()));
    let counts = splatter.clone();
    Ok(GpuSplatting {
        splatter: splatter.clone(),
        gpu_splatter: splatter,
        gpu,
        device: device.clone(),
        summary: Box::new(move || {
            let first = counts
                .first_failure
                .lock()
                .ok()
                .and_then(|f| f.clone())
                .map_or(String::new(), |f| format!(" (the first: {f})"));
            format!(
                "GPU {device}: {} splat calls on the GPU ({} with radiance records, whose glossy \
                 sums the CPU added), {} failed and ran on the CPU{first}",
                counts.gpu_calls.load(Ordering::Relaxed),
                counts.glossy_on_cpu.load(Ordering::Relaxed),
                counts.failures.load(Ordering::Relaxed)
            )
        }),
    })
}

/// Opens the GPU and makes its splatter.
///
/// # Errors
/// Always: this build has no `gpu` feature.
#[cfg(not(feature = "gpu"))]
pub fn splatter() -> Result<GpuSplatting> {
    anyhow::bail!(
        "--gpu: this ircache was built without the gpu feature (cargo build --features gpu)"
    )
}

/// With `--record-source gpu-plane`, attaches the GPU's record planes to `ic` (see
/// [`plane_source`]); nothing otherwise.
///
/// # Errors
/// As [`plane_source`].
pub fn attach_plane_source(
    ic: &mut ircache_render::integrators::ic::IcIntegrator,
    scene: &ircache_render::scene::Scene,
) -> Result<()> {
    use ircache_render::irradiance_cache::params::RecordSource;
    if ic.params.record_source == RecordSource::GpuPlane {
        ic.plane_source = Some(plane_source(scene, &ic.params)?);
    }
    Ok(())
}

/// The GPU's record planes for `--record-source gpu-plane`: the scene on the GPU (the scenes
/// its whole frame serves: Lambertian, constant albedos, one directional light), each batch's
/// planes rasterised, shaded and reduced there.
///
/// # Errors
/// Without a device, for a scene the GPU frame does not serve, or built without the `gpu`
/// feature.
#[cfg(feature = "gpu")]
pub fn plane_source(
    scene: &ircache_render::scene::Scene,
    params: &ircache_render::irradiance_cache::IcParams,
) -> Result<Arc<dyn ircache_render::irradiance_cache::plane::PlaneSource>> {
    use ircache_render::irradiance_cache::gather::{PLANE_HALF_SIZE, PLANE_PIXELS};
    use ircache_render::irradiance_cache::plane::HemispherePlane;
    let gpu = Arc::new(ircache_gpu::Gpu::new()?);
    let splatter = Arc::new(ircache_gpu::splat::GpuSplatter::new(gpu.clone()));
    let cache = ircache_render::irradiance_cache::IrradianceCache::new(scene, params);
    let frame = ircache_gpu::frame::GpuFrame::new(
        gpu,
        splatter,
        scene,
        &cache,
        ircache_gpu::frame::SHADOW_MAP,
    )
    .map_err(|e| anyhow::anyhow!("--record-source gpu-plane: {e}"))?;
    Ok(Arc::new(ircache_gpu::records::GpuPlaneSource::new(
        frame,
        &HemispherePlane::new(PLANE_PIXELS, PLANE_HALF_SIZE),
    )))
}

/// The GPU's record planes.
///
/// # Errors
/// Always: this build has no `gpu` feature.
#[cfg(not(feature = "gpu"))]
pub fn plane_source(
    _: &ircache_render::scene::Scene,
    _: &ircache_render::irradiance_cache::IcParams,
) -> Result<Arc<dyn ircache_render::irradiance_cache::plane::PlaneSource>> {
    anyhow::bail!(
        "--record-source gpu-plane: this ircache was built without the gpu feature (cargo build \
         --features gpu); --record-source plane makes the same records on the CPU"
    )
}

/// `render --integrator splat --gpu` as a whole frame on the GPU (`ircache_gpu::frame`): the
/// pre-pass on the CPU, then each of the `spp` layers rasterised, splatted, shadow-mapped and
/// composed on the GPU through points `layer_jitter(k)` from the pixel centres, and averaged
/// (a box filter). `Ok(false)`, after a note saying why, where the scene or the options ask for
/// what that path does not serve: the caller splats on the GPU and does the rest on the CPU.
///
/// # Errors
/// When the pre-pass, the GPU or writing the image fails.
#[cfg(feature = "gpu")]
pub fn whole_frame(
    splatting: &GpuSplatting,
    args: &crate::render::RenderArgs,
    scene: &ircache_render::scene::Scene,
    integrator: &ircache_render::integrators::Integrator,
    settings: &ircache_render::render::RenderSettings,
    output: &std::path::Path,
) -> Result<bool> {
    use ircache_gpu::frame::{layer_jitter, GpuFrame, SHADOW_MAP};
    use ircache_render::integrators::Integrator;
    use std::time::Instant;
    let other = if !args.aov.is_empty() {
        Some("--aov")
    } else if args.tile.is_some() {
        Some("--tile")
    } else if args.adaptive.is_some() {
        Some("--adaptive")
    } else if args.stats.is_some() {
        Some("--stats")
    } else if settings.filter != ircache_render::film::Filter::Box {
        Some("a reconstruction filter other than box")
    } else {
        None
    };
    if let Some(option) = other {
        eprintln!(
            "note: the whole frame on the GPU does not take {option}: splatting on the GPU, the \
             rest on the CPU"
        );
        return Ok(false);
    }
    if let Err(e) = GpuFrame::serves(scene) {
        let why = match e {
            ircache_gpu::GpuError::Unsupported(why) => why,
            e => e.to_string(),
        };
        eprintln!(
            "note: the whole frame on the GPU does not serve this scene ({why}): splatting on the \
             GPU, the rest on the CPU"
        );
        return Ok(false);
    }
    let t0 = Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()?;
    let (ready, _) = integrator.prepare(scene, settings, &pool)?;
    let Integrator::Ic(ic) = ready else {
        anyhow::bail!("--gpu needs --integrator splat");
    };
    let Some(cache) = ic.cache.clone() else {
        anyhow::bail!("--gpu: the pre-pass made no cache");
    };
    let pre_pass = t0.elapsed().as_secs_f64();
    let frame = match GpuFrame::new(
        splatting.gpu.clone(),
        splatting.gpu_splatter.clone(),
        scene,
        &cache,
        SHADOW_MAP,
    ) {
        Ok(frame) => frame,
        // The device refused the scene's buffers (too large for it, say).
        Err(e) => {
            eprintln!(
                "note: the whole frame could not be set up on the GPU ({e}): splatting on the GPU, \
                 the rest on the CPU"
            );
            return Ok(false);
        }
    };
    let (w, h) = (settings.width as u32, settings.height as u32);
    let job = frame.prepare(&cache, &scene.camera, w, h, settings.filter.radius())?;
    let layers = settings.sampler().spp.max(1);
    let t = Instant::now();
    for k in 0..layers {
        frame.render_layer(&job, layer_jitter(k), k > 0);
    }
    frame.wait()?;
    let gpu_seconds = t.elapsed().as_secs_f64();
    let image = frame.read(&job)?;
    ircache_image::write_image(
        output,
        &ircache_image::Image {
            width: settings.width,
            height: settings.height,
            pixels: image.pixels,
        },
        args.exposure,
    )?;
    if !args.quiet {
        eprintln!(
            "{}: {w}×{h}, {layers} layers, the whole frame on the GPU ({}) in {:.1} ms; pre-pass \
             {pre_pass:.2} s on the CPU ({} records); {} record sites no record served (no \
             indirect light there)",
            output.display(),
            splatting.device,
            gpu_seconds * 1e3,
            cache.levels.first().map_or(0, |s| s.len()),
            image.misses
        );
    }
    Ok(true)
}

/// Without the `gpu` feature there is no whole frame on the GPU.
///
/// # Errors
/// Never.
#[cfg(not(feature = "gpu"))]
pub fn whole_frame(
    _: &GpuSplatting,
    _: &crate::render::RenderArgs,
    _: &ircache_render::scene::Scene,
    _: &ircache_render::integrators::Integrator,
    _: &ircache_render::render::RenderSettings,
    _: &std::path::Path,
) -> Result<bool> {
    Ok(false)
}
