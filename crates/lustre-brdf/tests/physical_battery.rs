//! The common battery for the physically based models that real scenes need (issue 9): smooth and
//! rough conductor, smooth / rough / thin dielectric, smooth and rough plastic (Mitsuba 3's
//! formulations), the glTF metallic-roughness BRDF and the two-sided adapter. Chi-square between
//! `sample` and `pdf` on the part with a density and the frequency of every delta lobe against
//! the probability it reports, ∫pdf + delta probability = success probability, reciprocity where
//! it holds (generalized for refraction), white-furnace energy, known values, lobe flags, and
//! finiteness over random parameters.

use lustre_brdf::bsdf::LobeFlags;
use lustre_brdf::frame::{mirror_z, spherical};
use lustre_brdf::microfacet::distribution::{MicrofacetDistribution, MicrofacetType};
use lustre_brdf::microfacet::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance};
use lustre_brdf::models::conductor::{ComplexIor, Conductor};
use lustre_brdf::models::dielectric::Dielectric;
use lustre_brdf::models::lambert::Lambert;
use lustre_brdf::models::pbr_metallic_roughness::PbrMetallicRoughness;
use lustre_brdf::models::plastic::Plastic;
use lustre_brdf::models::rough_conductor::RoughConductor;
use lustre_brdf::models::rough_dielectric::RoughDielectric;
use lustre_brdf::models::rough_plastic::RoughPlastic;
use lustre_brdf::models::thin_dielectric::ThinDielectric;
use lustre_brdf::models::two_sided::TwoSided;
use lustre_brdf::numeric::SphereQuadrature;
use lustre_brdf::sampling::{hammersley, SplitMix64};
use lustre_brdf::validate::{
    albedo_quadrature, chi2_test, pdf_integral, reciprocity_error, sample_success_fraction,
    test_directions,
};
use lustre_brdf::{Bsdf, DVec3, Rgb};
use proptest::prelude::*;

use MicrofacetType::{Beckmann, Ggx};

fn quad() -> SphereQuadrature {
    SphereQuadrature {
        phi_points: 128,
        uniform_panels: 32,
        points_per_panel: 10,
        ..Default::default()
    }
}

fn dist(kind: MicrofacetType, au: f64, av: f64) -> MicrofacetDistribution {
    MicrofacetDistribution::new(kind, au, av).expect("valid roughness")
}

fn gold() -> ComplexIor {
    ComplexIor::preset("Au").expect("preset")
}

/// Models with a density, broad enough for the chi-square grid (some with delta lobes too).
fn chi2_models() -> Vec<Box<dyn Bsdf>> {
    vec![
        Box::new(RoughConductor::new(dist(Ggx, 0.2, 0.2), gold(), Rgb::ONE).unwrap()),
        Box::new(RoughConductor::new(dist(Ggx, 0.1, 0.4), gold(), Rgb::ONE).unwrap()),
        Box::new(RoughConductor::new(dist(Beckmann, 0.3, 0.3), gold(), Rgb::ONE).unwrap()),
        Box::new(
            RoughConductor::new(
                dist(Beckmann, 0.35, 0.12),
                ComplexIor::preset("Cu").unwrap(),
                Rgb::new(1.0, 0.9, 0.8),
            )
            .unwrap(),
        ),
        Box::new(RoughDielectric::new(dist(Ggx, 0.3, 0.3), 1.5, 1.0).unwrap()),
        Box::new(RoughDielectric::new(dist(Beckmann, 0.15, 0.35), 1.33, 1.0).unwrap()),
        Box::new(
            RoughPlastic::new(Ggx, 0.1, Rgb::new(0.6, 0.4, 0.2), Rgb::ONE, 1.5, 1.0, true).unwrap(),
        ),
        Box::new(
            RoughPlastic::new(Beckmann, 0.3, Rgb::splat(0.5), Rgb::ONE, 1.49, 1.0, false).unwrap(),
        ),
        Box::new(Plastic::new(Rgb::new(0.1, 0.5, 0.9), Rgb::ONE, 1.5, 1.0, false).unwrap()),
        Box::new(PbrMetallicRoughness::new(Rgb::new(0.8, 0.5, 0.3), 0.3, 0.5).unwrap()),
        Box::new(PbrMetallicRoughness::new(Rgb::splat(0.9), 1.0, 0.4).unwrap()),
    ]
}

