//! `tactile train cae|head|regressor|detector|segmenter|depth`. Every
//! default comes from the model's training config.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use tactile_burn::DeviceKind;
use tactile_burn::options::TestHoldoutArgs;
use tactile_cae::{CaeConfig, CaeTrainingConfig, Optimizer};
use tactile_core::dataset::Dataset;
use tactile_depth::{DenseNetPreset, DepthTrainingConfig, HeadKind, LossKind};
use tactile_estimate::{HeadConfig, RegressorConfig, Target};
use tactile_pipeline::tactip::{
    FeatureSource, RegressorPlan, RotationAugment, train_head, train_regressor,
};
use tactile_pose::PoseTrainingConfig;
use tactile_segment::SegmenterTrainingConfig;

use crate::args::{Preprocess, Size};

#[derive(Subcommand)]
pub(crate) enum TrainCmd {
    /// Paper A's convolutional autoencoder.
    Cae(CaeArgs),
    /// A shallow shape classifier on the features of a trained encoder.
    Head(HeadArgs),
    /// A regressor (pose, depth, force; angles on the circle) on features.
    Regressor(RegressorArgs),
    /// A supervised pose network (CNN on grey pin images) on TacTip frames.
    Pose(PoseArgs),
    /// Paper B's tendon detector on visuo-tactile frames.
    Detector(DetectorArgs),
    /// Paper B's U-Net tendon segmenter on visuo-tactile tendon frames.
    Segmenter(SegmenterArgs),
    /// Paper B's depth U-Net with a DenseNet encoder.
    Depth(DepthArgs),
    /// The input profile of a trained detector: its training frames' input statistics, saved in detector.json, so frames of another sensor are flagged and get no answer (a detector trained now has one already).
    Profile(ProfileArgs),
    /// Calibrate a trained detector's probabilities on frames it was not trained on: one logit scale about the threshold, fitted by maximum likelihood and folded into its last layer (decisions unchanged).
    Calibrate(ProfileArgs),
    /// Average models trained apart (pose networks, or detectors reading frames alike): copies them into one folder that every command and Python load as one model.
    #[command(alias = "pose-ensemble")]
    Ensemble(EnsembleArgs),
    /// Measure the pin lattice's orientation on an encoder's training frames and save it with the encoder, so frames of a sensor mounted turned are turned back before encoding.
    Align(ProfileArgs),
}

#[derive(Args)]
pub(crate) struct ProfileArgs {
    /// The detector folder (the encoder folder for `align`).
    #[arg(long)]
    model: PathBuf,
    /// Labelled dataset(s): the detector's training data for `profile` (the encoder's for `align`), frames it was not trained on for `calibrate`.
    #[arg(long, num_args = 1.., required = true)]
    data: Vec<PathBuf>,
}

#[derive(Args)]
pub(crate) struct EnsembleArgs {
    /// The member folders (pose networks or detectors).
    #[arg(long, num_args = 1.., required = true)]
    members: Vec<PathBuf>,
    /// The new ensemble folder (an existing one is left alone).
    #[arg(long)]
    out: PathBuf,
}

tactile_burn::schedule_args!(CaeSchedule, CaeTrainingConfig::new().schedule);
tactile_burn::schedule_args!(PoseSchedule, pose_defaults().schedule);

fn pose_defaults() -> PoseTrainingConfig {
    PoseTrainingConfig::new(vec![])
}

#[derive(Args)]
pub(crate) struct PoseArgs {
    /// TacTip dataset folder; with a `split` column, only `train` rows are used.
    #[arg(long)]
    data: PathBuf,
    /// Output model folder.
    #[arg(long)]
    out: PathBuf,
    /// Targets: label columns, NAME:PERIOD for an angle.
    #[arg(long, value_delimiter = ',', default_value = "x_mm,theta_deg,depth_mm")]
    targets: Vec<Target>,
    /// A training config (JSON: model widths and hidden units, pin-image preprocessing, augmentation); the schedule flags set its schedule.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Side of the grey pin image.
    #[arg(long)]
    input_px: Option<usize>,
    #[command(flatten)]
    holdout: TestHoldoutArgs,
    /// Train on every training row for exactly --max-epochs (the final model).
    #[arg(long)]
    all_rows: bool,
    /// Training loss on the standardised targets [default: the config's, else mse].
    #[arg(long, value_enum)]
    loss: Option<tactile_pose::training::PoseLoss>,
    #[command(flatten)]
    schedule: PoseSchedule,
}
tactile_burn::schedule_args!(SegmenterSchedule, SegmenterTrainingConfig::new().schedule);
tactile_burn::schedule_args!(DepthSchedule, DepthTrainingConfig::new().schedule);

