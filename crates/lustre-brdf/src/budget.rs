//! One budget check before work starts, shared by every command: the memory and disk a job will
//! need, estimated from its options and inputs (images, pyramids, tiles, pages, per-thread
//! buffers), checked against what the machine has (available memory, free disk where the
//! output goes). A job over either is refused with both numbers and the options to change, or
//! run anyway with `--force`.
//!
//! The estimates are the sums of the buffers a job allocates at once, each from its element
//! size, plus [`BASE_MEMORY`] for the process itself; BENCHMARKS.md lists them against the
//! measured peak memory and disk of five jobs (estimate ≥ measured, within 2×).

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Memory of the process before a job allocates: the binary with its built-in data (published
/// fits, neural BRDFs), the thread pool's stacks, the allocator's arenas. Measured 20–40 MB
/// (peak RSS of `lustre demo --size 8x8 --cpu`); counted as 64 MiB.
pub const BASE_MEMORY: u64 = 64 << 20;

/// Bytes in a MiB, for messages.
const MIB: f64 = (1u64 << 20) as f64;

/// A byte count as a person reads it: `200 B`, `512 KB`, `3.4 MB`, `6.9 GB`, `1.2 TB` (powers of 1024,
/// one decimal above 10 units shown as whole numbers).
pub fn bytes(n: u64) -> String {
    if n < 1024 {
        return format!("{n} B");
    }
    let n = n as f64;
    let (v, unit) = if n >= 1024.0 * 1024.0 * MIB {
        (n / (1024.0 * 1024.0 * MIB), "TB")
    } else if n >= 1024.0 * MIB {
        (n / (1024.0 * MIB), "GB")
    } else if n >= MIB {
        (n / MIB, "MB")
    } else {
        (n / 1024.0, "KB")
    };
    if v >= 10.0 {
        format!("{v:.0} {unit}")
    } else {
        format!("{v:.1} {unit}")
    }
}

/// What the machine offers a job: available memory and free disk at the output (`None` where
/// the system does not tell, e.g. off Linux, which skips that half of the check).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Machine {
    /// Memory the job can allocate without swapping: `MemAvailable`, lowered to the cgroup's
    /// remaining limit inside a container.
    pub memory: Option<u64>,
    /// Free bytes on the file system of the output, for an unprivileged user.
    pub disk: Option<u64>,
}

impl Machine {
    /// This machine, with the disk of `out` (the output file or folder; its nearest existing
    /// ancestor when it does not exist yet).
    pub fn current(out: Option<&Path>) -> Self {
        Machine {
            memory: available_memory(),
            disk: out.and_then(free_disk),
        }
    }
}

/// `MemAvailable` from `/proc/meminfo`, and the cgroup v2 limit minus usage when lower.
pub fn available_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kb = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse::<u64>()
        .ok()?;
    let mut avail = kb.saturating_mul(1024);
    let read = |p: &str| -> Option<u64> { std::fs::read_to_string(p).ok()?.trim().parse().ok() };
    if let (Some(max), Some(cur)) = (
        read("/sys/fs/cgroup/memory.max"),
        read("/sys/fs/cgroup/memory.current"),
    ) {
        avail = avail.min(max.saturating_sub(cur));
    }
    Some(avail)
}

/// Free bytes (for an unprivileged user) on the file system holding `path`, or its nearest
/// existing ancestor.
pub fn free_disk(path: &Path) -> Option<u64> {
    let mut p: PathBuf = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir().ok()?.join(path)
    };
    while !p.exists() {
        if !p.pop() {
            return None;
        }
    }
    statvfs_free(&p)
}

#[cfg(unix)]
fn statvfs_free(p: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(p.as_os_str().as_bytes()).ok()?;
    let mut s = std::mem::MaybeUninit::<libc::statvfs>::uninit();
    // SAFETY: `c` is a NUL-terminated path and `s` points to writable memory of the right type;
    // statvfs fills it when it returns 0.
    let rc = unsafe { libc::statvfs(c.as_ptr(), s.as_mut_ptr()) };
    if rc != 0 {
        return None;
    }
    // SAFETY: statvfs returned 0, so it initialized `s`.
    let s = unsafe { s.assume_init() };
    #[allow(clippy::unnecessary_cast)] // the field types differ between platforms
    Some((s.f_bavail as u64).saturating_mul(s.f_frsize as u64))
}

#[cfg(not(unix))]
fn statvfs_free(_p: &Path) -> Option<u64> {
    None
}

/// A job's estimated needs: named parts of memory and disk, the output whose disk counts, and
/// the options that change them (for the message).
#[derive(Clone, Debug, Default)]
pub struct Budget {
    job: String,
    change: String,
    memory: Vec<(String, u64)>,
    disk: Vec<(String, u64)>,
    out: Option<PathBuf>,
}

impl Budget {
    /// A budget for `job` (e.g. "lustre reference at 20000×20000, 2 threads"); `change` names
    /// the options that lower it (e.g. "lower --size").
    pub fn new(job: impl Into<String>, change: impl Into<String>) -> Self {
        Budget {
            job: job.into(),
            change: change.into(),
            ..Budget::default()
        }
    }

    /// Adds `n` elements of `size` bytes of memory, named `what` (saturating: absurd counts
    /// give an absurd, refused, total rather than an overflow).
    pub fn memory(mut self, what: impl Into<String>, n: u64, size: u64) -> Self {
        self.memory.push((what.into(), n.saturating_mul(size)));
        self
    }

