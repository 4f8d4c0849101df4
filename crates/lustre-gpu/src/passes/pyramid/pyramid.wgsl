// One down-sampling step of a cube-map pyramid (002 §3, Table 1): child texel (i, j) of face f
// is the solid-angle-weighted mean of the parent's taps 2i+off .. 2i+off+len−1 (and the same in
// j) with the separable kernel `weights`. Taps beyond a face edge read the texels that
// `lustre_env::cube::fetch_sources` names (the neighbouring face, or the average of the three
// texels meeting beyond a corner), uploaded as `ring`. The GPU twin of
// `lustre_env::pyramid::CubePyramid::build`'s `downsample`.

struct Params {
    // Parent face size N.
    parent_size: u32,
    // Child face size max(1, N / 2).
    child_size: u32,
    // Kernel length (2, 4 or 6) and the offset of its first tap relative to 2i.
    taps: u32,
    first: i32,
};

// Texels the ring holds outside each face edge.
const MARGIN: i32 = 2;

@group(0) @binding(0) var<uniform> params: Params;
// Parent texels, face-major then row-major (rgb, w unused).
@group(0) @binding(1) var<storage, read> parent: array<vec4<f32>>;
// Exact solid angle of parent texel (i, j), the same on every face.
@group(0) @binding(2) var<storage, read> omega: array<f32>;
// Per face, per ring position (see `ring_index`): up to three parent texel indices and their
// count in w.
@group(0) @binding(3) var<storage, read> ring: array<vec4<i32>>;
// The 1-D kernel weights.
@group(0) @binding(4) var<storage, read> weights: array<f32>;
@group(0) @binding(5) var<storage, read_write> child: array<vec4<f32>>;

// Position of tap (i, j), outside the face but within MARGIN of it, in the ring of one face:
// the MARGIN rows above (j < 0) and below (j ≥ N), each N + 2·MARGIN wide, then the MARGIN
// columns left (i < 0) and right (i ≥ N) of the N rows in between.
fn ring_index(i: i32, j: i32, n: i32) -> i32 {
    let e = n + 2 * MARGIN;
    if j < 0 {
        return (j + MARGIN) * e + (i + MARGIN);
    }
    if j >= n {
        return (MARGIN + (j - n)) * e + (i + MARGIN);
    }
    let sides = 2 * MARGIN * e;
    if i < 0 {
        return sides + j * MARGIN + (i + MARGIN);
    }
    return sides + n * MARGIN + j * MARGIN + (i - n);
}

fn ring_size(n: i32) -> i32 {
    return 2 * MARGIN * (n + 2 * MARGIN) + 2 * n * MARGIN;
}

// Index of a parent texel k rows/columns beyond an edge in the solid-angle table (the table
// is symmetric under the face's flips and transposition).
fn mirror(i: i32, n: i32) -> i32 {
    var m = i;
    if i < 0 {
        m = -i - 1;
    } else if i >= n {
        m = i - n;
    }
    return clamp(m, 0, n - 1);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = params.child_size;
    if gid.x >= size || gid.y >= size || gid.z >= 6u {
        return;
    }
    let n = i32(params.parent_size);
    let face = i32(gid.z);
    let bi = 2 * i32(gid.x) + params.first;
    let bj = 2 * i32(gid.y) + params.first;
    var acc = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var b = 0u; b < params.taps; b++) {
        let jj = bj + i32(b);
        for (var a = 0u; a < params.taps; a++) {
            let ii = bi + i32(a);
            var v: vec3<f32>;
            if ii >= 0 && ii < n && jj >= 0 && jj < n {
                v = parent[(face * n + jj) * n + ii].xyz;
            } else {
                let s = ring[face * ring_size(n) + ring_index(ii, jj, n)];
                if s.w == 1 {
                    v = parent[s.x].xyz;
                } else {
                    v = (parent[s.x].xyz + parent[s.y].xyz + parent[s.z].xyz) / 3.0;
                }
            }
            let k = weights[a] * weights[b] * omega[mirror(jj, n) * n + mirror(ii, n)];
            wsum += k;
            acc += k * v;
        }
    }
    child[(face * i32(size) + i32(gid.y)) * i32(size) + i32(gid.x)] = vec4<f32>(acc / wsum, 1.0);
}
