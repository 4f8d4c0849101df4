//! Shards (several machines, one batch): the manifest a shard writes instead of `summary.csv`,
//! and [`merge`], which checks that the shards are all there and belong to one batch, gathers
//! their JSON and writes the summary of the whole batch.

use super::resume::earlier_rows;
use super::{write_summary, BatchSummary, SummaryRow, SUMMARY_FILE};
use crate::{FitError, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The schema name of a shard's manifest.
pub const SHARD_SCHEMA: &str = "lustre-fit-shard";

/// What one shard of a batch fitted (`OUT/shards/fit-K-of-N.json`), read by [`merge`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShardManifest {
    /// Always [`SHARD_SCHEMA`].
    pub schema: String,
    /// Always 1.
    pub version: u32,
    /// This shard's index K (0-based).
    pub index: usize,
    /// The number of shards N.
    pub count: usize,
    /// The number of inputs of the whole batch (after expansion).
    pub total: usize,
    /// The fit options ([`FitOptions::to_json`]).
    ///
    /// [`FitOptions::to_json`]: super::FitOptions::to_json
    pub options: serde_json::Value,
    /// The batch positions of this shard's inputs, one per row.
    pub positions: Vec<usize>,
    /// This shard's summary rows, in position order.
    pub rows: Vec<SummaryRow>,
}

/// Checks a shard selection `(index, count)`: `count ≥ 1` and `index < count`.
pub fn check_shard(index: usize, count: usize) -> Result<()> {
    if count == 0 || index >= count {
        return Err(FitError::Option(format!(
            "shard {index}/{count}: expected K/N with N ≥ 1 and 0 ≤ K < N"
        )));
    }
    Ok(())
}

/// Where shard `index` of `count` writes its manifest inside an output folder.
pub fn shard_manifest_path(out: &Path, index: usize, count: usize) -> PathBuf {
    out.join("shards")
        .join(format!("fit-{index}-of-{count}.json"))
}

pub(super) fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| lustre_brdf::Error::io(dir, e))?;
    }
    let json = serde_json::to_string_pretty(value)
        .map_err(|e| FitError::Option(format!("{}: {e}", path.display())))?;
    lustre_brdf::error::write_atomic(path, format!("{json}\n").as_bytes())?;
    Ok(())
}

/// Reads every shard manifest in `dir/shards/`; unreadable or foreign files are errors naming
/// them.
fn read_manifests(dir: &Path) -> Result<Vec<(PathBuf, ShardManifest)>> {
    let shards = dir.join("shards");
    let list = std::fs::read_dir(&shards).map_err(|e| {
        FitError::Option(format!(
            "{}: no shard manifests ({e}); run `lustre fit --shard K/N --out {}` first",
            shards.display(),
            dir.display()
        ))
    })?;
    let mut paths: Vec<PathBuf> = list
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension().is_some_and(|e| e == "json")
                && p.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with("fit-"))
        })
        .collect();
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            let bytes = lustre_brdf::error::read_file(&p)?;
            let m: ShardManifest = serde_json::from_slice(&bytes).map_err(|e| {
                FitError::Option(format!(
                    "{}: not a lustre fit shard manifest: {e}",
                    p.display()
                ))
            })?;
            let consistent = m.schema == SHARD_SCHEMA
                && m.version == 1
                && m.index < m.count
                && m.positions.len() == m.rows.len()
                && m.positions
                    .iter()
                    .all(|&q| q < m.total && q % m.count == m.index);
            if !consistent {
                return Err(FitError::Option(format!(
                    "{}: an inconsistent shard manifest (schema, index, positions or rows)",
                    p.display()
                )));
            }
            Ok((p, m))
        })
        .collect()
}

/// Refuses while a shard still runs into one of `dirs` (it holds `DIR/shards/fit-K-of-N.lock`),
/// and holds the merge's own lock in the first: the guard to keep while merging.
fn lock_merge(dirs: &[PathBuf]) -> Result<lustre_brdf::error::OutputLock> {
    for d in dirs {
        if let Some((l, holder)) = lustre_brdf::error::held_shard_lock(&d.join("shards"))? {
            return Err(FitError::Option(format!(
                "{}: still fitting ({holder}); merge once every shard has finished",
                l.display()
            )));
        }
    }
    let shards = dirs[0].join("shards");
    std::fs::create_dir_all(&shards).map_err(|e| lustre_brdf::Error::io(&shards, e))?;
    Ok(lustre_brdf::error::lock_output(
        &shards.join("merge.lock"),
        "the merge",
    )?)
}

