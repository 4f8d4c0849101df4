//! What the page's JavaScript calls (wasm32 only): [`Page::open`] with the scene's bytes, then
//! per displayed frame a camera ([`Page::use_camera`], [`Page::use_path`], [`Page::walk`]), a
//! [`Page::render`] step and the pixels ([`Page::pixels`], [`Page::png`]) as promises. The
//! JavaScript only fetches, handles input and draws the returned pixels: every pass is
//! lustre-gpu's WGSL on the browser's WebGPU.

use crate::walk::{walk_camera, Walk};
use lustre_gpu::context::GpuContext;
use lustre_shade::request::{FrameRequest, Method};
use lustre_trace::path_tracer::PathCamera;
use std::cell::RefCell;
use std::rc::Rc;
use wasm_bindgen::prelude::*;

/// Panics print on the page's console.
#[wasm_bindgen(start)]
pub fn start() {
    console_error_panic_hook::set_once();
}

#[wasm_bindgen]
extern "C" {
    /// The page's console.
    #[wasm_bindgen(js_namespace = console, js_name = error)]
    fn console_error(s: &str);
    /// The page's console, for progress.
    #[wasm_bindgen(js_namespace = console, js_name = log)]
    fn console_log(s: &str);
}

struct State {
    walk: Walk,
    camera: PathCamera,
    size: (u32, u32),
    samples: u32,
    rays: u32,
}

/// A published scene on the browser's GPU and the camera the page shows.
#[wasm_bindgen]
pub struct Page {
    state: Rc<RefCell<State>>,
}

fn error(e: impl std::fmt::Display) -> JsValue {
    JsValue::from_str(&e.to_string())
}

#[wasm_bindgen]
impl Page {
    /// Opens the WebGPU device, reads the published scene `bytes` (named `name` in errors),
    /// uploads it and captures its probes (`probe_size`² faces); the first scene camera framed
    /// for a `width`×`height` frame. Rejects with a message that names the problem: no WebGPU
    /// adapter, a bad file, a scene the device cannot hold.
    pub async fn open(
        bytes: Vec<u8>,
        name: String,
        probe_size: u32,
        width: u32,
        height: u32,
    ) -> Result<Page, JsValue> {
        let ctx = GpuContext::new_async().await.map_err(|e| match e {
            lustre_gpu::GpuError::NoAdapter(_) => error(
                "This browser's WebGPU gives no adapter: it may be disabled, or blocklisted for \
                 this GPU (Chrome: see chrome://gpu). The page needs WebGPU.",
            ),
            e => error(e),
        })?;
        // What the browser reports later (a frame's validation error, a lost device) goes to
        // the console, where the page's test reads it.
        ctx.device
            .on_uncaptured_error(std::sync::Arc::new(|e: wgpu::Error| {
                console_error(&format!("lustre: WebGPU error: {e}"))
            }));
        ctx.device.set_device_lost_callback(|reason, message| {
            console_error(&format!(
                "lustre: the WebGPU device was lost ({reason:?}): {message}"
            ))
        });
        // The passes push no error scopes in a browser (they cannot wait for one): what the
        // browser refuses while the scene loads — a buffer or texture beyond one of its limits
        // (its message names the limit), memory, a shader — is caught here and shown.
        let device = ctx.device.clone();
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let t0 = js_sys::Date::now();
        let loaded = Walk::load(ctx, &name, &bytes, probe_size as usize, &mut |stage| {
            console_log(&format!(
                "lustre: {:.1} s: {stage}",
                (js_sys::Date::now() - t0) * 1e-3
            ))
        });
        let refused = match (memory.pop().await, validation.pop().await) {
            (Some(e), _) | (None, Some(e)) => Some(e),
            _ => None,
        };
        if let Some(e) = refused {
            return Err(error(format!(
                "{name}: this browser's WebGPU refused the scene's set-up: {e}"
            )));
        }
        let walk = loaded.map_err(error)?;
        let camera = walk.camera(None, width, height).map_err(error)?;
        Ok(Page {
            state: Rc::new(RefCell::new(State {
                walk,
                camera,
                size: (width, height),
                samples: 16,
                rays: 4,
            })),
        })
    }

    /// The adapter ("name (backend, device type)").
    pub fn adapter(&self) -> String {
        self.state.borrow().walk.adapter()
    }

    /// The scene's camera names.
    pub fn cameras(&self) -> Vec<String> {
        let s = self.state.borrow();
        s.walk
            .scene()
            .cameras
            .iter()
            .map(|c| c.name.clone())
            .collect()
    }

    /// The scene's camera path names.
    pub fn paths(&self) -> Vec<String> {
        let s = self.state.borrow();
        s.walk
            .scene()
            .camera_paths
            .iter()
            .map(|p| p.name.clone())
            .collect()
    }

    /// Duration of camera path `index`, seconds (0 for none).
    pub fn path_duration(&self, index: u32) -> f64 {
        let s = self.state.borrow();
        s.walk
            .scene()
            .camera_paths
            .get(index as usize)
            .map_or(0.0, |p| p.duration())
    }

