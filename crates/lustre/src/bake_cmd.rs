//! `lustre bake`: light maps of irradiance (000 §4.3, Eq. 4.1: Lo = kd·E/π) for any scene:
//! the light-map atlas (the scene's TEXCOORD_1 when valid, else generated), the bake in
//! resumable tiles, the assembly (buried fill, denoise, dilation) into half-float EXR pages,
//! and an updated scene file that references them.
//!
//! On many machines: `--shard K/N` (or `--shard-count N` inside a Kubernetes Indexed Job or a
//! SLURM array) bakes only the tiles whose index mod N is K into the shared `--out`; the same
//! command with `--merge` instead assembles them once all tiles are there; `--plan` says how many
//! tiles (shards at most) there are (docs: guide/scale-out.md).

use anyhow::{bail, Context};
use indicatif::{ProgressBar, ProgressStyle};
use lustre_scene::lightmap::{
    build_atlas_with_progress, write_atlas_glb, AtlasOptions, LightmapAtlas,
};
use lustre_scene::scene_file::{self, SceneFile};
use lustre_scene::{ObjectHints, Scene};
use lustre_trace::bake::{
    assemble, bake_tiles, check_shard_tiles, ATrousOptions, BakeOptions, Denoiser, Transport,
};
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::setup::{auto_setup, has_realtime_hints, Setup, SetupOptions};
use std::path::{Path, PathBuf};

/// Arguments of `lustre bake`.
#[derive(clap::Args, Debug)]
pub struct BakeArgs {
    /// The scene: a lustre scene file (.toml), glTF (.gltf/.glb), OBJ or Mitsuba XML.
    pub scene: PathBuf,
    /// Output folder (tiles/, the atlas .glb, the page EXRs, bake.json, scene.toml).
    #[arg(long)]
    pub out: PathBuf,
    /// Sample points (one path each) per texel.
    #[arg(long, default_value_t = 256)]
    pub spp: u32,
    /// Diffuse bounces (1 = direct light only).
    #[arg(long, default_value_t = 4)]
    pub bounces: u32,
    /// Light-map texel density, texels per metre (scene unit); when absent 32, halved while
    /// the scene's surface would need more than --max-texels texels (a scene in millimetres).
    #[arg(long)]
    pub texels_per_metre: Option<f32>,
    /// The light maps' texel budget: where the surface would need more, the few largest meshes
    /// (a ground plane under a building) get a coarser density of their own first, so the rest
    /// keeps its; else the density is halved (`fit_densities`).
    #[arg(long, default_value_t = DEFAULT_MAX_TEXELS)]
    pub max_texels: u64,
    /// Seed of the per-texel sample streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Tile side in texels (the unit of resuming and sharding).
    #[arg(long, default_value_t = 64)]
    pub tile: u32,
    /// Write the raw Monte Carlo means (no à-trous denoising).
    #[arg(long)]
    pub no_denoise: bool,
    /// Light transport in the irradiance: `diffuse` (paths through the scene made diffuse; the
    /// image converges to `lustre reference --diffuse`) or `full` (paths through the scene's own
    /// materials: light reflected by glossy floors and glass reaches the light maps, for
    /// `lustre render`).
    #[arg(long, value_enum, default_value_t = TransportArg::Diffuse)]
    pub transport: TransportArg,
    #[command(flatten)]
    pub shard: crate::shard::ShardArgs,
    /// The real-time set-up written into scene.toml: `auto` adds mirrors, object probes and
    /// room probes where the scene's own hints say nothing (`lustre_trace::setup`); `manual`
    /// keeps only the scene's hints.
    #[arg(long, value_enum, default_value_t = SetupArg::Auto)]
    pub setup: SetupArg,
    /// Assemble the tiles that the shards (`--shard K/N` runs with the same scene and options)
    /// baked into --out: fill, denoise, dilate, the page EXRs and the updated scene file.
    #[arg(long, conflicts_with_all = ["shard", "shard_count"])]
    pub merge: bool,
    /// Print the atlas and its tiles (the most shards the bake splits into) and check the
    /// options and the shard count, writing nothing: what the SLURM script runs before it
    /// submits an array.
    #[arg(long, conflicts_with = "merge")]
    pub plan: bool,
    /// Run even when the job's memory or disk estimate exceeds what the machine has.
    #[arg(long)]
    pub force: bool,
}

