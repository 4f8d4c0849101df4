//! A test shader around the binding-free WGSL modules: `body` runs once per invocation after
//! the modules it imports, reading and writing u32 storage arrays, validated by naga first.

use glam::DVec3;
use lustre_brdf::sampling::{uniform_sphere, SplitMix64};
use lustre_gpu::cube::linear_sampler;
use lustre_gpu::wgsl::{compose, Module};
use lustre_gpu::{GpuContext, GpuEnvironment};
use wgpu::naga;
use wgpu::util::DeviceExt;

/// Parses and validates `src` with naga, panicking with the located error.
pub fn validate(src: &str) -> naga::Module {
    let m = match naga::front::wgsl::parse_str(src) {
        Ok(m) => m,
        Err(e) => panic!("{}", e.emit_to_string(src)),
    };
    let mut v = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    );
    if let Err(e) = v.validate(&m) {
        panic!("{}", e.emit_to_string(src));
    }
    m
}

/// Runs `body` (WGSL statements using `i`, `input: array<u32>`, `output: array<u32>` and, with
/// `env`, its pyramid `env_pyramid: texture_cube<f32>` and the trilinear `env_sampler`) once
/// per invocation i < `count` after the modules `imports`, and reads `output` back.
pub fn run_shader(
    ctx: &GpuContext,
    imports: &[&Module],
    body: &str,
    input: &[u32],
    output_words: usize,
    count: u32,
    env: Option<&GpuEnvironment>,
) -> Vec<u32> {
    let env_decl = if env.is_some() {
        "@group(0) @binding(2) var env_pyramid: texture_cube<f32>;\n\
         @group(0) @binding(3) var env_sampler: sampler;\n"
    } else {
        ""
    };
    let pass = format!(
        "@group(0) @binding(0) var<storage, read> input: array<u32>;\n\
         @group(0) @binding(1) var<storage, read_write> output: array<u32>;\n\
         {env_decl}@compute @workgroup_size(64)\n\
         fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{\n\
         let i = gid.x;\n\
         if (i >= {count}u) {{ return; }}\n\
         {body}\n}}\n"
    );
    let src = compose(imports, &pass);
    validate(&src);
    let dev = &ctx.device;
    let scope = dev.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("test shader"),
        source: wgpu::ShaderSource::Wgsl(src.into()),
    });
    let pipeline = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("test shader"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let input_buf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("input"),
        contents: bytemuck::cast_slice(input),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (output_words * 4) as u64;
    let output_buf = dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("output"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let sampler = linear_sampler(ctx);
    let mut entries = vec![
        wgpu::BindGroupEntry {
            binding: 0,
            resource: input_buf.as_entire_binding(),
        },
        wgpu::BindGroupEntry {
            binding: 1,
            resource: output_buf.as_entire_binding(),
        },
    ];
    if let Some(env) = env {
        entries.push(wgpu::BindGroupEntry {
            binding: 2,
            resource: wgpu::BindingResource::TextureView(&env.pyramid.view),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 3,
            resource: wgpu::BindingResource::Sampler(&sampler),
        });
    }
    let bind_group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("test shader"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: None,
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(count.div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&output_buf, 0, &readback, 0, size);
    ctx.queue.submit([enc.finish()]);
    let slice = readback.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.wait().unwrap_or_else(|e| panic!("{e}"));
    if let Some(e) = pollster::block_on(scope.pop()) {
        panic!("test shader: {e}");
    }
    rx.recv()
        .unwrap_or_else(|e| panic!("{e}"))
        .unwrap_or_else(|e| panic!("{e}"));
    let out = bytemuck::cast_slice::<u8, u32>(
        &slice.get_mapped_range().unwrap_or_else(|e| panic!("{e}")),
    )
    .to_vec();
    readback.unmap();
    out
}

/// The f32 the GPU receives, back in f64.
pub fn f32_round(v: DVec3) -> DVec3 {
    DVec3::new(
        f64::from(v.x as f32),
        f64::from(v.y as f32),
        f64::from(v.z as f32),
    )
}

/// Angle between two directions, accurate near 0.
pub fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// A uniformly random direction above the surface (z ≥ 1e-3).
pub fn upper(g: &mut SplitMix64) -> DVec3 {
    let w = uniform_sphere(g.next_f64(), g.next_f64());
    DVec3::new(w.x, w.y, w.z.abs().max(1e-3)).normalize()
}

/// `n` direction pairs (ωi, ωo) above the surface: even ones anywhere, odd ones within a few
/// degrees of the mirror direction (the peak, where θh is small).
pub fn pairs(g: &mut SplitMix64, n: usize) -> Vec<(DVec3, DVec3)> {
    (0..n)
        .map(|k| {
            let wo = upper(g);
            let wi = if k % 2 == 0 {
                upper(g)
            } else {
                let mirror = DVec3::new(-wo.x, -wo.y, wo.z);
                let jitter = uniform_sphere(g.next_f64(), g.next_f64()) * 0.05 * g.next_f64();
                let w = (mirror + jitter).normalize();
                DVec3::new(w.x, w.y, w.z.abs().max(1e-3)).normalize()
            };
            (wi, wo)
        })
        .collect()
}
