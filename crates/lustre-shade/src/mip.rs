//! Per-sample MIP levels for environment-map lookups in a cube-map pyramid.
//!
//! - [`lobe_area`], [`regular_level`]: 002 §6, Eq. 14–16 (the regular patterns of 002 §5).
//! - [`thesis_level`]: 000 §4.4.3, Eq. 4.14–4.17 (the same area, projected with d² / cos β).
//! - [`ck_level`]: Colbert & Křivánek 2007 (filtered importance sampling).
//!
//! Every level is clamped to `[0, log2(face_size)]` (the pyramid goes down to 1×1, so larger
//! levels read the same texel), and a NaN level becomes 0.

use glam::DVec3;

/// Largest tan α of [`lobe_area`]: a lobe edge at or beyond 90° from the lobe centre (grazing
/// views of rough lobes) would make tan α infinite or negative; tan 89° ≈ 57 is used instead.
pub const MAX_TAN_ALPHA: f64 = 57.289_961_630_759_42;

/// Clamps a level to `[0, log2(face_size)]`; NaN → 0.
fn clamp_level(level: f64, face_size: usize) -> f64 {
    let top = (face_size.max(1) as f64).log2();
    if level.is_nan() {
        0.0
    } else {
        level.clamp(0.0, top)
    }
}

/// Mirror of `wo` about the unit vector `h`: 2 (wo·h) h − wo.
fn reflect(wo: DVec3, h: DVec3) -> DVec3 {
    2.0 * wo.dot(h) * h - wo
}

/// tan of the angle between two unit vectors, capped at [`MAX_TAN_ALPHA`] (002 Eq. 14–15).
fn tan_between(a: DVec3, b: DVec3) -> f64 {
    let alpha = a.dot(b).clamp(-1.0, 1.0).acos();
    let t = alpha.tan();
    if alpha >= std::f64::consts::FRAC_PI_2 || !t.is_finite() {
        MAX_TAN_ALPHA
    } else {
        t.min(MAX_TAN_ALPHA)
    }
}

/// The area A = π u v at unit distance of the elliptical cross-section of a lobe
/// (002 Eq. 14–15, 000 Eq. 4.14–4.15).
///
/// The extreme half vectors at the border q = ξ0 along x and y, h_U at θ = arctan(√(−ln ξ0) mx),
/// φ = 0 and h_V at θ = arctan(√(−ln ξ0) my), φ = 90° (002 Eq. 5, 11), are turned into incident
/// directions ω_U, ω_V by reflecting `wo_local`; the lobe centre ω_C reflects `wo_local` about
/// the normal. α_U = arccos(ω_C·ω_U), α_V likewise, u = tan α_U, v = tan α_V (each capped at
/// [`MAX_TAN_ALPHA`]). `wo_local` is a unit vector in the lobe's local frame; at normal
/// incidence α = 2θ. Returns 0 for invalid input (non-positive roughness, ξ0 ∉ (0, 1)).
pub fn lobe_area(mx: f64, my: f64, xi0: f64, wo_local: DVec3) -> f64 {
    if !(mx > 0.0 && my > 0.0 && xi0 > 0.0 && xi0 < 1.0 && wo_local.is_finite()) {
        return 0.0;
    }
    let wo = wo_local.normalize_or(DVec3::Z);
    let k = (-xi0.ln()).sqrt();
    let (tu, tv) = ((k * mx).atan(), (k * my).atan());
    let hu = DVec3::new(tu.sin(), 0.0, tu.cos());
    let hv = DVec3::new(0.0, tv.sin(), tv.cos());
    let wc = reflect(wo, DVec3::Z);
    let u = tan_between(wc, reflect(wo, hu));
    let v = tan_between(wc, reflect(wo, hv));
    std::f64::consts::PI * u * v
}

/// The MIP level of one regular sample, 002 Eq. 16:
/// log4( A·N / (4 n) · ‖ωi‖/‖ωi‖∞ · 1/(ωi·h) ), at least 0.
///
/// `area` from [`lobe_area`], `n_samples` the pattern size, `wi_world` the lookup direction
/// (its length does not matter), `wi_dot_h` = ωi·h (the half-vector density factor of 002
/// Eq. 17 without the ¼), N = `face_size`² the texels of a cube face (area 4 at unit
/// distance). The cube distortion is the distance ‖ωi‖/‖ωi‖∞ to the unit cube to the first
/// power, as printed in 002 Eq. 16 (000 Eq. 4.16 uses d²/cos β: [`thesis_level`]).
pub fn regular_level(
    area: f64,
    n_samples: usize,
    wi_world: DVec3,
    wi_dot_h: f64,
    face_size: usize,
) -> f64 {
    let inf = wi_world.abs().max_element();
    if !(inf > 0.0 && wi_dot_h > 0.0 && n_samples > 0) {
        return clamp_level(f64::INFINITY, face_size);
    }
    let n_texels = (face_size * face_size) as f64;
    let d = wi_world.length() / inf;
    let pixels = area * n_texels / (4.0 * n_samples as f64) * d / wi_dot_h;
    clamp_level(pixels.log2() / 2.0, face_size)
}

