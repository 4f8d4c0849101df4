//! lustre scene TOML: any text gives a scene file or an error, never a panic; a file that parses
//! writes back to text that parses to the same file.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_scene::scene_file;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let path = Path::new("/nonexistent/fuzz.toml");
        if let Ok(file) = scene_file::parse(path, text) {
            let again = file.to_toml().expect("a parsed scene file serializes");
            let back = scene_file::parse(path, &again).expect("a written scene file parses");
            assert_eq!(back, file);
        }
    }
});
