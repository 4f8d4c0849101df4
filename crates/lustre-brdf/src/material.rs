//! The versioned material JSON (`lustre-material`, version 1) that the fitter writes and the
//! renderer loads.
//!
//! ```json
//! {
//!   "schema": "lustre-material",
//!   "version": 1,
//!   "name": "gold-metallic-paint",
//!   "model": {
//!     "type": "kurt",
//!     "kd": [0.02, 0.01, 0.005],
//!     "reflection": [{ "ks": [0.6, 0.4, 0.2], "mx": 0.1, "my": 0.1, "r0": 0.9, "alpha": 0.0 }],
//!     "transmission": []
//!   },
//!   "fit": { "source": "gold.binary", "status": "converged", ... }
//! }
//! ```
//!
//! The model is either a Kurt model (000 Eq. 3.3–3.6: kd plus reflection and transmission lobes,
//! see [`crate::models::kurt`]) or a per-channel Cook-Torrance (004 Eq. III.1) with the SGD,
//! Beckmann or GGX distribution (see [`CtChannelParams`] for how a channel becomes a
//! [`CtChannel`]). `fit` is the optional record of how the model was obtained.
//!
//! [`parse`] checks the schema name first, then the version (a file of another version is a
//! clear error, not a misreading), then every parameter through the model constructors
//! ([`Kurt::new`], [`Ndf`], [`Fresnel`], [`CookTorrance::new`]), so a file that parses gives a
//! valid BSDF. Unknown fields are errors (typos do not pass silently). [`write()`] validates the
//! same way and writes atomically.

use crate::bsdf::Bsdf;
use crate::error::{check_range, read_file, write_atomic, Error, Result};
use crate::microfacet::fresnel::Fresnel;
use crate::microfacet::ndf::Ndf;
use crate::microfacet::smith::SgdG1Approx;
use crate::models::cook_torrance::{CookTorrance, CtChannel, G1Model};
use crate::models::kurt::{Kurt, KurtLobe};
use crate::rgb::Rgb;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `schema` field of every material file.
pub const SCHEMA: &str = "lustre-material";
/// The version this build reads and writes.
pub const VERSION: u32 = 1;

/// A material file: schema, version, name, model and an optional fit record.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialFile {
    /// Always [`SCHEMA`].
    pub schema: String,
    /// Always [`VERSION`] for files this build writes.
    pub version: u32,
    /// The material's name (non-empty).
    pub name: String,
    /// The model and its parameters.
    pub model: MaterialModel,
    /// How the model was obtained, when it is a fit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<FitRecord>,
}

/// One Kurt lobe (000 Eq. 3.4; for a transmission lobe `ks` is kt, Eq. 3.5).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LobeParams {
    /// Lobe weight per channel, ≥ 0.
    pub ks: [f64; 3],
    /// Roughness along the tangent x.
    pub mx: f64,
    /// Roughness along the bitangent y.
    pub my: f64,
    /// Schlick reflectance at normal incidence, in [0, 1].
    pub r0: f64,
    /// Shadowing exponent α, in [0, 1].
    pub alpha: f64,
}

impl LobeParams {
    fn to_lobe(self) -> Result<KurtLobe> {
        KurtLobe::new(Rgb(self.ks), self.mx, self.my, self.r0, self.alpha)
    }

    fn from_lobe(l: &KurtLobe) -> Self {
        LobeParams {
            ks: l.ks.0,
            mx: l.mx,
            my: l.my,
            r0: l.r0,
            alpha: l.alpha,
        }
    }
}

/// The microfacet distribution of a Cook-Torrance material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CtDistribution {
    /// Shifted gamma distribution (004 Eq. V.1).
    Sgd,
    /// Beckmann.
    Beckmann,
    /// GGX (Trowbridge-Reitz).
    Ggx,
}

impl CtDistribution {
    /// The lower-case name used in the JSON and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            CtDistribution::Sgd => "sgd",
            CtDistribution::Beckmann => "beckmann",
            CtDistribution::Ggx => "ggx",
        }
    }
}

