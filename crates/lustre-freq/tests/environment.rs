//! Local angular bandwidth (004 §IV.3.1) of the shared environment maps: finite everywhere,
//! high at a small sun, low on an overcast-smooth region.

use lustre_env::{read_map, shared_data_dir};
use lustre_freq::environment::angular_bandwidth;

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p) as usize]
}

#[test]
fn the_sun_is_the_highest_bandwidth_region_of_quarry() {
    let loaded = read_map(&shared_data_dir().join("envmaps/quarry_01_1k.hdr")).expect("map");
    let map = loaded.map;
    let t0 = std::time::Instant::now();
    let b = angular_bandwidth(&map).expect("bandwidth");
    let seconds = t0.elapsed().as_secs_f64();
    assert!(b.iter().all(|v| v.is_finite() && *v >= 0.0));
    let lum = |p: &[f32; 3]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let sun = (0..map.data.len())
        .max_by(|&a, &c| lum(&map.data[a]).total_cmp(&lum(&map.data[c])))
        .expect("pixels");
    let mut all = b.clone();
    let median = percentile(&mut all, 0.5);
    let p99 = percentile(&mut all, 0.99);
    eprintln!(
        "quarry_01_1k ({}×{}): {seconds:.2} s; bandwidth at the sun {:.1} cycles/rad, median {median:.1}, 99th percentile {p99:.1}",
        map.width, map.height, b[sun]
    );
    assert!(b[sun] >= p99, "sun {} vs 99th percentile {p99}", b[sun]);
    assert!(b[sun] >= 20.0 * median, "sun {} vs median {median}", b[sun]);
}
