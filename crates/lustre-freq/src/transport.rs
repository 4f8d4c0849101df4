//! Bandwidth through one bounce, the pixel's bandwidth and sampling rate, and the number of
//! shading samples (004 §IV.3.2–IV.3.5, Fig. IV.9, Eq. IV.4–IV.10).
//!
//! A local light field's spectrum is summarized by its 2D bandwidth ν = (ν_s, ν_a): spatial
//! (cycles per metre) and angular (cycles per radian). The operators of Fig. IV.9 are 2 × 2
//! matrices on ν; they are applied to the spectrum's bounding box, i.e. as |M| ν (element-wise
//! absolute values), so that a shear widens the box on either sign and the result stays a
//! non-negative, conservative extent (004 writes M ν).

use crate::{FreqError, Result};
use std::f64::consts::PI;

/// A 2D bandwidth: spatial (cycles per metre) and angular (cycles per radian), both ≥ 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bandwidth {
    /// ν_s.
    pub spatial: f64,
    /// ν_a.
    pub angular: f64,
}

impl Bandwidth {
    /// (ν_s, ν_a).
    pub fn new(spatial: f64, angular: f64) -> Self {
        Self { spatial, angular }
    }

    /// |M| ν for the matrix [[a, b], [c, d]].
    fn apply(self, m: [[f64; 2]; 2]) -> Self {
        Self {
            spatial: m[0][0].abs() * self.spatial + m[0][1].abs() * self.angular,
            angular: m[1][0].abs() * self.spatial + m[1][1].abs() * self.angular,
        }
    }

    /// T_d: transport through free space by `d` metres, an angular shear [[1, 0], [−d, 1]].
    pub fn transport(self, d: f64) -> Self {
        self.apply([[1.0, 0.0], [-d, 1.0]])
    }

    /// C_c: the curvature shear [[1, c], [0, 1]] (c: the surface's curvature, 1/m).
    pub fn curvature(self, c: f64) -> Self {
        self.apply([[1.0, c], [0.0, 1.0]])
    }

    /// P_i: the incident re-parametrization, a spatial scale by cos θi.
    pub fn project_in(self, cos_i: f64) -> Self {
        self.apply([[cos_i, 0.0], [0.0, 1.0]])
    }

    /// P_x: the outgoing re-parametrization, a spatial scale by 1 / cos θx.
    pub fn project_out(self, cos_x: f64) -> Self {
        self.apply([[1.0 / cos_x, 0.0], [0.0, 1.0]])
    }

    /// S: the mirror [[1, 0], [0, −1]] (it leaves the extents as they are).
    pub fn mirror(self) -> Self {
        self.apply([[1.0, 0.0], [0.0, -1.0]])
    }

    /// B_{t,ρ}: the BRDF band-limits the angular bandwidth to ρ, the texture adds t spatially.
    pub fn band_limit(self, texture: f64, brdf: f64) -> Self {
        Self {
            spatial: self.spatial + texture,
            angular: self.angular.min(brdf),
        }
    }
}

/// What the reflection operator needs at a shading point for one incident direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// cos θi of the incident direction (> 0).
    pub cos_i: f64,
    /// cos θx of the direction towards the pixel (> 0).
    pub cos_x: f64,
    /// The surface's curvature c (1/m; 0 for a plane).
    pub curvature: f64,
    /// The texture's spatial bandwidth t (cycles per metre).
    pub texture: f64,
    /// The BRDF's angular bandwidth ρ for this pair of directions (cycles per radian).
    pub brdf: f64,
}

/// Eq. IV.4: R ν = P_x C_−c S B_{t,ρ} C_c P_i ν.
pub fn reflect(nu: Bandwidth, s: &Surface) -> Bandwidth {
    nu.project_in(s.cos_i)
        .curvature(s.curvature)
        .band_limit(s.texture, s.brdf)
        .mirror()
        .curvature(-s.curvature)
        .project_out(s.cos_x)
}

