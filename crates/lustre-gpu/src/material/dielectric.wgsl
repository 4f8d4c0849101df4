// module dielectric: kind 9, a smooth glass interface (two Dirac lobes: the mirror and the
// refraction). CPU twin: lustre_brdf::models::dielectric::Dielectric::{eval, pdf, sample}: the
// mirror with probability F(cos θo) and weight R_s, else the refracted direction with 1 − F
// and weight T_s η_ti² (the radiance scaling across the interface). The walkthrough frame
// shades a scene's smooth glass as a thin sheet (kind 5); this is the smooth transmissive glTF
// material, which the CPU builds as this interface.
// Parameters (pack_dielectric): p0 = (η, 0, 0, 0), p1 = (reflectance rgb, 0),
// p2 = (transmittance rgb, 0).

struct Dielectric {
    eta: f32,
    reflectance: vec3<f32>,
    transmittance: vec3<f32>,
}

fn dielectric_unpack(p: array<vec4<f32>, 8>) -> Dielectric {
    return Dielectric(p[0].x, p[1].xyz, p[2].xyz);
}

fn dielectric_eval(m: Dielectric, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn dielectric_pdf(m: Dielectric, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return 0.0;
}

fn dielectric_sample(m: Dielectric, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (!(abs(wo.z) > 0.0)) {
        return no_sample();
    }
    let f = fresnel_dielectric(wo.z, m.eta);
    if (u.x < f.x) {
        return delta_sample(vec3<f32>(-wo.x, -wo.y, wo.z), m.reflectance, f.x);
    }
    let wi = normalize(refract_through(wo, vec3<f32>(0.0, 0.0, 1.0), f.y, f.w));
    return delta_sample(wi, m.transmittance * (f.w * f.w), 1.0 - f.x);
}
