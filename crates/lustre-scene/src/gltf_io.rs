//! glTF 2.0 (`.gltf` with external or embedded buffers, `.glb`) through the `gltf` crate.
//!
//! Meshes are flattened to world space through the default scene's node hierarchy (one
//! [`Mesh`] per primitive); POSITION, NORMAL, TANGENT, TEXCOORD_0/1 and the indices are read
//! after checking every accessor's type and bounds. Materials become
//! [`MaterialKind::PbrMetallicRoughness`] with base-colour (sRGB), metallic-roughness, normal and
//! emissive (sRGB) textures, alpha mask (cutoff; `BLEND` read as a stochastic mask with a
//! warning), `KHR_materials_emissive_strength`, `_transmission`, `_ior`, `_anisotropy`
//! (strength and rotation), `_specular`, `_clearcoat` and `_sheen` (their factors; the
//! extensions' textures are listed as warnings and not read). A material's emissive factor × strength becomes its meshes'
//! [`Mesh::emission`]. Perspective cameras keep `yfov` ([`FovAxis::Y`]) and `aspectRatio`.
//!
//! A glTF has no film: when the first camera has an aspect ratio, the film is 720 rows at that
//! aspect, otherwise the default 1024×1024. A required extension outside
//! [`SUPPORTED_REQUIRED`] is [`SceneError::UnsupportedExtension`].

use crate::camera::{Camera, FovAxis};
use crate::error::{read_referenced, Result, SceneError};
use crate::material::{
    AlphaMask, Material, MaterialKind, NormalMap, TextureRef, TexturedRgb, TexturedScalar,
};
use crate::mesh::Mesh;
use crate::texture::{ColorSpace, Texture};
use crate::{Film, Scene};
use glam::{DMat4, DVec3, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use lustre_brdf::models::pbr_metallic_roughness::PbrLayers;
use lustre_brdf::Rgb;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Extensions a file may *require* and still be read.
pub const SUPPORTED_REQUIRED: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_materials_transmission",
    "KHR_materials_ior",
];

/// Extensions read when used (not required).
pub const SUPPORTED_USED: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_anisotropy",
    "KHR_materials_specular",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
];

/// The glTF extension objects of `layers` (those that differ from the core model), keyed by
/// extension name, as the exporter writes them and [`layers_from_extensions`] reads them.
pub fn layers_extensions(layers: &PbrLayers) -> Vec<(&'static str, serde_json::Value)> {
    use serde_json::json;
    let mut out = Vec::new();
    if layers.has_specular() {
        out.push((
            "KHR_materials_specular",
            json!({ "specularFactor": layers.specular,
                    "specularColorFactor": layers.specular_color.0 }),
        ));
    }
    if layers.has_clearcoat() {
        out.push((
            "KHR_materials_clearcoat",
            json!({ "clearcoatFactor": layers.clearcoat,
                    "clearcoatRoughnessFactor": layers.clearcoat_roughness }),
        ));
    }
    if layers.has_sheen() {
        out.push((
            "KHR_materials_sheen",
            json!({ "sheenColorFactor": layers.sheen_color.0,
                    "sheenRoughnessFactor": layers.sheen_roughness }),
        ));
    }
    out
}

/// The layers of a material's `KHR_materials_specular`, `_clearcoat` and `_sheen` objects
/// (`ext(name)`), with the specification's defaults for what is absent; each texture the
/// objects name goes to `ignored`. A factor of the wrong type or out of range is an error
/// naming it.
pub fn layers_from_extensions(
    ext: &dyn Fn(&str) -> Option<serde_json::Value>,
    ignored: &mut Vec<String>,
) -> std::result::Result<PbrLayers, String> {
    let mut l = PbrLayers::default();
    let num = |o: &serde_json::Value, k: &str, default: f64| -> std::result::Result<f64, String> {
        match o.get(k) {
            None => Ok(default),
            Some(v) => v
                .as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("{k} is not a finite number")),
        }
    };
    let rgb = |o: &serde_json::Value, k: &str, default: Rgb| -> std::result::Result<Rgb, String> {
        match o.get(k) {
            None => Ok(default),
            Some(v) => {
                let a = v
                    .as_array()
                    .filter(|a| a.len() == 3)
                    .ok_or_else(|| format!("{k} must be 3 numbers"))?;
                let mut c = [0.0; 3];
                for (o, x) in c.iter_mut().zip(a) {
                    *o = x
                        .as_f64()
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| format!("{k} must be 3 finite numbers"))?;
                }
                Ok(Rgb(c))
            }
        }
    };
    let mut textures = |o: &serde_json::Value, keys: &[&str]| {
        for k in keys {
            if o.get(*k).is_some() {
                ignored.push(format!("{k} ignored (its factor used)"));
            }
        }
    };
    if let Some(o) = ext("KHR_materials_specular") {
        l.specular = num(&o, "specularFactor", 1.0)?;
        l.specular_color = rgb(&o, "specularColorFactor", Rgb::ONE)?;
        textures(&o, &["specularTexture", "specularColorTexture"]);
    }
    if let Some(o) = ext("KHR_materials_clearcoat") {
        l.clearcoat = num(&o, "clearcoatFactor", 0.0)?;
        l.clearcoat_roughness = num(&o, "clearcoatRoughnessFactor", 0.0)?;
        textures(
            &o,
            &[
                "clearcoatTexture",
                "clearcoatRoughnessTexture",
                "clearcoatNormalTexture",
            ],
        );
    }
    if let Some(o) = ext("KHR_materials_sheen") {
        l.sheen_color = rgb(&o, "sheenColorFactor", Rgb::ZERO)?;
        l.sheen_roughness = num(&o, "sheenRoughnessFactor", 0.0)?;
        textures(&o, &["sheenColorTexture", "sheenRoughnessTexture"]);
    }
    l.validate().map_err(|e| e.to_string())?;
    Ok(l)
}

