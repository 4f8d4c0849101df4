//! Checks of light-map UVs: charts, triangle overlap in UV space, and the page-resolution layout
//! (conservative rasterisation: overlap between charts and the gutter between them).

use super::LightmapAtlas;
use crate::mesh::Mesh;
use crate::Scene;
use glam::{DVec2, Vec2};
use std::collections::HashMap;

/// The chart of each triangle of `mesh` (numbered from 0 within the mesh) and the number of
/// charts: triangles are in one chart when they are connected through corners with bit-identical
/// `uv1`. A mesh without `uv1` is one chart per triangle.
pub fn uv1_charts(mesh: &Mesh) -> (Vec<u32>, u32) {
    let n = mesh.indices.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    if let Some(uv1) = &mesh.uv1 {
        let mut first: HashMap<(u32, u32), usize> = HashMap::new();
        for (t, tri) in mesh.indices.iter().enumerate() {
            for &v in tri {
                let uv = uv1[v as usize];
                let key = (uv.x.to_bits(), uv.y.to_bits());
                let other = *first.entry(key).or_insert(t);
                let (a, b) = (find(&mut parent, t), find(&mut parent, other));
                if a != b {
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
    }
    let mut id = vec![u32::MAX; n];
    let mut charts = 0u32;
    let mut out = Vec::with_capacity(n);
    for t in 0..n {
        let r = find(&mut parent, t);
        if id[r] == u32::MAX {
            id[r] = charts;
            charts += 1;
        }
        out.push(id[r]);
    }
    (out, charts)
}

/// Signed area of a UV triangle.
pub(crate) fn uv_area(t: &[Vec2; 3]) -> f64 {
    let [a, b, c] = t.map(|p| p.as_dvec2());
    0.5 * (b - a).perp_dot(c - a)
}

/// Whether the interiors of two triangles overlap (separating-axis test over the six edge
/// normals; triangles that only touch along an edge or at a corner, within a relative tolerance
/// of 1e-7 of the edge length, do not overlap). Degenerate triangles never overlap.
pub(crate) fn triangles_overlap(a: &[DVec2; 3], b: &[DVec2; 3]) -> bool {
    for tri in [a, b] {
        for i in 0..3 {
            let e = tri[(i + 1) % 3] - tri[i];
            let axis = e.perp();
            let len = axis.length();
            if len == 0.0 {
                return false;
            }
            let proj = |t: &[DVec2; 3]| {
                let d = t.map(|p| axis.dot(p));
                (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
            };
            let ((a0, a1), (b0, b1)) = (proj(a), proj(b));
            let scale = a1.abs().max(b1.abs()).max(a0.abs()).max(b0.abs()).max(len);
            let eps = 1e-7 * scale;
            if a1 <= b0 + eps || b1 <= a0 + eps {
                return false;
            }
        }
    }
    true
}

/// The first pair (i, j), i < j, of `tris` whose interiors overlap ([`triangles_overlap`]), found
/// through a uniform grid over the triangles' bounds.
pub(crate) fn find_overlap(tris: &[[DVec2; 3]]) -> Option<(usize, usize)> {
    if tris.len() < 2 {
        return None;
    }
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for t in tris {
        for p in t {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
    }
    let g = ((tris.len() as f64).sqrt() * 2.0).clamp(1.0, 2048.0) as usize;
    let size = (hi - lo).max(DVec2::splat(1e-30));
    let cell = |p: DVec2| {
        let c = ((p - lo) / size * g as f64).floor();
        (
            (c.x.max(0.0) as usize).min(g - 1),
            (c.y.max(0.0) as usize).min(g - 1),
        )
    };
    let bounds: Vec<((usize, usize), (usize, usize))> = tris
        .iter()
        .map(|t| {
            let (a, b) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
            (cell(a), cell(b))
        })
        .collect();
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); g * g];
    for (i, &((x0, y0), (x1, y1))) in bounds.iter().enumerate() {
        for y in y0..=y1 {
            for x in x0..=x1 {
                cells[y * g + x].push(i as u32);
            }
        }
    }
    for (c, list) in cells.iter().enumerate() {
        let (cx, cy) = (c % g, c / g);
        for (k, &i) in list.iter().enumerate() {
            for &j in &list[k + 1..] {
                let (bi, bj) = (bounds[i as usize], bounds[j as usize]);
                // Test each pair once: in the first cell both bounds share.
                let (fx, fy) = (bi.0 .0.max(bj.0 .0), bi.0 .1.max(bj.0 .1));
                if (fx, fy) != (cx, cy) {
                    continue;
                }
                if triangles_overlap(&tris[i as usize], &tris[j as usize]) {
                    return Some((i.min(j) as usize, i.max(j) as usize));
                }
            }
        }
    }
    None
}

/// What a page-resolution check of an atlas found ([`check_layout`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayoutCheck {
    /// Light-mapped triangles with a `uv1` corner outside [0, 1] (or light-mapped meshes without
    /// `uv1`, counted by triangles).
    pub outside: usize,
    /// Texels covered by two or more charts.
    pub shared_texels: u64,
    /// Covered texels with a texel of another chart within `gutter` texels (Chebyshev distance),
    /// including the shared ones.
    pub gutter_violations: u64,
    /// Covered texels over all pages (conservative rasterisation).
    pub covered_texels: u64,
    /// Charts over all pages.
    pub charts: u64,
}

impl LayoutCheck {
    /// True when nothing is outside, shared or too close.
    pub fn is_clean(&self) -> bool {
        self.outside == 0 && self.shared_texels == 0 && self.gutter_violations == 0
    }
}

const EMPTY: u32 = u32::MAX;
const MULTI: u32 = u32::MAX - 1;

/// Texels a triangle must reach into to cover them: f32 UVs on texel boundaries land up to
/// ≈ 5·10⁻⁴ texels off at 8192 texels.
pub const RASTER_TOLERANCE: f64 = 1e-3;

/// Whether the texel square (x, x+1) × (y, y+1) and the triangle `p` (texel units) share area
/// reaching more than [`RASTER_TOLERANCE`] into the square: no separating axis among the
/// triangle's three edge normals (the square's own axes are the caller's bounding-box test).
fn square_meets_triangle(p: &[DVec2; 3], x: f64, y: f64) -> bool {
    let corners = [
        DVec2::new(x, y),
        DVec2::new(x + 1.0, y),
        DVec2::new(x, y + 1.0),
        DVec2::new(x + 1.0, y + 1.0),
    ];
    for i in 0..3 {
        let axis = (p[(i + 1) % 3] - p[i]).perp();
        let d = p.map(|q| axis.dot(q));
        let (t0, t1) = (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]));
        let s = corners.map(|q| axis.dot(q));
        let (s0, s1) = (
            s[0].min(s[1]).min(s[2]).min(s[3]),
            s[0].max(s[1]).max(s[2]).max(s[3]),
        );
        let eps = RASTER_TOLERANCE * axis.length();
        if s1 <= t0 + eps || t1 <= s0 + eps {
            return false;
        }
    }
    true
}

