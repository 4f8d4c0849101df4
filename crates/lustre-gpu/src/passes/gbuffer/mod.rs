//! The raster G-buffer pass, `gbuffer.wgsl`: a scene's triangles, in the order of
//! [`lustre_trace::bake::diffuse_path_scene`]'s geometry (so triangle ids agree with the CPU),
//! drawn at a [`PathCamera`] into a G-buffer of triangle id (R32Uint, [`SKY`] where nothing
//! is drawn), barycentrics (b1, b2) and view depth (Rgba32Float), and unit shading normal
//! (Rgba32Float), with a Depth32Float reverse-Z depth test; alpha-masked materials discard
//! the fragments the CPU's ray test skips (opacity at uv0 below the cutoff, or below ½ without
//! one; `texture_sample.wgsl` is the CPU's texture lookup). Formats are the ones lavapipe
//! renders to (TOOLCHAIN.md: Rgba32Float; R32Uint and Depth32Float are Vulkan-mandatory
//! attachments).
//!
//! Camera model: the projection maps the CPU camera's image position (X, Y) of a W×H image to
//! NDC (2X/W − 1, 1 − 2Y/H), so a raster pixel centre is the ray
//! `PathCamera::direction(X + ½, Y + ½, W, H)`; the CPU twin is
//! [`lustre_trace::bake::gbuffer::trace_gbuffer`] (ray casting at the same centres). Raster
//! coverage (top-left rule) and ray casting (watertight test) may disagree on pixels whose
//! centre lies on an edge, and depth ties between coplanar triangles resolve differently.

use crate::bindings::record_texture_readback;
use crate::bindings::{buffer_init, map_read};
use crate::context::GpuContext;
use crate::error::{invalid, push_scope, scope_result, Result};
use crate::wgsl;
use glam::DVec3;
use lustre_scene::Scene;
use lustre_trace::bake::gbuffer::{VisibilityBuffer, SKY};
use lustre_trace::path_tracer::{Geometry, PathCamera};
use std::sync::OnceLock;

/// The WGSL source of the raster pass: the texture lookup module, then `gbuffer.wgsl`.
pub fn gbuffer_wgsl() -> &'static str {
    static SRC: OnceLock<String> = OnceLock::new();
    SRC.get_or_init(|| wgsl::compose(&[&wgsl::TEXTURE_SAMPLE], include_str!("gbuffer.wgsl")))
}

/// Vec4s per triangle in the raster pass's triangle buffer.
const STRIDE: usize = 8;

/// RGBA f32 texels of several textures, and per texture (first texel, width, height, 0).
pub(crate) type PackedTextures = (Vec<[f32; 4]>, Vec<[u32; 4]>);

/// The texels of `scene`'s textures `slots` (in that order) as RGBA f32, and per texture
/// (first texel, width, height, 0), as `texture_sample.wgsl` reads them; one dummy texel when
/// there are none. Errors: more texels than a storage buffer of `limit` bytes holds.
pub(crate) fn pack_textures(
    scene: &Scene,
    slots: &[usize],
    limit: usize,
) -> Result<PackedTextures> {
    let total: usize = slots
        .iter()
        .map(|&t| scene.textures[t].width as usize * scene.textures[t].height as usize)
        .sum();
    if total * 16 > limit || total > u32::MAX as usize {
        return Err(invalid(
            "textures",
            format!(
                "{total} texels need {} bytes; the device's storage buffers hold {limit}",
                total * 16
            ),
        ));
    }
    let mut texels = Vec::with_capacity(total.max(1));
    let mut info = Vec::with_capacity(slots.len().max(1));
    for &t in slots {
        let tex = &scene.textures[t];
        info.push([texels.len() as u32, tex.width, tex.height, 0]);
        for y in 0..tex.height {
            for x in 0..tex.width {
                texels.push(tex.texel(x, y));
            }
        }
    }
    if texels.is_empty() {
        texels.push([0.0; 4]);
        info.push([0; 4]);
    }
    Ok((texels, info))
}

/// The slot of texture `t` in `slots` (appended when new). Errors: `t` beyond the scene's
/// textures (names the material).
pub(crate) fn texture_slot(
    scene: &Scene,
    material: &str,
    t: usize,
    slots: &mut Vec<usize>,
) -> Result<i32> {
    if t >= scene.textures.len() {
        return Err(invalid(
            format!("material {material:?}"),
            format!("texture {t} of {} textures", scene.textures.len()),
        ));
    }
    Ok(match slots.iter().position(|&s| s == t) {
        Some(s) => s as i32,
        None => {
            slots.push(t);
            slots.len() as i32 - 1
        }
    })
}

