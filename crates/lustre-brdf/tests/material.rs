//! The material JSON: round trips, the catalog's `.json` resolution and the validation errors.

use lustre_brdf::material::{
    self, CtChannelParams, CtDistribution, FitErrors, FitRecord, LobeParams, MaterialFile,
    MaterialModel,
};
use lustre_brdf::models::kurt::{Kurt, KurtLobe};
use lustre_brdf::{catalog, frame, Bsdf, DVec3, Rgb};
use proptest::prelude::*;
use std::f64::consts::PI;
use std::path::Path;

fn kurt_with_transmission() -> Kurt {
    Kurt::new(
        Rgb::new(0.05, 0.04, 0.03),
        vec![
            KurtLobe::new(Rgb::new(0.8, 0.6, 0.4), 0.07, 0.21, 0.9, 0.3).expect("lobe"),
            KurtLobe::new(Rgb::splat(0.1), 0.4, 0.4, 0.05, 0.0).expect("lobe"),
        ],
        vec![KurtLobe::new(Rgb::new(0.7, 0.8, 0.9), 0.15, 0.12, 0.04, 0.0).expect("lobe")],
    )
    .expect("kurt")
}

fn record() -> FitRecord {
    FitRecord {
        source: "nbrdf:nickel".into(),
        errors: Some(FitErrors {
            ngan_l2: [0.01, 0.02, 0.03],
            l1: [0.1, 0.2, 0.3],
        }),
        albedo_data: Some([0.5, 0.4, 0.3]),
        albedo_model: Some([0.49, 0.41, 0.3]),
        time_s: 1.25,
        status: "converged".into(),
        message: String::new(),
        options: serde_json::json!({"model": "kurt", "lobes": 2}),
        input_hash: Some("crc32:0123abcd:35".into()),
    }
}

/// Directions over both hemispheres (transmission included).
fn directions() -> Vec<(DVec3, DVec3)> {
    let mut out = Vec::new();
    for (ti, pi) in [(10.0, 0.0), (40.0, 60.0), (70.0, 200.0)] {
        for (to, po) in [(0.0, 0.0), (30.0, 180.0), (55.0, 20.0), (150.0, 30.0)] {
            out.push((
                frame::spherical(frame::deg(ti), frame::deg(pi)),
                frame::spherical(frame::deg(to), frame::deg(po)),
            ));
        }
    }
    out
}

fn assert_same_bsdf(a: &dyn Bsdf, b: &dyn Bsdf) {
    for (wi, wo) in directions() {
        let (x, y) = (a.eval(wi, wo), b.eval(wi, wo));
        for c in 0..3 {
            assert!(
                (x[c] - y[c]).abs() <= 1e-12 * (1.0 + x[c].abs()),
                "{wi} {wo}: {x:?} vs {y:?}"
            );
        }
    }
}

#[test]
fn kurt_round_trip_through_a_file_and_the_catalog() {
    let dir = tempfile::tempdir().expect("temp dir");
    let k = kurt_with_transmission();
    let m = MaterialFile::new("brushed", MaterialModel::from_kurt(&k), Some(record())).expect("m");
    let path = dir.path().join("brushed.json");
    material::write(&path, &m).expect("write");
    let back = material::read(&path).expect("read");
    assert_eq!(back.schema, "lustre-material");
    assert_eq!(back.version, 1);
    assert_eq!(back.fit, m.fit);
    let kb = back.model.to_kurt().expect("kurt");
    assert_eq!(kb.reflection.len(), 2);
    assert_eq!(kb.transmission.len(), 1);
    assert_same_bsdf(&k, back.to_bsdf().expect("bsdf").as_ref());
    let resolved = catalog::resolve(&path.to_string_lossy()).expect("catalog resolves .json");
    assert!(resolved.flags().transmission);
    assert_same_bsdf(&k, resolved.as_ref());
    // No temporary file is left beside the output.
    let n = std::fs::read_dir(dir.path()).expect("dir").count();
    assert_eq!(n, 1);
    assert!(catalog::resolve(&format!("{}#x", path.display())).is_err());
}