/// Models whose every lobe is a Dirac delta.
fn delta_models() -> Vec<Box<dyn Bsdf>> {
    vec![
        Box::new(Conductor::preset("Au").unwrap()),
        Box::new(Dielectric::new(1.5, 1.0).unwrap()),
        Box::new(Dielectric::new(1.0, 1.33).unwrap()),
        Box::new(ThinDielectric::new(1.5046, 1.000277).unwrap()),
    ]
}

/// `wo` on both sides for transmissive models, above the surface otherwise.
fn directions(b: &dyn Bsdf) -> Vec<DVec3> {
    let mut d = test_directions();
    if b.flags().transmission {
        d.extend(test_directions().into_iter().take(4).map(mirror_z));
    }
    d
}

#[test]
fn chi_square_pdf_normalization_and_delta_frequencies() {
    let models: Vec<Box<dyn Bsdf>> = chi2_models().into_iter().chain(delta_models()).collect();
    let n_tests: usize = models.iter().map(|m| directions(m.as_ref()).len()).sum();
    for (mi, m) in models.iter().enumerate() {
        for (di, wo) in directions(m.as_ref()).into_iter().enumerate() {
            let r = chi2_test(m.as_ref(), wo, 16, 60_000, 2000 + (mi * 16 + di) as u64);
            assert!(r.passed(0.01, n_tests), "{} at wo={wo:?}: {r:?}", m.name());
            if m.flags().delta_only() {
                assert_eq!(r.pdf_integral, 0.0, "{}", m.name());
                assert!(r.delta_fraction > 0.999, "{}: {r:?}", m.name());
                continue;
            }
            // ∫pdf (quadrature) = fraction of non-delta successes; ∫pdf + delta ≤ 1.
            let integral = pdf_integral(m.as_ref(), wo, &quad());
            let frac = sample_success_fraction(m.as_ref(), wo, 40_000, 7 + di as u64);
            assert!(
                (integral - frac).abs() < 1.2e-2 && integral + r.delta_fraction <= 1.0 + 1e-2,
                "{} at wo={wo:?}: ∫pdf = {integral}, success = {frac}, delta {}",
                m.name(),
                r.delta_fraction
            );
        }
    }
}

#[test]
fn reciprocity_where_promised_and_generalized_for_refraction() {
    let mut reciprocal: Vec<Box<dyn Bsdf>> = chi2_models();
    reciprocal.push(Box::new(
        TwoSided::new(RoughConductor::new(dist(Ggx, 0.2, 0.5), gold(), Rgb::ONE).unwrap()).unwrap(),
    ));
    for m in reciprocal.iter().filter(|m| !m.flags().transmission) {
        assert!(m.flags().reciprocal, "{}", m.name());
        let e = reciprocity_error(m.as_ref(), 2000, 3);
        assert!(e < 1e-10, "{}: {e}", m.name());
    }
    // Refraction in radiance form: f(wi→wo)/η_o² = f(wo→wi)/η_i² (Veach 1997, Eq. 5.14), with
    // η_o the index on the side of wo. Reflection pairs are plainly reciprocal.
    let mut rng = SplitMix64::new(9);
    for (eta_int, m) in [
        (
            1.5,
            RoughDielectric::new(dist(Ggx, 0.3, 0.3), 1.5, 1.0).unwrap(),
        ),
        (
            1.33,
            RoughDielectric::new(dist(Beckmann, 0.1, 0.4), 1.33, 1.0).unwrap(),
        ),
    ] {
        assert!(!m.flags().reciprocal);
        let mut worst = 0.0f64;
        let mut compared = 0;
        for _ in 0..4000 {
            let a = spherical(rng.next_f64() * 1.55, rng.next_f64() * 6.283);
            let mut b = spherical(rng.next_f64() * 1.55, rng.next_f64() * 6.283);
            if rng.next_f64() < 0.5 {
                b = mirror_z(b);
            }
            let (wi, wo) = if rng.next_f64() < 0.5 { (a, b) } else { (b, a) };
            let side = |w: DVec3| if w.z > 0.0 { 1.0 } else { eta_int };
            let lhs = m.eval(wi, wo)[0] / (side(wo) * side(wo));
            let rhs = m.eval(wo, wi)[0] / (side(wi) * side(wi));
            let scale = lhs.abs().max(rhs.abs());
            if scale > 1e-300 {
                worst = worst.max((lhs - rhs).abs() / scale);
                compared += 1;
            }
        }
        assert!(compared > 1000, "{compared}");
        assert!(worst < 1e-10, "{}: {worst}", m.name());
    }
}

