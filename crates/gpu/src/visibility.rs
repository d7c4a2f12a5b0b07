//! Visibility by rasterisation (001 §4.4.2, the thesis's record computation; NOTES-001 §C.4),
//! the pass of `shaders/visibility.wgsl`: the scene's triangles through a view, each pixel
//! keeping the nearest triangle. A record's plane
//! ([`ircache_render::irradiance_cache::plane::HemispherePlane`]) is filled this way instead of
//! by one ray per pixel: [`PlaneVisibility::record_plane`] rasterises the plane above a record
//! and shades each pixel's surface on the CPU with the gather's own path continuation
//! ([`SceneRadiance::incident_at`]), the hit found on the rasterised triangle. The thesis shades
//! on the GPU too (direct light by shadow maps): not here yet. Analytic spheres are rasterised
//! as a tessellated shell slightly larger than the sphere (so it covers every pixel the sphere
//! does); a pixel that sees a shell is traced by Embree, which finds the sphere or what lies
//! past its silhouette.

use crate::Gpu;
use bytemuck::{Pod, Zeroable};
use ircache_math::{Frame, Vec3};
use ircache_render::camera::Camera;
use ircache_render::irradiance_cache::gather::{Gatherer, SceneRadiance, ShadingPoint, WorkState};
use ircache_render::irradiance_cache::plane::{HemispherePlane, PlanePixels};
use ircache_render::scene::{Scene, ShapeGeometry};
use std::sync::Arc;

/// A vertex as the shader reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuVertex {
    position: [f32; 3],
    triangle: u32,
}

/// The scene's triangles on the GPU and the pipeline that rasterises them.
#[derive(Debug)]
pub struct PlaneVisibility {
    gpu: Arc<Gpu>,
    pub(crate) pipeline: wgpu::RenderPipeline,
    pub(crate) layout: wgpu::BindGroupLayout,
    pub(crate) vertices: wgpu::Buffer,
    pub(crate) vertex_count: u32,
    /// Per triangle index: (shape, primitive); primitive [`SPHERE`] for a sphere's shell.
    pub(crate) triangles: Vec<(u32, u32)>,
    /// Spheres rasterised as shells.
    pub spheres: usize,
    /// Near clipping distance (a fraction of the scene's size: scale-free).
    near: f32,
    far: f32,
}

/// What each pixel of a view sees: (shape, primitive) or nothing.
pub type Seen = Vec<Option<(u32, u32)>>;

/// The primitive of a sphere's shell triangles.
pub const SPHERE: u32 = u32::MAX;

/// Rings and segments of a sphere's shell.
const SHELL_RINGS: usize = 12;
const SHELL_SEGMENTS: usize = 24;

/// Triangles of a latitude–longitude shell around a sphere, its vertices at 1/(cos(π/rings)
/// cos(π/segments)) times the radius, so that every facet lies outside the sphere: the shell
/// covers every direction the sphere does.
fn sphere_shell(center: Vec3, radius: f32) -> Vec<[Vec3; 3]> {
    use std::f32::consts::PI;
    let grow = 1.0 / ((PI / SHELL_RINGS as f32).cos() * (PI / SHELL_SEGMENTS as f32).cos());
    let r = radius * grow;
    let vertex = |ring: usize, segment: usize| {
        let theta = PI * ring as f32 / SHELL_RINGS as f32;
        let phi = 2.0 * PI * segment as f32 / SHELL_SEGMENTS as f32;
        center
            + r * Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            )
    };
    let mut out = Vec::with_capacity(2 * SHELL_RINGS * SHELL_SEGMENTS);
    for ring in 0..SHELL_RINGS {
        for segment in 0..SHELL_SEGMENTS {
            let (a, b) = (vertex(ring, segment), vertex(ring, segment + 1));
            let (c, d) = (vertex(ring + 1, segment), vertex(ring + 1, segment + 1));
            out.push([a, c, d]);
            out.push([a, d, b]);
        }
    }
    out
}

pub(crate) const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
pub(crate) const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

