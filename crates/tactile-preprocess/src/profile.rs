//! Is this a frame of the sensor the models were trained on? A few input
//! statistics per frame (an [`InputProfile`]'s descriptor) against their
//! spread over the training frames: frames far outside it (another
//! sensor, a uniform or natural image, the camera out of its housing) are
//! flagged instead of getting a confident answer.
//!
//! The descriptor reads the frame as the detector sees it (resized to its
//! input, 8 bits per channel): inside the sensing window (the inscribed
//! ellipse, away from its edge) the mean of each channel, the spread and
//! the fine texture of the brightness, and the colour balance; outside it
//! (the dark housing) the brightness and its spread.

use serde::{Deserialize, Serialize};

use crate::visuo::FloatImage;
use crate::{Error, Result};

/// The descriptor's values, in order.
pub const DESCRIPTOR: [&str; 9] = [
    "window mean red",
    "window mean green",
    "window mean blue",
    "window brightness spread",
    "window fine texture",
    "window red - green",
    "window blue - green",
    "housing brightness",
    "housing brightness spread",
];

/// The smallest spread a statistic is measured against, in [0, 1] pixel
/// units: a statistic that hardly varies in training still allows this.
pub const MIN_SCALE: f32 = 0.02;

/// Luma weights (ITU-R BT.601) of red, green and blue: the brightness the
/// descriptor reads.
pub const LUMA: [f32; 3] = [0.299, 0.587, 0.114];

/// Where the descriptor reads a `width x height` frame: the one
/// definition of its regions, used by [`descriptor`] and by the standalone
/// ONNX export's graph of it.
#[derive(Debug, Clone, PartialEq)]
pub struct Regions {
    /// Pixels (row-major) inside the sensing window, away from its edge.
    pub window: Vec<bool>,
    /// Window pixels with four neighbours (where the fine texture, a
    /// Laplacian, is read).
    pub texture: Vec<bool>,
    /// Pixels of the dark housing, well outside the window.
    pub housing: Vec<bool>,
}

impl Regions {
    /// The regions of a `width x height` frame: in the inscribed ellipse's
    /// normalised radius r, the window is r^2 <= 0.8, the housing r^2 >= 1.3.
    pub fn of(width: usize, height: usize) -> Self {
        let n = width * height;
        let mut r = Self {
            window: vec![false; n],
            texture: vec![false; n],
            housing: vec![false; n],
        };
        for y in 0..height {
            let v = (y as f32 + 0.5) / height as f32 - 0.5;
            for x in 0..width {
                let i = y * width + x;
                let u = (x as f32 + 0.5) / width as f32 - 0.5;
                let r2 = 4.0 * (u * u + v * v);
                if r2 <= 0.8 {
                    r.window[i] = true;
                    r.texture[i] = x > 0 && y > 0 && x + 1 < width && y + 1 < height;
                } else if r2 >= 1.3 {
                    r.housing[i] = true;
                }
            }
        }
        r
    }
}

/// The descriptor of an RGB image in [0, 1] (at least 8 x 8).
pub fn descriptor(img: &FloatImage) -> Result<Vec<f32>> {
    let (w, h) = (img.width, img.height);
    if img.channels != 3 || w < 8 || h < 8 {
        return Err(Error::Channels {
            expected: 3,
            found: img.channels,
        });
    }
    let luma: Vec<f32> = img
        .data
        .chunks_exact(3)
        .map(|p| LUMA[0] * p[0] + LUMA[1] * p[1] + LUMA[2] * p[2])
        .collect();
    let regions = Regions::of(w, h);
    let (mut inside, mut outside) = (Vec::with_capacity(w * h), Vec::new());
    let mut texture = Vec::with_capacity(w * h);
    let mut rgb = [0f64; 3];
    for i in 0..w * h {
        if regions.window[i] {
            inside.push(luma[i]);
            for (c, acc) in rgb.iter_mut().enumerate() {
                *acc += img.data[i * 3 + c] as f64;
            }
        } else if regions.housing[i] {
            outside.push(luma[i]);
        }
        if regions.texture[i] {
            let lap = 4.0 * luma[i] - luma[i - 1] - luma[i + 1] - luma[i - w] - luma[i + w];
            texture.push(lap.abs());
        }
    }
    let n = inside.len().max(1) as f64;
    let mean_sd = |v: &[f32]| {
        let n = v.len().max(1) as f64;
        let m = v.iter().map(|&x| x as f64).sum::<f64>() / n;
        let var = v.iter().map(|&x| (x as f64 - m).powi(2)).sum::<f64>() / n;
        (m as f32, var.sqrt() as f32)
    };
    let (_, spread) = mean_sd(&inside);
    let (tex, _) = mean_sd(&texture);
    let (house, house_sd) = mean_sd(&outside);
    let [r, g, b] = rgb.map(|v| (v / n) as f32);
    Ok(vec![r, g, b, spread, tex, r - g, b - g, house, house_sd])
}

