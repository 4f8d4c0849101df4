//! The quality harness: the published comparisons as data, and a runner that renders regular,
//! Colbert–Křivánek (CK) and reference images of an evaluation scene and measures them.
//!
//! - [`experiment_002`]: 002 §8 (Fig. 8–10). Specular-only Kurt lobes with the Fresnel and
//!   shadowing terms disabled (r0 = 1, α = 0): mx = my = 0.1 with 14 samples, mx = 0.2 / my = 0.075
//!   with 17 (ξ0 = 0.2, Fig. 8), mx = my = 0.15 with 14 / 30 / 270 samples (ξ0 = 0.2 / 0.1 / 0.01,
//!   Fig. 9–10). The paper's map: 1024² faces with tiny bright spots (2–10°, local ratios up to
//!   1:3000), Gaussian 6×6 MIP pyramid; error = RMS against a > 10,000-sample reference.
//! - [`experiment_000`]: 000 §4.4 Fig. 4.24: glossy metal (n = 15), anisotropic (n = 15), frosted
//!   glass (n = 5 + 5) and varnish (n = 7), integrated with Eq. 4.24 and Eq. 4.25; the thesis
//!   reports PSNR against a converged QMC reference. The thesis does not list the four materials'
//!   parameters: the Kurt parameters below are our choice for those names.
//!
//! The runner ([`run`]) renders, per material, the reference image ([`ReferenceKind`]): by
//! default the exact integral over every level-0 texel ([`truth::TexelTree`]: the evaluation
//! sphere is lit by the distant map only, so this is the answer, with no Monte-Carlo noise; its
//! quadrature error is measured against the full texel sum [`truth::truth`] on a few pixels),
//! and beside it, when `reference_spp ≥ 2`, the Monte-Carlo reference (level 0, BSDF and
//! environment importance sampling combined by MIS, two independent halves whose difference
//! estimates its noise); or the MIS image alone as the reference. Then per sample count the
//! regular images (one per method: 002's printed pattern, reach 1, ours = the row lattice) and
//! a CK image, and measures RMS (linear), PSNR and ΔE (display values) against the reference,
//! the reference's own error over that RMS, the RMS and PSNR against the MIS image, the wall
//! time of each image and the filtered lookups each method actually made per pixel (mean and
//! largest; never more than the budget per lobe). It writes PNGs, false-colour differences
//! (002 Fig. 9 style) and a Markdown table.

use crate::analytic_scene::{AnalyticHit, AnalyticScene, LookAtCamera, Plane, Sphere};
use crate::integrator::{self, FilteredEnvironment, Weighting};
use crate::pattern::ConcentricOptions;
use crate::render::render_with_progress;
use crate::truth;
use crate::{Result, ShadeError};
use glam::DVec3;
use lustre_brdf::models::kurt::{Kurt, KurtLobe};
use lustre_brdf::Rgb;
use lustre_env::{CubeMap, CubePyramid, EnvSampler, MipFilter, SpotMapParams, Sun, SunOptions};
use lustre_trace::image::Image;
use lustre_trace::metrics;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// One sample-count setting of a regular-sampling run: the budget per lobe and the pattern's ξ0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleSetting {
    /// Samples per lobe (the pattern closest to this budget is used; CK takes exactly this many).
    pub samples: usize,
    /// ξ0 of the concentric pattern (002 §5: the innermost circle's offset).
    pub xi0: f64,
}

/// A material of an experiment and the sample counts it is rendered with.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialCase {
    /// Short name (used in file names: letters, digits, '-').
    pub name: String,
    /// What the case reproduces (figure and parameters), for the table.
    pub description: String,
    /// The material.
    pub kurt: Kurt,
    /// Sample counts, each rendered once per weighting and once with CK.
    pub settings: Vec<SampleSetting>,
}

/// Which regular pattern a method uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatternChoice {
    /// 002 §5's concentric pattern, the largest within the budget (`integrator::plan_regular`, with ξ0).
    Concentric,
    /// 000 §4.4.3's centre + ring / linear pattern (`integrator::plan_thesis`; ξ0 unused).
    Thesis,
    /// 002 §5's concentric pattern with the rings stretched so the outermost lies at θmax
    /// (`integrator::plan_regular_with`, `ConcentricOptions { reach: Some(1.0) }`): the printed
    /// radii stop at ≈ θmax/2; this variant is ours.
    ConcentricReach1,
    /// Ours: the per-pixel row lattice (`integrator::plan_lattice`), one lookup per equal-mass
    /// cell at the level of the cell's solid angle; the weighting is its own (the method's
    /// `weighting` is ignored).
    Lattice,
    /// Ours with the map's suns split off ([`lustre_env::split_suns`]): each sun is shaded
    /// exactly as a directional light and counts as one lookup, the lattice reads the residual
    /// map with the rest of the budget (`integrator::plan_lattice_sun`).
    LatticeSun,
}

/// A regular-sampling method: a pattern and a weighting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RegularMethod {
    /// The pattern.
    pub pattern: PatternChoice,
    /// The weighting of the samples.
    pub weighting: Weighting,
}

