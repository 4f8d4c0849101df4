//! Texel coverage in light-map uv space and the supersample points of a texel.
//!
//! uv1 follows [`lustre_scene::lightmap`]: texel (x, y) of a W×H page covers
//! [x, x+1] × [y, y+1] in texel units (u·W, v·H). A triangle covers a texel when they overlap
//! (separating-axis test: the square's two axes and the triangle's three edge normals), so
//! texels that a chart only grazes are baked too (conservative rasterisation). Each covered texel
//! belongs to one chart (that of the lowest-numbered triangle containing its centre, else of the
//! lowest-numbered one overlapping it), and its samples land only on that chart's triangles.
//!
//! Charts are the connected components of a mesh's triangles, joined where they share a uv1
//! coordinate (bit for bit).

use crate::{Result, TraceError};
use lustre_brdf::sampling::SplitMix64;
use lustre_scene::lightmap::LightmapAtlas;
use lustre_scene::Scene;
use std::collections::HashMap;

/// A light-mapped triangle in texel units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelTriangle {
    /// Index of the triangle in scene order (meshes in order, their triangles in order), as in
    /// the path tracer's geometry.
    pub prim: u32,
    /// Page.
    pub page: u32,
    /// Chart id (global).
    pub chart: u32,
    /// Corners in texel units (u·W, v·H).
    pub uv: [[f64; 2]; 3],
    /// World size of one texel on this triangle: √(world area / area in texels).
    pub texel_size: f64,
}

/// A sample position on a texel: the triangle and the barycentric weights of its corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplePoint {
    /// Index into [`Raster::triangles`].
    pub tri: u32,
    /// Barycentric weights.
    pub bary: [f64; 3],
    /// The sample's position in texel units (before any snap onto the triangle).
    pub uv: [f64; 2],
}

/// The light-mapped triangles, binned by tile.
#[derive(Clone, Debug)]
pub struct Raster {
    /// Page width.
    pub width: u32,
    /// Page height.
    pub height: u32,
    /// Pages.
    pub pages: u32,
    /// Tile side.
    pub tile: u32,
    /// Light-mapped triangles with a non-zero area in texels.
    pub triangles: Vec<TexelTriangle>,
    /// Number of charts.
    pub charts: u32,
    /// Triangles of light-mapped meshes skipped for a zero area (in texels or in the world).
    pub skipped: usize,
    /// Per tile (pages in order, tiles row-major): indices into `triangles` overlapping it.
    bins: Vec<Vec<u32>>,
}

fn find(parent: &mut [u32], mut a: u32) -> u32 {
    while parent[a as usize] != a {
        parent[a as usize] = parent[parent[a as usize] as usize];
        a = parent[a as usize];
    }
    a
}

/// Signed doubled area of (a, b, c).
fn cross2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether triangle `t` and the box [x0, x1] × [y0, y1] overlap with a positive area.
pub fn overlaps(t: &[[f64; 2]; 3], x0: f64, y0: f64, x1: f64, y1: f64) -> bool {
    let (lo_x, hi_x) = minmax(t.iter().map(|p| p[0]));
    let (lo_y, hi_y) = minmax(t.iter().map(|p| p[1]));
    if hi_x <= x0 || lo_x >= x1 || hi_y <= y0 || lo_y >= y1 {
        return false;
    }
    let s = cross2(t[0], t[1], t[2]).signum();
    let corners = [[x0, y0], [x1, y0], [x0, y1], [x1, y1]];
    for e in 0..3 {
        let (a, b) = (t[e], t[(e + 1) % 3]);
        // All four corners outside or on this edge: no overlap of positive area.
        if corners.iter().all(|&c| s * cross2(a, b, c) <= 0.0) {
            return false;
        }
    }
    true
}