/// gltf 1.4.1 subtracts the 12-byte header from a GLB's declared length before checking it (an
/// overflow panic where overflow checks are on; found by the `gltf` fuzz target): check the header
/// here first. Files that do not start with the GLB magic are JSON and pass unchanged.
fn check_glb_header(bytes: &[u8]) -> std::result::Result<(), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let Some(length) = bytes.get(8..12) else {
        return Err(format!(
            "binary glTF (GLB) truncated: {} bytes, its header alone takes 12",
            bytes.len()
        ));
    };
    let declared = u32::from_le_bytes([length[0], length[1], length[2], length[3]]) as usize;
    if declared < 12 {
        return Err(format!(
            "binary glTF (GLB) header declares a total length of {declared} bytes, less than \
             the 12-byte header itself"
        ));
    }
    Ok(())
}

struct Reader<'a> {
    path: &'a Path,
    base: PathBuf,
    buffers: Vec<gltf::buffer::Data>,
    scene: Scene,
    images: HashMap<(usize, ColorSpace), usize>,
}

/// Reads a glTF file (`.gltf` or `.glb`) from memory; `path` names it and its folder resolves
/// external buffers and images.
pub fn from_slice(path: &Path, bytes: &[u8]) -> Result<Scene> {
    let fmt = |p: String| SceneError::format(path, p);
    let glb = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if glb && !bytes.starts_with(b"glTF") {
        let head: Vec<String> = bytes.iter().take(4).map(|b| format!("{b:02x}")).collect();
        return Err(fmt(format!(
            "not a binary glTF (GLB) file: it starts with {}, not the magic \"glTF\"",
            if head.is_empty() {
                "nothing (empty)".to_string()
            } else {
                head.join(" ")
            }
        )));
    }
    check_glb_header(bytes).map_err(fmt)?;
    let unvalidated = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| fmt(format!("not a valid glTF file: {e}")))?;
    for ext in unvalidated.extensions_required() {
        if !SUPPORTED_REQUIRED.contains(&ext) {
            return Err(SceneError::UnsupportedExtension {
                path: path.to_path_buf(),
                extension: ext.to_string(),
            });
        }
    }
    // gltf-json 1.4.1's validation indexes the POSITION accessor before checking that it
    // exists (a panic): check that reference first.
    let root = unvalidated.as_json();
    // glTF 2.x only: a 1.0 file (or a future 3.0) has another layout.
    let version = root.asset.version.trim();
    if version.split('.').next() != Some("2") {
        return Err(fmt(format!(
            "glTF version {version:?}: lustre reads glTF 2.x files only"
        )));
    }
    for (mi, mesh) in root.meshes.iter().enumerate() {
        for (pi, prim) in mesh.primitives.iter().enumerate() {
            for (sem, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    // The attribute's name as the file spells it (POSITION, TEXCOORD_1, ...).
                    let name = serde_json::to_value(sem)
                        .ok()
                        .and_then(|v| v.as_str().map(str::to_string))
                        .unwrap_or_else(|| "an attribute".into());
                    return Err(fmt(format!(
                        "mesh {mi} primitive {pi}: {name} names accessor {}, but the file has {} \
                         accessor(s)",
                        index.value(),
                        root.accessors.len()
                    )));
                }
            }
        }
    }
    // gltf 1.4.1 computes `offset + stride · (count − 1)` unchecked when it reads an accessor: a
    // count of 0 (the specification requires ≥ 1) or absurd sizes overflow (found by the `gltf`
    // fuzz target).
    const MAX_COUNT: u64 = 1 << 31;
    for (ai, acc) in root.accessors.iter().enumerate() {
        let sparse = acc.sparse.as_ref().map(|sp| sp.count.0);
        for (what, n) in [("count", Some(acc.count.0)), ("sparse count", sparse)] {
            match n {
                Some(n) if !(1..=MAX_COUNT).contains(&n) => {
                    return Err(fmt(format!(
                        "accessor {ai}: {what} {n} outside 1..={MAX_COUNT}"
                    )))
                }
                _ => {}
            }
        }
        let offset = acc.byte_offset.map_or(0, |o| o.0);
        if offset > MAX_COUNT {
            return Err(fmt(format!("accessor {ai}: byteOffset {offset} is absurd")));
        }
    }
    // gltf 1.4.1 unwraps an embedded image's mimeType and bufferView, or else its uri (the
    // specification requires them), when it reads the image's source: a panic without them
    // (found by the `gltf` fuzz target).
    for (ii, image) in root.images.iter().enumerate() {
        match (&image.buffer_view, &image.uri) {
            (Some(_), _) if image.mime_type.is_none() => {
                return Err(fmt(format!(
                    "image {ii} is in a bufferView but has no mimeType"
                )))
            }
            (Some(v), _) if v.value() >= root.buffer_views.len() => {
                return Err(fmt(format!(
                    "image {ii} names bufferView {}, but the file has {}",
                    v.value(),
                    root.buffer_views.len()
                )))
            }
            (None, None) => {
                return Err(fmt(format!(
                    "image {ii} has neither a uri nor a bufferView"
                )))
            }
            _ => {}
        }
    }
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice(bytes).map_err(|e| fmt(format!("invalid glTF: {e}")))?;
    let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut scene = Scene::new(path);
    for ext in document.extensions_used() {
        if !SUPPORTED_USED.contains(&ext) {
            scene.warnings.push(format!(
                "{}: extension {ext} is used but not supported: ignored",
                path.display()
            ));
        }
    }
    // Buffers: a missing external file is named; the rest goes through the gltf crate.
    for b in document.buffers() {
        if let gltf::buffer::Source::Uri(uri) = b.source() {
            if !uri.starts_with("data:") {
                let full = base.join(percent_decode(uri));
                if !full.exists() {
                    return Err(SceneError::MissingFile {
                        path: path.to_path_buf(),
                        referenced: full,
                    });
                }
            }
        }
    }
    let buffers = gltf::import_buffers(&document, Some(&base), blob)
        .map_err(|e| fmt(format!("cannot read buffers: {e}")))?;
    let mut r = Reader {
        path,
        base,
        buffers,
        scene,
        images: HashMap::new(),
    };
    let mut emission = Vec::new();
    for m in document.materials() {
        let (mat, e) = r.material(&m)?;
        r.scene.materials.push(mat);
        emission.push(e);
    }
    let roots: Vec<gltf::Node> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(s) => s.nodes().collect(),
        None => {
            r.scene.warnings.push(format!(
                "{}: no scene: every root node is read",
                path.display()
            ));
            let children: std::collections::HashSet<usize> = document
                .nodes()
                .flat_map(|n| n.children().map(|c| c.index()).collect::<Vec<_>>())
                .collect();
            document
                .nodes()
                .filter(|n| !children.contains(&n.index()))
                .collect()
        }
    };
    let mut default_material = None;
    // The node of each scene mesh, for the extras of a file lustre exported.
    let mut mesh_nodes = Vec::new();
    let mut stack: Vec<(gltf::Node, DMat4, usize)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY, 0))
        .collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > 256 {
            return Err(fmt(
                "the node hierarchy is deeper than 256 (a cycle?)".into()
            ));
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if !world.is_finite() {
            return Err(fmt(format!(
                "node {} has a non-finite transform",
                node.index()
            )));
        }
        if let Some(mesh) = node.mesh() {
            let prims: Vec<_> = mesh.primitives().collect();
            for (pi, prim) in prims.iter().enumerate() {
                let base_name = node
                    .name()
                    .or(mesh.name())
                    .map_or_else(|| format!("mesh{}", mesh.index()), str::to_string);
                let name = if prims.len() > 1 {
                    format!("{base_name}#{pi}")
                } else {
                    base_name
                };
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    r.scene.warnings.push(format!(
                        "{}: mesh {name:?}: primitive mode {:?} skipped (triangles only)",
                        path.display(),
                        prim.mode()
                    ));
                    continue;
                }
                let material = match prim.material().index() {
                    Some(i) => i,
                    None => *default_material.get_or_insert_with(|| {
                        let mut m = Material::new(
                            "gltf-default",
                            MaterialKind::PbrMetallicRoughness {
                                base_color: TexturedRgb::constant(Rgb::ONE),
                                metallic: TexturedScalar::constant(1.0),
                                roughness: TexturedScalar::constant(1.0),
                                transmission: TexturedScalar::constant(0.0),
                                ior: 1.5,
                                anisotropy: 0.0,
                                anisotropy_rotation: 0.0,
                                layers: PbrLayers::default(),
                            },
                        );
                        m.two_sided = false;
                        r.scene.materials.push(m);
                        emission.push(None);
                        r.scene.materials.len() - 1
                    }),
                };
                let mut m = r.primitive(prim, &name, material)?;
                m.transform(&world);
                m.emission = emission[material];
                r.scene.push_mesh(path, m)?;
                mesh_nodes.push(node.index());
            }
        }
        if let Some(cam) = node.camera() {
            match cam.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    let position = world.transform_point3(DVec3::ZERO);
                    let forward = world.transform_vector3(DVec3::NEG_Z);
                    let up = world.transform_vector3(DVec3::Y);
                    let fov = f64::from(p.yfov()).to_degrees();
                    let name = cam
                        .name()
                        .or(node.name())
                        .map_or_else(|| format!("camera{}", cam.index()), str::to_string);
                    let mut c =
                        Camera::look_at(name, position, position + forward, up, fov, FovAxis::Y)
                            .ok_or_else(|| {
                                fmt(format!(
                                    "camera {} has a degenerate transform or fov {fov}°",
                                    cam.index()
                                ))
                            })?;
                    c.aspect = p
                        .aspect_ratio()
                        .map(f64::from)
                        .filter(|a| a.is_finite() && *a > 0.0);
                    r.scene.cameras.push(c);
                }
                gltf::camera::Projection::Orthographic(_) => r.scene.warnings.push(format!(
                    "{}: orthographic camera {} skipped",
                    path.display(),
                    cam.index()
                )),
            }
        }
        let children: Vec<_> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
    }
    if let Some(aspect) = r.scene.cameras.first().and_then(|c| c.aspect) {
        let width = (720.0 * aspect).round();
        if (1.0..=65536.0).contains(&width) {
            r.scene.film = Film {
                width: width as u32,
                height: 720,
            };
        }
    }
    let raw = crate::lightmap::json_of(path, bytes)?;
    if raw.pointer("/asset/extras/lustre_scene").is_some() {
        r.lustre_extras(&document, &raw, &mesh_nodes)?;
    }
    Ok(r.scene)
}