/// Energy flux ratio: the mean over n Hammersley samples of weight·η² (the radiance scaling of
/// refraction undone), per channel maximum.
fn flux_albedo(b: &dyn Bsdf, wo: DVec3, n: usize) -> f64 {
    let mut sum = Rgb::ZERO;
    for k in 0..n {
        let (u1, u2) = hammersley(k as u32, n as u32);
        if let Some(s) = b.sample(wo, u1, u2) {
            sum += s.weight() * (s.eta * s.eta);
        }
    }
    (sum / n as f64).max_component()
}

const THETAS: [f64; 7] = [0.0, 0.5, 1.0, 1.3, 1.45, 1.52, 1.56];

#[test]
fn white_furnace_and_energy() {
    // Lossless delta models: exactly 1 in flux, sample by sample.
    for m in [
        Box::new(Conductor::preset("none").unwrap()) as Box<dyn Bsdf>,
        Box::new(Dielectric::new(1.5, 1.0).unwrap()),
        Box::new(ThinDielectric::new(1.5, 1.0).unwrap()),
    ] {
        for &t in &THETAS {
            for wo in [spherical(t, 0.4), mirror_z(spherical(t, 0.4))] {
                if wo.z < 0.0 && !m.flags().transmission {
                    continue;
                }
                let a = flux_albedo(m.as_ref(), wo, 4096);
                assert!((a - 1.0).abs() < 1e-12, "{} θo={t}: {a}", m.name());
            }
        }
    }
    // Smooth white plastic (linear): 1 up to the Fdr quadrature, by quadrature of the diffuse
    // part plus the delta coating.
    let p = Plastic::new(Rgb::ONE, Rgb::ONE, 1.5, 1.0, false).unwrap();
    let q = quad();
    for &t in &THETAS[..6] {
        let a = albedo_quadrature(&p, spherical(t, 0.2), &q);
        assert!((a[1] - 1.0).abs() < 2e-4, "plastic θo={t}: {a:?}");
    }
    // Single-scattering microfacet models lose energy: flux ≤ 1, from both sides.
    let lossy: Vec<(Box<dyn Bsdf>, f64)> = vec![
        (
            Box::new(
                RoughConductor::new(
                    dist(Ggx, 0.3, 0.3),
                    ComplexIor::preset("none").unwrap(),
                    Rgb::ONE,
                )
                .unwrap(),
            ),
            0.9,
        ),
        (
            Box::new(
                RoughConductor::new(
                    dist(Beckmann, 0.05, 0.5),
                    ComplexIor::preset("none").unwrap(),
                    Rgb::ONE,
                )
                .unwrap(),
            ),
            0.9,
        ),
        (
            Box::new(RoughDielectric::new(dist(Ggx, 0.05, 0.05), 1.5, 1.0).unwrap()),
            0.98,
        ),
        (
            Box::new(RoughDielectric::new(dist(Beckmann, 0.4, 0.2), 1.5, 1.0).unwrap()),
            0.85,
        ),
        (
            Box::new(RoughPlastic::new(Ggx, 0.1, Rgb::ONE, Rgb::ONE, 1.5, 1.0, false).unwrap()),
            0.9,
        ),
        (
            Box::new(RoughPlastic::new(Beckmann, 0.5, Rgb::ONE, Rgb::ONE, 1.5, 1.0, true).unwrap()),
            0.85,
        ),
        (
            Box::new(PbrMetallicRoughness::new(Rgb::ONE, 0.0, 0.5).unwrap()),
            0.85,
        ),
        (
            Box::new(PbrMetallicRoughness::new(Rgb::ONE, 1.0, 0.2).unwrap()),
            0.9,
        ),
    ];
    for (m, normal_min) in &lossy {
        assert!(m.flags().energy_conserving, "{}", m.name());
        let mut worst = 0.0f64;
        for &t in &THETAS {
            for wo in [spherical(t, 0.4), mirror_z(spherical(t, 0.4))] {
                if wo.z < 0.0 && !m.flags().transmission {
                    continue;
                }
                let a = flux_albedo(m.as_ref(), wo, 1 << 15);
                worst = worst.max(a);
                if t == 0.0 && wo.z > 0.0 {
                    assert!(a > *normal_min, "{} at normal incidence: {a}", m.name());
                }
            }
        }
        println!("{}: max flux albedo {worst:.4}", m.name());
        assert!(worst <= 1.0 + 5e-3, "{}: flux albedo {worst}", m.name());
    }
}

