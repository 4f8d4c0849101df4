//! What a glTF cannot say, said exactly: lustre's materials, cameras, camera paths and
//! environment as JSON for the `extras` of an exported scene, and read back from them, so that a
//! scene exported by [`super::scene`] reloads into lustre unchanged.
//!
//! A material is `{ "kind": NAME, …its parameters… }` in the field names of
//! [`MaterialKind`] (Mitsuba's), with `two_sided`, `alpha_mask`, `normal_map` and
//! `emission_texture` beside them. A textured parameter is `{ "factor": …, "texture": { "index":
//! glTF texture, "uv_set": 0|1 }, "channel": c }` (no `texture` when constant, no `channel` for
//! colours). A camera is `{ name, position, forward, up, fov_deg, fov_axis, aspect }`.

use crate::camera::{Camera, CameraPath, FovAxis, Keyframe};
use crate::environment::{Environment, EnvironmentSource, Sky};
use crate::error::{Result, SceneError};
use crate::material::MicrofacetType;
use crate::material::{
    AlphaMask, Material, MaterialKind, NormalMap, ResolvedSpec, TextureRef, TexturedRgb,
    TexturedScalar,
};
use glam::{DMat3, DVec3};
use lustre_brdf::models::pbr_metallic_roughness::PbrLayers;
use lustre_brdf::Rgb;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn texture_ref(t: Option<TextureRef>, tex: &dyn Fn(usize) -> usize) -> Value {
    match t {
        Some(t) => json!({ "index": tex(t.texture), "uv_set": t.uv_set }),
        None => Value::Null,
    }
}

fn rgb_json(c: &TexturedRgb, tex: &dyn Fn(usize) -> usize) -> Value {
    json!({ "factor": c.factor.0, "texture": texture_ref(c.texture, tex) })
}

fn scalar_json(s: &TexturedScalar, tex: &dyn Fn(usize) -> usize) -> Value {
    json!({ "factor": s.factor, "texture": texture_ref(s.texture, tex), "channel": s.channel })
}

/// `m` as JSON; `tex` maps a scene texture index to the glTF texture index that carries it.
pub fn material_to_json(m: &Material, tex: &dyn Fn(usize) -> usize) -> Value {
    let d = |t: &MicrofacetType| t.name();
    let mut v = match &m.kind {
        MaterialKind::Diffuse { reflectance } => {
            json!({ "reflectance": rgb_json(reflectance, tex) })
        }
        MaterialKind::Plastic {
            diffuse,
            specular,
            int_ior,
            ext_ior,
            nonlinear,
        } => json!({
            "diffuse": rgb_json(diffuse, tex), "specular": specular.0, "int_ior": int_ior,
            "ext_ior": ext_ior, "nonlinear": nonlinear,
        }),
        MaterialKind::RoughPlastic {
            diffuse,
            specular,
            alpha,
            distribution,
            int_ior,
            ext_ior,
            nonlinear,
        } => json!({
            "diffuse": rgb_json(diffuse, tex), "specular": specular.0,
            "alpha": scalar_json(alpha, tex), "distribution": d(distribution),
            "int_ior": int_ior, "ext_ior": ext_ior, "nonlinear": nonlinear,
        }),
        MaterialKind::Conductor { eta, k, specular } => json!({
            "eta": eta.0, "k": k.0, "specular": rgb_json(specular, tex),
        }),
        MaterialKind::RoughConductor {
            eta,
            k,
            specular,
            alpha_u,
            alpha_v,
            distribution,
        } => json!({
            "eta": eta.0, "k": k.0, "specular": rgb_json(specular, tex),
            "alpha_u": scalar_json(alpha_u, tex), "alpha_v": scalar_json(alpha_v, tex),
            "distribution": d(distribution),
        }),
        MaterialKind::Dielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
        }
        | MaterialKind::ThinDielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
        } => json!({
            "int_ior": int_ior, "ext_ior": ext_ior,
            "specular_reflectance": specular_reflectance.0,
            "specular_transmittance": specular_transmittance.0,
        }),
        MaterialKind::RoughDielectric {
            int_ior,
            ext_ior,
            alpha,
            distribution,
            specular_reflectance,
            specular_transmittance,
        } => json!({
            "int_ior": int_ior, "ext_ior": ext_ior, "alpha": scalar_json(alpha, tex),
            "distribution": d(distribution),
            "specular_reflectance": specular_reflectance.0,
            "specular_transmittance": specular_transmittance.0,
        }),
        MaterialKind::PbrMetallicRoughness {
            base_color,
            metallic,
            roughness,
            transmission,
            ior,
            anisotropy,
            anisotropy_rotation,
            layers,
        } => json!({
            "base_color": rgb_json(base_color, tex), "metallic": scalar_json(metallic, tex),
            "roughness": scalar_json(roughness, tex), "transmission": scalar_json(transmission, tex),
            "ior": ior, "anisotropy": anisotropy, "anisotropy_rotation": anisotropy_rotation,
            "layers": layers,
        }),
        MaterialKind::Spec(s) => json!({ "spec": s.spec, "edits": s.edits }),
    };
    v["kind"] = json!(m.kind.name());
    v["two_sided"] = json!(m.two_sided);
    if let Some(a) = &m.alpha_mask {
        v["alpha_mask"] = json!({ "opacity": scalar_json(&a.opacity, tex), "cutoff": a.cutoff });
    }
    if let Some(n) = &m.normal_map {
        v["normal_map"] = json!({ "texture": texture_ref(Some(n.texture), tex), "scale": n.scale });
    }
    if let Some(t) = m.emission_texture {
        v["emission_texture"] = texture_ref(Some(t), tex);
    }
    v
}