impl RegularMethod {
    /// The label in the table: "regular (Pdf002)", "thesis (Eq. 4.24)", ...
    pub fn label(&self) -> String {
        let p = match self.pattern {
            PatternChoice::Lattice => return "lattice (ours)".into(),
            PatternChoice::LatticeSun => return "lattice + sun (ours)".into(),
            PatternChoice::Concentric => "regular",
            PatternChoice::Thesis => "thesis",
            PatternChoice::ConcentricReach1 => "regular reach 1",
        };
        let w = match self.weighting {
            Weighting::Pdf002 => "Pdf002",
            Weighting::Thesis424 => "Eq. 4.24",
            Weighting::Thesis425 => "Eq. 4.25",
        };
        format!("{p} ({w})")
    }

    /// The tag in file names: "regular-002", "thesis-425", ...
    pub fn tag(&self) -> String {
        let p = match self.pattern {
            PatternChoice::Lattice => return "lattice".into(),
            PatternChoice::LatticeSun => return "lattice-sun".into(),
            PatternChoice::Concentric => "regular",
            PatternChoice::Thesis => "thesis",
            PatternChoice::ConcentricReach1 => "regular-reach1",
        };
        let w = match self.weighting {
            Weighting::Pdf002 => "002",
            Weighting::Thesis424 => "424",
            Weighting::Thesis425 => "425",
        };
        format!("{p}-{w}")
    }

    /// The material plan of this method; `suns` are the map's suns (used by
    /// [`PatternChoice::LatticeSun`] only).
    pub fn plan(
        &self,
        kurt: &Kurt,
        setting: SampleSetting,
        suns: &[Sun],
    ) -> Result<integrator::MaterialPlan> {
        match self.pattern {
            PatternChoice::Concentric => {
                integrator::plan_regular(kurt, setting.samples, setting.xi0)
            }
            PatternChoice::Thesis => integrator::plan_thesis(kurt, setting.samples),
            PatternChoice::ConcentricReach1 => integrator::plan_regular_with(
                kurt,
                setting.samples,
                setting.xi0,
                ConcentricOptions { reach: Some(1.0) },
            ),
            PatternChoice::Lattice => integrator::plan_lattice(kurt, setting.samples),
            PatternChoice::LatticeSun => integrator::plan_lattice_sun(kurt, setting.samples, suns),
        }
    }

    /// Whether the method shades the map without its suns (plus the suns).
    pub fn splits_suns(&self) -> bool {
        self.pattern == PatternChoice::LatticeSun
    }
}

/// A published comparison as data.
#[derive(Clone, Debug, PartialEq)]
pub struct Experiment {
    /// Identifier ("002", "000").
    pub id: String,
    /// Title for the report.
    pub title: String,
    /// The materials.
    pub materials: Vec<MaterialCase>,
    /// The regular-sampling methods rendered for every setting (CK is always rendered too).
    pub methods: Vec<RegularMethod>,
}

fn specular_only(mx: f64, my: f64) -> Result<Kurt> {
    // 002 §8: Fresnel and shadowing disabled (r0 = 1, α = 0), no diffuse term.
    Ok(Kurt::new(
        Rgb::ZERO,
        vec![KurtLobe::new(Rgb::ONE, mx, my, 1.0, 0.0)?],
        vec![],
    )?)
}

/// 002 §8, Fig. 8–10: the three specular materials and their sample counts (weighting Pdf002).
pub fn experiment_002() -> Result<Experiment> {
    let s = |samples, xi0| SampleSetting { samples, xi0 };
    Ok(Experiment {
        id: "002".into(),
        title: "002 §8 (Fig. 8–10): regular sampling vs Colbert–Křivánek, tiny-spot map".into(),
        materials: vec![
            MaterialCase {
                name: "iso-0.1".into(),
                description: "Fig. 8 top: mx = my = 0.1, r0 = 1, α = 0".into(),
                kurt: specular_only(0.1, 0.1)?,
                settings: vec![s(14, 0.2)],
            },
            MaterialCase {
                name: "aniso-0.2-0.075".into(),
                description: "Fig. 8 bottom: mx = 0.2, my = 0.075, r0 = 1, α = 0".into(),
                kurt: specular_only(0.2, 0.075)?,
                settings: vec![s(17, 0.2)],
            },
            MaterialCase {
                name: "iso-0.15".into(),
                description: "Fig. 9–10: mx = my = 0.15, r0 = 1, α = 0".into(),
                kurt: specular_only(0.15, 0.15)?,
                settings: vec![s(14, 0.2), s(30, 0.1), s(270, 0.01)],
            },
        ],
        methods: vec![
            RegularMethod {
                pattern: PatternChoice::Concentric,
                weighting: Weighting::Pdf002,
            },
            RegularMethod {
                pattern: PatternChoice::ConcentricReach1,
                weighting: Weighting::Pdf002,
            },
            RegularMethod {
                pattern: PatternChoice::Lattice,
                weighting: Weighting::Pdf002,
            },
            RegularMethod {
                pattern: PatternChoice::LatticeSun,
                weighting: Weighting::Pdf002,
            },
        ],
    })
}

