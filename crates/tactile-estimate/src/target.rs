//! What a regressor predicts, and how each quantity is encoded for the
//! network and scored afterwards.
//!
//! An angle is not a number on a line: 179 and -179 degrees are 2 degrees
//! apart. An angle target with period `P` (360 for a direction, 180 for an
//! edge or an axis, which look the same turned by 180) is encoded as
//! `(sin 2 pi a / P, cos 2 pi a / P)`, decoded with `atan2`, and its error
//! is the shortest way round the circle.

use crate::Result;
use serde::{Deserialize, Serialize};
use tactile_core::Error;

/// How a target is encoded and scored.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TargetKind {
    /// A quantity on the real line (mm, N).
    Linear,
    /// An angle in degrees with this period; decoded into
    /// `[start_deg, start_deg + period_deg)`.
    Angle {
        /// Degrees after which the angle repeats (360, or 180 for an axis).
        period_deg: f64,
        /// Start of the interval predictions are decoded into.
        start_deg: f64,
    },
}

/// A named label column of a dataset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Target {
    /// The label column.
    pub name: String,
    /// How it is encoded and scored.
    pub kind: TargetKind,
}

impl Target {
    /// A quantity on the real line.
    pub fn linear(name: &str) -> Self {
        Self {
            name: name.into(),
            kind: TargetKind::Linear,
        }
    }

    /// An angle decoded into the half-open period centred on 0.
    pub fn angle(name: &str, period_deg: f64) -> Self {
        Self {
            name: name.into(),
            kind: TargetKind::Angle {
                period_deg,
                start_deg: -period_deg / 2.0,
            },
        }
    }

    /// Parse `name` (linear) or `name:PERIOD` (angle), e.g. `theta_deg:180`.
    pub fn parse(s: &str) -> Result<Self> {
        match s.split_once(':') {
            None if !s.is_empty() => Ok(Self::linear(s)),
            Some((name, p)) if !name.is_empty() => {
                let period: f64 = p.parse().ok().filter(|v: &f64| *v > 0.0 && v.is_finite()).ok_or_else(|| {
                    Error::Config(format!(
                        "target '{s}': the angle period must be a positive number of degrees, e.g. {name}:180"
                    ))
                })?;
                Ok(Self::angle(name, period))
            }
            _ => Err(Error::Config(format!("target '{s}': expected NAME or NAME:PERIOD")).into()),
        }
    }

    /// Network columns this target takes.
    pub fn width(&self) -> usize {
        match self.kind {
            TargetKind::Linear => 1,
            TargetKind::Angle { .. } => 2,
        }
    }

    /// Encode one value into [`Self::width`] columns.
    pub fn encode(&self, v: f64) -> Vec<f64> {
        match self.kind {
            TargetKind::Linear => vec![v],
            TargetKind::Angle { period_deg, .. } => {
                let a = 2.0 * std::f64::consts::PI * v / period_deg;
                vec![a.sin(), a.cos()]
            }
        }
    }

    /// Decode columns back to a value.
    pub fn decode(&self, cols: &[f64]) -> f64 {
        match self.kind {
            TargetKind::Linear => cols[0],
            TargetKind::Angle {
                period_deg,
                start_deg,
            } => {
                let a = cols[0].atan2(cols[1]) * period_deg / (2.0 * std::f64::consts::PI);
                start_deg + (a - start_deg).rem_euclid(period_deg)
            }
        }
    }

    /// Absolute error, the short way round for angles.
    pub fn error(&self, pred: f64, truth: f64) -> f64 {
        match self.kind {
            TargetKind::Linear => (pred - truth).abs(),
            TargetKind::Angle { period_deg, .. } => {
                let d = (pred - truth).rem_euclid(period_deg);
                d.min(period_deg - d)
            }
        }
    }

    /// Mean absolute error over a set.
    pub fn mae(&self, pred: &[f64], truth: &[f64]) -> f64 {
        if truth.is_empty() {
            return f64::NAN;
        }
        pred.iter()
            .zip(truth)
            .map(|(p, t)| self.error(*p, *t))
            .sum::<f64>()
            / truth.len() as f64
    }
}

impl std::str::FromStr for Target {
    type Err = crate::Error;
    fn from_str(s: &str) -> Result<Self> {
        Self::parse(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_wrap_and_round_trip() {
        let t = Target::parse("theta_deg:180").unwrap();
        assert_eq!(t.width(), 2);
        assert!((t.error(89.0, -89.0) - 2.0).abs() < 1e-9);
        assert!((t.error(10.0, 190.0)).abs() < 1e-9);
        for v in [-89.5, -45.0, 0.0, 30.0, 89.9] {
            assert!((t.decode(&t.encode(v)) - v).abs() < 1e-9, "{v}");
        }
        let lin = Target::parse("x_mm").unwrap();
        assert_eq!(lin.decode(&lin.encode(-2.5)), -2.5);
        assert!(Target::parse("theta:0").is_err());
        assert!(Target::parse(":180").is_err());
    }
}
