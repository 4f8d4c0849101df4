// module pbr_metallic_roughness: kind 6, the glTF 2.0 metallic-roughness BRDF. CPU twin:
// lustre_brdf::models::pbr_metallic_roughness::PbrMetallicRoughness::{eval, pdf, sample}.
// Equations (glTF 2.0 appendix B): GGX D and Smith G with α = max(roughness², 10⁻³), Schlick
// weights w = (1 − |cos|)⁵; metal = spec (c + (1 − c) w), dielectric = c (1 − F)/π + spec F
// with F = 0.04 + 0.96 w, mixed by metallic; sampling picks the glossy lobe with the
// probability of its Fresnel-weighted share at ωo, else the cosine lobe.
// KHR_materials_anisotropy: GGX with α_t = mix(α, 1, s²) along t = (cos ρ, sin ρ, 0) and
// α_b = α across it; eval, pdf and sample work in the frame (t, z × t, z).
// Parameters (pack_pbr_metallic_roughness): p0 = (base colour rgb, metallic),
// p1 = (α_t, relative ior of a textured record's glass, α_b, anisotropy strength s),
// p2 = (cos ρ, sin ρ, 0, 0).

struct PbrMetallicRoughness {
    base: vec3<f32>,
    metallic: f32,
    mf: Microfacet,
    rot: vec2<f32>,
}

fn pbr_metallic_roughness_unpack(p: array<vec4<f32>, 8>) -> PbrMetallicRoughness {
    return PbrMetallicRoughness(p[0].xyz, p[0].w, Microfacet(p[1].x, p[1].z, MICROFACET_GGX),
        p[2].xy);
}

// `v` in the anisotropy frame and back.
fn pbr_to_aniso(m: PbrMetallicRoughness, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(m.rot.x * v.x + m.rot.y * v.y, -m.rot.y * v.x + m.rot.x * v.y, v.z);
}

fn pbr_from_aniso(m: PbrMetallicRoughness, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(m.rot.x * v.x - m.rot.y * v.y, m.rot.y * v.x + m.rot.x * v.y, v.z);
}

fn pbr_schlick5(c: f32) -> f32 {
    let m = clamp(1.0 - abs(c), 0.0, 1.0);
    let m2 = m * m;
    return m2 * m2 * m;
}

fn pbr_prob_specular(m: PbrMetallicRoughness, wo: vec3<f32>) -> f32 {
    let c = (m.base.x + m.base.y + m.base.z) / 3.0;
    let w = pbr_schlick5(wo.z);
    let f_d = 0.04 + 0.96 * w;
    let f_m = c + (1.0 - c) * w;
    let s = f_d + (f_m - f_d) * m.metallic;
    let d = (1.0 - m.metallic) * (1.0 - f_d) * c;
    if (s + d > 0.0) {
        return s / (s + d);
    }
    return 1.0;
}

fn pbr_metallic_roughness_eval(m: PbrMetallicRoughness, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    return pbr_eval_aniso(m, pbr_to_aniso(m, wi), pbr_to_aniso(m, wo));
}

fn pbr_eval_aniso(m: PbrMetallicRoughness, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    let h = normalize(wi + wo);
    let d = microfacet_d(m.mf, h);
    let denom = 4.0 * wi.z * wo.z;
    var spec = 0.0;
    if (d > 0.0 && denom > 0.0) {
        spec = d * microfacet_g1(m.mf, wi, h) * microfacet_g1(m.mf, wo, h) / denom;
    }
    let w = pbr_schlick5(dot(wo, h));
    let c = m.base;
    let metal = spec * (c + (vec3<f32>(1.0) - c) * w);
    let f = 0.04 + 0.96 * w;
    let dielectric = c * ((1.0 - f) / PI) + vec3<f32>(spec * f);
    return dielectric * (1.0 - m.metallic) + metal * m.metallic;
}

fn pbr_metallic_roughness_pdf(m: PbrMetallicRoughness, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return glossy_diffuse_pdf(m.mf, pbr_prob_specular(m, wo), pbr_to_aniso(m, wi),
        pbr_to_aniso(m, wo));
}

fn pbr_metallic_roughness_sample(m: PbrMetallicRoughness, wo_in: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (!(wo_in.z > 0.0)) {
        return no_sample();
    }
    let wo = pbr_to_aniso(m, wo_in);
    let ps = pbr_prob_specular(m, wo);
    let wi = glossy_diffuse_direction(m.mf, ps, wo, u);
    if (!(wi.z > 0.0)) {
        return no_sample();
    }
    let pdf = glossy_diffuse_pdf(m.mf, ps, wi, wo);
    if (!(pdf > 0.0 && pdf <= 3.4e38)) {
        return no_sample();
    }
    return BsdfSample(pbr_from_aniso(m, wi), pdf, pbr_eval_aniso(m, wi, wo), 0u);
}

// The record with its textured parameters at the pixel (FLAG_TEXTURED; textured.wgsl's
// `textured_bsdf` dispatches here): c = the clamped colour, s = the scalars as
// material::scene::pack_material_params lists them for this kind, unclamped.
fn pbr_metallic_roughness_textured(b_in: GpuBsdf, c: vec3<f32>, s: vec3<f32>) -> GpuBsdf {
    var b = b_in;
    let r = textured_unit(s.y);
    let eta = b.p[1].y;
    if (s.z >= 0.5) {
        let a = r * r;
        b.p[1] = vec4<f32>(1.0, 1.0, 1.0, 0.0);
        b.p[2] = vec4<f32>(c, 0.0);
        if (a < TEXTURED_PBR_ALPHA_MIN) {
            b.kind = KIND_DIELECTRIC;
            b.flags = b.flags | FLAG_DELTA_ONLY;
            b.p[0] = vec4<f32>(eta, 0.0, 0.0, 0.0);
        } else {
            // GGX: distribution code 1.
            b.kind = KIND_ROUGH_DIELECTRIC;
            b.p[0] = vec4<f32>(a, a, 1.0, eta);
        }
    } else {
        b.p[0] = vec4<f32>(c, textured_unit(s.x));
        // α at the texel; α_t from the record's anisotropy strength, the rotation kept.
        let a = max(r * r, TEXTURED_PBR_ALPHA_MIN);
        let strength = b.p[1].w;
        b.p[1] = vec4<f32>(a + (1.0 - a) * strength * strength, eta, a, strength);
    }
    return b;
}