/// 000 §4.4, Fig. 4.24: glossy metal, anisotropic, frosted glass and varnish with the thesis'
/// sample counts, the thesis pattern integrated with Eq. 4.24 and Eq. 4.25, and 002's concentric
/// pattern and weighting for comparison.
/// The parameters are ours (the thesis names the materials only).
pub fn experiment_000() -> Result<Experiment> {
    let lobe = KurtLobe::new;
    let s = |samples| SampleSetting { samples, xi0: 0.2 };
    Ok(Experiment {
        id: "000".into(),
        title: "000 §4.4 (Fig. 4.24): Eq. 4.24 vs Eq. 4.25 vs 002 weighting, four materials".into(),
        materials: vec![
            MaterialCase {
                name: "glossy-metal".into(),
                description: "glossy gold-like metal: m = 0.15, r0 = 0.9, n = 15".into(),
                kurt: Kurt::new(
                    Rgb::ZERO,
                    vec![lobe(Rgb::new(0.95, 0.8, 0.55), 0.15, 0.15, 0.9, 0.0)?],
                    vec![],
                )?,
                settings: vec![s(15)],
            },
            MaterialCase {
                name: "anisotropic".into(),
                description: "brushed metal: mx = 0.08, my = 0.3, r0 = 0.9, n = 15".into(),
                kurt: Kurt::new(
                    Rgb::splat(0.02),
                    vec![lobe(Rgb::splat(0.9), 0.08, 0.3, 0.9, 0.0)?],
                    vec![],
                )?,
                settings: vec![s(15)],
            },
            MaterialCase {
                name: "frosted-glass".into(),
                description: "frosted glass: reflection m = 0.08, transmission m = 0.15, r0 = 0.04, n = 5 + 5".into(),
                kurt: Kurt::new(
                    Rgb::ZERO,
                    vec![lobe(Rgb::ONE, 0.08, 0.08, 0.04, 0.0)?],
                    vec![lobe(Rgb::new(0.9, 0.92, 0.95), 0.15, 0.15, 0.04, 0.0)?],
                )?,
                settings: vec![s(5)],
            },
            MaterialCase {
                name: "varnish".into(),
                description: "varnished wood: kd = (0.3, 0.12, 0.05), m = 0.05, r0 = 0.05, n = 7".into(),
                kurt: Kurt::new(
                    Rgb::new(0.3, 0.12, 0.05),
                    vec![lobe(Rgb::ONE, 0.05, 0.05, 0.05, 0.0)?],
                    vec![],
                )?,
                settings: vec![s(7)],
            },
        ],
        methods: vec![
            RegularMethod {
                pattern: PatternChoice::Thesis,
                weighting: Weighting::Thesis424,
            },
            RegularMethod {
                pattern: PatternChoice::Thesis,
                weighting: Weighting::Thesis425,
            },
            RegularMethod {
                pattern: PatternChoice::Concentric,
                weighting: Weighting::Pdf002,
            },
            RegularMethod {
                pattern: PatternChoice::Lattice,
                weighting: Weighting::Pdf002,
            },
            RegularMethod {
                pattern: PatternChoice::LatticeSun,
                weighting: Weighting::Pdf002,
            },
        ],
    })
}

/// The environment of a run, owned: the MIP pyramid and the diffuse irradiance map of the
/// whole map, and the map's suns split off ([`lustre_env::split_suns`], default options) with
/// the pyramid of what is left.
pub struct EnvSetup {
    /// The filtered cube pyramid (specular lookups).
    pub pyramid: CubePyramid,
    /// E(n)/π (diffuse lookups).
    pub irradiance: CubeMap,
    /// The pyramid of the map without its suns (same filter).
    pub residual: CubePyramid,
    /// The suns split off (none on a map without small, very bright sources).
    pub suns: Vec<Sun>,
}

impl EnvSetup {
    /// Builds the pyramid of `base` with `filter`, a `irradiance_size`² irradiance map, and the
    /// residual's pyramid after [`lustre_env::split_suns`].
    pub fn new(base: CubeMap, filter: MipFilter, irradiance_size: usize) -> Result<Self> {
        let split = lustre_env::split_suns(&base, &SunOptions::default())?;
        let pyramid = CubePyramid::build(base, filter)?;
        let irradiance = lustre_env::irradiance_map(&pyramid, irradiance_size)?;
        let residual = CubePyramid::build(split.residual, filter)?;
        Ok(EnvSetup {
            pyramid,
            irradiance,
            residual,
            suns: split.suns,
        })
    }

    /// 002 §8's demanding map: `face_size`² faces with tiny bright spots 2–10° wide, local ratios
    /// up to 1:3000 on a dim background, Gaussian 6×6 pyramid.
    pub fn spots(face_size: usize, seed: u64) -> Result<Self> {
        let base = lustre_env::spot_map(&SpotMapParams {
            size: face_size,
            spots: 48,
            min_deg: 2.0,
            max_deg: 10.0,
            max_ratio: 3000.0,
            background: [0.01, 0.01, 0.01],
            seed,
        })?;
        Self::new(base, MipFilter::Gauss6, 16)
    }

    /// The borrowed view the integrators take.
    pub fn environment(&self) -> FilteredEnvironment<'_> {
        FilteredEnvironment {
            pyramid: &self.pyramid,
            irradiance: &self.irradiance,
        }
    }

    /// The view for methods that shade the suns apart: the residual's pyramid, the whole map's
    /// irradiance (the diffuse term is not split).
    pub fn residual_environment(&self) -> FilteredEnvironment<'_> {
        FilteredEnvironment {
            pyramid: &self.residual,
            irradiance: &self.irradiance,
        }
    }
}

