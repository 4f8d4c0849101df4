//! Radiance `.hdr` environment maps: any bytes give a map or an error, never a panic.
//!
//! Inputs whose first byte is odd get a valid header (`#?RADIANCE`, 2:1 size from the second
//! byte) prepended, so the fuzzer reaches the pixel decoder (RLE and flat scanlines) rather
//! than stopping at the magic check. Accepted maps are converted to a small cube pyramid.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lustre_env::{parse_hdr, CubeMap, CubePyramid, MipFilter};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let expanded;
    let bytes = match data {
        [flag, h, rest @ ..] if flag & 1 == 1 => {
            let h = (*h as usize % 16) + 1;
            let mut buf =
                format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {}\n", 2 * h).into_bytes();
            buf.extend_from_slice(rest);
            expanded = buf;
            &expanded[..]
        }
        _ => data,
    };
    if let Ok(m) = parse_hdr(Path::new("<fuzz>"), bytes) {
        assert_eq!(m.map.width, 2 * m.map.height);
        assert!(m.map.data.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
        if let Ok(c) = CubeMap::from_equirect(&m.map, 4) {
            let _ = CubePyramid::build(c, MipFilter::Gauss4);
        }
    }
});
