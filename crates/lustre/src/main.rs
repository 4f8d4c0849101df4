//! The lustre command line: thin over the libraries.

mod adaptive_cmd;
mod bake_cmd;
mod bandwidth_cmd;
mod budget;
mod compare_cmd;
mod demo_cmd;
mod export_cmd;
mod fit_cmd;
mod merl_cmd;
mod output;
mod plot_cmd;
mod publish_cmd;
mod reference_cmd;
mod render_cmd;
mod scene_cmd;
mod score_cmd;
mod shard;

use anyhow::Context;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use lustre_brdf::{catalog, frame, Bsdf};
use std::process::ExitCode;

/// lustre: BSDF models, measured materials and their plots.
#[derive(Parser)]
#[command(name = "lustre", version, about)]
struct Cli {
    /// The data folder for `data:PATH` specs and larger data (sets LUSTRE_DATA). The published
    /// fits and the MERL neural BRDFs are built in and need none.
    #[arg(long, global = true, value_name = "DIR")]
    data: Option<std::path::PathBuf>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Plot material lobes and transfer-probability arrays.
    Plot(plot_cmd::PlotArgs),
    /// Fit Cook-Torrance (SGD, Beckmann, GGX) or Kurt models to measured inputs, in a batch.
    Fit(fit_cmd::FitArgs),
    /// MERL tables: synthesize from a neural BRDF, inspect, list materials.
    Merl(merl_cmd::MerlArgs),
    /// Render the built-in demo scene with regular sampling and print its PSNR.
    Demo(demo_cmd::DemoArgs),
    /// Regular sampling vs Colbert–Křivánek vs reference (002 Fig. 8–10, 000 Fig. 4.24).
    Compare(compare_cmd::CompareArgs),
    /// Path-traced reference of a scene (lustre TOML, glTF, OBJ, Mitsuba XML), resumable.
    Reference(reference_cmd::ReferenceArgs),
    /// A walkthrough frame of a light-mapped scene: light maps, probes with bounding planes,
    /// mirror and see-through buffers, regular sampling of every material, on the GPU or the
    /// CPU, PNG/EXR, stage times, reference comparison.
    Render(render_cmd::RenderArgs),
    /// The interactive walkthrough and material editor: a window on the GPU renderer, walking,
    /// frame times, the material editor with live fitting and lobe plots, camera paths,
    /// screenshots, input scripts.
    View(lustre_view::ViewArgs),
    /// Light maps: atlas, multi-bounce irradiance in resumable tiles, denoised EXR pages and an
    /// updated scene file.
    Bake(bake_cmd::BakeArgs),
    /// Scenes: `lustre scene info SCENE` prints what lustre reads from a glTF, OBJ, Mitsuba XML
    /// or lustre scene file.
    Scene(scene_cmd::SceneArgs),
    /// Error metrics and albedos of any material against any measured input, without fitting.
    Score(score_cmd::ScoreArgs),
    /// Local bandwidth maps (004 Fig. IV.6 and IV.8): an environment map's angular bandwidth or
    /// a material's BRDF bandwidth table, as a log-scale heat map.
    Bandwidth(bandwidth_cmd::BandwidthArgs),
    /// Take results to other tools: a material as glTF 2.0 or Mitsuba 3 (a model fitted to it,
    /// with its error), a baked scene as one glTF 2.0 file with its light maps.
    Export(export_cmd::ExportArgs),
    /// A baked scene as a static web page: index.html, the walkthrough's passes compiled to
    /// WebAssembly on the browser's WebGPU, and the scene with its light maps.
    Publish(publish_cmd::PublishArgs),
    /// List built-in materials, analytic models, published fits, the 100 MERL materials and
    /// where data comes from.
    List,
    /// Print a material's flags, albedo and a few values.
    Info {
        /// Material specification (see `lustre list`).
        spec: String,
        /// Refuse MERL tables with unmeasured (negative) bins instead of masking them.
        #[arg(long)]
        strict: bool,
    },
}

/// Every value-taking argument accepts negative numbers (`--phi-i -30`), in every subcommand.
fn negative_numbers(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|a| {
        if a.get_action().takes_values() {
            a.allow_negative_numbers(true)
        } else {
            a
        }
    })
    .mut_subcommands(negative_numbers)
}

