//! Records computed by hemisphere rasterisation on the GPU (001 §4.4.2, Table 4.1; NOTES-001
//! §C.4), the pass of `shaders/records.wgsl`: the planes above many records rasterised side by
//! side into an atlas ([`crate::visibility`]), each pixel shaded on the GPU as a rasteriser
//! shades it (one bounce: the hit's albedo/π times the directional light through the shadow
//! map of [`GpuFrame`]), and summed with [`HemispherePlane`]'s border-compensated weights into
//! each record's irradiance, with the harmonic mean distance of the pixels' hits and the plane's
//! gradients ([`HemispherePlane::gradients`]). For the scenes [`GpuFrame`] serves, records of
//! the first bounce.

use crate::frame::{view_of, GpuFrame};
use crate::GpuError;
use bytemuck::{Pod, Zeroable};
use ircache_math::{Frame, Rgb, Vec3};
use ircache_render::irradiance_cache::gather::ShadingPoint;
use ircache_render::irradiance_cache::hemisphere::to_world;
use ircache_render::irradiance_cache::plane::{
    HemispherePlane, PlaneEstimator, PlaneMeasure, PlaneSource,
};

/// A record's plane as the shader reads it (`Plane`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuPlane {
    origin: [f32; 4],
    s: [f32; 4],
    t: [f32; 4],
    n: [f32; 4],
    ng: [f32; 4],
}

/// The pass's constants (`Params`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuParams {
    pixels: u32,
    columns: u32,
    count: u32,
    half_size: f32,
}

/// Workgroups along x (`GROUPS_X` in `records.wgsl`).
const GROUPS_X: u32 = 32_768;

/// A record computed from its rasterised plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneRecord {
    /// Irradiance, border-compensated.
    pub irradiance: Rgb,
    /// Harmonic mean distance of the pixels' hits; `None` where the plane saw nothing.
    pub harmonic_distance: Option<f32>,
    /// The nearest of the pixels' hits; `None` where the plane saw nothing.
    pub nearest_distance: Option<f32>,
    /// Translational gradient per channel, world space.
    pub grad_t: [Vec3; 3],
    /// Rotational gradient per channel, world space.
    pub grad_r: [Vec3; 3],
}

/// A record as the shader writes it (`Out`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuOut {
    irradiance: [f32; 4],
    /// Translational along s and t, rotational along s and t: rgb each.
    gradient: [[f32; 4]; 4],
}

/// A plane's weight tables on the GPU (border-compensated weights, tilt for the rotational
/// gradient, walls for the translational one), uploaded once and read by every batch.
#[derive(Debug)]
pub struct PlaneTables {
    /// The plane they belong to.
    pub plane: HemispherePlane,
    weights: wgpu::Buffer,
    tilt: wgpu::Buffer,
    walls: wgpu::Buffer,
}

impl GpuFrame {
    /// `plane`'s weight tables, uploaded to the GPU.
    #[must_use]
    pub fn plane_tables(&self, plane: &HemispherePlane) -> PlaneTables {
        let storage = wgpu::BufferUsages::STORAGE;
        let weights: Vec<f32> = plane
            .weights(PlaneEstimator::BorderCompensation)
            .iter()
            .map(|&w| w as f32)
            .collect();
        let tilt: Vec<[f32; 2]> = plane
            .tilt_weights()
            .iter()
            .map(|w| w.map(|v| v as f32))
            .collect();
        // At least one value: a binding may not be empty.
        let mut walls: Vec<f32> = plane.wall_weights().iter().map(|&w| w as f32).collect();
        walls.push(0.0);
        PlaneTables {
            plane: plane.clone(),
            weights: self
                .gpu
                .buffer("plane weights", bytemuck::cast_slice(&weights), storage),
            tilt: self
                .gpu
                .buffer("plane tilt", bytemuck::cast_slice(&tilt), storage),
            walls: self
                .gpu
                .buffer("plane walls", bytemuck::cast_slice(&walls), storage),
        }
    }

