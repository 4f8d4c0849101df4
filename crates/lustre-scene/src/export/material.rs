//! A material as glTF 2.0: the metallic-roughness parameters (`pbrMetallicRoughness`) on a
//! sample sphere with normals, tangents and texture coordinates, as a binary glTF.
//!
//! The sphere: radius 1 at the origin, Y up (glTF's axes), `LON` × `LAT` quads between rings
//! of constant θ (from +Y), the seam duplicated so that u runs 0 → 1 around it; at each pole one
//! vertex per segment (its own u), so that no triangle is degenerate. u = φ/2π, v = θ/π (glTF's
//! v runs down the texture); the tangent is ∂p/∂u normalized, (cos φ, 0, −sin φ), w = 1.

use crate::error::{Result, SceneError};
use crate::glb_write::Builder;
use lustre_brdf::models::pbr_metallic_roughness::PbrLayers;
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::path::Path;

/// Segments around the sample sphere.
pub const LON: u32 = 64;
/// Rings from pole to pole.
pub const LAT: u32 = 32;

/// A glTF 2.0 metallic-roughness material.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfMaterial {
    /// The material's (and the sphere's) name.
    pub name: String,
    /// `baseColorFactor` (linear RGB; alpha 1).
    pub base_color: [f64; 3],
    /// `metallicFactor`.
    pub metallic: f64,
    /// `roughnessFactor`.
    pub roughness: f64,
    /// `KHR_materials_anisotropy` `anisotropyStrength` (0: none written).
    pub anisotropy: f64,
    /// `KHR_materials_anisotropy` `anisotropyRotation` (radians from the tangent).
    pub anisotropy_rotation: f64,
    /// `KHR_materials_specular` / `_clearcoat` / `_sheen` (each written where it differs from the
    /// core model).
    pub layers: PbrLayers,
    /// What the exporter records beside it (`extras.lustre`: the source, the fit's errors).
    pub extras: Value,
}

impl GltfMaterial {
    /// The glTF `material` object. Errors: a value outside [0, 1] or not finite.
    pub fn to_json(&self) -> std::result::Result<Value, String> {
        let unit = |name: &str, v: f64| {
            if (0.0..=1.0).contains(&v) {
                Ok(v)
            } else {
                Err(format!("{name} = {v} must lie in [0, 1]"))
            }
        };
        let [r, g, b] = self.base_color;
        let mut m = json!({
            "name": self.name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [unit("base colour red", r)?, unit("base colour green", g)?,
                                    unit("base colour blue", b)?, 1.0],
                "metallicFactor": unit("metallic", self.metallic)?,
                "roughnessFactor": unit("roughness", self.roughness)?,
            },
            "extras": { "lustre": self.extras },
        });
        if self.anisotropy > 0.0 {
            if !self.anisotropy_rotation.is_finite() {
                return Err(format!(
                    "anisotropy rotation {} is not finite",
                    self.anisotropy_rotation
                ));
            }
            m["extensions"]["KHR_materials_anisotropy"] = json!({
                "anisotropyStrength": unit("anisotropy", self.anisotropy)?,
                "anisotropyRotation": self.anisotropy_rotation,
            });
        }
        self.layers.validate().map_err(|e| e.to_string())?;
        for (k, v) in crate::gltf_io::layers_extensions(&self.layers) {
            m["extensions"][k] = v;
        }
        Ok(m)
    }
}

/// The sample sphere's vertices (position = normal, tangent, uv) and triangles.
#[allow(clippy::type_complexity)]
pub fn sphere() -> (Vec<[f32; 3]>, Vec<[f32; 4]>, Vec<[f32; 2]>, Vec<[u32; 3]>) {
    let (mut pos, mut tan, mut uv, mut tris) = (vec![], vec![], vec![], vec![]);
    for j in 0..=LAT {
        let theta = PI * f64::from(j) / f64::from(LAT);
        for i in 0..=LON {
            // Pole vertices sit at the middle of their segment, so that each has its own u (the
            // last, past the seam, is not used).
            let fi = if (j == 0 || j == LAT) && i < LON {
                f64::from(i) + 0.5
            } else {
                f64::from(i)
            };
            let phi = 2.0 * PI * fi / f64::from(LON);
            let (st, ct) = theta.sin_cos();
            let (sp, cp) = phi.sin_cos();
            pos.push([(st * sp) as f32, ct as f32, (st * cp) as f32]);
            tan.push([cp as f32, 0.0, -sp as f32, 1.0]);
            uv.push([
                (fi / f64::from(LON)) as f32,
                (f64::from(j) / f64::from(LAT)) as f32,
            ]);
        }
    }
    let at = |j: u32, i: u32| j * (LON + 1) + i;
    for j in 0..LAT {
        for i in 0..LON {
            let (a, b, c, d) = (at(j, i), at(j + 1, i), at(j + 1, i + 1), at(j, i + 1));
            if j + 1 == LAT {
                // The south pole: one triangle per segment, its pole vertex b.
                tris.push([a, b, d]);
            } else if j == 0 {
                tris.push([a, b, c]);
            } else {
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            }
        }
    }
    (pos, tan, uv, tris)
}

