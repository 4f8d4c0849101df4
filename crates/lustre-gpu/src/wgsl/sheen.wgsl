// module sheen: the KHR_materials_sheen lobe — Charlie D, Neubelt V and the tabulated
// directional albedo E(μ, r) (its fit's coefficients are appended below this text from the
// Rust constant). CPU twin: lustre_brdf::models::sheen::{sheen_alpha, charlie_d, neubelt_v,
// sheen_albedo}. α = max(r, 0.07)², D = (2 + 1/α) sin(θh)^(1/α) / (2π), V = 1 / (4 (cos θi +
// cos θo − cos θi cos θo)); ln E = Σᵢ xⁱ Σⱼ c[i][j] yʲ, x = μ/(r + 0.08), y = ln r.

fn sheen_alpha(r: f32) -> f32 {
    let c = clamp(r, 0.07, 1.0);
    return c * c;
}

fn charlie_d(alpha: f32, cos_h: f32) -> f32 {
    let inv = 1.0 / alpha;
    let sin2 = max(1.0 - cos_h * cos_h, 0.0);
    return (2.0 + inv) * pow(sin2, 0.5 * inv) / (2.0 * PI);
}

fn neubelt_v(cos_i: f32, cos_o: f32) -> f32 {
    if (!(cos_i > 0.0 && cos_o > 0.0)) {
        return 0.0;
    }
    return 1.0 / (4.0 * (cos_i + cos_o - cos_i * cos_o));
}

fn sheen_albedo(mu: f32, r_in: f32) -> f32 {
    let r = clamp(r_in, 0.07, 1.0);
    let x = clamp(mu, 0.0, 1.0) / (r + 0.08);
    let y = log(r);
    var p = 0.0;
    for (var i = 5; i >= 0; i = i - 1) {
        let c = SHEEN_ALBEDO_FIT[i];
        p = p * x + (((c.w * y + c.z) * y + c.y) * y + c.x);
    }
    return exp(clamp(p, -30.0, 3.0));
}