/// A smooth procedural sky for demos and tests: a blue gradient above, a warm ground below, a
/// bright sun and a few coloured patches (so reflections show structure), all finite and ≥ 0.
pub fn procedural_sky(d: DVec3) -> [f64; 3] {
    let d = d.normalize_or_zero();
    let up = d.y;
    let mut c = if up >= 0.0 {
        let t = up.sqrt();
        [0.9 - 0.6 * t, 1.0 - 0.45 * t, 1.1 - 0.1 * t]
    } else {
        let t = (-up).sqrt().min(1.0);
        [0.35 - 0.2 * t, 0.28 - 0.16 * t, 0.2 - 0.12 * t]
    };
    let sun = DVec3::new(0.5, 0.6, -0.62).normalize();
    let cs = d.dot(sun);
    let glow = ((cs - 0.97) / 0.03).max(0.0).powi(2);
    let disc = if cs > 0.9985 { 60.0 } else { 0.0 };
    for (k, v) in c.iter_mut().enumerate() {
        *v += [1.0, 0.9, 0.7][k] * (3.0 * glow + disc);
    }
    // Three soft "windows" near the horizon.
    for (dir, col) in [
        (DVec3::new(-0.8, 0.15, 0.5), [4.0, 3.2, 2.4]),
        (DVec3::new(0.9, 0.1, 0.4), [1.0, 2.0, 4.0]),
        (DVec3::new(0.0, 0.25, 1.0), [3.0, 3.0, 3.0]),
    ] {
        let a = d.dot(dir.normalize());
        if a > 0.985 {
            for (k, v) in c.iter_mut().enumerate() {
                *v += col[k];
            }
        }
    }
    c.map(|v| v.max(0.0))
}

/// The evaluation scene: one unit sphere (tangent axis +y) at the origin filling most of the
/// frame, seen slightly from above, carrying material 0.
pub fn evaluation_scene(material: Kurt) -> AnalyticScene {
    AnalyticScene {
        camera: LookAtCamera {
            eye: DVec3::new(0.0, 0.9, 2.86),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_deg: 44.0,
        },
        spheres: vec![Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
            material: 0,
            axis: DVec3::Y,
        }],
        planes: vec![],
        materials: vec![material],
    }
}

/// The demo scene of `lustre demo`: an anisotropic brushed metal, a frosted (transmissive) glass
/// and a red plastic sphere on a dark glossy floor.
pub fn demo_scene() -> Result<AnalyticScene> {
    let lobe = KurtLobe::new;
    let metal = Kurt::new(
        Rgb::new(0.04, 0.035, 0.03),
        vec![lobe(Rgb::new(0.85, 0.72, 0.5), 0.06, 0.22, 0.85, 0.0)?],
        vec![],
    )?;
    let glass = Kurt::new(
        Rgb::ZERO,
        vec![lobe(Rgb::ONE, 0.08, 0.08, 0.04, 0.0)?],
        vec![lobe(Rgb::new(0.9, 0.92, 0.95), 0.15, 0.15, 0.04, 0.0)?],
    )?;
    let plastic = Kurt::new(
        Rgb::new(0.45, 0.06, 0.05),
        vec![lobe(Rgb::splat(0.5), 0.12, 0.12, 0.05, 0.0)?],
        vec![],
    )?;
    let floor = Kurt::new(
        Rgb::new(0.12, 0.12, 0.13),
        vec![lobe(Rgb::splat(0.6), 0.2, 0.2, 0.04, 0.0)?],
        vec![],
    )?;
    let r = 0.6;
    let sphere = |x: f64, material| Sphere {
        center: DVec3::new(x, r, 0.0),
        radius: r,
        material,
        axis: DVec3::Y,
    };
    Ok(AnalyticScene {
        camera: LookAtCamera {
            eye: DVec3::new(0.0, 1.5, 4.6),
            target: DVec3::new(0.0, 0.45, 0.0),
            up: DVec3::Y,
            fov_y_deg: 38.0,
        },
        spheres: vec![sphere(-1.35, 0), sphere(0.0, 1), sphere(1.35, 2)],
        planes: vec![Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
            tangent: DVec3::X,
            half_size: 4.0,
            material: 3,
        }],
        materials: vec![metal, glass, plastic, floor],
    })
}

/// The background of every render: the pyramid's level 0 (bilinear).
pub fn background<'a>(env: &'a FilteredEnvironment<'a>) -> impl Fn(DVec3) -> Rgb + Sync + 'a {
    move |d| Rgb(env.pyramid.sample(d, 0.0))
}

/// A stable per-pixel seed for the reference integrator.
fn pixel_seed(hit: &AnalyticHit, salt: u64) -> u64 {
    let p = hit.position;
    let mut h = salt ^ 0x9E37_79B9_7F4A_7C15;
    for v in [p.x, p.y, p.z] {
        h = (h ^ v.to_bits())
            .wrapping_mul(0x0100_0000_01B3)
            .rotate_left(29);
    }
    h
}

/// Renders the reference: Monte Carlo on level 0 with `spp` iterations per pixel, BSDF and
/// environment importance sampling combined by MIS ([`integrator::shade_reference_mis`]); the
/// sampler is built from the pyramid ([`integrator::env_sampler`]). A black environment renders
/// black hits (nothing to sample, nothing to see).
pub fn render_reference(
    scene: &AnalyticScene,
    env: &FilteredEnvironment,
    w: usize,
    h: usize,
    spp: usize,
    seed: u64,
    progress: &(dyn Fn(usize) + Sync),
) -> Image {
    match integrator::env_sampler(env.pyramid) {
        Ok(sampler) => render_reference_with(scene, env, &sampler, w, h, spp, seed, progress),
        Err(_) => render_with_progress(scene, w, h, |_| Rgb::ZERO, background(env), progress),
    }
}