/// The non-negative integer at `key` of `v`.
fn index_at(v: &serde_json::Value, key: &str) -> Option<usize> {
    v.get(key)?.as_u64().and_then(|x| usize::try_from(x).ok())
}

/// `%20`-style escapes in a URI path.
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && i + 2 < bytes.len()
            && uri.is_char_boundary(i + 1)
            && uri.is_char_boundary(i + 3)
        {
            if let Ok(b) = u8::from_str_radix(&uri[i + 1..i + 3], 16) {
                out.push(b);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

impl Reader<'_> {
    /// A file `lustre export scene` wrote (`asset.extras.lustre_scene`): the exact materials,
    /// emission, hints, cameras, camera paths, film, environment, room probes and the embedded
    /// light maps replace what the glTF core said ([`crate::export::scene`]).
    fn lustre_extras(
        &mut self,
        document: &gltf::Document,
        raw: &serde_json::Value,
        mesh_nodes: &[usize],
    ) -> Result<()> {
        use crate::export::exact;
        use serde_json::Value;
        let path = self.path;
        let fmt = |p: String| SceneError::format(path, p);
        let info = raw
            .pointer("/asset/extras/lustre_scene")
            .cloned()
            .unwrap_or(Value::Null);
        let version = info.get("version").and_then(Value::as_u64);
        if version != Some(1) {
            return Err(fmt(format!(
                "lustre_scene version {version:?}: this lustre reads version 1"
            )));
        }
        let empty = Vec::new();
        let arr = |k: &str| raw.get(k).and_then(Value::as_array).unwrap_or(&empty);
        let (materials, nodes, textures) = (arr("materials"), arr("nodes"), arr("textures"));
        // Materials, exactly.
        for (i, m) in materials.iter().enumerate() {
            let Some(v) = m.pointer("/extras/lustre_material") else {
                continue;
            };
            let name = self.scene.materials[i].name.clone();
            let mut load = |k: usize, uv: u8| -> Result<TextureRef> {
                let tex = document.textures().nth(k).ok_or_else(|| {
                    SceneError::material(&name, format!("lustre extras name texture {k}"))
                })?;
                let cs = match textures
                    .get(k)
                    .and_then(|t| t.pointer("/extras/lustre_color_space"))
                    .and_then(Value::as_str)
                {
                    Some("srgb") => ColorSpace::Srgb,
                    _ => ColorSpace::Linear,
                };
                self.texture_of(&tex, u32::from(uv), cs)
            };
            let exact =
                exact::material_from_json(&name, v, &mut load).map_err(|e| fmt(e.to_string()))?;
            self.scene.materials[i] = exact;
        }
        // Per mesh: emission, hints, and the light map's page and own UVs.
        let mut mesh_page = vec![None; self.scene.meshes.len()];
        let mut page_texture: Vec<Option<usize>> = Vec::new();
        for (i, &n) in mesh_nodes.iter().enumerate() {
            let Some(extras) = nodes.get(n).and_then(|n| n.get("extras")) else {
                continue;
            };
            let mesh = &mut self.scene.meshes[i];
            if let Some(h) = extras.get("lustre_hints") {
                mesh.hints = serde_json::from_value(h.clone())
                    .map_err(|e| fmt(format!("node {n}: lustre_hints: {e}")))?;
            }
            if let Some(e) = extras.get("lustre_emission") {
                let c: [f64; 3] = serde_json::from_value(e.clone())
                    .map_err(|e| fmt(format!("node {n}: lustre_emission: {e}")))?;
                mesh.emission = Some(Rgb(c));
            }
            let Some(page) = index_at(extras, "lightmap_page") else {
                continue;
            };
            if index_at(extras, "scene_mesh") != Some(i) {
                return Err(fmt(format!(
                    "node {n} ({:?}): its scene_mesh is not its place in the file ({i})",
                    mesh.name
                )));
            }
            if extras.get("uv0").and_then(Value::as_bool) == Some(false) {
                mesh.uv0 = None;
            }
            if mesh.uv1.is_none() {
                return Err(fmt(format!("mesh {:?} has no TEXCOORD_1", mesh.name)));
            }
            let material = raw
                .pointer(&format!(
                    "/meshes/{}/primitives/0/material",
                    nodes[n]["mesh"]
                ))
                .and_then(Value::as_u64)
                .and_then(|m| materials.get(m as usize));
            let Some(t) = material
                .and_then(|m| m.pointer("/extensions/MOZ_lightmap"))
                .and_then(|l| index_at(l, "index"))
            else {
                return Err(fmt(format!(
                    "mesh {:?} has a light-map page but its material no MOZ_lightmap",
                    mesh.name
                )));
            };
            if page_texture.len() <= page {
                page_texture.resize(page + 1, None);
            }
            if page_texture[page].is_some_and(|p| p != t) {
                return Err(fmt(format!("light-map page {page} is two textures")));
            }
            page_texture[page] = Some(t);
            mesh_page[i] = Some(page as u32);
        }
        let lm = crate::lightmap::atlas_info(path, raw)?;
        if lm.scene_meshes != self.scene.meshes.len() {
            return Err(fmt(format!(
                "lustre_lightmap describes {} meshes, the file has {}",
                lm.scene_meshes,
                self.scene.meshes.len()
            )));
        }
        let mut pages = Vec::new();
        for p in 0..lm.atlas.pages as usize {
            let t = page_texture.get(p).copied().flatten().ok_or_else(|| {
                fmt(format!(
                    "light-map page {p}: no mesh's material names its texture"
                ))
            })?;
            let what = format!("light-map page {p}");
            let (w, h, texels) = self.rgbe_texture(document, t, &what)?;
            if (w, h) != (lm.atlas.width, lm.atlas.height) {
                return Err(fmt(format!(
                    "{what} is {w}×{h}, the atlas's pages {}×{}",
                    lm.atlas.width, lm.atlas.height
                )));
            }
            pages.push(texels);
        }
        self.scene.lightmap = Some(crate::lightmap::SceneLightmap {
            atlas: crate::lightmap::LightmapAtlas {
                mesh_page,
                ..lm.atlas
            },
            atlas_file: path.to_path_buf(),
            pages: Vec::new(),
            embedded: pages,
        });
        // Cameras (the paths' own camera nodes are not scene cameras), paths, film, the rest.
        self.scene.cameras = nodes
            .iter()
            .filter(|n| n.pointer("/extras/lustre_path").is_none())
            .filter_map(|n| n.pointer("/extras/lustre_camera"))
            .map(|c| exact::camera_from_json(c).ok_or_else(|| fmt(format!("camera {c}"))))
            .collect::<Result<_>>()?;
        self.scene.camera_paths = info
            .get("camera_paths")
            .and_then(Value::as_array)
            .unwrap_or(&empty)
            .iter()
            .map(|p| exact::path_from_json(p).ok_or_else(|| fmt(format!("camera path {p}"))))
            .collect::<Result<_>>()?;
        if let (Some(w), Some(h)) = (
            info.pointer("/film/width").and_then(Value::as_u64),
            info.pointer("/film/height").and_then(Value::as_u64),
        ) {
            self.scene.film = Film {
                width: u32::try_from(w).map_err(|_| fmt(format!("film width {w}")))?,
                height: u32::try_from(h).map_err(|_| fmt(format!("film height {h}")))?,
            };
        }
        if let Some(e) = info.get("environment").filter(|e| !e.is_null()) {
            let mut map = |t: usize| {
                let (w, h, texels) = self.rgbe_texture(document, t, "the environment map")?;
                lustre_env::equirect::EquirectMap::new(w as usize, h as usize, texels)
                    .map_err(|e| fmt(format!("the environment map: {e}")))
            };
            self.scene.environment =
                Some(exact::environment_from_json(path, &self.base, e, &mut map)?);
        }
        if let Some(p) = info.get("probes") {
            self.scene.probes = serde_json::from_value(p.clone())
                .map_err(|e| fmt(format!("lustre_scene.probes: {e}")))?;
        }
        Ok(())
    }

    fn texture(&mut self, info: &gltf::texture::Info, cs: ColorSpace) -> Result<TextureRef> {
        self.texture_of(&info.texture(), info.tex_coord(), cs)
    }

    fn texture_of(
        &mut self,
        tex: &gltf::Texture,
        tex_coord: u32,
        cs: ColorSpace,
    ) -> Result<TextureRef> {
        if tex_coord > 1 {
            return Err(SceneError::format(
                self.path,
                format!(
                    "texture {} uses TEXCOORD_{tex_coord} (0 and 1 are read)",
                    tex.index()
                ),
            ));
        }
        let image = tex.source();
        let key = (image.index(), cs);
        let index = match self.images.get(&key) {
            Some(&i) => i,
            None => {
                let t = match image.source() {
                    gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
                        return Err(SceneError::format(
                            self.path,
                            format!("image {}: data-URI images are not supported", image.index()),
                        ))
                    }
                    gltf::image::Source::Uri { uri, .. } => {
                        let full = self.base.join(percent_decode(uri));
                        let bytes = read_referenced(self.path, &full)?;
                        Texture::decode(&full, &bytes, cs)?
                    }
                    gltf::image::Source::View { view, .. } => {
                        let data = self.view_bytes(&view)?;
                        let name = PathBuf::from(format!(
                            "{}#image{}",
                            self.path.display(),
                            image.index()
                        ));
                        Texture::decode(&name, data, cs)?
                    }
                };
                self.scene.textures.push(t);
                let i = self.scene.textures.len() - 1;
                self.images.insert(key, i);
                i
            }
        };
        Ok(TextureRef {
            texture: index,
            uv_set: tex_coord as u8,
        })
    }

    /// Texture `t`, an embedded PNG of RGBE texels (light-map pages, the environment map):
    /// its width, height and decoded texels. Errors name `what`.
    fn rgbe_texture(
        &self,
        document: &gltf::Document,
        t: usize,
        what: &str,
    ) -> Result<(u32, u32, Vec<[f32; 3]>)> {
        let fmt = |p: String| SceneError::format(self.path, format!("{what}: {p}"));
        let image = document
            .textures()
            .nth(t)
            .map(|t| t.source())
            .ok_or_else(|| fmt(format!("no texture {t}")))?;
        let gltf::image::Source::View { view, .. } = image.source() else {
            return Err(fmt("the image is not embedded".into()));
        };
        let img = image::load_from_memory(self.view_bytes(&view)?)
            .map_err(|e| fmt(e.to_string()))?
            .to_rgba8();
        let texels = img
            .pixels()
            .map(|px| crate::export::scene::rgbe_decode(px.0))
            .collect();
        Ok((img.width(), img.height(), texels))
    }

    fn view_bytes(&self, view: &gltf::buffer::View) -> Result<&[u8]> {
        let b = &self.buffers[view.buffer().index()];
        let end = view.offset().checked_add(view.length());
        match end {
            Some(end) if end <= b.len() => Ok(&b[view.offset()..end]),
            _ => Err(SceneError::format(
                self.path,
                format!("buffer view {} runs past its buffer", view.index()),
            )),
        }
    }

    fn material(&mut self, m: &gltf::Material) -> Result<(Material, Option<Rgb>)> {
        let name = m.name().map_or_else(
            || format!("material{}", m.index().unwrap_or(0)),
            str::to_string,
        );
        let pbr = m.pbr_metallic_roughness();
        let bc = pbr.base_color_factor();
        let mut base_color = TexturedRgb::constant(rgb3([bc[0], bc[1], bc[2]]));
        let mut bc_tex = None;
        if let Some(info) = pbr.base_color_texture() {
            let t = self.texture(&info, ColorSpace::Srgb)?;
            base_color.texture = Some(t);
            bc_tex = Some(t);
        }
        let mr_tex = match pbr.metallic_roughness_texture() {
            Some(info) => Some(self.texture(&info, ColorSpace::Linear)?),
            None => None,
        };
        let metallic = TexturedScalar {
            factor: f64::from(pbr.metallic_factor()),
            texture: mr_tex,
            channel: 2,
        };
        let roughness = TexturedScalar {
            factor: f64::from(pbr.roughness_factor()),
            texture: mr_tex,
            channel: 1,
        };
        let transmission = match m.transmission() {
            None => TexturedScalar::constant(0.0),
            Some(t) => TexturedScalar {
                factor: f64::from(t.transmission_factor()),
                texture: match t.transmission_texture() {
                    Some(info) => Some(self.texture(&info, ColorSpace::Linear)?),
                    None => None,
                },
                channel: 0,
            },
        };
        let ior = m.ior().map_or(1.5, f64::from);
        let (mut anisotropy, mut anisotropy_rotation) = (0.0, 0.0);
        if let Some(a) = m.extension_value("KHR_materials_anisotropy") {
            anisotropy = a
                .get("anisotropyStrength")
                .and_then(|v| v.as_f64())
                .unwrap_or(0.0);
            anisotropy_rotation = a
                .get("anisotropyRotation")
                .and_then(|v| v.as_f64())
                .unwrap_or(0.0);
            if a.get("anisotropyTexture").is_some() {
                self.scene.warnings.push(format!(
                    "{}: material {name:?}: anisotropyTexture ignored (strength and rotation used)",
                    self.path.display()
                ));
            }
        }
        let check = |what: &str, v: f64, lo: f64, hi: f64| -> Result<()> {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(SceneError::material(
                    &name,
                    format!("{what} = {v} outside [{lo}, {hi}]"),
                ))
            }
        };
        check("metallicFactor", metallic.factor, 0.0, 1.0)?;
        check("roughnessFactor", roughness.factor, 0.0, 1.0)?;
        check("transmissionFactor", transmission.factor, 0.0, 1.0)?;
        check("ior", ior, 1.0, 10.0)?;
        check("anisotropyStrength", anisotropy, 0.0, 1.0)?;
        check("anisotropyRotation", anisotropy_rotation, -1e3, 1e3)?;
        for (i, c) in bc.iter().enumerate() {
            check(&format!("baseColorFactor[{i}]"), f64::from(*c), 0.0, 1.0)?;
        }
        let warn = |scene: &mut Scene, what: String| {
            scene.warnings.push(format!(
                "{}: material {name:?}: {what}",
                self.path.display()
            ));
        };
        if transmission.factor > 0.0 && transmission.factor < 1.0 || transmission.texture.is_some()
        {
            warn(
                &mut self.scene,
                format!(
                "transmission {} read per hit as 0 or 1 (threshold 0.5): no partial transmission",
                transmission.factor
            ),
            );
        }
        let mut ignored = Vec::new();
        let layers = layers_from_extensions(&|k: &str| m.extension_value(k).cloned(), &mut ignored)
            .map_err(|e| SceneError::material(&name, e))?;
        for what in ignored {
            warn(&mut self.scene, what);
        }
        let mut mat = Material::new(
            name.clone(),
            MaterialKind::PbrMetallicRoughness {
                base_color,
                metallic,
                roughness,
                transmission,
                ior,
                anisotropy,
                anisotropy_rotation,
                layers,
            },
        );
        mat.two_sided = m.double_sided();
        let opacity = TexturedScalar {
            factor: f64::from(bc[3]),
            texture: bc_tex,
            channel: 3,
        };
        match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => {}
            gltf::material::AlphaMode::Mask => {
                let cutoff = m.alpha_cutoff().unwrap_or(0.5);
                if !cutoff.is_finite() {
                    return Err(SceneError::material(&name, "alphaCutoff is not finite"));
                }
                mat.alpha_mask = Some(AlphaMask {
                    opacity,
                    cutoff: Some(cutoff),
                });
            }
            gltf::material::AlphaMode::Blend => {
                self.scene.warnings.push(format!(
                    "{}: material {name:?}: alphaMode BLEND read as a stochastic mask",
                    self.path.display()
                ));
                mat.alpha_mask = Some(AlphaMask {
                    opacity,
                    cutoff: None,
                });
            }
        }
        if let Some(n) = m.normal_texture() {
            let t = self.texture_of(&n.texture(), n.tex_coord(), ColorSpace::Linear)?;
            mat.normal_map = Some(NormalMap {
                texture: t,
                scale: n.scale(),
            });
        }
        if let Some(info) = m.emissive_texture() {
            mat.emission_texture = Some(self.texture(&info, ColorSpace::Srgb)?);
        }
        let strength = f64::from(m.emissive_strength().unwrap_or(1.0));
        let e = rgb3(m.emissive_factor()) * strength;
        if !e.is_finite() || e.min_component() < 0.0 {
            return Err(SceneError::material(
                &name,
                format!("emission {:?} is negative or not finite", e.0),
            ));
        }
        let emission = (e.max_component() > 0.0).then_some(e);
        Ok((mat, emission))
    }

    /// Checks an accessor's type and that it lies inside its buffer.
    fn check_accessor(
        &self,
        a: &gltf::Accessor,
        mesh: &str,
        what: &str,
        dims: &[Dimensions],
        types: &[DataType],
    ) -> Result<()> {
        let err = |p: String| SceneError::geometry(self.path, mesh, format!("{what}: {p}"));
        if !dims.contains(&a.dimensions()) || !types.contains(&a.data_type()) {
            return Err(err(format!(
                "accessor {} is {:?} {:?}, expected {dims:?} of {types:?}",
                a.index(),
                a.dimensions(),
                a.data_type()
            )));
        }
        if a.sparse().is_some() {
            return Err(err(format!(
                "accessor {} is sparse (not supported)",
                a.index()
            )));
        }
        let Some(view) = a.view() else {
            return Err(err(format!("accessor {} has no buffer view", a.index())));
        };
        let data = self.view_bytes(&view)?;
        let size = a.size();
        let stride = view.stride().unwrap_or(size).max(size);
        if a.count() > 0 {
            let need = (a.count() - 1)
                .checked_mul(stride)
                .and_then(|v| v.checked_add(a.offset()))
                .and_then(|v| v.checked_add(size));
            if need.is_none_or(|n| n > data.len()) {
                return Err(err(format!(
                    "accessor {} ({} elements) runs past its buffer view",
                    a.index(),
                    a.count()
                )));
            }
        }
        Ok(())
    }

    fn primitive(&self, prim: &gltf::Primitive, name: &str, material: usize) -> Result<Mesh> {
        let geom = |p: String| SceneError::geometry(self.path, name, p);
        let f32s = [DataType::F32];
        let uv_types = [DataType::F32, DataType::U8, DataType::U16];
        for (sem, a) in prim.attributes() {
            use gltf::Semantic::*;
            match sem {
                Positions => {
                    self.check_accessor(&a, name, "POSITION", &[Dimensions::Vec3], &f32s)?
                }
                Normals => self.check_accessor(&a, name, "NORMAL", &[Dimensions::Vec3], &f32s)?,
                Tangents => self.check_accessor(&a, name, "TANGENT", &[Dimensions::Vec4], &f32s)?,
                TexCoords(0) | TexCoords(1) => {
                    self.check_accessor(&a, name, "TEXCOORD", &[Dimensions::Vec2], &uv_types)?
                }
                _ => {}
            }
        }
        if let Some(a) = prim.indices() {
            self.check_accessor(
                &a,
                name,
                "indices",
                &[Dimensions::Scalar],
                &[DataType::U8, DataType::U16, DataType::U32],
            )?;
        }
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(|d| d.0.as_slice()));
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| geom("no POSITION attribute".into()))?
            .map(Vec3::from_array)
            .collect();
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        if !indices.len().is_multiple_of(3) {
            return Err(geom(format!(
                "{} indices are not whole triangles",
                indices.len()
            )));
        }
        let mut mesh = Mesh::new(
            name,
            positions,
            indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
            material,
        );
        mesh.normals = reader
            .read_normals()
            .map(|n| n.map(Vec3::from_array).collect());
        mesh.tangents = reader
            .read_tangents()
            .map(|t| t.map(Vec4::from_array).collect());
        mesh.uv0 = reader
            .read_tex_coords(0)
            .map(|t| t.into_f32().map(Vec2::from_array).collect());
        mesh.uv1 = reader
            .read_tex_coords(1)
            .map(|t| t.into_f32().map(Vec2::from_array).collect());
        Ok(mesh)
    }
}

fn rgb3(c: [f32; 3]) -> Rgb {
    Rgb::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2]))
}
