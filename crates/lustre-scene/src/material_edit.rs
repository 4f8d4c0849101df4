//! A material's parameters by name, and setting one from text: what `lustre view`'s material
//! editor shows as controls, what its input scripts and `lustre render --set NAME.FIELD=VALUE`
//! set, and what a scene file's `[material_params]` records (one code path for all of them).
//!
//! Every kind lists its parameters ([`fields`]) with their valid range; a value is set from
//! text ([`set`]: `0.2`, `0.1,0.2,0.3`, `ggx`, `true`, or a material specification), checked
//! against that range, and the material is rebuilt through its constructor checks so that an
//! edit never leaves an invalid material behind. A textured parameter edits its factor (the
//! texture is kept and multiplied in). `spec` swaps the material for any lustre material
//! specification (a catalog entry, a fitted material JSON, a measured file); the parameters of
//! an analytic specification `MODEL(key=value, …)` are fields too (`spec.KEY`).

use crate::error::{Result, SceneError};
use crate::material::{Material, MaterialKind, MicrofacetType, ResolvedSpec};
use lustre_brdf::microfacet::fresnel::Fresnel;
use lustre_brdf::microfacet::ndf::Ndf;
use lustre_brdf::microfacet::smith::{G1Table, SgdG1Approx};
use lustre_brdf::models::cook_torrance::{CookTorrance, CtChannel, G1Model};
use lustre_brdf::models::kurt::Kurt;
use lustre_brdf::{Bsdf, Rgb};
use std::sync::Arc;

/// A parameter's value.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldValue {
    /// A number.
    Scalar(f64),
    /// A linear RGB triple.
    Rgb([f64; 3]),
    /// One of [`Field::choices`].
    Choice(String),
    /// On or off.
    Flag(bool),
    /// Text (a material specification).
    Text(String),
}

impl FieldValue {
    /// The value as [`set`] reads it back.
    pub fn to_text(&self) -> String {
        match self {
            FieldValue::Scalar(v) => format!("{v}"),
            FieldValue::Rgb(c) => format!("{},{},{}", c[0], c[1], c[2]),
            FieldValue::Choice(s) | FieldValue::Text(s) => s.clone(),
            FieldValue::Flag(b) => format!("{b}"),
        }
    }
}

/// One editable parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Its name ([`set`]'s key).
    pub name: String,
    /// Its current value.
    pub value: FieldValue,
    /// Valid range of a number or of each RGB channel.
    pub range: (f64, f64),
    /// Best shown on a logarithmic scale (roughness, exponents).
    pub log: bool,
    /// A texture multiplies the value (the factor is what is edited).
    pub textured: bool,
    /// The words a [`FieldValue::Choice`] takes.
    pub choices: &'static [&'static str],
}

const UNIT: (f64, f64) = (0.0, 1.0);
const ALPHA: (f64, f64) = (1e-4, 1.0);
const IOR: (f64, f64) = (1.0, 4.0);
const METAL: (f64, f64) = (0.0, 20.0);
const DISTRIBUTIONS: &[&str] = &["beckmann", "ggx"];

fn scalar(name: &str, v: f64, range: (f64, f64), log: bool) -> Field {
    Field {
        name: name.to_string(),
        value: FieldValue::Scalar(v),
        range,
        log,
        textured: false,
        choices: &[],
    }
}

fn rgb(name: &str, c: Rgb, range: (f64, f64), textured: bool) -> Field {
    Field {
        name: name.to_string(),
        value: FieldValue::Rgb(c.0),
        range,
        log: false,
        textured,
        choices: &[],
    }
}

fn distribution(d: MicrofacetType) -> Field {
    Field {
        name: "distribution".to_string(),
        value: FieldValue::Choice(d.name().to_string()),
        range: UNIT,
        log: false,
        textured: false,
        choices: DISTRIBUTIONS,
    }
}