/// Calls `f(x, y)` for every texel of a `width × height` page that shares area with the UV
/// triangle `uv` (conservative rasterisation: every texel with any of the triangle's surface,
/// however little; texels the triangle only touches along an edge or at a corner, or reaches into
/// by less than [`RASTER_TOLERANCE`] texels, are left out). A triangle with zero UV area covers
/// nothing.
pub fn raster_conservative(uv: &[Vec2; 3], width: u32, height: u32, mut f: impl FnMut(u32, u32)) {
    let scale = DVec2::new(f64::from(width), f64::from(height));
    let p = uv.map(|q| q.as_dvec2() * scale);
    let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
    let range = |lo: f64, hi: f64, n: u32| -> Option<(u32, u32)> {
        let a = (lo + RASTER_TOLERANCE).floor().max(0.0);
        let b = ((hi - RASTER_TOLERANCE).ceil() - 1.0).min(f64::from(n) - 1.0);
        (a <= b && hi > lo).then_some((a as u32, b as u32))
    };
    let (Some((x0, x1)), Some((y0, y1))) = (range(lo.x, hi.x, width), range(lo.y, hi.y, height))
    else {
        return;
    };
    for y in y0..=y1 {
        for x in x0..=x1 {
            if square_meets_triangle(&p, f64::from(x), f64::from(y)) {
                f(x, y);
            }
        }
    }
}

