//! Helpers shared by the render crate's integration tests: tiny scenes built in code.

#![allow(dead_code)]

use ircache_math::{Mat4, Rgb, Vec3};
use ircache_render::integrators::Integrator;
use ircache_render::render::{render, RenderOutput, RenderSettings};
use ircache_render::scene::Scene;
use ircache_scene::*;
use std::path::PathBuf;
use std::sync::Arc;

/// A location for shapes made in code.
pub fn here() -> SourceLocation {
    SourceLocation {
        file: Arc::new(PathBuf::from("<test>")),
        line: 1,
        column: 1,
    }
}

/// A camera at `eye` looking at `target` (Mitsuba's lookat), square film.
pub fn sensor(eye: Vec3, target: Vec3, fov: f32, size: u32, spp: u32) -> SensorDesc {
    let dir = (target - eye).normalize();
    let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    let to_world = Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        eye.extend(1.0),
    );
    SensorDesc {
        medium: None,
        projection: ircache_scene::Projection::Pinhole,
        to_world,
        fov_degrees: fov,
        fov_axis: FovAxis::X,
        near_clip: 1e-4,
        far_clip: 1e6,
        film: FilmDesc {
            width: size,
            height: size,
            filter: FilterDesc::Box,
        },
        spp,
        sampler: "independent".into(),
        sampler_seed: 0,
        jitter: true,
    }
}

/// A diffuse BSDF of albedo `rho`.
pub fn diffuse(rho: Rgb) -> Arc<BsdfDesc> {
    Arc::new(BsdfDesc::Diffuse {
        reflectance: TextureDesc::Constant(rho),
    })
}

/// A scene from shapes and emitters with the given integrator.
pub fn scene(
    sensor: SensorDesc,
    integrator: IntegratorDesc,
    shapes: Vec<ShapeDesc>,
    emitters: Vec<EmitterDesc>,
) -> SceneDesc {
    SceneDesc {
        media: Vec::new(),
        source: PathBuf::from("<test>"),
        sensor,
        integrator,
        shapes,
        emitters,
        notes: Vec::new(),
    }
}

/// A path integrator description.
pub fn path(max_depth: i32) -> IntegratorDesc {
    IntegratorDesc {
        kind: "path".into(),
        max_depth,
        ..IntegratorDesc::default()
    }
}

/// Renders a description with `threads` threads and seed `seed`.
pub fn render_desc(desc: &SceneDesc, threads: usize, seed: u64) -> RenderOutput {
    let settings = RenderSettings::from_desc(desc, seed, threads).expect("sampler");
    render_settings(desc, &settings)
}

/// Renders a description with the pixel sampling `sampling`.
pub fn render_sampled(
    desc: &SceneDesc,
    sampling: ircache_render::render::Sampling,
    threads: usize,
    seed: u64,
) -> RenderOutput {
    let settings = RenderSettings {
        sampling,
        ..RenderSettings::from_desc(desc, seed, threads).expect("sampler")
    };
    render_settings(desc, &settings)
}

/// Renders a description with `settings`.
fn render_settings(desc: &SceneDesc, settings: &RenderSettings) -> RenderOutput {
    let scene = Scene::build(desc).expect("scene builds");
    let integrator = Integrator::from_desc(&desc.integrator).expect("integrator");
    render(&scene, &integrator, settings, &|_| {}).expect("render")
}

/// Mean and standard error of the mean of each channel over the image's pixels.
pub fn mean_and_error(img: &ircache_image::Image) -> (Rgb, Rgb) {
    let n = img.pixels.len() as f64;
    let mut s = [0.0f64; 3];
    let mut s2 = [0.0f64; 3];
    for p in &img.pixels {
        for c in 0..3 {
            s[c] += p[c] as f64;
            s2[c] += (p[c] as f64).powi(2);
        }
    }
    let m = s.map(|v| v / n);
    let e = [0, 1, 2].map(|c| ((s2[c] / n - m[c] * m[c]).max(0.0) / n).sqrt());
    (
        Rgb::new(m[0] as f32, m[1] as f32, m[2] as f32),
        Rgb::new(e[0] as f32, e[1] as f32, e[2] as f32),
    )
}

