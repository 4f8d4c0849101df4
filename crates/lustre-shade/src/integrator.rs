//! Per-pixel integrators: the specular integral of 002 Eq. 8 / 000 Eq. 4.3,
//!
//! L_o(ωo) = ∫ L_i(ωi) f(ωi, ωo) |cos θi| dωi,
//!
//! evaluated against a pre-filtered cube-map pyramid ([`FilteredEnvironment`]) by four integrators:
//!
//! - [`shade_regular`]: the regular half-vector patterns of 002 §5–7 (pseudo code
//!   `EvaluateSpecularLobe`), with the weightings of [`Weighting`] (002 Eq. 17–18; 000 Eq. 4.24,
//!   4.25) and per-sample MIP levels (002 Eq. 14–16). A straight loop that the GPU renderer mirrors
//!   line by line.
//! - [`shade_ck`]: Colbert & Křivánek (2007): Hammersley points through the importance warp
//!   (002 Eq. 6–7), pdf Eq. 10, MIP level from the pdf ([`crate::mip::ck_level`]).
//! - [`shade_reference`]: seeded Monte-Carlo importance sampling of any [`Bsdf`] on level 0
//!   (bilinear), reflection and transmission, diffuse included (000 §4.4.2, Eq. 4.4).
//! - [`Progressive`]: the same estimator with a QMC sequence (Sobol' (0,2)-sequence, per-pixel
//!   Cranley–Patterson rotation) accumulating across calls — 000 §4.4.2's refinement while the
//!   camera is still.
//!
//! Compact, very bright sources split off the map ([`lustre_env::split_suns`]) are shaded exactly
//! as directional lights by [`shade_suns`]; [`plan_lattice_sun`] plans ours around them.
//!
//! Optionally a lookup is corrected by [`BoundingPlane`]s (000 §4.4.1, Fig. 4.5): the secondary
//! ray from the shaded position is intersected with the planes and the cube map is read in the
//! direction from the projection centre to the hit point.
//!
//! **Two-sided surfaces.** Like [`Kurt`]'s thin-surface convention, a viewer below the surface
//! (wo·n < 0) is shaded with the frame flipped (n → −n, b → −b, so that b = n × t still holds):
//! the diffuse term and reflection lobes then act on the lower side and transmission lobes carry
//! light from the upper side. A viewer exactly in the tangent plane receives nothing.

use crate::mip;
use crate::pattern::{self, ConcentricOptions, Pattern, PatternKind};
use crate::{Result, ShadeError};
use glam::DVec3;
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::frame::{mirror_z, reflect};
use lustre_brdf::models::kurt::{
    lobe_eval, lobe_pdf, lobe_sample_h, schlick, Kurt, KurtLobe, LobeKind,
};
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::{hammersley, radical_inverse2, SplitMix64};
use lustre_env::{CubeMap, CubePyramid, EnvSampler, EquirectMap, Sun};
use lustre_trace::sampling::{power_heuristic, ShadingFrame, Strategy};

/// The number of samples below which a [`shade_reference`] image is not called a reference
/// (002 §8 uses "> 10000 samples").
pub const REFERENCE_SAMPLES: usize = 10_000;

/// The frame `f` facing `wo` (flipped when wo·n < 0) and `wo` in it.
#[inline]
fn facing(f: &ShadingFrame, wo: DVec3) -> (ShadingFrame, DVec3) {
    let f = if wo.dot(f.n) < 0.0 { f.flipped() } else { *f };
    (f, f.to_local(wo))
}

/// The pre-filtered incident light: a cube-map MIP pyramid for the lobes and an irradiance map
/// storing E(n)/π for the diffuse term (so that diffuse radiance = kd · lookup(n)).
#[derive(Clone, Copy, Debug)]
pub struct FilteredEnvironment<'a> {
    /// The radiance pyramid (002 §3).
    pub pyramid: &'a CubePyramid,
    /// Irradiance over π, looked up bilinearly at the normal.
    pub irradiance: &'a CubeMap,
}

/// A plane bounding the scene (000 §4.4.1): a secondary ray is intersected with it and the cube
/// map is read towards the hit point instead of along the ray. Positions are in world space with
/// the cube map's projection centre at the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingPlane {
    /// A point on the plane.
    pub point: DVec3,
    /// The plane's normal (any length > 0; normalized by [`BoundingPlane::new`]).
    pub normal: DVec3,
}

impl BoundingPlane {
    /// A plane through `point` with normal `normal`; an error unless both are finite and the
    /// normal is non-zero.
    pub fn new(point: DVec3, normal: DVec3) -> Result<Self> {
        if !point.is_finite() {
            return Err(ShadeError::Parameter(format!(
                "bounding plane point {point} is not finite"
            )));
        }
        let normal = normal.try_normalize().ok_or_else(|| {
            ShadeError::Parameter(format!(
                "bounding plane normal {normal} must be finite and non-zero"
            ))
        })?;
        Ok(BoundingPlane { point, normal })
    }

    /// The ray parameter s > 0 where `pos + s·dir` meets the plane, or `None` when the ray is
    /// parallel to the plane or points away from it, or when `pos` does not lie strictly on
    /// the projection centre's side of the plane: the planes bound the space around the centre
    /// and a secondary ray leaves it through them, so a point on a plane (a floor shaded
    /// through a probe whose floor plane is that floor) or beyond it is not bounded by it —
    /// else the sign of a rounding error in (q − p)·m would decide whether the lookup turns
    /// back towards the point itself.
    pub fn intersect(&self, pos: DVec3, dir: DVec3) -> Option<f64> {
        let denom = dir.dot(self.normal);
        if denom.is_nan() || denom.abs() <= 1e-12 {
            return None;
        }
        let gap = (self.point - pos).dot(self.normal);
        // A NaN gap (a non-finite position) is refused too.
        if gap * self.point.dot(self.normal) <= 0.0 || gap.is_nan() {
            return None;
        }
        let s = gap / denom;
        (s > 0.0 && s.is_finite()).then_some(s)
    }

    /// The corrected lookup direction (000 Fig. 4.5): the unit vector from the projection centre
    /// (origin) to where the secondary ray `pos + s·dir` hits the plane; `dir` itself when it
    /// misses or the hit point is the centre.
    pub fn corrected_direction(&self, pos: DVec3, dir: DVec3) -> DVec3 {
        self.intersect(pos, dir)
            .and_then(|s| (pos + dir * s).try_normalize())
            .unwrap_or(dir)
    }
}

