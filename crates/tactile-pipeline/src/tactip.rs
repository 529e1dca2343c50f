//! Paper A composed: one encoder, many cheap estimators. Features of a
//! dataset (from an encoder folder or a feature CSV), training the shape
//! head and the regressors on them, every estimator of a folder on one
//! encoding per frame, and their scores.

use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::time::Instant;

use tactile_burn::Runtime;
use tactile_burn::nn::RegressionLoss;
use tactile_cae::TactipEncoder;
use tactile_cae::data::PinSet;
use tactile_cae::inference::features_for_dataset;
use tactile_core::dataset::Dataset;
use tactile_core::image_io::GreyImage;
use tactile_core::metrics::{accuracy, confusion};
use tactile_core::source::FrameSource;

use crate::run::Flow;
use tactile_cae::data::ForeignFrame;
use tactile_estimate::eval::{Scores, score};
use tactile_estimate::{
    Activation, ClassifierHead, Estimates, Estimators, HeadConfig, Regressor, RegressorConfig,
    Target,
};
pub use tactile_preprocess::perturb::RotationAugment;
use tactile_preprocess::profile::InputProfile;
use tactile_preprocess::{FrameSizeCheck, PinImage, PreprocessConfig, is_flat_frame};

use crate::Result;

/// Where feature vectors come from.
#[derive(Debug, Clone)]
pub enum FeatureSource {
    /// A trained encoder folder: frames are preprocessed and encoded.
    Encoder(PathBuf),
    /// A feature CSV (`file,f0,f1,...`), rows matched to the dataset by file.
    Csv(PathBuf),
}

/// When the encoder in `dir` trained on some or all of `rows` of `ds`
/// (its notes, [`Provenance::seen`]: the same files or copies), the words
/// saying so, "trained on every one of these 24 test frames (its notes:
/// ...)": an error on those rows is then on frames its features fitted.
/// `None` when it did not, or its notes do not say.
///
/// [`Provenance::seen`]: tactile_core::dataset::Provenance::seen
pub fn encoder_trained_on(dir: &Path, ds: &Dataset, rows: &[usize]) -> Option<String> {
    use tactile_core::dataset::{Provenance, Seen};
    let art = <tactile_cae::CaeArtifact as tactile_burn::Artifact>::read(dir).ok()?;
    let p = Provenance::read(&art.notes);
    let how = match p.seen(dir, ds, rows) {
        Seen::All => "every one of",
        Seen::Some => "some of",
        Seen::None | Seen::Unknown => return None,
    };
    Some(format!(
        "trained on {how} these {} test frames (its notes: {})",
        rows.len(),
        p.names()
    ))
}

/// The rows of `ds` a pass gave results for (`rows`, in order): `ds`
/// itself when it gave every row, else the dataset of those rows alone
/// ([`Dataset::only_rows`]), so results are scored against their own
/// labels when an undecodable frame was left out.
fn decoded_rows<'a>(ds: &'a Dataset, rows: &[usize]) -> Cow<'a, Dataset> {
    if rows.len() == ds.len() {
        Cow::Borrowed(ds)
    } else {
        Cow::Owned(ds.only_rows(rows))
    }
}

/// How to train an encoder that leaves out the test rows of `ds` that a
/// split with `test_fraction` and `seed` holds out.
pub fn holdout_cure(ds: &Dataset, test_fraction: f64, seed: u64) -> String {
    if ds.split_indices("train").is_some() {
        "on the `train` rows only (without --every-split)".to_string()
    } else {
        format!("with --exclude-test {test_fraction} --split-seed {seed} (the test frames here)")
    }
}

/// Feature vectors of every frame of `ds`, in row order.
pub fn dataset_features(
    source: &FeatureSource,
    ds: &Dataset,
    runtime: Runtime,
) -> Result<Vec<Vec<f32>>> {
    Ok(match source {
        FeatureSource::Encoder(dir) => TactipEncoder::load(dir, runtime, 0)?.encode_dataset(ds)?.1,
        FeatureSource::Csv(csv) => features_for_dataset(csv, ds)?,
    })
}

/// The fingerprint of the encoder features come from (none for a CSV).
fn encoder_fingerprint(source: &FeatureSource) -> Result<Option<String>> {
    Ok(match source {
        FeatureSource::Encoder(dir) => Some(tactile_burn::artifact::fingerprint::<
            tactile_cae::CaeArtifact,
        >(dir)?),
        FeatureSource::Csv(_) => None,
    })
}

/// The encoder and every estimator of its folder (or the folders given).
pub struct TactipPerception {
    /// Frames to features.
    pub encoder: TactipEncoder,
    /// Features to shape, pose, depth, force.
    pub estimators: Estimators,
    /// The encoder's folder.
    dir: PathBuf,
}

/// What a TacTip model folder holds: the two kinds `predict` and the pose
/// benches read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TactipModelKind {
    /// A pose network, or an ensemble of them: it gives its targets itself.
    PoseNetwork,
    /// A CAE encoder, its estimators inside its folder.
    Encoder,
}

impl TactipModelKind {
    /// The kind of TacTip model in `dir`. A path that is no folder, or a
    /// folder of neither kind, is refused naming what it holds (`other`
    /// says what a model of another kind is to the caller: "a model
    /// `predict` and `evaluate` do not run").
    pub fn of(dir: &Path, other: &str) -> Result<Self> {
        use tactile_burn::Artifact;
        // A pose network, or an ensemble of them (a detector's ensemble is
        // no TacTip model).
        let pose =
            |d: &Path| tactile_pose::PoseArtifact::is_in(d) || tactile_pose::PoseEnsemble::is_in(d);
        tactile_core::io::expect_folder(dir, "model folder")?;
        if pose(dir) {
            return Ok(Self::PoseNetwork);
        }
        if tactile_cae::CaeArtifact::is_in(dir) {
            return Ok(Self::Encoder);
        }
        let model = |d: &Path| pose(d) || tactile_cae::CaeArtifact::is_in(d);
        Err(tactile_core::Error::wrong_kind(
            dir,
            "TacTip model folder",
            format!(
                "no pose network (pose.json, or an ensemble of them) and no cae.json{}",
                tactile_burn::artifact::folder_hint(dir, model, other)
            ),
        )
        .into())
    }
}

/// Anything that estimates targets from TacTip frames: an encoder with its
/// estimators (paper A), or a pose network (`pose.json`), which estimates
/// its targets directly.
pub enum Predictor {
    /// An encoder folder and its estimators.
    Encoder(TactipPerception),
    /// A supervised pose network.
    PoseNetwork(tactile_pose::PoseEstimator),
}

impl Predictor {
    /// The model in `dir`: a pose network when it holds `pose.json` (an
    /// ensemble of them with `ensemble.json`), else an
    /// encoder with the estimators in `heads` (every estimator folder
    /// inside it when empty).
    pub fn load(dir: &Path, heads: &[PathBuf], runtime: Runtime) -> Result<Self> {
        if TactipModelKind::of(dir, "a model `predict` and `evaluate` do not run")?
            == TactipModelKind::PoseNetwork
        {
            // A pose network gives its targets itself: estimator folders
            // would be left unread without a word.
            if let Some(h) = heads.first() {
                return Err(tactile_core::Error::model(
                    dir,
                    format!(
                        "a pose network, which gives its targets itself: estimator folders (--heads {}) read an encoder's features; leave them out, or pass an encoder folder",
                        h.display()
                    ),
                )
                .into());
            }
            Ok(Self::PoseNetwork(tactile_pose::PoseEstimator::load(
                dir, runtime, 0,
            )?))
        } else {
            Ok(Self::Encoder(TactipPerception::load(dir, heads, runtime)?))
        }
    }

