//! Training the pose network: Adam on the mean squared error of the
//! standardised target columns, label-preserving augmentation, early
//! stopping on the validation loss, best model kept, resumable.

use std::path::Path;

use burn::config::Config;
use burn::tensor::{Device, Tensor, TensorData};
use tactile_burn::train::{FitConfig, FitSummary, Schedule, fit};
use tactile_burn::{Artifact, DeviceKind};
use tactile_core::dataset::{Dataset, Provenance, TestHoldout};
use tactile_estimate::Target;
use tactile_estimate::regressor::{decode, encode, output_scaler, target_mae};
use tactile_preprocess::profile::InputProfile;
use tactile_preprocess::{Downsample, Lighting, PreprocessConfig};

use crate::artifact::PoseArtifact;
use crate::data::{Augment, PoseSet};
use crate::model::{PoseNet, PoseNetConfig};
use crate::{Error, Result};

/// Grey pin images of `side` pixels from 256 px TacTip frames: the
/// central 256 px, a 100 px circular mask (the sensor's tip), area
/// downsampling, grey levels kept (each pin's sub-pixel position is the
/// fraction of an output pixel it covers).
pub fn grey_pin_images(side: usize) -> PreprocessConfig {
    PreprocessConfig {
        lighting: Lighting::None {},
        equalize: false,
        threshold: None,
        mask_radius_px: Some(100.0),
        open_px: 0,
        grow_px: 0,
        crop_px: 256,
        output_px: side,
        binarise_offset: 0.3,
        downsample: Downsample::Area,
        binarise: false,
        align: None,
    }
}

/// The pose network's training loss (shared with the autoencoder's joint
/// head).
pub use tactile_burn::nn::RegressionLoss as PoseLoss;

/// Training settings.
#[derive(Config, Debug)]
pub struct PoseTrainingConfig {
    /// What it predicts, each a label column (`theta_deg` may be an angle).
    pub targets: Vec<Target>,
    /// The architecture (its `input_px` must be the preprocessing's side
    /// and its `outputs` the targets' columns; [`Self::checked`] sets both).
    #[config(default = "PoseNetConfig::new()")]
    pub model: PoseNetConfig,
    /// How frames become pin images (saved with the model).
    #[config(default = "grey_pin_images(64)")]
    pub preprocess: PreprocessConfig,
    /// Adam, batch 32, learning rate 1e-3 decaying 3 % per epoch.
    #[config(default = "Schedule::new(32, 80, 12, 1e-3).with_lr_decay(0.97).with_seed(7)")]
    pub schedule: Schedule,
    /// Label-preserving augmentation of the training frames.
    #[config(default = "Augment::new()")]
    pub augment: Augment,
    /// Fraction of the training rows held out for early stopping.
    #[config(default = 0.2)]
    pub val_fraction: f64,
    /// Without a `split` column: leave out the test frames a later
    /// evaluation with this split holds out.
    #[config(default = "None")]
    pub holdout: Option<TestHoldout>,
    /// Train on every training row for exactly `max_epochs` (the final
    /// model, its epoch count chosen on a validated run); the loss on the
    /// training rows is what the curves show.
    #[config(default = false)]
    pub all_rows: bool,
    /// The training loss, MSE when absent (configs written before it
    /// load unchanged); early stopping always compares the validation MSE.
    #[config(default = "None")]
    pub loss: Option<PoseLoss>,
    /// Train on the rows of every split, `val` and `test` too (the final
    /// model, its recipe chosen on a run that left them out).
    #[config(default = "None")]
    pub every_split: Option<bool>,
    /// With uncertainty and `all_rows` (no frame left unfitted to calibrate
    /// on): take the calibration of the pose network in this folder, the
    /// same recipe validated on frames it did not fit.
    #[config(default = "None")]
    pub calibration_from: Option<String>,
}

