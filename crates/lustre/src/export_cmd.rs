//! `lustre export`: lustre's results for other tools. `export material SPEC --to gltf --out
//! M.glb` fits the glTF 2.0 metallic-roughness model to any material (a measured file, a
//! neural BRDF, a fit JSON, a catalog spec; `lustre_fit::gltf`), prints its error beside that of
//! lustre's own GGX fit of the same data, and writes a sample sphere carrying it
//! (`lustre_scene::export::material`); `--to mitsuba --out M.xml` fits Mitsuba 3's rough
//! conductor and rough plastic (`lustre_fit::mitsuba`) and writes the better one, or an RGL
//! file as Mitsuba's `measured` (the XML: `lustre_fit::mitsuba`). `export scene
//! BAKED/scene.toml --out S.glb` writes a baked scene as one glTF 2.0 file with its light maps
//! (`MOZ_lightmap`, RGBE PNG pages), materials, cameras and camera paths
//! (`lustre_scene::export::scene`), which lustre reads back unchanged.

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use lustre_fit::ct::{fit_masked, CtDistribution, CtOptions};
use lustre_fit::data::{load_with, LoadOptions};
use lustre_fit::metrics::evaluate_masked;
use lustre_fit::mitsuba::{measured_xml, MitsubaBsdf};
use lustre_scene::export::material::{write_sphere_glb, GltfMaterial};
use serde_json::json;
use std::path::PathBuf;

/// Arguments of `lustre export`.
#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    #[command(subcommand)]
    pub command: ExportCommand,
}

/// The `lustre export` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum ExportCommand {
    /// A material as glTF 2.0 (the metallic-roughness model fitted to it by Ngan L2, on a
    /// sample sphere with normals, tangents and texture coordinates, as a .glb) or as a Mitsuba
    /// 3 BSDF (rough conductor or rough plastic, whichever fits better; an RGL file as
    /// `measured`); prints what the export loses (the fit's error beside lustre's own GGX fit
    /// of the same data).
    Material(MaterialArgs),
    /// A baked scene (the scene.toml `lustre bake` wrote) as one binary glTF 2.0 file: meshes
    /// with TEXCOORD_1 for the light-map atlas, the light-map pages as RGBE PNG textures through
    /// `MOZ_lightmap`, the nearest glTF materials (the exact lustre ones in their extras),
    /// an equirect environment map, cameras, and the camera paths as animations. lustre reads
    /// the file back as it was (`lustre render FILE.glb`).
    Scene(SceneArgs),
}

/// The formats `lustre export scene` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SceneFormat {
    /// glTF 2.0 binary (.glb) with the light maps inside (`MOZ_lightmap`).
    Glb,
}

/// Arguments of `lustre export scene`.
#[derive(clap::Args, Debug)]
pub struct SceneArgs {
    /// A baked scene file (DIR/scene.toml from `lustre bake SCENE --out DIR`).
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,
    /// The format to write.
    #[arg(long, value_enum, default_value_t = SceneFormat::Glb)]
    pub to: SceneFormat,
    /// The file to write (.glb; replaced atomically when it exists).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// The formats `lustre export material` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MaterialFormat {
    /// glTF 2.0 binary (.glb): `pbrMetallicRoughness` on a sample sphere.
    Gltf,
    /// A Mitsuba 3 XML file with one BSDF: `roughconductor` or `roughplastic`, whichever fits
    /// better, or `measured` for an RGL .bsdf file (copied beside it).
    Mitsuba,
}

/// Arguments of `lustre export material`.
#[derive(clap::Args, Debug)]
pub struct MaterialArgs {
    /// The material: a measured file (.binary, .bsdf, .dat, .gonio), a fit JSON, `nbrdf:NAME`,
    /// a published fit (`sgd:NAME`) or any model spec (see `lustre list`).
    #[arg(value_name = "SPEC")]
    pub spec: String,
    /// The format to write.
    #[arg(long, value_enum, default_value_t = MaterialFormat::Gltf)]
    pub to: MaterialFormat,
    /// The file to write (.glb for glTF, .xml for Mitsuba; replaced atomically when it exists).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Refuse MERL tables with unmeasured (negative) bins instead of masking them.
    #[arg(long)]
    pub strict: bool,
}

/// Runs `lustre export`.
pub fn run(args: &ExportArgs) -> anyhow::Result<()> {
    match &args.command {
        ExportCommand::Material(m) => material(m),
        ExportCommand::Scene(s) => scene(s),
    }
}