/// [`render_reference`] with a prebuilt environment sampler (reused across images).
#[allow(clippy::too_many_arguments)]
pub fn render_reference_with(
    scene: &AnalyticScene,
    env: &FilteredEnvironment,
    sampler: &EnvSampler,
    w: usize,
    h: usize,
    spp: usize,
    seed: u64,
    progress: &(dyn Fn(usize) + Sync),
) -> Image {
    render_with_progress(
        scene,
        w,
        h,
        |hit| {
            let m = &scene.materials[hit.material];
            integrator::shade_reference_mis(
                &hit.frame,
                hit.wo,
                m,
                env,
                sampler,
                lustre_trace::sampling::Strategy::Mis,
                spp,
                pixel_seed(hit, seed),
            )
        },
        background(env),
        progress,
    )
}

/// How the reference image of a run is computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ReferenceKind {
    /// The exact integral over every level-0 texel ([`truth::TexelTree::integrate`] with this
    /// absolute tolerance; the sphere scenes are lit by the distant map only, so this is the
    /// answer). Its own error is measured on `check_pixels` sphere pixels against the full
    /// texel sum ([`truth::truth`]) and reported as the reference row's RMS.
    Exact {
        /// Absolute tolerance per block (radiance units), see [`truth::TexelTree::integrate`].
        tolerance: f64,
        /// Sphere pixels checked against the full texel sum (spread over the image).
        check_pixels: usize,
    },
    /// Monte Carlo with MIS ([`render_reference_with`]), `reference_spp` iterations in two
    /// halves; its RMS row is the noise estimated from the halves.
    Mis,
}

/// Run options.
#[derive(Clone, Debug, PartialEq)]
pub struct HarnessOptions {
    /// Image width and height in pixels (square images).
    pub size: usize,
    /// The reference the methods are measured against.
    pub reference: ReferenceKind,
    /// Samples per pixel of the Monte-Carlo (MIS) reference (002 uses > 10,000). With
    /// [`ReferenceKind::Exact`] the MIS image is rendered too when this is ≥ 2, and reported
    /// beside the exact one (its noise from two halves, its error against the exact answer,
    /// every method's RMS and PSNR against it); 0 skips it.
    pub reference_spp: usize,
    /// Exposure of the PNGs, PSNR and ΔE (display = clamp(exposure · linear), sRGB).
    pub exposure: f64,
    /// |difference| (luminance) mapped to the ends of the false-colour ramp.
    pub diff_range: f64,
    /// Seed of the reference integrator.
    pub seed: u64,
}

impl Default for HarnessOptions {
    /// 160² images, the exact reference (tolerance 1e-6, 32 pixels checked) with a 10,240-sample
    /// MIS reference beside it, exposure 1, ramp ±0.5 (002 Fig. 9).
    fn default() -> Self {
        HarnessOptions {
            size: 160,
            reference: ReferenceKind::Exact {
                tolerance: 1e-6,
                check_pixels: 32,
            },
            reference_spp: 10_240,
            exposure: 1.0,
            diff_range: 0.5,
            seed: 1,
        }
    }
}

/// One measured image.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Experiment id.
    pub experiment: String,
    /// Material name.
    pub material: String,
    /// Samples per lobe (the reference's samples per pixel for the reference row).
    pub samples: usize,
    /// Method: [`RegularMethod::label`], "CK" or "reference".
    pub method: String,
    /// RMS (linear radiance, all channels) against the reference; for the reference row, the
    /// estimated RMS noise of the reference itself.
    pub rms: f64,
    /// PSNR in dB (display values, peak 1) against the reference (infinite for the reference).
    pub psnr: f64,
    /// Mean CIE76 ΔE (display values) against the reference (0 for the reference).
    pub delta_e: f64,
    /// Wall time of the image in seconds.
    pub seconds: f64,
    /// Filtered lookups per shaded (hit) pixel: mean and largest (the MIS reference's level-0
    /// lookups are its samples per pixel, the exact reference's its BSDF evaluations).
    pub lookups: (f64, usize),
    /// The own error of the reference this row is measured against (RMS: the exact
    /// reference's quadrature error on the checked pixels, or the MIS reference's noise), so
    /// that `reference_error / rms` shows whether the reference can judge the row.
    pub reference_error: f64,
    /// RMS and PSNR against the MIS reference when it is rendered beside the exact one (for
    /// the MIS row itself: its noise from the two halves, and no PSNR).
    pub vs_mis: Option<(f64, f64)>,
    /// The PNG written for the image, relative to the output directory (empty without output).
    pub file: String,
}

/// The measurements of a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// One row per image.
    pub rows: Vec<Row>,
    /// Options used.
    pub notes: Vec<String>,
}

