// module glossy_diffuse: a visible-normal microfacet reflection lobe picked with probability ps
// beside a cosine lobe — the density and the sampled direction the rough plastic and the glTF
// metallic-roughness model share. CPU twin: lustre_brdf::models::glossy_diffuse::{pdf, sample},
// the `pdf` and `sample` of lustre_brdf::models::rough_plastic::RoughPlastic and
// lustre_brdf::models::pbr_metallic_roughness::PbrMetallicRoughness (the same mixture, each
// with its own ps).

// The density of ωi: ps · D(h) G1(ωo, h) / (4 cos θo) + (1 − ps) cos θi / π; 0 unless both
// directions lie above the surface.
fn glossy_diffuse_pdf(mf: Microfacet, ps: f32, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return 0.0;
    }
    let h = normalize(wi + wo);
    let spec = microfacet_d(mf, h) * microfacet_g1(mf, wo, h) / (4.0 * wo.z);
    return ps * spec + (1.0 - ps) * wi.z / PI;
}

// A direction of that mixture for u: the microfacet lobe where u.x < ps (u.x rescaled), else
// the cosine lobe; the zero vector where the visible normal is degenerate.
fn glossy_diffuse_direction(mf: Microfacet, ps: f32, wo: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    if (u.x < ps) {
        let u1 = clamp(u.x / ps, 0.0, ONE_MINUS_EPS);
        let mv = microfacet_sample_visible(mf, wo, u1, u.y);
        if (mv.z == 0.0) {
            return vec3<f32>(0.0);
        }
        return reflect_about(wo, mv);
    }
    let u1 = clamp((u.x - ps) / (1.0 - ps), 0.0, ONE_MINUS_EPS);
    return cosine_hemisphere(u1, u.y);
}
