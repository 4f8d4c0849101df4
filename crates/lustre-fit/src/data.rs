//! Measured inputs as fitting data.
//!
//! An input is anything [`lustre_brdf::catalog::resolve`] accepts: a MERL `.binary`, an RGL
//! `.bsdf`, a goniometric `.gonio`, an ALTA `.dat`, `nbrdf:FILE#NAME` or `nbrdf:NAME` (the
//! embedded MERL NBRDF set). [`expand_inputs`] turns `nbrdf:FILE#*` (or `#all`, or `nbrdf:*` for
//! the embedded set) into one input per material.
//!
//! A MERL table's unmeasured (negative) bins are masked by default: [`MeasuredData::coverage`]
//! says which direction pairs were measured, the fitters and [`crate::metrics`] leave the others
//! out, and [`MeasuredData::missing`] counts them for the report. [`LoadOptions::strict`]
//! refuses such tables instead.
//!
//! [`load`] checks the data before anyone fits it: it evaluates the BSDF on a fixed set of
//! direction pairs (in-plane and out-of-plane, the specular configuration included, and the lower
//! hemisphere for transmitting data) and rejects data that is non-finite somewhere, all zero, or
//! negative-dominated (the negative values outweigh the positive ones), with
//! [`FitError::Data`] naming the input.

use crate::{FitError, Result};
use glam::DVec3;
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::frame::spherical;
use lustre_brdf::measured::merl::MerlCoverage;
use lustre_brdf::measured::nbrdf::NbrdfSet;
use std::path::PathBuf;

/// How [`load_with`] reads an input.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Refuse MERL tables with unmeasured (negative) bins instead of masking them.
    pub strict: bool,
}

/// A measured material ready to be fitted.
#[derive(Debug)]
pub struct MeasuredData {
    /// A short material name (the NBRDF material, or the file stem of a path).
    pub name: String,
    /// The input as given (file or specification).
    pub source: String,
    /// The data as a BSDF.
    pub bsdf: Box<dyn Bsdf>,
    /// Whether the data scatters into the lower hemisphere.
    pub transmission: bool,
    /// The measured direction pairs of a MERL table with unmeasured bins (`None`: all).
    pub coverage: Option<MerlCoverage>,
    /// Unmeasured stored values of a MERL table (all channels together; 0 for other inputs).
    pub missing: usize,
}

impl MeasuredData {
    /// Any BSDF as fitting data, named `name`: reflection (and transmission when it
    /// transmits), no coverage mask.
    pub fn from_bsdf(name: &str, bsdf: Box<dyn Bsdf>) -> Self {
        MeasuredData {
            name: name.to_string(),
            source: name.to_string(),
            transmission: bsdf.flags().transmission,
            bsdf,
            coverage: None,
            missing: 0,
        }
    }

    /// Whether the pair was measured (always true without a coverage mask).
    pub fn covers(&self, wi: DVec3, wo: DVec3) -> bool {
        self.coverage.as_ref().is_none_or(|c| c.covers(wi, wo))
    }

    /// A sentence on the masked bins for reports (empty when nothing is masked).
    pub fn mask_note(&self) -> String {
        match &self.coverage {
            Some(c) => format!(
                "{} unmeasured values ({} of 1458000 bins) masked",
                self.missing,
                c.masked_bins()
            ),
            None => String::new(),
        }
    }
}

/// Splits `nbrdf:FILE#NAME` / `nbrdf:NAME` into (file, name), the file `None` for the embedded
/// MERL set; `None` for other inputs.
fn split_nbrdf(input: &str) -> Option<(Option<PathBuf>, &str)> {
    let rest = input.trim().strip_prefix("nbrdf:")?.trim();
    Some(match rest.rsplit_once('#') {
        Some((f, n)) => (Some(PathBuf::from(f)), n.trim()),
        None => (None, rest),
    })
}

/// Expands `nbrdf:FILE#*`, `nbrdf:FILE#all`, `nbrdf:*` and `nbrdf:all` to one `nbrdf:FILE#NAME`
/// input per material of the file (in the file's sorted order); any other input is returned as
/// it is. Fails when the NBRDF file cannot be read or holds no material.
pub fn expand_inputs(input: &str) -> Result<Vec<String>> {
    let input = input.trim();
    match split_nbrdf(input) {
        Some((file, name)) if name == "*" || name == "all" => {
            let set = match &file {
                Some(f) => NbrdfSet::read(f)?,
                None => lustre_brdf::embedded::merl_nbrdf()?,
            };
            if set.is_empty() {
                return Err(FitError::Data {
                    input: input.to_string(),
                    problem: "the network file holds no material".into(),
                });
            }
            Ok(set
                .names()
                .iter()
                .map(|n| match &file {
                    Some(f) => format!("nbrdf:{}#{n}", f.display()),
                    None => format!("nbrdf:{n}"),
                })
                .collect())
        }
        _ => Ok(vec![input.to_string()]),
    }
}

