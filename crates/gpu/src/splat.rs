//! Radiance cache splatting on the GPU (001 ch. 4, Algorithm 3; NOTES-001 §C.2), the pass of
//! `shaders/splat.wgsl`: irradiance records over one layer of samples.
//!
//! The records' film rectangles are the CPU splatter's
//! ([`ircache_render::splatting::buffer::record_rects`]); the CPU files each record under the
//! 16 × 16 tiles its rectangle touches, in index order, and one workgroup per touched tile, one
//! invocation per sample, walks the tile's list. So a sample meets the same records in the same
//! order as on the CPU and the sums agree to the GPU's rounding, with no float blending, whose
//! order no GPU fixes (the thesis blends splatted quads into a float target). The G-buffer's
//! samples stay on the GPU while the G-buffer holds the same filling
//! ([`GBuffer::filling`]); each call sends its records and the sums of the tiles they touch and
//! reads those sums back, so the miss search's small batches move little. The glossy sums of radiance records (they
//! need the rotation and the BRDF coefficients on the GPU) are not there yet: the CPU adds them
//! ([`ircache_render::splatting::buffer::splat_parts`] with `Sums::Glossy`), counted in
//! [`GpuSplatter::glossy_on_cpu`].

use crate::{Gpu, GpuError};
use bytemuck::{Pod, Zeroable};
use ircache_render::camera::Camera;
use ircache_render::irradiance_cache::gather::IrradianceCache;
use ircache_render::irradiance_cache::record::{ErrorMetric, GradientMode, NO_RADIANCE};
use ircache_render::render::TILE;
use ircache_render::splatting::buffer::{
    record_rects_at, splat, splat_parts, SplatBuffer, Splatter, Sums,
};
use ircache_render::splatting::GBuffer;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// A record as the shader reads it (`Record` in `splat.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuRecord {
    p_r: [f32; 4],
    n: [f32; 4],
    e: [f32; 4],
    gt: [[f32; 4]; 3],
    gr: [[f32; 4]; 3],
}

/// A sample as the shader reads it (`Sample`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuSample {
    p: [f32; 4],
    n: [f32; 4],
    n_bump: [f32; 4],
}

/// A sample's sums (`Sums`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuSums {
    irradiance: [f32; 4],
    count: u32,
    min_error: f32,
    pad: [u32; 2],
}

/// The pass's constants (`Params`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuParams {
    width: u32,
    height: u32,
    tiles_x: u32,
    metric: u32,
    gradients: u32,
    accuracy: f32,
    tile_count: u32,
    threshold: f32,
}

/// Samples in a tile (`TILE`² in `splat.wgsl`).
const TILE_SAMPLES: usize = TILE * TILE;

/// Workgroups along x of a dispatch (`GROUPS_X`): touched tiles beyond wrap to further rows, so
/// that no film exceeds a device's 65 535 workgroups a dimension.
const GROUPS_X: u32 = 32_768;

/// A G-buffer's samples kept on the GPU, and the filling they copy.
#[derive(Debug)]
struct Resident {
    filling: std::sync::Weak<()>,
    samples: wgpu::Buffer,
}

/// Splatting on a GPU: a [`Splatter`].
#[derive(Debug)]
pub struct GpuSplatter {
    gpu: Arc<Gpu>,
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    /// Calls whose irradiance sums the GPU made.
    pub gpu_calls: AtomicU64,
    /// Of those, calls whose radiance records' glossy sums the CPU added.
    pub glossy_on_cpu: AtomicU64,
    /// Calls the GPU failed (read-back or device errors); the CPU did them whole.
    pub failures: AtomicU64,
    /// The first failure's message (later ones often only repeat its consequence).
    pub first_failure: std::sync::Mutex<Option<String>>,
    /// The samples of the last G-buffer splatted over.
    resident: std::sync::Mutex<Option<Resident>>,
}