#[test]
fn sampled_albedo_matches_quadrature() {
    // Bsdf::albedo (importance sampling, delta lobes included) vs quadrature + delta part.
    let q = quad();
    let models: Vec<Box<dyn Bsdf>> = chi2_models().into_iter().chain(delta_models()).collect();
    for m in &models {
        for wo in [spherical(0.3, 0.1), spherical(1.2, 2.0)] {
            let a = m.albedo(wo, 1 << 15);
            let b = albedo_quadrature(m.as_ref(), wo, &q);
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() < 1e-2 * b[c].max(0.05),
                    "{} θo: sampled {a:?} vs quadrature {b:?}",
                    m.name()
                );
            }
        }
    }
}

#[test]
fn known_values() {
    // Dielectric: reflection frequency = Fresnel; normal incidence (η−1)²/(η+1)² = 0.04.
    let g = Dielectric::new(1.5, 1.0).unwrap();
    let n = 100_000;
    let mut refl = 0;
    for k in 0..n {
        let (u1, u2) = hammersley(k, n);
        let s = g.sample(DVec3::Z, u1, u2).unwrap();
        assert!(s.is_delta());
        if s.lobe == LobeFlags::SPECULAR_REFLECTION {
            refl += 1;
            assert!((s.pdf - 0.04).abs() < 1e-12 && (s.weight()[0] - 1.0).abs() < 1e-12);
        } else {
            // Straight through at normal incidence, radiance × 1/η², η = 1.5.
            assert!((s.wi + DVec3::Z).length() < 1e-12, "{s:?}");
            assert!((s.weight()[0] - 1.0 / 2.25).abs() < 1e-12 && s.eta == 1.5);
        }
    }
    assert!((refl as f64 / n as f64 - 0.04).abs() < 1e-4, "{refl}");
    // Refraction obeys Snell's law from both sides.
    let wo = spherical(0.9, 0.5);
    let s = g.sample(wo, 0.99, 0.5).unwrap();
    let sin = |w: DVec3| (w.x * w.x + w.y * w.y).sqrt();
    assert!((sin(wo) - 1.5 * sin(s.wi)).abs() < 1e-12 && s.wi.z < 0.0);
    assert!(
        (s.wi.x / sin(s.wi) + wo.x / sin(wo)).abs() < 1e-12,
        "opposite azimuth"
    );
    let s = g.sample(mirror_z(spherical(0.5, 0.0)), 0.99, 0.5).unwrap();
    assert!((1.5 * 0.5f64.sin() - sin(s.wi)).abs() < 1e-12 && s.wi.z > 0.0);
    // Total internal reflection beyond the critical angle, from inside.
    let s = g.sample(mirror_z(spherical(0.8, 0.0)), 0.999, 0.5).unwrap();
    assert!(s.lobe == LobeFlags::SPECULAR_REFLECTION && s.pdf == 1.0);
    // Thin dielectric: R' = 2R/(1 + R) at normal incidence, transmission straight through.
    let t = ThinDielectric::new(1.5, 1.0).unwrap();
    assert!((t.reflectance(1.0) - 0.08 / 1.04).abs() < 1e-15);
    let s = t.sample(spherical(0.7, 1.0), 0.9, 0.1).unwrap();
    assert!((s.wi + spherical(0.7, 1.0)).length() < 1e-15 && s.eta == 1.0);
    assert!((s.weight()[2] - 1.0).abs() < 1e-12);
    // glTF metal with white base = rough "none" conductor with α = roughness² (Appendix B).
    let pbr = PbrMetallicRoughness::new(Rgb::ONE, 1.0, 0.6).unwrap();
    let rc = RoughConductor::new(
        dist(Ggx, 0.36, 0.36),
        ComplexIor::preset("none").unwrap(),
        Rgb::ONE,
    )
    .unwrap();
    let mut rng = SplitMix64::new(1);
    for _ in 0..200 {
        let wi = spherical(rng.next_f64() * 1.5, rng.next_f64() * 6.0);
        let wo = spherical(rng.next_f64() * 1.5, rng.next_f64() * 6.0);
        let (a, b) = (pbr.eval(wi, wo)[0], rc.eval(wi, wo)[0]);
        assert!((a - b).abs() <= 1e-12 * b.max(1e-300), "{a} vs {b}");
    }
    // glTF dielectric, roughness 1 at normal incidence with wi = wo = n: D = 1/π, V = 1/4.
    let p = PbrMetallicRoughness::new(Rgb::new(0.5, 0.2, 0.1), 0.0, 1.0).unwrap();
    let want = 0.5 * (1.0 - 0.04) / std::f64::consts::PI + 0.04 / (4.0 * std::f64::consts::PI);
    assert!((p.eval(DVec3::Z, DVec3::Z)[0] - want).abs() < 1e-14);
    // A nearly smooth rough conductor reflects like the smooth one.
    let sharp = RoughConductor::new(dist(Ggx, 1e-3, 1e-3), gold(), Rgb::ONE).unwrap();
    let smooth = Conductor::preset("Au").unwrap();
    for t in [0.0, 0.6, 1.2] {
        let wo = spherical(t, 0.3);
        let (a, b) = (sharp.albedo(wo, 4096), smooth.albedo(wo, 16));
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() < 3e-3, "θ={t}: {a:?} vs {b:?}");
        }
    }
    // A nearly smooth coating transmits 1 − F and reflects Fdr internally.
    let rp = RoughPlastic::new(Ggx, 0.005, Rgb::ONE, Rgb::ONE, 1.5, 1.0, false).unwrap();
    for mu in [0.3, 0.6, 1.0] {
        let want = 1.0 - fresnel_dielectric(mu, 1.5).r;
        assert!(
            (rp.transmittance(mu) - want).abs() < 5e-3,
            "μ={mu}: {}",
            rp.transmittance(mu)
        );
    }
    let fdr = fresnel_diffuse_reflectance(1.0 / 1.5);
    assert!(
        (rp.internal_reflectance() - fdr).abs() < 0.02,
        "{} vs {fdr}",
        rp.internal_reflectance()
    );
}

