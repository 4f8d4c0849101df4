// module record: the material record every pass that shades a material reads, and the kind and
// flag constants (generated from lustre_gpu::material::kinds::KINDS and the FLAG_* constants of
// lustre_gpu::material, appended below this file's text). CPU twin: lustre_gpu::material::GpuBsdf
// (144 bytes: kind, flags, two pad words, the model's 32 floats in its module's layout).

struct GpuBsdf {
    kind: u32,
    flags: u32,
    pad0: u32,
    pad1: u32,
    p: array<vec4<f32>, 8>,
}
