//! The batch runner behind `lustre fit`: fits a list of inputs in a rayon pool, writes one
//! material JSON per input and a CSV summary, and resumes an interrupted batch.
//!
//! Per input the runner writes `OUT/<name>.json` (atomically), where `<name>` is
//! [`output_name`] of the input (numbered `-2`, `-3`, ... when two inputs share a name):
//!
//! - a fit that produced a model (status `converged` or `not-converged`) gives a
//!   [`lustre_brdf::material::MaterialFile`] with its [`FitRecord`];
//! - a failed input (unreadable file, all-zero or NaN data, a fit error, even a panic inside the
//!   fitter) gives a [`FailureFile`] (schema [`FAILURE_SCHEMA`]) with the status and message, so
//!   the renderer refuses it with a clear message and the batch goes on.
//!
//! `OUT/summary.csv` (atomic) has one row per material JSON in the folder ([`SummaryRow`]): the
//! inputs of this batch, in input order, then every other `*.json` of an earlier batch (marked
//! `resumed`, rebuilt from its file), so the summary never loses a fit that is still there.
//!
//! **Resume**: unless `force` is set, an input whose JSON exists, parses as a material, records
//! the same input, the same model and the same options, has a status other than a failure and
//! is newer than the input's data file is not fitted again; its row is rebuilt from the file. A
//! corrupted, failed or outdated output is fitted again.
//!
//! **Other options**: an existing valid fit of the same input with another model or other
//! options is never overwritten silently: the batch refuses to start ([`FitError::Option`]
//! naming the files) unless `force` is set; `lustre fit --suffix` writes to other names instead.
//!
//! **Shards** (several machines, one batch): with [`BatchOptions::shard`] = `(K, N)` a run fits
//! only the inputs at positions `p % N == K` of the expanded input list (the names are those of
//! the whole list, so they do not depend on the shard), writes their JSON as usual, and instead
//! of `summary.csv` (which concurrent shards sharing a folder would overwrite) the shard's rows
//! to `OUT/shards/fit-K-of-N.json` ([`ShardManifest`], atomic, last: its presence means the shard
//! is complete). [`merge`] checks that all `N` manifests are there and agree, copies the JSON of
//! shards written to other folders, and writes `summary.csv` with the rows in input order: the
//! same files, byte for byte apart from each fit's wall time, as one unsharded run.
//!
//! Every fit records its options ([`FitOptions::to_json`]) in its JSON; a failure record keeps
//! the best parameters the fit reached, when it reached any ([`FailureFile::model`]).
//!
//! The fitting itself is behind the [`Fitter`] trait, so the machinery runs (and is tested)
//! with any fitter; [`MeasuredFitter`] is the real one.
//!
//! The code, one concern per file: `options` (the model choice and the fit options, checked
//! before any input is read), `dispatch` ([`MeasuredFitter`]: the model choice to the fit that
//! runs it), `runner` (the job loop and its progress display), `resume` (what the outputs
//! already in the folder allow to skip or forbid to overwrite), `summary` (`summary.csv`) and
//! `shards` (shard manifests and [`merge`]). This file holds the types they share.
//!
//! [`FitError::Option`]: crate::FitError::Option

mod dispatch;
mod options;
mod resume;
mod runner;
mod shards;
mod summary;
#[cfg(test)]
mod test_support;

pub use crate::metrics::Metric;
pub use dispatch::MeasuredFitter;
pub use options::{check_options, kurt_options, FitOptions, ModelChoice};
pub use runner::{output_name, run};
pub use shards::{check_shard, merge, shard_manifest_path, ShardManifest, SHARD_SCHEMA};
pub use summary::{write_summary, BatchSummary, SummaryRow, SUMMARY_FILE};

use crate::{FitStatus, Result};
use lustre_brdf::material::{FitErrors, FitRecord, MaterialModel};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// The schema name of the JSON written for a failed input.
pub const FAILURE_SCHEMA: &str = "lustre-fit-failure";

/// Everything a batch needs besides its inputs and its fitter.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// What to fit.
    pub fit: FitOptions,
    /// Worker threads (at least 1).
    pub jobs: usize,
    /// Fit every input again, even when a valid output exists.
    pub force: bool,
    /// The output folder (created if missing).
    pub out: PathBuf,
    /// Draw a progress bar on stderr (only shown on a terminal).
    pub progress: bool,
    /// Appended to every output name (`NAME-SUFFIX.json`), to keep fits with other options
    /// beside the earlier ones; empty for none.
    pub suffix: String,
    /// Fit only this shard of the inputs: `(index, count)`, inputs at positions `p` (after
    /// expansion) with `p % count == index`; `None` fits them all. See [`merge`].
    pub shard: Option<(usize, usize)>,
}

/// What a successful fit returns to the batch.
#[derive(Clone, Debug, PartialEq)]
pub struct Fitted {
    /// The fitted model.
    pub model: MaterialModel,
    /// How the optimizer ended (`Converged` or `NotConverged`; a failure status makes the input
    /// count as failed but its model is still written).
    pub status: FitStatus,
    /// A message in words (may be empty).
    pub message: String,
    /// Error metrics of the model against the data.
    pub errors: FitErrors,
    /// Albedo of the data at normal incidence.
    pub albedo_data: [f64; 3],
    /// Albedo of the model at normal incidence.
    pub albedo_model: [f64; 3],
}

impl Fitted {
    /// The record of this fit of `source` with `settings`, `time_s` seconds in all.
    pub fn record(&self, source: &str, options: &FitOptions, time_s: f64) -> FitRecord {
        FitRecord {
            source: source.to_string(),
            errors: Some(self.errors),
            albedo_data: Some(self.albedo_data),
            albedo_model: Some(self.albedo_model),
            time_s,
            status: status_str(self.status).into(),
            message: self.message.clone(),
            options: options.to_json(),
            input_hash: None,
        }
    }
}

/// The fitting behind a batch.
pub trait Fitter: Sync {
    /// Expands one command-line input into the inputs to fit (e.g. `nbrdf:FILE#*`).
    fn expand(&self, input: &str) -> Result<Vec<String>>;
    /// Fits one input; `stage` is told what the fit is doing (for the progress display).
    fn fit(&self, input: &str, options: &FitOptions, stage: &dyn Fn(&str)) -> Result<Fitted>;
}

/// The JSON written for a failed input: no model, only the record of what went wrong.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FailureFile {
    /// Always [`FAILURE_SCHEMA`].
    pub schema: String,
    /// Always 1.
    pub version: u32,
    /// The output name.
    pub name: String,
    /// The status, message and options.
    pub fit: FitRecord,
    /// The best parameters the fit reached before it failed, as the material JSON's `model`
    /// would hold them (absent when it reached none; a non-finite number reads `null`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<serde_json::Value>,
}

/// Whether a status counts as a failed input.
pub fn is_failure(s: FitStatus) -> bool {
    matches!(s, FitStatus::InvalidData | FitStatus::Error)
}

/// The status as its JSON/CSV word (`converged`, `not-converged`, `invalid-data`, `error`).
pub fn status_str(s: FitStatus) -> &'static str {
    match s {
        FitStatus::Converged => "converged",
        FitStatus::NotConverged => "not-converged",
        FitStatus::InvalidData => "invalid-data",
        FitStatus::Error => "error",
    }
}

/// The status of a word written by [`status_str`].
pub fn parse_status(s: &str) -> Option<FitStatus> {
    [
        FitStatus::Converged,
        FitStatus::NotConverged,
        FitStatus::InvalidData,
        FitStatus::Error,
    ]
    .into_iter()
    .find(|&x| status_str(x) == s)
}
