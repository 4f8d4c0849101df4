//! lustre-scene: one scene model for lustre, read from glTF 2.0, OBJ/MTL, Mitsuba scene XML and
//! the lustre scene file (TOML). Plain data in world space, ready for a BVH and a GPU upload; no
//! GPU code here.
//!
//! - [`Scene`]: meshes (world-space triangles, one material each, optional area emission and
//!   real-time hints), materials ([`Material`]: a model with possibly textured parameters,
//!   evaluated at a hit by [`Material::bsdf_at`]), textures (linear f32), an optional
//!   environment, cameras, camera paths, the film size, and the warnings of loading.
//! - [`Scene::load`] picks the reader by extension: `.gltf`/`.glb` ([`gltf_io`]), `.obj`
//!   ([`obj`]), `.xml` (Mitsuba 0.5 or 3.x, [`mitsuba`]), `.toml` (a lustre scene file,
//!   [`scene_file`]), then checks that every material builds. In-memory entry points (for
//!   fuzzing and tests): [`mitsuba::from_str`], [`gltf_io::from_slice`], [`obj::from_slice`],
//!   [`scene_file::from_str`] / [`scene_file::parse`]; relative paths resolve against the given
//!   path's folder.
//!
//! Conventions: +y up, right-handed; triangles counter-clockwise from the front, and an area
//! emitter emits from its front face ([`Mesh::emission`], Mitsuba's `area`); UVs with v = 0 at
//! the top of an image (glTF; OBJ's v is flipped on read); colours linear RGB; environment maps
//! in lustre-env's equirect convention (Mitsuba's envmap is turned by half a turn on read).
//!
//! ```no_run
//! use lustre_scene::Scene;
//! let scene = Scene::load("scene.xml".as_ref())?;
//! let camera = scene.camera(None).expect("a camera");
//! let dir = camera.ray_direction(0.5, 0.5, scene.film.width, scene.film.height);
//! for mesh in &scene.meshes {
//!     let material = &scene.materials[mesh.material];
//!     let bsdf = material.bsdf_at(&scene.textures, &[lustre_scene::Vec2::ZERO; 2])?;
//!     # let _ = (bsdf, dir);
//! }
//! # Ok::<(), lustre_scene::SceneError>(())
//! ```
//!
//! Measured with `lustre scene info` (dev profile with optimized dependencies, 2 cores shared
//! with other builds, so a range over runs): the Modern Hall XML loads in 0.35–1.1 s (most of it
//! building the two rough-plastic coating tables in the material check), its glTF in
//! 0.16–0.34 s, the Cornell box OBJ in < 2 ms.

pub mod builtin;
pub mod camera;
pub mod camera_path_file;
pub mod environment;
pub mod error;
pub mod export;
pub mod glb_write;
pub mod gltf_io;
pub mod lightmap;
pub mod material;
pub mod material_edit;
pub mod mesh;
pub mod mitsuba;
pub mod obj;
pub mod probe_site;
pub mod scene_file;
pub mod texture;

pub use camera::{Camera, CameraPath, FovAxis, Keyframe};
pub use environment::{Environment, EnvironmentSource, Sky};
pub use error::{Result, SceneError};
pub use glam::{Vec2, Vec3, Vec4};
pub use lightmap::{AtlasSource, LightmapAtlas, SceneLightmap};
pub use lustre_brdf::Rgb;
pub use material::{
    AlphaMask, Material, MaterialKind, MicrofacetType, NormalMap, ResolvedSpec, TextureRef,
    TexturedRgb, TexturedScalar,
};
pub use mesh::{Mesh, ObjectHints};
pub use probe_site::ProbeSite;
pub use texture::{ColorSpace, Texture};

use std::path::{Path, PathBuf};

/// Reads a whole file; failures name it.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>> {
    lustre_brdf::error::read_input(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        source: e,
    })
}

