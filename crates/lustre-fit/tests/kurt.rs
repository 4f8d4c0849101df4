//! Kurt fitting (000 §3.4.1): recovery of known parameters from synthetic Kurt data, options,
//! bad data.

use lustre_brdf::measured::gonio::{GonioAxes, GonioBsdf, GonioTable, Reconstruction};
use lustre_brdf::models::kurt::{Kurt, KurtLobe};
use lustre_brdf::{Bsdf, BsdfFlags, BsdfSample, DVec3, Rgb};
use lustre_fit::kurt::{fit, l1_error, parameter_names, KurtFit, KurtOptions};
use lustre_fit::{FitError, FitStatus};
use std::time::Instant;

fn lobe(ks: [f64; 3], mx: f64, my: f64, r0: f64, alpha: f64) -> KurtLobe {
    KurtLobe::new(Rgb(ks), mx, my, r0, alpha).expect("valid lobe")
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The Eq. 3.7 error of the zero model: the scale of the objective.
fn data_scale(data: &dyn Bsdf, transmission: bool) -> f64 {
    let zero = Kurt::new(Rgb::ZERO, vec![], vec![]).expect("zero model");
    let e = l1_error(data, &zero, transmission).expect("l1");
    (e[0] + e[1] + e[2]) / 3.0
}

fn run(data: &dyn Bsdf, transmission: bool, opts: &KurtOptions) -> KurtFit {
    let t = Instant::now();
    let f = fit(data, transmission, opts).expect("fit");
    eprintln!(
        "{}: {:.2} s, {} evaluations, objective {:.3e} (data scale {:.3e}), status {:?}\n{:?}",
        data.name(),
        t.elapsed().as_secs_f64(),
        f.evaluations,
        f.objective,
        data_scale(data, transmission),
        f.status,
        f.model
    );
    f
}

fn check_lobe(got: &KurtLobe, want: &KurtLobe, tol: f64) {
    for c in 0..3 {
        assert!(rel(got.ks[c], want.ks[c]) < tol, "ks {got:?} vs {want:?}");
    }
    assert!(rel(got.mx, want.mx) < tol, "mx {got:?} vs {want:?}");
    assert!(rel(got.my, want.my) < tol, "my {got:?} vs {want:?}");
    assert!((got.r0 - want.r0).abs() < tol, "r0 {got:?} vs {want:?}");
    assert!(
        (got.alpha - want.alpha).abs() < 2.0 * tol,
        "α {got:?} vs {want:?}"
    );
}

#[test]
fn one_isotropic_lobe_is_recovered() {
    let want = Kurt::new(
        Rgb::new(0.3, 0.2, 0.1),
        vec![lobe([0.5, 0.6, 0.7], 0.12, 0.12, 0.3, 0.4)],
        vec![],
    )
    .expect("model");
    let f = run(&want, false, &KurtOptions::default());
    for c in 0..3 {
        assert!(rel(f.model.kd[c], want.kd[c]) < 0.01, "kd {:?}", f.model.kd);
    }
    check_lobe(&f.model.reflection[0], &want.reflection[0], 0.02);
    assert!(
        f.objective < 1e-3 * data_scale(&want, false),
        "{}",
        f.objective
    );
    assert_eq!(f.status, FitStatus::Converged);
    // The objective is the Eq. 3.7 error of the returned model.
    let e = l1_error(&want, &f.model, false).expect("l1");
    let mean = (e[0] + e[1] + e[2]) / 3.0;
    let scale = data_scale(&want, false);
    assert!(
        (mean - f.objective).abs() < 1e-9 * scale,
        "{mean} vs {}",
        f.objective
    );
}

#[test]
fn anisotropic_lobe_is_recovered() {
    let want = Kurt::new(
        Rgb::splat(0.05),
        vec![lobe([0.8, 0.8, 0.8], 0.06, 0.25, 0.6, 0.2)],
        vec![],
    )
    .expect("model");
    assert!(want.flags().anisotropic);
    let f = run(&want, false, &KurtOptions::default());
    check_lobe(&f.model.reflection[0], &want.reflection[0], 0.03);
    assert!(
        f.objective < 2e-3 * data_scale(&want, false),
        "{}",
        f.objective
    );
}

#[test]
fn two_lobes_are_recovered() {
    // A sharp and a broad lobe (the scattergloss case of 000 Fig. 3.11).
    let sharp = lobe([0.6, 0.5, 0.4], 0.05, 0.05, 0.5, 0.3);
    let broad = lobe([0.3, 0.3, 0.3], 0.35, 0.35, 0.2, 0.0);
    let want = Kurt::new(Rgb::splat(0.1), vec![sharp, broad], vec![]).expect("model");
    let opts = KurtOptions {
        lobes: 2,
        ..KurtOptions::default()
    };
    let f = run(&want, false, &opts);
    let mut got = f.model.reflection.clone();
    got.sort_by(|a, b| a.mx.total_cmp(&b.mx));
    check_lobe(&got[0], &sharp, 0.05);
    check_lobe(&got[1], &broad, 0.1);
    assert!(
        f.objective < 5e-3 * data_scale(&want, false),
        "{}",
        f.objective
    );
    // One lobe cannot do as well.
    let one = run(&want, false, &KurtOptions::default());
    assert!(
        one.objective > 5.0 * f.objective,
        "{} vs {}",
        one.objective,
        f.objective
    );
}

#[test]
fn transmission_lobe_from_a_goniometric_table() {
    let refl = lobe([0.5; 3], 0.15, 0.15, 0.1, 0.3);
    let trans = lobe([0.6; 3], 0.3, 0.3, 0.2, 0.0);
    let truth = Kurt::new(Rgb::splat(0.4), vec![refl], vec![trans]).expect("model");
    let axes = GonioAxes::regular_degrees(5.0, 360.0, 1.0, 3.0, true).expect("axes");
    let table = GonioTable::tabulate(&truth, axes).expect("table");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("synthetic.gonio");
    table.write(&path).expect("write");
    let read = GonioTable::read(&path, None).expect("read");
    let data = GonioBsdf::new(read, Reconstruction::Quadrilinear);
    let opts = KurtOptions {
        transmission_lobes: 1,
        ..KurtOptions::default()
    };
    let f = run(&data, true, &opts);
    assert!(rel(f.model.kd[0], 0.4) < 0.03, "kd {:?}", f.model.kd);
    check_lobe(&f.model.reflection[0], &refl, 0.08);
    // kt and r0 of a transmission lobe are nearly degenerate: its Fresnel factor is
    // 1 − F = (1 − r0)(1 − (1 − u)⁵), so the data fixes kt·(1 − r0) (here 0.48) and the shape.
    let t = f.model.transmission[0];
    assert!(rel(t.ks[0] * (1.0 - t.r0), 0.48) < 0.05, "{t:?}");
    assert!(rel(t.mx, 0.3) < 0.05 && rel(t.my, 0.3) < 0.05, "{t:?}");
    assert!(t.alpha < 0.1, "{t:?}");
    assert!(
        f.objective < 1e-2 * data_scale(&data, true),
        "{}",
        f.objective
    );
}

#[test]
fn fixed_parameters_and_ranges_are_honoured() {
    let want = Kurt::new(
        Rgb::splat(0.2),
        vec![lobe([0.5, 0.6, 0.7], 0.1, 0.2, 0.3, 0.4)],
        vec![],
    )
    .expect("model");
    let opts = KurtOptions {
        fixed: vec![
            ("r01".into(), 0.25),
            ("kd".into(), 0.15),
            ("kd_g".into(), 0.18),
        ],
        ranges: vec![
            ("ks1".into(), 0.1, 0.4),
            ("ks1_b".into(), 0.6, 0.9),
            ("mx1".into(), 0.05, 0.5),
        ],
        grid: 5,
        levels: 5,
        ..KurtOptions::default()
    };
    let f = run(&want, false, &opts);
    let l = f.model.reflection[0];
    assert_eq!(l.r0, 0.25);
    assert_eq!(f.model.kd.0, [0.15, 0.18, 0.15]);
    for c in 0..2 {
        assert!((0.1..=0.4).contains(&l.ks[c]), "{l:?}");
    }
    assert!((0.6..=0.9).contains(&l.ks[2]), "{l:?}");
    assert!((0.05..=0.5).contains(&l.mx), "{l:?}");
    // The objective is the Eq. 3.7 error of the returned model (here far from zero).
    let e = l1_error(&want, &f.model, false).expect("l1");
    let mean = (e[0] + e[1] + e[2]) / 3.0;
    assert!(rel(mean, f.objective) < 1e-9, "{mean} vs {}", f.objective);
    // Everything fixed: the model is the fixed one.
    let all: Vec<(String, f64)> = ["kd", "ks1", "mx1", "my1", "r01", "alpha1"]
        .iter()
        .zip([0.2, 0.5, 0.1, 0.2, 0.3, 0.4])
        .map(|(n, v)| (n.to_string(), v))
        .collect();
    let g = fit(
        &want,
        false,
        &KurtOptions {
            fixed: all,
            ..KurtOptions::default()
        },
    )
    .expect("fit");
    assert_eq!(g.model.reflection[0].mx, 0.1);
    assert_eq!(g.model.reflection[0].ks, Rgb::splat(0.5));
    assert_eq!(g.model.kd, Rgb::splat(0.2));
}

#[test]
fn parameter_names_cover_every_lobe() {
    let opts = KurtOptions {
        lobes: 2,
        transmission_lobes: 1,
        ..KurtOptions::default()
    };
    let names = parameter_names(&opts);
    for n in [
        "kd", "kd_r", "ks1", "ks2_b", "mx1", "my2", "r02", "alpha1", "kt1", "kt1_g", "mxt1",
        "myt1", "r0t1", "alphat1",
    ] {
        assert!(names.iter().any(|x| x == n), "{n} missing from {names:?}");
    }
    assert_eq!(names.len(), 4 + 3 * 8);
    assert!(!parameter_names(&KurtOptions::default()).contains(&"ks2".to_string()));
}

fn option_error(opts: KurtOptions, transmission: bool) -> String {
    let lam = Kurt::new(Rgb::splat(0.5), vec![], vec![]).expect("model");
    match fit(&lam, transmission, &opts) {
        Err(FitError::Option(m)) => m,
        other => panic!("expected an option error, got {other:?}"),
    }
}

#[test]
fn bad_options_are_clear_errors() {
    let d = KurtOptions::default;
    let m = option_error(
        KurtOptions {
            fixed: vec![("ks3".into(), 0.5)],
            ..d()
        },
        false,
    );
    assert!(
        m.contains("unknown parameter 'ks3'") && m.contains("mx1"),
        "{m}"
    );
    let m = option_error(
        KurtOptions {
            ranges: vec![("mx1".into(), 0.3, 0.1)],
            ..d()
        },
        false,
    );
    assert!(m.contains("mx1") && m.contains("inverted"), "{m}");
    let m = option_error(
        KurtOptions {
            ranges: vec![("r01".into(), 0.2, 0.2)],
            ..d()
        },
        false,
    );
    assert!(m.contains("r01") && m.contains("empty"), "{m}");
    let m = option_error(
        KurtOptions {
            ranges: vec![("r01".into(), 0.2, 1.5)],
            ..d()
        },
        false,
    );
    assert!(m.contains("valid range"), "{m}");
    let m = option_error(
        KurtOptions {
            fixed: vec![("mx1".into(), 0.0)],
            ..d()
        },
        false,
    );
    assert!(m.contains("mx1"), "{m}");
    let m = option_error(
        KurtOptions {
            fixed: vec![("mx1".into(), 0.1)],
            ranges: vec![("mx1".into(), 0.1, 0.2)],
            ..d()
        },
        false,
    );
    assert!(m.contains("twice"), "{m}");
    let m = option_error(KurtOptions { grid: 1, ..d() }, false);
    assert!(m.contains("grid"), "{m}");
    let m = option_error(KurtOptions { levels: 0, ..d() }, false);
    assert!(m.contains("levels"), "{m}");
    let m = option_error(
        KurtOptions {
            transmission_lobes: 1,
            ..d()
        },
        false,
    );
    assert!(m.contains("transmission"), "{m}");
    let m = option_error(
        KurtOptions {
            ranges: vec![("ks1".into(), f64::NAN, 1.0)],
            ..d()
        },
        false,
    );
    assert!(m.contains("not finite"), "{m}");
}

/// A BSDF returning one constant (to build all-zero and NaN data).
#[derive(Debug)]
struct Constant(f64);

impl Bsdf for Constant {
    fn name(&self) -> String {
        format!("constant {}", self.0)
    }
    fn eval(&self, _wi: DVec3, _wo: DVec3) -> Rgb {
        Rgb::splat(self.0)
    }
    fn sample(&self, _wo: DVec3, _u1: f64, _u2: f64) -> Option<BsdfSample> {
        None
    }
    fn pdf(&self, _wi: DVec3, _wo: DVec3) -> f64 {
        0.0
    }
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, true)
    }
}

