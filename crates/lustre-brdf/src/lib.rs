//! lustre-brdf: BSDF models and measured-material formats.
//!
//! Everything here is plain data and pure functions in f64, in a local shading frame (normal +z,
//! tangent +x). No rendering. The fitter, the integrators and the plots all call the same
//! [`Bsdf`] implementations.
//!
//! Equation numbers refer to the seeds: 000 (Luksch's thesis: Kurt model, transmission,
//! goniometric tables), 002 (Luksch et al. 2014) and 004 (Bagher's thesis: SGD, Cook-Torrance,
//! classic models).

pub mod bsdf;
pub mod catalog;
pub mod error;
pub mod fits;
pub mod frame;
pub mod material;
pub mod measured;
pub mod microfacet;
pub mod models;
pub mod numeric;
pub mod rgb;
pub mod sampling;
pub mod validate;

pub use bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
pub use error::{Error, Result};
pub use glam::DVec3;
pub use rgb::Rgb;

/// The project's shared third-party data folder: `$LUSTRE_DATA` if set, else `../shared/data`
/// beside the repository (where CI and every checkout have it).
pub fn shared_data_dir() -> std::path::PathBuf {
    if let Some(p) = std::env::var_os("LUSTRE_DATA") {
        return p.into();
    }
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data")
}
