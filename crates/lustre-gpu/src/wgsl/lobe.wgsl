// module lobe: the Kurt lobe (000 §2.3, 002 §2).
// CPU twins: lustre_brdf::models::kurt::{schlick, lobe_eval} and the Beckmann distribution of
// lustre_brdf::models::kurt (002 Eq. 4–5). Equations: F(u) = r0 + (1 − r0)(1 − u)⁵ (002 Eq. 3);
// D(h) = exp(−tan²θh (cos²φh/mx² + sin²φh/my²)) / (π mx my cos⁴θh) (002 Eq. 4–5);
// f = ks F D / (4 (ωo·h) ((ωi·n)(ωo·n))^α) (002 Eq. 2).

// Schlick F(u) = r0 + (1 − r0)(1 − u)⁵ (000 Eq. 2.9, 002 Eq. 3).
fn schlick(r0: f32, u: f32) -> f32 {
    let m = clamp(1.0 - u, 0.0, 1.0);
    let m2 = m * m;
    return r0 + (1.0 - r0) * m2 * m2 * m;
}

// Beckmann D(h) = exp(−tan²θh (cos²φh/mx² + sin²φh/my²)) / (π mx my cos⁴θh) (002 Eq. 4–5).
fn beckmann_d(mx: f32, my: f32, h: vec3<f32>) -> f32 {
    if (h.z <= 0.0) {
        return 0.0;
    }
    let ax = h.x / (mx * h.z);
    let ay = h.y / (my * h.z);
    let e = -(ax * ax + ay * ay);
    // In logarithms as on the CPU: cos⁴θh and mx·my may under- or overflow in f32.
    return exp(e - log(PI) - log(mx) - log(my) - 4.0 * log(h.z));
}

// lobe_eval with unit ks: F D / (4 (ωo·h) ((ωi·n)(ωo·n))^α) (002 Eq. 2), 1 − F for a
// transmission lobe, in the reflection geometry (both directions above the surface).
fn lobe_eval(lobe: Lobe, transmission: bool, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return 0.0;
    }
    // lustre_brdf::frame::half_vector: none when |wi + wo|² ≤ 1e-24.
    let hs = wi + wo;
    let l2 = dot(hs, hs);
    if (!(l2 > 1e-24)) {
        return 0.0;
    }
    let h = hs / sqrt(l2);
    let u = dot(wo, h);
    if (!(u > 0.0)) {
        return 0.0;
    }
    var fresnel = schlick(lobe.r0, u);
    if (transmission) {
        fresnel = 1.0 - fresnel;
    }
    let d = beckmann_d(lobe.mx, lobe.my, h);
    var shadow = 1.0;
    if (lobe.alpha != 0.0) {
        shadow = pow(wi.z * wo.z, lobe.alpha);
    }
    return fresnel * d / (4.0 * u * shadow);
}
