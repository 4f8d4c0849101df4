//! Cook-Torrance as the SGD fits use it (004 Eq. III.1, §V.3):
//!
//! ```text
//! f = ρd/π + (ρs/π) F(i·h) D(θh) G1(θi) G1(θo) / (cos θi cos θo)
//! ```
//!
//! per RGB channel, each channel with its own NDF, G1 model and Fresnel term (the published SGD
//! fits are per channel, 004 §V.4.1). With ρs = π/4, F = 1 and the Smith G1 of D this is the
//! physical microfacet BRDF D G/(4 cos θi cos θo).
//!
//! Sampling follows 004 §V.3.5: the specular lobe with probability p_spec = ρs/(ρd + ρs) (channel
//! means), else the cosine-weighted diffuse lobe. The specular lobe draws h from the channels'
//! h-samplers (for SGD the GGX proxy, see [`crate::microfacet::ndf`]), choosing the channel in
//! proportion to its ρs (identical channels share one sampler), and reflects `wo` about h. The pdf
//! is the full mixture, so the weight f·cos/pdf is the paper's
//! w_spec = 4ρs/p_spec F D G cos³θm (α²+tan²θm)²/α², times |o·m|/cos θi, a Jacobian factor the
//! paper's expression omits (test `weight_is_the_papers_up_to_the_jacobian`).

use crate::bsdf::{
    finish_sample, sample_diffuse_mixture, select_component, Bsdf, BsdfFlags, BsdfSample, LobeFlags,
};
use crate::error::{check_range, Error, Result};
use crate::frame::reflect;
use crate::microfacet::fresnel::Fresnel;
use crate::microfacet::ndf::Ndf;
use crate::microfacet::smith::{g1_beckmann, g1_ggx, G1Table, SgdG1Approx};
use crate::rgb::Rgb;
use crate::sampling::cosine_hemisphere_pdf;
use glam::DVec3;
use std::f64::consts::{FRAC_1_PI, FRAC_PI_4};

/// Which Smith G1 a channel uses.
#[derive(Clone, Debug, PartialEq)]
pub enum G1Model {
    /// G1 = 1 (no shadowing).
    None,
    /// The numeric Smith G1 of the channel's NDF (004 Eq. III.4), tabulated.
    Numeric(Box<G1Table>),
    /// 004 Eq. V.3 approximation (as in the published SGD fits).
    SgdApprox(SgdG1Approx),
    /// The closed form of Beckmann or GGX (only valid for those NDFs).
    Closed,
}

impl G1Model {
    /// The numeric Smith G1 table of `ndf`.
    pub fn numeric(ndf: &Ndf) -> G1Model {
        G1Model::Numeric(Box::new(G1Table::new(ndf)))
    }
}

/// One RGB channel of a [`CookTorrance`] model.
#[derive(Clone, Debug, PartialEq)]
pub struct CtChannel {
    /// Diffuse coefficient ρd (f contains ρd/π).
    pub rho_d: f64,
    /// Specular coefficient ρs (f contains ρs/π · F D G/(cos cos)).
    pub rho_s: f64,
    /// Microfacet distribution.
    pub ndf: Ndf,
    /// Shadowing model.
    pub g1: G1Model,
    /// Fresnel term.
    pub fresnel: Fresnel,
}

impl CtChannel {
    /// A channel; see [`CookTorrance::new`] for the checks.
    pub fn new(rho_d: f64, rho_s: f64, ndf: Ndf, g1: G1Model, fresnel: Fresnel) -> Self {
        CtChannel {
            rho_d,
            rho_s,
            ndf,
            g1,
            fresnel,
        }
    }

    #[inline]
    fn g1(&self, cos_t: f64, theta: f64) -> f64 {
        match self.g1 {
            G1Model::None => 1.0,
            G1Model::Numeric(ref t) => t.eval(cos_t),
            G1Model::SgdApprox(ref a) => a.eval(theta),
            G1Model::Closed => match self.ndf {
                Ndf::Beckmann { alpha } => g1_beckmann(alpha, cos_t),
                Ndf::Ggx { alpha } => g1_ggx(alpha, cos_t),
                _ => 1.0, // rejected by CookTorrance::new
            },
        }
    }

