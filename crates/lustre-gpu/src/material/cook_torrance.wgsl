// module cook_torrance: the per-channel Cook-Torrance of `lustre fit` with the Beckmann or GGX
// distribution and the closed-form Smith G1 (GPU kinds 17 and 18).
// CPU twins: lustre_brdf::models::cook_torrance::CookTorrance::{eval, pdf, sample},
// lustre_brdf::microfacet::ndf::Ndf::{d, sample_h, pdf_h}, lustre_brdf::microfacet::smith::
// {g1_beckmann, g1_ggx}, lustre_brdf::microfacet::fresnel::Fresnel::eval (generalized Schlick).
// Equations (004 Eq. III.1, III.2, V.5):
// f = ρd/π + (ρs/π) F(ωi·h) D(θh) G1(θi) G1(θo) / (cos θi cos θo) per channel;
// D = P22(tan²θh)/(π cos⁴θh), Beckmann P22 = e^{−x/α²}/α², GGX P22 = α²/(α² + x)²;
// F = F0 + (1 − F0)(1 − cos θd)⁵ − F1 cos θd; G1 = 1/(1 + Λ) (microfacet.wgsl's Λ).
// Sampling (004 §V.3.5): the diffuse lobe (cosine) with probability 1 − p_spec,
// p_spec = ρ̄s/(ρ̄d + ρ̄s) (channel means), else a channel's distribution picked ∝ ρs (channels
// with the same distribution share one), h with φ = 2πu1 and tan²θh from u2 (Beckmann
// −α² ln(1 − u2), GGX α² u2/(1 − u2)), ωi = ωo reflected about h; pdf = the whole mixture,
// (1 − p_spec) cos θi/π + p_spec Σ wₗ D_l(h) cos θh / (4 ωo·h).
//
// Layout of the 32 floats (fit_models::pack_cook_torrance): channel c = 0, 1, 2 at 5c:
// ρd, ρs, α, F0, F1; [15] flags as an exact small integer: bit c set = channel c has the
// closed-form Smith G1 (clear: G1 = 1), bit 3 set = GGX (clear: Beckmann); [16 ..] zero.

struct CtChannel {
    rho_d: f32,
    rho_s: f32,
    alpha: f32,
    f0: f32,
    f1: f32,
    smith: u32,
}

// The sampling lobes (distinct distributions with ρs > 0) and their weights, shared with sgd.
struct CtLobes {
    alpha: vec3<f32>,
    w: vec3<f32>,
    count: u32,
    p_spec: f32,
}

struct CookTorrance {
    ch: array<CtChannel, 3>,
    // MICROFACET_BECKMANN or MICROFACET_GGX.
    dist: u32,
    lobes: CtLobes,
}

// Fresnel::GeneralizedSchlick::eval (004 Eq. V.5); the argument clamped to [0, 1].
fn ct_fresnel(f0: f32, f1: f32, cos_d: f32) -> f32 {
    let c = select(0.0, min(cos_d, 1.0), cos_d > 0.0);
    let m = 1.0 - c;
    let m5 = (m * m) * (m * m) * m;
    return f0 + (1.0 - f0) * m5 - f1 * c;
}

// Ndf::d for GGX: α²/(π(α² cos²θ + sin²θ)²), finite at grazing; h a unit vector.
fn ct_ggx_d(alpha: f32, h: vec3<f32>) -> f32 {
    if (!(h.z > 0.0)) {
        return 0.0;
    }
    let c = min(h.z, 1.0);
    let a2 = alpha * alpha;
    let d = a2 * c * c + (h.x * h.x + h.y * h.y);
    return a2 / (PI * d * d);
}

// Ndf::d for Beckmann: e^{−tan²θ/α²}/(π α² cos⁴θ), in logarithms (cos⁴θ underflows in f32).
fn ct_beckmann_d(alpha: f32, h: vec3<f32>) -> f32 {
    if (!(h.z > 0.0)) {
        return 0.0;
    }
    let c = min(h.z, 1.0);
    let a2 = alpha * alpha;
    let x = (h.x * h.x + h.y * h.y) / (c * c);
    return exp(-x / a2 - log(PI * a2) - 4.0 * log(c));
}

fn ct_d(dist: u32, alpha: f32, h: vec3<f32>) -> f32 {
    if (dist == MICROFACET_GGX) {
        return ct_ggx_d(alpha, h);
    }
    return ct_beckmann_d(alpha, h);
}

// g1_beckmann / g1_ggx of the direction w (cos θ = w.z > 0): 1/(1 + Λ).
fn ct_smith_g1(dist: u32, alpha: f32, w: vec3<f32>) -> f32 {
    if (!(w.z > 0.0)) {
        return 0.0;
    }
    let l = microfacet_lambda(Microfacet(alpha, alpha, dist), w);
    if (l < 0.0) {
        return 0.0;
    }
    return 1.0 / (1.0 + l);
}