impl PlaneVisibility {
    /// Uploads `scene`'s triangles.
    #[must_use]
    pub fn new(gpu: Arc<Gpu>, scene: &Scene) -> PlaneVisibility {
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        let mut spheres = 0;
        let mut push = |triangles: &mut Vec<(u32, u32)>, id: (u32, u32), tri: [Vec3; 3]| {
            let triangle = triangles.len() as u32;
            triangles.push(id);
            for p in tri {
                vertices.push(GpuVertex {
                    position: [p.x, p.y, p.z],
                    triangle,
                });
            }
        };
        for (shape_id, shape) in scene.shapes.iter().enumerate() {
            match &shape.geometry {
                ShapeGeometry::Mesh(mesh) => {
                    for (prim, tri) in mesh.indices.iter().enumerate() {
                        let p = tri.map(|v| mesh.positions[v as usize]);
                        push(&mut triangles, (shape_id as u32, prim as u32), p);
                    }
                }
                ShapeGeometry::Sphere { center, radius, .. } => {
                    spheres += 1;
                    for tri in sphere_shell(*center, *radius) {
                        push(&mut triangles, (shape_id as u32, SPHERE), tri);
                    }
                }
            }
        }
        let device = &gpu.device;
        let vertex_buffer = gpu.buffer(
            "scene triangles",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("visibility.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/visibility.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("visibility"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("visibility"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("visibility"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vertex"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                buffers: &[wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<GpuVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32],
                }],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fragment"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let (_, radius) = scene.lights.scene_bounds();
        let radius = radius.max(f32::MIN_POSITIVE);
        PlaneVisibility {
            gpu: gpu.clone(),
            pipeline,
            layout,
            vertices: vertex_buffer,
            vertex_count: vertices.len() as u32,
            triangles,
            spheres,
            near: 1e-5 * radius,
            far: 4.0 * radius,
        }
    }

    /// Triangles rasterised (spheres' shells included).
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The triangle each pixel of `plane` above `sp` sees: (shape, primitive) or `None`, in the
    /// plane's pixel order (row j from y = −s, column i from x = −s).
    ///
    /// # Errors
    /// When the GPU fails.
    pub fn triangles(
        &self,
        plane: &HemispherePlane,
        sp: &ShadingPoint,
    ) -> Result<Seen, crate::GpuError> {
        Ok(self
            .planes(plane, std::slice::from_ref(sp))?
            .pop()
            .unwrap_or_default())
    }

    /// [`PlaneVisibility::triangles`] for many points at once: their planes are rasterised side
    /// by side into one atlas, a viewport each, in as few passes as the device's largest
    /// texture allows (the thesis's record computation at GPU rates, one submission for
    /// thousands of records).
    ///
    /// # Errors
    /// When the GPU fails.
    pub fn planes(
        &self,
        plane: &HemispherePlane,
        points: &[ShadingPoint],
    ) -> Result<Vec<Seen>, crate::GpuError> {
        let n = plane.pixels as u32;
        let views: Vec<[[f32; 4]; 4]> =
            points.iter().map(|sp| self.plane_view(plane, sp)).collect();
        let texels = self.rasterise(&views, n, n)?;
        Ok(texels
            .into_iter()
            .map(|ids| {
                let n = n as usize;
                let mut result = vec![None; n * n];
                for r in 0..n {
                    // Texture row r is NDC y = 1 − 2(r + ½)/N: plane row N − 1 − r.
                    let j = n - 1 - r;
                    for (i, &id) in ids[r * n..][..n].iter().enumerate() {
                        result[j * n + i] = self.triangle_of(id);
                    }
                }
                result
            })
            .collect())
    }

