//! Assembling the tiles into pages: buried fill, denoise, dilation, half-float EXR, report.

use super::denoise::{atrous, Denoiser};
use super::fill::PageBuffer;
use super::tile::{lock_merge, read_tile, tile_path, tiles};
use super::trace::TexelRecord;
use super::{bake_hash, check_atlas, BakeOptions};
use crate::{Result, TraceError};
use lustre_scene::lightmap::LightmapAtlas;
use lustre_scene::Scene;
use serde::{Deserialize, Serialize};
use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// File name of page `p`'s EXR in the output folder.
pub fn page_file_name(p: u32) -> String {
    format!("lightmap_{p:03}.exr")
}

/// Name of the report in the output folder.
pub const REPORT_FILE: &str = "bake.json";

/// Per-page figures of an assembled bake.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PageReport {
    /// Page index.
    pub page: u32,
    /// The EXR (file name in the output folder).
    pub file: String,
    /// Texels covered by a chart.
    pub covered_texels: u64,
    /// Covered texels with no valid sample (under or inside geometry), filled from neighbours.
    pub buried_filled: u64,
    /// Buried texels that could not be filled (their chart has no valid texel; left black).
    pub buried_unfilled: u64,
    /// Gutter texels written by dilation.
    pub dilated_texels: u64,
    /// Mean luminance of the irradiance over the valid texels (before denoising).
    pub mean_irradiance: f64,
    /// Noise: the mean over valid texels of the standard error of the texel's mean luminance
    /// (√(sample variance / samples)), before denoising.
    pub noise_std_error: f64,
    /// `noise_std_error / mean_irradiance`.
    pub noise_relative: f64,
}

/// What [`assemble`] wrote into `OUT/bake.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakeReport {
    /// The scene file.
    pub scene: String,
    /// Fingerprint of the scene and settings ([`super::bake_hash`]), hex.
    pub hash: String,
    /// Samples per texel.
    pub spp: u32,
    /// Diffuse bounces.
    pub bounces: u32,
    /// Seed.
    pub seed: u64,
    /// Tile side.
    pub tile: u32,
    /// Page size and count.
    pub width: u32,
    /// Page height.
    pub height: u32,
    /// The denoiser (Debug form of [`Denoiser`]).
    pub denoiser: String,
    /// Per page.
    pub pages: Vec<PageReport>,
    /// Seconds reading tiles and filling buried texels.
    pub fill_seconds: f64,
    /// Seconds denoising.
    pub denoise_seconds: f64,
    /// Seconds dilating and writing the EXRs.
    pub write_seconds: f64,
}

/// An assembled bake in memory.
#[derive(Clone, Debug)]
pub struct Assembled {
    /// Per page: the final irradiance (filled, denoised, dilated), row-major.
    pub pages: Vec<Vec<[f32; 3]>>,
    /// Per page: the raw texel records of the tiles.
    pub texels: Vec<Vec<TexelRecord>>,
    /// The report written beside the pages.
    pub report: BakeReport,
    /// The EXR files written, per page.
    pub files: Vec<PathBuf>,
}

/// Encodes an RGB page as an OpenEXR file of half floats (the `exr` crate).
pub fn encode_exr_half(width: u32, height: u32, e: &[[f32; 3]]) -> Result<Vec<u8>> {
    use exr::prelude::*;
    let (w, h) = (width as usize, height as usize);
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = e[y * w + x];
        (
            f16::from_f32(p[0]),
            f16::from_f32(p[1]),
            f16::from_f32(p[2]),
        )
    });
    let image = Image::from_channels((w, h), channels);
    let mut bytes = Vec::new();
    image
        .write()
        // Blocks compressed in parallel are written in the order they finish: the same pixels,
        // other bytes. One thread keeps a page byte-identical across runs, shards and resumes.
        .non_parallel()
        .to_buffered(Cursor::new(&mut bytes))
        .map_err(|e| TraceError::Parameter(format!("EXR encoding: {e}")))?;
    Ok(bytes)
}