/// Format of the triangle-id target.
pub const PRIM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// Format of the barycentrics-and-depth and the normal targets.
pub const FLOAT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Format of the depth buffer (reverse Z).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// A scene's triangles on the GPU: per triangle its corners' positions, shading normals and
/// uv0, and its material; the materials' alpha masks with their opacity textures.
#[derive(Debug)]
pub struct GpuGeometry {
    /// 8 vec4 per triangle: positions of corners 0..2, their shading normals, (uv0 a, b),
    /// (uv0 c, material bits, 0).
    pub triangles: wgpu::Buffer,
    masks: wgpu::Buffer,
    texels: wgpu::Buffer,
    texture_info: wgpu::Buffer,
    /// Number of triangles.
    pub count: u32,
    /// Near plane (view depth) of the projection: 10⁻⁵ of the scene's bounding diagonal.
    pub near: f32,
    /// Whether any material has an alpha mask (drawn with the discarding fragment shader).
    pub masked: bool,
}

impl GpuGeometry {
    /// Uploads `g` (the triangles of `diffuse_path_scene(scene)`, in its order). Corners
    /// without shading normals get the geometric normal. Errors: no triangles, non-finite
    /// positions, material indices beyond `scene`'s, more data than a storage buffer of the
    /// device holds.
    pub fn upload(ctx: &GpuContext, scene: &Scene, g: &Geometry) -> Result<Self> {
        if g.positions.is_empty() {
            return Err(invalid("scene", "the scene has no triangles to draw"));
        }
        let limit = ctx.device.limits().max_storage_buffer_binding_size as usize;
        let bytes = g.positions.len() * STRIDE * 16;
        if bytes > limit || g.positions.len() > (u32::MAX / 3) as usize {
            return Err(invalid(
                "scene",
                format!(
                    "{} triangles need {bytes} bytes; the device's storage buffers hold {limit}",
                    g.positions.len()
                ),
            ));
        }
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        let mut data: Vec<[f32; 4]> = Vec::with_capacity(g.positions.len() * STRIDE);
        for (i, tri) in g.positions.iter().enumerate() {
            if tri.iter().any(|p| !p.is_finite()) {
                return Err(invalid(
                    "scene",
                    format!("triangle {i} has a non-finite corner"),
                ));
            }
            let ng = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            let ns = g.normals.get(i).copied().unwrap_or([ng; 3]);
            for p in tri {
                lo = lo.min(*p);
                hi = hi.max(*p);
                data.push([p.x as f32, p.y as f32, p.z as f32, 1.0]);
            }
            for n in ns {
                data.push([n.x as f32, n.y as f32, n.z as f32, 0.0]);
            }
            let uv = g.uvs.get(i).copied().unwrap_or([[0.0; 2]; 3]);
            let m = g.material.get(i).copied().unwrap_or(0);
            if m as usize >= scene.materials.len() {
                return Err(invalid(
                    "scene",
                    format!("triangle {i} has material {m} of {}", scene.materials.len()),
                ));
            }
            let f = |v: f64| v as f32;
            data.push([f(uv[0][0]), f(uv[0][1]), f(uv[1][0]), f(uv[1][1])]);
            data.push([f(uv[2][0]), f(uv[2][1]), f32::from_bits(m), 0.0]);
        }
        // The alpha test of `PathTracer::intersect`: opacity (at uv0, whichever set the texture
        // names) clamped to [0, 1], present at ≥ the cutoff (½ without one).
        let mut slots = Vec::new();
        let mut masks: Vec<[f32; 4]> = Vec::with_capacity(scene.materials.len().max(1));
        for (k, m) in scene.materials.iter().enumerate() {
            let glass = if lustre_shade::probe::transmits(scene, k) {
                256u32
            } else {
                0
            };
            masks.push(match &m.alpha_mask {
                None => [
                    0.0,
                    0.0,
                    f32::from_bits(-2i32 as u32),
                    f32::from_bits(glass),
                ],
                Some(a) => {
                    let t = match a.opacity.texture {
                        Some(r) => texture_slot(scene, &m.name, r.texture, &mut slots)?,
                        None => -1,
                    };
                    [
                        a.opacity.factor as f32,
                        a.cutoff.unwrap_or(0.5),
                        f32::from_bits(t as u32),
                        f32::from_bits(u32::from(a.opacity.channel.min(3)) | glass),
                    ]
                }
            });
        }
        if masks.is_empty() {
            masks.push([0.0; 4]);
        }
        let (texels, info) = pack_textures(scene, &slots, limit)?;
        let near = ((hi - lo).length() * 1e-5).max(1e-6) as f32;
        let storage = |label: &str, contents: &[u8]| {
            buffer_init(ctx, label, contents, wgpu::BufferUsages::STORAGE)
        };
        Ok(GpuGeometry {
            triangles: storage("gbuffer triangles", bytemuck::cast_slice(&data)),
            masks: storage("gbuffer alpha masks", bytemuck::cast_slice(&masks)),
            texels: storage("gbuffer opacity texels", bytemuck::cast_slice(&texels)),
            texture_info: storage("gbuffer opacity textures", bytemuck::cast_slice(&info)),
            count: g.positions.len() as u32,
            near,
            masked: scene.materials.iter().any(|m| m.alpha_mask.is_some()),
        })
    }
}

