//! Set-up shared by the GPU tests: the adapter (a test without one fails) and scenes with a
//! quick light-map bake.

#![allow(dead_code)] // Each test binary uses a subset.

pub mod line_up;
pub mod shader;
pub mod textures;

use lustre_gpu::{GpuContext, GpuViewBuffer};
use lustre_scene::lightmap::{build_atlas, AtlasOptions, LightmapAtlas};
use lustre_scene::Scene;
use lustre_shade::frame::{thin_sheet, FrameBuffers, FrameTables};
use lustre_shade::mirror::{MirrorBuffer, Reflector};
use lustre_shade::probe::LitScene;
use lustre_trace::bake::{assemble, bake_tiles, BakeOptions, Denoiser};

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

/// The CPU twins' view of a GPU frame's view buffers, read back: `views` holds the mirror
/// buffers (of `reflectors`, in order) then the see-through buffers, `tables` the per-mesh links.
pub fn frame_buffers(
    ctx: &GpuContext,
    lit: &LitScene,
    views: &[GpuViewBuffer],
    reflectors: &[Reflector],
    tables: &FrameTables,
) -> FrameBuffers {
    let views: Vec<_> = views
        .iter()
        .map(|v| v.read_back(ctx).expect("view read-back"))
        .collect();
    let (mirror_views, see_throughs) = views.split_at(reflectors.len());
    FrameBuffers {
        mirrors: reflectors
            .iter()
            .zip(mirror_views)
            .map(|(r, v)| MirrorBuffer {
                reflector: r.clone(),
                plane: r.plane,
                view: v.clone(),
            })
            .collect(),
        mirror_of_mesh: tables.mirror_of_mesh.clone(),
        see_throughs: see_throughs.to_vec(),
        see_through_of_mesh: tables.see_through_of_mesh.clone(),
        probe_of_mesh: tables.probe_of_mesh.clone(),
        thin: lit.scene.materials.iter().map(thin_sheet).collect(),
        first_prim: tables.first_prim.clone(),
        seconds: 0.0,
    }
}
