//! The lustre scene file: TOML, schema `lustre-scene`, version 1.
//!
//! ```toml
//! schema = "lustre-scene"
//! version = 1
//! film = { width = 1280, height = 720 }
//!
//! [[geometry]]
//! file = "modern_hall/mitsuba/scene.xml"   # .xml, .gltf, .glb or .obj; relative to this file
//! # transform = [16 numbers, row-major]     # optional, applied to the file's meshes
//!
//! [environment]                             # exactly one of map, constant, sky
//! map = "envmaps/venice_sunset_1k.hdr"
//! rotation_deg = 90.0                       # about +y
//! intensity = 1.0
//!
//! [[camera]]
//! name = "stairs"
//! position = [6.9, 1.65, 2.55]
//! look_at = [0.0, 1.5, 0.0]                 # or forward = [...]
//! up = [0.0, 1.0, 0.0]
//! fov_deg = 70.0
//! fov_axis = "x"                            # x, y, diagonal, smaller, larger
//!
//! [[camera_path]]
//! name = "walk"
//! looped = false
//! keyframes = [{ time = 0.0, camera = "default" }, { time = 4.0, camera = "stairs" }]
//!
//! [materials]                               # overrides: material name = lustre material spec
//! Wood = "sgd:pink-fabric"
//!
//! [[emitter]]                               # an extra area emitter, or `object = "NAME"`
//! shape = "rectangle"                       # rectangle, disk, cube or sphere
//! transform = [1, 0, 0, 0,  0, 1, 0, 3,  0, 0, 1, 0,  0, 0, 0, 1]
//! radiance = [5.0, 5.0, 5.0]
//!
//! [objects.Mesh011]                         # hints for the real-time renderer, by mesh name
//! planar_reflector = true
//! lightmap_texels_per_metre = 64.0
//!
//! [objects.Mesh014]
//! probe = true                              # a reflection probe for this object,
//! probe_centre = [-1.8, 5.2, -1.5]          # optional: captured here (else its bounds' centre)
//! thickness = 0.035                         # optional: a solid glass slab (refraction offset)
//!
//! [[probe]]                                 # a room probe (`lustre bake` places them
//! name = "room-1"                           # when the file lists none): captured at centre,
//! centre = [0.0, 1.5, 0.0]                  # lookups corrected against the box (optional;
//! box_min = [-4.0, 0.0, -3.0]               # else measured by ray casting from the centre)
//! box_max = [4.0, 3.0, 3.0]
//!
//! [lightmap]                                # light-map UVs and baked pages (`lustre bake`)
//! atlas = "lightmap.glb"                    # the atlas: light-mapped meshes with TEXCOORD_1
//! pages = ["lightmap_000.exr"]              # one per atlas page; [] before baking
//! texels_per_metre = 32.0                   # optional: checked against the atlas
//! gutter = 4                                # optional: checked against the atlas
//! ```
//!
//! With a `[lightmap]` section, [`build`] reads the atlas ([`crate::lightmap::read_atlas_glb`]):
//! each light-mapped mesh's vertices and indices are replaced by the atlas's (matched by order
//! and name; a mismatch is an error naming the `.glb`), so `Mesh::uv1` holds the light-map UVs,
//! and [`Scene::lightmap`] holds the atlas and the page paths. [`SceneFile::with_lightmap`] adds
//! the section to a file; [`SceneFile::for_geometry`] wraps a `.xml`/`.gltf`/`.glb`/`.obj` scene.
//!
//! [`parse`] checks, in this order: the TOML syntax, the `schema`, the `version`, the fields
//! (unknown ones are errors), then every value ([`SceneFile::validate`]); names that refer to
//! the loaded geometry (materials, objects, cameras of keyframes) are checked when the scene is
//! built ([`build`]). [`SceneFile::to_toml`] and [`write`] validate the same way; `write` is
//! atomic.

use crate::camera::{Camera, CameraPath, FovAxis, Keyframe};
use crate::environment::{Environment, EnvironmentSource, Sky};
use crate::error::{Result, SceneError};
use crate::material::{Material, MaterialKind, ResolvedSpec};
use crate::mesh::{self, ObjectHints};
use crate::probe_site::{ProbeSite, MAX_PROBE_SITES};
use crate::{Film, Scene};
use glam::{DMat3, DMat4, DVec3};
use lustre_brdf::Rgb;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

