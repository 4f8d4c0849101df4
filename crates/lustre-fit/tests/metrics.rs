//! Known values of the error metrics and the data checks.

use glam::DVec3;
use lustre_brdf::bsdf::{cosine_pdf, cosine_sample, Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use lustre_brdf::models::lambert::Lambert;
use lustre_brdf::rgb::Rgb;
use lustre_fit::metrics::{albedo, evaluate};
use lustre_fit::{data, FitError};
use std::f64::consts::PI;

#[test]
fn model_against_itself_is_zero() {
    let m = lustre_brdf::catalog::resolve("sgd:gold-metallic-paint").unwrap();
    let r = evaluate(m.as_ref(), m.as_ref(), false);
    assert_eq!(r.ngan_l2, [0.0; 3]);
    assert_eq!(r.l1, [0.0; 3]);
    assert_eq!(r.albedo_data, r.albedo_model);
}

#[test]
fn lambert_known_values() {
    // ∫∫ ((ρ−ρ')/π)² cos θi cos θo dωi dωo = (ρ−ρ')², max albedo ρ: E = |ρ−ρ'|/ρ.
    // The quadrature (boundary cuts where a direction reaches the horizon) is good to 3e-4.
    let (r1, r2) = (Rgb::new(0.5, 0.3, 0.8), Rgb::new(0.4, 0.35, 0.2));
    let a = Lambert::new(r1).unwrap();
    let b = Lambert::new(r2).unwrap();
    let rep = evaluate(&a, &b, false);
    for c in 0..3 {
        let want = (r1.0[c] - r2.0[c]).abs() / r1.0[c];
        assert!(
            (rep.ngan_l2[c] - want).abs() < 1e-3 * want,
            "channel {c}: {} vs {want}",
            rep.ngan_l2[c]
        );
        // Albedo of Lambert = ρ.
        assert!(
            (rep.albedo_data[c] - r1.0[c]).abs() < 1e-6,
            "{:?}",
            rep.albedo_data
        );
        assert!((rep.albedo_model[c] - r2.0[c]).abs() < 1e-6);
        // Eq. 3.7 on the 5° midpoint grid: |Δρ|/π · mean(cos θi) · Σ sin cos / Σ sin, which
        // tends to |Δρ|/π² (mean cos = 2/π, ratio = 1/2); midpoint sums agree to 1e-3.
        let want_l1 = (r1.0[c] - r2.0[c]).abs() / (PI * PI);
        assert!(
            (rep.l1[c] - want_l1).abs() < 2e-3 * want_l1,
            "channel {c}: {} vs {want_l1}",
            rep.l1[c]
        );
    }
}

#[test]
fn average_albedo_of_lambert_and_sgd() {
    let a = Lambert::new(Rgb::new(0.2, 0.5, 0.9)).unwrap();
    let v = lustre_fit::metrics::average_albedo(&a, false);
    for (got, want) in v.iter().zip([0.2, 0.5, 0.9]) {
        assert!((got - want).abs() < 1e-6, "{v:?}");
    }
    // The published SGD fit: the average lies below the maximum over θo.
    let m = lustre_brdf::catalog::resolve("sgd:gold-metallic-paint").unwrap();
    let avg = lustre_fit::metrics::average_albedo(m.as_ref(), false);
    let max = lustre_fit::metrics::max_albedo(m.as_ref(), false);
    for c in 0..3 {
        assert!(avg[c] > 0.0 && avg[c] <= max[c] * 1.001, "{avg:?} {max:?}");
    }
}

#[test]
fn albedo_at_oblique_incidence() {
    let a = Lambert::new(Rgb::splat(0.7)).unwrap();
    for t in [0.0f64, 30.0, 60.0, 80.0] {
        let wo = lustre_brdf::frame::spherical(t.to_radians(), 0.4);
        let v = albedo(&a, wo, false);
        assert!((v[0] - 0.7).abs() < 2e-3, "θo = {t}: {v:?}");
    }
}

/// A test BSDF returning a fixed value everywhere.
#[derive(Debug)]
struct Constant(f64);

impl Bsdf for Constant {
    fn name(&self) -> String {
        "constant".into()
    }
    fn eval(&self, _wi: DVec3, _wo: DVec3) -> Rgb {
        Rgb::splat(self.0)
    }
    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        cosine_sample(self, wo, u1, u2, LobeFlags::GLOSSY)
    }
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        cosine_pdf(wi, wo)
    }
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, false)
    }
}