/// The glTF material of a material given by a catalog specification: the metallic-roughness
/// model fitted to it (Ngan L2), and a line saying so with its error.
fn spec_fit(m: &lustre_scene::material::Material) -> Option<(serde_json::Value, String)> {
    let lustre_scene::material::MaterialKind::Spec(s) = &m.kind else {
        return None;
    };
    let bsdf = lustre_brdf::catalog::resolve(&s.spec).ok()?;
    let data = lustre_fit::data::MeasuredData::from_bsdf(&m.name, bsdf);
    let g = lustre_fit::gltf::fit_gltf(&data).ok()?;
    let [r, gr, b] = g.base_color.map(|c| c.clamp(0.0, 1.0));
    let edits = if s.edits.is_empty() {
        String::new()
    } else {
        format!(" (before {} edit(s))", s.edits.len())
    };
    Some((
        json!({ "baseColorFactor": [r, gr, b, 1.0], "metallicFactor": g.metallic,
                "roughnessFactor": g.roughness }),
        format!(
            "{}{edits} as the metallic-roughness model fitted to it: Ngan L2 {:.4}",
            s.spec,
            g.errors.ngan_mean()
        ),
    ))
}

fn scene(args: &SceneArgs) -> anyhow::Result<()> {
    let ext = args
        .out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if ext.as_deref() != Some("glb") {
        anyhow::bail!(
            "--out {}: a scene is exported as binary glTF; name it .glb",
            args.out.display()
        );
    }
    let baked = lustre_trace::baked::BakedScene::load(&args.scene)?;
    for w in &baked.warnings {
        eprintln!("warning: {w}");
    }
    let out = lustre_scene::export::scene::write_scene_glb(
        &baked.scene,
        &baked.atlas,
        &baked.pages,
        &spec_fit,
        &args.out,
    )?;
    let mb = |b: usize| b as f64 / 1e6;
    println!(
        "{} meshes ({} triangles), {} glTF materials, {} textures ({:.2} MB), {} cameras, {} \
         camera paths as animations",
        out.meshes,
        out.triangles,
        out.materials,
        out.textures,
        mb(out.texture_bytes),
        out.cameras,
        out.animations
    );
    println!(
        "light maps: {} page(s) of {}×{} texels, irradiance as RGBE in 8-bit PNG through \
         MOZ_lightmap ({:.2} MB)",
        out.lightmap_pages,
        out.lightmap_size.0,
        out.lightmap_size.1,
        mb(out.lightmap_bytes)
    );
    if out.environment_bytes > 0 {
        println!(
            "environment map: embedded, RGBE in 8-bit PNG ({:.2} MB)",
            mb(out.environment_bytes)
        );
    }
    if !out.approximations.is_empty() {
        println!("glTF materials for other viewers (the exact lustre ones are in their extras):");
        for a in &out.approximations {
            println!("  {a}");
        }
    }
    println!("wrote {} ({:.2} MB)", args.out.display(), mb(out.bytes));
    Ok(())
}

/// Three channels as `[a, b, c]` with four decimals.
fn rgb(v: &[f64; 3]) -> String {
    format!("[{:.4}, {:.4}, {:.4}]", v[0], v[1], v[2])
}

