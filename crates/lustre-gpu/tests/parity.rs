//! GPU ↔ CPU parity: the same scene, material plans (002's stored patterns with
//! Weighting::Pdf002, ours, the row lattice of `plan_lattice`, the lattice with several taps
//! in its long cells of `plan_tap_lattice`, and the lattice with two suns shaded exactly of
//! `plan_lattice_sun`) and environment rendered by
//! `lustre_shade::render` with `integrator::shade_regular` in f64 and by the
//! WGSL pass in f32 must agree to PSNR ≥ 45 dB (≥ 90 dB on lavapipe, whose float filtering
//! leaves only f32 rounding). Fails (does not skip) without an adapter. Set
//! `LUSTRE_GPU_PARITY_DUMP=DIR` to write both images as PNG.

use glam::DVec3;
use lustre_brdf::models::kurt::{Kurt, KurtLobe};
use lustre_brdf::Rgb;
use lustre_env::{CubeMap, CubePyramid, MipFilter, Sun};
use lustre_gpu::{GpuContext, GpuRenderer};
use lustre_shade::analytic_scene::{AnalyticScene, LookAtCamera, Plane, Sphere};
use lustre_shade::integrator::{
    plan_lattice, plan_lattice_sun, plan_regular, plan_tap_lattice, shade_regular,
    FilteredEnvironment, MaterialPlan, Weighting,
};
use lustre_shade::render::render;
use lustre_trace::image::Image;
use lustre_trace::metrics::{psnr, rms};

const W: usize = 128;
const H: usize = 96;

fn lobe(ks: [f64; 3], mx: f64, my: f64, r0: f64, alpha: f64) -> KurtLobe {
    KurtLobe::new(Rgb(ks), mx, my, r0, alpha).unwrap_or_else(|e| panic!("{e}"))
}

fn kurt(kd: [f64; 3], reflection: Vec<KurtLobe>, transmission: Vec<KurtLobe>) -> Kurt {
    Kurt::new(Rgb(kd), reflection, transmission).unwrap_or_else(|e| panic!("{e}"))
}

/// Three spheres (isotropic glossy; anisotropic two-lobe; thin glossy transmitter) on a floor
/// square with a rough anisotropic lobe, seen slightly from above.
fn scene() -> AnalyticScene {
    AnalyticScene {
        camera: LookAtCamera {
            eye: DVec3::new(0.3, 1.6, 5.0),
            target: DVec3::new(0.0, 0.6, 0.0),
            up: DVec3::Y,
            fov_y_deg: 45.0,
        },
        spheres: vec![
            Sphere {
                center: DVec3::new(-1.7, 0.8, 0.0),
                radius: 0.8,
                material: 0,
                axis: DVec3::Y,
            },
            Sphere {
                center: DVec3::new(0.0, 0.8, -0.3),
                radius: 0.8,
                material: 1,
                axis: DVec3::new(0.3, 1.0, 0.2).normalize(),
            },
            Sphere {
                center: DVec3::new(1.7, 0.8, 0.0),
                radius: 0.8,
                material: 2,
                axis: DVec3::Y,
            },
        ],
        planes: vec![Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
            tangent: DVec3::new(1.0, 0.0, 0.3),
            half_size: 3.0,
            material: 3,
        }],
        materials: vec![
            kurt(
                [0.1, 0.05, 0.02],
                vec![lobe([0.8, 0.6, 0.3], 0.08, 0.08, 0.6, 0.0)],
                vec![],
            ),
            kurt(
                [0.05, 0.08, 0.1],
                vec![
                    lobe([0.5, 0.5, 0.6], 0.05, 0.25, 0.3, 0.2),
                    lobe([0.2, 0.3, 0.3], 0.3, 0.3, 0.05, 0.0),
                ],
                vec![],
            ),
            kurt(
                [0.02, 0.02, 0.02],
                vec![lobe([0.3, 0.3, 0.3], 0.1, 0.1, 0.04, 0.0)],
                vec![lobe([0.6, 0.7, 0.8], 0.15, 0.15, 0.04, 0.0)],
            ),
            kurt(
                [0.3, 0.3, 0.25],
                vec![lobe([0.3, 0.3, 0.3], 0.4, 0.15, 0.1, 0.5)],
                vec![],
            ),
        ],
    }
}