/// `--setup`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetupArg {
    /// The automatic set-up where the scene's hints say nothing (a hand-written hint wins).
    Auto,
    /// The scene's own hints only.
    Manual,
}

/// `--transport`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportArg {
    /// The diffuse scene.
    Diffuse,
    /// The scene's own materials.
    Full,
}

impl BakeArgs {
    /// The bake settings of these arguments.
    pub fn options(&self) -> BakeOptions {
        BakeOptions {
            spp: self.spp,
            bounces: self.bounces,
            seed: self.seed,
            tile: self.tile,
            denoiser: if self.no_denoise {
                Denoiser::None
            } else {
                Denoiser::ATrous(ATrousOptions::default())
            },
            transport: match self.transport {
                TransportArg::Diffuse => Transport::Diffuse,
                TransportArg::Full => Transport::Full,
            },
        }
    }
}

/// File name of the atlas (the light-mapped meshes with their light-map uvs as TEXCOORD_1).
pub const ATLAS_FILE: &str = "lightmap.glb";
/// File name of the updated scene file.
pub const SCENE_FILE: &str = "scene.toml";

/// Loads the scene and its light-map atlas: the one its scene file's `[lightmap]` names when
/// there is one and no `--texels-per-metre` asks for another, else
/// [`lustre_scene::lightmap::build_atlas`] (the scene's valid TEXCOORD_1, or generated charts). Writes the atlas .glb into `out`. The same inputs
/// give the same atlas, so shards and the merge may each call this.
pub fn prepare(args: &BakeArgs) -> anyhow::Result<(Scene, LightmapAtlas)> {
    let (scene, atlas) = load_atlas(args)?;
    crate::budget::check(&bake_budget(args, &scene, &atlas)?, args.force)?;
    let created = !args.out.exists();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let glb = args.out.join(ATLAS_FILE);
    if let Err(e) = write_atlas_glb(&scene, &atlas, &glb) {
        if created {
            // A folder this run made and could not fill is not left behind.
            let _ = std::fs::remove_dir_all(&args.out);
        }
        return Err(e).with_context(|| format!("writing {}", glb.display()));
    }
    Ok((scene, atlas))
}

/// The memory and disk of a bake, a shard or a merge of `atlas`: the tile files (a shard's
/// share of them), the page EXRs, and in memory the tile records of every thread (a bake) or of
/// every page with the denoiser's buffers (a merge).
fn bake_budget(
    args: &BakeArgs,
    scene: &Scene,
    atlas: &LightmapAtlas,
) -> anyhow::Result<lustre_brdf::budget::Budget> {
    use crate::budget::{BAKE_MERGE_TEXEL, BAKE_PAGE_TEXEL_DISK};
    use lustre_trace::bake::tile::RECORD;
    let texels = u64::from(atlas.width) * u64::from(atlas.height) * u64::from(atlas.pages);
    let shard = args.shard.resolve()?;
    let shards = shard.map_or(1, |(_, n)| n as u64);
    let threads = rayon::current_num_threads() as u64;
    let tile = u64::from(args.tile);
    let job = format!(
        "lustre bake of {} page(s) of {}×{} texels{}",
        atlas.pages,
        atlas.width,
        atlas.height,
        match shard {
            Some((k, n)) => format!(", shard {k}/{n}"),
            None if args.merge => ", merge".into(),
            None => String::new(),
        }
    );
    let mut b = crate::budget::scene(
        lustre_brdf::budget::Budget::new(job, "lower --texels-per-metre or --tile"),
        scene,
    );
    if !args.merge {
        b = b
            .memory("tiles in flight", threads * tile * tile, RECORD as u64)
            .disk(&args.out, "tile files", texels / shards, RECORD as u64);
    }
    if shard.is_none() {
        b = b
            .memory("pages and denoiser", texels, BAKE_MERGE_TEXEL)
            .disk(&args.out, "page EXRs", texels, BAKE_PAGE_TEXEL_DISK);
    }
    Ok(b)
}