fn material(args: &MaterialArgs) -> anyhow::Result<()> {
    let ext = args
        .out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let want = match args.to {
        MaterialFormat::Gltf => "glb",
        MaterialFormat::Mitsuba => "xml",
    };
    if ext.as_deref() != Some(want) {
        anyhow::bail!(
            "--out {}: a {} export is written as .{want}; name it so",
            args.out.display(),
            match args.to {
                MaterialFormat::Gltf => "glTF (binary glTF)",
                MaterialFormat::Mitsuba => "Mitsuba (XML)",
            }
        );
    }
    let data = load_with(
        &args.spec,
        &LoadOptions {
            strict: args.strict,
        },
    )
    .with_context(|| format!("cannot load {:?}", args.spec))?;
    let rgl = rgl_file(&args.spec);
    if args.to == MaterialFormat::Mitsuba {
        if let Some(file) = rgl {
            return measured(args, &data.name, &file);
        }
    }
    let spinner = ProgressBar::new_spinner();
    spinner.set_style(
        ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    spinner.enable_steady_tick(std::time::Duration::from_millis(200));
    spinner.set_message(format!("fitting the exported model to {}", data.name));
    let fitted = match args.to {
        MaterialFormat::Gltf => lustre_fit::gltf::fit_gltf(&data).map(Fitted::Gltf),
        MaterialFormat::Mitsuba => lustre_fit::mitsuba::fit_mitsuba(&data).map(Fitted::Mitsuba),
    };
    spinner.set_message(format!("fitting lustre's GGX model to {}", data.name));
    let ggx = fit_masked(
        data.bsdf.as_ref(),
        CtDistribution::Ggx,
        &CtOptions::default(),
        data.coverage.as_ref(),
    );
    spinner.finish_and_clear();
    let fitted = fitted.with_context(|| format!("fitting the exported model to {}", data.name))?;
    let ggx_error = match ggx.and_then(|f| Ok(f.to_bsdf(&data.name)?)) {
        Ok(model) => Some(
            evaluate_masked(
                data.bsdf.as_ref(),
                &model,
                data.transmission,
                data.coverage.as_ref(),
            )
            .ngan_mean(),
        ),
        Err(e) => {
            eprintln!("warning: no GGX fit of {} to compare with: {e}", data.name);
            None
        }
    };
    let errors = match &fitted {
        Fitted::Gltf(g) => {
            println!(
                "glTF metallic-roughness fit of {}: base colour {}, metallic {:.4}, roughness {:.4}",
                args.spec,
                rgb(&g.base_color),
                g.metallic,
                g.roughness
            );
            g.errors
        }
        Fitted::Mitsuba(m) => {
            println!(
                "Mitsuba 3 {} fit of {}: {}",
                m.bsdf.plugin(),
                args.spec,
                match m.bsdf {
                    MitsubaBsdf::RoughConductor { specular, alpha } =>
                        format!("specular_reflectance {}, alpha {alpha:.4}", rgb(&specular)),
                    MitsubaBsdf::RoughPlastic { diffuse, alpha } => format!(
                        "diffuse_reflectance {}, alpha {alpha:.4}, int_ior {}",
                        rgb(&diffuse),
                        lustre_fit::mitsuba::PLASTIC_IOR
                    ),
                }
            );
            for (c, e) in m.candidates.iter().skip(1) {
                println!("  ({} fitted too: Ngan L2 {e:.4})", c.plugin());
            }
            m.errors
        }
    };
    println!(
        "  Ngan L2 {:.4} (RGB {}), L1 {:.4}; albedo at normal incidence {} (data {})",
        errors.ngan_mean(),
        rgb(&errors.ngan_l2),
        errors.l1_mean(),
        rgb(&errors.albedo_model),
        rgb(&errors.albedo_data)
    );
    if let Some(g) = ggx_error {
        println!("  lustre's Cook–Torrance GGX fit of the same data: Ngan L2 {g:.4}");
    }
    if data.transmission {
        eprintln!(
            "warning: {} transmits light; the exported material carries its reflection only \
             (the errors above count what is lost)",
            args.spec
        );
    }
    if data.bsdf.flags().anisotropic {
        eprintln!(
            "warning: {} is anisotropic; the exported model is isotropic (the errors above \
             count what is lost)",
            args.spec
        );
    }
    if let Some(g) = ggx_error.filter(|&g| errors.ngan_mean() > 2.0 * g) {
        eprintln!(
            "warning: the exported model fits {} {:.1}× worse than lustre's GGX fit (Ngan L2 \
             {:.4} against {g:.4}): the target model cannot carry this material well",
            args.spec,
            errors.ngan_mean() / g.max(f64::MIN_POSITIVE),
            errors.ngan_mean()
        );
    }
    let extras = json!({
        "source": args.spec,
        "ngan_l2": errors.ngan_l2,
        "l1": errors.l1,
        "ggx_ngan_l2": ggx_error,
    });
    match fitted {
        Fitted::Gltf(g) => {
            let material = GltfMaterial {
                name: data.name.clone(),
                base_color: g.base_color,
                metallic: g.metallic,
                roughness: g.roughness,
                extras,
            };
            let bytes = write_sphere_glb(&material, &args.out)?;
            println!("wrote {} ({bytes} bytes)", args.out.display());
        }
        Fitted::Mitsuba(m) => {
            let note = format!(
                "lustre export: {} fitted to {} (Ngan L2 {:.4}); in lustre: {}",
                m.bsdf.plugin(),
                args.spec,
                errors.ngan_mean(),
                m.bsdf.spec()
            );
            let xml = m.bsdf.xml(&data.name, &note);
            lustre_scene::scene_file::write_atomic(&args.out, xml.as_bytes())?;
            println!("  in lustre: {}", m.bsdf.spec());
            println!("wrote {}", args.out.display());
        }
    }
    Ok(())
}

/// What was fitted for the export.
enum Fitted {
    Gltf(lustre_fit::gltf::GltfFit),
    Mitsuba(lustre_fit::mitsuba::MitsubaFit),
}

/// The RGL `.bsdf` file a spec names, if it is one.
fn rgl_file(spec: &str) -> Option<PathBuf> {
    let p = PathBuf::from(spec.trim());
    let is_bsdf = p
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bsdf"));
    (is_bsdf && p.is_file()).then_some(p)
}

/// An RGL file as Mitsuba's `measured` BSDF: the XML and a copy of the file beside it.
fn measured(args: &MaterialArgs, name: &str, file: &std::path::Path) -> anyhow::Result<()> {
    let file_name = file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| format!("{name}.bsdf"));
    let dir = args
        .out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(std::path::Path::new("."));
    let copy = dir.join(&file_name);
    let bytes = lustre_brdf::error::read_file(file)?;
    if std::fs::canonicalize(&copy).ok() != std::fs::canonicalize(file).ok() {
        lustre_scene::scene_file::write_atomic(&copy, &bytes)?;
    }
    let note = format!(
        "lustre export: the RGL measurement {} as Mitsuba's measured BSDF (no fit, no loss)",
        file.display()
    );
    let xml = measured_xml(name, &file_name, &note);
    lustre_scene::scene_file::write_atomic(&args.out, xml.as_bytes())?;
    println!(
        "Mitsuba 3 measured BSDF of {}: the data itself ({} copied beside the XML)",
        args.spec,
        copy.display()
    );
    println!("wrote {}", args.out.display());
    Ok(())
}
