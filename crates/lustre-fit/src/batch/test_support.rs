//! Shared by the batch module's unit tests: a mock [`Fitter`] that fails, panics or succeeds
//! by input name, the batch options the tests start from, and a reader of `summary.csv`.

use super::{BatchOptions, FitOptions, Fitted, Fitter, ModelChoice};
use crate::{FitError, FitStatus, Result};
use lustre_brdf::material::{FitErrors, LobeParams, MaterialModel};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fitter by input name: `bad*` is unusable data, `panic*` panics, `nan*` returns a
/// model with a NaN parameter, `many` expands into two inputs, `noexpand` cannot be
/// expanded; anything else fits a fixed Kurt model. Counts its fits.
#[derive(Default)]
pub(super) struct Mock {
    pub(super) fits: AtomicUsize,
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

    fn fit(&self, input: &str, options: &FitOptions, stage: &dyn Fn(&str)) -> Result<Fitted> {
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
            status: if options.refine {
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

pub(super) fn options(out: &Path) -> BatchOptions {
    BatchOptions {
        fit: FitOptions::new(ModelChoice::Kurt),
        jobs: 2,
        force: false,
        out: out.to_path_buf(),
        progress: false,
        suffix: String::new(),
        shard: None,
    }
}

pub(super) fn csv_rows(p: &Path) -> Vec<csv::StringRecord> {
    let mut r = csv::Reader::from_path(p).expect("csv");
    let h = r.headers().expect("headers").clone();
    assert_eq!(&h[0], "name");
    assert_eq!(&h[3], "status");
    assert_eq!(&h[4], "ngan_l2_r");
    assert_eq!(h.len(), 19);
    r.records().map(|x| x.expect("record")).collect()
}
