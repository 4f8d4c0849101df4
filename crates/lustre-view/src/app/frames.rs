//! The link to the render thread: a frame asked for when the camera, the view's size or the
//! settings change, its replies taken (frames, picks, rebuilt materials, errors), the frame
//! shown as an egui texture, and whether the view has settled (the frame on screen is the one
//! asked for, every edit answered).

use super::{App, HISTORY};
use crate::camera::FlyCamera;
use crate::render::{Reply, Request};
use crate::Method;
use std::time::Instant;

impl App {
    /// Takes the render thread's replies.
    pub(super) fn poll_replies(&mut self) {
        while let Ok(r) = self.from_render.try_recv() {
            match r {
                Reply::Status(s) => {
                    if s.starts_with("render error") || s.starts_with("warning") {
                        self.note(s.clone(), s.starts_with("render error"));
                    } else if self.unattended && !s.contains(" tile ") {
                        println!("[{:.1} s] {s}", self.started.elapsed().as_secs_f64());
                    }
                    self.status = s;
                }
                Reply::Ready(info) => {
                    let aspect = f64::from(info.film.0) / f64::from(info.film.1).max(1.0);
                    self.camera = Some(FlyCamera::from_camera(&info.start, aspect));
                    self.speed = (info.extent / 10.0).max(0.05);
                    self.status = format!("{} on {}", info.name, info.adapter);
                    let text = self.status.clone();
                    self.note(format!("ready: {text}"), false);
                    if let Some(why) = &info.no_walkthrough {
                        // Adaptive-only: the window starts in the adaptive method.
                        self.settings.frame.method = Method::Adaptive;
                        self.note(format!("adaptive method only: {why}"), false);
                    }
                    self.info = Some(*info);
                }
                Reply::Frame(f) => {
                    self.frames_received += 1;
                    let now = Instant::now();
                    if let Some(t) = self.last_frame_at.replace(now) {
                        self.frame_times
                            .push_back(((now - t).as_secs_f64() * 1e3, f.times));
                        if self.frame_times.len() > HISTORY {
                            self.frame_times.pop_front();
                        }
                    }
                    if let (Some(pressed), Some(_)) = (self.fit_pressed, self.fit_applied.take()) {
                        let s = pressed.elapsed().as_secs_f64();
                        self.fit_to_screen = Some(s);
                        self.fit_pressed = None;
                        self.note(
                            format!("fit on screen {s:.2} s after Fit was pressed"),
                            false,
                        );
                    }
                    self.failed = None;
                    // A frame ends the adaptive method's table building and any render error.
                    let passing = ["adaptive shading", "render error"];
                    if passing.iter().any(|p| self.status.starts_with(p)) {
                        if let Some(info) = &self.info {
                            self.status = format!("{} on {}", info.name, info.adapter);
                        }
                    }
                    self.frame = Some(*f);
                    self.upload_frame();
                }
                Reply::FrameFailed {
                    camera,
                    size,
                    settings,
                    error,
                } => {
                    // Said in the view (the frame before it would not be what was asked for)
                    // and in the notes; a script goes on with its next command.
                    self.failed = Some((camera, size, settings));
                    self.frame = None;
                    let text = format!("render error: {error}");
                    // Once, not at every camera move (a scene the method cannot light).
                    if self.notes.last().is_none_or(|n| n.text != text) {
                        self.note(text.clone(), true);
                    }
                    self.status = text;
                }
                Reply::Picked(mesh) => {
                    self.pending_pick = false;
                    self.select(mesh);
                }
                Reply::MaterialSet {
                    material,
                    edit,
                    result,
                    seconds,
                } => {
                    self.pending_edits = self.pending_edits.saturating_sub(1);
                    if let Some(info) = &self.info {
                        self.status = format!("{} on {}", info.name, info.adapter);
                    }
                    match result {
                        Ok(m) => {
                            let name = m.name.clone();
                            if let Some((field, value)) = edit.split_once('=') {
                                self.edits.push((
                                    name.clone(),
                                    field.to_string(),
                                    value.to_string(),
                                ));
                                if field == "spec" && self.fit_pressed.is_some() {
                                    self.fit_applied = Some(value.to_string());
                                }
                            }
                            if let Some(info) = &mut self.info {
                                if let Some(slot) = info.materials.get_mut(material) {
                                    *slot = *m;
                                }
                            }
                            self.note(format!("{name}: {edit} (rebuilt in {seconds:.2} s)"), false);
                            // The rebuilt scene renders nothing until asked: ask again, and
                            // wait for that frame (not the one before the edit).
                            self.settings.generation += 1;
                            self.refresh_draft();
                        }
                        Err(e) => {
                            self.fit_pressed = None;
                            self.note(format!("{edit}: {e}"), true);
                            self.refresh_draft();
                        }
                    }
                }
                Reply::Fatal(e) => {
                    self.status = "stopped".into();
                    self.note(e.clone(), true);
                    self.fatal = Some(e);
                }
            }
        }
    }

    /// The frame as the egui texture, at the current exposure (or the adaptive method's buffer
    /// view as a heat map).
    pub(super) fn upload_frame(&mut self) {
        let Some(f) = &self.frame else { return };
        let buffer = f
            .adaptive
            .as_ref()
            .and_then(|a| Some((a.width, a.height, a.rgb(self.buffer_view)?)));
        self.heat_range = buffer.as_ref().map(|b| b.2 .1);
        let img = match buffer {
            Some((w, h, (rgb, _))) => egui::ColorImage::from_rgb([w, h], &rgb),
            None => egui::ColorImage::from_rgb(
                [f.image.width, f.image.height],
                &f.image.to_srgb8(self.exposure),
            ),
        };
        let opts = if self.scale >= 1.0 {
            egui::TextureOptions::NEAREST
        } else {
            egui::TextureOptions::LINEAR
        };
        match &mut self.texture {
            Some(t) => t.set(img, opts),
            None => self.texture = Some(self.ctx.load_texture("view", img, opts)),
        }
    }

    pub(super) fn pick(&mut self, pixel: (f64, f64)) {
        let Some((camera, size, _)) = self.sent else {
            return;
        };
        self.pending_pick = true;
        let _ = self.to_render.send(Request::Pick {
            camera,
            size,
            pixel,
        });
    }

    /// Sends a frame request when the camera, size or settings changed.
    pub(super) fn request_frame(&mut self) {
        let Some(cam) = self.camera else { return };
        let (w, h) = self.view_size;
        if w == 0 || h == 0 || self.fatal.is_some() {
            return;
        }
        let Some(pc) = cam.path_camera(w as u32, h as u32) else {
            return;
        };
        let key = (pc, (w, h), self.settings);
        if self.sent != Some(key) {
            self.sent = Some(key);
            let _ = self.to_render.send(Request::Frame {
                camera: pc,
                size: (w, h),
                settings: self.settings,
            });
        }
        if let Some(r) = &mut self.recording {
            let t = r.seconds();
            r.sample(t, cam.to_camera(&self.record_name));
        }
    }

    /// True when the frame on screen is the one of the current request and every edit and
    /// pick has been answered.
    pub(super) fn settled(&self) -> bool {
        let shown = self
            .frame
            .as_ref()
            .map(|f| (f.camera, (f.image.width, f.image.height), f.settings));
        self.pending_edits == 0
            && !self.pending_pick
            && self.fit.is_none()
            && self.sent.is_some()
            && (shown == self.sent || self.failed == self.sent)
    }
}