    /// f of this channel given the cosines (all > 0) and the angles (for Eq. V.3).
    #[inline]
    fn eval(&self, ci: f64, co: f64, ch: f64, cd: f64, ti: f64, to: f64) -> f64 {
        let spec = if self.rho_s != 0.0 {
            self.rho_s * self.fresnel.eval(cd) * self.ndf.d(ch) * self.g1(ci, ti) * self.g1(co, to)
                / (ci * co)
        } else {
            0.0
        };
        (self.rho_d + spec) * FRAC_1_PI
    }
}

/// Cook-Torrance with per-channel NDF, G1 and Fresnel (004 Eq. III.1).
#[derive(Clone, Debug)]
pub struct CookTorrance {
    name: String,
    ch: [CtChannel; 3],
    /// All three channels equal: evaluate once.
    gray: bool,
    /// Whether any channel needs θ (Eq. V.3).
    needs_theta: bool,
    p_spec: f64,
    /// Specular h-samplers with their selection weights.
    lobes: Vec<(Ndf, f64)>,
    lobe_weights: Vec<f64>,
    energy_conserving: bool,
}

impl CookTorrance {
    /// A model from three channels. ρd, ρs must be finite and ≥ 0; `G1Model::Closed` requires a
    /// Beckmann or GGX NDF.
    pub fn new(name: impl Into<String>, channels: [CtChannel; 3]) -> Result<Self> {
        for c in &channels {
            check_range("rho_d", c.rho_d, 0.0, f64::MAX)?;
            check_range("rho_s", c.rho_s, 0.0, f64::MAX)?;
            if c.g1 == G1Model::Closed && !matches!(c.ndf, Ndf::Beckmann { .. } | Ndf::Ggx { .. }) {
                let msg = format!("no closed-form Smith G1 for {}", c.ndf.name());
                return Err(Error::param("g1", f64::NAN, msg));
            }
        }
        let gray = channels[0] == channels[1] && channels[1] == channels[2];
        let needs_theta = channels
            .iter()
            .any(|c| matches!(c.g1, G1Model::SgdApprox(_)));
        let rd = channels.iter().map(|c| c.rho_d).sum::<f64>() / 3.0;
        let rs = channels.iter().map(|c| c.rho_s).sum::<f64>() / 3.0;
        let p_spec = if rd + rs > 0.0 { rs / (rd + rs) } else { 0.0 };
        let mut lobes: Vec<(Ndf, f64)> = Vec::new();
        for c in &channels {
            if let Some(l) = lobes.iter_mut().find(|l| l.0 == c.ndf) {
                l.1 += c.rho_s;
            } else {
                lobes.push((c.ndf, c.rho_s));
            }
        }
        let total: f64 = lobes.iter().map(|l| l.1).sum();
        if total > 0.0 {
            lobes.retain(|l| l.1 > 0.0);
            lobes.iter_mut().for_each(|l| l.1 /= total);
        } else {
            lobes.clear();
        }
        // Provable bound (module notes): with the exact Smith G1 of D, the specular albedo is at
        // most (4/π)ρs·max F, so ρd + (4/π)ρs max F ≤ 1 guarantees albedo ≤ 1.
        let energy_conserving = channels.iter().all(|c| {
            let exact_g1 = matches!(c.g1, G1Model::Numeric(_) | G1Model::Closed);
            let normalized = !matches!(c.ndf, Ndf::Sgd(s) if (s.kap() * s.alpha() * s.gamma0() - 1.0).abs() > 1e-9);
            (c.rho_s == 0.0 || (exact_g1 && normalized))
                && c.rho_d + 4.0 * FRAC_1_PI * c.rho_s * c.fresnel.max_value().max(0.0) <= 1.0
        });
        Ok(CookTorrance {
            name: name.into(),
            ch: channels,
            gray,
            needs_theta,
            p_spec,
            lobe_weights: lobes.iter().map(|l| l.1).collect(),
            lobes,
            energy_conserving,
        })
    }

    /// The same parameters in all three channels.
    pub fn gray(
        name: impl Into<String>,
        rho_d: f64,
        rho_s: f64,
        ndf: Ndf,
        g1: G1Model,
        fresnel: Fresnel,
    ) -> Result<Self> {
        let c = CtChannel::new(rho_d, rho_s, ndf, g1, fresnel);
        Self::new(name, [c.clone(), c.clone(), c])
    }

