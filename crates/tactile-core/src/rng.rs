//! Per-sample random numbers that are the same on every machine.
//!
//! Each sample gets its own generator keyed by `(seed, stream, index)`, so a
//! dataset can be rendered in parallel, in any order, and extended later
//! without changing the samples it already has. Uniform and normal draws are
//! computed here from raw 64-bit outputs (not through `rand`'s distribution
//! code) so a dependency update cannot change a dataset.

use crate::{Error, Result};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// An inclusive range `[min, max]` a parameter is drawn from, uniformly.
/// `min == max` fixes the parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Range {
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

impl Range {
    /// `[min, max]`.
    pub const fn new(min: f64, max: f64) -> Self {
        Self { min, max }
    }

    /// A fixed value.
    pub const fn fixed(v: f64) -> Self {
        Self { min: v, max: v }
    }

    /// The value a fraction `u` (in `[0, 1)`) of the way from `min` to
    /// `max`: a uniform draw's place in the range, the one formula every
    /// draw uses (so one uniform can set several ranges alike).
    pub fn at(&self, u: f64) -> f64 {
        self.min + (self.max - self.min) * u
    }

    /// Check the range is finite, ordered and inside `[lo, hi]`; `name` is
    /// the configuration key used in the message.
    pub fn check(&self, name: &str, lo: f64, hi: f64) -> Result<()> {
        if !self.min.is_finite() || !self.max.is_finite() {
            return Err(Error::Config(format!(
                "{name}: range [{:?}, {:?}] is not finite",
                self.min, self.max
            )));
        }
        if self.min > self.max {
            return Err(Error::Config(format!(
                "{name}: range is inverted (min {:?} > max {:?})",
                self.min, self.max
            )));
        }
        if self.min < lo || self.max > hi {
            return Err(Error::Config(format!(
                "{name}: range [{:?}, {:?}] leaves the allowed [{lo}, {hi}]",
                self.min, self.max
            )));
        }
        Ok(())
    }
}

/// `"min,max"`, as [`Range`]'s `FromStr` reads it.
impl std::fmt::Display for Range {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{}", self.min, self.max)
    }
}

/// Parse `"lo,hi"` or a single value (CLI flags).
impl std::str::FromStr for Range {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let num = |p: &str| {
            p.parse::<f64>()
                .map_err(|_| format!("'{p}' is not a number (expected MIN,MAX)"))
        };
        match parts.as_slice() {
            [v] => Ok(Range::fixed(num(v)?)),
            [a, b] => Ok(Range::new(num(a)?, num(b)?)),
            _ => Err(format!("'{s}': expected MIN,MAX")),
        }
    }
}

fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The random source of one sample.
pub struct SampleRng {
    rng: Xoshiro256PlusPlus,
    spare_normal: Option<f64>,
}

impl SampleRng {
    /// The generator of sample `index` in `stream` (streams separate, e.g.,
    /// a sequence's scene from its frames' noise) under the dataset `seed`.
    pub fn new(seed: u64, stream: u64, index: u64) -> Self {
        let key = splitmix64(
            seed ^ splitmix64(stream.wrapping_mul(0xA24B_AED4_963E_E407) ^ splitmix64(index)),
        );
        Self {
            rng: Xoshiro256PlusPlus::seed_from_u64(key),
            spare_normal: None,
        }
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `range`.
    pub fn draw(&mut self, range: Range) -> f64 {
        range.at(self.uniform())
    }

    /// `true` with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.uniform() < p
    }

    /// Uniform index in `0..n` (`n > 0`).
    pub fn index(&mut self, n: usize) -> usize {
        ((self.uniform() * n as f64) as usize).min(n.saturating_sub(1))
    }

    /// Standard normal (Box-Muller, with libm for bit-exact results).
    pub fn normal(&mut self) -> f64 {
        if let Some(v) = self.spare_normal.take() {
            return v;
        }
        let u1 = 1.0 - self.uniform(); // (0, 1]
        let u2 = self.uniform();
        let r = libm::sqrt(-2.0 * libm::log(u1));
        // `sincos` reduces the angle once; its values are `sin`'s and
        // `cos`'s to the bit (the same kernels), so streams are unchanged.
        let (sin, cos) = libm::sincos(2.0 * std::f64::consts::PI * u2);
        self.spare_normal = Some(r * sin);
        r * cos
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_independent() {
        let a: Vec<f64> = (0..4).map(|_| SampleRng::new(1, 0, 5).uniform()).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(
            SampleRng::new(1, 0, 5).uniform(),
            SampleRng::new(1, 0, 6).uniform()
        );
        assert_ne!(
            SampleRng::new(1, 0, 5).uniform(),
            SampleRng::new(1, 1, 5).uniform()
        );
        let mut r = SampleRng::new(3, 0, 0);
        let n = 20000;
        let xs: Vec<f64> = (0..n).map(|_| r.normal()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(
            mean.abs() < 0.03 && (var - 1.0).abs() < 0.05,
            "{mean} {var}"
        );
    }

    /// The normal stream is the Box-Muller pair of `sin` and `cos` to the
    /// bit, as it was before `sincos`: every seed's renders stay the same.
    #[test]
    fn normals_are_the_box_muller_pair_to_the_bit() {
        let (mut a, mut b) = (SampleRng::new(9, 2, 7), SampleRng::new(9, 2, 7));
        for _ in 0..200_000 {
            let r = libm::sqrt(-2.0 * libm::log(1.0 - b.uniform()));
            let t = 2.0 * std::f64::consts::PI * b.uniform();
            assert_eq!(a.normal().to_bits(), (r * libm::cos(t)).to_bits());
            assert_eq!(a.normal().to_bits(), (r * libm::sin(t)).to_bits());
        }
    }

    #[test]
    fn ranges_parse_and_check() {
        let r: Range = "1, 2.5".parse().unwrap();
        assert_eq!(r, Range::new(1.0, 2.5));
        assert!("x,1".parse::<Range>().is_err());
        let e = Range::new(3.0, 1.0)
            .check("depth_mm", 0.0, 5.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("depth_mm") && e.contains("inverted"), "{e}");
        assert!(Range::new(0.0, 9.0).check("depth_mm", 0.0, 5.0).is_err());
        // Far out of range: said as written. Before, 1e300 in 301 digits.
        let e = Range::new(1e300, 1e301)
            .check("press_mm", 0.0, 5.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.ends_with("press_mm: range [1e300, 1e301] leaves the allowed [0, 5]"),
            "{e}"
        );
    }
}
