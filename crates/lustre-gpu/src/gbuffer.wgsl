// The raster G-buffer pass (issue 11 §1): every triangle of the scene drawn from a storage
// buffer (vertex pulling, 3 vertices per triangle, no culling), depth-tested with reverse Z
// (infinite far plane, depth = near / view z, compare Greater, cleared to 0). The projection
// puts NDC x = 2 X / W − 1, y = 1 − 2 Y / H at the CPU camera's image position (X, Y), so the
// raster's pixel centres are the rays of `PathCamera::direction(X + ½, Y + ½, W, H)`.
// Writes the triangle id, the perspective-correct barycentrics (b1, b2) with the view depth, and
// the interpolated shading normal.

struct Camera {
    origin: vec4<f32>,
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // x: tan(fov_y / 2), y: aspect W / H, z: near plane (view depth), w: unused.
    params: vec4<f32>,
};

// Per triangle 6 vec4: positions (xyz) of corners 0..2, then shading normals of corners 0..2.
@group(0) @binding(0) var<storage, read> tris: array<vec4<f32>>;
@group(0) @binding(1) var<uniform> cam: Camera;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) prim: u32,
    @location(1) bary: vec2<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) depth: f32,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VsOut {
    let prim = vi / 3u;
    let corner = vi % 3u;
    let p = tris[prim * 6u + corner].xyz - cam.origin.xyz;
    let x = dot(p, cam.right.xyz);
    let y = dot(p, cam.up.xyz);
    let z = dot(p, cam.forward.xyz);
    let a = cam.params.x;
    var out: VsOut;
    out.clip = vec4<f32>(x / (a * cam.params.y), y / a, cam.params.z, z);
    out.prim = prim;
    var b = vec2<f32>(0.0, 0.0);
    if corner == 1u {
        b = vec2<f32>(1.0, 0.0);
    } else if corner == 2u {
        b = vec2<f32>(0.0, 1.0);
    }
    out.bary = b;
    out.normal = tris[prim * 6u + 3u + corner].xyz;
    out.depth = z;
    return out;
}

struct FsOut {
    @location(0) prim: u32,
    @location(1) bary_depth: vec4<f32>,
    @location(2) normal: vec4<f32>,
};

@fragment
fn fs_main(v: VsOut) -> FsOut {
    var out: FsOut;
    out.prim = v.prim;
    out.bary_depth = vec4<f32>(v.bary, v.depth, 0.0);
    let l = length(v.normal);
    var n = vec3<f32>(0.0, 0.0, 0.0);
    if l > 0.0 {
        n = v.normal / l;
    }
    out.normal = vec4<f32>(n, 0.0);
    return out;
}
