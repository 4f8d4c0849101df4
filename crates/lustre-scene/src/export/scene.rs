//! A baked scene as one binary glTF 2.0 file that other tools read, and that lustre reads back
//! unchanged (`lustre export scene BAKED/scene.toml --to glb`).
//!
//! - **Meshes**: one node and one mesh (one triangle primitive) per scene mesh, in scene order, in
//!   world space, named after it: POSITION, NORMAL, TANGENT, TEXCOORD_0 where the mesh has them,
//!   TEXCOORD_1 = the light-map UVs of a light-mapped mesh (and its TEXCOORD_0 too when it has
//!   no UVs of its own: glTF numbers texture coordinates without gaps).
//! - **Materials**: the nearest glTF metallic-roughness material ([`core_material`], with
//!   `KHR_materials_ior`, `_transmission`, `_anisotropy` and `_emissive_strength` where they
//!   apply) for other viewers, and the exact lustre material in `extras.lustre_material`
//!   ([`super::exact`]), which lustre's reader prefers. Emission is per glTF material, so meshes
//!   that share a material but differ in emission or light-map page get one material each.
//! - **Light maps**: each atlas page is a texture referenced by the material extension
//!   `MOZ_lightmap` (`{ index, texCoord: 1, intensity: 1 }`, Mozilla Hubs' extension, read by
//!   Hubs and by three.js through a loader plugin). The texel is irradiance E (W m⁻²; three.js's
//!   `lightMap` and Hubs's are irradiance too), **encoded RGBE in an 8-bit RGBA PNG**
//!   (Radiance's shared exponent: R, G, B mantissas rounded to nearest, A = exponent + 128;
//!   decode `m·2^(A−136)`, 0 where A = 0), marked `extras.lustre_encoding = "rgbe"` on the
//!   texture: at most 0.4 % error on the largest channel over 76 orders of magnitude in 4 bytes a
//!   texel, and PNG, which every glTF loader and browser decodes. Pages keep their baked size.
//! - **Textures**: an image file the scene read (JPEG, PNG) is embedded as it is; any other
//!   texture (decoded from an embedded image, a float image) as an 8-bit PNG (sRGB-encoded where
//!   it was decoded from sRGB).
//! - **Cameras**: one node per camera (glTF `yfov` at the film's aspect, `aspectRatio` set), the
//!   exact camera in the node's `extras.lustre_camera`. **Camera paths**: one camera node per
//!   path (`path:NAME`) and one animation (`NAME`): translation and rotation samplers, LINEAR,
//!   at the keyframes' times (glTF's LINEAR rotation is the slerp lustre uses), so the animation
//!   is the path; the field of view, which glTF cannot animate, and the exact keyframes are in
//!   `asset.extras.lustre_scene.camera_paths`.
//! - **Environment**: an equirect map is embedded as one more RGBE PNG texture
//!   (`extras.lustre_role = "environment"`) and named by `lustre_scene.environment.source.texture`,
//!   so the file needs nothing beside it; a constant or the built-in sky is written as numbers.
//! - **The rest** in `asset.extras`: `lustre_lightmap` (the atlas, as
//!   [`crate::lightmap::write_atlas_glb`] writes it, with `lightmap_page` / `scene_mesh` / `uv0`
//!   in the light-mapped nodes' extras) and `lustre_scene` (`version`, `film`, `environment`,
//!   `probes`, `camera_paths`); each node's real-time hints in `extras.lustre_hints`.

use super::exact;
use crate::environment::{Environment, EnvironmentSource};
use crate::error::{Result, SceneError};
use crate::glb_write::Builder;
use crate::lightmap::{AtlasSource, LightmapAtlas};
use crate::material::{Material, MaterialKind, TexturedRgb};
use crate::texture::{ColorSpace, Texture};
use crate::Scene;
use glam::{DMat3, DQuat};
use serde_json::{json, Value};
use std::collections::HashMap;
use std::path::Path;

