//! The fixed direction set of the fit and the data sampled on it (000 §3.4.1, Eq. 3.7).
//!
//! For every incident direction ωi of a small set (θi = 5°, 15°, …, 75°; φi = 0° for isotropic
//! data, φi ∈ {0°, 45°, 90°} for anisotropic data) the outgoing directions are a regular
//! (θo, φo) grid (4.5° × 8°, cell centres) plus a dense polar patch of radius 9° around the mirror
//! direction (a 0.05° cap, then 30 rings growing geometrically to 9°, × 22.5° sectors) that
//! replaces the grid cells inside it, so that sharp specular peaks are integrated: a lobe too
//! narrow for the metric to see would otherwise cost nothing and could take any ks. Each outgoing sample carries the solid angle of its cell as
//! the weight w(ωo) of Eq. 3.7: for the regular grid that is sin θo·Δθ·Δφ, the thesis' sin θo
//! correction. Transmission pairs use the same outgoing set mirrored through the surface plane.
//!
//! Only pairs where the data is non-zero in some channel are kept: Eq. 3.7 sums over M, "the
//! set of all non-zero scattering measurements".
//!
//! Per pair the lobe geometry is stored in the reflection frame (for transmission pairs with ωo
//! mirrored, 000 Eq. 3.5), reduced to what a candidate lobe needs: the transfer probability of a
//! lobe with unit ks is
//!
//! g = F(u) · exp(ln_base − tx/mx² − ty/my² − ln(π mx my) − α ln(cos θi cos θo))
//!
//! with u = ωo·h, tx = (hx/hz)², ty = (hy/hz)² and ln_base = ln(cos θo / (4 u hz⁴)), which is
//! `lobe_eval` of `models::kurt` (Eq. 3.3–3.5) times cos θo (Eq. 2.4), with one `exp` per pair.

use crate::{FitError, Result};
use glam::DVec3;
use lustre_brdf::frame::{half_vector, mirror_z, spherical};
use lustre_brdf::models::kurt::{schlick, KurtLobe, LobeKind};
use lustre_brdf::Bsdf;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Regular grid step in θo (degrees).
const GRID_DTHETA_DEG: f64 = 4.5;
/// Regular grid step in φo (degrees).
const GRID_DPHI_DEG: f64 = 8.0;
/// Radius of the dense patch around the mirror direction (degrees).
const PATCH_RADIUS_DEG: f64 = 9.0;
/// Radius of the central cap of the patch (degrees).
const PATCH_INNER_DEG: f64 = 0.05;
/// Rings of the patch between the cap and the radius (geometric spacing, ×1.19 per ring).
const PATCH_RINGS: usize = 30;
/// Sectors of the patch.
const PATCH_SECTORS: usize = 16;
/// Incident polar angles (degrees).
const THETA_I_DEG: [f64; 8] = [5.0, 15.0, 25.0, 35.0, 45.0, 55.0, 65.0, 75.0];
/// Incident azimuths for anisotropic data (degrees).
const PHI_I_ANISO_DEG: [f64; 3] = [0.0, 45.0, 90.0];

/// The pairs of one hemisphere (reflection or transmission), as plain arrays.
#[derive(Clone, Debug, Default)]
pub(crate) struct PairSet {
    /// a = w(ωo)·|cos θi| / Σ w(ωo) (Eq. 3.7; the sum runs over both hemispheres' pairs).
    pub weight: Vec<f64>,
    /// cos θo in the reflection frame (> 0).
    pub cos_o: Vec<f64>,
    /// ln(cos θo / (4 u hz⁴)).
    pub ln_base: Vec<f64>,
    /// (hx/hz)².
    pub tx: Vec<f64>,
    /// (hy/hz)².
    pub ty: Vec<f64>,
    /// ln(cos θi cos θo).
    pub ln_cc: Vec<f64>,
    /// (1 − u)⁵, so that Schlick's F = r0 + (1 − r0)·s5.
    pub s5: Vec<f64>,
    /// Measured transfer probability p = f·|cos θo| per channel.
    pub data: [Vec<f64>; 3],
    /// Whether a sample lies on the regular grid (the kd histogram uses only those).
    pub regular: Vec<bool>,
    /// The incident direction (upper hemisphere).
    pub wi: Vec<DVec3>,
    /// The outgoing direction in the reflection frame (upper hemisphere).
    pub wo: Vec<DVec3>,
}

