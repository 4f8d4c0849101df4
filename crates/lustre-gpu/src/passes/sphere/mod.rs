//! The sphere pass's compute pass, `sphere.wgsl`: ray casting and the regular-sampling integrator, one invocation
//! per pixel, into an Rgba32Float storage texture that is read back row by row.

use crate::bindings::{buffer_entry, buffer_init, compute_pipeline, storage_entry, uniform_entry};
use crate::context::GpuContext;
use crate::cube::{linear_sampler, CubeLevelRef, GpuCube};
use crate::error::{invalid, push_scope, scope_result, wgpu_error, Result};
use crate::packed::{
    f3, PackedScene, LOBE_SCHEME_LATTICE, LOBE_SCHEME_PATTERN, LOBE_SCHEME_TAP_LATTICE,
    MAX_LOBE_LOOKUPS, MAX_TAP_LATTICE_BUDGET,
};
use crate::wgsl::{self, compose};
use bytemuck::{Pod, Zeroable};

/// The pass's own WGSL (`shade.wgsl`): the scene, the bindings and the entry point.
pub const SPHERE_PASS_WGSL: &str = include_str!("sphere.wgsl");

/// The complete WGSL source of the pass: the modules of [`crate::wgsl`] it imports, then
/// `shade.wgsl`.
pub fn sphere_wgsl() -> String {
    compose(&[&wgsl::REGULAR], SPHERE_PASS_WGSL)
}

/// Workgroup edge of the compute shader (`@workgroup_size(8, 8, 1)`).
const WORKGROUP: u32 = 8;

/// The uniform block `Globals` of `shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Globals {
    eye: [f32; 4],
    fwd: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    params: [f32; 4],
    dims: [u32; 4],
}

/// The environment on the GPU: the filtered pyramid (all levels) and the irradiance cube.
#[derive(Debug)]
pub struct GpuEnvironment {
    /// The pyramid, level l of face size max(1, N >> l).
    pub pyramid: GpuCube,
    /// The irradiance map (stores E(n)/π), one level.
    pub irradiance: GpuCube,
}

