//! Visuo-tactile frames and `tendon` labels as detector batches.

use burn::tensor::{Device, Tensor, TensorData};
use rayon::prelude::*;
use tactile_core::Error;
use tactile_core::dataset::{Dataset, DatasetKind};
use tactile_core::source::UndecodableFrames;
use tactile_preprocess::visuo::{ChannelStats, FloatImage};

use crate::{DetectorConfig, Result};

/// Frames of a dataset resized to the detector's input, kept as whole
/// levels of the detector's input code (8 or 16 bits) to hold thousands in
/// memory, with their labels.
pub struct DetectionSet {
    /// Input width the frames were resized to.
    pub width: usize,
    /// Input height.
    pub height: usize,
    /// The detector's input form: the bits per channel the frames are held
    /// at, and its [`DetectorConfig::network_view`] that turns a held frame
    /// into what the network takes.
    pub detector: DetectorConfig,
    /// Each frame's `file` label.
    pub files: Vec<String>,
    /// `H x W x 3` levels per frame.
    pub frames: Vec<Vec<u16>>,
    /// Each frame's `tendon` label.
    pub tendon: Vec<bool>,
    /// Frames within two frames of a label change in their sequence (the
    /// onset and release of contact with the tendon).
    pub transition: Vec<bool>,
    /// The ridge amplitude `A` (mm) of each frame where the dataset gives
    /// one (`ridge_mm`, written by datasets-synth); used for soft labels.
    pub ridge_mm: Vec<Option<f64>>,
}

impl DetectionSet {
    /// Load and resize every frame (in parallel) to the input of
    /// `detector`, held at its bits (`tendon` is 0 or 1: `Dataset::open`
    /// refuses any other).
    pub fn from_dataset(ds: &Dataset, detector: &DetectorConfig) -> Result<Self> {
        let mut set = Self::labels_of(ds, detector)?;
        ds.check_frame_headers(&ds.every_row())?;
        set.frames = load_frames(ds, detector, &set.files, 0)?;
        Ok(set)
    }

    /// Every row of `ds` as [`DetectionSet::from_dataset`] loads it, a
    /// chunk of `chunk_rows` rows at a time, each chunk handed to `each` in
    /// order (its labels checked first, on every row): a dataset of any
    /// length in bounded memory. The onset and release frames are those of
    /// the whole dataset's sequences. A frame that cannot be decoded past
    /// its header (its pixel data cut short) is left out of its chunk, its
    /// labels with it, and counted ([`UndecodableFrames`], the rule of every
    /// reader of frames): the warning naming the first is returned; when no
    /// frame can be decoded the pass fails with the refusal.
    pub fn for_each_chunk(
        ds: &Dataset,
        detector: &DetectorConfig,
        chunk_rows: usize,
        mut each: impl FnMut(DetectionSet) -> Result<()>,
    ) -> Result<Option<String>> {
        let labels = Self::labels_of(ds, detector)?;
        ds.check_frame_headers(&ds.every_row())?;
        let mut skipped = UndecodableFrames::new(labels.files.len());
        let mut given = 0;
        let step = chunk_rows.max(1);
        for start in (0..labels.files.len()).step_by(step) {
            let end = (start + step).min(labels.files.len());
            let read = read_frames(ds, detector, &labels.files[start..end], start)?;
            let mut part = Self {
                width: labels.width,
                height: labels.height,
                frames: Vec::with_capacity(read.len()),
                files: Vec::with_capacity(read.len()),
                tendon: Vec::with_capacity(read.len()),
                transition: Vec::with_capacity(read.len()),
                ridge_mm: Vec::with_capacity(read.len()),
                detector: detector.clone(),
            };
            for (i, frame) in (start..end).zip(read) {
                let Some(frame) = skipped.decoded(frame)? else {
                    continue;
                };
                part.frames.push(frame);
                part.files.push(labels.files[i].clone());
                part.tendon.push(labels.tendon[i]);
                part.transition.push(labels.transition[i]);
                part.ridge_mm.push(labels.ridge_mm[i]);
            }
            // A chunk whose every frame was skipped gives no batch to run.
            if !part.frames.is_empty() {
                given += part.frames.len();
                each(part)?;
            }
        }
        let warning = skipped.warning();
        skipped.finish(given)?;
        Ok(warning)
    }

