//! Errors of the shading library.

use std::path::PathBuf;

/// What can go wrong building patterns, scenes or images, or shading.
#[derive(Debug, thiserror::Error)]
pub enum ShadeError {
    /// An absurd parameter (negative roughness, zero samples, empty image, ...).
    #[error("invalid parameter: {0}")]
    Parameter(String),
    /// An environment-map error.
    #[error(transparent)]
    Env(#[from] lustre_env::EnvError),
    /// A BSDF-library error.
    #[error(transparent)]
    Brdf(#[from] lustre_brdf::Error),
    /// From ray casting, the path tracer, baking or the images (lustre-trace).
    #[error(transparent)]
    Trace(#[from] lustre_trace::TraceError),
    /// A file could not be written or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system or encoder error.
        source: std::io::Error,
    },
}

/// The result type of lustre-shade.
pub type Result<T> = std::result::Result<T, ShadeError>;