/// The `schema` field of every lustre scene file.
pub const SCHEMA: &str = "lustre-scene";
/// The version this build reads and writes.
pub const VERSION: u32 = 1;

/// A lustre scene file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Always [`SCHEMA`].
    pub schema: String,
    /// Always [`VERSION`] for files this build writes.
    pub version: u32,
    /// Film size; the first geometry file's when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub film: Option<Film>,
    /// Geometry files, merged in order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub geometry: Vec<GeometryEntry>,
    /// Distant lighting (replaces the geometry files').
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub environment: Option<EnvironmentEntry>,
    /// Named cameras (added after the geometry files' cameras).
    #[serde(default, rename = "camera", skip_serializing_if = "Vec::is_empty")]
    pub cameras: Vec<CameraEntry>,
    /// Camera paths.
    #[serde(default, rename = "camera_path", skip_serializing_if = "Vec::is_empty")]
    pub camera_paths: Vec<CameraPathEntry>,
    /// Material overrides: material name → lustre material spec.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub materials: BTreeMap<String, String>,
    /// Material parameters set after the overrides: `"MATERIAL.PARAMETER" = "VALUE"`
    /// (`crate::material_edit`; what `lustre view` saves), in key order.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub material_params: BTreeMap<String, String>,
    /// Extra emitters.
    #[serde(default, rename = "emitter", skip_serializing_if = "Vec::is_empty")]
    pub emitters: Vec<EmitterEntry>,
    /// Real-time hints by mesh name.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub objects: BTreeMap<String, ObjectHints>,
    /// Room-scale reflection probes.
    #[serde(default, rename = "probe", skip_serializing_if = "Vec::is_empty")]
    pub probes: Vec<ProbeSite>,
    /// The light map: atlas and baked pages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lightmap: Option<LightmapEntry>,
}

/// The `[lightmap]` section: the atlas `.glb` ([`crate::lightmap::write_atlas_glb`]) and one
/// image per page, relative to the scene file's folder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightmapEntry {
    /// The atlas (`.glb`).
    pub atlas: String,
    /// One image per atlas page (normally half-float EXR), in page order; empty before baking.
    #[serde(default)]
    pub pages: Vec<String>,
    /// The atlas's density (texels per metre); checked against the atlas when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texels_per_metre: Option<f32>,
    /// The atlas's gutter in texels; checked against the atlas when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gutter: Option<u32>,
}

/// One geometry file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeometryEntry {
    /// The file (`.xml`, `.gltf`, `.glb`, `.obj`), relative to the scene file's folder.
    pub file: String,
    /// Row-major 4×4 transform applied to its meshes (and cameras).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<[f64; 16]>,
}

/// The environment: exactly one of `map`, `constant`, `sky`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentEntry {
    /// An equirect `.hdr`/`.exr` map, relative to the scene file's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map: Option<String>,
    /// A constant radiance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub constant: Option<[f64; 3]>,
    /// The built-in sky with its colours.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sky: Option<Sky>,
    /// Rotation of the map about +y in degrees (right-handed).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub rotation_deg: f64,
    /// Radiance scale.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub intensity: f64,
}

/// A named camera.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraEntry {
    /// Unique name.
    pub name: String,
    /// Centre of projection.
    pub position: [f64; 3],
    /// A point to look at (give this or `forward`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub look_at: Option<[f64; 3]>,
    /// A viewing direction (give this or `look_at`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forward: Option<[f64; 3]>,
    /// Up hint.
    #[serde(default = "y_up")]
    pub up: [f64; 3],
    /// Field of view in degrees along `fov_axis`.
    pub fov_deg: f64,
    /// The film axis of `fov_deg`.
    #[serde(default)]
    pub fov_axis: FovAxis,
}

/// A camera path over named cameras.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraPathEntry {
    /// Unique name.
    pub name: String,
    /// Start again after the last keyframe.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub looped: bool,
    /// Keyframes by strictly increasing time.
    pub keyframes: Vec<KeyframeEntry>,
}

/// One keyframe: a time and a camera name (of this file or of a geometry file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyframeEntry {
    /// Seconds from the path's start.
    pub time: f64,
    /// A camera name.
    pub camera: String,
}

