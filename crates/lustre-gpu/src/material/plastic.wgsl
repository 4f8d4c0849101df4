// module plastic: kind 8, a smooth dielectric coating over a diffuse base (a Dirac mirror lobe
// and a diffuse one). CPU twin: lustre_brdf::models::plastic::Plastic::{eval, pdf, sample}.
// Equations (Mitsuba's plastic): f = ρ' (1 − F(cos θi)) (1 − F(cos θo)) / (π η²) with
// ρ' = ρ/(1 − Fdr) (ρ/(1 − ρ Fdr) when nonlinear); the mirror picked with
// p_s = F(cos θo) w_s / (F w_s + (1 − F)(1 − w_s)), weight R_s F / p_s; else the cosine lobe,
// pdf (1 − p_s) cos θi / π.
// Parameters (pack_plastic): p0 = (ρ rgb, w_s), p1 = (R_s rgb, nonlinear 0/1),
// p2 = (η, Fdr, 0, 0).

struct Plastic {
    diffuse: vec3<f32>,
    specular_weight: f32,
    specular: vec3<f32>,
    nonlinear: bool,
    eta: f32,
    fdr: f32,
}

fn plastic_unpack(p: array<vec4<f32>, 8>) -> Plastic {
    return Plastic(p[0].xyz, p[0].w, p[1].xyz, p[1].w > 0.5, p[2].x, p[2].y);
}

fn plastic_prob_specular(m: Plastic, f_o: f32) -> f32 {
    let ps = f_o * m.specular_weight;
    let pd = (1.0 - f_o) * (1.0 - m.specular_weight);
    if (ps + pd > 0.0) {
        return ps / (ps + pd);
    }
    return 0.0;
}

fn plastic_eval(m: Plastic, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    let f_i = fresnel_dielectric(wi.z, m.eta).x;
    let f_o = fresnel_dielectric(wo.z, m.eta).x;
    var base: vec3<f32>;
    if (m.nonlinear) {
        base = m.diffuse / (vec3<f32>(1.0) - m.diffuse * m.fdr);
    } else {
        base = m.diffuse / (1.0 - m.fdr);
    }
    return base * (1.0 / (PI * m.eta * m.eta) * (1.0 - f_i) * (1.0 - f_o));
}

fn plastic_pdf(m: Plastic, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return 0.0;
    }
    let f_o = fresnel_dielectric(wo.z, m.eta).x;
    return (1.0 - plastic_prob_specular(m, f_o)) * wi.z / PI;
}

fn plastic_sample(m: Plastic, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (!(wo.z > 0.0)) {
        return no_sample();
    }
    let f_o = fresnel_dielectric(wo.z, m.eta).x;
    let ps = plastic_prob_specular(m, f_o);
    if (u.x < ps) {
        return delta_sample(vec3<f32>(-wo.x, -wo.y, wo.z), m.specular * (f_o / ps), ps);
    }
    let u1 = clamp((u.x - ps) / (1.0 - ps), 0.0, ONE_MINUS_EPS);
    let wi = cosine_hemisphere(u1, u.y);
    if (wi.z <= 0.0) {
        return no_sample();
    }
    let pdf = plastic_pdf(m, wi, wo);
    if (!(pdf > 0.0)) {
        return no_sample();
    }
    return BsdfSample(wi, pdf, plastic_eval(m, wi, wo), 0u);
}

// The record with its textured parameters at the pixel (FLAG_TEXTURED; textured.wgsl's
// `textured_bsdf` dispatches here): c = the clamped colour, s = the scalars as
// material::scene::pack_material_params lists them for this kind, unclamped.
fn plastic_textured(b_in: GpuBsdf, c: vec3<f32>, s: vec3<f32>) -> GpuBsdf {
    var b = b_in;
    b.p[0] = vec4<f32>(c, textured_coat_weight(c, b.p[1].xyz));
    return b;
}
