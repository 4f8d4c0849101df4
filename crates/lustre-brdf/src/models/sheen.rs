//! The sheen lobe of `KHR_materials_sheen`: the "Charlie" distribution (Estevez & Kulla 2017)
//! with Neubelt & Pettineo's visibility, as three.js and Filament evaluate cloth:
//!
//! ```text
//! α = max(r, 0.07)²                         (r: sheenRoughness; three.js clamps r at 0.07)
//! D(h) = (2 + 1/α) sin(θh)^(1/α) / (2π)
//! V(ωi, ωo) = 1 / (4 (cos θi + cos θo − cos θi cos θo))
//! f_sheen = sheenColor · D V
//! E(μ) = ∫ D V cos θi dωi                   (the lobe's directional albedo at cos θo = μ)
//! ```
//!
//! The layer scales the material beneath by min(1 − max(sheenColor)·E(cos θo), 1 −
//! max(sheenColor)·E(cos θi)) — the specification's reciprocal albedo scaling. E is a fit
//! ([`SHEEN_ALBEDO_FIT`]: ln E a polynomial in μ/(r + 0.08) and ln r) of a midpoint quadrature
//! the tests repeat; the WGSL twin evaluates the same polynomial.

use std::f64::consts::PI;

/// The smallest sheen roughness used (three.js and Filament's clamp).
pub const SHEEN_ROUGHNESS_MIN: f64 = 0.07;

/// α of the Charlie distribution at sheen roughness `r`.
pub fn sheen_alpha(r: f64) -> f64 {
    let r = r.clamp(SHEEN_ROUGHNESS_MIN, 1.0);
    r * r
}

/// D(h) = (2 + 1/α) sin(θh)^(1/α) / (2π), from cos θh.
pub fn charlie_d(alpha: f64, cos_h: f64) -> f64 {
    let inv = 1.0 / alpha;
    let sin2 = (1.0 - cos_h * cos_h).max(0.0);
    (2.0 + inv) * sin2.powf(0.5 * inv) / (2.0 * PI)
}

/// V = 1 / (4 (cos θi + cos θo − cos θi cos θo)) (0 unless both cosines are positive).
pub fn neubelt_v(cos_i: f64, cos_o: f64) -> f64 {
    if !(cos_i > 0.0 && cos_o > 0.0) {
        return 0.0;
    }
    1.0 / (4.0 * (cos_i + cos_o - cos_i * cos_o))
}

/// ln E = Σᵢ xⁱ Σⱼ c[i][j] yʲ with x = μ/(r + 0.08), y = ln r ([`sheen_albedo`]): a
/// least-squares fit (weights min(E, 1)) of ln E on 32 × 32 quadrature nodes.
pub const SHEEN_ALBEDO_FIT: [[f64; 4]; 6] = [
    [
        -0.4735508906003694,
        -0.4056086069103628,
        0.2678145551728674,
        0.040822932857742876,
    ],
    [
        -2.748412296963396,
        -0.3761382047947523,
        -0.08141563985462684,
        0.07952934179106845,
    ],
    [
        4.450307194996485,
        2.273320285616547,
        0.09214121339719579,
        -0.1438770134644679,
    ],
    [
        -6.018453605382834,
        -4.2619405963623915,
        -0.6353307482275377,
        0.10787152432170509,
    ],
    [
        3.6024470645909403,
        3.2402854869840545,
        0.8372721260414068,
        0.03351696155034878,
    ],
    [
        -0.906949213700729,
        -0.9960976872079316,
        -0.35522040613258155,
        -0.039918661325699094,
    ],
];

/// E(μ, r) by [`SHEEN_ALBEDO_FIT`] (μ clamped to [0, 1], r to [0.07, 1], ln E to [−30, 3]):
/// within 0.021 of the quadrature where E ≤ 1 and 3.1 % where E > 1 (tested).
pub fn sheen_albedo(mu: f64, r: f64) -> f64 {
    let r = r.clamp(SHEEN_ROUGHNESS_MIN, 1.0);
    let x = mu.clamp(0.0, 1.0) / (r + 0.08);
    let y = r.ln();
    let mut p = 0.0;
    for row in SHEEN_ALBEDO_FIT.iter().rev() {
        let q = row.iter().rev().fold(0.0, |q, &c| q * y + c);
        p = p * x + q;
    }
    p.clamp(-30.0, 3.0).exp()
}

/// E(μ, r) by a midpoint quadrature over the hemisphere of ωi (`n` θ × 2n φ cells, φ ∈ [0, π]
/// doubled by symmetry).
pub fn sheen_albedo_quadrature(mu: f64, r: f64, n: usize) -> f64 {
    let alpha = sheen_alpha(r);
    let mu = mu.clamp(0.0, 1.0);
    let wo = glam::DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let (dt, dp) = (0.5 * PI / n as f64, PI / (2 * n) as f64);
    let mut sum = 0.0;
    for i in 0..n {
        let t = (i as f64 + 0.5) * dt;
        let (st, ct) = t.sin_cos();
        for k in 0..2 * n {
            let p = (k as f64 + 0.5) * dp;
            let wi = glam::DVec3::new(st * p.cos(), st * p.sin(), ct);
            let h = wi + wo;
            let len = h.length();
            if len <= 0.0 {
                continue;
            }
            let d = charlie_d(alpha, h.z / len);
            sum += d * neubelt_v(ct, mu.max(1e-9)) * ct * st * dt * dp;
        }
    }
    2.0 * sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_albedo_fit_follows_the_quadrature() {
        // Between and on the fit's nodes: 0.021 absolute where E ≤ 1, 3.1 % relative above.
        let (mut abs, mut rel) = (0.0f64, 0.0f64);
        for k in 0..24 {
            for j in 0..24 {
                let (mu, r) = (j as f64 / 23.0, k as f64 / 23.0);
                let q = sheen_albedo_quadrature(mu, r, 96);
                let e = sheen_albedo(mu, r);
                if q <= 1.0 {
                    abs = abs.max((q - e).abs());
                } else {
                    rel = rel.max((q - e).abs() / q);
                }
            }
        }
        assert!(abs < 0.025 && rel < 0.04, "{abs} {rel}");
        // The quadrature converges: n = 96 against n = 256 at a sharp and a broad node.
        for (mu, r, want) in [(1.0 / 31.0, 0.0, 2.596429), (9.0 / 31.0, 1.0, 0.373377)] {
            let q = sheen_albedo_quadrature(mu, r, 96);
            assert!((q - want).abs() < 2e-2 * want, "{q} vs {want}");
        }
    }

    #[test]
    fn the_charlie_distribution_is_normalized() {
        // ∫ D(h) cos θh dωh = 1 for every α.
        for r in [0.07, 0.3, 0.6, 1.0] {
            let a = sheen_alpha(r);
            let n = 4000;
            let dt = 0.5 * PI / n as f64;
            let s: f64 = (0..n)
                .map(|i| {
                    let t = (i as f64 + 0.5) * dt;
                    charlie_d(a, t.cos()) * t.cos() * t.sin() * dt * 2.0 * PI
                })
                .sum();
            assert!((s - 1.0).abs() < 1e-4, "r={r}: {s}");
        }
    }
}
