//! Fresnel terms of the microfacet models: Schlick (004 §III.4.4.4.2), the generalized Schlick of
//! the SGD fits (004 Eq. V.5) and Lazányi's metal approximation (004 §III.4.4.4.2).

use crate::error::{check_range, Result};

/// A Fresnel reflectance as a function of cos θ_d = i·h.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fresnel {
    /// F = 1 (no Fresnel effect).
    One,
    /// Schlick: F = F0 + (1 − F0)(1 − cos θ)⁵.
    Schlick {
        /// Reflectance at normal incidence.
        f0: f64,
    },
    /// 004 Eq. V.5: F = F0 + (1 − F0)(1 − cos θ)⁵ − F1 cos θ. The published fits store values of
    /// F0 above 1 and negative F1; they are taken as they are.
    GeneralizedSchlick {
        /// F0.
        f0: f64,
        /// F1, the slope of the linear term.
        f1: f64,
    },
    /// Lazányi & Szirmay-Kalos (2005): F = ((n−1)² + 4n(1−cos θ)⁵ + k²)/((n+1)² + k²).
    Lazanyi {
        /// Real part of the refractive index.
        n: f64,
        /// Extinction coefficient.
        k: f64,
    },
}

impl Fresnel {
    /// Schlick with a validated F0 (finite, ≥ 0).
    pub fn schlick(f0: f64) -> Result<Fresnel> {
        Ok(Fresnel::Schlick {
            f0: check_range("f0", f0, 0.0, f64::MAX)?,
        })
    }

    /// Eq. V.5 with finite F0, F1 (any sign, as in the published table).
    pub fn generalized_schlick(f0: f64, f1: f64) -> Result<Fresnel> {
        Ok(Fresnel::GeneralizedSchlick {
            f0: check_range("f0", f0, -f64::MAX, f64::MAX)?,
            f1: check_range("f1", f1, -f64::MAX, f64::MAX)?,
        })
    }

    /// Lazányi with n > 0 and k ≥ 0.
    pub fn lazanyi(n: f64, k: f64) -> Result<Fresnel> {
        Ok(Fresnel::Lazanyi {
            n: check_range("n", n, 1e-6, 1e6)?,
            k: check_range("k", k, 0.0, 1e6)?,
        })
    }

    /// F(cos θ_d); the argument is clamped to [0, 1].
    #[inline]
    pub fn eval(&self, cos_theta_d: f64) -> f64 {
        let c = if cos_theta_d > 0.0 {
            cos_theta_d.min(1.0)
        } else {
            0.0
        };
        let m = 1.0 - c;
        let m5 = (m * m) * (m * m) * m;
        match *self {
            Fresnel::One => 1.0,
            Fresnel::Schlick { f0 } => f0 + (1.0 - f0) * m5,
            Fresnel::GeneralizedSchlick { f0, f1 } => f0 + (1.0 - f0) * m5 - f1 * c,
            Fresnel::Lazanyi { n, k } => {
                let k2 = k * k;
                ((n - 1.0) * (n - 1.0) + 4.0 * n * m5 + k2) / ((n + 1.0) * (n + 1.0) + k2)
            }
        }
    }

    /// An upper bound of F over cos θ ∈ [0, 1] (exact for One, Schlick and Lazányi; for Eq. V.5
    /// the maximum over 4097 points plus the Lipschitz margin (|F1| + 5|1 − F0|)·h/2, so a
    /// guaranteed bound).
    pub fn max_value(&self) -> f64 {
        match *self {
            Fresnel::One => 1.0,
            Fresnel::Schlick { f0 } => f0.max(1.0),
            // The numerator is largest at cos θ = 0, where F = 1.
            Fresnel::Lazanyi { .. } => 1.0,
            Fresnel::GeneralizedSchlick { f0, f1 } => {
                let n = 4096;
                let h = 1.0 / n as f64;
                let m = (0..=n)
                    .map(|i| self.eval(i as f64 * h))
                    .fold(f64::MIN, f64::max);
                m + (f1.abs() + 5.0 * (1.0 - f0).abs()) * h * 0.5
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schlick_known_values() {
        let f = Fresnel::schlick(0.04).unwrap();
        assert_eq!(f.eval(1.0), 0.04);
        assert_eq!(f.eval(0.0), 1.0);
        // cos 60° = 0.5: 0.04 + 0.96/32.
        assert!((f.eval(0.5) - (0.04 + 0.96 / 32.0)).abs() < 1e-15);
        // Clamped arguments.
        assert_eq!(f.eval(-0.3), 1.0);
        assert_eq!(f.eval(1.7), 0.04);
        assert_eq!(Fresnel::One.eval(0.3), 1.0);
    }

    #[test]
    fn generalized_reduces_to_schlick() {
        let g = Fresnel::generalized_schlick(0.3, 0.0).unwrap();
        let s = Fresnel::schlick(0.3).unwrap();
        for i in 0..=20 {
            let c = i as f64 / 20.0;
            assert_eq!(g.eval(c), s.eval(c));
        }
        // With F1: F(1) = F0 − F1, F(0) = 1.
        let g = Fresnel::generalized_schlick(0.8, 0.2).unwrap();
        assert!((g.eval(1.0) - 0.6).abs() < 1e-15);
        assert_eq!(g.eval(0.0), 1.0);
        // Hand value at c = 0.3: 0.8 + 0.2·0.7⁵ − 0.06.
        assert!((g.eval(0.3) - (0.8 + 0.2 * 0.7f64.powi(5) - 0.06)).abs() < 1e-15);
    }

    #[test]
    fn lazanyi_with_k0_is_schlick() {
        for &n in &[1.2, 1.5, 2.4, 0.6] {
            let l = Fresnel::lazanyi(n, 0.0).unwrap();
            let f0 = ((n - 1.0) / (n + 1.0)).powi(2);
            let s = Fresnel::schlick(f0).unwrap();
            for i in 0..=20 {
                let c = i as f64 / 20.0;
                assert!((l.eval(c) - s.eval(c)).abs() < 1e-14, "n={n} c={c}");
            }
        }
        // Gold-like n = 0.2, k = 3.4: at normal incidence ((0.8)² + k²)/((1.2)² + k²).
        let l = Fresnel::lazanyi(0.2, 3.4).unwrap();
        let want = (0.64 + 11.56) / (1.44 + 11.56);
        assert!((l.eval(1.0) - want).abs() < 1e-14);
        assert!((l.eval(0.0) - 1.0).abs() < 1e-14);
    }

    #[test]
    fn max_value_bounds_the_curve() {
        for f in [
            Fresnel::One,
            Fresnel::schlick(0.5).unwrap(),
            Fresnel::generalized_schlick(6.05524, 5.05524).unwrap(),
            Fresnel::generalized_schlick(0.0300766, -0.713784).unwrap(),
            Fresnel::lazanyi(0.2, 3.4).unwrap(),
        ] {
            let m = f.max_value();
            for i in 0..=10_000 {
                assert!(f.eval(i as f64 / 10_000.0) <= m + 1e-15, "{f:?}");
            }
            assert!(m < 1.0 + f.eval(1.0).abs() + 8.0);
        }
        assert!(Fresnel::schlick(-0.1).is_err());
        assert!(Fresnel::lazanyi(0.0, 1.0).is_err());
        assert!(Fresnel::generalized_schlick(f64::NAN, 0.0).is_err());
    }
}
