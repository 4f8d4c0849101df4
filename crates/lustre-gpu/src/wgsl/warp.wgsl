// module warp: regular sampling through a model's own sampling warp, here the rough
// conductor's (microfacet.wgsl, unit Fresnel). CPU twins: lustre_shade::warp::{fibonacci_point,
// shade_regular_warp}. Equations: the Fibonacci lattice u_i = ((i + ½)/n, frac(½ + i/φ)) (the
// second coordinate on the 2⁻²⁴ grid, as the CPU computes it);
// ωi = warp(u_i) with density p; Ω = 1/(n p) read at the footprint level ½ log2(Ω/Ωp(ωi)) − ½
// (mip.wgsl); estimate (1/n) Σ L(ωi) f cos θi / p (000 Eq. 4.4).

// 1/φ, the golden-ratio step, on the 2⁻²⁴ grid: round(2²⁴/φ).
const INV_GOLDEN_24: u32 = 10368890u;

// warp::fibonacci_point: point i of the n-point Fibonacci lattice in [0, 1)².
fn fibonacci_point(i: u32, n: u32) -> vec2<f32> {
    let v = (i * INV_GOLDEN_24 + 0x800000u) & 0xffffffu;
    return vec2<f32>((f32(i) + 0.5) / f32(max(n, 1u)), f32(v) * (1.0 / 16777216.0));
}

// warp::shade_regular_warp for the rough conductor with unit Fresnel and reflectance: `budget`
// Fibonacci points through microfacet_sample from ωo = wo_l (local to the frame t, b, n), each
// read from `env` at the footprint level of 1/(budget p), weighted f cos θi / p; failed samples
// count as zero.
fn regular_warp_microfacet(mf: Microfacet, wo_l: vec3<f32>, t: vec3<f32>, b: vec3<f32>,
                           n: vec3<f32>, budget: u32, env: texture_cube<f32>,
                           env_sampler: sampler, face: f32, max_lod: f32) -> vec3<f32> {
    if (budget == 0u) {
        return vec3<f32>(0.0);
    }
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < budget; i++) {
        let u = fibonacci_point(i, budget);
        let s = microfacet_sample(mf, wo_l, u.x, u.y);
        if (s.w == 0.0) {
            continue;
        }
        let weight = microfacet_eval(mf, s.xyz, wo_l) * s.z / s.w;
        let wi = to_world(s.xyz, t, b, n);
        let level = min(footprint_level(1.0 / (f32(budget) * s.w), wi, face), max_lod);
        sum += textureSampleLevel(env, env_sampler, wi, level).rgb * weight;
    }
    return sum / f32(budget);
}
