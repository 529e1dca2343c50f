//! Training the autoencoder: Adadelta (paper A) or Adam, stable BCE, early
//! stopping on the validation loss, best model kept, resumable.

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;

use burn::config::Config;
use burn::optim::ModuleOptimizer;
use serde::{Deserialize, Serialize};
use tactile_burn::nn::{RegressionLoss, bce_with_logits};
use tactile_burn::optim::AdadeltaConfig;
use tactile_burn::train::{FitConfig, FitSummary, Schedule, fit};
use tactile_burn::{Artifact, DeviceKind};
use tactile_core::dataset::{Dataset, Provenance, TestHoldout};
use tactile_core::rng::SampleRng;
use tactile_preprocess::perturb::RotationAugment;
use tactile_preprocess::profile::InputProfile;
use tactile_preprocess::{PinImage, PreprocessConfig};

use crate::Result;
use crate::artifact::CaeArtifact;
use crate::data::{PinSet, batch_tensor};
use crate::joint::{JointCae, JointLabels, JointTargets};
use crate::model::CaeConfig;
use crate::tasks::{ExtraTask, check_extra_tasks};

/// The optimiser.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Optimizer {
    /// Paper A's (Keras defaults).
    Adadelta,
    /// Converges in far fewer epochs on 2 cores.
    Adam,
}

impl Optimizer {
    /// The learning rate used when none is given: Keras' 1.0 for Adadelta,
    /// 0.003 for Adam.
    pub fn default_learning_rate(self) -> f64 {
        match self {
            Optimizer::Adadelta => 1.0,
            Optimizer::Adam => 3e-3,
        }
    }
}

/// Training settings; defaults are paper A's except the epoch budget.
#[derive(Config, Debug)]
pub struct CaeTrainingConfig {
    /// The architecture.
    #[config(default = "CaeConfig::new()")]
    pub model: CaeConfig,
    /// How frames become pin images (saved with the model).
    #[config(default = "PreprocessConfig::binary_frames()")]
    pub preprocess: PreprocessConfig,
    /// Paper A: batch 256, up to 10 000 epochs, patience 300 (the released
    /// script: 6000), Adadelta's learning rate 1.0.
    #[config(default = "Schedule::new(256, 3000, 300, 1.0)")]
    pub schedule: Schedule,
    /// Adadelta (paper A) or Adam.
    #[config(default = "Optimizer::Adadelta")]
    pub optimizer: Optimizer,
    /// Adadelta's decay and epsilon.
    #[config(default = "AdadeltaConfig::new()")]
    pub adadelta: AdadeltaConfig,
    /// Fraction of the training rows held out for early stopping.
    #[config(default = 0.2)]
    pub val_fraction: f64,
    /// Without a `split` column: leave out the test frames a later
    /// evaluation with this split holds out, so the encoder never sees them.
    #[config(default = "None")]
    pub holdout: Option<TestHoldout>,
    /// Train on the rows of every split (`val`, `test` too), still holding
    /// `val_fraction` of them out to stop on: the final model, its recipe
    /// chosen on a run that left them out.
    #[config(default = false)]
    pub every_split: bool,
    /// Rotation augmentation: each epoch, each training frame is seen as
    /// it is or as one of its turned copies (equally likely), so the
    /// features also describe frames of a sensor mounted turned.
    #[config(default = "None")]
    pub rotation: Option<RotationAugment>,
    /// Semi-supervised: the features also feed a head trained to predict
    /// these label columns (see [`crate::joint`]); only the autoencoder is
    /// saved.
    #[config(default = "None")]
    pub joint: Option<JointTargets>,
    /// Each time a training image is drawn, shift it (input and the
    /// reconstruction it is scored against alike) by whole pixels up to
    /// this fraction of its side (see
    /// [`tactile_preprocess::perturb::shift_pins`]); `None`: no shift.
    #[config(default = "None")]
    pub shift: Option<f64>,
    /// Further datasets trained on beside the main one, each with its own
    /// preprocessing, head and shift (see [`crate::tasks`]).
    #[config(default = "Vec::new()")]
    pub also: Vec<ExtraTask>,
}

/// One dataset of a run and how its frames are read.
struct Source<'a> {
    ds: &'a Dataset,
    preprocess: &'a PreprocessConfig,
    joint: Option<&'a JointTargets>,
    shift: f64,
}