/// Checks that `bytes` (the file `path`) hold a fit's JSON: an object with a lustre `schema` and
/// its `fit` record (a material or a [`super::FailureFile`]).
fn check_fit_file(path: &Path, bytes: &[u8]) -> Result<()> {
    let v: serde_json::Value = serde_json::from_slice(bytes).map_err(|e| {
        FitError::Option(format!(
            "{}: not a fit ({} bytes: {e}); run its shard again",
            path.display(),
            bytes.len()
        ))
    })?;
    let schema = v.get("schema").and_then(|s| s.as_str()).unwrap_or("");
    if !schema.starts_with("lustre-") || !v.get("fit").is_some_and(|f| f.is_object()) {
        return Err(FitError::Option(format!(
            "{}: not a lustre fit (no lustre schema and fit record); run its shard again",
            path.display()
        )));
    }
    Ok(())
}

/// Assembles the shards of a batch into `out` (`lustre fit --merge`): reads the manifests in
/// `out/shards/` and in every folder of `from` (shards run into separate folders), checks that
/// the N shards are all there, once, with the same batch size and options, copies the JSON of
/// every shard outside `out` into `out` (atomically), and writes `out/summary.csv`: the rows in
/// input order, then earlier fits in the folder, as an unsharded run writes it. Idempotent: an
/// interrupted merge is simply run again.
pub fn merge(out: &Path, from: &[PathBuf]) -> Result<BatchSummary> {
    std::fs::create_dir_all(out).map_err(|e| lustre_brdf::Error::io(out, e))?;
    let mut dirs = vec![out.to_path_buf()];
    dirs.extend(from.iter().filter(|d| d.as_path() != out).cloned());
    let _held = lock_merge(&dirs)?;
    let mut found: Vec<(PathBuf, PathBuf, ShardManifest)> = Vec::new();
    for d in &dirs {
        match read_manifests(d) {
            Ok(list) => found.extend(list.into_iter().map(|(p, m)| (d.clone(), p, m))),
            // The output folder itself need not hold shards when they are all elsewhere.
            Err(_) if d.as_path() == out && !from.is_empty() => {}
            Err(e) => return Err(e),
        }
    }
    let Some((_, first_path, first)) = found.first() else {
        return Err(FitError::Option(format!(
            "{}: no shard manifests found",
            out.display()
        )));
    };
    let (n, total, options) = (first.count, first.total, first.options.clone());
    let mut by_index: Vec<Option<usize>> = vec![None; n];
    for (i, (_, p, m)) in found.iter().enumerate() {
        if m.count != n || m.total != total || m.options != options {
            return Err(FitError::Option(format!(
                "{} (shard {}/{} of {} inputs, options {}) does not belong to the same batch as \
                 {} (N = {n}, {total} inputs, options {options})",
                p.display(),
                m.index,
                m.count,
                m.total,
                m.options,
                first_path.display()
            )));
        }
        match by_index[m.index] {
            Some(j) if found[j].2 != *m => {
                return Err(FitError::Option(format!(
                    "shard {}/{n} is in both {} and {}, with different results",
                    m.index,
                    found[j].1.display(),
                    p.display()
                )))
            }
            Some(_) => {}
            None => by_index[m.index] = Some(i),
        }
    }
    let missing: Vec<String> = by_index
        .iter()
        .enumerate()
        .filter(|(_, f)| f.is_none())
        .map(|(k, _)| k.to_string())
        .collect();
    if !missing.is_empty() {
        return Err(FitError::Option(format!(
            "{} of {n} shards are missing or unfinished (no manifest): {}; run them with \
             --shard K/{n} before merging",
            missing.len(),
            missing.join(", ")
        )));
    }
    // Every shard's fits are read and checked before anything is written: a damaged one (empty,
    // cut short, not a fit) refuses the merge and names the file.
    let mut copies: Vec<(PathBuf, Vec<u8>)> = Vec::new();
    let mut placed: Vec<(usize, SummaryRow)> = Vec::with_capacity(total);
    for (dir, _, m) in by_index.iter().flatten().map(|&i| &found[i]) {
        for (&pos, row) in m.positions.iter().zip(&m.rows) {
            let name = format!("{}.json", row.name);
            let src = dir.join(&name);
            let bytes = lustre_brdf::error::read_file(&src)?;
            check_fit_file(&src, &bytes)?;
            if dir.as_path() != out {
                copies.push((out.join(&name), bytes));
            }
            placed.push((pos, row.clone()));
        }
    }
    for (path, bytes) in &copies {
        lustre_brdf::error::write_atomic(path, bytes)?;
    }
    placed.sort_by_key(|(p, _)| *p);
    let mut rows: Vec<SummaryRow> = placed.into_iter().map(|(_, r)| r).collect();
    let batch = rows.len();
    rows.extend(earlier_rows(out, &rows));
    let summary_path = out.join(SUMMARY_FILE);
    write_summary(&summary_path, &rows)?;
    Ok(BatchSummary {
        rows,
        summary_path,
        batch,
    })
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{options, Mock};
    use super::*;
    use crate::batch::{run, BatchOptions, FitOptions, ModelChoice};

    /// Every file of a batch folder (JSON and CSV) with the wall times zeroed: the only field
    /// two runs of the same batch may differ in.
    fn without_times(dir: &Path) -> std::collections::BTreeMap<String, String> {
        let mut files = std::collections::BTreeMap::new();
        for e in std::fs::read_dir(dir).expect("dir").flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.is_dir() {
                continue;
            }
            let text = std::fs::read_to_string(&p).expect("text");
            let text = if name.ends_with(".json") {
                let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
                v["fit"]["time_s"] = 0.into();
                v.to_string()
            } else {
                let mut r = csv::Reader::from_reader(text.as_bytes());
                let h = r.headers().expect("headers").clone();
                let t = h.iter().position(|c| c == "time_s").expect("time column");
                let rows: Vec<String> = r
                    .records()
                    .map(|rec| {
                        let rec = rec.expect("row");
                        rec.iter()
                            .enumerate()
                            .map(|(i, c)| if i == t { "0" } else { c })
                            .collect::<Vec<_>>()
                            .join(",")
                    })
                    .collect();
                format!("{h:?}\n{}", rows.join("\n"))
            };
            files.insert(name, text);
        }
        files
    }

    #[test]
    fn merged_shards_equal_the_unsharded_batch() {
        let inputs: Vec<String> = ["a.gonio", "many", "bad.gonio", "c.gonio", "d/a.gonio"]
            .map(String::from)
            .to_vec();
        let dir = tempfile::tempdir().expect("dir");
        let whole = dir.path().join("whole");
        run(&inputs, &options(&whole), &Mock::default()).expect("batch");
        // Three shards sharing one folder (a shared file system), merged in place.
        let shared = dir.path().join("shared");
        let mut fitted = 0;
        for k in 0..3 {
            let opts = BatchOptions {
                shard: Some((k, 3)),
                ..options(&shared)
            };
            let s = run(&inputs, &opts, &Mock::default()).expect("shard");
            assert!(s
                .summary_path
                .ends_with(format!("shards/fit-{k}-of-3.json")));
            fitted += s.batch;
            if k < 2 {
                assert!(
                    !shared.join(SUMMARY_FILE).exists(),
                    "shards write no summary"
                );
                let e = merge(&shared, &[]).unwrap_err().to_string();
                assert!(e.contains("missing") && e.contains('2'), "{e}");
            }
        }
        assert_eq!(
            fitted, 6,
            "each of the 6 expanded inputs in exactly one shard"
        );
        let m = merge(&shared, &[]).expect("merge");
        assert_eq!((m.batch, m.failed()), (6, 1));
        assert_eq!(without_times(&shared), without_times(&whole));
        // Merging again (an interrupted merge rerun) changes nothing.
        merge(&shared, &[]).expect("merge again");
        assert_eq!(without_times(&shared), without_times(&whole));
        // Shards in separate folders, merged into a fourth.
        let parts: Vec<PathBuf> = (0..3)
            .map(|k| dir.path().join(format!("part{k}")))
            .collect();
        for (k, part) in parts.iter().enumerate() {
            let opts = BatchOptions {
                shard: Some((k, 3)),
                ..options(part)
            };
            run(&inputs, &opts, &Mock::default()).expect("shard");
        }
        let merged = dir.path().join("merged");
        merge(&merged, &parts).expect("merge");
        assert_eq!(without_times(&merged), without_times(&whole));
        // A shard of another batch (other options) is refused, naming it.
        let other = BatchOptions {
            shard: Some((1, 3)),
            fit: FitOptions {
                lobes: 2,
                ..FitOptions::new(ModelChoice::Kurt)
            },
            ..options(&dir.path().join("other"))
        };
        run(&inputs, &other, &Mock::default()).expect("shard");
        let e = merge(
            &dir.path().join("m2"),
            &[parts[0].clone(), dir.path().join("other"), parts[2].clone()],
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("fit-1-of-3.json") && e.contains("same batch"),
            "{e}"
        );
        // A corrupt manifest is named; bad selections are refused before fitting.
        std::fs::write(shard_manifest_path(&parts[1], 1, 3), "{").expect("write");
        let e = merge(&merged, &parts).unwrap_err().to_string();
        assert!(e.contains("fit-1-of-3.json"), "{e}");
        for (k, n) in [(3, 3), (0, 0)] {
            let opts = BatchOptions {
                shard: Some((k, n)),
                ..options(&dir.path().join("bad"))
            };
            assert!(run(&inputs, &opts, &Mock::default()).is_err());
        }
    }
}
