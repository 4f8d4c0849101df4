//! Fitting models that are linear in their colour: f = c·A + B per channel for fixed other
//! parameters (the glTF metallic-roughness model in its base colour, Mitsuba's rough conductor
//! in its specular reflectance, its rough plastic in its diffuse reflectance).
//!
//! For fixed other parameters, A and B come from the model itself (its values with colour 1 and
//! colour 0), and the colour that minimizes Ngan's L2 (004 §V.5.3: ∫∫ (f − data)² cos θi cos θo)
//! is the weighted least-squares c = Σ w A (d − B) / Σ w A², clamped to [0, 1] (the error is a
//! parabola in c, so the clamped value is the constrained minimum), with the weights of
//! [`NganQuadrature`]. The objective is the reported metric: the mean over the channels of
//! √(∫∫ (f − d)²) / A_max. The other parameters are searched by the callers ([`golden`]).

use crate::data::MeasuredData;
use crate::metrics::{max_albedo, NganQuadrature, WeightedPair};
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::Result;
use rayon::prelude::*;

/// The data side of the fit: every quadrature pair the data covers, with its values.
pub struct Rows {
    pairs: Vec<(WeightedPair, [f64; 3])>,
    /// The data's maximum albedo per channel (the metric's normalization).
    pub amax: [f64; 3],
}

/// The least-squares sums of one (metallic, roughness): Σ w A², Σ w A (d − B), Σ w (d − B)².
#[derive(Clone, Copy, Default)]
pub struct Sums {
    aa: f64,
    ab: [f64; 3],
    bb: [f64; 3],
}

impl std::ops::Add for Sums {
    type Output = Sums;
    fn add(self, o: Sums) -> Sums {
        Sums {
            aa: self.aa + o.aa,
            ab: std::array::from_fn(|c| self.ab[c] + o.ab[c]),
            bb: std::array::from_fn(|c| self.bb[c] + o.bb[c]),
        }
    }
}

impl Sums {
    /// The best base colour per channel and the objective (mean of √error / A_max).
    pub fn solve(&self, amax: &[f64; 3]) -> ([f64; 3], f64) {
        let top = amax.iter().cloned().fold(0.0, f64::max).max(1e-300);
        let mut colour = [0.0; 3];
        let mut objective = 0.0;
        for c in 0..3 {
            let x = if self.aa > 0.0 {
                (self.ab[c] / self.aa).clamp(0.0, 1.0)
            } else {
                0.0
            };
            colour[c] = x;
            let err = (x * x * self.aa - 2.0 * x * self.ab[c] + self.bb[c]).max(0.0);
            let norm = if amax[c] > 0.0 { amax[c] } else { top };
            objective += err.sqrt() / norm / 3.0;
        }
        (colour, objective)
    }
}

impl Rows {
    /// Evaluates the data on the Ngan quadrature's pairs it covers.
    pub fn new(data: &MeasuredData) -> Self {
        let iso = !data.bsdf.flags().anisotropic;
        let pairs = NganQuadrature::default()
            .pairs(iso)
            .into_par_iter()
            .flat_map_iter(|row| {
                row.into_iter()
                    .filter(|p| data.covers(p.wi, p.wo))
                    .map(|p| (p, data.bsdf.eval(p.wi, p.wo).0))
                    .collect::<Vec<_>>()
            })
            .collect();
        Rows {
            pairs,
            amax: max_albedo(data.bsdf.as_ref(), data.transmission),
        }
    }

    /// The sums of the model whose values are `black` (colour 0) and `white` (colour 1).
    pub fn sums(&self, black: &dyn Bsdf, white: &dyn Bsdf) -> Sums {
        self.pairs
            .par_chunks(4096)
            .map(|chunk| {
                let mut s = Sums::default();
                for (p, d) in chunk {
                    // A and B are the same in every channel (the colour is the only
                    // per-channel parameter): channel 0 gives them.
                    let b = black.eval(p.wi, p.wo).0[0];
                    let a = white.eval(p.wi, p.wo).0[0] - b;
                    s.aa += p.w * a * a;
                    for ((ab, bb), dc) in s.ab.iter_mut().zip(&mut s.bb).zip(d) {
                        let e = dc - b;
                        *ab += p.w * a * e;
                        *bb += p.w * e * e;
                    }
                }
                s
            })
            // Summed in chunk order: the same bits whatever the thread count.
            .collect::<Vec<_>>()
            .into_iter()
            .fold(Sums::default(), |x, y| x + y)
    }
}

/// Golden-section minimum of `f` on [lo, hi] (30 steps: the bracket shrinks 1e-6 times).
pub fn golden(lo: f64, hi: f64, f: impl Fn(f64) -> Result<f64>) -> Result<(f64, f64)> {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (lo, hi);
    let mut x1 = b - g * (b - a);
    let mut x2 = a + g * (b - a);
    let (mut f1, mut f2) = (f(x1)?, f(x2)?);
    for _ in 0..30 {
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = f(x1)?;
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = f(x2)?;
        }
    }
    Ok(if f1 <= f2 { (x1, f1) } else { (x2, f2) })
}