/// Restores the default action of SIGPIPE (Rust ignores it, so every `println!` after the
/// reader left, as in `lustre scene info … | head`, would panic): the process ends quietly, as
/// command-line tools do.
fn default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first in `main`, before any other thread exists; SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn main() -> ExitCode {
    default_sigpipe();
    quiet_vulkan_loader();
    let matches = negative_numbers(Cli::command()).get_matches();
    let result = Cli::from_arg_matches(&matches)
        .map_err(anyhow::Error::from)
        .and_then(run);
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of our output went away (`lustre list | head`): stop quietly, as a
        // program killed by SIGPIPE would.
        Err(e)
            if e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            }) =>
        {
            ExitCode::FAILURE
        }
        Err(e) => {
            // The chain in words; no backtrace for a user's error, even with RUST_BACKTRACE.
            eprintln!("error: {}", error_chain(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by ": ", leaving out a cause whose text the message already
/// holds (an I/O error wrapped with its path would otherwise be printed twice).
fn error_chain(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out
}

fn run(cli: Cli) -> anyhow::Result<()> {
    if let Some(d) = &cli.data {
        if !d.is_dir() {
            anyhow::bail!("--data {}: not a folder", d.display());
        }
        // Before any thread exists (the commands start their pools later).
        std::env::set_var("LUSTRE_DATA", d);
    }
    match cli.command {
        Command::Plot(args) => output::in_folder(&args.out, || plot_cmd::run(&args)),
        Command::Fit(args) => output::in_folder(&args.out, || fit_cmd::run(&args)),
        Command::Merl(args) => merl_cmd::run(&args),
        Command::Demo(args) => demo_cmd::run(&args),
        Command::Compare(args) => output::in_folder(&args.out, || compare_cmd::run(&args)),
        Command::Reference(args) => reference_cmd::run(&args),
        Command::Render(args) => output::in_folder(&args.out, || render_cmd::run(&args)),
        Command::View(args) => lustre_view::run(&args),
        Command::Bake(args) => output::in_folder(&args.out, || bake_cmd::run(&args)),
        Command::Bandwidth(args) => bandwidth_cmd::run(&args),
        Command::Scene(args) => scene_cmd::run(&args),
        Command::Score(args) => score_cmd::run(&args),
        Command::Export(args) => export_cmd::run(&args),
        Command::Publish(args) => output::in_folder(&args.out, || publish_cmd::run(&args)),
        Command::List => list(),
        Command::Info { spec, strict } => info(&spec, strict),
    }
}

fn list() -> anyhow::Result<()> {
    use std::io::Write;
    // Through a locked handle so that a closed pipe (`| head`) is an error, not a panic.
    let mut out = std::io::stdout().lock();
    writeln!(out, "built-in materials:")?;
    for (name, what) in catalog::builtins() {
        writeln!(out, "  {name:<14} {what}")?;
    }
    writeln!(out, "analytic models, as MODEL(key=value, ...):")?;
    for (name, keys) in catalog::models() {
        writeln!(out, "  {name:<30} {keys}")?;
    }
    writeln!(
        out,
        "published MERL fits and neural BRDFs, built into this binary:"
    )?;
    for (spec, source) in lustre_brdf::embedded::sources() {
        writeln!(out, "  {spec:<28} {source}")?;
    }
    let names = lustre_brdf::fits::sgd::list_materials()?;
    writeln!(out, "the {} MERL materials (NAME above):", names.len())?;
    // One column wider than the longest name, so that names never run together.
    let width = names.iter().map(|n| n.len()).max().unwrap_or(0) + 2;
    for row in names.chunks(4) {
        let cells: Vec<String> = row.iter().map(|n| format!("{n:<width$}")).collect();
        writeln!(out, "  {}", cells.join("").trim_end())?;
    }
    writeln!(
        out,
        "files: .binary (MERL; unmeasured bins masked, --strict refuses them), .bsdf (RGL), \
         .dat (ALTA), .gonio, .json (lustre material); nbrdf:FILE#NAME for other network files"
    )?;
    match lustre_brdf::data_dir() {
        Ok(d) => writeln!(
            out,
            "data folder (data:PATH): {} (LUSTRE_DATA)",
            d.display()
        )?,
        Err(e) => writeln!(out, "data folder (data:PATH): none: {e}")?,
    }
    Ok(())
}

fn info(spec: &str, strict: bool) -> anyhow::Result<()> {
    let b = catalog::resolve_with(spec, &catalog::ResolveOptions { strict })
        .with_context(|| format!("cannot resolve {spec:?}"))?;
    let flags = b.flags();
    println!("{}", b.name());
    if spec.trim().to_ascii_lowercase().ends_with(".binary") {
        let t = lustre_brdf::measured::merl::MerlTable::read(spec.trim())?;
        match t.coverage() {
            Some(c) => println!(
                "  unmeasured (negative) values: {} ({} of 1458000 bins), masked",
                t.missing_count(),
                c.masked_bins()
            ),
            None => println!("  unmeasured (negative) values: 0"),
        }
    }
    println!(
        "  reciprocal: {}, energy conserving: {}, transmission: {}, anisotropic: {}",
        flags.reciprocal, flags.energy_conserving, flags.transmission, flags.anisotropic
    );
    println!(
        "  lobes: {:?}{}",
        flags.lobes,
        if flags.has_delta() {
            " (has Dirac lobes: eval/pdf see only the rest)"
        } else {
            ""
        }
    );
    println!("  directional albedo (importance-sampled, 16384 Hammersley points):");
    for deg in [0.0, 30.0, 60.0, 80.0] {
        let wo = frame::spherical(frame::deg(deg), 0.0);
        let a = b.albedo(wo, 16384);
        println!(
            "    θo = {deg:>4}°: ({:.4}, {:.4}, {:.4})",
            a[0], a[1], a[2]
        );
    }
    let wo = frame::spherical(frame::deg(30.0), 0.0);
    let mirror = frame::spherical(frame::deg(30.0), std::f64::consts::PI);
    let v = b.eval(mirror, wo);
    println!(
        "  f at the mirror direction of θ = 30°: ({:.5}, {:.5}, {:.5}) 1/sr",
        v[0], v[1], v[2]
    );
    Ok(())
}

/// The Vulkan loader prints "XDG_RUNTIME_DIR is invalid or not set" on headless machines; give it
/// a private runtime folder when none is set. Runs first, before any thread exists.
fn quiet_vulkan_loader() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir()) {
        return;
    }
    let user = std::env::var("USER").unwrap_or_else(|_| "user".into());
    let dir = std::env::temp_dir().join(format!("lustre-xdg-{user}"));
    #[cfg(unix)]
    let made = {
        use std::os::unix::fs::DirBuilderExt;
        std::fs::DirBuilder::new().mode(0o700).create(&dir).is_ok() || dir.is_dir()
    };
    #[cfg(not(unix))]
    let made = std::fs::create_dir(&dir).is_ok() || dir.is_dir();
    if made {
        std::env::set_var("XDG_RUNTIME_DIR", &dir);
    }
}
