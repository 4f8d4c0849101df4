//! Tests of the shading kernels: white furnace, convergence against the reference on a smooth
//! map, progressive = one-shot QMC, transmission, two-sidedness, absurd inputs, finiteness.
//! Run with `--nocapture` to see the measured tables.

use glam::DVec3;
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::models::kurt::{Kurt, KurtLobe};
use lustre_brdf::numeric::SphereQuadrature;
use lustre_brdf::rgb::Rgb;
use lustre_brdf::validate::albedo_quadrature;
use lustre_env::{irradiance_map, CubeMap, CubePyramid, MipFilter};
use lustre_shade::integrator::{
    plan_lattice, plan_regular, plan_thesis, shade_ck, shade_qmc, shade_reference,
    shade_reference_with, shade_regular, BoundingPlane, FilteredEnvironment, Lookup, Progressive,
    Weighting,
};
use lustre_trace::sampling::ShadingFrame;
use proptest::prelude::*;
use std::sync::OnceLock;

type Env = (CubePyramid, CubeMap);

fn build_env(size: usize, f: impl Fn(DVec3) -> [f64; 3] + Sync) -> Env {
    let base = CubeMap::from_fn(size, f).expect("cube map");
    let pyramid = CubePyramid::build(base, MipFilter::Gauss6).expect("pyramid");
    let irr = irradiance_map(&pyramid, 16).expect("irradiance");
    (pyramid, irr)
}

fn environment(e: &Env) -> FilteredEnvironment<'_> {
    FilteredEnvironment {
        pyramid: &e.0,
        irradiance: &e.1,
    }
}

/// L = 1 everywhere.
fn constant_env() -> &'static Env {
    static E: OnceLock<Env> = OnceLock::new();
    E.get_or_init(|| build_env(32, |_| [1.0; 3]))
}

/// A smooth coloured map, L = 1 + d·a per channel.
fn smooth_env() -> &'static Env {
    static E: OnceLock<Env> = OnceLock::new();
    E.get_or_init(|| {
        let a = DVec3::new(0.3, 0.6, -0.2);
        let b = DVec3::new(-0.5, 0.2, 0.4);
        build_env(64, move |d| {
            [1.0 + d.dot(a), 1.0 + d.dot(b), 1.0 + 0.5 * d.y]
        })
    })
}

/// Light from below the horizon only (world −y), smooth: L = max(0, −d.y)^½.
fn below_env() -> &'static Env {
    static E: OnceLock<Env> = OnceLock::new();
    E.get_or_init(|| build_env(32, |d| [(-d.y).max(0.0).sqrt(); 3]))
}

/// Light from above only: L = max(0, d.y)^½.
fn above_env() -> &'static Env {
    static E: OnceLock<Env> = OnceLock::new();
    E.get_or_init(|| build_env(32, |d| [d.y.max(0.0).sqrt(); 3]))
}

/// Largest absolute channel.
fn maxabs(v: Rgb) -> f64 {
    v.map(f64::abs).max_component()
}

fn lobe(ks: f64, mx: f64, my: f64, r0: f64) -> KurtLobe {
    KurtLobe::new(Rgb::splat(ks), mx, my, r0, 0.0).expect("valid lobe")
}

/// White-furnace material: kd = 0, one lobe with ks = 1, r0 = 1, α = 0.
fn furnace(m: f64) -> Kurt {
    Kurt::new(Rgb::ZERO, vec![lobe(1.0, m, m, 1.0)], vec![]).expect("valid")
}

/// World frame with n = +y, t = +x; wo at polar angle θo (degrees) in the plane of t and n.
fn upright(theta_deg: f64) -> (ShadingFrame, DVec3) {
    let t = theta_deg.to_radians();
    (
        ShadingFrame::new(DVec3::Y, DVec3::X),
        DVec3::new(t.sin(), t.cos(), 0.0),
    )
}

fn quad() -> SphereQuadrature {
    SphereQuadrature {
        phi_points: 128,
        uniform_panels: 24,
        ..Default::default()
    }
}

