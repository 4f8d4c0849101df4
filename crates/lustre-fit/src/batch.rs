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
//! Every fit records its options ([`FitSettings::to_json`]) in its JSON; a failure record keeps
//! the best parameters the fit reached, when it reached any ([`FailureFile::model`]).
//!
//! The fitting itself is behind the [`Fitter`] trait, so the machinery runs (and is tested)
//! with any fitter; [`MeasuredFitter`] is the real one.

use crate::{ct, data, kurt, metrics, FitError, FitStatus, Result};
use lustre_brdf::material::{
    self, CtChannelParams, CtDistribution, FitErrors, FitRecord, MaterialFile, MaterialModel,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The schema name of the JSON written for a failed input.
pub const FAILURE_SCHEMA: &str = "lustre-fit-failure";
/// The file name of the CSV summary inside the output folder.
pub const SUMMARY_FILE: &str = "summary.csv";

/// The model a batch fits (`lustre fit --model`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelChoice {
    /// Cook-Torrance with the SGD distribution (004 §V.4).
    Sgd,
    /// Kurt et al. lobes (000 §3.4.1).
    Kurt,
    /// Cook-Torrance with the Beckmann distribution.
    Beckmann,
    /// Cook-Torrance with the GGX distribution.
    Ggx,
}

impl ModelChoice {
    /// The lower-case name (`sgd`, `kurt`, `beckmann`, `ggx`), as [`MaterialModel::kind`] gives it.
    pub fn as_str(self) -> &'static str {
        match self {
            ModelChoice::Sgd => "sgd",
            ModelChoice::Kurt => "kurt",
            ModelChoice::Beckmann => "beckmann",
            ModelChoice::Ggx => "ggx",
        }
    }
}

pub use crate::metrics::Metric;

impl Metric {
    /// The metric's value (mean of the channels) in `e`.
    pub fn of(self, e: &FitErrors) -> f64 {
        let v = match self {
            Metric::NganL2 => e.ngan_l2,
            Metric::L1 => e.l1,
        };
        v.iter().sum::<f64>() / 3.0
    }
}

/// The options that determine a fit's result; recorded in the JSON and compared on resume.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitSettings {
    /// The model.
    pub model: ModelChoice,
    /// Kurt: number of reflection lobes.
    pub lobes: usize,
    /// Kurt: number of transmission lobes.
    pub transmission_lobes: usize,
    /// Kurt: parameters held at a value (`--fix NAME=VALUE`).
    pub fixed: Vec<(String, f64)>,
    /// Kurt: parameter search ranges (`--range NAME=LO:HI`).
    pub ranges: Vec<(String, f64, f64)>,
    /// Refine the fit (CT: over the full data; Kurt: the final polish).
    pub refine: bool,
    /// Kurt: the metric the fit is judged by: each fit keeps the best on it of its candidates
    /// ([`kurt::fit_judged`]), and fits with 1..=`lobes` lobes are compared on it (the reported
    /// fit is the best of them, so more lobes never report a worse fit).
    pub metric: Metric,
    /// Refuse MERL tables with unmeasured bins instead of masking them.
    pub strict: bool,
}

impl FitSettings {
    /// Default settings for `model`: one lobe, no transmission lobe, nothing fixed, refine,
    /// Ngan's L2, unmeasured bins masked.
    pub fn new(model: ModelChoice) -> Self {
        FitSettings {
            model,
            lobes: 1,
            transmission_lobes: 0,
            fixed: Vec::new(),
            ranges: Vec::new(),
            refine: true,
            metric: Metric::NganL2,
            strict: false,
        }
    }

    /// The settings as the JSON object stored in [`FitRecord::options`]: the model and refine,
    /// plus the lobe counts, fixed parameters and ranges for Kurt (the only model they act on).
    pub fn to_json(&self) -> serde_json::Value {
        let mut v = serde_json::json!({ "model": self.model, "refine": self.refine });
        if self.strict {
            v["strict"] = true.into();
        }
        if self.model == ModelChoice::Kurt {
            v["metric"] = self.metric.as_str().into();
            v["lobes"] = self.lobes.into();
            v["transmission_lobes"] = self.transmission_lobes.into();
            v["fixed"] = serde_json::json!(self.fixed);
            v["ranges"] = serde_json::json!(self.ranges);
        }
        v
    }
}