#[test]
fn lobe_flags_are_consistent() {
    let mut models: Vec<Box<dyn Bsdf>> = chi2_models().into_iter().chain(delta_models()).collect();
    models.push(Box::new(Lambert::new(Rgb::splat(0.5)).unwrap()));
    for spec in [
        "kurt-glass",
        "kurt-demo",
        "phong",
        "ward",
        "sgd:nickel",
        "twosided:plastic",
    ] {
        models.push(lustre_brdf::catalog::resolve(spec).unwrap());
    }
    let mut rng = SplitMix64::new(4);
    for m in &models {
        let f = m.flags();
        assert_eq!(f.transmission, f.lobes.is_transmission(), "{}", m.name());
        assert!(!f.lobes.is_empty(), "{}", m.name());
        let mut seen = LobeFlags::NONE;
        for wo in directions(m.as_ref()) {
            for _ in 0..2000 {
                let Some(s) = m.sample(wo, rng.next_f64(), rng.next_f64()) else {
                    continue;
                };
                seen |= s.lobe;
                assert!(
                    f.lobes.contains(s.lobe),
                    "{}: {:?} ∉ {:?}",
                    m.name(),
                    s.lobe,
                    f.lobes
                );
                let side = LobeFlags::side(s.wi, wo);
                assert!(
                    s.lobe.contains(side),
                    "{}: {:?} for {side:?}",
                    m.name(),
                    s.lobe
                );
                let kinds = (s.lobe.is_diffuse() as u8)
                    + (s.lobe.is_glossy() as u8)
                    + (s.lobe.is_specular() as u8);
                assert_eq!(kinds, 1, "{}: {:?}", m.name(), s.lobe);
                if s.is_delta() {
                    assert!(s.pdf > 0.0 && s.pdf <= 1.0);
                    // Delta convention: no density at the delta direction unless another lobe has
                    // one there.
                    if f.delta_only() {
                        assert_eq!(m.pdf(s.wi, wo), 0.0);
                        assert_eq!(m.eval(s.wi, wo), Rgb::ZERO);
                    }
                } else {
                    assert!(
                        (m.pdf(s.wi, wo) - s.pdf).abs() <= 1e-9 * s.pdf,
                        "{}",
                        m.name()
                    );
                }
                if s.lobe.is_reflection() {
                    assert_eq!(s.eta, 1.0);
                }
            }
        }
        assert_eq!(
            seen,
            f.lobes,
            "{}: every declared lobe is sampled",
            m.name()
        );
    }
    let lambert = Lambert::new(Rgb::splat(0.5)).unwrap();
    assert!(lambert.flags().diffuse_only() && !lambert.flags().has_delta());
    let plastic = Plastic::new(Rgb::splat(0.5), Rgb::ONE, 1.5, 1.0, false).unwrap();
    assert!(plastic.flags().has_delta() && plastic.flags().has_non_delta());
}