/// One glTF material per scene material, emission (its bits) and light-map page.
type MaterialKey = (usize, Option<[u64; 3]>, Option<u32>);

/// What [`write_scene_glb`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneExport {
    /// Bytes of the file.
    pub bytes: usize,
    /// Meshes (nodes with a mesh).
    pub meshes: usize,
    /// Triangles.
    pub triangles: usize,
    /// glTF materials (scene materials split by emission and light-map page).
    pub materials: usize,
    /// Texture images embedded (not counting light-map pages).
    pub textures: usize,
    /// Bytes of those images.
    pub texture_bytes: usize,
    /// Light-map pages embedded, their size in texels and their bytes (PNG).
    pub lightmap_pages: usize,
    /// Page width × height.
    pub lightmap_size: (u32, u32),
    /// Bytes of the light-map PNGs.
    pub lightmap_bytes: usize,
    /// Bytes of the environment map's PNG (RGBE, as the light maps); 0 without a map.
    pub environment_bytes: usize,
    /// Cameras (not counting the paths' cameras).
    pub cameras: usize,
    /// Camera paths written as animations.
    pub animations: usize,
    /// Per scene material whose glTF material is an approximation: what it leaves out.
    pub approximations: Vec<String>,
}

/// The glTF metallic-roughness material nearest to a lustre material for other viewers:
/// `(pbrMetallicRoughness, extensions, what it leaves out)`. `tex` maps a scene texture to its
/// glTF texture index. Conductors are metals of base colour F0 (from η and k at normal
/// incidence, times the specular scale); plastics dielectrics of their diffuse colour; glass
/// transmissive dielectrics (`KHR_materials_transmission` 1, `KHR_materials_ior`); roughness =
/// √α (for Beckmann too); anisotropic roughness through `KHR_materials_anisotropy` (bitangent
/// α = the smaller, tangent α = mix(α, 1, strength²) = the larger, rotated to the larger
/// axis). `spec` gives the glTF material of a catalog-specified material (a fit made by the
/// caller: an object with its `pbrMetallicRoughness` and its `extensions`), else it becomes a
/// grey diffuse.
pub fn core_material(
    m: &Material,
    tex: &dyn Fn(usize) -> usize,
    spec: Option<&(Value, String)>,
) -> (Value, Value, Option<String>) {
    let colour = |c: &TexturedRgb| {
        let f = c.factor.0.map(|x| x.clamp(0.0, 1.0));
        let mut p = json!({ "baseColorFactor": [f[0], f[1], f[2], 1.0] });
        if let Some(t) = c.texture {
            p["baseColorTexture"] = json!({ "index": tex(t.texture), "texCoord": t.uv_set });
        }
        p
    };
    let rough = |a: f64| a.max(0.0).sqrt().clamp(0.0, 1.0);
    let ior_ext = |int: f64, ext: f64| {
        let ior = (int / ext).clamp(1.0, 10.0);
        json!({ "ior": ior })
    };
    let mut ext = json!({});
    let mut note = None;
    let pbr = match &m.kind {
        MaterialKind::Diffuse { reflectance } => {
            let mut p = colour(reflectance);
            p["metallicFactor"] = json!(0.0);
            p["roughnessFactor"] = json!(1.0);
            note = Some("Lambertian: glTF adds a 4 % specular layer".to_string());
            p
        }
        MaterialKind::Plastic {
            diffuse,
            int_ior,
            ext_ior,
            ..
        }
        | MaterialKind::RoughPlastic {
            diffuse,
            int_ior,
            ext_ior,
            ..
        } => {
            let mut p = colour(diffuse);
            let alpha = match &m.kind {
                MaterialKind::RoughPlastic { alpha, .. } => alpha.factor,
                _ => 0.0,
            };
            p["metallicFactor"] = json!(0.0);
            p["roughnessFactor"] = json!(rough(alpha));
            ext["KHR_materials_ior"] = ior_ext(*int_ior, *ext_ior);
            note = Some(
                "coated diffuse as glTF's dielectric (no internal scattering, roughness texture and \
                 specular scale dropped)"
                    .into(),
            );
            p
        }
        MaterialKind::Conductor { eta, k, specular }
        | MaterialKind::RoughConductor {
            eta, k, specular, ..
        } => {
            let f0 = |c: usize| {
                let (n, kk) = (eta.0[c], k.0[c]);
                (((n - 1.0).powi(2) + kk * kk) / ((n + 1.0).powi(2) + kk * kk))
                    * specular.factor.0[c]
            };
            let mut p = colour(&TexturedRgb {
                factor: lustre_brdf::Rgb([f0(0), f0(1), f0(2)]),
                texture: specular.texture,
            });
            p["metallicFactor"] = json!(1.0);
            let (au, av) = match &m.kind {
                MaterialKind::RoughConductor {
                    alpha_u, alpha_v, ..
                } => (alpha_u.factor, alpha_v.factor),
                _ => (0.0, 0.0),
            };
            let (lo, hi) = (au.min(av).max(0.0), au.max(av).min(1.0));
            p["roughnessFactor"] = json!(rough(lo));
            if hi > lo + 1e-9 {
                let strength = ((hi - lo) / (1.0 - lo).max(1e-9)).sqrt().min(1.0);
                let rotation = if au >= av {
                    0.0
                } else {
                    std::f64::consts::FRAC_PI_2
                };
                ext["KHR_materials_anisotropy"] =
                    json!({ "anisotropyStrength": strength, "anisotropyRotation": rotation });
            }
            note =
                Some("metal of F0 = its normal-incidence reflectance (Schlick's Fresnel)".into());
            p
        }
        MaterialKind::Dielectric {
            int_ior,
            ext_ior,
            specular_transmittance,
            ..
        }
        | MaterialKind::ThinDielectric {
            int_ior,
            ext_ior,
            specular_transmittance,
            ..
        }
        | MaterialKind::RoughDielectric {
            int_ior,
            ext_ior,
            specular_transmittance,
            ..
        } => {
            let mut p = colour(&TexturedRgb::constant(*specular_transmittance));
            let alpha = match &m.kind {
                MaterialKind::RoughDielectric { alpha, .. } => alpha.factor,
                _ => 0.0,
            };
            p["metallicFactor"] = json!(0.0);
            p["roughnessFactor"] = json!(rough(alpha));
            ext["KHR_materials_transmission"] = json!({ "transmissionFactor": 1.0 });
            ext["KHR_materials_ior"] = ior_ext(*int_ior, *ext_ior);
            if !matches!(m.kind, MaterialKind::ThinDielectric { .. }) {
                note = Some("solid glass as glTF's thin-walled transmission (no volume)".into());
            }
            p
        }
        MaterialKind::PbrMetallicRoughness {
            base_color,
            metallic,
            roughness,
            transmission,
            ior,
            anisotropy,
            anisotropy_rotation,
            layers,
        } => {
            let mut p = colour(base_color);
            p["metallicFactor"] = json!(metallic.factor.clamp(0.0, 1.0));
            p["roughnessFactor"] = json!(roughness.factor.clamp(0.0, 1.0));
            if let Some(t) = metallic.texture.or(roughness.texture) {
                p["metallicRoughnessTexture"] =
                    json!({ "index": tex(t.texture), "texCoord": t.uv_set });
            }
            if transmission.factor > 0.0 || transmission.texture.is_some() {
                let mut t = json!({ "transmissionFactor": transmission.factor.clamp(0.0, 1.0) });
                if let Some(tt) = transmission.texture {
                    t["transmissionTexture"] =
                        json!({ "index": tex(tt.texture), "texCoord": tt.uv_set });
                }
                ext["KHR_materials_transmission"] = t;
            }
            if (*ior - 1.5).abs() > 1e-9 {
                ext["KHR_materials_ior"] = json!({ "ior": ior });
            }
            if *anisotropy > 0.0 {
                ext["KHR_materials_anisotropy"] = json!({
                    "anisotropyStrength": anisotropy, "anisotropyRotation": anisotropy_rotation,
                });
            }
            for (k, v) in crate::gltf_io::layers_extensions(layers) {
                ext[k] = v;
            }
            p
        }
        MaterialKind::Spec(s) => match spec {
            Some((fit, how)) => {
                note = Some(how.clone());
                if let Some(e) = fit.get("extensions").and_then(Value::as_object) {
                    for (k, v) in e {
                        ext[k] = v.clone();
                    }
                }
                fit.get("pbrMetallicRoughness")
                    .cloned()
                    .unwrap_or(json!({}))
            }
            None => {
                note = Some(format!("{}: no glTF fit given; a grey diffuse", s.spec));
                json!({ "baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0,
                        "roughnessFactor": 1.0 })
            }
        },
    };
    (pbr, ext, note)
}