impl PairSet {
    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.weight.len()
    }

    /// Every `k`-th pair (k ≥ 1) with its weight times `k`, so that sums over the subset
    /// estimate the sums over the whole set (the grid and the mirror patch are thinned alike:
    /// pairs are stored per incident direction, grid rows then patch rings).
    pub fn every(&self, k: usize) -> PairSet {
        let k = k.max(1);
        fn pick<T: Clone>(v: &[T], k: usize) -> Vec<T> {
            v.iter().step_by(k).cloned().collect()
        }
        PairSet {
            weight: self
                .weight
                .iter()
                .step_by(k)
                .map(|w| w * k as f64)
                .collect(),
            cos_o: pick(&self.cos_o, k),
            ln_base: pick(&self.ln_base, k),
            tx: pick(&self.tx, k),
            ty: pick(&self.ty, k),
            ln_cc: pick(&self.ln_cc, k),
            s5: pick(&self.s5, k),
            data: std::array::from_fn(|c| pick(&self.data[c], k)),
            regular: pick(&self.regular, k),
            wi: pick(&self.wi, k),
            wo: pick(&self.wo, k),
        }
    }

    /// Fills `out[t]` with the transfer probability of `lobe` with unit ks at every pair.
    pub fn fill_lobe(&self, lobe: &KurtLobe, kind: LobeKind, out: &mut [f64]) {
        let c = LobeConst::new(lobe, kind);
        for (t, o) in out.iter_mut().enumerate() {
            *o = c.eval(self, t);
        }
    }
}

/// The per-candidate constants of the lobe formula above.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LobeConst {
    ix2: f64,
    iy2: f64,
    imx: f64,
    imy: f64,
    alpha: f64,
    ln_norm: f64,
    r0: f64,
    transmission: bool,
}

impl LobeConst {
    /// Constants of a lobe's shape (its ks is ignored).
    pub fn new(lobe: &KurtLobe, kind: LobeKind) -> Self {
        LobeConst {
            ix2: 1.0 / (lobe.mx * lobe.mx),
            iy2: 1.0 / (lobe.my * lobe.my),
            imx: 1.0 / lobe.mx,
            imy: 1.0 / lobe.my,
            alpha: lobe.alpha,
            ln_norm: (PI * lobe.mx * lobe.my).ln(),
            r0: lobe.r0,
            transmission: kind == LobeKind::Transmission,
        }
    }

    /// The transfer probability of the lobe with unit ks at pair `t`.
    #[inline]
    pub fn eval(&self, s: &PairSet, t: usize) -> f64 {
        let e = s.ln_base[t]
            - s.tx[t] * self.ix2
            - s.ty[t] * self.iy2
            - self.ln_norm
            - self.alpha * s.ln_cc[t];
        let f = self.r0 + (1.0 - self.r0) * s.s5[t];
        let fres = if self.transmission { 1.0 - f } else { f };
        fres * e.exp()
    }

    /// [`Self::eval`] and its derivatives with respect to (mx, my, r0, α):
    /// ∂g/∂mx = g (2 tx/mx² − 1)/mx, ∂g/∂my likewise, ∂g/∂r0 = ±(1 − s5)·exp(…), ∂g/∂α =
    /// −ln(cos θi cos θo)·g.
    #[inline]
    pub fn eval_grad(&self, s: &PairSet, t: usize) -> (f64, [f64; 4]) {
        let ex = (s.ln_base[t]
            - s.tx[t] * self.ix2
            - s.ty[t] * self.iy2
            - self.ln_norm
            - self.alpha * s.ln_cc[t])
            .exp();
        let f = self.r0 + (1.0 - self.r0) * s.s5[t];
        let (fres, dfres) = if self.transmission {
            (1.0 - f, s.s5[t] - 1.0)
        } else {
            (f, 1.0 - s.s5[t])
        };
        let g = fres * ex;
        (
            g,
            [
                g * (2.0 * s.tx[t] * self.ix2 - 1.0) * self.imx,
                g * (2.0 * s.ty[t] * self.iy2 - 1.0) * self.imy,
                dfres * ex,
                -s.ln_cc[t] * g,
            ],
        )
    }
}

