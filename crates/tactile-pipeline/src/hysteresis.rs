//! A two-threshold filter on the detector's probability over a sequence.

use tactile_core::{Error, Result};

/// A tendon appears when the probability reaches `on` and disappears when
/// it falls below `off` (`off <= on`), so a score hovering around one
/// threshold at an onset or release does not flicker.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hysteresis {
    /// Probability at which a tendon appears.
    pub on: f32,
    /// Probability below which it disappears.
    pub off: f32,
    /// The current decision.
    pub state: bool,
}

impl Hysteresis {
    /// A filter with no tendon yet; `0 <= off <= on <= 1`.
    pub fn new(on: f32, off: f32) -> Result<Self> {
        if !(0.0..=1.0).contains(&off) || !(0.0..=1.0).contains(&on) || off > on {
            return Err(Error::Config(format!(
                "hysteresis thresholds must satisfy 0 <= off <= on <= 1, got on {on}, off {off}"
            )));
        }
        Ok(Self {
            on,
            off,
            state: false,
        })
    }

    /// The decision for the next frame of the sequence.
    pub fn update(&mut self, p: f32) -> bool {
        self.state = if self.state {
            p >= self.off
        } else {
            p >= self.on
        };
        self.state
    }

    /// Start a new sequence (no tendon yet).
    pub fn reset(&mut self) {
        self.state = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hysteresis_holds_through_a_dip_and_resets_per_sequence() {
        let mut h = Hysteresis::new(0.6, 0.2).unwrap();
        let p = [0.1, 0.5, 0.7, 0.4, 0.3, 0.1, 0.5, 0.9];
        let got: Vec<bool> = p.iter().map(|&v| h.update(v)).collect();
        assert_eq!(got, [false, false, true, true, true, false, false, true]);
        h.reset();
        assert!(!h.update(0.5));
        assert!(Hysteresis::new(0.2, 0.6).is_err());
        assert!(Hysteresis::new(1.5, 0.2).is_err());
    }
}