#[test]
fn furnace_reference_and_progressive_match_albedo() {
    let env = environment(constant_env());
    println!("white furnace: m, θo, albedo (quadrature), reference 20k, QMC 4096");
    for m in [0.1, 0.3] {
        let k = furnace(m);
        for th in [0.0, 45.0, 75.0] {
            let (f, wo) = upright(th);
            let a = albedo_quadrature(&k, f.to_local(wo), &quad())[0];
            let r = shade_reference(&f, wo, &k, &env, 20_000, 7)[0];
            let q = shade_qmc(&f, wo, &k, &env, 4096, 11)[0];
            println!("  {m:4} {th:4}  {a:.5}  {r:.5}  {q:.5}");
            // The weight f cos/p = cos θi / cos θh (r0 = 1, α = 0) lies in [0, 1/cos θh]:
            // the MC standard error at 20k samples is below 0.003.
            assert!(
                (r - a).abs() < 0.01,
                "reference {r} vs albedo {a} (m {m}, θo {th})"
            );
            assert!(
                (q - a).abs() < 0.005,
                "QMC {q} vs albedo {a} (m {m}, θo {th})"
            );
        }
    }
}

#[test]
fn furnace_regular_weightings() {
    let env = environment(constant_env());
    println!("regular on a constant map: m, θo, budget, albedo, Pdf002, Eq. 4.24, Eq. 4.25");
    // 002's p_h = mean D over the pattern (Eq. 18) treats D as if ∫ D dωh = 1 while the model
    // normalizes ∫ D cos θh dωh = 1, so rough lobes read high (+7…15 % at m = 0.4, measured):
    // "a few %" is asserted up to m = 0.2, a loose bound beyond.
    let (mut worst, mut worst_rough): (f64, f64) = (0.0, 0.0);
    // Eq. 4.24 and 4.25 read high as well, and more (measured worst +2.5 % at m ≤ 0.1, +10.6 %
    // at m = 0.2, +34.6 % at m = 0.4, all at θo = 60°); on a constant map they agree with each
    // other to 0.4 %. Asserted with a margin: the bias stays within these bounds and positive.
    let bound_424 = |m: f64| {
        if m <= 0.1 {
            0.03
        } else if m <= 0.2 {
            0.12
        } else {
            0.40
        }
    };
    let mut worst_424: Vec<(f64, f64)> = Vec::new();
    for m in [0.05, 0.1, 0.2, 0.4] {
        let k = furnace(m);
        for budget in [9, 17, 30] {
            let plan = plan_regular(&k, budget, 0.01).expect("plan");
            for th in [0.0, 30.0, 60.0] {
                let (f, wo) = upright(th);
                let a = albedo_quadrature(&k, f.to_local(wo), &quad())[0];
                let v: Vec<f64> = [
                    Weighting::Pdf002,
                    Weighting::Thesis424,
                    Weighting::Thesis425,
                ]
                .iter()
                .map(|&w| shade_regular(&f, wo, &plan, &env, w)[0])
                .collect();
                println!(
                    "  {m:4} {th:4} {:3}  {a:.4}  {:.4} ({:+.1}%)  {:.4} ({:+.1}%)  {:.4} ({:+.1}%)",
                    plan.reflection[0].pattern.h.len(),
                    v[0],
                    100.0 * (v[0] / a - 1.0),
                    v[1],
                    100.0 * (v[1] / a - 1.0),
                    v[2],
                    100.0 * (v[2] / a - 1.0)
                );
                for (w, x) in [("4.24", v[1]), ("4.25", v[2])] {
                    let e = x / a - 1.0;
                    assert!(
                        e > -0.005 && e < bound_424(m),
                        "Eq. {w} at m {m}, θo {th}, budget {budget}: {:+.2}%",
                        100.0 * e
                    );
                }
                assert!(
                    (v[1] / v[2] - 1.0).abs() < 0.01,
                    "Eq. 4.24 {} vs 4.25 {}",
                    v[1],
                    v[2]
                );
                worst_424.push((m, (v[1] / a - 1.0).max(v[2] / a - 1.0)));
                let e = (v[0] / a - 1.0).abs();
                if m <= 0.2 {
                    worst = worst.max(e);
                } else {
                    worst_rough = worst_rough.max(e);
                }
                assert!(v.iter().all(|x| x.is_finite() && *x >= 0.0));
            }
        }
    }
    println!(
        "worst Pdf002 relative error: {:.2}% (m ≤ 0.2), {:.2}% (m = 0.4)",
        100.0 * worst,
        100.0 * worst_rough
    );
    let w424 = |lo: f64, hi: f64| {
        worst_424
            .iter()
            .filter(|x| x.0 > lo && x.0 <= hi)
            .map(|x| x.1)
            .fold(f64::MIN, f64::max)
    };
    println!(
        "worst Eq. 4.24/4.25 relative error: {:+.2}% (m ≤ 0.1), {:+.2}% (m = 0.2), {:+.2}% (m = 0.4)",
        100.0 * w424(0.0, 0.1),
        100.0 * w424(0.1, 0.2),
        100.0 * w424(0.2, 0.4)
    );
    assert!(worst < 0.04, "Pdf002 off the albedo by {worst}");
    assert!(
        worst_rough < 0.2,
        "Pdf002 off the albedo by {worst_rough} (m = 0.4)"
    );
}

