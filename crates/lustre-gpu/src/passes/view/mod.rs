//! The mirror and see-through passes on the GPU (000 §4.5.1): the
//! light-mapped scene rendered with one mesh left out — from the camera mirrored in a planar
//! reflector's plane, with what lies between the mirrored eye and the plane clipped
//! ([`GpuViewPass::render_mirror`]), or from the camera itself behind a transmissive object
//! ([`GpuViewPass::render_see_through`]) — into a view buffer: radiance with its 2×2 box MIP
//! levels built on the GPU (`view_mip.wgsl`), and the position and geometric normal of every
//! level-0 texel (`view_geometry.wgsl`), in the layout of [`GpuViewBuffer`].
//!
//! The mirrored camera's basis is left-handed (the reflection flips the winding); the raster
//! pass does not cull, so nothing is lost. The clip is a fragment discard (`gbuffer.wgsl`'s
//! `fs_clip`): a fragment on the mirrored eye's side of the plane and nearer the plane than the
//! eye lies between the eye and the plane along its ray, which the CPU's rays starting on the
//! plane skip. One sample per texel centre, as the CPU twin
//! [`lustre_shade::mirror::render_mirror`] / [`lustre_shade::mirror::render_see_through`].

use crate::bindings::{
    buffer_entry, buffer_init, compute_pipeline, storage_entry, texture_entry, uniform_entry,
};
use crate::context::GpuContext;
use crate::error::{invalid, push_scope, scope_result, Result};
use crate::passes::gbuffer::{DrawOptions, GBufferPass, GBufferTarget};
use crate::passes::lightmap_shade::{tex, LightmapFrameScene, LightmapShadePass};
use crate::passes::probe_capture::mesh_triangles;
use crate::view_buffer::{level_sizes, GpuViewBuffer};
use lustre_shade::mirror::{mirror_camera, Reflector, ReflectorPlane};
use lustre_shade::probe::LitScene;
use lustre_trace::path_tracer::PathCamera;

/// The WGSL source of the geometry step.
pub const VIEW_GEOMETRY_WGSL: &str = include_str!("view_geometry.wgsl");
/// The WGSL source of one radiance MIP step.
pub const VIEW_MIP_WGSL: &str = include_str!("view_mip.wgsl");

/// A view buffer and the G-buffer it was shaded from (kept for the CPU twin; drop it when not
/// needed).
#[derive(Debug)]
pub struct ViewRender {
    /// The view buffer.
    pub view: GpuViewBuffer,
    /// Its w×h G-buffer.
    pub gbuffer: GBufferTarget,
}

/// The compiled passes of the mirror and see-through buffers.
#[derive(Debug)]
pub struct GpuViewPass {
    gbuffer: GBufferPass,
    shade: LightmapShadePass,
    geometry: (wgpu::ComputePipeline, wgpu::BindGroupLayout),
    mip: (wgpu::ComputePipeline, wgpu::BindGroupLayout),
}