#[test]
fn two_sided_mirrors_the_back() {
    let inner =
        RoughPlastic::new(Ggx, 0.2, Rgb::new(0.7, 0.3, 0.1), Rgb::ONE, 1.5, 1.0, true).unwrap();
    let two = TwoSided::new(inner.clone()).unwrap();
    let (wi, wo) = (spherical(0.4, 0.2), spherical(1.0, 2.5));
    assert_eq!(two.eval(wi, wo), inner.eval(wi, wo));
    assert_eq!(two.eval(mirror_z(wi), mirror_z(wo)), inner.eval(wi, wo));
    assert_eq!(two.pdf(mirror_z(wi), mirror_z(wo)), inner.pdf(wi, wo));
    assert_eq!(
        inner.eval(mirror_z(wi), mirror_z(wo)),
        Rgb::ZERO,
        "one-sided inner"
    );
    let s = two.sample(mirror_z(wo), 0.3, 0.6).unwrap();
    let t = inner.sample(wo, 0.3, 0.6).unwrap();
    assert_eq!(s.wi, mirror_z(t.wi));
    assert_eq!((s.value, s.pdf, s.lobe), (t.value, t.pdf, t.lobe));
    // Battery from below: chi-square and albedo equal to the front's.
    let r = chi2_test(&two, mirror_z(wo), 16, 40_000, 5);
    assert!(r.passed(0.01, 1), "{r:?}");
    let a = two.albedo(mirror_z(wo), 4096);
    assert_eq!(a, inner.albedo(wo, 4096));
    assert!(TwoSided::new(Dielectric::new(1.5, 1.0).unwrap()).is_err());
    assert!(TwoSided::new(Conductor::preset("Ag").unwrap()).is_ok());
}

