// The bandwidth buffer's pyramids (004 §IV.4.1; CPU twin: the loop of
// lustre_adaptive::buffer::BandwidthBuffer::assemble): level k's entry for a block of 2^k × 2^k
// pixels is the min of the level ℓ and the max of the variance quota over the four level-(k−1)
// entries under it (those inside the image). Level 0 holds the pixels' own values.

struct Params {
    width: u32,
    height: u32,
    level: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> min_level: array<u32>;
@group(0) @binding(2) var<storage, read_write> max_quota: array<f32>;

// (first entry, blocks per row, rows) of level k.
fn level_layout(k: u32) -> vec3<u32> {
    var offset = 0u;
    for (var m = 0u; m < k; m++) {
        let s = 1u << m;
        offset += ((params.width + s - 1u) / s) * ((params.height + s - 1u) / s);
    }
    let s = 1u << k;
    return vec3<u32>(offset, (params.width + s - 1u) / s, (params.height + s - 1u) / s);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let here = level_layout(params.level);
    if (gid.x >= here.y || gid.y >= here.z) {
        return;
    }
    let below = level_layout(params.level - 1u);
    var l = 255u;
    var q = 0.0;
    for (var c = 0u; c < 4u; c++) {
        let x = 2u * gid.x + (c & 1u);
        let y = 2u * gid.y + (c >> 1u);
        if (x < below.y && y < below.z) {
            let i = below.x + y * below.y + x;
            l = min(l, min_level[i]);
            q = max(q, max_quota[i]);
        }
    }
    let o = here.x + gid.y * here.y + gid.x;
    min_level[o] = l;
    max_quota[o] = q;
}
