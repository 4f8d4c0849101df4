// module thin_dielectric: kind 5, a thin glass sheet (two Dirac lobes). CPU twin:
// lustre_brdf::models::thin_dielectric::ThinDielectric::{eval, pdf, sample}: R' = 2R/(1 + R)
// (both interfaces, R the dielectric reflectance at |cos θo|), the mirror with probability R'
// and weight R_s, straight through (−ωo) with 1 − R' and weight T_s. Frame shading also uses
// it for smooth glass (lustre_shade::frame::thin_sheet).
// Parameters (pack_thin_dielectric): p0 = (η, 0, 0, 0), p1 = (specular_reflectance rgb, 0),
// p2 = (specular_transmittance rgb, 0).

struct ThinDielectric {
    eta: f32,
    reflectance: vec3<f32>,
    transmittance: vec3<f32>,
}

fn thin_dielectric_unpack(p: array<vec4<f32>, 8>) -> ThinDielectric {
    return ThinDielectric(p[0].x, p[1].xyz, p[2].xyz);
}

fn thin_dielectric_eval(m: ThinDielectric, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn thin_dielectric_pdf(m: ThinDielectric, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return 0.0;
}

// ThinDielectric::reflectance.
fn thin_dielectric_reflectance(m: ThinDielectric, cos_theta: f32) -> f32 {
    let r = fresnel_dielectric(abs(cos_theta), m.eta).x;
    if (r < 1.0) {
        return 2.0 * r / (1.0 + r);
    }
    return 1.0;
}

fn thin_dielectric_sample(m: ThinDielectric, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (!(abs(wo.z) > 0.0)) {
        return no_sample();
    }
    let r = thin_dielectric_reflectance(m, wo.z);
    if (u.x < r) {
        return delta_sample(vec3<f32>(-wo.x, -wo.y, wo.z), m.reflectance, r);
    }
    return delta_sample(-wo, m.transmittance, 1.0 - r);
}
