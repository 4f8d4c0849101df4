//! The Ward-Dür BRDF (Dür 2006): Ward's lobe with the normalization 1/(cosθi cosθo) instead of
//! 1/√(cosθi cosθo), 004 §III.4.4.4 second equation:
//!
//! f = ρd/π + ρs · exp(−tan²θh (cos²φh/α² + sin²φh/β²)) / (4παβ cosθi cosθo).
//!
//! Reciprocal, but its albedo still exceeds 1 at grazing angles for some parameters (Neumann 1999;
//! measured in the tests). Sampling as in [`crate::models::ward`] (Walter 2005).

use crate::models::ward::{ward_variant, WardCore, WardKind};

/// The Ward-Dür anisotropic BRDF (α along the tangent +x, β along +y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WardDuer {
    core: WardCore,
}

ward_variant!(WardDuer, WardKind::Duer, "ward-duer");

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Bsdf;
    use crate::frame::spherical;
    use crate::rgb::Rgb;
    use glam::DVec3;
    use std::f64::consts::PI;

    #[test]
    fn known_value_and_ratio_to_ward() {
        // Away from the normal the two lobes differ by exactly √(cosθi cosθo).
        let d = WardDuer::new(Rgb::ZERO, Rgb::ONE, 0.2, 0.3).expect("valid");
        let w = crate::models::ward::Ward::new(Rgb::ZERO, Rgb::ONE, 0.2, 0.3).expect("valid");
        let wi = spherical(0.7, 0.4);
        let wo = spherical(0.9, -2.5);
        let r = w.specular_lobe(wi, wo) / d.specular_lobe(wi, wo);
        assert!((r - (wi.z * wo.z).sqrt()).abs() < 1e-12);
        let f = d.eval(DVec3::Z, DVec3::Z)[0];
        assert!((f - 1.0 / (4.0 * PI * 0.06)).abs() < 1e-12);
    }
}
