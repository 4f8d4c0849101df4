//! Set-up shared by the GPU tests: the adapter (a test without one fails) and scenes with a
//! quick light-map bake.

#![allow(dead_code)] // Each test binary uses a subset.

pub mod kernel;

use lustre_gpu::GpuContext;
use lustre_scene::lightmap::{build_atlas, AtlasOptions, LightmapAtlas};
use lustre_scene::Scene;
use lustre_shade::bake::{assemble, bake_tiles, BakeOptions, Denoiser};

/// The adapter; panics (the test fails) without one.
pub fn ctx() -> GpuContext {
    GpuContext::new().unwrap_or_else(|e| panic!("{e}"))
}

/// A scene with its light maps.
pub struct Baked {
    /// The scene (its meshes carry the atlas's light-map UVs).
    pub scene: Scene,
    /// The atlas.
    pub atlas: LightmapAtlas,
    /// The baked pages.
    pub pages: Vec<Vec<[f32; 3]>>,
}

/// `scene` with a quick bake: `texels_per_metre`, 1 path per texel, 2 bounces, no denoiser.
pub fn quick_bake(mut scene: Scene, texels_per_metre: f32) -> Baked {
    let (atlas, _) = build_atlas(
        &mut scene,
        &AtlasOptions {
            texels_per_metre,
            ..AtlasOptions::default()
        },
    )
    .expect("atlas");
    let opts = BakeOptions {
        spp: 1,
        bounces: 2,
        seed: 5,
        denoiser: Denoiser::None,
        ..BakeOptions::default()
    };
    let dir = tempfile::tempdir().expect("tempdir");
    bake_tiles(&scene, &atlas, &opts, dir.path(), None, &|_, _| {}).expect("bake");
    let pages = assemble(&scene, &atlas, &opts, dir.path())
        .expect("assemble")
        .pages;
    Baked {
        scene,
        atlas,
        pages,
    }
}