/// Radiance's RGBE encoding of one texel, rounded to the nearest mantissa (`[0; 4]` below
/// 1e-32 or where a channel is not finite): the largest channel is m·2^(A−136) with m in [128, 255].
pub fn rgbe(c: [f32; 3]) -> [u8; 4] {
    let m = c[0].max(c[1]).max(c[2]);
    if !(c.iter().all(|x| x.is_finite()) && m > 1e-32) {
        return [0; 4];
    }
    // m = f · 2^e with f in [0.5, 1); one exponent more where f rounds up to 256/256.
    let mut e = m.log2().floor() as i32 + 1;
    if (m * 256.0 / 2f32.powi(e)).round() >= 256.0 {
        e += 1;
    }
    let scale = 256.0 / 2f32.powi(e);
    let byte = |x: f32| (x.max(0.0) * scale).round().min(255.0) as u8;
    [
        byte(c[0]),
        byte(c[1]),
        byte(c[2]),
        (e + 128).clamp(0, 255) as u8,
    ]
}

/// Decodes [`rgbe`]: m·2^(A−136) per channel, 0 where A = 0 (as the `image` crate reads a
/// Radiance `.hdr`, so such a map's texels come back bit for bit).
pub fn rgbe_decode(p: [u8; 4]) -> [f32; 3] {
    if p[3] == 0 {
        return [0.0; 3];
    }
    let f = 2f32.powi(i32::from(p[3]) - 136);
    [0, 1, 2].map(|i| f32::from(p[i]) * f)
}