/// The film (output image) size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Default for Film {
    /// 1024×1024, used when the file names no film.
    fn default() -> Self {
        Film {
            width: 1024,
            height: 1024,
        }
    }
}

impl Film {
    /// Width / height.
    pub fn aspect(&self) -> f64 {
        f64::from(self.width) / f64::from(self.height)
    }
}

/// Counts gathered while loading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadStats {
    /// Degenerate triangles (a repeated index or zero area) dropped.
    pub degenerate_triangles: usize,
}

/// A scene: world-space geometry, materials, textures, lights and cameras.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Triangle meshes in world space.
    pub meshes: Vec<Mesh>,
    /// Materials, indexed by [`Mesh::material`].
    pub materials: Vec<Material>,
    /// Textures, indexed by [`TextureRef::texture`].
    pub textures: Vec<Texture>,
    /// Distant lighting, if any.
    pub environment: Option<Environment>,
    /// Cameras (the file's first camera first).
    pub cameras: Vec<Camera>,
    /// Camera paths.
    pub camera_paths: Vec<CameraPath>,
    /// Room-scale reflection probes (a scene file's `[[probe]]` sections).
    pub probes: Vec<ProbeSite>,
    /// The film size the file asks for.
    pub film: Film,
    /// The file the scene was read from.
    pub source: PathBuf,
    /// Named warnings: things read approximately or ignored.
    pub warnings: Vec<String>,
    /// Counts gathered while loading.
    pub stats: LoadStats,
    /// The light map a scene file's `[lightmap]` section names (atlas and baked pages); its
    /// meshes' `uv1` are the light-map UVs.
    pub lightmap: Option<SceneLightmap>,
}

impl Scene {
    /// An empty scene read from `source` (no meshes, default film).
    pub fn new(source: impl Into<PathBuf>) -> Self {
        Scene {
            meshes: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            environment: None,
            cameras: Vec::new(),
            camera_paths: Vec::new(),
            probes: Vec::new(),
            film: Film::default(),
            source: source.into(),
            warnings: Vec::new(),
            stats: LoadStats::default(),
            lightmap: None,
        }
    }

