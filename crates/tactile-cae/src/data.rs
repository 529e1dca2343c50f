//! From a dataset folder to pin-image tensors.

use std::path::PathBuf;

use burn::tensor::{Device, Tensor, TensorData};
use tactile_core::dataset::{Dataset, DatasetKind};
use tactile_core::{Error, Result};
use tactile_preprocess::{PinImage, PreprocessConfig, preprocess_files};

/// Pin images of a TacTip dataset, in `labels.csv` order.
pub struct PinSet {
    pub files: Vec<String>,
    pub images: Vec<PinImage>,
}

impl PinSet {
    /// Preprocess every frame of `ds` (in parallel).
    pub fn from_dataset(ds: &Dataset, cfg: &PreprocessConfig) -> Result<Self> {
        if ds.manifest.kind != DatasetKind::Tactip {
            return Err(Error::dataset(
                ds.root.join("manifest.json"),
                None,
                "kind is not 'tactip': the autoencoder reads TacTip datasets",
            ));
        }
        let files: Vec<String> = (0..ds.len())
            .map(|i| ds.text(i, "file").map(str::to_string))
            .collect::<Result<_>>()?;
        let paths: Vec<PathBuf> = files.iter().map(|f| ds.root.join(f)).collect();
        let images = preprocess_files(&paths, cfg)?;
        Ok(Self { files, images })
    }

    /// Number of images.
    pub fn len(&self) -> usize {
        self.images.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.images.is_empty()
    }

    /// A `[N, 1, S, S]` batch of the images at `idx`.
    pub fn batch(&self, idx: &[usize], device: &Device) -> Tensor<4> {
        batch_tensor(idx.iter().map(|&i| &self.images[i]), device)
    }
}

/// Stack pin images into a `[N, 1, S, S]` tensor.
pub fn batch_tensor<'a>(images: impl Iterator<Item = &'a PinImage>, device: &Device) -> Tensor<4> {
    let mut data = Vec::new();
    let mut n = 0;
    let mut side = 0;
    for img in images {
        side = img.side;
        data.extend_from_slice(&img.pixels);
        n += 1;
    }
    Tensor::from_data(TensorData::new(data, [n, 1, side, side]), device)
}
