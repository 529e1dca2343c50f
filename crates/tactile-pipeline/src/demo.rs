//! Paper A in a few frames, as `tactile demo` shows it: an encoder and its
//! shape head classify the first frames of each class of a dataset.

use std::path::Path;

use tactile_burn::{DeviceKind, Runtime};
use tactile_cae::TactipEncoder;
use tactile_cae::data::PinSet;
use tactile_core::dataset::Dataset;
use tactile_estimate::ClassifierHead;

use crate::Result;

/// One frame the demo classified.
#[derive(Debug, Clone)]
pub struct DemoFrame {
    /// The frame's file, as the dataset names it.
    pub file: String,
    /// Its `shape` label (`?` when it has none).
    pub truth: String,
    /// The head's class.
    pub predicted: String,
    /// The encoder's features of the frame.
    pub features: Vec<f32>,
}

/// What the demo did.
#[derive(Debug, Clone)]
pub struct Demo {
    /// The encoder's channel widths, block 1 to 4.
    pub widths: [usize; 4],
    /// Features per frame.
    pub feature_count: usize,
    /// The head's classes.
    pub classes: Vec<String>,
    /// The frames classified, class by class.
    pub frames: Vec<DemoFrame>,
}

impl Demo {
    /// Frames whose class was right.
    pub fn correct(&self) -> usize {
        self.frames
            .iter()
            .filter(|f| f.truth == f.predicted)
            .count()
    }
}

/// Classify the first `per_class` frames of each of the head's classes in
/// `data` (its `test` split when it has one) with the encoder in `model`
/// and its shape head `model/head`, on burn's flex device.
pub fn classify_samples(model: &Path, data: &Path, per_class: usize) -> Result<Demo> {
    let mut enc = TactipEncoder::load(model, Runtime::BurnFlex, 0)?;
    let head = ClassifierHead::load(model.join("head"), &DeviceKind::Flex.device())?;
    let ds = Dataset::open(data)?;
    let rows = ds
        .split_indices("test")
        .unwrap_or_else(|| (0..ds.len()).collect());
    let picked: Vec<usize> = head
        .classes()
        .iter()
        .flat_map(|class| {
            rows.iter()
                .copied()
                .filter(|&i| ds.text_opt(i, "shape") == Some(class.as_str()))
                .take(per_class)
        })
        .collect();
    let set = PinSet::from_rows(&ds, &picked, &enc.artifact.preprocess)?;
    let features = enc.encode(&set.images)?;
    let predicted = head.predict(&features)?;
    let frames = set
        .files
        .iter()
        .zip(features)
        .zip(predicted)
        .zip(&picked)
        .map(|(((file, features), p), &row)| DemoFrame {
            file: file.clone(),
            truth: ds.text_opt(row, "shape").unwrap_or("?").to_string(),
            predicted: head.classes()[p].clone(),
            features,
        })
        .collect();
    Ok(Demo {
        widths: enc.artifact.model.widths,
        feature_count: enc.feature_count(),
        classes: head.classes().to_vec(),
        frames,
    })
}
