// module cube_storage: cube-map pyramids held in storage buffers (lustre_env::cube::face_coords,
// CubeMap::{fetch, bilinear}, CubePyramid::sample). A pass defines `cube_texel(i: u32) ->
// vec3<f32>` (every level's texels, face-major, row-major), `cube_level(i: u32) -> vec4<u32>`
// (per level: first texel, face size, first ring entry, 0) and `cube_ring(i: u32) -> vec4<i32>`
// (per level and face, the 4(n + 1) texels one texel beyond the edges, in `ring_index` order:
// up to three global texel indices and their count; lustre-gpu's cube_storage::ring_entries).
// Requires (the pass defines): fn cube_texel(i: u32) -> vec3<f32>.
// Requires (the pass defines): fn cube_level(i: u32) -> vec4<u32>.
// Requires (the pass defines): fn cube_ring(i: u32) -> vec4<i32>.

// lustre_env::cube::face_coords: (face, s, t).
fn face_coords(d: vec3<f32>) -> vec3<f32> {
    let a = abs(d);
    if (a.x == 0.0 && a.y == 0.0 && a.z == 0.0) {
        return vec3<f32>(0.0, 0.5, 0.5);
    }
    var face: f32;
    var sc: f32;
    var tc: f32;
    var ma: f32;
    if (a.x >= a.y && a.x >= a.z) {
        ma = a.x;
        tc = -d.y;
        if (d.x > 0.0) {
            face = 0.0;
            sc = -d.z;
        } else {
            face = 1.0;
            sc = d.z;
        }
    } else if (a.y >= a.z) {
        ma = a.y;
        sc = d.x;
        if (d.y > 0.0) {
            face = 2.0;
            tc = d.z;
        } else {
            face = 3.0;
            tc = -d.z;
        }
    } else {
        ma = a.z;
        tc = -d.y;
        if (d.z > 0.0) {
            face = 4.0;
            sc = d.x;
        } else {
            face = 5.0;
            sc = -d.x;
        }
    }
    return vec3<f32>(face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0));
}

// Position of (i, j), one texel outside a face of size n, in the face's ring: the row above
// (n + 2 wide), the row below, then the left and right columns of the n rows.
fn ring_index(i: i32, j: i32, n: i32) -> i32 {
    if (j < 0) {
        return i + 1;
    }
    if (j >= n) {
        return (n + 2) + i + 1;
    }
    if (i < 0) {
        return 2 * (n + 2) + j;
    }
    return 2 * (n + 2) + n + j;
}

// CubeMap::fetch on one level: the texel, or across the edge (a corner averages three).
fn cube_fetch(level: vec4<u32>, face: i32, i: i32, j: i32) -> vec3<f32> {
    let n = i32(level.y);
    if (i >= 0 && j >= 0 && i < n && j < n) {
        return cube_texel(level.x + u32((face * n + j) * n + i));
    }
    let r = cube_ring(level.z + u32(face * 4 * (n + 1) + ring_index(i, j, n)));
    if (r.w == 1) {
        return cube_texel(u32(r.x));
    }
    return (cube_texel(u32(r.x)) + cube_texel(u32(r.y)) + cube_texel(u32(r.z))) / 3.0;
}

// CubeMap::bilinear.
fn cube_bilinear(level: vec4<u32>, d: vec3<f32>) -> vec3<f32> {
    let fc = face_coords(d);
    let face = i32(fc.x);
    let n = f32(level.y);
    let uu = fc.y * n - 0.5;
    let vv = fc.z * n - 0.5;
    let i0f = floor(uu);
    let j0f = floor(vv);
    let fu = uu - i0f;
    let fv = vv - j0f;
    let i0 = i32(i0f);
    let j0 = i32(j0f);
    // The four texels (i0 + di, j0 + dj), di = q & 1, dj = q >> 1, from one call site: a
    // compiler that inlines every call (SwiftShader, a browser's software WebGPU) did not
    // finish compiling the walkthrough's sampling pass with four.
    var t: array<vec3<f32>, 4>;
    for (var q = 0; q < 4; q++) {
        t[q] = cube_fetch(level, face, i0 + (q & 1), j0 + (q >> 1u));
    }
    return (1.0 - fv) * ((1.0 - fu) * t[0] + fu * t[1]) + fv * ((1.0 - fu) * t[2] + fu * t[3]);
}

// CubePyramid::sample over the `count` levels from level record `first`: trilinear between
// levels ⌊lod⌋ and ⌈lod⌉ (lod clamped; NaN reads level 0).
fn cube_trilinear(first: u32, count: u32, d: vec3<f32>, lod_in: f32) -> vec3<f32> {
    let top = f32(count - 1u);
    var lod = 0.0;
    if (lod_in == lod_in) {
        lod = clamp(lod_in, 0.0, top);
    }
    let l0f = floor(lod);
    let f = lod - l0f;
    let l0 = u32(l0f);
    let a = cube_bilinear(cube_level(first + l0), d);
    if (f == 0.0) {
        return a;
    }
    let b = cube_bilinear(cube_level(first + min(l0 + 1u, count - 1u)), d);
    return (1.0 - f) * a + f * b;
}
