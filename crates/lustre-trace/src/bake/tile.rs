//! Tiles: the unit of baking, resuming and sharding.
//!
//! Tile k (pages in order, tiles of [`super::BakeOptions::tile`]² texels row-major within a page;
//! edge tiles are smaller) is stored in `OUT/tiles/page{P}_tile{K}.bin`, written atomically:
//!
//! ```text
//! magic "LBAKTIL1" | hash u64 | page u32 | tile u32 | x0 u32 | y0 u32 | w u32 | h u32
//! | w·h texel records (17 × u32/f32 each, row-major) | CRC-32 of everything before it
//! ```
//! (little-endian; the hash is [`super::bake_hash`]). A file whose size, magic, CRC, rectangle
//! or hash is wrong is reported (named) and baked again.

use super::raster::Raster;
use super::trace::{TexelBaker, TexelRecord};
use super::{bake_hash, diffuse_path_scene, BakeOptions};
use crate::path_tracer::{PathOptions, PathTracer};
use crate::{Result, TraceError};
use lustre_scene::lightmap::LightmapAtlas;
use lustre_scene::Scene;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// First bytes of a tile file (the format version is its last character).
pub const MAGIC: &[u8; 8] = b"LBAKTIL1";
const HEADER: usize = 8 + 8 + 6 * 4;
/// Bytes of one texel record in a tile file (17 little-endian 4-byte values).
pub const RECORD: usize = 17 * 4;

/// A tile: its global index, page and texel rectangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileRect {
    /// Global index (pages in order, row-major within a page).
    pub index: u32,
    /// Page.
    pub page: u32,
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// Width in texels.
    pub w: u32,
    /// Height in texels.
    pub h: u32,
}

/// Every tile of an atlas, in index order.
pub fn tiles(atlas: &LightmapAtlas, tile: u32) -> Vec<TileRect> {
    let (tx, ty) = (atlas.width.div_ceil(tile), atlas.height.div_ceil(tile));
    let mut out = vec![];
    for page in 0..atlas.pages {
        for j in 0..ty {
            for i in 0..tx {
                let (x0, y0) = (i * tile, j * tile);
                out.push(TileRect {
                    index: out.len() as u32,
                    page,
                    x0,
                    y0,
                    w: tile.min(atlas.width - x0),
                    h: tile.min(atlas.height - y0),
                });
            }
        }
    }
    out
}

/// The file of tile `r` under `out_dir`.
pub fn tile_path(out_dir: &Path, r: &TileRect) -> PathBuf {
    out_dir
        .join("tiles")
        .join(format!("page{}_tile{:05}.bin", r.page, r.index))
}

/// The bytes of a tile file.
pub fn encode(hash: u64, r: &TileRect, texels: &[TexelRecord]) -> Vec<u8> {
    let mut b = Vec::with_capacity(HEADER + texels.len() * RECORD + 4);
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&hash.to_le_bytes());
    for v in [r.page, r.index, r.x0, r.y0, r.w, r.h] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for t in texels {
        let f = |b: &mut Vec<u8>, v: &[f32; 3]| {
            for c in v {
                b.extend_from_slice(&c.to_le_bytes());
            }
        };
        f(&mut b, &t.e);
        f(&mut b, &t.var);
        b.extend_from_slice(&t.valid.to_le_bytes());
        b.extend_from_slice(&t.chart.to_le_bytes());
        f(&mut b, &t.position);
        f(&mut b, &t.normal);
        f(&mut b, &t.albedo);
    }
    let crc = crc32fast::hash(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

/// Reads a tile file's bytes back; `Err` says what is wrong with it.
pub fn decode(
    bytes: &[u8],
    hash: u64,
    r: &TileRect,
) -> std::result::Result<Vec<TexelRecord>, String> {
    let n = (r.w * r.h) as usize;
    let want = HEADER + n * RECORD + 4;
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        return Err("not a lustre bake tile (bad magic or truncated header)".into());
    }
    let u32_at =
        |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let h = u64::from_le_bytes([
        bytes[8], bytes[9], bytes[10], bytes[11], bytes[12], bytes[13], bytes[14], bytes[15],
    ]);
    if h != hash {
        return Err(format!(
            "baked for another scene or other settings (hash {h:016x}, expected {hash:016x})"
        ));
    }
    let hdr = [16, 20, 24, 28, 32, 36].map(u32_at);
    if hdr != [r.page, r.index, r.x0, r.y0, r.w, r.h] {
        return Err(format!(
            "holds page {} tile {} at ({}, {}) {}×{}, expected page {} tile {} at ({}, {}) {}×{}",
            hdr[0], hdr[1], hdr[2], hdr[3], hdr[4], hdr[5], r.page, r.index, r.x0, r.y0, r.w, r.h
        ));
    }
    if bytes.len() != want {
        return Err(format!(
            "{} bytes, expected {want} (truncated?)",
            bytes.len()
        ));
    }
    let crc = u32_at(want - 4);
    if crc32fast::hash(&bytes[..want - 4]) != crc {
        return Err("checksum mismatch (corrupt)".into());
    }
    let f = |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let v3 = |o: usize| [f(o), f(o + 4), f(o + 8)];
    Ok((0..n)
        .map(|k| {
            let o = HEADER + k * RECORD;
            TexelRecord {
                e: v3(o),
                var: v3(o + 12),
                valid: u32_at(o + 24),
                chart: u32_at(o + 28),
                position: v3(o + 32),
                normal: v3(o + 44),
                albedo: v3(o + 56),
            }
        })
        .collect())
}