#[test]
fn zero_and_nan_data_are_errors() {
    for (c, what) in [(0.0, "zero"), (f64::NAN, "NaN")] {
        match fit(&Constant(c), false, &KurtOptions::default()) {
            Err(FitError::Data { input, problem }) => {
                assert!(input.contains("constant"), "{input}");
                assert!(problem.contains(what), "{problem}");
            }
            other => panic!("expected a data error, got {other:?}"),
        }
    }
    assert!(matches!(
        fit(&Constant(0.0), true, &KurtOptions::default()),
        Err(FitError::Data { .. })
    ));
}

#[test]
fn few_levels_report_not_converged() {
    let want = Kurt::new(
        Rgb::splat(0.1),
        vec![lobe([0.5; 3], 0.07, 0.07, 0.4, 0.3)],
        vec![],
    )
    .expect("model");
    let f = fit(
        &want,
        false,
        &KurtOptions {
            levels: 2,
            polish: false,
            ..KurtOptions::default()
        },
    )
    .expect("fit");
    assert_eq!(f.status, FitStatus::NotConverged, "{f:?}");
}

/// Kurt fits of real data are no worse than with the code before the fitting speed-ups
/// (the crate's QR-based LM polish on all pairs): the Eq. 3.7 objective of 1 and 2 lobes on an
/// RGL file and a MERL material at most 0.5 % above the recorded one (measured after the
/// change: −0.03 %, −3.9 %, +0.004 %, −16 %), and every polish ends with a reason in words.
#[test]
fn kurt_fits_of_real_data_are_no_worse_than_recorded() {
    let paper = lustre_brdf::shared_data_dir()
        .join("measured/rgl/paper_white_rgb.bsdf")
        .display()
        .to_string();
    let cases: [(&str, [f64; 2]); 2] = [
        (&paper, [2.529270e-3, 2.443483e-3]),
        ("nbrdf:pink-felt", [1.662840e-3, 1.170314e-3]),
    ];
    for (input, recorded) in cases {
        let d = lustre_fit::data::load(input).unwrap();
        for (k, want) in recorded.into_iter().enumerate() {
            let opts = KurtOptions {
                lobes: k + 1,
                ..KurtOptions::default()
            };
            let f = run(d.bsdf.as_ref(), false, &opts);
            assert!(
                f.objective <= want * 1.005,
                "{input}, {} lobe(s): objective {:.6e} vs recorded {want:.6e}",
                k + 1,
                f.objective
            );
            assert_eq!(
                f.status,
                FitStatus::Converged,
                "{input}, {} lobe(s): {}",
                k + 1,
                f.note
            );
            assert!(
                f.note.contains("polish from the") && f.note.contains("converged"),
                "{}",
                f.note
            );
        }
    }
}

