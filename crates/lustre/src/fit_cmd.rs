//! `lustre fit`: fits SGD / Beckmann / GGX Cook-Torrance or Kurt models to measured inputs in a
//! batch (one material JSON per input, `summary.csv`, resume; see `lustre_fit::batch`), with
//! optional measured-vs-model comparison plots.

use anyhow::{bail, Context, Result};
use clap::Parser;
use lustre_fit::batch::{self, BatchOptions, FitOptions, Fitter, Metric, ModelChoice, SummaryRow};
use std::path::{Path, PathBuf};

/// The model to fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ModelArg {
    /// Cook-Torrance with the shifted gamma distribution (004 §V.4).
    Sgd,
    /// Kurt et al. lobes, reflection and transmission (000 §3.4.1).
    Kurt,
    /// Cook-Torrance with the Beckmann distribution.
    Beckmann,
    /// Cook-Torrance with the GGX distribution.
    Ggx,
}

impl From<ModelArg> for ModelChoice {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Sgd => ModelChoice::Sgd,
            ModelArg::Kurt => ModelChoice::Kurt,
            ModelArg::Beckmann => ModelChoice::Beckmann,
            ModelArg::Ggx => ModelChoice::Ggx,
        }
    }
}

/// The metric of `--metric`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MetricArg {
    /// Ngan's normalized L2 (004 §V.5.3).
    NganL2,
    /// The L1 of transfer probabilities (000 Eq. 3.7).
    L1,
}

/// Arguments of `lustre fit`.
#[derive(Debug, clap::Args)]
pub struct FitArgs {
    /// The model to fit.
    #[arg(long, value_enum, required_unless_present = "merge")]
    pub model: Option<ModelArg>,
    /// Kurt: number of reflection lobes (at most 8).
    #[arg(long, default_value_t = 1)]
    pub lobes: usize,
    /// Kurt: number of transmission lobes (at most 8).
    #[arg(long = "transmission-lobes", default_value_t = 0)]
    pub transmission_lobes: usize,
    /// Kurt: hold a parameter at a value (repeatable), e.g. `--fix alpha1=0`.
    /// Names: kd, kd_r, ks1, ks1_g, mx1, my1, r01, alpha1, kt1, mxt1, ... (lobes numbered from 1).
    #[arg(long = "fix", value_name = "NAME=VALUE", value_parser = parse_fix)]
    pub fix: Vec<(String, f64)>,
    /// Kurt: search a parameter within [LO, HI] (repeatable), e.g. `--range mx1=0.01:0.5`.
    #[arg(long = "range", value_name = "NAME=LO:HI", value_parser = parse_range, allow_hyphen_values = true)]
    pub range: Vec<(String, f64, f64)>,
    /// Skip the refinement (CT: over the full data; Kurt: the final polish).
    #[arg(long = "no-refine")]
    pub no_refine: bool,
    /// Kurt: the metric the fit is judged by. Each fit keeps the best on it of its candidates
    /// (the search's result, the Eq. 3.7 polishes and, with ngan-l2, a polish of Ngan's L2), and
    /// fits with 1..=LOBES lobes are compared on it; the reported fit is the best of them, so
    /// more lobes never report a worse fit.
    #[arg(long, value_enum, default_value_t = MetricArg::NganL2)]
    pub metric: MetricArg,
    /// Refuse MERL tables with unmeasured (negative) bins instead of masking them.
    #[arg(long)]
    pub strict: bool,
    /// Append -TEXT to every output name: keeps fits with other options beside earlier ones.
    /// Letters, digits, `.`, `_`, `-` and `+` only (it is part of a file name).
    #[arg(long, value_name = "TEXT", value_parser = parse_suffix)]
    pub suffix: Option<String>,
    /// Inputs fitted in parallel (1–256).
    #[arg(long, default_value_t = default_jobs(), value_parser = parse_jobs)]
    pub jobs: usize,
    /// Also draw the measured-vs-model plots of `lustre plot` (polar + arrays) per input, into
    /// DIR/plots/NAME/.
    #[arg(long)]
    pub plots: bool,
    /// Fit every input again, even where a valid output exists (also one with other options);
    /// also runs a batch whose memory estimate exceeds what the machine has.
    #[arg(long)]
    pub force: bool,
    /// Output folder: NAME.json per input and summary.csv (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    #[command(flatten)]
    pub shard: crate::shard::ShardArgs,
    /// Assemble the shards of a batch (`--shard K/N` runs) into --out: checks that all N are
    /// there, copies the fits of shards run into other folders (given as INPUTs) and writes
    /// summary.csv as one unsharded run would.
    #[arg(long, conflicts_with_all = ["shard", "shard_count", "model", "plots", "force"])]
    pub merge: bool,
    /// Measured inputs: .binary (MERL), .bsdf (RGL), .gonio, .dat, nbrdf:NAME, nbrdf:FILE#NAME,
    /// nbrdf:FILE#* (every material of a network file). With --merge: the shards' output
    /// folders, when they are not --out.
    #[arg(value_name = "INPUT", required_unless_present = "merge")]
    pub inputs: Vec<String>,
}