    /// Every frame of `ds`: one column per target (per estimator output).
    pub fn perceive(&mut self, ds: &Dataset) -> Result<Perception> {
        let mismatch = dataset_frame_warning(ds, self.preprocessings());
        let mut r = match self {
            Self::Encoder(p) => p.perceive(ds)?,
            Self::PoseNetwork(p) => {
                let r = p.predict_dataset(ds)?;
                Perception {
                    files: r.files,
                    stamps_ns: None,
                    estimates: pose_estimates(&r.names, &r.values, r.std.as_deref()),
                    ms_encode: r.ms_per_frame,
                    ms_estimate: 0.0,
                    warnings: dataset_frame_warnings(
                        &r.flat,
                        &r.foreign,
                        r.undecodable,
                        p.artifact.input_profile.as_ref(),
                    ),
                }
            }
        };
        r.warnings.extend(mismatch);
        Ok(r)
    }

    /// Score the model on a labelled dataset: an encoder's every estimator
    /// ([`TactipPerception::evaluate`]), or a pose network's every target
    /// ([`tactile_estimate::eval::score_targets`]): each target's mean
    /// absolute error overall and per shape (angles the short way round),
    /// with a warning when its notes say it trained on every frame of `ds`,
    /// and the warnings `predict` gives of the frames (their size against
    /// the model's crop, blank frames, frames unlike its training frames,
    /// frames that cannot be decoded past their header, which are left
    /// out of the scores as `predict` leaves them out of its rows).
    pub fn evaluate(&mut self, ds: &Dataset) -> Result<Scores> {
        let mismatch = dataset_frame_warning(ds, self.preprocessings());
        let mut s = match self {
            Self::Encoder(p) => p.evaluate(ds)?,
            Self::PoseNetwork(p) => {
                let r = p.predict_dataset(ds)?;
                let scored = decoded_rows(ds, &r.rows);
                let given = tactile_estimate::eval::Given {
                    pred: &r.values,
                    std: r.std.as_deref(),
                };
                let targets = &p.artifact.targets;
                let mut s = tactile_estimate::eval::score_targets(targets, given, &scored)?;
                s.warning = p.scored_on_fitted(&scored);
                let profile = p.artifact.input_profile.as_ref();
                s.frame_warnings =
                    dataset_frame_warnings(&r.flat, &r.foreign, r.undecodable, profile);
                s
            }
        };
        s.frame_warnings.splice(0..0, mismatch);
        Ok(s)
    }

    /// The same columns as [`Self::perceive`] for grey frames, each
    /// preprocessed as the model's training frames were; a frame that
    /// cannot be is named by `name` of its place among `frames`.
    pub fn perceive_frames(
        &mut self,
        frames: &[GreyImage],
        name: impl Fn(usize) -> Option<String>,
    ) -> Result<Estimates> {
        // No frame is scored: only the estimates are wanted.
        Ok(self.perceive_frames_flagging(frames, &name, |_| true)?.0)
    }

    /// The model's pin profile ([`InputProfile::fit_pins`]; an ensemble's
    /// first member's), when it has one.
    pub fn input_profile(&self) -> Option<&InputProfile> {
        match self {
            Self::Encoder(p) => p.encoder.artifact.input_profile.as_ref(),
            Self::PoseNetwork(p) => p.artifact.input_profile.as_ref(),
        }
    }

    /// [`Self::perceive_frames`], with the frames outside the model's pin
    /// profile ([`ForeignFrame::among`]; none without one), named by
    /// `name`; those `skip` says (flat frames) are not scored.
    fn perceive_frames_flagging(
        &mut self,
        frames: &[GreyImage],
        name: &impl Fn(usize) -> Option<String>,
        skip: impl Fn(usize) -> bool + Sync,
    ) -> Result<(Estimates, Vec<ForeignFrame>)> {
        let pins = self
            .preprocessings()
            .into_iter()
            .map(|cfg| {
                tactile_preprocess::preprocess_each(frames, cfg).map_err(|e| e.name_frame(name))
            })
            .collect::<std::result::Result<Vec<Vec<PinImage>>, _>>()?;
        let foreign = match (self.input_profile(), pins.first()) {
            (Some(p), Some(first)) => ForeignFrame::among(p, first, skip, |i| {
                name(i).unwrap_or_else(|| format!("frames[{i}]"))
            }),
            _ => Vec::new(),
        };
        let estimates = match self {
            Self::Encoder(p) => p.estimate(pins.first().map_or(&[], Vec::as_slice))?,
            Self::PoseNetwork(p) => {
                let views: Vec<&[PinImage]> = pins.iter().map(Vec::as_slice).collect();
                let (values, std) = p.predict_scales_with_std(&views)?;
                let names: Vec<String> =
                    p.artifact.targets.iter().map(|t| t.name.clone()).collect();
                pose_estimates(&names, &values, std.as_deref())
            }
        };
        Ok((estimates, foreign))
    }

    /// Every frame of `input` (a dataset's, or a source's in batches):
    /// one column per target (per estimator output). No frame at all is
    /// an error naming the input.
    pub fn perceive_input(&mut self, input: &mut PredictInput, data: &Path) -> Result<Perception> {
        let r = match input {
            PredictInput::Dataset(ds) => self.perceive(ds)?,
            PredictInput::Source(source) => self.perceive_source(source)?,
        };
        if r.files.is_empty() {
            return Err(no_frames(data));
        }
        Ok(r)
    }

    /// Every frame of `input` as a stream of records ([`Perception::record`]),
    /// each handed to `on_record` as soon as it is estimated: a source's
    /// one frame at a time (a live frame with its latency), a dataset's
    /// once all its frames are. `on_record` says whether to go on;
    /// `on_warning` gets each of [`Perception::warnings`] before the
    /// records of the frames that raised it.
    pub fn stream_input(
        &mut self,
        input: &mut PredictInput,
        data: &Path,
        on_record: &mut dyn FnMut(serde_json::Value) -> Result<Flow>,
        on_warning: &mut dyn FnMut(&str),
    ) -> Result<Streamed> {
        match input {
            PredictInput::Dataset(_) => {
                let r = self.perceive_input(input, data)?;
                r.warnings.iter().for_each(|w| on_warning(w));
                for i in 0..r.files.len() {
                    if on_record(r.record(i, None))? == Flow::Stop {
                        break;
                    }
                }
                Ok(Streamed {
                    frames: r.files.len(),
                    dropped: None,
                })
            }
            PredictInput::Source(source) => {
                let frames = self.perceive_source_with(source, 1, &mut |batch, arrived| {
                    batch.warnings.iter().for_each(|w| on_warning(w));
                    for i in 0..batch.files.len() {
                        let arrived = arrived.get(i).copied().flatten();
                        if on_record(batch.record(i, arrived))? == Flow::Stop {
                            return Ok(Flow::Stop);
                        }
                    }
                    Ok(Flow::Continue)
                })?;
                source.late_warnings().iter().for_each(|w| on_warning(w));
                if frames == 0 {
                    return Err(no_frames(data));
                }
                let live = source.kind().is_live();
                Ok(Streamed {
                    frames,
                    dropped: live.then(|| source.dropped()),
                })
            }
        }
    }