/// Reads the JSON of [`material_to_json`]: `tex(glTF texture index, uv set)` loads a texture.
/// Errors name the material and the field.
pub fn material_from_json(
    name: &str,
    v: &Value,
    tex: &mut dyn FnMut(usize, u8) -> Result<TextureRef>,
) -> Result<Material> {
    let err = |p: String| SceneError::material(name, format!("lustre extras: {p}"));
    let f = |k: &str| -> Result<f64> {
        v.get(k)
            .and_then(Value::as_f64)
            .filter(|x| x.is_finite())
            .ok_or_else(|| err(format!("{k} missing or not a finite number")))
    };
    let rgb_of = |x: Option<&Value>, k: &str| -> Result<Rgb> {
        let a = x
            .and_then(Value::as_array)
            .filter(|a| a.len() == 3)
            .ok_or_else(|| err(format!("{k} must be 3 numbers")))?;
        let mut c = [0.0; 3];
        for (o, x) in c.iter_mut().zip(a) {
            *o = x
                .as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| err(format!("{k} must be 3 finite numbers")))?;
        }
        Ok(Rgb(c))
    };
    let rgb = |k: &str| rgb_of(v.get(k), k);
    let mut tref = |x: &Value, k: &str| -> Result<Option<TextureRef>> {
        if x.is_null() {
            return Ok(None);
        }
        let index = x.get("index").and_then(Value::as_u64);
        let uv = x.get("uv_set").and_then(Value::as_u64).filter(|u| *u <= 1);
        match (index, uv) {
            (Some(i), Some(u)) => Ok(Some(tex(i as usize, u as u8)?)),
            _ => Err(err(format!(
                "{k}.texture needs an index and a uv_set of 0 or 1"
            ))),
        }
    };
    let mut trgb = |k: &str| -> Result<TexturedRgb> {
        let x = v.get(k).ok_or_else(|| err(format!("{k} missing")))?;
        Ok(TexturedRgb {
            factor: rgb_of(x.get("factor"), k)?,
            texture: tref(x.get("texture").unwrap_or(&Value::Null), k)?,
        })
    };
    let scalar = |x: &Value,
                  k: &str,
                  tref: &mut dyn FnMut(&Value, &str) -> Result<Option<TextureRef>>|
     -> Result<TexturedScalar> {
        Ok(TexturedScalar {
            factor: x
                .get("factor")
                .and_then(Value::as_f64)
                .filter(|x| x.is_finite())
                .ok_or_else(|| err(format!("{k}.factor missing or not finite")))?,
            texture: tref(x.get("texture").unwrap_or(&Value::Null), k)?,
            channel: x
                .get("channel")
                .and_then(Value::as_u64)
                .filter(|c| *c <= 3)
                .ok_or_else(|| err(format!("{k}.channel must be 0 … 3")))?
                as u8,
        })
    };
    let kind_name = v.get("kind").and_then(Value::as_str).unwrap_or("");
    let dist = || -> Result<MicrofacetType> {
        let s = v.get("distribution").and_then(Value::as_str).unwrap_or("");
        MicrofacetType::parse(s).map_err(|e| err(format!("distribution: {e}")))
    };
    let b = |k: &str| v.get(k).and_then(Value::as_bool).unwrap_or(false);
    let kind = match kind_name {
        "diffuse" => MaterialKind::Diffuse {
            reflectance: trgb("reflectance")?,
        },
        "plastic" => MaterialKind::Plastic {
            diffuse: trgb("diffuse")?,
            specular: rgb("specular")?,
            int_ior: f("int_ior")?,
            ext_ior: f("ext_ior")?,
            nonlinear: b("nonlinear"),
        },
        "roughplastic" => {
            let diffuse = trgb("diffuse")?;
            let a = v.get("alpha").ok_or_else(|| err("alpha missing".into()))?;
            MaterialKind::RoughPlastic {
                diffuse,
                specular: rgb("specular")?,
                alpha: scalar(a, "alpha", &mut tref)?,
                distribution: dist()?,
                int_ior: f("int_ior")?,
                ext_ior: f("ext_ior")?,
                nonlinear: b("nonlinear"),
            }
        }
        "conductor" => MaterialKind::Conductor {
            eta: rgb("eta")?,
            k: rgb("k")?,
            specular: trgb("specular")?,
        },
        "roughconductor" => {
            let specular = trgb("specular")?;
            let au = v
                .get("alpha_u")
                .ok_or_else(|| err("alpha_u missing".into()))?;
            let av = v
                .get("alpha_v")
                .ok_or_else(|| err("alpha_v missing".into()))?;
            MaterialKind::RoughConductor {
                eta: rgb("eta")?,
                k: rgb("k")?,
                specular,
                alpha_u: scalar(au, "alpha_u", &mut tref)?,
                alpha_v: scalar(av, "alpha_v", &mut tref)?,
                distribution: dist()?,
            }
        }
        "dielectric" => MaterialKind::Dielectric {
            int_ior: f("int_ior")?,
            ext_ior: f("ext_ior")?,
            specular_reflectance: rgb("specular_reflectance")?,
            specular_transmittance: rgb("specular_transmittance")?,
        },
        "thindielectric" => MaterialKind::ThinDielectric {
            int_ior: f("int_ior")?,
            ext_ior: f("ext_ior")?,
            specular_reflectance: rgb("specular_reflectance")?,
            specular_transmittance: rgb("specular_transmittance")?,
        },
        "roughdielectric" => {
            let a = v.get("alpha").ok_or_else(|| err("alpha missing".into()))?;
            MaterialKind::RoughDielectric {
                int_ior: f("int_ior")?,
                ext_ior: f("ext_ior")?,
                alpha: scalar(a, "alpha", &mut tref)?,
                distribution: dist()?,
                specular_reflectance: rgb("specular_reflectance")?,
                specular_transmittance: rgb("specular_transmittance")?,
            }
        }
        "pbr" => {
            let base_color = trgb("base_color")?;
            let mut sc = |k: &str| -> Result<TexturedScalar> {
                let x = v.get(k).ok_or_else(|| err(format!("{k} missing")))?;
                scalar(x, k, &mut tref)
            };
            MaterialKind::PbrMetallicRoughness {
                base_color,
                metallic: sc("metallic")?,
                roughness: sc("roughness")?,
                transmission: sc("transmission")?,
                ior: f("ior")?,
                anisotropy: f("anisotropy")?,
                anisotropy_rotation: f("anisotropy_rotation")?,
                layers: match v.get("layers") {
                    None => PbrLayers::default(),
                    Some(l) => {
                        let l: PbrLayers = serde_json::from_value(l.clone())
                            .map_err(|e| err(format!("layers: {e}")))?;
                        l.validate().map_err(|e| err(format!("layers: {e}")))?;
                        l
                    }
                },
            }
        }
        "spec" => {
            let spec = v
                .get("spec")
                .and_then(Value::as_str)
                .ok_or_else(|| err("spec missing".into()))?;
            let edits: Vec<(String, String)> =
                serde_json::from_value(v.get("edits").cloned().unwrap_or(json!([])))
                    .map_err(|e| err(format!("edits: {e}")))?;
            let mut resolved = ResolvedSpec::resolve(name, spec)?;
            if !edits.is_empty() {
                let mut m = Material::new(name, MaterialKind::Spec(resolved));
                for (field, value) in &edits {
                    crate::material_edit::set(&mut m, field, value)
                        .map_err(|e| err(format!("edit {field} = {value}: {e}")))?;
                }
                let MaterialKind::Spec(s) = m.kind else {
                    return Err(err("an edit changed the material's kind".into()));
                };
                resolved = s;
            }
            MaterialKind::Spec(resolved)
        }
        other => return Err(err(format!("unknown kind {other:?}"))),
    };
    let mut m = Material::new(name, kind);
    m.two_sided = b("two_sided");
    if let Some(a) = v.get("alpha_mask").filter(|a| !a.is_null()) {
        let o = a
            .get("opacity")
            .ok_or_else(|| err("alpha_mask.opacity missing".into()))?;
        m.alpha_mask = Some(AlphaMask {
            opacity: scalar(o, "alpha_mask.opacity", &mut tref)?,
            cutoff: a.get("cutoff").and_then(Value::as_f64).map(|c| c as f32),
        });
    }
    if let Some(n) = v.get("normal_map").filter(|n| !n.is_null()) {
        let texture = tref(n.get("texture").unwrap_or(&Value::Null), "normal_map")?
            .ok_or_else(|| err("normal_map.texture missing".into()))?;
        let scale = n.get("scale").and_then(Value::as_f64).unwrap_or(1.0) as f32;
        m.normal_map = Some(NormalMap { texture, scale });
    }
    if let Some(t) = v.get("emission_texture") {
        m.emission_texture = tref(t, "emission_texture")?;
    }
    Ok(m)
}

