// module textured: a material's textured parameters and normal map at a pixel. CPU twins:
// lustre_scene::Material::with_bsdf_at (the clamps of `unit` and `clamp_alpha`, the glTF
// metallic-roughness model's choice of BRDF or (rough) dielectric by transmission),
// Material::normal_map_at and lustre_trace::path's `mapped_normal`. Binding-free: the caller
// samples the textures (factor × texel, as `TexturedRgb::at` / `TexturedScalar::at`) and passes
// the values; which parameter each value is depends on the kind (lustre_gpu::material::scene::
// pack_material_params): rgb = the Lambert / plastic diffuse reflectance, the conductor's
// specular colour or the glTF base colour; s = (αu, αv, −) of a rough conductor, (α, −, −) of a
// rough dielectric, (α, −, −) of a rough plastic whose roughness is textured (its coating's grid
// in the table buffer, read through `bsdf_table`), (metallic, roughness, transmission) of the
// glTF model. `textured_bsdf`, the dispatch to each kind's `<kind>_textured`, is generated from
// lustre_gpu::material::kinds::KINDS and appended below this file's text.

// Material::normal_map_at: the tangent-space normal of texel t (RGBA in [0, 1] → [−1, 1]; x and
// y scaled by glTF's normalTexture.scale; z kept above 10⁻⁴).
fn tangent_space_normal(t: vec4<f32>, scale: f32) -> vec3<f32> {
    let x = (2.0 * t.x - 1.0) * scale;
    let y = (2.0 * t.y - 1.0) * scale;
    let z = max(2.0 * t.z - 1.0, 1e-4);
    return normalize(vec3<f32>(x, y, z));
}

// lustre_trace::path::mapped_normal: the normal-mapped shading normal and the tangent, from the
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
