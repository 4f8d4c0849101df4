//! `lustre merl`: synthesize MERL tables from neural BRDFs and inspect MERL files.

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use lustre_brdf::frame::{deg, spherical};
use lustre_brdf::measured::merl::{
    table_from_bsdf, BinConvention, MerlTable, NegativeValues, BINS, CHANNEL_SCALE, FILE_BYTES,
};
use lustre_brdf::measured::nbrdf::{synthesize_merl_with, NbrdfSet};
use lustre_brdf::numeric::SphereQuadrature;
use lustre_brdf::validate::albedo_quadrature;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `lustre merl`.
#[derive(clap::Args, Debug)]
pub struct MerlArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: MerlCommand,
}

/// The `lustre merl` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum MerlCommand {
    /// Write a 90x90x180 `.binary` table: a neural BRDF (`--material`, from the built-in MERL
    /// set or `--nbrdf FILE`) or any material spec (`--from sgd:NAME`, `--from ggx(...)`)
    /// evaluated at every bin's node (its lower edge, the MERL convention; see `--convention`).
    Synth {
        /// An nbrdf-mlp-v1 JSON file (default: the built-in MERL set).
        #[arg(long)]
        nbrdf: Option<PathBuf>,
        /// The neural BRDF material (see `lustre merl list`).
        #[arg(long, conflicts_with = "from", required_unless_present = "from")]
        material: Option<String>,
        /// Any material spec instead of a neural BRDF, e.g. `sgd:nickel` (see `lustre list`).
        #[arg(long, value_name = "SPEC")]
        from: Option<String>,
        /// Which point of a bin the values stand for (lower-edge: MERL's; centre: for comparison).
        #[arg(long, value_enum, default_value_t = ConventionArg::LowerEdge)]
        convention: ConventionArg,
        /// Output `.binary` file (written atomically).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Print the dimensions, value ranges, unmeasured bins and directional albedo of a MERL
    /// `.binary` file.
    Info {
        /// The MERL `.binary` file.
        file: PathBuf,
        /// Refuse negative values (MERL's mark for unmeasured bins) instead of masking them.
        #[arg(long)]
        strict: bool,
    },
    /// List the materials of an nbrdf-mlp-v1 JSON file (default: the built-in MERL set).
    List {
        /// An nbrdf-mlp-v1 JSON file.
        #[arg(long)]
        nbrdf: Option<PathBuf>,
    },
}

/// The bin convention of `--convention`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ConventionArg {
    /// The bin's lower edge (MERL's convention, the default).
    LowerEdge,
    /// The bin's centre.
    Centre,
}

impl From<ConventionArg> for BinConvention {
    fn from(c: ConventionArg) -> Self {
        match c {
            ConventionArg::LowerEdge => BinConvention::LowerEdge,
            ConventionArg::Centre => BinConvention::Centre,
        }
    }
}

fn nbrdf_set(file: Option<&Path>) -> anyhow::Result<NbrdfSet> {
    Ok(match file {
        Some(f) => NbrdfSet::read(f)?,
        None => lustre_brdf::embedded::merl_nbrdf()?,
    })
}

/// Runs `lustre merl ...`.
pub fn run(args: &MerlArgs) -> anyhow::Result<()> {
    match &args.command {
        MerlCommand::Synth {
            nbrdf,
            material,
            from,
            convention,
            output,
        } => synth(
            nbrdf.as_deref(),
            material.as_deref(),
            from.as_deref(),
            (*convention).into(),
            output,
        ),
        MerlCommand::Info { file, strict } => info(file, *strict),
        MerlCommand::List { nbrdf } => {
            use std::io::Write;
            let set = nbrdf_set(nbrdf.as_deref())?;
            let from = nbrdf
                .as_ref()
                .map_or("the built-in set".to_string(), |f| f.display().to_string());
            // Through a locked handle so that a closed pipe (`| head`) is an error, not a panic.
            let mut out = std::io::stdout().lock();
            writeln!(out, "{} materials in {from} ({})", set.len(), set.dataset())?;
            for name in set.names() {
                writeln!(out, "{name}")?;
            }
            Ok(())
        }
    }
}

