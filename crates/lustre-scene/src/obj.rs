//! Wavefront OBJ/MTL (through `tobj`): one mesh per object/group, MTL materials as diffuse
//! (Kd, map_Kd), emission from Ke — or, in files of the embree era such as the Cornell box, from
//! an ambient Ka above 1 (with a warning). Polygons are fan-triangulated; v is flipped to the glTF
//! convention (v = 0 at the top of an image).

use crate::error::{read_referenced, Result, SceneError};
use crate::material::{Material, MaterialKind, TexturedRgb};
use crate::mesh::Mesh;
use crate::texture::ColorSpace;
use crate::Scene;
use glam::{Vec2, Vec3};
use lustre_brdf::Rgb;
use std::cell::RefCell;
use std::io::BufReader;
use std::path::Path;

fn folder(path: &Path) -> &Path {
    path.parent().unwrap_or(Path::new(""))
}

/// Parses OBJ text; with `with_mtl`, the `mtllib` files are read relative to `path`'s folder (a
/// missing one is an error naming it), otherwise they are ignored (Mitsuba's `obj` shape).
pub(crate) fn parse(
    path: &Path,
    bytes: &[u8],
    with_mtl: bool,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>)> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let mtl_error: RefCell<Option<SceneError>> = RefCell::new(None);
    let loader = |mtl: &Path| -> tobj::MTLLoadResult {
        if !with_mtl {
            return Ok((Vec::new(), Default::default()));
        }
        let full = folder(path).join(mtl);
        match read_referenced(path, &full) {
            Ok(bytes) => {
                tobj::load_mtl_buf(&mut BufReader::new(bytes.as_slice())).inspect_err(|e| {
                    *mtl_error.borrow_mut() =
                        Some(SceneError::format(&full, format!("cannot parse MTL: {e}")));
                })
            }
            Err(e) => {
                *mtl_error.borrow_mut() = Some(e);
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    };
    let (models, materials) = tobj::load_obj_buf(&mut BufReader::new(bytes), &options, loader)
        .map_err(|e| SceneError::format(path, format!("cannot parse OBJ: {e}")))?;
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let materials = materials.map_err(|e| SceneError::format(path, format!("MTL: {e}")))?;
    Ok((models, materials))
}

/// A tobj model as a [`Mesh`] (object space), with `material`.
pub(crate) fn to_mesh(path: &Path, model: &tobj::Model, material: usize) -> Result<Mesh> {
    let m = &model.mesh;
    let err = |p: &str| SceneError::geometry(path, &model.name, p.to_string());
    if !m.positions.len().is_multiple_of(3)
        || !m.normals.len().is_multiple_of(3)
        || !m.texcoords.len().is_multiple_of(2)
    {
        return Err(err("attribute arrays are not whole vectors"));
    }
    if !m.indices.len().is_multiple_of(3) {
        return Err(err("triangulated index count is not a multiple of 3"));
    }
    let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(Vec3::from_slice).collect();
    let mut mesh = Mesh::new(
        model.name.clone(),
        positions,
        m.indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
        material,
    );
    if !m.normals.is_empty() {
        mesh.normals = Some(m.normals.chunks_exact(3).map(Vec3::from_slice).collect());
    }
    if !m.texcoords.is_empty() {
        mesh.uv0 = Some(
            m.texcoords
                .chunks_exact(2)
                .map(|t| Vec2::new(t[0], 1.0 - t[1]))
                .collect(),
        );
    }
    Ok(mesh)
}

/// Reads an OBJ scene from memory; `path` names it and its folder resolves `mtllib` and textures.
pub fn from_slice(path: &Path, bytes: &[u8]) -> Result<Scene> {
    let mut scene = Scene::new(path);
    let (models, mtls) = parse(path, bytes, true)?;
    let mut emission: Vec<Option<Rgb>> = Vec::new();
    for mtl in &mtls {
        let kd = mtl.diffuse.map_or(Rgb::splat(0.8), rgb);
        let mut reflectance = TexturedRgb::constant(kd);
        if let Some(tex) = mtl.diffuse_texture.as_deref() {
            let t = scene.texture(path, &folder(path).join(tex), ColorSpace::Srgb)?;
            reflectance.texture = Some(t);
        }
        if mtl.specular.is_some_and(|s| s.iter().any(|&c| c > 0.0)) {
            scene.warnings.push(format!(
                "{}: material {:?}: specular Ks ignored (read as diffuse)",
                path.display(),
                mtl.name
            ));
        }
        let e = match (mtl.emissive, mtl.ambient) {
            (Some(ke), _) if ke.iter().any(|&c| c > 0.0) => Some(rgb(ke)),
            (_, Some(ka)) if ka.iter().any(|&c| c > 1.0) => {
                scene.warnings.push(format!(
                    "{}: material {:?}: ambient Ka {:?} above 1 read as emitted radiance",
                    path.display(),
                    mtl.name,
                    ka
                ));
                Some(rgb(ka))
            }
            _ => None,
        };
        emission.push(e);
        scene.materials.push(Material::new(
            mtl.name.clone(),
            MaterialKind::Diffuse { reflectance },
        ));
    }
    let mut default_material = None;
    for model in &models {
        let material = match model.mesh.material_id {
            Some(i) if i < mtls.len() => i,
            _ => *default_material.get_or_insert_with(|| {
                scene
                    .materials
                    .push(Material::diffuse("default", Rgb::splat(0.8)));
                scene.materials.len() - 1
            }),
        };
        let mut mesh = to_mesh(path, model, material)?;
        mesh.emission = emission.get(material).copied().flatten();
        scene.push_mesh(path, mesh)?;
    }
    Ok(scene)
}

fn rgb(c: [f32; 3]) -> Rgb {
    Rgb::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2]))
}