/// Pixels for the convergence study: (frame, wo, material).
fn study_pixels() -> Vec<(ShadingFrame, DVec3, Kurt)> {
    let iso = Kurt::new(Rgb::splat(0.1), vec![lobe(0.8, 0.15, 0.15, 1.0)], vec![]).expect("ok");
    let aniso = Kurt::new(Rgb::ZERO, vec![lobe(1.0, 0.08, 0.3, 1.0)], vec![]).expect("ok");
    let rough = Kurt::new(Rgb::ZERO, vec![lobe(1.0, 0.4, 0.4, 1.0)], vec![]).expect("ok");
    let frames = [
        ShadingFrame::new(DVec3::Y, DVec3::X),
        ShadingFrame::new(DVec3::new(0.6, 0.3, 0.5), DVec3::Z),
        ShadingFrame::new(DVec3::new(-0.2, -0.4, 0.9), DVec3::Y),
    ];
    let mut out = Vec::new();
    for f in frames {
        for (i, k) in [iso.clone(), aniso.clone(), rough.clone()]
            .into_iter()
            .enumerate()
        {
            let th = [10.0f64, 40.0, 65.0][i].to_radians();
            let wo = f.to_world(DVec3::new(th.sin() * 0.8, th.sin() * 0.6, th.cos()));
            out.push((f, wo, k));
        }
    }
    out
}

/// Mean relative error (all channels) of `shade` against `reference`.
fn mean_rel(reference: &[Rgb], got: &[Rgb]) -> f64 {
    let mut s = 0.0;
    for (r, g) in reference.iter().zip(got) {
        for c in 0..3 {
            s += (g[c] / r[c] - 1.0).abs();
        }
    }
    s / (3 * reference.len()) as f64
}