impl GpuEnvironment {
    /// Uploads the pyramid levels and the irradiance map.
    pub fn from_levels(
        ctx: &GpuContext,
        pyramid: &[CubeLevelRef<'_>],
        irradiance: CubeLevelRef<'_>,
    ) -> Result<Self> {
        Ok(GpuEnvironment {
            pyramid: GpuCube::upload(ctx, "environment pyramid", pyramid)?,
            irradiance: GpuCube::upload(ctx, "irradiance map", &[irradiance])?,
        })
    }
}

/// The scene buffers on the GPU.
#[derive(Debug)]
pub struct GpuScene {
    camera: crate::packed::CameraBasis,
    spheres: u32,
    planes: u32,
    buffers: [wgpu::Buffer; 6],
}

impl GpuScene {
    /// Uploads a packed scene after checking that every index is in range and every value
    /// finite.
    pub fn upload(ctx: &GpuContext, scene: &PackedScene) -> Result<Self> {
        check(scene)?;
        let storage = |label: &str, bytes: &[u8]| {
            // A binding may not be empty: one zero record stands in for an empty array.
            let zeros = [0u8; 64];
            let contents = if bytes.is_empty() { &zeros[..] } else { bytes };
            buffer_init(ctx, label, contents, wgpu::BufferUsages::STORAGE)
        };
        Ok(GpuScene {
            camera: scene.camera,
            spheres: scene.spheres.len() as u32,
            planes: scene.planes.len() as u32,
            buffers: [
                storage("spheres", bytemuck::cast_slice(&scene.spheres)),
                storage("planes", bytemuck::cast_slice(&scene.planes)),
                storage("materials", bytemuck::cast_slice(&scene.materials)),
                storage("lobes", bytemuck::cast_slice(&scene.lobes)),
                storage("samples", bytemuck::cast_slice(&scene.samples)),
                storage("suns", bytemuck::cast_slice(&scene.suns)),
            ],
        })
    }
}

/// Checks indices and finiteness of a packed scene.
fn check(scene: &PackedScene) -> Result<()> {
    if !scene.camera.is_finite() {
        return Err(invalid(
            "camera",
            "degenerate (eye = target or up parallel to the view direction)",
        ));
    }
    let nm = scene.materials.len() as u32;
    let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
    for (i, s) in scene.spheres.iter().enumerate() {
        if s.material >= nm
            || !finite(&s.center)
            || !finite(&s.axis)
            || !s.radius.is_finite()
            || s.radius <= 0.0
        {
            return Err(invalid(
                format!("sphere {i}"),
                format!(
                    "material {} of {nm}, or a non-finite/non-positive value",
                    s.material
                ),
            ));
        }
    }
    for (i, p) in scene.planes.iter().enumerate() {
        if p.material >= nm
            || !finite(&p.point)
            || !finite(&p.normal)
            || !finite(&p.tangent)
            || p.half_size.is_nan()
            || p.half_size <= 0.0
        {
            return Err(invalid(
                format!("plane {i}"),
                format!(
                    "material {} of {nm}, a non-finite value or half_size {} ≤ 0",
                    p.material, p.half_size
                ),
            ));
        }
    }
    for (i, m) in scene.materials.iter().enumerate() {
        let end = m.lobe_start as usize + m.reflection as usize + m.transmission as usize;
        let suns = m.sun_start as usize + m.sun_count as usize;
        if end > scene.lobes.len() || suns > scene.suns.len() || !finite(&m.kd) {
            return Err(invalid(
                format!("material {i}"),
                "lobe or sun range outside its array, or non-finite kd",
            ));
        }
    }
    for (i, s) in scene.suns.iter().enumerate() {
        let valid = finite(&s.direction)
            && finite(&s.irradiance)
            && s.irradiance.iter().all(|v| *v >= 0.0)
            && s.spread.is_finite()
            && s.spread >= 0.0;
        if !valid {
            return Err(invalid(
                format!("sun {i}"),
                "non-finite direction, a non-finite or negative irradiance or spread",
            ));
        }
    }
    for (i, l) in scene.lobes.iter().enumerate() {
        // A row-lattice lobe stores no half vectors: sample_count is its budget.
        let stored = match l.scheme {
            LOBE_SCHEME_PATTERN => l.sample_count as usize,
            LOBE_SCHEME_LATTICE | LOBE_SCHEME_TAP_LATTICE => 0,
            other => {
                return Err(invalid(
                    format!("lobe {i}"),
                    format!("unknown scheme {other}"),
                ))
            }
        };
        let end = l.sample_start as usize + stored;
        let values = [l.mx, l.my, l.r0, l.alpha, l.xi0, l.pdf_constant];
        if end > scene.samples.len() || !finite(&l.ks) || !finite(&values) {
            return Err(invalid(
                format!("lobe {i}"),
                "sample range outside the pattern array or a non-finite parameter",
            ));
        }
        let most = match l.scheme {
            LOBE_SCHEME_TAP_LATTICE => MAX_TAP_LATTICE_BUDGET,
            _ => MAX_LOBE_LOOKUPS,
        };
        if l.sample_count > most {
            return Err(invalid(
                format!("lobe {i}"),
                format!(
                    "{} lookups; the GPU pass takes at most {most} with this scheme \
                     (lavapipe ends longer shader loops silently)",
                    l.sample_count
                ),
            ));
        }
        if l.mx <= 0.0 || l.my <= 0.0 || l.xi0 <= 0.0 || l.xi0 >= 1.0 {
            return Err(invalid(
                format!("lobe {i}"),
                format!(
                    "mx {}, my {} must be > 0 and xi0 {} in (0, 1)",
                    l.mx, l.my, l.xi0
                ),
            ));
        }
    }
    if !scene.samples.iter().all(|s| finite(s)) {
        return Err(invalid("pattern", "non-finite half vector"));
    }
    Ok(())
}

/// A W×H Rgba32Float storage texture and the buffer it is read back through.
#[derive(Debug)]
pub struct RenderTarget {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    readback: wgpu::Buffer,
    padded_row: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl RenderTarget {
    /// Allocates a target of `width`×`height` pixels (both ≥ 1 and within the adapter's 2D limit).
    pub fn new(ctx: &GpuContext, width: usize, height: usize) -> Result<Self> {
        let max = ctx.device.limits().max_texture_dimension_2d as usize;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(invalid(
                "image size",
                format!("{width}×{height} is outside 1..={max} per side"),
            ));
        }
        let (w, h) = (width as u32, height as u32);
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("lustre-gpu target"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let padded_row = (w * 16).div_ceil(align) * align;
        let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lustre-gpu readback"),
            size: u64::from(padded_row) * u64::from(h),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Ok(RenderTarget {
            texture,
            view,
            readback,
            padded_row,
            width: w,
            height: h,
        })
    }

    /// Copies the target to the host: row-major RGB, row 0 at the top.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<Vec<[f32; 3]>> {
        let scope = push_scope(ctx);
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("lustre-gpu readback"),
            });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        ctx.queue.submit([enc.finish()]);
        let slice = self.readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            // The receiver lives until the poll below has returned.
            let _ = tx.send(r);
        });
        ctx.wait()?;
        scope_result(scope, "readback")?;
        rx.recv()
            .map_err(|e| wgpu_error("readback", e))?
            .map_err(|e| wgpu_error("readback", e))?;
        let out = {
            let view = slice
                .get_mapped_range()
                .map_err(|e| wgpu_error("readback", e))?;
            let (w, row) = (self.width as usize, self.padded_row as usize);
            let mut out = Vec::with_capacity(w * self.height as usize);
            for y in 0..self.height as usize {
                let px: &[f32] = bytemuck::cast_slice(&view[y * row..y * row + w * 16]);
                out.extend(px.chunks_exact(4).map(|c| [c[0], c[1], c[2]]));
            }
            out
        };
        self.readback.unmap();
        Ok(out)
    }
}