impl GpuSplatter {
    /// The pass on `gpu`.
    #[must_use]
    pub fn new(gpu: Arc<Gpu>) -> GpuSplatter {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("splat.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/splat.wgsl").into()),
        });
        let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("splat"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage(1, true),
                storage(2, true),
                storage(3, true),
                storage(4, true),
                storage(5, false),
                storage(6, true),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("splat"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("splat"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("splat"),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            cache: None,
        });
        GpuSplatter {
            gpu,
            pipeline,
            layout,
            gpu_calls: AtomicU64::new(0),
            glossy_on_cpu: AtomicU64::new(0),
            failures: AtomicU64::new(0),
            first_failure: std::sync::Mutex::new(None),
            resident: std::sync::Mutex::new(None),
        }
    }

    /// The GPU's part of [`Splatter::splat`]: irradiance records only.
    fn splat_on_gpu(
        &self,
        buffer: &mut SplatBuffer,
        g: &GBuffer,
        cache: &IrradianceCache,
        ids: Range<usize>,
        camera: &Camera,
        filter_reach: f32,
    ) -> Result<(), GpuError> {
        let Some(input) = SplatInput::pack(buffer, g, cache, ids, camera, filter_reach) else {
            return Ok(());
        };
        let samples = self.resident_samples(g);
        let job = self.upload(&input, &samples);
        self.dispatch(&job);
        self.read(&job, buffer)
    }

    /// `g`'s samples on the GPU: those already there while `g` holds the same filling, else
    /// uploaded (and kept in place of the previous G-buffer's).
    pub fn resident_samples(&self, g: &GBuffer) -> wgpu::Buffer {
        let mut resident = self
            .resident
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(r) = resident.as_ref() {
            if r.filling
                .upgrade()
                .is_some_and(|f| Arc::ptr_eq(&f, g.filling()))
            {
                return r.samples.clone();
            }
        }
        let v = |v: ircache_math::Vec3, w: f32| [v.x, v.y, v.z, w];
        let samples: Vec<GpuSample> = g
            .samples
            .par_iter()
            .map(|s| match &s.point {
                Some(sp) => GpuSample {
                    p: v(sp.it.p, 1.0),
                    n: v(sp.n, 0.0),
                    n_bump: v(sp.n_bump, 0.0),
                },
                None => GpuSample::zeroed(),
            })
            .collect();
        let buffer = self.gpu.buffer(
            "samples",
            bytemuck::cast_slice(&samples),
            wgpu::BufferUsages::STORAGE,
        );
        *resident = Some(Resident {
            filling: Arc::downgrade(g.filling()),
            samples: buffer.clone(),
        });
        buffer
    }

    /// Drops the resident samples (the next call uploads them again).
    pub fn forget_samples(&self) {
        *self
            .resident
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner) = None;
    }

    /// Uploads a packed input over resident `samples`: the buffers and the bind group of one
    /// dispatch.
    #[must_use]
    pub fn upload(&self, input: &SplatInput, samples: &wgpu::Buffer) -> SplatJob {
        self.upload_over(input, samples, None)
    }

    /// [`GpuSplatter::upload`] adding into `sums` (of `input`'s layout, already on the GPU)
    /// instead of uploading `input`'s: passes that share one film's sums.
    #[must_use]
    pub fn upload_over(
        &self,
        input: &SplatInput,
        samples: &wgpu::Buffer,
        sums: Option<&wgpu::Buffer>,
    ) -> SplatJob {
        let device = &self.gpu.device;
        let init = |label: &str, contents: &[u8], usage| self.gpu.buffer(label, contents, usage);
        let storage = wgpu::BufferUsages::STORAGE;
        let params_buffer = init(
            "params",
            bytemuck::bytes_of(&input.params),
            wgpu::BufferUsages::UNIFORM,
        );
        let records_buffer = init("records", bytemuck::cast_slice(&input.records), storage);
        let tiles_buffer = init("tiles", bytemuck::cast_slice(&input.tiles), storage);
        let start_buffer = init("tile start", bytemuck::cast_slice(&input.start), storage);
        let lists_buffer = init("tile records", bytemuck::cast_slice(&input.lists), storage);
        let sums_buffer = match sums {
            Some(b) => b.clone(),
            None => init(
                "sums",
                bytemuck::cast_slice(&input.sums),
                storage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            ),
        };
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("splat"),
            layout: &self.layout,
            entries: &[
                (0, &params_buffer),
                (1, &records_buffer),
                (2, samples),
                (3, &start_buffer),
                (4, &lists_buffer),
                (5, &sums_buffer),
                (6, &tiles_buffer),
            ]
            .map(|(binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }),
        });
        let count = input.params.tile_count;
        SplatJob {
            bind,
            sums: sums_buffer,
            groups: (count.min(GROUPS_X), count.div_ceil(GROUPS_X)),
            tiles: input.tiles.clone(),
            size: (input.params.width as usize, input.params.height as usize),
        }
    }

    /// Submits the splat of an uploaded job (its sums accumulate: a second dispatch adds the
    /// records again).
    pub fn dispatch(&self, job: &SplatJob) {
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        self.encode(&mut encoder, job);
        self.gpu.queue.submit([encoder.finish()]);
    }

    /// Records the splat of an uploaded job into `encoder`.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, job: &SplatJob) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &job.bind, &[]);
        pass.dispatch_workgroups(job.groups.0, job.groups.1, 1);
    }

    /// Waits for the GPU to finish what was submitted.
    ///
    /// # Errors
    /// When the device reports an error.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.gpu
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Reported(e.to_string()))?;
        self.gpu.check()
    }

    /// Reads a job's sums back into `buffer` (written only once they are back and checked).
    ///
    /// # Errors
    /// When the read-back fails or the device reported an error.
    pub fn read(&self, job: &SplatJob, buffer: &mut SplatBuffer) -> Result<(), GpuError> {
        let bytes = self.gpu.read_back(&job.sums)?;
        self.gpu.check()?;
        let sums: &[GpuSums] = bytemuck::cast_slice(&bytes);
        let (w, h) = job.size;
        let tiles_x = w.div_ceil(TILE);
        for (&tile, tile_sums) in job.tiles.iter().zip(sums.chunks_exact(TILE_SAMPLES)) {
            let (x0, y0) = (
                tile as usize % tiles_x * TILE,
                tile as usize / tiles_x * TILE,
            );
            for (k, s) in tile_sums.iter().enumerate() {
                let (x, y) = (x0 + k % TILE, y0 + k / TILE);
                if x < w && y < h {
                    let p = &mut buffer.pixels[y * w + x];
                    p.irradiance =
                        ircache_math::Rgb::new(s.irradiance[0], s.irradiance[1], s.irradiance[2]);
                    p.weight = s.irradiance[3];
                    p.count = s.count;
                    p.min_error = s.min_error;
                }
            }
        }
        Ok(())
    }
}

