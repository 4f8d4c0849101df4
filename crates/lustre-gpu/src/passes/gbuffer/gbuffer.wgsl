// The raster G-buffer pass: every triangle of the scene drawn from a storage
// buffer (vertex pulling, 3 vertices per triangle, no culling), depth-tested with reverse Z
// (infinite far plane, depth = near / view z, compare Greater, cleared to 0). The projection
// puts NDC x = 2 X / W − 1, y = 1 − 2 Y / H at the CPU camera's image position (X, Y), so the
// raster's pixel centres are the rays of `PathCamera::direction(X + ½, Y + ½, W, H)`.
// Writes the triangle id, the perspective-correct barycentrics (b1, b2) with the view depth, and
// the interpolated shading normal. Alpha-masked materials discard the fragments the CPU's ray
// test rejects (`PathTracer::intersect`: opacity at uv0 below the cutoff, or below ½ without one).
// `texture_sample.wgsl` is prepended.

struct Camera {
    origin: vec4<f32>,
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // x: tan(fov_y / 2), y: aspect W / H, z: near plane (view depth), w: unused.
    params: vec4<f32>,
    // Triangles [x, y) are left out (a probe's or a see-through object's mesh); x = y: none.
    // z = 1: triangles of transmitting materials are left out too (probes and view buffers
    // look through glass: lustre_shade::probe::LitScene::hit).
    skip: vec4<u32>,
    // The clip plane (unit normal xyz, offset w: s(p) = n·p + w) and (s(eye), tolerance, 0, 0):
    // a fragment with s(p) of the eye's sign but nearer the plane than the eye lies between the
    // eye and the plane along its ray and is discarded (the CPU mirror pass starts its rays on
    // the plane), and so is one within the tolerance of the plane (surfaces coplanar with the
    // reflector, which the CPU's rays starting on the plane do not see either). s(eye) = 0: no
    // clipping.
    plane: vec4<f32>,
    plane_eye: vec4<f32>,
};

// Per triangle 8 vec4: positions (xyz) of corners 0..2, shading normals of corners 0..2,
// (uv0 a.xy, b.xy), (uv0 c.xy, material bits, 0).
@group(0) @binding(0) var<storage, read> tris: array<vec4<f32>>;
@group(0) @binding(1) var<uniform> cam: Camera;
// Per material: (opacity factor, threshold, texture bits (i32: −2 not masked, −1 untextured),
// channel bits in 0..3 | 256 when the material transmits).
@group(0) @binding(2) var<storage, read> masks: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> texels: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> tex_info: array<vec4<u32>>;

// texture_sample.wgsl's texels and per-texture records.
fn texture_texel(i: u32) -> vec4<f32> {
    return texels[i];
}

fn texture_info(t: u32) -> vec4<u32> {
    return tex_info[t];
}

const STRIDE: u32 = 8u;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) prim: u32,
    @location(1) bary: vec2<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) depth: f32,
    @location(4) world: vec3<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VsOut {
    let prim = vi / 3u;
    let corner = vi % 3u;
    let world = tris[prim * STRIDE + corner].xyz;
    let p = world - cam.origin.xyz;
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
    out.normal = tris[prim * STRIDE + 3u + corner].xyz;
    out.depth = z;
    out.world = world;
    let glass = (bitcast<u32>(masks[bitcast<u32>(tris[prim * STRIDE + 7u].z)].w) & 256u) != 0u;
    if (prim >= cam.skip.x && prim < cam.skip.y) || (cam.skip.z != 0u && glass) {
        // A left-out triangle: all corners on one point outside the view, nothing rasterised.
        out.clip = vec4<f32>(-2.0, -2.0, 0.0, 1.0);
    }
    return out;
}

struct FsOut {
    @location(0) prim: u32,
    @location(1) bary_depth: vec4<f32>,
    @location(2) normal: vec4<f32>,
};

// Whether the CPU's alpha test keeps the point at barycentrics (1 − b1 − b2, b1, b2).
fn present(prim: u32, b: vec2<f32>) -> bool {
    let q = tris[prim * STRIDE + 7u];
    let mask = masks[bitcast<u32>(q.z)];
    let t = bitcast<i32>(mask.z);
    if t == -2 {
        return true;
    }
    var a = mask.x;
    if t >= 0 {
        let p = tris[prim * STRIDE + 6u];
        let uv = p.xy * (1.0 - b.x - b.y) + p.zw * b.x + q.xy * b.y;
        a = mask.x * texture_sample(u32(t), uv)[bitcast<u32>(mask.w) & 3u];
    }
    return clamp(a, 0.0, 1.0) >= mask.y;
}

fn write(v: VsOut) -> FsOut {
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

// Scenes without alpha masks: no discard, so the depth test may run before the shader.
@fragment
fn fs_main(v: VsOut) -> FsOut {
    return write(v);
}

// Scenes with alpha masks.
@fragment
fn fs_masked(v: VsOut) -> FsOut {
    if !present(v.prim, v.bary) {
        discard;
    }
    return write(v);
}

// Whether the point lies between the eye and the clip plane (see `Camera::plane`).
fn clipped(world: vec3<f32>) -> bool {
    let e = cam.plane_eye.x;
    if e == 0.0 {
        return false;
    }
    // The distance from the plane towards the eye's side.
    let s = sign(e) * (dot(cam.plane.xyz, world) + cam.plane.w);
    return s > -cam.plane_eye.y && s < abs(e);
}

// With a clip plane (mirror views), without alpha masks.
@fragment
fn fs_clip(v: VsOut) -> FsOut {
    if clipped(v.world) {
        discard;
    }
    return write(v);
}

// With a clip plane and alpha masks.
@fragment
fn fs_clip_masked(v: VsOut) -> FsOut {
    if clipped(v.world) || !present(v.prim, v.bary) {
        discard;
    }
    return write(v);
}