fn default_jobs() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Parses a thread count ≥ 1.
fn parse_jobs(s: &str) -> std::result::Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=MAX_JOBS).contains(&n) => Ok(n),
        _ => Err(format!(
            "{s:?}: expected a whole number from 1 to {MAX_JOBS}"
        )),
    }
}

/// The most inputs fitted at once (`--jobs`).
const MAX_JOBS: usize = 256;

/// Parses `NAME=VALUE` with a finite value.
fn parse_fix(s: &str) -> std::result::Result<(String, f64), String> {
    let (name, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, found {s:?}"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(format!("{s:?}: empty parameter name"));
    }
    let v: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("{s:?}: the value of {name} is not a number"))?;
    if !v.is_finite() {
        return Err(format!("{s:?}: the value of {name} is not finite"));
    }
    Ok((name.to_string(), v))
}

/// Parses `NAME=LO:HI` with finite LO < HI.
fn parse_range(s: &str) -> std::result::Result<(String, f64, f64), String> {
    let (name, r) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=LO:HI, found {s:?}"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(format!("{s:?}: empty parameter name"));
    }
    let (lo, hi) = r
        .split_once(':')
        .ok_or_else(|| format!("{s:?}: expected LO:HI after {name}="))?;
    let num = |x: &str| -> std::result::Result<f64, String> {
        let v: f64 = x
            .trim()
            .parse()
            .map_err(|_| format!("{s:?}: {x:?} is not a number"))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(format!("{s:?}: {x:?} is not finite"))
        }
    };
    let (lo, hi) = (num(lo)?, num(hi)?);
    if lo >= hi {
        return Err(format!(
            "{s:?}: the range of {name} is empty (LO must be < HI)"
        ));
    }
    Ok((name.to_string(), lo, hi))
}

impl FitArgs {
    /// The batch options, after the checks that do not depend on the inputs.
    pub fn batch_options(&self) -> Result<BatchOptions> {
        let Some(model) = self.model else {
            bail!("--model is required");
        };
        let model = ModelChoice::from(model);
        if model != ModelChoice::Kurt {
            if !self.fix.is_empty() || !self.range.is_empty() {
                bail!("--fix and --range apply to --model kurt only");
            }
            if self.lobes != 1 || self.transmission_lobes != 0 {
                bail!("--lobes and --transmission-lobes apply to --model kurt only");
            }
            if self.metric != MetricArg::NganL2 {
                bail!("--metric applies to --model kurt only (Cook-Torrance fits minimize Ngan's weighted L2)");
            }
        }
        let fit = FitOptions {
            model,
            lobes: self.lobes,
            transmission_lobes: self.transmission_lobes,
            fixed: self.fix.clone(),
            ranges: self.range.clone(),
            refine: !self.no_refine,
            metric: match self.metric {
                MetricArg::NganL2 => Metric::NganL2,
                MetricArg::L1 => Metric::L1,
            },
            strict: self.strict,
        };
        batch::check_options(&fit)?;
        Ok(BatchOptions {
            fit,
            jobs: self.jobs,
            force: self.force,
            out: self.out.clone(),
            progress: true,
            suffix: self.suffix.clone().unwrap_or_default(),
            shard: self.shard.resolve()?,
        })
    }
}

/// Runs `lustre fit` with the measured-data fitter.
pub fn run(args: &FitArgs) -> Result<()> {
    run_with(args, &batch::MeasuredFitter)
}