#[test]
fn convergence_on_a_smooth_map() {
    let env = environment(smooth_env());
    let px = study_pixels();
    let reference: Vec<Rgb> = px
        .iter()
        .enumerate()
        .map(|(i, (f, wo, k))| shade_reference(f, *wo, k, &env, 40_000, 100 + i as u64))
        .collect();
    // The QMC estimate converges to the same value (independent check of the reference).
    let qmc: Vec<Rgb> = px
        .iter()
        .enumerate()
        .map(|(i, (f, wo, k))| shade_qmc(f, *wo, k, &env, 16_384, i as u64))
        .collect();
    let e_qmc = mean_rel(&reference, &qmc);
    println!(
        "smooth map, {} pixels; QMC 16k vs reference 40k: {:.3}%",
        px.len(),
        100.0 * e_qmc
    );
    assert!(e_qmc < 0.01, "QMC vs reference {e_qmc}");
    let mut ck_err = Vec::new();
    for n in [8, 32, 128, 512] {
        let got: Vec<Rgb> = px
            .iter()
            .map(|(f, wo, k)| shade_ck(f, *wo, k, n, &env))
            .collect();
        let e = mean_rel(&reference, &got);
        println!(
            "  CK       N = {n:4}: mean relative error {:.3}%",
            100.0 * e
        );
        ck_err.push(e);
    }
    let mut errors: Vec<(bool, Weighting, usize, f64)> = Vec::new();
    for (name, thesis) in [("002 concentric", false), ("thesis", true)] {
        for w in [
            Weighting::Pdf002,
            Weighting::Thesis424,
            Weighting::Thesis425,
        ] {
            for budget in [5, 9, 19, 30] {
                let got: Vec<Rgb> = px
                    .iter()
                    .map(|(f, wo, k)| {
                        let plan = if thesis {
                            plan_thesis(k, budget)
                        } else {
                            plan_regular(k, budget, 0.01)
                        }
                        .expect("plan");
                        shade_regular(f, *wo, &plan, &env, w)
                    })
                    .collect();
                let e = mean_rel(&reference, &got);
                println!(
                    "  {name} {w:?} budget {budget:3}: mean relative error {:.3}%",
                    100.0 * e
                );
                // (Budgets are never exceeded: 19 is the isotropic s1 pattern with nc = 3.)
                if w == Weighting::Pdf002 && budget >= 19 {
                    // Measured: 4.6 %, 3.5 % (002 concentric), 4.6 %, 3.5 % (thesis) at 19 / 30.
                    assert!(e < 0.06, "{name} {w:?} {budget}: {e}");
                } else if w != Weighting::Pdf002 {
                    // Eq. 4.24/4.25 stay biased, 12–15 % (concentric) and 17–18.6 % (thesis
                    // patterns) at every budget (measured): bounded, and worse than Pdf002.
                    assert!(e < 0.20, "{name} {w:?} {budget}: {e}");
                }
                errors.push((thesis, w, budget, e));
            }
        }
    }
    for &(thesis, w, budget, e) in &errors {
        if w != Weighting::Pdf002 && budget >= 19 {
            let pdf002 = errors
                .iter()
                .find(|x| x.0 == thesis && x.1 == Weighting::Pdf002 && x.2 == budget)
                .map(|x| x.3)
                .expect("Pdf002 measured");
            assert!(
                pdf002 < e,
                "budget {budget}: Pdf002 {pdf002} not below {w:?} {e}"
            );
        }
    }
    for budget in [5, 9, 17, 30] {
        let got: Vec<Rgb> = px
            .iter()
            .map(|(f, wo, k)| {
                let plan = plan_lattice(k, budget).expect("plan");
                shade_regular(f, *wo, &plan, &env, Weighting::Pdf002)
            })
            .collect();
        let e = mean_rel(&reference, &got);
        println!(
            "  lattice (ours) budget {budget:3}: mean relative error {:.3}%",
            100.0 * e
        );
        if budget >= 17 {
            assert!(e < 0.02, "lattice {budget}: {e}");
        }
    }
    assert!(ck_err[3] < 0.03, "CK 512 vs reference {}", ck_err[3]);
    assert!(
        ck_err[3] <= ck_err[0] + 1e-3,
        "CK does not converge: {ck_err:?}"
    );
}

/// Bright soft spots (≈ 6° wide, 200:1 over the background), in the manner of 002 §8's map.
fn spot_env() -> &'static Env {
    static E: OnceLock<Env> = OnceLock::new();
    E.get_or_init(|| {
        let spots = [
            (DVec3::new(0.3, 0.9, 0.2), [200.0, 150.0, 100.0]),
            (DVec3::new(-0.6, 0.5, 0.4), [50.0, 80.0, 120.0]),
            (DVec3::new(0.5, 0.6, -0.6), [120.0, 120.0, 120.0]),
            (DVec3::new(0.9, 0.1, 0.3), [80.0, 40.0, 20.0]),
        ];
        build_env(128, move |d| {
            let mut c = [1.0; 3];
            for (dir, rgb) in &spots {
                let a = d.dot(dir.normalize()).clamp(-1.0, 1.0).acos();
                let g = (-(a / 0.05).powi(2)).exp();
                for k in 0..3 {
                    c[k] += rgb[k] * g;
                }
            }
            c
        })
    })
}

