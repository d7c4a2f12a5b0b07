// Records computed by hemisphere rasterisation (paper 001 §4.4.2, Table 4.1; NOTES-001 §C.4):
// the planes above records, rasterised side by side into an atlas (triangle ids), each pixel
// shaded on the GPU with what a rasteriser has (one bounce: the hit's albedo/π times the
// directional light through the shadow map), summed with the border-compensated weights of
// `irradiance_cache::plane` into the record's irradiance; with the harmonic mean distance of
// the pixels' hits. One workgroup per record.

struct Triangle {
    p0: vec4<f32>, // w: the shape's index (bits)
    p1: vec4<f32>,
    p2: vec4<f32>,
    n0: vec4<f32>, // w: 1 where the mesh has vertex normals
    n1: vec4<f32>,
    n2: vec4<f32>,
}

struct Shape {
    front: vec4<f32>,
    back: vec4<f32>,
}

struct Light {
    to_clip: mat4x4<f32>,
    to_light: vec4<f32>,
    irradiance: vec4<f32>,
    bias: vec4<f32>,
}

struct Plane {
    origin: vec4<f32>, // the record's position
    s: vec4<f32>,      // its frame: s, t and the normal n
    t: vec4<f32>,
    n: vec4<f32>,
    ng: vec4<f32>,     // the geometric normal on n's side: pixels below it stay black
}

struct Params {
    pixels: u32,    // per side
    columns: u32,   // atlas tiles a row
    count: u32,     // records in this batch
    half_size: f32, // the plane's s
}

struct Out {
    irradiance: vec4<f32>, // rgb; w: the harmonic mean distance of the hits (0: none)
}

const PI: f32 = 3.14159265358979;
const GROUPS_X: u32 = 32768u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var ids: texture_2d<u32>;
@group(0) @binding(2) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(3) var<storage, read> shapes: array<Shape>;
@group(0) @binding(4) var<storage, read> planes: array<Plane>;
@group(0) @binding(5) var<storage, read> weights: array<f32>;
@group(0) @binding(6) var<uniform> light: Light;
@group(0) @binding(7) var shadow: texture_depth_2d;
@group(0) @binding(8) var<storage, read_write> records: array<Out>;

var<workgroup> sums: array<vec4<f32>, 256>;  // rgb; w: Σ 1/distance
var<workgroup> hits: array<f32, 256>;

// The radiance leaving the hit of `triangle` along the ray (o, d) towards o: one bounce of the
// directional light, its visibility from the shadow map; and the hit's distance.
fn shade(triangle: u32, o: vec3<f32>, d: vec3<f32>) -> vec4<f32> {
    let tri = triangles[triangle];
    let e1 = tri.p1.xyz - tri.p0.xyz;
    let e2 = tri.p2.xyz - tri.p0.xyz;
    let ng_raw = cross(e1, e2);
    let t = dot(tri.p0.xyz - o, ng_raw) / dot(d, ng_raw);
    let p = o + t * d;
    let v = p - tri.p0.xyz;
    let d00 = dot(e1, e1);
    let d01 = dot(e1, e2);
    let d11 = dot(e2, e2);
    let d20 = dot(v, e1);
    let d21 = dot(v, e2);
    let denom = d00 * d11 - d01 * d01;
    let b1 = (d11 * d20 - d01 * d21) / denom;
    let b2 = (d00 * d21 - d01 * d20) / denom;
    let b0 = 1.0 - b1 - b2;
    var ns = normalize(ng_raw);
    if tri.n0.w > 0.5 {
        let interpolated = b0 * tri.n0.xyz + b1 * tri.n1.xyz + b2 * tri.n2.xyz;
        if dot(interpolated, interpolated) > 0.0 {
            ns = normalize(interpolated);
        }
    }
    let back = dot(ns, -d) < 0.0;
    let n = select(ns, -ns, back);
    let shape = bitcast<u32>(tri.p0.w);
    let albedo = select(shapes[shape].front.xyz, shapes[shape].back.xyz, back);
    var radiance = vec3<f32>(0.0);
    let cosine = dot(n, light.to_light.xyz);
    if cosine > 0.0 {
        let c = light.to_clip * vec4<f32>(p, 1.0);
        let uv = vec2<f32>(0.5 + 0.5 * c.x, 0.5 - 0.5 * c.y);
        var lit = 1.0;
        if all(uv >= vec2<f32>(0.0)) && all(uv < vec2<f32>(1.0)) {
            let stored = textureLoad(shadow, vec2<i32>(uv * light.bias.y), 0);
            let slope = sqrt(max(1.0 - cosine * cosine, 0.0)) / cosine;
            lit = select(0.0, 1.0, c.z - light.bias.x * (1.5 + min(slope, 16.0)) <= stored);
        }
        radiance = albedo / PI * light.irradiance.xyz * cosine * lit;
    }
    return vec4<f32>(radiance, t);
}

@compute @workgroup_size(256, 1, 1)
fn record(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = group.y * GROUPS_X + group.x;
    // Uniform across the workgroup: the barriers below see all of it or none.
    if k >= params.count {
        return;
    }
    let plane = planes[k];
    let n = params.pixels;
    let s = params.half_size;
    let tile = vec2<u32>((k % params.columns) * n, (k / params.columns) * n);
    var sum = vec4<f32>(0.0);
    var found = 0.0;
    for (var q = local; q < n * n; q = q + 256u) {
        let i = q % n;
        let j = q / n;
        // `HemispherePlane::direction`; texture row n − 1 − j holds plane row j.
        let x = -s + 2.0 * s * (f32(i) + 0.5) / f32(n);
        let y = -s + 2.0 * s * (f32(j) + 0.5) / f32(n);
        let d = normalize(plane.s.xyz * x + plane.t.xyz * y + plane.n.xyz);
        if dot(d, plane.ng.xyz) <= 0.0 {
            continue;
        }
        let id = textureLoad(ids, vec2<i32>(tile + vec2<u32>(i, n - 1u - j)), 0).r;
        if id == 0u {
            continue;
        }
        let shaded = shade(id - 1u, plane.origin.xyz, d);
        sum = sum + vec4<f32>(shaded.xyz * weights[q], 1.0 / max(shaded.w, 1e-30));
        found = found + 1.0;
    }
    sums[local] = sum;
    hits[local] = found;
    for (var stride = 128u; stride > 0u; stride = stride / 2u) {
        workgroupBarrier();
        if local < stride {
            sums[local] = sums[local] + sums[local + stride];
            hits[local] = hits[local] + hits[local + stride];
        }
    }
    if local == 0u {
        let total = sums[0];
        var harmonic = 0.0;
        if total.w > 0.0 {
            harmonic = hits[0] / total.w;
        }
        records[k].irradiance = vec4<f32>(total.xyz, harmonic);
    }
}
