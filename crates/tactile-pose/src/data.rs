//! Grey pin images with their pose labels, and the augmentation that keeps
//! the labels true: brightness gain and offset and sensor noise change how
//! a frame looks, never where the contact is; an optional small shift of
//! the whole image (which the camera, fixed to the tip, never makes) leaves
//! the pins' places relative to each other, so a network trained with it
//! must read those rather than where in the image a pin sits. Half-turn
//! copies, for a tip whose picture survives half a turn, train the targets
//! a half turn maps to themselves or their negatives.

use burn::config::Config;
use burn::tensor::{Device, Tensor, TensorData};
use tactile_cae::data::PinSet;
use tactile_core::dataset::Dataset;
use tactile_core::rng::SampleRng;
use tactile_estimate::Target;
use tactile_preprocess::PreprocessConfig;

use crate::Result;

pub use tactile_preprocess::perturb::MAX_SHIFT;

/// Label-preserving augmentation of a grey pin image.
#[derive(Config, Debug, PartialEq)]
pub struct Augment {
    /// Brightness gain drawn from `1 +- gain`.
    #[config(default = 0.1)]
    pub gain: f64,
    /// Brightness offset drawn from `+- offset`.
    #[config(default = 0.05)]
    pub offset: f64,
    /// Standard deviation of per-pixel Gaussian noise.
    #[config(default = 0.02)]
    pub noise: f64,
    /// Largest shift of the whole image along each axis, as a fraction of
    /// its side (whole pixels, the uncovered border black; absent: none).
    #[config(default = "None")]
    pub shift: Option<f64>,
    /// Half-turn copies: in each epoch each frame is turned 180 degrees
    /// about the pin image's centre with probability 1/2, and a turned
    /// copy trains only the targets named here, each label times its
    /// value, what a half turn of the rig multiplies it by (1 or -1); the
    /// other targets are left out of its loss (absent: no turn).
    #[config(default = "None")]
    pub half_turn: Option<std::collections::BTreeMap<String, f64>>,
}

/// The random stream of the half-turn draws, apart from the other
/// augmentations' (so adding it changes none of their draws).
const HALF_TURN_STREAM: u64 = 0x4841_4c46_5455_524e;

impl Augment {
    /// No change at all.
    pub fn none() -> Self {
        Self::new().with_gain(0.0).with_offset(0.0).with_noise(0.0)
    }

    /// The largest shift as a fraction of the side (0 when absent).
    fn shift_fraction(&self) -> f64 {
        self.shift.unwrap_or(0.0)
    }

    /// Whether brightness and noise are left alone.
    fn is_photometric_none(&self) -> bool {
        self.gain == 0.0 && self.offset == 0.0 && self.noise == 0.0
    }

    /// Check the amounts (each in [0, 1]) and the half turn's signs (each
    /// 1 or -1, at least one target).
    pub fn check(&self) -> tactile_core::Result<()> {
        tactile_burn::train::check_augment_amounts(&[
            ("gain", self.gain),
            ("offset", self.offset),
            ("noise", self.noise),
        ])?;
        tactile_preprocess::perturb::check_shift(self.shift_fraction())?;
        match &self.half_turn {
            Some(signs) if signs.is_empty() => Err(tactile_core::Error::Config(
                "half_turn: name at least one target the turned copies train".into(),
            )),
            Some(signs) => match signs.iter().find(|(_, v)| **v != 1.0 && **v != -1.0) {
                Some((name, v)) => Err(tactile_core::Error::Config(format!(
                    "half_turn: {name}'s sign must be 1 or -1 (what a half turn multiplies it by), got {v:?}"
                ))),
                None => Ok(()),
            },
            None => Ok(()),
        }
    }

    /// Whether frame `index` is turned half a turn in epoch `round` under
    /// `seed` (never without [`Self::half_turn`]).
    pub fn turns(&self, (seed, round): (u64, u64), index: usize) -> bool {
        self.half_turn.is_some()
            && SampleRng::new(seed ^ HALF_TURN_STREAM, round, index as u64).chance(0.5)
    }

    /// `pixels` (a square image) augmented with the draws of `rng`,
    /// clipped to [0, 1].
    pub fn apply(&self, pixels: &mut [f32], rng: &mut SampleRng) {
        if self.shift_fraction() == 0.0 && self.is_photometric_none() {
            return;
        }
        if self.shift_fraction() > 0.0 {
            tactile_preprocess::perturb::shift_pins(pixels, self.shift_fraction(), rng);
        }
        if self.is_photometric_none() {
            return;
        }
        let gain = 1.0 + self.gain * (2.0 * rng.uniform() - 1.0);
        let offset = self.offset * (2.0 * rng.uniform() - 1.0);
        for p in pixels {
            let v = *p as f64 * gain + offset + self.noise * rng.normal();
            *p = v.clamp(0.0, 1.0) as f32;
        }
    }
}

