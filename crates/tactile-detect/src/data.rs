//! Visuo-tactile frames and `tendon` labels as detector batches.

use burn::tensor::{Device, Tensor, TensorData};
use rayon::prelude::*;
use tactile_core::dataset::{Dataset, DatasetKind};
use tactile_core::{Error, Result};
use tactile_preprocess::visuo::{ChannelStats, FloatImage, load_frame};

/// Frames of a dataset resized to the detector's input, kept as 8-bit to
/// hold thousands in memory, with their labels.
pub struct DetectionSet {
    pub width: usize,
    pub height: usize,
    pub files: Vec<String>,
    /// `H x W x 3` bytes per frame.
    pub frames: Vec<Vec<u8>>,
    pub tendon: Vec<bool>,
    /// Frames within two frames of a label change in their sequence (the
    /// onset and release of contact with the tendon).
    pub transition: Vec<bool>,
}

impl DetectionSet {
    /// Load and resize every frame (in parallel); `tendon` must be 0 or 1.
    pub fn from_dataset(ds: &Dataset, [width, height]: [usize; 2]) -> Result<Self> {
        if ds.manifest.kind != DatasetKind::Visuotactile {
            return Err(Error::dataset(
                ds.root.join("manifest.json"),
                None,
                "kind is not 'visuotactile': the detector reads visuo-tactile datasets",
            ));
        }
        let tendon = (0..ds.len())
            .map(|i| match ds.number(i, "tendon")? {
                0.0 => Ok(false),
                1.0 => Ok(true),
                v => Err(Error::dataset(
                    ds.labels_path(),
                    Some(ds.rows[i].line),
                    format!("column 'tendon': {v} is neither 0 nor 1"),
                )),
            })
            .collect::<Result<Vec<_>>>()?;
        let files: Vec<String> = (0..ds.len())
            .map(|i| ds.text(i, "file").map(str::to_string))
            .collect::<Result<_>>()?;
        let frames = files
            .par_iter()
            .map(|f| {
                let img = load_frame(ds.root.join(f), width, height)?;
                Ok(to_bytes(&img))
            })
            .collect::<Result<Vec<_>>>()?;
        let transition = transitions(ds, &tendon)?;
        Ok(Self {
            width,
            height,
            files,
            frames,
            tendon,
            transition,
        })
    }

    pub fn len(&self) -> usize {
        self.frames.len()
    }

    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The frame as a float image in [0, 1].
    pub fn image(&self, i: usize) -> FloatImage {
        FloatImage {
            width: self.width,
            height: self.height,
            channels: 3,
            data: self.frames[i].iter().map(|&v| v as f32 / 255.0).collect(),
        }
    }

    /// Normalised `[N, 3, H, W]` batch of the frames at `idx`.
    pub fn batch(&self, idx: &[usize], stats: &ChannelStats, device: &Device) -> Result<Tensor<4>> {
        let mut data = Vec::with_capacity(idx.len() * 3 * self.width * self.height);
        for &i in idx {
            data.extend(stats.to_chw(&self.image(i))?);
        }
        Ok(Tensor::from_data(
            TensorData::new(data, [idx.len(), 3, self.height, self.width]),
            device,
        ))
    }

    /// `[N, 1]` labels of the frames at `idx`.
    pub fn labels(&self, idx: &[usize], device: &Device) -> Tensor<2> {
        let v: Vec<f32> = idx.iter().map(|&i| self.tendon[i] as u8 as f32).collect();
        Tensor::from_data(TensorData::new(v, [idx.len(), 1]), device)
    }
}

/// Quantise a [0, 1] image to bytes.
pub fn to_bytes(img: &FloatImage) -> Vec<u8> {
    img.data
        .iter()
        .map(|&v| (v * 255.0).round().clamp(0.0, 255.0) as u8)
        .collect()
}

/// Frames within two frames (same sequence, by `frame_index`) of a frame
/// with the other label. Datasets without sequences have none.
fn transitions(ds: &Dataset, tendon: &[bool]) -> Result<Vec<bool>> {
    let mut by_seq: std::collections::HashMap<String, Vec<(i64, usize)>> = Default::default();
    for i in 0..ds.len() {
        if let (Some(s), Some(f)) = (ds.text_opt(i, "sequence"), ds.number_opt(i, "frame_index")?) {
            by_seq.entry(s.to_string()).or_default().push((f as i64, i));
        }
    }
    let mut out = vec![false; ds.len()];
    for frames in by_seq.values_mut() {
        frames.sort_unstable();
        for (a, &(fa, ia)) in frames.iter().enumerate() {
            let lo = a.saturating_sub(2);
            let hi = (a + 3).min(frames.len());
            out[ia] = frames[lo..hi]
                .iter()
                .any(|&(fb, ib)| (fb - fa).abs() <= 2 && tendon[ib] != tendon[ia]);
        }
    }
    Ok(out)
}