    /// Adds `n` elements of `size` bytes written under `out`, named `what`.
    pub fn disk(mut self, out: &Path, what: impl Into<String>, n: u64, size: u64) -> Self {
        self.out = Some(out.to_path_buf());
        self.disk.push((what.into(), n.saturating_mul(size)));
        self
    }

    /// The memory estimate: [`BASE_MEMORY`] plus every part.
    pub fn memory_bytes(&self) -> u64 {
        self.memory
            .iter()
            .fold(BASE_MEMORY, |a, (_, b)| a.saturating_add(*b))
    }

    /// The disk estimate: every part.
    pub fn disk_bytes(&self) -> u64 {
        self.disk.iter().fold(0, |a, (_, b)| a.saturating_add(*b))
    }

    /// The output whose file system the disk estimate is checked against.
    pub fn output(&self) -> Option<&Path> {
        self.out.as_deref()
    }

    /// One line: "about 6.9 GB of memory (accumulator 4.5 GB, …) and 3.0 GB of disk (…)".
    pub fn summary(&self) -> String {
        let parts = |v: &[(String, u64)]| {
            v.iter()
                .filter(|(_, b)| *b > 0)
                .map(|(w, b)| format!("{w} {}", bytes(*b)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut s = format!("about {} of memory", bytes(self.memory_bytes()));
        let m = parts(&self.memory);
        if !m.is_empty() {
            s.push_str(&format!(" ({m})"));
        }
        if self.disk_bytes() > 0 {
            s.push_str(&format!(
                " and {} of disk ({})",
                bytes(self.disk_bytes()),
                parts(&self.disk)
            ));
        }
        s
    }

    /// Checks the budget against this machine; see [`Budget::check_against`].
    pub fn check(&self, force: bool) -> Result<Vec<String>> {
        self.check_against(&Machine::current(self.out.as_deref()), force)
    }

    /// Refuses a job whose memory or disk estimate exceeds what `machine` offers, naming both
    /// numbers and the options to change; with `force`, returns the same text as a warning
    /// instead. A job of over 1 GB that fits gets a note with its estimate.
    pub fn check_against(&self, machine: &Machine, force: bool) -> Result<Vec<String>> {
        let (mem, disk) = (self.memory_bytes(), self.disk_bytes());
        let mut over = Vec::new();
        if let Some(avail) = machine.memory.filter(|&a| mem > a) {
            over.push(format!("{} of memory are available", bytes(avail)));
        }
        if let Some(free) = machine.disk.filter(|&f| disk > f) {
            let at = self
                .out
                .as_deref()
                .map(|p| format!(" at {}", p.display()))
                .unwrap_or_default();
            over.push(format!("{} of disk are free{at}", bytes(free)));
        }
        if over.is_empty() {
            let big = mem > 1 << 30 || disk > 1 << 30;
            return Ok(if big {
                vec![format!("{} needs {}", self.job, self.summary())]
            } else {
                Vec::new()
            });
        }
        let text = format!(
            "{} needs {}, but {}",
            self.job,
            self.summary(),
            over.join(" and ")
        );
        if force {
            Ok(vec![format!("{text}; running anyway (--force)")])
        } else {
            Err(Error::Budget(format!(
                "{text}: {}, or pass --force to run it anyway",
                self.change
            )))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_counts_print_in_plain_units() {
        assert_eq!(bytes(200), "200 B");
        assert_eq!(bytes(512 << 10), "512 KB");
        assert_eq!(bytes(3 << 20), "3.0 MB");
        assert_eq!(bytes(7_400_000_000), "6.9 GB");
        assert_eq!(bytes(u64::MAX), "16777216 TB");
    }

    #[test]
    fn a_job_over_the_machine_is_refused_with_both_numbers_unless_forced() {
        let out = Path::new("/tmp/x.exr");
        let b = Budget::new("lustre reference at 20000×20000", "lower --size")
            .memory("accumulator", 400_000_000, 48)
            .disk(out, "images", 400_000_000, 24);
        let m = Machine {
            memory: Some(8 << 30),
            disk: Some(100 << 30),
        };
        let e = b.check_against(&m, false).unwrap_err().to_string();
        assert!(
            e.contains("needs about 18 GB of memory (accumulator 18 GB)")
                && e.contains("but 8.0 GB of memory are available")
                && e.contains("lower --size, or pass --force"),
            "{e}"
        );
        assert!(!e.contains("of disk are free"), "{e}");
        let w = b.check_against(&m, true).expect("forced");
        assert!(w.len() == 1 && w[0].contains("running anyway (--force)"));
        let small = Machine {
            memory: Some(8 << 30),
            disk: Some(1 << 30),
        };
        let e = b.check_against(&small, false).unwrap_err().to_string();
        assert!(e.contains("1.0 GB of disk are free at /tmp/x.exr"), "{e}");
        // Unknown machine figures check nothing.
        let none = Machine {
            memory: None,
            disk: None,
        };
        assert!(b.check_against(&none, false).is_ok());
    }

    #[test]
    fn absurd_counts_saturate_instead_of_overflowing() {
        let b = Budget::new("j", "c").memory("x", u64::MAX, 48);
        assert_eq!(b.memory_bytes(), u64::MAX);
    }

    #[test]
    fn this_machine_reports_memory_and_disk() {
        let m = Machine::current(Some(Path::new("no/such/folder/out.exr")));
        assert!(m.memory.is_some_and(|v| v > 1 << 20), "{m:?}");
        assert!(m.disk.is_some_and(|v| v > 1 << 20), "{m:?}");
    }
}
