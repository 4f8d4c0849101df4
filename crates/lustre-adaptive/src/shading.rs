//! The shading integral of one pixel (004 §IV.4.3, Eq. IV.1):
//!
//! L_p = ∫ L(ωi) f(ωi, ωo) cos θi dωi
//!
//! estimated from N samples: half drawn by importance sampling the BRDF, by inversion of its
//! tabulated CDFs ([`TabulatedSampler`], 004's choice; per view azimuth too for anisotropic
//! BRDFs) for reflection BRDFs or by the model's own `sample` otherwise (transmissive or Dirac
//! lobes), half by importance
//! sampling the environment, combined by the balance heuristic (004 samples the BRDF only; on
//! gold-paint under royal_esplanade_1k, BRDF sampling alone went from 12.8 to 22.3 dB between 1
//! and 256 samples at 128², about 1.2 dB per doubling, the balance heuristic from 12.8 to
//! 44.3 dB). Each technique's points are a Hammersley set rotated per pixel
//! (Cranley–Patterson); the adaptive renderer and the brute-force one share this estimator. No
//! visibility: the environment is seen from every point (as 004).
//!
//! [`Lighting::Preconvolved`] reads the environment's pyramid at the level of the BRDF's largest
//! bandwidth ν at the pixel (§IV.3.5), [`preconvolved_level`]: the coarsest level whose filter
//! still passes frequency ν with [`PRECONVOLVED_PASSBAND`] of its amplitude; where that is level
//! 0 (nothing to filter), the map itself, as [`Lighting::Direct`]
//! ([`ShadingContext::preconvolved_lod`]). 004's level, where
//! the level's Nyquist frequency meets ν (ℓ = log2(face / (π ν))), keeps only ≈ 6 % of ν's
//! amplitude under the Gaussian 6×6 pyramid and capped PSNR at 34–39 dB (BENCHMARKS.md).

use crate::gbuffer::Surfel;
use crate::light::AreaLight;
use crate::{AdaptiveError, Result};
use glam::DVec3;
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::{hammersley, SplitMix64};
use lustre_brdf::tabulated::{TabulatedOptions, TabulatedSampler};
use lustre_brdf::Bsdf;
use lustre_env::{CubePyramid, MipFilter};
use lustre_freq::brdf::{brdf_bandwidth, BrdfBandwidth, BrdfBandwidthOptions};
use lustre_freq::pixel::EnvironmentBandwidth;
use lustre_freq::spatial::texture_bandwidth;
use lustre_scene::Texture;
use lustre_trace::baked::environment_pyramid;
use lustre_trace::path_tracer::{EnvLight, PathScene};
use std::borrow::Cow;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::Arc;

/// Where the environment is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lighting {
    /// The full-resolution map, bilinear (Eq. IV.1, variance bound Eq. IV.9).
    Direct,
    /// The pyramid at the BRDF's bandwidth (§IV.3.5, variance bound Eq. IV.10); the map itself
    /// where that is the pyramid's finest level.
    Preconvolved,
}

/// How the per-material tables are built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingOptions {
    /// The sampling tables.
    pub tabulated: TabulatedOptions,
    /// The bandwidth tables (004: 16 × 16 incident directions).
    pub bandwidth: BrdfBandwidthOptions,
    /// Cube face of the pre-convolved pyramid (texels); 0 builds none.
    pub pyramid_face: usize,
}

impl Default for ShadingOptions {
    fn default() -> Self {
        Self {
            tabulated: TabulatedOptions::default(),
            bandwidth: BrdfBandwidthOptions::default(),
            pyramid_face: 256,
        }
    }
}

/// One material's tables, built from its BSDF at uv (½, ½) (homogeneous materials, as 004).
#[derive(Debug)]
pub struct MaterialTables {
    /// The BSDF's name.
    pub name: String,
    /// The tabulated CDFs, for reflection BRDFs without Dirac lobes.
    pub sampler: Option<TabulatedSampler>,
    /// The angular bandwidth.
    pub bandwidth: BrdfBandwidth,
    /// The local bandwidth of each texture that varies the BSDF or the shading normal
    /// ([`lustre_trace::path_tracer::Surface::bsdf_textures`]; shared between materials).
    pub textures: Vec<Arc<TextureBandwidth>>,
}

