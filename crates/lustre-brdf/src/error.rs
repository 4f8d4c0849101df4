//! Errors of the readers and model constructors: each names the file (when there is one) and the
//! problem, and no reader panics on bad input.

use std::path::PathBuf;

/// Everything that can go wrong when loading data or building a model.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be opened or read.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said (part of the message, not a separate cause, so that
        /// a chain of contexts prints it once).
        error: std::io::Error,
    },
    /// The file was read but its contents are not valid for its format.
    #[error("{path}: {problem}")]
    Format {
        /// The file (or a pseudo-path such as `<memory>`).
        path: PathBuf,
        /// What is wrong, in words.
        problem: String,
    },
    /// A model parameter is out of its valid range.
    #[error("invalid parameter {name} = {value}: {reason}")]
    Parameter {
        /// The parameter.
        name: String,
        /// The offending value.
        value: f64,
        /// Why it is rejected.
        reason: String,
    },
    /// A name (material, model) was not found.
    #[error("{0}")]
    NotFound(String),
}

/// Result alias for this crate.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// A format error for `path`.
    pub fn format(path: impl Into<PathBuf>, problem: impl Into<String>) -> Self {
        Error::Format {
            path: path.into(),
            problem: problem.into(),
        }
    }

    /// An I/O error for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            error: source,
        }
    }

    /// A parameter error.
    pub fn param(name: &str, value: f64, reason: impl Into<String>) -> Self {
        Error::Parameter {
            name: name.to_string(),
            value,
            reason: reason.into(),
        }
    }
}

/// Checks that a parameter is finite and within [lo, hi].
pub fn check_range(name: &str, value: f64, lo: f64, hi: f64) -> Result<f64> {
    if !value.is_finite() {
        return Err(Error::param(name, value, "not a finite number"));
    }
    if value < lo && hi == f64::INFINITY {
        return Err(Error::param(name, value, format!("must be ≥ {lo}")));
    }
    if value < lo || value > hi {
        return Err(Error::param(
            name,
            value,
            format!("must lie in [{lo}, {hi}]"),
        ));
    }
    Ok(value)
}

/// Checks that every channel of a colour is finite and within [lo, hi] (`hi` may be +∞); errors
/// name the channel (`name.r`, `name.g`, `name.b`).
pub fn check_rgb(name: &str, c: crate::rgb::Rgb, lo: f64, hi: f64) -> Result<crate::rgb::Rgb> {
    // The valid case is tested first without building the channel names: materials are built
    // at every path-tracer hit.
    if (0..3).all(|i| c[i].is_finite() && c[i] >= lo && c[i] <= hi) {
        return Ok(c);
    }
    for (i, ch) in ["r", "g", "b"].iter().enumerate() {
        check_range(&format!("{name}.{ch}"), c[i], lo, hi)?;
    }
    Ok(c)
}

/// Reads the whole file at `path`; a failure is an [`Error::Io`] naming the file.
pub fn read_file(path: &std::path::Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| Error::io(path, e))
}

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, then a rename.
pub fn write_atomic(path: &std::path::Path, bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut tmp = tempfile::NamedTempFile::new_in(&dir).map_err(|e| Error::io(&dir, e))?;
    tmp.write_all(bytes).map_err(|e| Error::io(path, e))?;
    // tempfile creates 0600 files; an output is an ordinary file (0644 before the umask).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(|e| Error::io(path, e))?;
    }
    tmp.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}
