//! The per-pixel prediction of 004 §IV.3.6 under a distant environment: from `n_b` incident
//! directions, the pixel's 2D bandwidth (Eq. IV.6, each direction's one-bounce bandwidth of
//! Eq. IV.4–IV.5) and the sums of the variance bound (Eq. IV.9, and Eq. IV.10 for
//! pre-convolved shading).
//!
//! The directions are `n_b` stratified (Hammersley, [`incident_direction`]) points of the
//! cosine-weighted hemisphere around the normal, the same at every pixel, so that the sum of Eq. IV.9 is over a fixed
//! quadrature of the integrand χ = L ρ (its scale is absorbed by the variance target; 004 uses
//! n_b = 16). Distant light has ν_s = 0, so T_d leaves its bandwidth (0, ν_a(ω)) unchanged.

use crate::brdf::BrdfBandwidth;
use crate::environment::angular_bandwidth;
use crate::transport::{one_bounce, pixel_bandwidth, Bandwidth, Surface, VarianceTerm};
use crate::{FreqError, Result};
use glam::DVec3;
use lustre_brdf::sampling::{cosine_hemisphere, hammersley};
use lustre_brdf::{Bsdf, Rgb};
use lustre_env::equirect::direction_uv;
use lustre_env::EquirectMap;
use std::borrow::Cow;
use std::f64::consts::PI;

/// An environment map with its angular bandwidth (cycles per radian per pixel); the lighting
/// side of a prediction (`lustre_shade::integrator::FilteredEnvironment` is the shading side: pyramids).
#[derive(Clone, Debug)]
pub struct EnvironmentBandwidth<'a> {
    /// The map.
    pub map: Cow<'a, EquirectMap>,
    /// [`angular_bandwidth`] of the map.
    pub bandwidth: Vec<f64>,
    /// The radiance scale the map is lit with (1 unless [`EnvironmentBandwidth::scaled`]): the
    /// luminance read is the map's times it; the bandwidth does not depend on it.
    pub scale: f64,
    /// Per texel, the map's luminance and its bandwidth side by side (what a prediction reads:
    /// one cache line, a third of the map's bytes).
    luminance_bandwidth: Vec<[f32; 2]>,
}

impl<'a> EnvironmentBandwidth<'a> {
    /// Computes the map's bandwidth.
    pub fn new(map: &'a EquirectMap) -> Result<Self> {
        Self::scaled(map, 1.0)
    }

    /// [`EnvironmentBandwidth::new`] for the map lit with radiance `scale` (an environment's
    /// scale; 0 is black). Errors on a negative or non-finite scale.
    pub fn scaled(map: &'a EquirectMap, scale: f64) -> Result<Self> {
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(FreqError::Parameter(format!(
                "environment scale {scale} must be finite and ≥ 0"
            )));
        }
        Self::build(Cow::Borrowed(map), scale)
    }

    /// A black environment (a uniform 8 × 4 map lit with scale 0): what a scene without one
    /// predicts with (no path from it weighs anything).
    pub fn black() -> Result<EnvironmentBandwidth<'static>> {
        let map = EquirectMap::new(8, 4, vec![[1.0; 3]; 32])
            .map_err(|e| FreqError::Parameter(format!("black environment: {e}")))?;
        EnvironmentBandwidth::build(Cow::Owned(map), 0.0)
    }

    fn build(map: Cow<'a, EquirectMap>, scale: f64) -> Result<Self> {
        let bandwidth = angular_bandwidth(&map)?;
        let luminance_bandwidth = map
            .data
            .iter()
            .zip(&bandwidth)
            .map(|(c, &b)| {
                let l = Rgb([c[0] as f64, c[1] as f64, c[2] as f64]).luminance() * scale;
                [l as f32, b as f32]
            })
            .collect();
        Ok(Self {
            map,
            bandwidth,
            scale,
            luminance_bandwidth,
        })
    }

    /// The bandwidth of the pixel seen in world direction `d` (nearest pixel; +y up, as
    /// [`EquirectMap::lookup_bilinear`]).
    pub fn bandwidth_at(&self, d: DVec3) -> f64 {
        let (u, v) = direction_uv(d);
        self.bandwidth_uv(u, v)
    }

    /// The map's luminance (bilinear, as [`EquirectMap::lookup_bilinear`] reads the radiance)
    /// and bandwidth ([`EnvironmentBandwidth::bandwidth_at`]) in direction `d`, its map
    /// coordinates found once.
    pub fn luminance_and_bandwidth(&self, d: DVec3) -> (f64, f64) {
        let (u, v) = direction_uv(d);
        let taps = self.map.bilinear_taps(u, v);
        let l = |i: usize| f64::from(self.luminance_bandwidth[taps.texels[i]][0]);
        let [w00, w10, w01, w11] = taps.weights;
        let luminance = (w00 * l(0) + w10 * l(1)) + (w01 * l(2) + w11 * l(3));
        let nearest = self.nearest_texel(u, v);
        (luminance, f64::from(self.luminance_bandwidth[nearest][1]))
    }

    fn bandwidth_uv(&self, u: f64, v: f64) -> f64 {
        self.bandwidth[self.nearest_texel(u, v)]
    }

    /// The index of the texel holding map coordinates (u, v).
    fn nearest_texel(&self, u: f64, v: f64) -> usize {
        let (w, h) = (self.map.width, self.map.height);
        let x = ((u * w as f64) as usize).min(w - 1);
        let y = ((v * h as f64) as usize).min(h - 1);
        y * w + x
    }
}