    /// Every frame of a recorded source (a folder of frames, an image, a
    /// video, a ROS 2 bag's image topic) or a live one that ends (a
    /// camera with a frame limit), in batches as they arrive; a bag's
    /// frames keep their stamps.
    pub fn perceive_source(&mut self, source: &mut FrameSource) -> Result<Perception> {
        let t0 = std::time::Instant::now();
        let mut all = Perception {
            files: Vec::new(),
            stamps_ns: None,
            estimates: Estimates::default(),
            ms_encode: 0.0,
            ms_estimate: 0.0,
            warnings: Vec::new(),
        };
        let mut stamps: Vec<Option<i64>> = Vec::new();
        self.perceive_source_with(source, SOURCE_BATCH, &mut |batch, _| {
            match &batch.stamps_ns {
                Some(s) => stamps.extend(s.iter().map(|&t| Some(t))),
                None => stamps.extend(batch.files.iter().map(|_| None)),
            }
            all.files.extend(batch.files);
            all.estimates.append(batch.estimates)?;
            all.warnings.extend(batch.warnings);
            Ok(Flow::Continue)
        })?;
        all.stamps_ns = stamps.into_iter().collect();
        all.warnings.extend(source.late_warnings());
        all.ms_encode = 1e3 * t0.elapsed().as_secs_f64() / all.files.len().max(1) as f64;
        Ok(all)
    }

    /// The frames of `source` in batches of up to `batch` (1 for a live
    /// stream, each frame estimated as it comes), each handed to `on_batch`
    /// with its estimates and, for live frames, when each arrived; the
    /// batch's `stamps_ns` holds each frame's stamp where it has one (a
    /// bag's). Colour frames are made grey with OpenCV's weights, as a
    /// colour PNG in a dataset is. Returns the frames estimated.
    pub fn perceive_source_with(
        &mut self,
        source: &mut FrameSource,
        batch: usize,
        on_batch: &mut BatchSink<'_>,
    ) -> Result<usize> {
        let batch = batch.clamp(1, SOURCE_BATCH);
        let mut grey: Vec<GreyImage> = Vec::with_capacity(batch);
        let (mut files, mut labels, mut stamps, mut arrived) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        // A stream's length is unknown: its bar counts without a total.
        let known = source.known_frames().unwrap_or(0);
        let pb = tactile_core::progress::progress_bar_if(known, "predict", batch > 1);
        let mut done = 0;
        let mut sizes = FrameSizeCheck::default();
        // Taken once: the model's preprocessings do not change in the loop.
        let cfgs: Vec<PreprocessConfig> = self.preprocessings().into_iter().cloned().collect();
        let mut warnings = Vec::new();
        let (mut flat_frames, mut foreign_frames) = (0, 0);
        // Whether each frame of the batch is flat (left to that warning).
        let mut flat_in_batch: Vec<bool> = Vec::with_capacity(batch);
        loop {
            let frame = source.next_frame()?;
            if let Some(f) = &frame {
                pb.inc(1);
                let (w, h) = (f.image.width(), f.image.height());
                let label = f.label();
                if let Some(why) = sizes.check(w, h, &cfgs) {
                    warnings.push(format!("warning: {label}: {why}"));
                }
                let g = f.grey()?;
                // Named as they come, the first few (a covered camera
                // would name every frame of a stream otherwise).
                let flat = cfgs.first().is_some_and(|c| is_flat_frame(&g, c));
                flat_in_batch.push(flat);
                if flat {
                    flat_frames += 1;
                    if flat_frames <= MAX_FLAT_NAMED {
                        warnings.extend(flat_frames_warning(
                            std::slice::from_ref(&label),
                            flat_frames == MAX_FLAT_NAMED,
                        ));
                    }
                }
                grey.push(g);
                files.push(f.name.clone());
                labels.push(label);
                stamps.push(f.stamp_ns);
                arrived.push(f.arrived);
            }
            if grey.len() == batch || (frame.is_none() && !grey.is_empty()) {
                let (estimates, foreign) =
                    self.perceive_frames_flagging(&grey, &|i| labels.get(i).cloned(), |i| {
                        flat_in_batch[i]
                    })?;
                if let Some(profile) = self.input_profile() {
                    for f in foreign {
                        foreign_frames += 1;
                        if foreign_frames <= MAX_FLAT_NAMED {
                            let wording = match foreign_frames == MAX_FLAT_NAMED {
                                true => Wording::NamedThenUnnamed,
                                false => Wording::Named,
                            };
                            warnings.extend(foreign_frames_warning(
                                std::slice::from_ref(&f),
                                profile,
                                wording,
                            ));
                        }
                    }
                }
                done += grey.len();
                grey.clear();
                labels.clear();
                flat_in_batch.clear();
                let p = Perception {
                    files: std::mem::take(&mut files),
                    stamps_ns: stamps.iter().copied().collect(),
                    estimates,
                    ms_encode: 0.0,
                    ms_estimate: 0.0,
                    warnings: std::mem::take(&mut warnings),
                };
                stamps.clear();
                let flow = on_batch(p, &arrived)?;
                arrived.clear();
                if flow == Flow::Stop {
                    break;
                }
            }
            if frame.is_none() {
                break;
            }
        }
        pb.finish_and_clear();
        Ok(done)
    }

    /// How the model reads a frame: an encoder's preprocessing, or each
    /// of a pose ensemble's (its members may read different pin images).
    pub fn preprocessings(&self) -> Vec<&PreprocessConfig> {
        match self {
            Self::Encoder(p) => vec![&p.encoder.artifact.preprocess],
            Self::PoseNetwork(p) => p.scales().iter().collect(),
        }
    }

    /// Estimators run per frame (the pose network counts as one).
    pub fn estimators(&self) -> usize {
        match self {
            Self::Encoder(p) => p.estimators.len(),
            Self::PoseNetwork(_) => 1,
        }
    }
}

/// Flat (or foreign) frames named one by one in a stream, or in a
/// dataset's warning, before they are only counted.
const MAX_FLAT_NAMED: usize = tactile_core::source::FRAMES_NAMED;

/// The frames of a warning ([`tactile_core::source::named_frames`]) and,
/// when `then_unnamed`, the words saying a stream names no more after
/// these.
fn named_frames(frames: &[String], then_unnamed: bool) -> (String, &'static str, &'static str) {
    let (named, these) = tactile_core::source::named_frames(frames);
    let then = match then_unnamed {
        true => " (any further ones are not named)",
        false => "",
    };
    (named, these, then)
}

/// The warning for frames one grey level throughout their crop
/// ([`is_flat_frame`]) ([`named_frames`]).
fn flat_frames_warning(flat: &[String], then_unnamed: bool) -> Option<String> {
    if flat.is_empty() {
        return None;
    }
    let (named, these, then) = named_frames(flat, then_unnamed);
    Some(format!(
        "warning: {named}: one grey level throughout the crop (a blank, covered or saturated camera?): no pins to read, so the estimates of {these} mean nothing{then}"
    ))
}

/// The warning for frames whose pin images lie outside the model's pin
/// profile ([`PinSet::foreign`](tactile_cae::data::PinSet::foreign))
/// ([`named_frames`]).
fn foreign_frames_warning(
    foreign: &[ForeignFrame],
    profile: &InputProfile,
    wording: Wording,
) -> Option<String> {
    if foreign.is_empty() {
        return None;
    }
    let worst = foreign.iter().map(|f| f.score).fold(f32::NAN, f32::max);
    let files: Vec<String> = foreign.iter().map(|f| f.file.clone()).collect();
    let (named, these, then) = named_frames(&files, wording == Wording::NamedThenUnnamed);
    let threshold = profile.threshold;
    let scored = match (wording, foreign.len()) {
        (Wording::Left, _) => {
            format!(
                "its pin spectrum scores above the {threshold:.1} its own sensor's frames stay below"
            )
        }
        (_, 1) => format!(
            "its pin spectrum scores {worst:.1}; its own sensor's frames stay below {threshold:.1}"
        ),
        _ => format!(
            "its pin spectrum scores up to {worst:.1}; its own sensor's frames stay below {threshold:.1}"
        ),
    };
    Some(format!(
        "warning: {named}: pins spaced unlike those of the {} frames this model was trained on ({scored}): a frame of another sensor, at another scale or crop, or without pins? The estimates of {these} may mean nothing: give frames of the sensor and resolution it was trained on, or train on yours{then}",
        profile.frames
    ))
}

