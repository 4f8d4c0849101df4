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

/// A plastic's base as a Lambertian (`CoatedBase`): kd is the base lobe's albedo under uniform
/// light averaged over cosine-weighted outgoing directions, (1/π)∫∫ f μi μo dωi dωo, here by a
/// midpoint rule over (μi, μo) of the BSDF's own `eval` (specular 0: the base lobe alone), for
/// smooth and rough coatings, linear and nonlinear ρ'.
#[test]
fn the_coated_base_is_the_base_lobes_mean_albedo() {
    use lustre_brdf::models::plastic::{CoatedBase, Plastic};
    let rho = Rgb([0.8, 0.5, 0.2]);
    let mean_albedo = |b: &dyn Bsdf| -> Rgb {
        let n = 800;
        let mut sum = Rgb::ZERO;
        for i in 0..n {
            let mi = (i as f64 + 0.5) / n as f64;
            let wi = DVec3::new((1.0 - mi * mi).sqrt(), 0.0, mi);
            for o in 0..n {
                let mo = (o as f64 + 0.5) / n as f64;
                let wo = DVec3::new(-(1.0 - mo * mo).sqrt(), 0.0, mo);
                // dω = 2π dμ (isotropic base), (1/π)·2π·2π / n² · f μi μo ... with the 1/π
                // of the cosine-weighted mean over ωo: 4 ∫∫ f π μi μo dμi dμo.
                sum += b.eval(wi, wo) * (4.0 * std::f64::consts::PI * mi * mo);
            }
        }
        sum * (1.0 / (n * n) as f64)
    };
    for nonlinear in [false, true] {
        let smooth = Plastic::new(rho, Rgb::ZERO, 1.5, 1.0, nonlinear).unwrap();
        let base = smooth.coated_base();
        let (want, got) = (mean_albedo(&smooth), base.kd(rho));
        for c in 0..3 {
            assert!(
                (want[c] - got[c]).abs() < 2e-4 * want[c],
                "smooth {nonlinear}: {want:?} {got:?}"
            );
        }
        for alpha in [0.01, 0.1, 0.4] {
            let rough = RoughPlastic::new(
                MicrofacetType::Ggx,
                alpha,
                rho,
                Rgb::ZERO,
                1.5,
                1.0,
                nonlinear,
            )
            .unwrap();
            let t = rough.mean_transmittance();
            assert!(t > 0.8 && t < 0.95, "T̄ {t}");
            let (want, got) = (mean_albedo(&rough), rough.coated_base().kd(rho));
            for c in 0..3 {
                assert!(
                    (want[c] - got[c]).abs() < 2e-3 * want[c],
                    "α {alpha} {nonlinear}: {want:?} {got:?}"
                );
            }
        }
    }
    // Far below ρ: the coating's Fresnel and 1/η² take about half of it.
    let b = Plastic::new(rho, Rgb::ZERO, 1.5, 1.0, true)
        .unwrap()
        .coated_base();
    let kd = b.kd(rho);
    assert!(kd[0] < 0.75 * rho[0] && kd[2] < 0.6 * rho[2], "{kd:?}");
    assert_eq!(CoatedBase::UNCOATED.kd(rho), rho);
}
