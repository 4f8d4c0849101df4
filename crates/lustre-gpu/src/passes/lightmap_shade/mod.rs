//! Light-mapped diffuse shading of a G-buffer on the GPU (000 Eq. 4.1),
//! `lightmap_shade.wgsl`: per pixel the emission (front side) plus kd·E/π, E bilinear from the
//! light-map page at uv1, kd the material's diffuse albedo (constant or base-colour textured),
//! the environment (equirect, `EnvLight::eval`'s bilinear lookup) where the G-buffer is sky;
//! k×k G-buffer pixels box-averaged into one output pixel. The CPU twin is
//! [`lustre_trace::bake::gbuffer::shade_gbuffer`].
//!
//! Uploads: light-map pages as one Rgba32Float 2D texture array; the environment as an
//! Rgba32Float 2D texture; base-colour textures as RGBA f32 texels in a storage buffer; all
//! read with `textureLoad` / indexing and filtered by hand (the CPU's texel-centre, clamp and
//! wrap rules).
//!
//! [`LightmapRenderer`] runs both passes: [`LightmapRenderer::render`].

use crate::bindings::{buffer_entry, buffer_init, map_read, texture_entry};
use crate::context::GpuContext;
use crate::error::{invalid, push_scope, scope_result, wgpu_error, Result};
use crate::passes::gbuffer::{
    camera_uniform, pack_textures, texture_slot, GBufferPass, GBufferTarget, GpuGeometry,
};
use crate::wgsl;
use lustre_brdf::rgb::Rgb;
use lustre_scene::lightmap::LightmapAtlas;
use lustre_scene::{MaterialKind, Scene, TexturedRgb, TexturedScalar};
use lustre_trace::bake::gbuffer::{gbuffer_size, VisibilityBuffer};
use lustre_trace::bake::render::Lightmapped;
use lustre_trace::bake::{diffuse_path_scene, BaseAlbedo};
use lustre_trace::image::Image;
use lustre_trace::path_tracer::{EnvLight, Geometry, PathCamera};
use std::sync::OnceLock;

/// The WGSL source of the shading pass: the albedo and texture modules, then
/// `lightmap_shade.wgsl`.
pub fn lightmap_shade_wgsl() -> &'static str {
    static SRC: OnceLock<String> = OnceLock::new();
    SRC.get_or_init(|| {
        wgsl::compose(
            &[&wgsl::MATERIAL_ALBEDO],
            include_str!("lightmap_shade.wgsl"),
        )
    })
}

const NO_PAGE: u32 = u32::MAX;

/// A light-mapped scene's shading data on the GPU.
#[derive(Debug)]
pub struct GpuLightmapScene {
    triangles: wgpu::Buffer,
    materials: wgpu::Buffer,
    texels: wgpu::Buffer,
    texture_info: wgpu::Buffer,
    pages: wgpu::Texture,
    environment: wgpu::Texture,
    page_size: [u32; 2],
    /// (rows of the world → map rotation, scale), `None` without an environment.
    env: Option<([[f32; 4]; 3], f32)>,
    /// Triangles (as in the geometry).
    pub count: u32,
}

/// A textured scalar as `lightmap_shade.wgsl`'s `scalar_at` reads it: (factor, texture slot
/// bits (−1 none), uv set bits, channel bits).
pub(crate) fn gpu_scalar(
    scene: &Scene,
    material: &str,
    v: &TexturedScalar,
    slots: &mut Vec<usize>,
) -> Result<[f32; 4]> {
    let (t, uv_set) = match v.texture {
        Some(r) => (
            texture_slot(scene, material, r.texture, slots)?,
            u32::from(r.uv_set.min(1)),
        ),
        None => (-1, 0),
    };
    Ok([
        v.factor as f32,
        f32::from_bits(t as u32),
        f32::from_bits(uv_set),
        f32::from_bits(u32::from(v.channel.min(3))),
    ])
}

