//! Changes of camera conditions applied to raw TacTip frames (paper A,
//! section V): more sensor noise, an illumination gradient, an external
//! light blob, a rotated mounting. The robustness study measures how every
//! estimator's error grows under each.

use tactile_core::image_io::GreyImage;
use tactile_core::rng::SampleRng;

use crate::Result;

/// `levels` (grey levels, or a colour frame's channels) with Gaussian
/// sensor noise of `sigma` levels, one draw each in order, rounded and
/// kept in 0-255: [`Perturbation::Noise`], and the noisier camera of
/// `tactile bench own-sensor`.
pub fn add_noise(levels: &[u8], sigma: f64, rng: &mut SampleRng) -> Vec<u8> {
    levels
        .iter()
        .map(|&s| (s as f64 + sigma * rng.normal()).round().clamp(0.0, 255.0) as u8)
        .collect()
}

/// A change of camera conditions applied to raw frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Perturbation {
    /// Extra Gaussian sensor noise.
    Noise {
        /// Standard deviation, grey levels.
        sigma: f64,
    },
    /// A linear gain ramp `1 + slope * r` across the frame (r in [-1, 1]
    /// along a random direction) on top of the sensor's own.
    Gradient {
        /// Gain change at the frame's edge.
        slope: f64,
    },
    /// An external Gaussian light blob of this amplitude (grey levels),
    /// sigma 30 px, centred somewhere within 100 px of the middle.
    Blob {
        /// Peak, grey levels.
        amplitude: f64,
    },
    /// The sensor turned about the camera axis.
    Rotation {
        /// Angle, degrees.
        deg: f64,
    },
}

impl Perturbation {
    /// The study: three strengths of each (the clean frames come first).
    pub fn study() -> Vec<(&'static str, Vec<Perturbation>)> {
        use Perturbation::*;
        vec![
            (
                "noise",
                [6.0, 12.0, 24.0].map(|sigma| Noise { sigma }).to_vec(),
            ),
            (
                "gradient",
                [0.3, 0.6, 0.9].map(|slope| Gradient { slope }).to_vec(),
            ),
            (
                "blob",
                [60.0, 120.0, 180.0]
                    .map(|amplitude| Blob { amplitude })
                    .to_vec(),
            ),
            (
                "rotation",
                [2.0, 5.0, 10.0].map(|deg| Rotation { deg }).to_vec(),
            ),
        ]
    }

    /// Human-readable strength.
    pub fn describe(&self) -> String {
        match *self {
            Self::Noise { sigma } => format!("noise sigma {sigma} grey levels"),
            Self::Gradient { slope } => format!("gain gradient +-{:.0} %", 100.0 * slope),
            Self::Blob { amplitude } => format!("light blob {amplitude} grey levels"),
            Self::Rotation { deg } => format!("rotated {deg} deg"),
        }
    }

    /// Apply to one frame; `rng` makes the random parts (noise, direction,
    /// position) reproducible per frame.
    pub fn apply(&self, img: &GreyImage, rng: &mut SampleRng) -> Result<GreyImage> {
        let (w, h) = (img.width(), img.height());
        let src = img.as_slice();
        let (cu, cv) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
        let half = cu.max(cv).max(1.0);
        let mut out = vec![0u8; w * h];
        match *self {
            Self::Noise { sigma } => out = add_noise(src, sigma, rng),
            Self::Gradient { slope } => {
                let a = 2.0 * std::f64::consts::PI * rng.uniform();
                let (du, dv) = (a.cos(), a.sin());
                for (k, o) in out.iter_mut().enumerate() {
                    let (u, v) = ((k % w) as f64 - cu, (k / w) as f64 - cv);
                    let r = (u * du + v * dv) / half;
                    *o = (src[k] as f64 * (1.0 + slope * r))
                        .round()
                        .clamp(0.0, 255.0) as u8;
                }
            }
            Self::Blob { amplitude } => {
                let (a, d) = (
                    2.0 * std::f64::consts::PI * rng.uniform(),
                    100.0 * rng.uniform().sqrt(),
                );
                let (bu, bv) = (cu + d * a.cos(), cv + d * a.sin());
                for (k, o) in out.iter_mut().enumerate() {
                    let (u, v) = ((k % w) as f64 - bu, (k / w) as f64 - bv);
                    let g = (-(u * u + v * v) / (2.0 * 30.0 * 30.0)).exp();
                    *o = (src[k] as f64 + amplitude * g).round().clamp(0.0, 255.0) as u8;
                }
            }
            Self::Rotation { deg } => {
                // Inverse mapping with bilinear interpolation; outside -> 0.
                let (s, c) = deg.to_radians().sin_cos();
                let at = |x: isize, y: isize| -> f64 {
                    if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
                        0.0
                    } else {
                        src[y as usize * w + x as usize] as f64
                    }
                };
                for (k, o) in out.iter_mut().enumerate() {
                    let (u, v) = ((k % w) as f64 - cu, (k / w) as f64 - cv);
                    let (x, y) = (c * u + s * v + cu, -s * u + c * v + cv);
                    let (x0, y0) = (x.floor(), y.floor());
                    let (fx, fy) = (x - x0, y - y0);
                    let (x0, y0) = (x0 as isize, y0 as isize);
                    let v = at(x0, y0) * (1.0 - fx) * (1.0 - fy)
                        + at(x0 + 1, y0) * fx * (1.0 - fy)
                        + at(x0, y0 + 1) * (1.0 - fx) * fy
                        + at(x0 + 1, y0 + 1) * fx * fy;
                    *o = v.round().clamp(0.0, 255.0) as u8;
                }
            }
        }
        Ok(tactile_core::image_io::grey_image(w, h, out)?)
    }
}