    /// The triangle each pixel of `camera`'s `width × height` film sees through its centre, in
    /// film order (row 0 at the top): the geometry of a G-buffer by rasterisation (001 §4.5).
    ///
    /// # Errors
    /// When the GPU fails, or the camera is not a pinhole (rasterisation projects through one).
    pub fn camera_view(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Seen, crate::GpuError> {
        if !camera.is_pinhole() {
            return Err(crate::GpuError::Unsupported(format!(
                "rasterising the camera's view needs a pinhole, not a {} camera",
                camera.projection.name()
            )));
        }
        let view = camera_clip(camera);
        let ids = self.rasterise(&[view], width, height)?;
        Ok(ids
            .first()
            .map(|ids| ids.iter().map(|&id| self.triangle_of(id)).collect())
            .unwrap_or_default())
    }

    /// A bind group of views (column-major world-to-clip matrices; instance k draws view k).
    pub(crate) fn views(&self, matrices: &[[[f32; 4]; 4]]) -> wgpu::BindGroup {
        self.views_buffer(matrices).1
    }

    /// [`PlaneVisibility::views`] and its buffer, which can be written again.
    pub(crate) fn views_buffer(
        &self,
        matrices: &[[[f32; 4]; 4]],
    ) -> (wgpu::Buffer, wgpu::BindGroup) {
        let buffer = self.gpu.buffer(
            "views",
            bytemuck::cast_slice(matrices),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let group = self
            .gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("visibility"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            });
        (buffer, group)
    }

    /// Atlas columns and rows of `width × height` views the device's largest texture holds (64
    /// at most each way).
    ///
    /// # Errors
    /// When one view exceeds the device's largest texture.
    pub(crate) fn atlas_grid(
        &self,
        width: u32,
        height: u32,
    ) -> Result<(u32, u32), crate::GpuError> {
        let largest = self.gpu.device.limits().max_texture_dimension_2d;
        if width > largest || height > largest {
            return Err(crate::GpuError::Device(format!(
                "a {width} × {height} view exceeds the device's largest texture ({largest})"
            )));
        }
        Ok((
            (largest / width).clamp(1, 64),
            (largest / height).clamp(1, 64),
        ))
    }

    /// Records a pass drawing views 0..`count` of `views` side by side into an atlas of
    /// `columns` tiles of `tile` pixels a row (`ids`, `depth`): one viewport and one instanced
    /// draw per view. The depth is kept when `store_depth` (a shadow map: one view, one tile).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn draw_atlas(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        views: &wgpu::BindGroup,
        count: u32,
        (width, height): (u32, u32),
        columns: u32,
        ids: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        store_depth: bool,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("visibility"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: ids,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: if store_depth {
                        wgpu::StoreOp::Store
                    } else {
                        wgpu::StoreOp::Discard
                    },
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, views, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        for k in 0..count {
            let (x, y) = ((k % columns) * width, (k / columns) * height);
            // The scissor as well as the viewport: no fragment of one view in another's tile,
            // whatever the device's guard band.
            pass.set_viewport(x as f32, y as f32, width as f32, height as f32, 0.0, 1.0);
            pass.set_scissor_rect(x, y, width, height);
            // The instance index selects the view.
            pass.draw(0..self.vertex_count, k..k + 1);
        }
    }

    /// A rasterised id (triangle + 1; 0 for nothing) as (shape, primitive).
    fn triangle_of(&self, id: u32) -> Option<(u32, u32)> {
        id.checked_sub(1)
            .and_then(|t| self.triangles.get(t as usize).copied())
    }

    /// The world-to-clip matrix (column-major) of the plane above `sp`.
    pub(crate) fn plane_view(&self, plane: &HemispherePlane, sp: &ShadingPoint) -> [[f32; 4]; 4] {
        let frame = Frame::from_z(sp.n);
        let (s, near, far) = (plane.half_size as f32, self.near, self.far);
        // Camera space (frame.s, frame.t, n) from the record's position; x and y over s·z
        // fill the clip square; depth (z − near)·far / ((far − near)·z).
        let p = sp.it.p;
        let row = |a: Vec3| [a.x, a.y, a.z, -a.dot(p)];
        let (rx, ry, rz) = (row(frame.s), row(frame.t), row(frame.n));
        let a = far / (far - near);
        let mut to_clip = [rx.map(|v| v / s), ry.map(|v| v / s), rz.map(|v| v * a), rz];
        to_clip[2][3] -= near * a;
        column_major(to_clip)
    }

    /// Rasterises the scene through each view into a `width × height` tile of an atlas (one
    /// viewport and one instanced draw per view, as many views per pass as the device's largest
    /// texture holds) and returns each tile's ids, row 0 at the top.
    fn rasterise(
        &self,
        views: &[[[f32; 4]; 4]],
        width: u32,
        height: u32,
    ) -> Result<Vec<Vec<u32>>, crate::GpuError> {
        let device = &self.gpu.device;
        let (columns, rows) = self.atlas_grid(width, height)?;
        let mut out = Vec::with_capacity(views.len());
        for batch in views.chunks((columns * rows) as usize) {
            let count = batch.len() as u32;
            let (used_columns, used_rows) = (columns.min(count), count.div_ceil(columns));
            let (atlas_w, atlas_h) = (used_columns * width, used_rows * height);
            let bind = self.views(batch);
            let size = wgpu::Extent3d {
                width: atlas_w,
                height: atlas_h,
                depth_or_array_layers: 1,
            };
            let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
            let ids = self.gpu.texture(
                "visibility",
                (atlas_w, atlas_h),
                FORMAT,
                attachment | wgpu::TextureUsages::COPY_SRC,
            );
            let depth = self
                .gpu
                .texture("visibility", (atlas_w, atlas_h), DEPTH, attachment);
            let ids_view = ids.create_view(&wgpu::TextureViewDescriptor::default());
            let depth_view = depth.create_view(&wgpu::TextureViewDescriptor::default());
            let row_bytes = (4 * atlas_w).div_ceil(256) * 256;
            let read = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("visibility out"),
                size: u64::from(row_bytes * atlas_h),
                usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut encoder =
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
            self.draw_atlas(
                &mut encoder,
                &bind,
                count,
                (width, height),
                columns,
                &ids_view,
                &depth_view,
                false,
            );
            encoder.copy_texture_to_buffer(
                ids.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &read,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row_bytes),
                        rows_per_image: Some(atlas_h),
                    },
                },
                size,
            );
            self.gpu.queue.submit([encoder.finish()]);
            let bytes = self.gpu.read_back(&read)?;
            self.gpu.check()?;
            for k in 0..count {
                let (x, y) = ((k % columns) * width, (k / columns) * height);
                let mut tile = Vec::with_capacity((width * height) as usize);
                for r in 0..height {
                    let at = ((y + r) * row_bytes + 4 * x) as usize;
                    tile.extend_from_slice(bytemuck::cast_slice::<u8, u32>(
                        &bytes[at..at + 4 * width as usize],
                    ));
                }
                out.push(tile);
            }
        }
        Ok(out)
    }

    /// The radiance through each pixel's centre of `plane` above `sp` and the distance to what
    /// it sees, as [`HemispherePlane::sample`] gives them, with each pixel's surface found by rasterising and
    /// its hit on the rasterised triangle (Embree where the pixel ray misses that triangle by
    /// rounding at its edge, and where it sees a sphere's shell; counted in the second value).
    ///
    /// # Errors
    /// When the GPU fails.
    #[allow(clippy::too_many_arguments)]
    pub fn record_plane(
        &self,
        scene: &Scene,
        light: &SceneRadiance,
        g: &Gatherer,
        st: &mut WorkState,
        plane: &HemispherePlane,
        sp: &ShadingPoint,
        level: u32,
        key: u64,
    ) -> Result<(PlanePixels, usize), crate::GpuError> {
        let seen = self.triangles(plane, sp)?;
        let mut fallbacks = 0;
        let out = plane.sample_with(g.seed, sp, level, key, |k, d, key, rng| {
            let ray = scene.spawn_ray(&sp.it, d);
            let hit = match seen[k] {
                Some((_, SPHERE)) => {
                    fallbacks += 1;
                    scene.intersect(&ray)
                }
                Some((shape, prim)) => scene.hit_triangle(&ray, shape, prim).or_else(|| {
                    fallbacks += 1;
                    scene.intersect(&ray)
                }),
                None => None,
            };
            st.counts.gather_rays += 1;
            match hit {
                Some(hit) => {
                    let incident =
                        light.incident_at(g.cache, g.seed, st, &ray, hit, level, key, rng);
                    (incident.radiance, incident.distance)
                }
                None => (g.light.escaped(d), f32::INFINITY),
            }
        });
        Ok((out, fallbacks))
    }
}