/// Everything a batch needs besides its inputs and its fitter.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// What to fit.
    pub settings: FitSettings,
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
    pub fn record(&self, source: &str, settings: &FitSettings, time_s: f64) -> FitRecord {
        FitRecord {
            source: source.to_string(),
            errors: Some(self.errors),
            albedo_data: Some(self.albedo_data),
            albedo_model: Some(self.albedo_model),
            time_s,
            status: status_str(self.status).into(),
            message: self.message.clone(),
            options: settings.to_json(),
        }
    }
}

/// The fitting behind a batch.
pub trait Fitter: Sync {
    /// Expands one command-line input into the inputs to fit (e.g. `nbrdf:FILE#*`).
    fn expand(&self, input: &str) -> Result<Vec<String>>;
    /// Fits one input; `stage` is told what the fit is doing (for the progress display).
    fn fit(&self, input: &str, settings: &FitSettings, stage: &dyn Fn(&str)) -> Result<Fitted>;
}

/// The real fitter: [`data::load`] (with its value checks), then [`ct::fit`] or
/// [`kurt::fit`], then [`metrics::evaluate`] of the fitted model (built from the material JSON
/// model, as the renderer will build it) against the data.
#[derive(Clone, Copy, Debug, Default)]
pub struct MeasuredFitter;

impl Fitter for MeasuredFitter {
    fn expand(&self, input: &str) -> Result<Vec<String>> {
        data::expand_inputs(input)
    }

    fn fit(&self, input: &str, s: &FitSettings, stage: &dyn Fn(&str)) -> Result<Fitted> {
        stage("reading the data");
        let data = data::load_with(input, &data::LoadOptions { strict: s.strict })?;
        let mask = data.coverage.as_ref();
        let mut notes = Vec::new();
        let mask_note = data.mask_note();
        if !mask_note.is_empty() {
            notes.push(mask_note);
        }
        let evaluate = |model: &MaterialModel| -> Result<metrics::ErrorReport> {
            let bsdf = model.to_bsdf(&data.name)?;
            Ok(metrics::evaluate_masked(
                data.bsdf.as_ref(),
                bsdf.as_ref(),
                data.transmission,
                mask,
            ))
        };
        let (model, status, report) = match s.model {
            ModelChoice::Kurt => {
                // Fits with 1..=L lobes (and the transmission lobes); the reported one is the
                // best on the user's metric, so more lobes never report a worse fit.
                let mut best: Option<(MaterialModel, FitStatus, metrics::ErrorReport, usize)> =
                    None;
                // The metric's data side, evaluated once for every lobe count's candidates.
                let judge = metrics::MetricJudge::new(
                    s.metric,
                    data.bsdf.as_ref(),
                    data.transmission,
                    mask,
                );
                let counts: Vec<usize> = if s.lobes <= 1 {
                    vec![s.lobes]
                } else {
                    (1..=s.lobes).collect()
                };
                for &k in &counts {
                    stage(&format!("Kurt search and polish, {k} of {} lobes", s.lobes));
                    let opts = kurt::KurtOptions {
                        lobes: k,
                        ..kurt_options(s)
                    };
                    let f = kurt::fit_judged(
                        data.bsdf.as_ref(),
                        data.transmission,
                        &opts,
                        mask,
                        Some(&judge),
                    )?;
                    let mut m = f.model.clone();
                    // Pad to L lobes with ks = 0 so that the model has the requested shape.
                    while m.reflection.len() < s.lobes {
                        let mut l = *m.reflection.last().ok_or_else(|| {
                            FitError::Option("a Kurt fit returned no reflection lobe".into())
                        })?;
                        l.ks = lustre_brdf::Rgb::ZERO;
                        m.reflection.push(l);
                    }
                    let model = MaterialModel::from_kurt(&m);
                    stage(&format!("error metrics of the {k}-lobe fit"));
                    let r = evaluate(&model)?;
                    let value = s.metric.of(&FitErrors {
                        ngan_l2: r.ngan_l2,
                        l1: r.l1,
                    });
                    notes.push(format!(
                        "{k} lobes: {} {value:.6}, Eq. 3.7 objective {:.6}, {} evaluations, {}",
                        s.metric.as_str(),
                        f.objective,
                        f.evaluations,
                        f.note
                    ));
                    let better = best.as_ref().is_none_or(|b| {
                        value
                            < s.metric.of(&FitErrors {
                                ngan_l2: b.2.ngan_l2,
                                l1: b.2.l1,
                            })
                    });
                    if better {
                        best = Some((model, f.status, r, k));
                    }
                }
                let (model, status, r, k) =
                    best.ok_or_else(|| FitError::Option("no Kurt fit was run (0 lobes)".into()))?;
                if counts.len() > 1 {
                    notes.push(format!(
                        "reported: the {k}-lobe fit (best {} of 1..={} lobes)",
                        s.metric.as_str(),
                        s.lobes
                    ));
                }
                (model, status, r)
            }
            m => {
                let (dist, mdist) = match m {
                    ModelChoice::Sgd => (ct::Distribution::Sgd, CtDistribution::Sgd),
                    ModelChoice::Beckmann => (ct::Distribution::Beckmann, CtDistribution::Beckmann),
                    _ => (ct::Distribution::Ggx, CtDistribution::Ggx),
                };
                let opts = ct::CtOptions {
                    refine: s.refine,
                    ..ct::CtOptions::default()
                };
                stage("two-slice fit and refinement");
                let f = ct::fit_masked(data.bsdf.as_ref(), dist, &opts, mask)?;
                let channels = std::array::from_fn(|i| {
                    let c = &f.channels[i];
                    CtChannelParams {
                        rho_d: c.rho_d,
                        rho_s: c.rho_s,
                        alpha: c.alpha,
                        p: c.p,
                        kap: c.kap,
                        f0: c.f0,
                        f1: c.f1,
                        g1: c.g1,
                    }
                });
                notes.push(format!("{} iterations", f.iterations));
                notes.extend(f.notes.iter().cloned());
                let model = MaterialModel::cook_torrance(mdist, channels)?;
                stage("error metrics");
                let r = evaluate(&model)?;
                (model, f.status, r)
            }
        };
        Ok(Fitted {
            model,
            status,
            message: notes.join("; "),
            errors: FitErrors {
                ngan_l2: report.ngan_l2,
                l1: report.l1,
            },
            albedo_data: report.albedo_data,
            albedo_model: report.albedo_model,
        })
    }
}