/// The editable parameters of `m`, in a fixed order per kind (`two_sided` last).
pub fn fields(m: &Material) -> Vec<Field> {
    use MaterialKind as K;
    let tex_s = |name: &str, t: &crate::material::TexturedScalar, range, log| Field {
        textured: t.texture.is_some(),
        ..scalar(name, t.factor, range, log)
    };
    let mut out = match &m.kind {
        K::Diffuse { reflectance } => vec![rgb(
            "reflectance",
            reflectance.factor,
            UNIT,
            reflectance.texture.is_some(),
        )],
        K::Plastic {
            diffuse,
            specular,
            int_ior,
            ext_ior,
            nonlinear,
        } => vec![
            rgb("diffuse", diffuse.factor, UNIT, diffuse.texture.is_some()),
            rgb("specular", *specular, UNIT, false),
            scalar("int_ior", *int_ior, IOR, false),
            scalar("ext_ior", *ext_ior, IOR, false),
            flag("nonlinear", *nonlinear),
        ],
        K::RoughPlastic {
            diffuse,
            specular,
            alpha,
            distribution: d,
            int_ior,
            ext_ior,
            nonlinear,
        } => vec![
            rgb("diffuse", diffuse.factor, UNIT, diffuse.texture.is_some()),
            rgb("specular", *specular, UNIT, false),
            tex_s("alpha", alpha, ALPHA, true),
            distribution(*d),
            scalar("int_ior", *int_ior, IOR, false),
            scalar("ext_ior", *ext_ior, IOR, false),
            flag("nonlinear", *nonlinear),
        ],
        K::Conductor { eta, k, specular } => vec![
            rgb("eta", *eta, METAL, false),
            rgb("k", *k, METAL, false),
            rgb(
                "specular",
                specular.factor,
                UNIT,
                specular.texture.is_some(),
            ),
        ],
        K::RoughConductor {
            eta,
            k,
            specular,
            alpha_u,
            alpha_v,
            distribution: d,
        } => vec![
            rgb("eta", *eta, METAL, false),
            rgb("k", *k, METAL, false),
            rgb(
                "specular",
                specular.factor,
                UNIT,
                specular.texture.is_some(),
            ),
            tex_s("alpha_u", alpha_u, ALPHA, true),
            tex_s("alpha_v", alpha_v, ALPHA, true),
            distribution(*d),
        ],
        K::Dielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
        }
        | K::ThinDielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
        } => vec![
            scalar("int_ior", *int_ior, IOR, false),
            scalar("ext_ior", *ext_ior, IOR, false),
            rgb("specular_reflectance", *specular_reflectance, UNIT, false),
            rgb(
                "specular_transmittance",
                *specular_transmittance,
                UNIT,
                false,
            ),
        ],
        K::RoughDielectric {
            int_ior,
            ext_ior,
            alpha,
            distribution: d,
            specular_reflectance,
            specular_transmittance,
        } => vec![
            scalar("int_ior", *int_ior, IOR, false),
            scalar("ext_ior", *ext_ior, IOR, false),
            tex_s("alpha", alpha, ALPHA, true),
            distribution(*d),
            rgb("specular_reflectance", *specular_reflectance, UNIT, false),
            rgb(
                "specular_transmittance",
                *specular_transmittance,
                UNIT,
                false,
            ),
        ],
        K::PbrMetallicRoughness {
            base_color,
            metallic,
            roughness,
            transmission,
            ior,
            anisotropy,
            anisotropy_rotation,
            layers,
        } => vec![
            rgb(
                "base_color",
                base_color.factor,
                UNIT,
                base_color.texture.is_some(),
            ),
            tex_s("metallic", metallic, UNIT, false),
            tex_s("roughness", roughness, UNIT, false),
            tex_s("transmission", transmission, UNIT, false),
            scalar("ior", *ior, IOR, false),
            scalar("anisotropy", *anisotropy, UNIT, false),
            scalar(
                "anisotropy_rotation",
                *anisotropy_rotation,
                (-std::f64::consts::PI, std::f64::consts::PI),
                false,
            ),
            scalar("specular", layers.specular, UNIT, false),
            rgb("specular_color", layers.specular_color, (0.0, 10.0), false),
            scalar("clearcoat", layers.clearcoat, UNIT, false),
            scalar(
                "clearcoat_roughness",
                layers.clearcoat_roughness,
                UNIT,
                false,
            ),
            rgb("sheen_color", layers.sheen_color, UNIT, false),
            scalar("sheen_roughness", layers.sheen_roughness, UNIT, false),
        ],
        K::Spec(s) => {
            let mut v = vec![Field {
                name: "spec".to_string(),
                value: FieldValue::Text(s.spec.clone()),
                range: UNIT,
                log: false,
                textured: false,
                choices: &[],
            }];
            if let Some((_, params)) = analytic_spec(&s.spec) {
                v.extend(params.iter().filter_map(|(k, val)| {
                    let x: f64 = val.parse().ok()?;
                    Some(scalar(&format!("spec.{k}"), x, SPEC_RANGE, false))
                }));
            } else {
                v.extend(model_fields(s.bsdf.as_ref()));
            }
            v
        }
    };
    out.push(flag("two_sided", m.two_sided));
    out
}

fn flag(name: &str, b: bool) -> Field {
    Field {
        name: name.to_string(),
        value: FieldValue::Flag(b),
        range: UNIT,
        log: false,
        textured: false,
        choices: &[],
    }
}

/// `MODEL(key=value, …)` split into the model and its (key, value) pairs, in order; `None` for
/// any other specification.
pub fn analytic_spec(spec: &str) -> Option<(String, Vec<(String, String)>)> {
    let s = spec.trim();
    let open = s.find('(')?;
    let inner = s.strip_suffix(')')?.get(open + 1..)?;
    let model = s[..open].trim();
    if model.is_empty() || model.contains(':') {
        return None;
    }
    let mut params = vec![];
    for part in inner.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (k, v) = part.split_once('=')?;
        params.push((k.trim().to_string(), v.trim().to_string()));
    }
    Some((model.to_string(), params))
}

/// The valid range of a spec field (the catalog checks the value).
const SPEC_RANGE: (f64, f64) = (-1e9, 1e9);

fn parse_scalar(field: &str, text: &str, (lo, hi): (f64, f64)) -> std::result::Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("{field}: {text:?} is not a number"))?;
    if !v.is_finite() || v < lo || v > hi {
        return Err(format!("{field}: {v} is outside [{lo}, {hi}]"));
    }
    Ok(v)
}

fn parse_rgb(field: &str, text: &str, range: (f64, f64)) -> std::result::Result<Rgb, String> {
    let parts: Vec<&str> = text.split(',').collect();
    let c = match parts.as_slice() {
        [g] => {
            let v = parse_scalar(field, g, range)?;
            [v; 3]
        }
        [r, g, b] => [
            parse_scalar(field, r, range)?,
            parse_scalar(field, g, range)?,
            parse_scalar(field, b, range)?,
        ],
        _ => return Err(format!("{field}: {text:?} is not one or three numbers")),
    };
    Ok(Rgb(c))
}