/// A visible surface point: its frame, the direction and distance to the eye, its curvature and
/// its texture's spatial bandwidth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    /// Tangent, bitangent and normal (world, orthonormal).
    pub frame: (DVec3, DVec3, DVec3),
    /// Unit direction towards the eye (world).
    pub wo: DVec3,
    /// Distance to the eye (metres).
    pub eye_distance: f64,
    /// Curvature c (1/m).
    pub curvature: f64,
    /// Texture bandwidth t (cycles per metre).
    pub texture: f64,
}

/// What one pixel's prediction gives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelPrediction {
    /// ν at the image plane (Eq. IV.6).
    pub bandwidth: Bandwidth,
    /// Σ (ν_a^i + ν_ρa^i) χ_i² (Eq. IV.9).
    pub variance: f64,
    /// Σ 2 ν_ρa^i χ_i² (Eq. IV.10).
    pub variance_preconvolved: f64,
    /// The directions' estimate of the pixel's radiance (luminance), π / n_b Σ χ_i: the
    /// cosine-weighted quadrature of ∫ χ cos θi dω (a scale for relative variance targets).
    pub radiance: f64,
    /// Σ λ_i, the weight behind [`PixelPrediction::bandwidth`] (to merge it with other
    /// lights' paths in Eq. IV.6).
    pub weight: f64,
}

/// Direction k of the n_b of a prediction (local frame): point k of the Hammersley set with
/// both coordinates at their cell's centre ((k + ½) / n_b, and the radical inverse + ½ / n_b),
/// on the cosine-weighted hemisphere. Centred, the azimuths never fall on the φ edges of a
/// BRDF bandwidth table (whose 16 cells would otherwise hold every one of 16 points on an
/// edge, where f32 and f64 round apart).
pub fn incident_direction(k: usize, n_b: usize) -> DVec3 {
    let (u1, u2) = hammersley(k as u32, n_b as u32);
    cosine_hemisphere(u1, u2 + 0.5 / n_b as f64)
}

/// The n_b directions of a prediction, [`incident_direction`] k = 0 … n_b − 1 (the same for
/// every pixel: a pass computes them once, with their polar angles).
pub fn incident_directions(n_b: usize) -> Vec<Incident> {
    (0..n_b)
        .map(|k| Incident::new(incident_direction(k, n_b)))
        .collect()
}

/// An incident direction in the shading frame with its polar angles, found once for a set of
/// directions every pixel shares (the tables' cells need them, `BrdfBandwidthView::at_polar`,
/// `LuminanceView::at_polar`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incident {
    /// The direction (local frame, unit).
    pub dir: DVec3,
    /// acos(clamp(z, 0, 1)).
    pub theta: f64,
    /// atan2(y, x).
    pub phi: f64,
}

impl Incident {
    /// `dir` with its angles.
    pub fn new(dir: DVec3) -> Self {
        Self {
            dir,
            theta: dir.z.clamp(0.0, 1.0).acos(),
            phi: dir.y.atan2(dir.x),
        }
    }
}