/// The Kurt options of `s` (search grid and levels at their defaults).
pub fn kurt_options(s: &FitSettings) -> kurt::KurtOptions {
    kurt::KurtOptions {
        lobes: s.lobes,
        transmission_lobes: s.transmission_lobes,
        fixed: s.fixed.clone(),
        ranges: s.ranges.clone(),
        polish: s.refine,
        ..kurt::KurtOptions::default()
    }
}

/// Checks what can be checked before any input is read: for Kurt, that every `--fix` and
/// `--range` name is one of [`kurt::parameter_names`] and that there is a lobe to fit; for
/// Cook-Torrance, that no Kurt-only option is set.
pub fn check_settings(s: &FitSettings) -> Result<()> {
    if s.model == ModelChoice::Kurt && s.lobes == 0 && s.transmission_lobes == 0 {
        return Err(FitError::Option(
            "--lobes 0 without transmission lobes fits no lobe (only kd, a diffuse model): \
             use --lobes 1 or more"
                .into(),
        ));
    }
    if s.model != ModelChoice::Kurt {
        if !s.fixed.is_empty() || !s.ranges.is_empty() {
            return Err(FitError::Option(format!(
                "fixed parameters and ranges apply to the Kurt model only, not {}",
                s.model.as_str()
            )));
        }
        return Ok(());
    }
    let names = kurt::parameter_names(&kurt_options(s));
    let given = s
        .fixed
        .iter()
        .map(|f| f.0.as_str())
        .chain(s.ranges.iter().map(|r| r.0.as_str()));
    for n in given {
        if !names.iter().any(|k| k == n) {
            return Err(FitError::Option(format!(
                "unknown Kurt parameter {n:?} for {} reflection and {} transmission lobes \
                 (known: {})",
                s.lobes,
                s.transmission_lobes,
                names.join(", ")
            )));
        }
    }
    Ok(())
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

    fn new(name: &str, record: &FitRecord, model: &str, status: FitStatus, resumed: bool) -> Self {
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
struct Job {
    input: String,
    name: String,
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
    if let Some((k, n)) = opts.shard {
        check_shard(k, n)?;
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
                other_options(&path, j, &opts.settings)
                    .map(|old| format!("{} ({old})", path.display()))
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
            options: opts.settings.to_json(),
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
    /// The fit options ([`FitSettings::to_json`]).
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

fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
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
            let bytes = std::fs::read(&p).map_err(|e| lustre_brdf::Error::io(&p, e))?;
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
    let mut placed: Vec<(usize, SummaryRow)> = Vec::with_capacity(total);
    for (dir, _, m) in by_index.iter().flatten().map(|&i| &found[i]) {
        for (&pos, row) in m.positions.iter().zip(&m.rows) {
            if dir.as_path() != out {
                let name = format!("{}.json", row.name);
                let src = dir.join(&name);
                let bytes = std::fs::read(&src).map_err(|e| lustre_brdf::Error::io(&src, e))?;
                lustre_brdf::error::write_atomic(&out.join(&name), &bytes)?;
            }
            placed.push((pos, row.clone()));
        }
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

/// A description of the existing fit at `path` when it is a valid fit of the same input with
/// another model or other options (`None` otherwise: no file, a failure, a corrupted file, a fit
/// of another input, or the same options).
fn other_options(path: &Path, job: &Job, settings: &FitSettings) -> Option<String> {
    let m = material::read(path).ok()?;
    let f = m.fit.as_ref()?;
    let status = parse_status(&f.status)?;
    let differs = m.model.kind() != settings.model.as_str() || f.options != settings.to_json();
    (f.source == job.input && !is_failure(status) && differs)
        .then(|| format!("{}, options {}", m.model.kind(), f.options))
}

/// The rows of the `*.json` files in `out` that are not among `rows` (fits of earlier batches),
/// sorted by name: materials with their numbers, failure records with their status.
fn earlier_rows(out: &Path, rows: &[SummaryRow]) -> Vec<SummaryRow> {
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

/// The row of an existing output that can be reused, if any (see the module notes).
fn reusable(path: &Path, job: &Job, settings: &FitSettings) -> Option<SummaryRow> {
    let m = material::read(path).ok()?;
    let f = m.fit.as_ref()?;
    let status = parse_status(&f.status)?;
    let same = f.source == job.input
        && m.model.kind() == settings.model.as_str()
        && f.options == settings.to_json()
        && !is_failure(status)
        && !input_is_newer(&job.input, path);
    same.then(|| SummaryRow::new(&job.name, f, m.model.kind(), status, true))
}

/// Whether the input's data file (the path of a file input, the network file of
/// `nbrdf:FILE#NAME`) was modified after `output` was written.
fn input_is_newer(input: &str, output: &Path) -> bool {
    let spec = input.strip_prefix("nbrdf:").unwrap_or(input);
    let file = spec.rsplit_once('#').map_or(spec, |(f, _)| f);
    let mtime = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    match (mtime(Path::new(file)), mtime(output)) {
        (Some(i), Some(o)) => i > o,
        _ => false,
    }
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
    let settings = &opts.settings;
    if !opts.force {
        if let Some(row) = reusable(&path, job, settings) {
            return row;
        }
    }
    let t0 = Instant::now();
    let result = match &job.expand_error {
        Some(e) => Err((error_status(e), e.to_string())),
        None => {
            match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                fitter.fit(&job.input, settings, stage)
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
    let model = settings.model.as_str();
    let mut record = FitRecord {
        source: job.input.clone(),
        errors: None,
        albedo_data: None,
        albedo_model: None,
        time_s,
        status: String::new(),
        message: String::new(),
        options: settings.to_json(),
    };
    let mut kept = None;
    let written = match result {
        Ok(f) => {
            record = f.record(&job.input, settings, time_s);
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
    use super::*;
    use lustre_brdf::material::LobeParams;
    use lustre_brdf::Bsdf;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A fitter by input name: `bad*` is unusable data, `panic*` panics, `nan*` returns a
    /// model with a NaN parameter, `many` expands into two inputs, `noexpand` cannot be
    /// expanded; anything else fits a fixed Kurt model. Counts its fits.
    #[derive(Default)]
    struct Mock {
        fits: AtomicUsize,
    }

    fn kurt_model(mx: f64) -> MaterialModel {
        MaterialModel::Kurt {
            kd: [0.1, 0.2, 0.3],
            reflection: vec![LobeParams {
                ks: [0.5; 3],
                mx,
                my: 0.2,
                r0: 0.9,
                alpha: 0.0,
            }],
            transmission: vec![],
        }
    }

    impl Fitter for Mock {
        fn expand(&self, input: &str) -> Result<Vec<String>> {
            match input {
                "many" => Ok(vec![
                    "nbrdf:set.json#red".into(),
                    "nbrdf:set.json#blue".into(),
                ]),
                "noexpand" => Err(FitError::Data {
                    input: input.into(),
                    problem: "no such network file".into(),
                }),
                _ => Ok(vec![input.to_string()]),
            }
        }

        fn fit(&self, input: &str, settings: &FitSettings, stage: &dyn Fn(&str)) -> Result<Fitted> {
            stage("mock fit");
            self.fits.fetch_add(1, Ordering::SeqCst);
            let name = Path::new(input)
                .file_name()
                .map_or(input.into(), |n| n.to_string_lossy());
            if name.starts_with("bad") {
                return Err(FitError::Data {
                    input: input.into(),
                    problem: "all samples are zero".into(),
                });
            }
            if name.starts_with("panic") {
                panic!("index out of bounds in the mock");
            }
            let mx = if name.starts_with("nan") {
                f64::NAN
            } else {
                0.1
            };
            Ok(Fitted {
                model: kurt_model(mx),
                status: if settings.refine {
                    FitStatus::Converged
                } else {
                    FitStatus::NotConverged
                },
                message: String::new(),
                errors: FitErrors {
                    ngan_l2: [0.01, 0.02, 0.03],
                    l1: [0.1, 0.2, 0.3],
                },
                albedo_data: [0.5; 3],
                albedo_model: [0.45; 3],
            })
        }
    }

    fn options(out: &Path) -> BatchOptions {
        BatchOptions {
            settings: FitSettings::new(ModelChoice::Kurt),
            jobs: 2,
            force: false,
            out: out.to_path_buf(),
            progress: false,
            suffix: String::new(),
            shard: None,
        }
    }

    fn mtime(p: &Path) -> std::time::SystemTime {
        std::fs::metadata(p)
            .and_then(|m| m.modified())
            .expect("mtime")
    }

    fn csv_rows(p: &Path) -> Vec<csv::StringRecord> {
        let mut r = csv::Reader::from_path(p).expect("csv");
        let h = r.headers().expect("headers").clone();
        assert_eq!(&h[0], "name");
        assert_eq!(&h[3], "status");
        assert_eq!(&h[4], "ngan_l2_r");
        assert_eq!(h.len(), 19);
        r.records().map(|x| x.expect("record")).collect()
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
            settings: FitSettings {
                lobes: 2,
                ..FitSettings::new(ModelChoice::Kurt)
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
        let ggx = |lobes| FitSettings {
            lobes,
            ..FitSettings::new(ModelChoice::Ggx)
        };
        assert_eq!(ggx(1).to_json(), ggx(3).to_json());
        assert_ne!(
            FitSettings::new(ModelChoice::Kurt).to_json(),
            other.settings.to_json()
        );
    }

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
            settings: FitSettings {
                refine: false,
                ..FitSettings::new(ModelChoice::Kurt)
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
        let later = mtime(&out.join("t.json")) + std::time::Duration::from_secs(5);
        std::fs::File::options()
            .write(true)
            .open(&data)
            .and_then(|f| f.set_modified(later))
            .expect("touch");
        let s = run(&inputs, &options(&out), &mock).expect("batch");
        assert_eq!(
            mock.fits.load(Ordering::SeqCst),
            2,
            "the newer input is refitted"
        );
        assert_eq!(s.resumed(), 0);
    }

    /// The real fitter on a neural BRDF: the written model is the CT fit's own BSDF, and the
    /// recorded metrics are those of that model.
    #[test]
    fn measured_fitter_writes_the_ct_fits_model() {
        let input = "nbrdf:nickel";
        let s = FitSettings::new(ModelChoice::Ggx);
        let f = MeasuredFitter.fit(input, &s, &|_| {}).expect("fit");
        let data = data::load(input).expect("data");
        let direct = ct::fit(
            data.bsdf.as_ref(),
            ct::Distribution::Ggx,
            &ct::CtOptions::default(),
        )
        .expect("ct fit")
        .to_bsdf("direct")
        .expect("bsdf");
        let ours = f.model.to_bsdf("ours").expect("bsdf");
        for (ti, to, dphi) in [
            (0.1, 0.1, 3.1),
            (0.5, 0.4, 3.0),
            (1.0, 0.3, 1.0),
            (1.3, 1.2, 2.5),
        ] {
            let wi = lustre_brdf::frame::spherical(ti, 0.0);
            let wo = lustre_brdf::frame::spherical(to, dphi);
            let (a, b) = (direct.eval(wi, wo), ours.eval(wi, wo));
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() <= 1e-12 * a[c].abs().max(1e-300),
                    "{a:?} {b:?}"
                );
            }
        }
        let r = metrics::evaluate(data.bsdf.as_ref(), &direct, data.transmission);
        assert_eq!(f.errors.ngan_l2, r.ngan_l2);
        assert_eq!(f.albedo_data, r.albedo_data);
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
            settings: FitSettings {
                lobes: 2,
                ..FitSettings::new(ModelChoice::Kurt)
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
