// module rough_conductor: kind 1, a rough metal. CPU twin:
// lustre_brdf::models::rough_conductor::RoughConductor::{eval, pdf, sample}. Equations:
// f = F(ωi·h) R D(h) G1(ωi) G1(ωo) / (4 cos θi cos θo) (Walter et al. 2007, Eq. 20), F the
// conductor Fresnel of η + ik; sampling by visible normals (microfacet.wgsl).
// Parameters (pack_rough_conductor): p0 = (αu, αv, distribution: 0 Beckmann / 1 GGX, 0),
// p1 = (η rgb, 0), p2 = (k rgb, 0), p3 = (specular_reflectance rgb, 0).

struct RoughConductor {
    mf: Microfacet,
    eta: vec3<f32>,
    k: vec3<f32>,
    specular: vec3<f32>,
}

fn rough_conductor_unpack(p: array<vec4<f32>, 8>) -> RoughConductor {
    return RoughConductor(Microfacet(p[0].x, p[0].y, u32(p[0].z)), p[1].xyz, p[2].xyz, p[3].xyz);
}

fn rough_conductor_eval(m: RoughConductor, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    let h = normalize(wi + wo);
    let d = microfacet_d(m.mf, h);
    if (d == 0.0) {
        return vec3<f32>(0.0);
    }
    let g = microfacet_g1(m.mf, wi, h) * microfacet_g1(m.mf, wo, h);
    return fresnel_conductor(dot(wi, h), m.eta, m.k) * m.specular * (d * g / (4.0 * wi.z * wo.z));
}

fn rough_conductor_pdf(m: RoughConductor, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return microfacet_pdf(m.mf, wi, wo);
}

fn rough_conductor_sample(m: RoughConductor, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    let mv = microfacet_sample_visible(m.mf, wo, u.x, u.y);
    if (mv.z == 0.0) {
        return no_sample();
    }
    let wi = reflect_about(wo, mv);
    if (!(wi.z > 0.0)) {
        return no_sample();
    }
    let pdf = rough_conductor_pdf(m, wi, wo);
    if (!(pdf > 0.0 && pdf <= 3.4e38)) {
        return no_sample();
    }
    return BsdfSample(wi, pdf, rough_conductor_eval(m, wi, wo), 0u);
}

// The record with its textured parameters at the pixel (FLAG_TEXTURED; textured.wgsl's
// `textured_bsdf` dispatches here): c = the clamped colour, s = the scalars as
// material::scene::pack_material_params lists them for this kind, unclamped.
fn rough_conductor_textured(b_in: GpuBsdf, c: vec3<f32>, s: vec3<f32>) -> GpuBsdf {
    var b = b_in;
    b.p[0].x = textured_alpha(s.x);
    b.p[0].y = textured_alpha(s.y);
    b.p[3] = vec4<f32>(c, 0.0);
    return b;
}
