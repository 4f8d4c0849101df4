// The BSDF models of the view-dependent pass evaluated on a list of cases, for their parity
// tests against lustre-brdf (lustre_gpu::material::harness::evaluate_models). Per case: in
// (ωo, record index bits), (ωi, 0), (u1, u2, 0, 0); out (eval rgb, pdf), (sampled ωi, pdf),
// (sampled value rgb, delta).

@group(0) @binding(0) var<storage, read> records: array<GpuBsdf>;
@group(0) @binding(1) var<storage, read> tables: array<f32>;
@group(0) @binding(2) var<storage, read> cases: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> results: array<vec4<f32>>;

fn bsdf_table(i: u32) -> f32 {
    return tables[i];
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (3u * i + 2u >= arrayLength(&cases)) {
        return;
    }
    let a = cases[3u * i];
    let wi = cases[3u * i + 1u].xyz;
    let u = cases[3u * i + 2u].xy;
    let b = records[bitcast<u32>(a.w)];
    let wo = a.xyz;
    results[3u * i] = vec4<f32>(bsdf_eval(b, wi, wo), bsdf_pdf(b, wi, wo));
    let s = bsdf_sample(b, wo, u);
    results[3u * i + 1u] = vec4<f32>(s.wi, s.pdf);
    results[3u * i + 2u] = vec4<f32>(s.value, f32(s.delta));
}
