// module fresnel: Fresnel terms and the small sampling helpers the scene models share. CPU
// twins: lustre_brdf::microfacet::fresnel::{fresnel_dielectric, fresnel_conductor},
// lustre_brdf::models::dielectric::refract, lustre_brdf::sampling::{split_uniform,
// cosine_hemisphere}. Equations: the unpolarised dielectric reflectance
// ½((cos i − η cos t)/(cos i + η cos t))² + ½((cos t − η cos i)/(cos t + η cos i))² with total
// internal reflection; the conductor reflectance of index η + ik (Mitsuba's fresnel_conductor);
// refraction m (w·m η_ti + cos θt) − w η_ti.

// The largest f32 below 1 (the CPU's 1 − ε clamps).
const ONE_MINUS_EPS: f32 = 0.99999994;

// fresnel_dielectric: (r, cos θt (signed, towards the other side), η_it, η_ti).
fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> vec4<f32> {
    let outside = cos_theta_i >= 0.0;
    var eta_it = eta;
    var eta_ti = 1.0 / eta;
    if (!outside) {
        eta_it = 1.0 / eta;
        eta_ti = eta;
    }
    let cos_t2 = 1.0 - (1.0 - cos_theta_i * cos_theta_i) * eta_ti * eta_ti;
    let ci = abs(cos_theta_i);
    let ct = sqrt(max(cos_t2, 0.0));
    var r: f32;
    if (eta == 1.0) {
        r = 0.0;
    } else if (ci == 0.0 || cos_t2 <= 0.0) {
        r = 1.0;
    } else {
        let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
        let a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
        r = 0.5 * (a_s * a_s + a_p * a_p);
    }
    var cos_t = 0.0;
    if (cos_t2 > 0.0) {
        cos_t = select(ct, -ct, outside);
    }
    return vec4<f32>(clamp(r, 0.0, 1.0), cos_t, eta_it, eta_ti);
}

// fresnel_conductor for one channel.
fn fresnel_conductor1(cos_theta_i: f32, eta: f32, k: f32) -> f32 {
    let c = clamp(cos_theta_i, 0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - s2;
    let a2pb2 = sqrt(max(t1 * t1 + 4.0 * k * k * eta * eta, 0.0));
    let a = sqrt(max(0.5 * (a2pb2 + t1), 0.0));
    let term1 = a2pb2 + c2;
    let term2 = 2.0 * c * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2pb2 * c2 + s4;
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    let f = 0.5 * (rs + rp);
    if (!(abs(f) <= 3.4e38)) {
        return 1.0;
    }
    return clamp(f, 0.0, 1.0);
}

// ComplexIor::fresnel: per channel.
fn fresnel_conductor(cos_theta_i: f32, eta: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(fresnel_conductor1(cos_theta_i, eta.x, k.x),
                     fresnel_conductor1(cos_theta_i, eta.y, k.y),
                     fresnel_conductor1(cos_theta_i, eta.z, k.z));
}

// dielectric::refract.
fn refract_through(w: vec3<f32>, m: vec3<f32>, cos_theta_t: f32, eta_ti: f32) -> vec3<f32> {
    return m * (dot(w, m) * eta_ti + cos_theta_t) - w * eta_ti;
}

// split_uniform: two numbers from the odd and even bits of u's binary fraction. u is read on
// the 2⁻²⁴ grid (exact for the lattice and CK points, which lie on it): bit j of m = u·2²⁴ is
// bit j + 28 of the CPU's 52, so the odd ones go to a, the even ones to b.
fn split_uniform(u: f32) -> vec2<f32> {
    let m = u32(clamp(u, 0.0, 1.0) * 16777216.0);
    var a = 0u;
    var b = 0u;
    for (var j = 0u; j < 24u; j++) {
        let bit = (m >> j) & 1u;
        if ((j & 1u) == 1u) {
            a |= bit << ((j + 27u) / 2u);
        } else {
            b |= bit << ((j + 28u) / 2u);
        }
    }
    let scale = 1.0 / 67108864.0;
    return vec2<f32>(f32(a) * scale + 0.5 * scale, f32(b) * scale + 0.5 * scale);
}

// sampling::cosine_hemisphere.
fn cosine_hemisphere(u1: f32, u2: f32) -> vec3<f32> {
    let r = sqrt(u1);
    let phi = 2.0 * PI * u2;
    return vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u1, 0.0)));
}