/// Most turned copies of each training frame.
pub const MAX_ROTATED_COPIES: usize = 32;

/// The largest turn of rotation augmentation when none is asked for,
/// degrees: a little past the 5 degrees a hand-mounted sensor is off by.
pub const DEFAULT_ROTATION_DEG: f64 = 6.0;

/// Largest augmentation angle accepted, degrees.
pub const MAX_ROTATION_DEG: f64 = 45.0;

/// Rotation augmentation of training frames: besides each frame as it is,
/// a model sees `copies` versions of it turned about the camera axis by
/// angles uniform in `[-max_deg, max_deg]`, as a sensor mounted turned
/// would show it. Frames are turned before preprocessing, the way
/// [`Perturbation::Rotation`] turns them in the robustness study.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RotationAugment {
    /// Turned copies of each training frame.
    pub copies: usize,
    /// Largest angle, degrees.
    pub max_deg: f64,
    /// Seed of the angles.
    pub seed: u64,
}

impl RotationAugment {
    /// `copies` turned copies up to `max_deg` degrees, or none when
    /// `copies` is 0 (a front end's flags as given).
    pub fn optional(copies: usize, max_deg: f64, seed: u64) -> Option<Self> {
        (copies > 0).then_some(Self {
            copies,
            max_deg,
            seed,
        })
    }

    /// Check the copies (1 to [`MAX_ROTATED_COPIES`]) and the angle (above
    /// 0, at most [`MAX_ROTATION_DEG`]).
    pub fn check(&self) -> Result<()> {
        if !(1..=MAX_ROTATED_COPIES).contains(&self.copies) {
            return Err(tactile_core::Error::Config(format!(
                "rotation augmentation: copies must be 1 to {MAX_ROTATED_COPIES}, got {}",
                self.copies
            ))
            .into());
        }
        if !(self.max_deg > 0.0 && self.max_deg <= MAX_ROTATION_DEG) {
            return Err(tactile_core::Error::Config(format!(
                "rotation augmentation: the largest angle must be above 0 and at most {MAX_ROTATION_DEG} degrees, got {:?}",
                self.max_deg
            ))
            .into());
        }
        Ok(())
    }

    /// The angle of copy `copy` of dataset row `row`, degrees.
    pub fn angle_deg(&self, row: usize, copy: usize) -> f64 {
        let mut rng = SampleRng::new(self.seed, copy as u64, row as u64);
        self.max_deg * (2.0 * rng.uniform() - 1.0)
    }

    /// The pin images of the turned copies of `frame` (dataset row `row`).
    pub fn pins(
        &self,
        frame: &GreyImage,
        row: usize,
        cfg: &crate::PreprocessConfig,
    ) -> Result<Vec<crate::PinImage>> {
        (0..self.copies)
            .map(|k| {
                let deg = self.angle_deg(row, k);
                // A rotation draws nothing from its stream.
                let turned =
                    Perturbation::Rotation { deg }.apply(frame, &mut SampleRng::new(0, 0, 0))?;
                crate::preprocess(&turned, cfg)
            })
            .collect()
    }

