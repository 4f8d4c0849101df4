//! ALTA `.dat` tables: any bytes give a table or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_brdf::{measured::alta::AltaTable, Bsdf, DVec3};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(t) = AltaTable::parse(Path::new("<fuzz>"), data, None) {
        let wo = DVec3::new(0.3, 0.1, 0.9).normalize();
        let _ = t.eval(DVec3::Z, wo);
    }
});
