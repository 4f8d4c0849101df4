//! Resuming a batch from the outputs already in its folder (the rules are in the `batch`
//! module's notes): which JSON can be reused instead of fitting again, which holds a fit made
//! with other options (never overwritten silently), and the rows of earlier batches' fits.

use super::runner::Job;
use super::{is_failure, parse_status, FailureFile, FitOptions, SummaryRow};
use lustre_brdf::material;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// A description of the existing fit at `path` when it is a valid fit of the same input with
/// another model or other options (`None` otherwise: no file, a failure, a corrupted file, a fit
/// of another input, or the same options).
pub(super) fn other_options(path: &Path, job: &Job, options: &FitOptions) -> Option<String> {
    let m = material::read(path).ok()?;
    let f = m.fit.as_ref()?;
    let status = parse_status(&f.status)?;
    let differs = m.model.kind() != options.model.as_str() || f.options != options.to_json();
    (f.source == job.input && !is_failure(status) && differs)
        .then(|| format!("{}, options {}", m.model.kind(), f.options))
}

/// The rows of the `*.json` files in `out` that are not among `rows` (fits of earlier batches),
/// sorted by name: materials with their numbers, failure records with their status.
pub(super) fn earlier_rows(out: &Path, rows: &[SummaryRow]) -> Vec<SummaryRow> {
    let have: HashSet<String> = rows.iter().map(|r| r.name.to_ascii_lowercase()).collect();
    let Ok(dir) = std::fs::read_dir(out) else {
        return Vec::new();
    };
    let mut paths: Vec<PathBuf> = dir
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    paths.sort();
    paths
        .into_iter()
        .filter_map(|p| {
            let name = p.file_stem()?.to_string_lossy().into_owned();
            if have.contains(&name.to_ascii_lowercase()) {
                return None;
            }
            if let Ok(m) = material::read(&p) {
                let f = m.fit.as_ref()?;
                let status = parse_status(&f.status)?;
                return Some(SummaryRow::new(&name, f, m.model.kind(), status, true));
            }
            let bytes = std::fs::read(&p).ok()?;
            let f: FailureFile = serde_json::from_slice(&bytes).ok()?;
            let status = parse_status(&f.fit.status)?;
            let model = f
                .fit
                .options
                .get("model")
                .and_then(|v| v.as_str())
                .unwrap_or("")
                .to_string();
            Some(SummaryRow::new(&name, &f.fit, &model, status, true))
        })
        .collect()
}

/// The row of an existing output that can be reused, if any (see the `batch` module notes).
pub(super) fn reusable(path: &Path, job: &Job, options: &FitOptions) -> Option<SummaryRow> {
    let m = material::read(path).ok()?;
    let f = m.fit.as_ref()?;
    let status = parse_status(&f.status)?;
    let same = f.source == job.input
        && m.model.kind() == options.model.as_str()
        && f.options == options.to_json()
        && !is_failure(status)
        && f.input_hash == input_hash(&job.input);
    same.then(|| SummaryRow::new(&job.name, f, m.model.kind(), status, true))
}

/// The data file of an input: the path of a file input, the network file of
/// `nbrdf:FILE#NAME`; `None` for a built-in (`nbrdf:NAME`).
fn input_file(input: &str) -> Option<&Path> {
    let spec = input.strip_prefix("nbrdf:").unwrap_or(input);
    let file = spec.rsplit_once('#').map_or(spec, |(f, _)| f);
    let p = Path::new(file);
    p.is_file().then_some(p)
}