/// How a warning of foreign frames words itself.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Wording {
    /// Their score named (a dataset's frames, in one warning).
    Named,
    /// Their score named, and the words saying a stream names no more
    /// after these.
    NamedThenUnnamed,
    /// No score, so the text repeats alike ([`GivenFrames::warnings`]).
    Left,
}

/// Frames given in a call rather than as a dataset or a source (Python's
/// `TactipEncoder` and `PoseEstimator` calls), preprocessed a chunk at a
/// time so that a long batch never holds more than a chunk's frames and
/// pin images, while it notes what is owed a warning: the blank frames and
/// those whose pin images lie outside the model's pin profile, each named
/// `frames[i]` by its place in the call.
#[derive(Debug, Default)]
pub struct GivenFrames {
    /// Frames preprocessed so far.
    count: usize,
    /// The blank ones, named.
    flat: Vec<String>,
    /// The others outside the pin profile.
    foreign: Vec<ForeignFrame>,
}

impl GivenFrames {
    /// The pin images of the next `frames` of the call, each made grey by
    /// `grey`, per preprocessing of `scales` (an encoder has one, a
    /// multi-scale pose ensemble several); the first one's pins are scored
    /// against `profile`. An error names the frame by its place in the
    /// call; a stop request (Ctrl-C) ends the work between frames.
    pub fn preprocess<F: Sync>(
        &mut self,
        frames: &[F],
        scales: &[PreprocessConfig],
        profile: Option<&InputProfile>,
        grey: impl Fn(&F) -> tactile_core::Result<GreyImage> + Sync,
    ) -> Result<Vec<Vec<PinImage>>> {
        let first = self.count;
        let in_call = |e: tactile_preprocess::Error| e.frame_from(first);
        let Some((cfg, others)) = scales.split_first() else {
            return Ok(Vec::new());
        };
        let (first_pins, flat) =
            tactile_preprocess::preprocess_each_noting_flat(frames, cfg, |f| {
                Ok(Cow::Owned(grey(f)?))
            })
            .map_err(in_call)?;
        let mut pins = vec![first_pins];
        for cfg in others {
            let each =
                tactile_preprocess::preprocess_each_by(frames, cfg, |f| Ok(Cow::Owned(grey(f)?)));
            pins.push(each.map_err(in_call)?);
        }
        let name = |i: usize| format!("frames[{}]", first + i);
        self.flat
            .extend((0..flat.len()).filter(|&i| flat[i]).map(name));
        if let Some(p) = profile {
            self.foreign
                .extend(ForeignFrame::among(p, &pins[0], |i| flat[i], name));
        }
        self.count += frames.len();
        Ok(pins)
    }

    /// The warnings of the frames preprocessed so far: the blank ones, and
    /// the others outside `profile`. Their words hold no score, so a loop
    /// fed the wrong camera repeats one text, which Python's warning
    /// filters show once per call site.
    pub fn warnings(&self, profile: Option<&InputProfile>) -> Vec<String> {
        flat_frames_warning(&self.flat, false)
            .into_iter()
            .chain(profile.and_then(|p| foreign_frames_warning(&self.foreign, p, Wording::Left)))
            .collect()
    }
}

/// A dataset's features ([`encode_dataset`]).
pub struct DatasetFeatures {
    /// Each encoded frame's `file` label.
    pub files: Vec<String>,
    /// Each encoded frame's row in the dataset.
    pub rows: Vec<usize>,
    /// Each encoded frame's features.
    pub features: Vec<Vec<f32>>,
    /// The warnings of its frames ([`dataset_frame_warnings`]).
    pub warnings: Vec<String>,
}

/// Every frame of `ds` encoded by `encoder`
/// ([`TactipEncoder::encode_dataset_flagging`]: a frame that cannot be
/// decoded past its header left out), with the warnings of its frames: what
/// `tactile encode` writes, and `predict` and `evaluate` read.
pub fn encode_dataset(encoder: &mut TactipEncoder, ds: &Dataset) -> Result<DatasetFeatures> {
    let e = encoder.encode_dataset_flagging(ds)?;
    let profile = encoder.artifact.input_profile.as_ref();
    Ok(DatasetFeatures {
        warnings: dataset_frame_warnings(&e.flat, &e.foreign, e.undecodable, profile),
        files: e.files,
        rows: e.rows,
        features: e.features,
    })
}

/// `tactile encode`'s and Python's `TactipEncoder.encode_dataset`'s pass:
/// every frame of `ds` encoded ([`encode_dataset`]), its warnings led by the
/// dataset's frame size when the encoder's preprocessing was not made for
/// it ([`dataset_frame_warning`]); with `out`, a feature CSV
/// (`file,f0,f1,...`) checked before any frame is read (no file of the
/// dataset, no other format's name) and written after.
pub fn encode_dataset_to(
    encoder: &mut TactipEncoder,
    ds: &Dataset,
    out: Option<&Path>,
) -> Result<DatasetFeatures> {
    if let Some(out) = out {
        tactile_core::dataset::check_output_file(out, &[ds])?;
        tactile_core::dataset::refuse_misnamed_results(
            out,
            tactile_core::dataset::ResultsFormat::Csv,
        )?;
    }
    let size = dataset_frame_warning(ds, [&encoder.artifact.preprocess]);
    let mut e = encode_dataset(encoder, ds)?;
    e.warnings.splice(0..0, size);
    if let Some(out) = out {
        tactile_cae::inference::write_features_csv(out, &e.files, &e.features)?;
    }
    Ok(e)
}

/// The warnings of a dataset pass's frames: its blank frames (`flat`),
/// its frames outside the model's pin `profile` (`foreign`), in one
/// warning each, then the pass's own warning of the frames it could not
/// decode past their header and left out (`undecodable`).
pub fn dataset_frame_warnings(
    flat: &[String],
    foreign: &[ForeignFrame],
    undecodable: Option<String>,
    profile: Option<&InputProfile>,
) -> Vec<String> {
    flat_frames_warning(flat, false)
        .into_iter()
        .chain(profile.and_then(|p| foreign_frames_warning(foreign, p, Wording::Named)))
        .chain(undecodable)
        .collect()
}

/// A warning naming `ds` when its frames (the manifest's size) do not suit
/// one of a model's preprocessings `cfgs` ([`FrameSizeCheck`]).
pub fn dataset_frame_warning<'a>(
    ds: &Dataset,
    cfgs: impl IntoIterator<Item = &'a PreprocessConfig>,
) -> Option<String> {
    let (w, h) = (ds.manifest.width as usize, ds.manifest.height as usize);
    FrameSizeCheck::default()
        .check(w, h, cfgs)
        .map(|why| format!("warning: {}: {why}", ds.root.display()))
}

/// The error of an input that gave no frame at all.
fn no_frames(data: &Path) -> crate::Error {
    tactile_core::Error::Invalid(format!("{}: no frames to estimate", data.display())).into()
}

/// The frames `tactile predict` and Python's `tactile.predict` estimate.
pub enum PredictInput {
    /// A dataset folder (it holds `manifest.json`): every row of
    /// `labels.csv`, in order, named by its `file`.
    Dataset(Dataset),
    /// Any other frame source: a folder of frame files, one image,
    /// a video, a ROS 2 bag's image topic, or a camera read for a number
    /// of frames.
    Source(FrameSource),
}

