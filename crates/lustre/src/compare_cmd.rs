//! `lustre compare`: reproduces 002 Fig. 8–10 (regular sampling vs Colbert–Křivánek on a
//! tiny-spot map) and 000 Fig. 4.24 (Eq. 4.24 vs Eq. 4.25) as images and a Markdown table, with
//! our row lattice beside 002's printed method and the filtered lookups every method made per
//! pixel (each within its per-lobe budget).

use anyhow::{bail, Context};
use indicatif::{ProgressBar, ProgressStyle};
use lustre_env::{CubeMap, MipFilter};
use lustre_shade::harness::{self, EnvSetup, HarnessOptions, ReferenceKind};
use std::path::PathBuf;
use std::sync::Mutex;

/// Arguments of `lustre compare`.
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// Which comparison: `002` (paper Fig. 8–10), `000` (thesis Fig. 4.24) or `all`.
    #[arg(long, default_value = "all")]
    pub experiment: String,
    /// Image width and height in pixels.
    #[arg(long, default_value_t = 160)]
    pub size: usize,
    /// The reference: `exact` (the integral over every level-0 texel: the spheres are lit by
    /// the distant map only) or `mis` (Monte Carlo, BSDF + environment sampling with MIS).
    #[arg(long, default_value = "exact")]
    pub reference: String,
    /// Absolute tolerance per block of the exact reference (radiance units).
    #[arg(long, default_value_t = 1e-6)]
    pub tolerance: f64,
    /// Sphere pixels on which the exact reference is checked against the full texel sum.
    #[arg(long, default_value_t = 32)]
    pub check_pixels: usize,
    /// Samples per pixel of the MIS reference (002 compares against > 10,000); with
    /// `--reference exact` it is rendered beside the exact one (its noise and error reported),
    /// 0 skips it.
    #[arg(long, default_value_t = 10_240)]
    pub reference_spp: usize,
    /// Environment: `spots` (002's tiny bright spots on a dim background) or an .hdr/.exr
    /// equirectangular map.
    #[arg(long, default_value = "spots")]
    pub map: String,
    /// Cube-face size of the environment (002 uses 1024).
    #[arg(long, default_value_t = 1024)]
    pub face_size: usize,
    /// Exposure of the PNGs and of PSNR / ΔE.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f64,
    /// Seed of the spot map and the reference integrator.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory (images and compare.md).
    #[arg(long)]
    pub out: PathBuf,
    /// Run even when the job's memory or disk estimate exceeds what the machine has.
    #[arg(long)]
    pub force: bool,
}

/// Runs `lustre compare`.
pub fn run(args: &CompareArgs) -> anyhow::Result<()> {
    let experiments = match args.experiment.as_str() {
        "002" => vec![harness::experiment_002()?],
        "000" => vec![harness::experiment_000()?],
        "all" => vec![harness::experiment_002()?, harness::experiment_000()?],
        other => bail!("--experiment {other:?}: expected 002, 000 or all"),
    };
    if args.face_size == 0 {
        bail!("--face-size must be > 0");
    }
    if args.size == 0 {
        bail!("--size must be > 0");
    }
    if args.reference_spp > 1 << 24 || args.check_pixels > 1 << 20 {
        bail!(
            "--reference-spp {} and --check-pixels {}: at most {} and {}",
            args.reference_spp,
            args.check_pixels,
            1 << 24,
            1 << 20
        );
    }
    let (face, size) = (args.face_size as u64, args.size as u64);
    let need = lustre_brdf::budget::Budget::new(
        format!("lustre compare at {size}×{size} with {face}×{face} cube faces"),
        "lower --size or --face-size",
    )
    .memory(
        "environment (map, pyramids, sampling)",
        face.saturating_mul(face).saturating_mul(6),
        crate::budget::COMPARE_ENV_TEXEL,
    )
    .memory(
        "images",
        size.saturating_mul(size),
        crate::budget::COMPARE_PIXEL,
    )
    .disk(&args.out, "PNGs", size.saturating_mul(size), 64);
    crate::budget::check(&need, args.force)?;
    let env = if args.map == "spots" {
        eprintln!(
            "environment: tiny-spot map, {0}×{0} faces, Gaussian 6×6 pyramid",
            args.face_size
        );
        EnvSetup::spots(args.face_size, args.seed).context("building the spot map")?
    } else {
        let path = PathBuf::from(&args.map);
        crate::budget::map(&path, "--map", args.force)?;
        let loaded = lustre_env::read_map(&path)
            .with_context(|| format!("--map {}: cannot read the environment", path.display()))?;
        if let Some(w) = loaded.sanitized_warning(&path) {
            eprintln!("warning: {w}");
        }
        let base = CubeMap::from_equirect(&loaded.map, args.face_size)
            .with_context(|| format!("--map {}: cube-map conversion", path.display()))?;
        EnvSetup::new(base, MipFilter::Gauss6, 16).context("filtering the environment")?
    };
    let reference = match args.reference.as_str() {
        "exact" => {
            if !(args.tolerance >= 0.0 && args.tolerance.is_finite()) {
                bail!("--tolerance {}: must be finite and ≥ 0", args.tolerance);
            }
            ReferenceKind::Exact {
                tolerance: args.tolerance,
                check_pixels: args.check_pixels,
            }
        }
        "mis" => {
            if args.reference_spp < 2 {
                bail!("--reference mis needs --reference-spp ≥ 2");
            }
            ReferenceKind::Mis
        }
        other => bail!("--reference {other:?}: expected exact or mis"),
    };
    if args.reference_spp > 0 && args.reference_spp < 10_000 {
        eprintln!(
            "note: --reference-spp {} is below the > 10,000 samples per pixel of 002 §8",
            args.reference_spp
        );
    }
    let opts = HarnessOptions {
        size: args.size,
        reference,
        reference_spp: args.reference_spp,
        exposure: args.exposure,
        seed: args.seed,
        ..HarnessOptions::default()
    };
    let bar = ProgressBar::new(1);
    bar.set_style(
        ProgressStyle::with_template("{msg:40} [{bar:30}] {pos}/{len} rows, {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let stage = Mutex::new(String::new());
    let report = harness::run(
        &experiments,
        &env,
        &opts,
        Some(&args.out),
        &|label, done, total| {
            if let Ok(mut s) = stage.lock() {
                if *s != label {
                    *s = label.to_string();
                    bar.set_message(label.to_string());
                    bar.set_length(total as u64);
                    bar.set_position(0);
                }
            }
            bar.set_position((done as u64).max(bar.position()));
        },
    )
    .with_context(|| format!("comparison into {}", args.out.display()))?;
    bar.finish_and_clear();
    println!("{}", report.to_markdown());
    println!("wrote {}", args.out.join("compare.md").display());
    Ok(())
}
