// module frame: vectors in the local shading frame.
// CPU twins: lustre_brdf::frame::{reflect, mirror_z} and lustre_trace::sampling::ShadingFrame::
// to_world. Local = (w·t, w·b, w·n).

// 000 Eq. 4.8: the mirror of w about the unit vector h, 2 (w·h) h − w.
fn reflect_about(w: vec3<f32>, h: vec3<f32>) -> vec3<f32> {
    return 2.0 * dot(w, h) * h - w;
}

// 000 Eq. 3.5: the thin BTDF's direction, w mirrored through the tangent plane.
fn mirror_z(w: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(w.x, w.y, -w.z);
}

// ShadingFrame::to_world: h.x t + h.y b + h.z n.
fn to_world(h: vec3<f32>, t: vec3<f32>, b: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return h.x * t + h.y * b + h.z * n;
}
