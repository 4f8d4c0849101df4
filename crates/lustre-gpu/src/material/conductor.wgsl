// module conductor: kind 4, a smooth metal (one Dirac lobe). CPU twin:
// lustre_brdf::models::conductor::Conductor::{eval, pdf, sample}: ωi = (−ωo.x, −ωo.y, ωo.z)
// with weight F(cos θo) R, probability 1; eval and pdf are 0.
// Parameters (pack_conductor): p0 = (η rgb, 0), p1 = (k rgb, 0), p2 = (specular rgb, 0).

struct Conductor {
    eta: vec3<f32>,
    k: vec3<f32>,
    specular: vec3<f32>,
}

fn conductor_unpack(p: array<vec4<f32>, 8>) -> Conductor {
    return Conductor(p[0].xyz, p[1].xyz, p[2].xyz);
}

fn conductor_eval(m: Conductor, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn conductor_pdf(m: Conductor, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return 0.0;
}

fn conductor_sample(m: Conductor, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (!(wo.z > 0.0)) {
        return no_sample();
    }
    let wi = vec3<f32>(-wo.x, -wo.y, wo.z);
    return delta_sample(wi, fresnel_conductor(wo.z, m.eta, m.k) * m.specular, 1.0);
}

// The record with its textured parameters at the pixel (FLAG_TEXTURED; textured.wgsl's
// `textured_bsdf` dispatches here): c = the clamped colour, s = the scalars as
// material::scene::pack_material_params lists them for this kind, unclamped.
fn conductor_textured(b_in: GpuBsdf, c: vec3<f32>, s: vec3<f32>) -> GpuBsdf {
    var b = b_in;
    b.p[2] = vec4<f32>(c, 0.0);
    return b;
}