#[derive(Args)]
pub(crate) struct CaeArgs {
    /// TacTip dataset folder; with a `split` column, only `train` rows are used.
    #[arg(long)]
    data: PathBuf,
    /// Output model folder.
    #[arg(long)]
    out: PathBuf,
    /// Preprocessing: binary (already binarised frames), paper, lighting-compensated, or a JSON file.
    #[arg(long, default_value = "binary")]
    preprocess: Preprocess,
    /// Encoder widths, e.g. 16,8,8,4 (paper) or 16,16,8,4 (authors' release).
    #[arg(long, value_delimiter = ',', default_values_t = CaeConfig::new().widths)]
    widths: Vec<usize>,
    /// Feature count (8/16/32/64): sets the last width.
    #[arg(long)]
    features: Option<usize>,
    /// No ReLU before the last pooling: features cannot die (see CaeConfig).
    #[arg(long)]
    linear_latent: bool,
    /// Adadelta (paper A) or Adam.
    #[arg(long, value_enum, default_value_t = CaeTrainingConfig::new().optimizer)]
    optimizer: Optimizer,
    /// Fraction of the training rows held out for early stopping.
    #[arg(long, default_value_t = CaeTrainingConfig::new().val_fraction)]
    val_fraction: f64,
    #[command(flatten)]
    holdout: TestHoldoutArgs,
    #[command(flatten)]
    schedule: CaeSchedule,
    #[command(flatten)]
    rotate: RotateArgs,
    #[command(flatten)]
    joint: tactile_cae::joint::JointArgs,
}

#[derive(Args)]
pub(crate) struct FeatureArgs {
    /// Trained encoder folder (features are computed from the frames).
    #[arg(long, required_unless_present = "features")]
    encoder: Option<PathBuf>,
    /// Precomputed feature CSV (file,f0,f1,...) instead of an encoder, e.g. the authors' golden-features.csv; needs --out.
    #[arg(long, conflicts_with = "encoder", requires = "out")]
    features: Option<PathBuf>,
}

impl FeatureArgs {
    fn source(&self) -> Result<FeatureSource> {
        match (&self.encoder, &self.features) {
            (_, Some(csv)) => Ok(FeatureSource::Csv(csv.clone())),
            (Some(e), None) => Ok(FeatureSource::Encoder(e.clone())),
            (None, None) => bail!("give --encoder DIR or --features CSV"),
        }
    }

    /// `out`, or `ENCODER/name`.
    fn out(&self, out: &Option<PathBuf>, name: &str) -> Result<PathBuf> {
        out.clone()
            .or_else(|| self.encoder.as_ref().map(|e| e.join(name)))
            .context("--features needs --out")
    }
}

#[derive(Args)]
pub(crate) struct HeadArgs {
    #[command(flatten)]
    features: FeatureArgs,
    /// Dataset with `shape` labels (and a `split` column: train/test).
    #[arg(long)]
    data: PathBuf,
    /// Head folder (default: ENCODER/head).
    #[arg(long)]
    out: Option<PathBuf>,
    /// A separate test dataset (default: the `test` split of --data).
    #[arg(long, requires = "encoder")]
    test: Option<PathBuf>,
    /// Ensemble members; each early-stops on its own fold of the train split.
    #[arg(long, default_value_t = HeadConfig::new(0, vec![]).folds)]
    folds: usize,
    /// Repeats of the k-fold split (members = folds x repeats).
    #[arg(long, default_value_t = HeadConfig::new(0, vec![]).repeats)]
    repeats: usize,
    /// Fold and weight seed.
    #[arg(long, default_value_t = HeadConfig::new(0, vec![]).schedule.seed)]
    seed: u64,
    /// Training device.
    #[arg(long, value_enum, default_value_t = DeviceKind::Flex)]
    device: DeviceKind,
    #[command(flatten)]
    rotate: RotateArgs,
}