/// Analytic emitter shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    /// [−1, 1]² in z = 0, emitting towards +z.
    Rectangle,
    /// The unit disk in z = 0, emitting towards +z.
    Disk,
    /// [−1, 1]³.
    Cube,
    /// The unit sphere.
    Sphere,
}

/// An emitter: an existing mesh made emissive (`object`), or a new shape (`shape`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmitterEntry {
    /// Make the meshes of this name emit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub object: Option<String>,
    /// Or add this shape.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<ShapeKind>,
    /// Row-major 4×4 transform of the shape.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<[f64; 16]>,
    /// Emitted radiance (linear RGB, ≥ 0).
    pub radiance: [f64; 3],
}

fn one() -> f64 {
    1.0
}
fn is_one(v: &f64) -> bool {
    *v == 1.0
}
fn is_zero(v: &f64) -> bool {
    *v == 0.0
}
fn y_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

fn finite(name: &str, v: &[f64]) -> std::result::Result<(), String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("{name} has a non-finite value {v:?}"))
    }
}

fn matrix(m: &[f64; 16]) -> DMat4 {
    DMat4::from_cols_array(m).transpose()
}

impl SceneFile {
    /// An empty file of this schema and version.
    pub fn new() -> Self {
        SceneFile {
            schema: SCHEMA.to_string(),
            version: VERSION,
            film: None,
            geometry: Vec::new(),
            environment: None,
            cameras: Vec::new(),
            camera_paths: Vec::new(),
            materials: BTreeMap::new(),
            material_params: BTreeMap::new(),
            emitters: Vec::new(),
            objects: BTreeMap::new(),
            probes: Vec::new(),
            lightmap: None,
        }
    }

    /// A file whose only geometry is `file` (a `.xml`, `.gltf`, `.glb` or `.obj`, absolute or
    /// relative to the scene file that will hold this), to which a `[lightmap]` can be added.
    pub fn for_geometry(file: &str) -> SceneFile {
        SceneFile {
            geometry: vec![GeometryEntry {
                file: file.to_string(),
                transform: None,
            }],
            ..SceneFile::new()
        }
    }

    /// This file with a `[lightmap]` section for `atlas` (written by
    /// [`crate::lightmap::write_atlas_glb`] to `atlas_glb`) and its baked `pages` (one per atlas
    /// page, or none before baking), paths relative to the folder of the scene file that will
    /// hold it. Density and gutter are recorded for the check on load.
    pub fn with_lightmap(
        mut self,
        atlas_glb: &str,
        pages: Vec<String>,
        atlas: &crate::lightmap::LightmapAtlas,
    ) -> SceneFile {
        self.lightmap = Some(LightmapEntry {
            atlas: atlas_glb.to_string(),
            pages,
            texels_per_metre: Some(atlas.texels_per_metre),
            gutter: Some(atlas.gutter),
        });
        self
    }

    /// This file with every relative path (geometry, environment map, material files, light
    /// map) made absolute against `base` (the folder of the file it was read from), so that it
    /// can be written to another folder.
    pub fn with_absolute_paths(mut self, base: &Path) -> SceneFile {
        let abs = |p: &str| -> String {
            if Path::new(p).is_absolute() {
                p.to_string()
            } else {
                base.join(p).to_string_lossy().into_owned()
            }
        };
        for g in &mut self.geometry {
            g.file = abs(&g.file);
        }
        if let Some(e) = &mut self.environment {
            if let Some(m) = &mut e.map {
                *m = abs(m);
            }
        }
        for spec in self.materials.values_mut() {
            *spec = resolve_spec_path(base, spec);
        }
        if let Some(l) = &mut self.lightmap {
            l.atlas = abs(&l.atlas);
            for p in &mut l.pages {
                *p = abs(p);
            }
        }
        self
    }

