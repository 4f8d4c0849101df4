//! Side tables of the measured BRDFs the GPU evaluates and samples (`wgsl/measured.wgsl`, read
//! through a pass's `bsdf_table`): a MERL table's stored values, a neural BRDF's weights, and
//! the tabulated CDFs of [`lustre_brdf::tabulated::TabulatedSampler`].

use lustre_brdf::measured::merl::{MerlTable, BINS, RES_PHI_D, RES_THETA_D, RES_THETA_H};
use lustre_brdf::measured::nbrdf::Nbrdf;
use lustre_brdf::tabulated::TabulatedSampler;
use lustre_brdf::Bsdf;

/// A measured BRDF the GPU evaluates directly (`measured_eval` of `wgsl/measured.wgsl`).
#[derive(Clone, Copy, Debug)]
pub enum MeasuredBrdf<'a> {
    /// A neural BRDF (kind 0).
    Nbrdf(&'a Nbrdf),
    /// A MERL table (kind 1).
    Merl(&'a MerlTable),
}

impl<'a> MeasuredBrdf<'a> {
    /// The measured BRDF behind `b`, or `None` for any other model.
    pub fn of(b: &'a dyn Bsdf) -> Option<Self> {
        let any = b.as_any()?;
        if let Some(n) = any.downcast_ref::<Nbrdf>() {
            return Some(Self::Nbrdf(n));
        }
        any.downcast_ref::<MerlTable>().map(Self::Merl)
    }

    /// Appends its words to `table`; returns `measured_eval`'s (kind, first word, node offset).
    pub fn pack(&self, table: &mut Vec<f32>) -> (u32, u32, f32) {
        let base = table.len() as u32;
        match self {
            Self::Nbrdf(n) => {
                table.extend(pack_nbrdf(n));
                (0, base, 0.0)
            }
            Self::Merl(m) => {
                table.extend(pack_merl(m));
                (1, base, m.convention().offset() as f32)
            }
        }
    }
}

/// The words of a MERL table for `merl_lookup`: its 3 × 90·90·180 stored values (unscaled,
/// channel-major, bin (i, j, k) at `k + 180·(j + 90·i)`), a missing bin as −1.
pub fn pack_merl(table: &MerlTable) -> Vec<f32> {
    let mut out = Vec::with_capacity(3 * BINS);
    for c in 0..3 {
        for i in 0..RES_THETA_H {
            for j in 0..RES_THETA_D {
                for k in 0..RES_PHI_D {
                    out.push(if table.is_missing(c, i, j, k) {
                        -1.0
                    } else {
                        table.stored(c, i, j, k) as f32
                    });
                }
            }
        }
    }
    out
}

/// The words of a neural BRDF for `nbrdf_eval`: its 6-21-21-3 network's parameters in
/// [`Nbrdf::parameters`]' order (w1, b1, w2, b2, w3, b3), 675 of them.
pub fn pack_nbrdf(net: &Nbrdf) -> Vec<f32> {
    net.parameters().iter().map(|&v| v as f32).collect()
}

/// `TabulatedDims` of `measured.wgsl`: the sampler's bins and defensive fraction.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTabulatedDims {
    /// View bins.
    pub view_bins: u32,
    /// θi cells.
    pub theta_bins: u32,
    /// φ cells.
    pub phi_bins: u32,
    /// The cosine-sampled fraction ε.
    pub defensive: f32,
}

/// The words of a tabulated sampler for `tabulated_sample` / `tabulated_pdf`, and its layout:
/// per view bin, the `cells + 1` cumulative weights over the table's total (0 … 1; all 0 for a
/// black table), then the `cells` weights over the total (computed in f64, so a cell's density
/// does not come from the difference of two f32 sums).
pub fn pack_tabulated(sampler: &TabulatedSampler) -> (Vec<f32>, GpuTabulatedDims) {
    let o = sampler.options();
    let cells = o.theta_bins * o.phi_bins;
    let cdf = sampler.cumulative();
    let mut out = Vec::with_capacity(o.view_bins * (2 * cells + 1));
    for table in cdf.chunks_exact(cells + 1) {
        let total = table[cells];
        let norm = if total > 0.0 { 1.0 / total } else { 0.0 };
        out.extend(table.iter().map(|&v| (v * norm) as f32));
        out.extend(table.windows(2).map(|w| ((w[1] - w[0]) * norm) as f32));
    }
    let dims = GpuTabulatedDims {
        view_bins: o.view_bins as u32,
        theta_bins: o.theta_bins as u32,
        phi_bins: o.phi_bins as u32,
        defensive: o.defensive as f32,
    };
    (out, dims)
}
