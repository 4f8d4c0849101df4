//! The job loop behind [`run`]: expands the inputs into jobs with unique output names, keeps
//! a shard's share, refuses to overwrite fits made with other options, fits the jobs on a
//! thread pool with a progress bar (catching a fitter's errors and panics), writes each
//! input's JSON (a material or a [`FailureFile`]), then `summary.csv` or the shard's manifest.

use super::resume::{earlier_rows, other_options, reusable};
use super::shards::write_json;
use super::{
    check_shard, shard_manifest_path, status_str, write_summary, BatchOptions, BatchSummary,
    FailureFile, Fitter, ShardManifest, SummaryRow, FAILURE_SCHEMA, SHARD_SCHEMA, SUMMARY_FILE,
};
use crate::{FitError, FitStatus, Result};
use lustre_brdf::material::{self, FitRecord, MaterialFile};
use rayon::prelude::*;
use std::collections::HashSet;
use std::path::Path;
use std::time::Instant;

/// A file-name-safe name for an input: the material name of `nbrdf:FILE#NAME` or `nbrdf:NAME`,
/// else the file stem (plus a `#fragment`), with characters other than ASCII letters, digits,
/// `-`, `_` and `.` replaced by `-`; at most 100 characters; never empty or hidden (a name that
/// sanitizes to nothing, such as `*`, falls back to the file's stem, then to `input`).
pub fn output_name(input: &str) -> String {
    let input = input.trim();
    let raw = if let Some(rest) = input.strip_prefix("nbrdf:") {
        rest.rsplit_once('#').map_or(rest, |(_, n)| n).to_string()
    } else {
        let (path, frag) = match input.rsplit_once('#') {
            Some((p, f)) => (p, Some(f)),
            None => (input, None),
        };
        let stem = Path::new(path)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        match frag {
            Some(f) => format!("{stem}-{f}"),
            None => stem,
        }
    };
    let s: String = raw
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '-'
            }
        })
        .take(100)
        .collect();
    let s = s.trim_matches(|c| c == '-' || c == '.').to_string();
    match input.rsplit_once('#') {
        // `nbrdf:FILE#*` that could not be expanded: name it after the file.
        Some((file, _)) if s.is_empty() => output_name(file.trim_start_matches("nbrdf:")),
        _ if s.is_empty() => "input".into(),
        _ => s,
    }
}

/// One unit of work: an expanded input, its output name, or the error of its expansion.
pub(super) struct Job {
    pub(super) input: String,
    pub(super) name: String,
    expand_error: Option<FitError>,
}