/// One-lobe Kurt fits of real MERL materials whose polish stopped at its former evaluation limit
/// (50·(n+1) residual evaluations, Jacobians included: ≈ 50 iterations) before the limit counted
/// iterations: the polish now meets a convergence criterion, the fit reports `Converged`, and
/// the Eq. 3.7 objective is at most 0.1 % above the one recorded then (alum-bronze 3.6621e-3,
/// chrome 4.1296e-3, docs/results/merl100.md of that run).
#[test]
fn one_lobe_polish_of_merl_materials_converges() {
    for (input, recorded) in [
        ("nbrdf:alum-bronze", 3.6621e-3),
        ("nbrdf:chrome", 4.1296e-3),
    ] {
        let d = lustre_fit::data::load(input).unwrap();
        let f = run(d.bsdf.as_ref(), false, &KurtOptions::default());
        assert_eq!(f.status, FitStatus::Converged, "{input}: {}", f.note);
        assert!(
            f.kept.starts_with("polish from the search: converged ("),
            "{input}: {}",
            f.note
        );
        assert!(
            f.objective <= recorded * 1.001,
            "{input}: objective {:.6e} vs recorded {recorded:.6e}",
            f.objective
        );
    }
}

/// Eq. 3.7 polish, on real data (blue-fabric, one lobe): the Eq. 3.7 polish drives the
/// lobe to α = 1, r0 = 1, where f ∝ (cos θi·cos θo)^−1 blows Ngan's L2 up at grazing angles
/// (4.85 reported before, against 0.646 for the search's result it started from; 0.683 with the
/// earlier, unconverged polish). Judged by the user's metric (Ngan's L2 and the L1) the reported
/// fit is never worse than the search's result (`refine` off), and with Ngan's L2 the kept
/// candidate is the converged Ngan-L2 polish (measured 0.225).
#[test]
fn kurt_fit_is_never_worse_on_the_users_metric_than_its_search() {
    use lustre_fit::batch::{FitOptions, Fitter, MeasuredFitter, Metric, ModelChoice};
    for metric in [Metric::NganL2, Metric::L1] {
        let settings = |refine| FitOptions {
            metric,
            refine,
            ..FitOptions::new(ModelChoice::Kurt)
        };
        let fit = |refine| {
            MeasuredFitter
                .fit("nbrdf:blue-fabric", &settings(refine), &|_| {})
                .expect("fit")
        };
        let (polished, search) = (fit(true), fit(false));
        let (p, s) = (metric.of(&polished.errors), metric.of(&search.errors));
        eprintln!(
            "{metric:?}: search {s:.4e}, reported {p:.4e}\n{}",
            polished.message
        );
        assert!(p <= s, "{metric:?}: reported {p} > search {s}");
        assert!(polished.message.contains("kept"), "{}", polished.message);
        if metric == Metric::NganL2 {
            assert!(p < 0.3, "Ngan L2 {p}");
            assert_eq!(
                polished.status,
                FitStatus::Converged,
                "{}",
                polished.message
            );
            assert!(
                polished.message.contains("kept Ngan-L2 polish from"),
                "{}",
                polished.message
            );
        }
    }
}

