//! Undoing a sensor mounted turned. A TacTip's pins sit on a hexagonal
//! lattice, so the directions from each pin to its neighbours repeat every
//! 60 degrees and their six-fold circular mean is the lattice's
//! orientation. A frame whose lattice is turned from the training frames'
//! (a tip screwed on a few degrees off) is turned back before the rest of
//! the chain, so a model trained on straight frames sees what it knows. A
//! contact moves some pins, but the mean over every neighbour pair of ~127
//! pins barely moves with it. The chain measures the lattice on its own
//! binary image (after the lighting step and the mask), so a straight
//! frame costs one connected-components pass; a turned one is turned back
//! raw and lit again.

use serde::{Deserialize, Serialize};
use tactile_core::image_io::GreyImage;
use tactile_core::rng::SampleRng;

use crate::perturb::Perturbation;
use crate::pins::{median_spacing_px, pin_centroids};
use crate::{PreprocessConfig, Result};

/// Largest turn corrected, degrees: beyond half the lattice's 60 degree
/// period a turn cannot be told from one the other way.
pub const MAX_TURN_DEG: f64 = 25.0;

/// The largest turn a fitted alignment undoes, degrees: far enough for a
/// tip screwed on a few degrees off, short of the 30 degrees between the
/// two natural ways to lay a hexagonal lattice, so frames of a sensor built
/// with the other one are left alone rather than turned.
pub const DEFAULT_MAX_TURN_DEG: f64 = 12.0;

/// Fewest pins from which an orientation is measured.
pub const MIN_PINS: usize = 12;

/// Smallest blob counted as a pin, pixels.
const MIN_PIN_AREA_PX: usize = 4;

/// How a frame is turned back to the training frames' lattice.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PinAlign {
    /// Lattice orientation of the training frames, degrees in [-30, 30).
    pub reference_deg: f64,
    /// Turns below this are left alone: the measurement's spread on the
    /// training frames, so a straight frame is never resampled.
    pub tolerance_deg: f64,
    /// Turns beyond this are left alone (at most [`MAX_TURN_DEG`]).
    pub max_turn_deg: f64,
}

impl PinAlign {
    /// The turn from the reference of a lattice at `angle_deg`, when it is
    /// one to undo: above the tolerance and at most the largest turn.
    pub fn turn_to_undo(&self, angle_deg: f64) -> Option<f64> {
        let turn = lattice_delta(angle_deg, self.reference_deg);
        (turn.abs() > self.tolerance_deg && turn.abs() <= self.max_turn_deg).then_some(turn)
    }

    /// One line for a person: the reference and the turns undone.
    pub fn describe(&self, frames: usize) -> String {
        format!(
            "pin lattice at {:.2} deg over {frames} frames; turns of {:.2} to {:.0} deg are undone",
            self.reference_deg, self.tolerance_deg, self.max_turn_deg
        )
    }

    /// Check the angles.
    pub fn check(&self) -> tactile_core::Result<()> {
        let ok = |v: f64, lo: f64, hi: f64| v.is_finite() && (lo..=hi).contains(&v);
        if !ok(self.reference_deg, -30.0, 30.0)
            || !ok(self.tolerance_deg, 0.0, MAX_TURN_DEG)
            || !ok(self.max_turn_deg, 0.0, MAX_TURN_DEG)
        {
            return Err(tactile_core::Error::Config(format!(
                "pin alignment: reference must be in [-30, 30] degrees, tolerance and largest turn in [0, {MAX_TURN_DEG}], got {self:?}"
            )));
        }
        Ok(())
    }
}