/// Reads tile `r` from `out_dir`: `Ok(None)` when the file does not exist, `Err(reason)` when
/// it is unreadable, corrupt or mismatched.
pub fn read_tile(
    out_dir: &Path,
    hash: u64,
    r: &TileRect,
) -> std::result::Result<Option<Vec<TexelRecord>>, String> {
    let path = tile_path(out_dir, r);
    match std::fs::read(&path) {
        Ok(b) => decode(&b, hash, r).map(Some),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e.to_string()),
    }
}

/// What [`bake_tiles`] did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TilesReport {
    /// Tiles of this shard.
    pub tiles: usize,
    /// Tiles baked now.
    pub baked: usize,
    /// Tiles found complete on disk (resumed).
    pub reused: usize,
    /// Texels covered by a chart in the tiles baked now.
    pub texels: u64,
    /// Paths traced (valid samples) in the tiles baked now.
    pub paths: u64,
    /// Samples found invalid (under or inside geometry).
    pub invalid_samples: u64,
    /// Light-mapped triangles skipped for a zero area.
    pub skipped_triangles: usize,
    /// Seconds building the BVH, the diffuse scene and the coverage.
    pub setup_seconds: f64,
    /// Seconds tracing.
    pub trace_seconds: f64,
    /// Problems met (corrupt or mismatched tiles re-baked, material approximations).
    pub warnings: Vec<String>,
}

/// Checks a `(K, N)` shard.
pub fn check_shard(shard: Option<(u32, u32)>) -> Result<()> {
    match shard {
        Some((k, n)) if n == 0 || k >= n => Err(TraceError::Parameter(format!(
            "shard {k}/{n}: need 0 ≤ K < N"
        ))),
        _ => Ok(()),
    }
}

