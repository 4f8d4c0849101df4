//! lustre-gpu: the regular-sampling kernel of lustre-shade in WGSL through wgpu, headless.
