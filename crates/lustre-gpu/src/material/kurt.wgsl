// module kurt: the Kurt BRDF with Luksch's transmission lobes as a whole BSDF (GPU kind 19).
// CPU twins: lustre_brdf::models::kurt::Kurt::{eval, pdf, sample} and kurt::{lobe_sample_h,
// lobe_pdf}; the lobe value is lobe.wgsl's lobe_eval (kurt::lobe_eval). Equations (000 §3.3,
// §4.4.2): f = kd/π + Σ ks f_rlobe + Σ kt f_tlobe (Eq. 3.6), a transmission lobe being a
// reflection lobe of ωi mirrored through the surface plane with 1 − F (Eq. 3.5); thin and
// two-sided: for ωo below the surface both directions are mirrored first. Sampling: a component
// (diffuse, each lobe) ∝ the luminance of kd, ks, kt picked with u1; diffuse cosine-sampled; a
// lobe draws h by Eq. 4.5–4.7 (φh = atan2(my sin 2πu2, mx cos 2πu2), tan²θh = −ln(1 − u1)/
// (cos²φh/mx² + sin²φh/my²)) and reflects ωo about it (Eq. 4.8), mirrored for transmission;
// pdf = the mixture with lobe density D(h) cos θh / (4 ωo·h) (Eq. 4.9).
//
// Layout of the 32 floats (fit_models::pack_kurt): [0 .. 3] kd; [3] nr + 8 nt (exact small
// integer: reflection and transmission lobe counts, nr + nt ≤ 4); lobe i (reflection lobes
// first) at 4 + 7i: ks (3), mx, my, r0, α; unused lobes zero.

const KURT_MAX_LOBES: u32 = 4u;

struct Kurt {
    kd: vec3<f32>,
    nr: u32,
    nt: u32,
    lobes: array<Lobe, 4>,
}

fn kurt_unpack(p: array<vec4<f32>, 8>) -> Kurt {
    var f = mix_floats(p);
    let counts = u32(f[3]);
    var m: Kurt;
    m.kd = vec3<f32>(f[0], f[1], f[2]);
    m.nr = min(counts % 8u, KURT_MAX_LOBES);
    m.nt = min(counts / 8u, KURT_MAX_LOBES - m.nr);
    for (var i = 0u; i < KURT_MAX_LOBES; i++) {
        let b = 4u + 7u * i;
        m.lobes[i] = Lobe(vec3<f32>(f[b], f[b + 1u], f[b + 2u]), f[b + 3u], f[b + 4u], f[b + 5u],
                          f[b + 6u], 0.0, 0.0, 0u, 0u, 0u);
    }
    return m;
}

// kurt::lobe_pdf: D(h) cos θh / (4 ωo·h), both directions above the surface.
fn kurt_lobe_pdf(l: Lobe, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return 0.0;
    }
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
    return beckmann_d(l.mx, l.my, h) * h.z / (4.0 * u);
}

// kurt::lobe_sample_h (000 Eq. 4.5–4.7).
fn kurt_lobe_sample_h(l: Lobe, u1: f32, u2: f32) -> vec3<f32> {
    let phi0 = 2.0 * PI * u2;
    let phi = atan2(l.my * sin(phi0), l.mx * cos(phi0));
    let sp = sin(phi);
    let cp = cos(phi);
    let a = cp * cp / (l.mx * l.mx) + sp * sp / (l.my * l.my);
    // −ln ξ1 with ξ1 = 1 − u1, accurate for small u1.
    let t2 = -max(mix_ln_one_minus(u1), -87.3) / a;
    let ct = 1.0 / sqrt(1.0 + t2);
    let st = sqrt(t2 / (1.0 + t2));
    return vec3<f32>(st * cp, st * sp, ct);
}

fn kurt_eval(m: Kurt, wi_in: vec3<f32>, wo_in: vec3<f32>) -> vec3<f32> {
    var wi = wi_in;
    var wo = wo_in;
    if (wo.z < 0.0) {
        wi = mirror_z(wi);
        wo = mirror_z(wo);
    }
    if (!(wo.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    var lobes = m.lobes;
    var f = vec3<f32>(0.0);
    if (wi.z > 0.0) {
        f = m.kd / PI;
        for (var i = 0u; i < m.nr; i++) {
            f += lobes[i].ks * lobe_eval(lobes[i], false, wi, wo);
        }
    } else if (wi.z < 0.0) {
        let wm = mirror_z(wi);
        for (var i = m.nr; i < m.nr + m.nt; i++) {
            f += lobes[i].ks * lobe_eval(lobes[i], true, wm, wo);
        }
    }
    return f;
}

// The component weights: luminance of kd, then of each lobe's ks.
fn kurt_weights(m: Kurt) -> array<f32, 8> {
    var lobes = m.lobes;
    var w: array<f32, 8>;
    w[0] = mix_luminance(m.kd);
    for (var i = 0u; i < m.nr + m.nt; i++) {
        w[i + 1u] = mix_luminance(lobes[i].ks);
    }
    return w;
}

fn kurt_pdf(m: Kurt, wi_in: vec3<f32>, wo_in: vec3<f32>) -> f32 {
    var wi = wi_in;
    var wo = wo_in;
    if (wo.z < 0.0) {
        wi = mirror_z(wi);
        wo = mirror_z(wo);
    }
    if (!(wo.z > 0.0)) {
        return 0.0;
    }
    var w = kurt_weights(m);
    var total = 0.0;
    for (var i = 0u; i <= m.nr + m.nt; i++) {
        total += w[i];
    }
    if (!(total > 0.0)) {
        return 0.0;
    }
    var lobes = m.lobes;
    var p = 0.0;
    if (wi.z > 0.0) {
        p = w[0] * wi.z / PI;
        for (var i = 0u; i < m.nr; i++) {
            if (w[i + 1u] > 0.0) {
                p += w[i + 1u] * kurt_lobe_pdf(lobes[i], wi, wo);
            }
        }
    } else if (wi.z < 0.0) {
        let wm = mirror_z(wi);
        for (var i = m.nr; i < m.nr + m.nt; i++) {
            if (w[i + 1u] > 0.0) {
                p += w[i + 1u] * kurt_lobe_pdf(lobes[i], wm, wo);
            }
        }
    }
    return p / total;
}

fn kurt_sample(m: Kurt, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    let flip = wo.z < 0.0;
    let wo_u = select(wo, mirror_z(wo), flip);
    if (!(wo_u.z > 0.0)) {
        return mix_no_sample();
    }
    let n = 1u + m.nr + m.nt;
    let s = mix_select(kurt_weights(m), n, u.x);
    if (s.index >= n) {
        return mix_no_sample();
    }
    var wi_u: vec3<f32>;
    if (s.index == 0u) {
        wi_u = mix_cosine_hemisphere(s.u, u.y);
    } else {
        var lobes = m.lobes;
        let l = lobes[s.index - 1u];
        let h = kurt_lobe_sample_h(l, s.u, u.y);
        if (!(dot(wo_u, h) > 0.0)) {
            return mix_no_sample();
        }
        let r = reflect_about(wo_u, h);
        if (!(r.z > 0.0)) {
            return mix_no_sample();
        }
        wi_u = select(r, mirror_z(r), s.index > m.nr);
    }
    let wi = select(wi_u, mirror_z(wi_u), flip);
    let pdf = kurt_pdf(m, wi, wo);
    if (!(pdf > 0.0 && pdf <= 0x1.fffffep+127f)) {
        return mix_no_sample();
    }
    return BsdfSample(wi, pdf, kurt_eval(m, wi, wo), 0u);
}
