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
    #[error("invalid parameter {name} = {}: {reason}", plain_number(*value))]
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

/// The largest reflectance parameter (kd, ks, ρ) a model takes: an albedo of 10⁶ amplifies light
/// a million times and is no material; larger values overflow the albedo sums to ∞.
pub const MAX_REFLECTANCE: f64 = 1e6;

/// A number as a person reads it in a message: plain between 10⁻⁴ and 10⁶, else in exponent
/// form (`1e300`, not 301 digits); the largest finite values as ∞.
pub fn plain_number(v: f64) -> String {
    if v >= f64::MAX {
        "∞".into()
    } else if v <= -f64::MAX {
        "-∞".into()
    } else if v != 0.0 && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Checks that a parameter is finite and within [lo, hi] (either end may be ±`f64::MAX` or ±∞
/// for none); the message prints the limits in plain form.
pub fn check_range(name: &str, value: f64, lo: f64, hi: f64) -> Result<f64> {
    if !value.is_finite() {
        return Err(Error::param(name, value, "not a finite number"));
    }
    if value < lo || value > hi {
        let reason = match (lo <= -f64::MAX, hi >= f64::MAX) {
            (false, true) => format!("must be ≥ {}", plain_number(lo)),
            (true, false) => format!("must be ≤ {}", plain_number(hi)),
            _ => format!("must lie in [{}, {}]", plain_number(lo), plain_number(hi)),
        };
        return Err(Error::param(name, value, reason));
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

/// An exclusive hold on a job's part of an output folder (a shard, a merge), released when
/// dropped or when the process dies (an advisory `flock` on `path`, which works across the
/// machines of an NFS share): two processes writing the same part are refused, not interleaved.
/// The lock file stays; it records who holds it.
#[derive(Debug)]
pub struct OutputLock {
    _file: std::fs::File,
}

/// Holds `path` for `what` (e.g. "shard 1/3"), or, when another process holds it, an error
/// naming `what`, the lock file and its holder (host and process). The folder must exist.
pub fn lock_output(path: &std::path::Path, what: &str) -> Result<OutputLock> {
    use std::io::{Read, Seek, Write};
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(path)
        .map_err(|e| Error::io(path, e))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            let mut holder = String::new();
            // Best effort: the holder wrote its name after locking.
            let _ = file.read_to_string(&mut holder);
            let holder = holder.trim();
            return Err(Error::format(
                path,
                format!(
                    "{what} is being written by another process{}; wait for it to finish (or \
                     stop it) before running {what} again into this folder",
                    if holder.is_empty() {
                        String::new()
                    } else {
                        format!(" ({holder})")
                    }
                ),
            ));
        }
        Err(std::fs::TryLockError::Error(e)) => return Err(Error::io(path, e)),
    }
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "this machine".into());
    let me = format!("{what}: process {} on {host}\n", std::process::id());
    file.set_len(0)
        .and_then(|()| file.rewind())
        .and_then(|()| file.write_all(me.as_bytes()))
        .map_err(|e| Error::io(path, e))?;
    Ok(OutputLock { _file: file })
}

/// Whether another process holds the lock at `path` (see [`lock_output`]); `false` when the
/// file does not exist.
pub fn output_locked(path: &std::path::Path) -> Result<bool> {
    let file = match std::fs::File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(false),
        Err(e) => return Err(Error::io(path, e)),
    };
    match file.try_lock_shared() {
        Ok(()) => Ok(false),
        Err(std::fs::TryLockError::WouldBlock) => Ok(true),
        Err(std::fs::TryLockError::Error(e)) => Err(Error::io(path, e)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_and_values_print_in_plain_form() {
        let e = check_range("x", -1.0, 0.0, f64::MAX)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "invalid parameter x = -1: must be ≥ 0");
        let e = check_range("rho", 1e300, 0.0, 1.0).unwrap_err().to_string();
        assert_eq!(e, "invalid parameter rho = 1e300: must lie in [0, 1]");
        let e = check_range("f", 2e7, -f64::MAX, 1e6)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "invalid parameter f = 2e7: must be ≤ 1e6");
        let e = check_range("a", 1e-5, 1e-4, 10.0).unwrap_err().to_string();
        assert_eq!(e, "invalid parameter a = 1e-5: must lie in [0.0001, 10]");
        assert!(check_range("ok", 5.0, 0.0, f64::INFINITY).is_ok());
    }

    #[test]
    fn an_output_lock_refuses_a_second_holder_until_dropped() {
        let dir = tempfile::tempdir().expect("dir");
        let path = dir.path().join("shard-0-of-2.lock");
        assert!(!output_locked(&path).expect("no file"));
        let held = lock_output(&path, "shard 0/2").expect("first");
        assert!(output_locked(&path).expect("held"));
        let e = lock_output(&path, "shard 0/2")
            .expect_err("second")
            .to_string();
        assert!(
            e.contains("shard 0/2 is being written by another process")
                && e.contains(&format!("process {}", std::process::id()))
                && e.contains("shard-0-of-2.lock"),
            "{e}"
        );
        drop(held);
        assert!(!output_locked(&path).expect("released"));
        let _again = lock_output(&path, "shard 0/2").expect("after release");
    }
}