/// A texture's local spatial bandwidth in cycles per texel (004 §IV.3.1:
/// [`lustre_freq::spatial::texture_bandwidth`], the 95th percentile of the local wavelet
/// spectrum, the texture tiling).
#[derive(Clone, Debug)]
pub struct TextureBandwidth {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Cycles per texel, row-major as the texture's texels (row 0 at v = 0).
    pub cycles_per_texel: Vec<f64>,
}

impl TextureBandwidth {
    /// The bandwidth map of `t`'s RGB (luminance).
    pub fn new(t: &Texture) -> Result<Self> {
        let (w, h) = (t.width as usize, t.height as usize);
        let texels: Vec<[f32; 3]> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let v = t.texel(x as u32, y as u32);
                [v[0], v[1], v[2]]
            })
            .collect();
        Ok(Self {
            width: w,
            height: h,
            cycles_per_texel: texture_bandwidth(&texels, w, h)?,
        })
    }

    /// Cycles per metre at `uv` (the texel under it, repeating as `Texture::sample`) on a
    /// surface whose texture coordinates change by `uv_rate` per metre: the bandwidth per texel
    /// times the larger of the texels per metre along u and v.
    pub fn at(&self, uv: [f64; 2], uv_rate: [f64; 2]) -> f64 {
        let texel = |c: f64, n: usize| -> usize {
            if c.is_finite() {
                ((c * n as f64).floor() as i64).rem_euclid(n as i64) as usize
            } else {
                0
            }
        };
        let (x, y) = (texel(uv[0], self.width), texel(uv[1], self.height));
        let per_metre = (uv_rate[0] * self.width as f64).max(uv_rate[1] * self.height as f64);
        let v = self.cycles_per_texel[y * self.width + x] * per_metre;
        if v.is_finite() {
            v
        } else {
            0.0
        }
    }
}

/// What shading needs: the scene's materials with their tables, the environment and its
/// pyramid, the area lights.
pub struct ShadingContext<'a, 's> {
    /// The scene (materials).
    pub scene: &'a PathScene<'s>,
    /// The scene's environment; a black one (radiance scale 0) where the scene has none
    /// ([`ShadingContext::lit_by_environment`]).
    pub env: Cow<'a, EnvLight>,
    /// Per material of the scene.
    pub materials: Vec<MaterialTables>,
    /// The pre-convolved pyramid (world directions), when built.
    pub pyramid: Option<CubePyramid>,
    /// Area lights (004 §IV.5.3), sampled directly besides the environment.
    pub lights: Vec<AreaLight>,
}

impl<'a, 's> ShadingContext<'a, 's> {
    /// Builds every material's tables (`progress(k, n)` after each) and the pyramid. A scene
    /// without an environment gets a black one: its light is then the area lights' alone
    /// ([`ShadingContext::lights`], e.g. [`crate::light::scene_lights`]; see
    /// [`ShadingContext::check_lit`]).
    pub fn new(
        scene: &'a PathScene<'s>,
        options: ShadingOptions,
        progress: &dyn Fn(usize, usize),
    ) -> Result<Self> {
        let env = match &scene.environment {
            Some(e) => Cow::Borrowed(e),
            None => Cow::Owned(black_environment()?),
        };
        let n = scene.materials.len();
        let mut materials = Vec::with_capacity(n);
        // One bandwidth map per texture, however many materials use it.
        let mut maps: HashMap<*const Texture, Arc<TextureBandwidth>> = HashMap::new();
        for (k, m) in scene.materials.iter().enumerate() {
            let mut built: Option<Result<MaterialTables>> = None;
            m.with_bsdf([0.5, 0.5], &mut |b: &dyn Bsdf| {
                built = Some(tables(b, &options));
            });
            let mut t = built.ok_or_else(|| {
                AdaptiveError::Parameter(format!("material {k} gave no BSDF at uv (½, ½)"))
            })??;
            for tex in m.bsdf_textures() {
                let map = match maps.get(&(tex as *const Texture)) {
                    Some(m) => m.clone(),
                    None => {
                        let m = Arc::new(TextureBandwidth::new(tex)?);
                        maps.insert(tex as *const Texture, m.clone());
                        m
                    }
                };
                t.textures.push(map);
            }
            materials.push(t);
            progress(k + 1, n);
        }
        let pyramid = if options.pyramid_face > 0 {
            Some(environment_pyramid(&env, options.pyramid_face)?)
        } else {
            None
        };
        Ok(Self {
            scene,
            env,
            materials,
            pyramid,
            lights: vec![],
        })
    }

