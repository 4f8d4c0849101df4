//! `lustre bandwidth`: maps of local bandwidth (004 §IV.3.1) — an environment map's angular
//! bandwidth (Fig. IV.6) or a material's BRDF bandwidth table (Fig. IV.8) — as log-scale heat
//! maps, thin over `lustre-freq`.

use anyhow::{bail, Context};
use lustre_brdf::catalog;
use lustre_freq::brdf::{brdf_bandwidth, BrdfBandwidthOptions};
use lustre_freq::environment::angular_bandwidth;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `lustre bandwidth`.
#[derive(clap::Args, Debug)]
pub struct BandwidthArgs {
    /// An equirectangular environment map (.hdr or .exr): its local angular bandwidth in
    /// cycles per radian, one value per pixel (004 Fig. IV.6).
    #[arg(long, value_name = "FILE", conflicts_with = "material")]
    pub map: Option<PathBuf>,
    /// A material specification (see `lustre list`): its angular bandwidth for 16 × 16
    /// incident directions, each a 16 × 16 block of outgoing directions (θ down, φ across;
    /// 004 Fig. IV.8).
    #[arg(long, value_name = "SPEC")]
    pub material: Option<String>,
    /// The heat map to write (PNG).
    #[arg(long, value_name = "FILE.png")]
    pub out: PathBuf,
    /// Read a map larger than the available memory anyway (see "Limits and the budget check").
    #[arg(long)]
    pub force: bool,
}

fn percentile(values: &[f64], p: f64) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p) as usize]
}

/// Runs `lustre bandwidth`.
pub fn run(args: &BandwidthArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let (what, values, width, height) = match (&args.map, &args.material) {
        (Some(path), None) => {
            crate::budget::map(path, "--map", args.force)?;
            let loaded = lustre_env::read_map(path).with_context(|| {
                format!("--map {}: cannot read the environment", path.display())
            })?;
            if let Some(w) = loaded.sanitized_warning(path) {
                eprintln!("warning: {w}");
            }
            let map = loaded.map;
            let b = angular_bandwidth(&map)
                .with_context(|| format!("--map {}: bandwidth", path.display()))?;
            (path.display().to_string(), b, map.width, map.height)
        }
        (None, Some(spec)) => {
            let bsdf = catalog::resolve_with(spec, &catalog::ResolveOptions::default())
                .with_context(|| format!("--material {spec:?}: cannot resolve"))?;
            let o = BrdfBandwidthOptions::default();
            let table = brdf_bandwidth(bsdf.as_ref(), o)
                .with_context(|| format!("--material {spec:?}: bandwidth"))?;
            // Incident cell (θi row, φi column) → a block; its outgoing cells inside.
            let side = o.incident * o.out;
            let mut img = vec![0.0; side * side];
            for (k, v) in table.data.iter().enumerate() {
                let (cell, inner) = (k / (o.out * o.out), k % (o.out * o.out));
                let (ti, pi) = (cell / o.incident, cell % o.incident);
                let (to, po) = (inner / o.out, inner % o.out);
                img[(ti * o.out + to) * side + pi * o.out + po] = *v;
            }
            (bsdf.name(), img, side, side)
        }
        _ => bail!("give one of --map FILE or --material SPEC"),
    };
    let seconds = t0.elapsed().as_secs_f64();
    let scale = lustre_plot::heat_map(&values, width, height, &args.out)
        .with_context(|| format!("--out {}", args.out.display()))?;
    println!(
        "{what}: {width}×{height} values in {seconds:.2} s; angular bandwidth median {:.2}, 99th percentile {:.2}, largest {:.2} cycles per radian; colours from {:.3} to {:.3} (log scale, 0 black)",
        percentile(&values, 0.5),
        percentile(&values, 0.99),
        percentile(&values, 1.0),
        scale.low,
        scale.high
    );
    println!("wrote {}", args.out.display());
    Ok(())
}