impl PredictInput {
    /// Open `data`, checked before any model loads: a folder with
    /// `manifest.json` is a dataset (and must be a whole one), anything
    /// else a frame source; `topic` picks a bag's image topic, `limit`
    /// keeps the first frames. A live camera needs a limit unless
    /// `streamed` (each frame's estimates go out as it is done), since
    /// otherwise the estimates are written when the frames end.
    pub fn open(
        data: &Path,
        topic: Option<&str>,
        limit: Option<u64>,
        streamed: bool,
    ) -> Result<Self> {
        use tactile_core::source::{SourceOptions, SourceSpec};
        if data.is_dir() && data.join("manifest.json").exists() {
            // A frame source checks its limit itself, a dataset here.
            tactile_core::source::check_limit(limit)?;
            if topic.is_some() {
                return Err(tactile_core::Error::Config(format!(
                    "a topic picks a ROS 2 bag's images; {} is a dataset folder",
                    data.display()
                ))
                .into());
            }
            let mut ds = Dataset::open(data)?;
            if let Some(n) = limit {
                ds.rows.truncate(usize::try_from(n).unwrap_or(usize::MAX));
            }
            return Ok(Self::Dataset(ds));
        }
        let spec = match topic {
            Some(t) => SourceSpec::Bag {
                path: data.to_path_buf(),
                topic: Some(t.to_string()),
            },
            None => SourceSpec::Path(data.to_path_buf()),
        };
        let options = SourceOptions {
            limit,
            ..SourceOptions::default()
        };
        let source = FrameSource::open(&spec, options)?;
        if source.kind().is_live() && limit.is_none() && !streamed {
            return Err(tactile_core::Error::Config(format!(
                "{} is a live {}: give a frame limit (the estimates are written when the frames \
                 end), or stream each frame's estimates as it comes (`tactile predict --out -`; \
                 Python: tactile.frames with tactile.PoseEstimator)",
                tactile_core::source::shown(data),
                match source.kind() {
                    tactile_core::source::SourceKind::Stream => "stream",
                    _ => "camera",
                }
            ))
            .into());
        }
        Ok(Self::Source(source))
    }

    /// What the user should know of the input (gaps in a folder's frame
    /// numbering, one split of a bag read alone).
    pub fn warnings(&self) -> Vec<String> {
        match self {
            Self::Dataset(_) => Vec::new(),
            Self::Source(s) => s.warnings(),
        }
    }

    /// Before any work: `out` can be written and is not part of the input
    /// (`data`, what this was opened from).
    pub fn check_output(&self, data: &Path, out: &Path) -> Result<()> {
        let datasets: Vec<&Dataset> = match self {
            Self::Dataset(ds) => vec![ds],
            Self::Source(_) => Vec::new(),
        };
        tactile_core::dataset::check_run_output(out, Some(data), &datasets)?;
        // After the refusals that say an output would destroy something;
        // an `.mcap` name (ROS 2 messages) is no misnamed CSV.
        Ok(tactile_core::dataset::refuse_misnamed_results(
            out,
            tactile_core::dataset::ResultsFormat::Csv,
        )?)
    }
}

/// What [`Predictor::stream_input`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Streamed {
    /// Frames estimated.
    pub frames: usize,
    /// A live source's frames dropped because the models fell behind.
    pub dropped: Option<u64>,
}

/// What [`Predictor::perceive_source_with`] hands each batch to: the
/// batch's estimates and when each live frame arrived; it says whether to
/// go on.
pub type BatchSink<'a> = dyn FnMut(Perception, &[Option<Instant>]) -> Result<Flow> + 'a;

/// Frames a source's estimates are made of at once.
const SOURCE_BATCH: usize = 64;

/// A pose network's estimates as columns: each target, then with
/// uncertainty each target's `<target>_std`.
fn pose_estimates(names: &[String], values: &[Vec<f64>], std: Option<&[Vec<f64>]>) -> Estimates {
    let column = |rows: &[Vec<f64>], j: usize| {
        tactile_estimate::Column::Number(rows.iter().map(|row| row[j]).collect())
    };
    let mut columns: Vec<_> = (0..names.len())
        .map(|j| (names[j].clone(), column(values, j)))
        .collect();
    if let Some(std) = std {
        columns.extend((0..names.len()).map(|j| {
            (
                tactile_estimate::registry::std_column(&names[j]),
                column(std, j),
            )
        }));
    }
    Estimates { columns }
}

impl Perception {
    /// The CSV's columns: `file`, `stamp_ns` when the frames had stamps,
    /// then every estimate's.
    pub fn header(&self) -> Vec<String> {
        let mut header = vec!["file".to_string()];
        if self.stamps_ns.is_some() {
            header.push("stamp_ns".into());
        }
        header.extend(self.estimates.columns.iter().map(|c| c.0.clone()));
        header
    }

    /// Row `i` of the CSV, the cells of [`Self::header`] (numbers with 4
    /// decimals).
    pub fn row(&self, i: usize) -> Vec<String> {
        let mut row = vec![self.files[i].clone()];
        if let Some(s) = &self.stamps_ns {
            row.push(s[i].to_string());
        }
        row.extend(self.estimates.row(i));
        row
    }

    /// Row `i` as one JSON object, for a stream of records: `file`,
    /// `stamp_ns` (a bag's), `latency_ms` (a live frame's, from its
    /// arrival to now), then every estimate (a number, `null` for NaN, or
    /// a class name).
    pub fn record(&self, i: usize, arrived: Option<Instant>) -> serde_json::Value {
        use serde_json::Value;
        let mut m = serde_json::Map::new();
        m.insert("file".into(), Value::from(self.files[i].clone()));
        if let Some(s) = &self.stamps_ns {
            m.insert("stamp_ns".into(), Value::from(s[i]));
        }
        if let Some(t) = arrived {
            m.insert(
                "latency_ms".into(),
                Value::from(1e3 * t.elapsed().as_secs_f64()),
            );
        }
        for (name, column) in &self.estimates.columns {
            let v = match column {
                tactile_estimate::Column::Number(v) => {
                    serde_json::Number::from_f64(v[i]).map_or(Value::Null, Value::Number)
                }
                tactile_estimate::Column::Class(v) => Value::from(v[i].clone()),
            };
            m.insert(name.clone(), v);
        }
        Value::Object(m)
    }

    /// Write every row as CSV to `path`, atomically.
    pub fn write_csv(&self, path: &Path) -> tactile_core::Result<()> {
        tactile_core::io::write_atomic_with(path, |w| {
            let mut csv = csv::Writer::from_writer(w);
            csv.write_record(self.header())?;
            for i in 0..self.files.len() {
                csv.write_record(self.row(i))?;
            }
            csv.flush()
        })
    }
}

/// What perception made of a dataset or a frame source.
pub struct Perception {
    /// Each frame's `file` label (a source's frame name: its file name,
    /// or its number in a video or on a bag's topic, `000042`).
    pub files: Vec<String>,
    /// Each frame's message stamp, ns since the epoch, when every frame
    /// had one (a ROS 2 bag's).
    pub stamps_ns: Option<Vec<i64>>,
    /// Every estimator's outputs.
    pub estimates: Estimates,
    /// Preprocessing and encoding time per frame, ms.
    pub ms_encode: f64,
    /// Time of all estimators per frame, ms.
    pub ms_estimate: f64,
    /// What the user should know of the frames: each frame size the model
    /// was not made for, named by its first frame ([`FrameSizeCheck`]);
    /// each begins `warning: `, as a frame folder's own do
    /// ([`tactile_core::source::FrameList::warnings`]).
    pub warnings: Vec<String>,
}

