//! Outputs whole or absent: a command that fails leaves no empty folder of its own behind.

use std::path::Path;

/// Runs `job`, whose outputs go into the folder `dir`; when it fails and `dir` did not exist
/// before, removes the folders it left empty (the files it left, such as a bake's resumable
/// tiles, stay, with the folders that hold them).
pub fn in_folder<T>(dir: &Path, job: impl FnOnce() -> anyhow::Result<T>) -> anyhow::Result<T> {
    let existed = dir.exists();
    let result = job();
    if result.is_err() && !existed {
        remove_empty(dir);
    }
    result
}

/// Removes `dir` and the folders under it that hold no files.
fn remove_empty(dir: &Path) {
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                remove_empty(&e.path());
            }
        }
    }
    // Refused (and ignored) while anything is left in it.
    let _ = std::fs::remove_dir(dir);
}

#[cfg(test)]
mod tests {
    use super::in_folder;

    #[test]
    fn a_failed_job_removes_only_the_empty_folders_it_made() {
        let root = tempfile::tempdir().expect("dir");
        let made = root.path().join("out");
        let r: anyhow::Result<()> = in_folder(&made, || {
            std::fs::create_dir_all(made.join("tiles/empty"))?;
            anyhow::bail!("failed")
        });
        assert!(r.is_err() && !made.exists());
        // A file left (a resumable checkpoint) keeps its folders; empty ones go.
        let r: anyhow::Result<()> = in_folder(&made, || {
            std::fs::create_dir_all(made.join("tiles"))?;
            std::fs::create_dir_all(made.join("empty"))?;
            std::fs::write(made.join("tiles/t.bin"), b"x")?;
            anyhow::bail!("failed")
        });
        assert!(r.is_err());
        assert!(made.join("tiles/t.bin").is_file() && !made.join("empty").exists());
        // A folder that existed before is left as it was.
        let before = root.path().join("before");
        std::fs::create_dir_all(&before).expect("mkdir");
        let r: anyhow::Result<()> = in_folder(&before, || anyhow::bail!("failed"));
        assert!(r.is_err() && before.is_dir());
        // Success keeps everything.
        let ok = root.path().join("ok");
        in_folder(&ok, || Ok(std::fs::create_dir_all(&ok)?)).expect("ok");
        assert!(ok.is_dir());
    }
}
