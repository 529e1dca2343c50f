//! How a calibrated sensor's gel takes a press: inside the contact the
//! skin follows the object; around it the soft gel sinks too (a gap opens
//! between object and skin before the geometric edge, so the contact is
//! smaller than the overlap), and far from it the skin is at rest. The
//! classic calibrated simulators (Taxim) model the spread with Gaussian
//! smoothing of the object's overlap with the gel; here one Gaussian of
//! width `sigma_mm` and a gain at most 1 do it, fitted to the ball presses
//! (contact radius known, the gel around it reconstructed):
//!
//! `indentation = max(overlap, gain * blur(max(overlap, 0)), 0)`
//!
//! where `overlap = approach - s(x)` is how far the object's surface at
//! `x` lies past the skin's rest surface (`s` its height above its lowest
//! point; `-inf` off the object). The skin is never shallower than the
//! object (the object pushes it); where the smoothed push (the gel dragged
//! along) lies deeper than the object, skin and object have parted.

use serde::{Deserialize, Serialize};
use tactile_core::{Error, Result};

use crate::raster::{Border, gaussian_blur};

/// Widest spread, mm.
pub const MAX_SIGMA_MM: f64 = 10.0;

/// The gel's spread around a contact.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GelResponse {
    /// Width of the Gaussian spread, mm.
    pub sigma_mm: f64,
    /// Gain on the smoothed overlap, in (0, 1] (above 1 a wide flat press
    /// would push the skin deeper than the object).
    pub gain: f64,
}

impl GelResponse {
    /// Check a response read from a file.
    pub fn check(&self) -> Result<()> {
        if !(self.sigma_mm.is_finite() && self.sigma_mm > 0.0 && self.sigma_mm <= MAX_SIGMA_MM) {
            return Err(Error::Config(format!(
                "gel: sigma_mm must be in (0, {MAX_SIGMA_MM}], got {:?}",
                self.sigma_mm
            )));
        }
        if !(self.gain.is_finite() && self.gain > 0.0 && self.gain <= 1.0) {
            return Err(Error::Config(format!(
                "gel: gain must be in (0, 1], got {:?}",
                self.gain
            )));
        }
        Ok(())
    }

    /// The skin's indentation, mm, of an `overlap_mm` map (`w x h`,
    /// row-major, `step_mm` per pixel; `-inf` off the object).
    pub fn indentation_mm(
        &self,
        overlap_mm: &[f32],
        (w, h): (usize, usize),
        step_mm: f64,
    ) -> Vec<f32> {
        let positive: Vec<f32> = overlap_mm.iter().map(|v| v.max(0.0)).collect();
        let spread = smooth(positive, (w, h), self.sigma_mm / step_mm);
        overlap_mm
            .iter()
            .zip(&spread)
            .map(|(&o, &s)| o.max(self.gain as f32 * s).max(0.0))
            .collect()
    }

    /// A ball of radius `ball_mm` pressed to contact radius `contact_mm`:
    /// its approach and the radial profile of the indentation at `radii_mm`
    /// (`None` when this response cannot reach that contact).
    pub fn ball_profile(
        &self,
        ball_mm: f64,
        contact_mm: f64,
        radii_mm: &[f64],
    ) -> Option<(f64, Vec<f64>)> {
        let reach = radii_mm.iter().copied().fold(contact_mm, f64::max);
        let sweep = BallSweep::new(ball_mm, reach, self.sigma_mm);
        sweep.profile(self.gain, contact_mm, radii_mm)
    }

    /// The approach of a ball of radius `ball_mm` pressed to each of
    /// `contacts_mm` (`None` where this response cannot reach it): one sweep
    /// of approaches serves them all.
    pub fn ball_approaches(&self, ball_mm: f64, contacts_mm: &[f64]) -> Vec<Option<f64>> {
        let reach = contacts_mm.iter().copied().fold(0f64, f64::max);
        let sweep = BallSweep::new(ball_mm, reach, self.sigma_mm);
        contacts_mm
            .iter()
            .map(|&a| sweep.profile(self.gain, a, &[]).map(|p| p.0))
            .collect()
    }

