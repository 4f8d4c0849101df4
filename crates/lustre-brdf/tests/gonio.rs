//! Goniometric transfer-probability tables (000 §2.3, §3.2) and ALTA files.

use lustre_brdf::frame::{reflect, spherical};
use lustre_brdf::measured::alta::{AltaTable, AltaUnit, ALTA_COS_FLOOR};
use lustre_brdf::measured::gonio::{GonioAxes, GonioBsdf, GonioTable, GonioUnits, Reconstruction};
use lustre_brdf::numeric::SphereQuadrature;
use lustre_brdf::sampling::{cosine_hemisphere, cosine_hemisphere_pdf, SplitMix64};
use lustre_brdf::validate::{
    chi2_test, integrate_reflection, integrate_transmission, test_directions,
};
use lustre_brdf::{Bsdf, BsdfFlags, BsdfSample, DVec3, Error, LobeFlags, Rgb};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// An analytic test lobe: Lambert + a normalized Phong lobe around the mirror direction (or
/// around wi itself when `retro`) + a Phong transmission lobe around −wi.
#[derive(Debug)]
struct Lobe {
    kd: f64,
    ks: f64,
    n: f64,
    kt: f64,
    m: f64,
    retro: bool,
}

impl Lobe {
    fn f(&self, wi: DVec3, wo: DVec3) -> f64 {
        if wi.z <= 0.0 {
            return 0.0;
        }
        if wo.z >= 0.0 {
            let axis = if self.retro {
                wi
            } else {
                reflect(wi, DVec3::Z)
            };
            self.kd / PI
                + self.ks * (self.n + 2.0) / (2.0 * PI) * wo.dot(axis).max(0.0).powf(self.n)
        } else {
            self.kt * (self.m + 2.0) / (2.0 * PI) * wo.dot(-wi).max(0.0).powf(self.m)
        }
    }
    fn p(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.f(wi, wo) * wo.z.abs()
    }
}

impl Bsdf for Lobe {
    fn name(&self) -> String {
        "analytic lobe".into()
    }
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        Rgb::splat(self.f(wi, wo))
    }
    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        let wi = cosine_hemisphere(u1, u2);
        Some(BsdfSample::new(
            wi,
            self.eval(wi, wo),
            cosine_hemisphere_pdf(wi),
            LobeFlags::GLOSSY_REFLECTION,
        ))
    }
    fn pdf(&self, wi: DVec3, _wo: DVec3) -> f64 {
        cosine_hemisphere_pdf(wi)
    }
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::default()
            .with_lobes(LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION)
    }
}

const GLOSSY: Lobe = Lobe {
    kd: 0.2,
    ks: 0.5,
    n: 20.0,
    kt: 0.2,
    m: 10.0,
    retro: false,
};
const NARROW: Lobe = Lobe {
    kd: 0.02,
    ks: 0.6,
    n: 300.0,
    kt: 0.3,
    m: 300.0,
    retro: false,
};
const RETRO: Lobe = Lobe {
    kd: 0.02,
    ks: 0.6,
    n: 300.0,
    kt: 0.0,
    m: 1.0,
    retro: true,
};

/// θi every 15°, φi every 90°, θo every 5° over both hemispheres, φo every 10°.
fn coarse(lobe: &Lobe) -> GonioTable {
    let axes = GonioAxes::regular_degrees(15.0, 90.0, 5.0, 10.0, true).expect("axes");
    GonioTable::tabulate(lobe, axes).expect("table")
}