/// The training frames' descriptors summarised: per statistic a centre
/// (median) and a scale (1.4826 x the median absolute deviation, at least
/// [`MIN_SCALE`]); a frame's score is its largest distance from the centre
/// in scales, and a frame scoring above `threshold` is out of distribution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InputProfile {
    /// What each value is ([`DESCRIPTOR`]).
    pub names: Vec<String>,
    /// Per statistic, the training median.
    pub centre: Vec<f32>,
    /// Per statistic, the training spread.
    pub scale: Vec<f32>,
    /// Scores above this are out of distribution.
    pub threshold: f32,
    /// Training frames it was fitted on.
    pub frames: usize,
}

impl InputProfile {
    /// One line for a person: how many frames it was fitted on and where it
    /// flags a frame.
    pub fn describe(&self) -> String {
        format!(
            "input profile of {} frames: flags scores above {:.1}",
            self.frames, self.threshold
        )
    }

    /// Fewest training frames a profile is fitted on.
    pub const MIN_FRAMES: usize = 20;

    /// Fit on the descriptors of the training frames: the threshold is
    /// `margin` times their 99.9th-percentile score (at least 6 scales).
    pub fn fit(descriptors: &[Vec<f32>], margin: f32) -> Result<Self> {
        let k = DESCRIPTOR.len();
        if descriptors.len() < Self::MIN_FRAMES || descriptors.iter().any(|d| d.len() != k) {
            return Err(Error::Core(tactile_core::Error::Invalid(format!(
                "an input profile needs at least {} frames with {k} statistics each, got {}",
                Self::MIN_FRAMES,
                descriptors.len()
            ))));
        }
        let median = |mut v: Vec<f32>| {
            v.sort_by(f32::total_cmp);
            v[v.len() / 2]
        };
        let centre: Vec<f32> = (0..k)
            .map(|i| median(descriptors.iter().map(|d| d[i]).collect()))
            .collect();
        let scale: Vec<f32> = (0..k)
            .map(|i| {
                let mad = median(
                    descriptors
                        .iter()
                        .map(|d| (d[i] - centre[i]).abs())
                        .collect(),
                );
                (1.4826 * mad).max(MIN_SCALE)
            })
            .collect();
        let mut p = Self {
            names: DESCRIPTOR.iter().map(|s| s.to_string()).collect(),
            centre,
            scale,
            threshold: f32::INFINITY,
            frames: descriptors.len(),
        };
        let mut scores: Vec<f32> = descriptors.iter().map(|d| p.score(d)).collect();
        scores.sort_by(f32::total_cmp);
        let q = scores[((scores.len() - 1) as f64 * 0.999).round() as usize];
        p.threshold = (margin * q).max(6.0);
        Ok(p)
    }

    /// How far a descriptor lies from the training frames: its largest
    /// distance from the centre, in scales.
    pub fn score(&self, descriptor: &[f32]) -> f32 {
        descriptor
            .iter()
            .zip(self.centre.iter().zip(&self.scale))
            .map(|(d, (c, s))| ((d - c) / s).abs())
            .fold(0.0, f32::max)
    }

    /// Check a loaded profile: as many centres and scales as statistics,
    /// all finite, scales positive, a positive threshold.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let k = DESCRIPTOR.len();
        if self.centre.len() != k || self.scale.len() != k {
            return Err(format!(
                "input profile: {} centres and {} scales, {k} statistics expected",
                self.centre.len(),
                self.scale.len()
            ));
        }
        if self.centre.iter().any(|v| !v.is_finite())
            || self.scale.iter().any(|v| !(v.is_finite() && *v > 0.0))
            || !(self.threshold.is_finite() && self.threshold > 0.0)
        {
            return Err(
                "input profile: centres must be finite, scales and the threshold positive".into(),
            );
        }
        Ok(())
    }
}