    /// The response whose ball presses best match reconstructed ones
    /// (each of `presses`: a ball, its contact radius and the
    /// reconstruction's radial profile out to a few contact radii; the
    /// presses may be of several balls). A grid search over width and
    /// gain; returns the response and its mean |profile error|, mm.
    pub fn fit(presses: &[BallProfile]) -> Result<(Self, f64)> {
        if presses.is_empty() {
            return Err(Error::Config("gel: no presses to fit the spread on".into()));
        }
        // The balls pressed, each with how far its presses reach, and each
        // press's ball among them and the radii of its profile.
        let mut balls: Vec<(f64, f64)> = Vec::new();
        let mut reads: Vec<(usize, Vec<f64>)> = Vec::with_capacity(presses.len());
        for p in presses {
            let radii: Vec<f64> = p.profile.iter().map(|q| q.0).collect();
            let reach = radii.iter().copied().fold(p.contact_mm, f64::max);
            let ball = match balls.iter().position(|b| b.0 == p.ball_mm) {
                Some(b) => b,
                None => {
                    balls.push((p.ball_mm, 0.0));
                    balls.len() - 1
                }
            };
            balls[ball].1 = balls[ball].1.max(reach);
            reads.push((ball, radii));
        }
        let mut best: Option<(Self, f64)> = None;
        for si in 0..14 {
            let sigma_mm = 0.1 * 1.25f64.powi(si);
            // One sweep of approaches per ball and width serves every gain.
            let sweeps: Vec<BallSweep> = (balls.iter())
                .map(|&(ball_mm, reach)| BallSweep::new(ball_mm, reach, sigma_mm))
                .collect();
            for gi in 1..=20 {
                let gain = 0.05 * gi as f64;
                let (mut sum, mut n, mut ok) = (0.0, 0usize, true);
                for (p, (ball, radii)) in presses.iter().zip(&reads) {
                    let Some((_, model)) = sweeps[*ball].profile(gain, p.contact_mm, radii) else {
                        ok = false;
                        break;
                    };
                    for (m, (_, t)) in model.iter().zip(&p.profile) {
                        sum += (m - t).abs();
                        n += 1;
                    }
                }
                if !ok || n == 0 {
                    continue;
                }
                let err = sum / n as f64;
                if best.is_none_or(|(_, e)| err < e) {
                    best = Some((Self { sigma_mm, gain }, err));
                }
            }
        }
        best.ok_or_else(|| {
            Error::Config("gel: no spread reaches the presses' contact radii".into())
        })
    }
}

/// A ball press as the gel's fit reads it.
#[derive(Debug, Clone, PartialEq)]
pub struct BallProfile {
    /// The ball's radius, mm.
    pub ball_mm: f64,
    /// The contact circle's radius, mm.
    pub contact_mm: f64,
    /// The indentation's radial profile, `(r_mm, indentation_mm)` pairs.
    pub profile: Vec<(f64, f64)>,
}

/// A Gaussian blur of width `sigma_px` (zeros beyond the edges); a wide one
/// runs on a grid shrunk to about a third of it and is enlarged back
/// (both through `image`'s triangle filter), which a smooth field allows.
fn smooth(plane: Vec<f32>, (w, h): (usize, usize), sigma_px: f64) -> Vec<f32> {
    use image::imageops::{FilterType, resize};
    use image::{ImageBuffer, Luma};
    let k = ((sigma_px / 3.0).floor() as usize)
        .clamp(1, 16)
        .min(w.min(h) / 4)
        .max(1);
    if k == 1 {
        let mut out = plane;
        gaussian_blur(&mut out, w, h, sigma_px, Border::Zero);
        return out;
    }
    let (sw, sh) = (w.div_ceil(k), h.div_ceil(k));
    let Some(full) = ImageBuffer::<Luma<f32>, Vec<f32>>::from_raw(w as u32, h as u32, plane) else {
        return vec![0.0; w * h];
    };
    let small = resize(&full, sw as u32, sh as u32, FilterType::Triangle);
    let mut v = small.into_raw();
    gaussian_blur(
        &mut v,
        sw,
        sh,
        sigma_px * sw as f64 / w as f64,
        Border::Zero,
    );
    let Some(small) = ImageBuffer::<Luma<f32>, Vec<f32>>::from_raw(sw as u32, sh as u32, v) else {
        return vec![0.0; w * h];
    };
    resize(&small, w as u32, h as u32, FilterType::Triangle).into_raw()
}