impl TactipPerception {
    /// Load `encoder` onto `runtime` and the estimators in `heads` (every
    /// estimator folder inside `encoder` when empty); estimators trained on
    /// features of another length are refused.
    pub fn load(encoder: &Path, heads: &[PathBuf], runtime: Runtime) -> Result<Self> {
        let encoder_net = TactipEncoder::load(encoder, runtime, 0)?;
        let device = runtime
            .device()
            .unwrap_or(tactile_burn::DeviceKind::Flex)
            .device();
        let estimators = Estimators::load(encoder, heads, &device)?;
        let fp = tactile_burn::artifact::fingerprint::<tactile_cae::CaeArtifact>(encoder)?;
        estimators.check_encoder(&fp, encoder_net.feature_count())?;
        Ok(Self {
            encoder: encoder_net,
            estimators,
            dir: encoder.to_path_buf(),
        })
    }

    /// Every estimator on one encoding of each pin image.
    pub fn estimate(&mut self, pins: &[tactile_preprocess::PinImage]) -> Result<Estimates> {
        let feats = self.encoder.encode(pins)?;
        Ok(self.estimators.estimate(&feats)?)
    }

    /// Perceive every frame of a dataset, timing encoding and estimation.
    pub fn perceive(&mut self, ds: &Dataset) -> Result<Perception> {
        let t0 = std::time::Instant::now();
        let DatasetFeatures {
            files,
            features: feats,
            warnings,
            ..
        } = encode_dataset(&mut self.encoder, ds)?;
        let ms_encode = 1e3 * t0.elapsed().as_secs_f64() / ds.len().max(1) as f64;
        let t1 = std::time::Instant::now();
        let estimates = self.estimators.estimate(&feats)?;
        let ms_estimate = 1e3 * t1.elapsed().as_secs_f64() / ds.len().max(1) as f64;
        Ok(Perception {
            files,
            stamps_ns: None,
            estimates,
            ms_encode,
            ms_estimate,
            warnings,
        })
    }

    /// Score every estimator on a labelled dataset, with a warning when
    /// the encoder's notes say it trained on every frame of `ds`
    /// ([`tactile_burn::artifact::scored_on_fitted`]) and those of its
    /// blank frames and frames unlike its training frames.
    /// A frame that cannot be decoded past its header is left out of the
    /// scores with the warning `predict` gives (`decoded_rows`).
    pub fn evaluate(&mut self, ds: &Dataset) -> Result<Scores> {
        let encoded = encode_dataset(&mut self.encoder, ds)?;
        let scored = decoded_rows(ds, &encoded.rows);
        let mut s = score(&self.estimators, &encoded.features, &scored)?;
        s.frame_warnings = encoded.warnings;
        s.warning = tactile_burn::artifact::scored_on_fitted::<tactile_cae::CaeArtifact>(
            &self.dir, &scored,
        );
        Ok(s)
    }
    /// Score every estimator on pin images made otherwise (perturbed
    /// frames) and labelled by the rows of `ds`.
    pub fn evaluate_pins(&mut self, pins: &PinSet, ds: &Dataset) -> Result<Scores> {
        let feats = self.encoder.encode(&pins.images)?;
        Ok(score(&self.estimators, &feats, ds)?)
    }
}

/// Sorted class names of a column and each row's class index. A column of
/// one class is refused: a classifier of it learns nothing and scores
/// 100 %.
pub fn classes_of(ds: &Dataset, column: &str) -> Result<(Vec<String>, Vec<usize>)> {
    let names: Vec<String> = (0..ds.len())
        .map(|i| ds.text(i, column).map(str::to_string))
        .collect::<tactile_core::Result<_>>()?;
    let mut classes = names.clone();
    classes.sort();
    classes.dedup();
    if classes.len() < 2 {
        let what = match classes.first() {
            Some(only) => format!("every one of its {} frames is '{only}'", ds.len()),
            None => "it has no frames".to_string(),
        };
        return Err(tactile_core::Error::dataset(
            ds.labels_path(),
            None,
            format!(
                "column '{column}': {what}, and a classifier needs at least 2 classes to tell apart"
            ),
        )
        .into());
    }
    let y = names
        .iter()
        .map(|n| classes.iter().position(|c| c == n).unwrap_or(0))
        .collect();
    Ok((classes, y))
}

/// A head's accuracy on test frames.
pub struct HeadTest {
    /// Fraction right.
    pub accuracy: f64,
    /// Frames right.
    pub right: usize,
    /// Frames tested.
    pub frames: usize,
    /// `confusion[truth][predicted]`.
    pub confusion: Vec<Vec<usize>>,
    /// What a reader of the accuracy must know: the encoder trained on
    /// the test frames. The CLI notes it on standard error; Python raises
    /// it as a `UserWarning`.
    pub warning: Option<String>,
}

impl HeadTest {
    /// The accuracy and the confusion table (rows: truth) for a person.
    pub fn describe(&self, classes: &[String]) -> Vec<String> {
        let mut lines = vec![
            format!(
                "test shape accuracy: {:.1} % ({}/{})",
                100.0 * self.accuracy,
                self.right,
                self.frames
            ),
            format!(
                "confusion (rows: truth, columns: predicted): {}",
                classes.join(" ")
            ),
        ];
        for (c, row) in classes.iter().zip(&self.confusion) {
            let cells: String = row.iter().map(|v| format!("{v:>5}")).collect();
            lines.push(format!("  {c:>12} {cells}"));
        }
        lines
    }
}

/// Features of the turned copies ([`RotationAugment`]) of the frames at
/// `rows` of `ds`: for each row in order, `copies` feature vectors.
pub fn rotated_features(
    aug: &RotationAugment,
    encoder: &mut TactipEncoder,
    ds: &Dataset,
    rows: &[usize],
) -> Result<Vec<Vec<f32>>> {
    aug.check()?;
    let cfg = encoder.artifact.preprocess.clone();
    let bar = tactile_core::progress::progress_bar(rows.len() as u64, "rotated copies");
    let mut out = Vec::with_capacity(rows.len() * aug.copies);
    // A few hundred frames at a time keeps the pin images' memory small.
    for chunk in rows.chunks(256) {
        let pins: Vec<PinImage> = aug
            .dataset_pins(ds, chunk, &cfg)?
            .into_iter()
            .flatten()
            .collect();
        out.extend(encoder.encode(&pins)?);
        bar.inc(chunk.len() as u64);
    }
    bar.finish_and_clear();
    Ok(out)
}

