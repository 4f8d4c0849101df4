//! Filling buried texels and dilating charts into their gutters.
//!
//! Both grow known values outwards one ring of texels per pass: an unknown texel with known
//! 8-neighbours of the right chart takes their mean. Buried texels (covered, no valid sample)
//! grow from their own chart until none is left (a chart without any valid texel stays black);
//! uncovered texels grow for `gutter` passes from the chart with the lowest id among their known
//! neighbours, so a bilinear lookup at a chart's border reads that chart's values.

use super::trace::NO_CHART;

/// A page being assembled: irradiance, chart per texel, which texels hold a value.
#[derive(Clone, Debug, PartialEq)]
pub struct PageBuffer {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Irradiance per texel.
    pub e: Vec<[f32; 3]>,
    /// Chart per texel ([`NO_CHART`] uncovered and not dilated).
    pub chart: Vec<u32>,
    /// Whether a texel holds a value.
    pub known: Vec<bool>,
}

impl PageBuffer {
    /// One pass: texels for which `allow(index)` holds and that are unknown take the mean of
    /// their known 8-neighbours of chart `want(index, neighbour charts)`. Returns the number
    /// filled.
    fn pass(&mut self, allow: &dyn Fn(usize) -> bool, own_chart: bool) -> usize {
        let (w, h) = (self.width as i64, self.height as i64);
        let mut updates = vec![];
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if self.known[i] || !allow(i) {
                    continue;
                }
                let mut nb = vec![];
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (nx, ny) = (x + dx, y + dy);
                        if (dx, dy) == (0, 0) || nx < 0 || ny < 0 || nx >= w || ny >= h {
                            continue;
                        }
                        let j = (ny * w + nx) as usize;
                        if self.known[j] && self.chart[j] != NO_CHART {
                            nb.push(j);
                        }
                    }
                }
                let chart = if own_chart {
                    self.chart[i]
                } else {
                    match nb.iter().map(|&j| self.chart[j]).min() {
                        Some(c) => c,
                        None => continue,
                    }
                };
                let mut sum = [0.0f64; 3];
                let mut n = 0;
                for &j in nb.iter().filter(|&&j| self.chart[j] == chart) {
                    for (s, &v) in sum.iter_mut().zip(&self.e[j]) {
                        *s += f64::from(v);
                    }
                    n += 1;
                }
                if n > 0 {
                    updates.push((i, chart, sum.map(|s| (s / f64::from(n)) as f32)));
                }
            }
        }
        for &(i, chart, e) in &updates {
            self.e[i] = e;
            self.chart[i] = chart;
            self.known[i] = true;
        }
        updates.len()
    }

    /// Fills the covered texels that are not known from known texels of their chart, until
    /// none can be filled; returns how many were filled.
    pub fn fill_buried(&mut self) -> usize {
        let covered: Vec<bool> = self.chart.iter().map(|&c| c != NO_CHART).collect();
        let mut total = 0;
        loop {
            let n = self.pass(&|i| covered[i], true);
            if n == 0 {
                return total;
            }
            total += n;
        }
    }

    /// Dilates the charts into the uncovered texels, `passes` rings; returns how many texels
    /// were written.
    pub fn dilate(&mut self, passes: u32) -> usize {
        let uncovered: Vec<bool> = self.chart.iter().map(|&c| c == NO_CHART).collect();
        (0..passes)
            .map(|_| self.pass(&|i| uncovered[i], false))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buried_fill_stays_in_its_chart_and_dilation_grows_rings() {
        // 5×1: chart 0 at x = 0, 1 (x = 1 buried), gap at 2, chart 1 at x = 3, 4.
        let mut p = PageBuffer {
            width: 5,
            height: 1,
            e: vec![[1.0; 3], [0.0; 3], [0.0; 3], [5.0; 3], [7.0; 3]],
            chart: vec![0, 0, NO_CHART, 1, 1],
            known: vec![true, false, false, true, true],
        };
        assert_eq!(p.fill_buried(), 1);
        assert_eq!(p.e[1], [1.0; 3]);
        assert_eq!(p.dilate(1), 1);
        // The gap texel takes chart 0 (lowest id) only.
        assert_eq!((p.e[2], p.chart[2]), ([1.0; 3], 0));
    }
}