/// The lookup direction for a secondary ray from `pos` along `dir` with several bounding planes:
/// the nearest hit wins (000 §4.4.1); `dir` when no plane is hit.
pub fn corrected_direction(planes: &[BoundingPlane], pos: DVec3, dir: DVec3) -> DVec3 {
    let mut best: Option<(f64, &BoundingPlane)> = None;
    for p in planes {
        if let Some(s) = p.intersect(pos, dir) {
            if best.is_none_or(|(b, _)| s < b) {
                best = Some((s, p));
            }
        }
    }
    match best {
        Some((s, _)) => (pos + dir * s).try_normalize().unwrap_or(dir),
        None => dir,
    }
}

/// Where the lookups of one pixel happen when bounding planes correct them: the shaded position
/// (relative to the projection centre) and the planes.
#[derive(Clone, Copy, Debug)]
pub struct Lookup<'a> {
    /// The shaded point, world space, projection centre at the origin.
    pub position: DVec3,
    /// The bounding planes ([`corrected_direction`]).
    pub planes: &'a [BoundingPlane],
}

/// Radiance from `env` along the world direction `wi` at MIP level `lod`, through the optional
/// bounding-plane correction.
#[inline]
pub(crate) fn incident(
    env: &FilteredEnvironment,
    lookup: Option<&Lookup>,
    wi: DVec3,
    lod: f64,
) -> Rgb {
    let d = match lookup {
        Some(l) => corrected_direction(l.planes, l.position, wi),
        None => wi,
    };
    Rgb(env.pyramid.sample(d, lod))
}

/// Diffuse radiance kd · E(n)/π (000 Eq. 3.6's kd/π term integrated against the irradiance map).
#[inline]
fn diffuse(kd: Rgb, env: &FilteredEnvironment, n: DVec3) -> Rgb {
    kd * Rgb(env.irradiance.bilinear(n))
}

/// How the regular samples of one lobe are weighted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weighting {
    /// 002 Eq. 17–18 and the pseudo code: pdf_i = p_h / (4 h·ωi) with the constant
    /// p_h = mean D(h) over the pattern; L = (1/n) Σ L_i f_i cos θi / pdf_i.
    Pdf002,
    /// 000 Eq. 4.24: L = Σ L_i cos²θi f_i / Σ p_i cos θi, p the importance pdf (Eq. 4.9).
    Thesis424,
    /// 000 Eq. 4.25: L = Σ L_i cos²θi f_i²/p_i / Σ f_i cos θi.
    Thesis425,
}

/// The regular pattern of one Kurt lobe.
#[derive(Clone, Debug)]
pub struct LobePlan {
    /// Half vectors in the lobe's local frame and the pdf constant (002 §5, Eq. 18).
    pub pattern: Pattern,
}

/// A Kurt material with one regular pattern per lobe, built once and reused at every pixel.
#[derive(Clone, Debug)]
pub struct MaterialPlan {
    /// The material.
    pub kurt: Kurt,
    /// One plan per reflection lobe, in the order of `kurt.reflection`.
    pub reflection: Vec<LobePlan>,
    /// One plan per transmission lobe, in the order of `kurt.transmission`.
    pub transmission: Vec<LobePlan>,
    /// Suns split off the environment ([`plan_lattice_sun`]), shaded exactly by
    /// [`shade_suns`] after the lobes; empty for every other plan.
    pub suns: Vec<Sun>,
}

/// Builds the regular patterns of every lobe: `pattern::concentric_for_budget(mx, my, budget,
/// xi0)` (the largest concentric pattern within the budget; 002 §5 takes the closest, which
/// may exceed it). Errors: an invalid material (negative or non-finite roughness, ks, kd, r0
/// or α out of range), a zero budget, or ξ0 outside (0, 1).
pub fn plan_regular(kurt: &Kurt, budget_per_lobe: usize, xi0: f64) -> Result<MaterialPlan> {
    plan_regular_with(kurt, budget_per_lobe, xi0, ConcentricOptions::default())
}

/// [`plan_regular`] with options of the concentric pattern, e.g. `ConcentricOptions { reach:
/// Some(1.0) }`: the rings stretched so the outermost lies at θmax (measured better than the
/// printed radii on the 002 §8 map; `examples/regular_study.rs`, `lustre compare`).
pub fn plan_regular_with(
    kurt: &Kurt,
    budget_per_lobe: usize,
    xi0: f64,
    opts: ConcentricOptions,
) -> Result<MaterialPlan> {
    if !(xi0 > 0.0 && xi0 < 1.0) {
        return Err(ShadeError::Parameter(format!(
            "xi0 = {xi0}: the pattern border must lie in (0, 1)"
        )));
    }
    plan_with(kurt, budget_per_lobe, |l| {
        pattern::concentric_for_budget_opts(l.mx, l.my, budget_per_lobe, xi0, opts)
    })
}

/// Builds the thesis patterns of every lobe (`pattern::thesis`, 000 §4.4.3: centre + ring, or a
/// line along the major axis when strongly anisotropic), the patterns 000 Eq. 4.24–4.25 were
/// designed for. Errors as [`plan_regular`].
pub fn plan_thesis(kurt: &Kurt, budget_per_lobe: usize) -> Result<MaterialPlan> {
    plan_with(kurt, budget_per_lobe, |l| {
        pattern::thesis(l.mx, l.my, budget_per_lobe)
    })
}

/// Plans every lobe with ours, the per-pixel row lattice ([`pattern::row_lattice`]): exactly
/// `budget_per_lobe` filtered lookups per lobe (fewer where samples fall below the horizon),
/// see [`shade_regular_with`]. Errors as [`plan_regular`].
pub fn plan_lattice(kurt: &Kurt, budget_per_lobe: usize) -> Result<MaterialPlan> {
    plan_with(kurt, budget_per_lobe, |l| {
        pattern::row_lattice(l.mx, l.my, budget_per_lobe)
    })
}

/// Ours with the environment's suns split off ([`lustre_env::split_suns`]): every lobe planned
/// with the row lattice of `budget_per_lobe − suns.len()` lookups, and each sun evaluated
/// exactly per lobe ([`shade_suns`], one evaluation each, charged against the budget), so a
/// pixel still makes at most `budget_per_lobe` per lobe. Shade it with a [`FilteredEnvironment`] whose
/// pyramid is the split's residual (the irradiance map stays the whole map's). Errors as
/// [`plan_regular`], or a budget that leaves the lattice no lookup.
pub fn plan_lattice_sun(kurt: &Kurt, budget_per_lobe: usize, suns: &[Sun]) -> Result<MaterialPlan> {
    if budget_per_lobe <= suns.len() {
        return Err(ShadeError::Parameter(format!(
            "a budget of {budget_per_lobe} per lobe leaves no lookup beside {} sun evaluations",
            suns.len()
        )));
    }
    let mut plan = plan_lattice(kurt, budget_per_lobe - suns.len())?;
    plan.suns = suns.to_vec();
    Ok(plan)
}

