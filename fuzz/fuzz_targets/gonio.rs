//! lustre goniometric tables: any bytes give a table or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_brdf::measured::gonio::{GonioTable, Reconstruction};
use lustre_brdf::DVec3;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(t) = GonioTable::parse(Path::new("<fuzz>"), data, None) {
        let wi = DVec3::new(0.3, 0.1, 0.9).normalize();
        let wo = DVec3::new(-0.2, 0.4, 0.8).normalize();
        let _ = t.transfer_probability(wi, wo, Reconstruction::HalfVector);
        let _ = t.transfer_probability(wi, wo, Reconstruction::Quadrilinear);
    }
});
