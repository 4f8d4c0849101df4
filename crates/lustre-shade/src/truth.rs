//! The exact answer for a distant environment: L_o(ωo) = ∫ L(ωi) f(ωi, ωo) |cos θi| dωi
//! (002 Eq. 8, 000 Eq. 4.3) summed over every texel of a cube map's level 0.
//!
//! The environment is piecewise constant over its texels (the signal the pyramid filters), so
//! the integral is Σ_texels L_t ∫_texel f |cos θi| dω. The inner integral is the BSDF at the
//! texel centre times the exact texel solid angle ([`lustre_env::cube::rect_solid_angle`]), or,
//! where the lobe is narrower than a texel, the mean over S×S sub-squares of the texel, each
//! weighted by its own exact solid angle ([`supersampling`] picks S). No Monte-Carlo noise: the
//! only error is the variation of f cos θi inside a (sub-)texel, which [`truth`]'s tests bound.
//!
//! [`TexelTree`] gives the same sum fast for images: exact block sums (Σ L Ω and the radiance
//! centroid per 2^k × 2^k block) are accepted whole where f |cos θi| is nearly linear over the
//! block and refined down to single texels elsewhere (near the lobe peaks always), so a 1024²
//! cube costs ≈ 3·10⁴ BSDF evaluations per pixel instead of 6.3 million; its tests and
//! `lustre compare` measure its difference to [`truth`].
//!
//! [`configurations`] draws the seeded shading configurations (normal, tangent, view) the truth
//! harness (`examples/truth_study.rs`) measures every method on.

use glam::DVec3;
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::models::kurt::Kurt;
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::SplitMix64;
use lustre_env::cube::{face_point, rect_solid_angle};
use lustre_env::CubeMap;
use lustre_trace::sampling::ShadingFrame;

/// Largest supersampling factor per texel axis.
pub const MAX_SUPERSAMPLING: usize = 8;

/// The exact integral of `bsdf` against the piecewise-constant cube map `map` for the shading
/// frame `frame` and the world direction to the viewer `wo`, with every texel split into
/// `supersample`² sub-squares (1 = texel centres; clamped to 1 ..= [`MAX_SUPERSAMPLING`]).
/// Two-sided as the integrators: `bsdf.eval` receives local directions and decides the side.
pub fn truth(
    map: &CubeMap,
    frame: &ShadingFrame,
    wo: DVec3,
    bsdf: &dyn Bsdf,
    supersample: usize,
) -> Rgb {
    let s = supersample.clamp(1, MAX_SUPERSAMPLING);
    let n = map.size;
    let wo_l = frame.to_local(wo);
    let step = 2.0 / n as f64;
    let sub = step / s as f64;
    let mut total = Rgb::ZERO;
    for (face, texels) in map.faces.iter().enumerate() {
        for j in 0..n {
            let y0 = -1.0 + j as f64 * step;
            for i in 0..n {
                let l = texels[j * n + i];
                if l == [0.0; 3] {
                    continue;
                }
                let x0 = -1.0 + i as f64 * step;
                let acc = sub_texel_sum(face, x0, y0, sub, s, |d| {
                    let wi = frame.to_local(d);
                    bsdf.eval(wi, wo_l) * wi.z.abs()
                });
                total += acc * Rgb([l[0] as f64, l[1] as f64, l[2] as f64]);
            }
        }
    }
    total
}

/// Σ g(d)·Ω over the `s`² sub-squares of side `sub` (face coordinates) of the texel whose
/// lower corner is (`x0`, `y0`) on `face`, d the normalized direction to each sub-square's
/// centre and Ω its exact solid angle.
fn sub_texel_sum(
    face: usize,
    x0: f64,
    y0: f64,
    sub: f64,
    s: usize,
    mut g: impl FnMut(DVec3) -> Rgb,
) -> Rgb {
    let mut acc = Rgb::ZERO;
    for b in 0..s {
        let ya = y0 + b as f64 * sub;
        for a in 0..s {
            let xa = x0 + a as f64 * sub;
            let omega = rect_solid_angle(xa, xa + sub, ya, ya + sub);
            let d = face_point(face, xa + 0.5 * sub, ya + 0.5 * sub).normalize();
            acc += g(d) * omega;
        }
    }
    acc
}