/// A material as `lightmap_shade.wgsl` reads it ([`lustre_trace::bake::diffuse_albedo`]):
/// (base factor, k), (base texture slot bits, uv set bits, two-sided, 1 when metallic or
/// transmission is textured, 2 for a textured plastic's coated base), then metallic and
/// transmission as [`gpu_scalar`] (a coated base: its Fdr in the first row's x). Untextured
/// factors are clamped (and a plastic's coated base applied) here; with textured metallic or
/// transmission, k is computed per pixel; a textured plastic's kd = k·c / (1 − Fdr·c) per pixel.
fn gpu_material(
    scene: &Scene,
    m: usize,
    base: BaseAlbedo,
    slots: &mut Vec<usize>,
) -> Result<[[f32; 4]; 4]> {
    let material = &scene.materials[m];
    let clamp = |c: Rgb| {
        c.map(|v| {
            if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                0.0
            }
        })
    };
    let untextured = |c: Rgb, k: f64| (clamp(c), None, k);
    let rgb = |t: &TexturedRgb, k: f64| match t.texture {
        Some(r) => (t.factor, Some(r), k),
        None => untextured(t.factor, k),
    };
    let mut scalars = None;
    let mut mode = 0.0;
    let (factor, texture, k) = match &material.kind {
        MaterialKind::Diffuse { reflectance } => rgb(reflectance, 1.0),
        MaterialKind::Plastic { diffuse, .. } | MaterialKind::RoughPlastic { diffuse, .. } => {
            match diffuse.texture {
                Some(r) => {
                    mode = 2.0;
                    let fdr = base.coat.fdr as f32;
                    scalars = Some([[fdr, 0.0, 0.0, 0.0], [0.0; 4]]);
                    (diffuse.factor, Some(r), base.coat.scale)
                }
                None => untextured(base.coat.kd(clamp(diffuse.factor)), 1.0),
            }
        }
        MaterialKind::PbrMetallicRoughness {
            base_color,
            metallic,
            transmission,
            ..
        } => {
            if metallic.texture.is_some() || transmission.texture.is_some() {
                mode = 1.0;
                scalars = Some([
                    gpu_scalar(scene, &material.name, metallic, slots)?,
                    gpu_scalar(scene, &material.name, transmission, slots)?,
                ]);
                rgb(base_color, 1.0)
            } else if transmission.factor >= 0.5 {
                untextured(Rgb::ZERO, 0.0)
            } else {
                rgb(base_color, 1.0 - metallic.factor.clamp(0.0, 1.0))
            }
        }
        MaterialKind::Spec(_) => untextured(base.spec, 1.0),
        _ => untextured(Rgb::ZERO, 0.0),
    };
    let (tex, uv_set) = match texture {
        Some(r) => (
            texture_slot(scene, &material.name, r.texture, slots)?,
            u32::from(r.uv_set.min(1)),
        ),
        None => (-1, 0),
    };
    let f = factor.0.map(|v| v as f32);
    let [metal, trans] = scalars.unwrap_or([[0.0; 4]; 2]);
    Ok([
        [f[0], f[1], f[2], k as f32],
        [
            f32::from_bits(tex as u32),
            f32::from_bits(uv_set),
            if material.two_sided { 1.0 } else { 0.0 },
            mode,
        ],
        metal,
        trans,
    ])
}

/// What `lightmap_shade.wgsl` (and `frame_shade.wgsl`'s per-pixel albedo) read of a scene:
/// per triangle 8 vec4 (corner normals, uv0, uv1 in texels, emission and light-map page,
/// material), per material 4 vec4 ([`gpu_material`]), the textures' texels and their table.
pub(crate) struct ShadingRecords {
    pub tris: Vec<[f32; 4]>,
    pub mats: Vec<[f32; 4]>,
    pub texels: Vec<[f32; 4]>,
    pub info: Vec<[u32; 4]>,
}