#[test]
fn cook_torrance_matches_the_catalog_model_and_the_hand_value() {
    let ch = CtChannelParams {
        rho_d: 0.2,
        rho_s: 0.6,
        alpha: 0.15,
        p: 0.0,
        kap: 0.0,
        f0: 0.3,
        f1: 0.1,
        g1: None,
    };
    let m = MaterialModel::cook_torrance(CtDistribution::Ggx, [ch; 3]).expect("ggx");
    assert_eq!(m.kind(), "ggx");
    let b = m.to_bsdf("ggx-test").expect("bsdf");
    let c = catalog::resolve("ggx(rho_d=0.2, rho_s=0.6, alpha=0.15, f0=0.3, f1=0.1)").expect("c");
    assert_same_bsdf(c.as_ref(), b.as_ref());
    // Purely diffuse: f = ρd/π for every pair (004 Eq. III.1 with ρs = 0).
    let diffuse = CtChannelParams { rho_s: 0.0, ..ch };
    let m = MaterialModel::cook_torrance(CtDistribution::Beckmann, [diffuse; 3]).expect("m");
    let v = m
        .to_bsdf("d")
        .expect("bsdf")
        .eval(DVec3::Z, DVec3::new(0.6, 0.0, 0.8));
    assert!((v[0] - 0.2 / PI).abs() < 1e-15, "{v:?}");
}

/// The published SGD fit of `name` (004 Table V.2) as material-file channels with the Eq. V.3
/// shadowing.
fn published_sgd(name: &str) -> [CtChannelParams; 3] {
    let ps = lustre_brdf::fits::sgd::SgdFits::load_default()
        .expect("table")
        .params(name)
        .expect(name);
    ps.map(|q| CtChannelParams {
        rho_d: q.rho_d,
        rho_s: q.rho_s,
        alpha: q.alpha,
        p: q.p,
        kap: q.kap,
        f0: q.f0,
        f1: q.f1,
        g1: Some([q.lambda, q.c, q.k]),
    })
}

#[test]
fn sgd_channels_with_the_g1_approximation_round_trip() {
    let channels = published_sgd("nickel");
    let m = MaterialFile::new(
        "nickel",
        MaterialModel::cook_torrance(CtDistribution::Sgd, channels).expect("sgd"),
        None,
    )
    .expect("file");
    let json = m.to_json().expect("json");
    assert!(json.contains("\"type\": \"cook-torrance\""), "{json}");
    assert!(json.contains("\"distribution\": \"sgd\""), "{json}");
    assert!(!json.contains("\"fit\""), "{json}");
    let back = material::parse(Path::new("nickel.json"), json.as_bytes()).expect("parse");
    let (a, b) = (m.to_bsdf().expect("a"), back.to_bsdf().expect("b"));
    assert_same_bsdf(a.as_ref(), b.as_ref());
    // Same model as the published fit up to θ0 (here recomputed from λ, c, k by Eq. V.3): the
    // values at small angles, where G1 = 1 in both, agree with the published model.
    let published = lustre_brdf::fits::sgd::load("nickel").expect("published");
    let (wi, wo) = (frame::spherical(0.2, 0.0), frame::spherical(0.1, PI));
    let (x, y) = (published.eval(wi, wo), a.eval(wi, wo));
    for c in 0..3 {
        assert!((x[c] - y[c]).abs() <= 1e-9 * x[c].abs(), "{x:?} vs {y:?}");
    }
}

fn err(json: &str) -> String {
    match material::parse(Path::new("bad.json"), json.as_bytes()) {
        Ok(m) => panic!("accepted {json}: {m:?}"),
        Err(e) => e.to_string(),
    }
}

fn kurt_json(version: &str, schema: &str, mx: &str) -> String {
    format!(
        r#"{{"schema": "{schema}", "version": {version}, "name": "x",
            "model": {{"type": "kurt", "kd": [0.1, 0.1, 0.1],
              "reflection": [{{"ks": [0.5, 0.5, 0.5], "mx": {mx}, "my": 0.2, "r0": 0.9, "alpha": 0}}]}}}}"#
    )
}

