//! `--gpu`: the GPU splatter (the `ircache-gpu` crate) behind the `gpu` feature, on by default.

use anyhow::Result;
use ircache_render::splatting::buffer::Splatter;
use std::sync::Arc;

/// A splatter on the GPU and a line saying where its calls ran.
pub struct GpuSplatting {
    /// The splatter, for the integrator or the walkthrough.
    pub splatter: Arc<dyn Splatter>,
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
    let splatter = Arc::new(ircache_gpu::splat::GpuSplatter::new(gpu));
    let counts = splatter.clone();
    Ok(GpuSplatting {
        splatter,
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