/// Bakes the tiles of `shard` (`Some((K, N))`: the tiles whose index mod N is K; `None`: all)
/// that `out_dir/tiles/` does not already hold intact, writing each atomically as it finishes.
/// `progress(done, total)` after each tile of the shard (reused ones included). Errors: bad
/// options or shard, an atlas that does not fit the scene, a scene without light, I/O.
pub fn bake_tiles(
    scene: &Scene,
    atlas: &LightmapAtlas,
    opts: &BakeOptions,
    out_dir: &Path,
    shard: Option<(u32, u32)>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<TilesReport> {
    let t0 = Instant::now();
    check_shard_tiles(atlas, opts, shard)?;
    let dir = out_dir.join("tiles");
    std::fs::create_dir_all(&dir).map_err(|e| TraceError::Io {
        path: dir.clone(),
        source: e,
    })?;
    // One process per shard: a resubmitted task while the first still runs is refused.
    let (lock, what) = match shard {
        Some((k, n)) => (
            dir.join(format!("shard-{k}-of-{n}.lock")),
            format!("shard {k}/{n}"),
        ),
        None => (dir.join("all.lock"), "the bake".to_string()),
    };
    let _held = lustre_brdf::error::lock_output(&lock, &what)?;
    let hash = bake_hash(scene, atlas, opts);
    with_baker(scene, atlas, opts, |baker, warnings| {
        bake_tiles_with(baker, warnings, atlas, out_dir, shard, hash, t0, progress)
    })
}

/// Checks the options and a `(K, N)` shard against the atlas's tiles; returns the number of
/// tiles (the most shards a bake splits into). More shards than tiles is an error: the extra
/// shards would bake nothing.
pub fn check_shard_tiles(
    atlas: &LightmapAtlas,
    opts: &BakeOptions,
    shard: Option<(u32, u32)>,
) -> Result<usize> {
    check_shard(shard)?;
    opts.validate()?;
    let all = tiles(atlas, opts.tile).len();
    if let Some((_, n)) = shard.filter(|&(_, n)| n as usize > all) {
        return Err(TraceError::Parameter(format!(
            "{n} shards for {all} tiles: shards {all} to {} would bake nothing; use at most {all} \
             shards (or smaller tiles)",
            n - 1
        )));
    }
    Ok(all)
}

/// Refuses while a process bakes tiles into `out_dir` (a shard or a whole bake holds its lock
/// in `out_dir/tiles/`), and holds the merge's own lock: the guard to keep while assembling.
pub(super) fn lock_merge(out_dir: &Path) -> Result<lustre_brdf::error::OutputLock> {
    let dir = out_dir.join("tiles");
    let io = |e| TraceError::Io {
        path: dir.clone(),
        source: e,
    };
    std::fs::create_dir_all(&dir).map_err(io)?;
    if let Some((l, holder)) = lustre_brdf::error::held_shard_lock(&dir)? {
        return Err(TraceError::Parameter(format!(
            "{}: still baking ({holder}); merge once every shard has finished",
            l.display()
        )));
    }
    Ok(lustre_brdf::error::lock_output(
        &dir.join("merge.lock"),
        "the merge",
    )?)
}

/// Sets up the path tracer and coverage of a bake and hands the per-texel estimator to `f`
/// with the scene's warnings.
fn with_baker<R>(
    scene: &Scene,
    atlas: &LightmapAtlas,
    opts: &BakeOptions,
    f: impl FnOnce(&TexelBaker, Vec<String>) -> Result<R>,
) -> Result<R> {
    opts.validate()?;
    let (ps, bases, warnings) = diffuse_path_scene(scene)?;
    let ps = match opts.transport {
        super::Transport::Diffuse => ps,
        super::Transport::Full => crate::reference::path_scene(scene)?.0,
    };
    let pt = PathTracer::new(
        &ps,
        PathOptions {
            max_depth: opts.bounces + 1,
            ..PathOptions::default()
        },
    )?;
    let raster = Raster::new(scene, atlas, opts.tile)?;
    let baker = TexelBaker {
        scene,
        ps: &ps,
        pt: &pt,
        raster: &raster,
        bases: &bases,
        opts,
    };
    f(&baker, warnings)
}

/// Bakes the listed texels `(page, x, y)` of `atlas` with `opts` as [`bake_tiles`] would (the
/// same seeds, so the same records), writing nothing: for checks and tools that need a few
/// texels, e.g. at another spp. Errors: as [`bake_tiles`], and a texel outside the atlas.
pub fn bake_texels(
    scene: &Scene,
    atlas: &LightmapAtlas,
    opts: &BakeOptions,
    texels: &[(u32, u32, u32)],
) -> Result<Vec<TexelRecord>> {
    if let Some(&(p, x, y)) = texels
        .iter()
        .find(|&&(p, x, y)| p >= atlas.pages || x >= atlas.width || y >= atlas.height)
    {
        return Err(TraceError::Parameter(format!(
            "texel ({x}, {y}) of page {p} is outside the {}×{} × {} atlas",
            atlas.width, atlas.height, atlas.pages
        )));
    }
    with_baker(scene, atlas, opts, |baker, _| {
        Ok(texels
            .par_iter()
            .map(|&(p, x, y)| baker.texel(p, x, y).0)
            .collect())
    })
}

#[allow(clippy::too_many_arguments)]
fn bake_tiles_with(
    baker: &TexelBaker,
    warnings: Vec<String>,
    atlas: &LightmapAtlas,
    out_dir: &Path,
    shard: Option<(u32, u32)>,
    hash: u64,
    t0: Instant,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<TilesReport> {
    let opts = baker.opts;
    let mine: Vec<TileRect> = tiles(atlas, opts.tile)
        .into_iter()
        .filter(|r| shard.is_none_or(|(k, n)| r.index % n == k))
        .collect();
    let mut report = TilesReport {
        tiles: mine.len(),
        skipped_triangles: baker.raster.skipped,
        warnings,
        setup_seconds: t0.elapsed().as_secs_f64(),
        ..TilesReport::default()
    };
    let t1 = Instant::now();
    // Tiles of another bake (other scene or options) or damaged ones: baked again, reported once.
    let mut rebaked: Vec<String> = Vec::new();
    for (done, r) in mine.iter().enumerate() {
        match read_tile(out_dir, hash, r) {
            Ok(Some(_)) => {
                report.reused += 1;
                progress(done + 1, mine.len());
                continue;
            }
            Ok(None) => {}
            Err(why) => rebaked.push(format!("{}: {why}", tile_path(out_dir, r).display())),
        }
        let texels: Vec<_> = (0..r.w * r.h)
            .into_par_iter()
            .map(|k| baker.texel(r.page, r.x0 + k % r.w, r.y0 + k / r.w))
            .collect();
        for (t, c) in &texels {
            if t.covered() {
                report.texels += 1;
            }
            report.paths += c.samples - c.invalid;
            report.invalid_samples += c.invalid;
        }
        let recs: Vec<TexelRecord> = texels.into_iter().map(|(t, _)| t).collect();
        let path = tile_path(out_dir, r);
        lustre_brdf::error::write_atomic(&path, &encode(hash, r, &recs))?;
        report.baked += 1;
        progress(done + 1, mine.len());
    }
    report.trace_seconds = t1.elapsed().as_secs_f64();
    if !rebaked.is_empty() {
        let shown: Vec<&str> = rebaked.iter().take(3).map(String::as_str).collect();
        let more = rebaked.len() - shown.len();
        report.warnings.push(format!(
            "{} tile(s) made by another bake (other scene or options) or damaged, baked again: \
             {}{}",
            rebaked.len(),
            shown.join("; "),
            if more > 0 {
                format!("; and {more} more")
            } else {
                String::new()
            }
        ));
    }
    Ok(report)
}
