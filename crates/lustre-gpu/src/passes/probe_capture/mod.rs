//! Reflection probes captured and filtered on the GPU (000 §4.4):
//! the raster G-buffer pass and the light-mapped shading pass render the six cube faces from
//! the probe's centre with the probe's own mesh left out, k×k supersampled, the shading pass
//! writing each face straight into the base level of a [`GpuPyramid`], which
//! [`GpuPyramidBuilder::build_from_buffer`] then filters (Gaussian 6×6, 002 §3) without a host
//! round trip. The bounding planes stay on the CPU ([`auto_planes`]).
//!
//! The face cameras are 90° square [`PathCamera`]s whose pixel centres are exactly the texel
//! centres of `lustre_env::cube` (Vulkan face order and orientation): pixel (X + ½, Y + ½) of a
//! face rendered at N×N looks along `face_point(face, sc, tc)` with sc = 2(X + ½)/N − 1,
//! tc = 2(Y + ½)/N − 1, so a (k·N)² G-buffer box-averaged k×k is the CPU's s×s stratified
//! supersampling ([`lustre_shade::probe::capture_cube`], s = k) at the same sample positions.
//! Some face bases are left-handed; the raster pass does not cull, so this does not matter.
//!
//! CPU twin: [`lustre_trace::bake::gbuffer::shade_gbuffer`] on the read-back face G-buffers
//! ([`GpuProbeCapture::face_gbuffer`]) → the same cube → `CubePyramid::build`.

use crate::context::GpuContext;
use crate::error::{invalid, Result};
use crate::passes::gbuffer::{DrawOptions, GBufferPass, GBufferTarget};
use crate::passes::lightmap_shade::{LightmapFrameScene, LightmapShadePass};
use crate::passes::pyramid::{GpuPyramid, GpuPyramidBuilder, PYRAMID_USAGE};
use glam::DVec3;
use lustre_env::cube::face_point;
use lustre_env::MipFilter;
use lustre_scene::Scene;
use lustre_shade::integrator::BoundingPlane;
use lustre_shade::probe::{
    auto_planes, probe_placement, room_placement, LitScene, Probe, ProbeOptions,
};
use lustre_trace::bake::gbuffer::VisibilityBuffer;
use lustre_trace::path_tracer::PathCamera;
use std::ops::Range;

/// The camera of cube face `face` (0..6: +X, −X, +Y, −Y, +Z, −Z) at `centre`: 90° square, its
/// pixel centres on the cube's texel centres (module docs).
pub fn face_camera(centre: DVec3, face: usize) -> PathCamera {
    let c = face_point(face, 0.0, 0.0);
    PathCamera {
        origin: centre,
        forward: c,
        // PathCamera::direction: forward + px·right + py·up with px = sc, py = −tc.
        right: face_point(face, 1.0, 0.0) - c,
        up: c - face_point(face, 0.0, 1.0),
        tan_half_fov_y: 1.0,
    }
}

/// The triangles of mesh `mesh` in the order of `diffuse_path_scene`'s geometry (the meshes'
/// triangles in mesh order). Errors: no such mesh (names the scene).
pub fn mesh_triangles(scene: &Scene, mesh: usize) -> Result<Range<u32>> {
    if mesh >= scene.meshes.len() {
        return Err(invalid(
            "mesh",
            format!(
                "{}: no mesh {mesh} (the scene has {})",
                scene.source.display(),
                scene.meshes.len()
            ),
        ));
    }
    let start: usize = scene.meshes[..mesh].iter().map(|m| m.indices.len()).sum();
    let end = start + scene.meshes[mesh].indices.len();
    let to_u32 = |v: usize| {
        u32::try_from(v).map_err(|_| invalid("mesh", format!("triangle {v} beyond u32")))
    };
    Ok(to_u32(start)?..to_u32(end)?)
}

/// A probe captured on the GPU: what [`Probe`] holds, with the pyramid on the GPU.
#[derive(Debug)]
pub struct GpuProbe {
    /// The object's mesh name, or the room probe's name.
    pub name: String,
    /// The object's mesh index; `None` for a room probe.
    pub mesh: Option<u32>,
    /// The projection centre (world space).
    pub centre: DVec3,
    /// Bounding planes relative to `centre` ([`auto_planes`], on the CPU).
    pub planes: Vec<BoundingPlane>,
    /// The captured light, Gaussian 6×6 pyramid.
    pub pyramid: GpuPyramid,
}

