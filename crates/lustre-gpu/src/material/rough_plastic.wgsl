// module rough_plastic: kind 2, a rough dielectric coating over a diffuse base. CPU twin:
// lustre_brdf::models::rough_plastic::RoughPlastic::{eval, pdf, sample}. Equations (Mitsuba's
// roughplastic): f = R_s F(ωo·h) D G / (4 cos θi cos θo) + ρ' T(cos θi) T(cos θo) / (π η²),
// ρ' = ρ/(1 − Fdr) (or ρ/(1 − ρ Fdr) when nonlinear); sampling picks the glossy lobe with
// p_s = (1 − T(cos θo)) w_s / ((1 − T) w_s + T (1 − w_s)) (w_s the specular weight), else the
// cosine lobe (lustre_brdf::models::glossy_diffuse::{sample, pdf}).
// The 64-entry external transmittance table T(μ) (μ = i/63, linearly interpolated) does not fit
// the record: it lives in the pass's table buffer, read through `bsdf_table(i)`, which every
// pass that imports this module defines.
// Parameters (pack_rough_plastic): p0 = (α, distribution, η, Fdr), p1 = (ρ rgb, w_s),
// p2 = (R_s rgb, nonlinear 0/1), p3 = (first table entry, second table entry (both exact as
// f32), blend, 1: a textured roughness's grid, resolved per pixel by textured.wgsl). T is the
// blend of the two tables (RoughPlasticCoating::at; one table, blend 0, when α is constant).
// Requires (the pass defines): fn bsdf_table(i: u32) -> f32.

struct RoughPlastic {
    mf: Microfacet,
    eta: f32,
    fdr: f32,
    diffuse: vec3<f32>,
    specular_weight: f32,
    specular: vec3<f32>,
    nonlinear: bool,
    table: u32,
    table2: u32,
    blend: f32,
}

const ROUGH_PLASTIC_TABLE: u32 = 64u;

fn rough_plastic_unpack(p: array<vec4<f32>, 8>) -> RoughPlastic {
    return RoughPlastic(Microfacet(p[0].x, p[0].x, u32(p[0].y)), p[0].z, p[0].w, p[1].xyz, p[1].w,
                        p[2].xyz, p[2].w > 0.5, u32(p[3].x), u32(p[3].y), p[3].z);
}

// RoughPlastic::transmittance.
fn rough_plastic_transmittance(m: RoughPlastic, mu: f32) -> f32 {
    let x = clamp(mu, 0.0, 1.0) * f32(ROUGH_PLASTIC_TABLE - 1u);
    let i = min(u32(x), ROUGH_PLASTIC_TABLE - 2u);
    let t = x - f32(i);
    let a = bsdf_table(m.table + i) * (1.0 - t) + bsdf_table(m.table + i + 1u) * t;
    if (m.blend == 0.0) {
        return a;
    }
    let b = bsdf_table(m.table2 + i) * (1.0 - t) + bsdf_table(m.table2 + i + 1u) * t;
    return a * (1.0 - m.blend) + b * m.blend;
}

fn rough_plastic_prob_specular(m: RoughPlastic, wo: vec3<f32>) -> f32 {
    let t = rough_plastic_transmittance(m, wo.z);
    let ps = (1.0 - t) * m.specular_weight;
    let pd = t * (1.0 - m.specular_weight);
    if (ps + pd > 0.0) {
        return ps / (ps + pd);
    }
    return 0.0;
}

fn rough_plastic_eval(m: RoughPlastic, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    let h = normalize(wi + wo);
    let d = microfacet_d(m.mf, h);
    var spec = 0.0;
    if (d > 0.0) {
        let f = fresnel_dielectric(dot(wo, h), m.eta).x;
        spec = f * d * microfacet_g1(m.mf, wi, h) * microfacet_g1(m.mf, wo, h) / (4.0 * wi.z * wo.z);
    }
    var base: vec3<f32>;
    if (m.nonlinear) {
        base = m.diffuse / (vec3<f32>(1.0) - m.diffuse * m.fdr);
    } else {
        base = m.diffuse / (1.0 - m.fdr);
    }
    let t = rough_plastic_transmittance(m, wi.z) * rough_plastic_transmittance(m, wo.z);
    return m.specular * spec + base * (1.0 / (PI * m.eta * m.eta) * t);
}

fn rough_plastic_pdf(m: RoughPlastic, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return glossy_diffuse_pdf(m.mf, rough_plastic_prob_specular(m, wo), wi, wo);
}

fn rough_plastic_sample(m: RoughPlastic, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (!(wo.z > 0.0)) {
        return no_sample();
    }
    let wi = glossy_diffuse_direction(m.mf, rough_plastic_prob_specular(m, wo), wo, u);
    if (!(wi.z > 0.0)) {
        return no_sample();
    }
    let pdf = rough_plastic_pdf(m, wi, wo);
    if (!(pdf > 0.0 && pdf <= 3.4e38)) {
        return no_sample();
    }
    return BsdfSample(wi, pdf, rough_plastic_eval(m, wi, wo), 0u);
}

// The record with its textured parameters at the pixel (FLAG_TEXTURED; textured.wgsl's
// `textured_bsdf` dispatches here): c = the clamped colour, s = the scalars as
// material::scene::pack_material_params lists them for this kind, unclamped.
fn rough_plastic_textured(b_in: GpuBsdf, c: vec3<f32>, s: vec3<f32>) -> GpuBsdf {
    var b = b_in;
    b.p[1] = vec4<f32>(c, textured_coat_weight(c, b.p[2].xyz));
    if (b.p[3].w > 0.5) {
        // RoughPlasticCoating::at: the grid's rows i and i + 1 around α (log-spaced),
        // their Fdr after the COATING_ALPHAS tables.
        let a = textured_alpha(s.x);
        let x = log2(a / COATING_ALPHA_MIN) * f32(COATING_ALPHAS - 1u)
            / -log2(COATING_ALPHA_MIN);
        let i = min(u32(max(x, 0.0)), COATING_ALPHAS - 2u);
        let t = clamp(x - f32(i), 0.0, 1.0);
        let start = u32(b.p[3].x);
        let fdr = start + COATING_ALPHAS * ROUGH_PLASTIC_TABLE;
        b.p[0].x = a;
        b.p[0].w = bsdf_table(fdr + i) * (1.0 - t) + bsdf_table(fdr + i + 1u) * t;
        b.p[3] = vec4<f32>(f32(start + i * ROUGH_PLASTIC_TABLE),
                           f32(start + (i + 1u) * ROUGH_PLASTIC_TABLE), t, 0.0);
    }
    return b;
}
