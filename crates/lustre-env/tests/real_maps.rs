//! Readers and conversions on the real maps of the shared data (`envmaps/`).

use lustre_env::{map_size, read_map, shared_data_dir, CubeMap, CubePyramid, EnvError, MipFilter};
use std::path::PathBuf;

fn envmaps() -> PathBuf {
    shared_data_dir().join("envmaps")
}

fn rel(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3)
        .map(|c| ((a[c] - b[c]) / b[c]).abs())
        .fold(0.0, f64::max)
}

#[test]
fn reads_every_hdr_and_exr_map() {
    let mut n = 0;
    for e in std::fs::read_dir(envmaps()).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if name.contains("dwab") {
            continue;
        }
        let m = read_map(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(m.map.width, 2 * m.map.height, "{name}");
        // The header alone gives the size the decoder finds.
        let size = map_size(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(size, (m.map.width, m.map.height), "{name}");
        let s = m.map.integral();
        eprintln!(
            "{name}: {}×{}, ∫L = {s:?}, nonfinite {}, negative {}",
            m.map.width, m.map.height, m.nonfinite, m.negative
        );
        assert!(s.iter().all(|v| v.is_finite() && *v > 0.0), "{name}");
        n += 1;
    }
    assert!(n >= 13, "{n} maps");
}

#[test]
fn dwab_exr_decodes_or_names_the_compression() {
    let p = envmaps().join("studio_interior_dwab.exr");
    match read_map(&p) {
        Ok(m) => {
            let zip = read_map(&envmaps().join("studio_interior.exr")).unwrap();
            assert_eq!((m.map.width, m.map.height), (zip.map.width, zip.map.height));
            let r = rel(m.map.integral(), zip.map.integral());
            // The ZIP file holds the same (already DWAB-quantized) half floats.
            let same = m
                .map
                .data
                .iter()
                .zip(&zip.map.data)
                .filter(|(a, b)| a == b)
                .count();
            let frac = same as f64 / m.map.data.len() as f64;
            eprintln!(
                "DWAB decoded; ∫L differs from the ZIP file by {r:e}; {:.4}% texels identical",
                100.0 * frac
            );
            assert!(r < 0.02, "{r}");
            assert!(frac > 0.9, "{frac}");
        }
        Err(EnvError::Format { problem, .. }) => {
            eprintln!("{problem}");
            assert!(problem.contains("DWAB"), "{problem}");
        }
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn cube_conversion_preserves_energy_on_real_maps() {
    for name in ["quarry_01_1k.hdr", "studio_interior.exr"] {
        let m = read_map(&envmaps().join(name)).unwrap().map;
        let reference = m.integral();
        let cube = CubeMap::from_equirect(&m, 256).unwrap();
        let r = rel(cube.integral(), reference);
        eprintln!("{name}: cube 256 ∫L relative error {r:e}");
        assert!(r < 1e-3, "{name}: {r}");
        for f in [MipFilter::Box2, MipFilter::Gauss4, MipFilter::Gauss6] {
            let p = CubePyramid::build(cube.clone(), f).unwrap();
            assert_eq!(p.levels.len(), 9);
            let drift: Vec<String> = p
                .levels
                .iter()
                .map(|m| format!("{:.1e}", rel(m.integral(), reference)))
                .collect();
            eprintln!(
                "{name} {f:?}: ∫L relative drift per level {}",
                drift.join(" ")
            );
            // Solid-angle-weighted filtering keeps the energy at every level.
            for (l, m) in p.levels.iter().enumerate() {
                let d = rel(m.integral(), cube.integral());
                let tol = if f == MipFilter::Box2 {
                    1e-5
                } else if m.size >= 16 {
                    5e-3
                } else {
                    3e-2
                };
                assert!(d < tol, "{name} {f:?} level {l}: ∫L drift {d:e}");
            }
        }
    }
}
