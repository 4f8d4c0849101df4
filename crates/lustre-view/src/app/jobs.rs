//! Background jobs: a fit of a measured file ([`crate::fit::FitJob`], its own thread) started
//! from the material panel or the script, polled once a window frame, its material applied to
//! the selected object when it is done.

use super::App;
use crate::fit::FitJob;
use std::time::Instant;

impl App {
    pub(super) fn start_fit(&mut self, input: &str, model: &str) {
        if self.selected_material().is_none() {
            self.note("select the object to fit a material for first", true);
            return;
        }
        self.fit_pressed = Some(Instant::now());
        self.fit_to_screen = None;
        self.fit = Some(FitJob::start(input, model, &self.args.out.join("fits")));
    }

    pub(super) fn poll_fit(&mut self) {
        let Some(job) = &mut self.fit else { return };
        let Some(r) = job.poll() else { return };
        let (input, model) = (job.input.clone(), job.model.clone());
        self.fit = None;
        match r {
            Ok(done) => {
                let json = done.json.display().to_string();
                self.note(
                    format!(
                        "fitted {input} ({model}) in {:.2} s: Ngan L2 ({:.4}, {:.4}, {:.4}) → {json}",
                        done.seconds, done.ngan_l2[0], done.ngan_l2[1], done.ngan_l2[2]
                    ),
                    false,
                );
                self.fit_done = Some(done);
                self.set_material("spec", &json);
            }
            Err(e) => {
                self.fit_pressed = None;
                self.note(format!("fit of {input} failed: {e}"), true);
            }
        }
    }
}