#[test]
fn validation_errors_name_the_file_and_the_problem() {
    // The template itself is valid (transmission may be left out).
    let ok = material::parse(
        Path::new("ok.json"),
        kurt_json("1", "lustre-material", "0.1").as_bytes(),
    )
    .expect("valid");
    assert_eq!(ok.model.kind(), "kurt");
    let e = err(&kurt_json("1", "lustre-scene", "0.1"));
    assert!(e.contains("bad.json") && e.contains("schema"), "{e}");
    let e = err(&kurt_json("2", "lustre-material", "0.1"));
    assert!(e.contains("version 2 is not supported"), "{e}");
    let e = err(&kurt_json("1.5", "lustre-material", "0.1"));
    assert!(e.contains("version"), "{e}");
    let e = err(&kurt_json("1", "lustre-material", "-0.1"));
    assert!(
        e.contains("bad.json") && e.contains("reflection[0].mx"),
        "{e}"
    );
    let e = err(&kurt_json("1", "lustre-material", "NaN"));
    assert!(e.contains("not valid JSON"), "{e}");
    let e = err(&kurt_json("1", "lustre-material", "1e999"));
    assert!(e.contains("bad.json"), "{e}");
    let e = err(&kurt_json("1", "lustre-material", "0.1, \"mz\": 3"));
    assert!(e.contains("mz"), "unknown fields are rejected: {e}");
    let e = err(r#"{"version": 1}"#);
    assert!(e.contains("schema"), "{e}");
    let e = err("[1, 2]");
    assert!(e.contains("object"), "{e}");
    let e = err(r#"{"schema": "lustre-material", "version": 1, "name": "x",
        "model": {"type": "cook-torrance", "distribution": "ggx", "channels": [
          {"rho_d": 0.1, "rho_s": 0.5, "alpha": 0.1, "p": 0, "kap": 1, "f0": 1, "f1": 0},
          {"rho_d": 0.1, "rho_s": -0.5, "alpha": 0.1, "p": 0, "kap": 1, "f0": 1, "f1": 0},
          {"rho_d": 0.1, "rho_s": 0.5, "alpha": 0.1, "p": 0, "kap": 1, "f0": 1, "f1": 0}]}}"#);
    assert!(e.contains("channels.g.rho_s"), "{e}");
    let e = err(r#"{"schema": "lustre-material", "version": 1, "name": "x",
        "model": {"type": "cook-torrance", "distribution": "beckmann", "channels": [
          {"rho_d": 0.1, "rho_s": 0.5, "alpha": 0.1, "p": 0, "kap": 1, "f0": 1, "f1": 0, "g1": [1, 2, 3]},
          {"rho_d": 0.1, "rho_s": 0.5, "alpha": 0.1, "p": 0, "kap": 1, "f0": 1, "f1": 0},
          {"rho_d": 0.1, "rho_s": 0.5, "alpha": 0.1, "p": 0, "kap": 1, "f0": 1, "f1": 0}]}}"#);
    assert!(e.contains("channels.r.g1") && e.contains("sgd only"), "{e}");
    let e = err(r#"{"schema": "lustre-material", "version": 1, "name": "x",
        "model": {"type": "phong", "n": 3}}"#);
    assert!(e.contains("phong"), "{e}");
    let e = material::read(Path::new("/nonexistent/m.json")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/m.json"), "{e}");
}

#[test]
fn invalid_values_are_never_written() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("nan.json");
    let mut m = MaterialFile::new(
        "x",
        MaterialModel::from_kurt(&kurt_with_transmission()),
        Some(record()),
    )
    .expect("m");
    if let MaterialModel::Kurt { reflection, .. } = &mut m.model {
        reflection[0].my = f64::NAN;
    }
    let e = material::write(&path, &m).unwrap_err().to_string();
    assert!(
        e.contains("nan.json") && e.contains("reflection[0].my"),
        "{e}"
    );
    assert!(!path.exists());
    let mut m = MaterialFile::new(
        "x",
        MaterialModel::from_kurt(&kurt_with_transmission()),
        None,
    )
    .expect("m");
    m.fit = Some(FitRecord {
        time_s: f64::INFINITY,
        ..record()
    });
    assert!(material::write(&path, &m).is_err());
    assert!(MaterialFile::new(" ", m.model.clone(), None).is_err());
    let bad = MaterialModel::Kurt {
        kd: [0.1; 3],
        reflection: vec![LobeParams {
            ks: [0.1; 3],
            mx: 0.1,
            my: 0.1,
            r0: 1.5,
            alpha: 0.0,
        }],
        transmission: vec![],
    };
    assert!(bad.validate().unwrap_err().to_string().contains("r0"));
    assert!(bad.to_cook_torrance("x").is_err());
}

#[test]
fn a_failed_fit_record_round_trips() {
    let m = MaterialFile::new(
        "failed-but-kept",
        MaterialModel::from_kurt(&kurt_with_transmission()),
        Some(FitRecord {
            errors: None,
            albedo_data: None,
            albedo_model: None,
            status: "not-converged".into(),
            message: "LM stopped after 200 iterations".into(),
            ..record()
        }),
    )
    .expect("m");
    let json = m.to_json().expect("json");
    let back = material::parse(Path::new("f.json"), json.as_bytes()).expect("parse");
    assert_eq!(back, m);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
        let _ = material::parse(Path::new("fuzz.json"), &bytes);
    }

    #[test]
    fn valid_kurt_parameters_round_trip(
        kd in 0.0..1.0f64, ks in 0.0..5.0f64, mx in 1e-3..2.0f64, my in 1e-3..2.0f64,
        r0 in 0.0..=1.0f64, alpha in 0.0..=1.0f64,
    ) {
        let k = Kurt::new(
            Rgb::splat(kd),
            vec![KurtLobe::new(Rgb::new(ks, ks * 0.5, 0.0), mx, my, r0, alpha).expect("lobe")],
            vec![],
        ).expect("kurt");
        let m = MaterialFile::new("p", MaterialModel::from_kurt(&k), None).expect("m");
        let json = m.to_json().expect("json");
        let back = material::parse(Path::new("p.json"), json.as_bytes()).expect("parse");
        let kb = back.model.to_kurt().expect("kurt");
        let l = kb.reflection[0];
        for (a, b) in [(l.mx, mx), (l.my, my), (l.r0, r0), (l.alpha, alpha), (kb.kd[0], kd)] {
            prop_assert!((a - b).abs() <= 1e-15 * b.abs().max(1e-300));
        }
    }
}

