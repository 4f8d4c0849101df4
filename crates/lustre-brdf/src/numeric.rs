//! Quadrature used by the models (numeric Smith G1), the albedo and the test battery.

use glam::DVec3;
use std::f64::consts::PI;

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton iteration on P_n; exact to ~1e-15).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    let m = n.div_ceil(2);
    for i in 0..m {
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, 0.0);
            for j in 0..n {
                let p2 = p1;
                p1 = p0;
                p0 = ((2 * j + 1) as f64 * z * p1 - j as f64 * p2) / (j + 1) as f64;
            }
            dp = n as f64 * (z * p0 - p1) / (z * z - 1.0);
            let dz = p0 / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
        w[n - 1 - i] = w[i];
    }
    (x, w)
}

/// A reusable composite Gauss-Legendre rule.
#[derive(Clone, Debug)]
pub struct GaussRule {
    x: Vec<f64>,
    w: Vec<f64>,
}

impl GaussRule {
    /// An `n`-point rule.
    pub fn new(n: usize) -> Self {
        let (x, w) = gauss_legendre(n);
        GaussRule { x, w }
    }

    /// ∫_a^b f over the given panel edges (sorted), `n` points per panel.
    pub fn integrate_panels(&self, edges: &[f64], mut f: impl FnMut(f64) -> f64) -> f64 {
        let mut sum = 0.0;
        for e in edges.windows(2) {
            let (a, b) = (e[0], e[1]);
            let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
            let mut s = 0.0;
            for (xi, wi) in self.x.iter().zip(&self.w) {
                s += wi * f(c + h * xi);
            }
            sum += s * h;
        }
        sum
    }

    /// ∫_a^b f with `panels` equal panels.
    pub fn integrate(&self, a: f64, b: f64, panels: usize, f: impl FnMut(f64) -> f64) -> f64 {
        let edges: Vec<f64> = (0..=panels)
            .map(|k| a + (b - a) * k as f64 / panels as f64)
            .collect();
        self.integrate_panels(&edges, f)
    }
}

/// Panel edges on [0, π] for an angle measured from a lobe centre: geometric near 0 (down to
/// `theta_min`), uniform beyond `theta_split`. Resolves lobes from 1e-4 rad to the full sphere.
pub fn peaked_theta_edges(theta_min: f64, theta_split: f64, uniform_panels: usize) -> Vec<f64> {
    let mut edges = vec![0.0];
    let mut t = theta_min;
    while t < theta_split {
        edges.push(t);
        t *= 1.6;
    }
    for k in 0..=uniform_panels {
        edges.push(theta_split + (PI - theta_split) * k as f64 / uniform_panels as f64);
    }
    edges
}

/// Options for [`integrate_sphere`].
#[derive(Clone, Copy, Debug)]
pub struct SphereQuadrature {
    /// Gauss points per θ panel.
    pub points_per_panel: usize,
    /// Points in φ (trapezoid rule, periodic).
    pub phi_points: usize,
    /// Smallest geometric θ panel edge.
    pub theta_min: f64,
    /// Where the geometric panels stop.
    pub theta_split: f64,
    /// Uniform θ panels beyond the split.
    pub uniform_panels: usize,
}

impl Default for SphereQuadrature {
    fn default() -> Self {
        SphereQuadrature {
            points_per_panel: 12,
            phi_points: 256,
            theta_min: 1e-4,
            theta_split: 0.2,
            uniform_panels: 48,
        }
    }
}

/// ∫_{S²} f(ω) dω in spherical coordinates about `centre`, refined near the centre so that a
/// lobe peaked there is resolved.
pub fn integrate_sphere(f: impl Fn(DVec3) -> f64, centre: DVec3, q: &SphereQuadrature) -> f64 {
    let (t, b) = crate::frame::basis(centre);
    let rule = GaussRule::new(q.points_per_panel);
    let edges = peaked_theta_edges(q.theta_min, q.theta_split, q.uniform_panels);
    let dphi = 2.0 * PI / q.phi_points as f64;
    rule.integrate_panels(&edges, |th| {
        let (st, ct) = th.sin_cos();
        let mut s = 0.0;
        for k in 0..q.phi_points {
            let ph = (k as f64 + 0.5) * dphi;
            let (sp, cp) = ph.sin_cos();
            let w = t * (st * cp) + b * (st * sp) + centre * ct;
            s += f(w);
        }
        s * dphi * st
    })
}

/// Regularized upper incomplete gamma Q(a, x) = Γ(a, x)/Γ(a) for a > 0, x ≥ 0: series for
/// x < a + 1, Lentz continued fraction beyond (Numerical Recipes §6.2). Valid for large `a`
/// (chi-square tails with hundreds of degrees of freedom).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if a.is_nan() || a <= 0.0 || x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    let gln = puruspe::ln_gamma(a);
    if x < a + 1.0 {
        let (mut ap, mut del) = (a, 1.0 / a);
        let mut sum = del;
        for _ in 0..100_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (1.0 - sum * (-x + a * x.ln() - gln).exp()).clamp(0.0, 1.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..100_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        ((-x + a * x.ln() - gln).exp() * h).clamp(0.0, 1.0)
    }
}

