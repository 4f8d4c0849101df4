//! Errors of the environment-map library.

use std::path::PathBuf;

/// What can go wrong reading, converting or filtering environment maps.
#[derive(Debug, thiserror::Error)]
pub enum EnvError {
    /// The file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The file's content is not a valid or supported environment map.
    #[error("{}: {problem}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong, in words.
        problem: String,
    },
    /// An absurd parameter (zero size, non-square face, negative radius, ...).
    #[error("invalid parameter: {0}")]
    Parameter(String),
}

/// The result type of lustre-env.
pub type Result<T> = std::result::Result<T, EnvError>;