#[test]
fn bad_data_is_rejected() {
    for (v, what) in [
        (0.0, "zero"),
        (f64::NAN, "non-finite"),
        (f64::INFINITY, "non-finite"),
        (-0.2, "negative"),
    ] {
        match data::check_values("mem:test", &Constant(v), false) {
            Err(FitError::Data { input, problem }) => {
                assert_eq!(input, "mem:test");
                assert!(problem.contains(what), "{problem}");
            }
            other => panic!("{v}: {other:?}"),
        }
    }
    assert!(data::check_values("ok", &Constant(0.1), true).is_ok());
    // A zero Lambert through the catalog.
    match data::load("lambert(kd=0)") {
        Err(FitError::Data { input, .. }) => assert_eq!(input, "lambert(kd=0)"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn nbrdf_inputs_expand_and_load() {
    let file = lustre_brdf::shared_data_dir().join("nbrdf/merl_nbrdf.json");
    let all = data::expand_inputs(&format!("nbrdf:{}#*", file.display())).unwrap();
    assert_eq!(all.len(), 100);
    assert!(all.iter().all(|s| s.starts_with("nbrdf:")));
    assert_eq!(
        data::expand_inputs("nbrdf:gold-paint").unwrap(),
        vec!["nbrdf:gold-paint".to_string()]
    );
    let d = data::load(&all[0]).unwrap();
    assert!(!d.transmission);
    assert!(all[0].ends_with(&d.name), "{} {}", all[0], d.name);
    assert!(data::load("nbrdf:all").is_err());
    assert!(data::load("nbrdf:no-such-material").is_err());
}

/// The judge a fit uses to pick among its candidates (`MetricJudge`, data side evaluated once)
/// gives the same bits as the metric functions the batch reports, for Ngan's L2 and the L1, on a
/// real input against two published fits (one judge reused across models), and with a Lambertian
/// whose Ngan L2 is known (|ρ − ρ'|/ρ, see `lambert_known_values`).
#[test]
fn metric_judge_equals_the_reported_metrics() {
    use lustre_fit::metrics::{l1_error, max_albedo, ngan_l2, Metric, MetricJudge};
    let d = data::load("nbrdf:nickel").unwrap();
    let data = d.bsdf.as_ref();
    let models = [
        lustre_brdf::catalog::resolve("sgd:nickel").unwrap(),
        lustre_brdf::catalog::resolve("sgd:gold-metallic-paint").unwrap(),
    ];
    let ngan = MetricJudge::new(Metric::NganL2, data, false, None);
    let l1 = MetricJudge::new(Metric::L1, data, false, None);
    let amax = max_albedo(data, false);
    for m in &models {
        assert_eq!(
            ngan.per_channel(m.as_ref()),
            ngan_l2(data, m.as_ref(), &amax)
        );
        assert_eq!(
            l1.per_channel(m.as_ref()),
            l1_error(data, m.as_ref(), false)
        );
        let mean = ngan_l2(data, m.as_ref(), &amax).iter().sum::<f64>() / 3.0;
        assert_eq!(ngan.of(m.as_ref()), mean);
    }
    let (r1, r2) = (Rgb::new(0.5, 0.3, 0.8), Rgb::new(0.4, 0.35, 0.2));
    let a = Lambert::new(r1).unwrap();
    let judge = MetricJudge::new(Metric::NganL2, &a, false, None);
    let e = judge.per_channel(&Lambert::new(r2).unwrap());
    for (c, ec) in e.iter().enumerate() {
        let want = (r1.0[c] - r2.0[c]).abs() / r1.0[c];
        assert!(
            (ec - want).abs() < 3e-4 * want.max(1.0),
            "{c}: {ec} vs {want}"
        );
    }
}
