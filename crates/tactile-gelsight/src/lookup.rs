//! The classic anchor: a lookup table from colour change to slope
//! (Johnson and Adelson's GelSight table, as Taxim calibrates it). Each
//! working pixel's colour change (three channels, in the model's feature
//! units) falls in a cell of a regular grid; the cell holds the mean slope
//! of the calibration pixels that fell in it. An empty cell answers from
//! the same place on coarser grids, and with no slope if every one is
//! empty. It sees neither position nor neighbours: what it cannot tell
//! apart (a shadow and a slope of the same colour) it averages.

use serde::{Deserialize, Serialize};

use crate::prepare::FEATURES;

/// Finest cells per channel.
pub const DEFAULT_BINS: usize = 24;
/// Colour change (feature units: the change x `DIFF_GAIN`) the table spans
/// either side of 0; beyond it a change counts as the last cell's.
pub const SPAN: f32 = 1.5;
/// Most cells per channel.
pub const MAX_BINS: usize = 64;

/// One level of the table: `bins^3` cells of summed slopes and counts.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Level {
    bins: usize,
    sum_gx: Vec<f64>,
    sum_gy: Vec<f64>,
    count: Vec<u32>,
}

impl Level {
    fn new(bins: usize) -> Self {
        let n = bins * bins * bins;
        Self {
            bins,
            sum_gx: vec![0.0; n],
            sum_gy: vec![0.0; n],
            count: vec![0; n],
        }
    }

    fn cell(&self, rgb: [f32; 3]) -> usize {
        let b = self.bins;
        let q = |v: f32| {
            let t = ((v + SPAN) / (2.0 * SPAN) * b as f32).floor();
            if t.is_nan() {
                0
            } else {
                (t.max(0.0) as usize).min(b - 1)
            }
        };
        (q(rgb[0]) * b + q(rgb[1])) * b + q(rgb[2])
    }
}

/// A colour-change to slope table, finest level first, each coarser one
/// half as many cells per channel.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LookupTable {
    levels: Vec<Level>,
}

impl LookupTable {
    /// An empty table of `bins` finest cells per channel (2 to
    /// [`MAX_BINS`]).
    pub fn new(bins: usize) -> tactile_core::Result<Self> {
        if !(2..=MAX_BINS).contains(&bins) {
            return Err(tactile_core::Error::Config(format!(
                "lookup table: 2-{MAX_BINS} cells per channel, got {bins}"
            )));
        }
        let mut levels = Vec::new();
        let mut b = bins;
        while b >= 2 {
            levels.push(Level::new(b));
            b /= 2;
        }
        Ok(Self { levels })
    }

    /// Add the pixels of one frame: `features` as the network takes them
    /// (`[FEATURES, n]`, channels first), its slope targets and weights
    /// (pixels of weight 0 are not known and are skipped).
    pub fn add(&mut self, features: &[f32], (gx, gy): (&[f32], &[f32]), weight: &[f32]) {
        let n = weight.len();
        debug_assert_eq!(features.len(), FEATURES * n);
        for p in 0..n {
            if weight[p] <= 0.0 {
                continue;
            }
            let rgb = [features[p], features[n + p], features[2 * n + p]];
            for l in &mut self.levels {
                let c = l.cell(rgb);
                l.sum_gx[c] += gx[p] as f64;
                l.sum_gy[c] += gy[p] as f64;
                l.count[c] += 1;
            }
        }
    }

    /// The slopes of every pixel of `features` (`[FEATURES, n]`): `gx`
    /// then `gy`, `2n` values, as the network gives them.
    pub fn slopes(&self, features: &[f32]) -> Vec<f32> {
        let n = features.len() / FEATURES;
        let mut out = vec![0f32; 2 * n];
        for p in 0..n {
            let rgb = [features[p], features[n + p], features[2 * n + p]];
            for l in &self.levels {
                let c = l.cell(rgb);
                if l.count[c] > 0 {
                    let k = l.count[c] as f64;
                    out[p] = (l.sum_gx[c] / k) as f32;
                    out[n + p] = (l.sum_gy[c] / k) as f32;
                    break;
                }
            }
        }
        out
    }

    /// Finest cells per channel.
    pub fn bins(&self) -> usize {
        self.levels.first().map_or(0, |l| l.bins)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_cell_answers_its_mean_and_an_empty_one_a_coarser_cell() {
        let mut t = LookupTable::new(8).unwrap();
        // Two pixels: one red-ish change, one blue-ish.
        let n = 2;
        let mut f = vec![0f32; FEATURES * n];
        f[0] = 1.2; // pixel 0, red
        f[2 * n + 1] = 1.2; // pixel 1, blue
        t.add(&f, (&[0.3, -0.2], &[0.1, 0.4]), &[1.0, 1.0]);
        t.add(&f, (&[0.5, -0.2], &[0.1, 0.4]), &[1.0, 0.0]);
        let s = t.slopes(&f);
        assert!(
            (s[0] - 0.4).abs() < 1e-6 && (s[1] + 0.2).abs() < 1e-6,
            "{s:?}"
        );
        // A change next to the red one but in another fine cell.
        let mut g = vec![0f32; FEATURES];
        g[0] = 1.0;
        let s = t.slopes(&g);
        assert!((s[0] - 0.4).abs() < 1e-6, "{s:?}");
        // Far from anything seen: no slope.
        let mut g = vec![0f32; FEATURES];
        g[1] = -1.4;
        assert_eq!(t.slopes(&g), vec![0.0, 0.0]);
        assert!(LookupTable::new(1).is_err() && LookupTable::new(65).is_err());
    }
}