/// How many pixels of `plane` above `sp` see in `seen` the triangle Embree's ray through the
/// pixel centre hits: the check of a rasterised plane against ray casting.
#[must_use]
pub fn pixels_seeing_the_rays(
    scene: &Scene,
    plane: &HemispherePlane,
    sp: &ShadingPoint,
    seen: &Seen,
) -> usize {
    let frame = Frame::from_z(sp.n);
    let mut agree = 0;
    for j in 0..plane.pixels {
        for i in 0..plane.pixels {
            let d = frame.from_local(plane.direction(i, j));
            let hit = scene.intersect(&scene.spawn_ray(&sp.it, d));
            agree += usize::from(hit.map(|h| (h.shape, h.prim)) == seen[j * plane.pixels + i]);
        }
    }
    agree
}

/// Rows of a 4 × 4 matrix as WGSL's column-major array.
pub(crate) fn column_major(rows: [[f32; 4]; 4]) -> [[f32; 4]; 4] {
    let mut columns = [[0f32; 4]; 4];
    for (r, row) in rows.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            columns[c][r] = *v;
        }
    }
    columns
}

/// `camera`'s world-to-clip matrix (column-major): clip x = −x/tan½x and y = y/tan½y over
/// w = z in camera space (the film's x runs along camera −x, its y along −y, NDC y up), depth
/// (z − near)·far / ((far − near)·z), so that each pixel centre sees what
/// [`Camera::generate_ray`] sees through it.
pub(crate) fn camera_clip(camera: &Camera) -> [[f32; 4]; 4] {
    camera_clip_shifted(camera, [0.0, 0.0])
}

/// [`camera_clip`] with the image shifted by `ndc` (in normalised device coordinates, y up):
/// what lies at NDC (u, v) lands at (u + ndc₀, v + ndc₁).
pub(crate) fn camera_clip_shifted(camera: &Camera, ndc: [f32; 2]) -> [[f32; 4]; 4] {
    let to_camera = camera.to_world.inverse();
    let row = |r: usize| {
        let m = to_camera.row(r);
        [m.x, m.y, m.z, m.w]
    };
    let (x, y, z) = (row(0), row(1), row(2));
    let (near, far) = (camera.near_clip, camera.far_clip);
    let a = far / (far - near);
    let mut depth = z.map(|v| v * a);
    depth[3] -= near * a;
    let mut clip_x = x.map(|v| -v / camera.tan_half_x);
    let mut clip_y = y.map(|v| v / camera.tan_half_y);
    for k in 0..4 {
        clip_x[k] += ndc[0] * z[k];
        clip_y[k] += ndc[1] * z[k];
    }
    column_major([clip_x, clip_y, depth, z])
}