    /// Every row's labels, checked, without its frame.
    fn labels_of(ds: &Dataset, detector: &DetectorConfig) -> Result<Self> {
        let [width, height] = detector.input_size;
        ds.expect_kind(DatasetKind::Visuotactile)?;
        // `Dataset::open` refused a tendon that is neither 0 nor 1.
        let tendon = (0..ds.len())
            .map(|i| Ok(ds.number(i, "tendon")? == 1.0))
            .collect::<tactile_core::Result<Vec<_>>>()?;
        let files: Vec<String> = (0..ds.len())
            .map(|i| ds.text(i, "file").map(str::to_string))
            .collect::<tactile_core::Result<_>>()?;
        let transition = transitions(ds, &tendon)?;
        let ridge_mm = (0..ds.len())
            .map(|i| ds.number_opt(i, "ridge_mm"))
            .collect::<tactile_core::Result<Vec<_>>>()?;
        Ok(Self {
            width,
            height,
            detector: detector.clone(),
            files,
            frames: Vec::new(),
            tendon,
            transition,
            ridge_mm,
        })
    }

    /// Frames held.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Append another set loaded at the same size (training on several
    /// datasets); its frames follow this set's, so its indices shift by
    /// the old `len()`.
    pub fn append(&mut self, other: DetectionSet) -> Result<()> {
        if (other.width, other.height) != (self.width, self.height) {
            return Err(crate::Error::InputSize {
                expected: [self.width, self.height],
                found: [other.width, other.height],
            });
        }
        let form = |d: &DetectorConfig| (d.bits(), d.normalises_exposure());
        if form(&other.detector) != form(&self.detector) {
            return Err(tactile_core::Error::Invalid(format!(
                "cannot join frames held for another input form ({} bits) to these ({} bits)",
                other.detector.bits(),
                self.detector.bits()
            ))
            .into());
        }
        self.files.extend(other.files);
        self.frames.extend(other.frames);
        self.tendon.extend(other.tendon);
        self.transition.extend(other.transition);
        self.ridge_mm.extend(other.ridge_mm);
        Ok(())
    }

    /// True when it holds no frame.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The frame as a float image in [0, 1], as the camera gave it (the
    /// input profile's view).
    pub fn image(&self, i: usize) -> FloatImage {
        self.detector.image_of_levels(&self.frames[i])
    }

    /// The frame as the network takes it, before the channel statistics.
    pub fn view(&self, i: usize) -> FloatImage {
        self.detector.network_view(self.image(i))
    }

    /// Normalised `3 x H x W` inputs of the frames at `idx`, end to end.
    pub fn inputs(&self, idx: &[usize], stats: &ChannelStats) -> Result<Vec<f32>> {
        let mut data = Vec::with_capacity(idx.len() * 3 * self.width * self.height);
        for &i in idx {
            data.extend(self.detector.network_input(self.image(i), stats)?);
        }
        Ok(data)
    }

    /// [`Self::batch`] with every frame changed by `augment`, frame `i`
    /// with the stream `(seed, round, i)` (round: the epoch).
    pub fn augmented_batch(
        &self,
        idx: &[usize],
        stats: &ChannelStats,
        augment: &crate::augment::PhotometricAugment,
        (seed, round): (u64, u64),
        device: &Device,
    ) -> Result<Tensor<4>> {
        let mut data = Vec::with_capacity(idx.len() * 3 * self.width * self.height);
        for &i in idx {
            let mut img = self.image(i);
            augment.apply(
                &mut img,
                &mut tactile_core::rng::SampleRng::new(seed, round, i as u64),
            );
            data.extend(self.detector.network_input(img, stats)?);
        }
        Ok(Tensor::from_data(
            TensorData::new(data, [idx.len(), 3, self.height, self.width]),
            device,
        ))
    }

