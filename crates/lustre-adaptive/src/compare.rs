//! Equal-quality comparison (004 Fig. IV.15): the time a renderer needs to reach a PSNR, read
//! off its measured (time, PSNR) curve.

/// One measured render.
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// What was rendered (e.g. "brute 16", "adaptive mean 4").
    pub label: String,
    /// Wall time (s).
    pub time_s: f64,
    /// PSNR (dB) against the reference.
    pub psnr: f64,
    /// Shading samples taken.
    pub samples: u64,
    /// Surface pixels shaded.
    pub shaded: usize,
}

/// The time at which `curve` reaches `psnr`: log-time interpolated linearly in PSNR between the
/// two measured points around it (the curve's points in any order; PSNR must rise with time).
/// `None` when `psnr` lies outside the measured range.
pub fn time_at_psnr(curve: &[Measured], psnr: f64) -> Option<f64> {
    at_psnr(curve, psnr, |m| m.time_s)
}

/// The samples `curve` needs to reach `psnr`, read as [`time_at_psnr`] reads time: unlike
/// wall time it does not move between runs (the renders are seeded), so the ratio of samples at
/// equal PSNR is the deterministic part of a speed-up.
pub fn samples_at_psnr(curve: &[Measured], psnr: f64) -> Option<f64> {
    at_psnr(curve, psnr, |m| m.samples as f64)
}

fn at_psnr(curve: &[Measured], psnr: f64, cost: impl Fn(&Measured) -> f64) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = curve
        .iter()
        .filter(|m| m.psnr.is_finite() && cost(m) > 0.0)
        .map(|m| (m.psnr, cost(m).ln()))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    for pair in pts.windows(2) {
        let ((p0, t0), (p1, t1)) = (pair[0], pair[1]);
        if psnr >= p0 && psnr <= p1 {
            let f = if p1 > p0 {
                (psnr - p0) / (p1 - p0)
            } else {
                0.0
            };
            return Some((t0 + f * (t1 - t0)).exp());
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(time_s: f64, psnr: f64) -> Measured {
        Measured {
            label: String::new(),
            time_s,
            psnr,
            samples: (time_s * 1000.0) as u64,
            shaded: 0,
        }
    }

    #[test]
    fn interpolates_log_time_and_refuses_to_extrapolate() {
        let curve = [m(4.0, 30.0), m(1.0, 24.0), m(2.0, 27.0)];
        assert!((time_at_psnr(&curve, 27.0).unwrap() - 2.0).abs() < 1e-12);
        // Half-way in PSNR between 2 s and 4 s is √8 s in log time.
        assert!((time_at_psnr(&curve, 28.5).unwrap() - 8f64.sqrt()).abs() < 1e-12);
        assert_eq!(time_at_psnr(&curve, 31.0), None);
        assert_eq!(time_at_psnr(&curve, 20.0), None);
        // Samples are read the same way.
        assert!((samples_at_psnr(&curve, 28.5).unwrap() - 1000.0 * 8f64.sqrt()).abs() < 1e-9);
        assert_eq!(samples_at_psnr(&curve, 31.0), None);
    }
}
