// module microfacet: anisotropic GGX and Beckmann microfacet distributions with visible-normal
// sampling, and the rough-conductor lobe built on them (unit Fresnel: the caller multiplies by
// F(ωi·h) and the reflectance). CPU twins: lustre_brdf::microfacet::distribution::
// MicrofacetDistribution::{d, lambda, g1, pdf_visible, sample_visible} and
// lustre_brdf::models::rough_conductor::RoughConductor::{eval, pdf, sample}. Equations:
// Beckmann D(m) = exp(−((mx/αu)² + (my/αv)²)/mz²) / (π αu αv mz⁴);
// GGX D(m) = 1 / (π αu αv ((mx/αu)² + (my/αv)² + mz²)²);
// Smith Λ, a = cos θ / √(αu² x² + αv² y²): GGX (√(1 + 1/a²) − 1)/2, Beckmann
// (erf(a) − 1)/2 + e^{−a²}/(2a√π) (Heitz 2014, Eqs. 72, 86); G1 = 1/(1 + Λ);
// D_v(m) = G1(v, m) max(0, v·m) D(m) / cos θv; f = D G1(ωi) G1(ωo) / (4 cos θi cos θo)
// (Walter et al. 2007, Eq. 20); p(ωi) = D(h) G1(ωo, h) / (4 cos θo). Sampling: GGX by Heitz 2018
// (JCGT 7(4), listing 1), Beckmann by stretched slopes (Heitz & d'Eon 2014, §4), the slope
// marginal inverted by Newton's method with bisection as on the CPU, in f32.

// kind: 0 Beckmann, 1 GGX (MicrofacetType).
struct Microfacet {
    alpha_u: f32,
    alpha_v: f32,
    kind: u32,
}

const MICROFACET_BECKMANN: u32 = 0u;
const MICROFACET_GGX: u32 = 1u;

// erf(x) by Abramowitz & Stegun 7.1.26 (absolute error < 1.5e-7), odd.
fn erf_f32(x: f32) -> f32 {
    let a = abs(x);
    let t = 1.0 / (1.0 + 0.3275911 * a);
    let p = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741
        + t * (-1.453152027 + t * 1.061405429))));
    let y = 1.0 - p * exp(-a * a);
    return select(y, -y, x < 0.0);
}

// erf⁻¹ on (−1, 1), Giles' single-precision polynomial (pattern::gauss_quantile(u) is
// erf⁻¹(2u − 1)).
fn erfinv_f32(x: f32) -> f32 {
    return gauss_quantile(0.5 * (x + 1.0));
}

// MicrofacetDistribution::d: D(m) in 1/sr, 0 below the surface or where D·mz ≤ 1e-20.
fn microfacet_d(mf: Microfacet, m: vec3<f32>) -> f32 {
    let cz = m.z;
    if (!(cz > 0.0)) {
        return 0.0;
    }
    let x = m.x / mf.alpha_u;
    let y = m.y / mf.alpha_v;
    let c2 = cz * cz;
    var r: f32;
    if (mf.kind == MICROFACET_BECKMANN) {
        r = exp(-(x * x + y * y) / c2) / (PI * mf.alpha_u * mf.alpha_v * c2 * c2);
    } else {
        let t = x * x + y * y + c2;
        r = 1.0 / (PI * mf.alpha_u * mf.alpha_v * t * t);
    }
    if (r * cz > 1e-20 && r <= 3.4e38) {
        return r;
    }
    return 0.0;
}

// MicrofacetDistribution::lambda: Smith Λ(v); −1 stands for +∞ (v in the surface plane).
fn microfacet_lambda(mf: Microfacet, v: vec3<f32>) -> f32 {
    let ax = mf.alpha_u * v.x;
    let ay = mf.alpha_v * v.y;
    let xy2 = ax * ax + ay * ay;
    if (xy2 == 0.0) {
        return 0.0;
    }
    let z2 = v.z * v.z;
    if (z2 == 0.0) {
        return -1.0;
    }
    if (mf.kind == MICROFACET_GGX) {
        return 0.5 * (sqrt(1.0 + xy2 / z2) - 1.0);
    }
    let a = sqrt(z2 / xy2);
    if (a > 12.0) {
        return 0.0;
    }
    return max(-0.5 * (1.0 - erf_f32(a)) + exp(-a * a) / (2.0 * a * sqrt(PI)), 0.0);
}