/// The scene and its light-map atlas, as [`prepare`] finds them, writing nothing.
fn load_atlas(args: &BakeArgs) -> anyhow::Result<(Scene, LightmapAtlas)> {
    let mut scene =
        Scene::load(&args.scene).with_context(|| format!("loading {}", args.scene.display()))?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let existing = scene.lightmap.as_ref().map(|l| l.atlas.clone());
    let atlas = match existing {
        Some(a) if args.texels_per_metre.is_none() => {
            eprintln!(
                "atlas: the scene's own ({} page(s) of {}×{}, {} texels/m)",
                a.pages, a.width, a.height, a.texels_per_metre
            );
            a
        }
        _ => {
            let mut aopts = AtlasOptions::default();
            if args.max_texels == 0 {
                bail!("--max-texels 0: the light maps need at least one texel");
            }
            let start = match args.texels_per_metre {
                Some(d) if !(d.is_finite() && d > 0.0) => {
                    bail!("--texels-per-metre {d}: must be finite and > 0")
                }
                Some(d) => d,
                None => aopts.texels_per_metre,
            };
            let fit = fit_densities(&scene, start, args.max_texels);
            if fit.density < start {
                eprintln!(
                    "atlas: {} texels per scene unit, not {start}: the scene's surface is large \
                     in its units (--texels-per-metre and --max-texels choose)",
                    fit.density
                );
            }
            if let Some(&(m, d)) = fit.capped.first() {
                eprintln!(
                    "atlas: {} large mesh(es) at a coarser density of their own to stay within {} \
                     texels ({:?} at {d:.3} texels per unit; --max-texels chooses)",
                    fit.capped.len(),
                    args.max_texels,
                    scene.meshes[m].name
                );
            }
            for &(m, d) in &fit.capped {
                scene.meshes[m].hints.lightmap_texels_per_metre = Some(d);
            }
            aopts.texels_per_metre = fit.density;
            let bar = ProgressBar::new(0);
            bar.set_style(
                ProgressStyle::with_template("atlas: {msg} [{bar:30}] {pos}/{len}, {elapsed}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            let built = build_atlas_with_progress(&mut scene, &aopts, &|p| {
                bar.set_message(p.stage);
                bar.set_length(p.total.unwrap_or(p.done) as u64);
                bar.set_position(p.done as u64);
            });
            bar.finish_and_clear();
            let (atlas, r) =
                built.with_context(|| format!("light-map atlas of {}", args.scene.display()))?;
            eprintln!(
                "atlas: {:?}, {} charts on {} page(s) of {}×{}, {} meshes ({} skipped), {} triangles, utilisation {:.1} %, stretch L2 {:.3} / max {:.3}, {:.2} s",
                r.source,
                r.charts,
                r.pages,
                r.width,
                r.height,
                r.meshes,
                r.skipped_meshes,
                r.triangles,
                100.0 * r.utilisation,
                r.stretch_l2,
                r.stretch_max,
                r.time_s
            );
            for n in &r.notes {
                eprintln!("note: {n}");
            }
            atlas
        }
    };
    Ok((scene, atlas))
}

/// The automatic real-time set-up of `scene` (`lustre_trace::setup::auto_setup`), its report
/// printed.
pub fn decide_setup(scene: &Scene) -> anyhow::Result<Setup> {
    let (ps, _) = lustre_trace::reference::path_scene(scene)?;
    let tracer = PathTracer::new(&ps, PathOptions::default())?;
    let setup = auto_setup(scene, &tracer, &SetupOptions::default());
    println!("{}", setup.report);
    Ok(setup)
}

