//! A linear RGB triple in f64.
//!
//! Evaluation, fitting sums and the reference integrators all work in f64: fitting accumulates
//! millions of squared residuals and the quadrature tests compare integrals to 1e-6, which f32
//! cannot carry. The GPU renderer converts to f32 at its boundary.

use serde::{Deserialize, Serialize};
use std::ops::{Add, AddAssign, Div, Index, IndexMut, Mul, MulAssign, Sub};

/// Linear RGB, one f64 per channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Rgb(pub [f64; 3]);

impl Rgb {
    /// Black.
    pub const ZERO: Rgb = Rgb([0.0; 3]);
    /// White (1, 1, 1).
    pub const ONE: Rgb = Rgb([1.0; 3]);

    /// A triple from its channels.
    pub const fn new(r: f64, g: f64, b: f64) -> Self {
        Rgb([r, g, b])
    }

    /// The same value in every channel.
    pub const fn splat(v: f64) -> Self {
        Rgb([v; 3])
    }

    /// The channels as f32 (an image's pixel).
    pub fn to_f32(self) -> [f32; 3] {
        self.0.map(|c| c as f32)
    }

    /// Rec. 709 luminance.
    pub fn luminance(&self) -> f64 {
        0.2126 * self.0[0] + 0.7152 * self.0[1] + 0.0722 * self.0[2]
    }

    /// Arithmetic mean of the channels.
    pub fn mean(&self) -> f64 {
        (self.0[0] + self.0[1] + self.0[2]) / 3.0
    }

    /// Largest channel.
    pub fn max_component(&self) -> f64 {
        self.0[0].max(self.0[1]).max(self.0[2])
    }

    /// Smallest channel.
    pub fn min_component(&self) -> f64 {
        self.0[0].min(self.0[1]).min(self.0[2])
    }

    /// True when every channel is finite.
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }

    /// Applies `f` to every channel.
    pub fn map(self, f: impl Fn(f64) -> f64) -> Rgb {
        Rgb([f(self.0[0]), f(self.0[1]), f(self.0[2])])
    }

    /// Channel-wise combination of two triples.
    pub fn zip(self, o: Rgb, f: impl Fn(f64, f64) -> f64) -> Rgb {
        Rgb([
            f(self.0[0], o.0[0]),
            f(self.0[1], o.0[1]),
            f(self.0[2], o.0[2]),
        ])
    }
}

impl Add for Rgb {
    type Output = Rgb;
    fn add(self, o: Rgb) -> Rgb {
        self.zip(o, |a, b| a + b)
    }
}
impl AddAssign for Rgb {
    fn add_assign(&mut self, o: Rgb) {
        *self = *self + o;
    }
}
impl Sub for Rgb {
    type Output = Rgb;
    fn sub(self, o: Rgb) -> Rgb {
        self.zip(o, |a, b| a - b)
    }
}
impl Mul for Rgb {
    type Output = Rgb;
    fn mul(self, o: Rgb) -> Rgb {
        self.zip(o, |a, b| a * b)
    }
}
impl Mul<f64> for Rgb {
    type Output = Rgb;
    fn mul(self, s: f64) -> Rgb {
        self.map(|a| a * s)
    }
}
impl Mul<Rgb> for f64 {
    type Output = Rgb;
    fn mul(self, c: Rgb) -> Rgb {
        c * self
    }
}
impl MulAssign<f64> for Rgb {
    fn mul_assign(&mut self, s: f64) {
        *self = *self * s;
    }
}
impl Div<f64> for Rgb {
    type Output = Rgb;
    fn div(self, s: f64) -> Rgb {
        self.map(|a| a / s)
    }
}
impl Index<usize> for Rgb {
    type Output = f64;
    fn index(&self, i: usize) -> &f64 {
        &self.0[i]
    }
}
impl IndexMut<usize> for Rgb {
    fn index_mut(&mut self, i: usize) -> &mut f64 {
        &mut self.0[i]
    }
}
impl std::iter::Sum for Rgb {
    fn sum<I: Iterator<Item = Rgb>>(iter: I) -> Rgb {
        iter.fold(Rgb::ZERO, |a, b| a + b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arithmetic_and_luminance() {
        let a = Rgb::new(1.0, 2.0, 3.0);
        assert_eq!(a + Rgb::ONE, Rgb::new(2.0, 3.0, 4.0));
        assert_eq!(a * 2.0, Rgb::new(2.0, 4.0, 6.0));
        assert_eq!(a.max_component(), 3.0);
        assert!((Rgb::ONE.luminance() - 1.0).abs() < 1e-12);
    }
}