/// The [`ShadingRecords`] of the triangles `g` of `scene` mapped by `lit`, with the
/// materials' [`BaseAlbedo`]s `bases`; the textures are those of `slots` (textures other records already
/// refer to by slot), then those the records add. Errors (named): a triangle's material or a
/// texture beyond the scene's, records beyond `max_buffer` bytes.
pub(crate) fn shading_records(
    scene: &Scene,
    lit: &Lightmapped,
    g: &Geometry,
    bases: &[BaseAlbedo],
    mut slots: Vec<usize>,
    max_buffer: usize,
) -> Result<ShadingRecords> {
    let mut mats = Vec::with_capacity(4 * scene.materials.len());
    for m in 0..scene.materials.len() {
        let b = bases.get(m).copied().unwrap_or_default();
        mats.extend(gpu_material(scene, m, b, &mut slots)?);
    }
    if mats.is_empty() {
        mats.push([0.0; 4]);
    }
    let (texels, info) = pack_textures(scene, &slots, max_buffer)?;
    let mut tris: Vec<[f32; 4]> = Vec::with_capacity(8 * g.positions.len());
    let v4 = |p: [f64; 2], q: [f64; 2]| [p[0] as f32, p[1] as f32, q[0] as f32, q[1] as f32];
    for (i, tri) in g.positions.iter().enumerate() {
        let ng = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        for n in g.normals.get(i).copied().unwrap_or([ng; 3]) {
            tris.push([n.x as f32, n.y as f32, n.z as f32, 0.0]);
        }
        let uv0 = g.uvs.get(i).copied().unwrap_or([[0.0; 2]; 3]);
        let (page, uv1) = lit.lightmap_triangle(i).unwrap_or((NO_PAGE, [[0.0; 2]; 3]));
        tris.push(v4(uv0[0], uv0[1]));
        tris.push(v4(uv0[2], uv1[0]));
        tris.push(v4(uv1[1], uv1[2]));
        let e = g.emission.get(i).copied().unwrap_or(Rgb::ZERO);
        tris.push([e[0] as f32, e[1] as f32, e[2] as f32, f32::from_bits(page)]);
        let m = g.material.get(i).copied().unwrap_or(0);
        if m as usize >= scene.materials.len() {
            return Err(invalid(
                "scene",
                format!("triangle {i} has material {m} of {}", scene.materials.len()),
            ));
        }
        tris.push([f32::from_bits(m), 0.0, 0.0, 0.0]);
    }
    if tris.len() * 16 > max_buffer {
        return Err(invalid(
            "scene",
            format!(
                "{} triangles need {} bytes of shading data; the device's storage buffers hold {max_buffer}",
                g.positions.len(),
                tris.len() * 16
            ),
        ));
    }
    Ok(ShadingRecords {
        tris,
        mats,
        texels,
        info,
    })
}

