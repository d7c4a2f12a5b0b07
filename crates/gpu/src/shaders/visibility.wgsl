// Visibility by rasterisation (paper 001 §4.4.2): the scene's triangles seen through one view,
// each pixel keeping the nearest triangle's index + 1 (0: nothing), so that a record's plane of
// pixels (irradiance_cache::plane) is filled by rasterising instead of one ray per pixel.

// Column-major world-to-clip matrices, one per view; the instance index selects it (each view
// drawn into its own viewport of an atlas).
@group(0) @binding(0) var<storage, read> views: array<mat4x4<f32>>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) triangle: u32,
}

@vertex
fn vertex(
    @location(0) position: vec3<f32>,
    @location(1) triangle: u32,
    @builtin(instance_index) view: u32,
) -> VertexOut {
    var out: VertexOut;
    out.clip = views[view] * vec4<f32>(position, 1.0);
    out.triangle = triangle;
    return out;
}

@fragment
fn fragment(in: VertexOut) -> @location(0) u32 {
    return in.triangle + 1u;
}