/// Sets parameter `field` of `m` to `value` (text, as [`FieldValue::to_text`] writes it).
/// Errors (naming the material and the field; `m` is left as it was): an unknown field, a
/// value that does not parse or lies outside the field's range, a specification that does
/// not resolve, or a combination the model's constructor refuses.
pub fn set(m: &mut Material, field: &str, value: &str) -> Result<()> {
    let err = |why: String| SceneError::material(&m.name, why);
    if field == "spec" && !matches!(m.kind, MaterialKind::Spec(_)) {
        // A swap: any kind becomes the specification's model.
        let r = ResolvedSpec::resolve(&m.name, value.trim())?;
        let mut trial = m.clone();
        trial.set_kind(MaterialKind::Spec(r));
        trial
            .bsdf_at(&[], &[glam::Vec2::ZERO; 2])
            .map_err(|e| SceneError::material(&m.name, format!("spec = {value}: {e}")))?;
        *m = trial;
        return Ok(());
    }
    let known = fields(m);
    let Some(f) = known.iter().find(|f| f.name == field) else {
        let names: Vec<&str> = known.iter().map(|f| f.name.as_str()).collect();
        return Err(err(format!(
            "no parameter {field:?} in a {} material (parameters: {})",
            m.kind.name(),
            names.join(", ")
        )));
    };
    let mut kind = m.kind.clone();
    let mut two_sided = m.two_sided;
    let parsed = match &f.value {
        FieldValue::Scalar(_) => parse_scalar(field, value, f.range).map(FieldValue::Scalar),
        FieldValue::Rgb(_) => parse_rgb(field, value, f.range).map(|c| FieldValue::Rgb(c.0)),
        FieldValue::Choice(_) => {
            let w = value.trim().to_ascii_lowercase();
            if f.choices.contains(&w.as_str()) {
                Ok(FieldValue::Choice(w))
            } else {
                Err(format!("{field}: {value:?} is not one of {:?}", f.choices))
            }
        }
        FieldValue::Flag(_) => match value.trim() {
            "true" | "1" | "on" => Ok(FieldValue::Flag(true)),
            "false" | "0" | "off" => Ok(FieldValue::Flag(false)),
            _ => Err(format!("{field}: {value:?} is not true or false")),
        },
        FieldValue::Text(_) => Ok(FieldValue::Text(value.trim().to_string())),
    }
    .map_err(err)?;
    if field == "two_sided" {
        if let FieldValue::Flag(b) = parsed {
            two_sided = b;
        }
    } else {
        assign(&mut kind, field, &parsed, &m.name).map_err(err)?;
    }
    // Build the model once so that an invalid combination is refused here.
    let mut trial = m.clone();
    trial.set_kind(kind);
    trial.two_sided = two_sided;
    trial
        .bsdf_at(&[], &[glam::Vec2::ZERO; 2])
        .map_err(|e| SceneError::material(&m.name, format!("{field} = {value}: {e}")))?;
    *m = trial;
    Ok(())
}

