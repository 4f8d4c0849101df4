//! glTF 2.0 (.gltf JSON or .glb): any bytes give a scene or an error, never a panic; external
//! files resolve under a folder that does not exist (embedded buffers are read).
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(scene) = lustre_scene::gltf_io::from_slice(Path::new("/nonexistent/fuzz.gltf"), data) {
        for m in &scene.meshes {
            assert!(m.positions.iter().all(|p| p.is_finite()));
            assert!(m.indices.iter().flatten().all(|&i| (i as usize) < m.positions.len()));
        }
    }
});
