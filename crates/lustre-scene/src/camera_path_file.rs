//! Camera path files (`lustre-camera-path`, version 1): a camera path with its cameras inline,
//! as `lustre view` records a walk and `lustre render --path FILE.json` replays it.
//!
//! ```json
//! { "schema": "lustre-camera-path", "version": 1, "name": "walk", "looped": false,
//!   "keyframes": [ { "time": 0.0, "position": [0, 1.6, 3], "forward": [0, 0, -1],
//!                    "up": [0, 1, 0], "fov_deg": 55.0, "fov_axis": "y" } ] }
//! ```
//!
//! Reading checks the schema, then the version, then every keyframe (finite values, a unit-able
//! forward not parallel to up, a field of view in (0, 180), strictly increasing times, at least
//! one keyframe); errors name the file and the keyframe.

use crate::camera::{Camera, CameraPath, FovAxis, Keyframe};
use crate::error::{Result, SceneError};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `schema` field of every camera path file.
pub const SCHEMA: &str = "lustre-camera-path";
/// The version this build reads and writes.
pub const VERSION: u32 = 1;

/// A camera path file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraPathFile {
    /// Always [`SCHEMA`].
    pub schema: String,
    /// Always [`VERSION`].
    pub version: u32,
    /// The path's name.
    pub name: String,
    /// Start again after the last keyframe.
    #[serde(default)]
    pub looped: bool,
    /// Keyframes by strictly increasing time.
    pub keyframes: Vec<KeyframeCamera>,
}

/// One keyframe with its camera.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyframeCamera {
    /// Seconds from the path's start.
    pub time: f64,
    /// Centre of projection.
    pub position: [f64; 3],
    /// Viewing direction.
    pub forward: [f64; 3],
    /// Up hint (made orthogonal to `forward`).
    pub up: [f64; 3],
    /// Field of view in degrees along `fov_axis`.
    pub fov_deg: f64,
    /// The film axis of `fov_deg`.
    #[serde(default)]
    pub fov_axis: FovAxis,
}

impl CameraPathFile {
    /// The file of `path` (its cameras' names are not kept).
    pub fn from_path(path: &CameraPath) -> Self {
        CameraPathFile {
            schema: SCHEMA.to_string(),
            version: VERSION,
            name: path.name.clone(),
            looped: path.looped,
            keyframes: path
                .keyframes
                .iter()
                .map(|k| KeyframeCamera {
                    time: k.time,
                    position: k.camera.position.to_array(),
                    forward: k.camera.forward.to_array(),
                    up: k.camera.up.to_array(),
                    fov_deg: k.camera.fov_deg,
                    fov_axis: k.camera.fov_axis,
                })
                .collect(),
        }
    }

    /// The camera path this file describes (cameras named `NAME@TIME`). Errors name `file`
    /// and the keyframe.
    pub fn to_path(&self, file: &Path) -> Result<CameraPath> {
        let bad =
            |i: usize, what: String| SceneError::format(file, format!("keyframe {i}: {what}"));
        if self.keyframes.is_empty() {
            return Err(SceneError::format(file, "the camera path has no keyframes"));
        }
        let mut keyframes = Vec::with_capacity(self.keyframes.len());
        for (i, k) in self.keyframes.iter().enumerate() {
            if !k.time.is_finite() {
                return Err(bad(i, format!("time {} is not finite", k.time)));
            }
            if let Some(prev) = keyframes.last().map(|p: &Keyframe| p.time) {
                if k.time <= prev {
                    return Err(bad(
                        i,
                        format!(
                            "time {} does not follow {prev} (times must increase)",
                            k.time
                        ),
                    ));
                }
            }
            let v = |a: [f64; 3]| glam::DVec3::from_array(a);
            let camera = Camera::look_at(
                format!("{}@{}", self.name, k.time),
                v(k.position),
                v(k.position) + v(k.forward),
                v(k.up),
                k.fov_deg,
                k.fov_axis,
            )
            .ok_or_else(|| {
                bad(
                    i,
                    format!(
                        "camera at {:?} looking along {:?} (up {:?}, {}°) is degenerate",
                        k.position, k.forward, k.up, k.fov_deg
                    ),
                )
            })?;
            keyframes.push(Keyframe {
                time: k.time,
                camera,
            });
        }
        Ok(CameraPath {
            name: self.name.clone(),
            keyframes,
            looped: self.looped,
        })
    }