/// One channel of a Cook-Torrance material (004 Eq. III.1, V.1, V.3, V.5).
///
/// Becomes a [`CtChannel`] as follows: NDF `sgd` → [`Ndf::sgd_with_kap`]`(alpha, p, kap)`,
/// `beckmann` → [`Ndf::beckmann`]`(alpha)`, `ggx` → [`Ndf::ggx`]`(alpha)` (then `p` and `kap`
/// are not used but must be finite); Fresnel → [`Fresnel::generalized_schlick`]`(f0, f1)`
/// (Eq. V.5); G1 → for SGD `g1 = [λ, c, k]`: the Eq. V.3 approximation
/// [`SgdG1Approx::from_lck`], absent: the numeric Smith G1; for Beckmann and GGX always the
/// closed-form Smith G1 (`g1` must be absent). `lustre_fit::ct` fits channels of this type.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CtChannelParams {
    /// Diffuse coefficient ρd (f contains ρd/π), ≥ 0.
    pub rho_d: f64,
    /// Specular coefficient ρs, ≥ 0.
    pub rho_s: f64,
    /// Distribution width α.
    pub alpha: f64,
    /// SGD shape p.
    pub p: f64,
    /// SGD normalization kap (> 0 for SGD).
    pub kap: f64,
    /// Eq. V.5 F0.
    pub f0: f64,
    /// Eq. V.5 F1.
    pub f1: f64,
    /// SGD only: the Eq. V.3 shadowing approximation [λ, c, k]; absent: the exact Smith G1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g1: Option<[f64; 3]>,
}

impl CtChannelParams {
    /// The channel as the BSDF library's [`CtChannel`], validated (see the type's notes).
    pub fn to_channel(&self, distribution: CtDistribution) -> Result<CtChannel> {
        check_range("rho_d", self.rho_d, 0.0, f64::MAX)?;
        check_range("rho_s", self.rho_s, 0.0, f64::MAX)?;
        let ndf = match distribution {
            CtDistribution::Sgd => Ndf::sgd_with_kap(self.alpha, self.p, self.kap)?,
            CtDistribution::Beckmann | CtDistribution::Ggx => {
                check_range("p", self.p, -f64::MAX, f64::MAX)?;
                check_range("kap", self.kap, -f64::MAX, f64::MAX)?;
                if distribution == CtDistribution::Beckmann {
                    Ndf::beckmann(self.alpha)?
                } else {
                    Ndf::ggx(self.alpha)?
                }
            }
        };
        let g1 = match (self.g1, distribution) {
            (Some([lambda, c, k]), CtDistribution::Sgd) => {
                G1Model::SgdApprox(SgdG1Approx::from_lck(lambda, c, k)?)
            }
            (None, CtDistribution::Sgd) => G1Model::numeric(&ndf),
            (None, _) => G1Model::Closed,
            (Some([lambda, ..]), d) => {
                let reason = format!(
                    "the Eq. V.3 approximation applies to sgd only, not {}",
                    d.as_str()
                );
                return Err(Error::param("g1", lambda, reason));
            }
        };
        let fresnel = Fresnel::generalized_schlick(self.f0, self.f1)?;
        Ok(CtChannel::new(self.rho_d, self.rho_s, ndf, g1, fresnel))
    }
}

impl CtChannelParams {
    /// The parameters of a BSDF library channel. Errors: an exponential distribution, a
    /// Lazányi Fresnel, Beckmann or GGX without the closed-form Smith G1, SGD without shadowing
    /// or with an Eq. V.3 approximation whose c underflowed (none of which a material file
    /// holds).
    pub fn from_channel(c: &CtChannel) -> Result<Self> {
        let (f0, f1) = c.fresnel.generalized_schlick_form().ok_or_else(|| {
            Error::NotFound(
                "a Lazányi Fresnel has no material-file form (generalized Schlick has)".into(),
            )
        })?;
        let (alpha, p, kap, g1) = match (&c.ndf, &c.g1) {
            (Ndf::Sgd(s), G1Model::SgdApprox(a)) if a.c > 0.0 => {
                (s.alpha(), s.p(), s.kap(), Some([a.lambda, a.c, a.k]))
            }
            (Ndf::Sgd(s), G1Model::Numeric(_)) => (s.alpha(), s.p(), s.kap(), None),
            (Ndf::Beckmann { alpha } | Ndf::Ggx { alpha }, G1Model::Closed) => {
                (*alpha, 0.0, 1.0, None)
            }
            (ndf, g1) => {
                let g1 = match g1 {
                    G1Model::None => "no shadowing",
                    G1Model::Numeric(_) => "the numeric Smith G1",
                    G1Model::SgdApprox(_) => "an Eq. V.3 approximation with c = 0",
                    G1Model::Closed => "the closed-form Smith G1",
                };
                return Err(Error::NotFound(format!(
                    "{} with {g1} has no material-file form",
                    ndf.name()
                )));
            }
        };
        Ok(CtChannelParams {
            rho_d: c.rho_d,
            rho_s: c.rho_s,
            alpha,
            p,
            kap,
            f0,
            f1,
            g1,
        })
    }
}