/// A scene of just `shapes` and `emitters` behind a fixed camera (for the emitter tests).
pub fn light_scene(shapes: Vec<ShapeDesc>, emitters: Vec<EmitterDesc>) -> SceneDesc {
    SceneDesc {
        media: Vec::new(),
        source: PathBuf::from("<test>"),
        sensor: SensorDesc {
            medium: None,
            projection: ircache_scene::Projection::Pinhole,
            to_world: Mat4::IDENTITY,
            fov_degrees: 45.0,
            fov_axis: FovAxis::X,
            near_clip: 0.01,
            far_clip: 1e4,
            film: FilmDesc {
                width: 4,
                height: 4,
                filter: FilterDesc::Box,
            },
            spp: 1,
            sampler: "independent".into(),
            sampler_seed: 0,
            jitter: true,
        },
        integrator: IntegratorDesc::default(),
        shapes,
        emitters,
        notes: Vec::new(),
    }
}

/// A diffuse shape with an area emitter of `radiance`.
pub fn emitting_shape(geometry: Geometry, radiance: Rgb) -> ShapeDesc {
    ShapeDesc {
        media: Default::default(),
        id: None,
        geometry,
        bsdf: Arc::new(BsdfDesc::Diffuse {
            reflectance: TextureDesc::Constant(Rgb::splat(0.5)),
        }),
        emitter: Some(radiance),
        emitter_texture: None,
        emitter_pattern: None,
        location: here(),
    }
}

/// A one-sided quad from corners in order (normal by the right-hand rule).
pub fn quad(corners: [Vec3; 4], bsdf: Arc<BsdfDesc>, emitter: Option<Rgb>) -> ShapeDesc {
    ShapeDesc {
        media: Default::default(),
        id: None,
        geometry: Geometry::Mesh(TriangleMesh {
            positions: corners.to_vec(),
            normals: None,
            uvs: None,
            indices: vec![[0, 1, 2], [0, 2, 3]],
        }),
        bsdf,
        emitter,
        emitter_texture: None,
        emitter_pattern: None,
        location: here(),
    }
}

/// A quad from four corners in order, as two triangles, `twosided` with `bsdf` on both sides.
pub fn two_sided_quad(corners: [Vec3; 4], bsdf: Arc<BsdfDesc>) -> ShapeDesc {
    let two_sided = Arc::new(BsdfDesc::TwoSided {
        front: bsdf,
        back: None,
    });
    quad(corners, two_sided, None)
}

/// Lambert's form factor from a differential area at `x` with normal `n` to a polygon above
/// its tangent plane: (1/2π) |Σ_i β_i n·Γ_i|.
pub fn form_factor(x: Vec3, n: Vec3, poly: &[Vec3]) -> f32 {
    let mut s = 0.0f64;
    for i in 0..poly.len() {
        let a = (poly[i] - x).normalize().as_dvec3();
        let b = (poly[(i + 1) % poly.len()] - x).normalize().as_dvec3();
        let beta = a.dot(b).clamp(-1.0, 1.0).acos();
        s += beta * n.as_dvec3().dot(a.cross(b).normalize());
    }
    (s.abs() / (2.0 * std::f64::consts::PI)) as f32
}

/// A scalar grid over the box `[lo, hi]` with samples `f(x, y, z)` at the cell centres.
pub fn grid(res: [usize; 3], lo: Vec3, hi: Vec3, f: impl Fn(Vec3) -> f32) -> VolumeDesc {
    let to_world = Mat4::from_translation(lo) * Mat4::from_scale(hi - lo);
    let mut data = Vec::new();
    for z in 0..res[2] {
        for y in 0..res[1] {
            for x in 0..res[0] {
                let u = Vec3::new(
                    (x as f32 + 0.5) / res[0] as f32,
                    (y as f32 + 0.5) / res[1] as f32,
                    (z as f32 + 0.5) / res[2] as f32,
                );
                data.push(f(to_world.transform_point3(u)));
            }
        }
    }
    VolumeDesc::Grid(Arc::new(GridVolumeDesc {
        path: "<test>".into(),
        resolution: res,
        channels: 1,
        data,
        to_world,
        filter: TextureFilter::Bilinear,
        wrap: WrapMode::Clamp,
    }))
}

/// The project's scene `scenes/NAME/scene.xml` (Mitsuba XML) with `defines`.
pub fn project_scene(name: &str, defines: &[(String, String)]) -> SceneDesc {
    let path = ircache_testing::project_scenes()
        .join(name)
        .join("scene.xml");
    ircache_scene::mitsuba::load(&path, defines)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