impl GpuLightmapScene {
    /// Uploads what shading needs: per triangle of `g` (the geometry `lit` was built for) its
    /// normals, uv0, light-map page and uv1, emission and material; the materials' diffuse
    /// albedo (`lit`'s [`Lightmapped::bases`]); the light-map pages of `atlas`;
    /// `environment`. Errors: texture references beyond the scene's (named), pages or textures
    /// beyond the device's limits.
    pub fn upload(
        ctx: &GpuContext,
        scene: &Scene,
        atlas: &LightmapAtlas,
        pages: &[Vec<[f32; 3]>],
        lit: &Lightmapped,
        g: &Geometry,
        environment: Option<&EnvLight>,
    ) -> Result<Self> {
        let limits = ctx.device.limits();
        if g.positions.is_empty() {
            return Err(invalid("scene", "the scene has no triangles to shade"));
        }
        let ShadingRecords {
            tris,
            mats,
            texels,
            info,
        } = shading_records(
            scene,
            lit,
            g,
            lit.bases(),
            Vec::new(),
            limits.max_storage_buffer_binding_size as usize,
        )?;
        let max2d = limits.max_texture_dimension_2d;
        if atlas.width == 0
            || atlas.height == 0
            || atlas.width > max2d
            || atlas.height > max2d
            || atlas.pages > limits.max_texture_array_layers
            || pages.len() != atlas.pages as usize
        {
            return Err(invalid(
                "light map",
                format!(
                    "{} pages of {}×{} (atlas: {} pages) do not fit the device's {max2d}² × {} textures",
                    pages.len(),
                    atlas.width,
                    atlas.height,
                    atlas.pages,
                    limits.max_texture_array_layers
                ),
            ));
        }
        let scope = push_scope(ctx);
        let storage = |label: &str, contents: &[u8]| {
            buffer_init(ctx, label, contents, wgpu::BufferUsages::STORAGE)
        };
        let n_pages = atlas.pages.max(1);
        let page_tex = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("light-map pages"),
            size: wgpu::Extent3d {
                width: atlas.width,
                height: atlas.height,
                depth_or_array_layers: n_pages,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for (layer, page) in pages.iter().enumerate() {
            let rgba: Vec<[f32; 4]> = page.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
            write_layer(
                ctx,
                &page_tex,
                layer as u32,
                atlas.width,
                atlas.height,
                &rgba,
            );
        }
        let (env_data, env_w, env_h, env) = match environment {
            Some(e) => {
                let map = e.map();
                let r = e.to_world();
                let row = |c: glam::DVec3| [c.x as f32, c.y as f32, c.z as f32, 0.0];
                (
                    map.data.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect(),
                    map.width as u32,
                    map.height as u32,
                    Some((
                        [row(r.x_axis), row(r.y_axis), row(r.z_axis)],
                        e.scale() as f32,
                    )),
                )
            }
            None => (vec![[0.0f32; 4]], 1, 1, None),
        };
        if env_w > max2d || env_h > max2d {
            return Err(invalid(
                "environment",
                format!("a {env_w}×{env_h} map exceeds the device's {max2d}² textures"),
            ));
        }
        let env_tex = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("environment"),
            size: wgpu::Extent3d {
                width: env_w,
                height: env_h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        write_layer(ctx, &env_tex, 0, env_w, env_h, &env_data);
        let out = GpuLightmapScene {
            triangles: storage("light-map triangles", bytemuck::cast_slice(&tris)),
            materials: storage("light-map materials", bytemuck::cast_slice(&mats)),
            texels: storage("base-colour texels", bytemuck::cast_slice(&texels)),
            texture_info: storage("base-colour textures", bytemuck::cast_slice(&info)),
            pages: page_tex,
            environment: env_tex,
            page_size: [atlas.width, atlas.height],
            env,
            count: g.positions.len() as u32,
        };
        scope_result(scope, "uploading the light-mapped scene")?;
        Ok(out)
    }
}

fn write_layer(ctx: &GpuContext, t: &wgpu::Texture, layer: u32, w: u32, h: u32, px: &[[f32; 4]]) {
    ctx.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: t,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer,
            },
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(px),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(w * 16),
            rows_per_image: Some(h),
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
}

/// The compiled shading pass.
#[derive(Debug)]
pub struct LightmapShadePass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl LightmapShadePass {
    /// Compiles `lightmap_shade.wgsl`.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        use crate::bindings::{compute_pipeline, storage_entry, uniform_entry};
        let float = wgpu::TextureSampleType::Float { filterable: false };
        let d2 = wgpu::TextureViewDimension::D2;
        let (pipeline, layout) = compute_pipeline(
            ctx,
            "lightmap_shade.wgsl",
            "compiling lightmap_shade.wgsl",
            lightmap_shade_wgsl(),
            &[
                uniform_entry(0),
                texture_entry(1, wgpu::TextureSampleType::Uint, d2),
                texture_entry(2, float, d2),
                storage_entry(3, true),
                storage_entry(4, true),
                storage_entry(5, true),
                storage_entry(6, true),
                texture_entry(7, float, wgpu::TextureViewDimension::D2Array),
                texture_entry(8, float, d2),
                storage_entry(9, false),
            ],
        )?;
        Ok(LightmapShadePass { pipeline, layout })
    }

    /// Shades the (k·w)×(k·h) `gbuffer` of `scene` seen from `camera` into `out` (w·h RGBA f32
    /// texels; submitted, not waited for).
    pub fn shade(
        &self,
        ctx: &GpuContext,
        scene: &GpuLightmapScene,
        gbuffer: &GBufferTarget,
        camera: &PathCamera,
        k: u32,
        out: &ShadeTarget,
    ) -> Result<()> {
        if k == 0 || gbuffer.width != out.width * k || gbuffer.height != out.height * k {
            return Err(invalid(
                "supersampling",
                format!(
                    "a {}×{} G-buffer is not {k}×{k} times the {}×{} image",
                    gbuffer.width, gbuffer.height, out.width, out.height
                ),
            ));
        }
        self.shade_into(ctx, scene, gbuffer, camera, k, &out.buffer, 0)
    }

