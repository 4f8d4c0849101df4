//! The lustre command line: thin over the libraries.

mod compare_cmd;
mod demo_cmd;
mod fit_cmd;
mod merl_cmd;
mod plot_cmd;
mod reference_cmd;
mod scene_cmd;

use anyhow::Context;
use clap::{Parser, Subcommand};
use lustre_brdf::{catalog, frame, Bsdf};

/// lustre: BSDF models, measured materials and their plots.
#[derive(Parser)]
#[command(name = "lustre", version, about)]
struct Cli {
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
    /// Scenes: `lustre scene info SCENE` prints what lustre reads from a glTF, OBJ, Mitsuba XML
    /// or lustre scene file.
    Scene(scene_cmd::SceneArgs),
    /// List built-in materials, analytic models with their parameters, and published fits.
    List,
    /// Print a material's flags, albedo and a few values.
    Info {
        /// Material specification (see `lustre list`).
        spec: String,
    },
}

fn main() -> anyhow::Result<()> {
    quiet_vulkan_loader();
    match Cli::parse().command {
        Command::Plot(args) => plot_cmd::run(&args),
        Command::Fit(args) => fit_cmd::run(&args),
        Command::Merl(args) => merl_cmd::run(&args),
        Command::Demo(args) => demo_cmd::run(&args),
        Command::Compare(args) => compare_cmd::run(&args),
        Command::Reference(args) => reference_cmd::run(&args),
        Command::Scene(args) => scene_cmd::run(&args),
        Command::List => {
            println!("built-in materials:");
            for (name, what) in catalog::builtins() {
                println!("  {name:<14} {what}");
            }
            println!("analytic models, as MODEL(key=value, ...):");
            for (name, keys) in catalog::models() {
                println!("  {name:<30} {keys}");
            }
            println!("published MERL fits: sgd:NAME, sgd-numeric:NAME, abc:NAME, lafortune:NAME");
            println!("neural BRDFs: nbrdf:NAME, nbrdf:FILE#NAME; files: .binary .bsdf .dat .gonio");
            Ok(())
        }
        Command::Info { spec } => info(&spec),
    }
}

fn info(spec: &str) -> anyhow::Result<()> {
    let b = catalog::resolve(spec).with_context(|| format!("cannot resolve {spec:?}"))?;
    let flags = b.flags();
    println!("{}", b.name());
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