/// Assembles a bake whose tiles are all in `out_dir/tiles/` (baked by [`super::bake_tiles`],
/// in one run or in shards): reads every tile, fills buried texels, denoises with
/// `opts.denoiser`, dilates the charts by the atlas gutter, and writes (atomically) one
/// half-float EXR per page ([`page_file_name`]) and `bake.json`. Idempotent: an interrupted
/// assembly is simply run again. Errors: missing tiles (counted, the first named), a corrupt or
/// mismatched tile (named), I/O.
pub fn assemble(
    scene: &Scene,
    atlas: &LightmapAtlas,
    opts: &BakeOptions,
    out_dir: &Path,
) -> Result<Assembled> {
    opts.validate()?;
    check_atlas(scene, atlas)?;
    let _held = lock_merge(out_dir)?;
    let t0 = Instant::now();
    let hash = bake_hash(scene, atlas, opts);
    let (w, h) = (atlas.width, atlas.height);
    let n = (w * h) as usize;
    let mut texels = vec![vec![TexelRecord::default(); n]; atlas.pages as usize];
    let mut missing = vec![];
    for r in tiles(atlas, opts.tile) {
        match read_tile(out_dir, hash, &r) {
            Ok(Some(recs)) => {
                for (k, rec) in recs.into_iter().enumerate() {
                    let (x, y) = (r.x0 + k as u32 % r.w, r.y0 + k as u32 / r.w);
                    texels[r.page as usize][(y * w + x) as usize] = rec;
                }
            }
            Ok(None) => missing.push(tile_path(out_dir, &r)),
            Err(why) => {
                return Err(TraceError::Parameter(format!(
                    "{}: {why} (bake it again)",
                    tile_path(out_dir, &r).display()
                )))
            }
        }
    }
    if let Some(first) = missing.first() {
        return Err(TraceError::Parameter(format!(
            "{} tiles are not baked yet (first: {}); bake every shard before assembling",
            missing.len(),
            first.display()
        )));
    }
    let mut report = BakeReport {
        scene: scene.source.display().to_string(),
        hash: format!("{hash:016x}"),
        spp: opts.spp,
        bounces: opts.bounces,
        seed: opts.seed,
        tile: opts.tile,
        width: w,
        height: h,
        denoiser: format!("{:?}", opts.denoiser),
        pages: vec![],
        fill_seconds: t0.elapsed().as_secs_f64(),
        denoise_seconds: 0.0,
        write_seconds: 0.0,
    };
    let mut pages = vec![];
    let mut files = vec![];
    for (p, recs) in texels.iter().enumerate() {
        let t_fill = Instant::now();
        let mut buf = PageBuffer {
            width: w,
            height: h,
            e: recs.iter().map(|r| r.e).collect(),
            chart: recs.iter().map(|r| r.chart).collect(),
            known: recs.iter().map(|r| r.covered() && r.valid > 0).collect(),
        };
        let covered = recs.iter().filter(|r| r.covered()).count() as u64;
        let buried = recs.iter().filter(|r| r.covered() && r.valid == 0).count() as u64;
        let filled = buf.fill_buried() as u64;
        let valid: Vec<&TexelRecord> = recs.iter().filter(|r| r.valid > 0).collect();
        let lum = |e: [f32; 3]| {
            0.2126 * f64::from(e[0]) + 0.7152 * f64::from(e[1]) + 0.0722 * f64::from(e[2])
        };
        let var: Vec<f64> = recs.iter().map(|r| lum_var(r.var)).collect();
        let nv = valid.len().max(1) as f64;
        let mean = valid.iter().map(|r| lum(r.e)).sum::<f64>() / nv;
        let sem = valid.iter().map(|r| lum_var(r.var).sqrt()).sum::<f64>() / nv;
        report.fill_seconds += t_fill.elapsed().as_secs_f64();
        let t_dn = Instant::now();
        if let Denoiser::ATrous(o) = &opts.denoiser {
            atrous(&mut buf, recs, &var, o);
        }
        report.denoise_seconds += t_dn.elapsed().as_secs_f64();
        let t_w = Instant::now();
        let dilated = buf.dilate(atlas.gutter.max(1)) as u64;
        let file = page_file_name(p as u32);
        let path = out_dir.join(&file);
        lustre_brdf::error::write_atomic(&path, &encode_exr_half(w, h, &buf.e)?)?;
        report.write_seconds += t_w.elapsed().as_secs_f64();
        report.pages.push(PageReport {
            page: p as u32,
            file,
            covered_texels: covered,
            buried_filled: filled,
            buried_unfilled: buried - filled,
            dilated_texels: dilated,
            mean_irradiance: mean,
            noise_std_error: sem,
            noise_relative: if mean > 0.0 { sem / mean } else { 0.0 },
        });
        files.push(path);
        pages.push(buf.e);
    }
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| TraceError::Parameter(format!("report: {e}")))?;
    lustre_brdf::error::write_atomic(&out_dir.join(REPORT_FILE), json.as_bytes())?;
    Ok(Assembled {
        pages,
        texels,
        report,
        files,
    })
}

/// Variance of the luminance of a mean with per-channel variances `v`: (Σ k_c σ_c)², exact for
/// fully correlated channels (white light) and an upper bound otherwise (Cauchy–Schwarz).
fn lum_var(v: [f32; 3]) -> f64 {
    let k = [0.2126f64, 0.7152, 0.0722];
    (0..3)
        .map(|c| k[c] * f64::from(v[c]).max(0.0).sqrt())
        .sum::<f64>()
        .powi(2)
}