    /// Shades the (k·w)×(k·h) `gbuffer` as [`LightmapShadePass::shade`] does, into texels
    /// `offset .. offset + w·h` of the RGBA f32 storage buffer `out` (e.g. one face of a cube
    /// pyramid's base level, or level 0 of a view buffer; submitted, not waited for). Errors:
    /// a G-buffer size not a multiple of k, an output beyond the buffer.
    #[allow(clippy::too_many_arguments)]
    pub fn shade_into(
        &self,
        ctx: &GpuContext,
        scene: &GpuLightmapScene,
        gbuffer: &GBufferTarget,
        camera: &PathCamera,
        k: u32,
        out: &wgpu::Buffer,
        offset: u32,
    ) -> Result<()> {
        if k == 0 || !gbuffer.width.is_multiple_of(k) || !gbuffer.height.is_multiple_of(k) {
            return Err(invalid(
                "supersampling",
                format!(
                    "a {}×{} G-buffer is not {k}×{k} supersampled",
                    gbuffer.width, gbuffer.height
                ),
            ));
        }
        let (w, h) = (gbuffer.width / k, gbuffer.height / k);
        let end = u64::from(offset) + u64::from(w) * u64::from(h);
        if end * 16 > out.size() {
            return Err(invalid(
                "shading output",
                format!(
                    "texels {offset}..{end} of a {w}×{h} image exceed a buffer of {} texels",
                    out.size() / 16
                ),
            ));
        }
        let scope = push_scope(ctx);
        let cam = camera_uniform(camera, gbuffer.width, gbuffer.height, 0.0);
        let mut u: Vec<[u32; 4]> = cam.iter().map(|v| v.map(f32::to_bits)).collect();
        u.push([
            gbuffer.width,
            gbuffer.height,
            k,
            u32::from(scene.env.is_some()),
        ]);
        u.push([scene.page_size[0], scene.page_size[1], offset, 0]);
        let (rows, scale) = scene.env.unwrap_or(([[0.0; 4]; 3], 0.0));
        for r in rows {
            u.push(r.map(f32::to_bits));
        }
        u.push([scale.to_bits(), 0, 0, 0]);
        let uniform = buffer_init(
            ctx,
            "light-map shading uniform",
            bytemuck::cast_slice(&u),
            wgpu::BufferUsages::UNIFORM,
        );
        let view = |t: &wgpu::Texture, dim| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(dim),
                ..Default::default()
            })
        };
        let d2 = wgpu::TextureViewDimension::D2;
        let views = [
            view(&gbuffer.prim, d2),
            view(&gbuffer.bary_depth, d2),
            view(&scene.pages, wgpu::TextureViewDimension::D2Array),
            view(&scene.environment, d2),
        ];
        let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lightmap_shade.wgsl"),
            layout: &self.layout,
            entries: &[
                buffer_entry(0, &uniform),
                tex(1, &views[0]),
                tex(2, &views[1]),
                buffer_entry(3, &scene.triangles),
                buffer_entry(4, &scene.materials),
                buffer_entry(5, &scene.texels),
                buffer_entry(6, &scene.texture_info),
                tex(7, &views[2]),
                tex(8, &views[3]),
                buffer_entry(9, out),
            ],
        });
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("light-map shading"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("light-map shading"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        ctx.queue.submit([enc.finish()]);
        scope_result(scope, "light-map shading")
    }
}

pub(crate) fn tex(binding: u32, v: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(v),
    }
}

/// The HDR output of the shading pass: w·h RGBA f32 texels in a storage buffer.
#[derive(Debug)]
pub struct ShadeTarget {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    buffer: wgpu::Buffer,
    readback: wgpu::Buffer,
}

impl ShadeTarget {
    /// An output of `w`×`h` pixels. Errors: a zero size, a buffer beyond the device's limit.
    pub fn new(ctx: &GpuContext, w: u32, h: u32) -> Result<Self> {
        let bytes = u64::from(w) * u64::from(h) * 16;
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        if w == 0 || h == 0 {
            return Err(invalid("image size", format!("{w}×{h} is empty")));
        }
        if bytes > limit {
            return Err(invalid(
                "image size",
                format!(
                    "{w}×{h} needs a storage buffer of {}, more than this GPU's {}: render a \
                     smaller image",
                    lustre_brdf::budget::bytes(bytes),
                    lustre_brdf::budget::bytes(limit)
                ),
            ));
        }
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("light-map shading output"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("light-map shading readback"),
            size: bytes,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Ok(ShadeTarget {
            width: w,
            height: h,
            buffer,
            readback,
        })
    }

    /// The w·h RGBA f32 texels (the view-dependent pass reads them).
    pub(crate) fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// Copies the image to the host.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<Image> {
        let scope = push_scope(ctx);
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("light-map shading readback"),
            });
        enc.copy_buffer_to_buffer(&self.buffer, 0, &self.readback, 0, self.buffer.size());
        ctx.queue.submit([enc.finish()]);
        let bytes = map_read(ctx, &self.readback, "light-map shading readback", scope)?;
        let px: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        Image::from_data(
            self.width as usize,
            self.height as usize,
            px.iter().map(|p| [p[0], p[1], p[2]]).collect(),
        )
        .map_err(|e| wgpu_error("light-map shading readback", e))
    }
}