    /// The records at `points`, each from the plane of `tables` rasterised above it and shaded
    /// on the GPU, in as few passes as the device's largest texture allows.
    ///
    /// # Errors
    /// When the GPU fails.
    pub fn plane_records(
        &self,
        tables: &PlaneTables,
        points: &[ShadingPoint],
    ) -> Result<Vec<PlaneRecord>, GpuError> {
        let device = &self.gpu.device;
        let plane = &tables.plane;
        let n = plane.pixels as u32;
        let (columns, rows) = self.visibility.atlas_grid(n, n)?;
        let storage = wgpu::BufferUsages::STORAGE;
        let (weights, tilt, walls) = (&tables.weights, &tables.tilt, &tables.walls);
        let mut out = Vec::with_capacity(points.len());
        for batch in points.chunks((columns * rows) as usize) {
            let count = batch.len() as u32;
            let views: Vec<[[f32; 4]; 4]> = batch
                .iter()
                .map(|sp| self.visibility.plane_view(plane, sp))
                .collect();
            let views = self.visibility.views(&views);
            let planes: Vec<GpuPlane> = batch
                .iter()
                .map(|sp| {
                    let frame = Frame::from_z(sp.n);
                    let v = |v: ircache_math::Vec3| [v.x, v.y, v.z, 0.0];
                    let ng = sp.it.ng * sp.n.dot(sp.it.ng).signum();
                    GpuPlane {
                        origin: v(sp.it.p),
                        s: v(frame.s),
                        t: v(frame.t),
                        n: v(frame.n),
                        ng: v(ng),
                    }
                })
                .collect();
            let planes = self
                .gpu
                .buffer("planes", bytemuck::cast_slice(&planes), storage);
            let params = GpuParams {
                pixels: n,
                columns,
                count,
                half_size: plane.half_size as f32,
            };
            let params = self.gpu.buffer(
                "record params",
                bytemuck::bytes_of(&params),
                wgpu::BufferUsages::UNIFORM,
            );
            let records = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("plane records"),
                size: std::mem::size_of::<GpuOut>() as u64 * u64::from(count),
                usage: storage | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let (atlas_w, atlas_h) = (columns.min(count) * n, count.div_ceil(columns) * n);
            let atlas = (atlas_w, atlas_h);
            let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
            let ids = view_of(&self.gpu.texture(
                "plane atlas",
                atlas,
                crate::visibility::FORMAT,
                attachment | wgpu::TextureUsages::TEXTURE_BINDING,
            ));
            let depth = view_of(&self.gpu.texture(
                "plane atlas depth",
                atlas,
                crate::visibility::DEPTH,
                attachment,
            ));
            fn resource(b: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
                b.as_entire_binding()
            }
            let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("plane records"),
                layout: &self.records.get_bind_group_layout(0),
                entries: &[
                    (0, resource(&params)),
                    (1, wgpu::BindingResource::TextureView(&ids)),
                    (2, resource(&self.triangles)),
                    (3, resource(&self.shapes)),
                    (4, resource(&planes)),
                    (5, resource(weights)),
                    (6, resource(&self.light)),
                    (7, wgpu::BindingResource::TextureView(&self.shadow)),
                    (8, resource(&records)),
                    (9, resource(tilt)),
                    (10, resource(walls)),
                ]
                .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource }),
            });
            let mut encoder =
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
            self.visibility.draw_atlas(
                &mut encoder,
                &views,
                count,
                (n, n),
                columns,
                &ids,
                &depth,
                false,
            );
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
                pass.set_pipeline(&self.records);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(count.min(GROUPS_X), count.div_ceil(GROUPS_X), 1);
            }
            self.gpu.queue.submit([encoder.finish()]);
            let bytes = self.gpu.read_back(&records)?;
            self.gpu.check()?;
            let values: &[GpuOut] = bytemuck::cast_slice(&bytes);
            out.extend(values.iter().zip(batch).map(|(v, sp)| {
                let frame = Frame::from_z(sp.n);
                let [tx, ty, rx, ry] = v.gradient;
                // The shader's (s, t) components per channel, as a local gradient.
                let world = |x: [f32; 4], y: [f32; 4]| {
                    let local = [0, 1, 2].map(|c| Vec3::new(x[c], y[c], 0.0));
                    to_world(&local, frame.s, frame.t)
                };
                let e = v.irradiance;
                PlaneRecord {
                    irradiance: Rgb::new(e[0], e[1], e[2]),
                    harmonic_distance: (e[3] > 0.0).then_some(e[3]),
                    nearest_distance: (tx[3] < 1e38).then_some(tx[3]),
                    grad_t: world(tx, ty),
                    grad_r: world(rx, ry),
                }
            }));
        }
        Ok(out)
    }
}

/// The GPU's plane records as the cache's source of first-level records
/// (`--record-source gpu-plane`): each batch's planes rasterised, shaded and reduced at once.
#[derive(Debug)]
pub struct GpuPlaneSource {
    /// The scene on the GPU.
    pub frame: GpuFrame,
    /// The plane above each record, its tables on the GPU.
    pub tables: PlaneTables,
}

impl GpuPlaneSource {
    /// Records from `plane` rasterised in `frame`'s scene.
    #[must_use]
    pub fn new(frame: GpuFrame, plane: &HemispherePlane) -> Self {
        let tables = frame.plane_tables(plane);
        GpuPlaneSource { frame, tables }
    }
}

impl PlaneSource for GpuPlaneSource {
    fn measure(&self, points: &[ShadingPoint]) -> Result<Vec<PlaneMeasure>, String> {
        let records = self
            .frame
            .plane_records(&self.tables, points)
            .map_err(|e| e.to_string())?;
        Ok(records
            .into_iter()
            .map(|r| PlaneMeasure {
                e: r.irradiance,
                grad_t: r.grad_t,
                grad_r: r.grad_r,
                nearest: r.nearest_distance.unwrap_or(f32::INFINITY),
                harmonic: r.harmonic_distance.unwrap_or(f32::INFINITY),
            })
            .collect())
    }
}
