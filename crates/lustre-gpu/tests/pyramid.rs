//! GPU ↔ CPU parity of the cube-map pyramid (`pyramid.wgsl` vs `CubePyramid::build`): every
//! level of a real environment map (a small sun near a face corner, where the seams and the
//! corner averages matter most) for each filter, and a non-power-of-two base. The GPU sums in
//! f32, the CPU in f64: every level must agree to ≥ 90 dB (peak = the level's brightest
//! texel) and to 1e-4 relative in its integral. Fails (does not skip) without an adapter.

use lustre_env::{read_map, shared_data_dir, CubeMap, CubePyramid, MipFilter};
use lustre_gpu::{GpuContext, GpuPyramidBuilder};

fn ctx() -> GpuContext {
    GpuContext::new().unwrap_or_else(|e| panic!("{e}"))
}

/// (PSNR in dB against the level's peak, relative difference of the integrals) per level.
fn compare(cpu: &CubePyramid, gpu: &CubePyramid) -> Vec<(usize, f64, f64)> {
    assert_eq!(cpu.levels.len(), gpu.levels.len());
    cpu.levels
        .iter()
        .zip(&gpu.levels)
        .map(|(a, b)| {
            assert_eq!(a.size, b.size);
            let (mut se, mut peak, mut n) = (0.0f64, 0.0f64, 0usize);
            for (fa, fb) in a.faces.iter().zip(&b.faces) {
                for (x, y) in fa.iter().zip(fb) {
                    for c in 0..3 {
                        se += (f64::from(x[c]) - f64::from(y[c])).powi(2);
                        peak = peak.max(f64::from(x[c]));
                        n += 1;
                    }
                }
            }
            let rms = (se / n as f64).sqrt();
            let psnr = if rms > 0.0 {
                20.0 * (peak / rms).log10()
            } else {
                f64::INFINITY
            };
            let (ia, ib) = (a.integral(), b.integral());
            let rel = (0..3)
                .map(|c| ((ia[c] - ib[c]) / ia[c].max(1e-30)).abs())
                .fold(0.0, f64::max);
            (a.size, psnr, rel)
        })
        .collect()
}

#[test]
fn gpu_pyramid_matches_the_cpu_pyramid() {
    let ctx = ctx();
    let builder = GpuPyramidBuilder::new(&ctx).unwrap_or_else(|e| panic!("{e}"));
    let path = shared_data_dir().join("envmaps/quarry_01_1k.hdr");
    let map = read_map(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .map;
    for (size, filter) in [
        (128, MipFilter::Gauss6),
        (128, MipFilter::Gauss4),
        (128, MipFilter::Box2),
        (48, MipFilter::Gauss6),
    ] {
        let base = CubeMap::from_equirect(&map, size).unwrap_or_else(|e| panic!("{e}"));
        let cpu = CubePyramid::build(base.clone(), filter).unwrap_or_else(|e| panic!("{e}"));
        let gpu = builder
            .build(&ctx, &base, filter)
            .and_then(|p| p.read_back(&ctx))
            .unwrap_or_else(|e| panic!("{e}"));
        for (n, psnr, rel) in compare(&cpu, &gpu) {
            eprintln!("{size}² {filter:?}: level {n}²: {psnr:.1} dB, integral {rel:.2e}");
            assert!(psnr >= 90.0, "{size}² {filter:?} level {n}²: {psnr:.1} dB");
            assert!(
                rel <= 1e-4,
                "{size}² {filter:?} level {n}²: integral off by {rel:e}"
            );
        }
    }
}

#[test]
fn a_bright_texel_at_a_face_corner_spreads_over_all_three_faces() {
    // One bright texel in the corner of +X where +X, +Y and −Z meet: its energy must reach
    // the same corner of the two other faces at the next level, as on the CPU.
    let ctx = ctx();
    let builder = GpuPyramidBuilder::new(&ctx).unwrap_or_else(|e| panic!("{e}"));
    let n = 16;
    let mut faces: [Vec<[f32; 3]>; 6] = std::array::from_fn(|_| vec![[0.1; 3]; n * n]);
    faces[0][0] = [1000.0; 3];
    let base = CubeMap::new(n, faces).unwrap_or_else(|e| panic!("{e}"));
    let cpu = CubePyramid::build(base.clone(), MipFilter::Gauss6).unwrap_or_else(|e| panic!("{e}"));
    let gpu = builder
        .build(&ctx, &base, MipFilter::Gauss6)
        .and_then(|p| p.read_back(&ctx))
        .unwrap_or_else(|e| panic!("{e}"));
    let lit: Vec<usize> = (0..6)
        .filter(|&f| gpu.levels[1].faces[f].iter().any(|v| v[0] > 1.0))
        .collect();
    assert_eq!(lit.len(), 3, "faces lit at level 1: {lit:?}");
    for (n, psnr, rel) in compare(&cpu, &gpu) {
        assert!(
            psnr >= 90.0 && rel <= 1e-4,
            "level {n}²: {psnr:.1} dB, {rel:e}"
        );
    }
}
