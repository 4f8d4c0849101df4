//! What a batch is asked to fit: the model ([`ModelChoice`]), the options that determine a
//! fit's result ([`FitOptions`], recorded in every JSON and compared on resume), the Kurt
//! options they give, and the checks made before any input is read.

use super::Metric;
use crate::{kurt, FitError, Result};
use lustre_brdf::material::FitErrors;
use serde::{Deserialize, Serialize};

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
    ///
    /// [`MaterialModel::kind`]: lustre_brdf::material::MaterialModel::kind
    pub fn as_str(self) -> &'static str {
        match self {
            ModelChoice::Sgd => "sgd",
            ModelChoice::Kurt => "kurt",
            ModelChoice::Beckmann => "beckmann",
            ModelChoice::Ggx => "ggx",
        }
    }
}

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
pub struct FitOptions {
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

impl FitOptions {
    /// Default settings for `model`: one lobe, no transmission lobe, nothing fixed, refine,
    /// Ngan's L2, unmeasured bins masked.
    pub fn new(model: ModelChoice) -> Self {
        FitOptions {
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
    ///
    /// [`FitRecord::options`]: lustre_brdf::material::FitRecord::options
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

/// The Kurt options of `s` (search grid and levels at their defaults).
pub fn kurt_options(s: &FitOptions) -> kurt::KurtOptions {
    kurt::KurtOptions {
        lobes: s.lobes,
        transmission_lobes: s.transmission_lobes,
        fixed: s.fixed.clone(),
        ranges: s.ranges.clone(),
        polish: s.refine,
        ..kurt::KurtOptions::default()
    }
}

/// The most Kurt lobes of either kind a fit takes.
pub const MAX_LOBES: usize = 8;

/// Checks what can be checked before any input is read: for Kurt, that every `--fix` and
/// `--range` name is one of [`kurt::parameter_names`] and that there is a lobe to fit; for
/// Cook-Torrance, that no Kurt-only option is set.
pub fn check_options(s: &FitOptions) -> Result<()> {
    if s.lobes > MAX_LOBES || s.transmission_lobes > MAX_LOBES {
        return Err(FitError::Option(format!(
            "--lobes {} / --transmission-lobes {}: at most {MAX_LOBES} each (the search's cost \
             grows steeply with the lobes; measured materials are fitted with 1 to 3)",
            s.lobes, s.transmission_lobes
        )));
    }
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
