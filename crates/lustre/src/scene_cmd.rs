//! `lustre scene info SCENE`: what a scene file holds, as lustre reads it.

use anyhow::Context;
use clap::{Args, Subcommand};
use lustre_scene::{EnvironmentSource, Scene};
use std::path::PathBuf;

/// Scenes: glTF, OBJ, Mitsuba XML or a lustre scene file (.toml).
#[derive(Args)]
pub struct SceneArgs {
    #[command(subcommand)]
    command: SceneCommand,
}

#[derive(Subcommand)]
enum SceneCommand {
    /// Print counts (meshes, triangles, materials, textures, emitters, cameras), the film, the
    /// environment, the load time and every warning.
    Info {
        /// The scene (.gltf, .glb, .obj, .xml or .toml).
        scene: PathBuf,
    },
}

pub fn run(args: &SceneArgs) -> anyhow::Result<()> {
    match &args.command {
        SceneCommand::Info { scene } => info(scene),
    }
}

fn info(path: &std::path::Path) -> anyhow::Result<()> {
    let t = std::time::Instant::now();
    let s = Scene::load(path).with_context(|| format!("cannot load {}", path.display()))?;
    let secs = t.elapsed().as_secs_f64();
    println!("{} (loaded in {secs:.3} s)", path.display());
    println!(
        "  meshes {}, triangles {} ({} degenerate dropped), vertices {}",
        s.meshes.len(),
        s.triangle_count(),
        s.stats.degenerate_triangles,
        s.meshes.iter().map(|m| m.positions.len()).sum::<usize>()
    );
    println!("  materials {}:", s.materials.len());
    for (i, m) in s.materials.iter().enumerate() {
        let users = s.meshes.iter().filter(|x| x.material == i).count();
        println!(
            "    {:<20} {:<15} {}{}meshes {users}",
            m.name,
            m.kind.name(),
            if m.two_sided { "two-sided, " } else { "" },
            if m.alpha_mask.is_some() {
                "masked, "
            } else {
                ""
            },
        );
    }
    println!("  textures {}:", s.textures.len());
    for t in &s.textures {
        println!(
            "    {} ({}×{}, {} channels, {:?})",
            t.source.display(),
            t.width,
            t.height,
            t.channels,
            t.color_space
        );
    }
    let emitters = s.emitters();
    let power: f64 = emitters
        .iter()
        .map(|&i| s.meshes[i].emission.map_or(0.0, |e| e.luminance()) * s.meshes[i].area())
        .sum();
    println!(
        "  emitters {} (Σ luminance × area = {power:.4})",
        emitters.len()
    );
    match &s.environment {
        None => println!("  environment: none"),
        Some(e) => {
            let what = match &e.source {
                EnvironmentSource::Map { path, map } => {
                    format!("map {} ({}×{})", path.display(), map.width, map.height)
                }
                EnvironmentSource::Constant(c) => format!("constant {:?}", c.0),
                EnvironmentSource::Sky(_) => "built-in sky".to_string(),
            };
            println!("  environment: {what}, intensity {}", e.intensity);
        }
    }
    if let Some((lo, hi)) = s.bounds() {
        println!("  bounds {lo} .. {hi}");
    }
    println!("  film {}×{}", s.film.width, s.film.height);
    for c in &s.cameras {
        println!(
            "  camera {:?}: at {:.4}, looking {:.4}, fov {}° along {:?} ({:.3}° vertical on the film)",
            c.name,
            c.position,
            c.forward,
            c.fov_deg,
            c.fov_axis,
            c.fov_y_deg(s.film.aspect())
        );
    }
    for p in &s.camera_paths {
        println!(
            "  camera path {:?}: {} keyframes over {} s",
            p.name,
            p.keyframes.len(),
            p.duration()
        );
    }
    println!("  warnings {}:", s.warnings.len());
    for w in &s.warnings {
        println!("    {w}");
    }
    Ok(())
}
