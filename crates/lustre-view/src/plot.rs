//! The material editor's polar lobe plot: the BRDF's slice in the plane of incidence,
//! f(ωi, ωo)·cos θo for θo from −90° (back towards the light) to +90° (the mirror side), of the
//! measurement and of its fit, as BRDF Explorer draws it.

use glam::DVec3;
use lustre_brdf::Bsdf;

/// One slice: signed outgoing angles (radians, + on the mirror side) and the luminance of
/// f·cos θo at each.
#[derive(Clone, Debug, PartialEq)]
pub struct LobeSlice {
    /// Incident elevation, degrees.
    pub theta_i_deg: f64,
    /// Signed θo per point, radians.
    pub angles: Vec<f64>,
    /// Luminance (Rec. 709) of f·cos θo per point; 0 where the model gives no finite value.
    pub values: Vec<f64>,
}

/// The slice of `bsdf` at incident elevation `theta_i_deg` with `n` ≥ 2 points.
pub fn lobe_slice(bsdf: &dyn Bsdf, theta_i_deg: f64, n: usize) -> LobeSlice {
    let n = n.max(2);
    let ti = theta_i_deg.to_radians();
    let wi = DVec3::new(-ti.sin(), 0.0, ti.cos());
    let half = std::f64::consts::FRAC_PI_2 * 0.999;
    let angles: Vec<f64> = (0..n)
        .map(|k| -half + 2.0 * half * k as f64 / (n - 1) as f64)
        .collect();
    let values = angles
        .iter()
        .map(|&t| {
            let wo = DVec3::new(t.sin(), 0.0, t.cos());
            let f = bsdf.eval(wi, wo);
            let y = (0.2126 * f[0] + 0.7152 * f[1] + 0.0722 * f[2]) * t.cos();
            if y.is_finite() {
                y.max(0.0)
            } else {
                0.0
            }
        })
        .collect();
    LobeSlice {
        theta_i_deg,
        angles,
        values,
    }
}

/// The slice's points in the plot's plane: x = r sin θo, y = r cos θo with r the cube root of
/// the value over the cube root of `max` (so the largest lobe reaches 1).
pub fn polar_points(s: &LobeSlice, max: f64) -> Vec<[f64; 2]> {
    let m = max.max(1e-12).cbrt();
    s.angles
        .iter()
        .zip(&s.values)
        .map(|(&t, &v)| {
            let r = v.cbrt() / m;
            [r * t.sin(), r * t.cos()]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_brdf::models::lambert::Lambert;
    use lustre_brdf::Rgb;

    #[test]
    fn lambert_slice_is_kd_over_pi_cos() {
        let l = Lambert::new(Rgb::new(0.5, 0.5, 0.5)).unwrap();
        let s = lobe_slice(&l, 30.0, 31);
        for (t, v) in s.angles.iter().zip(&s.values) {
            assert!((v - 0.5 / std::f64::consts::PI * t.cos()).abs() < 1e-9);
        }
        let p = polar_points(&s, 0.5 / std::f64::consts::PI);
        // Straight up reaches 1.
        assert!((p[15][1] - 1.0).abs() < 1e-9 && p[15][0].abs() < 1e-9);
    }

    #[test]
    fn glossy_peak_is_on_the_mirror_side() {
        let b = lustre_brdf::catalog::resolve("ggx(rho_d=0, rho_s=0.8, alpha=0.05)").unwrap();
        let s = lobe_slice(b.as_ref(), 40.0, 181);
        let k = (0..s.values.len())
            .max_by(|&a, &b| s.values[a].total_cmp(&s.values[b]))
            .unwrap();
        assert!(
            (s.angles[k].to_degrees() - 40.0).abs() < 1.5,
            "{}",
            s.angles[k].to_degrees()
        );
    }
}
