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
//!
//! Then the layers of the ratified extensions, each a Nelder–Mead simplex over four variables
//! from the best so far (a small grid first where the layer starts from nothing), each kept only
//! where it lowers the objective by at least 1 % ([`EXTENSION_GAIN`]), in this order:
//!
//! - `KHR_materials_specular` (dielectric F0 = 0.04·t, weight k): (ln r, m, k, ln t), t ≤ 25;
//! - `KHR_materials_clearcoat` (weight w, roughness r_c): grid w ∈ {¼, ½, 1} × (r_c ∈ {0.05,
//!   0.1, 0.2, 0.35} over the core's r, or r_c = the core's r over r ∈ {0.4, 0.6, 0.8, 1}),
//!   then (ln r, m, w, ln r_c);
//! - `KHR_materials_sheen` (grey colour s, roughness r_s): grid s ∈ {¼, ½, 1} × r_s ∈ {0.3,
//!   0.6, 1}, then (ln r, m, s, r_s).
//!
//! Each layer keeps the model linear in c, so the base colour stays the closed-form solve. A
//! layer whose factors end within 1 % of the core model's (specular k, t = 1; coat or sheen
//! below 0.01) is dropped, keeping the simplex's refinement of r and m.

use crate::data::MeasuredData;
use crate::linear::{golden, Rows, Sums};
use crate::metrics::{evaluate_masked, ErrorReport};
use lustre_brdf::models::pbr_metallic_roughness::{PbrLayers, PbrMetallicRoughness, PBR_ALPHA_MIN};
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
    /// `KHR_materials_specular` / `_clearcoat` / `_sheen` (the core model where no layer helped).
    #[serde(default)]
    pub layers: PbrLayers,
    /// Ngan's L2 (mean over RGB) of the core metallic-roughness fit (anisotropy included),
    /// before the layers: what a reader without the three extensions sees.
    #[serde(default)]
    pub core_ngan_l2: f64,
    /// The fitted model's errors against the data (Ngan L2, L1, albedos).
    pub errors: ErrorReport,
}

/// The least relative gain of the objective for which a layer is written.
pub const EXTENSION_GAIN: f64 = 0.01;

impl GltfFit {
    /// The fitted model.
    pub fn model(&self) -> Result<PbrMetallicRoughness> {
        Params {
            m: self.metallic,
            r: self.roughness,
            s: self.anisotropy,
            rho: self.anisotropy_rotation,
            layers: self.layers,
        }
        .model(Rgb(self.base_color))
    }
}

/// The searched parameters: metallic, roughness, anisotropy strength and rotation, layers.
#[derive(Clone, Copy, Debug)]
struct Params {
    m: f64,
    r: f64,
    s: f64,
    rho: f64,
    layers: PbrLayers,
}

impl Params {
    fn model(self, c: Rgb) -> Result<PbrMetallicRoughness> {
        let p = PbrMetallicRoughness::new(c, self.m, self.r)?.with_layers(1.5, self.layers)?;
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
            layers: iso.layers,
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
        layers: PbrLayers::default(),
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
        (p, best) = fit_anisotropy(&rows, p, best, r_lo)?;
    }
    let errors_of = |p: Params| -> Result<([f64; 3], ErrorReport)> {
        let (base_color, _) = sums(&rows, p)?.solve(&rows.amax);
        let model = p.model(Rgb(base_color))?;
        let e = evaluate_masked(
            data.bsdf.as_ref(),
            &model,
            data.transmission,
            data.coverage.as_ref(),
        );
        Ok((base_color, e))
    };
    let core_ngan_l2 = errors_of(p)?.1.ngan_mean();
    p = fit_layers(&rows, p, best, r_lo)?;
    let (base_color, errors) = errors_of(p)?;
    Ok(GltfFit {
        base_color,
        metallic: p.m,
        roughness: p.r,
        anisotropy: p.s,
        anisotropy_rotation: p.rho,
        layers: p.layers,
        core_ngan_l2,
        errors,
    })
}