fn minmax(it: impl Iterator<Item = f64>) -> (f64, f64) {
    it.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// Barycentric weights of `q` in `t` (any sign), or `None` for a degenerate triangle.
fn bary(t: &[[f64; 2]; 3], q: [f64; 2]) -> Option<[f64; 3]> {
    let area = cross2(t[0], t[1], t[2]);
    if area == 0.0 || !area.is_finite() {
        return None;
    }
    let b0 = cross2(t[1], t[2], q) / area;
    let b1 = cross2(t[2], t[0], q) / area;
    Some([b0, b1, 1.0 - b0 - b1])
}

/// The point of `t` nearest `q`: (squared distance, barycentric weights).
fn nearest(t: &[[f64; 2]; 3], q: [f64; 2]) -> Option<(f64, [f64; 3])> {
    let b = bary(t, q)?;
    if b.iter().all(|&w| w >= 0.0) {
        // Inside, but within EDGE_INSET of an edge (the distance to the edge opposite vertex i
        // is b_i times the triangle's height over it): moved in as the snapped ones.
        let area2 = cross2(t[0], t[1], t[2]).abs();
        let near_edge = (0..3).any(|i| {
            let (a, c) = (t[(i + 1) % 3], t[(i + 2) % 3]);
            let len = ((c[0] - a[0]).powi(2) + (c[1] - a[1]).powi(2)).sqrt();
            len > 0.0 && b[i] * area2 / len < EDGE_INSET
        });
        return Some((0.0, if near_edge { inset(t, b) } else { b }));
    }
    let mut best: Option<(f64, [f64; 3])> = None;
    for e in 0..3 {
        let (i, j) = (e, (e + 1) % 3);
        let (a, c) = (t[i], t[j]);
        let d = [c[0] - a[0], c[1] - a[1]];
        let len2 = d[0] * d[0] + d[1] * d[1];
        let s = if len2 > 0.0 {
            (((q[0] - a[0]) * d[0] + (q[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let p = [a[0] + s * d[0], a[1] + s * d[1]];
        let dist = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
        let mut w = [0.0; 3];
        w[i] = 1.0 - s;
        w[j] = s;
        if best.is_none_or(|(bd, _)| dist < bd) {
            best = Some((dist, w));
        }
    }
    best.map(|(dist, w)| (dist, inset(t, w)))
}

/// Barycentric weights `w` of `t` moved EDGE_INSET texels towards its centroid (all of the way
/// when that is nearer). A sample on or within a hair of an edge, where a wall meets a ceiling
/// made of another mesh, starts its rays on (or within 4·10⁻⁵ of) the other surface's plane,
/// and some pass out through the seam (bright dots along a room's edges).
fn inset(t: &[[f64; 2]; 3], w: [f64; 3]) -> [f64; 3] {
    let p = [0, 1].map(|k| w[0] * t[0][k] + w[1] * t[1][k] + w[2] * t[2][k]);
    let c = [0, 1].map(|k| (t[0][k] + t[1][k] + t[2][k]) / 3.0);
    let len = ((c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2)).sqrt();
    let s = if len > 0.0 {
        (EDGE_INSET / len).min(1.0)
    } else {
        0.0
    };
    w.map(|x| (1.0 - s) * x + s / 3.0)
}

/// How far (texels) a sample snapped onto a triangle's edge, or within this of one, is moved
/// inside (`nearest`).
pub const EDGE_INSET: f64 = 0.05;

/// The seed of sample `k` of texel (x, y) of page `page`.
pub fn texel_seed(seed: u64, page: u32, x: u32, y: u32, k: u32) -> u64 {
    let mut g = SplitMix64::new(
        seed ^ u64::from(page).wrapping_mul(0xD6E8_FEB8_6659_FD93)
            ^ u64::from(x).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ u64::from(y).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ u64::from(k).wrapping_mul(0x1656_67B1_9E37_79F9),
    );
    g.next_u64()
}

impl Raster {
    /// Collects the light-mapped triangles of `scene` (meshes with a page in `atlas`, whose
    /// `uv1` [`super::check_atlas`] has checked), their charts, and bins them into tiles of
    /// side `tile`.
    pub fn new(scene: &Scene, atlas: &LightmapAtlas, tile: u32) -> Result<Raster> {
        super::check_atlas(scene, atlas)?;
        if tile == 0 {
            return Err(TraceError::Parameter("tile side must be ≥ 1".into()));
        }
        let (w, h) = (f64::from(atlas.width), f64::from(atlas.height));
        let mut triangles = vec![];
        let mut skipped = 0;
        // Union-find over the light-mapped triangles of each mesh.
        let mut parent: Vec<u32> = vec![];
        let mut prim = 0u32;
        for (mesh, page) in scene.meshes.iter().zip(&atlas.mesh_page) {
            let n = mesh.indices.len() as u32;
            let (Some(page), Some(uv1)) = (page, &mesh.uv1) else {
                prim += n;
                continue;
            };
            let mut first_at: HashMap<(u32, u32), u32> = HashMap::new();
            for (k, t) in mesh.indices.iter().enumerate() {
                let uv = t.map(|i| {
                    let v = uv1[i as usize];
                    [f64::from(v.x) * w, f64::from(v.y) * h]
                });
                let [a, b, c] = mesh.triangle(k);
                let world = 0.5 * f64::from((b - a).cross(c - a).length());
                let texels = 0.5 * cross2(uv[0], uv[1], uv[2]).abs();
                if !(world > 0.0 && texels > 0.0 && world.is_finite()) {
                    skipped += 1;
                    continue;
                }
                let me = triangles.len() as u32;
                parent.push(me);
                for &i in t {
                    let v = uv1[i as usize];
                    let key = (v.x.to_bits(), v.y.to_bits());
                    match first_at.get(&key) {
                        Some(&o) => {
                            let (ra, rb) = (find(&mut parent, me), find(&mut parent, o));
                            if ra != rb {
                                parent[ra.max(rb) as usize] = ra.min(rb);
                            }
                        }
                        None => {
                            first_at.insert(key, me);
                        }
                    }
                }
                triangles.push(TexelTriangle {
                    prim: prim + k as u32,
                    page: *page,
                    chart: 0,
                    uv,
                    texel_size: (world / texels).sqrt(),
                });
            }
            prim += n;
        }
        let mut chart_of_root: HashMap<u32, u32> = HashMap::new();
        for (k, t) in triangles.iter_mut().enumerate() {
            let r = find(&mut parent, k as u32);
            let next = chart_of_root.len() as u32;
            t.chart = *chart_of_root.entry(r).or_insert(next);
        }
        let (tx, ty) = (atlas.width.div_ceil(tile), atlas.height.div_ceil(tile));
        let per_page = (tx * ty) as usize;
        let mut bins = vec![vec![]; per_page * atlas.pages as usize];
        let ts = f64::from(tile);
        for (k, t) in triangles.iter().enumerate() {
            let (lo_x, hi_x) = minmax(t.uv.iter().map(|p| p[0]));
            let (lo_y, hi_y) = minmax(t.uv.iter().map(|p| p[1]));
            let cx = |v: f64| ((v / ts).floor().max(0.0) as u32).min(tx - 1);
            let cy = |v: f64| ((v / ts).floor().max(0.0) as u32).min(ty - 1);
            for j in cy(lo_y)..=cy(hi_y) {
                for i in cx(lo_x)..=cx(hi_x) {
                    let (x0, y0) = (f64::from(i) * ts, f64::from(j) * ts);
                    if overlaps(&t.uv, x0, y0, x0 + ts, y0 + ts) {
                        bins[t.page as usize * per_page + (j * tx + i) as usize].push(k as u32);
                    }
                }
            }
        }
        Ok(Raster {
            width: atlas.width,
            height: atlas.height,
            pages: atlas.pages,
            tile,
            charts: chart_of_root.len() as u32,
            triangles,
            skipped,
            bins,
        })
    }

    /// Tiles per page along x and y.
    pub fn tiles_xy(&self) -> (u32, u32) {
        (
            self.width.div_ceil(self.tile),
            self.height.div_ceil(self.tile),
        )
    }

    /// The triangles overlapping texel (x, y) of `page` whose chart is the texel's, with that
    /// chart; `None` for a texel no triangle covers.
    pub fn texel(&self, page: u32, x: u32, y: u32) -> Option<(u32, Vec<u32>)> {
        let (tx, ty) = self.tiles_xy();
        let bin = &self.bins[(page * tx * ty + (y / self.tile) * tx + x / self.tile) as usize];
        let (x0, y0) = (f64::from(x), f64::from(y));
        let centre = [x0 + 0.5, y0 + 0.5];
        let over: Vec<u32> = bin
            .iter()
            .copied()
            .filter(|&k| overlaps(&self.triangles[k as usize].uv, x0, y0, x0 + 1.0, y0 + 1.0))
            .collect();
        let first = *over.first()?;
        let chart = over
            .iter()
            .find(|&&k| {
                bary(&self.triangles[k as usize].uv, centre)
                    .is_some_and(|b| b.iter().all(|&w| w >= 0.0))
            })
            .map_or(self.triangles[first as usize].chart, |&k| {
                self.triangles[k as usize].chart
            });
        let tris = over
            .into_iter()
            .filter(|&k| self.triangles[k as usize].chart == chart)
            .collect();
        Some((chart, tris))
    }

    /// Sample `k` of `spp` on texel (x, y) among `tris` (from [`Raster::texel`]): a point of
    /// the cell k mod n² of an n×n grid over the texel (n = ⌈√spp⌉), jittered by `rng`, moved
    /// to the nearest point of the texel's triangles when it falls outside them.
    pub fn sample(
        &self,
        x: u32,
        y: u32,
        tris: &[u32],
        k: u32,
        spp: u32,
        rng: &mut SplitMix64,
    ) -> Option<SamplePoint> {
        let n = (f64::from(spp).sqrt().ceil() as u32).max(1);
        let cell = k % (n * n);
        let (cx, cy) = (cell % n, cell / n);
        let (ju, jv) = (rng.next_f64(), rng.next_f64());
        let q = [
            f64::from(x) + (f64::from(cx) + ju) / f64::from(n),
            f64::from(y) + (f64::from(cy) + jv) / f64::from(n),
        ];
        let mut best: Option<(f64, u32, [f64; 3])> = None;
        for &t in tris {
            if let Some((d, b)) = nearest(&self.triangles[t as usize].uv, q) {
                if best.is_none_or(|(bd, _, _)| d < bd) {
                    best = Some((d, t, b));
                }
                if d == 0.0 {
                    break;
                }
            }
        }
        best.map(|(_, tri, bary)| SamplePoint { tri, bary, uv: q })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlap_is_conservative_and_separates() {
        let t = [[0.0, 0.0], [4.0, 0.0], [0.0, 4.0]];
        assert!(overlaps(&t, 0.0, 0.0, 1.0, 1.0));
        // Grazed by the hypotenuse only near (1.9, 1.9).
        assert!(overlaps(&t, 1.5, 1.5, 2.5, 2.5));
        assert!(!overlaps(&t, 2.5, 2.5, 3.5, 3.5));
        // Orientation does not matter.
        let r = [t[0], t[2], t[1]];
        assert!(overlaps(&r, 1.5, 1.5, 2.5, 2.5));
        assert!(!overlaps(&r, 2.5, 2.5, 3.5, 3.5));
    }

    #[test]
    fn nearest_snaps_outside_points_to_the_edge() {
        let t = [[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]];
        let (d, b) = nearest(&t, [1.0, -1.0]).unwrap();
        assert!((d - 1.0).abs() < 1e-12);
        // Onto the edge at (1, 0), then EDGE_INSET texels towards the centroid (2/3, 2/3).
        let p = [0, 1].map(|c| b[0] * t[0][c] + b[1] * t[1][c] + b[2] * t[2][c]);
        let to_c: [f64; 2] = [2.0 / 3.0 - 1.0, 2.0 / 3.0];
        let len = (to_c[0] * to_c[0] + to_c[1] * to_c[1]).sqrt();
        for k in 0..2 {
            let expect = [1.0, 0.0][k] + to_c[k] * EDGE_INSET / len;
            assert!((p[k] - expect).abs() < 1e-12, "{p:?}");
        }
        assert!(b.iter().all(|&w| w > 0.0) && (b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // Inside but 0.01 texel from the edge y = 0: moved in the same way; deep inside: kept.
        let (d, b) = nearest(&t, [1.0, 0.01]).unwrap();
        assert_eq!(d, 0.0);
        let p = [0, 1].map(|c| b[0] * t[0][c] + b[1] * t[1][c] + b[2] * t[2][c]);
        let to_c: [f64; 2] = [2.0 / 3.0 - 1.0, 2.0 / 3.0 - 0.01];
        let len = (to_c[0] * to_c[0] + to_c[1] * to_c[1]).sqrt();
        for k in 0..2 {
            let expect = [1.0, 0.01][k] + to_c[k] * EDGE_INSET / len;
            assert!((p[k] - expect).abs() < 1e-12, "{p:?}");
        }
        let (d, _) = nearest(&t, [0.5, 0.5]).unwrap();
        assert_eq!(d, 0.0);
    }
}
