// Records computed by hemisphere rasterisation (paper 001 §4.4.2, Table 4.1; NOTES-001 §C.4):
// the planes above records, rasterised side by side into an atlas (triangle ids), each pixel
// shaded on the GPU with what a rasteriser has (one bounce: the hit's albedo/π times the
// directional light through the shadow map), summed with the border-compensated weights of
// `irradiance_cache::plane` into the record's irradiance; with the harmonic mean distance of
// the pixels' hits. One workgroup per record. Prepended: `surface.wgsl`.

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
    let hit = surface_hit(triangles[triangle], o, d);
    let albedo = select(shapes[hit.shape].front.xyz, shapes[hit.shape].back.xyz, hit.back);
    return vec4<f32>(albedo / PI * sun_irradiance(light, shadow, hit.p, hit.n), hit.t);
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