impl PoseTrainingConfig {
    /// The config with the model's input side and outputs made to agree
    /// with the preprocessing and targets, and every value checked.
    pub fn checked(mut self) -> Result<Self> {
        self.model.input_px = self.preprocess.output_px;
        self.model.outputs = self.targets.iter().map(Target::width).sum();
        self.model.check()?;
        self.preprocess.check()?;
        self.schedule.check()?;
        self.augment.check()?;
        tactile_core::dataset::check_val_fraction(self.val_fraction)?;
        tactile_core::dataset::check_every_split(self.every_split == Some(true), self.holdout)?;
        if self.calibration_from.is_some() && !self.model.has_uncertainty() {
            return Err(tactile_core::Error::Config(
                "calibration_from is for a network with uncertainty".into(),
            )
            .into());
        }
        if self.targets.is_empty() {
            return Err(tactile_core::Error::Config("no targets to predict".into()).into());
        }
        if self.model.has_uncertainty() {
            crate::uncertainty::check_linear(&self.targets).map_err(tactile_core::Error::Config)?;
        }
        let signs = self.augment.half_turn.iter().flat_map(|s| s.keys());
        if let Some(name) = signs
            .into_iter()
            .find(|n| !self.targets.iter().any(|t| &t.name == *n))
        {
            return Err(tactile_core::Error::Config(format!(
                "half_turn: {name} is not one of the targets ({})",
                self.targets
                    .iter()
                    .map(|t| t.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
            .into());
        }
        Ok(self)
    }
}

/// Frames per network call when predicting.
pub const PREDICT_BATCH: usize = 128;

/// Standardised output columns of `model` on the frames `rows` of `set`.
pub fn predict_columns(
    model: &PoseNet,
    set: &PoseSet,
    rows: &[usize],
    device: &Device,
) -> Result<Vec<Vec<f32>>> {
    let mut out = Vec::with_capacity(rows.len());
    for chunk in rows.chunks(PREDICT_BATCH) {
        let (x, _) = set.batch(chunk, &Augment::none(), (0, 0), device);
        let y = model.forward(x);
        let k = y.dims()[1];
        let v: Vec<f32> = y
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .map_err(|e| tactile_core::Error::Invalid(format!("reading predictions: {e:?}")))?;
        out.extend(v.chunks(k).map(<[f32]>::to_vec));
    }
    Ok(out)
}

/// Train on the training rows of `data` and write everything into `out`:
/// `pose.json`/`pose.bpk` (best model), `curves.csv`/`curves.png`,
/// `training.json` (with the kept model's validation MAE per target) and
/// `checkpoint/`.
pub fn train(
    config: &PoseTrainingConfig,
    data: &Dataset,
    out: &Path,
    device: DeviceKind,
    resume: bool,
) -> Result<FitSummary> {
    let config = &config.clone().checked()?;
    <crate::PoseArtifact as tactile_burn::Artifact>::check_out_dir(out, &[data])?;
    data.expect_columns(config.targets.iter().map(|t| t.name.as_str()))?;
    tactile_core::note!("preprocessing {} frames", data.len());
    let set = PoseSet::from_dataset(data, &config.preprocess, &config.targets)?;
    let rows = data.rows_to_fit(config.every_split == Some(true), config.holdout)?;
    let candidates = rows.len();
    let rows = set.labelled(&rows);
    if rows.len() < 2 && candidates >= 2 {
        let names: Vec<&str> = config.targets.iter().map(|t| t.name.as_str()).collect();
        return Err(tactile_core::Error::dataset(
            data.labels_path(),
            None,
            format!(
                "{} of {candidates} training frames have every target labelled ({}); choose targets this dataset labels",
                rows.len(),
                names.join(", ")
            ),
        )
        .into());
    }
    let (train, val) = if config.all_rows {
        (rows.clone(), rows)
    } else {
        data.hold_out(rows, config.val_fraction, config.schedule.seed)?
    };
    let train_labels = set.label_rows(&train);
    let warnings = tactile_estimate::target::unvarying_targets(
        &config.targets,
        &train_labels,
        &data.labels_path().display().to_string(),
    );
    for w in &warnings {
        tactile_core::note!("warning: {w}");
    }
    let encoded = encode(&config.targets, &train_labels);
    let outputs = output_scaler(&config.targets, &encoded);
    let k = config.model.outputs;
    // Standardised target columns of every row, for the loss.
    let mut columns = vec![Vec::new(); set.pins.len()];
    for (&i, e) in train.iter().zip(outputs.apply(&encoded).chunks(k)) {
        columns[i] = e.to_vec();
    }
    let turned = config
        .augment
        .half_turn
        .as_ref()
        .map(|signs| TurnedLabels::new(&config.targets, signs, &set, &train, &outputs));
    let val_truth = set.label_rows(&val);
    let unc = config.model.has_uncertainty();
    let borrowed_scale = match (&config.calibration_from, unc) {
        (Some(dir), true) => Some(borrowed_calibration(Path::new(dir), &config.targets)?),
        (Some(_), false) => {
            return Err(tactile_core::Error::Config(
                "calibration_from is for a network with uncertainty".into(),
            )
            .into());
        }
        (None, true) if config.all_rows => {
            tactile_core::note!(
                "uncertainty calibrated on the training rows (every row is fitted): its intervals will be too narrow; give calibration_from a validated run"
            );
            None
        }
        _ => None,
    };
    let artifact = PoseArtifact {
        model: config.model.clone(),
        preprocess: config.preprocess.clone(),
        targets: config.targets.clone(),
        outputs: outputs.clone(),
        std_scale: None,
        input_profile: InputProfile::of_training_pins(
            &train
                .iter()
                .map(|&i| &set.pins.images[i])
                .collect::<Vec<_>>(),
        )?,
        notes: Provenance::of(&[data])
            .every_split(config.every_split == Some(true))
            .excluding_test(config.holdout)
            .notes(serde_json::json!({
                "device": device.name(),
                "all_rows": config.all_rows,
            })),
    };
    let dev = device.device();
    let ad = dev.clone().autodiff();
    ad.seed(config.schedule.seed);
    let model = config.model.init(&ad);
    let loss = config.loss.unwrap_or_default();
    let title = format!("Pose network training ({}, standardised)", loss.name());
    let fit_cfg = FitConfig::new(&config.schedule, &title)
        .saving_to(out, resume)
        .with_checkpoint_every(5)
        .with_run_id(tactile_burn::artifact::run_fingerprint(config, &[data])?);
    let unfinished = tactile_burn::artifact::Unfinished::begin(out)?;
    let seed = config.schedule.seed;
    let last_mae = std::cell::RefCell::new(Vec::new());
    let last_scale = std::cell::RefCell::new(None::<Vec<f64>>);
    let (_, mut summary) = fit::<_, Error>(
        &fit_cfg,
        model,
        burn::optim::AdamConfig::new().init(),
        (&train, val.len()),
        |m: &PoseNet, batch, epoch| {
            let round = (seed, epoch as u64 + 1);
            let (x, turns) = set.batch(batch, &config.augment, round, &ad);
            let out = m.forward(x);
            let Some(turned) = &turned else {
                let y: Vec<f32> = batch.iter().flat_map(|&i| columns[i].clone()).collect();
                let y = Tensor::<2>::from_data(TensorData::new(y, [batch.len(), k]), &ad);
                let diff = out.clone().narrow(1, 0, k) - y;
                let fit = loss.penalty(diff.clone()).mean();
                return Ok(if unc {
                    fit + crate::uncertainty::laplace_nll(diff, out.narrow(1, k, k)).mean()
                } else {
                    fit
                });
            };
            // Turned copies: their turned labels, and only the targets the
            // turn keeps count (the mean is over the columns that count).
            let (mut y, mut weight) = (Vec::new(), Vec::new());
            for (&i, turn) in batch.iter().zip(turns) {
                if turn {
                    y.extend_from_slice(&turned.columns[i]);
                    weight.extend_from_slice(&turned.weight);
                } else {
                    y.extend_from_slice(&columns[i]);
                    weight.extend(std::iter::repeat_n(1.0f32, k));
                }
            }
            let counted = weight.iter().sum::<f32>().max(1.0);
            let y = Tensor::<2>::from_data(TensorData::new(y, [batch.len(), k]), &ad);
            let w = Tensor::<2>::from_data(TensorData::new(weight, [batch.len(), k]), &ad);
            let diff = out.clone().narrow(1, 0, k) - y;
            let mut per = loss.penalty(diff.clone());
            if unc {
                per = per + crate::uncertainty::laplace_nll(diff, out.narrow(1, k, k));
            }
            Ok((per * w).sum() / counted)
        },
        |m| {
            let all = predict_columns(m, &set, &val, &dev)?;
            let cols: Vec<&[f32]> = all.iter().map(|r| &r[..k]).collect();
            let pred: Vec<Vec<f64>> = cols
                .iter()
                .map(|r| decode(&config.targets, &outputs, r))
                .collect();
            if unc {
                let truth = outputs.apply(&encode(&config.targets, &val_truth));
                *last_scale.borrow_mut() = Some(crate::uncertainty::calibrate_raw(
                    all.iter().map(Vec::as_slice),
                    &truth,
                    k,
                ));
            }
            let mse = cols
                .iter()
                .zip(
                    outputs
                        .apply(&encode(&config.targets, &val_truth))
                        .chunks(k),
                )
                .map(|(p, t)| {
                    p.iter()
                        .zip(t)
                        .map(|(a, b)| ((a - b) as f64).powi(2))
                        .sum::<f64>()
                })
                .sum::<f64>()
                / (cols.len() * k).max(1) as f64;
            let mae = target_mae(&config.targets, &pred, &val_truth);
            let first = mae.first().copied();
            *last_mae.borrow_mut() = mae;
            Ok((mse, first))
        },
        |m| {
            let mut a = artifact.clone();
            if unc {
                a.std_scale = borrowed_scale
                    .clone()
                    .or_else(|| last_scale.borrow().clone());
            }
            if let serde_json::Value::Object(n) = &mut a.notes {
                n.insert(
                    "validation_mae".into(),
                    serde_json::json!(*last_mae.borrow()),
                );
            }
            Ok(a.save(m, out)?)
        },
    )?;
    let kept = PoseArtifact::read_unfinished(out)?;
    let mae: Vec<f64> = kept
        .notes
        .get("validation_mae")
        .and_then(|v| serde_json::from_value(v.clone()).ok())
        .unwrap_or_default();
    summary.warnings = warnings;
    tactile_burn::artifact::write_training_record(
        out,
        config,
        &summary,
        serde_json::json!({ "train_frames": train.len(), "val_frames": val.len(), "validation_mae": mae }),
    )?;
    unfinished.finish()?;
    Ok(summary)
}

/// The standardised columns of the training rows' labels turned half a
/// turn (each named target times its sign), and which output columns a
/// turned copy trains (1) or leaves out of its loss (0).
struct TurnedLabels {
    /// Per set row (empty for rows that are not trained on).
    columns: Vec<Vec<f32>>,
    /// Per output column.
    weight: Vec<f32>,
}

impl TurnedLabels {
    fn new(
        targets: &[Target],
        signs: &std::collections::BTreeMap<String, f64>,
        set: &PoseSet,
        train: &[usize],
        outputs: &tactile_estimate::regressor::Scaler,
    ) -> Self {
        let sign = |t: &Target| signs.get(&t.name).copied();
        let rows: Vec<Vec<f64>> = set
            .label_rows(train)
            .into_iter()
            .map(|r| {
                r.iter()
                    .zip(targets)
                    .map(|(v, t)| v * sign(t).unwrap_or(1.0))
                    .collect()
            })
            .collect();
        let k: usize = targets.iter().map(Target::width).sum();
        let mut columns = vec![Vec::new(); set.pins.len()];
        for (&i, e) in train
            .iter()
            .zip(outputs.apply(&encode(targets, &rows)).chunks(k))
        {
            columns[i] = e.to_vec();
        }
        let weight = targets
            .iter()
            .flat_map(|t| std::iter::repeat_n(f32::from(u8::from(sign(t).is_some())), t.width()))
            .collect();
        Self { columns, weight }
    }
}

/// The uncertainty calibration of the validated pose network in `dir`,
/// which must predict `targets` with uncertainty.
fn borrowed_calibration(dir: &Path, targets: &[Target]) -> Result<Vec<f64>> {
    let a = PoseArtifact::read(dir)?;
    match a.std_scale {
        Some(s) if a.targets == targets => Ok(s),
        _ => Err(tactile_core::Error::model(
            dir.join("pose.json"),
            "calibration_from needs a pose network with uncertainty for the same targets",
        )
        .into()),
    }
}

/// A pose network's errors on the test rows of a split.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PoseScores {
    /// Target names.
    pub targets: Vec<String>,
    /// Mean absolute error per target, labels' units.
    pub mae: Vec<f64>,
    /// Test frames scored.
    pub frames: usize,
}

impl PoseScores {
    /// One line for a person.
    pub fn describe(&self) -> String {
        let parts: Vec<String> = self
            .targets
            .iter()
            .zip(&self.mae)
            .map(|(t, m)| format!("{t} {m:.4}"))
            .collect();
        format!(
            "{} held-out test frames (never trained on): MAE {}",
            self.frames,
            parts.join(", ")
        )
    }
}

/// Score the pose network in `dir` on the test rows that `holdout` leaves
/// out of `data` (the frames [`train`] with that holdout never saw).
pub fn test_scores(
    dir: &Path,
    data: &Dataset,
    holdout: TestHoldout,
    runtime: tactile_burn::Runtime,
) -> Result<PoseScores> {
    let mut est = crate::PoseEstimator::load(dir, runtime, 0)?;
    let split = data.three_way_split(holdout.test_fraction, 0.2, holdout.split_seed)?;
    let targets = est.artifact.targets.clone();
    let set = PoseSet::from_rows(data, &split.test, &est.artifact.preprocess, &targets)?;
    let rows = set.labelled(&(0..split.test.len()).collect::<Vec<_>>());
    let pins: Vec<_> = rows.iter().map(|&i| set.pins.images[i].clone()).collect();
    let pred = est.predict(&pins)?;
    Ok(PoseScores {
        targets: targets.iter().map(|t| t.name.clone()).collect(),
        mae: target_mae(&targets, &pred, &set.label_rows(&rows)),
        frames: rows.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A turned copy's labels are each named target times its sign,
    /// standardised as the others; only the named targets count.
    #[test]
    fn turned_labels_negate_what_the_turn_negates_and_weigh_only_those() {
        let targets: Vec<Target> = ["depth_mm", "shear_x_mm", "shear_theta_deg"]
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        let labels = [[1.0, 2.0, 3.0], [2.0, -1.0, 1.0], [4.0, 0.5, -2.0]];
        let set = PoseSet {
            pins: tactile_cae::data::PinSet {
                files: vec!["f".into(); 3],
                rows: Vec::new(),
                flat: Vec::new(),
                images: vec![
                    tactile_preprocess::PinImage {
                        side: 1,
                        pixels: vec![0.0],
                    };
                    3
                ],
            },
            labels: labels.iter().map(|r| r.map(Some).to_vec()).collect(),
        };
        let train = [0, 2];
        let encoded = encode(&targets, &set.label_rows(&train));
        let outputs = output_scaler(&targets, &encoded);
        let signs = std::collections::BTreeMap::from([
            ("shear_x_mm".to_string(), -1.0),
            ("shear_theta_deg".to_string(), 1.0),
        ]);
        let t = TurnedLabels::new(&targets, &signs, &set, &train, &outputs);
        assert_eq!(t.weight, vec![0.0, 1.0, 1.0]);
        assert!(t.columns[1].is_empty(), "row 1 is not trained on");
        for &i in &train {
            let back = decode(&targets, &outputs, &t.columns[i]);
            let want = [labels[i][0], -labels[i][1], labels[i][2]];
            for (b, w) in back.iter().zip(want) {
                assert!((b - w).abs() < 1e-5, "{back:?} {want:?}");
            }
        }
        // A sign for a target the network does not predict is refused
        // before any frame is read.
        let mut c = PoseTrainingConfig::new(targets);
        c.augment = c
            .augment
            .with_half_turn(Some(std::collections::BTreeMap::from([(
                "roll_deg".to_string(),
                -1.0,
            )])));
        let e = c.checked().unwrap_err().to_string();
        assert!(
            e.contains("half_turn: roll_deg is not one of the targets"),
            "{e}"
        );
    }

    /// Configs written before the loss option load as MSE; `"l1"` is read
    /// and written back by name; an unknown loss is refused, not ignored.
    #[test]
    fn the_loss_is_optional_named_and_checked() {
        // A training config as a network trained before the option saved it.
        let mut v = serde_json::to_value(PoseTrainingConfig::new(vec![])).unwrap();
        v.as_object_mut().unwrap().remove("loss");
        let old: PoseTrainingConfig = serde_json::from_value(v).unwrap();
        assert_eq!(old.loss, None);
        assert_eq!(old.loss.unwrap_or_default(), PoseLoss::Mse);
        let mut v = serde_json::to_value(&old).unwrap();
        v["loss"] = "l1".into();
        let l1: PoseTrainingConfig = serde_json::from_value(v.clone()).unwrap();
        assert_eq!(l1.loss, Some(PoseLoss::L1));
        assert_eq!(serde_json::to_value(&l1).unwrap()["loss"], "l1");
        v["loss"] = "huber".into();
        assert!(serde_json::from_value::<PoseTrainingConfig>(v).is_err());
    }
}
