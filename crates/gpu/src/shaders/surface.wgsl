// What the whole frame (`frame.wgsl`) and the records from rasterised planes (`records.wgsl`)
// share, prepended to each: the scene's triangles, shapes and directional light as the GPU holds
// them, the hit of a ray on the triangle a rasteriser found for it, and the light's irradiance
// through the shadow map.

struct Triangle {
    p0: vec4<f32>, // w: the shape's index (bits)
    p1: vec4<f32>,
    p2: vec4<f32>,
    n0: vec4<f32>, // w: 1 where the mesh has vertex normals
    n1: vec4<f32>,
    n2: vec4<f32>,
}

struct Shape {
    front: vec4<f32>, // albedo seen from the front; w = 1 where the front is a record site
    back: vec4<f32>,
}

struct Light {
    to_clip: mat4x4<f32>,  // world to the shadow map's orthographic clip space
    to_light: vec4<f32>,   // unit direction towards the light
    irradiance: vec4<f32>,
    bias: vec4<f32>,       // x: a texel in depth units; y: the map's size in texels
}

struct SurfaceHit {
    p: vec3<f32>,
    n: vec3<f32>,  // the shading normal on the ray's side (`ShadingPoint::facing`)
    t: f32,        // the distance along the ray
    back: bool,    // the ray meets the triangle's back
    shape: u32,
}

const PI: f32 = 3.14159265358979;

// The ray (o, d) on `tri`'s plane: its hit, barycentric coordinates, and the shading normal
// interpolated from the vertices' (the geometric one without), turned to face the ray.
fn surface_hit(tri: Triangle, o: vec3<f32>, d: vec3<f32>) -> SurfaceHit {
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
    var hit: SurfaceHit;
    hit.p = p;
    hit.n = select(ns, -ns, back);
    hit.t = t;
    hit.back = back;
    hit.shape = bitcast<u32>(tri.p0.w);
    return hit;
}

// The light's irradiance at p on a surface of normal n, its visibility from the shadow map
// with a slope-scaled bias of a texel or more.
fn sun_irradiance(light: Light, shadow: texture_depth_2d, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let cosine = dot(n, light.to_light.xyz);
    if cosine <= 0.0 {
        return vec3<f32>(0.0);
    }
    let c = light.to_clip * vec4<f32>(p, 1.0);
    let uv = vec2<f32>(0.5 + 0.5 * c.x, 0.5 - 0.5 * c.y);
    var lit = 1.0;
    if all(uv >= vec2<f32>(0.0)) && all(uv < vec2<f32>(1.0)) {
        let stored = textureLoad(shadow, vec2<i32>(uv * light.bias.y), 0);
        let slope = sqrt(max(1.0 - cosine * cosine, 0.0)) / cosine;
        let bias = light.bias.x * (1.5 + min(slope, 16.0));
        lit = select(0.0, 1.0, c.z - bias <= stored);
    }
    return light.irradiance.xyz * cosine * lit;
}