/// Orientation of a hexagonal set of points, degrees in (-30, 30]: the
/// six-fold circular mean of the directions to each point's neighbours
/// (points closer than 1.4 nearest-neighbour spacings). `None` for fewer
/// than [`MIN_PINS`] points or no clear six-fold order.
pub fn lattice_angle_deg(points: &[(f32, f32)]) -> Option<f64> {
    if points.len() < MIN_PINS {
        return None;
    }
    let d = |a: &(f32, f32), b: &(f32, f32)| ((a.0 - b.0) as f64).hypot((a.1 - b.1) as f64);
    let reach = 1.4 * median_spacing_px(points)? as f64;
    let (mut s, mut c, mut n) = (0.0, 0.0, 0usize);
    for (i, a) in points.iter().enumerate() {
        for b in &points[i + 1..] {
            if d(a, b) <= reach {
                let phi = ((b.1 - a.1) as f64).atan2((b.0 - a.0) as f64);
                s += (6.0 * phi).sin();
                c += (6.0 * phi).cos();
                n += 1;
            }
        }
    }
    // A lattice gives a resultant near 1; scattered blobs near 0.
    if n < MIN_PINS || s.hypot(c) < 0.3 * n as f64 {
        return None;
    }
    Some(s.atan2(c).to_degrees() / 6.0)
}

/// The pin lattice's orientation in `frame`, measured on the binary image
/// `cfg`'s chain makes of it before any turn (what [`crate::preprocess`]
/// measures), degrees.
pub fn frame_lattice_angle_deg(frame: &GreyImage, cfg: &PreprocessConfig) -> Result<Option<f64>> {
    let binary = crate::lit_and_masked(frame, cfg)?;
    Ok(lattice_angle_deg(&pin_centroids(&binary, MIN_PIN_AREA_PX)?))
}

/// The smallest signed difference of two lattice angles, degrees.
fn lattice_delta(a: f64, b: f64) -> f64 {
    (a - b + 30.0).rem_euclid(60.0) - 30.0
}

/// The turn, degrees, of the pin lattice in a binary image (pins non-zero)
/// from `align`'s reference, when it is one to undo: above the tolerance
/// and at most the largest turn. `None` otherwise, or when no lattice is
/// found.
pub fn turn_to_undo(binary: &GreyImage, align: &PinAlign) -> Result<Option<f64>> {
    let Some(angle) = lattice_angle_deg(&pin_centroids(binary, MIN_PIN_AREA_PX)?) else {
        return Ok(None);
    };
    Ok(align.turn_to_undo(angle))
}

/// `image` turned about its centre by `-turn` degrees (bilinear), undoing
/// a lattice turned by `turn`.
pub fn turn_back(image: &GreyImage, turn: f64) -> Result<GreyImage> {
    // `Rotation { deg }` adds `deg` to every in-image direction angle.
    Perturbation::Rotation { deg: -turn }.apply(image, &mut SampleRng::new(0, 0, 0))
}

/// `frame` turned so its lattice sits at `align`'s reference, or `None`
/// when it already does (within the tolerance), the turn is beyond the
/// largest corrected, or no lattice is found.
pub fn aligned(
    frame: &GreyImage,
    cfg: &PreprocessConfig,
    align: &PinAlign,
) -> Result<Option<GreyImage>> {
    match frame_lattice_angle_deg(frame, cfg)?.and_then(|a| align.turn_to_undo(a)) {
        Some(turn) => Ok(Some(turn_back(frame, turn)?)),
        None => Ok(None),
    }
}

/// Fit the alignment on training frames: the reference is the median
/// lattice angle, the tolerance the 95th percentile of the frames'
/// distance from it (at least 0.5 degrees), the largest turn
/// [`DEFAULT_MAX_TURN_DEG`]. Frames with no lattice are skipped; fewer than 10
/// measured frames is an error.
pub fn fit_pin_align(frames: &[GreyImage], cfg: &PreprocessConfig) -> Result<(PinAlign, usize)> {
    use rayon::prelude::*;
    let angles = frames
        .par_iter()
        .map(|f| frame_lattice_angle_deg(f, cfg))
        .collect::<Result<Vec<_>>>()?;
    fit_pin_align_to(&angles)
}