/// Writes `v` into field `field` of `kind`.
fn assign(
    kind: &mut MaterialKind,
    field: &str,
    v: &FieldValue,
    material: &str,
) -> std::result::Result<(), String> {
    use MaterialKind as K;
    let num = || match v {
        FieldValue::Scalar(x) => *x,
        _ => 0.0,
    };
    let col = || match v {
        FieldValue::Rgb(c) => Rgb(*c),
        _ => Rgb::ZERO,
    };
    let dist = || match v {
        FieldValue::Choice(s) if s == "ggx" => MicrofacetType::Ggx,
        _ => MicrofacetType::Beckmann,
    };
    if let K::Spec(s) = kind {
        if let Some(key) = field.strip_prefix("model.") {
            s.bsdf = Arc::from(set_model(s.bsdf.as_ref(), key, v)?);
            s.edits.push((field.to_string(), v.to_text()));
            return Ok(());
        }
        let spec = match (field, v) {
            ("spec", FieldValue::Text(t)) => t.clone(),
            (_, FieldValue::Scalar(x)) => {
                let key = field.strip_prefix("spec.").unwrap_or(field);
                let (model, params) = analytic_spec(&s.spec).unwrap_or_default();
                let body: Vec<String> = params
                    .iter()
                    .map(|(k, old)| {
                        if k == key {
                            format!("{k}={x}")
                        } else {
                            format!("{k}={old}")
                        }
                    })
                    .collect();
                format!("{model}({})", body.join(", "))
            }
            _ => return Err(format!("{field}: not settable")),
        };
        *s = ResolvedSpec::resolve(material, &spec).map_err(|e| e.to_string())?;
        return Ok(());
    }
    match (kind, field) {
        (K::Diffuse { reflectance: t }, "reflectance")
        | (K::Plastic { diffuse: t, .. }, "diffuse")
        | (K::RoughPlastic { diffuse: t, .. }, "diffuse")
        | (K::Conductor { specular: t, .. }, "specular")
        | (K::RoughConductor { specular: t, .. }, "specular")
        | (K::PbrMetallicRoughness { base_color: t, .. }, "base_color") => t.factor = col(),
        (K::Plastic { specular: c, .. }, "specular")
        | (K::RoughPlastic { specular: c, .. }, "specular")
        | (K::Conductor { eta: c, .. }, "eta")
        | (K::RoughConductor { eta: c, .. }, "eta")
        | (K::Conductor { k: c, .. }, "k")
        | (K::RoughConductor { k: c, .. }, "k")
        | (
            K::Dielectric {
                specular_reflectance: c,
                ..
            },
            "specular_reflectance",
        )
        | (
            K::ThinDielectric {
                specular_reflectance: c,
                ..
            },
            "specular_reflectance",
        )
        | (
            K::RoughDielectric {
                specular_reflectance: c,
                ..
            },
            "specular_reflectance",
        )
        | (
            K::Dielectric {
                specular_transmittance: c,
                ..
            },
            "specular_transmittance",
        )
        | (
            K::ThinDielectric {
                specular_transmittance: c,
                ..
            },
            "specular_transmittance",
        )
        | (
            K::RoughDielectric {
                specular_transmittance: c,
                ..
            },
            "specular_transmittance",
        ) => *c = col(),
        (K::PbrMetallicRoughness { layers, .. }, "specular_color") => layers.specular_color = col(),
        (K::PbrMetallicRoughness { layers, .. }, "sheen_color") => layers.sheen_color = col(),
        (K::PbrMetallicRoughness { layers, .. }, "specular") => layers.specular = num(),
        (K::PbrMetallicRoughness { layers, .. }, "clearcoat") => layers.clearcoat = num(),
        (K::PbrMetallicRoughness { layers, .. }, "clearcoat_roughness") => {
            layers.clearcoat_roughness = num()
        }
        (K::PbrMetallicRoughness { layers, .. }, "sheen_roughness") => {
            layers.sheen_roughness = num()
        }
        (K::RoughPlastic { alpha: t, .. }, "alpha")
        | (K::RoughDielectric { alpha: t, .. }, "alpha")
        | (K::RoughConductor { alpha_u: t, .. }, "alpha_u")
        | (K::RoughConductor { alpha_v: t, .. }, "alpha_v")
        | (K::PbrMetallicRoughness { metallic: t, .. }, "metallic")
        | (K::PbrMetallicRoughness { roughness: t, .. }, "roughness")
        | (
            K::PbrMetallicRoughness {
                transmission: t, ..
            },
            "transmission",
        ) => t.factor = num(),
        (K::Plastic { int_ior: x, .. }, "int_ior")
        | (K::RoughPlastic { int_ior: x, .. }, "int_ior")
        | (K::Dielectric { int_ior: x, .. }, "int_ior")
        | (K::ThinDielectric { int_ior: x, .. }, "int_ior")
        | (K::RoughDielectric { int_ior: x, .. }, "int_ior")
        | (K::Plastic { ext_ior: x, .. }, "ext_ior")
        | (K::RoughPlastic { ext_ior: x, .. }, "ext_ior")
        | (K::Dielectric { ext_ior: x, .. }, "ext_ior")
        | (K::ThinDielectric { ext_ior: x, .. }, "ext_ior")
        | (K::RoughDielectric { ext_ior: x, .. }, "ext_ior")
        | (K::PbrMetallicRoughness { ior: x, .. }, "ior")
        | (K::PbrMetallicRoughness { anisotropy: x, .. }, "anisotropy")
        | (
            K::PbrMetallicRoughness {
                anisotropy_rotation: x,
                ..
            },
            "anisotropy_rotation",
        ) => *x = num(),
        (
            K::RoughPlastic {
                distribution: d, ..
            },
            "distribution",
        )
        | (
            K::RoughConductor {
                distribution: d, ..
            },
            "distribution",
        )
        | (
            K::RoughDielectric {
                distribution: d, ..
            },
            "distribution",
        ) => *d = dist(),
        (K::Plastic { nonlinear: b, .. }, "nonlinear")
        | (K::RoughPlastic { nonlinear: b, .. }, "nonlinear") => {
            *b = matches!(v, FieldValue::Flag(true))
        }
        (_, f) => return Err(format!("{f}: not settable")),
    }
    Ok(())
}

/// The distributions of a fitted Cook–Torrance model's `model.distribution`.
const CT_DISTRIBUTIONS: &[&str] = &["sgd", "beckmann", "ggx"];
/// SGD shape p given to a Beckmann or GGX channel switched to SGD (within the published fits'
/// range).
const SWITCHED_SGD_P: f64 = 0.5;
/// Usual range of a Kurt lobe's or a Cook–Torrance channel's specular weight.
const WEIGHT: (f64, f64) = (0.0, 10.0);
/// Usual range of a Kurt lobe's roughness mx, my.
const KURT_ROUGHNESS: (f64, f64) = (1e-3, 2.0);
/// The SGD shape p over which `lustre fit` searches (−1.9 + 4.8 sigmoid q).
const SGD_P: (f64, f64) = (-1.9, 2.9);

/// `range` widened to hold `values` (a fitted value may lie outside the usual range; the
/// model's constructor is the final check).
fn widened((lo, hi): (f64, f64), values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .filter(|v| v.is_finite())
        .fold((lo, hi), |(a, b), &v| (a.min(v), b.max(v)))
}

/// The width α of a Beckmann, GGX or SGD distribution, its name and SGD's p.
fn ndf_shape(n: &Ndf) -> Option<(&'static str, f64, Option<f64>)> {
    match n {
        Ndf::Sgd(s) => Some(("sgd", s.alpha(), Some(s.p()))),
        Ndf::Beckmann { alpha } => Some(("beckmann", *alpha, None)),
        Ndf::Ggx { alpha } => Some(("ggx", *alpha, None)),
        Ndf::Exponential { .. } => None,
    }
}