#[test]
fn convergence_on_a_spot_map() {
    let env = environment(spot_env());
    let px = study_pixels();
    let reference: Vec<Rgb> = px
        .iter()
        .enumerate()
        .map(|(i, (f, wo, k))| shade_qmc(f, *wo, k, &env, 65_536, 200 + i as u64))
        .collect();
    let rmc: Vec<Rgb> = px
        .iter()
        .enumerate()
        .map(|(i, (f, wo, k))| shade_reference(f, *wo, k, &env, 40_000, 300 + i as u64))
        .collect();
    let e_mc = mean_rel(&reference, &rmc);
    println!(
        "spot map, {} pixels; MC 40k vs QMC 64k: {:.3}%",
        px.len(),
        100.0 * e_mc
    );
    assert!(e_mc < 0.03, "MC vs QMC reference {e_mc}");
    let mut ck_err = Vec::new();
    for n in [8, 32, 128, 512] {
        let got: Vec<Rgb> = px
            .iter()
            .map(|(f, wo, k)| shade_ck(f, *wo, k, n, &env))
            .collect();
        let e = mean_rel(&reference, &got);
        println!("  CK N = {n:4}: mean relative error {:.2}%", 100.0 * e);
        ck_err.push(e);
    }
    // Measured mean relative errors of the regular Pdf002 kernel on this map: 27.1 %, 24.9 %,
    // 19.4 %, 15.0 % at budgets 5, 9, 17, 30 (the reference's own noise: ~1 %, the MC/QMC
    // difference above). Asserted with a margin, and the decrease from 5 to 30.
    let mut regular_err = Vec::new();
    for (budget, bound) in [(5, 0.30), (9, 0.29), (17, 0.21), (30, 0.17)] {
        let got: Vec<Rgb> = px
            .iter()
            .map(|(f, wo, k)| {
                let plan = plan_regular(k, budget, 0.01).expect("plan");
                shade_regular(f, *wo, &plan, &env, Weighting::Pdf002)
            })
            .collect();
        let e = mean_rel(&reference, &got);
        // Per material (iso 0.15 at 10°, aniso 0.08×0.3 at 40°, rough 0.4 at 65°).
        let per: Vec<String> = (0..3)
            .map(|m| {
                let idx: Vec<usize> = (0..px.len()).filter(|i| i % 3 == m).collect();
                let r: Vec<Rgb> = idx.iter().map(|&i| reference[i]).collect();
                let g: Vec<Rgb> = idx.iter().map(|&i| got[i]).collect();
                format!("{:.1}%", 100.0 * mean_rel(&r, &g))
            })
            .collect();
        println!(
            "  regular Pdf002 budget {budget:3}: mean relative error {:.2}% (iso, aniso, rough: {})",
            100.0 * e,
            per.join(", ")
        );
        assert!(got.iter().all(|v| v.is_finite()));
        assert!(e < bound, "regular Pdf002 budget {budget}: {e}");
        regular_err.push(e);
    }
    assert!(
        regular_err[3] < regular_err[0] - 0.08,
        "regular does not improve with the budget: {regular_err:?}"
    );
    assert!(ck_err[3] < ck_err[0], "CK does not converge: {ck_err:?}");
}

#[test]
fn progressive_equals_one_shot() {
    let env = environment(smooth_env());
    let k = Kurt::new(
        Rgb::new(0.2, 0.1, 0.05),
        vec![lobe(0.6, 0.1, 0.25, 0.3)],
        vec![lobe(0.3, 0.2, 0.2, 0.1)],
    )
    .expect("ok");
    let (f, wo) = upright(35.0);
    let mut p = Progressive::new(42);
    assert_eq!(p.estimate(), Rgb::ZERO);
    for _ in 0..4 {
        p.add_samples(&f, wo, &k, &env, 300);
    }
    assert_eq!(p.samples(), 1200);
    let one = shade_qmc(&f, wo, &k, &env, 1200, 42);
    assert_eq!(p.estimate(), one, "4 × 300 vs one-shot 1200");
    // A different pixel rotation gives a different (but close) estimate.
    let other = shade_qmc(&f, wo, &k, &env, 1200, 43);
    assert_ne!(other, one);
    assert!(maxabs(other - one) < 0.02 * one.max_component());
    p.reset();
    assert_eq!(p.samples(), 0);
}