/// The camera uniform of `gbuffer.wgsl` and `lightmap_shade.wgsl`: origin, forward, right, up
/// (xyz), then (tan(fov_y/2), W/H, near, 0).
pub(crate) fn camera_uniform(camera: &PathCamera, w: u32, h: u32, near: f32) -> [[f32; 4]; 5] {
    let v = |d: DVec3| [d.x as f32, d.y as f32, d.z as f32, 0.0];
    [
        v(camera.origin),
        v(camera.forward),
        v(camera.right),
        v(camera.up),
        [
            camera.tan_half_fov_y as f32,
            (f64::from(w) / f64::from(h)) as f32,
            near,
            0.0,
        ],
    ]
}

/// The G-buffer targets of one size.
#[derive(Debug)]
pub struct GBufferTarget {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Triangle ids ([`PRIM_FORMAT`]).
    pub prim: wgpu::Texture,
    /// (b1, b2, view depth, 0) ([`FLOAT_FORMAT`]).
    pub bary_depth: wgpu::Texture,
    /// Unit shading normal ([`FLOAT_FORMAT`]).
    pub normal: wgpu::Texture,
    depth: wgpu::Texture,
}

impl GBufferTarget {
    /// Targets of `w`×`h` pixels. Errors: a zero size or one beyond the device's texture limit.
    pub fn new(ctx: &GpuContext, w: u32, h: u32) -> Result<Self> {
        let max = ctx.device.limits().max_texture_dimension_2d;
        if w == 0 || h == 0 || w > max || h > max {
            return Err(invalid(
                "G-buffer size",
                format!("{w}×{h} must be between 1×1 and {max}×{max}"),
            ));
        }
        let scope = push_scope(ctx);
        let tex = |label: &str, format: wgpu::TextureFormat, usage: wgpu::TextureUsages| {
            ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let color = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let t = GBufferTarget {
            width: w,
            height: h,
            prim: tex("gbuffer prim", PRIM_FORMAT, color),
            bary_depth: tex("gbuffer bary", FLOAT_FORMAT, color),
            normal: tex("gbuffer normal", FLOAT_FORMAT, color),
            depth: tex(
                "gbuffer depth",
                DEPTH_FORMAT,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            ),
        };
        scope_result(scope, "creating the G-buffer")?;
        Ok(t)
    }

    /// Copies the G-buffer to the host.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<VisibilityBuffer> {
        let (w, h) = (self.width, self.height);
        let prim: Vec<u32> =
            bytemuck::cast_slice(&read_texture(ctx, &self.prim, w, h, 4)?).to_vec();
        let bd = read_texture(ctx, &self.bary_depth, w, h, 16)?;
        let bd: &[[f32; 4]] = bytemuck::cast_slice(&bd);
        let nn = read_texture(ctx, &self.normal, w, h, 16)?;
        let nn: &[[f32; 4]] = bytemuck::cast_slice(&nn);
        Ok(VisibilityBuffer {
            width: w as usize,
            height: h as usize,
            bary: bd
                .iter()
                .zip(&prim)
                .map(|(v, &p)| if p == SKY { [0.0; 2] } else { [v[0], v[1]] })
                .collect(),
            depth: bd
                .iter()
                .zip(&prim)
                .map(|(v, &p)| if p == SKY { 0.0 } else { v[2] })
                .collect(),
            normal: nn.iter().map(|v| [v[0], v[1], v[2]]).collect(),
            prim,
        })
    }
}