/// An RGBA8 PNG in memory.
fn png(path: &Path, width: u32, height: u32, channels: u8, data: Vec<u8>) -> Result<Vec<u8>> {
    let colour = match channels {
        1 => image::ExtendedColorType::L8,
        2 => image::ExtendedColorType::La8,
        3 => image::ExtendedColorType::Rgb8,
        _ => image::ExtendedColorType::Rgba8,
    };
    let mut out = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut out),
        &data,
        width,
        height,
        colour,
    )
    .map_err(|e| SceneError::format(path, format!("encoding a PNG: {e}")))?;
    Ok(out)
}

/// The sRGB transfer function (IEC 61966-2-1), the inverse of
/// [`crate::texture::srgb_to_linear`].
fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// A texture's image: its file as it is (JPEG, PNG) when it came from one, else an 8-bit PNG.
fn texture_image(path: &Path, t: &Texture) -> Result<(Vec<u8>, &'static str)> {
    let ext = t
        .source
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let mime = match ext.as_deref() {
        Some("jpg" | "jpeg") => Some("image/jpeg"),
        Some("png") => Some("image/png"),
        _ => None,
    };
    if let Some(mime) = mime {
        if let Ok(bytes) = std::fs::read(&t.source) {
            return Ok((bytes, mime));
        }
    }
    let ch = usize::from(t.channels);
    let colour = if ch == 2 || ch == 4 { ch - 1 } else { ch };
    let data: Vec<u8> = t
        .data
        .chunks(ch)
        .flat_map(|texel| {
            texel.iter().enumerate().map(|(i, &v)| {
                let v = if t.color_space == ColorSpace::Srgb && i < colour {
                    linear_to_srgb(v)
                } else {
                    v
                };
                (v.clamp(0.0, 1.0) * 255.0).round() as u8
            })
        })
        .collect();
    Ok((png(path, t.width, t.height, t.channels, data)?, "image/png"))
}