impl GpuViewPass {
    /// Compiles the raster, shading, geometry and MIP passes.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let d2 = wgpu::TextureViewDimension::D2;
        let geometry = compute_pipeline(
            ctx,
            "view_geometry.wgsl",
            "compiling view_geometry.wgsl",
            VIEW_GEOMETRY_WGSL,
            &[
                uniform_entry(0),
                texture_entry(1, wgpu::TextureSampleType::Uint, d2),
                texture_entry(2, wgpu::TextureSampleType::Float { filterable: false }, d2),
                storage_entry(3, true),
                storage_entry(4, false),
            ],
        )?;
        let mip = compute_pipeline(
            ctx,
            "view_mip.wgsl",
            "compiling view_mip.wgsl",
            VIEW_MIP_WGSL,
            &[uniform_entry(0), storage_entry(1, false)],
        )?;
        Ok(GpuViewPass {
            gbuffer: GBufferPass::new(ctx)?,
            shade: LightmapShadePass::new(ctx)?,
            geometry,
            mip,
        })
    }

    /// The mirror buffer of reflector `mesh` for `camera` at w×h (000 §4.5.1), as
    /// [`lustre_shade::mirror::render_mirror`]: the reflector's plane from `lit` (the CPU's
    /// [`ReflectorPlane::of_mesh`]), the mirrored camera, the reflector left out and what lies
    /// between the mirrored eye and the plane clipped. Returns the reflector and the buffer once
    /// the GPU has finished. Errors: no such mesh, a reflector that is not planar, sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn render_mirror(
        &self,
        ctx: &GpuContext,
        scene: &LightmapFrameScene,
        lit: &LitScene,
        mesh: usize,
        camera: &PathCamera,
        w: usize,
        h: usize,
    ) -> Result<(Reflector, ViewRender)> {
        let reflector = ReflectorPlane::of_mesh(lit, mesh, camera.origin)
            .map_err(|e| invalid("planar reflector", e.to_string()))?;
        let plane = reflector.plane;
        let cam = mirror_camera(camera, &plane);
        // In the plane: within 10⁻⁴ of the reflector's own diagonal (not the scene's).
        let size = lit
            .mesh_bounds(mesh)
            .map_or(0.0, |(lo, hi)| (hi - lo).length());
        let opts = DrawOptions {
            skip: Some(mesh_triangles(lit.scene, mesh)?),
            plane: Some((plane.point, plane.normal)),
            plane_tolerance: (size > 0.0).then_some(1e-4 * size),
            through_glass: true,
        };
        let view = self.render_view(ctx, scene, &cam, w, h, &opts, mesh as u32, Some(plane))?;
        Ok((reflector, view))
    }

    /// What `camera` sees at w×h with mesh `mesh` of `lit`'s scene left out (a transmissive
    /// object), as [`lustre_shade::mirror::render_see_through`]. Returns once the GPU has
    /// finished. Errors: no such mesh, sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn render_see_through(
        &self,
        ctx: &GpuContext,
        scene: &LightmapFrameScene,
        lit: &LitScene,
        mesh: usize,
        camera: &PathCamera,
        w: usize,
        h: usize,
    ) -> Result<ViewRender> {
        let opts = DrawOptions {
            skip: Some(mesh_triangles(lit.scene, mesh)?),
            through_glass: true,
            ..DrawOptions::default()
        };
        self.render_view(ctx, scene, camera, w, h, &opts, mesh as u32, None)
    }

    /// The view buffer of `camera` at w×h drawn with `opts` (one sample per texel centre):
    /// G-buffer, light-mapped shading into level 0, geometry, box MIP levels. `mesh` and
    /// `front` are recorded in the buffer. Returns once the GPU has finished.
    #[allow(clippy::too_many_arguments)]
    pub fn render_view(
        &self,
        ctx: &GpuContext,
        scene: &LightmapFrameScene,
        camera: &PathCamera,
        w: usize,
        h: usize,
        opts: &DrawOptions,
        mesh: u32,
        front: Option<ReflectorPlane>,
    ) -> Result<ViewRender> {
        let (wu, hu) = match (u32::try_from(w), u32::try_from(h)) {
            (Ok(a), Ok(b)) if a > 0 && b > 0 => (a, b),
            _ => return Err(invalid("view buffer size", format!("{w}×{h}"))),
        };
        let sizes = level_sizes(w, h);
        let total: usize = sizes.iter().map(|(a, b)| a * b).sum();
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        if (total as u64) * 16 > limit || (w * h) as u64 * 32 > limit {
            return Err(invalid(
                "view buffer size",
                format!("{w}×{h} exceeds the device's {limit}-byte storage buffers"),
            ));
        }
        let target = GBufferTarget::new(ctx, wu, hu)?;
        // COPY_DST: a see-through layer is copied over level 0.
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let buffer = |label: &str, bytes: u64| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        let radiance = buffer("view buffer radiance", total as u64 * 16);
        let geometry = buffer("view buffer geometry", (w * h) as u64 * 32);
        self.gbuffer
            .draw_with(ctx, &scene.geometry, camera, &target, opts)?;
        self.shade
            .shade_into(ctx, &scene.shading, &target, camera, 1, &radiance, 0)?;
        let scope = push_scope(ctx);
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("view buffer"),
            });
        let params = buffer_init(
            ctx,
            "view geometry params",
            bytemuck::cast_slice(&[wu, hu, 0, 0]),
            wgpu::BufferUsages::UNIFORM,
        );
        let views = [&target.prim, &target.bary_depth].map(|t| t.create_view(&Default::default()));
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("view_geometry.wgsl"),
            layout: &self.geometry.1,
            entries: &[
                buffer_entry(0, &params),
                tex(1, &views[0]),
                tex(2, &views[1]),
                buffer_entry(3, &scene.geometry.triangles),
                buffer_entry(4, &geometry),
            ],
        });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("view geometry"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.geometry.0);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(wu.div_ceil(8), hu.div_ceil(8), 1);
        }
        self.encode_levels(ctx, &mut enc, &radiance, &sizes);
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        scope_result(scope, "view buffer")?;
        Ok(ViewRender {
            view: GpuViewBuffer {
                radiance,
                geometry,
                width: w,
                height: h,
                level_sizes: sizes,
                camera: *camera,
                mesh,
                front,
            },
            gbuffer: target,
        })
    }

    /// Rebuilds `view`'s MIP levels from its level 0 (after a see-through layer was copied
    /// over it). Submitted, not waited for.
    pub fn build_levels(&self, ctx: &GpuContext, view: &GpuViewBuffer) -> Result<()> {
        let scope = push_scope(ctx);
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("view buffer levels"),
            });
        self.encode_levels(ctx, &mut enc, &view.radiance, &view.level_sizes);
        ctx.queue.submit([enc.finish()]);
        scope_result(scope, "view buffer levels")
    }

    /// The 2×2 box MIP steps of `radiance` (levels of `sizes`, finest first), one pass each.
    fn encode_levels(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        radiance: &wgpu::Buffer,
        sizes: &[(usize, usize)],
    ) {
        let mut offset = 0usize;
        for pair in sizes.windows(2) {
            let ((pw, ph), (cw, ch)) = (pair[0], pair[1]);
            let p = [
                pw as u32,
                ph as u32,
                cw as u32,
                ch as u32,
                offset as u32,
                (offset + pw * ph) as u32,
                0,
                0,
            ];
            let params = buffer_init(
                ctx,
                "view mip params",
                bytemuck::cast_slice(&p),
                wgpu::BufferUsages::UNIFORM,
            );
            let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("view_mip.wgsl"),
                layout: &self.mip.1,
                entries: &[buffer_entry(0, &params), buffer_entry(1, radiance)],
            });
            // One pass per level: the next level reads what this one wrote.
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("view mip"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.mip.0);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups((cw as u32).div_ceil(8), (ch as u32).div_ceil(8), 1);
            offset += pw * ph;
        }
    }
}

/// This pass as a node of [`crate::passes`].
pub const NODE: crate::passes::Node = crate::passes::Node {
    name: "view",
    shaders: &[
        ("view_geometry.wgsl", VIEW_GEOMETRY_WGSL),
        ("view_mip.wgsl", VIEW_MIP_WGSL),
    ],
    inputs: &[
        crate::passes::Resource::Scene,
        crate::passes::Resource::LightMaps,
        crate::passes::Resource::Environment,
        crate::passes::Resource::Camera,
    ],
    outputs: &[crate::passes::Resource::ViewBuffers],
};