/// Pin images of a TacTip dataset with one label row per frame.
pub struct PoseSet {
    /// The frames' pin images.
    pub pins: PinSet,
    /// Per frame, one value per target in the labels' units (`None` when a
    /// label is empty).
    pub labels: Vec<Vec<Option<f64>>>,
}

impl PoseSet {
    /// Preprocess every frame of `ds` and read `targets`' columns.
    pub fn from_dataset(ds: &Dataset, cfg: &PreprocessConfig, targets: &[Target]) -> Result<Self> {
        Self::from_rows(ds, &ds.every_row(), cfg, targets)
    }

    /// [`Self::from_dataset`] of the frames at `rows` alone (set row `k` is
    /// dataset row `rows[k]`), so scoring a split reads only its frames.
    pub fn from_rows(
        ds: &Dataset,
        rows: &[usize],
        cfg: &PreprocessConfig,
        targets: &[Target],
    ) -> Result<Self> {
        Self::from_pins(ds, rows, PinSet::from_rows(ds, rows, cfg)?, targets)
    }

    /// The set of `pins` already made of the frames at `rows`, with
    /// `targets`' columns read.
    pub fn from_pins(
        ds: &Dataset,
        rows: &[usize],
        pins: PinSet,
        targets: &[Target],
    ) -> Result<Self> {
        let labels = rows
            .iter()
            .map(|&i| {
                targets
                    .iter()
                    .map(|t| ds.target_opt(i, &t.name))
                    .collect::<tactile_core::Result<Vec<_>>>()
            })
            .collect::<tactile_core::Result<Vec<_>>>()?;
        Ok(Self { pins, labels })
    }

    /// Rows of `rows` with every target labelled.
    pub fn labelled(&self, rows: &[usize]) -> Vec<usize> {
        rows.iter()
            .copied()
            .filter(|&i| self.labels[i].iter().all(|v| v.is_some_and(f64::is_finite)))
            .collect()
    }

    /// Label rows of `rows` (all labelled; see [`Self::labelled`]).
    pub fn label_rows(&self, rows: &[usize]) -> Vec<Vec<f64>> {
        rows.iter()
            .map(|&i| {
                self.labels[i]
                    .iter()
                    .map(|v| v.unwrap_or(f64::NAN))
                    .collect()
            })
            .collect()
    }

