//! Mitsuba scene XML: any text gives a scene or an error, never a panic; referenced files
//! resolve under a folder that does not exist, so only the XML reader itself is exercised.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(scene) = lustre_scene::mitsuba::from_str(Path::new("/nonexistent/fuzz.xml"), text) {
            for m in &scene.meshes {
                assert!(m.positions.iter().all(|p| p.is_finite()));
                assert!(m.indices.iter().flatten().all(|&i| (i as usize) < m.positions.len()));
                assert!(m.material < scene.materials.len());
            }
        }
    }
});
