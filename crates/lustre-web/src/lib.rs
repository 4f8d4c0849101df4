//! The walkthrough in a browser. `lustre publish` writes a static folder: `index.html`, this
//! crate compiled to `wasm32-unknown-unknown` with its wasm-bindgen glue, and `scene.glb` (the
//! baked scene with its light maps, the exact materials, cameras and camera paths). The page
//! runs lustre-gpu's passes — the same WGSL as `lustre render --device gpu` — on the browser's
//! WebGPU: [`walk`] makes the scene ready and steps the frame (no browser types; compiled and
//! tested natively too), `page` (wasm32 only) is what the page's JavaScript calls.

pub mod walk;

#[cfg(target_arch = "wasm32")]
mod page;
