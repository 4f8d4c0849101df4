//! BRDF bandwidth tables (004 §IV.3.1, Fig. IV.8) of measured materials: the glossy paint's
//! lobe carries more angular bandwidth than the rubber's, and every entry is finite.

use glam::DVec3;
use lustre_brdf::measured::nbrdf::NbrdfSet;
use lustre_freq::brdf::{brdf_bandwidth, BrdfBandwidthOptions};

#[test]
fn gold_paint_has_more_angular_bandwidth_than_blue_rubber() {
    let set = NbrdfSet::read(lustre_brdf::shared_data_dir().join("nbrdf/merl_nbrdf.json"))
        .expect("merl_nbrdf.json");
    let o = BrdfBandwidthOptions::default();
    let t0 = std::time::Instant::now();
    let gold = brdf_bandwidth(&set.material("gold-paint").expect("gold"), o).expect("gold");
    let seconds = t0.elapsed().as_secs_f64();
    let rubber = brdf_bandwidth(&set.material("blue-rubber").expect("rubber"), o).expect("rubber");
    assert_eq!(gold.data.len(), 16 * 16 * 16 * 16);
    assert!(gold
        .data
        .iter()
        .chain(&rubber.data)
        .all(|v| v.is_finite() && *v >= 0.0));
    // Around the mirror direction of θi = 30°.
    let t = 30f64.to_radians();
    let wi = DVec3::new(t.sin(), 0.0, t.cos());
    let mirror = DVec3::new(-wi.x, 0.0, wi.z);
    let (g, r) = (gold.at(wi, mirror), rubber.at(wi, mirror));
    let mean = |d: &[f64]| d.iter().sum::<f64>() / d.len() as f64;
    eprintln!(
        "16×16 incident × 16×16 outgoing (64² slices): gold-paint {seconds:.2} s; at the mirror of θi = 30°: gold-paint {g:.1}, blue-rubber {r:.1} cycles/rad; table means {:.1} / {:.1}",
        mean(&gold.data),
        mean(&rubber.data)
    );
    assert!(g >= 2.0 * r, "gold {g} vs rubber {r}");
}
