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
pub mod budget;
pub mod catalog;
pub mod embedded;
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
pub mod tabulated;
pub mod validate;

pub use bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
pub use error::{Error, Result};
pub use glam::DVec3;
pub use rgb::Rgb;

/// The data folder of a user's installation: `$LUSTRE_DATA` (the CLI's `--data DIR` sets it).
/// Only larger data (measured files, environment maps) lives there; the published fit tables
/// and the MERL neural BRDFs are embedded ([`embedded`]). The error says how to set it.
pub fn data_dir() -> Result<std::path::PathBuf> {
    match std::env::var_os("LUSTRE_DATA") {
        Some(p) if !p.is_empty() => {
            let p = std::path::PathBuf::from(p);
            if p.is_dir() {
                Ok(p)
            } else {
                Err(Error::NotFound(format!(
                    "LUSTRE_DATA = {} is not a folder (it should hold the shared data: fits/, \
                     nbrdf/, measured/, envmaps/)",
                    p.display()
                )))
            }
        }
        _ => Err(Error::NotFound(
            "no data folder: set LUSTRE_DATA (or pass --data DIR) to the folder holding the \
             shared data (fits/, nbrdf/, measured/, envmaps/)"
                .into(),
        )),
    }
}

/// The project's shared third-party data folder for tests, benchmarks and examples run from the
/// source tree: `$LUSTRE_DATA` if set, else `../shared/data` beside the repository (where CI and
/// every checkout have it). Library code that runs in the installed binary uses [`data_dir`]
/// or [`embedded`] instead, so that no build-tree path is compiled into it.
pub fn shared_data_dir() -> std::path::PathBuf {
    if let Some(p) = std::env::var_os("LUSTRE_DATA") {
        return p.into();
    }
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data")
}