/// The compiled pass: pipeline, bind group layout and sampler.
#[derive(Debug)]
pub struct GpuRenderer {
    ctx: GpuContext,
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
}

/// Everything bound for one dispatch: scene, environment and target.
#[derive(Debug)]
pub struct SphereBindings {
    bind_group: wgpu::BindGroup,
    width: u32,
    height: u32,
}

impl GpuRenderer {
    /// Compiles `shade.wgsl` on `ctx`'s device.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let cube = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::Cube,
                multisampled: false,
            },
            count: None,
        };
        let (pipeline, layout) = compute_pipeline(
            ctx,
            "shade.wgsl",
            "compiling shade.wgsl",
            &sphere_wgsl(),
            &[
                uniform_entry(0),
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, true),
                storage_entry(4, true),
                storage_entry(5, true),
                storage_entry(10, true),
                cube(6),
                cube(7),
                wgpu::BindGroupLayoutEntry {
                    binding: 8,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 9,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: wgpu::TextureFormat::Rgba32Float,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    count: None,
                },
            ],
        )?;
        Ok(GpuRenderer {
            ctx: ctx.clone(),
            sampler: linear_sampler(ctx),
            pipeline,
            layout,
        })
    }

    /// The context the renderer runs on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// Binds a scene, an environment and a target for [`GpuRenderer::draw`].
    pub fn bind(
        &self,
        scene: &GpuScene,
        env: &GpuEnvironment,
        target: &RenderTarget,
    ) -> Result<SphereBindings> {
        let c = &scene.camera;
        let w4 = |v: glam::DVec3| {
            let a = f3(v);
            [a[0], a[1], a[2], 0.0]
        };
        let globals = Globals {
            eye: w4(c.eye),
            fwd: w4(c.fwd),
            right: w4(c.right),
            up: w4(c.up),
            params: [
                c.a as f32,
                (f64::from(target.width) / f64::from(target.height)) as f32,
                (env.pyramid.levels - 1) as f32,
                env.pyramid.size as f32,
            ],
            dims: [target.width, target.height, scene.spheres, scene.planes],
        };
        let uniform = buffer_init(
            &self.ctx,
            "globals",
            bytemuck::bytes_of(&globals),
            wgpu::BufferUsages::UNIFORM,
        );
        let scope = push_scope(&self.ctx);
        let bind_group = self
            .ctx
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shade.wgsl"),
                layout: &self.layout,
                entries: &[
                    buffer_entry(0, &uniform),
                    buffer_entry(1, &scene.buffers[0]),
                    buffer_entry(2, &scene.buffers[1]),
                    buffer_entry(3, &scene.buffers[2]),
                    buffer_entry(4, &scene.buffers[3]),
                    buffer_entry(5, &scene.buffers[4]),
                    buffer_entry(10, &scene.buffers[5]),
                    wgpu::BindGroupEntry {
                        binding: 6,
                        resource: wgpu::BindingResource::TextureView(&env.pyramid.view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 7,
                        resource: wgpu::BindingResource::TextureView(&env.irradiance.view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 8,
                        resource: wgpu::BindingResource::Sampler(&self.sampler),
                    },
                    wgpu::BindGroupEntry {
                        binding: 9,
                        resource: wgpu::BindingResource::TextureView(&target.view),
                    },
                ],
            });
        scope_result(scope, "binding the frame")?;
        Ok(SphereBindings {
            bind_group,
            width: target.width,
            height: target.height,
        })
    }

    /// Dispatches the pass over the bound target and waits until the GPU has finished.
    pub fn draw(&self, bindings: &SphereBindings) -> Result<()> {
        let scope = push_scope(&self.ctx);
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("shade.wgsl"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("shade.wgsl"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bindings.bind_group, &[]);
            pass.dispatch_workgroups(
                bindings.width.div_ceil(WORKGROUP),
                bindings.height.div_ceil(WORKGROUP),
                1,
            );
        }
        self.ctx.queue.submit([enc.finish()]);
        self.ctx.wait()?;
        scope_result(scope, "shading")
    }

    /// Uploads a packed scene and environment levels, renders `width`×`height` and reads the
    /// pixels back (row-major RGB, row 0 at the top).
    pub fn render_packed(
        &self,
        scene: &PackedScene,
        env: &GpuEnvironment,
        width: usize,
        height: usize,
    ) -> Result<Vec<[f32; 3]>> {
        let gpu_scene = GpuScene::upload(&self.ctx, scene)?;
        let target = RenderTarget::new(&self.ctx, width, height)?;
        let bindings = self.bind(&gpu_scene, env, &target)?;
        self.draw(&bindings)?;
        target.read_back(&self.ctx)
    }
}

