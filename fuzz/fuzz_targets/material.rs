//! lustre material JSON: any bytes give a material or an error, never a panic; a material that
//! parses gives a BSDF whose values are finite.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_brdf::material;
use lustre_brdf::DVec3;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = material::parse(Path::new("<fuzz>"), data) {
        let b = m.to_bsdf().expect("a parsed material builds its BSDF");
        let wi = DVec3::new(0.3, 0.1, 0.9).normalize();
        let wo = DVec3::new(-0.2, 0.4, 0.8).normalize();
        let _ = b.eval(wi, wo);
        let _ = material::parse(Path::new("<fuzz>"), m.to_json().expect("re-serializes").as_bytes())
            .expect("a parsed material parses again");
    }
});