    /// Checks every value; the error names the field.
    pub fn validate(&self) -> std::result::Result<(), String> {
        if self.schema != SCHEMA {
            return Err(format!("schema is {:?}, expected {SCHEMA:?}", self.schema));
        }
        if self.version != VERSION {
            return Err(format!(
                "version {} is not supported (this build reads {VERSION})",
                self.version
            ));
        }
        if let Some(f) = self.film {
            if f.width == 0 || f.height == 0 || f.width > 65536 || f.height > 65536 {
                return Err(format!(
                    "film {}×{} is not 1..=65536 pixels",
                    f.width, f.height
                ));
            }
        }
        for (i, g) in self.geometry.iter().enumerate() {
            if g.file.trim().is_empty() {
                return Err(format!("geometry[{i}].file is empty"));
            }
            if let Some(t) = &g.transform {
                finite(&format!("geometry[{i}].transform"), t)?;
                if matrix(t).determinant() == 0.0 {
                    return Err(format!("geometry[{i}].transform is singular"));
                }
            }
        }
        if let Some(e) = &self.environment {
            let n = usize::from(e.map.is_some())
                + usize::from(e.constant.is_some())
                + usize::from(e.sky.is_some());
            if n != 1 {
                return Err("environment needs exactly one of map, constant, sky".into());
            }
            finite("environment.rotation_deg", &[e.rotation_deg])?;
            if !(e.intensity.is_finite() && e.intensity >= 0.0) {
                return Err(format!(
                    "environment.intensity {} must be finite and ≥ 0",
                    e.intensity
                ));
            }
            let colours = e
                .constant
                .iter()
                .copied()
                .chain(e.sky.iter().flat_map(|s| [s.zenith, s.horizon, s.ground]));
            for c in colours {
                if !c.iter().all(|v| v.is_finite() && *v >= 0.0) {
                    return Err(format!("environment colour {c:?} must be finite and ≥ 0"));
                }
            }
        }
        for (name, hints) in &self.objects {
            if let Some(n) = hints.samples {
                if !(1..=crate::mesh::MAX_OBJECT_SAMPLES).contains(&n) {
                    return Err(format!(
                        "objects.{name}.samples = {n} is outside 1..={}",
                        crate::mesh::MAX_OBJECT_SAMPLES
                    ));
                }
            }
            if let Some(c) = &hints.probe_centre {
                finite(&format!("objects.{name}.probe_centre"), c)?;
                if !hints.probe {
                    return Err(format!("objects.{name}: probe_centre without probe = true"));
                }
            }
        }
        if self.probes.len() > MAX_PROBE_SITES {
            return Err(format!(
                "{} probes: at most {MAX_PROBE_SITES}",
                self.probes.len()
            ));
        }
        let mut probe_names = std::collections::HashSet::new();
        for p in &self.probes {
            p.validate()?;
            if !probe_names.insert(p.name.as_str()) {
                return Err(format!("probe name {:?} is given twice", p.name));
            }
        }
        let mut names = std::collections::HashSet::new();
        for c in &self.cameras {
            if c.name.trim().is_empty() || !names.insert(c.name.as_str()) {
                return Err(format!("camera name {:?} is empty or given twice", c.name));
            }
            finite(&format!("camera {:?} position", c.name), &c.position)?;
            finite(&format!("camera {:?} up", c.name), &c.up)?;
            if c.look_at.is_some() == c.forward.is_some() {
                return Err(format!(
                    "camera {:?} needs exactly one of look_at, forward",
                    c.name
                ));
            }
            if !(c.fov_deg > 0.0 && c.fov_deg < 180.0) {
                return Err(format!(
                    "camera {:?} fov_deg {} must lie in (0, 180)",
                    c.name, c.fov_deg
                ));
            }
            if self.camera_entry(c).is_none() {
                return Err(format!(
                    "camera {:?}: zero view direction or up parallel to it",
                    c.name
                ));
            }
        }
        let mut paths = std::collections::HashSet::new();
        for p in &self.camera_paths {
            if p.name.trim().is_empty() || !paths.insert(p.name.as_str()) {
                return Err(format!(
                    "camera path name {:?} is empty or given twice",
                    p.name
                ));
            }
            if p.keyframes.is_empty() {
                return Err(format!("camera path {:?} has no keyframes", p.name));
            }
            let mut last = f64::NEG_INFINITY;
            for k in &p.keyframes {
                if !k.time.is_finite() || k.time <= last {
                    return Err(format!(
                        "camera path {:?}: keyframe times must be finite and strictly increasing ({} after {last})",
                        p.name, k.time
                    ));
                }
                last = k.time;
            }
        }
        for (name, spec) in &self.materials {
            if spec.trim().is_empty() {
                return Err(format!("materials.{name:?} is an empty spec"));
            }
        }
        for (i, e) in self.emitters.iter().enumerate() {
            if e.object.is_some() == e.shape.is_some() {
                return Err(format!("emitter[{i}] needs exactly one of object, shape"));
            }
            if !e.radiance.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(format!(
                    "emitter[{i}].radiance {:?} must be finite and ≥ 0",
                    e.radiance
                ));
            }
            if let Some(t) = &e.transform {
                finite(&format!("emitter[{i}].transform"), t)?;
                if e.object.is_some() {
                    return Err(format!(
                        "emitter[{i}]: a transform applies to a shape, not an object"
                    ));
                }
            }
        }
        if let Some(l) = &self.lightmap {
            if l.atlas.trim().is_empty() {
                return Err("lightmap.atlas is empty".into());
            }
            let mut seen = std::collections::HashSet::new();
            for (i, p) in l.pages.iter().enumerate() {
                if p.trim().is_empty() || !seen.insert(p.as_str()) {
                    return Err(format!("lightmap.pages[{i}] {p:?} is empty or given twice"));
                }
            }
            if let Some(d) = l.texels_per_metre {
                if !(d.is_finite() && d > 0.0) {
                    return Err(format!("lightmap.texels_per_metre {d} must be > 0"));
                }
            }
        }
        for (name, h) in &self.objects {
            if let Some(d) = h.lightmap_texels_per_metre {
                if !(d.is_finite() && d > 0.0) {
                    return Err(format!(
                        "objects.{name:?}.lightmap_texels_per_metre {d} must be > 0"
                    ));
                }
            }
            if let Some(t) = h.thickness {
                if !(t.is_finite() && t > 0.0) {
                    return Err(format!(
                        "objects.{name:?}.thickness {t} must be finite and > 0"
                    ));
                }
            }
        }
        Ok(())
    }

    fn camera_entry(&self, c: &CameraEntry) -> Option<Camera> {
        let position = DVec3::from_array(c.position);
        let target = match (c.look_at, c.forward) {
            (Some(t), _) => DVec3::from_array(t),
            (None, Some(f)) => position + DVec3::from_array(f),
            (None, None) => return None,
        };
        Camera::look_at(
            c.name.clone(),
            position,
            target,
            DVec3::from_array(c.up),
            c.fov_deg,
            c.fov_axis,
        )
    }

    /// The file as TOML text, after validation.
    pub fn to_toml(&self) -> std::result::Result<String, String> {
        self.validate()?;
        toml::to_string(self).map_err(|e| format!("cannot serialize: {e}"))
    }
}

