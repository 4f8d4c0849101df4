//! A scene with its baked light maps, as the walkthrough frame reads it (`lustre render`,
//! `lustre view`): a scene file `lustre bake` wrote, the built-in room (baked once into a folder
//! and reused), or the material preview (a sphere under the environment, no light maps). Also
//! the environment pyramid that lights glossy surfaces in scenes without probe objects.

use crate::bake::render::read_pages;
use crate::bake::{assemble, bake_tiles, BakeOptions, Transport};
use crate::error::{Result, TraceError};
use crate::path_tracer::EnvLight;
use glam::DMat3;
use lustre_env::cube::CubeMap;
use lustre_env::pyramid::{CubePyramid, MipFilter};
use lustre_scene::lightmap::{build_atlas, AtlasOptions, AtlasSource, LightmapAtlas};
use lustre_scene::{Environment, EnvironmentSource, Scene};
use std::path::Path;
use std::sync::Arc;

/// A scene, its light-map atlas and its baked pages (one RGB texel list per page).
pub struct BakedScene {
    /// The scene.
    pub scene: Scene,
    /// Its light-map atlas.
    pub atlas: LightmapAtlas,
    /// The baked irradiance pages.
    pub pages: Vec<Vec<[f32; 3]>>,
    /// Warnings of the scene's loader.
    pub warnings: Vec<String>,
}

fn scene_error(what: &str, e: impl std::fmt::Display) -> TraceError {
    TraceError::Parameter(format!("{what}: {e}"))
}

impl BakedScene {
    /// The scene file at `path` with its light maps (the scene.toml `lustre bake --out DIR`
    /// writes). Errors: the file's, or a scene without light maps (saying how to bake them).
    pub fn load(path: &Path) -> Result<Self> {
        let scene = Scene::load(path)
            .map_err(|e| scene_error(&format!("loading {}", path.display()), e))?;
        let warnings = scene.warnings.clone();
        let Some(lightmap) = &scene.lightmap else {
            return Err(TraceError::Parameter(format!(
                "{}: no light maps; bake them first (`lustre bake {} --out DIR`) and use DIR/scene.toml",
                path.display(),
                path.display()
            )));
        };
        let pages =
            read_pages(lightmap).map_err(|e| scene_error(&path.display().to_string(), e))?;
        let atlas = lightmap.atlas.clone();
        Ok(BakedScene {
            scene,
            atlas,
            pages,
            warnings,
        })
    }

    /// The built-in room with its light maps: an atlas at 16 texels/m and a bake of 64 paths
    /// per texel through the full materials into `bake_dir` (its tiles reused on the next
    /// call); `environment` replaces the built-in sky. `progress(tiles done, tiles)`.
    pub fn builtin_room(
        bake_dir: &Path,
        environment: Option<Environment>,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Self> {
        let mut scene =
            lustre_scene::builtin::room().map_err(|e| scene_error("the built-in room", e))?;
        if environment.is_some() {
            scene.environment = environment;
        }
        let aopts = AtlasOptions {
            texels_per_metre: 16.0,
            ..AtlasOptions::default()
        };
        let (atlas, _) = build_atlas(&mut scene, &aopts)
            .map_err(|e| scene_error("the built-in room's atlas", e))?;
        let opts = BakeOptions {
            spp: 64,
            bounces: 8,
            transport: Transport::Full,
            ..BakeOptions::default()
        };
        bake_tiles(&scene, &atlas, &opts, bake_dir, None, progress)?;
        let assembled = assemble(&scene, &atlas, &opts, bake_dir)?;
        Ok(BakedScene {
            scene,
            atlas,
            pages: assembled.pages,
            warnings: vec![],
        })
    }

    /// The material preview: a sphere of `spec` under `environment` (the built-in sky by
    /// default), no light maps (an atlas of one black texel that no mesh uses).
    pub fn preview(spec: &str, environment: Option<Environment>) -> Result<Self> {
        let scene = lustre_scene::builtin::preview(spec, environment)
            .map_err(|e| scene_error(&format!("material {spec}"), e))?;
        let atlas = LightmapAtlas {
            width: 1,
            height: 1,
            pages: 1,
            mesh_page: vec![None; scene.meshes.len()],
            gutter: 0,
            texels_per_metre: 0.0,
            source: AtlasSource::Texcoord1,
        };
        Ok(BakedScene {
            scene,
            atlas,
            pages: vec![vec![[0.0; 3]]],
            warnings: vec![],
        })
    }
}

/// An equirect `.hdr` / `.exr` map as a scene's environment, with the warning for texels set to
/// 0 (non-finite or negative; [`lustre_env::io::LoadedMap::sanitized_warning`]).
pub fn read_environment(path: &Path) -> Result<(Environment, Option<String>)> {
    let loaded = lustre_env::io::read_map(path)?;
    let warning = loaded.sanitized_warning(path);
    Ok((
        Environment {
            source: EnvironmentSource::Map {
                path: path.to_path_buf(),
                map: Arc::new(loaded.map),
            },
            to_local: DMat3::IDENTITY,
            intensity: 1.0,
        },
        warning,
    ))
}

/// The Gaussian 6×6 pyramid of the path scene's environment at `face` texels per cube face:
/// the world-oriented map resampled with its texels' areas (not point-sampled), a rotated or
/// scaled light through its own lookup.
pub fn environment_pyramid(env: &EnvLight, face: usize) -> Result<CubePyramid> {
    let cube = if env.to_world() == DMat3::IDENTITY && env.scale() == 1.0 {
        CubeMap::from_equirect(env.map(), face)?
    } else {
        CubeMap::from_fn(face, |d| env.eval(d).0)?
    };
    Ok(CubePyramid::build(cube, MipFilter::Gauss6)?)
}