/// The GLB of `material` on the sample sphere (one scene, one node, one mesh).
pub fn sphere_glb(material: &GltfMaterial, path: &Path) -> Result<Vec<u8>> {
    let mat = material
        .to_json()
        .map_err(|e| SceneError::format(path, format!("material {:?}: {e}", material.name)))?;
    let (pos, tan, uv, tris) = sphere();
    let mut b = Builder::default();
    let p = b.floats(&pos, "VEC3", true);
    let n = b.floats(&pos, "VEC3", false);
    let t = b.floats(&tan, "VEC4", false);
    let u = b.floats(&uv, "VEC2", false);
    let i = b.indices(&tris);
    let mut doc = json!({
        "asset": { "version": "2.0", "generator": "lustre export" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "name": material.name, "mesh": 0 }],
        "meshes": [{
            "name": material.name,
            "primitives": [{
                "attributes": { "POSITION": p, "NORMAL": n, "TANGENT": t, "TEXCOORD_0": u },
                "indices": i,
                "material": 0,
                "mode": 4,
            }],
        }],
        "materials": [mat],
        "accessors": b.accessors,
        "bufferViews": b.views,
    });
    if let Some(ext) = mat.get("extensions").and_then(Value::as_object) {
        doc["extensionsUsed"] = json!(ext.keys().collect::<Vec<_>>());
    }
    crate::glb_write::glb_bytes(path, &doc, b.bin)
}

/// Writes [`sphere_glb`] to `path` atomically; returns its size in bytes.
pub fn write_sphere_glb(material: &GltfMaterial, path: &Path) -> Result<u64> {
    let bytes = sphere_glb(material, path)?;
    crate::scene_file::write_atomic(path, &bytes)?;
    Ok(bytes.len() as u64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn the_sphere_faces_out_with_unit_frames_and_no_degenerate_triangle() {
        let (pos, tan, uv, tris) = sphere();
        assert_eq!(pos.len(), ((LAT + 1) * (LON + 1)) as usize);
        assert_eq!(tris.len(), (2 * LON * (LAT - 1)) as usize);
        for (p, t) in pos.iter().zip(&tan) {
            let (p, tv) = (Vec3::from(*p), Vec3::new(t[0], t[1], t[2]));
            assert!((p.length() - 1.0).abs() < 1e-6 && (tv.length() - 1.0).abs() < 1e-6);
            assert!(p.dot(tv).abs() < 1e-6 && t[3] == 1.0);
        }
        for tri in &tris {
            let [a, b, c] = tri.map(|k| Vec3::from(pos[k as usize]));
            let n = (b - a).cross(c - a);
            assert!(n.length() > 1e-6, "degenerate {tri:?}");
            // Counter-clockwise seen from outside: the face normal points out.
            assert!(n.dot(a + b + c) > 0.0, "inward {tri:?}");
        }
        assert!(uv
            .iter()
            .all(|u| (0.0..=1.0).contains(&u[0]) && (0.0..=1.0).contains(&u[1])));
    }

    /// An anisotropic material with every layer.
    fn layered() -> GltfMaterial {
        GltfMaterial {
            name: "layered".into(),
            base_color: [0.5, 0.4, 0.3],
            metallic: 0.2,
            roughness: 0.5,
            anisotropy: 0.3,
            anisotropy_rotation: 0.4,
            layers: PbrLayers {
                specular: 0.6,
                specular_color: lustre_brdf::Rgb::new(2.0, 1.5, 1.0),
                clearcoat: 0.8,
                clearcoat_roughness: 0.15,
                sheen_color: lustre_brdf::Rgb::new(0.4, 0.3, 0.2),
                sheen_roughness: 0.7,
            },
            extras: json!({}),
        }
    }

    #[test]
    fn the_layers_are_written_as_their_extensions_and_read_back() {
        let m = layered();
        let layers = m.layers;
        let dir = tempfile::tempdir().expect("dir");
        let path = dir.path().join("m.glb");
        write_sphere_glb(&m, &path).expect("written");
        let bytes = std::fs::read(&path).expect("read");
        let text = String::from_utf8_lossy(&bytes);
        for ext in [
            "KHR_materials_specular",
            "KHR_materials_clearcoat",
            "KHR_materials_sheen",
            "KHR_materials_anisotropy",
        ] {
            assert_eq!(
                text.matches(ext).count(),
                2,
                "{ext}: used and in the material"
            );
        }
        let scene = crate::Scene::load(&path).expect("reloads");
        let crate::MaterialKind::PbrMetallicRoughness {
            layers: got,
            anisotropy,
            ..
        } = &scene.materials[0].kind
        else {
            panic!("{:?}", scene.materials[0].kind)
        };
        assert_eq!(*got, layers);
        assert_eq!(*anisotropy, 0.3);
        // Out of range: refused, naming the factor.
        let bad = GltfMaterial {
            layers: PbrLayers {
                clearcoat: 1.5,
                ..layers
            },
            ..m
        };
        let e = sphere_glb(&bad, &path).unwrap_err().to_string();
        assert!(e.contains("clearcoatFactor"), "{e}");
    }

    #[test]
    fn a_material_out_of_range_is_refused_naming_it() {
        let m = GltfMaterial {
            base_color: [0.5, 1.5, 0.5],
            ..layered()
        };
        let e = sphere_glb(&m, Path::new("m.glb")).unwrap_err().to_string();
        assert!(
            e.contains("base colour green = 1.5 must lie in [0, 1]"),
            "{e}"
        );
    }
}
