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
    /// A material as glTF 2.0 (the metallic-roughness model fitted to it by Ngan L2, with the
    /// KHR_materials_anisotropy / _specular / _clearcoat / _sheen layers where they lower the
    /// error, on a sample sphere with normals, tangents and texture coordinates, as a .glb) or
    /// as a Mitsuba
    /// 3 BSDF (rough conductor or rough plastic, whichever fits better; an RGL file as
    /// `measured`); prints what the export loses (the fit's error beside lustre's own GGX fit
    /// of the same data).
    Material(MaterialArgs),
    /// A baked scene (the scene.toml `lustre bake` wrote) as one binary glTF 2.0 file: meshes
    /// with TEXCOORD_1 for the light-map atlas, the light-map pages as RGBE PNG textures through
    /// `MOZ_lightmap`, the nearest glTF materials (the exact lustre ones in their extras),
    /// an equirect environment map, cameras, and the camera paths as animations; the probes'
    /// cube maps as .hdr faces beside it (FILE.glb.probes/). lustre reads the file back as it
    /// was (`lustre render FILE.glb`). With `--to mitsuba`, any scene as a
    /// Mitsuba 3 scene folder (scene.xml, OBJ meshes, textures) that Mitsuba renders as it is.
    Scene(SceneArgs),
}

/// The formats `lustre export scene` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SceneFormat {
    /// glTF 2.0 binary (.glb) with the light maps inside (`MOZ_lightmap`); the scene must be
    /// baked.
    Glb,
    /// A Mitsuba 3 scene folder: DIR/scene.xml, the meshes as OBJ in DIR/meshes, textures and
    /// the environment map in DIR/textures (any scene; light maps are not needed).
    Mitsuba,
}

