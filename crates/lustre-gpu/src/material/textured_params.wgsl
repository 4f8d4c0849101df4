// module textured_params: the clamps and weights a material kind's `<kind>_textured` applies to
// its parameters at a pixel. CPU twins: lustre_scene::material::{clamp_unit, clamp_alpha},
// lustre_brdf::models::rough_plastic::{COATING_ALPHAS, COATING_ALPHA_MIN},
// lustre_brdf::models::pbr_metallic_roughness::PBR_ALPHA_MIN.

// lustre_brdf::models::rough_plastic::{COATING_ALPHAS, COATING_ALPHA_MIN}.
const COATING_ALPHAS: u32 = 65u;
const COATING_ALPHA_MIN: f32 = 1e-4;
// lustre_brdf::models::pbr_metallic_roughness::PBR_ALPHA_MIN.
const TEXTURED_PBR_ALPHA_MIN: f32 = 1e-3;

// lustre_scene::material::clamp_unit: NaN → 0, else clamped to [0, 1].
fn textured_unit(x: f32) -> f32 {
    return select(0.0, clamp(x, 0.0, 1.0), x == x);
}

fn textured_unit3(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(textured_unit(c.x), textured_unit(c.y), textured_unit(c.z));
}

// lustre_scene::material::clamp_alpha: NaN → 1, else clamped to [10⁻⁴, 1].
fn textured_alpha(a: f32) -> f32 {
    return select(1.0, clamp(a, 1e-4, 1.0), a == a);
}

// A plastic's specular sampling weight (RoughPlastic::with_reflectances, Plastic's).
fn textured_coat_weight(rho: vec3<f32>, spec: vec3<f32>) -> f32 {
    let d = (rho.x + rho.y + rho.z) / 3.0;
    let s = (spec.x + spec.y + spec.z) / 3.0;
    if (d + s > 0.0) {
        return s / (d + s);
    }
    return 0.5;
}