// MicrofacetDistribution::g1: 1/(1 + Λ(v)), 0 when v sees the back of m or they disagree on
// the side.
fn microfacet_g1(mf: Microfacet, v: vec3<f32>, m: vec3<f32>) -> f32 {
    if (dot(v, m) * v.z <= 0.0) {
        return 0.0;
    }
    let l = microfacet_lambda(mf, v);
    if (l < 0.0) {
        return 0.0;
    }
    return 1.0 / (1.0 + l);
}

// MicrofacetDistribution::pdf_visible: D_v(m) for v above the surface, else 0.
fn microfacet_pdf_visible(mf: Microfacet, v: vec3<f32>, m: vec3<f32>) -> f32 {
    if (!(v.z > 0.0)) {
        return 0.0;
    }
    let vm = dot(v, m);
    if (vm <= 0.0) {
        return 0.0;
    }
    return microfacet_d(mf, m) * microfacet_g1(mf, v, m) * vm / v.z;
}

// Heitz 2018, listing 1: a GGX normal visible from v.
fn sample_visible_ggx(mf: Microfacet, v: vec3<f32>, u1: f32, u2: f32) -> vec3<f32> {
    let vh = normalize(vec3<f32>(mf.alpha_u * v.x, mf.alpha_v * v.y, v.z));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if (lensq > 0.0) {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u1);
    let phi = 2.0 * PI * u2;
    let p1 = r * cos(phi);
    var p2 = r * sin(phi);
    let s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * p2;
    let nh = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
    return normalize(vec3<f32>(mf.alpha_u * nh.x, mf.alpha_v * nh.y, max(nh.z, 0.0)));
}

// beckmann_slopes_11: the slopes of a visible normal of the α = 1 Beckmann distribution seen
// at cos θ, sin θ (azimuth 0; sin θ is passed, as √(1 − cos²θ) loses it in f32 near θ = 0); x̃ inverts C(x̃) = 1 + erf(x̃) + tanθ e^{−x̃²}/√π on (−∞, cot θ] by
// Newton's method safeguarded by bisection on [−6, cot θ], ỹ = erf⁻¹(2u2 − 1).
fn beckmann_slopes_11(cos_theta: f32, sin_t: f32, u1_in: f32, u2_in: f32) -> vec2<f32> {
    let u1 = clamp(u1_in, 1e-7, 1.0 - 1e-7);
    let u2 = clamp(u2_in, 1e-7, 1.0 - 1e-7);
    let sy = erfinv_f32(2.0 * u2 - 1.0);
    if (sin_t < 1e-9) {
        return vec2<f32>(erfinv_f32(2.0 * u1 - 1.0), sy);
    }
    let tan_t = sin_t / cos_theta;
    let cot_t = cos_theta / sin_t;
    let inv_sqrt_pi = 1.0 / sqrt(PI);
    var lo = -6.0;
    var hi = min(cot_t, 6.0);
    let norm = 1.0 + erf_f32(cot_t) + inv_sqrt_pi * tan_t * exp(-cot_t * cot_t);
    let target_value = u1 * norm;
    let e_hi = erf_f32(cot_t);
    let guess = e_hi - (e_hi + 1.0) * erf_f32(sqrt(-log(u1)));
    var x = clamp(erfinv_f32(clamp(guess, -1.0 + 1e-6, 1.0 - 1e-6)), lo, hi);
    for (var k = 0; k < 24; k++) {
        let f = 1.0 + erf_f32(x) + inv_sqrt_pi * tan_t * exp(-x * x) - target_value;
        if (f > 0.0) {
            hi = x;
        } else {
            lo = x;
        }
        if (abs(f) <= 1e-6 * norm || hi - lo < 1e-6) {
            break;
        }
        let deriv = 2.0 * inv_sqrt_pi * exp(-x * x) * (1.0 - x * tan_t);
        let next = x - f / deriv;
        if (deriv > 0.0 && next > lo && next < hi) {
            x = next;
        } else {
            x = 0.5 * (lo + hi);
        }
    }
    return vec2<f32>(x, sy);
}