/// Plans every lobe with the row lattice whose long cells are read by several taps along their
/// long axis ([`pattern::tap_lattice`], an anisotropic footprint per cell): still at most
/// `budget_per_lobe` filtered lookups per lobe, with fewer cells where cells take several taps.
/// See [`shade_regular_with`]. Errors as [`plan_regular`].
pub fn plan_tap_lattice(kurt: &Kurt, budget_per_lobe: usize) -> Result<MaterialPlan> {
    plan_with(kurt, budget_per_lobe, |l| {
        pattern::tap_lattice(l.mx, l.my, budget_per_lobe)
    })
}

/// Validates the material and the budget, then builds one pattern per lobe with `make`.
fn plan_with(
    kurt: &Kurt,
    budget_per_lobe: usize,
    make: impl Fn(&KurtLobe) -> Result<Pattern>,
) -> Result<MaterialPlan> {
    kurt.validate()?;
    if budget_per_lobe == 0 {
        return Err(ShadeError::Parameter(
            "sample budget per lobe must be at least 1".into(),
        ));
    }
    let plan = |lobes: &[KurtLobe]| -> Result<Vec<LobePlan>> {
        lobes
            .iter()
            .map(|l| Ok(LobePlan { pattern: make(l)? }))
            .collect()
    };
    Ok(MaterialPlan {
        kurt: kurt.clone(),
        reflection: plan(&kurt.reflection)?,
        transmission: plan(&kurt.transmission)?,
        suns: vec![],
    })
}

/// Regular sampling (002 §5–7): diffuse = kd · irradiance(n) plus, per lobe, the pseudo code
/// `EvaluateSpecularLobe` with the weighting `w`. See [`shade_regular_with`].
pub fn shade_regular(
    f: &ShadingFrame,
    wo: DVec3,
    plan: &MaterialPlan,
    env: &FilteredEnvironment,
    w: Weighting,
) -> Rgb {
    shade_regular_with(f, wo, plan, env, w, None)
}

/// [`shade_regular`] that also returns the number of filtered (pyramid) lookups it made, the
/// irradiance lookup of the diffuse term not counted.
pub fn shade_regular_counted(
    f: &ShadingFrame,
    wo: DVec3,
    plan: &MaterialPlan,
    env: &FilteredEnvironment,
    w: Weighting,
) -> (Rgb, usize) {
    shade_regular_full(f, wo, plan, env, w, None)
}

/// [`shade_regular`] with optional bounding-plane lookups. `wo` is the world direction to the
/// viewer. Per lobe (the GPU renderer mirrors this loop):
///
/// 1. A = π u v, the lobe's cross-section at unit distance (002 Eq. 14–15, [`mip::lobe_area`]).
/// 2. For each pattern half vector h (lobe-local = shading-local frame): ωi = 2(ωo·h)h − ωo
///    (the pseudo code's `reflect(−ωo, h)`, 000 Eq. 4.8). For a transmission lobe the light
///    comes from ωi mirrored through the tangent plane (000 Eq. 3.5–3.6) and the lobe is
///    evaluated on the mirrored pair, as [`lobe_eval`] with [`LobeKind::Transmission`] expects.
///    Samples with ωi below the horizon are skipped (they still count in n for [`Weighting::Pdf002`]).
/// 3. level = [`mip::regular_level`] (002 Eq. 16), L = pyramid lookup at that level.
/// 4. f = [`lobe_eval`] (002 Eq. 2 with Eq. 3–5), weighted by `w`.
///
/// Lobes planned with [`plan_lattice`] ([`PatternKind::RowLattice`]) take ours instead, and
/// ignore `w` ([`lattice_lobe`]): equal-mass cells of the slope-space Gaussian, laid out per
/// pixel in rows across the lobe's image in ωi so that every cell is about round there, each
/// read once at the level of its own solid angle ([`mip::footprint_level`]); lobes planned with
/// [`plan_tap_lattice`] ([`PatternKind::TapLattice`]) read the cells that are long in ωi by
/// several taps along their long axis, within the same budget. A plan with suns
/// ([`plan_lattice_sun`]) adds their exact contribution ([`shade_suns`]) and counts each
/// evaluation as a lookup.
pub fn shade_regular_with(
    f: &ShadingFrame,
    wo: DVec3,
    plan: &MaterialPlan,
    env: &FilteredEnvironment,
    w: Weighting,
    lookup: Option<&Lookup>,
) -> Rgb {
    shade_regular_full(f, wo, plan, env, w, lookup).0
}

/// [`shade_regular_with`] and the number of pyramid lookups made.
fn shade_regular_full(
    f: &ShadingFrame,
    wo: DVec3,
    plan: &MaterialPlan,
    env: &FilteredEnvironment,
    w: Weighting,
    lookup: Option<&Lookup>,
) -> (Rgb, usize) {
    let (frame, wo_l) = facing(f, wo);
    if wo_l.z.is_nan() || wo_l.z <= 0.0 {
        return (Rgb::ZERO, 0);
    }
    let k = &plan.kurt;
    let mut out = diffuse(k.kd, env, frame.n);
    let lobes = k
        .reflection
        .iter()
        .zip(&plan.reflection)
        .map(|(l, p)| (l, p, LobeKind::Reflection))
        .chain(
            k.transmission
                .iter()
                .zip(&plan.transmission)
                .map(|(l, p)| (l, p, LobeKind::Transmission)),
        );
    let mut lookups = 0;
    for (lobe, lp, kind) in lobes {
        let px = Pixel {
            frame,
            wo_l,
            env,
            lookup,
        };
        let (c, n) = match lp.pattern.kind {
            PatternKind::RowLattice { budget } => lattice_lobe(&px, lobe, kind, budget, 1),
            PatternKind::TapLattice { budget } => {
                lattice_lobe(&px, lobe, kind, budget, pattern::LATTICE_MAX_TAPS)
            }
            _ => regular_lobe(&px, lobe, kind, &lp.pattern, w),
        };
        out += c;
        lookups += n;
    }
    let (c, n) = suns_facing(&frame, wo_l, k, &plan.suns);
    (out + c, lookups + n)
}

/// The lobes of `kurt` lit by suns split off the environment ([`lustre_env::split_suns`]),
/// exactly: Σ_suns Σ_lobes f(ωs, ωo) |cos θs| E_s (000 Eq. 3.3–3.6 at the sun's direction; a
/// transmission lobe takes light from below, evaluated on the pair mirrored through the tangent
/// plane as [`lobe_eval`] expects). The diffuse term is not included: it reads the irradiance
/// map, which is built from the whole map, suns included. Also returns the evaluations made (one
/// per sun and lobe on the lobe's side), which a fair comparison charges against the budget.
/// Frames and two-sided surfaces as [`shade_regular`].
pub fn shade_suns(f: &ShadingFrame, wo: DVec3, kurt: &Kurt, suns: &[Sun]) -> (Rgb, usize) {
    let (frame, wo_l) = facing(f, wo);
    if wo_l.z.is_nan() || wo_l.z <= 0.0 {
        return (Rgb::ZERO, 0);
    }
    suns_facing(&frame, wo_l, kurt, suns)
}