/// Train the shape head on the `train` split of `ds` (or every row) and
/// save it in `out`; test it on `test` (another dataset, features from the
/// same encoder) or on the `test` split when there is one.
pub fn train_head(
    config: HeadConfig,
    source: &FeatureSource,
    ds: &Dataset,
    test: Option<&Dataset>,
    out: &Path,
    runtime: Runtime,
    rotation: Option<RotationAugment>,
) -> Result<(ClassifierHead, Option<HeadTest>)> {
    if ds.is_empty() {
        return Err(
            tactile_core::Error::dataset(ds.labels_path(), None, "no frames to train on").into(),
        );
    }
    <tactile_estimate::head::HeadArtifact as tactile_burn::Artifact>::check_out_dir(out, &[ds])?;
    ds.expect_columns(["shape"])?;
    let train = ds.split_indices("train").unwrap_or_else(|| ds.every_row());
    // A test set holding training frames (the training folder again, or a
    // copy of its frames' links) would score frames the head fitted.
    if let Some(t) = test {
        let shared = ds.rows_sharing_frames(&train, t);
        if let Some(&j) = shared.first() {
            return Err(tactile_core::Error::dataset(
                t.labels_path(),
                Some(t.rows[j].line),
                format!(
                    "{} of its {} frames are frames the head trains on (this one: '{}'), so its \
                     accuracy would be on frames it fitted: test on frames it does not train on, \
                     or leave --test out (a split column's test rows are then the test)",
                    shared.len(),
                    t.len(),
                    t.text(j, "file")?
                ),
            )
            .into());
        }
    }
    let feats = dataset_features(source, ds, runtime)?;
    let (classes, y) = classes_of(ds, "shape")?;
    let pick = |idx: &[usize]| -> (Vec<Vec<f32>>, Vec<usize>) {
        (
            idx.iter().map(|&i| feats[i].clone()).collect(),
            idx.iter().map(|&i| y[i]).collect(),
        )
    };
    let (mut tx, mut ty) = pick(&train);
    // The frame of each row fitted, so a frame listed twice and its
    // rotated copies fit or stop a member of the ensemble together.
    let mut frames = ds.frame_of_rows(&train);
    if let Some(aug) = rotation {
        aug.check()?;
        let FeatureSource::Encoder(dir) = source else {
            return Err(tactile_core::Error::Invalid(
                "rotation augmentation turns the frames, so it needs an encoder, not a feature file"
                    .into(),
            )
            .into());
        };
        let mut encoder = TactipEncoder::load(dir, runtime, 0)?;
        let turned = rotated_features(&aug, &mut encoder, ds, &train)?;
        for (k, f) in turned.into_iter().enumerate() {
            tx.push(f);
            ty.push(y[train[k / aug.copies]]);
            frames.push(frames[k / aug.copies]);
        }
    }
    let config = HeadConfig {
        inputs: feats[0].len(),
        classes: classes.clone(),
        ..config
    };
    tactile_core::note!(
        "training a {}-fold head ensemble on {} frames",
        config.folds,
        tx.len()
    );
    let device = runtime
        .device()
        .unwrap_or(tactile_burn::DeviceKind::Flex)
        .device();
    let mut head = ClassifierHead::train_by_frame(config, &tx, &ty, &frames, &device)?;
    head.artifact.encoder = encoder_fingerprint(source)?;
    // The rows it fitted (the `train` rows, else every row), as every
    // trainer records them.
    head.artifact.notes = tactile_core::dataset::Provenance::of(&[ds]).notes(match rotation {
        Some(aug) => serde_json::json!({ "rotation_augment": aug }),
        None => serde_json::json!({}),
    });
    // Weights and config of one run, never of two into the same folder.
    let _lock = tactile_core::io::FolderLock::creating(out)?;
    head.save(out)?;
    // The test frames: the `--test` set's, else the `split` column's.
    let test_rows = match test {
        Some(t) => Some((t, (0..t.len()).collect::<Vec<_>>())),
        None => ds.split_indices("test").map(|rows| (ds, rows)),
    };
    let test_set: Option<(Vec<Vec<f32>>, Vec<usize>)> = match test {
        Some(t) => {
            let f = dataset_features(source, t, runtime)?;
            let y = (0..t.len())
                .map(|i| {
                    let s = t.text(i, "shape")?;
                    classes.iter().position(|c| c == s).ok_or_else(|| {
                        tactile_core::Error::dataset(
                            t.labels_path(),
                            Some(t.rows[i].line),
                            format!("shape '{s}' was not in the training set"),
                        )
                    })
                })
                .collect::<tactile_core::Result<Vec<_>>>()?;
            Some((f, y))
        }
        None => test_rows.as_ref().map(|(_, rows)| pick(rows)),
    };
    let warning = match (source, &test_rows) {
        (FeatureSource::Encoder(dir), Some((t, rows))) => {
            encoder_trained_on(dir, t, rows).map(|saw| {
                format!(
                    "the encoder {saw}, so the accuracy is on frames its features fitted: for a held-out accuracy train the encoder without them (on the `train` rows only, or on another recording)"
                )
            })
        }
        _ => None,
    };
    let tested = match test_set {
        Some((sx, sy)) => {
            let pred = head.predict(&sx)?;
            Some(HeadTest {
                accuracy: accuracy(&pred, &sy),
                right: pred.iter().zip(&sy).filter(|(a, b)| a == b).count(),
                frames: sy.len(),
                confusion: confusion(&pred, &sy, classes.len()),
                warning,
            })
        }
        None => None,
    };
    Ok((head, tested))
}

/// How a regressor is trained on a dataset.
#[derive(Debug, Clone)]
pub struct RegressorPlan {
    /// What it predicts.
    pub targets: Vec<Target>,
    /// Hidden widths (ReLU).
    pub hidden: Vec<usize>,
    /// Without a `split` column: fraction of frames held out for testing
    /// (0: none, every frame trains; the final model).
    pub test_fraction: f64,
    /// Fraction of the training frames used for early stopping.
    pub val_fraction: f64,
    /// Split and weight seed.
    pub seed: u64,
    /// Train on the frames of every split (`val`, `test` too; a share of
    /// them still stops it): the final model.
    pub every_split: bool,
    /// Use only frames where every target is labelled; otherwise an empty
    /// label is an error.
    pub only_labelled: bool,
    /// Train only on frames of these shapes (the `shape` label): a
    /// specialised regressor, such as a sphere's position. Empty: every
    /// frame.
    pub shapes: Vec<String>,
    /// The loss on the standardised targets (MSE: the default; L1: the
    /// reported metric's).
    pub loss: RegressionLoss,
    /// Also give each target's standard deviation, calibrated on the
    /// early-stopping frames (linear targets only).
    pub uncertainty: bool,
}

impl RegressorPlan {
    /// The defaults: the regressor's own hidden widths and seed, 20 % of the
    /// frames for testing and 20 % of the rest for early stopping.
    pub fn new(targets: Vec<Target>) -> Self {
        let defaults = RegressorConfig::new(0, Vec::new());
        Self {
            targets,
            hidden: defaults.hidden.iter().map(|h| h.0).collect(),
            test_fraction: 0.2,
            val_fraction: 0.2,
            seed: defaults.schedule.seed,
            every_split: false,
            only_labelled: false,
            shapes: Vec::new(),
            uncertainty: false,
            loss: RegressionLoss::Mse,
        }
    }
}

/// A trained regressor and its test error.
pub struct RegressorFit {
    /// The regressor.
    pub regressor: Regressor,
    /// Frames of each split: train, validation, test.
    pub frames: [usize; 3],
    /// Mean absolute error per target on the test frames (empty with no
    /// test frames).
    pub test_mae: Vec<f64>,
    /// What a reader of the model and its test error must know: a target
    /// labelled with one value on every training frame, the encoder trained
    /// on test frames. The CLI notes them on standard error; Python raises
    /// them as `UserWarning`s.
    pub warnings: Vec<String>,
}

impl RegressorFit {
    /// Lines for a person: the test error per target, or that every
    /// frame trained.
    pub fn describe(&self, targets: &[Target]) -> String {
        if self.frames[2] == 0 {
            return format!(
                "every frame trained ({} for early stopping); no test frames",
                self.frames[1]
            );
        }
        let mut s = format!("test mean absolute error ({} frames):", self.frames[2]);
        for (t, e) in targets.iter().zip(&self.test_mae) {
            s.push_str(&format!("\n  {:<14} {e:.4}", t.name));
        }
        s
    }
}