    /// [`Self::pins`] of the frames at `rows` of `ds`, in parallel; an
    /// error names the frame's file.
    pub fn dataset_pins(
        &self,
        ds: &tactile_core::dataset::Dataset,
        rows: &[usize],
        cfg: &crate::PreprocessConfig,
    ) -> Result<Vec<Vec<crate::PinImage>>> {
        use rayon::prelude::*;
        self.check()?;
        rows.par_iter()
            .map(|&i| {
                let frame = ds.load_grey(i, "file")?;
                self.pins(&frame, i, cfg)
                    .map_err(|e| e.in_file(ds.path_of(i, "file").unwrap_or_default()))
            })
            .collect()
    }
}

/// Largest whole-image shift of a pin image in training, a fraction of its
/// side.
pub const MAX_SHIFT: f64 = 0.25;

/// Check a training shift: a fraction of the side in `[0, MAX_SHIFT]`.
pub fn check_shift(fraction: f64) -> tactile_core::Result<()> {
    if !(0.0..=MAX_SHIFT).contains(&fraction) {
        return Err(tactile_core::Error::Config(format!(
            "augmentation shift must be in [0, {MAX_SHIFT}] of the side, got {fraction:?}"
        )));
    }
    Ok(())
}

/// Shift the square pin image `pixels` by whole pixels `(dx, dy)`, each
/// drawn uniformly up to `fraction` of the side, the uncovered border
/// black. The camera, fixed to the tip, never moves like this, so a
/// network trained on shifted images must read where pins sit relative to
/// each other, not where in the image. Draws two numbers from `rng`.
pub fn shift_pins(pixels: &mut [f32], fraction: f64, rng: &mut SampleRng) {
    let side = pixels.len().isqrt();
    let most = fraction * side as f64;
    let dx = (most * (2.0 * rng.uniform() - 1.0)).round() as isize;
    let dy = (most * (2.0 * rng.uniform() - 1.0)).round() as isize;
    if dx == 0 && dy == 0 {
        return;
    }
    let src = pixels.to_vec();
    let s = side as isize;
    for y in 0..s {
        for x in 0..s {
            let (sx, sy) = (x - dx, y - dy);
            pixels[(y * s + x) as usize] = if (0..s).contains(&sx) && (0..s).contains(&sy) {
                src[(sy * s + sx) as usize]
            } else {
                0.0
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_augment_checks_its_flags_and_draws_seeded_angles_in_range() {
        assert!(RotationAugment::optional(0, 6.0, 1).is_none());
        let aug = RotationAugment::optional(4, 6.0, 1).unwrap();
        aug.check().unwrap();
        let angles: Vec<f64> = (0..50)
            .flat_map(|r| (0..4).map(move |k| (r, k)))
            .map(|(r, k)| aug.angle_deg(r, k))
            .collect();
        assert!(angles.iter().all(|a| a.abs() <= 6.0));
        assert!(angles.iter().any(|&a| a > 3.0) && angles.iter().any(|&a| a < -3.0));
        assert_eq!(aug.angle_deg(7, 2), aug.angle_deg(7, 2));
        assert_ne!(aug.angle_deg(7, 2), aug.angle_deg(7, 3));
        for bad in [
            RotationAugment { copies: 33, ..aug },
            RotationAugment {
                max_deg: 0.0,
                ..aug
            },
            RotationAugment {
                max_deg: f64::NAN,
                ..aug
            },
            RotationAugment {
                max_deg: 90.0,
                ..aug
            },
        ] {
            let e = bad.check().unwrap_err().to_string();
            assert!(e.contains("rotation augmentation"), "{e}");
        }
    }

    #[test]
    fn perturbations_keep_the_size_and_are_seeded() {
        let img = tactile_core::image_io::grey_image(
            40,
            30,
            (0..1200).map(|i| (i % 251) as u8).collect(),
        )
        .unwrap();
        for (_, levels) in Perturbation::study() {
            for p in levels {
                let a = p.apply(&img, &mut SampleRng::new(1, 2, 3)).unwrap();
                let b = p.apply(&img, &mut SampleRng::new(1, 2, 3)).unwrap();
                assert_eq!((a.width(), a.height()), (40, 30));
                assert_eq!(a.as_slice(), b.as_slice(), "{}", p.describe());
                assert_ne!(a.as_slice(), img.as_slice(), "{}", p.describe());
            }
        }
    }
}
