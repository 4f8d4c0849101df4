//! `pattern::ConcentricOptions::reach` (the option found by `examples/regular_study.rs`): the
//! default reproduces 002 §5 as printed; a reach puts the outermost ring at reach·θmax and
//! keeps the printed ring counts; bad reaches are errors.

use glam::DVec3;
use lustre_shade::pattern::{
    concentric, concentric_for_budget, concentric_for_budget_opts, concentric_with, q, theta_max,
    ConcentricOptions, Spacing,
};

fn polar(h: DVec3) -> f64 {
    h.z.clamp(-1.0, 1.0).acos()
}

#[test]
fn default_options_are_the_printed_patterns() {
    for (mx, my) in [(0.1, 0.1), (0.2, 0.075), (0.05, 0.3)] {
        for xi0 in [0.01, 0.1, 0.2] {
            for nc in 1..6 {
                for sp in [Spacing::S1, Spacing::S2] {
                    let a = concentric(mx, my, nc, sp, xi0).unwrap();
                    let b =
                        concentric_with(mx, my, nc, sp, xi0, ConcentricOptions::default()).unwrap();
                    assert_eq!(a, b);
                }
            }
            for budget in [5, 14, 17, 30, 270] {
                let a = concentric_for_budget(mx, my, budget, xi0).unwrap();
                let b =
                    concentric_for_budget_opts(mx, my, budget, xi0, ConcentricOptions::default())
                        .unwrap();
                assert_eq!(a, b);
            }
        }
    }
}

#[test]
fn reach_places_the_outer_ring_and_keeps_counts() {
    // As printed, nc = 3 ends at θmax/2 (s1: 2/4) and 2.5/5 (s2); Fig. 4 counts 19 and 30.
    let (m, xi0) = (0.1, 0.1);
    let tmax = theta_max(m, m, xi0);
    for (sp, count) in [(Spacing::S1, 19), (Spacing::S2, 30)] {
        let printed = concentric(m, m, 3, sp, xi0).unwrap();
        let outer = printed.h.iter().map(|&h| polar(h)).fold(0.0, f64::max);
        assert!(
            (outer - 0.5 * tmax).abs() < 1e-12,
            "{sp:?}: {outer} vs {tmax}"
        );
        for reach in [0.35, 1.0, 1.5] {
            let opts = ConcentricOptions { reach: Some(reach) };
            let p = concentric_with(m, m, 3, sp, xi0, opts).unwrap();
            if reach > 1.0 {
                // The outer ring lies beyond θmax (q < ξ0) and is rejected: 1 + 6 and 4 + 10.
                let outer_ring = if sp == Spacing::S1 { 12 } else { 16 };
                assert_eq!(p.h.len(), count - outer_ring);
                let outer = p.h.iter().map(|&h| polar(h)).fold(0.0, f64::max);
                assert!(outer <= tmax, "{sp:?}: {outer} > θmax {tmax}");
                continue;
            }
            assert_eq!(p.h.len(), count, "{sp:?}, reach {reach}");
            let outer = p.h.iter().map(|&h| polar(h)).fold(0.0, f64::max);
            assert!((outer - reach * tmax).abs() < 1e-12, "{sp:?}: {outer}");
            // Radii scale by one factor: the ratio of the first ring to the outer one is kept.
            let inner = |hs: &[DVec3]| {
                hs.iter()
                    .map(|&h| polar(h))
                    .filter(|&t| t > 1e-9)
                    .fold(f64::INFINITY, f64::min)
            };
            let o_printed = 0.5 * tmax;
            assert!((inner(&p.h) / (reach * tmax) - inner(&printed.h) / o_printed).abs() < 1e-12);
            // Wider rings sample lower D: the pdf constant (002 Eq. 18) falls as the reach grows.
            assert!(p.pdf_constant > 0.0);
            assert_eq!(
                reach > 0.5,
                p.pdf_constant < printed.pdf_constant,
                "reach {reach}"
            );
        }
    }
}

#[test]
fn anisotropic_reach_rejects_below_the_threshold() {
    let (mx, my, xi0) = (0.2, 0.075, 0.2);
    for reach in [1.0, 1.5] {
        let opts = ConcentricOptions { reach: Some(reach) };
        let p = concentric_for_budget_opts(mx, my, 17, xi0, opts).unwrap();
        // Within the budget (the next larger pattern, 20 samples with reach 1, exceeds it).
        assert!(
            p.h.len() <= 17 && p.h.len() + 4 >= 17,
            "{} samples",
            p.h.len()
        );
        for &h in &p.h {
            assert!(q(mx, my, h) >= xi0 * (1.0 - 1e-9), "{h} below ξ0");
            assert!((h.length() - 1.0).abs() < 1e-12 && h.z > 0.0);
        }
    }
}

#[test]
fn bad_reach_is_an_error() {
    for r in [0.0, -1.0, f64::NAN, f64::INFINITY, 100.0] {
        let opts = ConcentricOptions { reach: Some(r) };
        let e = concentric_with(0.3, 0.3, 3, Spacing::S1, 0.1, opts);
        assert!(e.is_err(), "reach {r}");
        assert!(concentric_for_budget_opts(0.3, 0.3, 14, 0.1, opts).is_err());
    }
}