    /// Whether the environment lights the scene (false: the scene has none, and only the
    /// area lights do).
    pub fn lit_by_environment(&self) -> bool {
        self.env.scale() > 0.0
    }

    /// Errors, saying why, when nothing lights the scene: no environment and no area light.
    pub fn check_lit(&self) -> Result<()> {
        crate::light::check_lit(self.scene, &self.lights)
    }

    /// The bandwidth side of the scene's environment (`lustre_freq`'s prediction): its map,
    /// scaled as the shading reads it; black where the scene has none. Borrows the scene, not
    /// the context.
    pub fn environment_bandwidth(&self) -> Result<EnvironmentBandwidth<'a>> {
        Ok(match &self.scene.environment {
            Some(e) => EnvironmentBandwidth::scaled(e.map(), e.scale())?,
            None => EnvironmentBandwidth::black()?,
        })
    }

    /// The spatial bandwidth of the textures of `s`'s material at `s` in cycles per metre (the
    /// largest over its textures; 0 when untextured): what Fig. IV.9's texture operator adds.
    pub fn texture_bandwidth(&self, s: &Surfel) -> f64 {
        self.materials[s.material]
            .textures
            .iter()
            .map(|t| t.at(s.uv, s.uv_rate))
            .fold(0.0, f64::max)
    }

    /// The pyramid level for frequencies up to `nu` cycles per radian ([`preconvolved_level`];
    /// 0 without a pyramid).
    pub fn level_for(&self, nu: f64) -> f64 {
        match &self.pyramid {
            Some(p) => preconvolved_level(p, nu),
            None => 0.0,
        }
    }

    /// Where a pre-convolved lookup for a BRDF bandwidth of `nu` reads: the pyramid at
    /// `Some(level)` ([`ShadingContext::level_for`]), or the map itself (`None`) where that level
    /// is 0 — nothing to filter, and the cube's finest level would only resample the map.
    pub fn preconvolved_lod(&self, nu: f64) -> Option<f64> {
        Some(self.level_for(nu)).filter(|&l| l > 0.0)
    }

    /// L_p at `s` from `n` samples (≥ 1), the environment read at `lod` (`None`: the map at full
    /// resolution); `seed` rotates the point sets.
    ///
    /// The n samples are split between the BRDF (⌈n/2⌉) and the environment's importance
    /// sampling (⌊n/2⌋), combined by the multi-sample balance heuristic (Veach 1997 §9.2):
    /// every sample X_j weighs f L cos θ / (n_f p_f(X_j) + n_l p_l(X_j)). Dirac lobes are
    /// reached by the BRDF's samples only. Each area light adds n samples of its own area.
    pub fn shade(&self, s: &Surfel, n: usize, lod: Option<f64>, seed: u64) -> Rgb {
        let env = &*self.env;
        let f = &s.frame;
        let to_local = |d: DVec3| DVec3::new(d.dot(f.t), d.dot(f.b), d.dot(f.n));
        let to_world = |d: DVec3| f.t * d.x + f.b * d.y + f.n * d.z;
        let wo = to_local(s.wo);
        let light = |d: DVec3| -> Rgb {
            match (lod, &self.pyramid) {
                (Some(l), Some(p)) => Rgb(p.sample(d, l)),
                _ => env.eval(d),
            }
        };
        // The light and the environment sampler's density at d (the map's coordinates found
        // once when the map itself is read).
        let light_and_pdf = |d: DVec3| -> (Rgb, f64) {
            match (lod, &self.pyramid) {
                (Some(l), Some(p)) => (Rgb(p.sample(d, l)), env.pdf(d)),
                _ => env.eval_and_pdf(d),
            }
        };
        let n = n.max(1);
        // Under a black environment the BRDF's and the environment's samples would find
        // nothing (area lights are reached by their own samples only).
        let (n_f, n_l) = if self.lit_by_environment() {
            (n.div_ceil(2), n / 2)
        } else {
            (0, 0)
        };
        let mut rng = SplitMix64::new(seed);
        let rot = [
            rng.next_f64(),
            rng.next_f64(),
            rng.next_f64(),
            rng.next_f64(),
        ];
        let tables = &self.materials[s.material];
        let light_rot: Vec<(f64, f64)> = self
            .lights
            .iter()
            .map(|_| (rng.next_f64(), rng.next_f64()))
            .collect();
        let mut sum = Rgb::ZERO;
        let mut add = |v: Rgb| {
            if v.0.iter().all(|c| c.is_finite()) {
                sum += v;
            }
        };
        self.scene.materials[s.material].with_bsdf(s.uv, &mut |b: &dyn Bsdf| {
            let brdf_pdf = |wi: DVec3| match &tables.sampler {
                Some(t) => t.pdf(wi, wo),
                None => b.pdf(wi, wo),
            };
            let mix = |p_f: f64, p_l: f64| n_f as f64 * p_f + n_l as f64 * p_l;
            for k in 0..n_f {
                let (h1, h2) = hammersley(k as u32, n_f as u32);
                let (u1, u2) = ((h1 + rot[0]).fract(), (h2 + rot[1]).fract());
                match &tables.sampler {
                    Some(t) => {
                        if let Some(wi) = t.sample(wo, u1, u2) {
                            let (l, p_l) = light_and_pdf(to_world(wi));
                            let den = mix(t.pdf(wi, wo), p_l);
                            if den > 0.0 {
                                add(b.eval(wi, wo) * (wi.z.abs() / den) * l);
                            }
                        }
                    }
                    None => {
                        if let Some(smp) = b.sample(wo, u1, u2) {
                            let d = to_world(smp.wi);
                            if smp.is_delta() {
                                add(smp.weight() * light(d) * (1.0 / n_f as f64));
                            } else {
                                let (l, p_l) = light_and_pdf(d);
                                let den = mix(smp.pdf, p_l);
                                if den > 0.0 {
                                    add(smp.value * (smp.wi.z.abs() / den) * l);
                                }
                            }
                        }
                    }
                }
            }
            for k in 0..n_l {
                let (h1, h2) = hammersley(k as u32, n_l as u32);
                let (u1, u2) = ((h1 + rot[2]).fract(), (h2 + rot[3]).fract());
                let (d, _) = env.sample(u1, u2);
                let wi = to_local(d);
                let (l, p_l) = light_and_pdf(d);
                let den = mix(brdf_pdf(wi), p_l);
                if den > 0.0 {
                    add(b.eval(wi, wo) * (wi.z.abs() / den) * l);
                }
            }
            // Area lights: n points per light, stratified over its area, each weighing
            // A cos θl / (n d²) (the solid angle it stands for).
            for (area, &(r1, r2)) in self.lights.iter().zip(&light_rot) {
                for k in 0..n {
                    let (h1, h2) = hammersley(k as u32, n as u32);
                    let (u, v) = ((h1 + r1).fract(), (h2 + r2).fract());
                    let (w, dist, cos_l) = area.towards(s.position, u, v);
                    if cos_l <= 0.0 {
                        continue;
                    }
                    let wi = to_local(w);
                    let g = cos_l * area.area() / (dist * dist * n as f64);
                    add(b.eval(wi, wo) * (wi.z.abs() * g) * area.emitted(u, v));
                }
            }
        });
        sum
    }
}

