//! A BRDF's local angular bandwidth, tabulated over incident directions (004 §IV.3.1,
//! "Reflectance (angular)", Fig. IV.8): for each of `incident`² incident directions (θi
//! uniform in [0, π/2), φi uniform in [0, 2π), cell centres) the outgoing lobe's luminance
//! f(ωi, ωo) is rendered on a `slice`² grid of the upper hemisphere (x: φo uniform in [0, 2π),
//! periodic; y: θo uniform in [0, π/2)), its local bandwidth taken ([`local_bandwidth`], cycles
//! per pixel) and turned into cycles per radian with the grid's largest pixels per radian,
//! max(slice / (2π sin θo), slice / (π/2)); the slice is then reduced to `out`² by the maximum
//! over blocks (004 computes at a higher resolution and reduces to 16 × 16, the conservative
//! way).

use crate::wavelet::{local_bandwidth, Edges};
use crate::{FreqError, Result};
use glam::DVec3;
use lustre_brdf::Bsdf;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// The grids of a [`BrdfBandwidth`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BrdfBandwidthOptions {
    /// Incident directions per axis (004: 16).
    pub incident: usize,
    /// Outgoing grid per axis at which the bandwidth is computed (a power of two ≥ `out`).
    pub slice: usize,
    /// Outgoing cells per axis kept (004: 16); `slice` must be a multiple.
    pub out: usize,
}

impl Default for BrdfBandwidthOptions {
    fn default() -> Self {
        Self {
            incident: 16,
            slice: 64,
            out: 16,
        }
    }
}

/// The table: per incident cell (θi row, φi column), `out`² outgoing cells (θo row, φo column)
/// of angular bandwidth in cycles per radian.
#[derive(Clone, Debug, PartialEq)]
pub struct BrdfBandwidth {
    /// The grids.
    pub options: BrdfBandwidthOptions,
    /// `incident² · out²` values, incident cell-major.
    pub data: Vec<f64>,
}

impl BrdfBandwidth {
    /// The bandwidth stored for the incident and outgoing cells holding `wi` and `wo` (local,
    /// above the surface; directions below are clamped onto the horizon's cells).
    pub fn at(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.view(wo).at(wi)
    }

    /// The table seen from `wo` (its outgoing cell found once, for many `wi`).
    pub fn view(&self, wo: DVec3) -> BrdfBandwidthView<'_> {
        let o = &self.options;
        let (to, po) = grid_cell(wo, o.out);
        BrdfBandwidthView {
            table: self,
            out_cell: to * o.out + po,
        }
    }
}

/// A [`BrdfBandwidth`] at one outgoing direction ([`BrdfBandwidth::view`]).
#[derive(Clone, Copy, Debug)]
pub struct BrdfBandwidthView<'a> {
    table: &'a BrdfBandwidth,
    out_cell: usize,
}

impl BrdfBandwidthView<'_> {
    /// The bandwidth for incident direction `wi` (as [`BrdfBandwidth::at`]).
    pub fn at(&self, wi: DVec3) -> f64 {
        self.at_polar(wi.z.clamp(0.0, 1.0).acos(), wi.y.atan2(wi.x))
    }

    /// [`BrdfBandwidthView::at`] from ωi's θ = acos(clamp(z, 0, 1)) and azimuth atan2(y, x),
    /// when a caller knows them (a fixed set of directions).
    pub fn at_polar(&self, theta: f64, phi: f64) -> f64 {
        let o = &self.table.options;
        let (ti, pi) = polar_cell(theta, phi, o.incident);
        self.table.data[(ti * o.incident + pi) * o.out * o.out + self.out_cell]
    }
}

/// The (θ row, φ column) of the `n`² hemisphere grid holding `w` (θ uniform in [0, π/2), φ in
/// [0, 2π); below the horizon clamps onto it).
fn grid_cell(w: DVec3, n: usize) -> (usize, usize) {
    polar_cell(w.z.clamp(0.0, 1.0).acos(), w.y.atan2(w.x), n)
}

/// [`grid_cell`] from the direction's θ and azimuth (any multiple of 2π).
fn polar_cell(theta: f64, phi: f64, n: usize) -> (usize, usize) {
    let phi = phi.rem_euclid(2.0 * PI);
    (
        ((theta / FRAC_PI_2 * n as f64) as usize).min(n - 1),
        ((phi / (2.0 * PI) * n as f64) as usize).min(n - 1),
    )
}