// Ndf::sample_h's last step: the unit normal with tan²θ = x and φ = 2πu1.
fn ct_normal_from_x(x: f32, u1: f32) -> vec3<f32> {
    let cos_t = 1.0 / sqrt(1.0 + x);
    let sin_t = sqrt(x / (1.0 + x));
    let phi = 2.0 * PI * u1;
    return vec3<f32>(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// Ndf::sample_h for Beckmann and GGX (u2 clamped below 1).
fn ct_sample_h(dist: u32, alpha: f32, u1: f32, u2_in: f32) -> vec3<f32> {
    let u2 = clamp(u2_in, 0.0, MIX_ONE_MINUS_EPSILON);
    let a2 = alpha * alpha;
    var x: f32;
    if (dist == MICROFACET_GGX) {
        x = a2 * u2 / (1.0 - u2);
    } else {
        x = -a2 * mix_ln_one_minus(u2);
    }
    return ct_normal_from_x(x, u1);
}

// CookTorrance::new's sampling lobes: channels whose distribution equals an earlier channel's
// (same[c] = that channel, else c) share its lobe; lobes of zero weight dropped; p_spec from
// the channel means.
fn ct_lobes(alpha: vec3<f32>, rho_d: vec3<f32>, rho_s: vec3<f32>, same: vec3<u32>) -> CtLobes {
    var out = CtLobes(vec3<f32>(0.0), vec3<f32>(0.0), 0u, 0.0);
    var w = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        w[same[c]] += rho_s[c];
    }
    let total = w.x + w.y + w.z;
    if (total > 0.0) {
        for (var c = 0u; c < 3u; c++) {
            if (same[c] == c && w[c] > 0.0) {
                out.alpha[out.count] = alpha[c];
                out.w[out.count] = w[c] / total;
                out.count += 1u;
            }
        }
    }
    let rd = (rho_d.x + rho_d.y + rho_d.z) / 3.0;
    let rs = (rho_s.x + rho_s.y + rho_s.z) / 3.0;
    if (rd + rs > 0.0) {
        out.p_spec = rs / (rd + rs);
    }
    return out;
}

// same[c] for distributions given by their parameters (equal parameters, equal distribution).
fn ct_same(a: vec3<f32>, b: vec3<f32>) -> vec3<u32> {
    var same = vec3<u32>(0u, 1u, 2u);
    if (a.y == a.x && b.y == b.x) {
        same.y = 0u;
    }
    if (a.z == a.x && b.z == b.x) {
        same.z = 0u;
    } else if (a.z == a.y && b.z == b.y) {
        same.z = same.y;
    }
    return same;
}

fn cook_torrance_unpack(p: array<vec4<f32>, 8>) -> CookTorrance {
    var f = mix_floats(p);
    let flags = u32(f[15]);
    var m: CookTorrance;
    m.dist = select(MICROFACET_BECKMANN, MICROFACET_GGX, (flags & 8u) != 0u);
    for (var c = 0u; c < 3u; c++) {
        let b = 5u * c;
        m.ch[c] = CtChannel(f[b], f[b + 1u], f[b + 2u], f[b + 3u], f[b + 4u], (flags >> c) & 1u);
    }
    let alpha = vec3<f32>(f[2], f[7], f[12]);
    m.lobes = ct_lobes(alpha, vec3<f32>(f[0], f[5], f[10]), vec3<f32>(f[1], f[6], f[11]),
                       ct_same(alpha, alpha));
    return m;
}

// The half vector of cook_torrance_eval and sgd_eval: h, ωi·h and cos θi cos θo; `above`
// false where ωi or ωo is not above the surface (f = 0, the other fields 0).
struct CtHalf {
    h: vec3<f32>,
    cos_d: f32,
    cos_io: f32,
    above: bool,
}

fn ct_half(wi: vec3<f32>, wo: vec3<f32>) -> CtHalf {
    let ci = wi.z;
    let co = wo.z;
    if (!(ci > 0.0 && co > 0.0)) {
        return CtHalf(vec3<f32>(0.0), 0.0, 0.0, false);
    }
    let hv = wi + wo;
    let h = hv / length(hv);
    return CtHalf(h, dot(wi, h), ci * co, true);
}

// One channel of cook_torrance_eval and sgd_eval (004 Eq. III.1):
// (ρd + ρs F(ωi·h) D g_i g_o / (cos θi cos θo))/π, the specular term 0 where ρs = 0; g_i and
// g_o the shadowing, multiplied in that order (sgd: G1(ωi) and G1(ωo); cook_torrance: its
// product G1(ωi) G1(ωo), or 1, and 1).
fn ct_channel(rho_d: f32, rho_s: f32, f0: f32, f1: f32, d: f32, g_i: f32, g_o: f32,
              e: CtHalf) -> f32 {
    var spec = 0.0;
    if (rho_s != 0.0) {
        spec = rho_s * ct_fresnel(f0, f1, e.cos_d) * d * g_i * g_o / e.cos_io;
    }
    return (rho_d + spec) / PI;
}

// One channel of cook_torrance_eval.
fn cook_torrance_channel(dist: u32, q: CtChannel, e: CtHalf, wi: vec3<f32>,
                         wo: vec3<f32>) -> f32 {
    if (q.rho_s == 0.0) {
        // No specular term: D and G are not evaluated.
        return ct_channel(q.rho_d, 0.0, q.f0, q.f1, 0.0, 1.0, 1.0, e);
    }
    var g = 1.0;
    if (q.smith == 1u) {
        g = ct_smith_g1(dist, q.alpha, wi) * ct_smith_g1(dist, q.alpha, wo);
    }
    return ct_channel(q.rho_d, q.rho_s, q.f0, q.f1, ct_d(dist, q.alpha, e.h), g, 1.0, e);
}

fn cook_torrance_eval(m: CookTorrance, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let e = ct_half(wi, wo);
    if (!e.above) {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(cook_torrance_channel(m.dist, m.ch[0], e, wi, wo),
                     cook_torrance_channel(m.dist, m.ch[1], e, wi, wo),
                     cook_torrance_channel(m.dist, m.ch[2], e, wi, wo));
}

// CookTorrance::pdf, shared with sgd: lobe l draws h with density D_l(h) cos θh of `dist`
// with α = lobes.alpha[l] (sgd passes its GGX proxies).
fn ct_mixture_pdf(lobes: CtLobes, dist: u32, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return 0.0;
    }
    var p = (1.0 - lobes.p_spec) * wi.z / PI;
    if (lobes.p_spec > 0.0) {
        let h = normalize(wi + wo);
        let od = dot(wo, h);
        if (od > 0.0) {
            var ph = 0.0;
            for (var l = 0u; l < lobes.count; l++) {
                ph += lobes.w[l] * ct_d(dist, lobes.alpha[l], h) * h.z;
            }
            p += lobes.p_spec * ph / (4.0 * od);
        }
    }
    return p;
}

fn cook_torrance_pdf(m: CookTorrance, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return ct_mixture_pdf(m.lobes, m.dist, wi, wo);
}

// The direction of CookTorrance::sample before its checks, shared with sgd: the
// diffuse/specular choice with u.x, the lobe with the rescaled u.x, then the lobe's h (of
// `dist` with α = lobes.alpha[l]). Returns vec4(ωi, 1), or vec4(0) for none.
fn ct_sample_direction(lobes: CtLobes, dist: u32, wo: vec3<f32>, u: vec2<f32>) -> vec4<f32> {
    var w: array<f32, 8>;
    w[0] = 1.0 - lobes.p_spec;
    w[1] = lobes.p_spec;
    let s = mix_select(w, 2u, u.x);
    if (s.index == 0u) {
        return vec4<f32>(mix_cosine_hemisphere(s.u, u.y), 1.0);
    }
    if (s.index != 1u) {
        return vec4<f32>(0.0);
    }
    var lw: array<f32, 8>;
    for (var l = 0u; l < 3u; l++) {
        lw[l] = lobes.w[l];
    }
    let k = mix_select(lw, lobes.count, s.u);
    if (k.index >= lobes.count) {
        return vec4<f32>(0.0);
    }
    let h = ct_sample_h(dist, lobes.alpha[k.index], k.u, u.y);
    return vec4<f32>(reflect_about(wo, h), 1.0);
}

// cook_torrance_sample and sgd_sample but the value: ωi from ct_sample_direction and its density
// ct_mixture_pdf (value 0, for the kind to fill in), or no sample where ωo, ωi or the density
// fails its check.
fn ct_sample(lobes: CtLobes, dist: u32, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (!(wo.z > 0.0)) {
        return mix_no_sample();
    }
    let d = ct_sample_direction(lobes, dist, wo, u);
    let wi = d.xyz;
    if (d.w == 0.0 || !(wi.z > 0.0) || !mix_finite3(wi)) {
        return mix_no_sample();
    }
    let pdf = ct_mixture_pdf(lobes, dist, wi, wo);
    if (!(pdf > 0.0 && pdf <= 0x1.fffffep+127f)) {
        return mix_no_sample();
    }
    return BsdfSample(wi, pdf, vec3<f32>(0.0), 0u);
}

fn cook_torrance_sample(m: CookTorrance, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    var s = ct_sample(m.lobes, m.dist, wo, u);
    if (s.pdf > 0.0) {
        s.value = cook_torrance_eval(m, s.wi, wo);
    }
    return s;
}
