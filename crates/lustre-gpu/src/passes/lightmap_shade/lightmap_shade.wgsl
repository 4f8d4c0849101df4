// Light-mapped diffuse shading of a G-buffer (000 Eq. 4.1): the twin of
// `lustre_trace::bake::gbuffer::shade_gbuffer`, i.e. of `Lightmapped::radiance` per G-buffer
// pixel and `EnvLight::eval` for sky pixels, in f32. One thread per output pixel averages its
// k×k G-buffer pixels (box filter). All filtering is by hand with textureLoad so that the
// texel-centre, clamp and wrap conventions are the CPU's exactly.

struct Shade {
    origin: vec4<f32>,
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // x: tan(fov_y / 2), y: aspect of the G-buffer (W / H).
    params: vec4<f32>,
    // G-buffer width, height, k, 1 when there is an environment.
    sizes: vec4<u32>,
    // Light-map page width, height; z: the first output texel (the image is written at
    // out_px[z + y·w + x], e.g. one face of a cube's base level).
    page: vec4<u32>,
    // Rows of the world → map rotation (the transpose of the environment's to_world).
    env_row0: vec4<f32>,
    env_row1: vec4<f32>,
    env_row2: vec4<f32>,
    // x: environment scale.
    env: vec4<f32>,
};

@group(0) @binding(0) var<uniform> u: Shade;
@group(0) @binding(1) var prim_tex: texture_2d<u32>;
@group(0) @binding(2) var bary_tex: texture_2d<f32>;
// 8 vec4 per triangle: shading normals of corners 0..2; uv0 (a.xy, b.xy), (c.xy, uv1 a.xy);
// uv1 (b.xy, c.xy) in texel units; (emission rgb, page bits); (material bits, 0, 0, 0).
@group(0) @binding(3) var<storage, read> tris: array<vec4<f32>>;
// 4 vec4 per material: (base factor rgb, scale k); (base texture slot bits (i32, −1 none), uv set
// bits, two-sided, 1 when metallic or transmission is textured); metallic and transmission as
// (factor, texture slot bits, uv set bits, channel bits).
@group(0) @binding(4) var<storage, read> mats: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> texels: array<vec4<f32>>;
// Per texture: (first texel, width, height, 0).
@group(0) @binding(6) var<storage, read> tex_info: array<vec4<u32>>;

// texture_sample.wgsl's texels and per-texture records.
fn texture_texel(i: u32) -> vec4<f32> {
    return texels[i];
}

fn texture_info(t: u32) -> vec4<u32> {
    return tex_info[t];
}

// material_albedo.wgsl's material rows.
fn material_row(i: u32) -> vec4<f32> {
    return mats[i];
}
@group(0) @binding(7) var pages: texture_2d_array<f32>;
@group(0) @binding(8) var env_tex: texture_2d<f32>;
@group(0) @binding(9) var<storage, read_write> out_px: array<vec4<f32>>;

const PI: f32 = 3.14159265358979323846;
const SKY: u32 = 0xffffffffu;
const NO_PAGE: u32 = 0xffffffffu;

// `lustre_trace::bake::render::bilinear`: texel centres at (x + ½, y + ½), clamped at the border.
fn page_bilinear(page: u32, x: f32, y: f32) -> vec3<f32> {
    let w = u.page.x;
    let h = u.page.y;
    let fx = clamp(x - 0.5, 0.0, f32(w - 1u));
    let fy = clamp(y - 0.5, 0.0, f32(h - 1u));
    let x0 = u32(floor(fx));
    let y0 = u32(floor(fy));
    let x1 = min(x0 + 1u, w - 1u);
    let y1 = min(y0 + 1u, h - 1u);
    let tx = fx - f32(x0);
    let ty = fy - f32(y0);
    let l = i32(page);
    let a = textureLoad(pages, vec2<i32>(i32(x0), i32(y0)), l, 0).xyz;
    let b = textureLoad(pages, vec2<i32>(i32(x1), i32(y0)), l, 0).xyz;
    let c = textureLoad(pages, vec2<i32>(i32(x0), i32(y1)), l, 0).xyz;
    let e = textureLoad(pages, vec2<i32>(i32(x1), i32(y1)), l, 0).xyz;
    return (a * (1.0 - tx) + b * tx) * (1.0 - ty) + (c * (1.0 - tx) + e * tx) * ty;
}

fn finite3(c: vec3<f32>) -> bool {
    return all(abs(c) <= vec3<f32>(3.0e38));
}

