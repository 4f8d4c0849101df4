//! `lustre scene info SCENE`: what a scene file holds, as lustre reads it. `lustre scene setup
//! SCENE`: the real-time set-up `lustre bake` would write for it (`lustre_trace::setup`), and
//! a top view of it as SVG.

use anyhow::Context;
use clap::{Args, Subcommand};
use lustre_plot::{TopItem, TopKind};
use lustre_scene::{EnvironmentSource, Scene};
use std::path::{Path, PathBuf};

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
    /// The automatic real-time set-up: the one-line report, every choice, and with --top-view a
    /// top view (x right, z down) of the room probes' boxes (cyan), the object probes (yellow),
    /// the planar reflectors (magenta), the cameras (black) over every mesh's bounds (grey).
    Setup {
        /// The scene (.gltf, .glb, .obj, .xml or .toml).
        scene: PathBuf,
        /// Ignore the scene's own hints and room probes.
        #[arg(long)]
        ignore_hints: bool,
        /// Write the top view as BASE.png and BASE.svg.
        #[arg(long, value_name = "BASE")]
        top_view: Option<PathBuf>,
    },
}

pub fn run(args: &SceneArgs) -> anyhow::Result<()> {
    match &args.command {
        SceneCommand::Info { scene } => info(scene),
        SceneCommand::Setup {
            scene,
            ignore_hints,
            top_view,
        } => setup(scene, *ignore_hints, top_view.as_deref()),
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

fn setup(path: &Path, ignore_hints: bool, top: Option<&Path>) -> anyhow::Result<()> {
    let mut s = Scene::load(path).with_context(|| format!("cannot load {}", path.display()))?;
    if ignore_hints {
        lustre_trace::setup::clear_hints(&mut s);
    }
    let setup = crate::bake_cmd::decide_setup(&s)?;
    for (name, h) in &setup.objects {
        let what = match (h.planar_reflector, h.probe) {
            (true, _) => "planar reflector",
            (false, true) => "object probe",
            _ => "hints",
        };
        println!("  {name}: {what}");
    }
    for p in &setup.probes {
        println!(
            "  room probe {:?} at {:?}, box {:?} .. {:?}",
            p.name, p.centre, p.box_min, p.box_max
        );
    }
    lustre_trace::setup::apply(&mut s, &setup);
    if let Some(base) = top {
        let files = lustre_plot::top_view(&top_view_items(&s), 800, base)
            .with_context(|| format!("--top-view {}", base.display()))?;
        for f in files.paths() {
            println!("wrote {}", f.display());
        }
    }
    Ok(())
}

/// The top view of `scene`'s set-up (`lustre_plot::top_view`).
fn top_view_items(scene: &Scene) -> Vec<TopItem> {
    let xz = |v: glam::Vec3| [f64::from(v.x), f64::from(v.z)];
    let mut items = vec![];
    for m in &scene.meshes {
        let Some((lo, hi)) = m.bounds() else { continue };
        let kind = match (m.hints.planar_reflector, m.hints.probe) {
            (true, _) => TopKind::Reflector,
            (false, true) => TopKind::ObjectProbe,
            _ => TopKind::Mesh,
        };
        items.push(TopItem {
            kind,
            label: m.name.clone(),
            lo: xz(lo),
            hi: xz(hi),
            at: xz(lo),
        });
    }
    for p in &scene.probes {
        let at = [p.centre[0], p.centre[2]];
        let (lo, hi) = p
            .parallax_box()
            .map_or((at, at), |(a, b)| ([a[0], a[2]], [b[0], b[2]]));
        items.push(TopItem {
            kind: TopKind::RoomProbe,
            label: p.name.clone(),
            lo,
            hi,
            at,
        });
    }
    for c in &scene.cameras {
        let at = [c.position.x, c.position.z];
        items.push(TopItem {
            kind: TopKind::Camera,
            label: c.name.clone(),
            lo: at,
            hi: [at[0] + c.forward.x, at[1] + c.forward.z],
            at,
        });
    }
    items
}
