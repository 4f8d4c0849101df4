//! Published-fit CSV tables (SGD, ABC, Lafortune): any bytes give tables or errors, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_brdf::fits::{abc::AbcFits, lafortune::LafortuneFits, sgd::SgdFits};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let p = Path::new("<fuzz>");
    if let Ok(t) = SgdFits::parse(p, data) {
        for n in t.list_materials() {
            let _ = t.cook_torrance(&n);
        }
    }
    if let Ok(t) = AbcFits::parse(p, data) {
        for n in t.names() {
            let _ = t.material(&n);
        }
    }
    if let Ok(t) = LafortuneFits::parse(p, data) {
        for n in t.names() {
            let _ = t.material(&n);
        }
    }
});