/// Checks an atlas at page resolution: rasterises every light-mapped triangle conservatively,
/// labels texels by chart ([`uv1_charts`], each mesh's charts distinct), and counts texels
/// shared by two charts and texels with another chart within `atlas.gutter` texels. Memory: one
/// `u32` per page texel (two while checking the gutter).
pub fn check_layout(scene: &Scene, atlas: &LightmapAtlas) -> LayoutCheck {
    let (w, h) = (atlas.width, atlas.height);
    let mut out = LayoutCheck::default();
    if w == 0 || h == 0 {
        return out;
    }
    let texels = w as usize * h as usize;
    let mut next_chart = 0u32;
    let mut charts_of = Vec::new();
    for (mesh, page) in scene.meshes.iter().zip(&atlas.mesh_page) {
        if page.is_some() {
            let (ids, n) = uv1_charts(mesh);
            charts_of.push(Some((ids, next_chart)));
            next_chart += n;
            out.charts += u64::from(n);
        } else {
            charts_of.push(None);
        }
    }
    for page in 0..atlas.pages {
        let mut label = vec![EMPTY; texels];
        for ((mesh, p), charts) in scene.meshes.iter().zip(&atlas.mesh_page).zip(&charts_of) {
            let (Some(p), Some((ids, base))) = (p, charts) else {
                continue;
            };
            if *p != page {
                continue;
            }
            let Some(uv1) = &mesh.uv1 else {
                out.outside += mesh.indices.len();
                continue;
            };
            for (t, tri) in mesh.indices.iter().enumerate() {
                let uv = tri.map(|v| uv1[v as usize]);
                if uv
                    .iter()
                    .any(|q| !(0.0..=1.0).contains(&q.x) || !(0.0..=1.0).contains(&q.y))
                {
                    out.outside += 1;
                    continue;
                }
                let id = base + ids[t];
                raster_conservative(&uv, w, h, |x, y| {
                    let l = &mut label[y as usize * w as usize + x as usize];
                    if *l == EMPTY {
                        *l = id;
                    } else if *l != id {
                        *l = MULTI;
                    }
                });
            }
        }
        let g = atlas.gutter as usize;
        let combine = |a: u32, b: u32| {
            if a == EMPTY {
                b
            } else if b == EMPTY || a == b {
                a
            } else {
                MULTI
            }
        };
        let (wu, hu) = (w as usize, h as usize);
        // The set of labels in the (2g+1)² window, as EMPTY / one label / MULTI: rows, then
        // columns.
        let mut row = vec![EMPTY; texels];
        for y in 0..hu {
            for x in 0..wu {
                let (a, b) = (x.saturating_sub(g), (x + g).min(wu - 1));
                row[y * wu + x] = label[y * wu + a..=y * wu + b]
                    .iter()
                    .fold(EMPTY, |s, &l| combine(s, l));
            }
        }
        for y in 0..hu {
            for x in 0..wu {
                let l = label[y * wu + x];
                if l == EMPTY {
                    continue;
                }
                out.covered_texels += 1;
                if l == MULTI {
                    out.shared_texels += 1;
                    out.gutter_violations += 1;
                    continue;
                }
                let (a, b) = (y.saturating_sub(g), (y + g).min(hu - 1));
                let window = (a..=b).fold(EMPTY, |s, yy| combine(s, row[yy * wu + x]));
                if window != l {
                    out.gutter_violations += 1;
                }
            }
        }
    }
    out
}