impl GpuProbe {
    /// The probe on the host, as the CPU's [`Probe`] (the pyramid read back).
    pub fn read_back(&self, ctx: &GpuContext) -> Result<Probe> {
        Ok(Probe {
            name: self.name.clone(),
            mesh: self.mesh,
            centre: self.centre,
            planes: self.planes.clone(),
            pyramid: self.pyramid.read_back(ctx)?,
        })
    }
}

/// The compiled passes of the probe capture.
#[derive(Debug)]
pub struct GpuProbeCapture {
    gbuffer: GBufferPass,
    shade: LightmapShadePass,
    pyramid: GpuPyramidBuilder,
}

impl GpuProbeCapture {
    /// Compiles the raster, shading and pyramid passes.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        Ok(GpuProbeCapture {
            gbuffer: GBufferPass::new(ctx)?,
            shade: LightmapShadePass::new(ctx)?,
            pyramid: GpuPyramidBuilder::new(ctx)?,
        })
    }

    /// The probe of mesh `mesh` as [`lustre_shade::probe::capture_probe`] makes it, captured
    /// and filtered (Gaussian 6×6) on the GPU: placement and bounding planes from `lit` (the
    /// CPU's), the cube of `opts.face_size` with `opts.supersample`² samples per texel from
    /// `scene` (the same scene uploaded). Returns once the GPU has finished. Errors: those of
    /// `probe_placement` (no such mesh, a centre inside a solid), bad options, device limits.
    pub fn capture_probe(
        &self,
        ctx: &GpuContext,
        scene: &LightmapFrameScene,
        lit: &LitScene,
        mesh: usize,
        opts: &ProbeOptions,
    ) -> Result<GpuProbe> {
        let shade_err = |e: lustre_shade::ShadeError| invalid("probe", e.to_string());
        opts.validate().map_err(shade_err)?;
        let (name, centre) = probe_placement(lit, mesh).map_err(shade_err)?;
        let skip = mesh_triangles(lit.scene, mesh)?;
        let pyramid = self.capture(
            ctx,
            scene,
            centre,
            Some(skip),
            opts.face_size,
            opts.supersample,
            MipFilter::Gauss6,
        )?;
        let planes =
            auto_planes(lit, centre, Some(mesh as u32), opts.plane_rays).map_err(shade_err)?;
        Ok(GpuProbe {
            name,
            mesh: Some(mesh as u32),
            centre,
            planes,
            pyramid,
        })
    }

    /// Room probe `index` of the scene as [`lustre_shade::probe::capture_room_probe`] makes
    /// it, captured and filtered on the GPU (nothing left out); placement and planes from
    /// [`room_placement`] (the CPU's). Errors: those of `room_placement` (no such probe, a
    /// centre inside a solid), bad options, device limits.
    pub fn capture_room_probe(
        &self,
        ctx: &GpuContext,
        scene: &LightmapFrameScene,
        lit: &LitScene,
        index: usize,
        opts: &ProbeOptions,
    ) -> Result<GpuProbe> {
        let shade_err = |e: lustre_shade::ShadeError| invalid("probe", e.to_string());
        opts.validate().map_err(shade_err)?;
        let (name, centre, planes) =
            room_placement(lit, index, opts.plane_rays).map_err(shade_err)?;
        let pyramid = self.capture(
            ctx,
            scene,
            centre,
            None,
            opts.face_size,
            opts.supersample,
            MipFilter::Gauss6,
        )?;
        Ok(GpuProbe {
            name,
            mesh: None,
            centre,
            planes,
            pyramid,
        })
    }

    /// Captures the cube seen from `centre` (triangles `skip` left out) at `size`² texels per
    /// face, k×k samples per texel, and filters it with `filter`: a [`GpuPyramid`] whose base
    /// level the shading pass wrote. Returns once the GPU has finished.
    #[allow(clippy::too_many_arguments)]
    pub fn capture(
        &self,
        ctx: &GpuContext,
        scene: &LightmapFrameScene,
        centre: DVec3,
        skip: Option<Range<u32>>,
        size: usize,
        k: u32,
        filter: MipFilter,
    ) -> Result<GpuPyramid> {
        let base = self.capture_cube(ctx, scene, centre, skip, size, k)?;
        self.pyramid.build_from_buffer(ctx, base, size, filter)
    }

    /// The base level only: 6·size² RGBA f32 texels (face-major, row-major) in a buffer of
    /// [`PYRAMID_USAGE`] (submitted, not waited for). Errors: a non-finite centre, a size of 0
    /// or a (k·size)² G-buffer beyond the device's textures, k = 0.
    pub fn capture_cube(
        &self,
        ctx: &GpuContext,
        scene: &LightmapFrameScene,
        centre: DVec3,
        skip: Option<Range<u32>>,
        size: usize,
        k: u32,
    ) -> Result<wgpu::Buffer> {
        let gsize = check_capture(centre, size, k)?;
        let target = GBufferTarget::new(ctx, gsize, gsize)?;
        let face = (size * size) as u64;
        let base = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probe cube"),
            size: 6 * face * 16,
            usage: PYRAMID_USAGE,
            mapped_at_creation: false,
        });
        let opts = DrawOptions {
            skip,
            plane: None,
            plane_tolerance: None,
            through_glass: true,
        };
        for f in 0..6 {
            let cam = face_camera(centre, f);
            self.gbuffer
                .draw_with(ctx, &scene.geometry, &cam, &target, &opts)?;
            let offset = u32::try_from(f as u64 * face)
                .map_err(|_| invalid("probe face size", format!("{size} is too large")))?;
            self.shade
                .shade_into(ctx, &scene.shading, &target, &cam, k, &base, offset)?;
        }
        Ok(base)
    }

    /// The (k·size)² G-buffer of face `face` as [`GpuProbeCapture::capture_cube`] draws it,
    /// read back (for the CPU twin).
    #[allow(clippy::too_many_arguments)]
    pub fn face_gbuffer(
        &self,
        ctx: &GpuContext,
        scene: &LightmapFrameScene,
        centre: DVec3,
        skip: Option<Range<u32>>,
        face: usize,
        size: usize,
        k: u32,
    ) -> Result<VisibilityBuffer> {
        let gsize = check_capture(centre, size, k)?;
        if face >= 6 {
            return Err(invalid("cube face", format!("{face} is not in 0..6")));
        }
        let target = GBufferTarget::new(ctx, gsize, gsize)?;
        let opts = DrawOptions {
            skip,
            plane: None,
            plane_tolerance: None,
            through_glass: true,
        };
        self.gbuffer.draw_with(
            ctx,
            &scene.geometry,
            &face_camera(centre, face),
            &target,
            &opts,
        )?;
        target.read_back(ctx)
    }
}