/// A view of raw bytes (an image) in the binary chunk; returns the view index.
fn image_view(b: &mut Builder, bytes: &[u8]) -> usize {
    let offset = b.bin.len();
    b.bin.extend_from_slice(bytes);
    while !b.bin.len().is_multiple_of(4) {
        b.bin.push(0);
    }
    b.views
        .push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() }));
    b.views.len() - 1
}

/// A camera's orientation as a glTF node rotation (the camera looks down −z, +y up).
fn orientation(right: glam::DVec3, up: glam::DVec3, forward: glam::DVec3) -> [f64; 4] {
    DQuat::from_mat3(&DMat3::from_cols(right, up, -forward))
        .normalize()
        .to_array()
}

/// Writes `scene` (its light-map `atlas` and baked `pages`) atomically to `path` as a binary glTF
/// (see the module documentation). `spec_fit(material)` gives the glTF material of a material
/// given by a catalog specification and a line saying how it was fitted. Errors: an atlas or
/// pages that do not describe this scene, a file over 4 GB, an I/O failure (naming `path`).
pub fn write_scene_glb(
    scene: &Scene,
    atlas: &LightmapAtlas,
    pages: &[Vec<[f32; 3]>],
    spec_fit: &dyn Fn(&Material) -> Option<(Value, String)>,
    path: &Path,
) -> Result<SceneExport> {
    let fmt = |p: String| SceneError::format(path, p);
    if atlas.mesh_page.len() != scene.meshes.len() {
        return Err(fmt(format!(
            "the atlas describes {} meshes, the scene has {}",
            atlas.mesh_page.len(),
            scene.meshes.len()
        )));
    }
    let texels = atlas.width as usize * atlas.height as usize;
    if pages.len() != atlas.pages as usize || pages.iter().any(|p| p.len() != texels) {
        return Err(fmt(format!(
            "{} baked pages for an atlas of {} pages of {}×{} texels",
            pages.len(),
            atlas.pages,
            atlas.width,
            atlas.height
        )));
    }
    let mut b = Builder::default();
    let (mut images, mut textures) = (Vec::new(), Vec::new());
    let mut texture_bytes = 0;
    for (i, t) in scene.textures.iter().enumerate() {
        let (bytes, mime) = texture_image(path, t)?;
        texture_bytes += bytes.len();
        let view = image_view(&mut b, &bytes);
        images.push(json!({ "bufferView": view, "mimeType": mime, "name": format!("texture{i}") }));
        let cs = match t.color_space {
            ColorSpace::Srgb => "srgb",
            ColorSpace::Linear => "linear",
        };
        textures.push(json!({ "source": i, "sampler": 0, "extras": { "lustre_color_space": cs } }));
    }
    let mut lightmap_bytes = 0;
    let mut page_texture = Vec::new();
    for (k, page) in pages.iter().enumerate() {
        let data: Vec<u8> = page.iter().flat_map(|&c| rgbe(c)).collect();
        let bytes = png(path, atlas.width, atlas.height, 4, data)?;
        lightmap_bytes += bytes.len();
        let view = image_view(&mut b, &bytes);
        images.push(json!({ "bufferView": view, "mimeType": "image/png",
                            "name": format!("lightmap_{k:03}") }));
        textures.push(json!({ "source": images.len() - 1, "sampler": 1,
                              "extras": { "lustre_encoding": "rgbe" } }));
        page_texture.push(textures.len() - 1);
    }
    // The environment map, as the light maps (RGBE in an 8-bit PNG), for viewers and the reload.
    let mut environment_texture = None;
    let mut environment_bytes = 0;
    if let Some(Environment {
        source: EnvironmentSource::Map { map, .. },
        ..
    }) = &scene.environment
    {
        let data: Vec<u8> = map.data.iter().flat_map(|&c| rgbe(c)).collect();
        let (w, h) = (map.width as u32, map.height as u32);
        let bytes = png(path, w, h, 4, data)?;
        environment_bytes = bytes.len();
        let view = image_view(&mut b, &bytes);
        images.push(json!({ "bufferView": view, "mimeType": "image/png", "name": "environment" }));
        textures.push(json!({ "source": images.len() - 1, "sampler": 0,
                              "extras": { "lustre_encoding": "rgbe", "lustre_role": "environment" } }));
        environment_texture = Some(textures.len() - 1);
    }
    let tex = |i: usize| i;
    // glTF materials: one per (scene material, emission, light-map page).
    let mut materials = Vec::new();
    let mut material_of: HashMap<MaterialKey, usize> = HashMap::new();
    let mut approximations = Vec::new();
    let mut used_ext = std::collections::BTreeSet::new();
    let spec_fits: Vec<Option<(Value, String)>> = scene.materials.iter().map(spec_fit).collect();
    let (mut nodes, mut meshes) = (Vec::new(), Vec::new());
    let mut triangles = 0;
    for (i, (m, page)) in scene.meshes.iter().zip(&atlas.mesh_page).enumerate() {
        let emission = m.emission.map(|e| e.0.map(f64::to_bits));
        let key = (m.material, emission, *page);
        let material = match material_of.get(&key) {
            Some(&k) => k,
            None => {
                let mat = scene.materials.get(m.material).ok_or_else(|| {
                    fmt(format!(
                        "mesh {:?} names material {} of {}",
                        m.name,
                        m.material,
                        scene.materials.len()
                    ))
                })?;
                let (pbr, mut ext, note) = core_material(mat, &tex, spec_fits[m.material].as_ref());
                if let Some(n) = note {
                    let line = format!("{} ({}): {n}", mat.name, mat.kind.name());
                    if !approximations.contains(&line) {
                        approximations.push(line);
                    }
                }
                let mut j = json!({
                    "name": mat.name,
                    "pbrMetallicRoughness": pbr,
                    "doubleSided": mat.two_sided,
                    "extras": { "lustre_material": exact::material_to_json(mat, &tex) },
                });
                if let Some(n) = &mat.normal_map {
                    j["normalTexture"] = json!({ "index": tex(n.texture.texture),
                        "texCoord": n.texture.uv_set, "scale": n.scale });
                }
                if let Some(e) = m.emission {
                    let peak = e.max_component();
                    if peak > 0.0 {
                        j["emissiveFactor"] = json!(e.0.map(|c| c / peak));
                        if peak != 1.0 {
                            ext["KHR_materials_emissive_strength"] =
                                json!({ "emissiveStrength": peak });
                        }
                    }
                    if let Some(t) = mat.emission_texture {
                        j["emissiveTexture"] = json!({ "index": tex(t.texture),
                                                       "texCoord": t.uv_set });
                    }
                }
                if let Some(p) = page {
                    ext["MOZ_lightmap"] = json!({ "index": page_texture[*p as usize],
                                                  "texCoord": 1, "intensity": 1.0 });
                }
                if let Some(a) = &mat.alpha_mask {
                    if let Some(c) = a.cutoff {
                        j["alphaMode"] = json!("MASK");
                        j["alphaCutoff"] = json!(c);
                    }
                }
                if let Some(obj) = ext.as_object().filter(|o| !o.is_empty()) {
                    used_ext.extend(obj.keys().cloned());
                    j["extensions"] = ext;
                }
                materials.push(j);
                material_of.insert(key, materials.len() - 1);
                materials.len() - 1
            }
        };
        let mut attributes = b.mesh_attributes(m);
        let mut extras = json!({});
        if let (Some(p), Some(uv1)) = (page, &m.uv1) {
            let u: Vec<[f32; 2]> = uv1.iter().map(|v| v.to_array()).collect();
            let lm = b.floats(&u, "VEC2", false);
            attributes.insert("TEXCOORD_1".into(), json!(lm));
            if m.uv0.is_none() {
                attributes.insert("TEXCOORD_0".into(), json!(lm));
            }
            extras = json!({ "lightmap_page": p, "scene_mesh": i, "uv0": m.uv0.is_some() });
        } else if page.is_some() {
            return Err(SceneError::geometry(
                path,
                &m.name,
                "light-mapped mesh without uv1",
            ));
        }
        if let Some(e) = m.emission {
            extras["lustre_emission"] = json!(e.0);
        }
        if m.hints != crate::mesh::ObjectHints::default() {
            extras["lustre_hints"] = json!(m.hints);
        }
        triangles += m.indices.len();
        let indices = b.indices(&m.indices);
        meshes.push(json!({
            "name": m.name,
            "primitives": [{ "attributes": attributes, "indices": indices, "mode": 4,
                             "material": material }],
        }));
        let mut node = json!({ "name": m.name, "mesh": meshes.len() - 1 });
        if extras.as_object().is_some_and(|o| !o.is_empty()) {
            node["extras"] = extras;
        }
        nodes.push(node);
    }
    let aspect = f64::from(scene.film.width) / f64::from(scene.film.height);
    let mut cameras = Vec::new();
    let camera_node = |c: &crate::Camera, index: usize, name: String| {
        json!({
            "name": name,
            "camera": index,
            "translation": c.position.to_array(),
            "rotation": orientation(c.right(), c.up, c.forward),
            "extras": { "lustre_camera": exact::camera_to_json(c) },
        })
    };
    let path_node = |c: &crate::Camera, index: usize, name: &str| {
        let mut n = camera_node(c, index, format!("path:{name}"));
        n["extras"]["lustre_path"] = json!(name);
        n
    };
    let perspective = |c: &crate::Camera| {
        json!({ "type": "perspective", "name": c.name, "perspective": {
            "yfov": c.fov_y_deg(aspect).to_radians(), "aspectRatio": aspect, "znear": 0.01 } })
    };
    for c in &scene.cameras {
        cameras.push(perspective(c));
        nodes.push(camera_node(c, cameras.len() - 1, c.name.clone()));
    }
    let mut animations = Vec::new();
    for p in &scene.camera_paths {
        let Some(first) = p.keyframes.first() else {
            continue;
        };
        let mut cam = perspective(&first.camera);
        cam["name"] = json!(format!("path:{}", p.name));
        cameras.push(cam);
        nodes.push(path_node(&first.camera, cameras.len() - 1, &p.name));
        let node = nodes.len() - 1;
        let t0 = first.time.min(0.0);
        let times: Vec<[f32; 1]> = p.keyframes.iter().map(|k| [(k.time - t0) as f32]).collect();
        let trans: Vec<[f32; 3]> = p
            .keyframes
            .iter()
            .map(|k| k.camera.position.as_vec3().to_array())
            .collect();
        let mut rot: Vec<[f32; 4]> = Vec::new();
        for k in &p.keyframes {
            let c = &k.camera;
            let mut q = orientation(c.right(), c.up, c.forward).map(|x| x as f32);
            // Consecutive quaternions in one hemisphere: the shortest slerp, as lustre's.
            if let Some(prev) = rot.last() {
                if prev.iter().zip(&q).map(|(a, b)| a * b).sum::<f32>() < 0.0 {
                    q = q.map(|x| -x);
                }
            }
            rot.push(q);
        }
        let input = b.animation_floats(&times, "SCALAR", true);
        let t_out = b.animation_floats(&trans, "VEC3", false);
        let r_out = b.animation_floats(&rot, "VEC4", false);
        animations.push(json!({
            "name": p.name,
            "samplers": [
                { "input": input, "output": t_out, "interpolation": "LINEAR" },
                { "input": input, "output": r_out, "interpolation": "LINEAR" },
            ],
            "channels": [
                { "sampler": 0, "target": { "node": node, "path": "translation" } },
                { "sampler": 1, "target": { "node": node, "path": "rotation" } },
            ],
        }));
    }
    let source = match &atlas.source {
        AtlasSource::Texcoord1 => "texcoord1".to_string(),
        AtlasSource::Generated { unwrapper } => unwrapper.clone(),
    };
    let paths: Vec<Value> = scene.camera_paths.iter().map(exact::path_to_json).collect();
    let material_count = materials.len();
    let mut doc = json!({
        "asset": {
            "version": "2.0",
            "generator": concat!("lustre ", env!("CARGO_PKG_VERSION"), " scene export"),
            "extras": {
                "lustre_lightmap": {
                    "width": atlas.width, "height": atlas.height, "pages": atlas.pages,
                    "gutter": atlas.gutter, "texels_per_metre": atlas.texels_per_metre,
                    "source": source, "scene_meshes": scene.meshes.len(),
                },
                "lustre_scene": {
                    "version": 1,
                    "film": { "width": scene.film.width, "height": scene.film.height },
                    "environment": scene.environment.as_ref().map(|e| exact::environment_to_json(e, environment_texture)),
                    "probes": scene.probes,
                    "camera_paths": paths,
                },
            },
        },
        "scene": 0,
        "scenes": [{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "samplers": [
            { "magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497 },
            { "magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071 },
        ],
        "accessors": b.accessors,
        "bufferViews": b.views,
    });
    if !images.is_empty() {
        doc["images"] = json!(images);
        doc["textures"] = json!(textures);
    }
    if !cameras.is_empty() {
        doc["cameras"] = json!(cameras);
    }
    if !animations.is_empty() {
        doc["animations"] = json!(animations);
    }
    if !used_ext.is_empty() {
        doc["extensionsUsed"] = json!(used_ext.into_iter().collect::<Vec<_>>());
    }
    let out = crate::glb_write::glb_bytes(path, &doc, b.bin)?;
    crate::scene_file::write_atomic(path, &out)?;
    Ok(SceneExport {
        bytes: out.len(),
        meshes: scene.meshes.len(),
        triangles,
        materials: material_count,
        textures: scene.textures.len(),
        texture_bytes,
        lightmap_pages: pages.len(),
        lightmap_size: (atlas.width, atlas.height),
        lightmap_bytes,
        environment_bytes,
        cameras: scene.cameras.len(),
        animations: animations.len(),
        approximations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgbe_keeps_eight_bits_of_the_brightest_channel() {
        // Over 60 stops, every channel comes back within half a mantissa step of the largest
        // channel's scale, at most 1/256 of the largest channel.
        let mut x = 1.3e-9f32;
        while x < 1e9 {
            for c in [[x, 0.37 * x, 0.011 * x], [0.2 * x, x, 0.999 * x]] {
                let d = rgbe_decode(rgbe(c));
                for (a, b) in c.iter().zip(d) {
                    assert!((a - b).abs() <= x / 256.0 * 1.0001, "{c:?} → {d:?}");
                }
            }
            x *= 1.37;
        }
        // A texel that is m·2^(A−136) already (a Radiance .hdr as the image crate reads it)
        // comes back bit for bit.
        for p in [[128, 7, 0, 130], [255, 255, 255, 100], [1, 200, 3, 140]] {
            assert_eq!(rgbe(rgbe_decode(p)), p, "{p:?}");
        }
        assert_eq!(rgbe([0.0; 3]), [0; 4]);
        assert_eq!(rgbe([f32::NAN, 1.0, 1.0]), [0; 4]);
        assert_eq!(rgbe([-1.0, 0.0, 0.0]), [0; 4]);
        assert_eq!(rgbe_decode([0; 4]), [0.0; 3]);
        // A value that rounds up to the next power of two moves to the next exponent.
        assert_eq!(rgbe([0.999_9, 0.0, 0.0]), [128, 0, 0, 129]);
        assert_eq!(rgbe([0.99, 0.0, 0.0]), [253, 0, 0, 128]);
    }
}
