//! glTF 2.0 (`.gltf` with external or embedded buffers, `.glb`) through the `gltf` crate.
//!
//! Meshes are flattened to world space through the default scene's node hierarchy (one
//! [`Mesh`] per primitive); POSITION, NORMAL, TANGENT, TEXCOORD_0/1 and the indices are read
//! after checking every accessor's type and bounds. Materials become
//! [`MaterialKind::PbrMetallicRoughness`] with base-colour (sRGB), metallic-roughness, normal and
//! emissive (sRGB) textures, alpha mask (cutoff; `BLEND` read as a stochastic mask with a
//! warning), `KHR_materials_emissive_strength`, `_transmission`, `_ior` and `_anisotropy`
//! (strength and rotation). A material's emissive factor × strength becomes its meshes'
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
];

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
    Ok(r.scene)
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
        if anisotropy != 0.0 {
            warn(
                &mut self.scene,
                format!(
                    "anisotropy {anisotropy} ignored: the glTF BRDF in lustre-brdf is isotropic"
                ),
            );
        }
        if transmission.factor == 0.0 && transmission.texture.is_none() && (ior - 1.5).abs() > 1e-6
        {
            warn(
                &mut self.scene,
                format!("ior {ior} ignored: the glTF BRDF uses 1.5 (F0 = 0.04)"),
            );
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