/// Runs `lustre fit` with `fitter`: the batch, a line per input, the plots; an error when any
/// input (or plot) failed, after everything else is done.
pub fn run_with(args: &FitArgs, fitter: &dyn Fitter) -> Result<()> {
    if args.merge {
        return merge(args);
    }
    let opts = args.batch_options()?;
    // The inputs fitted at once, each its table and working arrays (2× its file).
    let largest = args
        .inputs
        .iter()
        .filter_map(|i| std::fs::metadata(i).ok())
        .map(|m| m.len().saturating_mul(2))
        .max()
        .unwrap_or(0)
        .max(crate::budget::FIT_INPUT);
    let at_once = args.jobs.min(args.inputs.len().max(1)) as u64;
    let need = lustre_brdf::budget::Budget::new(
        format!(
            "lustre fit of {} input(s), {at_once} at once",
            args.inputs.len()
        ),
        "lower --jobs",
    )
    .memory("inputs being fitted", at_once, largest);
    crate::budget::check(&need, args.force)?;
    let summary = batch::run(&args.inputs, &opts, fitter)
        .with_context(|| format!("fitting into {}", args.out.display()))?;
    for r in summary.batch_rows() {
        println!("{}", row_line(r));
    }
    if let Some((k, n)) = opts.shard {
        println!(
            "shard {k}/{n}: {} inputs: {} fitted, {} resumed, {} failed; {} written (when all {n} \
             shards are done: lustre fit --merge --out {})",
            summary.batch,
            summary.fitted(),
            summary.resumed(),
            summary.failed(),
            summary.summary_path.display(),
            args.out.display()
        );
        // A failed input is a row of the merged summary; the merge reports it.
        return Ok(());
    }
    let mut plot_failures = 0;
    if args.plots {
        for r in summary.batch_rows().iter().filter(|r| !r.failed()) {
            if let Err(e) = plot_row(&args.out, r) {
                eprintln!("warning: no plots for {}: {e:#}", r.input);
                plot_failures += 1;
            }
        }
    }
    let n = summary.batch;
    let earlier = summary.earlier_rows().len();
    println!(
        "{}: {n} inputs: {} fitted, {} resumed, {} failed{}",
        summary.summary_path.display(),
        summary.fitted(),
        summary.resumed(),
        summary.failed(),
        if earlier > 0 {
            format!(" (the summary also lists {earlier} earlier fits in the folder)")
        } else {
            String::new()
        }
    );
    if summary.failed() > 0 {
        bail!(
            "{} of {n} inputs failed (see {})",
            summary.failed(),
            summary.summary_path.display()
        );
    }
    if plot_failures > 0 {
        bail!("the plots of {plot_failures} inputs failed");
    }
    Ok(())
}

/// `lustre fit --merge`: the shards into one folder and its summary.
fn merge(args: &FitArgs) -> Result<()> {
    let from: Vec<PathBuf> = args.inputs.iter().map(PathBuf::from).collect();
    let summary = batch::merge(&args.out, &from)
        .with_context(|| format!("merging shards into {}", args.out.display()))?;
    println!(
        "{}: {} inputs merged: {} with a fit, {} failed",
        summary.summary_path.display(),
        summary.batch,
        summary.batch - summary.failed(),
        summary.failed()
    );
    if summary.failed() > 0 {
        bail!(
            "{} of {} inputs failed (see {})",
            summary.failed(),
            summary.batch,
            summary.summary_path.display()
        );
    }
    Ok(())
}

/// One line per input: name, status, Ngan L2 per channel, time, message.
fn row_line(r: &SummaryRow) -> String {
    let num = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
    let mut s = format!(
        "{:<28} {:<13} ngan-l2 ({}, {}, {}) {:>7.2}s",
        r.name,
        batch::status_str(r.status),
        num(r.ngan_l2_r),
        num(r.ngan_l2_g),
        num(r.ngan_l2_b),
        r.time_s
    );
    if r.resumed {
        s.push_str(" (resumed)");
    }
    if !r.message.is_empty() {
        s.push_str(&format!(" {}", r.message));
    }
    s
}

