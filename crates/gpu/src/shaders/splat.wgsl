// Radiance cache splatting of irradiance records (paper 001 ch. 4, Algorithm 3; NOTES-001 §C.2):
// each sample of a layer sums the weighted, gradient-extrapolated irradiance (000 eq. 3.15) of
// every record whose influence covers it. Records are binned per 16 × 16 tile on the CPU (each
// record under the tiles its film rectangle touches, in index order); one workgroup per touched
// tile, one invocation per sample, walks the tile's list: the sums are the CPU splatter's, in
// the same order, with no float blending (whose order a GPU does not fix). The samples cover
// the film; the sums, the touched tiles only (TILE² each, row-major within the tile).

struct Record {
    p_r: vec4<f32>,   // position, radius
    n: vec4<f32>,     // normal
    e: vec4<f32>,     // irradiance
    gt: array<vec4<f32>, 3>, // translational gradient per channel
    gr: array<vec4<f32>, 3>, // rotational gradient per channel
}

struct Sample {
    p: vec4<f32>,      // position, w = 1 where the sample is a record site
    n: vec4<f32>,      // shading normal before bump mapping (error, in-front test)
    n_bump: vec4<f32>, // after it (rotational gradient)
}

struct Sums {
    irradiance: vec4<f32>, // Σ w E′, w = Σ w
    count: u32,
    min_error: f32,
    pad0: u32,
    pad1: u32,
}

struct Params {
    width: u32,
    height: u32,
    tiles_x: u32,
    metric: u32,    // 0 Ward, 1 Tabellion, 2 Hessian
    gradients: u32, // 0 none, 1 rotation, 2 full
    accuracy: f32,
    tile_count: u32, // touched tiles
    threshold: f32,  // records serve up to this error; above 1, only samples none served yet
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> records: array<Record>;
@group(0) @binding(2) var<storage, read> samples: array<Sample>;
@group(0) @binding(3) var<storage, read> tile_start: array<u32>;   // per touched tile
@group(0) @binding(4) var<storage, read> tile_records: array<u32>;
@group(0) @binding(5) var<storage, read_write> sums: array<Sums>; // per touched tile, TILE²
@group(0) @binding(6) var<storage, read> tiles: array<u32>;       // touched tiles' film indices

const TILE: u32 = 16u;
// Workgroups along x; touched tiles beyond wrap to further rows (`splat::GROUPS_X`).
const GROUPS_X: u32 = 32768u;

// `irradiance_cache::record::ErrorMetric::error`; negative when the record lies in front.
fn record_error(rec: Record, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let d = p - rec.p_r.xyz;
    let dist = length(d);
    if dist > 1e-4 * rec.p_r.w && dot(d, n + rec.n.xyz) < -0.1 * dist {
        return -1.0;
    }
    let normal = sqrt(max(1.0 - min(dot(n, rec.n.xyz), 1.0), 0.0));
    let rr = rec.p_r.w;
    if params.metric == 0u {
        return (dist / rr + normal) / params.accuracy;
    }
    if params.metric == 1u {
        return (0.2 / params.accuracy) * max(dist / rr, normal / 0.1232574);
    }
    return dist / rr + normal / params.accuracy;
}

// `ErrorMetric::weight` at `params.threshold`.
fn record_weight(e: f32) -> f32 {
    if params.metric == 1u {
        return max(1.0 - e / params.threshold, 1e-6);
    }
    return 1.0 / max(e, 1e-4);
}

// `irradiance_cache::record::extrapolate`.
fn extrapolate(rec: Record, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var e = rec.e.xyz;
    if params.gradients != 0u {
        let axis = cross(rec.n.xyz, n);
        e = e + vec3<f32>(dot(axis, rec.gr[0].xyz), dot(axis, rec.gr[1].xyz), dot(axis, rec.gr[2].xyz));
    }
    if params.gradients == 2u {
        let d = p - rec.p_r.xyz;
        e = e + vec3<f32>(dot(d, rec.gt[0].xyz), dot(d, rec.gt[1].xyz), dot(d, rec.gt[2].xyz));
    }
    return e;
}

// A tile's records pass through workgroup memory in chunks of 64 (11 KB: within every device's
// 16 KB), loaded by the first 64 invocations: every sample of the tile reads every record of its
// list, so each is read from global memory once per tile instead of once per sample.
const CHUNK: u32 = 64u;
var<workgroup> chunk: array<Record, CHUNK>;

@compute @workgroup_size(16, 16, 1)
fn splat(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let t = group.y * GROUPS_X + group.x;
    // Uniform across the workgroup: the barriers below see all of it or none.
    if t >= params.tile_count {
        return;
    }
    let tile = tiles[t];
    let x = (tile % params.tiles_x) * TILE + lid.x;
    let y = (tile / params.tiles_x) * TILE + lid.y;
    // Every invocation stays to the end: the barriers need the whole workgroup.
    let inside = x < params.width && y < params.height;
    let slot = t * TILE * TILE + local;
    var s: Sample;
    if inside {
        s = samples[y * params.width + x];
    }
    var out = sums[slot];
    // Above threshold 1, as the lookup's fallback: only samples no record served so far.
    let served = inside && s.p.w != 0.0 && (params.threshold <= 1.0 || out.irradiance.w == 0.0);
    let first = tile_start[t];
    let end = tile_start[t + 1u];
    for (var base = first; base < end; base = base + CHUNK) {
        workgroupBarrier();
        if local < CHUNK && base + local < end {
            chunk[local] = records[tile_records[base + local]];
        }
        workgroupBarrier();
        if served {
            let count = min(CHUNK, end - base);
            for (var k = 0u; k < count; k = k + 1u) {
                let rec = chunk[k];
                let err = record_error(rec, s.p.xyz, s.n.xyz);
                if err < 0.0 || err > params.threshold {
                    continue;
                }
                let w = record_weight(err);
                out.irradiance = out.irradiance + vec4<f32>(extrapolate(rec, s.p.xyz, s.n_bump.xyz) * w, w);
                out.count = out.count + 1u;
                out.min_error = min(out.min_error, err);
            }
        }
    }
    if served {
        sums[slot] = out;
    }
}
