// module sgd: the per-channel Cook-Torrance with the shifted gamma distribution (SGD) and the
// Eq. V.3 shadowing approximation — the published fits of Bagher et al. (`sgd:NAME`) and the
// SGD fits `lustre fit` writes (GPU kind 16).
// CPU twins: lustre_brdf::models::cook_torrance::CookTorrance::{eval, pdf, sample} with
// Ndf::Sgd (lustre_brdf::microfacet::ndf::{Sgd, Ndf::d, sample_h, pdf_h}),
// lustre_brdf::microfacet::smith::SgdG1Approx::eval and lustre_brdf::numeric::upper_gamma.
// Equations (004 Eq. III.1, V.2, V.3, V.5): f per channel as in cook_torrance.wgsl with
// D = P22(tan²θh)/(π cos⁴θh), P22(x) = kap e^{−A} A^{−p}, A = α + x/α,
// kap = 1/(α Γ(1−p, α)) (computed here, see below); G1(θ) = clamp(1 + λ(1 − e^{c(θ−θ0)^k}), 0, 1)
// for θ > θ0, 1 below. Sampling as cook_torrance.wgsl with the GGX proxy of each distinct
// channel distribution (x = α_proxy² u2/(1 − u2); the CPU rounds α_proxy to a half-precision
// value, so the layout carries it exactly).
//
// Layout of the 32 floats (fit_models::pack_sgd): channel c = 0, 1, 2 at 10c: ρd, ρs, α, p,
// F0, F1, λ, ln c, k, θ0 (λ = 0 and θ0 = 4: no shadowing); [30] the bits of
// pack2x16float(α_proxy r, α_proxy g), [31] of pack2x16float(α_proxy b, 1), decoded by
// half_to_f32. kap is not stored:
// the packer checks that the model's kap is 1/(αΓ(1−p, α)) (every `lustre fit` SGD fit; the
// published table to its six printed digits except chrome) and sgd_unpack computes it with
// upper_gamma_f32.

struct SgdChannel {
    rho_d: f32,
    rho_s: f32,
    alpha: f32,
    p: f32,
    ln_kap: f32,
    f0: f32,
    f1: f32,
    lambda: f32,
    ln_c: f32,
    k: f32,
    theta0: f32,
}

struct Sgd {
    ch: array<SgdChannel, 3>,
    // The GGX proxies of the distinct distributions (alpha) and their weights.
    lobes: CtLobes,
}

// Euler's constant γ.
const EULER_GAMMA: f32 = 0.5772156649;

// (Γ(1 + s) − 1)/s for |s| < 1 from the Taylor series of 1/Γ(1 + s) = 1 + s R(s)
// (Abramowitz & Stegun 6.1.34), without cancellation near s = 0.
fn gamma1p_minus1_over_s(s: f32) -> f32 {
    var r = -0.0000000011812746;
    r = 0.0000000050020075 + s * r;
    r = 0.0000000061160950 + s * r;
    r = -0.0000002056338417 + s * r;
    r = 0.0000011330272320 + s * r;
    r = -0.0000012504934821 + s * r;
    r = -0.0000201348547807 + s * r;
    r = 0.0001280502823882 + s * r;
    r = -0.0002152416741149 + s * r;
    r = -0.0011651675918591 + s * r;
    r = 0.0072189432466630 + s * r;
    r = -0.0096219715278770 + s * r;
    r = -0.0421977345555443 + s * r;
    r = 0.1665386113822915 + s * r;
    r = -0.0420026350340952 + s * r;
    r = -0.6558780715202538 + s * r;
    r = EULER_GAMMA + s * r;
    return -r / (1.0 + s * r);
}

// (eᵗ − 1)/t: its Taylor series for |t| < 0.1 (relative error < 3e-10; exp and log of f32
// near 1 carry absolute, not relative, errors), else directly.
fn expm1_over_t(t: f32) -> f32 {
    if (abs(t) < 0.1) {
        return 1.0 + t * (0.5 + t * (1.0 / 6.0 + t * (1.0 / 24.0 + t * (1.0 / 120.0
            + t * (1.0 / 720.0)))));
    }
    return (exp(t) - 1.0) / t;
}