/// `c` as JSON.
pub fn camera_to_json(c: &Camera) -> Value {
    json!({
        "name": c.name, "position": c.position.to_array(), "forward": c.forward.to_array(),
        "up": c.up.to_array(), "fov_deg": c.fov_deg, "fov_axis": c.fov_axis, "aspect": c.aspect,
    })
}

fn vec3(v: &Value, k: &str) -> Option<DVec3> {
    let a = v.get(k)?.as_array()?;
    if a.len() != 3 {
        return None;
    }
    let x: Vec<f64> = a.iter().filter_map(Value::as_f64).collect();
    (x.len() == 3)
        .then(|| DVec3::new(x[0], x[1], x[2]))
        .filter(|p| p.is_finite())
}

/// Reads the JSON of [`camera_to_json`]; `None` when it is not a valid camera.
pub fn camera_from_json(v: &Value) -> Option<Camera> {
    let name = v.get("name")?.as_str()?;
    let position = vec3(v, "position")?;
    let forward = vec3(v, "forward")?;
    let up = vec3(v, "up")?;
    let fov = v.get("fov_deg")?.as_f64()?;
    let axis: FovAxis = serde_json::from_value(v.get("fov_axis")?.clone()).ok()?;
    let mut c = Camera::look_at(name, position, position + forward, up, fov, axis)?;
    // Exactly as written (look_at re-orthogonalises, which may move the last bit).
    c.forward = forward;
    c.up = up;
    c.aspect = v.get("aspect").and_then(Value::as_f64);
    Some(c)
}