/// Loads one input through the catalog and checks its values (see the module notes), masking
/// unmeasured MERL bins.
pub fn load(input: &str) -> Result<MeasuredData> {
    load_with(input, &LoadOptions::default())
}

/// [`load`] with options.
pub fn load_with(input: &str, opts: &LoadOptions) -> Result<MeasuredData> {
    let input = input.trim();
    if let Some((_, name)) = split_nbrdf(input) {
        if name == "*" || name == "all" {
            return Err(FitError::Data {
                input: input.to_string(),
                problem: "a wildcard input names several materials; expand it first \
                          (data::expand_inputs)"
                    .into(),
            });
        }
    }
    let path_part = input.rsplit_once('#').map_or(input, |(p, _)| p);
    let is_merl = !input.starts_with("nbrdf:")
        && std::path::Path::new(path_part)
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("binary"));
    let (bsdf, coverage, missing): (Box<dyn Bsdf>, _, _) = if is_merl {
        use lustre_brdf::measured::merl::{MerlTable, NegativeValues};
        let negative = if opts.strict {
            NegativeValues::Reject
        } else {
            NegativeValues::Missing
        };
        let t = MerlTable::read_with(path_part, negative)?;
        let (c, n) = (t.coverage(), t.missing_count());
        (Box::new(t), c, n)
    } else {
        let ro = lustre_brdf::catalog::ResolveOptions {
            strict: opts.strict,
        };
        (lustre_brdf::catalog::resolve_with(input, &ro)?, None, 0)
    };
    let name = match split_nbrdf(input) {
        Some((_, n)) => n.to_string(),
        None => {
            let path_part = input.rsplit_once('#').map_or(input, |(p, _)| p);
            std::path::Path::new(path_part)
                .file_stem()
                .map_or_else(|| input.to_string(), |s| s.to_string_lossy().into_owned())
        }
    };
    let transmission = bsdf.flags().transmission;
    check_values(input, bsdf.as_ref(), transmission)?;
    Ok(MeasuredData {
        name,
        source: input.to_string(),
        bsdf,
        transmission,
        coverage,
        missing,
    })
}

/// Direction pairs (wi, wo) on which [`check_values`] looks at the data: θi, θo on a 10° grid
/// (5°..85°), several relative azimuths, and the mirror configuration; with `transmission`
/// also wi in the lower hemisphere.
fn check_pairs(transmission: bool) -> Vec<(DVec3, DVec3)> {
    let mut v = Vec::new();
    let thetas: Vec<f64> = (0..9)
        .map(|k| (5.0 + 10.0 * k as f64).to_radians())
        .collect();
    for &to in &thetas {
        let wo = spherical(to, 0.0);
        // The mirror direction (specular peak) and a ring around it.
        v.push((spherical(to, std::f64::consts::PI), wo));
        for &ti in &thetas {
            for k in 0..8 {
                let phi = k as f64 * std::f64::consts::FRAC_PI_4 + 0.1;
                let wi = spherical(ti, phi);
                v.push((wi, wo));
                if transmission {
                    v.push((DVec3::new(wi.x, wi.y, -wi.z), wo));
                }
            }
        }
    }
    v
}

/// Rejects non-finite, all-zero or negative-dominated data with [`FitError::Data`].
pub fn check_values(input: &str, bsdf: &dyn Bsdf, transmission: bool) -> Result<()> {
    let err = |problem: String| FitError::Data {
        input: input.to_string(),
        problem,
    };
    let (mut pos, mut neg) = (0.0f64, 0.0f64);
    for (wi, wo) in check_pairs(transmission) {
        let f = bsdf.eval(wi, wo);
        for (c, &x) in f.0.iter().enumerate() {
            if !x.is_finite() {
                return Err(err(format!(
                    "non-finite value {x} in channel {c} at wi = {wi:.4}, wo = {wo:.4}"
                )));
            }
            if x > 0.0 {
                pos += x;
            } else {
                neg -= x;
            }
        }
    }
    if pos == 0.0 && neg == 0.0 {
        return Err(err("all values are zero".into()));
    }
    if neg >= pos {
        return Err(err(format!(
            "negative-dominated data (sum of negative values {neg:.4e} ≥ sum of positive \
             values {pos:.4e})"
        )));
    }
    Ok(())
}