// Γ(s, x) for s in (−½, 1], x > 0: for x ≤ 2 the series
// Γ(s, x) = (Γ(1+s) − 1)/s − ln x (x^s − 1)/(s ln x) − x^s Σ_{n≥1} (−x)ⁿ/(n!(s + n)),
// which is E1(x) at s = 0 and has no cancellation near s = 0; above 2 the continued fraction
// (modified Lentz) of e^{−x} x^s/(x + 1 − s − …).
fn upper_gamma_base(s: f32, x: f32) -> f32 {
    let lx = log(x);
    if (x <= 2.0) {
        var sum = 0.0;
        var term = 1.0;
        for (var n = 1; n < 40; n++) {
            term *= -x / f32(n);
            let add = term / (s + f32(n));
            sum += add;
            if (abs(add) < 1e-9 * abs(sum)) {
                break;
            }
        }
        return gamma1p_minus1_over_s(s) - lx * expm1_over_t(s * lx) - exp(s * lx) * sum;
    }
    let tiny = 1e-30;
    var b = x + 1.0 - s;
    var c = 1.0 / tiny;
    var d = 1.0 / b;
    var h = d;
    for (var i = 1; i < 100; i++) {
        let an = -f32(i) * (f32(i) - s);
        b += 2.0;
        d = an * d + b;
        if (abs(d) < tiny) {
            d = tiny;
        }
        c = b + an / c;
        if (abs(c) < tiny) {
            c = tiny;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (abs(del - 1.0) < 1e-7) {
            break;
        }
    }
    return exp(-x + s * lx) * h;
}

// numeric::upper_gamma in f32: Γ(s, x) = ∫ₓ^∞ t^{s−1} e^{−t} dt for s in (−4.5, 4.5], x > 0,
// from upper_gamma_base at s moved into (−½, 1] by Γ(s+1, x) = sΓ(s, x) + x^s e^{−x}:
// upwards from s0 in (0, 1] (two positive terms), downwards from s0 in (−½, ½] (the series
// then has no small divisor s + 1).
fn upper_gamma_f32(s: f32, x: f32) -> f32 {
    var s0 = s;
    var up = 0u;
    var down = 0u;
    while (s0 > 1.0 && up < 4u) {
        s0 -= 1.0;
        up++;
    }
    while (s0 <= -0.5 && down < 4u) {
        s0 += 1.0;
        down++;
    }
    var g = upper_gamma_base(s0, x);
    let lx = log(x);
    for (var i = 0u; i < up; i++) {
        // Γ(s0 + 1, x) = s0 Γ(s0, x) + x^{s0} e^{−x}.
        g = s0 * g + exp(s0 * lx - x);
        s0 += 1.0;
    }
    for (var i = 0u; i < down; i++) {
        // Γ(s0 − 1, x) = (Γ(s0, x) − x^{s0−1} e^{−x})/(s0 − 1).
        s0 -= 1.0;
        g = (g - exp(s0 * lx - x)) / s0;
    }
    return g;
}

// SgdG1Approx::eval at the angle of w from the normal (θ from atan2, accurate near 0).
fn sgd_g1(q: SgdChannel, w: vec3<f32>) -> f32 {
    let theta = atan2(length(w.xy), w.z);
    let d = theta - q.theta0;
    if (!(d > 0.0)) {
        return 1.0;
    }
    let e = exp(q.ln_c + q.k * log(d));
    let g = 1.0 + q.lambda * (1.0 - exp(e));
    if (g != g) {
        return 0.0;
    }
    return clamp(g, 0.0, 1.0);
}

// Ndf::d for the SGD: kap e^{−A} A^{−p}/(π cos⁴θ), in logarithms.
fn sgd_d(q: SgdChannel, h: vec3<f32>) -> f32 {
    if (!(h.z > 0.0)) {
        return 0.0;
    }
    let c = min(h.z, 1.0);
    let x = (h.x * h.x + h.y * h.y) / (c * c);
    let a = q.alpha + x / q.alpha;
    return exp(q.ln_kap - a - q.p * log(a) - log(PI) - 4.0 * log(c));
}

// A non-negative IEEE half-precision value from its 16 bits, exactly (unpack2x16float by
// hand: the builtin needs a capability some backends lack).
fn half_to_f32(h: u32) -> f32 {
    let e = (h >> 10u) & 0x1fu;
    let m = f32(h & 0x3ffu);
    if (e == 0u) {
        return ldexp(m, -24);
    }
    return ldexp(1.0 + m / 1024.0, i32(e) - 15);
}

fn sgd_unpack(p: array<vec4<f32>, 8>) -> Sgd {
    var f = mix_floats(p);
    var m: Sgd;
    for (var c = 0u; c < 3u; c++) {
        let b = 10u * c;
        let alpha = f[b + 2u];
        let sp = f[b + 3u];
        let ln_kap = -log(alpha) - log(upper_gamma_f32(1.0 - sp, alpha));
        m.ch[c] = SgdChannel(f[b], f[b + 1u], alpha, sp, ln_kap, f[b + 4u], f[b + 5u],
                             f[b + 6u], f[b + 7u], f[b + 8u], f[b + 9u]);
    }
    let rg = bitcast<u32>(f[30]);
    let proxy = vec3<f32>(half_to_f32(rg & 0xffffu), half_to_f32(rg >> 16u),
                          half_to_f32(bitcast<u32>(f[31]) & 0xffffu));
    m.lobes = ct_lobes(proxy, vec3<f32>(f[0], f[10], f[20]), vec3<f32>(f[1], f[11], f[21]),
                       ct_same(vec3<f32>(f[2], f[12], f[22]), vec3<f32>(f[3], f[13], f[23])));
    return m;
}

// One channel of sgd_eval.
fn sgd_channel(q: SgdChannel, e: CtHalf, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (q.rho_s == 0.0) {
        // No specular term: D and G are not evaluated.
        return ct_channel(q.rho_d, 0.0, q.f0, q.f1, 0.0, 1.0, 1.0, e);
    }
    return ct_channel(q.rho_d, q.rho_s, q.f0, q.f1, sgd_d(q, e.h), sgd_g1(q, wi), sgd_g1(q, wo),
                      e);
}

fn sgd_eval(m: Sgd, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let e = ct_half(wi, wo);
    if (!e.above) {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(sgd_channel(m.ch[0], e, wi, wo), sgd_channel(m.ch[1], e, wi, wo),
                     sgd_channel(m.ch[2], e, wi, wo));
}

fn sgd_pdf(m: Sgd, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    return ct_mixture_pdf(m.lobes, MICROFACET_GGX, wi, wo);
}

fn sgd_sample(m: Sgd, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    var s = ct_sample(m.lobes, MICROFACET_GGX, wo, u);
    if (s.pdf > 0.0) {
        s.value = sgd_eval(m, s.wi, wo);
    }
    return s;
}