/// [`shade_suns`] in the frame already facing the viewer, ωo = `wo_l` above the surface.
fn suns_facing(frame: &ShadingFrame, wo_l: DVec3, kurt: &Kurt, suns: &[Sun]) -> (Rgb, usize) {
    let mut out = Rgb::ZERO;
    let mut evals = 0;
    for sun in suns {
        let s = frame.to_local(sun.direction);
        let e = Rgb(sun.irradiance);
        let (lobes, kind, wi) = if s.z > 0.0 {
            (&kurt.reflection, LobeKind::Reflection, s)
        } else if s.z < 0.0 {
            (&kurt.transmission, LobeKind::Transmission, mirror_z(s))
        } else {
            continue;
        };
        for lobe in lobes {
            out += lobe_eval(&sun_widened(lobe, sun.spread), kind, wi, wo_l) * e * wi.z;
            evals += 1;
        }
    }
    (out, evals)
}

/// `lobe` convolved with a sun's extent: the sun's texels lie around its direction with an
/// energy-weighted RMS angle `spread` (2D), so σ² = spread²/2 per axis in ωi and, the half
/// vector turning by half as much, spread²/8 in h; the lobe's slope distribution is a Gaussian
/// of variance m²/2 per axis (000 Eq. 4.5), so the convolution has m'² = m² + spread²/4 (near
/// the lobe's centre, where slope ≈ angle). Evaluated at the sun's direction, it stands for
/// ∫_sun f L dω / E to second order, where a point would over-read a sharp lobe's peak.
pub fn sun_widened(lobe: &KurtLobe, spread: f64) -> KurtLobe {
    let w = if spread.is_finite() {
        spread * spread / 4.0
    } else {
        0.0
    };
    KurtLobe {
        mx: (lobe.mx * lobe.mx + w).sqrt(),
        my: (lobe.my * lobe.my + w).sqrt(),
        ..*lobe
    }
}

/// What one pixel's lobes share: the frame facing the viewer, ωo in it (above the surface), the
/// light and the optional lookup correction.
struct Pixel<'a> {
    frame: ShadingFrame,
    wo_l: DVec3,
    env: &'a FilteredEnvironment<'a>,
    lookup: Option<&'a Lookup<'a>>,
}

/// One lobe of [`shade_regular_with`] with a stored pattern; the radiance and the lookups.
fn regular_lobe(
    px: &Pixel,
    lobe: &KurtLobe,
    kind: LobeKind,
    pattern: &Pattern,
    w: Weighting,
) -> (Rgb, usize) {
    let Pixel {
        frame,
        wo_l,
        env,
        lookup,
    } = *px;
    let n = pattern.h.len();
    if n == 0 {
        return (Rgb::ZERO, 0);
    }
    // The lobe shape without its colour: Eq. 4.25 squares f, so ks is applied once at the end
    // (as the pseudo code's `SpecularCoefficient * brdfSum`).
    let unit = KurtLobe {
        ks: Rgb::ONE,
        ..*lobe
    };
    let face = env.pyramid.base_size();
    // 002 Eq. 14–15: A = π u v.
    let area = mip::lobe_area(lobe.mx, lobe.my, pattern.xi0, wo_l);
    let mut sum = Rgb::ZERO;
    let mut weight_sum = 0.0;
    let mut lookups = 0;
    for &h in &pattern.h {
        let ho = wo_l.dot(h); // ωo·h = ωi·h
        if ho.is_nan() || ho <= 0.0 {
            continue;
        }
        let r = reflect(wo_l, h); // 000 Eq. 4.8
        let cos_i = r.z;
        if cos_i.is_nan() || cos_i <= 0.0 {
            continue;
        }
        let wi_l = match kind {
            LobeKind::Reflection => r,
            LobeKind::Transmission => mirror_z(r), // 000 Eq. 3.5: the thin-BTDF's direction
        };
        let wi = frame.to_world(wi_l);
        let level = mip::regular_level(area, n, wi, ho, face); // 002 Eq. 16
        let li = incident(env, lookup, wi, level);
        lookups += 1;
        let g = lobe_eval(&unit, kind, r, wo_l)[0]; // 002 Eq. 2
        match w {
            Weighting::Pdf002 => {
                // 002 Eq. 17–18: p_o = p_h / (4 h·ωi).
                let pdf = pattern.pdf_constant / (4.0 * ho);
                if pdf > 0.0 {
                    sum += li * (g * cos_i / pdf); // 002 Eq. 9, inner sum
                }
            }
            Weighting::Thesis424 => {
                let p = lobe_pdf(&unit, r, wo_l); // 000 Eq. 4.9
                sum += li * (cos_i * cos_i * g);
                weight_sum += p * cos_i;
            }
            Weighting::Thesis425 => {
                let p = lobe_pdf(&unit, r, wo_l);
                if p > 0.0 {
                    sum += li * (cos_i * cos_i * g * g / p);
                    weight_sum += g * cos_i;
                }
            }
        }
    }
    let scale = match w {
        Weighting::Pdf002 => 1.0 / n as f64,
        Weighting::Thesis424 | Weighting::Thesis425 => {
            if weight_sum > 0.0 {
                1.0 / weight_sum
            } else {
                0.0
            }
        }
    };
    (lobe.ks * sum * scale, lookups)
}

/// The major axis of the lobe's image in ωi at its centre and the ratio of its axes: the
/// Jacobian of the slope-space point s ↦ h = normalize(mx sx, my sy, 1) ↦ ωi = 2(ωo·h)h − ωo at
/// s = 0 has the columns 2 m_a (ωo_a n + ωo_z e_a) (a = x, y), so JᵀJ = 4 [[mx² (ωo_x² + ωo_z²),
/// mx my ωo_x ωo_y], [mx my ωo_x ωo_y, my² (ωo_y² + ωo_z²)]]. Returns the unit eigenvector of the
/// larger eigenvalue (in s) and √(λ1/λ2) ≥ 1; ωo must lie above the surface.
pub fn lattice_axes(mx: f64, my: f64, wo_l: DVec3) -> ((f64, f64), f64) {
    let a = 4.0 * mx * mx * (wo_l.x * wo_l.x + wo_l.z * wo_l.z);
    let c = 4.0 * my * my * (wo_l.y * wo_l.y + wo_l.z * wo_l.z);
    let b = 4.0 * mx * my * wo_l.x * wo_l.y;
    let half = 0.5 * (a - c);
    let root = (half * half + b * b).sqrt();
    let (l1, l2) = (0.5 * (a + c) + root, 0.5 * (a + c) - root);
    let ratio = (l1 / l2).sqrt();
    let (ex, ey) = if half >= 0.0 {
        (half + root, b)
    } else {
        (b, root - half)
    };
    let len = (ex * ex + ey * ey).sqrt();
    let e1 = if len > 0.0 && len.is_finite() {
        (ex / len, ey / len)
    } else {
        (1.0, 0.0)
    };
    (e1, if ratio.is_finite() { ratio } else { 1.0 })
}

