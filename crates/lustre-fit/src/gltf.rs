//! The glTF 2.0 metallic-roughness material (the specification's Appendix B,
//! [`PbrMetallicRoughness`]) fitted to measured data, for export to engines that read glTF.
//!
//! # The fit
//!
//! For a fixed metallic m and roughness r the model is linear in the base colour c, per channel:
//!
//! ```text
//! f = c·A + B,   A = (1 − m)(1 − F)/π + m·S(1 − s),   B = (1 − m)·F·S + m·S·s
//! S = D G / (4 cos θi cos θo) (GGX, α = r²),  s = (1 − |ωo·h|)⁵,  F = 0.04 + 0.96 s
//! ```
//!
//! so the base colour that minimizes Ngan's L2 is solved in closed form ([`crate::linear`]).
//! Metallic and roughness are searched: a grid (11 metallic × 25 roughness
//! values, geometric in roughness from √1e-3, the model's smallest α, to 1), then golden-section
//! refinements of each in turn around the best node. A and B come from the model itself (its
//! value with a white and a black base colour), so the fit always minimizes the error of the
//! model the exporter writes.
//!
//! Anisotropic data also gets `KHR_materials_anisotropy` (strength s, rotation ρ: α_t = mix(α,
//! 1, s²) along the rotated tangent, α_b = α = r² across it): a grid over s ∈ {0.3, 0.5, 0.7,
//! 0.85, 0.95}, ρ ∈ {0, π/8, …, 7π/8} (ρ and ρ + π are the same lobe) and r ∈ {0.4, 0.6, 0.8,
//! 1} × the isotropic best, then a Nelder–Mead simplex over (ln α_b, ln α_t, ρ, m) (α_b and α_t
//! are the lobe's independent widths across and along the direction, where r and s move
//! together); kept only where it lowers the error.

use crate::data::MeasuredData;
use crate::linear::{golden, Rows, Sums};
use crate::metrics::{evaluate_masked, ErrorReport};
use lustre_brdf::models::pbr_metallic_roughness::{PbrMetallicRoughness, PBR_ALPHA_MIN};
use lustre_brdf::rgb::Rgb;
use lustre_brdf::Result;
use serde::{Deserialize, Serialize};

/// A glTF metallic-roughness material fitted to data, with its errors against the data.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GltfFit {
    /// `baseColorFactor` (linear RGB).
    pub base_color: [f64; 3],
    /// `metallicFactor`.
    pub metallic: f64,
    /// `roughnessFactor` (perceptual: α = roughness²).
    pub roughness: f64,
    /// `KHR_materials_anisotropy` strength (0: isotropic).
    #[serde(default)]
    pub anisotropy: f64,
    /// `KHR_materials_anisotropy` rotation from the tangent, radians in [0, π).
    #[serde(default)]
    pub anisotropy_rotation: f64,
    /// The fitted model's errors against the data (Ngan L2, L1, albedos).
    pub errors: ErrorReport,
}

impl GltfFit {
    /// The fitted model.
    pub fn model(&self) -> Result<PbrMetallicRoughness> {
        Params {
            m: self.metallic,
            r: self.roughness,
            s: self.anisotropy,
            rho: self.anisotropy_rotation,
        }
        .model(Rgb(self.base_color))
    }
}

/// The searched parameters: metallic, roughness, anisotropy strength and rotation.
#[derive(Clone, Copy, Debug)]
struct Params {
    m: f64,
    r: f64,
    s: f64,
    rho: f64,
}

impl Params {
    fn model(self, c: Rgb) -> Result<PbrMetallicRoughness> {
        let p = PbrMetallicRoughness::new(c, self.m, self.r)?;
        if self.s > 0.0 {
            p.with_anisotropy(self.s, self.rho)
        } else {
            Ok(p)
        }
    }
}

/// The smallest roughness searched: the model clamps α = r² below at [`PBR_ALPHA_MIN`].
fn min_roughness() -> f64 {
    PBR_ALPHA_MIN.sqrt()
}

/// The least-squares sums of the model at `p`.
fn sums(rows: &Rows, p: Params) -> Result<Sums> {
    let white = p.model(Rgb::splat(1.0))?;
    let black = p.model(Rgb::splat(0.0))?;
    Ok(rows.sums(&black, &white))
}

fn objective(rows: &Rows, p: Params) -> Result<f64> {
    Ok(sums(rows, p)?.solve(&rows.amax).1)
}