/// Arguments of `lustre export scene`.
#[derive(clap::Args, Debug)]
pub struct SceneArgs {
    /// A baked scene file (DIR/scene.toml from `lustre bake SCENE --out DIR`) for glTF; any
    /// scene lustre reads for Mitsuba.
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,
    /// The format to write.
    #[arg(long, value_enum, default_value_t = SceneFormat::Glb)]
    pub to: SceneFormat,
    /// The file to write (.glb; replaced atomically when it exists), or for Mitsuba the folder
    /// (created; its files replaced atomically, scene.xml last).
    #[arg(long, value_name = "FILE|DIR")]
    pub out: PathBuf,
    /// glTF: the probes' cube-map face size in texels (as `lustre render --probe-size`); the
    /// probes are captured as the renderer captures them and written beside the .glb.
    #[arg(long, default_value_t = 128)]
    pub probe_size: usize,
    /// Mitsuba: samples per pixel written as the scene's `spp` default (`mitsuba -D spp=N`
    /// overrides it).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
    pub spp: u32,
    /// Mitsuba: the path integrator's `max_depth` default (lustre reference's --max-depth).
    #[arg(long, default_value_t = 65, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub max_depth: u32,
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
pub(crate) fn spec_fit(
    m: &lustre_scene::material::Material,
) -> Option<(serde_json::Value, String)> {
    let lustre_scene::material::MaterialKind::Spec(s) = &m.kind else {
        return None;
    };
    let bsdf = lustre_brdf::catalog::resolve(&s.spec).ok()?;
    let data = lustre_fit::data::MeasuredData::from_bsdf(&m.name, bsdf);
    let g = lustre_fit::gltf::fit_gltf(&data).ok()?;
    let edits = if s.edits.is_empty() {
        String::new()
    } else {
        format!(" (before {} edit(s))", s.edits.len())
    };
    let material = gltf_material(&m.name, &g, json!({ "source": s.spec }));
    Some((
        material.to_json().ok()?,
        format!(
            "{}{edits} as the metallic-roughness model fitted to it: Ngan L2 {:.4}",
            s.spec,
            g.errors.ngan_mean()
        ),
    ))
}

/// The Mitsuba BSDF of a material given by a catalog specification: an RGL file as Mitsuba's
/// `measured` (copied into the folder), anything else the better of Mitsuba's rough conductor
/// and rough plastic fitted to it (Ngan L2), and a line saying so with its error.
fn spec_mitsuba(
    m: &lustre_scene::material::Material,
    id: &str,
    dir: &std::path::Path,
) -> Option<(String, String)> {
    let lustre_scene::material::MaterialKind::Spec(s) = &m.kind else {
        return None;
    };
    let element = |xml: String| -> Option<String> {
        let (a, b) = (xml.find("<bsdf")?, xml.rfind("</bsdf>")?);
        Some(xml[a..b + "</bsdf>".len()].to_string())
    };
    if s.edits.is_empty() {
        if let Some(file) = rgl_file(&s.spec) {
            let name = file.file_name()?.to_string_lossy().into_owned();
            let rel = format!("textures/{name}");
            let bytes = std::fs::read(&file).ok()?;
            lustre_scene::scene_file::write_atomic(&dir.join(&rel), &bytes).ok()?;
            let note = format!("{} as Mitsuba's measured BSDF (no fit, no loss)", s.spec);
            return Some((element(measured_xml(id, &rel, &note))?, note));
        }
    }
    let bsdf = lustre_brdf::catalog::resolve(&s.spec).ok()?;
    let data = lustre_fit::data::MeasuredData::from_bsdf(&m.name, bsdf);
    let f = lustre_fit::mitsuba::fit_mitsuba(&data).ok()?;
    let edits = if s.edits.is_empty() {
        String::new()
    } else {
        format!(" (before {} edit(s))", s.edits.len())
    };
    let note = format!(
        "{}{edits} as Mitsuba's {} fitted to it: Ngan L2 {:.4}",
        s.spec,
        f.bsdf.plugin(),
        f.errors.ngan_mean()
    );
    Some((element(f.bsdf.xml(id, &note))?, note))
}

/// `lustre export scene --to mitsuba`: any scene as a Mitsuba 3 scene folder.
fn scene_mitsuba(args: &SceneArgs) -> anyhow::Result<()> {
    if args.out.is_file() {
        anyhow::bail!(
            "--out {}: a Mitsuba scene is a folder (scene.xml, meshes/, textures/); this is a file",
            args.out.display()
        );
    }
    let scene = lustre_scene::Scene::load(&args.scene)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let settings = lustre_scene::export::mitsuba::MitsubaSettings {
        spp: args.spp,
        max_depth: args.max_depth,
    };
    // Fitting a Mitsuba model to each lustre specification takes seconds: say so.
    let fits = scene
        .materials
        .iter()
        .filter(|m| matches!(m.kind, lustre_scene::material::MaterialKind::Spec(_)))
        .count();
    let spinner = ProgressBar::new_spinner();
    if fits > 0 {
        spinner.set_style(
            ProgressStyle::with_template("{spinner} {msg} {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        spinner.enable_steady_tick(std::time::Duration::from_millis(200));
        spinner.set_message(format!(
            "writing the scene; fitting Mitsuba models to {fits} lustre material(s)"
        ));
    }
    let out = lustre_scene::export::mitsuba::write_mitsuba_scene(
        &scene,
        &args.out,
        settings,
        &spec_mitsuba,
    );
    spinner.finish_and_clear();
    let out = out?;
    println!(
        "{} meshes ({} triangles, OBJ), {} BSDFs, {} texture files, {} area emitters, {} sensors; \
         path tracer, max_depth {}, {} spp, {}×{} (override with mitsuba -D)",
        out.meshes,
        out.triangles,
        out.materials,
        out.textures,
        out.emitters,
        out.cameras,
        args.max_depth,
        args.spp,
        scene.film.width,
        scene.film.height
    );
    if !out.approximations.is_empty() {
        println!("what Mitsuba's plugins approximate:");
        for a in &out.approximations {
            println!("  {a}");
        }
    }
    println!(
        "wrote {} ({:.2} MB in all)",
        args.out.join("scene.xml").display(),
        out.bytes as f64 / 1e6
    );
    Ok(())
}

fn scene(args: &SceneArgs) -> anyhow::Result<()> {
    if args.to == SceneFormat::Mitsuba {
        return scene_mitsuba(args);
    }
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
    // The probes' settings are checked before anything is written.
    lustre_shade::probe::ProbeOptions {
        face_size: args.probe_size,
        ..lustre_shade::probe::ProbeOptions::default()
    }
    .validate()?;
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
    if let Some(p) = write_probes(&baked, &args.out, args.probe_size)? {
        println!(
            "probes: {} cube map(s) of 6 × {}² texels as Radiance .hdr faces (OpenGL cube-map \
             convention) and probes.json in {} ({:.2} MB, captured in {:.1} s)",
            p.count,
            args.probe_size,
            p.dir.display(),
            mb(p.bytes),
            p.seconds
        );
    }
    Ok(())
}

/// The probe cube maps written beside an exported glTF.
struct ProbeFiles {
    dir: PathBuf,
    count: usize,
    bytes: usize,
    seconds: f64,
}

/// The file name of face `f` of probe `k` named `name`.
fn face_file(k: usize, name: &str, f: usize) -> String {
    let name: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_".contains(c) {
                c
            } else {
                '_'
            }
        })
        .take(48)
        .collect();
    format!(
        "{k:02}_{name}_{}.hdr",
        ["px", "nx", "py", "ny", "pz", "nz"][f]
    )
}