    /// Normalised `[N, 3, H, W]` batch of the frames at `idx`.
    pub fn batch(&self, idx: &[usize], stats: &ChannelStats, device: &Device) -> Result<Tensor<4>> {
        Ok(Tensor::from_data(
            TensorData::new(
                self.inputs(idx, stats)?,
                [idx.len(), 3, self.height, self.width],
            ),
            device,
        ))
    }

    /// `[N, 1]` labels of the frames at `idx`.
    pub fn labels(&self, idx: &[usize], device: &Device) -> Tensor<2> {
        let v: Vec<f32> = idx.iter().map(|&i| self.tendon[i] as u8 as f32).collect();
        Tensor::from_data(TensorData::new(v, [idx.len(), 1]), device)
    }

    /// `[N, 1]` training targets: the 0/1 labels, or with `soft` the
    /// [`SoftLabels::target`] of each frame's ridge amplitude.
    pub fn targets(&self, idx: &[usize], soft: Option<&SoftLabels>, device: &Device) -> Tensor<2> {
        let Some(soft) = soft else {
            return self.labels(idx, device);
        };
        let v: Vec<f32> = idx
            .iter()
            .map(|&i| soft.target(self.tendon[i], self.ridge_mm[i]))
            .collect();
        Tensor::from_data(TensorData::new(v, [idx.len(), 1]), device)
    }

    /// Refuse soft labels for a dataset without `ridge_mm`.
    pub fn check_soft_labels(&self, labels_file: &std::path::Path) -> Result<()> {
        match self.ridge_mm.iter().position(Option::is_none) {
            None => Ok(()),
            Some(i) => Err(crate::Error::Core(Error::dataset(
                labels_file,
                None,
                format!(
                    "soft labels need the column 'ridge_mm' on every frame ({} has none)",
                    self.files[i]
                ),
            ))),
        }
    }
}

/// Frames of several datasets at one input size, each split by its own
/// sequences into training and validation: `(frames, train, validation)`
/// with indices into the joined set.
pub fn load_split(
    datasets: &[Dataset],
    detector: &DetectorConfig,
    val_fraction: f64,
    seed: u64,
    soft_labels: bool,
) -> Result<(DetectionSet, Vec<usize>, Vec<usize>)> {
    let (mut train, mut val) = (Vec::new(), Vec::new());
    let mut data: Option<DetectionSet> = None;
    for ds in datasets {
        let (t, v) = ds.split_by_sequence(val_fraction, seed)?;
        tactile_core::note!(
            "loading {} frames of {} at {}x{} ({} train, {} validation, split by sequence)",
            ds.len(),
            ds.root.display(),
            detector.input_size[0],
            detector.input_size[1],
            t.len(),
            v.len()
        );
        let set = DetectionSet::from_dataset(ds, detector)?;
        if soft_labels {
            set.check_soft_labels(&ds.labels_path())?;
        }
        let offset = data.as_ref().map_or(0, DetectionSet::len);
        train.extend(t.into_iter().map(|i| i + offset));
        val.extend(v.into_iter().map(|i| i + offset));
        match data.as_mut() {
            None => data = Some(set),
            Some(d) => d.append(set)?,
        }
    }
    let data = data.ok_or_else(|| tactile_core::Error::Config("no dataset to train on".into()))?;
    Ok((data, train, val))
}

/// Soft detector targets from the ridge amplitude: the label is a hard
/// threshold on `A` (sensors.md: `tendon` needs `A >= 0.03` mm), so frames
/// near it are nearly indistinguishable; training the logit toward
/// `ln(A / threshold) / width` teaches the network to measure the ridge
/// rather than to memorise which side of the line each frame fell on.
#[derive(burn::config::Config, Debug, PartialEq)]
pub struct SoftLabels {
    /// The label's amplitude threshold (mm).
    pub threshold_mm: f64,
    /// Width of the transition in natural-log units of `A`.
    pub width: f64,
}

