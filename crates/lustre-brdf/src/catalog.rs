//! Resolves a material specification (a model with parameters, a published fit by name, a
//! measured file or an NBRDF material) to a [`crate::Bsdf`].
//!
//! Stand-in (branch wt-f only, to be replaced by the real catalog): resolves `lambert` and
//! `kurt-demo` (a Lambert term plus a normalized Phong lobe) so that `lustre plot` builds.

use crate::{Bsdf, BsdfFlags, BsdfSample, DVec3, Error, Result, Rgb};
use std::f64::consts::PI;

/// The names [`resolve`] accepts.
pub fn list() -> Vec<String> {
    vec!["kurt-demo".into(), "lambert".into()]
}

/// The BSDF a specification names.
pub fn resolve(spec: &str) -> Result<Box<dyn Bsdf>> {
    match spec {
        "lambert" => Ok(Box::new(StandIn {
            kd: Rgb::splat(0.5),
            ks: Rgb::ZERO,
            n: 1.0,
        })),
        "kurt-demo" => Ok(Box::new(StandIn {
            kd: Rgb::new(0.2, 0.12, 0.06),
            ks: Rgb::splat(0.6),
            n: 40.0,
        })),
        _ => Err(Error::NotFound(format!(
            "unknown material '{spec}' (known: {})",
            list().join(", ")
        ))),
    }
}

#[derive(Debug)]
struct StandIn {
    kd: Rgb,
    ks: Rgb,
    n: f64,
}

impl Bsdf for StandIn {
    fn name(&self) -> String {
        "stand-in".into()
    }
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        let c = DVec3::new(-wi.x, -wi.y, wi.z).dot(wo).max(0.0);
        self.kd / PI + self.ks * ((self.n + 2.0) / (2.0 * PI) * c.powf(self.n))
    }
    fn sample(&self, _wo: DVec3, _u1: f64, _u2: f64) -> Option<BsdfSample> {
        None
    }
    fn pdf(&self, _wi: DVec3, _wo: DVec3) -> f64 {
        0.0
    }
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::default()
    }
}