/// The first pair of overlapping light-mapped triangles on one page, as (mesh, triangle, mesh,
/// triangle), or `None`. Every pair is considered, in one chart or not.
pub fn find_overlapping_triangles(
    scene: &Scene,
    atlas: &LightmapAtlas,
) -> Option<(usize, usize, usize, usize)> {
    for page in 0..atlas.pages {
        let mut tris = Vec::new();
        let mut owner = Vec::new();
        for (mi, (mesh, p)) in scene.meshes.iter().zip(&atlas.mesh_page).enumerate() {
            if *p != Some(page) {
                continue;
            }
            let Some(uv1) = &mesh.uv1 else { continue };
            for (t, tri) in mesh.indices.iter().enumerate() {
                tris.push(tri.map(|v| uv1[v as usize].as_dvec2()));
                owner.push((mi, t));
            }
        }
        if let Some((i, j)) = find_overlap(&tris) {
            return Some((owner[i].0, owner[i].1, owner[j].0, owner[j].1));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(p: [[f64; 2]; 3]) -> [DVec2; 3] {
        p.map(DVec2::from_array)
    }

    #[test]
    fn overlap_test_separates_neighbours_and_catches_overlap() {
        let a = t([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        let shared_edge = t([[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        let corner = t([[1.0, 0.0], [2.0, 0.0], [1.0, 1.0]]);
        let inside = t([[0.1, 0.1], [0.3, 0.1], [0.1, 0.3]]);
        let crossing = t([[0.4, -0.2], [0.6, -0.2], [0.5, 0.3]]);
        assert!(!triangles_overlap(&a, &shared_edge));
        assert!(!triangles_overlap(&a, &corner));
        assert!(triangles_overlap(&a, &inside));
        assert!(triangles_overlap(&a, &crossing));
        assert_eq!(find_overlap(&[a, shared_edge, corner]), None);
        assert_eq!(
            find_overlap(&[a, shared_edge, corner, crossing]),
            Some((0, 3))
        );
    }

    #[test]
    fn conservative_raster_covers_touched_texels() {
        // A triangle inside texel (1, 1) of a 4×4 page covers only that texel.
        let uv = [
            Vec2::new(0.3, 0.3),
            Vec2::new(0.45, 0.3),
            Vec2::new(0.3, 0.45),
        ];
        let mut hit = Vec::new();
        raster_conservative(&uv, 4, 4, |x, y| hit.push((x, y)));
        assert_eq!(hit, vec![(1, 1)]);
        // A square on texel boundaries, [1, 3]² in texels, covers 4 texels, not its neighbours.
        let q = [0.25f32, 0.75];
        let mut hit = Vec::new();
        for uv in [
            [
                Vec2::new(q[0], q[0]),
                Vec2::new(q[1], q[0]),
                Vec2::new(q[1], q[1]),
            ],
            [
                Vec2::new(q[0], q[0]),
                Vec2::new(q[1], q[1]),
                Vec2::new(q[0], q[1]),
            ],
        ] {
            raster_conservative(&uv, 4, 4, |x, y| hit.push((x, y)));
        }
        hit.sort_unstable();
        hit.dedup();
        assert_eq!(hit, vec![(1, 1), (1, 2), (2, 1), (2, 2)]);
        // The lower-left half of the page: the diagonal x + y = 4 passes through corners only, so
        // texel (x, y) shares area with it when x + y ≤ 3: rows of 4, 3, 2 and 1 texels.
        let uv = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)];
        let mut n = 0;
        raster_conservative(&uv, 4, 4, |x, y| {
            assert!(x + y <= 3, "({x}, {y})");
            n += 1;
        });
        assert_eq!(n, 10);
        // A sliver covers every texel it crosses.
        let uv = [
            Vec2::new(0.1, 0.1),
            Vec2::new(0.9, 0.1),
            Vec2::new(0.9, 0.1001),
        ];
        let mut n = 0;
        raster_conservative(&uv, 4, 4, |_, y| {
            assert_eq!(y, 0);
            n += 1;
        });
        assert_eq!(n, 4);
    }
}
