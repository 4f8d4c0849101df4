//! Recording the camera path while walking: keyframes taken as the camera moves, written as a
//! `lustre-camera-path` JSON that `lustre render --path FILE.json` replays. The keyframe rules
//! are [`Recording`]'s plain methods; the window asks them once a frame.

use super::App;
use lustre_scene::camera_path_file::CameraPathFile;
use lustre_scene::{Camera, CameraPath, Keyframe};
use std::time::Instant;

/// A recording of the camera path.
pub(super) struct Recording {
    started: Instant,
    keyframes: Vec<Keyframe>,
    /// Where the path is written (a name in the output folder, or an absolute path).
    pub(super) file: String,
}

impl Recording {
    /// A recording starting now, with `first` (if any) as its first keyframe, at 0 s.
    fn new(first: Option<Camera>, file: String) -> Self {
        Recording {
            started: Instant::now(),
            keyframes: first
                .map(|camera| Keyframe { time: 0.0, camera })
                .into_iter()
                .collect(),
            file,
        }
    }

    /// Seconds since the recording started.
    pub(super) fn seconds(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    /// Whether `c` is away from the last keyframe's camera (its position or its direction), or
    /// there is no keyframe yet.
    fn moved(&self, c: &Camera) -> bool {
        self.keyframes
            .last()
            .is_none_or(|k| k.camera.position != c.position || k.camera.forward != c.forward)
    }

    /// Takes camera `c` at `t` seconds as a keyframe when it moved since the last one and the
    /// time is past the last one's.
    pub(super) fn sample(&mut self, t: f64, c: Camera) {
        if self.moved(&c) && self.keyframes.last().is_none_or(|k| t > k.time) {
            self.keyframes.push(Keyframe { time: t, camera: c });
        }
    }

    /// Takes camera `c`, where the recording stops at `t` seconds, as its last keyframe when it
    /// moved since the last one: at least 1 ms after that one (a script's instant walk ends
    /// between two frames).
    fn close(&mut self, t: f64, c: Camera) {
        if self.moved(&c) {
            let t = self.keyframes.last().map_or(t, |k| t.max(k.time + 1e-3));
            self.keyframes.push(Keyframe { time: t, camera: c });
        }
    }
}

impl App {
    /// Starts a recording at the current camera (its first keyframe, at 0 s).
    pub(super) fn start_recording(&mut self) {
        let first = self.camera.map(|c| c.to_camera(&self.record_name));
        self.recording = Some(Recording::new(first, format!("{}.json", self.record_name)));
    }

    pub(super) fn stop_recording(&mut self) {
        let Some(mut r) = self.recording.take() else {
            return;
        };
        // The camera where the recording stops is its last keyframe (a script's instant walk
        // ends between two frames).
        if let Some(c) = self.camera {
            let c = c.to_camera(&self.record_name);
            let t = r.seconds();
            r.close(t, c);
        }
        let path = CameraPath {
            name: self.record_name.clone(),
            keyframes: r.keyframes,
            looped: false,
        };
        let file = self.out_path(&r.file);
        match CameraPathFile::write(&file, &path) {
            Ok(()) => self.note(
                format!(
                    "camera path of {} keyframes, {:.1} s → {} (lustre render --path {})",
                    path.keyframes.len(),
                    path.duration(),
                    file.display(),
                    file.display()
                ),
                false,
            ),
            Err(e) => self.note(e.to_string(), true),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use lustre_scene::FovAxis;

    fn at(x: f64) -> Camera {
        let (p, target) = (DVec3::new(x, 1.0, 0.0), DVec3::new(x, 1.0, -1.0));
        Camera::look_at("walk", p, target, DVec3::Y, 60.0, FovAxis::Y).unwrap()
    }

    fn times(r: &Recording) -> Vec<f64> {
        r.keyframes.iter().map(|k| k.time).collect()
    }

    #[test]
    fn a_keyframe_is_taken_only_when_the_camera_moved_and_time_went_on() {
        let mut r = Recording::new(Some(at(0.0)), "walk.json".into());
        assert_eq!(times(&r), [0.0]);
        r.sample(0.5, at(0.0));
        assert_eq!(times(&r), [0.0], "still: no keyframe");
        r.sample(0.5, at(1.0));
        assert_eq!(times(&r), [0.0, 0.5]);
        r.sample(0.5, at(2.0));
        assert_eq!(times(&r), [0.0, 0.5], "the same time twice: not taken");
        r.sample(0.75, at(2.0));
        assert_eq!(times(&r), [0.0, 0.5, 0.75]);
        assert_eq!(r.keyframes[2].camera.position.x, 2.0);
    }

    #[test]
    fn a_recording_without_a_camera_starts_at_the_first_sample() {
        let mut r = Recording::new(None, "walk.json".into());
        assert!(r.keyframes.is_empty());
        r.sample(0.25, at(0.0));
        assert_eq!(times(&r), [0.25]);
    }

    #[test]
    fn the_stopping_camera_closes_the_path_after_its_last_keyframe() {
        // A script's instant walk: the camera moved, no frame in between.
        let mut r = Recording::new(Some(at(0.0)), "walk.json".into());
        r.close(0.0, at(3.0));
        assert_eq!(times(&r), [0.0, 1e-3]);
        assert_eq!(r.keyframes[1].camera.position.x, 3.0);
        // Where it stopped already: nothing added.
        r.close(2.0, at(3.0));
        assert_eq!(times(&r), [0.0, 1e-3]);
        // Later on: at its own time.
        r.close(2.0, at(4.0));
        assert_eq!(times(&r), [0.0, 1e-3, 2.0]);
    }
}