/// Eq. IV.5: ν^i = T_d' R T_d ν_l^i — from the light (`light`, at distance `d` from the
/// surface; 0 and ν_s = 0 for distant illumination) to the image plane at distance `d_eye`.
pub fn one_bounce(light: Bandwidth, d: f64, s: &Surface, d_eye: f64) -> Bandwidth {
    reflect(light.transport(d), s).transport(d_eye)
}

/// Eq. IV.6: the pixel's bandwidth, the average of the paths' bandwidths ν^i weighted by
/// λ_i = L_i ρ cos θi (`paths`: (λ_i, ν^i)); zero when every weight is 0.
pub fn pixel_bandwidth(paths: &[(f64, Bandwidth)]) -> Bandwidth {
    let total: f64 = paths.iter().map(|(l, _)| l.max(0.0)).sum();
    if total <= 0.0 {
        return Bandwidth::default();
    }
    let mut out = Bandwidth::default();
    for (l, nu) in paths {
        let w = l.max(0.0) / total;
        out.spatial += w * nu.spatial;
        out.angular += w * nu.angular;
    }
    out
}

/// Eq. IV.7: the image-space bandwidth b_p = ν_a max(f_x / W, f_y / H) in cycles per pixel, for
/// fields of view `fov` (radians) and an image of `size` pixels; the sampling rate is 2 b_p.
pub fn image_bandwidth(angular: f64, fov: (f64, f64), size: (usize, usize)) -> f64 {
    angular * (fov.0 / size.0.max(1) as f64).max(fov.1 / size.1.max(1) as f64)
}

/// One incident direction's share of the variance bound: the angular bandwidths of the
/// incident light field at the surface ν_a^i and of the BRDF ν_ρa^i, and χ_i = L_i ρ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VarianceTerm {
    /// ν_a^i of T_d ν_l^i.
    pub light: f64,
    /// ν_ρa^i.
    pub brdf: f64,
    /// χ_i.
    pub chi: f64,
}

/// Σ (ν_a^i + ν_ρa^i) χ_i² (Eq. IV.9), or Σ 2 ν_ρa^i χ_i² for pre-convolved shading
/// (Eq. IV.10: the illumination filtered down to the BRDF's bandwidth).
pub fn variance_sum(terms: &[VarianceTerm], preconvolved: bool) -> f64 {
    terms
        .iter()
        .map(|t| {
            let nu = if preconvolved {
                2.0 * t.brdf
            } else {
                t.light + t.brdf
            };
            nu * t.chi * t.chi
        })
        .sum()
}