fn synth(
    nbrdf: Option<&Path>,
    material: Option<&str>,
    from: Option<&str>,
    convention: BinConvention,
    output: &Path,
) -> anyhow::Result<()> {
    let bar = ProgressBar::new(BINS as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} bins ({eta})")
            .context("progress bar template")?
            .progress_chars("=> "),
    );
    let t0 = Instant::now();
    let (material, table) = match (material, from) {
        (Some(m), _) => {
            let net = nbrdf_set(nbrdf)?.material(m)?;
            bar.set_message(format!("synthesizing {m}"));
            (
                m.to_string(),
                synthesize_merl_with(&net, convention, |n| bar.inc(n)),
            )
        }
        (None, Some(spec)) => {
            if nbrdf.is_some() {
                anyhow::bail!("--nbrdf goes with --material, not with --from");
            }
            let b = lustre_brdf::catalog::resolve(spec)
                .with_context(|| format!("cannot resolve {spec:?}"))?;
            bar.set_message(format!("tabulating {spec}"));
            let name = spec.replace([':', '(', ')', ',', '=', ' '], "_");
            let t = table_from_bsdf(name, b.as_ref(), convention, |n| bar.inc(n))
                .with_context(|| format!("tabulating {spec}"))?;
            (spec.to_string(), t)
        }
        (None, None) => anyhow::bail!("give --material NAME or --from SPEC"),
    };
    let t_synth = t0.elapsed();
    bar.finish_and_clear();
    let t1 = Instant::now();
    table.write(output)?;
    let t_write = t1.elapsed();
    let v = table.stored_values();
    let max = v.iter().copied().fold(0.0f64, f64::max);
    let zeros = v.iter().filter(|x| **x == 0.0).count();
    println!(
        "{material}: {BINS} bins x 3 channels evaluated at bin {}s in {:.2} s ({:.0} ns/bin on {} threads), \
         written to {} ({FILE_BYTES} bytes) in {:.2} s",
        convention.name(),
        t_synth.as_secs_f64(),
        t_synth.as_secs_f64() * 1e9 / BINS as f64,
        rayon::current_num_threads(),
        output.display(),
        t_write.as_secs_f64()
    );
    println!(
        "stored values: max {max:.4e}, {zeros} zeros (clamped by the network) of {}",
        v.len()
    );
    Ok(())
}

fn info(file: &Path, strict: bool) -> anyhow::Result<()> {
    let negative = if strict {
        NegativeValues::Reject
    } else {
        NegativeValues::Missing
    };
    let table = MerlTable::read_with(file, negative)?;
    println!(
        "{}: MERL isotropic table, dims (90, 90, 180), {FILE_BYTES} bytes",
        file.display()
    );
    match table.coverage() {
        Some(c) => println!(
            "unmeasured (negative) values: {} ({} of {BINS} bins), masked: left out of fits and \
             error metrics, interpolated over in evaluation",
            table.missing_count(),
            c.masked_bins()
        ),
        None => println!("unmeasured (negative) values: 0"),
    }
    let v = table.stored_values();
    for (c, name) in ["red", "green", "blue"].iter().enumerate() {
        let ch = &v[c * BINS..(c + 1) * BINS];
        let mask = table.missing_mask().map(|m| &m[c * BINS..(c + 1) * BINS]);
        let (mut lo, mut hi, mut sum, mut n) = (f64::INFINITY, 0.0f64, 0.0, 0usize);
        for (b, &x) in ch.iter().enumerate() {
            if mask.is_some_and(|m| m[b]) {
                continue;
            }
            lo = lo.min(x);
            hi = hi.max(x);
            sum += x;
            n += 1;
        }
        let n = n.max(1);
        let s = CHANNEL_SCALE[c];
        println!(
            "{name:>5}: f_r in [{:.4e}, {:.4e}] /sr, mean over measured bins {:.4e} (scale {s:.6e})",
            lo * s,
            hi * s,
            sum / n as f64 * s
        );
    }
    let q = SphereQuadrature::default();
    println!("directional albedo (quadrature, trilinear):");
    for theta in [0.0, 30.0, 60.0, 80.0] {
        let a = albedo_quadrature(&table, spherical(deg(theta), 0.0), &q);
        println!(
            "  theta_o = {theta:>4.1} deg: ({:.4}, {:.4}, {:.4})",
            a[0], a[1], a[2]
        );
    }
    Ok(())
}