/// [`fit_pin_align`] on each frame's measured lattice angle (`None` where
/// a frame shows no lattice), so frames need not all be held in memory.
pub fn fit_pin_align_to(frame_angles: &[Option<f64>]) -> Result<(PinAlign, usize)> {
    let angles: Vec<f64> = frame_angles.iter().flatten().copied().collect();
    if angles.len() < 10 {
        return Err(tactile_core::Error::Invalid(format!(
            "pin alignment: a pin lattice was found in {} of {} frames, at least 10 are needed",
            angles.len(),
            frame_angles.len()
        ))
        .into());
    }
    // Circular median on the 60 degree period: centre on the mean first.
    let (s, c) = angles.iter().fold((0.0, 0.0), |(s, c), a| {
        let r = (6.0 * a).to_radians();
        (s + r.sin(), c + r.cos())
    });
    let centre = s.atan2(c).to_degrees() / 6.0;
    let mut off: Vec<f64> = angles.iter().map(|&a| lattice_delta(a, centre)).collect();
    off.sort_by(f64::total_cmp);
    let reference = lattice_delta(centre + off[off.len() / 2], 0.0);
    let mut spread: Vec<f64> = angles
        .iter()
        .map(|&a| lattice_delta(a, reference).abs())
        .collect();
    spread.sort_by(f64::total_cmp);
    let p95 = spread[(spread.len() * 95 / 100).min(spread.len() - 1)];
    Ok((
        PinAlign {
            reference_deg: reference,
            tolerance_deg: p95.max(0.5),
            max_turn_deg: DEFAULT_MAX_TURN_DEG,
        },
        angles.len(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hexagonal patch of `rings` rings, spacing 10, turned by `deg`.
    fn lattice(deg: f64, rings: i32) -> Vec<(f32, f32)> {
        let (s, c) = deg.to_radians().sin_cos();
        let mut p = Vec::new();
        for q in -rings..=rings {
            for r in -rings..=rings {
                if (q + r).abs() > rings {
                    continue;
                }
                let (x, y) = (
                    10.0 * (q as f64 + r as f64 / 2.0),
                    10.0 * r as f64 * 0.75f64.sqrt(),
                );
                p.push(((c * x - s * y) as f32, (s * x + c * y) as f32));
            }
        }
        p
    }

    #[test]
    fn lattice_angle_follows_a_turn_modulo_sixty_degrees() {
        for deg in [-20.0, -5.0, 0.0, 2.0, 7.5, 29.0] {
            let a = lattice_angle_deg(&lattice(deg, 6)).unwrap();
            assert!(lattice_delta(a, deg).abs() < 1e-6, "{deg}: {a}");
        }
        assert!((lattice_angle_deg(&lattice(65.0, 6)).unwrap() - 5.0).abs() < 1e-6);
        // Too few points, or points scattered at random.
        assert_eq!(lattice_angle_deg(&lattice(0.0, 1)), None);
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32 * 200.0
        };
        let scattered: Vec<(f32, f32)> = (0..120).map(|_| (next(), next())).collect();
        assert_eq!(lattice_angle_deg(&scattered), None);
    }

    #[test]
    fn fitting_on_frames_without_pins_is_refused_saying_how_many_showed_a_lattice() {
        let blank = tactile_core::image_io::grey_image(300, 300, vec![30u8; 300 * 300]).unwrap();
        let e = fit_pin_align(&vec![blank; 12], &PreprocessConfig::lighting_compensated())
            .unwrap_err()
            .to_string();
        assert!(e.contains("found in 0 of 12 frames"), "{e}");
    }

    #[test]
    fn alignment_values_are_checked() {
        let ok = PinAlign {
            reference_deg: 1.0,
            tolerance_deg: 0.5,
            max_turn_deg: 20.0,
        };
        ok.check().unwrap();
        for bad in [
            PinAlign {
                reference_deg: f64::NAN,
                ..ok
            },
            PinAlign {
                tolerance_deg: -1.0,
                ..ok
            },
            PinAlign {
                max_turn_deg: 90.0,
                ..ok
            },
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
        }
    }
}
