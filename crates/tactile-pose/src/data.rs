//! Grey pin images with their pose labels, and the augmentation that keeps
//! the labels true: brightness gain and offset and sensor noise change how
//! a frame looks, never where the contact is (no geometric change).

use burn::config::Config;
use burn::tensor::{Device, Tensor, TensorData};
use tactile_cae::data::PinSet;
use tactile_core::dataset::Dataset;
use tactile_core::rng::SampleRng;
use tactile_estimate::Target;
use tactile_preprocess::PreprocessConfig;

use crate::Result;

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
}

impl Augment {
    /// No change at all.
    pub fn none() -> Self {
        Self::new().with_gain(0.0).with_offset(0.0).with_noise(0.0)
    }

    /// Check the amounts (each in [0, 1]).
    pub fn check(&self) -> tactile_core::Result<()> {
        tactile_burn::train::check_augment_amounts(&[
            ("gain", self.gain),
            ("offset", self.offset),
            ("noise", self.noise),
        ])
    }

    /// `pixels` augmented with the draws of `rng`, clipped to [0, 1].
    pub fn apply(&self, pixels: &mut [f32], rng: &mut SampleRng) {
        if *self == Self::none() {
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
        Self::from_rows(ds, &(0..ds.len()).collect::<Vec<_>>(), cfg, targets)
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
                    .map(|t| ds.number_opt(i, &t.name))
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
    /// streams of `seed` keyed by `round` (the epoch) and each frame.
    pub fn batch(
        &self,
        idx: &[usize],
        augment: &Augment,
        (seed, round): (u64, u64),
        device: &Device,
    ) -> Tensor<4> {
        let side = self.pins.images.first().map_or(0, |p| p.side);
        let mut data = Vec::with_capacity(idx.len() * side * side);
        for &i in idx {
            let mut px = self.pins.images[i].pixels.clone();
            augment.apply(&mut px, &mut SampleRng::new(seed, round, i as u64));
            data.extend(px);
        }
        Tensor::from_data(TensorData::new(data, [idx.len(), 1, side, side]), device)
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
}