/// The parameters of a fitted model, `model.…`: a Kurt model's kd and, per lobe,
/// `reflection[i].{ks, mx, my, r0, alpha}` (and `transmission[i]`), 000 Eq. 3.3–3.6; a
/// Cook–Torrance model's (004 Eq. III.1, V.1, V.5) distribution and its per-channel ρd, ρs,
/// α, SGD's p, F0 and F1 as RGB triples. Nothing for any other BSDF.
fn model_fields(b: &dyn Bsdf) -> Vec<Field> {
    let any = b.as_any();
    if let Some(k) = any.and_then(|a| a.downcast_ref::<Kurt>()) {
        let mut v = vec![rgb("model.kd", k.kd, widened(UNIT, &k.kd.0), false)];
        for (what, lobes) in [
            ("reflection", &k.reflection),
            ("transmission", &k.transmission),
        ] {
            for (i, l) in lobes.iter().enumerate() {
                let name = |p: &str| format!("model.{what}[{i}].{p}");
                v.push(rgb(&name("ks"), l.ks, widened(WEIGHT, &l.ks.0), false));
                v.push(scalar(
                    &name("mx"),
                    l.mx,
                    widened(KURT_ROUGHNESS, &[l.mx]),
                    true,
                ));
                v.push(scalar(
                    &name("my"),
                    l.my,
                    widened(KURT_ROUGHNESS, &[l.my]),
                    true,
                ));
                v.push(scalar(&name("r0"), l.r0, UNIT, false));
                v.push(scalar(&name("alpha"), l.alpha, UNIT, false));
            }
        }
        return v;
    }
    let Some(ct) = any.and_then(|a| a.downcast_ref::<CookTorrance>()) else {
        return vec![];
    };
    let ch = ct.channels();
    let per = |f: &dyn Fn(&CtChannel) -> Option<f64>| -> Option<[f64; 3]> {
        Some([f(&ch[0])?, f(&ch[1])?, f(&ch[2])?])
    };
    let triple = |name: &str, c: [f64; 3], range| rgb(name, Rgb(c), widened(range, &c), false);
    let mut v = vec![];
    let shapes = per(&|c| ndf_shape(&c.ndf).map(|s| s.1));
    let same_kind = ch
        .iter()
        .all(|c| std::mem::discriminant(&c.ndf) == std::mem::discriminant(&ch[0].ndf));
    if let (Some(alpha), true, Some((dist, ..))) = (shapes, same_kind, ndf_shape(&ch[0].ndf)) {
        v.push(Field {
            name: "model.distribution".to_string(),
            value: FieldValue::Choice(dist.to_string()),
            range: UNIT,
            log: false,
            textured: false,
            choices: CT_DISTRIBUTIONS,
        });
        v.push(Field {
            log: true,
            ..triple("model.alpha", alpha, (1e-3, 1.0))
        });
        if let Some(p) = per(&|c| ndf_shape(&c.ndf).and_then(|s| s.2)) {
            v.push(triple("model.p", p, SGD_P));
        }
    }
    if let Some(x) = per(&|c| Some(c.rho_d)) {
        v.push(triple("model.rho_d", x, UNIT));
    }
    if let Some(x) = per(&|c| Some(c.rho_s)) {
        v.push(triple("model.rho_s", x, WEIGHT));
    }
    if let Some(f0) = per(&|c| c.fresnel.generalized_schlick_form().map(|f| f.0)) {
        v.push(triple("model.f0", f0, UNIT));
    }
    if let Some(f1) = per(&|c| c.fresnel.generalized_schlick_form().map(|f| f.1)) {
        v.push(triple("model.f1", f1, (-1.0, 1.0)));
    }
    v
}

/// A channel's distribution after an edit: SGD normalized (kap = 1/(αΓ(1−p, α)), 004
/// Eq. V.2) with its shadowing kept in kind — an Eq. V.3 approximation is fitted anew to the
/// new distribution (§V.3.3, as `lustre fit` does; also for a channel switched from Beckmann
/// or GGX, so that the GPU layout holds it), a numeric Smith G1 recomputed, none kept;
/// Beckmann and GGX with the closed-form Smith G1 (or none, if the channel had none).
fn reshaped(dist: &str, alpha: f64, p: f64, old: &G1Model) -> lustre_brdf::Result<(Ndf, G1Model)> {
    Ok(match dist {
        "sgd" => {
            let ndf = Ndf::sgd(alpha, p)?;
            let g1 = match old {
                G1Model::None => G1Model::None,
                G1Model::Numeric(_) => G1Model::numeric(&ndf),
                G1Model::SgdApprox(_) | G1Model::Closed => {
                    G1Model::SgdApprox(SgdG1Approx::fit(&G1Table::new(&ndf)).0)
                }
            };
            (ndf, g1)
        }
        d => {
            let ndf = if d == "ggx" {
                Ndf::ggx(alpha)?
            } else {
                Ndf::beckmann(alpha)?
            };
            let g1 = match old {
                G1Model::None => G1Model::None,
                _ => G1Model::Closed,
            };
            (ndf, g1)
        }
    })
}