/// Every dataset's frames as one set of rows: the pin images, the
/// training and validation rows, each row's shift, each head's labels
/// (placed at its dataset's rows) and turned copies.
struct Rows {
    pins: PinSet,
    train: Vec<usize>,
    val: Vec<usize>,
    shift: Vec<f64>,
    labels: Vec<JointLabels>,
    turned: HashMap<usize, Vec<PinImage>>,
}

impl Rows {
    fn read(config: &CaeTrainingConfig, sources: &[Source]) -> Result<Self> {
        let total: usize = sources.iter().map(|s| s.ds.len()).sum();
        let mut rows = Rows {
            pins: PinSet::from_images(Vec::with_capacity(total)),
            train: Vec::new(),
            val: Vec::new(),
            shift: Vec::with_capacity(total),
            labels: Vec::new(),
            turned: HashMap::new(),
        };
        for s in sources {
            let offset = rows.pins.len();
            let usable = s.ds.rows_to_fit(config.every_split, config.holdout)?;
            let (train, val) =
                s.ds.hold_out(usable, config.val_fraction, config.schedule.seed)?;
            tactile_core::note!(
                "preprocessing {} frames of {} ({} train, {} validation)",
                s.ds.len(),
                s.ds.root.display(),
                train.len(),
                val.len()
            );
            let pins = PinSet::from_dataset(s.ds, s.preprocess)?;
            if let Some(j) = s.joint {
                let labels = JointLabels::read(s.ds, j, &train)?;
                for w in &labels.warnings {
                    tactile_core::note!("warning: {w}");
                }
                rows.labels.push(labels.placed(offset, total));
            }
            // Per training row, its turned copies (none without augmentation).
            if let Some(aug) = &config.rotation {
                tactile_core::note!(
                    "turning {} training frames {} times",
                    train.len(),
                    aug.copies
                );
                let copies = aug.dataset_pins(s.ds, &train, s.preprocess)?;
                rows.turned
                    .extend(train.iter().map(|&i| i + offset).zip(copies));
            }
            rows.shift.extend(std::iter::repeat_n(s.shift, pins.len()));
            rows.pins.images.extend(pins.images);
            rows.train.extend(train.iter().map(|&i| i + offset));
            rows.val.extend(val.iter().map(|&i| i + offset));
        }
        Ok(rows)
    }
}