/// Upper incomplete gamma Γ(s, x) = ∫_x^∞ t^{s−1} e^{−t} dt for any real s < 1 and x > 0
/// (s may be ≤ 0, as SGD's 1 − p is when p ≥ 1), by the recurrence Γ(s, x) = (Γ(s+1, x) − x^s e^{−x})/s.
pub fn upper_gamma(s: f64, x: f64) -> f64 {
    if s > 0.0 {
        return gamma_q(s, x) * puruspe::gamma(s);
    }
    if s == 0.0 {
        return exp_integral_e1(x);
    }
    let g1 = upper_gamma(s + 1.0, x);
    (g1 - x.powf(s) * (-x).exp()) / s
}

/// Exponential integral E1(x) for x > 0 (series below 1, continued fraction above).
pub fn exp_integral_e1(x: f64) -> f64 {
    const EULER: f64 = 0.577_215_664_901_532_9;
    if x <= 1.0 {
        let mut sum = 0.0;
        let mut term = 1.0;
        for k in 1..200 {
            term *= -x / k as f64;
            let add = -term / k as f64;
            sum += add;
            if add.abs() < 1e-17 * sum.abs() {
                break;
            }
        }
        -EULER - x.ln() + sum
    } else {
        // Lentz continued fraction.
        let mut b = x + 1.0;
        let mut c = 1e300;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..500 {
            let an = -((i * i) as f64);
            b += 2.0;
            d = 1.0 / (an * d + b);
            c = b + an / c;
            let del = c * d;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        h * (-x).exp()
    }
}

/// erf⁻¹(x) on (−1, 1) by Giles' single-precision polynomial ("Approximating the erfinv
/// function", GPU Computing Gems, 2011; relative error < 4e-7). The GPU kernels use the same
/// polynomial; `microfacet::distribution` refines it to double precision.
pub fn erfinv_giles(x: f64) -> f64 {
    let w = -((1.0 - x) * (1.0 + x)).ln();
    let p = if w < 5.0 {
        let w = w - 2.5;
        let mut p = 2.810_226_36e-08;
        for c in [
            3.432_739_39e-07,
            -3.523_387_7e-06,
            -4.391_506_54e-06,
            0.000_218_580_87,
            -0.001_253_725_03,
            -0.004_177_681_64,
            0.246_640_727,
            1.501_409_41,
        ] {
            p = c + p * w;
        }
        p
    } else {
        let w = w.sqrt() - 3.0;
        let mut p = -0.000_200_214_257;
        for c in [
            0.000_100_950_558,
            0.001_349_343_22,
            -0.003_673_428_44,
            0.005_739_507_73,
            -0.007_622_461_3,
            0.009_438_870_47,
            1.001_674_06,
            2.832_976_82,
        ] {
            p = c + p * w;
        }
        p
    };
    p * x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let r = GaussRule::new(8);
        let v = r.integrate(0.0, 2.0, 1, |x| x.powi(15));
        assert!((v - 2f64.powi(16) / 16.0).abs() < 1e-9 * v);
    }

    #[test]
    fn sphere_area_and_narrow_lobe() {
        let q = SphereQuadrature::default();
        let area = integrate_sphere(|_| 1.0, DVec3::new(0.0, 0.6, 0.8), &q);
        assert!((area - 4.0 * PI).abs() < 1e-9, "{area}");
        // A normalized Phong lobe of exponent 1e6 centred off-axis integrates to 1.
        let c = DVec3::new(0.6, 0.0, 0.8);
        let n = 1e6;
        let v = integrate_sphere(|w| crate::sampling::cosine_power_pdf(w.dot(c), n), c, &q);
        assert!((v - 1.0).abs() < 1e-6, "{v}");
    }

    #[test]
    fn gamma_q_large_order() {
        // Chi-square survival with 287 dof at the mean is about 0.5; at the 0.99 quantile 0.01.
        let q = gamma_q(287.0 / 2.0, 287.0 / 2.0);
        assert!((q - 0.489).abs() < 0.01, "{q}");
        assert!((gamma_q(1.0, 2.0) - (-2.0f64).exp()).abs() < 1e-12);
        assert!((gamma_q(0.5, 0.3) - puruspe::gammq(0.5, 0.3)).abs() < 1e-12);
    }

    #[test]
    fn incomplete_gamma_negative_order() {
        // Γ(s, x) for s = −0.5 against direct quadrature of t^{s−1} e^{−t} on [x, x + 60].
        for &(s, x) in &[
            (-0.5f64, 0.3f64),
            (0.5, 0.01),
            (-0.9, 2.0),
            (0.0, 0.7),
            (-1.0, 0.5),
        ] {
            let r = GaussRule::new(20);
            // Substitute t = x e^u to tame the x^s singularity; stop where e^{-t} < 1e-30.
            let direct = r.integrate(0.0, (70.0f64 / x).ln(), 400, |u| {
                let t = x * u.exp();
                t.powf(s - 1.0) * (-t).exp() * t
            });
            let g = upper_gamma(s, x);
            assert!(
                (g - direct).abs() < 1e-9 * direct.abs().max(1.0),
                "s={s} x={x}: {g} vs {direct}"
            );
        }
    }
}
