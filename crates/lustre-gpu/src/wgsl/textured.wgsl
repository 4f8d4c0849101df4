// module textured: a material's textured parameters and normal map at a pixel. CPU twins:
// lustre_scene::Material::with_bsdf_at (the clamps of `unit` and `clamp_alpha`, the glTF
// metallic-roughness model's choice of BRDF or (rough) dielectric by transmission),
// Material::normal_map_at and lustre_shade::path's `mapped_normal`. Binding-free: the caller
// samples the textures (factor × texel, as `TexturedRgb::at` / `TexturedScalar::at`) and passes
// the values; which parameter each value is depends on the kind (frame_shade.rs
// `pack_material_params`): rgb = the Lambert / plastic diffuse reflectance, the conductor's
// specular colour or the glTF base colour; s = (αu, αv, −) of a rough conductor, (α, −, −) of a
// rough dielectric, (α, −, −) of a rough plastic whose roughness is textured (its coating's grid
// in the table buffer, read through `bsdf_table`), (metallic, roughness, transmission) of the
// glTF model.

// Only the kinds below carry textured parameters (pack_material sets FLAG_TEXTURED on them).
const FLAG_TEXTURED: u32 = 8u;
// The shading normal is tilted by a tangent-space normal map.
const FLAG_NORMAL_MAPPED: u32 = 16u;
// lustre_brdf::models::rough_plastic::{COATING_ALPHAS, COATING_ALPHA_MIN}.
const COATING_ALPHAS: u32 = 65u;
const COATING_ALPHA_MIN: f32 = 1e-4;
// lustre_brdf::models::pbr_metallic_roughness::PBR_ALPHA_MIN.
const TEXTURED_PBR_ALPHA_MIN: f32 = 1e-3;

// lustre-scene's `unit`: NaN → 0, else clamped to [0, 1].
fn textured_unit(x: f32) -> f32 {
    return select(0.0, clamp(x, 0.0, 1.0), x == x);
}

fn textured_unit3(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(textured_unit(c.x), textured_unit(c.y), textured_unit(c.z));
}

// lustre-scene's `clamp_alpha`: NaN → 1, else clamped to [10⁻⁴, 1].
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

// The record `b` (FLAG_TEXTURED) with its parameters at the pixel: rgb and s as listed above,
// unclamped. A glTF record (kind 6, p1.y = the relative ior) becomes the glass Material::bsdf_at
// builds where the transmission is ≥ ½: a smooth dielectric (kind 9, Dirac) below α = 10⁻³,
// else a GGX rough dielectric (kind 3), both tinted by the base colour.
fn textured_bsdf(b_in: GpuBsdf, rgb: vec3<f32>, s: vec3<f32>) -> GpuBsdf {
    var b = b_in;
    let c = textured_unit3(rgb);
    switch b.kind {
        case 1u: {
            b.p[0].x = textured_alpha(s.x);
            b.p[0].y = textured_alpha(s.y);
            b.p[3] = vec4<f32>(c, 0.0);
        }
        case 2u: {
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
        }
        case 3u: {
            let a = textured_alpha(s.x);
            b.p[0].x = a;
            b.p[0].y = a;
        }
        case 4u: {
            b.p[2] = vec4<f32>(c, 0.0);
        }
        case 6u: {
            let r = textured_unit(s.y);
            let eta = b.p[1].y;
            if (s.z >= 0.5) {
                let a = r * r;
                b.p[1] = vec4<f32>(1.0, 1.0, 1.0, 0.0);
                b.p[2] = vec4<f32>(c, 0.0);
                if (a < TEXTURED_PBR_ALPHA_MIN) {
                    b.kind = 9u;
                    b.flags = b.flags | FLAG_DELTA_ONLY;
                    b.p[0] = vec4<f32>(eta, 0.0, 0.0, 0.0);
                } else {
                    // GGX: distribution code 1.
                    b.kind = 3u;
                    b.p[0] = vec4<f32>(a, a, 1.0, eta);
                }
            } else {
                b.p[0] = vec4<f32>(c, textured_unit(s.x));
                b.p[1] = vec4<f32>(max(r * r, TEXTURED_PBR_ALPHA_MIN), eta, 0.0, 0.0);
            }
        }
        case 7u: {
            b.p[0] = vec4<f32>(c, 0.0);
        }
        case 8u: {
            b.p[0] = vec4<f32>(c, textured_coat_weight(c, b.p[1].xyz));
        }
        default: {}
    }
    return b;
}

// Material::normal_map_at: the tangent-space normal of texel t (RGBA in [0, 1] → [−1, 1]; x and
// y scaled by glTF's normalTexture.scale; z kept above 10⁻⁴).
fn tangent_space_normal(t: vec4<f32>, scale: f32) -> vec3<f32> {
    let x = (2.0 * t.x - 1.0) * scale;
    let y = (2.0 * t.y - 1.0) * scale;
    let z = max(2.0 * t.z - 1.0, 1e-4);
    return normalize(vec3<f32>(x, y, z));
}

// lustre_shade::path::mapped_normal: the normal-mapped shading normal and the tangent, from the
// interpolated normal ns, a tangent t, the bitangent's sign hand (glTF: B = hand · ns × T) and the
// tangent-space normal; ns and t unchanged where the tangent is parallel to ns, (ns, T) where
// the mapped normal vanishes.
fn mapped_normal(ns: vec3<f32>, t: vec3<f32>, hand: f32, n_ts: vec3<f32>) -> array<vec3<f32>, 2> {
    let tp = t - ns * dot(ns, t);
    let lt = length(tp);
    if (!(lt > 0.0 && lt <= 3.4e38)) {
        return array<vec3<f32>, 2>(ns, t);
    }
    let tn = tp / lt;
    let bn = cross(ns, tn) * hand;
    let m = tn * n_ts.x + bn * n_ts.y + ns * n_ts.z;
    let lm = length(m);
    if (!(lm > 0.0 && lm <= 3.4e38)) {
        return array<vec3<f32>, 2>(ns, tn);
    }
    return array<vec3<f32>, 2>(m / lm, tn);
}
