// module rough_dielectric: kind 3, a rough glass interface (glossy reflection and
// transmission). CPU twin: lustre_brdf::models::rough_dielectric::RoughDielectric::{eval, pdf,
// sample}. Equations (Walter et al. 2007): the generalised half vector h = ωo + η ωi (facing
// +z); reflection F D G / (4 |cos θi cos θo|), transmission (1 − F) D G |ωi·h ωo·h| /
// (|cos θi cos θo| (ωo·h + η ωi·h)²); pdf = D_v(h) · (F or 1 − F) · Jacobian; sampling: a
// visible normal from (u1, the odd bits of u2), reflect when the even bits of u2 < F.
// Parameters (pack_rough_dielectric): p0 = (αu, αv, distribution, η), p1 = (reflectance rgb,
// 0), p2 = (transmittance rgb, 0).

struct RoughDielectric {
    mf: Microfacet,
    eta: f32,
    reflectance: vec3<f32>,
    transmittance: vec3<f32>,
}

fn rough_dielectric_unpack(p: array<vec4<f32>, 8>) -> RoughDielectric {
    return RoughDielectric(Microfacet(p[0].x, p[0].y, u32(p[0].z)), p[0].w, p[1].xyz, p[2].xyz);
}

// RoughDielectric::config: (h, 1) for reflection, (h, 0) for transmission (η of the
// configuration from rough_dielectric_eta), w = −1 for none.
fn rough_dielectric_config(m: RoughDielectric, wi: vec3<f32>, wo: vec3<f32>) -> vec4<f32> {
    if (wo.z == 0.0 || wi.z == 0.0) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let refl = wi.z * wo.z > 0.0;
    var eta = 1.0;
    if (!refl) {
        eta = select(1.0 / m.eta, m.eta, wo.z > 0.0);
    }
    let hv = wo + wi * eta;
    let l = length(hv);
    if (!(l > 0.0 && l <= 3.4e38)) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    var h = hv / l;
    if (h.z < 0.0) {
        h = -h;
    }
    if (dot(wo, h) * wo.z <= 0.0 || dot(wi, h) * wi.z <= 0.0) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    return vec4<f32>(h, select(0.0, 1.0, refl));
}

fn rough_dielectric_eta(m: RoughDielectric, wo: vec3<f32>, refl: bool) -> f32 {
    if (refl) {
        return 1.0;
    }
    return select(1.0 / m.eta, m.eta, wo.z > 0.0);
}

fn rough_dielectric_eval(m: RoughDielectric, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let c = rough_dielectric_config(m, wi, wo);
    if (c.w < 0.0) {
        return vec3<f32>(0.0);
    }
    let h = c.xyz;
    let refl = c.w > 0.5;
    let d = microfacet_d(m.mf, h);
    if (d == 0.0) {
        return vec3<f32>(0.0);
    }
    let g = microfacet_g1(m.mf, wi, h) * microfacet_g1(m.mf, wo, h);
    let oh = dot(wo, h);
    let ih = dot(wi, h);
    let f = fresnel_dielectric(oh, m.eta).x;
    let ci = abs(wi.z);
    let co = abs(wo.z);
    if (refl) {
        return m.reflectance * (f * d * g / (4.0 * ci * co));
    }
    let eta = rough_dielectric_eta(m, wo, false);
    let denom = oh + eta * ih;
    let v = (1.0 - f) * d * g * abs(ih * oh) / (ci * co * denom * denom);
    return m.transmittance * abs(v);
}

fn rough_dielectric_pdf(m: RoughDielectric, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    let c = rough_dielectric_config(m, wi, wo);
    if (c.w < 0.0) {
        return 0.0;
    }
    let h = c.xyz;
    let refl = c.w > 0.5;
    let oh = dot(wo, h);
    let ih = dot(wi, h);
    var jacobian: f32;
    if (refl) {
        jacobian = 1.0 / (4.0 * abs(ih));
    } else {
        let eta = rough_dielectric_eta(m, wo, false);
        let denom = oh + eta * ih;
        jacobian = eta * eta * abs(ih) / (denom * denom);
    }
    let s = sign(wo.z);
    let f = fresnel_dielectric(oh, m.eta).x;
    let choice = select(1.0 - f, f, refl);
    return microfacet_pdf_visible(m.mf, wo * s, h) * choice * jacobian;
}

fn rough_dielectric_sample(m: RoughDielectric, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (wo.z == 0.0) {
        return no_sample();
    }
    let s = sign(wo.z);
    let split = split_uniform(u.y);
    let mv = microfacet_sample_visible(m.mf, wo * s, u.x, split.x);
    if (mv.z == 0.0) {
        return no_sample();
    }
    let fr = fresnel_dielectric(dot(wo, mv), m.eta);
    var wi: vec3<f32>;
    let refl = split.y < fr.x;
    if (refl) {
        wi = reflect_about(wo, mv);
    } else {
        wi = refract_through(wo, mv, fr.y, fr.w);
    }
    let l = length(wi);
    if (!(l > 0.0 && l <= 3.4e38)) {
        return no_sample();
    }
    wi = wi / l;
    let same = wi.z * wo.z > 0.0;
    if (same != refl || wi.z == 0.0) {
        return no_sample();
    }
    let pdf = rough_dielectric_pdf(m, wi, wo);
    if (!(pdf > 0.0 && pdf <= 3.4e38)) {
        return no_sample();
    }
    return BsdfSample(wi, pdf, rough_dielectric_eval(m, wi, wo), 0u);
}

// The record with its textured parameters at the pixel (FLAG_TEXTURED; textured.wgsl's
// `textured_bsdf` dispatches here): c = the clamped colour, s = the scalars as
// material::scene::pack_material_params lists them for this kind, unclamped.
fn rough_dielectric_textured(b_in: GpuBsdf, c: vec3<f32>, s: vec3<f32>) -> GpuBsdf {
    var b = b_in;
    let a = textured_alpha(s.x);
    b.p[0].x = a;
    b.p[0].y = a;
    return b;
}