    /// Parses `text` (the contents of `file`): schema first, then version, then the keyframes.
    pub fn parse(file: &Path, text: &str) -> Result<CameraPath> {
        let value: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| SceneError::format(file, format!("not JSON: {e}")))?;
        match value.get("schema").and_then(|s| s.as_str()) {
            Some(SCHEMA) => {}
            Some(other) => {
                return Err(SceneError::format(
                    file,
                    format!("schema {other:?} is not {SCHEMA:?}"),
                ))
            }
            None => {
                return Err(SceneError::format(
                    file,
                    format!("no \"schema\": {SCHEMA:?}"),
                ))
            }
        }
        match value.get("version").and_then(|v| v.as_u64()) {
            Some(v) if v == u64::from(VERSION) => {}
            v => {
                return Err(SceneError::format(
                    file,
                    format!("version {v:?} is not {VERSION} (this build reads version {VERSION})"),
                ))
            }
        }
        let parsed: CameraPathFile =
            serde_json::from_value(value).map_err(|e| SceneError::format(file, e.to_string()))?;
        parsed.to_path(file)
    }

    /// Reads and parses the camera path file `file`.
    pub fn read(file: &Path) -> Result<CameraPath> {
        let bytes = lustre_brdf::error::read_input(file).map_err(|e| SceneError::Io {
            path: file.to_path_buf(),
            source: e,
        })?;
        let text = std::str::from_utf8(&bytes)
            .map_err(|e| SceneError::format(file, format!("not UTF-8 text: {e}")))?;
        Self::parse(file, text)
    }

    /// Writes `path` to `file` atomically.
    pub fn write(file: &Path, path: &CameraPath) -> Result<()> {
        let text = serde_json::to_string_pretty(&CameraPathFile::from_path(path))
            .map_err(|e| SceneError::format(file, format!("not written: {e}")))?;
        crate::scene_file::write_atomic(file, text.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn path() -> CameraPath {
        let cam = |x: f64| {
            Camera::look_at(
                "c",
                DVec3::new(x, 1.0, 2.0),
                DVec3::ZERO,
                DVec3::Y,
                50.0,
                FovAxis::Y,
            )
            .unwrap()
        };
        CameraPath {
            name: "walk".into(),
            keyframes: vec![
                Keyframe {
                    time: 0.0,
                    camera: cam(0.0),
                },
                Keyframe {
                    time: 0.5,
                    camera: cam(1.0),
                },
            ],
            looped: false,
        }
    }

    #[test]
    fn round_trip_keeps_every_camera() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("walk.json");
        let p = path();
        CameraPathFile::write(&f, &p).unwrap();
        let q = CameraPathFile::read(&f).unwrap();
        assert_eq!(q.keyframes.len(), 2);
        for (a, b) in p.keyframes.iter().zip(&q.keyframes) {
            assert_eq!(a.time, b.time);
            assert!((a.camera.position - b.camera.position).length() < 1e-12);
            assert!((a.camera.forward - b.camera.forward).length() < 1e-12);
            assert!((a.camera.up - b.camera.up).length() < 1e-12);
            assert_eq!(a.camera.fov_deg, b.camera.fov_deg);
            assert_eq!(a.camera.fov_axis, b.camera.fov_axis);
        }
    }

    #[test]
    fn bad_files_are_named_errors() {
        let f = Path::new("walk.json");
        let good = serde_json::to_value(CameraPathFile::from_path(&path())).unwrap();
        let with = |k: &str, v: serde_json::Value| {
            let mut g = good.clone();
            g[k] = v;
            CameraPathFile::parse(f, &g.to_string())
                .unwrap_err()
                .to_string()
        };
        assert!(with("schema", "lustre-material".into()).contains("is not"));
        assert!(with("version", 2.into()).contains("version"));
        assert!(with("keyframes", serde_json::json!([])).contains("no keyframes"));
        let mut k = good["keyframes"].clone();
        k[1]["time"] = 0.0.into();
        assert!(with("keyframes", k).contains("keyframe 1"));
        let mut k = good["keyframes"].clone();
        k[0]["forward"] = serde_json::json!([0.0, 0.0, 0.0]);
        assert!(with("keyframes", k).contains("degenerate"));
        let mut k = good["keyframes"].clone();
        k[0]["fov_deg"] = 180.0.into();
        assert!(with("keyframes", k).contains("keyframe 0"));
        let e = CameraPathFile::parse(f, "{").unwrap_err().to_string();
        assert!(e.contains("walk.json") && e.contains("not JSON"));
        let e = CameraPathFile::parse(f, &with_extra(&good))
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown field"));
    }

    fn with_extra(good: &serde_json::Value) -> String {
        let mut g = good.clone();
        g["colour"] = 1.into();
        g.to_string()
    }
}
