//! The budget check of every command ([`lustre_brdf::budget`]): the per-element sizes of the
//! buffers each job allocates, and the check itself with its notes.
//!
//! Sizes are the bytes each pixel, texel or triangle costs at the job's peak, from the buffers
//! the code allocates at once (named beside each constant); BENCHMARKS.md compares the totals
//! with the measured peaks.

use lustre_brdf::budget::{Budget, Machine};
use lustre_scene::Scene;

/// `lustre reference`, per pixel: the accumulator's two f64 halves (48 B), the image and the
/// two f32 halves written each pass (36 B), the EXR encoder's copies and compressed blocks,
/// the PNG's bytes; measured ≈ 140 B at 2048², counted as 192 B.
pub const REFERENCE_PIXEL: u64 = 192;
/// `lustre reference`, per pixel on disk: OUT.exr, OUT.even.exr, OUT.odd.exr and the two
/// `.next` halves at the moment of a commit (5 × 12 B, uncompressed at worst), the PNG (3 B).
pub const REFERENCE_PIXEL_DISK: u64 = 63;
/// The walkthrough (`lustre render`), per pixel: the frame (f32 RGB), its float and 8-bit
/// conversions for the EXR and PNG, the mirror and see-through buffers; measured ≈ 55 B on
/// the CPU at 2048², counted as 96 B (the GPU's supersampled G-buffer is counted apart).
pub const RENDER_PIXEL: u64 = 96;
/// The GPU's host-side cost: the driver, compiled pipelines, staging buffers. On lavapipe
/// (software Vulkan: its device memory is host memory) the walkthrough of a preview measured
/// ≈ 450 MB at 256²; counted as 512 MB, conservative on a discrete GPU whose buffers live in
/// its own memory.
pub const GPU_DEVICE: u64 = 512 << 20;
/// The GPU walkthrough per G-buffer sample (k² a pixel): the G-buffer, the frame's storage and
/// read-back; measured ≈ 155 B on lavapipe at 1024² with 2×2 samples, counted as 192 B.
pub const GBUFFER_SAMPLE: u64 = 192;
/// `lustre render` on disk per pixel and frame: frame.exr (12 B) and frame.png (3 B).
pub const RENDER_PIXEL_DISK: u64 = 15;
/// The adaptive and brute-force renderers, per G-buffer sample: position, normal, frame,
/// material, bandwidths, the hierarchy's levels and the shaded colour (≈ 120 B), counted as
/// 256 B.
pub const ADAPTIVE_SAMPLE: u64 = 256;
/// `lustre compare`, per texel of a cube face (×6 faces): the base map, its two filtered
/// pyramids (4/3 each) and the sampling tables, f32 RGB; measured ≈ 40 B at 1024² faces,
/// counted as 64 B.
pub const COMPARE_ENV_TEXEL: u64 = 64;
/// `lustre compare`, per pixel: the images of every method and experiment (about a dozen f32
/// RGB images), the references' f64 accumulators and the PNGs; counted as 512 B.
pub const COMPARE_PIXEL: u64 = 512;
/// `lustre demo` on the CPU, per pixel: the regular image and the reference image (12 B
/// each), the PNG conversion (3 B); measured ≈ 24 B at 3840×2160, counted as 40 B.
pub const DEMO_PIXEL_CPU: u64 = 40;
/// `lustre demo` on the GPU, per pixel: as on the CPU, with the frame's storage and read-back
/// buffers (32 B); plus [`DEMO_GPU_DEVICE`].
pub const DEMO_PIXEL_GPU: u64 = 72;
/// `lustre demo`'s GPU host-side cost (one sphere pass, lighter than the walkthrough's
/// [`GPU_DEVICE`]): the whole demo measured 194–221 MB on lavapipe at 1920×1080; counted as 160 MB.
pub const DEMO_GPU_DEVICE: u64 = 160 << 20;
/// `lustre bake --merge` (and an unsharded bake's assembly), per atlas texel: the decoded tile
/// records (68 B), the denoiser's guide and two ping-pong buffers (≈ 60 B), the dilated page
/// (12 B); counted as 160 B.
pub const BAKE_MERGE_TEXEL: u64 = 160;
/// A bake's page EXRs per atlas texel: the irradiance page (f32 RGB, 12 B uncompressed at worst).
pub const BAKE_PAGE_TEXEL_DISK: u64 = 12;
/// A scene in memory per triangle: the mesh (positions, normals, uvs, indices), the path
/// tracer's copy and its BVH; counted as 512 B.
pub const SCENE_TRIANGLE: u64 = 512;
/// `lustre fit`, per input fitted at once: the least counted; an input file counts twice its
/// size (the bytes read and the table as f64 samples with the fit's working arrays: a MERL
/// table of 35 MB peaks at ≈ 60 MB a fit).
pub const FIT_INPUT: u64 = 32 << 20;

