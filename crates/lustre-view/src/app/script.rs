//! Unattended runs: the input script ([`crate::script`] parses it) run command by command
//! through the same actions as the keyboard, the mouse and the panels, each command that
//! changes what is rendered waiting for the frame that shows it; and the run's end (the
//! script's `quit`, `--frames` reached, a fatal error, the timeout).

use super::{App, LOOK_RADIANS_PER_PIXEL};
use crate::camera::Movement;
use crate::script::{Command, Direction};
use std::path::Path;
use std::time::Duration;
use winit::event_loop::ActiveEventLoop;

/// What a script command waits for before the next one runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Wait {
    /// Window frames.
    Frames(u32),
    /// The frame of the current camera and settings, every edit answered.
    Settle,
    /// The screenshot asked for has been written.
    Screenshot,
}

impl Wait {
    /// What is still waited for after this window frame, given whether the view has `settled`
    /// and whether a screenshot is still to be written; `None`: the script goes on. A wait for
    /// `n` frames counts one down per window frame and ends at 0.
    fn next(self, settled: bool, screenshot_pending: bool) -> Option<Wait> {
        match self {
            Wait::Frames(n) if n > 0 => Some(Wait::Frames(n - 1)),
            Wait::Settle if !settled => Some(Wait::Settle),
            Wait::Screenshot if screenshot_pending => Some(Wait::Screenshot),
            _ => None,
        }
    }
}

/// The keys `walk` holds: one unit along one of the camera's axes.
fn movement(d: Direction) -> Movement {
    match d {
        Direction::Forward => Movement {
            forward: 1.0,
            ..Default::default()
        },
        Direction::Back => Movement {
            forward: -1.0,
            ..Default::default()
        },
        Direction::Right => Movement {
            right: 1.0,
            ..Default::default()
        },
        Direction::Left => Movement {
            right: -1.0,
            ..Default::default()
        },
        Direction::Up => Movement {
            up: 1.0,
            ..Default::default()
        },
        Direction::Down => Movement {
            up: -1.0,
            ..Default::default()
        },
    }
}

impl App {
    /// Runs script commands until one has to wait.
    pub(super) fn step_script(&mut self) {
        if self.info.is_none() || self.camera.is_none() {
            return;
        }
        loop {
            if let Some(w) = self.wait {
                self.wait = w.next(self.settled(), self.screenshot.is_some());
                if self.wait.is_some() {
                    return;
                }
            }
            if self.script.front() == Some(&Command::Quit) {
                return;
            }
            let Some(cmd) = self.script.pop_front() else {
                return;
            };
            self.exec(cmd);
            if self.wait.is_some() {
                return;
            }
        }
    }

    fn exec(&mut self, cmd: Command) {
        let settle = Some(Wait::Settle);
        match cmd {
            Command::Wait(n) => self.wait = Some(Wait::Frames(n)),
            Command::Walk(d, secs) => {
                let m = movement(d);
                let speed = self.speed;
                if let Some(c) = &mut self.camera {
                    c.walk(m, speed, secs);
                }
                self.wait = settle;
            }
            Command::Look(dx, dy) => {
                if let Some(c) = &mut self.camera {
                    c.look(dx, dy, LOOK_RADIANS_PER_PIXEL);
                }
                self.wait = settle;
            }
            Command::Camera(name) => {
                if !self.set_camera_named(&name) {
                    self.note(format!("script: no camera named {name:?}"), true);
                }
                self.wait = settle;
            }
            Command::Select(x, y) => {
                self.pick((x, y));
                self.wait = settle;
            }
            Command::SelectMaterial(name) => {
                let mesh = self.info.as_ref().and_then(|i| {
                    i.meshes
                        .iter()
                        .position(|(_, m)| i.materials.get(*m).is_some_and(|x| x.name == name))
                });
                match mesh {
                    Some(m) => self.select(Some(m)),
                    None => self.note(format!("script: no object with material {name:?}"), true),
                }
            }
            Command::Set(field, value) => {
                self.set_material(&field, &value);
                self.wait = settle;
            }
            Command::Material(spec) => {
                self.set_material("spec", &spec);
                self.wait = settle;
            }
            Command::Method(m) => {
                self.choose_method(m);
                self.wait = settle;
            }
            Command::Samples(n) => {
                self.settings.frame.samples = n;
                self.wait = settle;
            }
            Command::Buffer(v) => {
                self.buffer_view = v;
                self.upload_frame();
            }
            Command::Rate(r) => {
                self.settings.adaptive.rate = r;
                self.wait = settle;
            }
            Command::SampleRule(r) => {
                self.settings.adaptive.rule = r;
                self.wait = settle;
            }
            Command::Budget(n) => {
                match self.selected {
                    Some(mesh) => self.set_object_samples(mesh, n),
                    None => self.note("script: budget needs a selected object", true),
                }
                self.wait = settle;
            }
            Command::Exposure(e) => {
                self.exposure = e;
                self.upload_frame();
            }
            Command::ShowSetup(on) => self.show_setup = on,
            Command::Fit(file, model) => {
                self.start_fit(&file, &model);
                self.wait = settle;
            }
            Command::RecordStart => self.start_recording(),
            Command::RecordStop(file) => {
                self.record_name = Path::new(&file)
                    .file_stem()
                    .map_or("walk".into(), |s| s.to_string_lossy().into_owned());
                if let Some(r) = &mut self.recording {
                    r.file = file;
                }
                self.stop_recording();
            }
            Command::Screenshot(file) => {
                self.screenshot = Some(self.out_path(&file));
                self.wait = Some(Wait::Screenshot);
            }
            Command::SaveMaterial(file) => {
                self.save_material_path = file;
                self.save_material();
            }
            Command::SaveScene(file) => {
                self.save_scene_path = file;
                self.save_scene();
            }
            // Left at the front of the script for `check_end`.
            Command::Quit => {}
        }
    }