/// The supersampling factor for a Kurt material seen from `wo_local` (shading-local) on a cube
/// of face `face_size`: the narrowest lobe's smallest angular width in ωi, 2 · min(mx, my) ·
/// max(cos θo, 0.05) (the half-vector width doubled by the reflection, foreshortened out of the
/// plane of incidence at grazing views), is covered by at least 3 sub-texels of the largest
/// texel (2/N rad at a face centre). 1 for lobes wider than three texels.
pub fn supersampling(kurt: &Kurt, wo_local: DVec3, face_size: usize) -> usize {
    let m = kurt
        .reflection
        .iter()
        .chain(&kurt.transmission)
        .map(|l| l.mx.min(l.my))
        .fold(f64::INFINITY, f64::min);
    supersampling_for(m, wo_local, face_size)
}

/// [`supersampling`] for any lobe whose smallest slope-space width is `roughness` (Beckmann's
/// m, a microfacet α; for a model without one, a lower bound of its lobe width): at least 3
/// sub-texels across 2 · `roughness` · max(cos θo, 0.05). 1 when `roughness` is infinite (no
/// lobe), [`MAX_SUPERSAMPLING`] when it is 0 or NaN.
pub fn supersampling_for(roughness: f64, wo_local: DVec3, face_size: usize) -> usize {
    if roughness == f64::INFINITY {
        return 1;
    }
    let width = 2.0 * roughness * wo_local.z.abs().max(0.05);
    let texel = 2.0 / face_size.max(1) as f64;
    let s = (3.0 * texel / width).ceil();
    if s.is_finite() {
        (s as usize).clamp(1, MAX_SUPERSAMPLING)
    } else {
        MAX_SUPERSAMPLING
    }
}

/// Face blocks at the coarsest level of a [`TexelTree`] (per face edge, at most).
const TREE_TOP_BLOCKS: usize = 8;

/// One block of a [`TexelTree`] level: the exact sums over its level-0 texels.
#[derive(Clone, Copy, Debug, Default)]
struct Block {
    /// Σ L_c Ω per channel (W/sr·sr = the block's radiant contribution to a constant f).
    s: [f32; 3],
    /// Σ ℓ Ω d, ℓ = the channel mean of L, d the unit texel direction (the block's centroid
    /// direction, weighted by radiance, unnormalized).
    m: [f32; 3],
    /// Σ ℓ Ω.
    lum: f32,
}

/// Exact block sums of a cube map's level 0 for [`TexelTree::integrate`]: level k ≥ 1 holds,
/// per face, ⌈N/2^k⌉² blocks of 2^k × 2^k texels with Σ L Ω (per channel), Σ ℓ Ω and the
/// radiance-weighted centroid direction Σ ℓ Ω d; level 0 is the map itself with the exact texel
/// solid angles. Built once per map (sums in f64, stored in f32).
#[derive(Clone, Debug)]
pub struct TexelTree<'a> {
    map: &'a CubeMap,
    omega: Vec<f64>,
    levels: Vec<Vec<Block>>,
}

/// What one [`TexelTree::integrate`] call cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TreeStats {
    /// BSDF evaluations.
    pub evals: usize,
    /// Level-0 texels summed one by one.
    pub texels: usize,
}

