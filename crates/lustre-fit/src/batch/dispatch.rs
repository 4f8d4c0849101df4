//! From the model choice to the fit that runs it: [`MeasuredFitter`], the real [`Fitter`],
//! reads the data, runs the Kurt search (over 1..=`lobes` lobes, keeping the best on the
//! chosen metric) or the Cook-Torrance fit with the chosen distribution, and measures the
//! fitted model against the data.

use super::{kurt_options, FitOptions, Fitted, Fitter, ModelChoice};
use crate::{ct, data, kurt, metrics, FitError, FitStatus, Result};
use lustre_brdf::material::{CtDistribution, FitErrors, MaterialModel};

/// The real fitter: [`data::load`] (with its value checks), then [`ct::fit`] or
/// [`kurt::fit`], then [`metrics::evaluate`] of the fitted model (built from the material JSON
/// model, as the renderer will build it) against the data.
#[derive(Clone, Copy, Debug, Default)]
pub struct MeasuredFitter;

impl Fitter for MeasuredFitter {
    fn expand(&self, input: &str) -> Result<Vec<String>> {
        data::expand_inputs(input)
    }

    fn fit(&self, input: &str, s: &FitOptions, stage: &dyn Fn(&str)) -> Result<Fitted> {
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
                let dist = match m {
                    ModelChoice::Sgd => CtDistribution::Sgd,
                    ModelChoice::Beckmann => CtDistribution::Beckmann,
                    _ => CtDistribution::Ggx,
                };
                let opts = ct::CtOptions {
                    refine: s.refine,
                    ..ct::CtOptions::default()
                };
                stage("two-slice fit and refinement");
                let f = ct::fit_masked(data.bsdf.as_ref(), dist, &opts, mask)?;
                notes.push(format!("{} iterations", f.iterations));
                notes.extend(f.notes.iter().cloned());
                let model = MaterialModel::cook_torrance(dist, f.channels)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_brdf::Bsdf;

    /// The real fitter on a neural BRDF: the written model is the CT fit's own BSDF, and the
    /// recorded metrics are those of that model.
    #[test]
    fn measured_fitter_writes_the_ct_fits_model() {
        let input = "nbrdf:nickel";
        let s = FitOptions::new(ModelChoice::Ggx);
        let f = MeasuredFitter.fit(input, &s, &|_| {}).expect("fit");
        let data = data::load(input).expect("data");
        let direct = ct::fit(
            data.bsdf.as_ref(),
            CtDistribution::Ggx,
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
}