/// One lobe with ours, the row lattice of `budget` lookups (a [`PatternKind::RowLattice`] plan
/// with `max_taps` = 1, a [`PatternKind::TapLattice`] plan with [`pattern::LATTICE_MAX_TAPS`]);
/// the radiance and the lookups made (≤ `budget`).
///
/// 1. The lobe is the Gaussian e^{−|s|²}/π of the slope-space point s (h ∝ (mx sx, my sy, 1);
///    its density is D(h) cos θh, 000 Eq. 4.5–4.7). Its image in ωi has the axes of
///    [`lattice_axes`]: major e1, ratio ρ.
/// 2. k = [`pattern::lattice_rows`]`(c, ρ)` rows along the minor axis e2 at the quantiles
///    y_j = [`pattern::gauss_quantile`]((j + ½)/k), row j holding m_j = [`pattern::row_length`]
///    cells at x_i = quantile((i + ½)/m_j) along e1: c cells of mass μ = 1/(k m_j), about
///    round in ωi near the centre (grazing views and anisotropy stretch the lattice, not the
///    cells). With one tap per cell, c = `budget`.
/// 3. With taps ([`lattice_taps`]): a cell that is long in ωi (the tails: a quantile cell
///    widens as the density falls) is read by t = round(long/short) ≤ `max_taps` taps at its
///    sub-quantiles along the long axis, each of mass μ/t and read at its own (≈ the short
///    axis's) level — hardware anisotropic filtering inside the cell. c is the largest cell
///    count whose taps fit the budget ([`lattice_cells`]); cells whose centre lies below the
///    horizon count 0 taps.
/// 4. Each s = x e1 + y e2 gives h and ωi = 2(ωo·h)h − ωo (mirrored through the tangent plane
///    for transmission, 000 Eq. 3.5); samples with ωo·h ≤ 0 or ωi below the horizon contribute
///    nothing and make no lookup (the integrand is zero there).
/// 5. The tap's solid angle is μ / p(ωi), p = D cos θh / (4 ωo·h) (000 Eq. 4.9) =
///    e^{−|s|²} / (4π mx my (ωo·h) cos³θh); it is read at [`mip::footprint_level`].
/// 6. Weight μ · f cos θi / p = μ · F cos θi / (((cos θi cos θo)^α) cos θh) (000 Eq. 3.4 over
///    Eq. 4.9; F = 1 − Schlick for transmission), so L = ks Σ μ F cos θi L̄ / (G cos θh).
fn lattice_lobe(
    px: &Pixel,
    lobe: &KurtLobe,
    kind: LobeKind,
    budget: usize,
    max_taps: usize,
) -> (Rgb, usize) {
    let Pixel {
        frame,
        wo_l,
        env,
        lookup,
    } = *px;
    if budget == 0 {
        return (Rgb::ZERO, 0);
    }
    let face = env.pyramid.base_size();
    let (mx, my) = (lobe.mx, lobe.my);
    let ((e1x, e1y), ratio) = lattice_axes(mx, my, wo_l);
    let geo = LatticeGeometry {
        mx,
        my,
        e1: (e1x, e1y),
        wo_l,
    };
    let max_taps = max_taps.clamp(1, budget);
    let (cells, rows) = lattice_cells(&geo, budget, ratio, max_taps);
    let mut sum = Rgb::ZERO;
    let mut lookups = 0;
    for j in 0..rows {
        let m = pattern::row_length(cells, rows, j);
        for i in 0..m {
            let (taps, along_e1) = if max_taps > 1 {
                lattice_taps(&geo, i, m, j, rows, max_taps)
            } else {
                (1, true)
            };
            let mass = 1.0 / (rows * m * taps) as f64;
            for q in 0..taps {
                let sub = (q as f64 + 0.5) / taps as f64;
                let (ux, uy) = if along_e1 {
                    ((i as f64 + sub) / m as f64, (j as f64 + 0.5) / rows as f64)
                } else {
                    ((i as f64 + 0.5) / m as f64, (j as f64 + sub) / rows as f64)
                };
                let s = geo.slope(pattern::gauss_quantile(ux), pattern::gauss_quantile(uy));
                let h = DVec3::new(mx * s.0, my * s.1, 1.0).normalize();
                let ho = wo_l.dot(h);
                if ho.is_nan() || ho <= 0.0 {
                    continue;
                }
                let r = reflect(wo_l, h);
                let cos_i = r.z;
                if cos_i.is_nan() || cos_i <= 0.0 {
                    continue;
                }
                let wi_l = match kind {
                    LobeKind::Reflection => r,
                    LobeKind::Transmission => mirror_z(r),
                };
                let wi = frame.to_world(wi_l);
                let cell = mass
                    * 4.0
                    * std::f64::consts::PI
                    * mx
                    * my
                    * ho
                    * h.z.powi(3)
                    * (s.0 * s.0 + s.1 * s.1).exp();
                let li = incident(env, lookup, wi, mip::footprint_level(cell, wi, face));
                lookups += 1;
                let f = schlick(lobe.r0, ho);
                let fresnel = match kind {
                    LobeKind::Reflection => f,
                    LobeKind::Transmission => 1.0 - f,
                };
                let shadow = if lobe.alpha == 0.0 {
                    1.0
                } else {
                    (cos_i * wo_l.z).powf(lobe.alpha)
                };
                sum += li * (mass * fresnel * cos_i / (shadow * h.z));
            }
        }
    }
    (lobe.ks * sum, lookups)
}

/// The lattice of one lobe at one pixel: roughness, the major axis e1 of the lobe's image in ωi
/// (in slope space; e2 = e1 turned by 90°) and ωo (local, above the surface).
pub struct LatticeGeometry {
    /// Roughness along the tangent.
    pub mx: f64,
    /// Roughness along the bitangent.
    pub my: f64,
    /// The unit major axis in slope space ([`lattice_axes`]).
    pub e1: (f64, f64),
    /// ωo in the local frame.
    pub wo_l: DVec3,
}

impl LatticeGeometry {
    /// The slope-space point x e1 + y e2.
    #[inline]
    pub fn slope(&self, x: f64, y: f64) -> (f64, f64) {
        let (a, b) = self.e1;
        (x * a - y * b, x * b + y * a)
    }