impl Default for SceneFile {
    fn default() -> Self {
        SceneFile::new()
    }
}

/// Parses a scene file from text; `path` names it in messages. Checks the TOML syntax, the
/// `schema`, the `version`, the fields, then every value.
pub fn parse(path: &Path, text: &str) -> Result<SceneFile> {
    let fmt = |p: String| SceneError::format(path, p);
    let table: toml::Table = text
        .parse()
        .map_err(|e| fmt(format!("malformed TOML: {e}")))?;
    match table.get("schema").map(|v| v.as_str()) {
        Some(Some(SCHEMA)) => {}
        Some(Some(other)) => {
            return Err(fmt(format!(
                "schema is {other:?}, expected {SCHEMA:?} (not a lustre scene file)"
            )))
        }
        Some(None) => return Err(fmt("schema is not a string".into())),
        None => return Err(fmt(format!("no schema = {SCHEMA:?} field"))),
    }
    match table.get("version").map(|v| v.as_integer()) {
        Some(Some(v)) if v == i64::from(VERSION) => {}
        Some(Some(v)) => {
            return Err(fmt(format!(
                "version {v} is not supported (this build reads version {VERSION})"
            )))
        }
        Some(None) => return Err(fmt("version is not a whole number".into())),
        None => return Err(fmt("no version field".into())),
    }
    let file: SceneFile =
        toml::from_str(text).map_err(|e| fmt(format!("invalid scene file: {e}")))?;
    file.validate().map_err(fmt)?;
    Ok(file)
}

/// Validates `file` and writes it to `path` atomically.
pub fn write(path: &Path, file: &SceneFile) -> Result<()> {
    let text = file
        .to_toml()
        .map_err(|e| SceneError::format(path, format!("not written: {e}")))?;
    write_atomic(path, text.as_bytes())
}

