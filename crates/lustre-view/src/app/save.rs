//! Saving: the selected material as material JSON, the scene file with the edits, and the
//! window's screenshot with what the 3D view shows (JSON) and its camera as a camera path.

use super::App;
use crate::adaptive::rule_name;
use crate::render::SceneSource;
use crate::Method;
use anyhow::anyhow;
use lustre_scene::camera_path_file::CameraPathFile;
use lustre_scene::material_edit;
use lustre_scene::{CameraPath, Keyframe, Material, MaterialKind};
use std::path::Path;

impl App {
    pub(super) fn save_material(&mut self) {
        let file = self.out_path(&self.save_material_path);
        let Some(m) = self
            .selected_material()
            .and_then(|m| self.info.as_ref()?.materials.get(m).cloned())
        else {
            self.note("select an object first", true);
            return;
        };
        let r = match &m.kind {
            // An unedited material JSON is copied with its fit record.
            MaterialKind::Spec(s)
                if s.edits.is_empty() && s.spec.to_ascii_lowercase().ends_with(".json") =>
            {
                lustre_brdf::material::read(Path::new(&s.spec))
                    .and_then(|f| lustre_brdf::material::write(&file, &f))
                    .map_err(|e| e.to_string())
            }
            // Anything else fitted (a catalog fit, an edited model) is written from its
            // parameters; an edited model has no fit record.
            MaterialKind::Spec(s) => {
                lustre_brdf::material::MaterialModel::from_bsdf(s.bsdf.as_ref())
                    .and_then(|model| {
                        lustre_brdf::material::MaterialFile::new(m.name.clone(), model, None)
                    })
                    .and_then(|f| lustre_brdf::material::write(&file, &f))
                    .map_err(|e| format!("{:?} ({}): {e}; save the scene to keep it", m.name, s.spec))
            }
            k => Err(format!(
                "{:?} is a {} material, not a fitted model: its parameters are saved with the scene",
                m.name,
                k.name()
            )),
        };
        match r {
            Ok(()) => self.note(format!("material {:?} → {}", m.name, file.display()), false),
            Err(e) => self.note(e, true),
        }
    }

    pub(super) fn save_scene(&mut self) {
        let file = self.out_path(&self.save_scene_path);
        let r = match &self.source {
            SceneSource::BuiltinRoom(_) => Err(
                "the built-in room has no scene file: save the material JSON or the camera path; \
                 `lustre render --set MATERIAL.PARAMETER=VALUE` replays the edits"
                    .to_string(),
            ),
            SceneSource::Unbaked(scene) => Err(format!(
                "{} has no scene file: save the material JSON or the camera path; `lustre render \
                 --method adaptive --set MATERIAL.PARAMETER=VALUE` replays the edits",
                scene.source.display()
            )),
            SceneSource::File(src) => {
                let current = self.info.as_ref().map_or(&[][..], |i| &i.materials[..]);
                edited_scene_file(src, &self.edits, current).and_then(|f| {
                    lustre_scene::scene_file::write(&file, &f).map_err(|e| e.to_string())
                })
            }
        };
        match r {
            Ok(()) => self.note(format!("scene → {}", file.display()), false),
            Err(e) => self.note(e, true),
        }
    }

