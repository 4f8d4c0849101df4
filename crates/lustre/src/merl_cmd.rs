//! `lustre merl`: synthesize MERL tables from neural BRDFs and inspect MERL files.

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use lustre_brdf::frame::{deg, spherical};
use lustre_brdf::measured::merl::{MerlTable, NegativeValues, BINS, CHANNEL_SCALE, FILE_BYTES};
use lustre_brdf::measured::nbrdf::{synthesize_merl, NbrdfSet};
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
    /// Evaluate a neural BRDF at every MERL bin centre and write a 90x90x180 `.binary` table.
    Synth {
        /// The nbrdf-mlp-v1 JSON file (e.g. shared/data/nbrdf/merl_nbrdf.json).
        #[arg(long)]
        nbrdf: PathBuf,
        /// The material name inside that file (see `lustre merl list`).
        #[arg(long)]
        material: String,
        /// Output `.binary` file (written atomically).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Print the dimensions, value ranges and directional albedo of a MERL `.binary` file.
    Info {
        /// The MERL `.binary` file.
        file: PathBuf,
        /// Treat negative values (MERL's mark for unmeasured bins) as missing instead of failing.
        #[arg(long)]
        allow_missing: bool,
    },
    /// List the materials of an nbrdf-mlp-v1 JSON file.
    List {
        /// The nbrdf-mlp-v1 JSON file.
        #[arg(long)]
        nbrdf: PathBuf,
    },
}

/// Runs `lustre merl ...`.
pub fn run(args: &MerlArgs) -> anyhow::Result<()> {
    match &args.command {
        MerlCommand::Synth {
            nbrdf,
            material,
            output,
        } => synth(nbrdf, material, output),
        MerlCommand::Info {
            file,
            allow_missing,
        } => info(file, *allow_missing),
        MerlCommand::List { nbrdf } => {
            use std::io::Write;
            let set = NbrdfSet::read(nbrdf)?;
            // Through a locked handle so that a closed pipe (`| head`) is an error, not a panic.
            let mut out = std::io::stdout().lock();
            writeln!(
                out,
                "{} materials in {} ({})",
                set.len(),
                nbrdf.display(),
                set.dataset()
            )?;
            for name in set.names() {
                writeln!(out, "{name}")?;
            }
            Ok(())
        }
    }
}

fn synth(nbrdf: &Path, material: &str, output: &Path) -> anyhow::Result<()> {
    let set = NbrdfSet::read(nbrdf)?;
    let net = set.material(material)?;
    let bar = ProgressBar::new(BINS as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} bins ({eta})")
            .context("progress bar template")?
            .progress_chars("=> "),
    );
    bar.set_message(format!("synthesizing {material}"));
    let t0 = Instant::now();
    let table = synthesize_merl(&net, |n| bar.inc(n));
    let t_synth = t0.elapsed();
    bar.finish_and_clear();
    let t1 = Instant::now();
    table.write(output)?;
    let t_write = t1.elapsed();
    let v = table.stored_values();
    let max = v.iter().copied().fold(0.0f64, f64::max);
    let zeros = v.iter().filter(|x| **x == 0.0).count();
    println!(
        "{material}: {BINS} bins x 3 channels evaluated in {:.2} s ({:.0} ns/bin on {} threads), \
         written to {} ({FILE_BYTES} bytes) in {:.2} s",
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

fn info(file: &Path, allow_missing: bool) -> anyhow::Result<()> {
    let negative = if allow_missing {
        NegativeValues::Missing
    } else {
        NegativeValues::Reject
    };
    let table = MerlTable::read_with(file, negative)?;
    println!(
        "{}: MERL isotropic table, dims (90, 90, 180), {FILE_BYTES} bytes",
        file.display()
    );
    println!("missing values: {}", table.missing_count());
    let v = table.stored_values();
    for (c, name) in ["red", "green", "blue"].iter().enumerate() {
        let ch = &v[c * BINS..(c + 1) * BINS];
        let (mut lo, mut hi, mut sum) = (f64::INFINITY, 0.0f64, 0.0);
        for &x in ch {
            lo = lo.min(x);
            hi = hi.max(x);
            sum += x;
        }
        let s = CHANNEL_SCALE[c];
        println!(
            "{name:>5}: f_r in [{:.4e}, {:.4e}] /sr, mean over bins {:.4e} (scale {s:.6e})",
            lo * s,
            hi * s,
            sum / BINS as f64 * s
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