/// `p` as JSON (its keyframes' cameras in full).
pub fn path_to_json(p: &CameraPath) -> Value {
    let keys: Vec<Value> = p
        .keyframes
        .iter()
        .map(|k| json!({ "time": k.time, "camera": camera_to_json(&k.camera) }))
        .collect();
    json!({ "name": p.name, "looped": p.looped, "keyframes": keys })
}

/// Reads the JSON of [`path_to_json`]; `None` when it is not a valid path.
pub fn path_from_json(v: &Value) -> Option<CameraPath> {
    let keyframes: Option<Vec<Keyframe>> = v
        .get("keyframes")?
        .as_array()?
        .iter()
        .map(|k| {
            Some(Keyframe {
                time: k.get("time")?.as_f64().filter(|t| t.is_finite())?,
                camera: camera_from_json(k.get("camera")?)?,
            })
        })
        .collect();
    let keyframes =
        keyframes.filter(|k| !k.is_empty() && k.windows(2).all(|w| w[1].time > w[0].time))?;
    Some(CameraPath {
        name: v.get("name")?.as_str()?.to_string(),
        keyframes,
        looped: v.get("looped")?.as_bool()?,
    })
}

/// `e` as JSON: its source (a map as the glTF texture `map_texture` that carries it, or by its
/// path when there is none; a constant; the sky), rotation and intensity.
pub fn environment_to_json(e: &Environment, map_texture: Option<usize>) -> Value {
    let source = match (&e.source, map_texture) {
        (EnvironmentSource::Map { path, .. }, Some(t)) => {
            let name = path.file_name().map(|n| n.to_string_lossy().to_string());
            json!({ "texture": t, "file": name })
        }
        (EnvironmentSource::Map { path, .. }, None) => json!({ "map": path }),
        (EnvironmentSource::Constant(c), _) => json!({ "constant": c.0 }),
        (EnvironmentSource::Sky(s), _) => json!({ "sky": s }),
    };
    let m = e.to_local.to_cols_array();
    json!({ "source": source, "to_local": m, "intensity": e.intensity })
}

