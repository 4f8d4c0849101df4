//! The material editor panel: the selected object's sample budget, its material's parameters
//! as controls, a swap for any specification (the catalog filtered), a fit of a measured file
//! with the lobe plot of measurement and fit, and saving the material JSON and the scene.

use super::App;
use crate::fit::{FitDone, PLOT_THETA_I};
use crate::plot::polar_points;
use lustre_scene::material_edit::{Field, FieldValue};

impl App {
    pub(super) fn material_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("Material");
        let Some(info) = &self.info else {
            ui.label("loading…");
            return;
        };
        let sel = self.selected.and_then(|m| info.meshes.get(m).cloned());
        let Some((mesh_name, _)) = sel else {
            ui.label("click an object to select it");
            self.notes_ui(ui);
            return;
        };
        ui.label(format!("object {mesh_name:?}"));
        // The object's own sample budget (else the global one).
        let mesh = self.selected.unwrap_or(0);
        let own = info.object_samples.get(mesh).copied().flatten();
        let mut on = own.is_some();
        let mut n = own.unwrap_or(self.settings.frame.samples);
        let mut budget = None;
        let c = ui.checkbox(&mut on, "its own sample budget");
        let r = ui.add_enabled(on, egui::Slider::new(&mut n, 1..=64));
        if c.changed() || r.drag_stopped() || (r.changed() && !r.dragged()) {
            budget = Some(on.then_some(n));
        }
        let mut commits: Vec<(String, String)> = vec![];
        if let Some(d) = &mut self.draft {
            let mat = &info.materials[d.material];
            ui.label(format!("material {:?} ({})", mat.name, mat.kind.name()));
            // Grouped names (`model.reflection[0].mx`) get a group line and their last part
            // as the label, so that rows stay within the panel.
            let mut group = String::new();
            for f in &mut d.fields {
                let g = f.name.rsplit_once('.').map_or("", |(g, _)| g).to_string();
                if g != group && !g.is_empty() && g != "spec" {
                    ui.small(&g);
                }
                group = g;
                if let Some(v) = field_ui(ui, f) {
                    commits.push((f.name.clone(), v));
                }
            }
            ui.separator();
            ui.label("swap for a specification (catalog, material JSON, measured file)");
            ui.add(egui::TextEdit::singleline(&mut d.spec).desired_width(f32::INFINITY));
            ui.horizontal(|ui| {
                ui.label("catalog");
                ui.add(egui::TextEdit::singleline(&mut self.catalog_filter).desired_width(120.0));
            });
            let filter = self.catalog_filter.to_ascii_lowercase();
            egui::ComboBox::from_id_salt("catalog")
                .selected_text("pick…")
                .show_ui(ui, |ui| {
                    for name in self
                        .catalog
                        .iter()
                        .filter(|n| n.to_ascii_lowercase().contains(&filter))
                        .take(200)
                    {
                        if ui.selectable_label(false, name).clicked() {
                            d.spec = name.clone();
                        }
                    }
                });
            if ui.button("apply").clicked() && !d.spec.trim().is_empty() {
                commits.push(("spec".into(), d.spec.trim().to_string()));
            }
        }
        for (f, v) in commits {
            self.set_material(&f, &v);
        }
        if let Some(samples) = budget {
            self.set_object_samples(mesh, samples);
        }
        ui.separator();
        ui.label("Fit a measured file (MERL .binary, RGL .bsdf, nbrdf:NAME, data:…)");
        ui.add(egui::TextEdit::singleline(&mut self.fit_input).desired_width(f32::INFINITY));
        ui.horizontal(|ui| {
            for m in ["sgd", "kurt", "beckmann", "ggx"] {
                ui.radio_value(&mut self.fit_model, m.to_string(), m);
            }
        });
        if let Some(job) = &self.fit {
            ui.add(egui::ProgressBar::new(0.0).animate(true).text(format!(
                "{} · {:.1} s",
                job.stage,
                job.started.elapsed().as_secs_f64()
            )));
        } else if ui.button("Fit").clicked() && !self.fit_input.trim().is_empty() {
            let (i, m) = (self.fit_input.trim().to_string(), self.fit_model.clone());
            self.start_fit(&i, &m);
        }
        if let Some(s) = self.fit_to_screen {
            ui.label(format!("last fit on screen {s:.2} s after pressing Fit"));
        }
        if let Some(done) = &self.fit_done {
            lobe_plot(ui, done);
        }
        ui.separator();
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.save_material_path).desired_width(120.0));
            if ui.button("save material JSON").clicked() {
                self.save_material();
            }
        });
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.save_scene_path).desired_width(120.0));
            if ui.button("save scene").clicked() {
                self.save_scene();
            }
        });
        self.notes_ui(ui);
    }
}