/// Train on the training rows of `data` (see
/// [`Dataset::training_rows`]) and write everything into `out`:
/// `cae.json`/`cae.bpk` (best model), `curves.csv`/`curves.png`,
/// `training.json` and `checkpoint/`. With `resume`, training continues
/// from that checkpoint and gives the same result as an uninterrupted run.
pub fn train(
    config: &CaeTrainingConfig,
    data: &Dataset,
    out: &Path,
    device: DeviceKind,
    resume: bool,
) -> Result<FitSummary> {
    config.schedule.check()?;
    config.model.check()?;
    config.preprocess.check()?;
    tactile_core::dataset::check_val_fraction(config.val_fraction)?;
    if let Some(j) = &config.joint {
        j.check()?;
    }
    let shift = config.shift.unwrap_or(0.0);
    tactile_preprocess::perturb::check_shift(shift)?;
    check_extra_tasks(&config.also, config.model.input_px)?;
    let extra = config
        .also
        .iter()
        .map(|t| Dataset::open(&t.data))
        .collect::<tactile_core::Result<Vec<_>>>()?;
    let sources: Vec<Source> = std::iter::once(Source {
        ds: data,
        preprocess: &config.preprocess,
        joint: config.joint.as_ref(),
        shift,
    })
    .chain(config.also.iter().zip(&extra).map(|(t, ds)| Source {
        ds,
        preprocess: &t.preprocess,
        joint: t.joint.as_ref(),
        shift: t.shift.unwrap_or(0.0),
    }))
    .collect();
    let datasets: Vec<&Dataset> = sources.iter().map(|s| s.ds).collect();
    <crate::CaeArtifact as tactile_burn::Artifact>::check_out_dir(out, &datasets)?;
    for s in &sources {
        if let Some(j) = s.joint {
            s.ds.expect_columns(j.targets.iter().map(|t| t.name.as_str()))?;
        }
    }
    let Rows {
        pins,
        train,
        val,
        shift: row_shift,
        labels,
        turned,
    } = Rows::read(config, &sources)?;
    let joints: Vec<&JointTargets> = sources.iter().filter_map(|s| s.joint).collect();
    let notes = Provenance::of(&datasets)
        .every_split(config.every_split)
        .excluding_test(config.holdout)
        .notes(serde_json::json!({ "device": device.name() }));
    let trained: Vec<&PinImage> = train.iter().map(|&i| &pins.images[i]).collect();
    let artifact = CaeArtifact {
        model: config.model.clone(),
        preprocess: config.preprocess.clone(),
        input_profile: InputProfile::of_training_pins(&trained)?,
        notes,
    };
    let dev = device.device();
    let ad = dev.clone().autodiff();
    // Seeded initial weights: the same config gives the same run.
    ad.seed(config.schedule.seed);
    let model = JointCae::new(
        config.model.init(&ad),
        &joints,
        config.model.feature_count(),
        &ad,
    );
    let heads: Vec<(f32, RegressionLoss)> = joints
        .iter()
        .map(|j| (j.weight as f32, j.head_loss()))
        .collect();
    let optim: ModuleOptimizer = match config.optimizer {
        Optimizer::Adadelta => config.adadelta.init(),
        Optimizer::Adam => burn::optim::AdamConfig::new().init(),
    };
    let title = match joints.first() {
        Some(j) => format!("CAE training ({})", j.describe()),
        None => "CAE training (binary cross-entropy)".into(),
    };
    let fit_cfg = FitConfig::new(&config.schedule, &title)
        .saving_to(out, resume)
        .with_checkpoint_every(25)
        .with_run_id(tactile_burn::artifact::run_fingerprint(config, &datasets)?);
    let unfinished = tactile_burn::artifact::Unfinished::begin(out)?;
    let warnings: Vec<String> = labels.iter().flat_map(|l| l.warnings.clone()).collect();
    let (_, mut summary) = fit::<_, crate::Error>(
        &fit_cfg,
        model,
        optim,
        (&train, val.len()),
        |m: &JointCae, batch, epoch| {
            // Each drawn image is borrowed, and copied only to be shifted.
            let drawn: Vec<Cow<PinImage>> = batch
                .iter()
                .map(|&i| {
                    let copies = turned.get(&i).map_or(&[][..], Vec::as_slice);
                    let mut rng = SampleRng::new(config.schedule.seed, epoch as u64, i as u64);
                    let pick = (rng.uniform() * (copies.len() + 1) as f64) as usize;
                    let mut pin = Cow::Borrowed(copies.get(pick).unwrap_or(&pins.images[i]));
                    if row_shift[i] > 0.0 {
                        let pixels = &mut pin.to_mut().pixels;
                        tactile_preprocess::perturb::shift_pins(pixels, row_shift[i], &mut rng);
                    }
                    pin
                })
                .collect();
            let x = batch_tensor(drawn.iter().map(|p| p.as_ref()), &ad);
            let (logits, columns) = m.forward(x.clone());
            let mut loss = bce_with_logits(logits, x);
            for ((c, l), &(weight, head_loss)) in columns.into_iter().zip(&labels).zip(&heads) {
                loss = loss + l.loss(c, batch, head_loss) * weight;
            }
            Ok(loss)
        },
        |m| {
            // Validation loss: the training loss's terms on the held-out
            // rows, each head's over its labelled rows.
            let (mut bce, mut head, mut weighted) = (0.0, 0.0, 0.0);
            for chunk in val.chunks(config.schedule.batch_size.max(1)) {
                let x = pins.batch(chunk, &dev);
                let (logits, columns) = m.forward(x.clone());
                let n = chunk.len() as f64;
                bce += bce_with_logits(logits, x).into_scalar::<f32>() as f64 * n;
                for ((c, l), &(weight, head_loss)) in columns.into_iter().zip(&labels).zip(&heads) {
                    let sum = l.loss(c, chunk, head_loss).into_scalar::<f32>() as f64
                        * l.labelled(chunk) as f64;
                    head += sum;
                    weighted += weight as f64 * sum;
                }
            }
            let n = val.len().max(1) as f64;
            let metric = (!labels.is_empty()).then(|| head / n);
            Ok(((bce + weighted) / n, metric))
        },
        |m| Ok(artifact.save(&m.cae, out)?),
    )?;
    summary.warnings = warnings;
    tactile_burn::artifact::write_training_record(
        out,
        config,
        &summary,
        serde_json::json!({ "train_frames": train.len(), "val_frames": val.len() }),
    )?;
    unfinished.finish()?;
    Ok(summary)
}