/// Writes `bytes` to `path` atomically (`lustre_brdf::error::write_atomic`: a temporary file
/// in the same folder, synced, then renamed over it).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    lustre_brdf::error::write_atomic(path, bytes)
        .map_err(|e| SceneError::format(path, format!("not written: {e}")))
}

/// Resolves a material spec: a relative file path (`.json`, `.bsdf`, `.binary`, `.dat`,
/// `.gonio`, optionally with `#fragment`) is taken relative to `base`.
fn resolve_spec_path(base: &Path, spec: &str) -> String {
    let s = spec.trim();
    let prefixed = s
        .split_once(':')
        .is_some_and(|(p, _)| p.len() > 1 && !p.contains(['/', '.', '(']));
    if s.contains('(') || prefixed {
        return s.to_string();
    }
    let (file, frag) = match s.rsplit_once('#') {
        Some((f, g)) => (f, Some(g)),
        None => (s, None),
    };
    let ext = Path::new(file)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let is_file = matches!(
        ext.as_deref(),
        Some("json" | "bsdf" | "binary" | "dat" | "gonio")
    );
    if !is_file || Path::new(file).is_absolute() {
        return s.to_string();
    }
    let full = base.join(file).to_string_lossy().into_owned();
    match frag {
        Some(g) => format!("{full}#{g}"),
        None => full,
    }
}