/// The model of a material file; the JSON carries the variant as `"type": "kurt"` or
/// `"type": "cook-torrance"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum MaterialModel {
    /// Kurt et al. with Luksch's transmission lobes (000 Eq. 3.6).
    Kurt {
        /// Diffuse coefficient per channel, ≥ 0.
        kd: [f64; 3],
        /// Reflection lobes.
        reflection: Vec<LobeParams>,
        /// Transmission lobes (may be absent in the JSON: none).
        #[serde(default)]
        transmission: Vec<LobeParams>,
    },
    /// Per-channel Cook-Torrance (004 Eq. III.1).
    CookTorrance {
        /// The microfacet distribution of all three channels.
        distribution: CtDistribution,
        /// Parameters of the r, g, b channels.
        channels: [CtChannelParams; 3],
    },
}

impl MaterialModel {
    /// The parameters of a Kurt model.
    pub fn from_kurt(k: &Kurt) -> Self {
        MaterialModel::Kurt {
            kd: k.kd.0,
            reflection: k.reflection.iter().map(LobeParams::from_lobe).collect(),
            transmission: k.transmission.iter().map(LobeParams::from_lobe).collect(),
        }
    }

    /// The parameters of a fitted model's BSDF: a [`Kurt`] model or a [`CookTorrance`] with
    /// one distribution (SGD, Beckmann or GGX) in all channels (see
    /// [`CtChannelParams::from_channel`] for what else it needs). Errors say why any other BSDF
    /// has no material-file form. A Beckmann or GGX channel gets p = 0, kap = 1 (unused).
    pub fn from_bsdf(bsdf: &dyn Bsdf) -> Result<Self> {
        let any = bsdf.as_any();
        if let Some(k) = any.and_then(|a| a.downcast_ref::<Kurt>()) {
            return Ok(Self::from_kurt(k));
        }
        let Some(ct) = any.and_then(|a| a.downcast_ref::<CookTorrance>()) else {
            return Err(Error::NotFound(format!(
                "{} is not a fitted model (Kurt, SGD, Beckmann or GGX Cook-Torrance)",
                bsdf.name()
            )));
        };
        let ch = ct.channels();
        let distribution = match ch[0].ndf {
            Ndf::Sgd(_) => CtDistribution::Sgd,
            Ndf::Beckmann { .. } => CtDistribution::Beckmann,
            Ndf::Ggx { .. } => CtDistribution::Ggx,
            Ndf::Exponential { .. } => {
                return Err(Error::NotFound(format!(
                    "{}: the exponential distribution has no material-file form",
                    bsdf.name()
                )))
            }
        };
        let mut channels = Vec::with_capacity(3);
        for (i, c) in ch.iter().enumerate() {
            if std::mem::discriminant(&c.ndf) != std::mem::discriminant(&ch[0].ndf) {
                return Err(Error::NotFound(format!(
                    "{}: channel {i} has {} where channel 0 has {} (a material file has one \
                     distribution)",
                    bsdf.name(),
                    c.ndf.name(),
                    ch[0].ndf.name()
                )));
            }
            channels.push(
                CtChannelParams::from_channel(c)
                    .map_err(|e| Error::NotFound(format!("{} channel {i}: {e}", bsdf.name())))?,
            );
        }
        let channels: [CtChannelParams; 3] = channels
            .try_into()
            .map_err(|_| Error::NotFound("three channels expected".into()))?;
        Self::cook_torrance(distribution, channels)
    }

    /// A Cook-Torrance model from per-channel parameters, validated.
    pub fn cook_torrance(
        distribution: CtDistribution,
        channels: [CtChannelParams; 3],
    ) -> Result<Self> {
        let m = MaterialModel::CookTorrance {
            distribution,
            channels,
        };
        m.validate()?;
        Ok(m)
    }