/// Rotation augmentation (`train cae`, `train head`).
#[derive(Args)]
pub(crate) struct RotateArgs {
    /// Also train on this many copies of each frame turned by up to --rotate-deg (a sensor mounted turned).
    #[arg(long, default_value_t = 0)]
    rotate_copies: usize,
    /// Largest turn of those copies, degrees.
    #[arg(long, default_value_t = 6.0)]
    rotate_deg: f64,
}

impl RotateArgs {
    fn augment(&self, seed: u64) -> Option<RotationAugment> {
        RotationAugment::optional(self.rotate_copies, self.rotate_deg, seed)
    }
}

#[derive(Args)]
pub(crate) struct RegressorArgs {
    #[command(flatten)]
    features: FeatureArgs,
    /// Dataset with the target label columns.
    #[arg(long)]
    data: PathBuf,
    /// Targets: label columns, angles with their period, e.g. x_mm,theta_deg:180,depth_mm.
    #[arg(long, value_delimiter = ',', required = true)]
    targets: Vec<Target>,
    /// Output folder (default: ENCODER/regressor).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Without a `split` column: fraction of frames held out for testing (0: none, every frame trains).
    #[arg(long, default_value_t = RegressorPlan::new(vec![]).test_fraction)]
    test_fraction: f64,
    /// Fraction of the training frames used for early stopping.
    #[arg(long, default_value_t = RegressorPlan::new(vec![]).val_fraction)]
    val_fraction: f64,
    /// Hidden layer widths (ReLU), e.g. 32,16 (the authors' force head).
    #[arg(long, value_delimiter = ',', default_values_t = RegressorPlan::new(vec![]).hidden)]
    hidden: Vec<usize>,
    /// Split and weight seed.
    #[arg(long, default_value_t = RegressorConfig::new(0, vec![]).schedule.seed)]
    seed: u64,
    /// Training device.
    #[arg(long, value_enum, default_value_t = DeviceKind::Flex)]
    device: DeviceKind,
    /// Use only frames where every target is labelled (e.g. theta_deg, empty for spheres and flats); otherwise an empty label is an error.
    #[arg(long)]
    only_labelled: bool,
    /// Train only on frames of these shapes: a specialised regressor (a sphere's position, say) that answers where the head sees them.
    #[arg(long, value_delimiter = ',')]
    shapes: Vec<String>,
}

#[derive(Args)]
pub(crate) struct DetectorArgs {
    /// Visuo-tactile dataset(s), each split by `sequence` into train and validation (e.g. the default distribution plus a set of light presses that crowds the frames near the label's threshold).
    #[arg(long, num_args = 1.., required = true)]
    data: Vec<PathBuf>,
    /// Output model folder.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    options: tactile_detect::DetectorOptions,
}

#[derive(Args)]
pub(crate) struct SegmenterArgs {
    /// Visuo-tactile dataset; its tendon frames are split by `sequence`.
    #[arg(long)]
    data: PathBuf,
    /// Output model folder.
    #[arg(long)]
    out: PathBuf,
    /// Side of the square window (a multiple of 16; paper B: 160).
    #[arg(long, default_value_t = SegmenterTrainingConfig::new().model.side)]
    side: usize,
    /// Channels of the first U-Net block.
    #[arg(long, default_value_t = SegmenterTrainingConfig::new().model.base)]
    base: usize,
    /// Rotated copies of each training frame (paper B's augmentation).
    #[arg(long, default_value_t = SegmenterTrainingConfig::new().copies)]
    copies: usize,
    /// Fraction of the sequences that validate.
    #[arg(long, default_value_t = SegmenterTrainingConfig::new().val_fraction)]
    val_fraction: f64,
    #[command(flatten)]
    schedule: SegmenterSchedule,
}

