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
    /// The fitted model's errors against the data (Ngan L2, L1, albedos).
    pub errors: ErrorReport,
}

impl GltfFit {
    /// The fitted model.
    pub fn model(&self) -> Result<PbrMetallicRoughness> {
        PbrMetallicRoughness::new(Rgb(self.base_color), self.metallic, self.roughness)
    }
}

/// The smallest roughness searched: the model clamps α = r² below at [`PBR_ALPHA_MIN`].
fn min_roughness() -> f64 {
    PBR_ALPHA_MIN.sqrt()
}

/// The least-squares sums of the model at (m, r).
fn sums(rows: &Rows, m: f64, r: f64) -> Result<Sums> {
    let white = PbrMetallicRoughness::new(Rgb::splat(1.0), m, r)?;
    let black = PbrMetallicRoughness::new(Rgb::splat(0.0), m, r)?;
    Ok(rows.sums(&black, &white))
}

fn objective(rows: &Rows, m: f64, r: f64) -> Result<f64> {
    Ok(sums(rows, m, r)?.solve(&rows.amax).1)
}

/// Fits the glTF metallic-roughness model to `data` (module notes).
pub fn fit_gltf(data: &MeasuredData) -> Result<GltfFit> {
    let rows = Rows::new(data);
    let (r_lo, steps) = (min_roughness(), 24);
    let roughness: Vec<f64> = (0..=steps)
        .map(|k| r_lo * (1.0 / r_lo).powf(k as f64 / steps as f64))
        .collect();
    let (mut best_m, mut best_r, mut best) = (0.0, 1.0, f64::INFINITY);
    for &r in &roughness {
        for k in 0..=10 {
            let m = k as f64 / 10.0;
            let e = objective(&rows, m, r)?;
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
        let (lr, e) = golden(lo, hi, |x| objective(&rows, best_m, x.exp()))?;
        if e < best {
            (best_r, best) = (lr.exp(), e);
        }
        let (m, e) = golden((best_m - 0.1).max(0.0), (best_m + 0.1).min(1.0), |m| {
            objective(&rows, m, best_r)
        })?;
        if e < best {
            (best_m, best) = (m, e);
        }
    }
    let (base_color, _) = sums(&rows, best_m, best_r)?.solve(&rows.amax);
    let model = PbrMetallicRoughness::new(Rgb(base_color), best_m, best_r)?;
    let errors = evaluate_masked(
        data.bsdf.as_ref(),
        &model,
        data.transmission,
        data.coverage.as_ref(),
    );
    Ok(GltfFit {
        base_color,
        metallic: best_m,
        roughness: best_r,
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
}
