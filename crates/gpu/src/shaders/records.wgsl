// Records computed by hemisphere rasterisation (paper 001 §4.4.2, Table 4.1; NOTES-001 §C.4):
// the planes above records, rasterised side by side into an atlas (triangle ids), each pixel
// shaded on the GPU with what a rasteriser has (one bounce: the hit's albedo/π times the
// directional light through the shadow map), summed with the border-compensated weights of
// `irradiance_cache::plane` into the record's irradiance; with the harmonic mean distance of
// the pixels' hits and the plane's gradients (`HemispherePlane::gradients`: the walls between
// neighbouring pixels, each moving at the nearer hit's distance; each pixel's ∫ ω dω). One
// workgroup per record. Prepended: `surface.wgsl`.

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
    // In the plane's frame (s, t): the translational gradient's two components, then the
    // rotational one's, each rgb; the first's w: the nearest hit (3e38: none).
    gradient: array<vec4<f32>, 4>,
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
@group(0) @binding(9) var<storage, read> tilt: array<vec2<f32>>;  // per pixel: ∫ (ω_x, ω_y) dω
@group(0) @binding(10) var<storage, read> walls: array<f32>;      // per wall (see `pixel_wall`)

var<workgroup> sums: array<vec4<f32>, 256>;  // one quantity at a time
var<workgroup> hits: array<f32, 256>;

// Pixel (i, j) of the plane above the record: its radiance and its hit's distance (−1: nothing
// seen, or below the surface).
fn pixel(plane: Plane, tile: vec2<u32>, i: u32, j: u32) -> vec4<f32> {
    let n = params.pixels;
    let s = params.half_size;
    // `HemispherePlane::direction`; texture row n − 1 − j holds plane row j.
    let x = -s + 2.0 * s * (f32(i) + 0.5) / f32(n);
    let y = -s + 2.0 * s * (f32(j) + 0.5) / f32(n);
    let d = normalize(plane.s.xyz * x + plane.t.xyz * y + plane.n.xyz);
    if dot(d, plane.ng.xyz) <= 0.0 {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let id = textureLoad(ids, vec2<i32>(tile + vec2<u32>(i, n - 1u - j)), 0).r;
    if id == 0u {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    return shade(id - 1u, plane.origin.xyz, d);
}

// The term of the wall between pixels a and b (b right of or above a) with weight w: the
// radiance difference over the nearer hit's distance (nothing where neither hit).
fn wall_term(a: vec4<f32>, b: vec4<f32>, w: f32) -> vec3<f32> {
    var closer = -1.0;
    if a.w > 0.0 {
        closer = a.w;
    }
    if b.w > 0.0 && (closer < 0.0 || b.w < closer) {
        closer = b.w;
    }
    if closer <= 0.0 {
        return vec3<f32>(0.0);
    }
    return (b.xyz - a.xyz) * (w / closer);
}

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
    // Irradiance and Σ 1/distance; translational (x, y) and rotational (x, y) gradients.
    var q4: array<vec4<f32>, 5>;
    q4[1].w = 3.0e38; // the nearest hit
    var found = 0.0;
    for (var q = local; q < n * n; q = q + 256u) {
        let i = q % n;
        let j = q / n;
        let here = pixel(plane, tile, i, j);
        if here.w > 0.0 {
            q4[0] = q4[0] + vec4<f32>(here.xyz * weights[q], 1.0 / max(here.w, 1e-30));
            q4[1].w = min(q4[1].w, here.w);
            found = found + 1.0;
        }
        // The walls to the right and above: x = edge(i + 1) has weight walls[j (n − 1) + i],
        // y = edge(j + 1) walls[i (n − 1) + j].
        if i + 1u < n {
            let t = wall_term(here, pixel(plane, tile, i + 1u, j), walls[j * (n - 1u) + i]);
            q4[1] = vec4<f32>(q4[1].xyz + t, q4[1].w);
        }
        if j + 1u < n {
            let t = wall_term(here, pixel(plane, tile, i, j + 1u), walls[i * (n - 1u) + j]);
            q4[2] = q4[2] + vec4<f32>(t, 0.0);
        }
        // ∇ᵣE = ∫ L (n × ω) dω = ∫ L (−ω_y, ω_x) dω.
        q4[3] = q4[3] - vec4<f32>(here.xyz * tilt[q].y, 0.0);
        q4[4] = q4[4] + vec4<f32>(here.xyz * tilt[q].x, 0.0);
    }
    hits[local] = found;
    var total: array<vec4<f32>, 5>;
    for (var v = 0u; v < 5u; v = v + 1u) {
        workgroupBarrier();
        sums[local] = q4[v];
        for (var stride = 128u; stride > 0u; stride = stride / 2u) {
            workgroupBarrier();
            if local < stride {
                let a = sums[local];
                let b = sums[local + stride];
                // The translational x sum carries the nearest hit in w.
                sums[local] = vec4<f32>(a.xyz + b.xyz, select(a.w + b.w, min(a.w, b.w), v == 1u));
                if v == 0u {
                    hits[local] = hits[local] + hits[local + stride];
                }
            }
        }
        workgroupBarrier();
        total[v] = sums[0];
    }
    if local == 0u {
        var harmonic = 0.0;
        if total[0].w > 0.0 {
            harmonic = hits[0] / total[0].w;
        }
        records[k].irradiance = vec4<f32>(total[0].xyz, harmonic);
        for (var g = 0u; g < 4u; g = g + 1u) {
            records[k].gradient[g] = total[g + 1u];
        }
    }
}