/// Writes `out/scene.toml`: the input scene (its scene file with absolute paths, or a file whose
/// geometry is the input) with a `[lightmap]` section naming the atlas and the baked pages,
/// and `setup`'s hints for the meshes the file has none for (its room probes when it lists
/// none).
pub fn write_scene_file(
    input: &Path,
    atlas: &LightmapAtlas,
    pages: &[PathBuf],
    out: &Path,
    setup: Option<&Setup>,
) -> anyhow::Result<PathBuf> {
    // Canonical (no `..`, no symlinks), so the scene file works from any directory and reads
    // cleanly; the input was just loaded, so it exists.
    let input_abs =
        std::fs::canonicalize(input).with_context(|| format!("resolving {}", input.display()))?;
    let is_toml = input
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    let base = if is_toml {
        let text = std::fs::read_to_string(input)
            .with_context(|| format!("reading {}", input.display()))?;
        let dir = input_abs.parent().unwrap_or(Path::new("/"));
        let mut f = scene_file::parse(input, &text)?.with_absolute_paths(dir);
        f.lightmap = None;
        f
    } else {
        SceneFile::for_geometry(&input_abs.to_string_lossy())
    };
    let names = pages
        .iter()
        .map(|p| {
            p.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        })
        .collect();
    let mut file = base.with_lightmap(ATLAS_FILE, names, atlas);
    if let Some(setup) = setup {
        for (name, hints) in &setup.objects {
            let entry = file.objects.entry(name.clone()).or_default();
            let thickness = entry.thickness.or(hints.thickness);
            if !has_realtime_hints(entry) {
                *entry = ObjectHints {
                    lightmap_texels_per_metre: entry.lightmap_texels_per_metre,
                    ..*hints
                };
            }
            entry.thickness = thickness;
        }
        if file.probes.is_empty() {
            file.probes = setup.probes.clone();
        }
    }
    let path = out.join(SCENE_FILE);
    scene_file::write(&path, &file).with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

/// Bakes the tiles of `shard` (all for `None`) with a progress bar over tiles; resumes from the
/// tiles already in `out/tiles/`.
pub fn bake_phase(
    scene: &Scene,
    atlas: &LightmapAtlas,
    opts: &BakeOptions,
    out: &Path,
    shard: Option<(u32, u32)>,
) -> anyhow::Result<()> {
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("baking [{bar:30}] {pos}/{len} tiles, {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let r = bake_tiles(scene, atlas, opts, out, shard, &|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })
    .with_context(|| format!("baking {}", scene.source.display()))?;
    bar.finish_and_clear();
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    let secs = r.trace_seconds.max(1e-9);
    println!(
        "tiles: {} ({} baked, {} resumed); {} texels, {} paths, {} invalid samples, {} zero-area triangles skipped; setup {:.2} s, trace {:.2} s ({:.0} texels/s, {:.0} paths/s)",
        r.tiles,
        r.baked,
        r.reused,
        r.texels,
        r.paths,
        r.invalid_samples,
        r.skipped_triangles,
        r.setup_seconds,
        r.trace_seconds,
        r.texels as f64 / secs,
        r.paths as f64 / secs
    );
    Ok(())
}

/// Assembles the tiles into the page EXRs and `bake.json`, and prints the per-page noise.
pub fn merge_phase(
    scene: &Scene,
    atlas: &LightmapAtlas,
    opts: &BakeOptions,
    out: &Path,
) -> anyhow::Result<Vec<PathBuf>> {
    let a = assemble(scene, atlas, opts, out)
        .with_context(|| format!("assembling the light maps in {}", out.display()))?;
    for p in &a.report.pages {
        println!(
            "page {}: {} covered texels ({} buried filled, {} unfilled, {} gutter texels dilated), mean E {:.4}, noise (std error) {:.4} = {:.2} %",
            p.page,
            p.covered_texels,
            p.buried_filled,
            p.buried_unfilled,
            p.dilated_texels,
            p.mean_irradiance,
            p.noise_std_error,
            100.0 * p.noise_relative
        );
    }
    println!(
        "assembly: fill {:.2} s, denoise {:.2} s, dilate + write {:.2} s",
        a.report.fill_seconds, a.report.denoise_seconds, a.report.write_seconds
    );
    Ok(a.files)
}

/// Runs `lustre bake`.
pub fn run(args: &BakeArgs) -> anyhow::Result<()> {
    bake(args).map(|_| ())
}

/// The most light-map texels a bake without `--texels-per-metre` covers the scene's surface
/// with: 2²⁴ (16 M texels; 192 MB of irradiance).
pub const DEFAULT_MAX_TEXELS: u64 = 1 << 24;

/// Light-map densities that fit a texel budget ([`fit_densities`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Densities {
    /// Texels per scene unit of the meshes without a density of their own.
    pub density: f32,
    /// Meshes given a coarser density of their own (mesh, texels per unit), largest first.
    pub capped: Vec<(usize, f32)>,
}

/// Light-map densities within `max_texels`: `start` texels per scene unit where the whole
/// surface fits. Else the largest meshes (without a density of their own) are capped to an
/// equal texel count C, chosen so that the scene fits exactly (water-filling: a room on a vast
/// ground plane keeps its density, the plane gets what is left), when at most a quarter of the
/// meshes need capping; otherwise (a scene in centimetres, where every mesh is large) `start`
/// is halved and the same tried again.
pub fn fit_densities(scene: &Scene, start: f32, max_texels: u64) -> Densities {
    let budget = max_texels as f64;
    let mut d = start;
    loop {
        let d2 = f64::from(d) * f64::from(d);
        let mut fixed = 0.0;
        let mut free: Vec<(f64, usize)> = vec![];
        for (i, m) in scene.meshes.iter().enumerate() {
            match m.hints.lightmap_texels_per_metre {
                Some(h) => fixed += m.area() * f64::from(h) * f64::from(h),
                None => free.push((m.area() * d2, i)),
            }
        }
        let total: f64 = fixed + free.iter().map(|f| f.0).sum::<f64>();
        if total <= budget || d <= f32::MIN_POSITIVE {
            return Densities {
                density: d,
                capped: vec![],
            };
        }
        free.sort_by(|a, b| b.0.total_cmp(&a.0));
        // Cap the k largest at C = (budget − fixed − the rest) / k, where C lies between the
        // k-th and the (k+1)-th need.
        let mut rest: f64 = free.iter().map(|f| f.0).sum();
        for k in 1..=(free.len() / 4).max(1).min(free.len()) {
            rest -= free[k - 1].0;
            let c = (budget - fixed - rest) / k as f64;
            let next = free.get(k).map_or(0.0, |f| f.0);
            if c >= next && c > 0.0 && c < free[k - 1].0 {
                let capped = free[..k]
                    .iter()
                    // Rounded down to f32 (less 10⁻⁶) so that the scene stays within.
                    .map(|&(need, i)| (i, (f64::from(d) * (c / need).sqrt() * (1.0 - 1e-6)) as f32))
                    .filter(|&(_, h)| h > 0.0)
                    .collect();
                return Densities { density: d, capped };
            }
        }
        d /= 2.0;
    }
}

/// `lustre bake`: returns the scene file written (`None` for a shard, which writes none).
pub fn bake(args: &BakeArgs) -> anyhow::Result<Option<PathBuf>> {
    let opts = args.options();
    opts.validate().context("bake settings")?;
    let shard = match args.shard.resolve()? {
        Some((k, n)) => {
            let k = u32::try_from(k).context("shard index")?;
            let n = u32::try_from(n).context("shard count")?;
            Some((k, n))
        }
        None => None,
    };
    if args.plan {
        let (scene, atlas) = load_atlas(args)?;
        let tiles = check_shard_tiles(&atlas, &opts, shard)
            .with_context(|| format!("planning {}", args.scene.display()))?;
        println!("budget: {}", bake_budget(args, &scene, &atlas)?.summary());
        println!(
            "plan: {} page(s) of {}×{} texels in {tiles} tiles of {}² texels: at most {tiles} \
             shards{}",
            atlas.pages,
            atlas.width,
            atlas.height,
            opts.tile,
            shard.map_or(String::new(), |(k, n)| format!("; shard {k}/{n} is valid"))
        );
        return Ok(None);
    }
    let (scene, atlas) = prepare(args)?;
    if !args.merge {
        bake_phase(&scene, &atlas, &opts, &args.out, shard)?;
    }
    if let Some((k, n)) = shard {
        println!(
            "shard {k}/{n} done; when all {n} are: lustre bake {} --out {} (same options) --merge",
            args.scene.display(),
            args.out.display()
        );
        return Ok(None);
    }
    let files = merge_phase(&scene, &atlas, &opts, &args.out)?;
    for f in &files {
        println!("wrote {}", f.display());
    }
    let setup = match args.setup {
        SetupArg::Auto => Some(decide_setup(&scene)?),
        SetupArg::Manual => None,
    };
    let scene_path = write_scene_file(&args.scene, &atlas, &files, &args.out, setup.as_ref())?;
    println!(
        "wrote {} and {}",
        args.out.join(ATLAS_FILE).display(),
        scene_path.display()
    );
    Ok(Some(scene_path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat4, DVec3};
    use lustre_scene::mesh;

    /// A scene of `sides` squares, side lengths in scene units.
    fn squares(sides: &[f64]) -> Scene {
        let mut s = Scene::new("squares");
        for (i, &a) in sides.iter().enumerate() {
            let mut m = mesh::rectangle(&format!("square-{i}"), 0);
            m.transform(&DMat4::from_scale(DVec3::splat(0.5 * a)));
            s.meshes.push(m);
        }
        s
    }

    fn texels(s: &Scene, f: &Densities) -> f64 {
        s.meshes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let d = f
                    .capped
                    .iter()
                    .find(|c| c.0 == i)
                    .map_or(f.density, |c| c.1);
                m.area() * f64::from(d) * f64::from(d)
            })
            .sum()
    }

    #[test]
    fn a_vast_ground_plane_is_capped_and_the_room_keeps_its_density() {
        // Eight 4-unit walls (16 each) and a 2000-unit ground: at 16 texels per unit the walls
        // need 8 · 4096 texels, the ground 1.02 G.
        let mut sides = vec![4.0; 8];
        sides.push(2000.0);
        let s = squares(&sides);
        let f = fit_densities(&s, 16.0, 1 << 20);
        assert_eq!(f.density, 16.0);
        assert_eq!(f.capped.len(), 1);
        assert_eq!(f.capped[0].0, 8);
        let t = texels(&s, &f);
        assert!(t <= (1 << 20) as f64 && t > 0.99 * (1 << 20) as f64, "{t}");
        // The ground gets what the walls leave: (2²⁰ − 8·4096) texels over 4·10⁶ units².
        let expect = (((1u64 << 20) - 8 * 4096) as f64 / 4e6).sqrt();
        assert!(
            (f64::from(f.capped[0].1) - expect).abs() < 1e-3,
            "{:?}",
            f.capped
        );
        // Within the budget nothing changes.
        let small = squares(&[4.0; 8]);
        assert_eq!(
            fit_densities(&small, 16.0, 1 << 20),
            Densities {
                density: 16.0,
                capped: vec![]
            }
        );
    }

    #[test]
    fn a_scene_in_centimetres_halves_the_density() {
        // Every mesh large (a scene in centimetres): capping a quarter cannot fit; halved.
        let s = squares(&[400.0; 8]);
        let f = fit_densities(&s, 16.0, 1 << 20);
        assert!(f.capped.is_empty(), "{f:?}");
        assert!(f.density < 16.0);
        assert!(texels(&s, &f) <= (1 << 20) as f64);
        assert!(
            texels(
                &s,
                &Densities {
                    density: 2.0 * f.density,
                    capped: vec![]
                }
            ) > (1 << 20) as f64
        );
    }
}
