//! A whole frame on the GPU (001 §4.5, the thesis's pipeline; NOTES-001 §C.1), the passes of
//! `shaders/frame.wgsl` around [`crate::splat`]: the camera's view rasterised
//! ([`crate::visibility`]), the G-buffer made from it on the GPU (each pixel centre's hit found
//! on its rasterised triangle), the cache's records splatted over it, and each pixel composed
//! from the splatted indirect irradiance and the direct light through a shadow map.
//!
//! For what a rasteriser serves without ray tracing: Lambertian surfaces of constant albedo
//! (no textures, no normal or bump maps, triangle meshes) under one directional light, as
//! `sponza-sun`; [`GpuFrame::new`] names what else a scene holds. The cache must be warm:
//! records serve a sample up to error 1, else 2, else 4, as the `ic` pixel pass looks them up
//! ([`LOOKUP_THRESHOLDS`]); samples none serves stay without indirect light and are counted
//! ([`FrameImage::misses`]; the CPU gathers a record there).

use crate::splat::{GpuSplatter, SplatInput, SplatJob};
use crate::visibility::{
    camera_clip_shifted, column_major, PlaneVisibility, DEPTH, FORMAT, SPHERE,
};
use crate::{Gpu, GpuError};
use bytemuck::{Pod, Zeroable};
use ircache_math::{Frame, Rgb, Vec3};
use ircache_render::camera::Camera;
use ircache_render::irradiance_cache::build::is_record_site;
use ircache_render::irradiance_cache::IrradianceCache;
use ircache_render::scene::{Scene, ShapeGeometry};
use std::sync::Arc;

/// A triangle as `frame.wgsl` reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuTriangle {
    p: [[f32; 4]; 3],
    n: [[f32; 4]; 3],
}

/// A shape's albedos and record sites, front and back (`Shape`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuShape {
    front: [f32; 4],
    back: [f32; 4],
}

/// The camera (`Camera`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuCamera {
    to_world: [[f32; 4]; 4],
    origin: [f32; 4],
    tan_half: [f32; 4],
    size: [u32; 4],
}

/// The directional light and its shadow map (`Light`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuLight {
    to_clip: [[f32; 4]; 4],
    to_light: [f32; 4],
    irradiance: [f32; 4],
    bias: [f32; 4],
}

/// The scene on the GPU for whole frames: its triangles, shapes, light and shadow map.
#[derive(Debug)]
pub struct GpuFrame {
    pub(crate) gpu: Arc<Gpu>,
    pub(crate) visibility: PlaneVisibility,
    splatter: Arc<GpuSplatter>,
    gbuffer: wgpu::ComputePipeline,
    compose: wgpu::ComputePipeline,
    /// Records from rasterised planes ([`crate::records`]).
    pub(crate) records: wgpu::ComputePipeline,
    pub(crate) triangles: wgpu::Buffer,
    pub(crate) shapes: wgpu::Buffer,
    pub(crate) light: wgpu::Buffer,
    pub(crate) shadow: wgpu::TextureView,
}

/// One frame's resources: its targets, the records packed and uploaded, the bind groups.
#[derive(Debug)]
pub struct FrameJob {
    size: (u32, u32),
    camera: Camera,
    camera_data: GpuCamera,
    camera_buffer: wgpu::Buffer,
    view_buffer: wgpu::Buffer,
    view: wgpu::BindGroup,
    ids: wgpu::TextureView,
    depth: wgpu::TextureView,
    /// The splat at each of [`LOOKUP_THRESHOLDS`], into one sums buffer.
    splat: Vec<SplatJob>,
    sums_bytes: u64,
    gbuffer: wgpu::BindGroup,
    compose: wgpu::BindGroup,
    image: wgpu::Buffer,
    misses: wgpu::Buffer,
    samples: wgpu::Buffer,
}

/// A composed frame read back.
#[derive(Clone, Debug)]
pub struct FrameImage {
    /// Radiance per pixel, row-major from the top.
    pub pixels: Vec<Rgb>,
    /// Record sites no record served (no indirect light there), summed over the layers.
    pub misses: u32,
}

/// How two images of one frame agree ([`FrameImage::agreement`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agreement {
    /// The sums of the two images' luminances.
    pub luminance: (f64, f64),
    /// Pixels whose channels all agree within 1e-3 of the larger image's largest channel there.
    pub within: usize,
}

