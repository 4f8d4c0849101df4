// module qmc: the low-discrepancy points and per-pixel seeds of progressive refinement
// (000 §4.4.2). CPU twins: lustre_shade::integrator::{sobol02, pixel_seed, Progressive::new},
// lustre_brdf::sampling::{radical_inverse2, SplitMix64}. Equations: the Sobol' (0,2)-sequence,
// x_i = the base-2 radical inverse of i, y_i = the second Sobol' dimension (generator matrix =
// Pascal's triangle mod 2); SplitMix64 (Steele et al. 2014): s += 0x9E3779B97F4A7C15,
// z = (s ^ s>>30)·0xBF58476D1CE4E5B9, z = (z ^ z>>27)·0x94D049BB133111EB, out = z ^ z>>31;
// pixel seed = the first output of SplitMix64(seed ^ (x << 32 | y)).
//
// WGSL has no 64-bit integers: a u64 is vec2<u32>(low word, high word). Points in [0, 1) are
// the top 24 bits of the CPU's 32 (or 53) bits, so f32 values are the CPU's rounded down to
// 2⁻²⁴ and never reach 1.

// sobol02 as integers: (x, y) · 2⁻³² is lustre_shade::integrator::sobol02(i) exactly.
fn sobol02_bits(i: u32) -> vec2<u32> {
    var r = 0u;
    var v = 1u << 31u;
    var k = i;
    while (k != 0u) {
        if ((k & 1u) != 0u) {
            r ^= v;
        }
        k >>= 1u;
        v ^= v >> 1u;
    }
    return vec2<u32>(reverseBits(i), r);
}

// The i-th point of the Sobol' (0,2)-sequence, truncated to 24 bits.
fn sobol02(i: u32) -> vec2<f32> {
    return vec2<f32>(sobol02_bits(i) >> vec2<u32>(8u)) * (1.0 / 16777216.0);
}

// 64-bit arithmetic on (low, high) words, wrapping like Rust's wrapping_add / wrapping_mul.
fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

// The full 64-bit product of two 32-bit words, by 16-bit halves.
fn mul32_wide(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return vec2<u32>((p00 & 0xffffu) | (mid << 16u),
                     p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let low = mul32_wide(a.x, b.x);
    return vec2<u32>(low.x, low.y + a.x * b.y + a.y * b.x);
}

// a >> s for 0 < s < 32.
fn shr64(a: vec2<u32>, s: u32) -> vec2<u32> {
    return vec2<u32>((a.x >> s) | (a.y << (32u - s)), a.y >> s);
}

// SplitMix64::next_u64: advances the state and returns the next 64 bits.
fn splitmix64_next(state: ptr<function, vec2<u32>>) -> vec2<u32> {
    *state = add64(*state, vec2<u32>(0x7F4A7C15u, 0x9E3779B9u));
    var z = *state;
    z = mul64(z ^ shr64(z, 30u), vec2<u32>(0x1CE4E5B9u, 0xBF58476Du));
    z = mul64(z ^ shr64(z, 27u), vec2<u32>(0x133111EBu, 0x94D049BBu));
    return z ^ shr64(z, 31u);
}

// integrator::pixel_seed: SplitMix64(seed ^ (x << 32 | y)).next_u64().
fn pixel_seed(x: u32, y: u32, seed: vec2<u32>) -> vec2<u32> {
    var state = seed ^ vec2<u32>(y, x);
    return splitmix64_next(&state);
}

// Progressive::new's Cranley–Patterson rotation: two SplitMix64(seed) draws in [0, 1)
// (SplitMix64::next_f64 keeps 53 bits; here the top 24).
fn qmc_rotation(seed: vec2<u32>) -> vec2<f32> {
    var state = seed;
    let a = splitmix64_next(&state);
    let b = splitmix64_next(&state);
    return vec2<f32>(f32(a.y >> 8u), f32(b.y >> 8u)) * (1.0 / 16777216.0);
}

// Progressive::add_samples' point i: the Sobol' point shifted by the rotation, modulo 1.
fn qmc_point(i: u32, rotation: vec2<f32>) -> vec2<f32> {
    return fract(sobol02(i) + rotation);
}
