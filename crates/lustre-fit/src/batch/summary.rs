//! The CSV summary, `summary.csv`: one [`SummaryRow`] per material JSON in the output folder,
//! [`BatchSummary`] (the rows of a batch and its counts) and the atomic writer.

use super::is_failure;
use crate::{FitError, FitStatus, Result};
use lustre_brdf::material::FitRecord;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The file name of the CSV summary inside the output folder.
pub const SUMMARY_FILE: &str = "summary.csv";

/// One row of the CSV summary (empty cells where a failed input has no numbers).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SummaryRow {
    /// Output name (the JSON is `<name>.json`).
    pub name: String,
    /// The input as given (after expansion).
    pub input: String,
    /// The model (`sgd`, `kurt`, `beckmann`, `ggx`).
    pub model: String,
    /// How the fit ended.
    pub status: FitStatus,
    /// Ngan's normalized L2, red.
    pub ngan_l2_r: Option<f64>,
    /// Ngan's normalized L2, green.
    pub ngan_l2_g: Option<f64>,
    /// Ngan's normalized L2, blue.
    pub ngan_l2_b: Option<f64>,
    /// L1 of Eq. 3.7, red.
    pub l1_r: Option<f64>,
    /// L1 of Eq. 3.7, green.
    pub l1_g: Option<f64>,
    /// L1 of Eq. 3.7, blue.
    pub l1_b: Option<f64>,
    /// Data albedo at normal incidence, red.
    pub albedo_data_r: Option<f64>,
    /// Data albedo at normal incidence, green.
    pub albedo_data_g: Option<f64>,
    /// Data albedo at normal incidence, blue.
    pub albedo_data_b: Option<f64>,
    /// Model albedo at normal incidence, red.
    pub albedo_model_r: Option<f64>,
    /// Model albedo at normal incidence, green.
    pub albedo_model_g: Option<f64>,
    /// Model albedo at normal incidence, blue.
    pub albedo_model_b: Option<f64>,
    /// Fit wall time in seconds (of the run that produced the JSON).
    pub time_s: f64,
    /// Whether the row was taken from an existing JSON instead of fitting again.
    pub resumed: bool,
    /// The message (empty when there is nothing to say).
    pub message: String,
}

impl SummaryRow {
    /// Whether the input failed (status `invalid-data` or `error`).
    pub fn failed(&self) -> bool {
        is_failure(self.status)
    }

    pub(super) fn new(
        name: &str,
        record: &FitRecord,
        model: &str,
        status: FitStatus,
        resumed: bool,
    ) -> Self {
        let e = record.errors;
        let pick = |a: Option<[f64; 3]>, i: usize| a.map(|a| a[i]);
        let (nl, l1) = (e.map(|e| e.ngan_l2), e.map(|e| e.l1));
        SummaryRow {
            name: name.to_string(),
            input: record.source.clone(),
            model: model.to_string(),
            status,
            ngan_l2_r: pick(nl, 0),
            ngan_l2_g: pick(nl, 1),
            ngan_l2_b: pick(nl, 2),
            l1_r: pick(l1, 0),
            l1_g: pick(l1, 1),
            l1_b: pick(l1, 2),
            albedo_data_r: pick(record.albedo_data, 0),
            albedo_data_g: pick(record.albedo_data, 1),
            albedo_data_b: pick(record.albedo_data, 2),
            albedo_model_r: pick(record.albedo_model, 0),
            albedo_model_g: pick(record.albedo_model, 1),
            albedo_model_b: pick(record.albedo_model, 2),
            time_s: record.time_s,
            resumed,
            message: record.message.clone(),
        }
    }
}

/// The outcome of a batch: one row per input, in input order, then the rows of earlier fits in
/// the same folder.
#[derive(Clone, Debug, PartialEq)]
pub struct BatchSummary {
    /// The rows, as in `summary.csv`: the batch's `batch` inputs first.
    pub rows: Vec<SummaryRow>,
    /// The CSV file written.
    pub summary_path: PathBuf,
    /// How many of the rows are this batch's inputs.
    pub batch: usize,
}

impl BatchSummary {
    /// This batch's rows.
    pub fn batch_rows(&self) -> &[SummaryRow] {
        &self.rows[..self.batch.min(self.rows.len())]
    }

    /// The rows of earlier batches' fits in the folder.
    pub fn earlier_rows(&self) -> &[SummaryRow] {
        &self.rows[self.batch.min(self.rows.len())..]
    }

    /// How many of this batch's inputs failed.
    pub fn failed(&self) -> usize {
        self.batch_rows().iter().filter(|r| r.failed()).count()
    }

    /// How many of this batch's inputs were taken over from an earlier run.
    pub fn resumed(&self) -> usize {
        self.batch_rows().iter().filter(|r| r.resumed).count()
    }

    /// How many of this batch's inputs were fitted now and gave a model (converged or not).
    pub fn fitted(&self) -> usize {
        self.batch_rows()
            .iter()
            .filter(|r| !r.resumed && !r.failed())
            .count()
    }
}

/// Writes the CSV summary atomically.
pub fn write_summary(path: &Path, rows: &[SummaryRow]) -> Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |e: csv::Error| FitError::Option(format!("{}: {e}", path.display()));
    for r in rows {
        w.serialize(r).map_err(csv_err)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| FitError::Option(format!("{}: {e}", path.display())))?;
    lustre_brdf::error::write_atomic(path, &bytes)?;
    Ok(())
}