    /// A short name of the model kind: `kurt`, `sgd`, `beckmann` or `ggx` (the `lustre fit
    /// --model` names).
    pub fn kind(&self) -> &'static str {
        match self {
            MaterialModel::Kurt { .. } => "kurt",
            MaterialModel::CookTorrance { distribution, .. } => distribution.as_str(),
        }
    }

    /// The Kurt model (an error for a Cook-Torrance material).
    pub fn to_kurt(&self) -> Result<Kurt> {
        match self {
            MaterialModel::Kurt {
                kd,
                reflection,
                transmission,
            } => {
                let lobes = |v: &[LobeParams], what: &str| -> Result<Vec<KurtLobe>> {
                    v.iter()
                        .enumerate()
                        .map(|(i, l)| l.to_lobe().map_err(|e| located(e, &format!("{what}[{i}]"))))
                        .collect()
                };
                Kurt::new(
                    Rgb(*kd),
                    lobes(reflection, "reflection")?,
                    lobes(transmission, "transmission")?,
                )
            }
            MaterialModel::CookTorrance { .. } => Err(Error::NotFound(
                "a Cook-Torrance material is not a Kurt model".into(),
            )),
        }
    }

    /// The Cook-Torrance model named `name` (an error for a Kurt material).
    pub fn to_cook_torrance(&self, name: &str) -> Result<CookTorrance> {
        match self {
            MaterialModel::CookTorrance {
                distribution,
                channels,
            } => {
                let mut out = Vec::with_capacity(3);
                for (c, ch) in channels.iter().zip(["r", "g", "b"]) {
                    out.push(
                        c.to_channel(*distribution)
                            .map_err(|e| located(e, &format!("channels.{ch}")))?,
                    );
                }
                let out: [CtChannel; 3] = out
                    .try_into()
                    .map_err(|_| Error::NotFound("three channels expected".into()))?;
                CookTorrance::new(name, out)
            }
            MaterialModel::Kurt { .. } => Err(Error::NotFound(
                "a Kurt material is not a Cook-Torrance model".into(),
            )),
        }
    }

    /// The model as a BSDF named `name` (Kurt models carry their own name).
    pub fn to_bsdf(&self, name: &str) -> Result<Box<dyn Bsdf>> {
        Ok(match self {
            MaterialModel::Kurt { .. } => Box::new(self.to_kurt()?),
            MaterialModel::CookTorrance { .. } => Box::new(self.to_cook_torrance(name)?),
        })
    }

    /// Checks every parameter through the model constructors.
    pub fn validate(&self) -> Result<()> {
        match self {
            MaterialModel::Kurt { .. } => self.to_kurt().map(drop),
            MaterialModel::CookTorrance { .. } => self.to_cook_torrance("validate").map(drop),
        }
    }
}

/// Prefixes a parameter error with where it sits in the file (`reflection[0].mx`,
/// `channels.g.alpha`).
fn located(e: Error, prefix: &str) -> Error {
    match e {
        Error::Parameter {
            name,
            value,
            reason,
        } => Error::Parameter {
            name: format!("{prefix}.{name}"),
            value,
            reason,
        },
        other => other,
    }
}

/// Error metrics of a fit, per channel (r, g, b).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitErrors {
    /// Ngan's normalized L2 (004 §V.5.3).
    pub ngan_l2: [f64; 3],
    /// The L1 transfer-probability metric (000 Eq. 3.7).
    pub l1: [f64; 3],
}

/// How a model was fitted: plain data, written by `lustre fit`, ignored by the renderer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitRecord {
    /// The fitted input (a file or a catalog specification).
    pub source: String,
    /// The error metrics; absent when the fit failed.
    #[serde(default)]
    pub errors: Option<FitErrors>,
    /// Albedo of the data at normal incidence, per channel; absent when the fit failed.
    #[serde(default)]
    pub albedo_data: Option<[f64; 3]>,
    /// Albedo of the model at normal incidence, per channel; absent when the fit failed.
    #[serde(default)]
    pub albedo_model: Option<[f64; 3]>,
    /// Wall time of the fit in seconds.
    pub time_s: f64,
    /// How the fit ended (`converged`, `not-converged`, `invalid-data`, `error`).
    pub status: String,
    /// A message in words (empty when there is nothing to say).
    #[serde(default)]
    pub message: String,
    /// The fitting options (model, lobes, fixed parameters, ranges, refinement).
    #[serde(default)]
    pub options: serde_json::Value,
    /// Fingerprint of the input's data file when it is a file (`crc32:HEX:LENGTH`, see
    /// `lustre_fit::batch`): a resumed batch reuses this fit only for the same bytes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_hash: Option<String>,
}