    /// The physical microfacet BRDF F D G/(4 cos θi cos θo) (ρs = π/4, ρd = 0) with the numeric
    /// (or closed-form) Smith G1 of `ndf`.
    pub fn microfacet(name: impl Into<String>, ndf: Ndf, fresnel: Fresnel) -> Result<Self> {
        let g1 = match ndf {
            Ndf::Beckmann { .. } | Ndf::Ggx { .. } => G1Model::Closed,
            _ => G1Model::numeric(&ndf),
        };
        Self::gray(name, 0.0, FRAC_PI_4, ndf, g1, fresnel)
    }

    /// The three channels.
    pub fn channels(&self) -> &[CtChannel; 3] {
        &self.ch
    }

    /// Probability of sampling the specular lobe.
    pub fn p_specular(&self) -> f64 {
        self.p_spec
    }
}

impl Bsdf for CookTorrance {
    fn name(&self) -> String {
        self.name.clone()
    }

    #[inline]
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let (ci, co) = (wi.z, wo.z);
        if !(ci > 0.0 && co > 0.0) {
            return Rgb::ZERO;
        }
        let hv = wi + wo;
        let inv = 1.0 / hv.length();
        let ch = hv.z * inv;
        let cd = wi.dot(hv) * inv;
        let (ti, to) = if self.needs_theta {
            (ci.min(1.0).acos(), co.min(1.0).acos())
        } else {
            (0.0, 0.0)
        };
        if self.gray {
            return Rgb::splat(self.ch[0].eval(ci, co, ch, cd, ti, to));
        }
        Rgb([
            self.ch[0].eval(ci, co, ch, cd, ti, to),
            self.ch[1].eval(ci, co, ch, cd, ti, to),
            self.ch[2].eval(ci, co, ch, cd, ti, to),
        ])
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if wo.z.is_nan() || wo.z <= 0.0 {
            return None;
        }
        let weights = [1.0 - self.p_spec, self.p_spec];
        let (wi, kind) = sample_diffuse_mixture(&weights, u1, u2, |_, u1, u2| {
            let (li, u1) = select_component(&self.lobe_weights, u1)?;
            let h = self.lobes[li].0.sample_h(u1, u2);
            Some(reflect(wo, h))
        })?;
        if wi.z.is_nan() || wi.z <= 0.0 || !wi.is_finite() {
            return None;
        }
        finish_sample(wi, wo, self.pdf(wi, wo), kind, || self.eval(wi, wo))
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        let mut p = (1.0 - self.p_spec) * cosine_hemisphere_pdf(wi);
        if self.p_spec > 0.0 {
            let hv = wi + wo;
            let h = hv / hv.length();
            let od = wo.dot(h);
            if od > 0.0 {
                let ph: f64 = self.lobes.iter().map(|(n, w)| w * n.pdf_h(h)).sum();
                p += self.p_spec * ph / (4.0 * od);
            }
        }
        p
    }

    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, self.energy_conserving)
            .with_lobes(LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION)
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;
    use crate::numeric::SphereQuadrature;
    use crate::validate::{
        albedo_quadrature, chi2_test, pdf_integral, reciprocity_error, sample_success_fraction,
        test_directions,
    };
    use std::f64::consts::PI;

    fn variants() -> Vec<CookTorrance> {
        let schlick = Fresnel::schlick(0.04).unwrap();
        vec![
            CookTorrance::gray(
                "ct-beckmann",
                0.3,
                0.2,
                Ndf::beckmann(0.2).unwrap(),
                G1Model::Closed,
                schlick,
            )
            .unwrap(),
            CookTorrance::gray(
                "ct-ggx",
                0.2,
                0.3,
                Ndf::ggx(0.1).unwrap(),
                G1Model::Closed,
                schlick,
            )
            .unwrap(),
            CookTorrance::gray(
                "ct-exponential",
                0.25,
                0.25,
                Ndf::exponential(0.15).unwrap(),
                G1Model::numeric(&Ndf::exponential(0.15).unwrap()),
                Fresnel::lazanyi(0.2, 3.4).unwrap(),
            )
            .unwrap(),
            {
                let n = Ndf::sgd(0.01, 0.6).unwrap();
                CookTorrance::gray("ct-sgd-numeric", 0.1, 0.5, n, G1Model::numeric(&n), schlick)
                    .unwrap()
            },
            // Per-channel SGD with the published approximation and Eq. V.5 (alum-bronze, r/g/b).
            CookTorrance::new(
                "ct-sgd-alum-bronze",
                [
                    CtChannel::new(
                        0.0478786,
                        0.0364976,
                        Ndf::sgd_with_kap(0.014832, 0.459076, 46.3841).unwrap(),
                        G1Model::SgdApprox(
                            SgdG1Approx::new(2.60672, 1.12717e-07, 47.783, 0.205635).unwrap(),
                        ),
                        Fresnel::generalized_schlick(6.05524, 5.05524).unwrap(),
                    ),
                    CtChannel::new(
                        0.0313514,
                        0.664975,
                        Ndf::sgd_with_kap(0.0300126, 0.450056, 24.5961).unwrap(),
                        G1Model::SgdApprox(
                            SgdG1Approx::new(2.97371, 1.06401e-07, 36.2767, 0.066289).unwrap(),
                        ),
                        Fresnel::generalized_schlick(0.235756, 0.182842).unwrap(),
                    ),
                    CtChannel::new(
                        0.0200638,
                        0.268836,
                        Ndf::sgd_with_kap(0.0490339, 0.529272, 14.8261).unwrap(),
                        G1Model::SgdApprox(
                            SgdG1Approx::new(2.7827, 5.27952e-08, 31.6066, -0.0661091).unwrap(),
                        ),
                        Fresnel::generalized_schlick(0.580647, 0.476088).unwrap(),
                    ),
                ],
            )
            .unwrap(),
        ]
    }

    fn q() -> SphereQuadrature {
        SphereQuadrature {
            phi_points: 96,
            uniform_panels: 32,
            theta_min: 1e-5,
            ..Default::default()
        }
    }

    #[test]
    fn pdf_integrates_to_success_fraction() {
        for m in variants() {
            for wo in test_directions() {
                let i = pdf_integral(&m, wo, &q());
                let f = sample_success_fraction(&m, wo, 100_000, 3);
                assert!(
                    (i - f).abs() < 1e-2,
                    "{} wo={wo}: ∫pdf {i} vs fraction {f}",
                    m.name()
                );
                assert!(i <= 1.0 + 1e-4, "{} wo={wo}: ∫pdf {i}", m.name());
            }
        }
    }

    #[test]
    fn chi_square_at_test_directions() {
        let dirs = test_directions();
        let models = variants();
        let n_tests = dirs.len() * models.len();
        for m in &models {
            for (k, &wo) in dirs.iter().enumerate() {
                let r = chi2_test(m, wo, 24, 200_000, 11 + k as u64);
                assert!(r.passed(0.01, n_tests), "{} wo={wo}: {r:?}", m.name());
            }
        }
    }

    #[test]
    fn reciprocal_and_energy() {
        for m in variants() {
            let e = reciprocity_error(&m, 2000, 5);
            assert!(e < 1e-12, "{}: {e}", m.name());
            if m.flags().energy_conserving {
                for wo in test_directions() {
                    let a = albedo_quadrature(&m, wo, &q());
                    assert!(
                        a.iter().all(|&v| v <= 1.0 + 1e-6),
                        "{} wo={wo}: {a:?}",
                        m.name()
                    );
                }
            }
        }
        // The first four promise energy conservation, the published SGD fit does not.
        let f: Vec<bool> = variants()
            .iter()
            .map(|m| m.flags().energy_conserving)
            .collect();
        assert_eq!(f, vec![true, true, true, true, false]);
    }

    #[test]
    fn physical_microfacet_is_white_furnace_bounded() {
        // ρs = π/4, F = 1, exact G1: albedo ≤ 1 and close to 1 near normal incidence for a smooth
        // surface (the missing part is multiple scattering).
        for ndf in [
            Ndf::ggx(0.05).unwrap(),
            Ndf::sgd(0.001, 0.8).unwrap(),
            Ndf::exponential(0.1).unwrap(),
        ] {
            let m = CookTorrance::microfacet("m", ndf, Fresnel::One).unwrap();
            assert!(m.flags().energy_conserving);
            for wo in test_directions() {
                let a = albedo_quadrature(&m, wo, &q())[0];
                assert!(a <= 1.0 + 1e-6, "{} {wo}: {a}", ndf.name());
                if wo.z > 0.8 {
                    assert!(a > 0.97, "{} {wo}: {a}", ndf.name());
                }
            }
        }
    }

    #[test]
    fn known_value_by_hand() {
        let ndf = Ndf::beckmann(0.3).unwrap();
        let m = CookTorrance::gray(
            "b",
            0.2,
            0.5,
            ndf,
            G1Model::Closed,
            Fresnel::schlick(0.05).unwrap(),
        )
        .unwrap();
        let wi = spherical(0.4, 0.0);
        let wo = spherical(0.7, 2.0);
        let h = (wi + wo).normalize();
        let th = h.z.acos();
        let d = (-(th.tan().powi(2)) / 0.09).exp() / (PI * 0.09 * h.z.powi(4));
        let f = 0.05 + 0.95 * (1.0 - wi.dot(h)).powi(5);
        let lam = |c: f64| {
            let a = c / (1.0 - c * c).sqrt() / 0.3;
            (puruspe::erf(a) - 1.0) / 2.0 + (-a * a).exp() / (2.0 * a * PI.sqrt())
        };
        let g = 1.0 / (1.0 + lam(wi.z)) / (1.0 + lam(wo.z));
        let want = 0.2 / PI + 0.5 / PI * f * d * g / (wi.z * wo.z);
        let got = m.eval(wi, wo);
        assert!((got[0] - want).abs() < 1e-12 * want, "{got:?} vs {want}");
        assert_eq!(m.eval(spherical(1.7, 0.0), wo), Rgb::ZERO);
        assert_eq!(m.eval(wi, -wo), Rgb::ZERO);
    }

    #[test]
    fn weight_is_the_papers_up_to_the_jacobian() {
        // Specular only (p_spec = 1), SGD sampled through its GGX proxy (004 §V.3.5).
        let ndf = Ndf::sgd(0.02, 0.7).unwrap();
        let Ndf::Sgd(s) = ndf else { unreachable!() };
        let fr = Fresnel::schlick(0.3).unwrap();
        let m = CookTorrance::gray("s", 0.0, 0.7, ndf, G1Model::numeric(&ndf), fr).unwrap();
        let g1 = G1Table::new(&ndf);
        let wo = spherical(0.6, 0.3);
        let mut n = 0;
        for k in 0..200 {
            let (u1, u2) = crate::sampling::hammersley(k, 200);
            let Some(smp) = m.sample(wo, u1, u2) else {
                continue;
            };
            n += 1;
            let h = (smp.wi + wo).normalize();
            let a = s.proxy_alpha();
            let t2 = (1.0 - h.z * h.z) / (h.z * h.z);
            let paper = 4.0
                * 0.7
                * fr.eval(smp.wi.dot(h))
                * ndf.d(h.z)
                * g1.eval(smp.wi.z)
                * g1.eval(wo.z)
                * h.z.powi(3)
                * (a * a + t2).powi(2)
                / (a * a);
            // Here the paper's i is our wo (the fixed direction), its o our sampled wi.
            let jac = smp.wi.dot(h) / wo.z;
            let w = smp.weight()[0];
            assert!(
                (w - paper * jac).abs() < 1e-9 * w.abs().max(1e-12),
                "{w} vs {}",
                paper * jac
            );
        }
        assert!(n > 150);
    }

    #[test]
    fn construction_is_validated() {
        let n = Ndf::sgd(0.1, 0.5).unwrap();
        assert!(CookTorrance::gray("x", 0.1, 0.1, n, G1Model::Closed, Fresnel::One).is_err());
        assert!(CookTorrance::gray("x", -0.1, 0.1, n, G1Model::None, Fresnel::One).is_err());
        assert!(CookTorrance::gray("x", 0.1, f64::NAN, n, G1Model::None, Fresnel::One).is_err());
        let z = CookTorrance::gray("x", 0.0, 0.0, n, G1Model::None, Fresnel::One).unwrap();
        assert!(z
            .sample(DVec3::Z, 0.3, 0.4)
            .is_none_or(|s| s.value == Rgb::ZERO));
        assert_eq!(z.eval(DVec3::Z, DVec3::Z), Rgb::ZERO);
    }

    mod prop {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(200))]
            #[test]
            fn finite_everywhere(
                a in 1e-5f64..1.0, p in 0.0f64..1.7, rd in 0.0f64..1.0, rs in 0.0f64..4.0,
                f0 in 0.0f64..8.0, f1 in -1.0f64..7.0, kind in 0usize..4,
                ti in 0.0f64..1.0, to in 0.0f64..1.0, pi in -3.2f64..3.2, po in -3.2f64..3.2,
                u1 in 0.0f64..1.0, u2 in 0.0f64..1.0,
            ) {
                // θ up to and slightly past grazing.
                let ti = ti * 1.58;
                let to = to * 1.58;
                let ndf = match kind {
                    0 => Ndf::beckmann(a).unwrap(),
                    1 => Ndf::ggx(a).unwrap(),
                    2 => Ndf::exponential(a).unwrap(),
                    _ => Ndf::sgd(a, p).unwrap(),
                };
                let g1 = match kind {
                    0 | 1 => G1Model::Closed,
                    _ => G1Model::SgdApprox(SgdG1Approx::from_lck(3.0, 1e-7, 40.0).unwrap()),
                };
                let m = CookTorrance::gray("p", rd, rs, ndf, g1,
                    Fresnel::generalized_schlick(f0, f1).unwrap()).unwrap();
                let wi = spherical(ti, pi);
                let wo = spherical(to, po);
                prop_assert!(m.eval(wi, wo).is_finite());
                prop_assert!(m.pdf(wi, wo).is_finite() && m.pdf(wi, wo) >= 0.0);
                if let Some(s) = m.sample(wo, u1, u2) {
                    prop_assert!(s.value.is_finite() && s.pdf.is_finite() && s.pdf > 0.0);
                    prop_assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-9);
                }
                // Exactly grazing.
                let g = DVec3::new(1.0, 0.0, 0.0);
                prop_assert!(m.eval(g, wo).is_finite() && m.eval(wo, g).is_finite());
                prop_assert!(m.sample(g, u1, u2).is_none());
            }
        }
    }

    /// Rough timing of one RGB eval of the per-channel SGD model (run with
    /// `cargo test --release -p lustre-brdf -- --ignored sgd_eval_timing --nocapture`).
    #[test]
    #[ignore]
    fn sgd_eval_timing() {
        let m = &variants()[4];
        let mut rng = crate::sampling::SplitMix64::new(1);
        let dirs: Vec<(DVec3, DVec3)> = (0..1024)
            .map(|_| {
                let a = crate::sampling::cosine_hemisphere(rng.next_f64(), rng.next_f64());
                let b = crate::sampling::cosine_hemisphere(rng.next_f64(), rng.next_f64());
                (a, b)
            })
            .collect();
        let reps = 2000;
        let start = std::time::Instant::now();
        let mut acc = 0.0;
        for _ in 0..reps {
            for &(a, b) in &dirs {
                acc += std::hint::black_box(m.eval(std::hint::black_box(a), b))[1];
            }
        }
        let ns = start.elapsed().as_secs_f64() * 1e9 / (reps * dirs.len()) as f64;
        // Load-independent yardstick: 12 exp + 12 ln per iteration (about what one RGB eval
        // needs: per channel D: 1 exp + 1 ln, two Eq. V.3 G1: 2 ln + 4 exp … minus sharing).
        let start = std::time::Instant::now();
        let mut b = 0.0;
        for _ in 0..reps {
            for &(a, _) in &dirs {
                let mut x = std::hint::black_box(a.z + 1.5);
                for _ in 0..12 {
                    x = x.ln().exp() + 1e-3;
                }
                b += x;
            }
        }
        let ns_ref = start.elapsed().as_secs_f64() * 1e9 / (reps * dirs.len()) as f64;
        println!("SGD Cook-Torrance RGB eval: {ns:.1} ns; 12 exp + 12 ln: {ns_ref:.1} ns (checksums {acc:.3} {b:.3})");
    }
}
