//! ircache's GPU passes, through wgpu (Vulkan, Metal, DirectX 12) and WGSL (paper 001 ch. 4,
//! §4.4–§4.6; NOTES-001 part C). One module and one shader file per pass:
//!
//! - [`splat`] (`shaders/splat.wgsl`): radiance cache splatting of irradiance records over a
//!   layer of samples, a [`ircache_render::splatting::buffer::Splatter`] the `splat` integrator
//!   and the walkthrough use in place of the CPU's.
//! - [`visibility`] (`shaders/visibility.wgsl`): the scene's triangles rasterised through a view,
//!   the nearest per pixel: a record's hemisphere plane filled by rasterising, thousands to a
//!   pass; the camera's view; a shadow map.
//! - [`frame`] (`shaders/frame.wgsl`): a whole frame with a warm cache, the thesis's pipeline
//!   (G-buffer by rasterisation, splatting, direct light by a shadow map, composition) for
//!   Lambertian scenes of constant albedo under one directional light.
//! - [`records`] (`shaders/records.wgsl`): records computed by hemisphere rasterisation, their
//!   planes rasterised, shaded and summed on the GPU, for the same scenes.
//!
//! Nothing else in ircache depends on this crate; the CLI uses it behind its `gpu` feature (on
//! by default). Without a device, [`Gpu::new`] says so ([`GpuError::NoDevice`]). On machines
//! without a GPU, Mesa's lavapipe (a software Vulkan device, Debian's `mesa-vulkan-drivers`) runs
//! the same shaders; the tests use it and say when no device exists.

pub mod frame;
pub mod records;
pub mod splat;
pub mod visibility;

use thiserror::Error;

/// What can go wrong on the GPU.
#[derive(Debug, Error)]
pub enum GpuError {
    /// No adapter: no GPU and no software device (install Mesa's lavapipe,
    /// `mesa-vulkan-drivers`, for one).
    #[error("no GPU device found ({0}); on a machine without a GPU, Mesa's lavapipe (Debian: mesa-vulkan-drivers) provides a software Vulkan device")]
    NoDevice(String),
    /// The device refused the request.
    #[error("the GPU device could not be opened: {0}")]
    Device(String),
    /// A buffer could not be read back.
    #[error("reading a GPU buffer back failed: {0}")]
    ReadBack(String),
    /// The device reported an error (validation, out of memory) for a pass.
    #[error("the GPU reported: {0}")]
    Reported(String),
    /// The scene holds what a GPU pass does not serve.
    #[error("not served on the GPU: {0}")]
    Unsupported(String),
}

/// An open device and its queue.
#[derive(Debug)]
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What it is (name, backend, driver).
    pub info: wgpu::AdapterInfo,
    /// Errors the device reported since the last [`Gpu::check`] (wgpu's default handler would
    /// panic).
    errors: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
}

impl Gpu {
    /// Opens the first adapter wgpu finds (a hardware GPU before a software one).
    ///
    /// # Errors
    /// [`GpuError::NoDevice`] when there is none, [`GpuError::Device`] when it refuses.
    pub fn new() -> Result<Gpu, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoDevice(e.to_string()))?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("ircache"),
            // What the adapter offers: large buffers, six storage buffers a pass.
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        let errors = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(std::sync::Arc::new(move |e: wgpu::Error| {
            if let Ok(mut list) = sink.lock() {
                list.push(e.to_string());
            }
        }));
        Ok(Gpu {
            device,
            queue,
            info,
            errors,
        })
    }

    /// The errors the device reported since the last call, as one.
    ///
    /// # Errors
    /// [`GpuError::Reported`] when there were any.
    pub fn check(&self) -> Result<(), GpuError> {
        let mut list = self
            .errors
            .lock()
            .map_err(|e| GpuError::Reported(e.to_string()))?;
        if list.is_empty() {
            Ok(())
        } else {
            let all = list.join("; ");
            list.clear();
            Err(GpuError::Reported(all))
        }
    }

    /// A one-line description: adapter name, kind and backend.
    #[must_use]
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.device_type, self.info.backend
        )
    }

    /// A buffer holding `contents`.
    pub(crate) fn buffer(
        &self,
        label: &str,
        contents: &[u8],
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
    }

    /// A 2D texture of one level and one sample.
    pub(crate) fn texture(
        &self,
        label: &str,
        (width, height): (u32, u32),
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> wgpu::Texture {
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    }

    /// Copies `source` (whole) into a mappable buffer and reads it back.
    ///
    /// # Errors
    /// [`GpuError::ReadBack`] when mapping fails.
    pub fn read_back(&self, source: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
        let size = source.size();
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read back"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encoder.copy_buffer_to_buffer(source, 0, &staging, 0, size);
        self.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::ReadBack(e.to_string()))?;
        rx.recv()
            .map_err(|e| GpuError::ReadBack(e.to_string()))?
            .map_err(|e| GpuError::ReadBack(e.to_string()))?;
        let bytes = staging.get_mapped_range(..).to_vec();
        staging.unmap();
        Ok(bytes)
    }
}