impl SoftLabels {
    /// Soft labels about the spec's tendon threshold (a ridge of 0.03 mm)
    /// with transition `width`, which must be positive.
    pub fn about_spec_threshold(width: f64) -> Result<Self> {
        if !(width > 0.0 && width.is_finite()) {
            return Err(tactile_core::Error::Config(format!(
                "soft-label width must be positive, got {width:?}"
            ))
            .into());
        }
        Ok(Self::new(
            tactile_core::spec::visuotactile::TENDON_MIN_AMPLITUDE_MM,
            width,
        ))
    }

    /// The target probability; frames labelled 0 although their ridge is
    /// above the threshold (tendon out of view) stay at 0, and the target
    /// never contradicts the label.
    pub fn target(&self, tendon: bool, ridge_mm: Option<f64>) -> f32 {
        let hard = tendon as u8 as f32;
        let Some(a) = ridge_mm.filter(|a| a.is_finite()) else {
            return hard;
        };
        if !tendon && a >= self.threshold_mm {
            return 0.0;
        }
        let z = (a.max(1e-6) / self.threshold_mm).ln() / self.width.max(1e-6);
        let p = (1.0 / (1.0 + (-z).exp())) as f32;
        if tendon { p.max(0.5) } else { p.min(0.5) }
    }
}

/// The frames of rows `first..first + files.len()` of `ds` (their `file`
/// labels `files`), resized in parallel to `detector`'s input and held at
/// its bits.
fn load_frames(
    ds: &Dataset,
    detector: &DetectorConfig,
    files: &[String],
    first: usize,
) -> Result<Vec<Vec<u16>>> {
    read_frames(ds, detector, files, first)?
        .into_iter()
        .map(|frame| Ok(frame?))
        .collect()
}

/// [`load_frames`], each frame that cannot be read kept apart as its error
/// (the outer error: a frame read that cannot be resized), so a pass may
/// skip it.
fn read_frames(
    ds: &Dataset,
    detector: &DetectorConfig,
    files: &[String],
    first: usize,
) -> Result<Vec<tactile_core::Result<Vec<u16>>>> {
    (0..files.len())
        .into_par_iter()
        .map(|k| {
            let frame = match ds.load_rgb(first + k) {
                Ok(frame) => frame,
                Err(e) => return Ok(Err(e)),
            };
            detector.frame_levels(&frame).map(Ok).map_err(|e| {
                tactile_core::Error::image(ds.root.join(&files[k]), e.to_string()).into()
            })
        })
        .collect()
}

/// Frames within two frames (same sequence, by `frame_index`) of a frame
/// with the other label. Datasets without sequences have none.
fn transitions(ds: &Dataset, tendon: &[bool]) -> tactile_core::Result<Vec<bool>> {
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

#[cfg(test)]
mod tests {
    use super::SoftLabels;

    #[test]
    fn soft_targets_follow_the_ridge_and_never_contradict_the_label() {
        let s = SoftLabels::new(0.03, 0.2);
        // At the threshold the target is one half; far from it, the label.
        assert!((s.target(true, Some(0.03)) - 0.5).abs() < 1e-6);
        assert!(s.target(true, Some(0.3)) > 0.999);
        assert!(s.target(false, Some(0.001)) < 1e-3);
        // Graded near the threshold, monotone in the amplitude.
        let (lo, hi) = (s.target(false, Some(0.027)), s.target(true, Some(0.034)));
        assert!(lo > 0.3 && lo < 0.5 && hi > 0.5 && hi < 0.7, "{lo} {hi}");
        // A tendon out of view (label 0, big ridge) stays a hard negative.
        assert_eq!(s.target(false, Some(0.5)), 0.0);
        // No amplitude, or a NaN one: the hard label.
        assert_eq!(s.target(true, None), 1.0);
        assert_eq!(s.target(false, Some(f64::NAN)), 0.0);
    }
}
