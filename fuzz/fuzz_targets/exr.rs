//! OpenEXR environment maps: any bytes give a map or an error, never a panic (nor an
//! allocation driven by an absurd header: the reader refuses sizes the file cannot hold).
//!
//! Inputs whose first byte is odd are spliced into a small valid file (8×4, RGB f32, ZIP):
//! the remaining bytes overwrite the file from an offset given by the second byte, so the
//! fuzzer mutates real headers, offset tables and compressed blocks.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_env::parse_exr;
use std::path::Path;
use std::sync::OnceLock;

fn template() -> &'static [u8] {
    static T: OnceLock<Vec<u8>> = OnceLock::new();
    T.get_or_init(|| {
        use exr::prelude::*;
        let img = Image::from_channels(
            (8, 4),
            SpecificChannels::rgb(|p: Vec2<usize>| (p.x() as f32, p.y() as f32, 0.5f32)),
        );
        let mut buf = std::io::Cursor::new(Vec::new());
        match img.write().to_buffered(&mut buf) {
            Ok(()) => buf.into_inner(),
            Err(_) => Vec::new(),
        }
    })
}

fuzz_target!(|data: &[u8]| {
    let expanded;
    let bytes = match data {
        [flag, off, rest @ ..] if flag & 1 == 1 => {
            let mut buf = template().to_vec();
            let start = (*off as usize * 2).min(buf.len());
            for (k, b) in rest.iter().enumerate() {
                match buf.get_mut(start + k) {
                    Some(slot) => *slot = *b,
                    None => buf.push(*b),
                }
            }
            expanded = buf;
            &expanded[..]
        }
        _ => data,
    };
    if let Ok(m) = parse_exr(Path::new("<fuzz>"), bytes) {
        assert_eq!(m.map.width, 2 * m.map.height);
        assert!(m.map.data.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    }
});