    /// A `[N, 1, S, S]` batch of the images at `idx`, augmented with
    /// streams of `seed` keyed by `round` (the epoch) and each frame, and
    /// which of them it turned half a turn (whose labels the loss turns:
    /// drawn here once, for both).
    pub fn batch(
        &self,
        idx: &[usize],
        augment: &Augment,
        (seed, round): (u64, u64),
        device: &Device,
    ) -> (Tensor<4>, Vec<bool>) {
        let side = self.pins.images.first().map_or(0, |p| p.side);
        let mut data = Vec::with_capacity(idx.len() * side * side);
        let mut turned = Vec::with_capacity(idx.len());
        for &i in idx {
            let mut px = self.pins.images[i].pixels.clone();
            let turn = augment.turns((seed, round), i);
            if turn {
                // Row-major and square: a half turn about the centre is the
                // pixels in reverse order.
                px.reverse();
            }
            augment.apply(&mut px, &mut SampleRng::new(seed, round, i as u64));
            data.extend(px);
            turned.push(turn);
        }
        let x = Tensor::from_data(TensorData::new(data, [idx.len(), 1, side, side]), device);
        (x, turned)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn augmentation_is_seeded_bounded_and_off_when_zero() {
        let a = Augment::new();
        let mut x = vec![0.5f32; 100];
        let mut y = x.clone();
        a.apply(&mut x, &mut SampleRng::new(1, 2, 3));
        a.apply(&mut y, &mut SampleRng::new(1, 2, 3));
        assert_eq!(x, y);
        assert!(x.iter().all(|v| (0.0..=1.0).contains(v)));
        assert!(x.iter().any(|&v| (v - 0.5).abs() > 1e-3));
        let mut z = vec![0.5f32; 100];
        Augment::none().apply(&mut z, &mut SampleRng::new(1, 2, 3));
        assert!(z.iter().all(|&v| v == 0.5));
        assert!(Augment::new().with_noise(2.0).check().is_err());
    }

    #[test]
    fn a_half_turn_turns_about_half_the_frames_about_the_centre() {
        let signs = std::collections::BTreeMap::from([("shear_x_mm".to_string(), -1.0)]);
        let a = Augment::none().with_half_turn(Some(signs));
        a.check().unwrap();
        // About half the frames of an epoch, drawn again alike, other
        // frames in another epoch.
        let turned: Vec<bool> = (0..1000).map(|i| a.turns((7, 1), i)).collect();
        let n = turned.iter().filter(|&&t| t).count();
        assert!((400..600).contains(&n), "{n} of 1000");
        assert_eq!(
            turned,
            (0..1000).map(|i| a.turns((7, 1), i)).collect::<Vec<_>>()
        );
        assert_ne!(
            turned,
            (0..1000).map(|i| a.turns((7, 2), i)).collect::<Vec<_>>()
        );
        assert!(!(0..1000).any(|i| Augment::new().turns((7, 1), i)));
        // A turned 3x3 image: pixel (r, c) comes from (2 - r, 2 - c).
        let image: Vec<f32> = (0..9).map(|v| v as f32 / 10.0).collect();
        let set = PoseSet {
            pins: PinSet {
                files: vec!["a".into(); 40],
                rows: Vec::new(),
                flat: Vec::new(),
                images: vec![
                    tactile_preprocess::PinImage {
                        side: 3,
                        pixels: image.clone(),
                    };
                    40
                ],
            },
            labels: vec![vec![Some(0.0)]; 40],
        };
        let idx: Vec<usize> = (0..40).collect();
        let dev = Default::default();
        let (batch, turned) = set.batch(&idx, &a, (7, 1), &dev);
        let batch: Vec<f32> = batch
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .unwrap();
        for (i, px) in batch.chunks(9).enumerate() {
            assert_eq!(turned[i], a.turns((7, 1), i), "frame {i}");
            let want: Vec<f32> = match turned[i] {
                true => (0..9).map(|k| image[8 - k]).collect(),
                false => image.clone(),
            };
            assert_eq!(px, want.as_slice(), "frame {i}");
        }
        // Signs other than 1 and -1, or no target, are refused.
        for bad in [vec![("x".to_string(), 0.5)], vec![]] {
            let a = Augment::none().with_half_turn(Some(bad.into_iter().collect()));
            assert!(a.check().is_err());
        }
    }

    #[test]
    fn shift_moves_whole_pixels_and_blacks_the_border() {
        // A 10x10 ramp; a shift of up to 0.2 of the side is at most 2 px.
        let ramp: Vec<f32> = (0..100).map(|i| i as f32 / 100.0).collect();
        let a = Augment::none().with_shift(Some(0.2));
        a.check().unwrap();
        let mut moved = 0;
        for k in 0..40 {
            let mut x = ramp.clone();
            a.apply(&mut x, &mut SampleRng::new(7, 1, k));
            let mut y = ramp.clone();
            a.apply(&mut y, &mut SampleRng::new(7, 1, k));
            assert_eq!(x, y, "seeded");
            // Some whole-pixel shift (dx, dy) of at most 2 explains every pixel.
            let (dx, dy) = (0..5)
                .flat_map(|dy| (0..5).map(move |dx| (dx as isize - 2, dy as isize - 2)))
                .find(|&(dx, dy)| {
                    (0..10).all(|yy: isize| {
                        (0..10).all(|xx: isize| {
                            let (sx, sy) = (xx - dx, yy - dy);
                            let want = if (0..10).contains(&sx) && (0..10).contains(&sy) {
                                ramp[(sy * 10 + sx) as usize]
                            } else {
                                0.0
                            };
                            x[(yy * 10 + xx) as usize] == want
                        })
                    })
                })
                .expect("a whole-pixel shift of at most 2 with a black border");
            moved += usize::from(dx != 0 || dy != 0);
        }
        assert!(moved > 20, "most draws move the image ({moved} of 40)");
        // Without a shift, the draws (and so older models' runs) are as before.
        let mut x = ramp.clone();
        let mut y = ramp.clone();
        Augment::new().apply(&mut x, &mut SampleRng::new(1, 2, 3));
        Augment::new()
            .with_shift(Some(0.0))
            .apply(&mut y, &mut SampleRng::new(1, 2, 3));
        assert_eq!(x, y);
        assert!(Augment::none().with_shift(Some(0.5)).check().is_err());
        assert!(Augment::none().with_shift(Some(-0.1)).check().is_err());
        assert!(Augment::none().with_shift(Some(f64::NAN)).check().is_err());
    }
}
