//! Published-fit CSV tables: any bytes give a table or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(t) = lustre_brdf::fits::FitTable::parse(Path::new("<fuzz>"), data, "name") {
        for n in t.names() {
            let _ = t.value(n, "kD_r");
            let _ = t.rgb(n, "alpha");
        }
    }
});