/// The same coarse incident grid but densely measured outgoing directions (2° × 2°).
fn dense_outgoing(lobe: &Lobe) -> GonioTable {
    let axes = GonioAxes::regular_degrees(15.0, 90.0, 2.0, 2.0, true).expect("axes");
    GonioTable::from_fn("dense", axes, |wi, wo| lobe.p(wi, wo)).expect("table")
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

fn is_format_error(e: &Error, needle: &str) -> bool {
    matches!(e, Error::Format { problem, .. } if problem.contains(needle))
}

// ---------------------------------------------------------------------------------- gonio ---

#[test]
fn half_vector_beats_quadrilinear_near_the_peak() {
    // 000 Fig. 3.1 vs 3.2: incident directions between measured ones (θi = 37.5°, halfway
    // between the 30° and 45° nodes; φi = 0 and, blending φi too, 45°).
    let t = dense_outgoing(&NARROW);
    let mut worst_hv: f64 = 0.0;
    let mut best_quad: f64 = f64::INFINITY;
    for &phi_i in &[0.0f64, 45.0] {
        let wi = spherical(37.5f64.to_radians(), phi_i.to_radians());
        let mirror = reflect(wi, DVec3::Z);
        for (what, wo) in [("reflection peak", mirror), ("transmission peak", -wi)] {
            let truth = NARROW.p(wi, wo);
            let q = t.transfer_probability(wi, wo, Reconstruction::Quadrilinear);
            let h = t.transfer_probability(wi, wo, Reconstruction::HalfVector);
            let (eq, eh) = (rel(q, truth), rel(h, truth));
            println!(
                "φi={phi_i}° {what}: truth {truth:.4}, quadrilinear {q:.4} (err {eq:.3}), half-vector {h:.4} (err {eh:.4}), ratio {:.1}",
                eq / eh
            );
            worst_hv = worst_hv.max(eh);
            best_quad = best_quad.min(eq);
        }
        // Off the peak (3° away in θo) the half-vector reconstruction still follows the lobe.
        let wo = spherical((37.5f64 + 3.0).to_radians(), phi_i.to_radians() + PI);
        let truth = NARROW.p(wi, wo);
        let h = t.transfer_probability(wi, wo, Reconstruction::HalfVector);
        let q = t.transfer_probability(wi, wo, Reconstruction::Quadrilinear);
        println!(
            "φi={phi_i}° 3° off peak: truth {truth:.4}, quadrilinear {q:.4}, half-vector {h:.4}"
        );
        assert!(
            rel(h, truth) < 0.3,
            "off-peak half-vector error {}",
            rel(h, truth)
        );
    }
    println!("worst half-vector error {worst_hv:.4}, best quadrilinear error {best_quad:.3}");
    assert!(worst_hv < 0.1, "half-vector error at the peak {worst_hv}");
    assert!(
        best_quad > 0.5,
        "quadrilinear should grossly underestimate the peak: {best_quad}"
    );
    assert!(best_quad / worst_hv > 5.0);
}

#[test]
fn both_reconstructions_are_exact_at_grid_nodes() {
    let t = coarse(&GLOSSY);
    let a = t.axes().clone();
    let mut rng = SplitMix64::new(7);
    let pick = |rng: &mut SplitMix64, n: usize| ((rng.next_f64() * n as f64) as usize).min(n - 1);
    let mut worst: f64 = 0.0;
    for _ in 0..400 {
        let (ti, pi) = (
            pick(&mut rng, a.theta_i.len()),
            pick(&mut rng, a.phi_i.len()),
        );
        let (to, po) = (
            pick(&mut rng, a.theta_o.len()),
            pick(&mut rng, a.phi_o.len()),
        );
        let wi = spherical(a.theta_i[ti], a.phi_i[pi]);
        let wo = spherical(a.theta_o[to], a.phi_o[po]);
        let node = t.value(ti, pi, to, po).expect("on the grid");
        for r in [Reconstruction::Quadrilinear, Reconstruction::HalfVector] {
            let v = t.transfer_probability(wi, wo, r);
            let e = (v - node).abs() / node.max(1e-3);
            worst = worst.max(e);
            assert!(
                e < 1e-9,
                "{r:?} at node ({ti},{pi},{to},{po}): {v} vs {node}"
            );
        }
    }
    println!("worst relative error at nodes: {worst:.2e}");
}

#[test]
fn half_vector_fails_for_retro_reflection() {
    // 000 §3.2: reflecting about the half vector does not keep the lookup near a retro peak, so
    // the reconstruction loses it (worse than quadrilinear): a documented limitation.
    let t = dense_outgoing(&RETRO);
    let wi = spherical(37.5f64.to_radians(), 0.0);
    let truth = RETRO.p(wi, wi);
    let q = t.transfer_probability(wi, wi, Reconstruction::Quadrilinear);
    let h = t.transfer_probability(wi, wi, Reconstruction::HalfVector);
    println!("retro peak at θi=37.5°: truth {truth:.4}, quadrilinear {q:.4}, half-vector {h:.5}");
    assert!(
        rel(h, truth) > 0.9,
        "half-vector unexpectedly recovered the retro peak"
    );
    assert!(h < q);
    // At a measured incident direction both are exact, retro or not.
    let wi = spherical(30f64.to_radians(), 0.0);
    let h = t.transfer_probability(wi, wi, Reconstruction::HalfVector);
    assert!(rel(h, RETRO.p(wi, wi)) < 1e-9);
}

#[test]
fn rejection_sampler_matches_its_pdf() {
    let t = coarse(&GLOSSY);
    let mut dirs = test_directions();
    dirs.push(lustre_brdf::frame::mirror_z(dirs[1])); // a viewer below the sheet
    let n_tests = 2 * dirs.len();
    for recon in [Reconstruction::Quadrilinear, Reconstruction::HalfVector] {
        let b = GonioBsdf::new(t.clone(), recon);
        for (k, &wo) in dirs.iter().enumerate() {
            let r = chi2_test(&b, wo, 10, 20_000, 100 + k as u64);
            println!(
                "{recon:?} wo θ={:.2}: chi2 {:.1} dof {} p {:.3} ∫pdf {:.4} fraction {:.4}",
                wo.z.acos(),
                r.statistic,
                r.dof,
                r.p_value,
                r.pdf_integral,
                r.sample_fraction
            );
            assert!(r.passed(0.01, n_tests), "{recon:?} at {wo:?}: {r:?}");
        }
    }
}

#[test]
fn photon_sampler_follows_transfer_probability() {
    // The thesis's direction of use: photons from ωi, ωo drawn ∝ p(ωo|ωi); the fraction sent
    // into the lower hemisphere estimates t / (r + t).
    let t = coarse(&GLOSSY);
    let b = GonioBsdf::new(t.clone(), Reconstruction::HalfVector);
    let wi = spherical(0.6, 1.0);
    let (r, tr) = (
        t.reflectivity(wi, Reconstruction::HalfVector),
        t.transmissivity(wi, Reconstruction::HalfVector),
    );
    let mut rng = SplitMix64::new(3);
    let n = 20_000;
    let mut below = 0usize;
    for _ in 0..n {
        let (wo, pdf) = b.sample_outgoing(wi, &mut rng).expect("not absorbing");
        assert!((pdf - b.pdf_outgoing(wi, wo)).abs() < 1e-12 * pdf.max(1.0));
        below += (wo.z < 0.0) as usize;
    }
    let frac = below as f64 / n as f64;
    let expect = tr / (r + tr);
    let sigma = (expect * (1.0 - expect) / n as f64).sqrt();
    println!("transmitted fraction {frac:.4} vs t/(r+t) = {expect:.4} (σ {sigma:.4})");
    assert!((frac - expect).abs() < 5.0 * sigma);
}

#[test]
fn reflectivity_and_transmissivity_match_the_lobe() {
    let t = coarse(&GLOSSY);
    let q = SphereQuadrature::default();
    for &(th, ph) in &[(30.0f64, 90.0f64), (37.5, 20.0), (60.0, 180.0)] {
        let wi = spherical(th.to_radians(), ph.to_radians());
        let r_true = integrate_reflection(|wo| GLOSSY.p(wi, wo), wi, &q);
        let t_true = integrate_transmission(|wo| GLOSSY.p(wi, wo), wi, &q);
        for recon in [Reconstruction::Quadrilinear, Reconstruction::HalfVector] {
            let r = t.reflectivity(wi, recon);
            let tt = t.transmissivity(wi, recon);
            println!(
                "θi={th}° φi={ph}° {recon:?}: r {r:.4} (true {r_true:.4}, err {:.4}), t {tt:.4} (true {t_true:.4}, err {:.4}), absorbed {:.4}",
                rel(r, r_true),
                rel(tt, t_true),
                t.absorption(wi, recon)
            );
            // On incident nodes only the outgoing grid (5°×10°) limits the accuracy.
            let tol = if th == 37.5 { 0.04 } else { 0.01 };
            assert!(rel(r, r_true) < tol && rel(tt, t_true) < tol);
        }
    }
}

#[test]
fn bsdf_eval_is_p_over_cosine() {
    let t = coarse(&GLOSSY);
    let b = GonioBsdf::new(t, Reconstruction::Quadrilinear);
    let wi = spherical(30f64.to_radians(), 0.0);
    let wo = spherical(40f64.to_radians(), 180f64.to_radians());
    let f = b.eval(wi, wo)[0];
    assert!(
        rel(f, GLOSSY.f(wi, wo)) < 1e-9,
        "{f} vs {}",
        GLOSSY.f(wi, wo)
    );
    let mut rng = SplitMix64::new(11);
    for k in 0..2000 {
        let a = lustre_brdf::sampling::uniform_sphere(rng.next_f64(), rng.next_f64());
        let c = lustre_brdf::sampling::uniform_sphere(rng.next_f64(), rng.next_f64());
        for w in [a, c, DVec3::new(a.x + 1e-9, a.y, 0.0).normalize()] {
            let v = b.eval(w, c);
            assert!(v.is_finite() && v.min_component() >= 0.0);
            if k % 200 == 0 {
                // Each new viewer direction costs one normalization quadrature.
                let p = b.pdf(w, c);
                assert!(p.is_finite() && p >= 0.0);
            }
        }
    }
    assert!(b.flags().transmission && b.flags().anisotropic);
}

#[test]
fn write_parse_round_trip() {
    let t = coarse(&GLOSSY);
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("glossy.gonio");
    t.write(&path).expect("write");
    let back = GonioTable::read(&path, None).expect("read back");
    assert_eq!(back, t);
    // A small hand-written file in degrees and BRDF units.
    let text = "#lustre-gonio 1\n#units brdf\n#angles degrees\n#name tiny\n#theta_i 0\n#phi_i 0\n\
                #theta_o 0 60 90\n#phi_o 0 180\n## a comment\n\
                0 0 0 0 2\n0 0 0 180 2\n0 0 60 0 1\n0 0 60 180 3\n0 0 90 0 0\n0 0 90 180 0\n";
    let t = GonioTable::parse(Path::new("tiny"), text.as_bytes(), None).expect("tiny table");
    assert_eq!(t.name, "tiny");
    assert!((t.value(0, 0, 1, 1).unwrap() - 1.5).abs() < 1e-12); // 3 · cos 60°
    assert!(!t.has_transmission());
}

fn tiny_text() -> String {
    "#lustre-gonio 1\n#units transfer_probability\n#angles degrees\n#theta_i 0 45\n#phi_i 0\n\
     #theta_o 0 90 180\n#phi_o 0\n0 0 0 0 1\n0 0 90 0 0\n0 0 180 0 0.5\n45 0 0 0 1\n45 0 90 0 0\n45 0 180 0 0.5\n"
        .to_string()
}

#[test]
fn gonio_bad_input_gives_clear_errors() {
    let p = Path::new("bad.gonio");
    let ok = tiny_text();
    assert!(GonioTable::parse(p, ok.as_bytes(), None).is_ok());
    let cases: Vec<(String, &str)> = vec![
        (
            ok.replace("#units transfer_probability\n", ""),
            "missing #units",
        ),
        (
            ok.replace("transfer_probability", "watts"),
            "unknown #units",
        ),
        (ok.replace("#lustre-gonio 1", "#lustre-gonio 2"), "version"),
        (ok.replace("#angles degrees\n", ""), "#angles"),
        (ok.replace("45 0 180 0 0.5\n", ""), "incomplete grid"),
        (ok.replace("45 0 180 0 0.5\n", "45 0 90 0 0.5\n"), "twice"),
        (ok.replace("45 0 180 0 0.5", "45 0 180 0 NaN"), "line 13"),
        (ok.replace("45 0 180 0 0.5", "45 0 180 0 -1"), "negative"),
        (ok.replace("45 0 180 0 0.5", "45 0 180 0"), "fields"),
        (
            ok.replace("45 0 180 0 0.5", "45 0 170 0 0.5"),
            "not on the theta_o axis",
        ),
        (
            ok.replace("#theta_i 0 45", "#theta_i 45 0"),
            "strictly increasing",
        ),
        (ok.replace("#theta_i 0 45", "#theta_i 0 95"), "outside"),
        (ok.replace("#theta_o 0 90 180", "#theta_o 0 80 180"), "90°"),
        (
            ok.replace("#phi_i 0\n", "#phi_i 0\n#color red\n"),
            "unknown header",
        ),
    ];
    for (text, needle) in &cases {
        match GonioTable::parse(p, text.as_bytes(), None) {
            Err(e) => {
                println!("{needle}: {e}");
                assert!(is_format_error(&e, needle), "expected {needle:?}, got {e}");
                assert!(e.to_string().starts_with("bad.gonio"));
            }
            Ok(_) => panic!("accepted bad input ({needle})"),
        }
    }
    // Missing units are fine when the caller states them.
    let no_units = ok.replace("#units transfer_probability\n", "");
    assert!(GonioTable::parse(
        p,
        no_units.as_bytes(),
        Some(GonioUnits::TransferProbability)
    )
    .is_ok());
    // No byte prefix or mangling panics.
    let bytes = coarse(&GLOSSY).to_text().into_bytes();
    for cut in (0..2000)
        .step_by(37)
        .chain([bytes.len() - 1, bytes.len() / 2])
    {
        let _ = GonioTable::parse(p, &bytes[..cut.min(bytes.len())], None);
    }
    let mut rng = SplitMix64::new(5);
    for _ in 0..200 {
        let mut b = ok.clone().into_bytes();
        let i = (rng.next_f64() * b.len() as f64) as usize % b.len();
        b[i] = (rng.next_u64() & 0xff) as u8;
        let _ = GonioTable::parse(p, &b, None);
    }
    assert!(GonioAxes::regular_degrees(0.0, 90.0, 5.0, 10.0, true).is_err());
}

// ----------------------------------------------------------------------------------- ALTA ---

fn alta_path(name: &str) -> PathBuf {
    lustre_brdf::shared_data_dir()
        .join("measured/goniometric")
        .join(name)
}

/// The data rows of an ALTA file, parsed independently of the reader.
fn raw_rows(path: &Path) -> Vec<[f64; 4]> {
    let text = std::fs::read_to_string(path).expect("data file");
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .map(|t| t.parse().expect("number"))
                .collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

#[test]
fn alta_real_files_parse_and_reproduce_their_rows() {
    let jaune = alta_path("retro-3M-jaune.dat");
    let t = AltaTable::read(&jaune, None).expect("3M file");
    assert_eq!(t.unit(), AltaUnit::InvSteradianCosineFactor);
    assert_eq!(t.name, "3M Yellow");
    let rows = raw_rows(&jaune);
    assert_eq!(t.len(), rows.len());
    let deg: Vec<f64> = t.theta_l_slices().iter().map(|x| x.to_degrees()).collect();
    println!("3M Yellow: {} rows, θl slices {deg:?}", t.len());
    assert_eq!(deg.len(), 3);

    let gray = alta_path("retro-gray-tape.dat");
    let err = AltaTable::read(&gray, None).expect_err("no PARAM_OUT");
    println!("{err}");
    assert!(err.to_string().contains("PARAM_OUT"));
    let g = AltaTable::read(&gray, Some(AltaUnit::InvSteradianCosineFactor)).expect("with a unit");
    assert_eq!(g.len(), raw_rows(&gray).len());

    // Known rows: the raw value is reproduced exactly, and f = value / cos θv through the Bsdf.
    let mut worst: f64 = 0.0;
    for r in rows.iter().step_by(53) {
        let v = t.value(r[0], r[1], r[2]);
        assert!((v - r[3]).abs() <= 1e-12 * r[3].abs(), "row {r:?}: {v}");
        let tv = r[1].hypot(r[2]);
        if tv < 1.5 {
            let wi = spherical(r[0], 0.0);
            let wo = spherical(tv, r[2].atan2(r[1]));
            let f = t.eval(wi, wo)[0];
            let expect = r[3] / tv.cos().max(ALTA_COS_FLOOR);
            worst = worst.max(rel(f, expect));
        }
    }
    println!("worst relative error of f at rows: {worst:.2e}");
    assert!(worst < 1e-6);

    // The gray tape retro-reflects: at θl = 15° its largest f is within 2° of wi itself.
    let wi = spherical(15f64.to_radians(), 0.0);
    let mut best = (0.0, DVec3::Z);
    for i in 0..90 {
        for j in 0..180 {
            let wo = spherical((i as f64 + 0.5).to_radians(), (2.0 * j as f64).to_radians());
            let f = g.eval(wi, wo)[0];
            if f > best.0 {
                best = (f, wo);
            }
        }
    }
    let ang = best.1.dot(wi).clamp(-1.0, 1.0).acos().to_degrees();
    println!(
        "gray tape θl=15°: max f {:.2} at {ang:.2}° from the light",
        best.0
    );
    assert!(ang < 2.0);
    // Interpolated values between θl slices stay between their neighbours' range.
    let v = g.value(22.5f64.to_radians(), 0.1, 0.05);
    let (a, b) = (
        g.value(15f64.to_radians(), 0.1, 0.05),
        g.value(30f64.to_radians(), 0.1, 0.05),
    );
    assert!(v >= a.min(b) - 1e-12 && v <= a.max(b) + 1e-12);
}

#[test]
fn alta_bsdf_battery() {
    let t = AltaTable::read(&alta_path("retro-3M-jaune.dat"), None).expect("3M file");
    let dirs = test_directions();
    for (k, &wo) in dirs.iter().enumerate() {
        let r = chi2_test(&t, wo, 8, 10_000, 40 + k as u64);
        assert!(r.passed(0.01, dirs.len()), "{wo:?}: {r:?}");
    }
    let mut rng = SplitMix64::new(9);
    for _ in 0..3000 {
        let a = lustre_brdf::sampling::uniform_sphere(rng.next_f64(), rng.next_f64());
        let b = lustre_brdf::sampling::uniform_sphere(rng.next_f64(), rng.next_f64());
        let f = t.eval(a, b);
        assert!(f.is_finite() && f.min_component() >= 0.0, "{a:?} {b:?}");
    }
    assert!(t.eval(DVec3::Z, -DVec3::Z) == Rgb::ZERO);
}

#[test]
fn alta_bad_input_gives_clear_errors() {
    let p = Path::new("bad.dat");
    let head = "#DIM 3 1\n#VS 0\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n";
    let ok = format!("{head}0.2 0.1 0.0 1.5\n0.2 -0.1 0.0 0.5\n");
    let t = AltaTable::parse(p, ok.as_bytes(), None).expect("valid");
    assert_eq!(t.unit(), AltaUnit::InvSteradian);
    let cases: Vec<(String, &str)> = vec![
        (
            ok.replace("ISOTROPIC_TL_TV_PROJ_DPHI", "RUSIN_TH_TD_PD"),
            "RUSIN_TH_TD_PD",
        ),
        (ok.replace("INV_STERADIAN", "ENERGY"), "PARAM_OUT ENERGY"),
        (
            ok.replace("0.2 -0.1 0.0 0.5", "0.2 -0.1 0.0"),
            "line 6: 3 fields",
        ),
        (ok.replace("0.2 -0.1 0.0 0.5", "0.2 -0.1 0.0 nan"), "line 6"),
        (
            ok.replace("0.2 -0.1 0.0 0.5", "0.2 -0.1 0.0 inf"),
            "not finite",
        ),
        (
            ok.replace("0.2 -0.1 0.0 0.5", "0.2 -0.1 0.0 -2"),
            "negative",
        ),
        (ok.replace("#DIM 3 1", "#DIM 3 3"), "#DIM 3 3"),
        (ok.replace("#DIM 3 1\n", ""), "missing #DIM"),
        (ok.replace("#VS 0", "#VS 2"), "vertical segments"),
        (ok.replace("0.2 0.1 0.0 1.5", "0.2 3.1 0.0 1.5"), "exceeds"),
        (head.to_string(), "no data rows"),
    ];
    for (text, needle) in &cases {
        match AltaTable::parse(p, text.as_bytes(), None) {
            Err(e) => {
                println!("{needle}: {e}");
                assert!(is_format_error(&e, needle), "expected {needle:?}, got {e}");
            }
            Ok(_) => panic!("accepted bad input ({needle})"),
        }
    }
    // Truncations and corruptions of a real file never panic.
    let bytes = std::fs::read(alta_path("retro-gray-tape.dat")).expect("data");
    for cut in (0..bytes.len()).step_by(bytes.len() / 97) {
        let _ = AltaTable::parse(p, &bytes[..cut], Some(AltaUnit::InvSteradian));
    }
    let mut rng = SplitMix64::new(1);
    for _ in 0..100 {
        let mut b = ok.clone().into_bytes();
        let i = (rng.next_u64() as usize) % b.len();
        b[i] = (rng.next_u64() & 0xff) as u8;
        if let Ok(t) = AltaTable::parse(p, &b, None) {
            assert!(t.eval(spherical(0.2, 0.0), spherical(0.3, 2.0)).is_finite());
        }
    }
}
