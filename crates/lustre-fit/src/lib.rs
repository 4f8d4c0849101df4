//! lustre-fit: fitting compact models to measured BRDF data.
//!
//! - [`ct`]: the two-slice Levenberg-Marquardt fit of Cook-Torrance with the SGD, Beckmann or
//!   GGX distribution (004 §V.4), plus a refinement over the full data.
//! - [`kurt`]: the hierarchical brute-force search of Kurt et al. lobes with the L1
//!   transfer-probability metric (000 §3.4.1, Eq. 3.7), multi-lobe and transmission.
//! - [`metrics`]: Ngan's normalized L2 (004 §V.5.3), the L1 of Eq. 3.7 and albedos.
//! - [`gltf`]: the glTF 2.0 metallic-roughness material fitted to data, for export;
//!   [`mitsuba`]: Mitsuba 3's rough conductor and rough plastic fitted alike; [`linear`]: the
//!   closed-form colour of models linear in it.
//! - [`data`]: measured inputs (MERL, NBRDF, RGL, goniometric) as fitting data.
//! - [`batch`]: the batch runner behind `lustre fit` (material JSON, CSV, resume).

pub mod batch;
pub mod ct;
pub mod data;
pub mod gltf;
pub mod kurt;
pub mod linear;
pub mod metrics;
pub mod mitsuba;

use serde::{Deserialize, Serialize};

/// What can go wrong in a fit. Bad data is an error with a message, never a panic.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// An error of the BSDF library (reading a file, an invalid parameter).
    #[error(transparent)]
    Brdf(#[from] lustre_brdf::Error),
    /// The input's data cannot be fitted (all zero, NaN, no valid samples, ...).
    #[error("{input}: {problem}")]
    Data {
        /// The input (file or specification).
        input: String,
        /// What is wrong, in words.
        problem: String,
    },
    /// An invalid fitting option (unknown parameter name, empty range, ...).
    #[error("invalid fit option: {0}")]
    Option(String),
}

/// The result type of lustre-fit.
pub type Result<T> = std::result::Result<T, FitError>;

/// How a fit ended; written into the material JSON and the CSV summary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FitStatus {
    /// The optimizer met its convergence criterion.
    Converged,
    /// The optimizer stopped at its iteration or evaluation limit.
    NotConverged,
    /// The input could not be fitted (see the message).
    InvalidData,
    /// Something else failed (see the message).
    Error,
}