/// Both passes, compiled once.
#[derive(Debug)]
pub struct LightmapRenderer {
    /// The raster pass.
    pub gbuffer: GBufferPass,
    /// The shading pass.
    pub shade: LightmapShadePass,
}

/// A scene uploaded for [`LightmapRenderer`]: its triangles and its shading data.
#[derive(Debug)]
pub struct LightmapFrameScene {
    /// The triangles the raster pass draws.
    pub geometry: GpuGeometry,
    /// The shading data.
    pub shading: GpuLightmapScene,
}

impl LightmapFrameScene {
    /// Uploads `scene` with its light maps `pages` of `atlas` (as `bake::assemble` gives them).
    /// Errors (named): an empty scene, pages that do not fit the atlas, a scene with no light
    /// (as `diffuse_path_scene`), materials the GPU cannot shade, device limits.
    pub fn upload(
        ctx: &GpuContext,
        scene: &Scene,
        atlas: &LightmapAtlas,
        pages: &[Vec<[f32; 3]>],
    ) -> Result<Self> {
        let trace_err = |e: lustre_trace::TraceError| invalid("scene", e.to_string());
        let (ps, bases, _) = diffuse_path_scene(scene).map_err(trace_err)?;
        if ps.geometry.positions.is_empty() {
            return Err(invalid(
                "scene",
                format!("{}: the scene has no triangles", scene.source.display()),
            ));
        }
        let lit = Lightmapped::new(scene, atlas, pages, &ps.geometry, bases).map_err(trace_err)?;
        let geometry = GpuGeometry::upload(ctx, scene, &ps.geometry)?;
        let shading = GpuLightmapScene::upload(
            ctx,
            scene,
            atlas,
            pages,
            &lit,
            &ps.geometry,
            ps.environment.as_ref(),
        )?;
        Ok(LightmapFrameScene { geometry, shading })
    }
}

impl LightmapRenderer {
    /// Compiles both passes.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        Ok(LightmapRenderer {
            gbuffer: GBufferPass::new(ctx)?,
            shade: LightmapShadePass::new(ctx)?,
        })
    }

    /// Renders a w×h frame at `camera` with k×k supersampling: the G-buffer at (k·w)×(k·h),
    /// shaded and box-downsampled. Returns the image and the G-buffer (read back).
    pub fn render(
        &self,
        ctx: &GpuContext,
        scene: &LightmapFrameScene,
        camera: &PathCamera,
        w: usize,
        h: usize,
        k: u32,
    ) -> Result<(Image, VisibilityBuffer)> {
        let (gw, gh) = gbuffer_size(w, h, k).map_err(|e| invalid("image size", e.to_string()))?;
        let target = GBufferTarget::new(ctx, gw as u32, gh as u32)?;
        let out = ShadeTarget::new(ctx, w as u32, h as u32)?;
        self.draw(ctx, scene, camera, k, &target, &out)?;
        Ok((out.read_back(ctx)?, target.read_back(ctx)?))
    }

    /// Both passes into existing targets, then waits for the GPU (for timing without readback).
    pub fn draw(
        &self,
        ctx: &GpuContext,
        scene: &LightmapFrameScene,
        camera: &PathCamera,
        k: u32,
        target: &GBufferTarget,
        out: &ShadeTarget,
    ) -> Result<()> {
        self.gbuffer.draw(ctx, &scene.geometry, camera, target)?;
        self.shade
            .shade(ctx, &scene.shading, target, camera, k, out)?;
        ctx.wait()
    }
}

/// This pass as a node of [`crate::passes`].
pub const NODE: crate::passes::Node = crate::passes::Node {
    name: "lightmap_shade",
    shaders: &[("lightmap_shade.wgsl", include_str!("lightmap_shade.wgsl"))],
    inputs: &[
        crate::passes::Resource::GBuffer,
        crate::passes::Resource::Scene,
        crate::passes::Resource::LightMaps,
        crate::passes::Resource::Environment,
    ],
    outputs: &[crate::passes::Resource::LightmappedImage],
};