/// Approaches below a 48th of the ball's radius, each half the last.
const SHALLOW_HALVINGS: i32 = 8;

/// A ball pressed at a sweep of approaches, each approach's smoothed
/// overlap along a radius: every gain's contact and profile follow from
/// it without blurring again.
struct BallSweep {
    ball_mm: f64,
    step_mm: f64,
    /// Approaches, mm, increasing.
    approaches: Vec<f64>,
    /// Per approach, the blurred positive overlap at radius `k * step_mm`.
    blurred: Vec<Vec<f32>>,
}

impl BallSweep {
    fn new(ball_mm: f64, reach_mm: f64, sigma_mm: f64) -> Self {
        let extent = reach_mm.max(ball_mm) + 3.0 * sigma_mm;
        let step_mm = (extent / 120.0).max(0.02);
        let half = (extent / step_mm).ceil() as usize;
        let side = 2 * half + 1;
        let height = |r: f64| (r < ball_mm).then(|| ball_mm - (ball_mm * ball_mm - r * r).sqrt());
        // Every 48th of the ball's radius, and below the first halvings of
        // it down to a 12288th: a large ball pressed shallow (12.5 mm,
        // 0.1 mm deep) touches within a 48th.
        let approaches: Vec<f64> = (1..=SHALLOW_HALVINGS)
            .rev()
            .map(|j| ball_mm / 48.0 * 0.5f64.powi(j))
            .chain((1..=48).map(|k| ball_mm * k as f64 / 48.0))
            .collect();
        let blurred = approaches
            .iter()
            .map(|&d| {
                let plane: Vec<f32> = (0..side * side)
                    .map(|i| {
                        let (x, y) = (
                            (i % side) as f64 - half as f64,
                            (i / side) as f64 - half as f64,
                        );
                        height(x.hypot(y) * step_mm).map_or(0.0, |s| (d - s).max(0.0) as f32)
                    })
                    .collect();
                let plane = smooth(plane, (side, side), sigma_mm / step_mm);
                plane[half * side + half..(half + 1) * side].to_vec()
            })
            .collect();
        Self {
            ball_mm,
            step_mm,
            approaches,
            blurred,
        }
    }

    /// The indentation along a radius at approach index `k` and `gain`.
    fn radial(&self, k: usize, gain: f64) -> Vec<f64> {
        let d = self.approaches[k];
        self.blurred[k]
            .iter()
            .enumerate()
            .map(|(i, &b)| {
                let r = i as f64 * self.step_mm;
                let overlap = match r < self.ball_mm {
                    true => d - (self.ball_mm - (self.ball_mm * self.ball_mm - r * r).sqrt()),
                    false => f64::NEG_INFINITY,
                };
                overlap.max(gain * b as f64).max(0.0)
            })
            .collect()
    }

    /// The contact radius of a radial indentation at approach index `k`:
    /// the farthest radius where the skin meets the ball (linear between
    /// samples).
    fn contact_mm(&self, k: usize, gain: f64) -> f64 {
        let d = self.approaches[k];
        let mut far = 0f64;
        for (i, &b) in self.blurred[k].iter().enumerate() {
            let r = i as f64 * self.step_mm;
            if r >= self.ball_mm {
                break;
            }
            let overlap = d - (self.ball_mm - (self.ball_mm * self.ball_mm - r * r).sqrt());
            if overlap > 0.0 && overlap >= gain * b as f64 {
                far = r;
            }
        }
        far
    }