// Stretched-slope sampling of Beckmann visible normals (Heitz & d'Eon 2014, §4).
fn sample_visible_beckmann(mf: Microfacet, v: vec3<f32>, u1: f32, u2: f32) -> vec3<f32> {
    let vs = normalize(vec3<f32>(mf.alpha_u * v.x, mf.alpha_v * v.y, v.z));
    // sin θ of the stretched view from its tangential part (no cancellation near θ = 0).
    let sin_t = length(vs.xy);
    var cos_p = 1.0;
    var sin_p = 0.0;
    if (sin_t > 1e-12) {
        cos_p = vs.x / sin_t;
        sin_p = vs.y / sin_t;
    }
    let s = beckmann_slopes_11(vs.z, sin_t, u1, u2);
    let x = (cos_p * s.x - sin_p * s.y) * mf.alpha_u;
    let y = (sin_p * s.x + cos_p * s.y) * mf.alpha_v;
    return normalize(vec3<f32>(-x, -y, 1.0));
}

// MicrofacetDistribution::sample_visible: a normal visible from v, or vec3(0) for none (v
// below the surface, or a result that is not finite or not above the surface).
fn microfacet_sample_visible(mf: Microfacet, v: vec3<f32>, u1: f32, u2: f32) -> vec3<f32> {
    if (!(v.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    var m: vec3<f32>;
    if (mf.kind == MICROFACET_GGX) {
        m = sample_visible_ggx(mf, v, u1, u2);
    } else {
        m = sample_visible_beckmann(mf, v, u1, u2);
    }
    if (!(m.z > 0.0 && m.z <= 1.0 && abs(m.x) <= 1.0 && abs(m.y) <= 1.0)) {
        return vec3<f32>(0.0);
    }
    return m;
}

// RoughConductor::eval with F = 1 and unit reflectance: D G1(ωi) G1(ωo) / (4 cos θi cos θo).
fn microfacet_eval(mf: Microfacet, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return 0.0;
    }
    let h = normalize(wi + wo);
    let d = microfacet_d(mf, h);
    if (d == 0.0) {
        return 0.0;
    }
    let g = microfacet_g1(mf, wi, h) * microfacet_g1(mf, wo, h);
    return d * g / (4.0 * wi.z * wo.z);
}

// RoughConductor::pdf: D(h) G1(ωo, h) / (4 cos θo).
fn microfacet_pdf(mf: Microfacet, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return 0.0;
    }
    let h = normalize(wi + wo);
    if (dot(wo, h) <= 0.0 || dot(wi, h) <= 0.0) {
        return 0.0;
    }
    return microfacet_d(mf, h) * microfacet_g1(mf, wo, h) / (4.0 * wo.z);
}

// RoughConductor::sample's warp: ωi = ωo reflected about a visible normal, and its pdf;
// w = 0 when there is none (as the CPU's None).
fn microfacet_sample(mf: Microfacet, wo: vec3<f32>, u1: f32, u2: f32) -> vec4<f32> {
    let m = microfacet_sample_visible(mf, wo, u1, u2);
    if (m.z == 0.0) {
        return vec4<f32>(0.0);
    }
    let wi = reflect_about(wo, m);
    if (!(wi.z > 0.0)) {
        return vec4<f32>(0.0);
    }
    let p = microfacet_pdf(mf, wi, wo);
    if (!(p > 0.0 && p <= 3.4e38)) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(wi, p);
}