/// The MIP level of one regular sample, 000 Eq. 4.16–4.17: the sample area A' = A / n at unit
/// distance, projected onto the unit cube, A'_cube = A' · d² / cos β with d = ‖ωi‖/‖ωi‖∞ the
/// distance to the cube along ωi and cos β = ‖ωi‖∞/‖ωi‖ the cosine between ωi and the face
/// normal (so A'_cube = A' d³), then pixels = A'_cube · N / 4 with N = `face_size`²; level =
/// log4(pixels), at least 0. Unlike [`regular_level`] there is no 1/(ωi·h) factor.
pub fn thesis_level(area: f64, n_samples: usize, wi_world: DVec3, face_size: usize) -> f64 {
    let inf = wi_world.abs().max_element();
    if !(inf > 0.0 && n_samples > 0) {
        return clamp_level(f64::INFINITY, face_size);
    }
    let d = wi_world.length() / inf;
    let a_cube = area / n_samples as f64 * d * d * d;
    let pixels = a_cube * (face_size * face_size) as f64 / 4.0;
    clamp_level(pixels.log2() / 2.0, face_size)
}

/// The average solid angle of a texel of a cube map with faces `face_size`², Ωp = 4π/(6 N²):
/// the choice of Ωp in [`ck_level`] (the contract's; Colbert & Křivánek use the same mean).
pub fn texel_solid_angle_mean(face_size: usize) -> f64 {
    4.0 * std::f64::consts::PI / (6.0 * (face_size * face_size) as f64)
}

/// The solid angle of the texel of a cube map with faces `face_size`² seen in direction `dir`
/// (any length), to first order in the texel size: Ωp(ω) = (2/N)² / d³ with d = ‖ω‖/‖ω‖∞ the
/// distance to the unit cube along ω (the texel area (2/N)² at distance d, tilted by cos β = 1/d).
/// 4/N² at a face centre, 4/(3√3 N²) at a cube corner; the mean over the sphere is
/// [`texel_solid_angle_mean`].
pub fn texel_solid_angle_at(dir: DVec3, face_size: usize) -> f64 {
    let n = face_size.max(1) as f64;
    let inf = dir.abs().max_element();
    let d = if inf > 0.0 { dir.length() / inf } else { 1.0 };
    4.0 / (n * n * d * d * d)
}

/// [`ck_level`] with the direction-dependent texel solid angle [`texel_solid_angle_at`] of the
/// lookup direction `dir` instead of the mean: the texels near cube corners are smaller, so
/// the same sample solid angle covers more of them (+0.72 levels at a corner, −0.47 at a face
/// centre).
pub fn ck_level_at(pdf: f64, n_samples: usize, face_size: usize, dir: DVec3) -> f64 {
    if !(pdf > 0.0 && n_samples > 0) {
        return clamp_level(f64::INFINITY, face_size);
    }
    let omega_s = 1.0 / (n_samples as f64 * pdf);
    let omega_p = texel_solid_angle_at(dir, face_size);
    clamp_level(0.5 * (omega_s / omega_p).log2() + 1.0, face_size)
}

/// The Colbert-Křivánek MIP level of a sample drawn with density `pdf` (1/sr) out of
/// `n_samples`: max(½·log2(Ωs/Ωp) + 1, 0) with Ωs = 1/(N·pdf) and Ωp
/// = [`texel_solid_angle_mean`] (the mean texel solid angle, not the direction-dependent one;
/// the "+1" is their bias). A non-positive or NaN pdf gives the coarsest level.
pub fn ck_level(pdf: f64, n_samples: usize, face_size: usize) -> f64 {
    if !(pdf > 0.0 && n_samples > 0) {
        return clamp_level(f64::INFINITY, face_size);
    }
    let omega_s = 1.0 / (n_samples as f64 * pdf);
    let omega_p = texel_solid_angle_mean(face_size);
    clamp_level(0.5 * (omega_s / omega_p).log2() + 1.0, face_size)
}

/// The bias of [`footprint_level`] (in levels), measured on the truth harness
/// (`examples/truth_study.rs`): the Gaussian 6×6 pyramid's level-l lookup (with its bilinear
/// tap) has a standard deviation of ≈ 0.76·2^l texels, more than twice a square cell's
/// 0.29·side, so a cell of side 2^l texels is best read somewhat finer than level l.
pub const FOOTPRINT_LEVEL_BIAS: f64 = -0.5;

/// The MIP level of one cell of the row lattice (ours, `pattern::row_lattice`): the cell's
/// solid angle `cell` = mass / p(ωi) (sr) over the solid angle of the texel seen along
/// `wi_world` ([`texel_solid_angle_at`], the cube distortion d³), level = ½ log2(cell / Ωp) +
/// [`FOOTPRINT_LEVEL_BIAS`], clamped to `[0, log2(face_size)]`; a non-positive or NaN cell gives
/// the coarsest level.
pub fn footprint_level(cell: f64, wi_world: DVec3, face_size: usize) -> f64 {
    if cell.is_nan() || cell <= 0.0 {
        return clamp_level(f64::INFINITY, face_size);
    }
    let omega_p = texel_solid_angle_at(wi_world, face_size);
    clamp_level(
        0.5 * (cell / omega_p).log2() + FOOTPRINT_LEVEL_BIAS,
        face_size,
    )
}
