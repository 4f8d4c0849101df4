//! **Fit** in the material editor: lustre-fit on a measured file in a background thread (the
//! window never waits for it), its stage for the progress bar, the material JSON written
//! atomically into the viewer's output folder, and the lobe-plot slices of the measurement and
//! of the fit (computed in that thread too).

use crate::plot::{lobe_slice, LobeSlice};
use lustre_brdf::material::{self, MaterialFile};
use lustre_fit::batch::{self, FitOptions, Fitter, MeasuredFitter, ModelChoice};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{channel, Receiver, TryRecvError};
use std::time::Instant;

/// Incident elevations of the lobe plot, degrees.
pub const PLOT_THETA_I: [f64; 2] = [30.0, 60.0];

/// A finished fit.
#[derive(Clone, Debug)]
pub struct FitDone {
    /// The material JSON written.
    pub json: PathBuf,
    /// Ngan L2 per channel.
    pub ngan_l2: [f64; 3],
    /// Seconds the fit took (reading the data included).
    pub seconds: f64,
    /// Slices of the measurement, per [`PLOT_THETA_I`].
    pub measured: Vec<LobeSlice>,
    /// Slices of the fit.
    pub fitted: Vec<LobeSlice>,
}

enum Msg {
    Stage(String),
    Done(Result<FitDone, String>),
}

/// A fit running in the background.
pub struct FitJob {
    /// The measured input.
    pub input: String,
    /// The model name.
    pub model: String,
    /// When it started.
    pub started: Instant,
    /// What it is doing.
    pub stage: String,
    rx: Receiver<Msg>,
}

/// The model of a name (`sgd`, `kurt`, `beckmann`, `ggx`).
pub fn model_choice(name: &str) -> Option<ModelChoice> {
    match name {
        "sgd" => Some(ModelChoice::Sgd),
        "kurt" => Some(ModelChoice::Kurt),
        "beckmann" => Some(ModelChoice::Beckmann),
        "ggx" => Some(ModelChoice::Ggx),
        _ => None,
    }
}

impl FitJob {
    /// Starts fitting `input` with `model` into `out_dir` (NAME-MODEL.json).
    pub fn start(input: &str, model: &str, out_dir: &Path) -> FitJob {
        let (tx, rx) = channel();
        let (inp, m, dir) = (input.to_string(), model.to_string(), out_dir.to_path_buf());
        std::thread::spawn(move || {
            let stage = |s: &str| {
                let _ = tx.send(Msg::Stage(s.to_string()));
            };
            let r = fit(&inp, &m, &dir, &stage);
            let _ = tx.send(Msg::Done(r));
        });
        FitJob {
            input: input.to_string(),
            model: model.to_string(),
            started: Instant::now(),
            stage: "starting".into(),
            rx,
        }
    }

    /// The result once the fit has ended (stage updates are taken on the way).
    pub fn poll(&mut self) -> Option<Result<FitDone, String>> {
        loop {
            match self.rx.try_recv() {
                Ok(Msg::Stage(s)) => self.stage = s,
                Ok(Msg::Done(r)) => return Some(r),
                Err(TryRecvError::Empty) => return None,
                Err(TryRecvError::Disconnected) => {
                    return Some(Err("the fit thread stopped without a result".into()))
                }
            }
        }
    }
}

/// Fits `input`, writes the material JSON into `dir`, and slices both.
pub fn fit(input: &str, model: &str, dir: &Path, stage: &dyn Fn(&str)) -> Result<FitDone, String> {
    let t = Instant::now();
    let choice = model_choice(model).ok_or_else(|| format!("unknown model {model:?}"))?;
    let fitted = MeasuredFitter
        .fit(input, &FitOptions::new(choice), stage)
        .map_err(|e| format!("{input}: {e}"))?;
    stage("writing the material JSON");
    let name = batch::output_name(input);
    let settings = FitOptions::new(choice);
    let record = fitted.record(input, &settings, t.elapsed().as_secs_f64());
    let file = MaterialFile::new(name.clone(), fitted.model.clone(), Some(record))
        .map_err(|e| e.to_string())?;
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let json = dir.join(format!("{name}-{model}.json"));
    material::write(&json, &file).map_err(|e| e.to_string())?;
    stage("slicing the lobes");
    let measured_bsdf = lustre_brdf::catalog::resolve(input).map_err(|e| e.to_string())?;
    let fit_bsdf = fitted.model.to_bsdf(&name).map_err(|e| e.to_string())?;
    let slices = |b: &dyn lustre_brdf::Bsdf| -> Vec<LobeSlice> {
        PLOT_THETA_I
            .iter()
            .map(|&t| lobe_slice(b, t, 121))
            .collect()
    };
    Ok(FitDone {
        json,
        ngan_l2: fitted.errors.ngan_l2,
        seconds: t.elapsed().as_secs_f64(),
        measured: slices(measured_bsdf.as_ref()),
        fitted: slices(fit_bsdf.as_ref()),
    })
}