    /// Probes captured at load and the milliseconds of each, one "name ms" per line.
    pub fn probes(&self) -> String {
        let s = self.state.borrow();
        s.walk
            .capture_ms()
            .iter()
            .map(|(n, ms)| format!("{n} {ms:.1}"))
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// Sets the frame size, glossy samples per pixel and camera rays per pixel (k² of a k×k
    /// G-buffer; 4 as `lustre render`'s default). Rejects what `lustre render` refuses.
    pub fn configure(
        &self,
        width: u32,
        height: u32,
        samples: u32,
        rays: u32,
    ) -> Result<(), JsValue> {
        let req = FrameRequest {
            samples,
            rays,
            ..FrameRequest::default()
        };
        req.validate().map_err(error)?;
        if width == 0 || height == 0 || width > 8192 || height > 8192 {
            return Err(error(format!(
                "frame size {width}×{height}: each side must be in 1..=8192"
            )));
        }
        let mut s = self.state.borrow_mut();
        s.size = (width, height);
        s.samples = samples;
        s.rays = rays;
        Ok(())
    }

    /// Looks through scene camera `name` (`undefined`: the first, or a view framing the scene).
    pub fn use_camera(&self, name: Option<String>) -> Result<(), JsValue> {
        let mut s = self.state.borrow_mut();
        let (w, h) = s.size;
        s.camera = s.walk.camera(name.as_deref(), w, h).map_err(error)?;
        Ok(())
    }

    /// Looks through camera path `index` at `t` seconds.
    pub fn use_path(&self, index: u32, t: f64) -> Result<(), JsValue> {
        let mut s = self.state.borrow_mut();
        let (w, h) = s.size;
        s.camera = s.walk.path_camera(index as usize, t, w, h).map_err(error)?;
        Ok(())
    }

    /// Moves the camera (`forward`, `right`, `up` in scene units) and turns it (`yaw`,
    /// `pitch` in radians).
    pub fn walk(&self, forward: f64, right: f64, up: f64, yaw: f64, pitch: f64) {
        let mut s = self.state.borrow_mut();
        s.camera = walk_camera(&s.camera, (forward, right, up), (yaw, pitch));
    }

    /// One step of the frame: every pass after a move, the next progressive frame when
    /// `refine` > 0 at a still camera (up to `refine` frames), nothing when the image is
    /// complete. Returns what ran: "allocated", "moved", "reshaded", "accumulated" or
    /// "unchanged", and the frames the image holds, as "WORK FRAMES".
    pub fn render(&self, refine: u32) -> Result<String, JsValue> {
        let mut s = self.state.borrow_mut();
        let req = FrameRequest {
            method: if refine > 0 {
                Method::Progressive
            } else {
                Method::Regular
            },
            samples: s.samples,
            rays: s.rays,
            frames: refine.max(1),
            seed: 1,
        };
        let (w, h) = s.size;
        let camera = s.camera;
        let step = s
            .walk
            .step(&camera, (w as usize, h as usize), &req)
            .map_err(error)?;
        let work = match step.work {
            lustre_gpu::walkthrough::StepWork::Allocated => "allocated",
            lustre_gpu::walkthrough::StepWork::Moved => "moved",
            lustre_gpu::walkthrough::StepWork::Reshaded => "reshaded",
            lustre_gpu::walkthrough::StepWork::Accumulated => "accumulated",
            lustre_gpu::walkthrough::StepWork::Unchanged => "unchanged",
        };
        Ok(format!("{work} {}", step.frames))
    }

    /// The current frame as RGBA8 (sRGB at `exposure`, dithered as `lustre render` writes its
    /// PNG), for a canvas's ImageData: a promise, resolved when the GPU has finished it.
    pub fn pixels(&self, exposure: f64) -> js_sys::Promise {
        let pending = self.state.borrow().walk.image();
        wasm_bindgen_futures::future_to_promise(async move {
            let img = pending.map_err(error)?.await.map_err(error)?;
            let rgb = img.to_srgb8_dithered(exposure, 1);
            let rgba: Vec<u8> = rgb
                .chunks_exact(3)
                .flat_map(|p| [p[0], p[1], p[2], 255])
                .collect();
            Ok(js_sys::Uint8ClampedArray::from(&rgba[..]).into())
        })
    }

    /// The current frame as the PNG `lustre render` writes (8-bit sRGB at `exposure`, dithered
    /// with seed 1): a promise of its bytes.
    pub fn png(&self, exposure: f64) -> js_sys::Promise {
        let pending = self.state.borrow().walk.image();
        wasm_bindgen_futures::future_to_promise(async move {
            let img = pending.map_err(error)?.await.map_err(error)?;
            let png = img.encode_png_dithered(exposure, 1).map_err(error)?;
            Ok(js_sys::Uint8Array::from(&png[..]).into())
        })
    }
}