/// One splat's input as the GPU reads it, packed on the CPU: the records, the 16 × 16 tiles they
/// touch with each tile's records in index order, and those tiles' sums so far (the samples stay
/// on the GPU: [`GpuSplatter::resident_samples`]).
#[derive(Debug)]
pub struct SplatInput {
    params: GpuParams,
    records: Vec<GpuRecord>,
    /// Touched tiles (row-major film tile indices).
    tiles: Vec<u32>,
    /// Per touched tile, `TILE_SAMPLES` sums in the tile's row-major order.
    sums: Vec<GpuSums>,
    /// Compressed rows of `lists` per touched tile.
    start: Vec<u32>,
    lists: Vec<u32>,
}

impl SplatInput {
    /// Packs the level-0 records `ids` of `cache` over `g`'s samples and `buffer`'s sums;
    /// `None` when no record touches the film.
    #[must_use]
    pub fn pack(
        buffer: &SplatBuffer,
        g: &GBuffer,
        cache: &IrradianceCache,
        ids: Range<usize>,
        camera: &Camera,
        filter_reach: f32,
    ) -> Option<SplatInput> {
        let size = (g.width, g.height);
        Self::pack_over(
            Some(buffer),
            size,
            cache,
            ids,
            camera,
            filter_reach,
            1.0,
            false,
        )
    }

