//! MIP levels against hand-computed values (002 Eq. 14–16, 000 Eq. 4.14–4.17, Colbert-Křivánek).

use glam::DVec3;
use lustre_shade::mip::{
    ck_level, ck_level_at, lobe_area, regular_level, texel_solid_angle_at, texel_solid_angle_mean,
    thesis_level, MAX_TAN_ALPHA,
};

fn close(a: f64, b: f64, tol: f64) {
    assert!((a - b).abs() <= tol, "{a} vs {b} (tol {tol})");
}

#[test]
fn lobe_area_normal_incidence_by_hand() {
    // mx = my = 0.2, ξ0 = 0.1: t = tan θ = √(ln 10) · 0.2 = 0.3034854; at normal incidence the
    // reflected border direction is 2θ from the centre, u = v = tan 2θ = 2t/(1 − t²) = 0.668546.
    let t: f64 = 0.303_485_4;
    let u = 2.0 * t / (1.0 - t * t);
    close(u, 0.668_546, 1e-6);
    let a = lobe_area(0.2, 0.2, 0.1, DVec3::Z);
    close(a, std::f64::consts::PI * u * u, 1e-6);
    close(a, 1.404_148, 1e-5);
    // Anisotropic: u from mx, v from my.
    let (tx, ty) = (10f64.ln().sqrt() * 0.3, 10f64.ln().sqrt() * 0.1);
    let expect = std::f64::consts::PI * (2.0 * tx / (1.0 - tx * tx)) * (2.0 * ty / (1.0 - ty * ty));
    close(lobe_area(0.3, 0.1, 0.1, DVec3::Z), expect, 1e-9);
}

#[test]
fn lobe_area_oblique_and_grazing_stay_finite() {
    let wo = DVec3::new(0.6, 0.0, 0.8);
    let a = lobe_area(0.2, 0.2, 0.1, wo);
    assert!(a.is_finite() && a > 0.0);
    // Very rough lobe at grazing incidence: capped, not infinite or negative.
    let g = lobe_area(2.0, 2.0, 0.01, DVec3::new(0.999, 0.0, 0.0447).normalize());
    assert!(g.is_finite() && g > 0.0 && g <= std::f64::consts::PI * MAX_TAN_ALPHA * MAX_TAN_ALPHA);
    assert_eq!(lobe_area(-1.0, 0.2, 0.1, DVec3::Z), 0.0);
    assert_eq!(lobe_area(0.2, 0.2, 1.5, DVec3::Z), 0.0);
}

#[test]
fn regular_level_by_hand() {
    // A = 1, n = 4, face 128 (N = 16384), ωi = +z (d = 1), ωi·h = 1:
    // pixels = 1 · 16384 / 16 = 1024 → log4 = 5.
    close(regular_level(1.0, 4, DVec3::Z, 1.0, 128), 5.0, 1e-12);
    // Length of ωi does not matter.
    close(regular_level(1.0, 4, DVec3::Z * 3.0, 1.0, 128), 5.0, 1e-12);
    // Edge direction (1,1,0)/√2: d = √2 → +log4 √2 = 0.25; ωi·h = 0.5 → +log4 2 = 0.5.
    let e = DVec3::new(1.0, 1.0, 0.0).normalize();
    close(regular_level(1.0, 4, e, 1.0, 128), 5.25, 1e-12);
    close(regular_level(1.0, 4, e, 0.5, 128), 5.75, 1e-12);
    // Clamped below at 0 and above at log2(128) = 7.
    assert_eq!(regular_level(1e-9, 4, DVec3::Z, 1.0, 128), 0.0);
    assert_eq!(regular_level(1e9, 4, DVec3::Z, 1.0, 128), 7.0);
    assert_eq!(regular_level(1.0, 4, DVec3::Z, 0.0, 128), 7.0);
    assert_eq!(regular_level(f64::NAN, 4, DVec3::Z, 1.0, 128), 0.0);
}

#[test]
fn thesis_level_by_hand() {
    // A' = 1/4, face centre: pixels = 0.25 · 16384 / 4 = 1024 → 5.
    close(thesis_level(1.0, 4, DVec3::X, 128), 5.0, 1e-12);
    // Cube corner (1,1,1)/√3: d = √3, d²/cos β = d³ = 3√3 → + log4(3√3) = 1.188722.
    close(
        thesis_level(1.0, 4, DVec3::ONE.normalize(), 128),
        5.0 + (27f64.sqrt()).log2() / 2.0,
        1e-12,
    );
    close(5.0 + (27f64.sqrt()).log2() / 2.0, 6.188_722, 1e-6);
}

#[test]
fn ck_level_by_hand() {
    let face = 128;
    let omega_p = texel_solid_angle_mean(face);
    close(omega_p, 4.0 * std::f64::consts::PI / (6.0 * 16384.0), 1e-18);
    close(omega_p, 1.278_317e-4, 1e-9);
    // Ωs = 16 Ωp → ½ log2 16 + 1 = 3.
    let n = 8;
    let pdf = 1.0 / (n as f64 * 16.0 * omega_p);
    close(ck_level(pdf, n, face), 3.0, 1e-12);
    // Ωs = Ωp / 4 → −1 + 1 = 0; Ωs = Ωp / 64 → −2 → clamped to 0.
    close(ck_level(4.0 / (n as f64 * omega_p), n, face), 0.0, 1e-12);
    assert_eq!(ck_level(64.0 / (n as f64 * omega_p), n, face), 0.0);
    // Zero pdf → coarsest level.
    assert_eq!(ck_level(0.0, n, face), 7.0);
}

#[test]
fn texel_solid_angle_against_exact_cube_texels() {
    // The first-order texel solid angle against lustre-env's exact one, and the sum over the
    // sphere against 4π.
    let n = 32;
    let mut total = 0.0;
    for face in 0..6 {
        for j in 0..n {
            for i in 0..n {
                let d = lustre_env::CubeMap::texel_dir(n, face, i, j);
                let approx = texel_solid_angle_at(d, n);
                let exact = lustre_env::CubeMap::texel_solid_angle(n, i, j);
                assert!(
                    (approx - exact).abs() < 2e-3 * exact,
                    "{face} {i} {j}: {approx} vs {exact}"
                );
                total += approx;
            }
        }
    }
    // Midpoint rule: 12.56938 vs 4π = 12.56637 at N = 32.
    assert!((total - 4.0 * std::f64::consts::PI).abs() < 5e-3, "{total}");
    // Face centre 4/N², corner 4/(3√3 N²).
    close(texel_solid_angle_at(DVec3::Z, 128), 4.0 / 16384.0, 1e-15);
    close(
        texel_solid_angle_at(DVec3::ONE, 128),
        4.0 / (16384.0 * 27f64.sqrt()),
        1e-15,
    );
    // The direction-dependent level: at a face centre Ωp = 4/N² = (6/π)·mean, so the level is
    // ½ log2(π/6) = −0.4668 below ck_level; at a corner ½ log2(3√3 π/6) = +0.7220 above it.
    let pdf = 1.0 / (8.0 * 1e3 * texel_solid_angle_mean(128));
    let base = ck_level(pdf, 8, 128);
    close(
        ck_level_at(pdf, 8, 128, DVec3::Z) - base,
        0.5 * (std::f64::consts::PI / 6.0).log2(),
        1e-12,
    );
    close(
        ck_level_at(pdf, 8, 128, DVec3::ONE) - base,
        0.5 * (27f64.sqrt() * std::f64::consts::PI / 6.0).log2(),
        1e-12,
    );
}