fn check_finite(m: &dyn Bsdf, wi: DVec3, wo: DVec3, u1: f64, u2: f64) -> Result<(), TestCaseError> {
    let f = m.eval(wi, wo);
    prop_assert!(
        f.is_finite() && f.min_component() >= 0.0,
        "{}: f={f:?}",
        m.name()
    );
    let p = m.pdf(wi, wo);
    prop_assert!(p.is_finite() && p >= 0.0, "{}: pdf={p}", m.name());
    if let Some(s) = m.sample(wo, u1, u2) {
        prop_assert!(s.wi.is_finite() && s.value.is_finite() && s.pdf.is_finite() && s.pdf > 0.0);
        prop_assert!((s.wi.length() - 1.0).abs() < 1e-9, "{}: {s:?}", m.name());
        prop_assert!(s.weight().is_finite(), "{}: {s:?}", m.name());
    }
    Ok(())
}

fn direction() -> impl Strategy<Value = DVec3> {
    prop_oneof![
        (0.0..std::f64::consts::PI, -3.2..3.2f64).prop_map(|(t, p)| spherical(t, p)),
        (
            -3.2..3.2f64,
            prop::sample::select(vec![0.0f64, 1e-300, 1e-12, 1e-6, -1e-12, -1e-6])
        )
            .prop_map(|(p, z): (f64, f64)| DVec3::new(
                p.cos() * (1.0 - z * z).sqrt(),
                p.sin() * (1.0 - z * z).sqrt(),
                z
            )),
        Just(DVec3::Z),
        Just(-DVec3::Z),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn no_nan_or_inf(
        wi in direction(), wo in direction(), u1 in 0.0..1.0f64, u2 in 0.0..1.0f64,
        au in 1e-4..2.0f64, av in 1e-4..2.0f64, ior in 1.01..4.0f64, c in 0.0..=1.0f64,
        ggx in any::<bool>(), flip in any::<bool>(),
    ) {
        let kind = if ggx { Ggx } else { Beckmann };
        let (int, ext) = if flip { (1.0, ior) } else { (ior, 1.0) };
        let d = dist(kind, au, av);
        let models: Vec<Box<dyn Bsdf>> = vec![
            Box::new(RoughConductor::new(d, gold(), Rgb::splat(c)).unwrap()),
            Box::new(RoughDielectric::new(d, int, ext).unwrap()),
            Box::new(Dielectric::new(int, ext).unwrap()),
            Box::new(ThinDielectric::new(int, ext).unwrap()),
            Box::new(Conductor::preset("Cu").unwrap()),
            Box::new(Plastic::new(Rgb::splat(c), Rgb::ONE, int, ext, flip).unwrap()),
            Box::new(PbrMetallicRoughness::new(Rgb::splat(c), c, au.min(1.0)).unwrap()),
        ];
        for m in &models {
            check_finite(m.as_ref(), wi, wo, u1, u2)?;
        }
    }
}

#[test]
fn rough_plastic_extremes_are_finite() {
    // RoughPlastic builds tables, too slow for every proptest case: a fixed sweep instead.
    let mut rng = SplitMix64::new(8);
    for &(kind, alpha, int, ext) in &[
        (Ggx, 1e-4, 1.5, 1.0),
        (Beckmann, 2.0, 1.5, 1.0),
        (Ggx, 0.5, 1.0, 1.5),
        (Beckmann, 0.05, 3.0, 1.0),
    ] {
        let m = RoughPlastic::new(kind, alpha, Rgb::ONE, Rgb::ONE, int, ext, true).unwrap();
        for _ in 0..2000 {
            let wi = spherical(rng.next_f64() * 3.14, rng.next_f64() * 6.28);
            let wo = spherical(rng.next_f64() * 3.14, rng.next_f64() * 6.28);
            let f = m.eval(wi, wo);
            assert!(
                f.is_finite() && f.min_component() >= 0.0,
                "{}: {f:?}",
                m.name()
            );
            if let Some(s) = m.sample(wo, rng.next_f64(), rng.next_f64()) {
                assert!(s.weight().is_finite(), "{}: {s:?}", m.name());
            }
        }
    }
    assert!(RoughPlastic::new(Ggx, 0.1, Rgb::splat(1.1), Rgb::ONE, 1.5, 1.0, false).is_err());
    assert!(RoughPlastic::new(Ggx, f64::NAN, Rgb::ONE, Rgb::ONE, 1.5, 1.0, false).is_err());
}