/// `lustre plot INPUT --compare OUT/NAME.json --cube-root --out OUT/plots/NAME`;
/// skipped for a resumed input whose plot folder is not empty.
fn plot_row(out: &Path, r: &SummaryRow) -> Result<()> {
    let dir = out.join("plots").join(&r.name);
    let has_files = std::fs::read_dir(&dir).is_ok_and(|mut d| d.next().is_some());
    if r.resumed && has_files {
        return Ok(());
    }
    #[derive(Parser)]
    struct PlotCli {
        #[command(flatten)]
        args: crate::plot_cmd::PlotArgs,
    }
    let json = out.join(format!("{}.json", r.name));
    let cli = PlotCli::try_parse_from([
        "plot".as_ref(),
        "--out".as_ref(),
        dir.as_os_str(),
        "--compare".as_ref(),
        json.as_os_str(),
        // Narrow measured lobes and their diffuse floor on one readable scale (004 Fig. V.11).
        "--cube-root".as_ref(),
        "--".as_ref(),
        r.input.as_ref(),
    ])
    .context("plot arguments")?;
    crate::plot_cmd::run(&cli.args)
}

/// Parses `--suffix`: a part of a file name (no folder separator, which would drop the input's
/// name from the output's).
fn parse_suffix(s: &str) -> std::result::Result<String, String> {
    let ok = |c: char| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-' | '+');
    if s.is_empty() || !s.chars().all(ok) || s.chars().all(|c| c == '.') {
        return Err(format!(
            "{s:?}: a suffix is part of a file name: letters, digits, '.', '_', '-' and '+' only"
        ));
    }
    Ok(s.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: FitArgs,
    }

    fn parse(args: &[&str]) -> std::result::Result<FitArgs, String> {
        Cli::try_parse_from(std::iter::once("fit").chain(args.iter().copied()))
            .map(|c| c.args)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn fix_and_range_values_are_checked() {
        assert_eq!(parse_fix("alpha=0"), Ok(("alpha".into(), 0.0)));
        assert_eq!(parse_range(" mx = 0.01:0.5"), Ok(("mx".into(), 0.01, 0.5)));
        assert_eq!(parse_range("r0=-1:1"), Ok(("r0".into(), -1.0, 1.0)));
        for bad in ["alpha", "=1", "alpha=x", "alpha=nan", "alpha=inf"] {
            assert!(parse_fix(bad).is_err(), "{bad}");
        }
        for bad in [
            "mx",
            "mx=0.1",
            "mx=0.5:0.1",
            "mx=0.1:0.1",
            "mx=a:1",
            "=0:1",
            "mx=0:inf",
        ] {
            assert!(parse_range(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn command_lines_map_to_batch_options() {
        let a = parse(&[
            "--model",
            "kurt",
            "--lobes",
            "2",
            "--transmission-lobes",
            "1",
            "--fix",
            "alpha1=0",
            "--range",
            "mx1=0.01:0.5",
            "--no-refine",
            "--jobs",
            "3",
            "--force",
            "--out",
            "o",
            "a.gonio",
            "b.binary",
        ])
        .expect("parses");
        assert_eq!(a.inputs, ["a.gonio", "b.binary"]);
        let o = a.batch_options().expect("valid");
        assert_eq!(o.fit.model, ModelChoice::Kurt);
        assert_eq!((o.fit.lobes, o.fit.transmission_lobes), (2, 1));
        assert_eq!(o.fit.fixed, [("alpha1".to_string(), 0.0)]);
        assert_eq!(o.fit.ranges, [("mx1".to_string(), 0.01, 0.5)]);
        assert!(!o.fit.refine && o.force && o.jobs == 3);
        let o = parse(&["--model", "ggx", "--out", "o", "x.binary"])
            .expect("parses")
            .batch_options()
            .expect("valid");
        assert!(o.fit.refine && !o.force && o.jobs >= 1);
        // Errors: no input, no --out, unknown model, zero jobs, Kurt options on a CT model.
        assert!(parse(&["--model", "ggx", "--out", "o"]).is_err());
        assert!(parse(&["--model", "ggx", "x.binary"]).is_err());
        assert!(parse(&["--model", "phong", "--out", "o", "x"]).is_err());
        assert!(parse(&["--model", "ggx", "--jobs", "0", "--out", "o", "x"]).is_err());
        let e = parse(&["--model", "sgd", "--fix", "alpha1=0", "--out", "o", "x"])
            .expect("parses")
            .batch_options()
            .unwrap_err();
        assert!(e.to_string().contains("kurt only"), "{e}");
        assert!(
            parse(&["--model", "beckmann", "--lobes", "2", "--out", "o", "x"])
                .expect("parses")
                .batch_options()
                .is_err()
        );
    }
}