/// The fingerprint of an input's data file, `crc32:HEX:LENGTH` (`None` for a built-in input,
/// or a file that cannot be read: its fit fails and is not reused).
pub(super) fn input_hash(input: &str) -> Option<String> {
    let file = input_file(input)?;
    let bytes = lustre_brdf::error::read_input(file).ok()?;
    Some(format!(
        "crc32:{:08x}:{}",
        crc32fast::hash(&bytes),
        bytes.len()
    ))
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{csv_rows, options, Mock};
    use crate::batch::{run, BatchOptions, FitOptions, ModelChoice};
    use lustre_brdf::material;
    use std::path::Path;
    use std::sync::atomic::Ordering;

    fn mtime(p: &Path) -> std::time::SystemTime {
        std::fs::metadata(p)
            .and_then(|m| m.modified())
            .expect("mtime")
    }

    #[test]
    fn resume_skips_done_inputs_and_refits_corrupted_ones() {
        let dir = tempfile::tempdir().expect("dir");
        let inputs: Vec<String> = vec!["data/a.gonio".into(), "data/b.binary".into()];
        let mock = Mock::default();
        let opts = options(dir.path());
        let s = run(&inputs, &opts, &mock).expect("batch");
        assert_eq!(mock.fits.load(Ordering::SeqCst), 2);
        assert_eq!((s.failed(), s.resumed()), (0, 0));
        let (a, b) = (dir.path().join("a.json"), dir.path().join("b.json"));
        let m = material::read(&a).expect("a material");
        assert_eq!(m.fit.as_ref().map(|f| f.status.as_str()), Some("converged"));
        let t_a = mtime(&a);

        let s = run(&inputs, &opts, &mock).expect("resumed batch");
        assert_eq!(
            mock.fits.load(Ordering::SeqCst),
            2,
            "nothing is fitted again"
        );
        assert_eq!(s.resumed(), 2);
        assert_eq!(mtime(&a), t_a, "a.json is not rewritten");
        assert_eq!(s.rows[0].ngan_l2_g, Some(0.02));

        std::fs::write(&b, b"{\"schema\": \"lustre-mat").expect("corrupt");
        let s = run(&inputs, &opts, &mock).expect("batch");
        assert_eq!(
            mock.fits.load(Ordering::SeqCst),
            3,
            "only the corrupted one"
        );
        assert!(s.rows[0].resumed && !s.rows[1].resumed);
        material::read(&b).expect("b rewritten");

        let other = BatchOptions {
            fit: FitOptions {
                lobes: 2,
                ..FitOptions::new(ModelChoice::Kurt)
            },
            ..options(dir.path())
        };
        // Other options never overwrite silently: refused, nothing fitted, files unchanged.
        let e = run(&inputs, &other, &mock).unwrap_err().to_string();
        assert!(e.contains("--force") && e.contains("a.json"), "{e}");
        assert_eq!(
            mock.fits.load(Ordering::SeqCst),
            3,
            "refused before fitting"
        );
        assert_eq!(mtime(&a), t_a);
        // To another name: both fits stay and the summary covers all four JSON files.
        let suffixed = BatchOptions {
            suffix: "2lobes".into(),
            ..other.clone()
        };
        let s = run(&inputs, &suffixed, &mock).expect("batch");
        assert_eq!(mock.fits.load(Ordering::SeqCst), 5);
        let names: Vec<&str> = s.rows.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(names, ["a-2lobes", "b-2lobes", "a", "b"]);
        assert_eq!((s.fitted(), s.resumed(), s.failed()), (2, 0, 0));
        assert_eq!(s.earlier_rows().len(), 2);
        assert_eq!(csv_rows(&s.summary_path).len(), 4);
        let forced = BatchOptions {
            force: true,
            ..other.clone()
        };
        let s = run(&inputs, &forced, &mock).expect("batch");
        assert_eq!(mock.fits.load(Ordering::SeqCst), 7, "--force refits");
        assert_eq!(s.resumed(), 0);
        assert_eq!(csv_rows(&s.summary_path).len(), 4);
        let m = material::read(&a).expect("a material");
        assert_eq!(m.fit.expect("record").options["lobes"], 2);
        // The CT options ignore the lobe settings.
        let ggx = |lobes| FitOptions {
            lobes,
            ..FitOptions::new(ModelChoice::Ggx)
        };
        assert_eq!(ggx(1).to_json(), ggx(3).to_json());
        assert_ne!(
            FitOptions::new(ModelChoice::Kurt).to_json(),
            other.fit.to_json()
        );
    }

    #[test]
    fn a_changed_input_file_is_fitted_again() {
        let dir = tempfile::tempdir().expect("dir");
        let data = dir.path().join("t.gonio");
        std::fs::write(&data, b"data").expect("write");
        let out = dir.path().join("out");
        let inputs = vec![data.to_string_lossy().into_owned()];
        let mock = Mock::default();
        run(&inputs, &options(&out), &mock).expect("batch");
        run(&inputs, &options(&out), &mock).expect("batch");
        assert_eq!(mock.fits.load(Ordering::SeqCst), 1);
        // A newer file with the same bytes is the same input: reused.
        let later = mtime(&out.join("t.json")) + std::time::Duration::from_secs(5);
        std::fs::File::options()
            .write(true)
            .open(&data)
            .and_then(|f| f.set_modified(later))
            .expect("touch");
        let s = run(&inputs, &options(&out), &mock).expect("batch");
        assert_eq!((mock.fits.load(Ordering::SeqCst), s.resumed()), (1, 1));
        // Other bytes, even with an older time stamp, are refitted.
        std::fs::write(&data, b"datb").expect("edit");
        let earlier = mtime(&out.join("t.json")) - std::time::Duration::from_secs(60);
        std::fs::File::options()
            .write(true)
            .open(&data)
            .and_then(|f| f.set_modified(earlier))
            .expect("back-date");
        let s = run(&inputs, &options(&out), &mock).expect("batch");
        assert_eq!(
            mock.fits.load(Ordering::SeqCst),
            2,
            "the edited input is refitted"
        );
        assert_eq!(s.resumed(), 0);
        let m = lustre_brdf::material::read(&out.join("t.json")).expect("fit");
        let h = m.fit.and_then(|f| f.input_hash).expect("hash recorded");
        assert_eq!(h, format!("crc32:{:08x}:4", crc32fast::hash(b"datb")));
    }
}