    /// The approach and radial profile at `radii_mm` for contact radius
    /// `contact_mm`, interpolated between the two approaches around it.
    fn profile(&self, gain: f64, contact_mm: f64, radii_mm: &[f64]) -> Option<(f64, Vec<f64>)> {
        let contacts: Vec<f64> = (0..self.approaches.len())
            .map(|k| self.contact_mm(k, gain))
            .collect();
        let k = contacts
            .windows(2)
            .position(|w| w[0] <= contact_mm && contact_mm <= w[1])?;
        let span = contacts[k + 1] - contacts[k];
        let t = if span > 0.0 {
            (contact_mm - contacts[k]) / span
        } else {
            0.0
        };
        let (p0, p1) = (self.radial(k, gain), self.radial(k + 1, gain));
        let at = |p: &[f64], r: f64| {
            let x = r / self.step_mm;
            let i = (x.floor() as usize).min(p.len() - 1);
            let j = (i + 1).min(p.len() - 1);
            let f = x - i as f64;
            p[i] * (1.0 - f) + p[j] * f
        };
        let d = self.approaches[k] * (1.0 - t) + self.approaches[k + 1] * t;
        Some((
            d,
            radii_mm
                .iter()
                .map(|&r| at(&p0, r) * (1.0 - t) + at(&p1, r) * t)
                .collect(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ball_press_follows_the_ball_inside_and_sinks_around_it() {
        let gel = GelResponse {
            sigma_mm: 0.6,
            gain: 0.7,
        };
        gel.check().unwrap();
        let radii: Vec<f64> = (0..=40).map(|k| k as f64 * 0.15).collect();
        let (approach, p) = gel.ball_profile(2.0, 1.8, &radii).unwrap();
        // Deepest at the centre (the approach), the rim sunk, at rest far off.
        assert!((p[0] - approach).abs() < 1e-3, "{} {approach}", p[0]);
        let rim = p[12];
        assert!(rim > 0.1 && rim < approach, "{rim}");
        assert!(p[40] < 0.05 * approach, "{}", p[40]);
        assert!(p.windows(2).all(|w| w[1] <= w[0] + 1e-6));
        // The fit recovers the response that made a set of profiles, of
        // presses of a ball of `ball_mm` to `contacts`, each reached at an
        // approach below `deepest`.
        let recovers = |balls_mm: [f64; 2], contacts: [f64; 2], deepest: f64, within: f64| {
            let presses: Vec<BallProfile> = (balls_mm.iter().zip(contacts))
                .map(|(&ball_mm, a)| {
                    let (approach, prof) = gel.ball_profile(ball_mm, a, &radii).unwrap();
                    assert!(approach < deepest, "{approach}");
                    BallProfile {
                        ball_mm,
                        contact_mm: a,
                        profile: radii.iter().copied().zip(prof).collect(),
                    }
                })
                .collect();
            let (fit, err) = GelResponse::fit(&presses).unwrap();
            assert!(err < within, "{err}");
            assert!(
                (fit.sigma_mm - 0.6).abs() < 0.2 && (fit.gain - 0.7).abs() < 0.15,
                "{fit:?}"
            );
        };
        recovers([2.0; 2], [1.6, 1.8], 2.0, 0.03);
        // A large ball pressed shallow (25 mm, 0.09-0.16 mm deep: within a
        // 48th of its radius) is reached and fitted too; before, no
        // approach of the sweep was that shallow and the fit failed.
        recovers([12.5; 2], [1.5, 2.0], 12.5 / 48.0, 0.01);
        // Presses of two balls, each profile its own ball's.
        recovers([2.0, 3.0], [1.6, 1.8], 2.0, 0.03);
        assert!(
            GelResponse {
                sigma_mm: -1.0,
                gain: 0.5
            }
            .check()
            .is_err()
        );
        assert!(
            GelResponse {
                sigma_mm: 1.0,
                gain: 1.5
            }
            .check()
            .is_err()
        );
    }
}
