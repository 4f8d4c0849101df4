//! The atlas as a binary glTF: the light-mapped meshes in world space with TEXCOORD_1 = the
//! light-map UVs, so other tools can read them, and so a scene file can carry the atlas.
//!
//! One node and one mesh (one triangle primitive, no material) per light-mapped scene mesh, in
//! scene order, both named after the mesh; attributes POSITION, NORMAL, TANGENT and TEXCOORD_0
//! where the mesh has them, TEXCOORD_1 always (and as TEXCOORD_0 of a mesh without its own
//! UVs: glTF numbers texture coordinates without gaps), `u32` indices. Extras:
//! - `asset.extras.lustre_lightmap`: `{ width, height, pages, gutter, texels_per_metre, source,
//!   scene_meshes }` (the atlas, and the number of meshes of the scene it was made for);
//! - each node's (and mesh's) `extras`: `{ lightmap_page, scene_mesh, uv0 }` (the page, the mesh's
//!   index in the scene, and whether TEXCOORD_0 is the mesh's own).

use super::{AtlasSource, LightmapAtlas};
use crate::error::{Result, SceneError};
use crate::glb_write::Builder;
use crate::Scene;
use serde_json::{json, Value};
use std::path::Path;

/// Writes atomically to `path` a binary glTF with every light-mapped mesh of `scene` (world
/// space; POSITION, NORMAL, TANGENT, TEXCOORD_0 where present, TEXCOORD_1 = the light-map UVs;
/// node and mesh named after the mesh; page in the node's extras; see the module documentation).
/// Errors: an atlas that does not describe this scene (mesh count), a light-mapped mesh without
/// `uv1`, an I/O failure (naming `path`).
pub fn write_atlas_glb(scene: &Scene, atlas: &LightmapAtlas, path: &Path) -> Result<()> {
    let fmt = |p: String| SceneError::format(path, p);
    if atlas.mesh_page.len() != scene.meshes.len() {
        return Err(fmt(format!(
            "the atlas describes {} meshes, the scene has {}",
            atlas.mesh_page.len(),
            scene.meshes.len()
        )));
    }
    let mut b = Builder::default();
    let (mut nodes, mut meshes) = (Vec::new(), Vec::new());
    for (i, (m, page)) in scene.meshes.iter().zip(&atlas.mesh_page).enumerate() {
        let Some(page) = page else { continue };
        let Some(uv1) = &m.uv1 else {
            return Err(SceneError::geometry(
                path,
                &m.name,
                "light-mapped mesh without uv1",
            ));
        };
        let mut attributes = b.mesh_attributes(m);
        let u: Vec<[f32; 2]> = uv1.iter().map(|v| v.to_array()).collect();
        let lightmap_uv = b.floats(&u, "VEC2", false);
        attributes.insert("TEXCOORD_1".into(), json!(lightmap_uv));
        // glTF numbers TEXCOORD_n from 0 without gaps: a mesh without its own UVs gets the
        // light-map UVs as TEXCOORD_0 too (the same accessor), marked `uv0: false`.
        if m.uv0.is_none() {
            attributes.insert("TEXCOORD_0".into(), json!(lightmap_uv));
        }
        let indices = b.indices(&m.indices);
        let extras = json!({ "lightmap_page": page, "scene_mesh": i, "uv0": m.uv0.is_some() });
        meshes.push(json!({
            "name": m.name,
            "primitives": [{ "attributes": attributes, "indices": indices, "mode": 4 }],
            "extras": extras,
        }));
        nodes.push(json!({ "name": m.name, "mesh": meshes.len() - 1, "extras": extras }));
    }
    let source = match &atlas.source {
        AtlasSource::Texcoord1 => "texcoord1".to_string(),
        AtlasSource::Generated { unwrapper } => unwrapper.clone(),
    };
    let doc = json!({
        "asset": {
            "version": "2.0",
            "generator": "lustre light-map atlas",
            "extras": { "lustre_lightmap": {
                "width": atlas.width,
                "height": atlas.height,
                "pages": atlas.pages,
                "gutter": atlas.gutter,
                "texels_per_metre": atlas.texels_per_metre,
                "source": source,
                "scene_meshes": scene.meshes.len(),
            }},
        },
        "scene": 0,
        "scenes": [{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
        "accessors": b.accessors,
        "bufferViews": b.views,
    });
    let out = crate::glb_write::glb_bytes(path, &doc, b.bin)?;
    crate::scene_file::write_atomic(path, &out)
}

/// The JSON chunk of a GLB (or the text of a `.gltf`).
pub(crate) fn json_of(path: &Path, bytes: &[u8]) -> Result<Value> {
    let fmt = |p: String| SceneError::format(path, p);
    let json = if bytes.starts_with(b"glTF") {
        if bytes.len() < 20 {
            return Err(fmt("truncated GLB header".into()));
        }
        let len = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
        if &bytes[16..20] != b"JSON" || bytes.len() < 20 + len {
            return Err(fmt("GLB without a complete JSON chunk".into()));
        }
        &bytes[20..20 + len]
    } else {
        bytes
    };
    serde_json::from_slice(json).map_err(|e| fmt(format!("invalid glTF JSON: {e}")))
}

fn field_u32(v: &Value, key: &str) -> Option<u32> {
    v.get(key)?.as_u64().and_then(|x| u32::try_from(x).ok())
}

/// An atlas as `asset.extras.lustre_lightmap` describes it (no meshes' pages yet), and the
/// number of meshes of the scene it was made for.
pub(crate) struct AtlasInfo {
    pub atlas: LightmapAtlas,
    pub scene_meshes: usize,
}

/// Reads `asset.extras.lustre_lightmap` of a glTF's JSON; errors name `path`.
pub(crate) fn atlas_info(path: &Path, json: &Value) -> Result<AtlasInfo> {
    let fmt = |p: String| SceneError::format(path, p);
    let info = json
        .pointer("/asset/extras/lustre_lightmap")
        .ok_or_else(|| {
            fmt("no asset.extras.lustre_lightmap: not a lustre light-map atlas".into())
        })?;
    let get = |k: &str| {
        field_u32(info, k).ok_or_else(|| fmt(format!("lustre_lightmap.{k} missing or invalid")))
    };
    let (width, height, pages, gutter) =
        (get("width")?, get("height")?, get("pages")?, get("gutter")?);
    let scene_meshes = get("scene_meshes")? as usize;
    let texels_per_metre = info
        .get("texels_per_metre")
        .and_then(Value::as_f64)
        .filter(|d| d.is_finite() && *d > 0.0)
        .ok_or_else(|| fmt("lustre_lightmap.texels_per_metre missing or invalid".into()))?
        as f32;
    let source = match info.get("source").and_then(Value::as_str) {
        Some("texcoord1") => AtlasSource::Texcoord1,
        Some(s) => AtlasSource::Generated {
            unwrapper: s.to_string(),
        },
        None => return Err(fmt("lustre_lightmap.source missing".into())),
    };
    if width == 0 || height == 0 || pages == 0 || width > 65536 || height > 65536 {
        return Err(fmt(format!(
            "atlas of {pages} pages of {width}×{height} texels is invalid"
        )));
    }
    Ok(AtlasInfo {
        atlas: LightmapAtlas {
            width,
            height,
            pages,
            mesh_page: Vec::new(),
            gutter,
            texels_per_metre,
            source,
        },
        scene_meshes,
    })
}

/// Reads an atlas written by [`write_atlas_glb`] onto `scene`: each light-mapped mesh's
/// vertices and indices are replaced by the file's (matched by the scene-mesh index in the
/// extras and checked by name and triangle count), and the atlas is returned. Errors name the
/// file: not such a file, or made for another scene (mesh count, names, triangle counts).
pub fn read_atlas_glb(path: &Path, scene: &mut Scene) -> Result<LightmapAtlas> {
    let fmt = |p: String| SceneError::format(path, p);
    let bytes = crate::error::read_referenced(&scene.source.clone(), path)?;
    let json = json_of(path, &bytes)?;
    let AtlasInfo {
        atlas,
        scene_meshes,
    } = atlas_info(path, &json)?;
    let LightmapAtlas {
        width,
        height,
        pages,
        gutter,
        texels_per_metre,
        source,
        ..
    } = atlas;
    if scene_meshes != scene.meshes.len() {
        return Err(fmt(format!(
            "made for a scene of {scene_meshes} meshes, this one ({}) has {}",
            scene.source.display(),
            scene.meshes.len()
        )));
    }
    let nodes = json
        .get("nodes")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default();
    let loaded = crate::gltf_io::from_slice(path, &bytes)?;
    if loaded.meshes.len() != nodes.len() {
        return Err(fmt(format!(
            "{} nodes but {} triangle meshes",
            nodes.len(),
            loaded.meshes.len()
        )));
    }
    let mut mesh_page = vec![None; scene.meshes.len()];
    let mut last = None;
    for (k, (node, m)) in nodes.iter().zip(loaded.meshes).enumerate() {
        let extras = node.get("extras");
        let (Some(idx), Some(page)) = (
            extras.and_then(|e| field_u32(e, "scene_mesh")),
            extras.and_then(|e| field_u32(e, "lightmap_page")),
        ) else {
            return Err(fmt(format!(
                "node {k} ({:?}) has no scene_mesh / lightmap_page extras",
                m.name
            )));
        };
        let idx = idx as usize;
        if idx >= scene.meshes.len() || last.is_some_and(|l| idx <= l) || page >= pages {
            return Err(fmt(format!(
                "node {k} ({:?}): scene mesh {idx} / page {page} out of order or range",
                m.name
            )));
        }
        last = Some(idx);
        let target = &mut scene.meshes[idx];
        if target.name != m.name {
            return Err(fmt(format!(
                "mesh {k} is {:?} but scene mesh {idx} is {:?}: the atlas was made for another \
                 scene",
                m.name, target.name
            )));
        }
        if target.indices.len() != m.indices.len() {
            return Err(fmt(format!(
                "mesh {:?} has {} triangles, the scene's has {}: the atlas was made for other \
                 geometry",
                m.name,
                m.indices.len(),
                target.indices.len()
            )));
        }
        if m.uv1.is_none() {
            return Err(fmt(format!("mesh {:?} has no TEXCOORD_1", m.name)));
        }
        target.positions = m.positions;
        target.normals = m.normals;
        target.tangents = m.tangents;
        // `uv0: false`: TEXCOORD_0 repeats the light-map UVs (the writer's note above).
        let own_uv0 = extras.and_then(|e| e.get("uv0")).and_then(Value::as_bool);
        target.uv0 = if own_uv0 == Some(false) { None } else { m.uv0 };
        target.uv1 = m.uv1;
        target.indices = m.indices;
        mesh_page[idx] = Some(page);
    }
    Ok(LightmapAtlas {
        width,
        height,
        pages,
        mesh_page,
        gutter,
        texels_per_metre,
        source,
    })
}