    /// |∂ωi/∂s| along the slope-space unit vector `e` at the half vector h = n/|n|, n = (mx sx,
    /// my sy, 1): dh = (dn − h (h·dn))/|n| with dn = (mx e_x, my e_y, 0), dωi = 2((ωo·dh) h +
    /// (ωo·h) dh).
    fn stretch(&self, h: DVec3, len: f64, e: (f64, f64)) -> f64 {
        let dn = DVec3::new(self.mx * e.0, self.my * e.1, 0.0);
        let dh = (dn - h * h.dot(dn)) / len;
        (2.0 * (self.wo_l.dot(dh) * h + self.wo_l.dot(h) * dh)).length()
    }
}

/// The taps of cell (i of `m`, row j of `rows`) of a lattice and whether they run along e1
/// (else along e2): the cell's widths at its centre s = x_i e1 + y_j e2 are the quantile steps
/// 1/m / φ(x_i) and 1/rows / φ(y_j) (φ(x) = e^{−x²}/√π, the marginal density) times
/// |∂ωi/∂s| along e1 and e2 ([`LatticeGeometry::stretch`]); the cell gets t = round(long /
/// short) taps, clamped to 1 ..= `max_taps`, along its long axis. A cell whose centre has
/// ωo·h ≤ 0 or ωi below the horizon gets 0 taps (the integrand is zero there; its taps are
/// not read).
pub fn lattice_taps(
    geo: &LatticeGeometry,
    i: usize,
    m: usize,
    j: usize,
    rows: usize,
    max_taps: usize,
) -> (usize, bool) {
    let x = pattern::gauss_quantile((i as f64 + 0.5) / m as f64);
    let y = pattern::gauss_quantile((j as f64 + 0.5) / rows as f64);
    let s = geo.slope(x, y);
    let n = DVec3::new(geo.mx * s.0, geo.my * s.1, 1.0);
    let len = n.length();
    let h = n / len;
    let ho = geo.wo_l.dot(h);
    if !(ho > 0.0 && reflect(geo.wo_l, h).z > 0.0) {
        return (0, true);
    }
    let (a, b) = geo.e1;
    let wx = geo.stretch(h, len, (a, b)) * (x * x).exp() / m as f64;
    let wy = geo.stretch(h, len, (-b, a)) * (y * y).exp() / rows as f64;
    let aspect = wx / wy;
    if !(aspect.is_finite() && aspect > 0.0) {
        return (1, true);
    }
    let (t, along_e1) = if aspect >= 1.0 {
        (aspect, true)
    } else {
        (1.0 / aspect, false)
    };
    ((t.round() as usize).clamp(1, max_taps.max(1)), along_e1)
}

/// The cells and rows of a lattice with at most `budget` taps: with `max_taps` = 1, `budget`
/// cells in [`pattern::lattice_rows`]`(budget, ratio)` rows; otherwise the largest cell count
/// c ≤ `budget` whose taps ([`lattice_taps`] summed over its cells) are at most `budget`.
pub fn lattice_cells(
    geo: &LatticeGeometry,
    budget: usize,
    ratio: f64,
    max_taps: usize,
) -> (usize, usize) {
    if max_taps <= 1 {
        return (budget, pattern::lattice_rows(budget, ratio));
    }
    'count: for cells in (1..=budget).rev() {
        let rows = pattern::lattice_rows(cells, ratio);
        let mut total = 0;
        for j in 0..rows {
            let m = pattern::row_length(cells, rows, j);
            for i in 0..m {
                total += lattice_taps(geo, i, m, j, rows, max_taps).0;
                if total > budget {
                    continue 'count;
                }
            }
        }
        return (cells, rows);
    }
    (1, 1)
}

/// Colbert & Křivánek (2007) filtered importance sampling with [`Kurt`] lobes. See
/// [`shade_ck_with`].
pub fn shade_ck(
    f: &ShadingFrame,
    wo: DVec3,
    kurt: &Kurt,
    n_samples: usize,
    env: &FilteredEnvironment,
) -> Rgb {
    shade_ck_with(f, wo, kurt, n_samples, env, None)
}

/// [`shade_ck`] that also returns the number of pyramid lookups it made (≤ `n_samples` per
/// lobe: samples below the horizon make none).
pub fn shade_ck_counted(
    f: &ShadingFrame,
    wo: DVec3,
    kurt: &Kurt,
    n_samples: usize,
    env: &FilteredEnvironment,
) -> (Rgb, usize) {
    shade_ck_full(f, wo, kurt, n_samples, env, None)
}

/// [`shade_ck`] with optional bounding-plane lookups. Diffuse = kd · irradiance(n). **Per-lobe
/// budgets**: every lobe (reflection and transmission) receives its own `n_samples` Hammersley
/// points (u1, u2) — the same per-lobe budget as [`plan_regular`]'s — warped to half vectors by
/// [`lobe_sample_h`] (002 Eq. 6–7), reflected (000 Eq. 4.8; mirrored for transmission), and
/// weighted by f cos θi / p with p from 002 Eq. 10 ([`lobe_pdf`]); each is looked up at
/// [`mip::ck_level`]`(p, n_samples, face)`. Samples below the horizon contribute zero but count.
/// `n_samples = 0` leaves the diffuse term only.
pub fn shade_ck_with(
    f: &ShadingFrame,
    wo: DVec3,
    kurt: &Kurt,
    n_samples: usize,
    env: &FilteredEnvironment,
    lookup: Option<&Lookup>,
) -> Rgb {
    shade_ck_full(f, wo, kurt, n_samples, env, lookup).0
}

/// [`shade_ck_with`] and the number of pyramid lookups made.
fn shade_ck_full(
    f: &ShadingFrame,
    wo: DVec3,
    kurt: &Kurt,
    n_samples: usize,
    env: &FilteredEnvironment,
    lookup: Option<&Lookup>,
) -> (Rgb, usize) {
    let (frame, wo_l) = facing(f, wo);
    if wo_l.z.is_nan() || wo_l.z <= 0.0 {
        return (Rgb::ZERO, 0);
    }
    let mut out = diffuse(kurt.kd, env, frame.n);
    if n_samples == 0 {
        return (out, 0);
    }
    let mut lookups = 0;
    let face = env.pyramid.base_size();
    let lobes = kurt
        .reflection
        .iter()
        .map(|l| (l, LobeKind::Reflection))
        .chain(
            kurt.transmission
                .iter()
                .map(|l| (l, LobeKind::Transmission)),
        );
    let n = n_samples.min(u32::MAX as usize) as u32;
    for (lobe, kind) in lobes {
        let mut sum = Rgb::ZERO;
        for k in 0..n {
            let (u1, u2) = hammersley(k, n);
            let h = lobe_sample_h(lobe, u1, u2); // 002 Eq. 6–7
            let ho = wo_l.dot(h);
            if ho.is_nan() || ho <= 0.0 {
                continue;
            }
            let r = reflect(wo_l, h);
            if r.z.is_nan() || r.z <= 0.0 {
                continue;
            }
            let pdf = lobe_pdf(lobe, r, wo_l); // 002 Eq. 10
            if !(pdf > 0.0 && pdf.is_finite()) {
                continue;
            }
            let wi_l = match kind {
                LobeKind::Reflection => r,
                LobeKind::Transmission => mirror_z(r),
            };
            let wi = frame.to_world(wi_l);
            let li = incident(env, lookup, wi, mip::ck_level(pdf, n as usize, face));
            lookups += 1;
            sum += li * lobe_eval(lobe, kind, r, wo_l) * (r.z / pdf); // 002 Eq. 9
        }
        out += sum / n as f64;
    }
    (out, lookups)
}

