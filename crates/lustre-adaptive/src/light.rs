//! Textured quad emitters (004 §IV.5.3, Fig. IV.7, IV.21): a parallelogram that emits on the
//! side of edge_u × edge_v, its radiance a scale times a texture, shaded by sampling the light
//! directly (no BRDF importance sampling, no visibility, as 004), and its bandwidth propagated
//! to the pixel through the operators of Fig. IV.9.
//!
//! The texture's spatial bandwidth (cycles per metre) comes from
//! `lustre_freq::spatial::area_light_bandwidth` (zero-padded: the light's border is an edge of
//! its emission). Seen from a point, a path leaves the light at angle θl to its normal, so its
//! spatial bandwidth across the ray is ν_s / cos θl (the projection P of Fig. IV.9); T_d then
//! shears it into the angular bandwidth d ν_s / cos θl that the surface receives (Eq. IV.5).

use crate::{AdaptiveError, Result};
use glam::DVec3;
use lustre_brdf::rgb::Rgb;
use lustre_freq::spatial::area_light_bandwidth;

/// The texture of a light without one: constant, at a resolution fine enough for its edges'
/// bandwidth to show.
const PLAIN: usize = 16;

/// A textured parallelogram emitter.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// The corner at (u, v) = (0, 0).
    pub corner: DVec3,
    /// The edge to (1, 0).
    pub edge_u: DVec3,
    /// The edge to (0, 1).
    pub edge_v: DVec3,
    /// Radiance scale.
    pub radiance: Rgb,
    width: usize,
    height: usize,
    texels: Vec<[f32; 3]>,
    bandwidth: Vec<f64>,
    normal: DVec3,
    area: f64,
}

impl AreaLight {
    /// A light of `radiance` × `texture` (`(width, height, texels)`, row-major with row 0 at
    /// v = 0; `None`: constant). Errors, by name, on degenerate or non-finite edges, a negative
    /// or non-finite radiance, or a texture whose size does not match or that holds a negative
    /// or non-finite texel.
    pub fn new(
        corner: DVec3,
        edge_u: DVec3,
        edge_v: DVec3,
        radiance: Rgb,
        texture: Option<(usize, usize, Vec<[f32; 3]>)>,
    ) -> Result<Self> {
        let cross = edge_u.cross(edge_v);
        let area = cross.length();
        if !(corner.is_finite() && edge_u.is_finite() && edge_v.is_finite() && area > 1e-12) {
            return Err(AdaptiveError::Parameter(format!(
                "area light at {corner} with edges {edge_u} and {edge_v}: degenerate or not finite"
            )));
        }
        if !radiance.0.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(AdaptiveError::Parameter(format!(
                "area light radiance {:?} must be finite and ≥ 0",
                radiance.0
            )));
        }
        let (width, height, texels) =
            texture.unwrap_or_else(|| (PLAIN, PLAIN, vec![[1.0; 3]; PLAIN * PLAIN]));
        if width == 0 || height == 0 || texels.len() != width * height {
            return Err(AdaptiveError::Parameter(format!(
                "area light texture of {width} × {height} with {} texels",
                texels.len()
            )));
        }
        if let Some(k) = texels
            .iter()
            .position(|t| !t.iter().all(|c| c.is_finite() && *c >= 0.0))
        {
            return Err(AdaptiveError::Parameter(format!(
                "area light texel ({}, {}) is {:?} (must be finite and ≥ 0)",
                k % width,
                k / width,
                texels[k]
            )));
        }
        let bandwidth =
            area_light_bandwidth(&texels, width, height, (edge_u.length(), edge_v.length()))?;
        Ok(Self {
            corner,
            edge_u,
            edge_v,
            radiance,
            width,
            height,
            texels,
            bandwidth,
            normal: cross / area,
            area,
        })
    }

    /// The unit normal of the emitting side.
    pub fn normal(&self) -> DVec3 {
        self.normal
    }

    /// The area (m²).
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The point at (u, v) ∈ [0, 1]².
    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        self.corner + self.edge_u * u + self.edge_v * v
    }

    fn texel(&self, u: f64, v: f64) -> usize {
        let x = ((u * self.width as f64) as usize).min(self.width - 1);
        let y = ((v * self.height as f64) as usize).min(self.height - 1);
        y * self.width + x
    }

    /// The emitted radiance at (u, v) (nearest texel).
    pub fn emitted(&self, u: f64, v: f64) -> Rgb {
        let t = self.texels[self.texel(u, v)];
        Rgb([
            self.radiance.0[0] * f64::from(t[0]),
            self.radiance.0[1] * f64::from(t[1]),
            self.radiance.0[2] * f64::from(t[2]),
        ])
    }

    /// The texture: width, height and row-major texels (row 0 at v = 0).
    pub fn texture(&self) -> (usize, usize, &[[f32; 3]]) {
        (self.width, self.height, &self.texels)
    }

    /// The spatial bandwidth at (u, v) (cycles per metre, nearest texel).
    pub fn bandwidth_at(&self, u: f64, v: f64) -> f64 {
        self.bandwidth[self.texel(u, v)]
    }

    /// Sample (u, v) seen from `p`: the unit direction to it, its distance, and the cosine at
    /// the light (≤ 0 when `p` lies behind the emitting side).
    pub fn towards(&self, p: DVec3, u: f64, v: f64) -> (DVec3, f64, f64) {
        let d = self.point(u, v) - p;
        let dist = d.length();
        if dist <= 0.0 || !dist.is_finite() {
            return (DVec3::Z, 0.0, 0.0);
        }
        let w = d / dist;
        (w, dist, -w.dot(self.normal))
    }
}