/// The fitted model `b` with `model.KEY` set to `v` (see [`model_fields`]); parameters the
/// edit does not touch keep their exact values (a published fit's θ0 included).
fn set_model(
    b: &dyn Bsdf,
    key: &str,
    v: &FieldValue,
) -> std::result::Result<Box<dyn Bsdf>, String> {
    let num = match v {
        FieldValue::Scalar(x) => *x,
        _ => f64::NAN,
    };
    let col = match v {
        FieldValue::Rgb(c) => *c,
        _ => [f64::NAN; 3],
    };
    let unknown = || format!("model.{key}: not settable");
    let any = b.as_any();
    if let Some(k) = any.and_then(|a| a.downcast_ref::<Kurt>()) {
        let mut k = k.clone();
        if key == "kd" {
            k.kd = Rgb(col);
        } else {
            let (what, rest) = key.split_once('[').ok_or_else(unknown)?;
            let (i, param) = rest.split_once("].").ok_or_else(unknown)?;
            let i: usize = i.parse().map_err(|_| unknown())?;
            let lobes = match what {
                "reflection" => &mut k.reflection,
                "transmission" => &mut k.transmission,
                _ => return Err(unknown()),
            };
            let l = lobes.get_mut(i).ok_or_else(unknown)?;
            match param {
                "ks" => l.ks = Rgb(col),
                "mx" => l.mx = num,
                "my" => l.my = num,
                "r0" => l.r0 = num,
                "alpha" => l.alpha = num,
                _ => return Err(unknown()),
            }
        }
        return Kurt::new(k.kd, k.reflection, k.transmission)
            .map(|k| Box::new(k) as Box<dyn Bsdf>)
            .map_err(|e| format!("model.{key}: {e}"));
    }
    let ct = any
        .and_then(|a| a.downcast_ref::<CookTorrance>())
        .ok_or_else(unknown)?;
    let mut ch = ct.channels().clone();
    let model = |e: lustre_brdf::Error| format!("model.{key}: {e}");
    match key {
        "rho_d" => (0..3).for_each(|c| ch[c].rho_d = col[c]),
        "rho_s" => (0..3).for_each(|c| ch[c].rho_s = col[c]),
        "f0" | "f1" => {
            for (c, q) in ch.iter_mut().enumerate() {
                let (mut f0, mut f1) = q.fresnel.generalized_schlick_form().ok_or_else(unknown)?;
                if key == "f0" {
                    f0 = col[c];
                } else {
                    f1 = col[c];
                }
                q.fresnel = Fresnel::generalized_schlick(f0, f1).map_err(model)?;
            }
        }
        "alpha" | "p" | "distribution" => {
            // Equal channels share one distribution (and one shadowing fit).
            let mut done: Vec<(usize, (String, u64, u64))> = vec![];
            for c in 0..3 {
                let (dist, mut alpha, p) = ndf_shape(&ch[c].ndf).ok_or_else(unknown)?;
                let mut p = p.unwrap_or(SWITCHED_SGD_P);
                let mut dist = dist.to_string();
                match (key, v) {
                    ("alpha", _) => alpha = col[c],
                    ("p", _) => p = col[c],
                    (_, FieldValue::Choice(d)) => dist = d.clone(),
                    _ => return Err(unknown()),
                }
                let id = (dist.clone(), alpha.to_bits(), p.to_bits());
                if let Some(&(e, _)) = done.iter().find(|(_, k)| *k == id) {
                    ch[c].ndf = ch[e].ndf;
                    ch[c].g1 = ch[e].g1.clone();
                    continue;
                }
                (ch[c].ndf, ch[c].g1) = reshaped(&dist, alpha, p, &ch[c].g1).map_err(model)?;
                done.push((c, id));
            }
        }
        _ => return Err(unknown()),
    }
    CookTorrance::new(ct.name(), ch)
        .map(|m| Box::new(m) as Box<dyn Bsdf>)
        .map_err(model)
}

/// Parses `NAME.FIELD=VALUE` (`lustre render --set`, a scene file's `[material_params]` key
/// and value joined) into its three parts.
pub fn parse_assignment(text: &str) -> std::result::Result<(String, String, String), String> {
    let (lhs, value) = text
        .split_once('=')
        .ok_or_else(|| format!("{text:?} is not MATERIAL.PARAMETER=VALUE"))?;
    let (name, field) = lhs
        .trim()
        .split_once('.')
        .ok_or_else(|| format!("{lhs:?} is not MATERIAL.PARAMETER"))?;
    if name.is_empty() || field.is_empty() {
        return Err(format!("{lhs:?} is not MATERIAL.PARAMETER"));
    }
    Ok((
        name.to_string(),
        field.to_string(),
        value.trim().to_string(),
    ))
}