#[test]
fn transmission_lobe_is_lit_from_below() {
    let below = environment(below_env());
    let above = environment(above_env());
    let glass = Kurt::new(Rgb::ZERO, vec![], vec![lobe(1.0, 0.2, 0.2, 0.0)]).expect("ok");
    let mirror = Kurt::new(Rgb::ZERO, vec![lobe(1.0, 0.2, 0.2, 1.0)], vec![]).expect("ok");
    let (f, wo) = upright(30.0);
    let plan_g = plan_regular(&glass, 17, 0.01).expect("plan");
    let plan_m = plan_regular(&mirror, 17, 0.01).expect("plan");
    let reg = |p, e| shade_regular(&f, wo, p, e, Weighting::Pdf002)[0];
    let ck = |k, e| shade_ck(&f, wo, k, 64, e)[0];
    let rf = |k: &Kurt, e| shade_reference(&f, wo, k, e, 20_000, 3)[0];
    let (gr, gc, gf) = (reg(&plan_g, &below), ck(&glass, &below), rf(&glass, &below));
    println!("transmission, light below: regular {gr:.4}, CK {gc:.4}, reference {gf:.4}");
    assert!(gf > 0.3, "reference {gf}");
    for v in [gr, gc] {
        assert!((v / gf - 1.0).abs() < 0.1, "{v} vs reference {gf}");
    }
    // Light from above does not pass a transmission lobe, and a reflection lobe sees only it.
    let dark = [reg(&plan_g, &above), ck(&glass, &above), rf(&glass, &above)];
    let refl_below = [
        reg(&plan_m, &below),
        ck(&mirror, &below),
        rf(&mirror, &below),
    ];
    println!("  glass, light above: {dark:?}; mirror, light below: {refl_below:?}");
    for v in dark.iter().chain(&refl_below) {
        assert!(*v < 0.02 * gf, "{v}");
    }
}

#[test]
fn viewer_below_is_shaded_by_the_flipped_frame() {
    // The thin two-sided surface: seen from below (wo·n < 0) a reflection lobe reflects the lower
    // hemisphere, exactly as the flipped frame seen from its front.
    let env = environment(smooth_env());
    let k = Kurt::new(Rgb::splat(0.2), vec![lobe(0.7, 0.1, 0.3, 0.5)], vec![]).expect("ok");
    let f = ShadingFrame::new(DVec3::new(0.2, 1.0, 0.1), DVec3::X);
    let wo = f.to_world(DVec3::new(0.3, 0.2, -0.9).normalize());
    let plan = plan_regular(&k, 17, 0.01).expect("plan");
    let g = f.flipped();
    assert_eq!(
        shade_regular(&f, wo, &plan, &env, Weighting::Pdf002),
        shade_regular(&g, wo, &plan, &env, Weighting::Pdf002)
    );
    assert_eq!(
        shade_ck(&f, wo, &k, 16, &env),
        shade_ck(&g, wo, &k, 16, &env)
    );
    let a = shade_reference(&f, wo, &k, &env, 4000, 5);
    let b = shade_reference(&g, wo, &k, &env, 4000, 5);
    // Same expectation; the samples differ (the flipped frame's local y has the other sign).
    assert!(maxabs(a - b) < 0.03 * a.max_component(), "{a:?} {b:?}");
    assert!(a.min_component() > 0.1);
}

#[test]
fn bounding_plane_lookup_changes_the_reference() {
    // A mirror-like lobe at a point above a floor: with the floor plane the lookups move towards
    // the floor's hit points; at the projection centre nothing changes.
    let env = environment(smooth_env());
    let k = furnace(0.05);
    let (f, wo) = upright(60.0);
    let floor = [BoundingPlane::new(DVec3::new(0.0, -1.0, 0.0), DVec3::Y).expect("plane")];
    let plain = shade_reference(&f, -wo, &k, &env, 2000, 9);
    let at_centre = Lookup {
        position: DVec3::ZERO,
        planes: &floor,
    };
    let same = shade_reference_with(&f, -wo, &k, &env, 2000, 9, Some(&at_centre));
    assert!(maxabs(plain - same) < 1e-12);
    let offset = Lookup {
        position: DVec3::new(3.0, 0.0, 0.0),
        planes: &floor,
    };
    let moved = shade_reference_with(&f, -wo, &k, &env, 2000, 9, Some(&offset));
    assert!(maxabs(plain - moved) > 1e-3, "{plain:?} {moved:?}");
}

