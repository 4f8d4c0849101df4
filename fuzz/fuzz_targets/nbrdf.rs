//! Neural-BRDF JSON files: any bytes give networks or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_brdf::measured::nbrdf::NbrdfSet;

fuzz_target!(|data: &[u8]| {
    if let Ok(set) = NbrdfSet::parse("<fuzz>", data) {
        for name in set.names() {
            if let Ok(n) = set.material(name) {
                let _ = n.eval_angles(0.1, 0.5, 1.0);
            }
        }
    }
});
