// A frame on the GPU (paper 001 §4.5, the thesis's pipeline; NOTES-001 §C.1) for scenes of
// Lambertian surfaces with constant albedos under one directional light: `gbuffer` turns the
// rasterised camera view (triangle ids) into the splat pass's samples, each hit found on its
// triangle along the camera ray through the pixel centre; after the splat, `compose` shades
// each pixel: albedo/π × (splatted indirect irradiance + direct light through a shadow map),
// added to the layers before (jittered layers average to a box filter's estimate). Prepended:
// `surface.wgsl` (triangles, shapes, the light; a ray's hit; the light through the shadow map).

struct Camera {
    to_world: mat4x4<f32>,
    origin: vec4<f32>,
    tan_half: vec4<f32>, // x, y; zw: the layer's jitter from the pixel centres, in pixels
    size: vec4<u32>,     // width, height, tiles_x
}

struct Sample {
    p: vec4<f32>, // w = 1 where the sample is a record site
    n: vec4<f32>,
    n_bump: vec4<f32>,
}

struct Sums {
    irradiance: vec4<f32>,
    count: u32,
    min_error: f32,
    pad0: u32,
    pad1: u32,
}

const NONE: u32 = 0xffffffffu;
const BACK: u32 = 0x80000000u;
const TILE: u32 = 16u;

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var ids: texture_2d<u32>;
@group(0) @binding(2) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(3) var<storage, read> shapes: array<Shape>;
@group(0) @binding(4) var<storage, read_write> samples: array<Sample>;
@group(0) @binding(5) var<storage, read_write> hits: array<u32>; // shape | BACK, or NONE

@compute @workgroup_size(16, 16, 1)
fn gbuffer(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = camera.size.x;
    let h = camera.size.y;
    if id.x >= w || id.y >= h {
        return;
    }
    let i = id.y * w + id.x;
    let triangle = textureLoad(ids, vec2<i32>(id.xy), 0).r;
    var s: Sample;
    if triangle == 0u {
        samples[i] = s;
        hits[i] = NONE;
        return;
    }
    let tri = triangles[triangle - 1u];
    // `Camera::generate_ray` through the pixel centre moved by the layer's jitter (the raster
    // was shifted to match).
    let film = (vec2<f32>(id.xy) + 0.5 + camera.tan_half.zw) / vec2<f32>(f32(w), f32(h));
    let d_cam = normalize(vec3<f32>((1.0 - 2.0 * film.x) * camera.tan_half.x, (1.0 - 2.0 * film.y) * camera.tan_half.y, 1.0));
    let d = normalize((camera.to_world * vec4<f32>(d_cam, 0.0)).xyz);
    let hit = surface_hit(tri, camera.origin.xyz, d);
    let site = select(shapes[hit.shape].front.w, shapes[hit.shape].back.w, hit.back) > 0.5;
    s.p = vec4<f32>(hit.p, select(0.0, 1.0, site));
    s.n = vec4<f32>(hit.n, 0.0);
    s.n_bump = s.n;
    samples[i] = s;
    hits[i] = select(hit.shape, hit.shape | BACK, hit.back);
}

@group(0) @binding(6) var<storage, read> sums: array<Sums>;   // per touched tile, TILE²
@group(0) @binding(7) var<storage, read> slots: array<u32>;   // per film tile: its touched slot
@group(0) @binding(8) var<uniform> light: Light;
@group(0) @binding(9) var shadow: texture_depth_2d;
@group(0) @binding(10) var<storage, read_write> image: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> misses: atomic<u32>;

@compute @workgroup_size(16, 16, 1)
fn compose(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = camera.size.x;
    let h = camera.size.y;
    if id.x >= w || id.y >= h {
        return;
    }
    let i = id.y * w + id.x;
    let hit = hits[i];
    // Layers add up; w counts them.
    if hit == NONE {
        image[i] = image[i] + vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return;
    }
    let shape = hit & ~BACK;
    let albedo = select(shapes[shape].front.xyz, shapes[shape].back.xyz, (hit & BACK) != 0u);
    let s = samples[i];
    let n = s.n.xyz;
    var e = vec3<f32>(0.0);
    if s.p.w != 0.0 {
        let slot = slots[(id.y / TILE) * camera.size.z + id.x / TILE];
        var sum = vec4<f32>(0.0);
        if slot != NONE {
            sum = sums[slot * TILE * TILE + (id.y % TILE) * TILE + id.x % TILE].irradiance;
        }
        if sum.w > 0.0 {
            e = max(sum.xyz / sum.w, vec3<f32>(0.0));
        } else {
            atomicAdd(&misses, 1u);
        }
    }
    e = e + sun_irradiance(light, shadow, s.p.xyz, n);
    image[i] = image[i] + vec4<f32>(albedo / PI * e, 1.0);
}