    /// [`SplatInput::pack`] for a whole `size` film whose sums stay on the GPU (a frame whose
    /// samples the GPU made: [`crate::frame`]): every tile listed, touched or not, so that passes
    /// at several thresholds share one sums buffer; records serve up to error `threshold`, and
    /// above 1 only samples that none served yet (the lookup's fallback).
    #[must_use]
    pub fn pack_film(
        size: (usize, usize),
        cache: &IrradianceCache,
        ids: Range<usize>,
        camera: &Camera,
        filter_reach: f32,
        threshold: f32,
    ) -> Option<SplatInput> {
        Self::pack_over(
            None,
            size,
            cache,
            ids,
            camera,
            filter_reach,
            threshold,
            true,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn pack_over(
        buffer: Option<&SplatBuffer>,
        (w, h): (usize, usize),
        cache: &IrradianceCache,
        ids: Range<usize>,
        camera: &Camera,
        filter_reach: f32,
        threshold: f32,
        every_tile: bool,
    ) -> Option<SplatInput> {
        let store = cache.levels.first()?;
        let (tiles_x, tiles_y) = (w.div_ceil(TILE), h.div_ceil(TILE));
        let rects = record_rects_at(cache, ids.clone(), camera, (w, h), filter_reach, threshold);
        // Tile lists in index order (compressed rows).
        let tiles_of = |r: [usize; 4]| {
            (r[1] / TILE..r[3].div_ceil(TILE)).flat_map(move |ty| {
                (r[0] / TILE..r[2].div_ceil(TILE)).map(move |tx| ty * tiles_x + tx)
            })
        };
        let mut per_tile = vec![0u32; tiles_x * tiles_y];
        for &r in rects.iter().flatten() {
            for t in tiles_of(r) {
                per_tile[t] += 1;
            }
        }
        // Touched tiles, compacted; each one's slot in `start`.
        let tiles: Vec<u32> = (0..per_tile.len() as u32)
            .filter(|&t| every_tile || per_tile[t as usize] > 0)
            .collect();
        if per_tile.iter().all(|&c| c == 0) {
            return None;
        }
        let mut slot = vec![u32::MAX; per_tile.len()];
        let mut start = Vec::with_capacity(tiles.len() + 1);
        start.push(0u32);
        for (k, &t) in tiles.iter().enumerate() {
            slot[t as usize] = k as u32;
            start.push(start[k] + per_tile[t as usize]);
        }
        let mut fill = start.clone();
        let mut lists = vec![0u32; start[tiles.len()] as usize];
        for (k, r) in rects.iter().enumerate() {
            if let Some(r) = *r {
                for t in tiles_of(r) {
                    let c = slot[t] as usize;
                    lists[fill[c] as usize] = k as u32;
                    fill[c] += 1;
                }
            }
        }
        let v = |v: ircache_math::Vec3, w: f32| [v.x, v.y, v.z, w];
        let records: Vec<GpuRecord> = store.records()[ids]
            .iter()
            .map(|r| GpuRecord {
                p_r: v(r.p, r.r),
                n: v(r.n, 0.0),
                e: [r.e.r, r.e.g, r.e.b, 0.0],
                gt: r.grad_t.map(|g| v(g, 0.0)),
                gr: r.grad_r.map(|g| v(g, 0.0)),
            })
            .collect();
        let mut sums = vec![GpuSums::zeroed(); tiles.len() * TILE_SAMPLES];
        let tile_sums = sums.par_chunks_exact_mut(TILE_SAMPLES);
        tiles
            .par_iter()
            .zip(tile_sums)
            .for_each(|(&tile, tile_sums)| {
                let (x0, y0) = (
                    tile as usize % tiles_x * TILE,
                    tile as usize / tiles_x * TILE,
                );
                for (k, s) in tile_sums.iter_mut().enumerate() {
                    let (x, y) = (x0 + k % TILE, y0 + k / TILE);
                    *s = match buffer {
                        Some(b) if x < w && y < h => {
                            let p = &b.pixels[y * w + x];
                            GpuSums {
                                irradiance: [
                                    p.irradiance.r,
                                    p.irradiance.g,
                                    p.irradiance.b,
                                    p.weight,
                                ],
                                count: p.count,
                                min_error: p.min_error,
                                pad: [0; 2],
                            }
                        }
                        _ => GpuSums {
                            min_error: f32::INFINITY,
                            ..GpuSums::zeroed()
                        },
                    };
                }
            });
        let (metric, accuracy) = store.metric();
        let params = GpuParams {
            width: w as u32,
            height: h as u32,
            tiles_x: tiles_x as u32,
            metric: match metric {
                ErrorMetric::Ward => 0,
                ErrorMetric::Tabellion => 1,
                ErrorMetric::Hessian => 2,
            },
            gradients: match cache.params.gradients {
                GradientMode::None => 0,
                GradientMode::Rotation => 1,
                GradientMode::Full => 2,
            },
            accuracy,
            tile_count: tiles.len() as u32,
            threshold,
        };
        Some(SplatInput {
            params,
            records,
            tiles,
            sums,
            start,
            lists,
        })
    }

    /// Bytes uploaded: records, sums and tile lists (the samples apart).
    #[must_use]
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(self.records.as_slice())
            + std::mem::size_of_val(self.sums.as_slice())
            + 4 * (self.tiles.len() + self.start.len() + self.lists.len())
    }

    /// Tiles touched.
    #[must_use]
    pub fn tile_count(&self) -> usize {
        self.tiles.len()
    }

    /// Per film tile (row-major), its place among the touched tiles; `u32::MAX` where untouched.
    #[must_use]
    pub fn tile_slots(&self) -> Vec<u32> {
        let (w, h) = (self.params.width as usize, self.params.height as usize);
        let mut slots = vec![u32::MAX; w.div_ceil(TILE) * h.div_ceil(TILE)];
        for (k, &t) in self.tiles.iter().enumerate() {
            slots[t as usize] = k as u32;
        }
        slots
    }

    /// Record entries in the tile lists (a record once per tile its rectangle touches).
    #[must_use]
    pub fn entries(&self) -> usize {
        self.lists.len()
    }
}

/// An uploaded splat: what [`GpuSplatter::dispatch`] runs and [`GpuSplatter::read`] reads.
#[derive(Debug)]
pub struct SplatJob {
    bind: wgpu::BindGroup,
    pub(crate) sums: wgpu::Buffer,
    /// Workgroups dispatched along x and y.
    groups: (u32, u32),
    /// The touched tiles, whose sums come back.
    tiles: Vec<u32>,
    /// Film size.
    size: (usize, usize),
}

impl Splatter for GpuSplatter {
    fn splat(
        &self,
        buffer: &mut SplatBuffer,
        g: &GBuffer,
        cache: &IrradianceCache,
        ids: Range<usize>,
        camera: &Camera,
        filter_reach: f32,
    ) {
        // `splat_on_gpu` writes the buffer only once the GPU's sums are back and checked: a
        // failure leaves it as it was.
        match self.splat_on_gpu(buffer, g, cache, ids.clone(), camera, filter_reach) {
            Ok(()) => {
                self.gpu_calls.fetch_add(1, Ordering::Relaxed);
                // The radiance records' glossy sums on the CPU.
                let radiance = cache.levels.first().is_some_and(|s| {
                    s.records()[ids.clone()]
                        .iter()
                        .any(|r| r.radiance != NO_RADIANCE)
                });
                if radiance {
                    self.glossy_on_cpu.fetch_add(1, Ordering::Relaxed);
                    splat_parts(buffer, g, cache, ids, camera, filter_reach, Sums::Glossy);
                }
            }
            Err(e) => {
                self.failures.fetch_add(1, Ordering::Relaxed);
                if let Ok(mut first) = self.first_failure.lock() {
                    first.get_or_insert_with(|| e.to_string());
                }
                splat(buffer, g, cache, ids, camera, filter_reach);
            }
        }
    }
}