impl FitRecord {
    /// Checks that every number is finite (errors, albedos and time also ≥ 0) and the status
    /// is not empty.
    pub fn validate(&self) -> Result<()> {
        let check3 = |name: &str, v: &[f64; 3]| -> Result<()> {
            for (x, ch) in v.iter().zip(["r", "g", "b"]) {
                check_range(&format!("fit.{name}.{ch}"), *x, 0.0, f64::INFINITY)?;
            }
            Ok(())
        };
        if let Some(e) = &self.errors {
            check3("errors.ngan_l2", &e.ngan_l2)?;
            check3("errors.l1", &e.l1)?;
        }
        if let Some(a) = &self.albedo_data {
            check3("albedo_data", a)?;
        }
        if let Some(a) = &self.albedo_model {
            check3("albedo_model", a)?;
        }
        check_range("fit.time_s", self.time_s, 0.0, f64::INFINITY)?;
        if self.status.trim().is_empty() {
            return Err(Error::NotFound("fit.status is empty".into()));
        }
        Ok(())
    }
}

impl MaterialFile {
    /// A validated material file of the current schema and version.
    pub fn new(
        name: impl Into<String>,
        model: MaterialModel,
        fit: Option<FitRecord>,
    ) -> Result<Self> {
        let m = MaterialFile {
            schema: SCHEMA.into(),
            version: VERSION,
            name: name.into(),
            model,
            fit,
        };
        m.validate()?;
        Ok(m)
    }

    /// Checks schema, version, name, every model parameter and the fit record.
    pub fn validate(&self) -> Result<()> {
        if self.schema != SCHEMA {
            return Err(Error::NotFound(format!(
                "schema is {:?}, expected {SCHEMA:?}",
                self.schema
            )));
        }
        if self.version != VERSION {
            return Err(Error::NotFound(format!(
                "version {} is not supported (this build reads version {VERSION})",
                self.version
            )));
        }
        if self.name.trim().is_empty() {
            return Err(Error::NotFound("the material name is empty".into()));
        }
        self.model.validate()?;
        if let Some(f) = &self.fit {
            f.validate()?;
        }
        Ok(())
    }

    /// The model as a BSDF (named after the material).
    pub fn to_bsdf(&self) -> Result<Box<dyn Bsdf>> {
        self.model.to_bsdf(&self.name)
    }

    /// The pretty-printed JSON (validated first).
    pub fn to_json(&self) -> Result<String> {
        self.validate()?;
        serde_json::to_string_pretty(self)
            .map_err(|e| Error::NotFound(format!("cannot serialize material {}: {e}", self.name)))
    }
}

/// Parses a material file from memory; `path` names it in messages. Checks, in this order: the
/// JSON syntax, the `schema` name, the `version`, the fields, every parameter.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<MaterialFile> {
    let fmt = |problem: String| Error::format(path, problem);
    let value: serde_json::Value =
        serde_json::from_slice(bytes).map_err(|e| fmt(format!("not valid JSON: {e}")))?;
    let obj = value
        .as_object()
        .ok_or_else(|| fmt("expected a JSON object".into()))?;
    match obj.get("schema").and_then(|s| s.as_str()) {
        Some(SCHEMA) => {}
        Some(other) => {
            return Err(fmt(format!(
                "schema is {other:?}, expected {SCHEMA:?} (not a lustre material file)"
            )))
        }
        None => return Err(fmt(format!("no \"schema\": {SCHEMA:?} field"))),
    }
    match obj.get("version").map(|v| (v, v.as_u64())) {
        Some((_, Some(v))) if v == u64::from(VERSION) => {}
        Some((_, Some(v))) => {
            return Err(fmt(format!(
                "version {v} is not supported (this build reads version {VERSION})"
            )))
        }
        Some((v, None)) => return Err(fmt(format!("version {v} is not a whole number"))),
        None => return Err(fmt("no \"version\" field".into())),
    }
    let m: MaterialFile =
        serde_json::from_value(value).map_err(|e| fmt(format!("invalid material: {e}")))?;
    m.validate().map_err(|e| match e {
        Error::Parameter { .. } => fmt(format!("{e}")),
        Error::NotFound(s) => fmt(s),
        other => other,
    })?;
    Ok(m)
}

/// Reads and parses the material file at `path` (see [`parse`]).
pub fn read(path: &Path) -> Result<MaterialFile> {
    parse(path, &read_file(path)?)
}

/// Validates `m` and writes it to `path` as pretty-printed JSON, atomically.
pub fn write(path: &Path, m: &MaterialFile) -> Result<()> {
    let json = m.to_json().map_err(|e| match e {
        Error::Parameter { .. } => Error::format(path, format!("not written: {e}")),
        Error::NotFound(s) => Error::format(path, format!("not written: {s}")),
        other => other,
    })?;
    write_atomic(path, format!("{json}\n").as_bytes())
}