/// Both hemispheres of the direction set with the data sampled on them.
#[derive(Clone, Debug)]
pub(crate) struct Samples {
    /// Reflection pairs (ωo above the surface).
    pub refl: PairSet,
    /// Transmission pairs (ωo below; stored mirrored). Empty unless transmission is fitted.
    pub trans: PairSet,
}

impl Samples {
    /// Both hemispheres thinned by [`PairSet::every`].
    pub fn every(&self, k: usize) -> Samples {
        Samples {
            refl: self.refl.every(k),
            trans: self.trans.every(k),
        }
    }
}

/// Incident directions of the set.
fn incident_directions(anisotropic: bool) -> Vec<DVec3> {
    let phis: &[f64] = if anisotropic {
        &PHI_I_ANISO_DEG
    } else {
        &[0.0]
    };
    let mut v = Vec::new();
    for &t in &THETA_I_DEG {
        for &p in phis {
            v.push(spherical(t.to_radians(), p.to_radians()));
        }
    }
    v
}

/// Outgoing directions (reflection frame) with their solid angles and a regular-grid flag.
fn outgoing_directions(wi: DVec3) -> Vec<(DVec3, f64, bool)> {
    let r = DVec3::new(-wi.x, -wi.y, wi.z);
    let radius = PATCH_RADIUS_DEG.to_radians();
    let cos_radius = radius.cos();
    let mut v = Vec::new();
    let dt = GRID_DTHETA_DEG.to_radians();
    let dp = GRID_DPHI_DEG.to_radians();
    let nt = (90.0 / GRID_DTHETA_DEG).round() as usize;
    let np = (360.0 / GRID_DPHI_DEG).round() as usize;
    for k in 0..nt {
        let th = (k as f64 + 0.5) * dt;
        for j in 0..np {
            let wo = spherical(th, (j as f64 + 0.5) * dp);
            if wo.dot(r) <= cos_radius {
                v.push((wo, th.sin() * dt * dp, true));
            }
        }
    }
    // The patch: a polar grid about r, rings geometrically spaced from PATCH_INNER_DEG to the
    // radius so that lobes far sharper than the grid are still integrated, plus a central cap.
    let e1 = if r.z.abs() < 0.999 {
        DVec3::Z.cross(r).normalize()
    } else {
        DVec3::X
    };
    let e2 = r.cross(e1);
    let inner = PATCH_INNER_DEG.to_radians();
    let bound = |k: usize| inner * (radius / inner).powf(k as f64 / PATCH_RINGS as f64);
    v.push((r, 2.0 * PI * (1.0 - inner.cos()), false));
    let da = 2.0 * PI / PATCH_SECTORS as f64;
    for k in 0..PATCH_RINGS {
        let (b0, b1) = (bound(k), bound(k + 1));
        let psi = 0.5 * (b0 + b1);
        let w = (b0.cos() - b1.cos()) * da;
        for j in 0..PATCH_SECTORS {
            let a = (j as f64 + 0.5) * da;
            let wo = (psi.cos() * r + psi.sin() * (a.cos() * e1 + a.sin() * e2)).normalize();
            if wo.z > 1e-6 {
                v.push((wo, w, false));
            }
        }
    }
    v
}

/// One candidate pair before filtering.
struct RawPair {
    wi: DVec3,
    wo: DVec3,
    w: f64,
    regular: bool,
    p: [f64; 3],
}