/// Reads a `w`×`h` texture of `bpp` bytes per pixel back to the host (rows unpadded).
pub(crate) fn read_texture(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    w: u32,
    h: u32,
    bpp: u32,
) -> Result<Vec<u8>> {
    let scope = push_scope(ctx);
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("gbuffer readback"),
        });
    let (buffer, padded) = record_texture_readback(
        &ctx.device,
        &mut enc,
        texture,
        (w, h),
        bpp,
        "gbuffer readback",
    );
    ctx.queue.submit([enc.finish()]);
    let out = map_read(ctx, &buffer, "G-buffer readback", scope)?;
    let (row, padded) = ((w * bpp) as usize, padded as usize);
    Ok((0..h as usize)
        .flat_map(|y| out[y * padded..y * padded + row].iter().copied())
        .collect())
}

/// What a G-buffer draw leaves out: a range of triangles (one mesh of the scene; a probe
/// object, a see-through object, a reflector) and what lies between the eye and a plane (the
/// mirror pass, 000 §4.5.1).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DrawOptions {
    /// Triangles (indices in the geometry) not drawn.
    pub skip: Option<std::ops::Range<u32>>,
    /// A clip plane (a point on it, its normal): fragments on the eye's side of it and nearer
    /// the plane than the eye (those between the eye and the plane along the eye's rays), or
    /// within `plane_tolerance` of the plane, are discarded, as the CPU mirror pass starts its
    /// rays on the plane. An eye on the plane clips nothing.
    pub plane: Option<(DVec3, DVec3)>,
    /// How far beyond the clip plane surfaces still count as in it (the reflector's coplanar
    /// neighbours); `None`: 10⁻⁴ of the scene's diagonal. The mirror pass gives 10⁻⁴ of the
    /// reflector's own diagonal: on a 2 km site the scene's would clip the bottom 28 cm of a
    /// room's walls out of its floor's mirror, which then showed the sunlit ground through them.
    pub plane_tolerance: Option<f64>,
    /// Leave out the triangles of transmitting materials too (probes and view buffers look
    /// through glass, as `LitScene::hit`).
    pub through_glass: bool,
}

/// The camera uniform of `gbuffer.wgsl`: [`camera_uniform`], the skipped triangle range and the
/// clip plane with the eye's signed distance to it.
fn draw_uniform(
    camera: &PathCamera,
    w: u32,
    h: u32,
    near: f32,
    opts: &DrawOptions,
) -> Result<Vec<[u32; 4]>> {
    let mut u: Vec<[u32; 4]> = camera_uniform(camera, w, h, near)
        .iter()
        .map(|v| v.map(f32::to_bits))
        .collect();
    let skip = opts.skip.clone().unwrap_or(0..0);
    u.push([
        skip.start,
        skip.end.max(skip.start),
        u32::from(opts.through_glass),
        0,
    ]);
    let (plane, eye) = match opts.plane {
        Some((point, normal)) => {
            let n = normal
                .try_normalize()
                .filter(|_| point.is_finite())
                .ok_or_else(|| {
                    invalid(
                        "clip plane",
                        format!("point {point}, normal {normal} do not define a plane"),
                    )
                })?;
            let offset = -n.dot(point);
            (
                [n.x as f32, n.y as f32, n.z as f32, offset as f32],
                (n.dot(camera.origin) + offset) as f32,
            )
        }
        None => ([0.0; 4], 0.0),
    };
    u.push(plane.map(f32::to_bits));
    // Surfaces within the tolerance (by default 10 near planes, 10⁻⁴ of the scene's diagonal)
    // of the plane count as in it.
    let tolerance = opts.plane_tolerance.map_or(10.0 * near, |t| t as f32);
    u.push([eye.to_bits(), tolerance.to_bits(), 0, 0]);
    Ok(u)
}

/// The compiled raster pass.
#[derive(Debug)]
pub struct GBufferPass {
    /// Indexed by 2·clip + masked: `fs_main`, `fs_masked`, `fs_clip`, `fs_clip_masked`.
    pipelines: [wgpu::RenderPipeline; 4],
    layout: wgpu::BindGroupLayout,
}