/// The direction at the centre of cell (row `t`, column `p`) of an `n`² hemisphere grid.
fn cell_direction(t: usize, p: usize, n: usize) -> DVec3 {
    let theta = (t as f64 + 0.5) / n as f64 * FRAC_PI_2;
    let phi = (p as f64 + 0.5) / n as f64 * 2.0 * PI;
    DVec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// Tabulates `bsdf`'s angular bandwidth. Errors on absurd grids (zero, `slice` not a power of
/// two, not a multiple of `out`, above 1024) and on a BRDF value that is not finite (named with
/// the directions).
pub fn brdf_bandwidth(bsdf: &dyn Bsdf, options: BrdfBandwidthOptions) -> Result<BrdfBandwidth> {
    let o = options;
    if o.incident == 0
        || o.incident > 1024
        || o.out == 0
        || o.slice > 1024
        || !o.slice.is_power_of_two()
        || !o.slice.is_multiple_of(o.out)
    {
        return Err(FreqError::Parameter(format!(
            "BRDF bandwidth of {}: incident {} (1..=1024), slice {} (a power of two ≤ 1024) and out {} (dividing the slice) are not usable",
            bsdf.name(),
            o.incident,
            o.slice,
            o.out
        )));
    }
    let blocks: Vec<Vec<f64>> = (0..o.incident * o.incident)
        .into_par_iter()
        .map(|k| -> Result<Vec<f64>> {
            let wi = cell_direction(k / o.incident, k % o.incident, o.incident);
            let n = o.slice;
            let mut slice = Vec::with_capacity(n * n);
            for t in 0..n {
                for p in 0..n {
                    let wo = cell_direction(t, p, n);
                    let v = bsdf.eval(wi, wo).luminance();
                    if !v.is_finite() {
                        return Err(FreqError::Parameter(format!(
                            "BRDF bandwidth of {}: f = {v} at ωi = {wi:?}, ωo = {wo:?}",
                            bsdf.name()
                        )));
                    }
                    slice.push(v);
                }
            }
            let mut b = local_bandwidth(&slice, n, n, Edges::WrapX)?;
            for t in 0..n {
                let theta = (t as f64 + 0.5) / n as f64 * FRAC_PI_2;
                let per_radian = (n as f64 / (2.0 * PI * theta.sin())).max(n as f64 / FRAC_PI_2);
                for v in &mut b[t * n..(t + 1) * n] {
                    *v *= per_radian;
                }
            }
            let f = n / o.out;
            let mut out = vec![0.0f64; o.out * o.out];
            for t in 0..n {
                for p in 0..n {
                    let c = (t / f) * o.out + p / f;
                    out[c] = out[c].max(b[t * n + p]);
                }
            }
            Ok(out)
        })
        .collect::<Result<_>>()?;
    Ok(BrdfBandwidth {
        options,
        data: blocks.concat(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_brdf::models::kurt::{Kurt, KurtLobe};
    use lustre_brdf::Rgb;

    fn kurt(m: f64) -> Kurt {
        Kurt::new(
            Rgb::ZERO,
            vec![KurtLobe::new(Rgb::ONE, m, m, 1.0, 0.0).expect("lobe")],
            vec![],
        )
        .expect("kurt")
    }

    #[test]
    fn a_lambertian_brdf_has_no_bandwidth_and_narrow_lobes_have_more() {
        let lambert = Kurt::new(Rgb::splat(0.5), vec![], vec![]).expect("lambert");
        let o = BrdfBandwidthOptions {
            incident: 4,
            ..Default::default()
        };
        let b = brdf_bandwidth(&lambert, o).expect("bandwidth");
        assert!(b.data.iter().all(|&v| v == 0.0));
        // At the mirror direction of θi = 33.75°, a lobe 4× narrower has more bandwidth.
        let wi = cell_direction(1, 0, 4);
        let mirror = DVec3::new(-wi.x, -wi.y, wi.z);
        let narrow = brdf_bandwidth(&kurt(0.05), o)
            .expect("narrow")
            .at(wi, mirror);
        let wide = brdf_bandwidth(&kurt(0.2), o).expect("wide").at(wi, mirror);
        assert!(narrow >= 2.0 * wide && wide > 0.0, "{narrow} vs {wide}");
    }

    #[test]
    fn bad_grids_are_refused() {
        for o in [
            BrdfBandwidthOptions {
                incident: 0,
                ..Default::default()
            },
            BrdfBandwidthOptions {
                slice: 48,
                ..Default::default()
            },
            BrdfBandwidthOptions {
                out: 5,
                ..Default::default()
            },
        ] {
            let e = brdf_bandwidth(&kurt(0.1), o).expect_err("refused");
            assert!(e.to_string().contains("BRDF bandwidth"), "{e}");
        }
    }
}