impl<'a> TexelTree<'a> {
    /// The tree of `map` (any face size).
    pub fn new(map: &'a CubeMap) -> Self {
        let n = map.size;
        let omega = lustre_env::cube::solid_angle_table(n);
        let mut levels: Vec<Vec<Block>> = vec![vec![]];
        // Level 1 from the texels, then each level from the one below.
        let mut k = 1;
        loop {
            let nk = n.div_ceil(1 << k);
            let prev = n.div_ceil(1 << (k - 1));
            let mut blocks = vec![Block::default(); 6 * nk * nk];
            for face in 0..6 {
                for bj in 0..nk {
                    for bi in 0..nk {
                        let (mut s, mut m, mut lum) = ([0.0f64; 3], DVec3::ZERO, 0.0f64);
                        for cj in 2 * bj..(2 * bj + 2).min(prev) {
                            for ci in 2 * bi..(2 * bi + 2).min(prev) {
                                if k == 1 {
                                    let l = map.faces[face][cj * n + ci];
                                    let o = omega[cj * n + ci];
                                    let d = CubeMap::texel_dir(n, face, ci, cj);
                                    let ll = (l[0] as f64 + l[1] as f64 + l[2] as f64) / 3.0;
                                    for (sc, lc) in s.iter_mut().zip(l) {
                                        *sc += lc as f64 * o;
                                    }
                                    lum += ll * o;
                                    m += d * (ll * o);
                                } else {
                                    let b = levels[k - 1][(face * prev + cj) * prev + ci];
                                    for (sc, bc) in s.iter_mut().zip(b.s) {
                                        *sc += bc as f64;
                                    }
                                    lum += b.lum as f64;
                                    m += DVec3::new(b.m[0] as f64, b.m[1] as f64, b.m[2] as f64);
                                }
                            }
                        }
                        blocks[(face * nk + bj) * nk + bi] = Block {
                            s: s.map(|v| v as f32),
                            m: [m.x as f32, m.y as f32, m.z as f32],
                            lum: lum as f32,
                        };
                    }
                }
            }
            levels.push(blocks);
            if nk <= TREE_TOP_BLOCKS {
                break;
            }
            k += 1;
        }
        TexelTree { map, omega, levels }
    }

    /// The map the tree sums.
    pub fn map(&self) -> &CubeMap {
        self.map
    }

    /// ∫ L f |cos θi| dω of the Kurt material `kurt` for `frame` and the world direction to the
    /// viewer `wo`, by adaptive refinement of the block sums: a block is accepted as
    /// S · g(c) (S its exact Σ L Ω, g = f |cos θi| at its radiance centroid c, exact for g linear
    /// over the block) when ℓ-sum × max |g(corner) − g(c)| ≤ `tolerance` (absolute, radiance
    /// units) and it is not within 3 lobe widths of a lobe's peak direction (where it is always
    /// split until it is 4 times narrower than the lobe); otherwise its four children are
    /// visited. Level-0 texels are summed as [`truth`] does with [`supersampling`], so as the
    /// tolerance goes to 0 the result goes to [`truth`]'s (blocks where g is exactly constant at
    /// all five points, e.g. below the horizon, are still accepted whole). Returns the value and
    /// the work done.
    pub fn integrate(
        &self,
        frame: &ShadingFrame,
        wo: DVec3,
        kurt: &Kurt,
        tolerance: f64,
    ) -> (Rgb, TreeStats) {
        let n = self.map.size;
        let wo_l = frame.to_local(wo);
        let mut stats = TreeStats::default();
        let g = |d: DVec3, st: &mut TreeStats| -> Rgb {
            st.evals += 1;
            let wi = frame.to_local(d);
            kurt.eval(wi, wo_l) * wi.z.abs()
        };
        // Lobe peaks (world) and their narrowest angular width in ωi.
        let cos_o = wo_l.z.abs().max(0.05);
        let mirror = frame.to_world(DVec3::new(-wo_l.x, -wo_l.y, wo_l.z));
        let peaks: Vec<(DVec3, f64)> = kurt
            .reflection
            .iter()
            .map(|l| (mirror, 2.0 * l.mx.min(l.my) * cos_o))
            .chain(
                kurt.transmission
                    .iter()
                    .map(|l| (-wo, 2.0 * l.mx.min(l.my) * cos_o)),
            )
            .collect();
        let ss = supersampling(kurt, wo_l, n);
        let step = 2.0 / n as f64;
        let sub = step / ss as f64;
        let top = self.levels.len() - 1;
        let nt = n.div_ceil(1 << top);
        let mut stack: Vec<(usize, usize, usize, usize)> = Vec::with_capacity(256);
        for face in 0..6 {
            for bj in 0..nt {
                for bi in 0..nt {
                    stack.push((top, face, bi, bj));
                }
            }
        }
        let mut total = Rgb::ZERO;
        while let Some((k, face, bi, bj)) = stack.pop() {
            if k == 0 {
                let l = self.map.faces[face][bj * n + bi];
                if l == [0.0; 3] {
                    continue;
                }
                stats.texels += 1;
                let lr = Rgb([l[0] as f64, l[1] as f64, l[2] as f64]);
                if ss == 1 {
                    let d = CubeMap::texel_dir(n, face, bi, bj);
                    total += lr * g(d, &mut stats) * self.omega[bj * n + bi];
                } else {
                    let (x0, y0) = (-1.0 + bi as f64 * step, -1.0 + bj as f64 * step);
                    total += lr * sub_texel_sum(face, x0, y0, sub, ss, |d| g(d, &mut stats));
                }
                continue;
            }
            let nk = n.div_ceil(1 << k);
            let b = self.levels[k][(face * nk + bj) * nk + bi];
            if b.lum <= 0.0 {
                continue;
            }
            let w = (1usize << k) as f64 * step;
            let x0 = -1.0 + bi as f64 * w;
            let y0 = -1.0 + bj as f64 * w;
            let x1 = (x0 + w).min(1.0);
            let y1 = (y0 + w).min(1.0);
            let corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
                .map(|(x, y)| face_point(face, x, y).normalize());
            let centre = face_point(face, 0.5 * (x0 + x1), 0.5 * (y0 + y1)).normalize();
            let radius = corners
                .iter()
                .map(|c| c.dot(centre).clamp(-1.0, 1.0).acos())
                .fold(0.0, f64::max);
            let near_peak = peaks.iter().any(|&(p, width)| {
                radius > 0.25 * width
                    && p.dot(centre).clamp(-1.0, 1.0).acos() < radius + 3.0 * width
            });
            let accept = !near_peak && {
                let c = DVec3::new(b.m[0] as f64, b.m[1] as f64, b.m[2] as f64)
                    .try_normalize()
                    .unwrap_or(centre);
                let gc = g(c, &mut stats);
                let spread = corners
                    .iter()
                    .map(|&d| {
                        let e = g(d, &mut stats) - gc;
                        e.0.iter().fold(0.0f64, |a, v| a.max(v.abs()))
                    })
                    .fold(0.0, f64::max);
                if b.lum as f64 * spread <= tolerance {
                    total += Rgb([b.s[0] as f64, b.s[1] as f64, b.s[2] as f64]) * gc;
                    true
                } else {
                    false
                }
            };
            if !accept {
                let prev = n.div_ceil(1 << (k - 1));
                for cj in 2 * bj..(2 * bj + 2).min(prev) {
                    for ci in 2 * bi..(2 * bi + 2).min(prev) {
                        stack.push((k - 1, face, ci, cj));
                    }
                }
            }
        }
        (total, stats)
    }
}