    /// Total number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(Mesh::triangle_count).sum()
    }

    /// Indices of the meshes that emit light.
    pub fn emitters(&self) -> Vec<usize> {
        (0..self.meshes.len())
            .filter(|&i| self.meshes[i].emission.is_some())
            .collect()
    }

    /// World-space axis-aligned bounds (min, max); `None` for a scene without vertices.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.meshes
            .iter()
            .filter_map(Mesh::bounds)
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// The camera called `name`, or the first camera when `name` is `None`.
    pub fn camera(&self, name: Option<&str>) -> Option<&Camera> {
        match name {
            None => self.cameras.first(),
            Some(n) => self.cameras.iter().find(|c| c.name == n),
        }
    }

    /// The material index called `name`.
    pub fn material_index(&self, name: &str) -> Option<usize> {
        self.materials.iter().position(|m| m.name == name)
    }

    /// Reads a scene file, choosing the reader by extension: `.gltf`/`.glb`, `.obj`, `.xml`
    /// (Mitsuba), `.toml` (lustre scene file).
    pub fn load(path: &Path) -> Result<Scene> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let scene = match ext.as_str() {
            "xml" => mitsuba::read(path),
            "toml" => {
                let bytes = read_file(path)?;
                let text = std::str::from_utf8(&bytes)
                    .map_err(|e| SceneError::format(path, format!("not UTF-8 text: {e}")))?;
                scene_file::from_str(path, text)
            }
            "gltf" | "glb" => gltf_io::from_slice(path, &read_file(path)?),
            "obj" => obj::from_slice(path, &read_file(path)?),
            _ => Err(SceneError::format(
                path,
                format!(
                    "unknown scene extension {ext:?} (expected .gltf, .glb, .obj, .xml or .toml)"
                ),
            )),
        }?;
        if scene.triangle_count() == 0 {
            return Err(SceneError::format(
                path,
                format!(
                    "no geometry: {} mesh(es) with no triangle lustre can use (a face needs 3 or \
                     more vertices){}",
                    scene.meshes.len(),
                    if scene.warnings.is_empty() {
                        String::new()
                    } else {
                        let first: Vec<&str> =
                            scene.warnings.iter().take(3).map(String::as_str).collect();
                        format!("; {}", first.join("; "))
                    }
                ),
            ));
        }
        scene.check_materials()?;
        Ok(scene)
    }

    /// Checks that every material builds its BSDF ([`Material::check`]) and prepares the shared
    /// models; the error names the material and the file.
    pub fn check_materials(&self) -> Result<()> {
        for m in &self.materials {
            m.check(&self.textures).map_err(|e| match e {
                SceneError::Material { material, problem } => {
                    SceneError::format(&self.source, format!("material {material:?}: {problem}"))
                }
                other => other,
            })?;
        }
        Ok(())
    }

    /// The texture read from `path` in `color_space`, loaded once (later calls return the same
    /// index); `referrer` is the scene file that names it (a missing file is an error naming
    /// both).
    pub fn texture(
        &mut self,
        referrer: &Path,
        path: &Path,
        color_space: ColorSpace,
    ) -> Result<TextureRef> {
        if let Some(i) = self
            .textures
            .iter()
            .position(|t| t.source == path && t.color_space == color_space)
        {
            return Ok(TextureRef {
                texture: i,
                uv_set: 0,
            });
        }
        self.textures
            .push(Texture::read(referrer, path, color_space)?);
        Ok(TextureRef {
            texture: self.textures.len() - 1,
            uv_set: 0,
        })
    }

    /// Appends `other` (meshes, materials, textures, cameras, paths, warnings, counts), with its
    /// meshes and cameras moved by `transform`; its environment replaces this one's when this
    /// one has none. Material and texture indices are renumbered.
    pub fn merge(&mut self, other: Scene, transform: Option<glam::DMat4>) {
        let (mat_off, tex_off) = (self.materials.len(), self.textures.len());
        self.textures.extend(other.textures);
        for mut m in other.materials {
            m.for_each_texture_ref(|t| t.texture += tex_off);
            self.materials.push(m);
        }
        for mut m in other.meshes {
            m.material += mat_off;
            if let Some(t) = &transform {
                m.transform(t);
            }
            self.meshes.push(m);
        }
        for mut c in other.cameras {
            if let Some(t) = &transform {
                let p = t.transform_point3(c.position);
                let f = t.transform_vector3(c.forward);
                let u = t.transform_vector3(c.up);
                if let Some(moved) =
                    Camera::look_at(c.name.clone(), p, p + f, u, c.fov_deg, c.fov_axis)
                {
                    c = Camera {
                        aspect: c.aspect,
                        ..moved
                    };
                }
            }
            self.cameras.push(c);
        }
        self.camera_paths.extend(other.camera_paths);
        self.probes.extend(other.probes);
        if self.environment.is_none() {
            self.environment = other.environment;
        }
        self.warnings.extend(other.warnings);
        self.stats.degenerate_triangles += other.stats.degenerate_triangles;
    }

    /// Adds a mesh after validation ([`Mesh::validated`]): degenerate triangles are dropped and
    /// counted, with a warning naming the mesh. `path` names the file in errors.
    pub fn push_mesh(&mut self, path: &Path, mesh: Mesh) -> Result<()> {
        let (mesh, dropped) = mesh.validated(path, self.materials.len())?;
        if dropped > 0 {
            self.stats.degenerate_triangles += dropped;
            self.warnings.push(format!(
                "mesh {:?}: {dropped} degenerate triangle(s) dropped",
                mesh.name
            ));
        }
        self.meshes.push(mesh);
        Ok(())
    }
}