// `Lightmapped::radiance`.
fn radiance(prim: u32, b: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let base = prim * 8u;
    let ns = tris[base].xyz * b.x + tris[base + 1u].xyz * b.y + tris[base + 2u].xyz * b.z;
    let front = dot(ns, -d) > 0.0;
    let e = tris[base + 6u];
    var l = vec3<f32>(0.0);
    if front {
        l = e.xyz;
    }
    let page = bitcast<u32>(e.w);
    if page != NO_PAGE {
        let q4 = tris[base + 4u];
        let q5 = tris[base + 5u];
        let uv1 = q4.zw * b.x + q5.xy * b.y + q5.zw * b.z;
        let irr = page_bilinear(page, uv1.x, uv1.y);
        let q3 = tris[base + 3u];
        let uv0 = q3.xy * b.x + q3.zw * b.y + q4.xy * b.z;
        let m = bitcast<u32>(tris[base + 7u].x);
        let two_sided = mats[4u * m + 1u].z > 0.5;
        if front || two_sided {
            let kd = albedo(m, uv0, uv1 / vec2<f32>(f32(u.page.x), f32(u.page.y)));
            l += kd * irr * (1.0 / PI);
        }
    }
    return l;
}

// atan(x) for x in [0, 1] (Cephes atanf: range reduction at tan(π/8), relative error ≈ 2e-7).
// The built-in atan2/acos may be far less accurate (Vulkan allows 4096 ULP; lavapipe's are off by
// ≈ 1e-4 rad, a tenth of a texel of a 1k map).
fn atan_unit(x: f32) -> f32 {
    var y = 0.0;
    var t = x;
    if x > 0.41421356237 {
        y = PI / 4.0;
        t = (x - 1.0) / (x + 1.0);
    }
    let z = t * t;
    return y + ((((0.0805374449538 * z - 0.138776856032) * z + 0.199777106478) * z
        - 0.333329491539) * z * t + t);
}

// atan2(y, x) from `atan_unit`.
fn atan2_accurate(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    let hi = max(ax, ay);
    if hi == 0.0 {
        return 0.0;
    }
    var a = atan_unit(min(ax, ay) / hi);
    if ay > ax {
        a = PI / 2.0 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    if y < 0.0 {
        a = -a;
    }
    return a;
}

// `EquirectMap::lookup_bilinear` of the map direction, times the scale (`EnvLight::eval`).
fn environment(d: vec3<f32>) -> vec3<f32> {
    if u.sizes.w == 0u {
        return vec3<f32>(0.0);
    }
    var m = vec3<f32>(dot(u.env_row0.xyz, d), dot(u.env_row1.xyz, d), dot(u.env_row2.xyz, d));
    let len = length(m);
    if len > 0.0 && len < 3.0e38 {
        m = m / len;
    } else {
        m = vec3<f32>(0.0, 1.0, 0.0);
    }
    let dims = textureDimensions(env_tex);
    let w = i32(dims.x);
    let h = i32(dims.y);
    let phi = atan2_accurate(m.x, -m.z);
    let uu = 0.5 + phi / (2.0 * PI);
    // acos(m.y) for the unit m, without the cancellation of √(1 − y²) near the poles.
    let vv = atan2_accurate(sqrt(m.x * m.x + m.z * m.z), m.y) / PI;
    let x = uu * f32(w) - 0.5;
    let y = clamp(vv * f32(h) - 0.5, 0.0, f32(h - 1));
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let xa = ((i32(x0) % w) + w) % w;
    let xb = ((i32(x0) + 1) % w + w) % w;
    let ya = i32(y0);
    let yb = min(ya + 1, h - 1);
    let a = textureLoad(env_tex, vec2<i32>(xa, ya), 0).xyz;
    let b = textureLoad(env_tex, vec2<i32>(xb, ya), 0).xyz;
    let c = textureLoad(env_tex, vec2<i32>(xa, yb), 0).xyz;
    let e = textureLoad(env_tex, vec2<i32>(xb, yb), 0).xyz;
    let v = (1.0 - fy) * ((1.0 - fx) * a + fx * b) + fy * ((1.0 - fx) * c + fx * e);
    return v * u.env.x;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = u.sizes.z;
    let w = u.sizes.x / k;
    let h = u.sizes.y / k;
    if gid.x >= w || gid.y >= h {
        return;
    }
    let gw = f32(u.sizes.x);
    let gh = f32(u.sizes.y);
    let a = u.params.x;
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < k; j++) {
        for (var s = 0u; s < k; s++) {
            let gx = gid.x * k + s;
            let gy = gid.y * k + j;
            // `PathCamera::direction(gx + ½, gy + ½, gw, gh)`.
            let px = (2.0 * (f32(gx) + 0.5) / gw - 1.0) * a * u.params.y;
            let py = (1.0 - 2.0 * (f32(gy) + 0.5) / gh) * a;
            let d = normalize(u.forward.xyz + px * u.right.xyz + py * u.up.xyz);
            let p = textureLoad(prim_tex, vec2<i32>(i32(gx), i32(gy)), 0).x;
            var c: vec3<f32>;
            if p == SKY {
                c = environment(d);
            } else {
                let bd = textureLoad(bary_tex, vec2<i32>(i32(gx), i32(gy)), 0);
                c = radiance(p, vec3<f32>(1.0 - bd.x - bd.y, bd.x, bd.y), d);
            }
            if finite3(c) {
                sum += c;
            }
        }
    }
    out_px[u.page.z + gid.y * w + gid.x] = vec4<f32>(sum / f32(k * k), 1.0);
}