/// Monte-Carlo reference (000 Eq. 4.4 with the BSDF's own importance sampling): `n_samples`
/// directions from [`Bsdf::sample`] driven by [`SplitMix64`]`(seed)`, each weighted by
/// f |cos θi| / p and lit by the pyramid's level 0 (bilinear). Diffuse, reflection and
/// transmission all come through the sampler. `n_samples = 0` gives black. A reference image
/// uses at least [`REFERENCE_SAMPLES`].
pub fn shade_reference(
    f: &ShadingFrame,
    wo: DVec3,
    bsdf: &dyn Bsdf,
    env: &FilteredEnvironment,
    n_samples: usize,
    seed: u64,
) -> Rgb {
    shade_reference_with(f, wo, bsdf, env, n_samples, seed, None)
}

/// [`shade_reference`] with optional bounding-plane lookups.
pub fn shade_reference_with(
    f: &ShadingFrame,
    wo: DVec3,
    bsdf: &dyn Bsdf,
    env: &FilteredEnvironment,
    n_samples: usize,
    seed: u64,
    lookup: Option<&Lookup>,
) -> Rgb {
    if n_samples == 0 {
        return Rgb::ZERO;
    }
    let wo_l = f.to_local(wo);
    let mut rng = SplitMix64::new(seed);
    let mut sum = Rgb::ZERO;
    for _ in 0..n_samples {
        let (u1, u2) = (rng.next_f64(), rng.next_f64());
        sum += reference_sample(f, wo_l, bsdf, env, lookup, u1, u2);
    }
    sum / n_samples as f64
}

/// One term L(ωi) f |cos θi| / p of the importance-sampled estimator, level 0.
#[inline]
fn reference_sample(
    f: &ShadingFrame,
    wo_l: DVec3,
    bsdf: &dyn Bsdf,
    env: &FilteredEnvironment,
    lookup: Option<&Lookup>,
    u1: f64,
    u2: f64,
) -> Rgb {
    match bsdf.sample(wo_l, u1, u2) {
        Some(s) => {
            let wt = s.weight();
            if wt.is_finite() {
                incident(env, lookup, f.to_world(s.wi), 0.0) * wt
            } else {
                Rgb::ZERO
            }
        }
        None => Rgb::ZERO,
    }
}

/// The texel width (equirect, = 2 × height) of [`env_sampler`]'s distribution for a pyramid
/// with `face`² faces: 4 × face (equal texel size at the equator), clamped to [64, 2048].
pub fn env_sampler_width(face: usize) -> usize {
    (4 * face).clamp(64, 2048)
}

/// The importance sampler of a pyramid's level 0: an equirect map of
/// [`env_sampler_width`]`(face)` texels filled with bilinear level-0 lookups at the texel
/// centres, sampled by [`EnvSampler`] (sin θ-weighted piecewise-constant 2D distribution).
/// Errors when the map is black.
pub fn env_sampler(pyramid: &CubePyramid) -> Result<EnvSampler> {
    let w = env_sampler_width(pyramid.base_size());
    let h = w / 2;
    let data: Vec<[f32; 3]> = (0..w * h)
        .map(|k| {
            let d = EquirectMap::pixel_dir(w, h, k % w, k / w);
            pyramid.sample(d, 0.0).map(|v| v as f32)
        })
        .collect();
    let map = EquirectMap::new(w, h, data)?;
    Ok(EnvSampler::new(&map)?)
}

/// Monte-Carlo reference with environment importance sampling and multiple importance sampling
/// (000 Eq. 4.4; Veach 1997 §9.2): per iteration, with [`Strategy::Mis`], one direction from
/// [`Bsdf::sample`] weighted by f |cos θi| / p_f · w_f and one from `sampler` weighted by
/// L f |cos θi| / p_l · w_l, w the [`power_heuristic`]; lit by the pyramid's level 0
/// (bilinear), as [`shade_reference`]. [`Strategy::Bsdf`] and [`Strategy::Light`] keep one
/// technique with weight 1 (the test of the combination: all three converge to the same value).
/// `n_samples` iterations driven by [`SplitMix64`]`(seed)`; `n_samples = 0` gives black.
#[allow(clippy::too_many_arguments)]
pub fn shade_reference_mis(
    f: &ShadingFrame,
    wo: DVec3,
    bsdf: &dyn Bsdf,
    env: &FilteredEnvironment,
    sampler: &EnvSampler,
    strategy: Strategy,
    n_samples: usize,
    seed: u64,
) -> Rgb {
    if n_samples == 0 {
        return Rgb::ZERO;
    }
    let wo_l = f.to_local(wo);
    let mut rng = SplitMix64::new(seed);
    let mut sum = Rgb::ZERO;
    for _ in 0..n_samples {
        if strategy != Strategy::Light {
            let (u1, u2) = (rng.next_f64(), rng.next_f64());
            if let Some(s) = bsdf.sample(wo_l, u1, u2) {
                let wt = s.weight();
                if wt.is_finite() {
                    let wi = f.to_world(s.wi);
                    let mis = if strategy == Strategy::Mis && !s.lobe.is_specular() {
                        power_heuristic(s.pdf, sampler.pdf(wi))
                    } else {
                        1.0
                    };
                    sum += incident(env, None, wi, 0.0) * wt * mis;
                }
            }
        }
        if strategy != Strategy::Bsdf {
            let (u1, u2) = (rng.next_f64(), rng.next_f64());
            let s = sampler.sample(u1, u2);
            let wi_l = f.to_local(s.dir);
            let fv = bsdf.eval(wi_l, wo_l);
            if s.pdf > 0.0 && fv != Rgb::ZERO {
                let mis = if strategy == Strategy::Mis {
                    power_heuristic(s.pdf, bsdf.pdf(wi_l, wo_l))
                } else {
                    1.0
                };
                let c = incident(env, None, s.dir, 0.0) * fv * (wi_l.z.abs() / s.pdf * mis);
                if c.is_finite() {
                    sum += c;
                }
            }
        }
    }
    sum / n_samples as f64
}