#[test]
fn fitted_bsdfs_give_back_their_material_model() {
    // A model from a file comes back unchanged from its BSDF (Kurt, SGD with the Eq. V.3
    // shadowing, GGX).
    let kurt = MaterialModel::from_kurt(&kurt_with_transmission());
    let sgd =
        MaterialModel::cook_torrance(CtDistribution::Sgd, published_sgd("gold-metallic-paint"))
            .expect("sgd");
    let ggx = MaterialModel::cook_torrance(
        CtDistribution::Ggx,
        [CtChannelParams {
            rho_d: 0.2,
            rho_s: 0.6,
            alpha: 0.15,
            p: 0.0,
            kap: 1.0,
            f0: 0.3,
            f1: 0.1,
            g1: None,
        }; 3],
    )
    .expect("ggx");
    for m in &[kurt, ggx, sgd] {
        let b = m.to_bsdf("x").expect("bsdf");
        assert_eq!(&MaterialModel::from_bsdf(b.as_ref()).expect("model"), m);
    }
    // Every published SGD fit of the catalog has a material-file form whose BSDF agrees with
    // it up to θ0 of the shadowing approximation (recomputed from λ, c, k by Eq. V.3): at a
    // pair where G1 = 1 in both, f is equal.
    let (wi, wo) = (frame::spherical(0.2, 0.0), frame::spherical(0.1, PI));
    let mut n = 0;
    for name in lustre_brdf::fits::sgd::list_materials().expect("names") {
        let published = catalog::resolve(&format!("sgd:{name}")).expect("published");
        let m = MaterialModel::from_bsdf(published.as_ref())
            .unwrap_or_else(|e| panic!("sgd:{name}: {e}"));
        assert_eq!(m.kind(), "sgd");
        let back = m.to_bsdf(&name).expect("bsdf");
        let (x, y) = (published.eval(wi, wo), back.eval(wi, wo));
        for c in 0..3 {
            assert!(
                (x[c] - y[c]).abs() <= 1e-9 * x[c].abs(),
                "{name}: {x:?} vs {y:?}"
            );
        }
        n += 1;
    }
    assert_eq!(n, 100);
    // Anything else is refused with its reason.
    for (spec, says) in [
        ("lambert(kd=0.5)", "not a fitted model"),
        (
            "exponential(rho_d=0.1, rho_s=0.5, alpha=0.2)",
            "exponential",
        ),
    ] {
        let b = catalog::resolve(spec).expect(spec);
        let e = MaterialModel::from_bsdf(b.as_ref())
            .unwrap_err()
            .to_string();
        assert!(e.contains(says), "{spec}: {e}");
    }
}