/// Runs a batch: expands the inputs, fits them (resuming where valid outputs exist) on
/// `opts.jobs` threads, writes every JSON and `summary.csv`. Per-input failures are rows, not
/// errors; the error is for the batch as a whole (output folder not writable, no thread pool,
/// summary not written).
pub fn run(inputs: &[String], opts: &BatchOptions, fitter: &dyn Fitter) -> Result<BatchSummary> {
    std::fs::create_dir_all(&opts.out).map_err(|e| lustre_brdf::Error::io(&opts.out, e))?;
    let mut jobs = Vec::new();
    let mut taken = HashSet::new();
    let mut push = |input: String, expand_error: Option<FitError>| {
        let base = if opts.suffix.is_empty() {
            output_name(&input)
        } else {
            output_name(&format!("{}-{}", output_name(&input), opts.suffix))
        };
        let mut name = base.clone();
        let mut k = 2;
        // "summary" would not clash (summary.csv vs summary.json), but keep names unique
        // regardless of case so that case-insensitive file systems agree.
        while !taken.insert(name.to_ascii_lowercase()) {
            name = format!("{base}-{k}");
            k += 1;
        }
        jobs.push(Job {
            input,
            name,
            expand_error,
        });
    };
    for input in inputs {
        match fitter.expand(input) {
            Ok(list) => list.into_iter().for_each(|i| push(i, None)),
            Err(e) => push(input.clone(), Some(e)),
        }
    }
    let total = jobs.len();
    // One process per shard: a resubmitted task while the first still runs is refused.
    let mut _held = None;
    if let Some((k, n)) = opts.shard {
        check_shard(k, n)?;
        if n > total {
            return Err(FitError::Option(format!(
                "{n} shards for {total} inputs: shards {total} to {} would fit nothing; use at \
                 most {total} shards",
                n - 1
            )));
        }
        let dir = opts.out.join("shards");
        std::fs::create_dir_all(&dir).map_err(|e| lustre_brdf::Error::io(&dir, e))?;
        _held = Some(lustre_brdf::error::lock_output(
            &dir.join(format!("fit-{k}-of-{n}.lock")),
            &format!("shard {k}/{n}"),
        )?);
        jobs = jobs
            .into_iter()
            .enumerate()
            .filter(|(p, _)| p % n == k)
            .map(|(_, j)| j)
            .collect();
    }
    if !opts.force {
        let conflicts: Vec<String> = jobs
            .iter()
            .filter_map(|j| {
                let path = opts.out.join(format!("{}.json", j.name));
                other_options(&path, j, &opts.fit).map(|old| format!("{} ({old})", path.display()))
            })
            .collect();
        if !conflicts.is_empty() {
            let n = conflicts.len();
            let list: Vec<String> = conflicts.into_iter().take(5).collect();
            return Err(FitError::Option(format!(
                "{n} output(s) already hold a fit of the same input with another model or other \
                 options, e.g. {}; refit them with --force (overwrites), or keep both with \
                 --suffix TEXT (writes NAME-TEXT.json) or another --out folder",
                list.join(", ")
            )));
        }
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.jobs.max(1))
        .build()
        .map_err(|e| FitError::Option(format!("cannot start {} threads: {e}", opts.jobs)))?;
    let bar = if opts.progress {
        indicatif::ProgressBar::new(jobs.len() as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{spinner} fitting [{bar:30}] {pos}/{len} ({elapsed}) {msg}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    // Redraw while a long fit runs, so that its stage and the elapsed time stay current.
    bar.enable_steady_tick(std::time::Duration::from_millis(250));
    let stages: std::sync::Mutex<std::collections::BTreeMap<String, String>> =
        std::sync::Mutex::default();
    let show = |name: &str, what: Option<&str>| {
        let mut m = stages.lock().unwrap_or_else(|e| e.into_inner());
        match what {
            Some(w) => m.insert(name.to_string(), w.to_string()),
            None => m.remove(name),
        };
        let line: Vec<String> = m.iter().map(|(n, w)| format!("{n}: {w}")).collect();
        bar.set_message(line.join(" | "));
    };
    let rows: Vec<SummaryRow> = pool.install(|| {
        jobs.par_iter()
            .map(|job| {
                let row = run_one(job, opts, fitter, &|w| show(&job.name, Some(w)));
                show(&job.name, None);
                bar.inc(1);
                row
            })
            .collect()
    });
    bar.finish_and_clear();
    let batch = jobs.len();
    if let Some((k, n)) = opts.shard {
        let manifest = ShardManifest {
            schema: SHARD_SCHEMA.into(),
            version: 1,
            index: k,
            count: n,
            total,
            options: opts.fit.to_json(),
            positions: (0..total).filter(|p| p % n == k).collect(),
            rows: rows.clone(),
        };
        let summary_path = shard_manifest_path(&opts.out, k, n);
        write_json(&summary_path, &manifest)?;
        return Ok(BatchSummary {
            rows,
            summary_path,
            batch,
        });
    }
    let mut rows = rows;
    rows.extend(earlier_rows(&opts.out, &rows));
    let summary_path = opts.out.join(SUMMARY_FILE);
    write_summary(&summary_path, &rows)?;
    Ok(BatchSummary {
        rows,
        summary_path,
        batch,
    })
}

/// The status a fitting error maps to: bad data (unreadable or unusable input) or an error.
fn error_status(e: &FitError) -> FitStatus {
    match e {
        FitError::Brdf(_) | FitError::Data { .. } => FitStatus::InvalidData,
        FitError::Option(_) => FitStatus::Error,
    }
}

fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// Fits one input (or reuses its output) and writes its JSON; never fails.
fn run_one(
    job: &Job,
    opts: &BatchOptions,
    fitter: &dyn Fitter,
    stage: &(dyn Fn(&str) + Sync),
) -> SummaryRow {
    let path = opts.out.join(format!("{}.json", job.name));
    let options = &opts.fit;
    if !opts.force {
        if let Some(row) = reusable(&path, job, options) {
            return row;
        }
    }
    // Before the fit reads it: the bytes fitted, not those of a later edit.
    let input_hash = super::resume::input_hash(&job.input);
    let t0 = Instant::now();
    let result = match &job.expand_error {
        Some(e) => Err((error_status(e), e.to_string())),
        None => {
            match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                fitter.fit(&job.input, options, stage)
            })) {
                Ok(Ok(f)) => Ok(f),
                Ok(Err(e)) => Err((error_status(&e), e.to_string())),
                Err(p) => Err((
                    FitStatus::Error,
                    format!("the fit panicked: {}", panic_message(p.as_ref())),
                )),
            }
        }
    };
    let time_s = t0.elapsed().as_secs_f64();
    let model = options.model.as_str();
    let mut record = FitRecord {
        source: job.input.clone(),
        errors: None,
        albedo_data: None,
        albedo_model: None,
        time_s,
        status: String::new(),
        message: String::new(),
        options: options.to_json(),
        input_hash: input_hash.clone(),
    };
    let mut kept = None;
    let written = match result {
        Ok(f) => {
            record = FitRecord {
                input_hash,
                ..f.record(&job.input, options, time_s)
            };
            let file = MaterialFile::new(job.name.clone(), f.model.clone(), Some(record.clone()));
            match file.and_then(|m| material::write(&path, &m)) {
                Ok(()) => Ok(f.status),
                Err(e) => {
                    // Keep what the fit reached, to inspect.
                    kept = serde_json::to_value(&f.model).ok();
                    Err((
                        FitStatus::Error,
                        format!(
                            "the fit gave no valid material: {e} (its parameters are kept in \
                             this file's \"model\"; {})",
                            record.message
                        ),
                    ))
                }
            }
        }
        Err(e) => Err(e),
    };
    let status = match written {
        Ok(s) => s,
        Err((status, message)) => {
            record.errors = None;
            record.albedo_data = None;
            record.albedo_model = None;
            record.status = status_str(status).into();
            record.message = message;
            if let Err(e) = write_failure(&path, &job.name, &record, kept) {
                record.message = format!(
                    "{}; the failure record was not written: {e}",
                    record.message
                );
            }
            status
        }
    };
    SummaryRow::new(&job.name, &record, model, status, false)
}