/// Predicts one pixel from `n_b` directions. A point seen from below its surface, or degenerate
/// inputs (a zero normal, a non-finite distance or curvature) predict nothing (zeros), never
/// NaN; errors on `n_b` = 0.
pub fn predict(
    p: &ShadingPoint,
    env: &EnvironmentBandwidth,
    bsdf: &dyn Bsdf,
    brdf_bandwidth: &BrdfBandwidth,
    n_b: usize,
) -> Result<PixelPrediction> {
    predict_with(
        p,
        env,
        &|wi, wo| bsdf.eval(wi.dir, wo).luminance(),
        brdf_bandwidth,
        &incident_directions(n_b),
    )
    .map(|(prediction, _)| prediction)
}

/// [`predict`] from the directions `dirs` ([`incident_directions`]), with the BRDF's luminance
/// ρ(ωi, ωo) (local frame) given as a function: the BSDF's `eval`, or a table of it
/// (`TabulatedSampler::luminance_view`). Also returns the BRDF's largest bandwidth over `dirs`
/// (found for degenerate points too, ωo clamped onto the horizon). Errors on no direction.
pub fn predict_with(
    p: &ShadingPoint,
    env: &EnvironmentBandwidth,
    rho: &dyn Fn(&Incident, DVec3) -> f64,
    brdf_bandwidth: &BrdfBandwidth,
    dirs: &[Incident],
) -> Result<(PixelPrediction, f64)> {
    let n_b = dirs.len();
    if n_b == 0 {
        return Err(FreqError::Parameter(
            "pixel prediction with n_b = 0 incident directions".into(),
        ));
    }
    let (t, b, n) = p.frame;
    let wo_l = DVec3::new(p.wo.dot(t), p.wo.dot(b), p.wo.dot(n));
    let view = brdf_bandwidth.view(wo_l);
    let finite = [p.eye_distance, p.curvature, p.texture]
        .iter()
        .all(|v| v.is_finite());
    if !(wo_l.z > 0.0 && finite && n.length_squared() > 0.5) {
        let brdf_max = dirs
            .iter()
            .map(|d| view.at_polar(d.theta, d.phi))
            .fold(0.0, f64::max);
        return Ok((PixelPrediction::default(), brdf_max));
    }
    let mut paths = Vec::with_capacity(n_b);
    let mut terms = Vec::with_capacity(n_b);
    let mut chi_sum = 0.0;
    let mut brdf_max = 0.0f64;
    for incident in dirs {
        let wi_l = incident.dir;
        let wi = t * wi_l.x + b * wi_l.y + n * wi_l.z;
        let (radiance, nu_light) = env.luminance_and_bandwidth(wi);
        let rho = rho(incident, wo_l);
        let nu_brdf = view.at_polar(incident.theta, incident.phi);
        brdf_max = brdf_max.max(nu_brdf);
        let s = Surface {
            cos_i: wi_l.z.max(1e-6),
            cos_x: wo_l.z.max(1e-6),
            curvature: p.curvature,
            texture: p.texture,
            brdf: nu_brdf,
        };
        let nu = one_bounce(Bandwidth::new(0.0, nu_light), 0.0, &s, p.eye_distance);
        let chi = radiance * rho;
        chi_sum += chi;
        paths.push((chi * wi_l.z, nu));
        terms.push(VarianceTerm {
            light: nu_light,
            brdf: nu_brdf,
            chi,
        });
    }
    Ok((
        PixelPrediction {
            weight: paths.iter().map(|(l, _)| l.max(0.0)).sum(),
            bandwidth: pixel_bandwidth(&paths),
            variance: crate::transport::variance_sum(&terms, false),
            variance_preconvolved: crate::transport::variance_sum(&terms, true),
            radiance: PI * chi_sum / n_b as f64,
        },
        brdf_max,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::{brdf_bandwidth, BrdfBandwidthOptions};
    use lustre_brdf::models::kurt::{Kurt, KurtLobe};

    fn map(f: impl Fn(usize, usize) -> f32) -> EquirectMap {
        let (w, h) = (64, 32);
        EquirectMap::new(w, h, (0..w * h).map(|k| [f(k % w, k / w); 3]).collect()).expect("map")
    }

    fn point(curvature: f64) -> ShadingPoint {
        let wo = DVec3::new(0.3, 0.9, 0.0).normalize();
        ShadingPoint {
            frame: (DVec3::X, DVec3::NEG_Z, DVec3::Y),
            wo,
            eye_distance: 2.0,
            curvature,
            texture: 0.0,
        }
    }

    fn glossy() -> (Kurt, BrdfBandwidth) {
        let k = Kurt::new(
            Rgb::splat(0.1),
            vec![KurtLobe::new(Rgb::splat(0.5), 0.1, 0.1, 1.0, 0.0).expect("lobe")],
            vec![],
        )
        .expect("kurt");
        let o = BrdfBandwidthOptions {
            incident: 8,
            slice: 32,
            out: 8,
        };
        let b = brdf_bandwidth(&k, o).expect("bandwidth");
        (k, b)
    }

    #[test]
    fn an_environments_scale_scales_the_weights_but_not_the_bandwidth() {
        let (k, bw) = glossy();
        let sky = map(|x, y| 1.0 + ((x / 4 + y / 4) % 2) as f32);
        let one = EnvironmentBandwidth::new(&sky).expect("env");
        let three = EnvironmentBandwidth::scaled(&sky, 3.0).expect("env");
        let (a, b) = (
            predict(&point(0.5), &one, &k, &bw, 16).expect("one"),
            predict(&point(0.5), &three, &k, &bw, 16).expect("three"),
        );
        assert!(a.radiance > 0.0 && (b.radiance / a.radiance - 3.0).abs() < 1e-6);
        assert!((b.variance / a.variance - 9.0).abs() < 1e-5);
        assert!((b.bandwidth.angular - a.bandwidth.angular).abs() < 1e-9 * a.bandwidth.angular);
        let black = EnvironmentBandwidth::black().expect("black");
        let p = predict(&point(0.5), &black, &k, &bw, 16).expect("black");
        assert_eq!((p.radiance, p.variance, p.weight), (0.0, 0.0, 0.0));
        assert!(EnvironmentBandwidth::scaled(&sky, -1.0).is_err());
        assert!(EnvironmentBandwidth::scaled(&sky, f64::NAN).is_err());
    }

    #[test]
    fn a_black_or_constant_sky_and_degenerate_points_predict_no_nan() {
        let (k, bw) = glossy();
        let black = map(|_, _| 0.0);
        let env = EnvironmentBandwidth::new(&black).expect("env");
        let p = predict(&point(0.0), &env, &k, &bw, 16).expect("black");
        assert_eq!(p, PixelPrediction::default());
        let grey = map(|_, _| 1.0);
        let env = EnvironmentBandwidth::new(&grey).expect("env");
        let p = predict(&point(0.0), &env, &k, &bw, 16).expect("grey");
        // A constant sky has no angular bandwidth: what is left is the BRDF's, band-limited
        // by the sky's zero, i.e. nothing; the variance sum keeps the BRDF's term.
        assert_eq!(p.bandwidth, Bandwidth::default());
        assert!(p.variance > 0.0 && p.variance_preconvolved >= p.variance);
        for bad in [
            ShadingPoint {
                wo: DVec3::NEG_Y,
                ..point(0.0)
            },
            ShadingPoint {
                curvature: f64::NAN,
                ..point(0.0)
            },
            ShadingPoint {
                frame: (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO),
                ..point(0.0)
            },
        ] {
            let p = predict(&bad, &env, &k, &bw, 16).expect("degenerate");
            assert_eq!(p, PixelPrediction::default(), "{bad:?}");
        }
        assert!(predict(&point(0.0), &env, &k, &bw, 0).is_err());
    }

    #[test]
    fn stripes_in_the_sky_give_bandwidth_and_curvature_makes_it_spatial() {
        let (k, bw) = glossy();
        let stripes = map(|x, _| if (x / 2) % 2 == 0 { 1.0 } else { 0.1 });
        let env = EnvironmentBandwidth::new(&stripes).expect("env");
        let flat = predict(&point(0.0), &env, &k, &bw, 16).expect("flat");
        assert!(flat.bandwidth.angular > 0.0, "{flat:?}");
        assert_eq!(flat.bandwidth.spatial, 0.0);
        let curved = predict(&point(4.0), &env, &k, &bw, 16).expect("curved");
        assert!(curved.bandwidth.spatial > 0.0, "{curved:?}");
        // At the eye the spatial bandwidth shears into angular bandwidth.
        assert!(
            curved.bandwidth.angular > flat.bandwidth.angular,
            "{curved:?}"
        );
        assert!(flat.variance.is_finite() && curved.variance == flat.variance);
    }
}
