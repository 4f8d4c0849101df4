//! Errors of the ray-tracing library.

use std::path::PathBuf;

/// What can go wrong building the accelerator, tracing, baking, or reading and writing images.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// An absurd parameter (zero samples, empty image, an empty scene, ...).
    #[error("invalid parameter: {0}")]
    Parameter(String),
    /// An environment-map error.
    #[error(transparent)]
    Env(#[from] lustre_env::EnvError),
    /// A BSDF-library error.
    #[error(transparent)]
    Brdf(#[from] lustre_brdf::Error),
    /// A file could not be written or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system or encoder error.
        source: std::io::Error,
    },
}

/// The result type of lustre-trace.
pub type Result<T> = std::result::Result<T, TraceError>;