/// Samples `data` on the direction set. Errors when a sampled value is not finite or when
/// every sampled value is zero.
#[cfg(test)]
pub(crate) fn sample(data: &dyn Bsdf, transmission: bool) -> Result<Samples> {
    sample_masked(data, transmission, None)
}

/// [`sample`] keeping only the pairs `mask` covers (a MERL table's measured bins).
pub(crate) fn sample_masked(
    data: &dyn Bsdf,
    transmission: bool,
    mask: Option<&lustre_brdf::measured::merl::MerlCoverage>,
) -> Result<Samples> {
    let anisotropic = data.flags().anisotropic;
    let dirs = incident_directions(anisotropic);
    let mut pairs: Vec<(DVec3, DVec3, f64, bool)> = Vec::new();
    for &wi in &dirs {
        for (wo, w, regular) in outgoing_directions(wi) {
            pairs.push((wi, wo, w, regular));
        }
    }
    let hemis: &[bool] = if transmission {
        &[false, true]
    } else {
        &[false]
    };
    let mut raw: Vec<Vec<RawPair>> = Vec::new();
    let mut bad = 0usize;
    let mut total_w = 0.0;
    for &trans in hemis {
        let vals: Vec<RawPair> = pairs
            .par_iter()
            .map(|&(wi, wo, w, regular)| {
                let wo_actual = if trans { mirror_z(wo) } else { wo };
                let f = data.eval(wi, wo_actual);
                let c = wo_actual.z.abs();
                RawPair {
                    wi,
                    wo,
                    w,
                    regular,
                    p: [f[0] * c, f[1] * c, f[2] * c],
                }
            })
            .collect();
        bad += vals
            .iter()
            .filter(|r| r.p.iter().any(|v| !v.is_finite()))
            .count();
        let kept: Vec<RawPair> = vals
            .into_iter()
            .filter(|r| r.p.iter().any(|&v| v != 0.0))
            .filter(|r| {
                let wo = if trans { mirror_z(r.wo) } else { r.wo };
                mask.is_none_or(|m| m.covers(r.wi, wo))
            })
            .collect();
        total_w += kept.iter().map(|r| r.w).sum::<f64>();
        raw.push(kept);
    }
    let n_all = pairs.len() * hemis.len();
    if bad > 0 {
        return Err(FitError::Data {
            input: data.name(),
            problem: format!("{bad} of {n_all} sampled BSDF values are NaN or infinite"),
        });
    }
    if raw.iter().all(Vec::is_empty) || total_w <= 0.0 {
        return Err(FitError::Data {
            input: data.name(),
            problem: format!("all {n_all} sampled BSDF values are zero: nothing to fit"),
        });
    }
    let mut sets = raw.into_iter().map(|r| build_set(r, total_w));
    let refl = sets.next().unwrap_or_default();
    let trans = sets.next().unwrap_or_default();
    Ok(Samples { refl, trans })
}

/// Converts the kept pairs of one hemisphere into a [`PairSet`].
fn build_set(raw: Vec<RawPair>, total_w: f64) -> PairSet {
    let mut s = PairSet::default();
    for r in raw {
        // Upper-hemisphere pairs: the half vector exists and u, hz > 0.
        let Some(h) = half_vector(r.wi, r.wo) else {
            continue;
        };
        let u = r.wo.dot(h).max(1e-300);
        let hz = h.z.max(1e-300);
        s.weight.push(r.w * r.wi.z.abs() / total_w);
        s.cos_o.push(r.wo.z);
        s.ln_base.push(r.wo.z.ln() - (4.0 * u).ln() - 4.0 * hz.ln());
        s.tx.push((h.x / hz).powi(2));
        s.ty.push((h.y / hz).powi(2));
        s.ln_cc.push((r.wi.z * r.wo.z).ln());
        // Schlick's F = r0 + (1 − r0)·s5: s5 from models::kurt::schlick with r0 = 0.
        s.s5.push(schlick(0.0, u));
        for c in 0..3 {
            s.data[c].push(r.p[c]);
        }
        s.regular.push(r.regular);
        s.wi.push(r.wi);
        s.wo.push(r.wo);
    }
    s
}

