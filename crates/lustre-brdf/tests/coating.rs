//! The coating grid of a rough plastic with a textured roughness (`RoughPlasticCoating`): at
//! the grid's roughnesses it is `RoughPlastic::new` exactly; between them its interpolated T(μ)
//! and Fdr stay close to the exact tables, and the interpolated model is the same BSDF as the
//! exact one to within that.

use glam::DVec3;
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::microfacet::distribution::MicrofacetType;
use lustre_brdf::models::rough_plastic::{
    RoughPlastic, RoughPlasticCoating, COATING_ALPHAS, COATING_ALPHA_MIN,
};
use lustre_brdf::rgb::Rgb;

#[test]
fn the_grid_spans_the_clamped_roughnesses_log_evenly() {
    assert!((RoughPlasticCoating::alpha_of(0) - COATING_ALPHA_MIN).abs() < 1e-15);
    assert!((RoughPlasticCoating::alpha_of(COATING_ALPHAS - 1) - 1.0).abs() < 1e-12);
    for i in 0..COATING_ALPHAS - 1 {
        let (a, b) = (
            RoughPlasticCoating::alpha_of(i),
            RoughPlasticCoating::alpha_of(i + 1),
        );
        let (j, t) = RoughPlasticCoating::position((a * b).sqrt());
        assert_eq!(j, i);
        assert!((t - 0.5).abs() < 1e-9, "{t}");
    }
    assert_eq!(RoughPlasticCoating::position(1e-9), (0, 0.0));
    assert_eq!(
        RoughPlasticCoating::position(5.0),
        (COATING_ALPHAS - 2, 1.0)
    );
    assert_eq!(
        RoughPlasticCoating::position(f64::NAN),
        (COATING_ALPHAS - 2, 1.0)
    );
}

/// The largest difference of two coatings' T tables.
fn table_diff(a: &RoughPlastic, b: &RoughPlastic) -> f64 {
    a.transmittance_table()
        .iter()
        .zip(b.transmittance_table())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn interpolated_coatings_match_the_exact_tables() {
    for kind in [MicrofacetType::Ggx, MicrofacetType::Beckmann] {
        let grid = RoughPlasticCoating::new(kind, 1.5, 1.0, true).expect("grid");
        let (rho, spec) = (Rgb::new(0.4, 0.25, 0.1), Rgb::ONE);
        // At a grid roughness: exact.
        let i = 20;
        let a = RoughPlasticCoating::alpha_of(i);
        let exact = RoughPlastic::new(kind, a, rho, spec, 1.5, 1.0, true).expect("exact");
        let at = grid.at(a, rho, spec).expect("at");
        assert!(table_diff(&at, &exact) < 1e-12);
        // Between grid roughnesses (the Modern Hall's 0.01 and 0.1 among them).
        let (mut worst_t, mut worst_f, mut worst_f_rel) = (0.0f64, 0.0f64, 0.0f64);
        for a in [3e-4, 0.0025, 0.01, 0.037, 0.1, 0.23, 0.55, 0.9] {
            let exact = RoughPlastic::new(kind, a, rho, spec, 1.5, 1.0, true).expect("exact");
            let at = grid.at(a, rho, spec).expect("at");
            worst_t = worst_t.max(table_diff(&at, &exact));
            worst_f = worst_f.max((at.internal_reflectance() - exact.internal_reflectance()).abs());
            // The BRDF itself, over a fan of directions.
            for k in 0..64 {
                let th_o = 0.05 + 1.4 * f64::from(k % 8) / 8.0;
                let th_i = 0.05 + 1.4 * f64::from(k / 8) / 8.0;
                let wo = DVec3::new(th_o.sin(), 0.0, th_o.cos());
                let wi = DVec3::new(-th_i.sin() * 0.8, th_i.sin() * 0.6, th_i.cos());
                let (f, g) = (at.eval(wi, wo), exact.eval(wi, wo));
                for c in 0..3 {
                    let scale = g.0[c].abs().max(0.05);
                    worst_f_rel = worst_f_rel.max((f.0[c] - g.0[c]).abs() / scale);
                }
            }
        }
        eprintln!(
            "{kind:?}: |ΔT| ≤ {worst_t:.2e}, |ΔFdr| ≤ {worst_f:.2e}, BRDF relative ≤ \
             {worst_f_rel:.2e}"
        );
        assert!(worst_t < 2e-3, "{kind:?}: T off by {worst_t}");
        assert!(worst_f < 1e-3, "{kind:?}: Fdr off by {worst_f}");
        assert!(worst_f_rel < 3e-3, "{kind:?}: BRDF off by {worst_f_rel}");
    }
}
