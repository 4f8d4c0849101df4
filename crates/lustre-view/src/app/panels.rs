//! The egui panels: the layout (a status line, the view panel on the left, the material
//! editor on the right, the 3D view in the middle), the view panel (frame rates, the passes'
//! times, the method and its settings, walking, cameras, recording, screenshots), the notes,
//! and the 3D view with its input (click to select, drag to look, wheel for speed, WASD).

use super::window::configure;
use super::{App, HISTORY, LOOK_RADIANS_PER_PIXEL};
use crate::adaptive::{rule_name, BufferView, SAMPLE_RULES};
use crate::camera::Movement;
use crate::setup_overlay::OverlayKind;
use crate::Method;
use lustre_shade::request::MAX_SUPERSAMPLING;
use std::collections::VecDeque;

/// Width of the view panel, points.
const LEFT_PANEL: f32 = 210.0;
/// Width of the material panel, points.
const RIGHT_PANEL: f32 = 280.0;

impl App {
    /// The panels and the 3D view.
    pub(super) fn ui(&mut self, ui: &mut egui::Ui, dt: f64) {
        egui::Panel::top("top").show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.strong("lustre view");
                ui.label(&self.status);
                if let Some(f) = &self.fatal {
                    ui.colored_label(egui::Color32::RED, f);
                }
            });
        });
        // Panels of a fixed width (long lines wrap), the rest is the 3D view.
        egui::Panel::left("view")
            .resizable(false)
            .exact_size(LEFT_PANEL)
            .show(ui, |ui| {
                egui::ScrollArea::vertical()
                    .auto_shrink([false; 2])
                    .show(ui, |ui| self.view_panel(ui));
            });
        egui::Panel::right("material")
            .resizable(false)
            .exact_size(RIGHT_PANEL)
            .show(ui, |ui| {
                egui::ScrollArea::vertical()
                    .auto_shrink([false; 2])
                    .show(ui, |ui| self.material_panel(ui));
            });
        egui::CentralPanel::default().show(ui, |ui| self.central(ui, dt));
    }

    fn view_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("View");
        let ui_fps = if self.ui_times.is_empty() {
            0.0
        } else {
            1e3 * self.ui_times.len() as f64 / self.ui_times.iter().sum::<f64>().max(1e-9)
        };
        let view_fps = if self.frame_times.is_empty() {
            0.0
        } else {
            1e3 * self.frame_times.len() as f64
                / self.frame_times.iter().map(|f| f.0).sum::<f64>().max(1e-9)
        };
        ui.label(format!(
            "window {ui_fps:.1} fps · 3D {view_fps:.2} frames/s"
        ));
        if let Some(a) = self.frame.as_ref().and_then(|f| f.adaptive.as_deref()) {
            // The adaptive method's line: what it shaded and what it cost.
            ui.label(format!(
                "adaptive: {:.1} % of {} surface px shaded · {} samples ({:.2}/px) · bandwidth pass {:.0} ms · shading {:.0} ms · G-buffer {:.0} ms",
                100.0 * a.shaded_share(),
                a.surface_pixels,
                a.samples_total,
                a.samples_total as f64 / a.surface_pixels.max(1) as f64,
                a.bandwidth_ms,
                a.shading_ms,
                a.gbuffer_ms,
            ));
            let place = |gpu: bool| if gpu { "GPU" } else { "CPU" };
            ui.small(format!(
                "bandwidth pass on the {}, shading on the {} · material tables {:.2} s (once per scene and material edit)",
                place(a.on_gpu.0),
                place(a.on_gpu.1),
                a.tables_ms * 1e-3
            ));
            if let Some(why) = &a.why_cpu {
                ui.small(format!("CPU because: {why}"));
            }
        }
        if let Some(f) = &self.frame {
            let t = &f.times;
            ui.label(format!(
                "{}×{} · {} · {} frame(s) · step {:.1} ms",
                f.image.width,
                f.image.height,
                f.settings.frame.method.name(),
                f.frames,
                f.wall_ms
            ));
            if f.work.is_some() {
                let clock = if t.timestamps { "GPU" } else { "wall" };
                ui.label(format!(
                    "passes ({clock} ms): views {:.1} (layers {:.1}) · G-buffer {:.1} · light map {:.1} · glossy {:.1}",
                    t.views_ms, t.layers_ms, t.gbuffer_ms, t.lightmap_ms, t.shade_ms
                ));
                let hits = f.stats.glossy_hits.max(1);
                ui.label(format!(
                    "budget {} lookups/pixel · made {:.2} per glossy hit",
                    f.settings.frame.samples,
                    f.stats.lookups as f64 / hits as f64
                ));
            }
        }
        frame_graph(ui, &self.frame_times);
        ui.separator();
        ui.label("Method");
        for m in [
            Method::Regular,
            Method::Ck,
            Method::Progressive,
            Method::Reference,
            Method::Adaptive,
        ] {
            let text = match m {
                Method::Regular => "regular sampling",
                Method::Ck => "Colbert–Křivánek",
                Method::Progressive => "progressive when still",
                Method::Reference => "path-traced reference (CPU)",
                Method::Adaptive => "adaptive shading (004 ch. IV)",
                Method::Brute => "brute force (CPU)",
            };
            let refused = self.walkthrough_refusal(m);
            let radio = egui::RadioButton::new(self.settings.frame.method == m, text);
            let clicked = match refused {
                Some(why) => ui.add_enabled(false, radio).on_disabled_hover_text(why),
                None => ui.add(radio),
            }
            .clicked();
            if clicked {
                self.choose_method(m);
            }
        }
        if self.settings.frame.method == Method::Adaptive {
            self.adaptive_panel(ui);
        } else {
            ui.add(
                egui::Slider::new(&mut self.settings.frame.samples, 1..=64)
                    .text("samples (global)"),
            );
        }
        let mut k = self.settings.frame.supersampling();
        ui.add(egui::Slider::new(&mut k, 1..=MAX_SUPERSAMPLING).text("k×k G-buffer"));
        self.settings.frame.rays = k * k;
        ui.add(
            egui::Slider::new(&mut self.settings.frame.frames, 1..=1024)
                .logarithmic(true)
                .text("refine to"),
        );
        ui.add(egui::Slider::new(&mut self.scale, 0.1..=1.0).text("resolution"));
        if ui
            .add(
                egui::Slider::new(&mut self.exposure, 0.05..=20.0)
                    .logarithmic(true)
                    .text("exposure"),
            )
            .changed()
        {
            self.upload_frame();
        }
        ui.checkbox(
            &mut self.show_setup,
            "show set-up (room probes cyan, object probes yellow, reflectors magenta)",
        );
        if ui.checkbox(&mut self.vsync, "vsync").changed() {
            if let Some(g) = &mut self.gfx {
                configure(g, self.vsync);
            }
        }
        ui.separator();
        ui.label("Walk: WASD / arrows, Q/E down/up, drag to look, wheel: speed, shift: run");
        ui.add(
            egui::Slider::new(&mut self.speed, 0.01..=100.0)
                .logarithmic(true)
                .text("speed (units/s)"),
        );
        let names: Vec<String> = self
            .info
            .as_ref()
            .map(|i| i.cameras.iter().map(|c| c.name.clone()).collect())
            .unwrap_or_default();
        if !names.is_empty() {
            ui.label("Cameras");
            ui.horizontal_wrapped(|ui| {
                for n in names {
                    if ui.button(&n).clicked() {
                        self.set_camera_named(&n);
                    }
                }
            });
        }
        ui.horizontal(|ui| {
            ui.label("path");
            ui.add(egui::TextEdit::singleline(&mut self.record_name).desired_width(120.0));
        });
        if self.recording.is_some() {
            if ui.button("⏹ stop recording").clicked() {
                if let Some(r) = &mut self.recording {
                    r.file = format!("{}.json", self.record_name);
                }
                self.stop_recording();
            }
        } else if ui.button("⏺ record camera path").clicked() {
            self.start_recording();
        }
        if ui.button("screenshot (F12)").clicked() {
            self.screenshots += 1;
            self.screenshot =
                Some(self.out_path(&format!("screenshot-{:03}.png", self.screenshots)));
        }
    }

    /// The adaptive method's controls: mean N_p, rate, sample rule, the buffer shown.
    fn adaptive_panel(&mut self, ui: &mut egui::Ui) {
        ui.add(
            egui::Slider::new(&mut self.settings.frame.samples, 1..=256)
                .logarithmic(true)
                .text("mean N_p"),
        );
        let a = &mut self.settings.adaptive;
        ui.horizontal(|ui| {
            ui.label("rate");
            ui.radio_value(&mut a.rate, 2, "2")
                .on_hover_text("image samples per cycle of b_p: Nyquist's rate");
            ui.radio_value(&mut a.rate, 1, "1")
                .on_hover_text("Eq. IV.11 as printed: fewer pixels shaded");
        });
        egui::ComboBox::from_label("N_p rule")
            .selected_text(rule_name(a.rule))
            .show_ui(ui, |ui| {
                for r in SAMPLE_RULES {
                    ui.selectable_value(&mut a.rule, r, rule_name(r));
                }
            });
        ui.label("show");
        let before = self.buffer_view;
        for v in BufferView::ALL {
            ui.radio_value(&mut self.buffer_view, v, v.label());
        }
        if self.buffer_view != before {
            self.upload_frame();
        }
        if let Some((lo, hi)) = self.heat_range {
            ui.small(format!(
                "log heat map {lo:.3} … {hi:.3} (1st–99.9th percentile; black: 0)"
            ));
        }
    }

    pub(super) fn notes_ui(&self, ui: &mut egui::Ui) {
        ui.separator();
        for n in self.notes.iter().rev() {
            if n.error {
                ui.colored_label(egui::Color32::from_rgb(255, 110, 110), &n.text);
            } else {
                ui.label(&n.text);
            }
        }
    }

    fn central(&mut self, ui: &mut egui::Ui, dt: f64) {
        let ppp = ui.ctx().pixels_per_point();
        let avail = ui.available_size();
        let (rect, resp) = ui.allocate_exact_size(avail, egui::Sense::click_and_drag());
        let w = ((f64::from(avail.x * ppp)) * self.scale).floor().max(16.0) as usize;
        let h = ((f64::from(avail.y * ppp)) * self.scale).floor().max(16.0) as usize;
        self.view_size = (w, h);
        // The image on whole pixels from the panel's corner.
        let min_px = (rect.min.to_vec2() * ppp).round();
        let min = egui::pos2(min_px.x / ppp, min_px.y / ppp);
        if let (Some(t), Some(f)) = (&self.texture, &self.frame) {
            let size_px =
                egui::vec2(f.image.width as f32, f.image.height as f32) / self.scale as f32;
            let r = egui::Rect::from_min_size(min, size_px / ppp);
            ui.painter().with_clip_rect(rect).image(
                t.id(),
                r,
                egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                egui::Color32::WHITE,
            );
            self.view_rect_px = [min_px.x, min_px.y, size_px.x, size_px.y];
            if let (true, Some(info)) = (self.show_setup, &self.info) {
                let painter = ui.painter().with_clip_rect(r.intersect(rect));
                let to_screen = |p: [f64; 2]| {
                    r.min + egui::vec2(p[0] as f32, p[1] as f32) / (ppp * self.scale as f32)
                };
                let (iw, ih) = (
                    f64::from(f.image.width as u32),
                    f64::from(f.image.height as u32),
                );
                for (a, b, kind) in info.setup.segments(&f.camera, iw, ih) {
                    let colour = match kind {
                        OverlayKind::RoomProbe => egui::Color32::from_rgb(0, 220, 255),
                        OverlayKind::ObjectProbe => egui::Color32::from_rgb(255, 220, 0),
                        OverlayKind::Reflector => egui::Color32::from_rgb(255, 60, 220),
                    };
                    painter.line_segment([to_screen(a), to_screen(b)], (1.5, colour));
                }
            }
        } else {
            ui.painter().text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                &self.status,
                egui::FontId::proportional(16.0),
                egui::Color32::GRAY,
            );
        }
        if resp.clicked() {
            if let Some(p) = resp.interact_pointer_pos() {
                let px = (p - min) * ppp * self.scale as f32;
                self.pick((f64::from(px.x), f64::from(px.y)));
            }
        }
        if resp.dragged() {
            let d = resp.drag_delta() * ppp;
            if let Some(c) = &mut self.camera {
                c.look(f64::from(d.x), f64::from(d.y), LOOK_RADIANS_PER_PIXEL);
            }
        }
        let ctx = ui.ctx().clone();
        if resp.hovered() {
            let scroll = ctx.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.speed =
                    (self.speed * 1.2f64.powf(f64::from(scroll) / 50.0)).clamp(0.01, 100.0);
            }
        }
        if !ctx.egui_wants_keyboard_input() {
            let (m, run, shot) = ctx.input(|i| {
                let k = |a: egui::Key, b: egui::Key| {
                    if i.key_down(a) || i.key_down(b) {
                        1.0
                    } else {
                        0.0
                    }
                };
                (
                    Movement {
                        forward: k(egui::Key::W, egui::Key::ArrowUp)
                            - k(egui::Key::S, egui::Key::ArrowDown),
                        right: k(egui::Key::D, egui::Key::ArrowRight)
                            - k(egui::Key::A, egui::Key::ArrowLeft),
                        up: k(egui::Key::E, egui::Key::E) - k(egui::Key::Q, egui::Key::Q),
                    },
                    i.modifiers.shift,
                    i.key_pressed(egui::Key::F12),
                )
            });
            let speed = self.speed * if run { 4.0 } else { 1.0 };
            if let Some(c) = &mut self.camera {
                c.walk(m, speed, dt.min(0.25));
            }
            if shot {
                self.screenshots += 1;
                self.screenshot =
                    Some(self.out_path(&format!("screenshot-{:03}.png", self.screenshots)));
            }
        }
    }
}