/// A sky with a horizon gradient, coloured bands and a small bright sun (64² faces, Box2
/// pyramid), and a smooth stand-in irradiance map (the comparison only needs both renderers to
/// read the same one).
fn environment() -> (CubePyramid, CubeMap) {
    let sun = DVec3::new(0.5, 0.6, 0.6).normalize();
    let base = CubeMap::from_fn(64, |d| {
        let sky = 0.2 + 0.6 * d.y.max(0.0);
        let band = 0.5 + 0.5 * (6.0 * d.x.atan2(-d.z)).sin();
        let s = if d.dot(sun) > 0.995 { 8.0 } else { 0.0 };
        [sky + 0.3 * band + s, sky + 0.1 * band + s, 0.8 * sky + s]
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let pyramid = CubePyramid::build(base, MipFilter::Box2).unwrap_or_else(|e| panic!("{e}"));
    let irradiance = CubeMap::from_fn(8, |n| {
        let e = 0.4 + 0.3 * n.y + 0.1 * n.x;
        [e, 0.9 * e, 0.8 * e]
    })
    .unwrap_or_else(|e| panic!("{e}"));
    (pyramid, irradiance)
}

fn cpu_render(scene: &AnalyticScene, plans: &[MaterialPlan], env: &FilteredEnvironment) -> Image {
    render(
        scene,
        W,
        H,
        |hit| {
            shade_regular(
                &hit.frame,
                hit.wo,
                &plans[hit.material],
                env,
                Weighting::Pdf002,
            )
        },
        |d| Rgb(env.pyramid.sample(d, 0.0)),
    )
}

#[test]
fn gpu_render_matches_cpu_shade_regular() {
    let ctx = match GpuContext::new() {
        Ok(c) => c,
        Err(e) => panic!("the parity test needs an adapter (CI installs lavapipe): {e}"),
    };
    let scene = scene();
    let (pyramid, irradiance) = environment();
    // Two suns (as `lustre_env::split_suns` gives them): one high, lighting the spheres' tops
    // and the floor; one low behind the camera, seen through the transmitter from below too.
    let suns = [
        Sun {
            direction: DVec3::new(-0.3, 0.9, -0.3).normalize(),
            irradiance: [3.0, 2.8, 2.4],
            spread: 0.005,
        },
        Sun {
            direction: DVec3::new(0.4, -0.2, 0.9).normalize(),
            irradiance: [1.5, 1.5, 2.0],
            // A 4° source: the lobes are widened by it (`integrator::sun_widened`) on both sides.
            spread: 0.07,
        },
    ];
    // Six, as `split_suns` now gives a map with several lamps (moonless_golf_1k has five):
    // the two above and four dimmer ones near the horizon, one of them below it.
    let six: Vec<Sun> = suns
        .iter()
        .copied()
        .chain(
            [
                (0.9, 0.05, 0.4),
                (-0.8, 0.1, 0.6),
                (0.2, 0.02, -1.0),
                (-0.5, -0.05, -0.9),
            ]
            .map(|(x, y, z)| Sun {
                direction: DVec3::new(x, y, z).normalize(),
                irradiance: [0.6, 0.5, 0.4],
                spread: 0.008,
            }),
        )
        .collect();
    let env = FilteredEnvironment {
        pyramid: &pyramid,
        irradiance: &irradiance,
    };
    for (budget, tag) in [
        (7, "regular"),
        (19, "regular"),
        (7, "lattice"),
        (17, "lattice"),
        (7, "taps"),
        (17, "taps"),
        (7, "sun"),
        (17, "sun"),
        (17, "six-suns"),
    ] {
        let plans: Vec<MaterialPlan> = scene
            .materials
            .iter()
            .map(|k| {
                match tag {
                    "lattice" => plan_lattice(k, budget),
                    "taps" => plan_tap_lattice(k, budget),
                    "sun" => plan_lattice_sun(k, budget, &suns),
                    "six-suns" => plan_lattice_sun(k, budget, &six),
                    _ => plan_regular(k, budget, 0.1),
                }
                .unwrap_or_else(|e| panic!("{e}"))
            })
            .collect();
        let cpu = cpu_render(&scene, &plans, &env);
        let renderer = GpuRenderer::new(&ctx).unwrap_or_else(|e| panic!("{e}"));
        let gpu = renderer
            .render(&scene, &plans, &env, W, H)
            .unwrap_or_else(|e| panic!("{e}"));
        let p = psnr(&cpu, &gpu, 1.0).unwrap_or_else(|e| panic!("{e}"));
        let r = rms(&cpu, &gpu).unwrap_or_else(|e| panic!("{e}"));
        let mean: f64 = cpu
            .data
            .iter()
            .map(|c| f64::from(c[0] + c[1] + c[2]) / 3.0)
            .sum::<f64>()
            / (W * H) as f64;
        eprintln!(
            "{tag} budget {budget}: PSNR {p:.2} dB, linear RMS {r:.2e}, CPU mean {mean:.3} ({})",
            ctx.describe()
        );
        if let Ok(dir) = std::env::var("LUSTRE_GPU_PARITY_DUMP") {
            let dir = std::path::Path::new(&dir);
            cpu.write_png(&dir.join(format!("cpu-{tag}-{budget}.png")), 1.0)
                .unwrap_or_else(|e| panic!("{e}"));
            gpu.write_png(&dir.join(format!("gpu-{tag}-{budget}.png")), 1.0)
                .unwrap_or_else(|e| panic!("{e}"));
        }
        assert!(mean > 0.1, "the CPU image is nearly black (mean {mean})");
        assert!(p >= 45.0, "{tag} budget {budget}: PSNR {p:.2} dB < 45 dB");
        // lavapipe filters Rgba32Float in f32, so there the only differences are f32 rounding
        // (measured ≈ 120 dB; a level formula off by the 1/(ωi·h) factor already gives ≈ 58 dB).
        // Hardware GPUs filter with fixed-point weights and only get the 45 dB bound.
        if ctx.info.device_type == wgpu::DeviceType::Cpu && ctx.float32_filterable {
            assert!(
                p >= 90.0,
                "{tag} budget {budget}: PSNR {p:.2} dB < 90 dB on a CPU adapter"
            );
        }
    }
}