/// One layer's search (module notes): the grid `starts` (the best so far included), then a
/// Nelder–Mead simplex over `to_params(x)` from the best start `from(p)`; the result where it
/// lowers `err` by [`EXTENSION_GAIN`].
fn fit_layer(
    rows: &Rows,
    (p, err): (Params, f64),
    starts: &[Params],
    step: [f64; 4],
    from: impl Fn(&Params) -> [f64; 4],
    to_params: impl Fn(&[f64; 4]) -> Params,
) -> Result<(Params, f64)> {
    let (mut start, mut e0) = (p, f64::INFINITY);
    for q in starts {
        let e = objective(rows, *q)?;
        if e < e0 {
            (start, e0) = (*q, e);
        }
    }
    let (x, e) = nelder_mead(from(&start), step, 160, |x| objective(rows, to_params(x)))?;
    let (q, e) = if e < e0 {
        (to_params(&x), e)
    } else {
        (start, e0)
    };
    Ok(if e < err * (1.0 - EXTENSION_GAIN) {
        (q, e)
    } else {
        (p, err)
    })
}

/// The specular, clearcoat and sheen layers in turn (module notes).
fn fit_layers(rows: &Rows, p: Params, err: f64, r_lo: f64) -> Result<Params> {
    let lr = |x: f64| x.exp().clamp(r_lo, 1.0);
    let unit = |x: f64| x.clamp(0.0, 1.0);
    // KHR_materials_specular: (ln r, m, k, ln t).
    let spec = |p: Params, x: &[f64; 4]| Params {
        r: lr(x[0]),
        m: unit(x[1]),
        layers: PbrLayers {
            specular: unit(x[2]),
            specular_color: Rgb::splat(x[3].exp().clamp(0.0, 25.0)),
            ..p.layers
        },
        ..p
    };
    let best = fit_layer(
        rows,
        (p, err),
        &[p],
        [0.2, 0.1, 0.2, 0.5],
        |q| {
            [
                q.r.ln(),
                q.m,
                q.layers.specular,
                q.layers.specular_color.0[0].max(1e-3).ln(),
            ]
        },
        |x| spec(p, x),
    )?;
    // The simplex refines r and m too: a layer within 1 % of the core model's is not one.
    let mut best = best;
    let l = &mut best.0.layers;
    if (l.specular - 1.0).abs() < 0.01 && (l.specular_color.0[0] - 1.0).abs() < 0.01 {
        l.specular = 1.0;
        l.specular_color = Rgb::ONE;
    }
    // KHR_materials_clearcoat: (ln r, m, w, ln r_c).
    let p = best.0;
    let coat = |p: Params, w: f64, rc: f64, r: f64, m: f64| Params {
        r,
        m,
        layers: PbrLayers {
            clearcoat: w,
            clearcoat_roughness: rc,
            ..p.layers
        },
        ..p
    };
    let mut starts = vec![p];
    for w in [0.25, 0.5, 1.0] {
        for rc in [0.05, 0.1, 0.2, 0.35] {
            starts.push(coat(p, w, rc, p.r, p.m));
        }
        // The core's lobe as the coat over a rougher base.
        for r in [0.4f64, 0.6, 0.8, 1.0] {
            starts.push(coat(p, w, p.r, r.max(p.r), p.m));
        }
    }
    let best = fit_layer(
        rows,
        best,
        &starts,
        [0.2, 0.1, 0.2, 0.3],
        |q| {
            [
                q.r.ln(),
                q.m,
                q.layers.clearcoat.max(0.25),
                q.layers.clearcoat_roughness.max(0.05).ln(),
            ]
        },
        |x| {
            coat(
                p,
                unit(x[2]),
                x[3].exp().clamp(0.0, 1.0),
                lr(x[0]),
                unit(x[1]),
            )
        },
    )?;
    let mut best = best;
    if best.0.layers.clearcoat < 0.01 {
        best.0.layers.clearcoat = 0.0;
        best.0.layers.clearcoat_roughness = 0.0;
    }
    // KHR_materials_sheen: (ln r, m, s, r_s).
    let p = best.0;
    let sheen = |p: Params, s: f64, rs: f64, r: f64, m: f64| Params {
        r,
        m,
        layers: PbrLayers {
            sheen_color: Rgb::splat(s),
            sheen_roughness: rs,
            ..p.layers
        },
        ..p
    };
    let mut starts = vec![p];
    for s in [0.25, 0.5, 1.0] {
        for rs in [0.3, 0.6, 1.0] {
            starts.push(sheen(p, s, rs, p.r, p.m));
        }
    }
    let best = fit_layer(
        rows,
        best,
        &starts,
        [0.2, 0.1, 0.2, 0.15],
        |q| {
            [
                q.r.ln(),
                q.m,
                q.layers.sheen_color.0[0].max(0.25),
                q.layers.sheen_roughness.max(0.3),
            ]
        },
        |x| sheen(p, unit(x[2]), unit(x[3]), lr(x[0]), unit(x[1])),
    )?;
    let mut best = best.0;
    if best.layers.sheen_color.0[0] < 0.01 {
        best.layers.sheen_color = Rgb::ZERO;
        best.layers.sheen_roughness = 0.0;
    }
    Ok(best)
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
        let layers = PbrLayers {
            specular: 0.7,
            specular_color: Rgb([2.0, 1.0, 0.5]),
            clearcoat: 0.6,
            clearcoat_roughness: 0.1,
            sheen_color: Rgb([0.5, 0.4, 0.3]),
            sheen_roughness: 0.4,
        };
        for (m, r, l) in [
            (0.0, 0.2, PbrLayers::default()),
            (0.3, 0.5, PbrLayers::default()),
            (1.0, 0.05, PbrLayers::default()),
            (0.7, 1.0, PbrLayers::default()),
            (0.0, 0.6, layers),
            (0.5, 0.3, layers),
        ] {
            let at = |c: Rgb| {
                PbrMetallicRoughness::new(c, m, r)
                    .and_then(|p| p.with_layers(1.5, l))
                    .expect("model")
            };
            let (white, black) = (at(Rgb::splat(1.0)), at(Rgb::splat(0.0)));
            let c = Rgb([0.2, 0.55, 0.9]);
            let model = at(c);
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

    /// A coated dielectric and a sheened one are fitted back with their layer, and a material
    /// the core model fits exactly gets none.
    #[test]
    fn finds_the_layers_its_data_asks_for() {
        let coated = PbrMetallicRoughness::new(Rgb([0.6, 0.1, 0.1]), 0.0, 0.6)
            .and_then(|m| {
                m.with_layers(
                    1.5,
                    PbrLayers {
                        clearcoat: 1.0,
                        clearcoat_roughness: 0.1,
                        ..PbrLayers::default()
                    },
                )
            })
            .expect("model");
        let fit = fit_gltf(&MeasuredData::from_bsdf("coated", Box::new(coated))).expect("fit");
        assert!(fit.layers.clearcoat > 0.5, "{fit:?}");
        assert!(fit.errors.ngan_mean() < 0.2 * fit.core_ngan_l2, "{fit:?}");
        let sheened = PbrMetallicRoughness::new(Rgb([0.1, 0.1, 0.4]), 0.0, 0.9)
            .and_then(|m| {
                m.with_layers(
                    1.5,
                    PbrLayers {
                        sheen_color: Rgb::splat(0.8),
                        sheen_roughness: 0.5,
                        ..PbrLayers::default()
                    },
                )
            })
            .expect("model");
        let fit = fit_gltf(&MeasuredData::from_bsdf("sheen", Box::new(sheened))).expect("fit");
        assert!(fit.layers.has_sheen(), "{fit:?}");
        assert!(fit.errors.ngan_mean() < 0.2 * fit.core_ngan_l2, "{fit:?}");
        let plain = PbrMetallicRoughness::new(Rgb([0.1, 0.4, 0.7]), 0.0, 0.45).expect("model");
        let fit = fit_gltf(&MeasuredData::from_bsdf("plain", Box::new(plain))).expect("fit");
        assert_eq!(fit.layers, PbrLayers::default(), "{fit:?}");
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