/// The frame-time graph: the time between 3D frames and the GPU's per-pass times, stacked.
fn frame_graph(ui: &mut egui::Ui, times: &VecDeque<(f64, lustre_gpu::GpuFrameTimes)>) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(220.0, 70.0), egui::Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 2.0, egui::Color32::from_gray(24));
    let max = times.iter().map(|t| t.0).fold(1.0, f64::max);
    let n = HISTORY as f32;
    let y = |ms: f64| rect.bottom() - (ms / max) as f32 * rect.height();
    let colours = [
        egui::Color32::from_rgb(90, 160, 255),
        egui::Color32::from_rgb(120, 220, 120),
        egui::Color32::from_rgb(250, 200, 80),
        egui::Color32::from_rgb(240, 110, 90),
    ];
    for (i, (wall, t)) in times.iter().enumerate() {
        let x = rect.left() + (i as f32 + 0.5) * rect.width() / n;
        let mut acc = 0.0;
        for (k, ms) in [t.views_ms, t.gbuffer_ms, t.lightmap_ms, t.shade_ms]
            .into_iter()
            .enumerate()
        {
            p.line_segment(
                [egui::pos2(x, y(acc)), egui::pos2(x, y(acc + ms))],
                egui::Stroke::new(rect.width() / n, colours[k]),
            );
            acc += ms;
        }
        p.circle_filled(egui::pos2(x, y(*wall)), 1.2, egui::Color32::WHITE);
    }
    p.text(
        rect.left_top() + egui::vec2(3.0, 2.0),
        egui::Align2::LEFT_TOP,
        format!("{max:.0} ms · views, G-buffer, light map, glossy; • frame"),
        egui::FontId::proportional(10.0),
        egui::Color32::LIGHT_GRAY,
    );
}
