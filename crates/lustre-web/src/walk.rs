//! The page's walkthrough, independent of the browser: a published scene (the binary glTF
//! `lustre publish` writes, read from memory) made ready for the GPU exactly as `lustre render
//! --device gpu` makes a baked scene ready — the path scene and its BVH, the light-mapped
//! albedos, the scene uploaded, the passes compiled and the probes captured on the GPU — and a
//! [`GpuFrameSession`] stepped per displayed frame without waiting for the GPU.

use glam::DVec3;
use lustre_gpu::context::GpuContext;
use lustre_gpu::passes::lightmap_shade::LightmapFrameScene;
use lustre_gpu::walkthrough::{GpuFrameSession, GpuStep, GpuWalkthrough, WalkthroughPasses};
use lustre_scene::Scene;
use lustre_shade::probe::{has_probes, LitScene, ProbeOptions};
use lustre_shade::request::FrameRequest;
use lustre_trace::bake::render::{read_pages, Lightmapped};
use lustre_trace::bake::{base_albedo, BaseAlbedo};
use lustre_trace::baked::environment_pyramid;
use lustre_trace::image::Image;
use lustre_trace::path_tracer::{PathCamera, PathOptions, PathTracer};
use std::future::Future;
use std::path::Path;

/// A published scene on the GPU, and the frame session the page steps.
///
/// The scene and what borrows it (light-map atlas and pages, path scene, tracer, light-mapped
/// albedos) live as long as the page: they are leaked once per load, so the walkthrough can hold them without self-reference.
pub struct Walk {
    ctx: GpuContext,
    lit: LitScene<'static, 'static>,
    walk: GpuWalkthrough,
    session: GpuFrameSession,
}

impl std::fmt::Debug for Walk {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Walk")
            .field("scene", &self.lit.scene.source)
            .field("adapter", &self.ctx.describe())
            .finish_non_exhaustive()
    }
}

impl Walk {
    /// Reads the binary glTF `bytes` (named `name` in errors) with its embedded light maps,
    /// uploads it to `ctx` and captures its probes (`probe_size`² faces; the environment's
    /// pyramid instead for a scene without probes). Errors name the file and the problem: not a
    /// glTF, no light maps, a material the GPU cannot shade, a scene the device cannot hold.
    /// `progress` hears each stage as it starts.
    pub fn load(
        ctx: GpuContext,
        name: &str,
        bytes: &[u8],
        probe_size: usize,
        progress: &mut dyn FnMut(&str),
    ) -> Result<Walk, String> {
        progress("reading the scene");
        let path = Path::new(name);
        let scene = lustre_scene::gltf_io::from_slice(path, bytes).map_err(|e| e.to_string())?;
        let Some(lightmap) = &scene.lightmap else {
            return Err(format!(
                "{name}: no light maps (publish a baked scene: `lustre publish BAKED/scene.toml`)"
            ));
        };
        let pages: &'static [Vec<[f32; 3]>] = Box::leak(
            read_pages(lightmap)
                .map_err(|e| format!("{name}: {e}"))?
                .into_boxed_slice(),
        );
        let atlas = Box::leak(Box::new(lightmap.atlas.clone()));
        let probe_opts = ProbeOptions {
            face_size: probe_size,
            ..ProbeOptions::default()
        };
        probe_opts.validate().map_err(|e| e.to_string())?;
        let scene: &'static Scene = Box::leak(Box::new(scene));
        progress("building the ray-casting BVH and the light-mapped albedos");
        let (ps, _warnings) =
            lustre_trace::reference::path_scene(scene).map_err(|e| format!("{name}: {e}"))?;
        let ps = Box::leak(Box::new(ps));
        let bases: Vec<BaseAlbedo> = scene.materials.iter().map(base_albedo).collect();
        let lm = Lightmapped::new(scene, atlas, pages, &ps.geometry, bases)
            .map_err(|e| format!("{name}: light maps: {e}"))?;
        let lm = Box::leak(Box::new(lm));
        let pt = PathTracer::new(ps, PathOptions::default()).map_err(|e| e.to_string())?;
        let pt = Box::leak(Box::new(pt));
        let lit = LitScene::new(scene, ps, pt, lm).map_err(|e| e.to_string())?;
        let environment = match (has_probes(scene), &ps.environment) {
            (false, Some(env)) => {
                Some(environment_pyramid(env, probe_size).map_err(|e| e.to_string())?)
            }
            _ => None,
        };
        progress("uploading the scene");
        let uploaded = LightmapFrameScene::upload(&ctx, scene, atlas, pages)
            .map_err(|e| format!("uploading {name} to the GPU: {e}"))?;
        progress("compiling the passes");
        let passes = WalkthroughPasses::for_scene(&ctx, scene).map_err(|e| e.to_string())?;
        progress("capturing the probes");
        let walk = GpuWalkthrough::with_passes(
            &ctx,
            passes,
            &lit,
            uploaded,
            &probe_opts,
            environment.as_ref(),
        )
        .map_err(|e| format!("{name}: {e}"))?;
        Ok(Walk {
            ctx,
            lit,
            walk,
            session: GpuFrameSession::without_counts(),
        })
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        self.lit.scene
    }

    /// What the GPU is ("name (backend, device type)").
    pub fn adapter(&self) -> String {
        self.ctx.describe()
    }

    /// Probes captured and milliseconds each took.
    pub fn capture_ms(&self) -> &[(String, f64)] {
        &self.walk.capture_ms
    }

    /// The scene camera `name` (`None`: the first, or a view framing the scene) for a w×h
    /// frame, as `lustre render --camera` places it.
    pub fn camera(&self, name: Option<&str>, w: u32, h: u32) -> Result<PathCamera, String> {
        lustre_trace::reference::path_camera(self.lit.scene, name, w, h).map_err(|e| e.to_string())
    }

    /// Camera path `index` at `t` seconds (clamped to its keyframes) for a w×h frame.
    pub fn path_camera(&self, index: usize, t: f64, w: u32, h: u32) -> Result<PathCamera, String> {
        let path = self
            .lit
            .scene
            .camera_paths
            .get(index)
            .ok_or_else(|| format!("the scene has no camera path #{index}"))?;
        let cam = path
            .at(t)
            .ok_or_else(|| format!("camera path {:?} has no keyframes", path.name))?;
        lustre_trace::reference::film_camera(&cam, w, h).map_err(|e| e.to_string())
    }

    /// Renders, refines or keeps the w×h frame from `camera` ([`GpuFrameSession::step`]); the
    /// step never waits for the GPU.
    pub fn step(
        &mut self,
        camera: &PathCamera,
        size: (usize, usize),
        req: &FrameRequest,
    ) -> Result<GpuStep, String> {
        self.session
            .step(&self.ctx, &self.walk, &self.lit, camera, size, req)
            .map_err(|e| e.to_string())
    }

    /// The current frame, read back without blocking (the copy is recorded now; the future
    /// completes when the GPU has finished it). Errors: no frame yet.
    pub fn image(&self) -> Result<impl Future<Output = Result<Image, String>> + 'static, String> {
        let target = self
            .session
            .target()
            .filter(|_| self.session.frames() > 0)
            .ok_or("no frame has been rendered")?;
        let pending = target.read_back_async(&self.ctx);
        Ok(async move { pending.await.map_err(|e| e.to_string()) })
    }
}