/// The number of samples N_p that keeps the bound V(L_p) ≤ 4π² / N_p · `sum` ([`variance_sum`])
/// at or below `target`, clamped to `1..=max`. Errors on a target that is not positive and
/// finite or on `max` = 0.
pub fn samples_for(sum: f64, target: f64, max: usize) -> Result<usize> {
    if !(target > 0.0 && target.is_finite()) || max == 0 {
        return Err(FreqError::Parameter(format!(
            "samples for a variance target {target} (must be > 0 and finite) with at most {max} (must be ≥ 1)"
        )));
    }
    if sum.is_nan() || sum <= 0.0 {
        return Ok(1);
    }
    let n = (4.0 * PI * PI * sum / target).ceil();
    Ok(if n.is_finite() {
        (n as usize).clamp(1, max)
    } else {
        max
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(brdf: f64) -> Surface {
        Surface {
            cos_i: 0.8,
            cos_x: 0.6,
            curvature: 0.0,
            texture: 0.0,
            brdf,
        }
    }

    #[test]
    fn the_operators_of_fig_iv_9() {
        let nu = Bandwidth::new(2.0, 3.0);
        assert_eq!(nu.transport(0.5), Bandwidth::new(2.0, 4.0));
        assert_eq!(nu.curvature(2.0), Bandwidth::new(8.0, 3.0));
        assert_eq!(nu.project_in(0.5), Bandwidth::new(1.0, 3.0));
        assert_eq!(nu.project_out(0.5), Bandwidth::new(4.0, 3.0));
        assert_eq!(nu.mirror(), nu);
        assert_eq!(nu.band_limit(1.5, 2.0), Bandwidth::new(3.5, 2.0));
    }

    #[test]
    fn distant_light_on_a_flat_mirror_keeps_its_angular_bandwidth() {
        // ν_s = 0 from a distant light, no curvature, no texture: the BRDF band-limits the
        // angular bandwidth and transport to the eye leaves it (ν_s stays 0).
        let light = Bandwidth::new(0.0, 40.0);
        let out = one_bounce(light, 0.0, &flat(1e9), 3.0);
        assert_eq!(out, Bandwidth::new(0.0, 40.0));
        let rough = one_bounce(light, 0.0, &flat(5.0), 3.0);
        assert_eq!(rough, Bandwidth::new(0.0, 5.0));
    }

    #[test]
    fn curvature_turns_angular_bandwidth_into_spatial() {
        // A sphere of radius 0.5 m (c = 2) reflecting a distant 40-cycle/rad feature: spatial
        // bandwidth c ν_a appears, scaled by cos θi in and 1/cos θx out.
        let s = Surface {
            curvature: 2.0,
            ..flat(1e9)
        };
        let out = reflect(Bandwidth::new(0.0, 40.0), &s);
        // P_i: (0, 40); C_c: (80, 40); B: (80, 40); S; C_−c: (80 + 80, 40); P_x: (160/0.6, 40).
        assert!((out.spatial - 160.0 / 0.6).abs() < 1e-9, "{out:?}");
        assert_eq!(out.angular, 40.0);
        // Transport to the eye shears spatial into angular bandwidth.
        let eye = out.transport(2.0);
        assert!(
            (eye.angular - (40.0 + 2.0 * 160.0 / 0.6)).abs() < 1e-9,
            "{eye:?}"
        );
    }

    #[test]
    fn the_pixel_average_is_exact_for_equal_paths_and_follows_the_weights() {
        let a = Bandwidth::new(1.0, 10.0);
        let b = Bandwidth::new(3.0, 30.0);
        assert_eq!(pixel_bandwidth(&[(2.0, a), (5.0, a)]), a);
        assert_eq!(
            pixel_bandwidth(&[(1.0, a), (3.0, b)]),
            Bandwidth::new(2.5, 25.0)
        );
        assert_eq!(pixel_bandwidth(&[(0.0, a)]), Bandwidth::default());
        // 60° × 40° at 600 × 400: 2π/3 / 600 rad per pixel either way.
        let fov = (60f64.to_radians(), 40f64.to_radians());
        let bp = image_bandwidth(30.0, fov, (600, 400));
        assert!((bp - 30.0 * 60f64.to_radians() / 600.0).abs() < 1e-12);
    }

    #[test]
    fn sample_counts_follow_the_variance_bound() {
        let t = |light, brdf, chi| VarianceTerm { light, brdf, chi };
        let terms = [t(10.0, 5.0, 0.2), t(2.0, 5.0, 0.1)];
        let sum = variance_sum(&terms, false);
        assert!((sum - (15.0 * 0.04 + 7.0 * 0.01)).abs() < 1e-12);
        // Pre-convolved: the light's bandwidth becomes the BRDF's.
        assert!((variance_sum(&terms, true) - (10.0 * 0.04 + 10.0 * 0.01)).abs() < 1e-12);
        let n = samples_for(sum, 0.5, 4096).expect("n");
        assert_eq!(n, (4.0 * PI * PI * sum / 0.5).ceil() as usize);
        assert!(4.0 * PI * PI * sum / n as f64 <= 0.5);
        // Halving the target doubles the count; the clamps hold; bad targets are refused.
        let n2 = samples_for(sum, 0.25, 4096).expect("n2");
        assert!(n2 == 2 * n || n2 == 2 * n - 1, "{n} → {n2}");
        assert_eq!(samples_for(sum, 1e-12, 64).expect("max"), 64);
        assert_eq!(samples_for(0.0, 0.5, 64).expect("flat"), 1);
        assert!(samples_for(sum, 0.0, 64).is_err());
        assert!(samples_for(sum, f64::NAN, 64).is_err());
        assert!(samples_for(sum, 0.5, 0).is_err());
    }
}
