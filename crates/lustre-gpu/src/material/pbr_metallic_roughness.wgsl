// module pbr_metallic_roughness: kind 6, the glTF 2.0 metallic-roughness BRDF. CPU twin:
// lustre_brdf::models::pbr_metallic_roughness::PbrMetallicRoughness::{eval, pdf, sample}.
// Equations (glTF 2.0 appendix B): GGX D and Smith G with α = max(roughness², 10⁻³), Schlick
// weights w = (1 − |cos|)⁵; metal = spec (c + (1 − c) w), dielectric = c (1 − F)/π + spec F
// with F = 0.04 + 0.96 w, mixed by metallic; sampling picks the glossy lobe with the
// probability of its Fresnel-weighted share at ωo, else the cosine lobe.
// KHR_materials_anisotropy: GGX with α_t = mix(α, 1, s²) along t = (cos ρ, sin ρ, 0) and
// α_b = α across it; eval, pdf and sample work in the frame (t, z × t, z).
// The extensions' layers (KHR_materials_ior / _specular / _sheen / _clearcoat, in that order):
// dielectric = (1 − k max F) c/π + k F spec with F = f0 + (1 − f0) w per channel; f ← sheen D V +
// f · max(min(1 − max(s) E(cos θo), 1 − max(s) E(cos θi)), 0); f ← mix(f, coat, w_c (0.04 +
// 0.96 w)); sampling picks the coat with P_c = w_c (0.04 + 0.96 (1 − cos θo)⁵), else the
// mixture above with the sheen's max(s) E(cos θo) added to the cosine lobe's share.
// Parameters (pack_pbr_metallic_roughness): p0 = (base colour rgb, metallic),
// p1 = (α_t, relative ior of a textured record's glass, α_b, anisotropy strength s),
// p2 = (cos ρ, sin ρ, clearcoat w_c, coat α_c), p3 = (f0 rgb, specular k),
// p4 = (sheen colour rgb, sheen roughness r_s).

struct PbrMetallicRoughness {
    base: vec3<f32>,
    metallic: f32,
    mf: Microfacet,
    rot: vec2<f32>,
    coat_w: f32,
    coat: Microfacet,
    f0: vec3<f32>,
    specular: f32,
    sheen: vec3<f32>,
    sheen_r: f32,
}

fn pbr_metallic_roughness_unpack(p: array<vec4<f32>, 8>) -> PbrMetallicRoughness {
    return PbrMetallicRoughness(p[0].xyz, p[0].w, Microfacet(p[1].x, p[1].z, MICROFACET_GGX),
        p[2].xy, p[2].z, Microfacet(p[2].w, p[2].w, MICROFACET_GGX), p[3].xyz, p[3].w, p[4].xyz,
        p[4].w);
}

fn pbr_max3(v: vec3<f32>) -> f32 {
    return max(v.x, max(v.y, v.z));
}

// P_c: the coat's choice probability at cos θo.
fn pbr_prob_coat(m: PbrMetallicRoughness, cos_o: f32) -> f32 {
    if (!(m.coat_w > 0.0)) {
        return 0.0;
    }
    return m.coat_w * (0.04 + 0.96 * pbr_schlick5(cos_o));
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
    let f_d = m.specular * pbr_max3(m.f0 + (vec3<f32>(1.0) - m.f0) * w);
    let f_m = c + (1.0 - c) * w;
    let s = f_d + (f_m - f_d) * m.metallic;
    var d = (1.0 - m.metallic) * (1.0 - f_d) * c;
    let sheen = pbr_max3(m.sheen);
    if (sheen > 0.0) {
        d = d + sheen * sheen_albedo(wo.z, m.sheen_r);
    }
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
    let f = m.f0 + (vec3<f32>(1.0) - m.f0) * w;
    let dielectric = c * ((1.0 - m.specular * pbr_max3(f)) / PI) + f * (m.specular * spec);
    var out = dielectric * (1.0 - m.metallic) + metal * m.metallic;
    let sheen = pbr_max3(m.sheen);
    if (sheen > 0.0) {
        let scale = max(min(1.0 - sheen * sheen_albedo(wo.z, m.sheen_r),
            1.0 - sheen * sheen_albedo(wi.z, m.sheen_r)), 0.0);
        let dv = charlie_d(sheen_alpha(m.sheen_r), h.z) * neubelt_v(wi.z, wo.z);
        out = m.sheen * dv + out * scale;
    }
    if (m.coat_w > 0.0) {
        let dc = microfacet_d(m.coat, h);
        var coat = 0.0;
        if (dc > 0.0 && denom > 0.0) {
            coat = dc * microfacet_g1(m.coat, wi, h) * microfacet_g1(m.coat, wo, h) / denom;
        }
        let fc = m.coat_w * (0.04 + 0.96 * w);
        out = out * (1.0 - fc) + vec3<f32>(coat * fc);
    }
    return out;
}

// The density in the anisotropy frame: P_c · coat + (1 − P_c) · the glossy-diffuse mixture.
fn pbr_pdf_aniso(m: PbrMetallicRoughness, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return 0.0;
    }
    let base = glossy_diffuse_pdf(m.mf, pbr_prob_specular(m, wo), wi, wo);
    let pc = pbr_prob_coat(m, wo.z);
    if (!(pc > 0.0)) {
        return base;
    }
    let h = normalize(wi + wo);
    let coat = microfacet_d(m.coat, h) * microfacet_g1(m.coat, wo, h) / (4.0 * wo.z);
    return pc * coat + (1.0 - pc) * base;
}

fn pbr_metallic_roughness_pdf(m: PbrMetallicRoughness, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return pbr_pdf_aniso(m, pbr_to_aniso(m, wi), pbr_to_aniso(m, wo));
}

fn pbr_metallic_roughness_sample(m: PbrMetallicRoughness, wo_in: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (!(wo_in.z > 0.0)) {
        return no_sample();
    }
    let wo = pbr_to_aniso(m, wo_in);
    let pc = pbr_prob_coat(m, wo.z);
    var wi = vec3<f32>(0.0);
    if (u.x < pc) {
        let u1 = clamp(u.x / pc, 0.0, ONE_MINUS_EPS);
        let mv = microfacet_sample_visible(m.coat, wo, u1, u.y);
        if (mv.z == 0.0) {
            return no_sample();
        }
        wi = reflect_about(wo, mv);
    } else {
        let u1 = clamp((u.x - pc) / (1.0 - pc), 0.0, ONE_MINUS_EPS);
        wi = glossy_diffuse_direction(m.mf, pbr_prob_specular(m, wo), wo, vec2<f32>(u1, u.y));
    }
    if (!(wi.z > 0.0)) {
        return no_sample();
    }
    let pdf = pbr_pdf_aniso(m, wi, wo);
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