    /// Writes the window's pixels as PNG and, beside it, what the 3D view shows (JSON) and its
    /// camera as a camera path file.
    pub(super) fn write_screenshot(&mut self, path: &Path, (w, h, rgba): (u32, u32, Vec<u8>)) {
        let r = (|| -> anyhow::Result<()> {
            if let Some(d) = path.parent() {
                std::fs::create_dir_all(d)?;
            }
            let img = image::RgbaImage::from_raw(w, h, rgba)
                .ok_or_else(|| anyhow!("screenshot buffer of the wrong size"))?;
            let mut png = std::io::Cursor::new(vec![]);
            image::DynamicImage::ImageRgba8(img).write_to(&mut png, image::ImageFormat::Png)?;
            lustre_brdf::error::write_atomic(path, png.get_ref())?;
            let cam_file = path.with_extension("camera.json");
            if let Some(c) = self.camera {
                CameraPathFile::write(
                    &cam_file,
                    &CameraPath {
                        name: "screenshot".into(),
                        keyframes: vec![Keyframe {
                            time: 0.0,
                            camera: c.to_camera("screenshot"),
                        }],
                        looped: false,
                    },
                )?;
            }
            let set: Vec<String> = self
                .edits
                .iter()
                .map(|(m, f, v)| format!("{m}.{f}={v}"))
                .collect();
            let f = self.frame.as_ref();
            let selected = self.selected.and_then(|m| {
                let info = self.info.as_ref()?;
                let (name, mat) = info.meshes.get(m)?;
                Some(serde_json::json!({
                    "mesh": name,
                    "material": info.materials.get(*mat).map(|x| x.name.clone()),
                }))
            });
            let side = serde_json::json!({
                "window": [w, h],
                "view": {
                    "rect": self.view_rect_px,
                    "size": f.map(|f| [f.image.width, f.image.height]),
                    "scale": self.scale,
                },
                "camera": cam_file.file_name().map(|n| n.to_string_lossy().into_owned()),
                "method": self.settings.frame.method.name(),
                "adaptive": (self.settings.frame.method == Method::Adaptive).then(|| {
                    let a = f.and_then(|f| f.adaptive.as_deref());
                    serde_json::json!({
                        "buffer": self.buffer_view.name(),
                        "rate": self.settings.adaptive.rate,
                        "sample_rule": rule_name(self.settings.adaptive.rule),
                        "heat_range": self.heat_range.map(|(lo, hi)| [lo, hi]),
                        "surface_pixels": a.map(|a| a.surface_pixels),
                        "shaded_pixels": a.map(|a| a.shaded_pixels),
                        "upsampled_pixels": a.map(|a| a.upsampled_pixels),
                        "samples": a.map(|a| a.samples_total),
                        "gbuffer_ms": a.map(|a| a.gbuffer_ms),
                        "bandwidth_ms": a.map(|a| a.bandwidth_ms),
                        "shading_ms": a.map(|a| a.shading_ms),
                        "tables_ms": a.map(|a| a.tables_ms),
                        "bandwidth_on_gpu": a.map(|a| a.on_gpu.0),
                        "shading_on_gpu": a.map(|a| a.on_gpu.1),
                        "why_cpu": a.and_then(|a| a.why_cpu.clone()),
                    })
                }),
                "samples": self.settings.frame.samples,
                "supersampling": self.settings.frame.supersampling(),
                "exposure": self.exposure,
                "frames": f.map(|f| f.frames),
                "set": set,
                "object_samples": self.info.as_ref().map(|i| {
                    i.meshes
                        .iter()
                        .zip(&i.object_samples)
                        .filter_map(|((name, _), n)| n.map(|n| (name.clone(), n)))
                        .collect::<std::collections::BTreeMap<String, u32>>()
                }),
                "selected": selected,
                "scene": self.info.as_ref().map(|i| i.name.clone()),
                "adapter": self.info.as_ref().map(|i| i.adapter.clone()),
                "step_ms": f.map(|f| f.wall_ms),
                "pass_ms": f.map(|f| serde_json::json!({
                    "views": f.times.views_ms, "layers": f.times.layers_ms,
                    "gbuffer": f.times.gbuffer_ms, "lightmap": f.times.lightmap_ms,
                    "shade": f.times.shade_ms, "gpu_timestamps": f.times.timestamps,
                })),
                "window_frame_ms": self.ui_times.back(),
                "fit_to_screen_s": self.fit_to_screen,
            });
            lustre_brdf::error::write_atomic(
                &path.with_extension("json"),
                serde_json::to_string_pretty(&side)?.as_bytes(),
            )?;
            Ok(())
        })();
        match r {
            Ok(()) => self.note(format!("screenshot → {}", path.display()), false),
            Err(e) => self.note(format!("screenshot {}: {e:#}", path.display()), true),
        }
    }
}

/// The scene file `src` with the edits: `spec` swaps as material overrides (dropping earlier
/// parameter edits of that material), the rest as `[material_params]`; paths made absolute.
/// Where a fitted model's distribution, α or p was edited, all three are written with their
/// values in `current` (the materials as edited), so that the file rebuilds the same
/// distribution whatever the order of the edits.
fn edited_scene_file(
    src: &Path,
    edits: &[(String, String, String)],
    current: &[Material],
) -> Result<lustre_scene::scene_file::SceneFile, String> {
    let text = std::fs::read_to_string(src).map_err(|e| format!("{}: {e}", src.display()))?;
    let base = src.parent().unwrap_or(Path::new("."));
    let mut f = lustre_scene::scene_file::parse(src, &text)
        .map_err(|e| e.to_string())?
        .with_absolute_paths(base);
    for (m, field, value) in edits {
        if field == "spec" {
            f.materials.insert(m.clone(), value.clone());
            let prefix = format!("{m}.");
            f.material_params.retain(|k, _| !k.starts_with(&prefix));
        } else {
            f.material_params
                .insert(format!("{m}.{field}"), value.clone());
        }
    }
    const SHAPE: [&str; 3] = ["model.distribution", "model.alpha", "model.p"];
    for m in current {
        let prefix = format!("{}.", m.name);
        let reshaped = SHAPE
            .iter()
            .any(|k| f.material_params.contains_key(&format!("{prefix}{k}")));
        if reshaped {
            for k in SHAPE {
                f.material_params.remove(&format!("{prefix}{k}"));
            }
            for field in material_edit::fields(m) {
                if SHAPE.contains(&field.name.as_str()) {
                    f.material_params
                        .insert(format!("{prefix}{}", field.name), field.value.to_text());
                }
            }
        }
    }
    Ok(f)
}