/// A parameter's control; returns the value to set when the user committed a change (a
/// slider let go, a box edited, a choice made).
fn field_ui(ui: &mut egui::Ui, f: &mut Field) -> Option<String> {
    let mut commit = false;
    let (lo, hi) = f.range;
    let bounded = hi - lo <= 1e6;
    let label = match f.name.rsplit_once('.') {
        Some((g, last)) if g != "spec" => last,
        _ => f.name.as_str(),
    };
    ui.horizontal_wrapped(|ui| {
        ui.label(label);
        match &mut f.value {
            FieldValue::Scalar(v) => {
                let r = if bounded {
                    ui.add(egui::Slider::new(v, lo..=hi).logarithmic(f.log))
                } else {
                    let speed = (v.abs() * 0.01).max(1e-3);
                    ui.add(egui::DragValue::new(v).speed(speed))
                };
                commit = r.drag_stopped() || (r.changed() && !r.dragged());
            }
            FieldValue::Rgb(c) => {
                // A step of 1% of the value (a fitted weight may be 1e-3 in a range of 10).
                let scale = c.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                let speed = ((hi - lo) * 0.002).min((scale * 0.01).max(1e-3)).max(1e-4);
                for x in c.iter_mut() {
                    let r = ui.add(
                        egui::DragValue::new(x)
                            .range(lo..=hi)
                            .speed(speed)
                            .max_decimals(4),
                    );
                    commit |= r.drag_stopped() || (r.changed() && !r.dragged());
                }
                let shown = |x: f64| (lustre_trace::image::display_value(x, 1.0) * 255.0) as u8;
                let (rect, _) =
                    ui.allocate_exact_size(egui::vec2(14.0, 14.0), egui::Sense::hover());
                ui.painter().rect_filled(
                    rect,
                    2.0,
                    egui::Color32::from_rgb(shown(c[0]), shown(c[1]), shown(c[2])),
                );
            }
            FieldValue::Choice(s) => {
                let before = s.clone();
                egui::ComboBox::from_id_salt(&f.name)
                    .selected_text(s.clone())
                    .show_ui(ui, |ui| {
                        for c in f.choices {
                            ui.selectable_value(s, c.to_string(), *c);
                        }
                    });
                commit = *s != before;
            }
            FieldValue::Flag(b) => commit = ui.checkbox(b, "").changed(),
            FieldValue::Text(t) => {
                ui.label(t.as_str());
            }
        }
        if f.textured {
            ui.label("× texture");
        }
    });
    if commit && !matches!(f.value, FieldValue::Text(_)) {
        Some(f.value.to_text())
    } else {
        None
    }
}

/// The polar lobe plot of the last fit: measurement (white) and fit (orange) at each θi.
fn lobe_plot(ui: &mut egui::Ui, done: &FitDone) {
    ui.label(format!(
        "lobes in the plane of incidence (cube-root radius), θi = {}°, {}°: measured white, fit orange",
        PLOT_THETA_I[0], PLOT_THETA_I[1]
    ));
    let (rect, _) = ui.allocate_exact_size(egui::vec2(280.0, 150.0), egui::Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 2.0, egui::Color32::from_gray(20));
    let origin = egui::pos2(rect.center().x, rect.bottom() - 4.0);
    let radius = (rect.height() - 8.0).min(rect.width() / 2.0 - 4.0);
    p.circle_stroke(
        origin,
        radius,
        egui::Stroke::new(0.5, egui::Color32::from_gray(70)),
    );
    let max = done
        .measured
        .iter()
        .chain(&done.fitted)
        .flat_map(|s| s.values.iter().copied())
        .fold(1e-12, f64::max);
    let to_screen = |q: [f64; 2]| {
        egui::pos2(
            origin.x + q[0] as f32 * radius,
            origin.y - q[1] as f32 * radius,
        )
    };
    for (slices, colour) in [
        (&done.measured, egui::Color32::WHITE),
        (&done.fitted, egui::Color32::from_rgb(255, 150, 40)),
    ] {
        for s in slices {
            let pts: Vec<egui::Pos2> = polar_points(s, max).into_iter().map(to_screen).collect();
            p.add(egui::Shape::line(pts, egui::Stroke::new(1.2, colour)));
        }
    }
}
