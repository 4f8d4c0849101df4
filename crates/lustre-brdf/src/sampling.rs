//! Sample warps and low-discrepancy points shared by models, tests and integrators.

use glam::DVec3;
use std::f64::consts::PI;

/// The k-th point of an n-point Hammersley set in [0, 1)², with a half-cell offset on the
/// first coordinate so that no point sits on the boundary.
#[inline]
pub fn hammersley(k: u32, n: u32) -> (f64, f64) {
    ((k as f64 + 0.5) / n as f64, radical_inverse2(k))
}

/// Van der Corput radical inverse in base 2.
#[inline]
pub fn radical_inverse2(k: u32) -> f64 {
    k.reverse_bits() as f64 * (1.0 / 4_294_967_296.0)
}

/// Cosine-weighted direction on the upper hemisphere (Malley's method).
#[inline]
pub fn cosine_hemisphere(u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let z = (1.0 - u1).max(0.0).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`cosine_hemisphere`].
#[inline]
pub fn cosine_hemisphere_pdf(w: DVec3) -> f64 {
    if w.z > 0.0 {
        w.z / PI
    } else {
        0.0
    }
}

/// Uniform direction on the unit sphere.
#[inline]
pub fn uniform_sphere(u1: f64, u2: f64) -> DVec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A direction distributed ∝ cosⁿ of the angle to the +z axis (Phong lobe), and its pdf
/// (n + 1)/(2π) cosⁿ.
#[inline]
pub fn cosine_power(u1: f64, u2: f64, n: f64) -> DVec3 {
    let z = u1.powf(1.0 / (n + 1.0));
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`cosine_power`] for a direction whose cosine to the lobe axis is `c`.
#[inline]
pub fn cosine_power_pdf(c: f64, n: f64) -> f64 {
    if c > 0.0 {
        (n + 1.0) / (2.0 * PI) * c.powf(n)
    } else {
        0.0
    }
}

/// Expresses a lobe-local direction `v` (lobe axis +z) in the frame whose z is `axis`.
#[inline]
pub fn to_world(v: DVec3, axis: DVec3) -> DVec3 {
    let (t, b) = crate::frame::basis(axis);
    t * v.x + b * v.y + axis * v.z
}

/// Two uniform numbers in [0, 1) from one: the top 52 bits of `u`, de-interleaved (odd bits to
/// the first, even bits to the second), 26 bits each, centred in their cells. For a sampler that
/// needs a third number (a discrete lobe choice that depends on the sampled direction) while the
/// [`crate::Bsdf::sample`] interface passes two.
#[inline]
pub fn split_uniform(u: f64) -> (f64, f64) {
    let bits = (u.clamp(0.0, 1.0) * 4_503_599_627_370_496.0) as u64; // 2^52
    let (mut a, mut b) = (0u64, 0u64);
    for i in 0..26 {
        a |= ((bits >> (2 * i + 1)) & 1) << i;
        b |= ((bits >> (2 * i)) & 1) << i;
    }
    let scale = 1.0 / 67_108_864.0; // 2^-26
    ((a as f64 + 0.5) * scale, (b as f64 + 0.5) * scale)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hammersley_in_unit_square() {
        for k in 0..64 {
            let (a, b) = hammersley(k, 64);
            assert!((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b));
        }
        assert_eq!(radical_inverse2(1), 0.5);
        assert_eq!(radical_inverse2(2), 0.25);
    }

    #[test]
    fn split_uniform_is_uniform_and_independent() {
        // A 16×16 grid of the pair from 65 536 random numbers: every cell near 256.
        let mut rng = SplitMix64::new(3);
        let mut cells = [0u32; 256];
        for _ in 0..65_536 {
            let (a, b) = split_uniform(rng.next_f64());
            assert!((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b));
            cells[(a * 16.0) as usize * 16 + (b * 16.0) as usize] += 1;
        }
        // Chi-square with 255 dof: mean 255, sd 22.6.
        let chi2: f64 = cells
            .iter()
            .map(|&c| (c as f64 - 256.0).powi(2) / 256.0)
            .sum();
        assert!(chi2 < 255.0 + 5.0 * 22.6, "{chi2}");
    }

    #[test]
    fn warps_are_unit() {
        for k in 0..32 {
            let (u1, u2) = hammersley(k, 32);
            for w in [
                cosine_hemisphere(u1, u2),
                uniform_sphere(u1, u2),
                cosine_power(u1, u2, 20.0),
            ] {
                assert!((w.length() - 1.0).abs() < 1e-12);
            }
        }
    }
}

/// A small seeded generator (SplitMix64) for reproducible Monte-Carlo in library code and tests.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A uniform number in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }
}