impl FrameImage {
    /// How this image agrees with `other`, pixel by pixel.
    #[must_use]
    pub fn agreement(&self, other: &FrameImage) -> Agreement {
        let luminance = |p: &[Rgb]| p.iter().map(|c| f64::from(c.luminance())).sum::<f64>();
        let within = self
            .pixels
            .iter()
            .zip(&other.pixels)
            .filter(|(x, y)| {
                let d = **x - **y;
                d.r.abs().max(d.g.abs()).max(d.b.abs())
                    <= 1e-3 * x.max_channel().max(y.max_channel()).max(1e-6)
            })
            .count();
        Agreement {
            luminance: (luminance(&self.pixels), luminance(&other.pixels)),
            within,
        }
    }
}

/// The whole of `texture`.
pub(crate) fn view_of(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

/// The error thresholds at which records serve a sample, each where the ones before served
/// none: the `ic` pixel pass's lookup (`integrators::ic`).
pub const LOOKUP_THRESHOLDS: [f32; 3] = [1.0, 2.0, 4.0];

/// Layer `k`'s offset from the pixel centres, in pixels, each coordinate in [−½, ½): the R₂
/// sequence (the plastic number's powers), well spread at every count of layers; layer 0 at
/// the centre.
#[must_use]
pub fn layer_jitter(k: u32) -> [f32; 2] {
    // 1/g and 1/g² for g the plastic number, the root of x³ = x + 1.
    const A: [f64; 2] = [0.754_877_666_246_692_7, 0.569_840_290_998_053_2];
    A.map(|a| ((0.5 + f64::from(k) * a).fract() - 0.5) as f32)
}

/// Shadow map size in texels (each side).
pub const SHADOW_MAP: u32 = 4096;

impl GpuFrame {
    /// Whether the pipeline serves `scene`: one directional light and nothing else that emits,
    /// triangle meshes of Lambertian materials of constant albedo.
    ///
    /// # Errors
    /// [`GpuError::Unsupported`] naming what the scene holds that this pipeline does not serve.
    pub fn serves(scene: &Scene) -> Result<(), GpuError> {
        let unsupported = |what: String| Err(GpuError::Unsupported(what));
        if !scene.camera.is_pinhole() {
            return unsupported(format!(
                "the GPU frame projects through a pinhole, not the scene's {} camera",
                scene.camera.projection.name()
            ));
        }
        if scene.lights.only_directional().is_none() {
            let n = scene.lights.len();
            return unsupported(format!(
                "the GPU frame serves one directional light and no other emitter, not the scene's \
                 {n} emitter{}",
                if n == 1 { "" } else { "s" }
            ));
        }
        for (k, shape) in scene.shapes.iter().enumerate() {
            let material = &scene.materials[shape.material];
            let name = shape.name.as_deref().unwrap_or("(unnamed)");
            if matches!(shape.geometry, ShapeGeometry::Sphere { .. }) {
                return unsupported(format!("shape {k} ({name}) is a sphere"));
            }
            let bsdf = material.at(ircache_math::Vec2::ZERO);
            if material.is_textured()
                || material.is_masked()
                || !bsdf.is_diffuse_only()
                || shape.area_light.is_some()
            {
                return unsupported(format!(
                    "shape {k} ({name}) is not a Lambertian surface of constant albedo"
                ));
            }
        }
        Ok(())
    }

    /// The scene's triangles, materials and light on `gpu`, its shadow map (of `shadow_map`²
    /// texels) rasterised once; `splatter` splats the records.
    ///
    /// # Errors
    /// [`GpuError::Unsupported`] naming what the scene holds that this pipeline does not serve.
    pub fn new(
        gpu: Arc<Gpu>,
        splatter: Arc<GpuSplatter>,
        scene: &Scene,
        cache: &IrradianceCache,
        shadow_map: u32,
    ) -> Result<GpuFrame, GpuError> {
        Self::serves(scene)?;
        let Some((to_light, irradiance)) = scene.lights.only_directional() else {
            return Err(GpuError::Unsupported("no directional light".into()));
        };
        let mut shapes = Vec::with_capacity(scene.shapes.len());
        for (k, shape) in scene.shapes.iter().enumerate() {
            let bsdf = scene.materials[shape.material].at(ircache_math::Vec2::ZERO);
            let side = |up: f32| {
                let wo = Vec3::new(0.0, 0.0, up);
                let a = bsdf.lambertian_albedo(wo);
                let site = !cache.is_excluded(k as u32) && is_record_site(&bsdf, wo, false);
                [a.r, a.g, a.b, if site { 1.0 } else { 0.0 }]
            };
            shapes.push(GpuShape {
                front: side(1.0),
                back: side(-1.0),
            });
        }
        let visibility = PlaneVisibility::new(gpu.clone(), scene);
        let triangles: Vec<GpuTriangle> = visibility
            .triangles
            .iter()
            .map(|&(shape, prim)| {
                let ShapeGeometry::Mesh(m) = &scene.shapes[shape as usize].geometry else {
                    unreachable!("spheres were refused above ({SPHERE})")
                };
                let idx = m.indices[prim as usize].map(|i| i as usize);
                let v = |v: Vec3, w: f32| [v.x, v.y, v.z, w];
                let flat = scene.shapes[shape as usize].flat;
                let normals = m.normals.as_ref().filter(|_| !flat);
                GpuTriangle {
                    p: [0, 1, 2].map(|k| {
                        let w = if k == 0 { f32::from_bits(shape) } else { 0.0 };
                        v(m.positions[idx[k]], w)
                    }),
                    n: [0, 1, 2].map(|k| match normals {
                        Some(n) => v(n[idx[k]], 1.0),
                        None => [0.0; 4],
                    }),
                }
            })
            .collect();
        let device = &gpu.device;
        let storage = wgpu::BufferUsages::STORAGE;
        let triangles = gpu.buffer("triangles", bytemuck::cast_slice(&triangles), storage);
        let shapes = gpu.buffer("shapes", bytemuck::cast_slice(&shapes), storage);
        // The shadow map: an orthographic view along the light over the scene's bounding
        // sphere, depth (along the light's travel) from 0 to 1 across it.
        let (centre, radius) = scene.lights.scene_bounds();
        let radius = radius.max(f32::MIN_POSITIVE);
        let frame = Frame::from_z(-to_light);
        let row = |a: Vec3, scale: f32, offset: f32| {
            [
                a.x * scale,
                a.y * scale,
                a.z * scale,
                -a.dot(centre) * scale + offset,
            ]
        };
        let to_clip = column_major([
            row(frame.s, 1.0 / radius, 0.0),
            row(frame.t, 1.0 / radius, 0.0),
            row(frame.n, 0.5 / radius, 0.5),
            [0.0, 0.0, 0.0, 1.0],
        ]);
        let light = GpuLight {
            to_clip,
            to_light: [to_light.x, to_light.y, to_light.z, 0.0],
            irradiance: [irradiance.r, irradiance.g, irradiance.b, 0.0],
            bias: [1.0 / shadow_map as f32, shadow_map as f32, 0.0, 0.0],
        };
        let light = gpu.buffer(
            "light",
            bytemuck::bytes_of(&light),
            wgpu::BufferUsages::UNIFORM,
        );
        let map = (shadow_map, shadow_map);
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let shadow_ids = view_of(&gpu.texture("shadow map ids", map, FORMAT, attachment));
        let shadow = view_of(&gpu.texture(
            "shadow map",
            map,
            DEPTH,
            attachment | wgpu::TextureUsages::TEXTURE_BINDING,
        ));
        let shadow_view = visibility.views(&[to_clip]);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        visibility.draw_atlas(
            &mut encoder,
            &shadow_view,
            1,
            map,
            1,
            &shadow_ids,
            &shadow,
            true,
        );
        gpu.queue.submit([encoder.finish()]);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("frame.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                concat!(
                    include_str!("shaders/surface.wgsl"),
                    include_str!("shaders/frame.wgsl")
                )
                .into(),
            ),
        });
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                cache: None,
            })
        };
        let gbuffer = pipeline("gbuffer");
        let compose = pipeline("compose");
        let records_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("records.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                concat!(
                    include_str!("shaders/surface.wgsl"),
                    include_str!("shaders/records.wgsl")
                )
                .into(),
            ),
        });
        let records = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("records"),
            layout: None,
            module: &records_module,
            entry_point: Some("record"),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            cache: None,
        });
        gpu.check()?;
        Ok(GpuFrame {
            gpu,
            visibility,
            splatter,
            gbuffer,
            compose,
            records,
            triangles,
            shapes,
            light,
            shadow,
        })
    }

    /// A frame of `cache` (warm: its level-0 records, as they are) through `camera` at
    /// `width × height`: the targets made, the records packed and uploaded.
    ///
    /// # Errors
    /// When the cache has no record on the film, or the GPU fails.
    pub fn prepare(
        &self,
        cache: &IrradianceCache,
        camera: &Camera,
        width: u32,
        height: u32,
        filter_reach: f32,
    ) -> Result<FrameJob, GpuError> {
        let device = &self.gpu.device;
        let (w, h) = (width as usize, height as usize);
        let n = cache.levels.first().map_or(0, |s| s.len());
        // The lookup's thresholds (the `ic` pixel pass's fallback): 1, then 2 and 4 where
        // none served.
        let inputs: Vec<SplatInput> = LOOKUP_THRESHOLDS
            .iter()
            .filter_map(|&t| SplatInput::pack_film((w, h), cache, 0..n, camera, filter_reach, t))
            .collect();
        if inputs.len() < LOOKUP_THRESHOLDS.len() {
            return Err(GpuError::Unsupported("no record reaches the film".into()));
        }
        let slots = inputs[0].tile_slots();
        let storage = wgpu::BufferUsages::STORAGE;
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let samples = buffer(
            "frame samples",
            48 * (w * h) as u64,
            storage | wgpu::BufferUsages::COPY_SRC,
        );
        let hits = buffer("frame hits", 4 * (w * h) as u64, storage);
        let image = buffer(
            "frame image",
            16 * (w * h) as u64,
            storage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        );
        let misses = buffer(
            "frame misses",
            4,
            storage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        );
        let slots = self
            .gpu
            .buffer("tile slots", bytemuck::cast_slice(&slots), storage);
        // The passes after the first add into its sums.
        let mut splat = vec![self.splatter.upload(&inputs[0], &samples)];
        for input in &inputs[1..] {
            let job = self
                .splatter
                .upload_over(input, &samples, Some(&splat[0].sums));
            splat.push(job);
        }
        let cam = GpuCamera {
            to_world: camera.to_world.to_cols_array_2d(),
            origin: [camera.origin.x, camera.origin.y, camera.origin.z, 1.0],
            tan_half: [camera.tan_half_x, camera.tan_half_y, 0.0, 0.0],
            size: [width, height, width.div_ceil(16), 0],
        };
        let camera_buffer = self.gpu.buffer(
            "camera",
            bytemuck::bytes_of(&cam),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let ids = view_of(&self.gpu.texture(
            "camera view",
            (width, height),
            FORMAT,
            attachment | wgpu::TextureUsages::TEXTURE_BINDING,
        ));
        let depth = view_of(
            &self
                .gpu
                .texture("camera depth", (width, height), DEPTH, attachment),
        );
        let bind = |pipeline: &wgpu::ComputePipeline, entries: &[(u32, wgpu::BindingResource)]| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("frame"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries
                    .iter()
                    .map(|(binding, resource)| wgpu::BindGroupEntry {
                        binding: *binding,
                        resource: resource.clone(),
                    })
                    .collect::<Vec<_>>(),
            })
        };
        let gbuffer = bind(
            &self.gbuffer,
            &[
                (0, camera_buffer.as_entire_binding()),
                (1, wgpu::BindingResource::TextureView(&ids)),
                (2, self.triangles.as_entire_binding()),
                (3, self.shapes.as_entire_binding()),
                (4, samples.as_entire_binding()),
                (5, hits.as_entire_binding()),
            ],
        );
        let compose = bind(
            &self.compose,
            &[
                (0, camera_buffer.as_entire_binding()),
                (3, self.shapes.as_entire_binding()),
                (4, samples.as_entire_binding()),
                (5, hits.as_entire_binding()),
                (6, splat[0].sums.as_entire_binding()),
                (7, slots.as_entire_binding()),
                (8, self.light.as_entire_binding()),
                (9, wgpu::BindingResource::TextureView(&self.shadow)),
                (10, image.as_entire_binding()),
                (11, misses.as_entire_binding()),
            ],
        );
        let (view_buffer, view) = self
            .visibility
            .views_buffer(&[camera_clip_shifted(camera, [0.0; 2])]);
        let sums_bytes = splat[0].sums.size();
        self.gpu.check()?;
        Ok(FrameJob {
            size: (width, height),
            camera: camera.clone(),
            camera_data: cam,
            camera_buffer,
            view_buffer,
            view,
            ids,
            depth,
            splat,
            sums_bytes,
            gbuffer,
            compose,
            image,
            misses,
            samples,
        })
    }

    /// Renders the frame through the pixel centres: [`GpuFrame::render_layer`] alone.
    pub fn render(&self, job: &FrameJob) {
        self.render_layer(job, [0.0, 0.0], false);
    }

    /// Renders one layer of the frame through points `jitter` pixels from the pixel centres
    /// (each coordinate in [−½, ½)), added to the layers before when `accumulate`: rasterises
    /// the camera's view shifted by the jitter, makes the G-buffer, clears the sums and splats
    /// the records, composes; one submission. [`GpuFrame::read`] gives the layers' mean, a box
    /// filter's estimate.
    pub fn render_layer(&self, job: &FrameJob, jitter: [f32; 2], accumulate: bool) {
        let (w, h) = (job.size.0 as f32, job.size.1 as f32);
        let queue = &self.gpu.queue;
        let mut camera = job.camera_data;
        camera.tan_half[2] = jitter[0];
        camera.tan_half[3] = jitter[1];
        queue.write_buffer(&job.camera_buffer, 0, bytemuck::bytes_of(&camera));
        // Film x grows with NDC x and film y against NDC y: the point at film (x + ½ + jx) / w
        // moves to pixel x's centre.
        let shift = [-2.0 * jitter[0] / w, 2.0 * jitter[1] / h];
        let view = camera_clip_shifted(&job.camera, shift);
        queue.write_buffer(&job.view_buffer, 0, bytemuck::cast_slice(&[view]));
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        self.visibility.draw_atlas(
            &mut encoder,
            &job.view,
            1,
            job.size,
            1,
            &job.ids,
            &job.depth,
            false,
        );
        let groups = (job.size.0.div_ceil(16), job.size.1.div_ceil(16));
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
            pass.set_pipeline(&self.gbuffer);
            pass.set_bind_group(0, &job.gbuffer, &[]);
            pass.dispatch_workgroups(groups.0, groups.1, 1);
        }
        encoder.clear_buffer(&job.splat[0].sums, 0, Some(job.sums_bytes));
        if !accumulate {
            encoder.clear_buffer(&job.misses, 0, None);
            encoder.clear_buffer(&job.image, 0, None);
        }
        for splat in &job.splat {
            self.splatter.encode(&mut encoder, splat);
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
            pass.set_pipeline(&self.compose);
            pass.set_bind_group(0, &job.compose, &[]);
            pass.dispatch_workgroups(groups.0, groups.1, 1);
        }
        queue.submit([encoder.finish()]);
    }

    /// Waits for the frame.
    ///
    /// # Errors
    /// When the device reports an error.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.splatter.wait()
    }

    /// Reads the splatted sums back into `buffer` (of the frame's size).
    ///
    /// # Errors
    /// When the read-back fails or the device reported an error.
    pub fn read_sums(
        &self,
        job: &FrameJob,
        buffer: &mut ircache_render::splatting::SplatBuffer,
    ) -> Result<(), GpuError> {
        self.splatter.read(&job.splat[0], buffer)
    }

    /// Reads the G-buffer back: per pixel, the position and the normal facing the viewer where
    /// the pixel sees a record site, `None` elsewhere.
    ///
    /// # Errors
    /// When the read-back fails or the device reported an error.
    pub fn read_sites(&self, job: &FrameJob) -> Result<Vec<Option<(Vec3, Vec3)>>, GpuError> {
        let bytes = self.gpu.read_back(&job.samples)?;
        self.gpu.check()?;
        let samples: &[[[f32; 4]; 3]] = bytemuck::cast_slice(&bytes);
        Ok(samples
            .iter()
            .map(|[p, n, _]| {
                (p[3] != 0.0).then(|| (Vec3::new(p[0], p[1], p[2]), Vec3::new(n[0], n[1], n[2])))
            })
            .collect())
    }

    /// Reads the composed frame back.
    ///
    /// # Errors
    /// When the read-back fails or the device reported an error.
    pub fn read(&self, job: &FrameJob) -> Result<FrameImage, GpuError> {
        let bytes = self.gpu.read_back(&job.image)?;
        let misses = self.gpu.read_back(&job.misses)?;
        self.gpu.check()?;
        let texels: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        // Each texel sums its layers, w counting them.
        Ok(FrameImage {
            pixels: texels
                .iter()
                .map(|t| Rgb::new(t[0], t[1], t[2]) / t[3].max(1.0))
                .collect(),
            misses: bytemuck::cast_slice::<u8, u32>(&misses)[0],
        })
    }
}