/// Checks a capture's parameters; returns the G-buffer edge k·size.
fn check_capture(centre: DVec3, size: usize, k: u32) -> Result<u32> {
    if !centre.is_finite() {
        return Err(invalid("probe centre", format!("{centre} is not finite")));
    }
    let gsize = (size as u64).saturating_mul(u64::from(k));
    if size == 0 || k == 0 || gsize > u64::from(u32::MAX) {
        return Err(invalid(
            "probe capture",
            format!("face size {size} at {k}×{k} supersampling"),
        ));
    }
    Ok(gsize as u32)
}

/// This pass as a node of [`crate::passes`].
pub const NODE: crate::passes::Node = crate::passes::Node {
    name: "probe_capture",
    shaders: &[],
    inputs: &[
        crate::passes::Resource::Scene,
        crate::passes::Resource::LightMaps,
        crate::passes::Resource::Environment,
    ],
    outputs: &[crate::passes::Resource::ProbePyramids],
};

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_env::cube::face_coords;

    /// Pixel (X + ½, Y + ½) of each face camera at N×N looks along the cube's texel (X, Y) of
    /// that face.
    #[test]
    fn face_cameras_look_along_the_cube_texel_centres() {
        let n = 7;
        for face in 0..6 {
            let cam = face_camera(DVec3::new(1.0, -2.0, 0.5), face);
            for (i, j) in [(0, 0), (3, 1), (6, 6), (2, 5)] {
                let d = cam.direction(i as f64 + 0.5, j as f64 + 0.5, n, n);
                let sc = 2.0 * (i as f64 + 0.5) / n as f64 - 1.0;
                let tc = 2.0 * (j as f64 + 0.5) / n as f64 - 1.0;
                let want = face_point(face, sc, tc).normalize();
                assert!((d - want).length() < 1e-12, "face {face} ({i}, {j})");
                let (f, s, t) = face_coords(d);
                assert_eq!(f, face);
                assert!((s * n as f64 - (i as f64 + 0.5)).abs() < 1e-9);
                assert!((t * n as f64 - (j as f64 + 0.5)).abs() < 1e-9);
            }
        }
    }
}
