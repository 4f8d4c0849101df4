// module material_albedo: a material's diffuse albedo at a hit, the CPU's
// `lustre_trace::bake::diffuse_albedo`, for the light-map and view-dependent shading passes.
// Requires (the pass defines): fn material_row(i: u32) -> vec4<f32>.

// `lustre_trace::bake::diffuse_albedo` as uploaded: c = clamp(base factor · texture, 0, 1), then
// c · k, with k = 1 − clamp(metallic, 0, 1), or 0 where transmission ≥ ½, per pixel when those
// are textured (b.w = 1); a textured plastic's base seen through its coating (b.w = 2):
// k · c / (1 − Fdr · c) (`CoatedBase::kd`, Fdr in the third row's x).
fn albedo(m: u32, uv0: vec2<f32>, uv1: vec2<f32>) -> vec3<f32> {
    let a = material_row(4u * m);
    let b = material_row(4u * m + 1u);
    var k = a.w;
    if b.w > 0.5 && b.w < 1.5 {
        if scalar_at(material_row(4u * m + 3u), uv0, uv1) >= 0.5 {
            return vec3<f32>(0.0);
        }
        k = 1.0 - clamp(scalar_at(material_row(4u * m + 2u), uv0, uv1), 0.0, 1.0);
    }
    let t = bitcast<i32>(b.x);
    if t < 0 {
        return a.xyz * k;
    }
    var uv = uv0;
    if bitcast<u32>(b.y) == 1u {
        uv = uv1;
    }
    var c = a.xyz * texture_sample(u32(t), uv).xyz;
    if !all(abs(c) <= vec3<f32>(3.0e38)) {
        c = vec3<f32>(0.0);
    }
    c = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    if b.w > 1.5 {
        return k * c / (vec3<f32>(1.0) - material_row(4u * m + 2u).x * c);
    }
    return c * k;
}

