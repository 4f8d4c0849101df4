//! RGL tensor `.bsdf` files: any bytes give a BSDF or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_brdf::{measured::rgl::RglBsdf, Bsdf, DVec3};

fuzz_target!(|data: &[u8]| {
    if let Ok(b) = RglBsdf::parse("<fuzz>", data) {
        let wo = DVec3::new(0.3, 0.1, 0.9).normalize();
        let _ = b.eval(DVec3::Z, wo);
        let _ = b.sample(wo, 0.3, 0.7);
    }
});