#[derive(Args)]
pub(crate) struct DepthArgs {
    /// Visuo-tactile dataset (split by `sequence`).
    #[arg(long)]
    data: PathBuf,
    /// Output model folder.
    #[arg(long)]
    out: PathBuf,
    /// DenseNet encoder preset.
    #[arg(long, value_enum, default_value_t = DenseNetPreset::Small)]
    encoder: DenseNetPreset,
    /// Input WIDTHxHEIGHT, multiples of 32 (paper B: 256x256).
    #[arg(long, default_value_t = Size(DepthTrainingConfig::new().model.input_size))]
    input: Size,
    /// conv1x1 (paper B) or custom (two 3x3 conv + ReLU, then 1x1).
    #[arg(long, value_enum, default_value_t = DepthTrainingConfig::new().model.head)]
    head: HeadKind,
    /// l1 (paper B), mse, or l1-grad-ssim (DenseTact).
    #[arg(long, value_enum, default_value_t = DepthTrainingConfig::new().loss)]
    loss: LossKind,
    /// Feed the ground-truth tendon mask as a fourth channel.
    #[arg(long)]
    with_mask: bool,
    /// Train the decoder only.
    #[arg(long)]
    freeze_encoder: bool,
    /// torchvision DenseNet weights as safetensors (key mapping: the tactile-depth `torchvision` module docs); the preset must match.
    #[arg(long)]
    pretrained: Option<PathBuf>,
    /// Millimetres per model unit (1 = millimetres; 1000 = metres, which stalls and is refused).
    #[arg(long, default_value_t = DepthTrainingConfig::new().unit_mm)]
    unit_mm: f32,
    /// Channels of the deepest decoder block.
    #[arg(long, default_value_t = DepthTrainingConfig::new().model.decoder_width)]
    decoder_width: usize,
    /// Fraction of the sequences that validate.
    #[arg(long, default_value_t = DepthTrainingConfig::new().val_fraction)]
    val_fraction: f64,
    #[command(flatten)]
    schedule: DepthSchedule,
}