/// The frame [`GpuFrame`] renders, by ray tracing on the CPU: at each pixel centre moved by
/// each of `jitters` (pixels), the hit by Embree, its indirect irradiance looked up in the cache
/// (the same records and weights the splat sums), its direct light by a shadow ray; the mean
/// over the jitters. The GPU frame's reference.
#[must_use]
pub fn traced_frame(
    scene: &Scene,
    cache: &IrradianceCache,
    camera: &Camera,
    (width, height): (u32, u32),
    jitters: &[[f32; 2]],
) -> FrameImage {
    use rayon::prelude::*;
    let (w, h) = (width as usize, height as usize);
    let Some((to_light, irradiance)) = scene.lights.only_directional() else {
        return FrameImage {
            pixels: vec![Rgb::ZERO; w * h],
            misses: 0,
        };
    };
    let shaded: Vec<(Rgb, u32)> = (0..w * h)
        .into_par_iter()
        .map(|k| {
            jitters.iter().fold((Rgb::ZERO, 0), |(sum, missed), j| {
                let (l, m) =
                    traced_pixel(scene, cache, camera, (w, h), k, *j, to_light, irradiance);
                (sum + l / jitters.len() as f32, missed + u32::from(m))
            })
        })
        .collect();
    FrameImage {
        misses: shaded.iter().map(|s| s.1).sum(),
        pixels: shaded.into_iter().map(|s| s.0).collect(),
    }
}