/// A walking camera: `camera` moved `forward`, `right` and `up` (scene units, along its view,
/// its right and the world's up +Y) and turned by `yaw` about the world's up and `pitch` about its
/// right (radians; the view kept within 85° of the horizon).
pub fn walk_camera(
    camera: &PathCamera,
    (forward, right, up): (f64, f64, f64),
    (yaw, pitch): (f64, f64),
) -> PathCamera {
    let world_up = DVec3::Y;
    let level = DVec3::new(camera.forward.x, 0.0, camera.forward.z)
        .try_normalize()
        .unwrap_or(DVec3::Z);
    let elevation = camera.forward.y.clamp(-1.0, 1.0).asin();
    let pitch_limit = 85f64.to_radians();
    let elevation = (elevation + pitch).clamp(-pitch_limit, pitch_limit);
    let heading = glam::DQuat::from_axis_angle(world_up, -yaw) * level;
    let forward_dir = heading * elevation.cos() + world_up * elevation.sin();
    let right_dir = forward_dir.cross(world_up).normalize();
    let up_dir = right_dir.cross(forward_dir);
    let origin = camera.origin + forward_dir * forward + right_dir * right + world_up * up;
    PathCamera {
        origin,
        forward: forward_dir,
        right: right_dir,
        up: up_dir,
        tan_half_fov_y: camera.tan_half_fov_y,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> PathCamera {
        PathCamera::look_at(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), DVec3::Y, 60.0)
            .expect("camera")
    }

    #[test]
    fn walking_keeps_an_orthonormal_upright_basis() {
        let c = walk_camera(&camera(), (1.0, 0.5, 0.25), (0.3, 0.2));
        for (a, b) in [(c.forward, c.right), (c.forward, c.up), (c.right, c.up)] {
            assert!(a.dot(b).abs() < 1e-12);
        }
        for v in [c.forward, c.right, c.up] {
            assert!((v.length() - 1.0).abs() < 1e-12);
        }
        // Right stays horizontal, up points up, the view pitched by 0.2 rad.
        assert!(c.right.y.abs() < 1e-12);
        assert!(c.up.y > 0.0);
        assert!((c.forward.y.asin() - 0.2).abs() < 1e-12);
        // A turn without a move keeps the origin; no turn keeps the basis of look_at.
        let still = walk_camera(&camera(), (0.0, 0.0, 0.0), (0.0, 0.0));
        assert!((still.forward - camera().forward).length() < 1e-12);
        assert!((still.right - camera().right).length() < 1e-12);
        assert!((still.up - camera().up).length() < 1e-12);
    }

    #[test]
    fn a_move_goes_along_the_view_and_pitch_is_limited() {
        let c = walk_camera(&camera(), (2.0, 0.0, 0.0), (0.0, 0.0));
        assert!((c.origin - DVec3::new(0.0, 0.0, -2.0)).length() < 1e-12);
        let c = walk_camera(&camera(), (0.0, 1.0, 0.0), (0.0, 0.0));
        assert!((c.origin - DVec3::new(1.0, 0.0, 0.0)).length() < 1e-12);
        let up = walk_camera(&camera(), (0.0, 0.0, 0.0), (0.0, 3.0));
        assert!((up.forward.y.asin() - 85f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn bad_files_are_named_errors_not_panics() {
        let ctx = match GpuContext::new() {
            Ok(c) => c,
            Err(e) => panic!("the web crate's tests need an adapter (lavapipe): {e}"),
        };
        for (bytes, want) in [
            (&b""[..], "empty"),
            (&b"PNG\x0d\x0a"[..], "not a binary glTF"),
            (&b"glTF\x02\x00\x00\x00\x08\x00\x00\x00"[..], "less than"),
        ] {
            let e = Walk::load(ctx.clone(), "site/scene.glb", bytes, 32, &mut |_| {})
                .expect_err("refused");
            assert!(e.contains("site/scene.glb") && e.contains(want), "{e}");
        }
    }
}
