//! 004 Fig. IV.13's line-up under royal_esplanade_1k for the adaptive-shading tests: the scene,
//! its path tracer, a G-buffer and the shading context (material tables, no pyramid).

use lustre_adaptive::gbuffer::GBuffer;
use lustre_adaptive::shading::{ShadingContext, ShadingOptions};
use lustre_scene::Scene;
use lustre_trace::baked::read_environment;
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::{film_camera, path_scene};

/// The line-up of `spheres` (left to right) on `floor`.
pub fn scene(spheres: [&str; 3], floor: &str) -> Scene {
    let map = lustre_env::shared_data_dir().join("envmaps/royal_esplanade_1k.hdr");
    let env = read_environment(&map).expect("royal_esplanade_1k.hdr").0;
    lustre_scene::builtin::lineup(spheres, floor, Some(env)).expect("line-up")
}

/// Calls `f` with `scene`'s tracer, its G-buffer of `w × h` pixels from its first camera and
/// its shading context.
pub fn with_frame<R>(
    scene: &Scene,
    size: (usize, usize),
    f: impl FnOnce(&PathTracer, GBuffer, ShadingContext) -> R,
) -> R {
    let options = ShadingOptions {
        pyramid_face: 0,
        ..Default::default()
    };
    with_frame_options(scene, size, options, f)
}

/// [`with_frame`] with the shading context built with `options`.
pub fn with_frame_options<R>(
    scene: &Scene,
    (w, h): (usize, usize),
    options: ShadingOptions,
    f: impl FnOnce(&PathTracer, GBuffer, ShadingContext) -> R,
) -> R {
    let (ps, _) = path_scene(scene).expect("path scene");
    let tracer = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    let cam = film_camera(&scene.cameras[0], w as u32, h as u32).expect("camera");
    let g = GBuffer::render(&tracer, &ps, &cam, w, h).expect("G-buffer");
    let shading = ShadingContext::new(&ps, options, &|_, _| {}).expect("tables");
    f(&tracer, g, shading)
}