/// The fraction of a frequency's amplitude the pre-convolved lookup keeps at the BRDF's
/// bandwidth (see [`preconvolved_level`]).
pub const PRECONVOLVED_PASSBAND: f64 = 0.95;

/// The standard deviation of a level-ℓ lookup of a pyramid built with `filter`, in level-ℓ
/// texels: each down-sampling step adds the kernel's variance v (in parent texels²), so level ℓ
/// holds v (4^ℓ − 1)/3 level-0 texels² ≈ v/3 of its own texels², and the bilinear tap adds 1/6
/// (Gauss6: v = 5/4, σ = 0.76; Gauss4: 0.65; Box2: 0.5).
fn lookup_sigma_texels(filter: MipFilter) -> f64 {
    let (w, _) = filter.kernel();
    let mean: f64 = w.iter().enumerate().map(|(i, w)| i as f64 * w).sum();
    let var: f64 = w
        .iter()
        .enumerate()
        .map(|(i, w)| (i as f64 - mean).powi(2) * w)
        .sum();
    (var / 3.0 + 1.0 / 6.0).sqrt()
}

/// The coarsest level of `pyramid` that keeps [`PRECONVOLVED_PASSBAND`] (a) of the amplitude of
/// a frequency of `nu` cycles per radian: a level-ℓ lookup blurs by a Gaussian of σ = s 2^ℓ (π/2)
/// / face radians (s from [`lookup_sigma_texels`]), which scales frequency ν by e^{−2π² σ² ν²};
/// so 2^ℓ = √(−ln a / (2π²)) / (s (π/2) ν / face): for the Gaussian 6×6 pyramid about 2.9
/// levels finer than where the level's Nyquist frequency meets ν. Clamped to the pyramid; ν ≤ 0
/// or not finite reads level 0.
pub fn preconvolved_level(pyramid: &CubePyramid, nu: f64) -> f64 {
    if !(nu > 0.0 && nu.is_finite()) {
        return 0.0;
    }
    let top = (pyramid.level_count() - 1) as f64;
    let sigma = (-PRECONVOLVED_PASSBAND.ln() / (2.0 * PI * PI)).sqrt() / nu;
    let texel0 = lookup_sigma_texels(pyramid.filter) * (PI / 2.0) / pyramid.base_size() as f64;
    (sigma / texel0).log2().clamp(0.0, top)
}