/// One shading configuration: a frame and the world direction to the viewer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Configuration {
    /// The shading frame (normal uniform on the sphere, tangent uniform around it).
    pub frame: ShadingFrame,
    /// Unit direction to the viewer, world space.
    pub wo: DVec3,
    /// θo in degrees (angle between `wo` and the normal).
    pub theta_o_deg: f64,
}

/// `count` configurations from [`SplitMix64`]`(seed)`: normals uniform on the sphere, tangents
/// uniform in the tangent plane, θo uniform in [0°, `max_theta_deg`) and φo uniform, so every
/// θo bin of the same width holds about the same number of configurations.
pub fn configurations(count: usize, max_theta_deg: f64, seed: u64) -> Vec<Configuration> {
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|_| {
            let z = 1.0 - 2.0 * rng.next_f64();
            let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let n = DVec3::new(r * phi.cos(), r * phi.sin(), z);
            let hint = DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            );
            let frame = ShadingFrame::new(n, hint);
            let theta_o_deg = max_theta_deg * rng.next_f64();
            let (st, ct) = theta_o_deg.to_radians().sin_cos();
            let po = 2.0 * std::f64::consts::PI * rng.next_f64();
            let wo = frame.to_world(DVec3::new(st * po.cos(), st * po.sin(), ct));
            Configuration {
                frame,
                wo,
                theta_o_deg,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_brdf::models::kurt::KurtLobe;

    fn lobe_material(mx: f64, my: f64) -> Kurt {
        Kurt::new(
            Rgb::ZERO,
            vec![KurtLobe::new(Rgb::ONE, mx, my, 1.0, 0.0).expect("lobe")],
            vec![],
        )
        .expect("material")
    }

    /// A white environment and a Lambertian surface: ∫ (kd/π) cos θi dω over the upper
    /// hemisphere = kd exactly; the texel sum converges to it.
    #[test]
    fn white_map_lambertian_is_kd() {
        let map = CubeMap::from_fn(32, |_| [1.0, 1.0, 1.0]).expect("map");
        let kurt = Kurt::new(Rgb::new(0.5, 0.25, 1.0), vec![], vec![]).expect("material");
        let frame = ShadingFrame::new(DVec3::new(0.3, 0.8, -0.2), DVec3::X);
        let wo = frame.to_world(DVec3::new(0.2, 0.1, 0.9).normalize());
        let t = truth(&map, &frame, wo, &kurt, 1);
        for (c, want) in [0.5, 0.25, 1.0].into_iter().enumerate() {
            assert!((t[c] - want).abs() < 2e-3 * want, "{t:?}");
        }
        let t4 = truth(&map, &frame, wo, &kurt, 4);
        assert!(
            (t4[0] - 0.5).abs() < (t[0] - 0.5).abs() + 1e-6,
            "{t4:?} vs {t:?}"
        );
    }

    /// A white environment and one Beckmann lobe with r0 = 1, α = 0: the directional albedo
    /// ∫ D(h) cos θh [ωi above] dωh, estimated by importance sampling h (weight = the indicator
    /// only, so the estimate's noise is tiny and bounded).
    #[test]
    fn white_map_lobe_matches_albedo() {
        use lustre_brdf::frame::reflect;
        use lustre_brdf::models::kurt::lobe_sample_h;
        use lustre_brdf::sampling::hammersley;
        let map = CubeMap::from_fn(64, |_| [1.0, 1.0, 1.0]).expect("map");
        for (mx, my, th) in [(0.2, 0.2, 0.3f64), (0.3, 0.1, 1.2)] {
            let kurt = lobe_material(mx, my);
            let frame = ShadingFrame::new(DVec3::Y, DVec3::X);
            let wo_l = DVec3::new(th.sin() * 0.6, th.sin() * 0.8, th.cos());
            let wo = frame.to_world(wo_l);
            let t = truth(&map, &frame, wo, &kurt, 2)[0];
            // albedo = ∫ (D/(4 ωo·h)) cos θi dωi = E_h[cos θi / cos θh] with h ~ D cos θh.
            let n = 1 << 16;
            let mut acc = 0.0;
            for k in 0..n {
                let (u1, u2) = hammersley(k, n);
                let h = lobe_sample_h(&kurt.reflection[0], u1, u2);
                let wi = reflect(wo_l, h);
                if wo_l.dot(h) > 0.0 && wi.z > 0.0 {
                    acc += wi.z / h.z;
                }
            }
            let albedo = acc / n as f64;
            assert!(
                (t - albedo).abs() < 5e-3 * albedo,
                "mx {mx} my {my}: truth {t} vs albedo {albedo}"
            );
        }
    }

    /// A lobe narrower than a texel: the supersampled sums converge (S = 4 and S = 8 agree to
    /// 1 %), and `supersampling` asks for more than one sub-texel there.
    #[test]
    fn narrow_lobe_converges_with_supersampling() {
        let map = CubeMap::from_fn(16, |d| [1.0 + d.x.max(0.0) * 4.0, 1.0, 1.0]).expect("map");
        let kurt = lobe_material(0.04, 0.02);
        let frame = ShadingFrame::new(DVec3::new(1.0, 0.2, 0.1), DVec3::Y);
        let wo = frame.to_world(DVec3::new(0.3, 0.0, 0.95).normalize());
        assert!(supersampling(&kurt, frame.to_local(wo), 16) > 1);
        let a = truth(&map, &frame, wo, &kurt, 4)[0];
        let b = truth(&map, &frame, wo, &kurt, 8)[0];
        assert!((a - b).abs() < 0.01 * b, "{a} vs {b}");
    }

    /// A structured map (gradients and bands): the texel sum agrees with a converged QMC
    /// estimate of the integrators' reference integrator on the same level 0 (which reads it
    /// bilinearly) to 0.5 %, anisotropic lobe, oblique view.
    #[test]
    fn matches_converged_qmc_on_a_structured_map() {
        use crate::integrator::{shade_qmc, FilteredEnvironment};
        use lustre_env::{irradiance_map, CubePyramid, MipFilter};
        let base = CubeMap::from_fn(32, |d| {
            let d = d.normalize();
            let band = 0.5 + 0.5 * (5.0 * d.x.atan2(d.z)).sin();
            [1.0 + d.y.max(0.0) * 3.0 + band, 0.5 + band, 1.0 + 0.5 * d.x]
        })
        .expect("map");
        let pyramid = CubePyramid::build(base, MipFilter::Box2).expect("pyramid");
        let irradiance = irradiance_map(&pyramid, 4).expect("irradiance");
        let env = FilteredEnvironment {
            pyramid: &pyramid,
            irradiance: &irradiance,
        };
        let kurt = lobe_material(0.3, 0.12);
        for (n, th) in [(DVec3::new(0.2, 1.0, 0.3), 0.4f64), (DVec3::X, 1.1)] {
            let frame = ShadingFrame::new(n, DVec3::new(0.0, 0.3, 1.0));
            let wo = frame.to_world(DVec3::new(th.sin() * 0.8, th.sin() * 0.6, th.cos()));
            let t = truth(&pyramid.levels[0], &frame, wo, &kurt, 2);
            let q = shade_qmc(&frame, wo, &kurt, &env, 1 << 17, 3);
            for c in 0..3 {
                assert!((t[c] - q[c]).abs() < 5e-3 * q[c], "{t:?} vs {q:?}");
            }
        }
    }

    /// The adaptive tree against the full texel sum on 002's spot map (bright 2–10° spots on a
    /// dim gradient), isotropic, anisotropic and transmissive lobes, normal to grazing views:
    /// within 2e-4 relative at tolerance 1e-7; a coarser tolerance (1e-3) is further off and
    /// needs far fewer BSDF evaluations than there are texels.
    #[test]
    fn tree_matches_the_full_texel_sum() {
        let map = lustre_env::spot_map(&lustre_env::SpotMapParams {
            size: 64,
            spots: 48,
            min_deg: 2.0,
            max_deg: 10.0,
            max_ratio: 3000.0,
            background: [0.01; 3],
            seed: 3,
        })
        .expect("spot map");
        let tree = TexelTree::new(&map);
        let glass = Kurt::new(
            Rgb::new(0.1, 0.05, 0.02),
            vec![KurtLobe::new(Rgb::ONE, 0.08, 0.08, 0.04, 0.0).expect("lobe")],
            vec![KurtLobe::new(Rgb::splat(0.9), 0.15, 0.15, 0.04, 0.0).expect("lobe")],
        )
        .expect("glass");
        let mats = [lobe_material(0.1, 0.1), lobe_material(0.2, 0.075), glass];
        let configs = configurations(12, 85.0, 11);
        let (mut worst, mut worst_coarse, mut coarse_evals) = (0.0f64, 0.0f64, 0usize);
        for kurt in &mats {
            for c in &configs {
                let s = supersampling(kurt, c.frame.to_local(c.wo), map.size);
                let t = truth(&map, &c.frame, c.wo, kurt, s);
                let (a, _) = tree.integrate(&c.frame, c.wo, kurt, 1e-7);
                let (b, st) = tree.integrate(&c.frame, c.wo, kurt, 1e-3);
                coarse_evals += st.evals;
                for ch in 0..3 {
                    worst = worst.max((a[ch] - t[ch]).abs() / t[ch]);
                    worst_coarse = worst_coarse.max((b[ch] - t[ch]).abs() / t[ch]);
                }
            }
        }
        assert!(worst < 2e-4, "worst relative error {worst}");
        assert!(worst_coarse > worst, "{worst_coarse} vs {worst}");
        // The coarse tolerance visits far fewer points than the 24,576 texels.
        let per = coarse_evals / (mats.len() * configs.len());
        assert!(per < 6 * 64 * 64 / 4, "{per} evaluations per integral");
    }

    #[test]
    fn configurations_are_seeded_and_spread() {
        let a = configurations(400, 85.0, 7);
        assert_eq!(a, configurations(400, 85.0, 7));
        assert_ne!(a, configurations(400, 85.0, 8));
        let mut bins = [0usize; 5];
        for c in &a {
            let cos = c.wo.dot(c.frame.n);
            assert!((cos.acos().to_degrees() - c.theta_o_deg).abs() < 1e-9);
            assert!((c.wo.length() - 1.0).abs() < 1e-12);
            bins[(c.theta_o_deg / 17.0) as usize] += 1;
        }
        assert!(bins.iter().all(|&b| b > 50), "{bins:?}");
    }
}