/// Reads the JSON of [`environment_to_json`]: a map from the glTF texture `map(index)` decodes,
/// or read from its path resolved against `base`; errors name `file`.
pub fn environment_from_json(
    file: &Path,
    base: &Path,
    v: &Value,
    map: &mut dyn FnMut(usize) -> Result<lustre_env::equirect::EquirectMap>,
) -> Result<Environment> {
    let err = |p: &str| SceneError::format(file, format!("lustre environment extras: {p}"));
    let s = v.get("source").ok_or_else(|| err("source missing"))?;
    let source = if let Some(t) = s.get("texture") {
        let t = t.as_u64().ok_or_else(|| err("texture: an index"))?;
        EnvironmentSource::Map {
            path: file.to_path_buf(),
            map: Arc::new(map(t as usize)?),
        }
    } else if let Some(p) = s.get("map").and_then(Value::as_str) {
        let path = base.join(PathBuf::from(p));
        let loaded = lustre_env::io::read_map(&path)
            .map_err(|e| SceneError::format(&path, format!("environment map: {e}")))?;
        EnvironmentSource::Map {
            path,
            map: Arc::new(loaded.map),
        }
    } else if let Some(c) = s.get("constant") {
        let c: [f64; 3] =
            serde_json::from_value(c.clone()).map_err(|_| err("constant: 3 numbers"))?;
        EnvironmentSource::Constant(Rgb(c))
    } else if let Some(k) = s.get("sky") {
        let sky: Sky = serde_json::from_value(k.clone()).map_err(|e| err(&format!("sky: {e}")))?;
        EnvironmentSource::Sky(sky)
    } else {
        return Err(err("source is none of map, constant, sky"));
    };
    let m: [f64; 9] = serde_json::from_value(v.get("to_local").cloned().unwrap_or(Value::Null))
        .map_err(|_| err("to_local: 9 numbers"))?;
    let intensity = v
        .get("intensity")
        .and_then(Value::as_f64)
        .filter(|i| i.is_finite() && *i >= 0.0)
        .ok_or_else(|| err("intensity missing or negative"))?;
    Ok(Environment {
        source,
        to_local: DMat3::from_cols_array(&m),
        intensity,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scene texture `i` is glTF texture `i + 10` in the export.
    fn to_gltf(i: usize) -> usize {
        i + 10
    }

    fn textured(texture: usize, uv_set: u8) -> Option<TextureRef> {
        Some(TextureRef { texture, uv_set })
    }

    /// One material of every kind, with textures, masks, normal maps and an edited fit.
    fn materials() -> Vec<Material> {
        let c = |v: f64| TexturedScalar::constant(v);
        let t = TexturedScalar {
            factor: 0.7,
            texture: textured(2, 1),
            channel: 1,
        };
        let rgb = TexturedRgb {
            factor: Rgb([0.5, 0.25, 0.125]),
            texture: textured(0, 0),
        };
        let k = |r: f64| Rgb([r, r * 0.9, r * 0.8]);
        let kinds = vec![
            MaterialKind::Diffuse { reflectance: rgb },
            MaterialKind::Plastic {
                diffuse: TexturedRgb::constant(k(0.3)),
                specular: k(1.0),
                int_ior: 1.49,
                ext_ior: 1.000277,
                nonlinear: true,
            },
            MaterialKind::RoughPlastic {
                diffuse: rgb,
                specular: k(0.9),
                alpha: t,
                distribution: MicrofacetType::Beckmann,
                int_ior: 1.5,
                ext_ior: 1.0,
                nonlinear: false,
            },
            MaterialKind::Conductor {
                eta: k(0.2),
                k: k(3.9),
                specular: rgb,
            },
            MaterialKind::RoughConductor {
                eta: k(0.2),
                k: k(3.9),
                specular: TexturedRgb::constant(k(1.0)),
                alpha_u: c(0.05),
                alpha_v: t,
                distribution: MicrofacetType::Ggx,
            },
            MaterialKind::Dielectric {
                int_ior: 1.5,
                ext_ior: 1.0,
                specular_reflectance: k(1.0),
                specular_transmittance: k(0.8),
            },
            MaterialKind::RoughDielectric {
                int_ior: 1.33,
                ext_ior: 1.0,
                alpha: c(0.1),
                distribution: MicrofacetType::Ggx,
                specular_reflectance: k(1.0),
                specular_transmittance: k(1.0),
            },
            MaterialKind::ThinDielectric {
                int_ior: 1.52,
                ext_ior: 1.0,
                specular_reflectance: k(0.9),
                specular_transmittance: k(0.7),
            },
            MaterialKind::PbrMetallicRoughness {
                base_color: rgb,
                metallic: t,
                roughness: c(0.4),
                transmission: c(0.0),
                ior: 1.45,
                anisotropy: 0.6,
                anisotropy_rotation: 0.3,
                layers: PbrLayers {
                    specular: 0.7,
                    specular_color: Rgb::new(1.5, 1.0, 0.5),
                    clearcoat: 0.4,
                    clearcoat_roughness: 0.2,
                    sheen_color: Rgb::new(0.2, 0.3, 0.4),
                    sheen_roughness: 0.6,
                },
            },
            MaterialKind::Spec(ResolvedSpec::resolve("fit", "sgd:nickel").expect("sgd:nickel")),
        ];
        let mut out: Vec<Material> = kinds
            .into_iter()
            .enumerate()
            .map(|(i, kind)| {
                let mut m = Material::new(format!("m{i}"), kind);
                m.two_sided = i % 2 == 0;
                if i % 3 == 0 {
                    m.alpha_mask = Some(AlphaMask {
                        opacity: t,
                        cutoff: if i % 2 == 0 { Some(0.5) } else { None },
                    });
                    m.normal_map = Some(NormalMap {
                        texture: TextureRef {
                            texture: 1,
                            uv_set: 0,
                        },
                        scale: 0.75,
                    });
                    m.emission_texture = textured(3, 0);
                }
                m
            })
            .collect();
        let mut edited = out.last().cloned().expect("a spec");
        crate::material_edit::set(&mut edited, "model.rho_d", "0.5,0.25,0.125").expect("edit");
        edited.name = "edited".into();
        out.push(edited);
        out
    }

    #[test]
    fn every_material_kind_comes_back_unchanged() {
        for m in materials() {
            let v = material_to_json(&m, &to_gltf);
            // Through text, as in a file.
            let v: Value = serde_json::from_str(&v.to_string()).expect("JSON");
            let back = material_from_json(&m.name, &v, &mut |i, uv_set| {
                Ok(TextureRef {
                    texture: i - 10,
                    uv_set,
                })
            })
            .unwrap_or_else(|e| panic!("{}: {e}", m.name));
            assert_eq!(back, m, "{v}");
            // The edited fit evaluates as the edited one, not as the catalog's.
            if let (MaterialKind::Spec(a), MaterialKind::Spec(b)) = (&m.kind, &back.kind) {
                let wi = [0.3, 0.1, 0.95];
                let wo = [-0.2, 0.4, 0.89];
                assert_eq!(
                    a.bsdf.eval(wi.into(), wo.into()),
                    b.bsdf.eval(wi.into(), wo.into())
                );
            }
        }
    }

    #[test]
    fn bad_extras_name_the_material_and_field() {
        let m = &materials()[2];
        let mut v = material_to_json(m, &to_gltf);
        v["alpha"]["channel"] = json!(7);
        let e = material_from_json("Oak", &v, &mut |i, uv_set| {
            Ok(TextureRef { texture: i, uv_set })
        })
        .expect_err("channel 7");
        let e = e.to_string();
        assert!(e.contains("Oak") && e.contains("alpha.channel"), "{e}");
        v["kind"] = json!("velvet");
        let e = material_from_json("Oak", &v, &mut |_, _| unreachable!()).expect_err("kind");
        assert!(e.to_string().contains("velvet"), "{e}");
    }

    #[test]
    fn cameras_paths_and_environments_come_back() {
        let cam = |name: &str, x: f64| {
            let mut c = Camera::look_at(
                name,
                DVec3::new(x, 2.0, 3.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::Y,
                55.0,
                FovAxis::default(),
            )
            .expect("camera");
            c.aspect = Some(1.5);
            c
        };
        let c = cam("a", 1.0);
        let v: Value = serde_json::from_str(&camera_to_json(&c).to_string()).expect("JSON");
        assert_eq!(camera_from_json(&v), Some(c.clone()));
        let path = CameraPath {
            name: "walk".into(),
            keyframes: vec![
                Keyframe {
                    time: 0.0,
                    camera: c,
                },
                Keyframe {
                    time: 2.5,
                    camera: cam("b", -1.0),
                },
            ],
            looped: true,
        };
        let v: Value = serde_json::from_str(&path_to_json(&path).to_string()).expect("JSON");
        assert_eq!(path_from_json(&v), Some(path));
        for source in [
            EnvironmentSource::Sky(Sky::default()),
            EnvironmentSource::Constant(Rgb([0.1, 0.2, 0.3])),
        ] {
            let e = Environment {
                source,
                to_local: DMat3::from_rotation_y(0.4),
                intensity: 0.7,
            };
            let v: Value =
                serde_json::from_str(&environment_to_json(&e, None).to_string()).expect("JSON");
            let back = environment_from_json(Path::new("x.glb"), Path::new("."), &v, &mut |_| {
                unreachable!("no map")
            })
            .expect("env");
            assert_eq!(back, e);
        }
        // A map travels as a texture of the file.
        let map =
            lustre_env::equirect::EquirectMap::new(4, 2, vec![[0.5, 1.0, 2.0]; 8]).expect("map");
        let e = Environment {
            source: EnvironmentSource::Map {
                path: "sky.hdr".into(),
                map: Arc::new(map.clone()),
            },
            to_local: DMat3::IDENTITY,
            intensity: 2.0,
        };
        let v = environment_to_json(&e, Some(3));
        let back = environment_from_json(Path::new("x.glb"), Path::new("."), &v, &mut |t| {
            assert_eq!(t, 3);
            Ok(map.clone())
        })
        .expect("map");
        assert_eq!(
            back.source,
            EnvironmentSource::Map {
                path: "x.glb".into(),
                map: Arc::new(map)
            }
        );
    }
}