/// Writes the [`FailureFile`] of a failed input atomically.
fn write_failure(
    path: &Path,
    name: &str,
    record: &FitRecord,
    model: Option<serde_json::Value>,
) -> Result<()> {
    let f = FailureFile {
        schema: FAILURE_SCHEMA.into(),
        version: 1,
        name: name.to_string(),
        fit: record.clone(),
        model,
    };
    let json = serde_json::to_string_pretty(&f)
        .map_err(|e| FitError::Option(format!("{}: {e}", path.display())))?;
    lustre_brdf::error::write_atomic(path, format!("{json}\n").as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{csv_rows, options, Mock};
    use super::*;
    use crate::batch::{parse_status, FitOptions, ModelChoice};
    use std::sync::atomic::Ordering;

    #[test]
    fn failures_become_rows_and_the_batch_goes_on() {
        let dir = tempfile::tempdir().expect("dir");
        let inputs: Vec<String> = [
            "x/good.gonio",
            "x/bad.gonio",
            "panic.dat",
            "nan.bsdf",
            "noexpand",
            "many",
        ]
        .map(String::from)
        .to_vec();
        let mock = Mock::default();
        let s = run(&inputs, &options(dir.path()), &mock).expect("batch");
        let names: Vec<&str> = s.rows.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(
            names,
            ["good", "bad", "panic", "nan", "noexpand", "red", "blue"]
        );
        let status: Vec<&str> = s.rows.iter().map(|r| status_str(r.status)).collect();
        assert_eq!(
            status,
            [
                "converged",
                "invalid-data",
                "error",
                "error",
                "invalid-data",
                "converged",
                "converged"
            ]
        );
        assert_eq!(s.failed(), 4);
        assert_eq!((s.fitted(), s.resumed()), (3, 0), "counts add up to 7");
        assert!(s.rows[1].message.contains("all samples are zero"));
        assert!(
            s.rows[2].message.contains("panicked"),
            "{}",
            s.rows[2].message
        );
        assert!(s.rows[3].message.contains("mx"), "{}", s.rows[3].message);
        // A fit that exists but is invalid keeps its parameters in the failure record.
        let nan: FailureFile =
            serde_json::from_slice(&std::fs::read(dir.path().join("nan.json")).expect("nan.json"))
                .expect("failure record");
        let kept = nan.model.expect("parameters kept");
        assert_eq!(kept["reflection"][0]["my"], 0.2, "{kept}");
        assert!(
            kept["reflection"][0]["mx"].is_null(),
            "NaN reads null: {kept}"
        );
        assert!(s.rows[4].message.contains("no such network"));
        assert_eq!(s.rows[1].ngan_l2_r, None);
        let rows = csv_rows(&s.summary_path);
        assert_eq!(rows.len(), 7);
        assert_eq!(&rows[1][3], "invalid-data");
        assert_eq!(&rows[1][4], "", "no numbers for a failed input");
        assert_eq!(&rows[0][4], "0.01");
        // A failure record is JSON the renderer refuses with a clear message.
        let bad = dir.path().join("bad.json");
        let f: FailureFile =
            serde_json::from_slice(&std::fs::read(&bad).expect("bad.json")).expect("failure");
        assert_eq!(
            (f.schema.as_str(), f.fit.status.as_str()),
            (FAILURE_SCHEMA, "invalid-data")
        );
        let e = material::read(&bad).unwrap_err().to_string();
        assert!(e.contains(FAILURE_SCHEMA), "{e}");
        // Resume retries the failures only.
        let before = mock.fits.load(Ordering::SeqCst);
        let s = run(&inputs, &options(dir.path()), &mock).expect("batch");
        assert_eq!(mock.fits.load(Ordering::SeqCst), before + 3);
        assert_eq!(s.resumed(), 3);
        assert_eq!(s.fitted() + s.resumed() + s.failed(), 7);
    }

    #[test]
    fn output_names_are_safe_and_unique() {
        assert_eq!(output_name("/data/merl/gold-paint.binary"), "gold-paint");
        assert_eq!(output_name("nbrdf:nickel"), "nickel");
        assert_eq!(output_name("nbrdf:/x/set.json#blue metal"), "blue-metal");
        assert_eq!(output_name("t.gonio#quadrilinear"), "t-quadrilinear");
        assert_eq!(output_name("../"), "input");
        assert_eq!(output_name("nbrdf:/data/merl_nbrdf.json#*"), "merl_nbrdf");
        assert_eq!(output_name(".hidden"), "hidden");
        assert!(output_name(&"x".repeat(500)).len() <= 100);
        for s in [
            FitStatus::Converged,
            FitStatus::NotConverged,
            FitStatus::InvalidData,
            FitStatus::Error,
        ] {
            assert_eq!(parse_status(status_str(s)), Some(s));
            let json = serde_json::to_value(s).expect("json");
            assert_eq!(json.as_str(), Some(status_str(s)));
        }
        let dir = tempfile::tempdir().expect("dir");
        let inputs: Vec<String> = vec!["a/m.gonio".into(), "b/m.gonio".into(), "b/M.gonio".into()];
        let opts = BatchOptions {
            fit: FitOptions {
                refine: false,
                ..FitOptions::new(ModelChoice::Kurt)
            },
            ..options(dir.path())
        };
        let s = run(&inputs, &opts, &Mock::default()).expect("batch");
        let names: Vec<&str> = s.rows.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(names, ["m", "m-2", "M-3"]);
        assert_eq!(s.rows[0].status, FitStatus::NotConverged);
        assert_eq!(s.failed(), 0, "not converged is a result, not a failure");
    }

    #[test]
    fn an_unwritable_output_folder_is_an_error() {
        let dir = tempfile::tempdir().expect("dir");
        let file = dir.path().join("file");
        std::fs::write(&file, b"x").expect("write");
        let e = run(
            &["a.gonio".into()],
            &options(&file.join("sub")),
            &Mock::default(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("file"), "{e}");
    }
}