/// This pass as a node of [`crate::passes`].
pub const NODE: crate::passes::Node = crate::passes::Node {
    name: "sphere",
    shaders: &[("sphere.wgsl", SPHERE_PASS_WGSL)],
    inputs: &[
        crate::passes::Resource::SphereScene,
        crate::passes::Resource::Pyramid,
    ],
    outputs: &[crate::passes::Resource::SphereImage],
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packed::{GpuKurtMaterial, GpuLobe, GpuPlane, GpuSphere};
    use wgpu::naga;

    fn module() -> naga::Module {
        let src = sphere_wgsl();
        match naga::front::wgsl::parse_str(&src) {
            Ok(m) => m,
            Err(e) => panic!("{}", e.emit_to_string(&src)),
        }
    }

    #[test]
    fn wgsl_parses_and_validates_with_naga() {
        let m = module();
        let mut v = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        );
        if let Err(e) = v.validate(&m) {
            panic!("{}", e.emit_to_string(&sphere_wgsl()));
        }
        assert!(m.entry_points.iter().any(|e| e.name == "main"));
    }

    /// The Rust records have the sizes WGSL gives the structs (storage/uniform layout).
    #[test]
    fn record_layouts_match_wgsl() {
        let m = module();
        let span = |name: &str| {
            m.types
                .iter()
                .find(|(_, t)| t.name.as_deref() == Some(name))
                .map(|(_, t)| match t.inner {
                    naga::TypeInner::Struct { span, .. } => span as usize,
                    _ => panic!("{name} is not a struct"),
                })
                .unwrap_or_else(|| panic!("no struct {name}"))
        };
        assert_eq!(span("Globals"), std::mem::size_of::<Globals>());
        assert_eq!(span("Sphere"), std::mem::size_of::<GpuSphere>());
        assert_eq!(span("Plane"), std::mem::size_of::<GpuPlane>());
        assert_eq!(span("Material"), std::mem::size_of::<GpuKurtMaterial>());
        assert_eq!(span("Lobe"), std::mem::size_of::<GpuLobe>());
    }

    /// Budgets beyond what the pass shades right on lavapipe are refused by name, not
    /// rendered with samples silently dropped.
    #[test]
    fn budgets_beyond_the_loop_limit_are_refused() {
        use lustre_brdf::models::kurt::{Kurt, KurtLobe};
        use lustre_brdf::Rgb;
        use lustre_shade::integrator::{plan_lattice, plan_regular, plan_tap_lattice};
        let lobe = KurtLobe::new(Rgb::splat(0.5), 0.2, 0.075, 0.3, 0.0).expect("lobe");
        let m = Kurt::new(Rgb::splat(0.2), vec![lobe], vec![]).expect("material");
        let scene = |plan| {
            let s = lustre_shade::analytic_scene::AnalyticScene {
                camera: lustre_shade::analytic_scene::LookAtCamera {
                    eye: glam::DVec3::new(0.0, 0.0, 4.0),
                    target: glam::DVec3::ZERO,
                    up: glam::DVec3::Y,
                    fov_y_deg: 40.0,
                },
                spheres: vec![lustre_shade::analytic_scene::Sphere {
                    center: glam::DVec3::ZERO,
                    radius: 1.0,
                    material: 0,
                    axis: glam::DVec3::Y,
                }],
                planes: vec![],
                materials: vec![m.clone()],
            };
            PackedScene::new(&s, &[plan]).expect("packs")
        };
        let tap = MAX_TAP_LATTICE_BUDGET as usize;
        let most = MAX_LOBE_LOOKUPS as usize;
        for (plan, ok) in [
            (plan_tap_lattice(&m, tap), true),
            (plan_tap_lattice(&m, tap + 1), false),
            (plan_lattice(&m, most), true),
            (plan_lattice(&m, most + 1), false),
            (plan_regular(&m, 64, 0.1), true),
            (plan_regular(&m, 4 * most, 0.1), false),
        ] {
            let packed = scene(plan.expect("plan"));
            match check(&packed) {
                Ok(()) => assert!(ok, "{:?} passed", packed.lobes[0].sample_count),
                Err(e) => {
                    assert!(!ok, "{e}");
                    let e = e.to_string();
                    assert!(e.contains("lobe 0") && e.contains("at most"), "{e}");
                }
            }
        }
    }
}