pub(crate) fn main(cmd: TrainCmd) -> Result<()> {
    // An unwritable output folder fails first, before any data is read.
    let out = match &cmd {
        TrainCmd::Cae(a) => Some(&a.out),
        TrainCmd::Detector(a) => Some(&a.out),
        TrainCmd::Segmenter(a) => Some(&a.out),
        TrainCmd::Depth(a) => Some(&a.out),
        TrainCmd::Profile(a) | TrainCmd::Calibrate(a) | TrainCmd::Align(a) => Some(&a.model),
        TrainCmd::Pose(a) => Some(&a.out),
        TrainCmd::Ensemble(a) => Some(&a.out),
        TrainCmd::Head(a) => a.out.as_ref(),
        TrainCmd::Regressor(a) => a.out.as_ref(),
    };
    if let Some(out) = out {
        tactile_core::io::ensure_writable_dir(out)?;
    }
    match cmd {
        TrainCmd::Cae(a) => {
            let ds = Dataset::open(&a.data)?;
            let px = a.preprocess.config.output_px;
            let model = CaeConfig::from_options(&a.widths, a.features, a.linear_latent, px)?;
            let config = CaeTrainingConfig::new()
                .with_model(model)
                .with_preprocess(a.preprocess.config)
                .with_schedule(a.schedule.schedule(a.optimizer.default_learning_rate()))
                .with_optimizer(a.optimizer)
                .with_val_fraction(a.val_fraction)
                .with_holdout(a.holdout.holdout())
                .with_rotation(a.rotate.augment(a.schedule.seed))
                .with_joint(a.joint.config()?);
            let s = tactile_cae::training::train(
                &config,
                &ds,
                &a.out,
                a.schedule.device,
                a.schedule.resume,
            )?;
            say!("CAE {}; model in {}", s.describe(""), a.out.display());
        }
        TrainCmd::Head(a) => {
            let ds = Dataset::open(&a.data)?;
            let test = a.test.as_ref().map(Dataset::open).transpose()?;
            let out = a.features.out(&a.out, "head")?;
            let mut config = HeadConfig::new(0, vec![])
                .with_folds(a.folds)
                .with_repeats(a.repeats);
            config.schedule.seed = a.seed;
            let rt = a.device.runtime();
            let rotation = a.rotate.augment(a.seed);
            let src = a.features.source()?;
            let (head, tested) = train_head(config, &src, &ds, test.as_ref(), &out, rt, rotation)?;
            if let Some(t) = tested {
                t.describe(head.classes()).iter().for_each(|l| say!("{l}"));
            }
            say!("head saved in {}", out.display());
        }
        TrainCmd::Regressor(a) => {
            let ds = Dataset::open(&a.data)?;
            let out = a.features.out(&a.out, "regressor")?;
            let plan = RegressorPlan {
                hidden: a.hidden,
                test_fraction: a.test_fraction,
                val_fraction: a.val_fraction,
                seed: a.seed,
                only_labelled: a.only_labelled,
                shapes: a.shapes,
                ..RegressorPlan::new(a.targets)
            };
            let fit = train_regressor(&plan, &a.features.source()?, &ds, &out, a.device.runtime())?;
            say!("{}", fit.describe(&plan.targets));
            say!("regressor saved in {}", out.display());
        }
        TrainCmd::Pose(a) => {
            let ds = Dataset::open(&a.data)?;
            let mut config = match &a.config {
                Some(p) => tactile_core::io::read_json::<PoseTrainingConfig>(p)?,
                None => pose_defaults(),
            };
            config.preprocess.output_px = a.input_px.unwrap_or(config.preprocess.output_px);
            let holdout = a.holdout.holdout();
            let (s, lr) = (&a.schedule, config.schedule.learning_rate);
            let config = PoseTrainingConfig {
                targets: a.targets.clone(),
                schedule: s.schedule(lr),
                holdout,
                all_rows: a.all_rows,
                loss: a.loss.or(config.loss),
                ..config
            };
            let fit = tactile_pose::training::train(&config, &ds, &a.out, s.device, s.resume)?;
            say!(
                "{}; model in {}",
                fit.describe(&a.targets[0].name),
                a.out.display()
            );
            if let Some(h) = holdout {
                let r = tactile_pose::training::test_scores(&a.out, &ds, h, s.device.runtime())?;
                say!("{}", r.describe());
            }
        }
        TrainCmd::Detector(a) => {
            let datasets: Vec<_> = a.data.iter().map(Dataset::open).collect::<Result<_, _>>()?;
            let fit = a.options.train(&datasets, &a.out)?;
            say!("{}; model in {}", fit.describe(), a.out.display());
        }
        TrainCmd::Segmenter(a) => {
            let ds = Dataset::open(&a.data)?;
            let d = SegmenterTrainingConfig::new();
            let config = SegmenterTrainingConfig::new()
                .with_model(d.model.with_side(a.side).with_base(a.base))
                .with_schedule(a.schedule.schedule(d.schedule.learning_rate))
                .with_copies(a.copies)
                .with_val_fraction(a.val_fraction);
            let s = &a.schedule;
            let fit = tactile_segment::training::train(&config, &ds, &a.out, s.device, s.resume)?;
            say!("{}; model in {}", fit.describe("mean IoU"), a.out.display());
        }
        TrainCmd::Profile(a) => {
            let data: Vec<_> = a.data.iter().map(Dataset::open).collect::<Result<_, _>>()?;
            let p = tactile_detect::profile::add_input_profile(&a.model, &data)?;
            say!("{} saved in {}", p.describe(), a.model.display());
        }
        TrainCmd::Ensemble(a) => {
            say!(
                "{}",
                tactile_pipeline::ensemble::assemble_ensemble(&a.members, &a.out)?
            );
        }
        TrainCmd::Align(a) => {
            let data: Vec<_> = a.data.iter().map(Dataset::open).collect::<Result<_, _>>()?;
            let (p, n) = tactile_cae::artifact::add_pin_alignment(&a.model, &data)?;
            say!("{}", p.describe(n));
        }
        TrainCmd::Calibrate(a) => {
            let data: Vec<_> = a.data.iter().map(Dataset::open).collect::<Result<_, _>>()?;
            let fit = tactile_detect::calibrate::calibrate_on(&a.model, &data)?;
            say!("{}; detector in {}", fit.describe(), a.model.display());
        }
        TrainCmd::Depth(a) => {
            let ds = Dataset::open(&a.data)?;
            let d = DepthTrainingConfig::new();
            let model = tactile_depth::DepthNetConfig::new(a.encoder.config(), a.input.0)
                .with_head(a.head)
                .with_decoder_width(a.decoder_width);
            let config = DepthTrainingConfig::new()
                .with_model(model)
                .with_schedule(a.schedule.schedule(d.schedule.learning_rate))
                .with_loss(a.loss)
                .with_unit_mm(a.unit_mm)
                .with_with_mask(a.with_mask)
                .with_freeze_encoder(a.freeze_encoder)
                .with_pretrained(a.pretrained.map(|p| p.display().to_string()))
                .with_val_fraction(a.val_fraction);
            let s = &a.schedule;
            let fit = tactile_depth::training::train(&config, &ds, &a.out, s.device, s.resume)?;
            say!("{}; model in {}", fit.describe("MAE (mm)"), a.out.display());
        }
    }
    Ok(())
}