/// Train a regressor on `ds` and save it in `out`.
pub fn train_regressor(
    plan: &RegressorPlan,
    source: &FeatureSource,
    ds: &Dataset,
    out: &Path,
    runtime: Runtime,
) -> Result<RegressorFit> {
    <tactile_estimate::regressor::RegressorArtifact as tactile_burn::Artifact>::check_out_dir(
        out,
        &[ds],
    )?;
    ds.expect_columns(plan.targets.iter().map(|t| t.name.as_str()))?;
    let feats = dataset_features(source, ds, runtime)?;
    // Every target must be labelled on every frame used: with
    // `only_labelled`, frames missing one are left out of every split.
    let labels = (0..ds.len())
        .map(|i| -> tactile_core::Result<Option<Vec<f64>>> {
            if !plan.shapes.is_empty()
                && !plan
                    .shapes
                    .iter()
                    .any(|k| Some(k.as_str()) == ds.text_opt(i, "shape"))
            {
                return Ok(None);
            }
            let mut row = Vec::with_capacity(plan.targets.len());
            for t in &plan.targets {
                match (ds.target_opt(i, &t.name)?, plan.only_labelled) {
                    (Some(v), _) => row.push(v),
                    (None, true) => return Ok(None),
                    (None, false) => row.push(ds.target(i, &t.name)?),
                }
            }
            Ok(Some(row))
        })
        .collect::<tactile_core::Result<Vec<_>>>()?;
    let mut s = if plan.test_fraction == 0.0 || plan.every_split {
        // The final model: every frame trains (of every split with
        // `every_split`), a share of them for early stopping; nothing is
        // left to test on.
        let rows = ds.rows_to_fit(plan.every_split, None)?;
        let (train, val) = ds.hold_out(rows, plan.val_fraction, plan.seed)?;
        tactile_core::dataset::Splits {
            train,
            val,
            test: Vec::new(),
        }
    } else {
        ds.three_way_split(plan.test_fraction, plan.val_fraction, plan.seed)?
    };
    for rows in [&mut s.train, &mut s.val, &mut s.test] {
        rows.retain(|&i| labels[i].is_some());
    }
    let wants_test = plan.test_fraction > 0.0 && !plan.every_split;
    if s.train.is_empty() || s.val.is_empty() || (s.test.is_empty() && wants_test) {
        return Err(tactile_core::Error::dataset(
            ds.labels_path(),
            None,
            format!(
                "too few frames with every target labelled (and of the shapes asked for): {} train, {} validation, {} test",
                s.train.len(),
                s.val.len(),
                s.test.len()
            ),
        )
        .into());
    }
    let labels: Vec<Vec<f64>> = labels.into_iter().map(Option::unwrap_or_default).collect();
    let pick = |idx: &[usize]| -> (Vec<Vec<f32>>, Vec<Vec<f64>>) {
        (
            idx.iter().map(|&i| feats[i].clone()).collect(),
            idx.iter().map(|&i| labels[i].clone()).collect(),
        )
    };
    let (tx, ty) = pick(&s.train);
    let (vx, vy) = pick(&s.val);
    let (sx, sy) = pick(&s.test);
    tactile_core::note!(
        "training a regressor for {} on {} frames ({} validation, {} test)",
        plan.targets
            .iter()
            .map(|t| t.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        tx.len(),
        vx.len(),
        sx.len()
    );
    let mut cfg = RegressorConfig::new(feats[0].len(), plan.targets.clone())
        .with_hidden(plan.hidden.iter().map(|&w| (w, Activation::Relu)).collect())
        .with_loss((plan.loss != RegressionLoss::Mse).then_some(plan.loss))
        .with_uncertainty(plan.uncertainty.then_some(true));
    cfg.schedule.seed = plan.seed;
    let device = runtime
        .device()
        .unwrap_or(tactile_burn::DeviceKind::Flex)
        .device();
    let mut regressor = Regressor::train(cfg, (&tx, &ty), (&vx, &vy), &device)?;
    regressor.artifact.encoder = encoder_fingerprint(source)?;
    regressor.artifact.shapes = plan.shapes.clone();
    // Which rows it trained on, as a pose network records them, so a
    // calibration on them can say so.
    let final_model = plan.every_split || plan.test_fraction == 0.0;
    regressor.artifact.notes = tactile_core::dataset::Provenance::of(&[ds])
        .every_split(plan.every_split)
        .excluding_test(
            (!final_model).then_some(tactile_core::dataset::TestHoldout {
                test_fraction: plan.test_fraction,
                split_seed: plan.seed,
            }),
        )
        .notes(serde_json::json!({}));
    let _lock = tactile_core::io::FolderLock::creating(out)?;
    regressor.save(out)?;
    let test_mae = if sx.is_empty() {
        Vec::new()
    } else {
        regressor.evaluate(&sx, &sy)?
    };
    let warnings = match source {
        FeatureSource::Encoder(dir) if !s.test.is_empty() => {
            encoder_trained_on(dir, ds, &s.test).map(|saw| {
                format!(
                    "the encoder {saw}, so the test error is on frames its features fitted: for a held-out error train the encoder {}, or test on another recording",
                    holdout_cure(ds, plan.test_fraction, plan.seed)
                )
            })
        }
        _ => None,
    };
    let unvarying = tactile_estimate::target::unvarying_targets(
        &plan.targets,
        &ty,
        &ds.labels_path().display().to_string(),
    );
    Ok(RegressorFit {
        regressor,
        frames: [tx.len(), vx.len(), sx.len()],
        test_mae,
        warnings: unvarying.into_iter().chain(warnings).collect(),
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn refusal(dir: &Path) -> String {
        match Predictor::load(dir, &[], Runtime::BurnFlex) {
            Ok(_) => panic!("{} loaded", dir.display()),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn a_folder_that_is_no_tactip_model_is_named_with_what_it_holds() {
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path();
        // The folder above the models: they are named.
        for (sub, file) in [("cae-a", "cae.json"), ("pose-b", "pose.json")] {
            std::fs::create_dir(root.join(sub)).unwrap();
            std::fs::write(root.join(sub).join(file), "{}").unwrap();
        }
        let e = refusal(root);
        assert!(
            e.contains("not a TacTip model folder")
                && e.contains("cae-a, pose-b in it are: pass one"),
            "{e}"
        );
        // A palpation model, or a detector's ensemble: its files are named.
        let depth = root.join("depth");
        std::fs::create_dir(&depth).unwrap();
        std::fs::write(depth.join("depth.json"), "{}").unwrap();
        let e = refusal(&depth);
        assert!(
            e.contains("it holds depth.json: a model `predict` and `evaluate` do not run"),
            "{e}"
        );
        let det = root.join("detector");
        std::fs::create_dir_all(det.join("member-0")).unwrap();
        std::fs::write(det.join("ensemble.json"), "{}").unwrap();
        std::fs::write(det.join("member-0/detector.json"), "{}").unwrap();
        let e = refusal(&det);
        assert!(e.contains("it holds ensemble.json"), "{e}");
        // A file, and a folder that does not exist.
        let e = refusal(&depth.join("depth.json"));
        assert!(e.contains("depth.json: not a model folder (a file)"), "{e}");
        let e = refusal(&root.join("nowhere"));
        assert!(e.contains("nowhere: model folder does not exist"), "{e}");
    }

    /// Estimator folders read an encoder's features: given with a pose
    /// network they are refused, not left unread; one that is no estimator
    /// is named as such.
    #[test]
    fn estimator_folders_go_with_an_encoder_only() {
        let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
        let head = models.join("cae-surface/pose");
        let e = match Predictor::load(&models.join("pose-surface"), &[head], Runtime::BurnFlex) {
            Ok(_) => panic!("a pose network took estimator folders"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.contains("pose-surface: a pose network")
                && e.contains("--heads")
                && e.contains("cae-surface/pose"),
            "{e}"
        );
        let nothing = tempfile::tempdir().unwrap();
        let e = match Predictor::load(
            &models.join("cae-surface"),
            &[nothing.path().to_path_buf()],
            Runtime::BurnFlex,
        ) {
            Ok(_) => panic!("an empty folder was taken for an estimator"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.contains(
                ": not an estimator folder (no head.json, regressor.json or ensemble of regressors)"
            ),
            "{e}"
        );
    }
}
