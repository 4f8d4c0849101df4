//! The scene's distant lighting: an equirect map (lustre-env's convention), a constant radiance,
//! or a built-in sky, with a rotation and an intensity.
//!
//! Radiance arriving from world direction d is `intensity · L(to_local · d)`, where L reads the
//! source in its own frame. A Mitsuba `envmap` reads direction v = to_world⁻¹·d at
//! u = atan2(v.x, −v.z)/2π; lustre's equirect reads u = ½ + atan2(v.x, −v.z)/2π, half a turn
//! further, so the Mitsuba reader composes its transform with a half turn about +y.

use glam::{DMat3, DVec3};
use lustre_brdf::Rgb;
use lustre_env::EquirectMap;
use std::path::PathBuf;
use std::sync::Arc;

/// A simple analytic sky: `zenith` at the top, `horizon` at the horizon (interpolated in cos θ),
/// `ground` below.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sky {
    /// Radiance straight up.
    pub zenith: [f64; 3],
    /// Radiance at the horizon.
    pub horizon: [f64; 3],
    /// Radiance of every direction below the horizon.
    pub ground: [f64; 3],
}

impl Default for Sky {
    fn default() -> Self {
        Sky {
            zenith: [0.25, 0.45, 0.9],
            horizon: [0.9, 0.95, 1.0],
            ground: [0.3, 0.28, 0.25],
        }
    }
}

impl Sky {
    /// Radiance in local direction d (unit).
    pub fn radiance(&self, d: DVec3) -> Rgb {
        if d.y < 0.0 {
            return Rgb(self.ground);
        }
        let s = d.y.clamp(0.0, 1.0);
        Rgb::new(
            self.horizon[0] + (self.zenith[0] - self.horizon[0]) * s,
            self.horizon[1] + (self.zenith[1] - self.horizon[1]) * s,
            self.horizon[2] + (self.zenith[2] - self.horizon[2]) * s,
        )
    }
}

/// Where the environment's radiance comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvironmentSource {
    /// An equirect map read from `path` (lustre-env's convention).
    Map {
        /// The file.
        path: PathBuf,
        /// Its pixels.
        map: Arc<EquirectMap>,
    },
    /// The same radiance from every direction.
    Constant(Rgb),
    /// The built-in analytic sky.
    Sky(Sky),
}

/// Distant lighting.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    /// The radiance source.
    pub source: EnvironmentSource,
    /// Rotation from world to the source's frame (orthonormal).
    pub to_local: DMat3,
    /// Radiance scale, ≥ 0.
    pub intensity: f64,
}

impl Environment {
    /// A constant environment of radiance `l`.
    pub fn constant(l: Rgb) -> Self {
        Environment {
            source: EnvironmentSource::Constant(l),
            to_local: DMat3::IDENTITY,
            intensity: 1.0,
        }
    }

    /// Radiance arriving from world direction `d` (need not be normalised).
    pub fn radiance(&self, d: DVec3) -> Rgb {
        let v = (self.to_local * d).normalize_or(DVec3::Y);
        let l = match &self.source {
            EnvironmentSource::Map { map, .. } => Rgb(map.lookup_bilinear(v)),
            EnvironmentSource::Constant(c) => *c,
            EnvironmentSource::Sky(s) => s.radiance(v),
        };
        l * self.intensity
    }

    /// The environment as an equirect map in *world* orientation (`width` × `width/2`; a map
    /// source keeps its own size when unrotated): what an importance sampler or a GPU upload
    /// needs. `width` is rounded up to an even number ≥ 2.
    pub fn to_world_equirect(&self, width: usize) -> EquirectMap {
        if let EnvironmentSource::Map { map, .. } = &self.source {
            if self.to_local == DMat3::IDENTITY {
                let mut m = (**map).clone();
                let s = self.intensity as f32;
                for p in &mut m.data {
                    *p = [p[0] * s, p[1] * s, p[2] * s];
                }
                return m;
            }
        }
        let w = width.max(2).div_ceil(2) * 2;
        let h = w / 2;
        let mut data = Vec::with_capacity(w * h);
        for j in 0..h {
            for i in 0..w {
                let d = EquirectMap::pixel_dir(w, h, i, j);
                let l = self.radiance(d);
                data.push([l[0] as f32, l[1] as f32, l[2] as f32]);
            }
        }
        EquirectMap {
            width: w,
            height: h,
            data,
        }
    }
}