/// Sets `field` to `value` in every material of `materials` named `name`. Errors: no material
/// of that name (listing the names), or [`set`]'s.
pub fn set_named(materials: &mut [Material], name: &str, field: &str, value: &str) -> Result<()> {
    let mut found = false;
    for m in materials.iter_mut().filter(|m| m.name == name) {
        set(m, field, value)?;
        found = true;
    }
    if found {
        Ok(())
    } else {
        let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
        Err(SceneError::material(
            name,
            format!("no material of that name (materials: {})", names.join(", ")),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{TexturedRgb, TexturedScalar};

    fn plastic() -> Material {
        Material::new(
            "floor",
            MaterialKind::RoughPlastic {
                diffuse: TexturedRgb::constant(Rgb([0.2, 0.1, 0.1])),
                specular: Rgb::ONE,
                alpha: TexturedScalar::constant(0.04),
                distribution: MicrofacetType::Ggx,
                int_ior: 1.5,
                ext_ior: 1.0,
                nonlinear: false,
            },
        )
    }

    #[test]
    fn every_listed_field_can_be_set_to_its_own_value() {
        let kinds = [
            plastic(),
            Material::diffuse("d", Rgb([0.5, 0.5, 0.5])),
            Material::new(
                "s",
                MaterialKind::Spec(
                    ResolvedSpec::resolve("s", "kurt(kd=0.1, ks=0.5, mx=0.1, my=0.2, r0=0.9)")
                        .unwrap(),
                ),
            ),
            spec("sgd:gold-metallic-paint"),
            spec("beckmann(rho_d=0.1, rho_s=0.5, alpha=0.2)"),
            spec("kurt-glass"),
        ];
        for m in kinds {
            for f in fields(&m) {
                let mut n = m.clone();
                set(&mut n, &f.name, &f.value.to_text()).unwrap();
                assert_eq!(fields(&n), fields(&m), "{} {}", m.name, f.name);
            }
        }
    }

    fn spec(spec: &str) -> Material {
        Material::new(
            "s",
            MaterialKind::Spec(ResolvedSpec::resolve("s", spec).unwrap()),
        )
    }

    fn bsdf(m: &Material) -> Arc<dyn Bsdf> {
        match &m.kind {
            MaterialKind::Spec(s) => s.bsdf.clone(),
            k => panic!("{k:?}"),
        }
    }

    /// The channels of a Cook–Torrance spec material.
    fn channels(m: &Material) -> [CtChannel; 3] {
        bsdf(m)
            .as_any()
            .and_then(|a| a.downcast_ref::<CookTorrance>())
            .unwrap()
            .channels()
            .clone()
    }

    fn names(m: &Material) -> Vec<String> {
        fields(m).into_iter().map(|f| f.name).collect()
    }

    /// Directions of a few reflection pairs, off the mirror direction and on it.
    fn pairs() -> Vec<(glam::DVec3, glam::DVec3)> {
        let d = |t: f64, p: f64| glam::DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
        vec![
            (d(0.3, 0.0), d(0.3, std::f64::consts::PI)),
            (d(1.0, 0.5), d(0.7, 3.0)),
            (d(0.1, 0.0), d(1.2, 1.0)),
        ]
    }

    #[test]
    fn a_published_sgd_fit_edits_channel_by_channel() {
        let m = spec("sgd:gold-metallic-paint");
        assert_eq!(
            names(&m),
            [
                "spec",
                "model.distribution",
                "model.alpha",
                "model.p",
                "model.rho_d",
                "model.rho_s",
                "model.f0",
                "model.f1",
                "two_sided"
            ]
        );
        // ρd: f changes by Δρd/π per channel (004 Eq. III.1) and nothing else moves (the
        // published θ0 of the shadowing is kept).
        let old = bsdf(&m);
        let before = channels(&m);
        let mut e = m.clone();
        set(&mut e, "model.rho_d", "0.5,0.25,0.125").unwrap();
        let new = bsdf(&e);
        for (wi, wo) in pairs() {
            let (a, b) = (old.eval(wi, wo), new.eval(wi, wo));
            for (c, rd) in [0.5, 0.25, 0.125].into_iter().enumerate() {
                let want = a[c] + (rd - before[c].rho_d) / std::f64::consts::PI;
                assert!(
                    (b[c] - want).abs() <= 1e-12 * (1.0 + want.abs()),
                    "{b:?} {want}"
                );
            }
        }
        assert_ne!(e, m, "an edit makes the material differ");
        match &e.kind {
            MaterialKind::Spec(s) => {
                assert_eq!(s.spec, "sgd:gold-metallic-paint");
                assert_eq!(
                    s.edits,
                    [("model.rho_d".to_string(), "0.5,0.25,0.125".to_string())]
                );
            }
            k => panic!("{k:?}"),
        }
        // α: a normalized SGD (kap·α·Γ(1−p, α) = 1) with the Eq. V.3 shadowing refitted.
        set(&mut e, "model.alpha", "0.05,0.05,0.05").unwrap();
        let ch = channels(&e);
        for (c, q) in ch.iter().enumerate() {
            let Ndf::Sgd(s) = q.ndf else {
                panic!("{:?}", q.ndf)
            };
            assert_eq!(s.alpha(), 0.05);
            assert_eq!(Some(s.p()), ndf_shape(&before[c].ndf).and_then(|x| x.2));
            assert!((s.kap() * s.alpha() * s.gamma0() - 1.0).abs() < 1e-12);
            let G1Model::SgdApprox(a) = &q.g1 else {
                panic!("{:?}", q.g1)
            };
            let table = G1Table::new(&q.ndf);
            assert!(a.l2_error(&table) < 1e-3, "{}", a.l2_error(&table));
        }
        // Switching the distribution: GGX with the closed-form G1, then back to SGD.
        set(&mut e, "model.distribution", "ggx").unwrap();
        let q = &channels(&e)[1];
        assert_eq!((q.ndf, &q.g1), (Ndf::Ggx { alpha: 0.05 }, &G1Model::Closed));
        assert!(!names(&e).contains(&"model.p".to_string()));
        set(&mut e, "model.distribution", "sgd").unwrap();
        let q = &channels(&e)[2];
        assert!(matches!(q.g1, G1Model::SgdApprox(_)), "{:?}", q.g1);
        assert_eq!(q.ndf, Ndf::sgd(0.05, SWITCHED_SGD_P).unwrap());
        // Refused, the material unchanged: out of range, not a triple, no such choice.
        let kept = e.clone();
        for (f, v) in [
            ("model.rho_s", "-1,0,0"),
            ("model.alpha", "0,0.1,0.1"),
            ("model.p", "5,0,0"),
            ("model.rho_d", "0.5,0.5"),
            ("model.distribution", "phong"),
            ("model.kd", "0.1,0.1,0.1"),
        ] {
            let r = set(&mut e, f, v);
            assert!(r.is_err(), "{f} = {v} accepted");
            assert_eq!(e, kept, "{f} = {v} changed the material");
        }
    }

    #[test]
    fn a_kurt_model_edits_lobe_by_lobe() {
        let m = spec("kurt-glass");
        let n = names(&m);
        for f in [
            "model.kd",
            "model.reflection[0].ks",
            "model.reflection[0].mx",
            "model.reflection[0].my",
            "model.reflection[0].r0",
            "model.reflection[0].alpha",
            "model.transmission[0].ks",
            "model.transmission[0].alpha",
        ] {
            assert!(n.iter().any(|x| x == f), "{f} not in {n:?}");
        }
        let mut e = m.clone();
        set(&mut e, "model.transmission[0].my", "0.3").unwrap();
        set(&mut e, "model.kd", "0.2,0.1,0").unwrap();
        let b = bsdf(&e);
        let k = b.as_any().and_then(|a| a.downcast_ref::<Kurt>()).unwrap();
        assert_eq!(k.transmission[0].my, 0.3);
        assert_eq!(k.kd, Rgb([0.2, 0.1, 0.0]));
        let old = bsdf(&m);
        let o = old.as_any().and_then(|a| a.downcast_ref::<Kurt>()).unwrap();
        assert_eq!(k.reflection, o.reflection);
        assert_eq!(k.transmission[0].mx, o.transmission[0].mx);
        let kept = e.clone();
        for (f, v) in [
            ("model.reflection[0].r0", "1.5"),
            ("model.reflection[0].mx", "0"),
            ("model.reflection[7].mx", "0.1"),
            ("model.kd", "-0.1,0,0"),
            ("model.rho_d", "0.1,0.1,0.1"),
        ] {
            assert!(set(&mut e, f, v).is_err(), "{f} = {v} accepted");
            assert_eq!(e, kept);
        }
    }

    #[test]
    fn a_swap_drops_the_edits_and_an_analytic_spec_keeps_its_own_fields() {
        let mut m = spec("sgd:gold-metallic-paint");
        set(&mut m, "model.rho_s", "1,1,1").unwrap();
        set(&mut m, "spec", "ggx(rho_d=0.1, rho_s=0.5, alpha=0.2)").unwrap();
        match &m.kind {
            MaterialKind::Spec(s) => assert!(s.edits.is_empty()),
            k => panic!("{k:?}"),
        }
        // `MODEL(key=value, …)` is edited through its own keys, not `model.…`.
        assert!(names(&m).iter().all(|f| !f.starts_with("model.")));
        assert!(names(&m).contains(&"spec.alpha".to_string()));
    }

    #[test]
    fn set_changes_the_model_and_refuses_bad_values() {
        let mut m = plastic();
        set(&mut m, "alpha", "0.3").unwrap();
        match &m.kind {
            MaterialKind::RoughPlastic { alpha, .. } => assert_eq!(alpha.factor, 0.3),
            k => panic!("{k:?}"),
        }
        set(&mut m, "diffuse", "0.5,0.25,0").unwrap();
        set(&mut m, "distribution", "beckmann").unwrap();
        set(&mut m, "two_sided", "true").unwrap();
        assert!(m.two_sided);
        // Any kind can be swapped for a specification.
        let mut swapped = m.clone();
        set(&mut swapped, "spec", "kurt-demo").unwrap();
        assert!(matches!(&swapped.kind, MaterialKind::Spec(s) if s.spec == "kurt-demo"));
        assert!(swapped.two_sided);
        let before = m.clone();
        for (f, v, says) in [
            ("alpha", "NaN", "outside"),
            ("alpha", "2", "outside"),
            ("diffuse", "0.1,0.2", "three"),
            ("distribution", "phong", "one of"),
            ("roughness", "0.1", "no parameter"),
            ("alpha", "rough", "not a number"),
        ] {
            let e = set(&mut m, f, v).unwrap_err().to_string();
            assert!(e.contains(says) && e.contains("floor"), "{f}={v}: {e}");
            assert_eq!(m, before);
        }
    }

    #[test]
    fn spec_fields_rewrite_the_spec_and_swap_it() {
        let mut m = Material::new(
            "s",
            MaterialKind::Spec(
                ResolvedSpec::resolve("s", "ggx(rho_d=0.1, rho_s=0.5, alpha=0.2)").unwrap(),
            ),
        );
        let names: Vec<String> = fields(&m).into_iter().map(|f| f.name).collect();
        assert_eq!(
            names,
            [
                "spec",
                "spec.rho_d",
                "spec.rho_s",
                "spec.alpha",
                "two_sided"
            ]
        );
        set(&mut m, "spec.alpha", "0.05").unwrap();
        match &m.kind {
            MaterialKind::Spec(s) => assert_eq!(s.spec, "ggx(rho_d=0.1, rho_s=0.5, alpha=0.05)"),
            k => panic!("{k:?}"),
        }
        set(&mut m, "spec", "kurt-demo").unwrap();
        let names: Vec<String> = fields(&m).into_iter().map(|f| f.name).collect();
        assert_eq!(names[..2], ["spec", "model.kd"]);
        let e = set(&mut m, "spec", "nope:thing").unwrap_err().to_string();
        assert!(e.contains("nope:thing"), "{e}");
    }

    #[test]
    fn assignments_parse_and_name_materials() {
        assert_eq!(
            parse_assignment("floor.alpha=0.2").unwrap(),
            ("floor".into(), "alpha".into(), "0.2".into())
        );
        assert!(parse_assignment("floor=0.2").is_err());
        assert!(parse_assignment(".alpha=0.2").is_err());
        let mut ms = vec![plastic()];
        set_named(&mut ms, "floor", "alpha", "0.1").unwrap();
        let e = set_named(&mut ms, "wall", "alpha", "0.1")
            .unwrap_err()
            .to_string();
        assert!(e.contains("materials: floor"), "{e}");
    }
}
