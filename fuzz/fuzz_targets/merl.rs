//! MERL `.binary` tables: any bytes give a table or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_brdf::measured::merl::{MerlTable, NegativeValues};

fuzz_target!(|data: &[u8]| {
    for policy in [NegativeValues::Reject, NegativeValues::Missing] {
        if let Ok(t) = MerlTable::parse_with("<fuzz>", data, policy) {
            let _ = t.lookup_trilinear(0.1, 0.2, 0.3);
            let _ = t.lookup_nearest(1.5, 1.5, -0.3);
        }
    }
});
