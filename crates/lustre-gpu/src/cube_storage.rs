//! Cube-map pyramids in storage buffers, for `wgsl/cube_storage.wgsl`: every level's texels,
//! the level records, and per level and face the texels one texel beyond the edges (the rings,
//! from [`lustre_env::cube::fetch_sources`]) so that bilinear lookups cross edges as
//! `CubeMap::bilinear` does.

use lustre_env::cube::fetch_sources;
use lustre_env::CubePyramid;

/// The texels one texel beyond the edges of a face of size n (`cube_storage.wgsl`'s
/// `ring_index` order), as global indices of the level starting at texel `first`.
pub(crate) fn ring_entries(n: usize, first: u32, out: &mut Vec<[i32; 4]>) {
    let nn = n as i64;
    let mut positions = vec![];
    for j in [-1, nn] {
        for i in -1..=nn {
            positions.push((i, j));
        }
    }
    for i in [-1, nn] {
        for j in 0..nn {
            positions.push((i, j));
        }
    }
    for face in 0..6 {
        for &(i, j) in &positions {
            let (src, count) = fetch_sources(n, face, i, j);
            let idx = src.map(|(f, a, b)| (first as usize + (f * n + b) * n + a) as i32);
            out.push([idx[0], idx[1], idx[2], count as i32]);
        }
    }
}

/// A CPU pyramid's words for `cube_storage.wgsl`: its texels (RGB, w = 0), its level records
/// (first texel, face size, first ring entry, 0) and its rings.
pub struct PackedPyramid {
    /// Every level's texels, face-major, row-major.
    pub texels: Vec<[f32; 4]>,
    /// Per level: first texel, face size, first ring entry, 0.
    pub levels: Vec<[u32; 4]>,
    /// The rings of every level.
    pub ring: Vec<[i32; 4]>,
}

/// Packs `p` (its levels from the base up).
pub fn pack_pyramid(p: &CubePyramid) -> PackedPyramid {
    let mut out = PackedPyramid {
        texels: vec![],
        levels: vec![],
        ring: vec![],
    };
    for m in &p.levels {
        let first = out.texels.len() as u32;
        out.levels
            .push([first, m.size as u32, out.ring.len() as u32, 0]);
        for face in &m.faces {
            out.texels
                .extend(face.iter().map(|t| [t[0], t[1], t[2], 0.0]));
        }
        ring_entries(m.size, first, &mut out.ring);
    }
    out
}