/// An environment map, per texel: the decoder's image and the f32 RGB map, the sampling
/// tables and the filtered copies built from it; measured 51 B (`render --env`) and 59 B
/// (`bandwidth --map`) at 8192×4096, counted as 64 B.
pub const ENV_MAP_TEXEL: u64 = 64;

/// Checks the memory of the environment map at `path` from its header, before it is decoded
/// (a 67 MB file may declare 65536×32768 texels: 137 GB decoded).
pub fn map(path: &std::path::Path, option: &str, force: bool) -> anyhow::Result<()> {
    let (w, h) = lustre_env::map_size(path)
        .map_err(|e| anyhow::anyhow!("{option} {}: {e}", path.display()))?;
    let need = Budget::new(
        format!("reading the environment map {} ({w}×{h})", path.display()),
        format!("give {option} a smaller map"),
    )
    .memory("the map", (w as u64) * (h as u64), ENV_MAP_TEXEL);
    check(&need, force)
}

/// The memory of a loaded scene and what the tracer builds on it: triangles, textures and its
/// environment map.
pub fn scene(b: Budget, scene: &Scene) -> Budget {
    let texels: u64 = scene
        .textures
        .iter()
        .map(|t| u64::from(t.width) * u64::from(t.height) * u64::from(t.channels) * 4)
        .sum();
    let env_texels = match scene.environment.as_ref().map(|e| &e.source) {
        Some(lustre_scene::EnvironmentSource::Map { map, .. }) => (map.width * map.height) as u64,
        _ => 0,
    };
    b.memory(
        "scene and BVH",
        scene.triangle_count() as u64,
        SCENE_TRIANGLE,
    )
    .memory("textures", texels, 1)
    .memory("environment map", env_texels, ENV_MAP_TEXEL)
}

/// Parses a byte count: a whole number with an optional K, M, G or T suffix (powers of 1024).
pub fn parse_bytes(s: &str) -> Option<u64> {
    let s = s.trim();
    let (digits, shift) = match s.char_indices().last()? {
        (i, 'K' | 'k') => (&s[..i], 10),
        (i, 'M' | 'm') => (&s[..i], 20),
        (i, 'G' | 'g') => (&s[..i], 30),
        (i, 'T' | 't') => (&s[..i], 40),
        _ => (s, 0),
    };
    digits.trim().parse::<u64>().ok()?.checked_mul(1 << shift)
}

/// This machine as the check sees it: `LUSTRE_MEMORY_LIMIT` and `LUSTRE_DISK_LIMIT` (bytes,
/// or with a K/M/G/T suffix) lower what it offers, e.g. on a workstation shared with others.
fn machine(b: &Budget) -> anyhow::Result<Machine> {
    let mut m = Machine::current(b.output());
    for (var, field) in [
        ("LUSTRE_MEMORY_LIMIT", &mut m.memory),
        ("LUSTRE_DISK_LIMIT", &mut m.disk),
    ] {
        if let Some(v) = std::env::var_os(var) {
            let v = v.to_string_lossy();
            let limit = parse_bytes(&v).ok_or_else(|| {
                anyhow::anyhow!("{var}={v:?}: expected a byte count such as 8G or 500M")
            })?;
            *field = Some(field.map_or(limit, |have| have.min(limit)));
        }
    }
    Ok(m)
}

/// Checks `b` on this machine: prints its notes (a big job's estimate, a forced one's excess),
/// or refuses the job. `LUSTRE_SHOW_BUDGET=1` prints every job's estimate.
pub fn check(b: &Budget, force: bool) -> anyhow::Result<()> {
    for note in b.check_against(&machine(b)?, force)? {
        eprintln!("note: {note}");
    }
    if std::env::var_os("LUSTRE_SHOW_BUDGET").is_some() {
        eprintln!(
            "budget: {} bytes of memory, {} bytes of disk: {}",
            b.memory_bytes(),
            b.disk_bytes(),
            b.summary()
        );
    }
    Ok(())
}

/// Refuses `b` when it is over what this machine offers, and prints nothing otherwise: an early
/// check of part of a job, before work whose own check follows.
pub fn refuse(b: &Budget) -> anyhow::Result<()> {
    b.check_against(&machine(b)?, false)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn byte_counts_parse_with_suffixes() {
        use super::parse_bytes;
        assert_eq!(parse_bytes("512"), Some(512));
        assert_eq!(parse_bytes("8G"), Some(8 << 30));
        assert_eq!(parse_bytes(" 500m "), Some(500 << 20));
        assert_eq!(parse_bytes("1T"), Some(1 << 40));
        assert_eq!(parse_bytes("x"), None);
        assert_eq!(parse_bytes("-1G"), None);
        assert_eq!(parse_bytes("99999999999T"), None);
    }
}