impl Report {
    /// The Markdown table (one section per experiment) with the notes.
    pub fn to_markdown(&self) -> String {
        let mut s = String::from("# lustre compare\n\n");
        for n in &self.notes {
            let _ = writeln!(s, "- {n}");
        }
        let mut last = String::new();
        for r in &self.rows {
            if r.experiment != last {
                last = r.experiment.clone();
                let _ = write!(
                    s,
                    "\n## Experiment {last}\n\n| material | n | method | lookups mean / max | RMS | ref. error ÷ RMS | PSNR (dB) | ΔE | time (s) | vs MIS: RMS, PSNR (dB) | image |\n|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---|\n"
                );
            }
            let psnr = if r.psnr.is_finite() {
                format!("{:.2}", r.psnr)
            } else {
                "—".into()
            };
            let ratio = if r.rms > 0.0 && r.method != "reference (exact)" {
                format!("{:.4}", r.reference_error / r.rms)
            } else {
                "—".into()
            };
            let rms = if r.rms > 0.0 && r.rms < 1e-4 {
                format!("{:.1e}", r.rms)
            } else {
                format!("{:.5}", r.rms)
            };
            let mis = match r.vs_mis {
                Some((rms, p)) if p.is_finite() => format!("{rms:.5}, {p:.2}"),
                Some((noise, _)) => format!("noise {noise:.5}"),
                None => "—".into(),
            };
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.1} / {} | {rms} | {ratio} | {} | {:.3} | {:.3} | {mis} | {} |",
                r.material,
                r.samples,
                r.method,
                r.lookups.0,
                r.lookups.1,
                psnr,
                r.delta_e,
                r.seconds,
                r.file
            );
        }
        s
    }

    /// The RMS of `method` for a material and sample count, if measured.
    pub fn rms_of(&self, material: &str, samples: usize, method: &str) -> Option<f64> {
        self.rows
            .iter()
            .find(|r| r.material == material && r.samples == samples && r.method == method)
            .map(|r| r.rms)
    }
}

/// One rendered method image: label, file tag, image, seconds, lookups (mean, max) per pixel.
type Rendered = (String, String, Image, f64, (f64, usize));

/// Lookups counted across the pixels of one image (shaded from several threads).
#[derive(Default)]
struct LookupCount {
    pixels: AtomicUsize,
    total: AtomicUsize,
    max: AtomicUsize,
}

impl LookupCount {
    /// Records one pixel's lookups and passes its colour through.
    fn add(&self, (c, n): (Rgb, usize)) -> Rgb {
        self.pixels.fetch_add(1, Ordering::Relaxed);
        self.total.fetch_add(n, Ordering::Relaxed);
        self.max.fetch_max(n, Ordering::Relaxed);
        c
    }

    /// Mean and largest lookups per shaded pixel.
    fn summary(&self) -> (f64, usize) {
        let p = self.pixels.load(Ordering::Relaxed).max(1);
        (
            self.total.load(Ordering::Relaxed) as f64 / p as f64,
            self.max.load(Ordering::Relaxed),
        )
    }
}

/// What the runner reports while it works: a stage label, rows done and rows in the image.
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// The exact reference's own error: RMS over `count` sphere pixels (spread evenly over the
/// hit pixels of the n×n image) and channels of [`truth::TexelTree::integrate`] at `tolerance`
/// against the full texel sum [`truth::truth`] (with [`truth::supersampling`]). 0 when
/// `count` is 0 or nothing is hit.
fn exact_check(
    scene: &AnalyticScene,
    tree: &truth::TexelTree,
    kurt: &Kurt,
    tolerance: f64,
    n: usize,
    count: usize,
) -> f64 {
    use rayon::prelude::*;
    let hits: Vec<AnalyticHit> = (0..n * n)
        .filter_map(|k| {
            let (o, d) = scene.primary(k % n, k / n, n, n);
            scene.intersect(o, d)
        })
        .collect();
    if count == 0 || hits.is_empty() {
        return 0.0;
    }
    let stride = (hits.len() / count).max(1);
    let picked: Vec<&AnalyticHit> = hits.iter().step_by(stride).take(count).collect();
    let map = tree.map();
    let sq: f64 = picked
        .par_iter()
        .map(|hit| {
            let s = truth::supersampling(kurt, hit.frame.to_local(hit.wo), map.size);
            let t = truth::truth(map, &hit.frame, hit.wo, kurt, s);
            let (a, _) = tree.integrate(&hit.frame, hit.wo, kurt, tolerance);
            (0..3).map(|c| (a[c] - t[c]).powi(2)).sum::<f64>()
        })
        .sum();
    (sq / (3 * picked.len()) as f64).sqrt()
}