/// The nodes of Ngan's quadrature `q` (`isotropic`: φh integrated out) that `mask` covers, as
/// a reflection [`PairSet`] whose Σ a·(data − p)² is Ngan's integral
/// ∫∫ (f_data − f_model)² cos θi cos θo dωi dωo: data p = f·cos θo and a = w / cos²θo with w
/// the node's weight. Zero data values count (it is an L2 of f, not of the measured pairs).
/// Errors when a value is not finite.
pub(crate) fn ngan_set(
    data: &dyn Bsdf,
    q: &crate::metrics::NganQuadrature,
    isotropic: bool,
    mask: Option<&lustre_brdf::measured::merl::MerlCoverage>,
) -> Result<Samples> {
    let raw: Vec<RawPair> = q
        .pairs(isotropic)
        .into_par_iter()
        .flat_map_iter(|row| {
            row.into_iter()
                .filter(|p| mask.is_none_or(|m| m.covers(p.wi, p.wo)))
                .map(|p| {
                    let f = data.eval(p.wi, p.wo);
                    let c = p.wo.z;
                    RawPair {
                        wi: p.wi,
                        wo: p.wo,
                        // build_set multiplies by cos θi.
                        w: p.w / (c * c * p.wi.z),
                        regular: false,
                        p: [f[0] * c, f[1] * c, f[2] * c],
                    }
                })
        })
        .collect();
    let bad = raw
        .iter()
        .filter(|r| r.p.iter().any(|v| !v.is_finite()))
        .count();
    if bad > 0 {
        return Err(FitError::Data {
            input: data.name(),
            problem: format!(
                "{bad} of {} BSDF values on Ngan's quadrature are NaN or infinite",
                raw.len()
            ),
        });
    }
    Ok(Samples {
        refl: build_set(raw, 1.0),
        trans: PairSet::default(),
    })
}

/// kd from the histogram of measured BRDF values (000 §3.4.1): kd/π is the most common value of
/// f = p / cos θo over the reflection hemisphere. The histogram has logarithmic bins 5 % wide,
/// each sample counted with its solid angle (on the regular grid only, so the dense specular
/// patch does not bias the count); kd/π is the median of the values in the fullest bin.
pub(crate) fn estimate_kd(s: &PairSet) -> [f64; 3] {
    let mut kd = [0.0; 3];
    for (c, out) in kd.iter_mut().enumerate() {
        let vals: Vec<(f64, f64)> = (0..s.len())
            .filter(|&t| s.regular[t])
            .map(|t| (s.data[c][t] / s.cos_o[t], s.weight[t] / s.wi[t].z.abs()))
            .filter(|&(f, _)| f > 0.0 && f.is_finite())
            .collect();
        let Some(fmax) = vals.iter().map(|v| v.0).reduce(f64::max) else {
            continue;
        };
        let fmin = (fmax * 1e-9).max(vals.iter().map(|v| v.0).fold(fmax, f64::min));
        let bin_w = 1.05f64.ln();
        let nbins = (((fmax / fmin).ln() / bin_w).floor() as usize + 1).min(100_000);
        let bin = |f: f64| (((f.max(fmin) / fmin).ln() / bin_w) as usize).min(nbins - 1);
        let mut hist = vec![0.0; nbins];
        for &(f, w) in &vals {
            hist[bin(f)] += w;
        }
        let best = hist
            .iter()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |acc, (i, &h)| {
                    if h > acc.1 {
                        (i, h)
                    } else {
                        acc
                    }
                },
            )
            .0;
        let mut inside: Vec<f64> = vals
            .iter()
            .map(|v| v.0)
            .filter(|&f| bin(f) == best)
            .collect();
        inside.sort_by(f64::total_cmp);
        if let Some(m) = inside.get(inside.len() / 2) {
            *out = PI * m;
        }
    }
    kd
}
