// The geometry of a view buffer (000 §4.5.1; `lustre_shade::mirror::ViewBuffer`'s texels): per
// level-0 texel of the G-buffer, (world position, 1) and (unit geometric normal, 0) of the
// surface it shows, or two zero vectors where it shows the environment. The position is the
// triangle's corners interpolated with the G-buffer's barycentrics (the CPU's o + t·d), the
// normal the normalised cross product of its edges, as `render_view` computes them.

struct Params {
    // Width, height.
    size: vec4<u32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var prim_tex: texture_2d<u32>;
@group(0) @binding(2) var bary_tex: texture_2d<f32>;
// The G-buffer pass's triangles: 8 vec4 each, corner positions first.
@group(0) @binding(3) var<storage, read> tris: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> geometry: array<vec4<f32>>;

const SKY: u32 = 0xffffffffu;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = params.size.x;
    let h = params.size.y;
    if gid.x >= w || gid.y >= h {
        return;
    }
    let i = gid.y * w + gid.x;
    let p = textureLoad(prim_tex, vec2<i32>(i32(gid.x), i32(gid.y)), 0).x;
    if p == SKY {
        geometry[2u * i] = vec4<f32>(0.0);
        geometry[2u * i + 1u] = vec4<f32>(0.0);
        return;
    }
    let b = textureLoad(bary_tex, vec2<i32>(i32(gid.x), i32(gid.y)), 0).xy;
    let p0 = tris[8u * p].xyz;
    let p1 = tris[8u * p + 1u].xyz;
    let p2 = tris[8u * p + 2u].xyz;
    let x = p0 * (1.0 - b.x - b.y) + p1 * b.x + p2 * b.y;
    let c = cross(p1 - p0, p2 - p0);
    let l = length(c);
    var n = vec3<f32>(0.0);
    if l > 0.0 {
        n = c / l;
    }
    geometry[2u * i] = vec4<f32>(x, 1.0);
    geometry[2u * i + 1u] = vec4<f32>(n, 0.0);
}