#[test]
fn absurd_inputs_are_errors() {
    let good = furnace(0.2);
    assert!(plan_regular(&good, 0, 0.01).is_err());
    assert!(plan_thesis(&good, 0).is_err());
    for xi0 in [0.0, 1.0, -0.5, f64::NAN] {
        assert!(plan_regular(&good, 9, xi0).is_err(), "xi0 {xi0}");
    }
    let mut bad = good.clone();
    bad.reflection[0].mx = -0.1;
    let e = plan_regular(&bad, 9, 0.01).expect_err("negative roughness");
    assert!(e.to_string().contains("mx"), "{e}");
    let mut bad_t = good.clone();
    bad_t.transmission.push(lobe(1.0, 0.1, 0.1, 0.0));
    bad_t.transmission[0].my = f64::NAN;
    assert!(plan_regular(&bad_t, 9, 0.01).is_err());
    // Zero samples: black (reference), diffuse only (CK).
    let env = environment(constant_env());
    let (f, wo) = upright(20.0);
    assert_eq!(shade_reference(&f, wo, &good, &env, 0, 1), Rgb::ZERO);
    let diffuse = Kurt::new(Rgb::splat(0.5), good.reflection.clone(), vec![]).expect("ok");
    let d = shade_ck(&f, wo, &diffuse, 0, &env);
    assert!((d[0] - 0.5).abs() < 0.02, "{d:?}");
    // A viewer in the tangent plane sees nothing.
    assert_eq!(shade_ck(&f, DVec3::X, &diffuse, 8, &env), Rgb::ZERO);
}

#[test]
fn albedo_of_the_sampler_agrees_with_quadrature() {
    // Cross-check of the furnace target itself: Bsdf::albedo and the quadrature agree.
    let k = furnace(0.2);
    let wo = DVec3::new(0.5, 0.0, 0.75f64.sqrt());
    let a = k.albedo(wo, 1 << 14)[0];
    let q = albedo_quadrature(&k, wo, &quad())[0];
    assert!((a - q).abs() < 2e-3, "{a} vs {q}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn kernels_are_finite(
        nx in -1.0f64..1.0, ny in -1.0f64..1.0, nz in -1.0f64..1.0,
        ox in -1.0f64..1.0, oy in -1.0f64..1.0, oz in -1.0f64..1.0,
        mx in 0.005f64..1.5, my in 0.005f64..1.5, r0 in 0.0f64..1.0, alpha in 0.0f64..1.0,
        budget in 1usize..40,
    ) {
        let env = environment(constant_env());
        let f = ShadingFrame::new(DVec3::new(nx, ny, nz), DVec3::new(oy, oz, ox));
        let wo = DVec3::new(ox, oy, oz).try_normalize().unwrap_or(DVec3::Y);
        let l = KurtLobe::new(Rgb::new(0.5, 0.3, 0.2), mx, my, r0, alpha).expect("valid");
        let k = Kurt::new(Rgb::splat(0.1), vec![l], vec![l]).expect("valid");
        let plan = plan_regular(&k, budget, 0.01).expect("plan");
        for w in [Weighting::Pdf002, Weighting::Thesis424, Weighting::Thesis425] {
            let v = shade_regular(&f, wo, &plan, &env, w);
            prop_assert!(v.is_finite() && v.min_component() >= 0.0, "{w:?}: {v:?}");
        }
        let c = shade_ck(&f, wo, &k, budget, &env);
        prop_assert!(c.is_finite() && c.min_component() >= 0.0, "{c:?}");
        let r = shade_reference(&f, wo, &k, &env, 64, 1);
        prop_assert!(r.is_finite() && r.min_component() >= 0.0, "{r:?}");
    }
}