/// The environment of a scene without one: black (a uniform map, radiance scale 0).
fn black_environment() -> Result<EnvLight> {
    let map = lustre_env::EquirectMap::new(8, 4, vec![[1.0; 3]; 32])?;
    Ok(EnvLight::new(map, glam::DMat3::IDENTITY, 0.0)?)
}

/// The tables of one BSDF.
fn tables(b: &dyn Bsdf, options: &ShadingOptions) -> Result<MaterialTables> {
    let f = b.flags();
    let sampler = if f.transmission || f.has_delta() {
        None
    } else {
        Some(TabulatedSampler::new(b, options.tabulated)?)
    };
    Ok(MaterialTables {
        name: b.name(),
        sampler,
        bandwidth: brdf_bandwidth(b, options.bandwidth)?,
        textures: vec![],
    })
}

/// A pixel's seed: the frame's seed mixed with the pixel index.
pub fn pixel_seed(seed: u64, pixel: usize) -> u64 {
    let mut r = SplitMix64::new(seed ^ (pixel as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    r.next_u64()
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_env::CubeMap;

    /// A cosine of ν cycles per radian across the +z face's centre, read at the pre-convolved
    /// level, keeps about [`PRECONVOLVED_PASSBAND`] of its amplitude (less at the face centre,
    /// where a cube texel spans 4/π of the mean texel angle); at 004's Nyquist level it is
    /// nearly gone.
    #[test]
    fn the_preconvolved_level_keeps_the_brdf_bandwidth() {
        let face = 256;
        for filter in [MipFilter::Gauss6, MipFilter::Gauss4, MipFilter::Box2] {
            for nu in [1.0, 2.0, 4.0] {
                let cube = CubeMap::from_fn(face, |d| {
                    let v = 1.0 + (2.0 * PI * nu * d.x.atan2(d.z)).cos();
                    [v; 3]
                })
                .expect("cube");
                let p = CubePyramid::build(cube, filter).expect("pyramid");
                let amplitude = |level: f64| p.sample(DVec3::Z, level)[0] - 1.0;
                let level = preconvolved_level(&p, nu);
                let nyquist = (face as f64 / (PI * nu)).log2();
                assert!(
                    level > 0.5 && level < nyquist - 1.5,
                    "{filter:?} ν {nu}: {level}"
                );
                let kept = amplitude(level);
                assert!(
                    (0.85..0.99).contains(&kept),
                    "{filter:?} ν {nu}: level {level:.2} keeps {kept:.3}"
                );
                let at_nyquist = amplitude(nyquist);
                assert!(
                    at_nyquist < 0.35,
                    "{filter:?} ν {nu}: {at_nyquist:.3} at {nyquist:.2}"
                );
            }
        }
        let p = CubePyramid::build(
            CubeMap::from_fn(4, |_| [1.0; 3]).expect("cube"),
            MipFilter::Gauss6,
        )
        .expect("pyramid");
        for nu in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(preconvolved_level(&p, nu), 0.0);
        }
        assert_eq!(preconvolved_level(&p, 1e-9), 2.0);
    }
}
