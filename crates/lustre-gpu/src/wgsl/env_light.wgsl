// module env_light: a distant environment light (lustre_trace::path::EnvLight): the bilinear
// radiance of an equirect map (lustre_env::EquirectMap::lookup_bilinear), its importance
// sampling by texels (lustre_env::sampling::EnvSampler: a row by the marginal, a texel by the
// row's conditional, then uniform in solid angle inside it) and that sampling's density. All in
// the map's frame (+y up, u = ½ + atan2(x, −z) / 2π, v = acos(y) / π).
//
// A pass defines `env_texel(i: u32) -> vec3<f32>` (texel i = y · width + x, RGB) and
// `env_table(i: u32) -> f32` (the words of lustre-gpu's env_light::pack_sampler: the rows'
// distribution at `rows`, then per row j the texels' at `cols + j (2 width + 1)`, then the rows'
// solid angles; a distribution of n cells is its n + 1 cumulative values, then the n
// probabilities, computed in f64).
// Requires (the pass defines): fn env_texel(i: u32) -> vec3<f32>.
// Requires (the pass defines): fn env_table(i: u32) -> f32.

struct EnvDims {
    width: u32,
    height: u32,
    rows: u32,
    cols: u32,
}

// (u, v) in [0, 1]² of a map direction.
fn equirect_uv(d: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(0.5 + atan2(d.x, -d.z) / (2.0 * PI), acos(clamp(d.y, -1.0, 1.0)) / PI);
}

// The unit direction of `d`, or +y when it has none.
fn env_unit(d: vec3<f32>) -> vec3<f32> {
    let len = length(d);
    if (!(len > 0.0 && len < 3.0e38)) {
        return vec3<f32>(0.0, 1.0, 0.0);
    }
    return d / len;
}

fn env_wrapped(dims: EnvDims, x: i32, y: i32) -> vec3<f32> {
    let w = i32(dims.width);
    let xi = ((x % w) + w) % w;
    return env_texel(u32(y) * dims.width + u32(xi));
}

// EquirectMap::lookup_bilinear: texel centres at half-integers, x wraps, y clamps.
fn env_bilinear(dims: EnvDims, d_in: vec3<f32>) -> vec3<f32> {
    let uv = equirect_uv(env_unit(d_in));
    let w = f32(dims.width);
    let h = f32(dims.height);
    let x = uv.x * w - 0.5;
    let y = clamp(uv.y * h - 0.5, 0.0, h - 1.0);
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let y1 = min(i32(y0) + 1, i32(dims.height) - 1);
    let a = env_wrapped(dims, i32(x0), i32(y0));
    let b = env_wrapped(dims, i32(x0) + 1, i32(y0));
    let c = env_wrapped(dims, i32(x0), y1);
    let e = env_wrapped(dims, i32(x0) + 1, y1);
    return (1.0 - fy) * ((1.0 - fx) * a + fx * b) + fy * ((1.0 - fx) * c + fx * e);
}

// Distribution1D::sample of the n-cell distribution at word `base`: (the cell, u rescaled to
// [0, 1) inside it).
fn env_pick(base: u32, n: u32, u: f32) -> vec2<f32> {
    // The number of cumulative values ≤ u; the cell is one less.
    var lo = 0u;
    var hi = n + 1u;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (env_table(base + mid) <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    let k = min(max(lo, 1u) - 1u, n - 1u);
    let a = env_table(base + k);
    let b = env_table(base + k + 1u);
    var r = 0.5;
    if (b > a) {
        r = (u - a) / (b - a);
    }
    return vec2<f32>(f32(k), clamp(r, 0.0, 0.99999994));
}

// EnvSampler::texel_probability(i, j) / Ω_j.
fn env_density(dims: EnvDims, i: u32, j: u32) -> f32 {
    let row = env_table(dims.rows + dims.height + 1u + j);
    let col = env_table(dims.cols + j * (2u * dims.width + 1u) + dims.width + 1u + i);
    let omega = env_table(dims.cols + dims.height * (2u * dims.width + 1u) + j);
    return row * col / omega;
}

// EnvSampler::sample: (the map direction, its solid-angle density).
fn env_sample(dims: EnvDims, u1: f32, u2: f32) -> vec4<f32> {
    let rj = env_pick(dims.rows, dims.height, u2);
    let j = u32(rj.x);
    let ci = env_pick(dims.cols + j * (2u * dims.width + 1u), dims.width, u1);
    let i = u32(ci.x);
    let h = f32(dims.height);
    let c0 = cos(PI * f32(j) / h);
    let c1 = cos(PI * f32(j + 1u) / h);
    let cos_t = clamp(c0 + rj.y * (c1 - c0), -1.0, 1.0);
    let sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    let phi = 2.0 * PI * ((f32(i) + ci.y) / f32(dims.width) - 0.5);
    let dir = vec3<f32>(sin_t * sin(phi), cos_t, -sin_t * cos(phi));
    return vec4<f32>(dir, env_density(dims, i, j));
}

// EnvSampler::pdf: the density of the texel holding `d` (EnvSampler::texel_of).
fn env_pdf(dims: EnvDims, d: vec3<f32>) -> f32 {
    let uv = equirect_uv(env_unit(d));
    let i = min(u32(max(uv.x, 0.0) * f32(dims.width)), dims.width - 1u);
    let j = min(u32(max(uv.y, 0.0) * f32(dims.height)), dims.height - 1u);
    return env_density(dims, i, j);
}
