// One level of a view buffer's radiance pyramid (`lustre_shade::mirror::box_levels`): texel
// (x, y) of the child is the mean of the parent's texels (2x + a, 2y + b), a, b ∈ {0, 1}, that
// exist (odd sizes: the last column/row averages 2 or 1). Parent and child are regions of one
// buffer (all levels concatenated, finest first, row-major, (rgb, 1)).

struct Params {
    // Parent width, height, child width, height.
    size: vec4<u32>,
    // First texel of the parent, of the child.
    offset: vec4<u32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> radiance: array<vec4<f32>>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let pw = params.size.x;
    let ph = params.size.y;
    let cw = params.size.z;
    let ch = params.size.w;
    if gid.x >= cw || gid.y >= ch {
        return;
    }
    var sum = vec3<f32>(0.0);
    var k = 0.0;
    for (var b = 0u; b < 2u; b++) {
        for (var a = 0u; a < 2u; a++) {
            let sx = 2u * gid.x + a;
            let sy = 2u * gid.y + b;
            if sx < pw && sy < ph {
                sum += radiance[params.offset.x + sy * pw + sx].xyz;
                k += 1.0;
            }
        }
    }
    radiance[params.offset.y + gid.y * cw + gid.x] = vec4<f32>(sum / k, 1.0);
}