/// The suns of `setup` as "elevation E°, spread S°, P % of ∫L dω; …" (elevation above the
/// map's horizon, +y up; P = the sun's share of the whole map's ∫L dω), or "none".
pub fn describe_suns(setup: &EnvSetup) -> String {
    let total: f64 = setup.pyramid.levels[0].integral().iter().sum();
    if setup.suns.is_empty() {
        return "none".into();
    }
    setup
        .suns
        .iter()
        .map(|s| {
            format!(
                "elevation {:.1}°, spread {:.2}°, {:.1} % of ∫L dω",
                s.direction.y.clamp(-1.0, 1.0).asin().to_degrees(),
                s.spread.to_degrees(),
                100.0 * s.irradiance.iter().sum::<f64>() / total.max(1e-300)
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The report's line on the suns split off `setup`'s map (for the `lattice + sun` method).
fn sun_note(setup: &EnvSetup) -> String {
    format!(
        "suns split off ({}; `lattice + sun` shades each as one evaluation of the lobes widened by its spread, `integrator::sun_widened`, and reads the residual map with the rest of its budget): {}",
        SunOptions::default().describe(),
        describe_suns(setup)
    )
}

/// Runs `experiments` on `setup`'s map with `opts`; writes images and `compare.md` into `out`
/// when given (the directory is created). Every image is timed; see the module docs for what is
/// measured. Methods that split the suns off read `setup`'s residual pyramid and its suns.
pub fn run(
    experiments: &[Experiment],
    setup: &EnvSetup,
    opts: &HarnessOptions,
    out: Option<&Path>,
    progress: Progress,
) -> Result<Report> {
    if opts.size == 0 || (opts.reference == ReferenceKind::Mis && opts.reference_spp < 2) {
        return Err(ShadeError::Parameter(format!(
            "harness: size {} must be > 0 and reference_spp {} ≥ 2 for the MIS reference",
            opts.size, opts.reference_spp
        )));
    }
    if let ReferenceKind::Exact { tolerance, .. } = opts.reference {
        if !(tolerance >= 0.0 && tolerance.is_finite()) {
            return Err(ShadeError::Parameter(format!(
                "harness: exact-reference tolerance {tolerance} must be finite and ≥ 0"
            )));
        }
    }
    if !(opts.exposure > 0.0 && opts.exposure.is_finite()) {
        return Err(ShadeError::Parameter(format!(
            "harness: exposure {} must be finite and > 0",
            opts.exposure
        )));
    }
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).map_err(|e| ShadeError::Io {
            path: dir.to_path_buf(),
            source: e,
        })?;
    }
    let n = opts.size;
    let whole = setup.environment();
    let env = &whole;
    let residual = setup.residual_environment();
    let sampler = integrator::env_sampler(env.pyramid)?;
    let tree = match opts.reference {
        ReferenceKind::Exact { .. } => Some(truth::TexelTree::new(&env.pyramid.levels[0])),
        ReferenceKind::Mis => None,
    };
    let mut report = Report {
        rows: vec![],
        notes: vec![
            match opts.reference {
                ReferenceKind::Exact { tolerance, check_pixels } => format!(
                    "{n}×{n} images; reference: the exact integral ∫ L f |cos θi| dω over every level-0 texel (piecewise-constant texels, exact solid angles; `truth::TexelTree`, adaptive block sums, absolute tolerance {tolerance:e} per block); its RMS row is its measured error against the full texel sum (`truth::truth`) on {check_pixels} sphere pixels; lookups of the exact row = BSDF evaluations per pixel{}",
                    if opts.reference_spp >= 2 {
                        format!("; beside it the Monte-Carlo reference (MIS, level 0 bilinear, {} iterations per pixel in two independent halves; its noise = RMS of the halves' difference / 2), and every method's RMS / PSNR against that MIS image", opts.reference_spp)
                    } else {
                        String::new()
                    }
                ),
                ReferenceKind::Mis => format!(
                    "{n}×{n} images; reference: Monte Carlo on MIP level 0, BSDF + environment importance sampling with MIS (power heuristic), {} iterations per pixel (two independent halves; its RMS row is the estimated noise of their mean)",
                    opts.reference_spp
                ),
            },
            "ref. error ÷ RMS: the reference's own error (exact: quadrature error; MIS: noise) over the row's RMS; ≤ 0.1 means the reference can judge the row".to_string(),
            format!(
                "environment: {}² faces, {} MIP levels ({:?} filter); RMS on linear radiance of the whole image; PSNR and ΔE on display values (exposure {}, sRGB, peak 1)",
                env.pyramid.base_size(),
                env.pyramid.levels.len(),
                env.pyramid.filter,
                opts.exposure
            ),
            sun_note(setup),
        ],
    };
    let save = |img: &Image, name: &str| -> Result<String> {
        match out {
            Some(dir) => {
                let file = format!("{name}.png");
                img.write_png(&dir.join(&file), opts.exposure)?;
                Ok(file)
            }
            None => Ok(String::new()),
        }
    };
    for exp in experiments {
        for case in &exp.materials {
            let scene = evaluation_scene(case.kurt.clone());
            scene.validate()?;
            let stem = format!("{}_{}", exp.id, case.name);
            let kurt = &scene.materials[0];
            // The MIS reference in two independent halves (their mean is the reference, their
            // difference estimates its noise: RMS(mean − truth) ≈ RMS(a − b)/2).
            let mis = if opts.reference == ReferenceKind::Mis || opts.reference_spp >= 2 {
                let half = opts.reference_spp / 2;
                let label = format!("{stem} MIS reference");
                let t0 = Instant::now();
                let a = render_reference_with(&scene, env, &sampler, n, n, half, opts.seed, &|r| {
                    progress(&label, r, 2 * n)
                });
                let b = render_reference_with(
                    &scene,
                    env,
                    &sampler,
                    n,
                    n,
                    opts.reference_spp - half,
                    opts.seed.wrapping_add(0x5851_F42D_4C95_7F2D),
                    &|r| progress(&label, n + r, 2 * n),
                );
                let seconds = t0.elapsed().as_secs_f64();
                let noise = metrics::rms(&a, &b)? / 2.0;
                let image = Image {
                    width: n,
                    height: n,
                    data: a
                        .data
                        .iter()
                        .zip(&b.data)
                        .map(|(p, q)| [0, 1, 2].map(|c| 0.5 * (p[c] + q[c])))
                        .collect(),
                };
                Some((image, noise, seconds))
            } else {
                None
            };
            let (reference, reference_error, mis_image) = match (opts.reference, mis) {
                (
                    ReferenceKind::Exact {
                        tolerance,
                        check_pixels,
                    },
                    mis,
                ) => {
                    let tree = tree.as_ref().ok_or_else(|| {
                        ShadeError::Parameter(
                            "harness: no texel tree for the exact reference".into(),
                        )
                    })?;
                    let label = format!("{stem} exact reference");
                    let count = LookupCount::default();
                    let t0 = Instant::now();
                    let exact = render_with_progress(
                        &scene,
                        n,
                        n,
                        |hit| {
                            let (c, st) = tree.integrate(&hit.frame, hit.wo, kurt, tolerance);
                            count.add((c, st.evals))
                        },
                        background(env),
                        &|r| progress(&label, r, n),
                    );
                    let seconds = t0.elapsed().as_secs_f64();
                    let t1 = Instant::now();
                    let error = exact_check(&scene, tree, kurt, tolerance, n, check_pixels);
                    let check_seconds = t1.elapsed().as_secs_f64();
                    let file = save(&exact, &format!("{stem}_reference"))?;
                    report.rows.push(Row {
                        experiment: exp.id.clone(),
                        material: case.name.clone(),
                        samples: 0,
                        method: "reference (exact)".into(),
                        rms: error,
                        psnr: f64::INFINITY,
                        delta_e: 0.0,
                        seconds,
                        lookups: count.summary(),
                        reference_error: error,
                        vs_mis: None,
                        file,
                    });
                    report.notes.push(format!(
                        "{stem}: exact reference {seconds:.1} s; its check against the full texel sum on {check_pixels} sphere pixels took {check_seconds:.1} s"
                    ));
                    let mis_image = match mis {
                        Some((img, noise, seconds)) => {
                            let file = save(&img, &format!("{stem}_reference-mis"))?;
                            report.rows.push(Row {
                                experiment: exp.id.clone(),
                                material: case.name.clone(),
                                samples: opts.reference_spp,
                                method: "reference (MIS)".into(),
                                rms: metrics::rms(&img, &exact)?,
                                psnr: metrics::psnr(&img, &exact, opts.exposure)?,
                                delta_e: metrics::delta_e(&img, &exact, opts.exposure)?,
                                seconds,
                                lookups: (opts.reference_spp as f64, opts.reference_spp),
                                reference_error: error,
                                vs_mis: Some((noise, f64::NAN)),
                                file,
                            });
                            Some(img)
                        }
                        None => None,
                    };
                    (exact, error, mis_image)
                }
                (ReferenceKind::Mis, Some((img, noise, seconds))) => {
                    let file = save(&img, &format!("{stem}_reference"))?;
                    report.rows.push(Row {
                        experiment: exp.id.clone(),
                        material: case.name.clone(),
                        samples: opts.reference_spp,
                        method: "reference (MIS)".into(),
                        rms: noise,
                        psnr: f64::INFINITY,
                        delta_e: 0.0,
                        seconds,
                        lookups: (opts.reference_spp as f64, opts.reference_spp),
                        reference_error: noise,
                        vs_mis: None,
                        file,
                    });
                    (img, noise, None)
                }
                (ReferenceKind::Mis, None) => {
                    return Err(ShadeError::Parameter(
                        "harness: the MIS reference needs reference_spp ≥ 2".into(),
                    ))
                }
            };
            for setting in &case.settings {
                let mut images: Vec<Rendered> = vec![];
                for m in &exp.methods {
                    let plan = m.plan(&case.kurt, *setting, &setup.suns)?;
                    let w = m.weighting;
                    let env = if m.splits_suns() { &residual } else { env };
                    let label = format!("{stem} n={} {}", setting.samples, m.label());
                    let count = LookupCount::default();
                    let t0 = Instant::now();
                    let img = render_with_progress(
                        &scene,
                        n,
                        n,
                        |hit| {
                            count.add(integrator::shade_regular_counted(
                                &hit.frame, hit.wo, &plan, env, w,
                            ))
                        },
                        background(env),
                        &|r| progress(&label, r, n),
                    );
                    let s = t0.elapsed().as_secs_f64();
                    images.push((m.label(), m.tag(), img, s, count.summary()));
                }
                let label = format!("{stem} n={} CK", setting.samples);
                let count = LookupCount::default();
                let t0 = Instant::now();
                let img = render_with_progress(
                    &scene,
                    n,
                    n,
                    |hit| {
                        count.add(integrator::shade_ck_counted(
                            &hit.frame,
                            hit.wo,
                            kurt,
                            setting.samples,
                            env,
                        ))
                    },
                    background(env),
                    &|r| progress(&label, r, n),
                );
                images.push((
                    "CK".into(),
                    "ck".into(),
                    img,
                    t0.elapsed().as_secs_f64(),
                    count.summary(),
                ));
                for (method, tag, img, seconds, lookups) in images {
                    let name = format!("{stem}_n{}_{tag}", setting.samples);
                    let file = save(&img, &name)?;
                    let diff = metrics::false_colour(&img, &reference, opts.diff_range)?;
                    save(&diff, &format!("{name}_diff"))?;
                    report.rows.push(Row {
                        experiment: exp.id.clone(),
                        material: case.name.clone(),
                        samples: setting.samples,
                        method,
                        rms: metrics::rms(&img, &reference)?,
                        psnr: metrics::psnr(&img, &reference, opts.exposure)?,
                        delta_e: metrics::delta_e(&img, &reference, opts.exposure)?,
                        seconds,
                        lookups,
                        reference_error,
                        vs_mis: match &mis_image {
                            Some(m) => Some((
                                metrics::rms(&img, m)?,
                                metrics::psnr(&img, m, opts.exposure)?,
                            )),
                            None => None,
                        },
                        file,
                    });
                }
            }
        }
    }
    if let Some(dir) = out {
        let path = dir.join("compare.md");
        lustre_brdf::error::write_atomic(&path, report.to_markdown().as_bytes())?;
    }
    Ok(report)
}
