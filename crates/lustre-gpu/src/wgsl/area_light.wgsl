// module area_light: textured parallelogram emitters (lustre_adaptive::light::AreaLight, 004
// §IV.5.3), as adaptive_pass::pack_lights lays them out: corner (xyz) and texture width, edge u
// and texture height, edge v and the first texel, the radiance scale (rgb) and the area, the
// emitting side's normal. A pass binds its lights' texels itself (RGB, and in w the spatial
// bandwidth in cycles per metre).

struct AreaLight {
    corner: vec4<f32>,
    edge_u: vec4<f32>,
    edge_v: vec4<f32>,
    radiance: vec4<f32>,
    normal: vec4<f32>,
}

// AreaLight::point: the point at (u, v) ∈ [0, 1]².
fn area_light_point(light: AreaLight, uv: vec2<f32>) -> vec3<f32> {
    return light.corner.xyz + light.edge_u.xyz * uv.x + light.edge_v.xyz * uv.y;
}

// AreaLight::texel: the index among the pass's light texels of the texel holding (u, v).
fn area_light_texel(light: AreaLight, uv: vec2<f32>) -> u32 {
    let tw = u32(light.corner.w);
    let th = u32(light.edge_u.w);
    let x = min(u32(uv.x * f32(tw)), tw - 1u);
    let y = min(u32(uv.y * f32(th)), th - 1u);
    return u32(light.edge_v.w) + y * tw + x;
}