/// Multi-lobe convergence, on real data: blue-fabric with two lobes.
/// The alternation of lobes does not settle in 3 rounds, and the polish stopped at its iteration
/// limit while its error still fell (docs/results/merl100.md before: NotConverged, Eq. 3.7
/// 3.8028e-4). The joint polish of all lobes now holds parameters on a bound that the gradient
/// pushes outward (active set) and converges; its convergence decides the status, and the
/// alternation is only noted. The objective is no worse than recorded then (measured 3.6713e-4).
#[test]
fn multi_lobe_polish_converges_where_the_alternation_does_not_settle() {
    let d = lustre_fit::data::load("nbrdf:blue-fabric").unwrap();
    let f = run(
        d.bsdf.as_ref(),
        false,
        &KurtOptions {
            lobes: 2,
            ..KurtOptions::default()
        },
    );
    assert!(f.note.contains("did not settle"), "{}", f.note);
    assert_eq!(f.status, FitStatus::Converged, "{}", f.note);
    assert!(
        f.kept.starts_with("polish from the") && f.kept.contains(": converged ("),
        "{}",
        f.kept
    );
    assert!(f.objective <= 3.8028e-4, "objective {:.6e}", f.objective);
}

/// Physical by construction, on real data: RGL paper_white, whose
/// directional albedo stays ≤ 1 in every channel. Its Kurt fits (Ngan's L2 judging, as
/// `lustre fit --model kurt` and the merl100 example) had a blue albedo of 1.011 (one lobe) and
/// 1.028 (two lobes) before the albedo bound (docs/results/merl100.md of that run, Ngan L2
/// 2.4567e-1 and 2.3840e-1). The fit now exists, stays ≤ 1 in every channel (the example's
/// check: the largest albedo over θo = 0°, 10°, …, 80°), says what it capped, and costs at
/// most 1 % of Ngan's L2 (measured 2.4575e-1 and 2.3898e-1).
#[test]
fn kurt_fit_of_paper_white_keeps_its_albedo_below_one() {
    use lustre_fit::metrics::{max_albedo, ngan_l2, Metric, MetricJudge};
    let file = lustre_brdf::shared_data_dir().join("measured/rgl/paper_white_rgb.bsdf");
    let d = lustre_fit::data::load(&file.display().to_string()).expect("paper_white");
    let data = d.bsdf.as_ref();
    let data_max = max_albedo(data, false);
    assert!(
        data_max.iter().all(|&a| a <= 1.0),
        "data albedo {data_max:?}"
    );
    let judge = MetricJudge::new(Metric::NganL2, data, false, None);
    for (lobes, before) in [(1, 2.4567e-1), (2, 2.3840e-1)] {
        let f = lustre_fit::kurt::fit_judged(
            data,
            false,
            &KurtOptions {
                lobes,
                ..KurtOptions::default()
            },
            None,
            Some(&judge),
        )
        .expect("fit");
        let a = max_albedo(&f.model, false);
        let e = ngan_l2(data, &f.model, &data_max);
        let e = (e[0] + e[1] + e[2]) / 3.0;
        eprintln!(
            "{lobes} lobe(s): albedo {a:?}, Ngan L2 {e:.4e} (before {before:.4e})\n{}",
            f.note
        );
        for (c, ac) in a.iter().enumerate() {
            assert!(*ac <= 1.0, "{lobes} lobe(s), channel {c}: albedo {ac}");
        }
        assert!(
            f.albedo_caps.iter().any(|n| n.starts_with("channel b")),
            "{:?}",
            f.albedo_caps
        );
        assert!(f.note.contains("albedo was capped"), "{}", f.note);
        assert!(
            e <= 1.01 * before,
            "{lobes} lobe(s): Ngan L2 {e} vs {before}"
        );
    }
}