/// The i-th point of the Sobol' (0,2)-sequence in [0, 1)²: the base-2 radical inverse and the
/// second Sobol' dimension (generator matrix = Pascal's triangle mod 2). Any prefix of 2^m points
/// is a (0, m, 2)-net, so the sequence can be extended sample by sample.
#[inline]
pub fn sobol02(i: u32) -> (f64, f64) {
    let mut r = 0u32;
    let mut v = 1u32 << 31;
    let mut k = i;
    while k != 0 {
        if k & 1 != 0 {
            r ^= v;
        }
        k >>= 1;
        v ^= v >> 1;
    }
    (radical_inverse2(i), r as f64 * (1.0 / 4_294_967_296.0))
}

/// A seed for pixel (x, y) of an image rendered with `seed` (decorrelates neighbouring pixels).
pub fn pixel_seed(x: usize, y: usize, seed: u64) -> u64 {
    let mut g = SplitMix64::new(seed ^ ((x as u64) << 32 | (y as u64 & 0xffff_ffff)));
    g.next_u64()
}

/// Progressive QMC refinement of one pixel (000 §4.4.2: with a still camera the image converges
/// towards the reference over frames). Sample i uses the i-th [`sobol02`] point shifted by this
/// pixel's Cranley–Patterson rotation, pushed through [`Bsdf::sample`], lit at level 0. Calls
/// accumulate: after k calls of n samples the estimate equals [`shade_qmc`] with k·n samples.
/// The sequence index wraps after 2³² samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Progressive {
    rotation: (f64, f64),
    sum: Rgb,
    count: usize,
}

impl Progressive {
    /// An empty accumulator whose rotation is drawn from [`SplitMix64`]`(seed)`; use
    /// [`pixel_seed`] for per-pixel seeds.
    pub fn new(seed: u64) -> Self {
        let mut g = SplitMix64::new(seed);
        Progressive {
            rotation: (g.next_f64(), g.next_f64()),
            sum: Rgb::ZERO,
            count: 0,
        }
    }

    /// Adds `n` samples (the next `n` points of the sequence) for this pixel's configuration.
    pub fn add_samples(
        &mut self,
        f: &ShadingFrame,
        wo: DVec3,
        bsdf: &dyn Bsdf,
        env: &FilteredEnvironment,
        n: usize,
    ) {
        let wo_l = f.to_local(wo);
        let (r1, r2) = self.rotation;
        for i in self.count..self.count + n {
            let (a, b) = sobol02(i as u32);
            let (u1, u2) = ((a + r1).fract(), (b + r2).fract());
            self.sum += reference_sample(f, wo_l, bsdf, env, None, u1, u2);
        }
        self.count += n;
    }

    /// The current estimate (black before the first sample).
    pub fn estimate(&self) -> Rgb {
        if self.count == 0 {
            Rgb::ZERO
        } else {
            self.sum / self.count as f64
        }
    }

    /// Samples accumulated so far.
    pub fn samples(&self) -> usize {
        self.count
    }

    /// Forgets all samples (the camera moved); the rotation is kept.
    pub fn reset(&mut self) {
        self.sum = Rgb::ZERO;
        self.count = 0;
    }
}

/// One-shot QMC estimate with `n` samples: the same as a fresh [`Progressive::new`]`(seed)` fed
/// `n` samples at once.
pub fn shade_qmc(
    f: &ShadingFrame,
    wo: DVec3,
    bsdf: &dyn Bsdf,
    env: &FilteredEnvironment,
    n: usize,
    seed: u64,
) -> Rgb {
    let mut p = Progressive::new(seed);
    p.add_samples(f, wo, bsdf, env, n);
    p.estimate()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sobol_prefix_is_a_net() {
        // Every 2^m prefix is a (0, m, 2)-net: each of the 2^m elementary intervals of shape
        // 2^-a × 2^-(m-a) holds exactly one point.
        let m = 6;
        let n = 1u32 << m;
        for a in 0..=m {
            let mut seen = vec![false; n as usize];
            for i in 0..n {
                let (x, y) = sobol02(i);
                let cx = (x * (1u32 << a) as f64) as usize;
                let cy = (y * (1u32 << (m - a)) as f64) as usize;
                let cell = cx * (1usize << (m - a)) + cy;
                assert!(!seen[cell], "a = {a}, point {i} shares a cell");
                seen[cell] = true;
            }
        }
    }

    #[test]
    fn bounding_plane_by_hand() {
        // Floor y = −1; a ray from (1, 0, 0) straight down hits (1, −1, 0).
        let floor = BoundingPlane::new(DVec3::new(0.0, -1.0, 0.0), DVec3::new(0.0, 3.0, 0.0))
            .expect("valid plane");
        let pos = DVec3::new(1.0, 0.0, 0.0);
        let d = floor.corrected_direction(pos, -DVec3::Y);
        assert!(
            (d - DVec3::new(1.0, -1.0, 0.0).normalize()).length() < 1e-12,
            "{d}"
        );
        // Upwards it misses: the direction is unchanged.
        assert_eq!(floor.corrected_direction(pos, DVec3::Y), DVec3::Y);
        // With a ceiling at y = 2 the upward ray hits (1, 2, 0); downward still the floor.
        let ceiling = BoundingPlane::new(DVec3::new(0.0, 2.0, 0.0), -DVec3::Y).expect("valid");
        let planes = [floor, ceiling];
        let up = corrected_direction(&planes, pos, DVec3::Y);
        assert!((up - DVec3::new(1.0, 2.0, 0.0).normalize()).length() < 1e-12);
        let dn = corrected_direction(&planes, pos, -DVec3::Y);
        assert!((dn - d).length() < 1e-12);
        // A point on the floor plane or below it is not bounded by it: upwards it reads the
        // ceiling, downwards (leaving the room) it is not corrected by the floor.
        for y in [-1.0, -1.0 - 1e-9, -1.5] {
            let on = DVec3::new(1.0, y, 0.0);
            let up = corrected_direction(&planes, on, DVec3::Y);
            assert!(
                (up - DVec3::new(1.0, 2.0, 0.0).normalize()).length() < 1e-12,
                "{y}: {up}"
            );
            assert_eq!(
                corrected_direction(&planes, on, -DVec3::Y),
                -DVec3::Y,
                "{y}"
            );
        }
        // At the projection centre the correction is the identity.
        let w = DVec3::new(0.3, -0.8, 0.1).normalize();
        assert!((corrected_direction(&planes, DVec3::ZERO, w) - w).length() < 1e-12);
        assert!(BoundingPlane::new(DVec3::ZERO, DVec3::ZERO).is_err());
        assert!(BoundingPlane::new(DVec3::splat(f64::NAN), DVec3::Y).is_err());
    }
}