/// Minimizes `f` over ℝ⁴ from `x0` by Nelder–Mead (reflection 1, expansion 2, contraction ½,
/// shrink ½) with initial steps `step`, for at most `max_evals` evaluations or until the
/// simplex's values agree to 1e-12 (relative); the best point and its value.
fn nelder_mead(
    x0: [f64; 4],
    step: [f64; 4],
    max_evals: usize,
    f: impl Fn(&[f64; 4]) -> Result<f64>,
) -> Result<([f64; 4], f64)> {
    let mut pts: Vec<([f64; 4], f64)> = Vec::with_capacity(5);
    pts.push((x0, f(&x0)?));
    for i in 0..4 {
        let mut x = x0;
        x[i] += step[i];
        pts.push((x, f(&x)?));
    }
    let mut evals = 5;
    let lerp = |a: &[f64; 4], b: &[f64; 4], t: f64| -> [f64; 4] {
        [0, 1, 2, 3].map(|k| a[k] + t * (b[k] - a[k]))
    };
    while evals < max_evals {
        pts.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (lo, hi) = (pts[0].1, pts[4].1);
        if hi - lo <= 1e-12 * (lo.abs() + hi.abs()) + 1e-300 {
            break;
        }
        let centroid = [0, 1, 2, 3].map(|k| pts[..4].iter().map(|p| p.0[k]).sum::<f64>() / 4.0);
        let worst = pts[4].0;
        let xr = lerp(&centroid, &worst, -1.0);
        let fr = f(&xr)?;
        evals += 1;
        if fr < pts[0].1 {
            let xe = lerp(&centroid, &worst, -2.0);
            let fe = f(&xe)?;
            evals += 1;
            pts[4] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < pts[3].1 {
            pts[4] = (xr, fr);
        } else {
            let xc = lerp(&centroid, &worst, 0.5);
            let fc = f(&xc)?;
            evals += 1;
            if fc < pts[4].1 {
                pts[4] = (xc, fc);
            } else {
                let best = pts[0].0;
                for p in pts.iter_mut().skip(1) {
                    let x = lerp(&best, &p.0, 0.5);
                    *p = (x, f(&x)?);
                    evals += 1;
                }
            }
        }
    }
    pts.sort_by(|a, b| a.1.total_cmp(&b.1));
    Ok(pts[0])
}

/// The anisotropy search (module notes) from the isotropic best `iso` with error `e`.
fn fit_anisotropy(rows: &Rows, iso: Params, e: f64, r_lo: f64) -> Result<(Params, f64)> {
    use std::f64::consts::PI;
    let (mut best, mut err) = (iso, e);
    for s in [0.3, 0.5, 0.7, 0.85, 0.95] {
        for k in 0..8 {
            for f in [0.4, 0.6, 0.8, 1.0] {
                let p = Params {
                    s,
                    rho: k as f64 * PI / 8.0,
                    r: (iso.r * f).max(r_lo),
                    ..iso
                };
                let e = objective(rows, p)?;
                if e < err {
                    (best, err) = (p, e);
                }
            }
        }
    }
    if best.s == 0.0 {
        return Ok((best, err));
    }
    // α_b = r² and α_t = mix(α_b, 1, s²) set the lobe's width across and along the
    // anisotropy direction independently, where r and s move together: a Nelder–Mead simplex
    // over (ln α_b, ln α_t, ρ, m), the parameters clamped to their ranges.
    let alpha = |r: f64| (r * r).max(PBR_ALPHA_MIN);
    let to_params = |x: &[f64; 4]| {
        let a = x[0].exp().clamp(PBR_ALPHA_MIN, 1.0);
        let at = x[1].exp().clamp(a, 1.0);
        Params {
            r: a.sqrt().max(r_lo),
            s: ((at - a) / (1.0 - a).max(1e-12)).sqrt().min(1.0),
            rho: x[2],
            m: x[3].clamp(0.0, 1.0),
        }
    };
    let a0 = alpha(best.r);
    let x0 = [
        a0.ln(),
        (a0 + (1.0 - a0) * best.s * best.s).ln(),
        best.rho,
        best.m,
    ];
    let (x, e) = nelder_mead(x0, [0.3, 0.3, 0.15, 0.1], 600, |x| {
        objective(rows, to_params(x))
    })?;
    if e < err {
        best = to_params(&x);
        best.rho = best.rho.rem_euclid(PI);
        err = e;
    }
    Ok((best, err))
}

/// Fits the glTF metallic-roughness model to `data` (module notes).
pub fn fit_gltf(data: &MeasuredData) -> Result<GltfFit> {
    let rows = Rows::new(data);
    let (r_lo, steps) = (min_roughness(), 24);
    let roughness: Vec<f64> = (0..=steps)
        .map(|k| r_lo * (1.0 / r_lo).powf(k as f64 / steps as f64))
        .collect();
    let iso = |m: f64, r: f64| Params {
        m,
        r,
        s: 0.0,
        rho: 0.0,
    };
    let (mut best_m, mut best_r, mut best) = (0.0, 1.0, f64::INFINITY);
    for &r in &roughness {
        for k in 0..=10 {
            let m = k as f64 / 10.0;
            let e = objective(&rows, iso(m, r))?;
            if e < best {
                (best_m, best_r, best) = (m, r, e);
            }
        }
    }
    // Refine roughness (in log space, within a grid step either side), then metallic, twice.
    let ratio = (1.0 / r_lo).powf(1.0 / steps as f64);
    for _ in 0..2 {
        let (lo, hi) = (
            (best_r / ratio).max(r_lo).ln(),
            (best_r * ratio).min(1.0).ln(),
        );
        let (lr, e) = golden(lo, hi, |x| objective(&rows, iso(best_m, x.exp())))?;
        if e < best {
            (best_r, best) = (lr.exp(), e);
        }
        let (m, e) = golden((best_m - 0.1).max(0.0), (best_m + 0.1).min(1.0), |m| {
            objective(&rows, iso(m, best_r))
        })?;
        if e < best {
            (best_m, best) = (m, e);
        }
    }
    let mut p = iso(best_m, best_r);
    if data.bsdf.flags().anisotropic {
        p = fit_anisotropy(&rows, p, best, r_lo)?.0;
    }
    let (base_color, _) = sums(&rows, p)?.solve(&rows.amax);
    let model = p.model(Rgb(base_color))?;
    let errors = evaluate_masked(
        data.bsdf.as_ref(),
        &model,
        data.transmission,
        data.coverage.as_ref(),
    );
    Ok(GltfFit {
        base_color,
        metallic: p.m,
        roughness: p.r,
        anisotropy: p.s,
        anisotropy_rotation: p.rho,
        errors,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_brdf::bsdf::Bsdf;

    /// The model is linear in its base colour, as the fit assumes.
    #[test]
    fn the_model_is_linear_in_the_base_colour() {
        let dirs = [
            (0.3, 0.1, 0.8, -0.2, 0.4, 0.7),
            (0.0, 0.6, 0.5, 0.5, 0.0, 0.2),
            (-0.7, 0.2, 0.3, 0.6, 0.1, 0.9),
        ];
        for (m, r) in [(0.0, 0.2), (0.3, 0.5), (1.0, 0.05), (0.7, 1.0)] {
            let white = PbrMetallicRoughness::new(Rgb::splat(1.0), m, r).expect("model");
            let black = PbrMetallicRoughness::new(Rgb::splat(0.0), m, r).expect("model");
            let c = Rgb([0.2, 0.55, 0.9]);
            let model = PbrMetallicRoughness::new(c, m, r).expect("model");
            for &(a, b, z, d, e, w) in &dirs {
                let wi = glam::DVec3::new(a, b, z).normalize();
                let wo = glam::DVec3::new(d, e, w).normalize();
                let (f1, f0, f) = (white.eval(wi, wo), black.eval(wi, wo), model.eval(wi, wo));
                for k in 0..3 {
                    let lin = c.0[k] * (f1.0[k] - f0.0[k]) + f0.0[k];
                    assert!((lin - f.0[k]).abs() <= 1e-12 * f.0[k].abs().max(1.0));
                }
            }
        }
    }

    /// Data made by the model itself is fitted back: its parameters and an error near zero.
    #[test]
    fn recovers_the_parameters_of_its_own_model() {
        for (c, m, r) in [
            ([0.8, 0.5, 0.2], 1.0, 0.3),
            ([0.1, 0.4, 0.7], 0.0, 0.45),
            ([0.9, 0.9, 0.85], 0.35, 0.2),
        ] {
            let truth = PbrMetallicRoughness::new(Rgb(c), m, r).expect("model");
            let fit = fit_gltf(&MeasuredData::from_bsdf("truth", Box::new(truth))).expect("fit");
            assert!(fit.errors.ngan_mean() < 2e-3, "{fit:?}");
            assert!((fit.roughness - r).abs() < 0.01, "{fit:?}");
            assert!((fit.metallic - m).abs() < 0.02, "{fit:?}");
            for (got, want) in fit.base_color.iter().zip(&c) {
                assert!((got - want).abs() < 0.01, "{fit:?}");
            }
        }
    }

    /// An anisotropic model is fitted back with its strength and rotation.
    #[test]
    fn recovers_an_anisotropic_model() {
        let truth = PbrMetallicRoughness::new(Rgb([0.9, 0.7, 0.5]), 1.0, 0.25)
            .and_then(|m| m.with_anisotropy(0.7, 1.1))
            .expect("model");
        let data = MeasuredData::from_bsdf("truth", Box::new(truth));
        let fit = fit_gltf(&data).expect("fit");
        assert!(fit.errors.ngan_mean() < 0.02, "{fit:?}");
        assert!((fit.anisotropy - 0.7).abs() < 0.03, "{fit:?}");
        assert!((fit.anisotropy_rotation - 1.1).abs() < 0.03, "{fit:?}");
        assert!((fit.roughness - 0.25).abs() < 0.01, "{fit:?}");
        assert!(fit.model().expect("model").flags().anisotropic);
    }
}
