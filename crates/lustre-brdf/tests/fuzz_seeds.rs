//! The committed fuzz seed corpus (`fuzz/seeds/<target>/`, written by `fuzz/make_seeds.py`):
//! every seed of a lustre-brdf target is a valid input that its parser accepts, so that the
//! fuzzers start from inputs that reach past the magic numbers and headers.

use lustre_brdf::fits::{abc::AbcFits, lafortune::LafortuneFits, sgd::SgdFits};
use lustre_brdf::measured::{alta::AltaTable, gonio::GonioTable, nbrdf::NbrdfSet, rgl::RglBsdf};
use lustre_brdf::{material, Bsdf, DVec3};
use std::path::{Path, PathBuf};

fn seeds(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/seeds")
        .join(target);
    let mut v: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flatten()
        .map(|e| {
            let p = e.path();
            let b = std::fs::read(&p).expect("seed");
            (p, b)
        })
        .collect();
    v.sort();
    assert!(!v.is_empty(), "no seed for {target}");
    v
}

#[test]
fn every_seed_is_a_valid_input_of_its_target() {
    let wo = DVec3::new(0.3, 0.1, 0.9).normalize();
    for (p, b) in seeds("alta") {
        let t = AltaTable::parse(&p, &b, None).unwrap_or_else(|e| panic!("{e}"));
        assert!(t.eval(DVec3::Z, wo).is_finite());
    }
    for (p, b) in seeds("fit_csv") {
        let ok = SgdFits::parse(&p, &b).is_ok_and(|t| {
            t.list_materials()
                .iter()
                .all(|n| t.cook_torrance(n).is_ok())
        }) || AbcFits::parse(&p, &b).is_ok()
            || LafortuneFits::parse(&p, &b).is_ok();
        assert!(ok, "{}", p.display());
    }
    for (p, b) in seeds("gonio") {
        GonioTable::parse(&p, &b, None).unwrap_or_else(|e| panic!("{e}"));
    }
    for (p, b) in seeds("material") {
        material::parse(&p, &b)
            .and_then(|m| m.to_bsdf())
            .unwrap_or_else(|e| panic!("{e}"));
    }
    for (p, b) in seeds("nbrdf") {
        let s = NbrdfSet::parse(&p, &b).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.len(), 1);
    }
    for (p, b) in seeds("rgl") {
        let r = RglBsdf::parse(&p, &b).unwrap_or_else(|e| panic!("{e}"));
        assert!(r.eval(DVec3::Z, wo).max_component() > 0.0);
        assert!(b.len() < 10_000, "a seed stays small");
    }
    // The MERL target expands an odd first byte into a full table: the seeds are such inputs.
    for (p, b) in seeds("merl") {
        assert!(b[0] & 1 == 1 && b.len() >= 21, "{}", p.display());
    }
}