    /// Ends unattended runs: a fatal error, the script's quit, --frames reached, the timeout.
    pub(super) fn check_end(&mut self, event_loop: &ActiveEventLoop) {
        if !self.unattended {
            return;
        }
        if let Some(e) = &self.fatal {
            let e = e.clone();
            self.finish(event_loop, Err(e));
            return;
        }
        if self.started.elapsed() > Duration::from_secs_f64(self.args.timeout) {
            let msg = format!(
                "timed out after {:.0} s ({} command(s) left, status: {})",
                self.args.timeout,
                self.script.len(),
                self.status
            );
            self.finish(event_loop, Err(msg));
            return;
        }
        if self.screenshot.is_some() || self.wait.is_some() {
            return;
        }
        if self.script.front() == Some(&Command::Quit) {
            self.finish(event_loop, Ok(()));
            return;
        }
        if !self.script.is_empty() {
            return;
        }
        if let Some(n) = self.args.frames {
            if self.frames_shown >= n && self.settled() {
                if let (Some(p), false) = (&self.args.screenshot, self.quit_after_screenshot) {
                    self.screenshot = Some(p.clone());
                    self.quit_after_screenshot = true;
                    return;
                }
                self.finish(event_loop, Ok(()));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_wait_counts_down_then_lets_the_script_go_on() {
        let mut w = Some(Wait::Frames(2));
        let mut frames = 0;
        while let Some(x) = w {
            w = x.next(false, true);
            frames += 1;
            assert!(frames < 10, "a wait for 2 frames never ended");
        }
        // 2 frames waited, the third goes on.
        assert_eq!(frames, 3);
        assert_eq!(Wait::Frames(0).next(false, true), None);
    }

    #[test]
    fn a_settle_wait_ends_with_the_settled_view_and_a_screenshot_wait_when_written() {
        assert_eq!(Wait::Settle.next(false, false), Some(Wait::Settle));
        assert_eq!(Wait::Settle.next(true, true), None);
        assert_eq!(Wait::Screenshot.next(true, true), Some(Wait::Screenshot));
        assert_eq!(Wait::Screenshot.next(false, false), None);
    }

    #[test]
    fn each_walk_direction_holds_one_key() {
        let all = [
            (Direction::Forward, [1.0, 0.0, 0.0]),
            (Direction::Back, [-1.0, 0.0, 0.0]),
            (Direction::Right, [0.0, 1.0, 0.0]),
            (Direction::Left, [0.0, -1.0, 0.0]),
            (Direction::Up, [0.0, 0.0, 1.0]),
            (Direction::Down, [0.0, 0.0, -1.0]),
        ];
        for (d, [forward, right, up]) in all {
            let m = movement(d);
            assert_eq!(m, Movement { forward, right, up }, "{d:?}");
        }
    }
}
