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
    /// A job needs more memory or disk than the machine has ([`crate::budget`]).
    #[error("{0}")]
    Budget(String),
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

/// The largest input file a reader takes (4 GiB: a MERL table is 35 MB, the largest RGL and
/// EXR files in the shared data under 300 MB).
pub const MAX_INPUT_BYTES: u64 = 4 << 30;

/// Reads the whole input file at `path`, the one way every reader reads: only a regular file
/// (a folder, FIFO, device or socket is refused before it is opened, so a FIFO never blocks
/// and `/dev/zero` never fills memory), of at most [`MAX_INPUT_BYTES`], checked from its size
/// before reading and again while reading. The error says what is wrong, without the path
/// (each crate's error adds it).
pub fn read_input(path: &std::path::Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    check_input(path)?;
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::new();
    file.take(MAX_INPUT_BYTES + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// Checks that `path` is a regular file (after symbolic links) of at most [`MAX_INPUT_BYTES`],
/// for readers that hand the path to a library; the error as in [`read_input`].
pub fn check_input(path: &std::path::Path) -> std::io::Result<()> {
    let meta = std::fs::metadata(path)?;
    let ft = meta.file_type();
    if !ft.is_file() {
        let what = if ft.is_dir() {
            "a folder"
        } else {
            special_kind(&ft)
        };
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{what}, not a regular file"),
        ));
    }
    if meta.len() > MAX_INPUT_BYTES {
        return Err(too_big(meta.len()));
    }
    Ok(())
}

fn too_big(n: u64) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!(
            "{} is over the {} an input file may have",
            crate::budget::bytes(n),
            crate::budget::bytes(MAX_INPUT_BYTES)
        ),
    )
}

#[cfg(unix)]
fn special_kind(ft: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if ft.is_fifo() {
        "a FIFO (named pipe)"
    } else if ft.is_char_device() {
        "a character device"
    } else if ft.is_block_device() {
        "a block device"
    } else if ft.is_socket() {
        "a socket"
    } else {
        "a special file"
    }
}

#[cfg(not(unix))]
fn special_kind(_ft: &std::fs::FileType) -> &'static str {
    "a special file"
}

/// Reads the whole input file at `path` ([`read_input`]); a failure is an [`Error::Io`]
/// naming the file.
pub fn read_file(path: &std::path::Path) -> Result<Vec<u8>> {
    read_input(path).map_err(|e| Error::io(path, e))
}

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, then a rename.
pub fn write_atomic(path: &std::path::Path, bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(Error::format(
            &dir,
            "no such folder (the output's folder must exist)",
        ));
    }
    // tempfile's own error names its hidden `.tmpXXXX` file; the user named the folder.
    let mut tmp = tempfile::NamedTempFile::new_in(&dir)
        .map_err(|e| Error::io(&dir, std::io::Error::from(e.kind())))?;
    // The file itself, not the NamedTempFile, whose errors append the hidden name.
    tmp.as_file_mut()
        .write_all(bytes)
        .map_err(|e| Error::io(path, e))?;
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

/// The first shard lock (`*.lock` other than `merge.lock`, by name) in `dir` that another
/// process holds, with its holder's line: what a merge refuses to start beside. `None` when
/// every shard has finished (or `dir` does not exist).
pub fn held_shard_lock(dir: &std::path::Path) -> Result<Option<(PathBuf, String)>> {
    let Ok(list) = std::fs::read_dir(dir) else {
        return Ok(None);
    };
    let mut locks: Vec<PathBuf> = list
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension().is_some_and(|e| e == "lock")
                && p.file_stem().is_some_and(|s| s != "merge")
        })
        .collect();
    locks.sort();
    for l in locks {
        if output_locked(&l)? {
            let holder = std::fs::read_to_string(&l).unwrap_or_default();
            return Ok(Some((l, holder.trim().to_string())));
        }
    }
    Ok(None)
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
    fn an_atomic_write_names_the_folder_not_its_temporary_file() {
        // A folder whose own name has no ".tmp" in it.
        let dir = tempfile::Builder::new()
            .prefix("atomic")
            .tempdir()
            .expect("dir");
        let missing = dir.path().join("no-such-folder");
        let e = write_atomic(&missing.join("out.json"), b"{}")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no-such-folder: no such folder"), "{e}");
        assert!(!e.contains(".tmp"), "{e}");
        let f = dir.path().join("out.json");
        write_atomic(&f, b"{}").expect("write");
        assert_eq!(std::fs::read(&f).expect("read"), b"{}");
    }

    #[test]
    fn only_regular_files_are_read() {
        let dir = tempfile::tempdir().expect("dir");
        let e = read_file(dir.path()).unwrap_err().to_string();
        assert!(e.contains("a folder, not a regular file"), "{e}");
        let e = read_file(std::path::Path::new("/dev/zero"))
            .unwrap_err()
            .to_string();
        assert!(
            e == "/dev/zero: a character device, not a regular file",
            "{e}"
        );
        let fifo = dir.path().join("pipe");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo");
        assert!(made.success());
        // Refused before opening: opening a FIFO with no writer would block.
        let e = read_file(&fifo).unwrap_err().to_string();
        assert!(
            e.ends_with("pipe: a FIFO (named pipe), not a regular file"),
            "{e}"
        );
        let f = dir.path().join("f");
        std::fs::write(&f, b"abc").expect("write");
        assert_eq!(read_file(&f).expect("read"), b"abc");
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
