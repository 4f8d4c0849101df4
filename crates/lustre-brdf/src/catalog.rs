//! Resolves a material specification to a [`Bsdf`]: a model with parameters, a built-in
//! material, a published fit by name, an NBRDF material, or a measured file by path.
//!
//! Grammar (whitespace ignored):
//! - `NAME` — a built-in material (see [`builtins`]), e.g. `kurt-demo`;
//! - `MODEL(key=value, ...)` — an analytic model with its parameters, e.g.
//!   `kurt(kd=0.1, ks=0.6, mx=0.1, my=0.3, r0=0.9)` (see [`models`] for models and keys);
//! - `sgd:MATERIAL`, `abc:MATERIAL`, `lafortune:MATERIAL` — a published MERL fit
//!   (`../shared/data/fits/`);
//! - `nbrdf:MATERIAL` or `nbrdf:FILE#MATERIAL` — a neural BRDF (default file: the MERL set);
//! - a path ending in `.binary` (MERL), `.bsdf` (RGL tensor), `.dat` (ALTA table) or
//!   `.gonio` (lustre goniometric table).

use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// Parameters of a `MODEL(key=value, ...)` specification, consumed as they are read so that
/// unknown keys can be reported.
#[derive(Debug, Clone)]
pub struct Params {
    model: String,
    values: BTreeMap<String, f64>,
}

impl Params {
    /// Parses `model(k=v, ...)` or a bare `model`.
    pub fn parse(spec: &str) -> Result<Params> {
        let spec = spec.trim();
        let (model, body) = match spec.find('(') {
            Some(i) => {
                let body = spec[i + 1..].strip_suffix(')').ok_or_else(|| {
                    Error::NotFound(format!("{spec:?}: missing closing parenthesis"))
                })?;
                (spec[..i].trim(), body)
            }
            None => (spec, ""),
        };
        let mut values = BTreeMap::new();
        for kv in body.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (k, v) = kv.split_once('=').ok_or_else(|| {
                Error::NotFound(format!("{spec:?}: expected key=value, found {kv:?}"))
            })?;
            let v: f64 = v.trim().parse().map_err(|_| {
                Error::NotFound(format!(
                    "{spec:?}: the value of {} is not a number: {v:?}",
                    k.trim()
                ))
            })?;
            if values.insert(k.trim().to_string(), v).is_some() {
                return Err(Error::NotFound(format!(
                    "{spec:?}: {} is given twice",
                    k.trim()
                )));
            }
        }
        Ok(Params {
            model: model.to_string(),
            values,
        })
    }

    /// The model name.
    pub fn model(&self) -> &str {
        &self.model
    }

    /// Takes `key`, or `default` when absent.
    pub fn get(&mut self, key: &str, default: f64) -> f64 {
        self.values.remove(key).unwrap_or(default)
    }

    /// Fails if any key was not consumed.
    pub fn finish(self) -> Result<()> {
        if self.values.is_empty() {
            return Ok(());
        }
        let keys: Vec<_> = self.values.keys().cloned().collect();
        Err(Error::NotFound(format!(
            "model {} has no parameter(s) {}",
            self.model,
            keys.join(", ")
        )))
    }
}