/// Captures the scene's probes (object probes, then room probes) as `lustre render` does and
/// writes each as six Radiance `.hdr` faces (+X, −X, +Y, −Y, +Z, −Z; OpenGL's cube-map
/// convention, row 0 at the top) in `OUT.probes/`, with `probes.json` naming them with their
/// centres and bounding planes. `None` when the scene has no probes.
fn write_probes(
    baked: &lustre_trace::baked::BakedScene,
    out: &std::path::Path,
    face_size: usize,
) -> anyhow::Result<Option<ProbeFiles>> {
    use lustre_shade::probe::{capture_probes, has_probes, LitScene, ProbeOptions};
    let scene = &baked.scene;
    if !has_probes(scene) {
        return Ok(None);
    }
    let opts = ProbeOptions {
        face_size,
        ..ProbeOptions::default()
    };
    opts.validate()?;
    let t = std::time::Instant::now();
    let (ps, _) = lustre_trace::reference::path_scene(scene)?;
    let bases: Vec<lustre_trace::bake::BaseAlbedo> = scene
        .materials
        .iter()
        .map(lustre_trace::bake::base_albedo)
        .collect();
    let lm = lustre_trace::bake::render::Lightmapped::new(
        scene,
        &baked.atlas,
        &baked.pages,
        &ps.geometry,
        bases,
    )?;
    let pt = lustre_trace::path_tracer::PathTracer::new(
        &ps,
        lustre_trace::path_tracer::PathOptions::default(),
    )?;
    let lit = LitScene::new(scene, &ps, &pt, &lm)?;
    let total = scene.meshes.iter().filter(|m| m.hints.probe).count() + scene.probes.len();
    let bar = ProgressBar::new(total as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} probes captured {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let probes = capture_probes(&lit, &opts, &mut |_, _| bar.inc(1))?;
    bar.finish_and_clear();
    let mut dir = out.as_os_str().to_owned();
    dir.push(".probes");
    let dir = PathBuf::from(dir);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut bytes = 0;
    let mut list = Vec::new();
    for (k, p) in probes.iter().enumerate() {
        let cube = &p.pyramid.levels[0];
        let mut faces = Vec::new();
        for (f, face) in cube.faces.iter().enumerate() {
            let texels: Vec<image::Rgb<f32>> = face.iter().map(|&c| image::Rgb(c)).collect();
            let mut hdr = Vec::new();
            image::codecs::hdr::HdrEncoder::new(&mut hdr)
                .encode(&texels, cube.size, cube.size)
                .with_context(|| format!("encoding probe {:?}", p.name))?;
            let name = face_file(k, &p.name, f);
            lustre_scene::scene_file::write_atomic(&dir.join(&name), &hdr)?;
            bytes += hdr.len();
            faces.push(name);
        }
        let planes: Vec<serde_json::Value> = p
            .planes
            .iter()
            .map(|b| json!({ "point": (b.point + p.centre).to_array(), "normal": b.normal.to_array() }))
            .collect();
        list.push(json!({
            "name": p.name,
            "kind": if p.mesh.is_some() { "object" } else { "room" },
            "mesh": p.mesh,
            "centre": p.centre.to_array(),
            "planes": planes,
            "faces": faces,
        }));
    }
    let index = json!({
        "schema": "lustre-probes",
        "version": 1,
        "scene": out.file_name().map(|n| n.to_string_lossy().to_string()),
        "face_size": face_size,
        "faces": "+X, -X, +Y, -Y, +Z, -Z; OpenGL cube-map convention, row 0 at the top; \
                  linear radiance (Radiance RGBE .hdr)",
        "planes": "world-space point and normal of each bounding plane (parallax), the normal pointing into the probe's volume",
        "probes": list,
    });
    let text = serde_json::to_string_pretty(&index)?;
    lustre_scene::scene_file::write_atomic(&dir.join("probes.json"), text.as_bytes())?;
    bytes += text.len();
    Ok(Some(ProbeFiles {
        dir,
        count: probes.len(),
        bytes,
        seconds: t.elapsed().as_secs_f64(),
    }))
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
            if g.anisotropy > 0.0 {
                println!(
                    "  KHR_materials_anisotropy: strength {:.4}, rotation {:.4} rad from the tangent",
                    g.anisotropy, g.anisotropy_rotation
                );
            }
            let l = &g.layers;
            let d = lustre_brdf::models::pbr_metallic_roughness::PbrLayers::default();
            if l.has_specular() {
                println!(
                    "  KHR_materials_specular: specularFactor {:.4}, specularColorFactor {}",
                    l.specular,
                    rgb(&l.specular_color.0)
                );
            }
            if l.has_clearcoat() {
                println!(
                    "  KHR_materials_clearcoat: clearcoatFactor {:.4}, clearcoatRoughnessFactor {:.4}",
                    l.clearcoat, l.clearcoat_roughness
                );
            }
            if l.has_sheen() {
                println!(
                    "  KHR_materials_sheen: sheenColorFactor {}, sheenRoughnessFactor {:.4}",
                    rgb(&l.sheen_color.0),
                    l.sheen_roughness
                );
            }
            if *l != d {
                println!(
                    "  without the specular / clearcoat / sheen layers (a reader that ignores \
                     them): Ngan L2 {:.4}",
                    g.core_ngan_l2
                );
            }
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
    let exported_anisotropic = matches!(&fitted, Fitted::Gltf(g) if g.anisotropy > 0.0);
    if data.bsdf.flags().anisotropic && !exported_anisotropic {
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
            let material = gltf_material(&data.name, &g, extras);
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

/// The glTF material of a fit: its factors and extensions (base colour clamped to [0, 1]).
fn gltf_material(
    name: &str,
    g: &lustre_fit::gltf::GltfFit,
    extras: serde_json::Value,
) -> GltfMaterial {
    GltfMaterial {
        name: name.to_string(),
        base_color: g.base_color.map(|c| c.clamp(0.0, 1.0)),
        metallic: g.metallic,
        roughness: g.roughness,
        anisotropy: g.anisotropy,
        anisotropy_rotation: g.anisotropy_rotation,
        layers: g.layers,
        extras,
    }
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