/// Builds the scene a scene file describes; `path` is the scene file (its folder resolves
/// relative paths).
pub fn build(path: &Path, file: &SceneFile) -> Result<Scene> {
    let fmt = |p: String| SceneError::format(path, p);
    file.validate().map_err(fmt)?;
    let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut scene = Scene::new(path);
    let mut film = None;
    for g in &file.geometry {
        let full = base.join(&g.file);
        let ext = full
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if ext.as_deref() == Some("toml") {
            return Err(fmt(format!(
                "geometry {:?}: a scene file cannot include another scene file",
                g.file
            )));
        }
        if !full.exists() {
            return Err(SceneError::MissingFile {
                path: path.to_path_buf(),
                referenced: full,
            });
        }
        let part = Scene::load(&full)?;
        film.get_or_insert(part.film);
        scene.merge(part, g.transform.as_ref().map(matrix));
    }
    scene.film = file.film.or(film).unwrap_or_default();
    if let Some(e) = &file.environment {
        let source = if let Some(m) = &e.map {
            let full = base.join(m);
            if !full.exists() {
                return Err(SceneError::MissingFile {
                    path: path.to_path_buf(),
                    referenced: full,
                });
            }
            let loaded = lustre_env::read_map(&full)?;
            scene.warnings.extend(loaded.sanitized_warning(&full));
            EnvironmentSource::Map {
                path: full,
                map: Arc::new(loaded.map),
            }
        } else if let Some(c) = e.constant {
            EnvironmentSource::Constant(Rgb(c))
        } else {
            EnvironmentSource::Sky(e.sky.unwrap_or_default())
        };
        scene.environment = Some(Environment {
            source,
            to_local: DMat3::from_rotation_y(-e.rotation_deg.to_radians()),
            intensity: e.intensity,
        });
    }
    for c in &file.cameras {
        let cam = file
            .camera_entry(c)
            .ok_or_else(|| fmt(format!("camera {:?} is degenerate", c.name)))?;
        scene.cameras.retain(|x| x.name != c.name);
        scene.cameras.push(cam);
    }
    for p in &file.camera_paths {
        let mut keyframes = Vec::new();
        for k in &p.keyframes {
            let camera = scene
                .cameras
                .iter()
                .find(|c| c.name == k.camera)
                .ok_or_else(|| {
                    fmt(format!(
                        "camera path {:?}: no camera named {:?}",
                        p.name, k.camera
                    ))
                })?
                .clone();
            keyframes.push(Keyframe {
                time: k.time,
                camera,
            });
        }
        scene.camera_paths.push(CameraPath {
            name: p.name.clone(),
            keyframes,
            looped: p.looped,
        });
    }
    for (name, spec) in &file.materials {
        let resolved = resolve_spec_path(&base, spec);
        let mut found = false;
        let mut rs = None;
        for m in scene.materials.iter_mut().filter(|m| &m.name == name) {
            let r = match &rs {
                Some(r) => Clone::clone(r),
                None => {
                    let r = ResolvedSpec::resolve(name, &resolved)?;
                    rs = Some(r.clone());
                    r
                }
            };
            m.kind = MaterialKind::Spec(r);
            found = true;
        }
        if !found {
            return Err(fmt(format!(
                "materials: no material named {name:?} in the geometry"
            )));
        }
    }
    // In key order: a material's `model.distribution` comes before `model.p` (which exists
    // under SGD only); `model.alpha` before it gives the same model (α is kept by a switch).
    for (key, value) in &file.material_params {
        let (name, field) = key.split_once('.').unwrap_or((key.as_str(), ""));
        crate::material_edit::set_named(&mut scene.materials, name, field, value)
            .map_err(|e| fmt(format!("material_params: {e}")))?;
    }
    for (i, e) in file.emitters.iter().enumerate() {
        let radiance = Rgb(e.radiance);
        if let Some(obj) = &e.object {
            let mut found = false;
            for m in scene.meshes.iter_mut().filter(|m| &m.name == obj) {
                m.emission = Some(radiance);
                found = true;
            }
            if !found {
                return Err(fmt(format!("emitter[{i}]: no mesh named {obj:?}")));
            }
        } else if let Some(shape) = e.shape {
            let black = match scene.material_index("emitter-black") {
                Some(m) => m,
                None => {
                    scene
                        .materials
                        .push(Material::diffuse("emitter-black", Rgb::ZERO));
                    scene.materials.len() - 1
                }
            };
            let name = format!("emitter{i}");
            let mut m = match shape {
                ShapeKind::Rectangle => mesh::rectangle(&name, black),
                ShapeKind::Disk => mesh::disk(&name, black),
                ShapeKind::Cube => mesh::cube(&name, black),
                ShapeKind::Sphere => mesh::sphere(&name, glam::Vec3::ZERO, 1.0, black),
            };
            if let Some(t) = &e.transform {
                m.transform(&matrix(t));
            }
            m.emission = Some(radiance);
            scene.push_mesh(path, m)?;
        }
    }
    scene.probes = file.probes.clone();
    for (name, hints) in &file.objects {
        let mut found = false;
        for m in scene.meshes.iter_mut().filter(|m| &m.name == name) {
            m.hints = *hints;
            found = true;
        }
        if !found {
            return Err(fmt(format!("objects: no mesh named {name:?}")));
        }
    }
    if let Some(l) = &file.lightmap {
        let atlas_file = base.join(&l.atlas);
        if !atlas_file.exists() {
            return Err(SceneError::MissingFile {
                path: path.to_path_buf(),
                referenced: atlas_file,
            });
        }
        let atlas = crate::lightmap::read_atlas_glb(&atlas_file, &mut scene)?;
        let glb = |p: String| SceneError::format(&atlas_file, p);
        if let Some(d) = l.texels_per_metre {
            if d != atlas.texels_per_metre {
                return Err(glb(format!(
                    "made at {} texels per metre, {} says {d}",
                    atlas.texels_per_metre,
                    path.display()
                )));
            }
        }
        if let Some(g) = l.gutter {
            if g != atlas.gutter {
                return Err(glb(format!(
                    "made with a {}-texel gutter, {} says {g}",
                    atlas.gutter,
                    path.display()
                )));
            }
        }
        if !l.pages.is_empty() && l.pages.len() != atlas.pages as usize {
            return Err(fmt(format!(
                "lightmap.pages names {} images, the atlas {} has {} pages",
                l.pages.len(),
                atlas_file.display(),
                atlas.pages
            )));
        }
        let mut pages = Vec::new();
        for p in &l.pages {
            let full = base.join(p);
            if !full.exists() {
                return Err(SceneError::MissingFile {
                    path: path.to_path_buf(),
                    referenced: full,
                });
            }
            pages.push(full);
        }
        scene.lightmap = Some(crate::lightmap::SceneLightmap {
            atlas,
            atlas_file,
            pages,
            embedded: Vec::new(),
        });
    }
    Ok(scene)
}

/// Reads a scene file from text and builds its scene.
pub fn from_str(path: &Path, text: &str) -> Result<Scene> {
    build(path, &parse(path, text)?)
}