/// One traced sample of [`traced_frame`]: the radiance and whether no record served the site.
#[allow(clippy::too_many_arguments)]
fn traced_pixel(
    scene: &Scene,
    cache: &IrradianceCache,
    camera: &Camera,
    (w, h): (usize, usize),
    k: usize,
    jitter: [f32; 2],
    to_light: Vec3,
    irradiance: Rgb,
) -> (Rgb, bool) {
    use ircache_render::irradiance_cache::gather::ShadingPoint;
    let mode = cache.params.gradients;
    let film = ircache_math::Vec2::new(
        ((k % w) as f32 + 0.5 + jitter[0]) / w as f32,
        ((k / w) as f32 + 0.5 + jitter[1]) / h as f32,
    );
    let ray = camera.generate_ray(film);
    let Some(it) = scene.intersect(&ray) else {
        return (Rgb::ZERO, false);
    };
    let sp = ShadingPoint::facing(it, -ray.d);
    let bsdf = it.bsdf(
        &scene.materials[scene.shapes[it.shape as usize].material],
        ray.d,
    );
    let wo_local = it.frame.to_local(-ray.d);
    let albedo = bsdf.lambertian_albedo(wo_local);
    let site = !cache.is_excluded(it.shape) && is_record_site(&bsdf, wo_local, false);
    let (mut e, mut missed) = (Rgb::ZERO, false);
    if site {
        let served = cache.levels.first().and_then(|s| {
            LOOKUP_THRESHOLDS
                .iter()
                .find_map(|&t| s.interpolate(sp.it.p, sp.n, sp.n_bump, t, mode))
        });
        match served {
            Some(i) => e = i.e,
            None => missed = true,
        }
    }
    let cosine = sp.n.dot(to_light);
    if cosine > 0.0
        && !scene
            .accel
            .occluded(&scene.shadow_ray(&it, to_light, f32::INFINITY))
    {
        e += irradiance * cosine;
    }
    (albedo * e / std::f32::consts::PI, missed)
}
