//! `lustre publish`: a baked scene as a static web page that renders it with the walkthrough's
//! own passes (lustre-web: lustre-gpu compiled to wasm32 on the browser's WebGPU).

use anyhow::Context;
use lustre_trace::baked::BakedScene;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `lustre publish`.
#[derive(clap::Args, Debug)]
pub struct PublishArgs {
    /// A baked scene file (DIR/scene.toml from `lustre bake SCENE --out DIR`, or a .glb from
    /// `lustre export scene`); none: the built-in room, baked into OUT/bake on first use.
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,
    /// The folder to write: index.html, main.js, the wasm module and its glue, scene.glb
    /// (files replaced atomically).
    #[arg(long)]
    pub out: PathBuf,
    /// The page's build (`scripts/build-web` writes it): default $LUSTRE_WEB, else `web` beside
    /// the binary's folder (target/web for target/release/lustre), else
    /// `share/lustre/web` beside it.
    #[arg(long, value_name = "DIR")]
    pub web: Option<PathBuf>,
}

/// The files of the page's build, copied as they are.
const PAGE_FILES: [&str; 4] = [
    "index.html",
    "main.js",
    "lustre_web.js",
    "lustre_web_bg.wasm",
];

/// The folder holding the page's build: `--web`, `$LUSTRE_WEB`, then beside the binary.
fn page_build(arg: Option<&Path>) -> anyhow::Result<PathBuf> {
    let complete = |d: &Path| PAGE_FILES.iter().all(|f| d.join(f).is_file());
    if let Some(d) = arg {
        if !complete(d) {
            anyhow::bail!(
                "--web {}: not the page's build (it needs {}); build it with scripts/build-web",
                d.display(),
                PAGE_FILES.join(", ")
            );
        }
        return Ok(d.to_path_buf());
    }
    let mut tried = vec![];
    if let Some(d) = std::env::var_os("LUSTRE_WEB") {
        tried.push(PathBuf::from(d));
    }
    if let Some(bin) = std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(Path::to_path_buf))
    {
        if let Some(up) = bin.parent() {
            tried.push(up.join("web"));
            tried.push(up.join("share/lustre/web"));
        }
    }
    tried.iter().find(|d| complete(d)).cloned().ok_or_else(|| {
        let list: Vec<String> = tried.iter().map(|d| d.display().to_string()).collect();
        anyhow::anyhow!(
            "the page's build (the wasm module and its glue) is not in {}: build it with \
             scripts/build-web (wasm32 target and wasm-bindgen-cli), or give --web DIR",
            list.join(", ")
        )
    })
}

/// Bytes of `data` compressed by gzip at its best level (what a static server sends with
/// `Content-Encoding: gzip`).
fn gzip_size(data: &[u8]) -> anyhow::Result<usize> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    e.write_all(data)?;
    Ok(e.finish()?.len())
}

/// Runs `lustre publish`.
pub fn run(args: &PublishArgs) -> anyhow::Result<()> {
    let web = page_build(args.web.as_deref())?;
    let baked = match &args.scene {
        Some(path) => BakedScene::load(path)?,
        None => {
            let (scene, atlas, pages) = crate::render_cmd::builtin(&args.out, None)?;
            BakedScene {
                scene,
                atlas,
                pages,
                warnings: vec![],
            }
        }
    };
    for w in &baked.warnings {
        eprintln!("warning: {w}");
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let glb = args.out.join("scene.glb");
    let export = lustre_scene::export::scene::write_scene_glb(
        &baked.scene,
        &baked.atlas,
        &baked.pages,
        &crate::export_cmd::spec_fit,
        &glb,
    )?;
    let mut rows = vec![];
    for f in PAGE_FILES {
        let from = web.join(f);
        let bytes = std::fs::read(&from).with_context(|| format!("reading {}", from.display()))?;
        lustre_brdf::error::write_atomic(&args.out.join(f), &bytes)?;
        rows.push((f.to_string(), bytes.len(), gzip_size(&bytes)?));
    }
    let bytes = std::fs::read(&glb).with_context(|| format!("reading {}", glb.display()))?;
    rows.push(("scene.glb".into(), bytes.len(), gzip_size(&bytes)?));
    let mb = |b: usize| b as f64 / 1e6;
    println!(
        "{}: {} meshes ({} triangles), {} cameras, {} camera paths; light maps {} page(s) of \
         {}×{} texels, irradiance as RGBE in 8-bit PNG ({:.2} MB)",
        args.scene
            .as_ref()
            .map_or("the built-in room".into(), |p| p.display().to_string()),
        export.meshes,
        export.triangles,
        export.cameras,
        export.animations,
        export.lightmap_pages,
        export.lightmap_size.0,
        export.lightmap_size.1,
        mb(export.lightmap_bytes)
    );
    println!("{:<20} {:>10} {:>10}", "file", "MB", "gzip MB");
    for (f, raw, gz) in &rows {
        println!("{f:<20} {:>10.3} {:>10.3}", mb(*raw), mb(*gz));
    }
    let (raw, gz) = rows.iter().fold((0, 0), |(a, b), (_, r, g)| (a + r, b + g));
    println!(
        "{:<20} {:>10.3} {:>10.3}",
        "the page downloads",
        mb(raw),
        mb(gz)
    );
    println!(
        "wrote {}: serve it (e.g. `python3 -m http.server -d {}`) and open it in a browser \
         with WebGPU",
        args.out.display(),
        args.out.display()
    );
    Ok(())
}