impl GBufferPass {
    /// Compiles `gbuffer.wgsl`.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let scope = push_scope(ctx);
        let module = ctx
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("gbuffer.wgsl"),
                source: wgpu::ShaderSource::Wgsl(gbuffer_wgsl().into()),
            });
        let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("gbuffer.wgsl"),
                entries: &[
                    entry(0, wgpu::BufferBindingType::Storage { read_only: true }),
                    entry(1, wgpu::BufferBindingType::Uniform),
                    entry(2, wgpu::BufferBindingType::Storage { read_only: true }),
                    entry(3, wgpu::BufferBindingType::Storage { read_only: true }),
                    entry(4, wgpu::BufferBindingType::Storage { read_only: true }),
                ],
            });
        let pipeline_layout = ctx
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("gbuffer.wgsl"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
        let target = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let pipeline = |fragment: &'static str| {
            ctx.device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("gbuffer.wgsl"),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleList,
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Greater),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fragment),
                        compilation_options: Default::default(),
                        targets: &[
                            target(PRIM_FORMAT),
                            target(FLOAT_FORMAT),
                            target(FLOAT_FORMAT),
                        ],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
        };
        let pipelines = [
            pipeline("fs_main"),
            pipeline("fs_masked"),
            pipeline("fs_clip"),
            pipeline("fs_clip_masked"),
        ];
        scope_result(scope, "compiling gbuffer.wgsl")?;
        Ok(GBufferPass { pipelines, layout })
    }

    /// Draws `geometry` seen from `camera` into `target` (submitted; returns without waiting).
    pub fn draw(
        &self,
        ctx: &GpuContext,
        geometry: &GpuGeometry,
        camera: &PathCamera,
        target: &GBufferTarget,
    ) -> Result<()> {
        self.draw_with(ctx, geometry, camera, target, &DrawOptions::default())
    }

    /// [`GBufferPass::draw`] leaving out what `opts` names. Errors: a degenerate clip plane.
    pub fn draw_with(
        &self,
        ctx: &GpuContext,
        geometry: &GpuGeometry,
        camera: &PathCamera,
        target: &GBufferTarget,
        opts: &DrawOptions,
    ) -> Result<()> {
        let cam = draw_uniform(camera, target.width, target.height, geometry.near, opts)?;
        let scope = push_scope(ctx);
        let uniform = buffer_init(
            ctx,
            "gbuffer camera",
            bytemuck::cast_slice(&cam),
            wgpu::BufferUsages::UNIFORM,
        );
        let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer.wgsl"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: geometry.triangles.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: geometry.masks.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: geometry.texels.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: geometry.texture_info.as_entire_binding(),
                },
            ],
        });
        let views = [&target.prim, &target.bary_depth, &target.normal]
            .map(|t| t.create_view(&Default::default()));
        let depth_view = target.depth.create_view(&Default::default());
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("gbuffer"),
            });
        {
            let attach = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let mut prim = attach(&views[0]);
            if let Some(p) = prim.as_mut() {
                // The sky id: 0xFFFFFFFF (a u32 target clears to the integer value).
                p.ops.load = wgpu::LoadOp::Clear(wgpu::Color {
                    r: f64::from(SKY),
                    g: 0.0,
                    b: 0.0,
                    a: 0.0,
                });
            }
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("gbuffer"),
                color_attachments: &[prim, attach(&views[1]), attach(&views[2])],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let clip = 2 * usize::from(opts.plane.is_some());
            pass.set_pipeline(&self.pipelines[clip + usize::from(geometry.masked)]);
            pass.set_bind_group(0, &bind, &[]);
            pass.draw(0..geometry.count * 3, 0..1);
        }
        ctx.queue.submit([enc.finish()]);
        scope_result(scope, "drawing the G-buffer")
    }
}

/// This pass as a node of [`crate::passes`].
pub const NODE: crate::passes::Node = crate::passes::Node {
    name: "gbuffer",
    shaders: &[("gbuffer.wgsl", include_str!("gbuffer.wgsl"))],
    inputs: &[
        crate::passes::Resource::Scene,
        crate::passes::Resource::Camera,
    ],
    outputs: &[crate::passes::Resource::GBuffer],
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::passes::lightmap_shade::lightmap_shade_wgsl;

    /// Both shaders (with the shared texture lookup) parse and validate without an adapter, and
    /// the uniform blocks have the sizes the Rust side writes.
    #[test]
    fn wgsl_parses_and_validates_with_naga() {
        for (src, entries, uniform, bytes) in [
            (
                gbuffer_wgsl(),
                &[
                    "vs_main",
                    "fs_main",
                    "fs_masked",
                    "fs_clip",
                    "fs_clip_masked",
                ][..],
                "Camera",
                8 * 16,
            ),
            (lightmap_shade_wgsl(), &["main"][..], "Shade", 11 * 16),
        ] {
            let m = crate::wgsl::validated(src);
            for e in entries {
                assert!(m.entry_points.iter().any(|p| p.name == *e), "{e}");
            }
            let size = m
                .types
                .iter()
                .find(|(_, t)| t.name.as_deref() == Some(uniform))
                .map(|(_, t)| t.inner.size(m.to_ctx()))
                .unwrap_or_else(|| panic!("no struct {uniform}"));
            assert_eq!(size, bytes, "{uniform}");
        }
    }
}
