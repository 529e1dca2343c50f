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

/// A warning for each of `targets` that one value labels on every one of
/// `rows` (label rows in `targets` order, the frames a model fits; an angle
/// counts as one value whole turns apart): a network learns nothing of such
/// a target and estimates that value for every frame, so its error on other
/// frames is the spread of their labels. `labels` is the file the rows
/// come from. Fewer than two rows warn of nothing.
pub fn unvarying_targets(targets: &[Target], rows: &[Vec<f64>], labels: &str) -> Vec<String> {
    if rows.len() < 2 {
        return Vec::new();
    }
    targets
        .iter()
        .enumerate()
        .filter_map(|(j, t)| {
            let first = *rows[0].get(j)?;
            let tolerance = 1e-9 * (1.0 + first.abs());
            rows.iter()
                .all(|r| r.get(j).is_some_and(|&v| t.error(v, first) <= tolerance))
                .then(|| {
                    format!(
                        "{labels}: {name} is {first} on every one of the {n} frames this model fits: it learns nothing of a value that never changes and will estimate {first} for every frame; label {name} where it varies, or leave it out of the targets",
                        name = t.name,
                        n = rows.len()
                    )
                })
        })
        .collect()
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
    fn a_target_of_one_value_throughout_is_named() {
        let targets = [
            Target::linear("depth_mm"),
            Target::linear("shear_x_mm"),
            Target::angle("theta_deg", 180.0),
        ];
        // shear_x_mm never changes; theta_deg is one axis (0 and 180 alike).
        let rows = vec![
            vec![1.0, 0.0, 0.0],
            vec![2.0, 0.0, 180.0],
            vec![3.0, 0.0, -180.0],
        ];
        let w = unvarying_targets(&targets, &rows, "labels.csv");
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(
            w[0].starts_with("labels.csv: shear_x_mm is 0 on every one of the 3 frames"),
            "{}",
            w[0]
        );
        assert!(w[1].contains("theta_deg is 0"), "{}", w[1]);
        // A target that varies anywhere, and one frame alone, warn of nothing.
        let rows = vec![vec![1.0, 0.0, 0.0], vec![1.0, 0.5, 10.0]];
        assert!(
            unvarying_targets(&targets, &rows, "l")
                .iter()
                .all(|w| w.contains("depth_mm"))
        );
        assert!(unvarying_targets(&targets, &rows[..1], "l").is_empty());
    }

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
