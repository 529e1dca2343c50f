//! `tactile train cae|head|regressor|detector|segmenter|depth`. Every
//! default comes from the model's training config.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use tactile_core::dataset::Dataset;
use tactile_pipeline::options::{HeadOptions, RegressorOptions};
use tactile_pipeline::tactip::{FeatureSource, train_head, train_regressor};

#[derive(Subcommand)]
pub(crate) enum TrainCmd {
    /// Paper A's convolutional autoencoder.
    Cae(TrainerArgs<tactile_cae::CaeOptions>),
    /// A shallow shape classifier on the features of a trained encoder.
    Head(HeadArgs),
    /// A regressor (pose, depth, force; angles on the circle) on features.
    Regressor(RegressorArgs),
    /// A supervised pose network (CNN on grey pin images) on TacTip frames.
    Pose(TrainerArgs<tactile_pose::PoseOptions>),
    /// Paper B's tendon detector on visuo-tactile frames.
    Detector(DetectorArgs),
    /// Paper B's U-Net tendon segmenter on visuo-tactile tendon frames.
    Segmenter(TrainerArgs<tactile_segment::SegmenterOptions>),
    /// Paper B's depth U-Net with a DenseNet encoder.
    Depth(TrainerArgs<tactile_depth::DepthOptions>),
    /// The input profile of a trained detector or TacTip model (an encoder, a pose network or ensemble): its training frames' input statistics (a TacTip model's: where its pin images' power lies across spatial frequencies), saved in its config, so frames of another sensor are flagged (a detector gives them no answer; `predict` names them in a warning). A model trained now has one already.
    Profile(ProfileArgs),
    /// Calibrate a trained model on frames it was not trained on: a detector's probabilities (one logit scale about the threshold, fitted by maximum likelihood and folded into its last layer; decisions unchanged), or the deviations of a pose network or of a regressor kept in its encoder folder (one factor per target so ±1 holds 68.3 % of the errors; `--split val` takes a split's rows, `--calibration-from` a validated run's factors).
    Calibrate(CalibrateArgs),
    /// Average models trained apart (pose networks, detectors reading frames alike, or regressors on one encoder's features trained with other seeds): copies them into one folder that every command and Python load as one model (a regressor ensemble inside the encoder folder runs as one of its estimators). A detector member's folded calibration is unfolded in its copy; calibrate the ensemble as a whole.
    #[command(alias = "pose-ensemble")]
    Ensemble(EnsembleArgs),
    /// Measure the pin lattice's orientation on an encoder's training frames and save it with the encoder, so frames of a sensor mounted turned are turned back before encoding.
    Align(AlignArgs),
}

#[derive(Args)]
pub(crate) struct ProfileArgs {
    /// The detector, encoder or pose-network folder.
    #[arg(long)]
    model: PathBuf,
    /// Dataset(s): the model's training data.
    #[arg(long, num_args = 1.., required = true)]
    data: Vec<PathBuf>,
    /// A TacTip model: only the rows whose `split` column says this (e.g. train).
    #[arg(long)]
    split: Option<String>,
}

#[derive(Args)]
pub(crate) struct AlignArgs {
    /// The encoder folder.
    #[arg(long)]
    model: PathBuf,
    /// Dataset(s): the encoder's training data (every frame is measured).
    #[arg(long, num_args = 1.., required = true)]
    data: Vec<PathBuf>,
}

#[derive(Args)]
pub(crate) struct CalibrateArgs {
    /// The detector, pose-network or regressor folder (a regressor inside the encoder folder it reads, e.g. ENCODER/pose).
    #[arg(long)]
    model: PathBuf,
    /// Labelled dataset(s) of frames it was not trained on (one for a pose network or regressor).
    #[arg(long, num_args = 1..)]
    data: Vec<PathBuf>,
    /// A pose network or regressor: only the rows whose `split` column says this (e.g. val).
    #[arg(long)]
    split: Option<String>,
    /// A pose network or regressor trained on every frame: take the deviation factors of this validated run (same targets) instead.
    #[arg(long, value_name = "DIR")]
    calibration_from: Option<PathBuf>,
}

#[derive(Args)]
pub(crate) struct EnsembleArgs {
    /// The member folders, 2 to 8 (pose networks, detectors, depth networks or regressors; single models, not ensembles).
    #[arg(long, num_args = 1.., required = true)]
    members: Vec<PathBuf>,
    /// The new ensemble folder (an existing one is left alone).
    #[arg(long)]
    out: PathBuf,
}

/// `--config FILE`: the trainer's options as a JSON object (the keyword
/// names `tactile.train.options(NAME)` lists); flags given here win.
#[derive(Args)]
pub(crate) struct ConfigArg {
    /// Options file: a JSON object of this trainer's options by name (as Python's keywords), e.g. configs/pose/p128.json; flags given on the command line override it.
    #[arg(long)]
    config: Option<PathBuf>,
}

impl ConfigArg {
    pub(crate) fn resolve<T: tactile_burn::options::Options>(&self, parsed: T) -> Result<T> {
        crate::args::resolve(parsed, self.config.as_deref())
    }
}

/// A network trainer's flags: its dataset, its new model folder, an
/// options file and its options.
#[derive(Args)]
pub(crate) struct TrainerArgs<O: Args> {
    /// Dataset folder: TacTip for cae and pose (with a `split` column, only `train` rows are used), visuo-tactile for segmenter and depth (split by `sequence`).
    #[arg(long)]
    data: PathBuf,
    /// Output model folder.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    config: ConfigArg,
    #[command(flatten)]
    options: O,
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
    #[command(flatten)]
    config: ConfigArg,
    #[command(flatten)]
    options: HeadOptions,
}

#[derive(Args)]
pub(crate) struct RegressorArgs {
    #[command(flatten)]
    features: FeatureArgs,
    /// Dataset with the target label columns.
    #[arg(long)]
    data: PathBuf,
    /// Targets: label columns, angles with their period, e.g. x_mm,theta_deg:180,depth_mm.
    #[arg(long, value_delimiter = ',', num_args = 1.., required = true)]
    targets: Vec<String>,
    /// Output folder (default: ENCODER/regressor).
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    config: ConfigArg,
    #[command(flatten)]
    options: RegressorOptions,
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
    config: ConfigArg,
    #[command(flatten)]
    options: tactile_detect::DetectorOptions,
}

pub(crate) fn main(cmd: TrainCmd) -> Result<()> {
    // An unwritable output folder fails first, before any data is read.
    let out = match &cmd {
        TrainCmd::Cae(a) => Some(&a.out),
        TrainCmd::Detector(a) => Some(&a.out),
        TrainCmd::Segmenter(a) => Some(&a.out),
        TrainCmd::Depth(a) => Some(&a.out),
        TrainCmd::Profile(a) => Some(&a.model),
        TrainCmd::Align(a) => Some(&a.model),
        TrainCmd::Calibrate(a) => Some(&a.model),
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
            let options = a.config.resolve(a.options)?;
            let ds = Dataset::open(&a.data)?;
            let s = options.train(&ds, &a.out)?;
            say!("CAE {}; model in {}", s.describe(""), a.out.display());
        }
        TrainCmd::Head(a) => {
            let options = a.config.resolve(a.options)?;
            let ds = Dataset::open(&a.data)?;
            let test = a.test.as_ref().map(Dataset::open).transpose()?;
            let out = a.features.out(&a.out, "head")?;
            let (config, rotation) = options.config()?;
            let rt = options.device.runtime();
            let src = a.features.source()?;
            let (head, tested) = train_head(config, &src, &ds, test.as_ref(), &out, rt, rotation)?;
            if let Some(t) = tested {
                t.describe(head.classes()).iter().for_each(|l| say!("{l}"));
                if let Some(w) = &t.warning {
                    tactile_core::note!("warning: {w}");
                }
            }
            say!("head saved in {}", out.display());
        }
        TrainCmd::Regressor(a) => {
            let options = a.config.resolve(a.options)?;
            let plan = options.plan(&a.targets)?;
            let ds = Dataset::open(&a.data)?;
            let out = a.features.out(&a.out, "regressor")?;
            let rt = options.device.runtime();
            let fit = train_regressor(&plan, &a.features.source()?, &ds, &out, rt)?;
            say!("{}", fit.describe(&plan.targets));
            for w in &fit.warnings {
                tactile_core::note!("warning: {w}");
            }
            say!("regressor saved in {}", out.display());
        }
        TrainCmd::Pose(a) => {
            let options = a.config.resolve(a.options)?;
            let ds = Dataset::open(&a.data)?;
            let fit = options.train(&ds, &a.out)?;
            say!(
                "{}; model in {}",
                fit.fit.describe(&options.targets[0]),
                a.out.display()
            );
            if let Some(r) = &fit.test {
                say!("{}", r.describe());
            }
        }
        TrainCmd::Detector(a) => {
            let options = a.config.resolve(a.options)?;
            let datasets = Dataset::open_all(&a.data)?;
            let fit = options.train(&datasets, &a.out)?;
            say!("{}; model in {}", fit.describe(), a.out.display());
        }
        TrainCmd::Segmenter(a) => {
            let options = a.config.resolve(a.options)?;
            let ds = Dataset::open(&a.data)?;
            let fit = options.train(&ds, &a.out)?;
            say!("{}; model in {}", fit.describe("mean IoU"), a.out.display());
        }
        TrainCmd::Profile(a) => {
            let data = Dataset::open_all(&a.data)?;
            let p =
                tactile_pipeline::profile::add_input_profile(&a.model, &data, a.split.as_deref())?;
            say!("{} saved in {}", p.describe(), a.model.display());
        }
        TrainCmd::Ensemble(a) => {
            say!(
                "{}",
                tactile_pipeline::ensemble::assemble_ensemble(&a.members, &a.out)?
            );
        }
        TrainCmd::Align(a) => {
            let data = Dataset::open_all(&a.data)?;
            let (p, n) = tactile_cae::artifact::add_pin_alignment(&a.model, &data)?;
            say!("{}", p.describe(n));
        }
        TrainCmd::Calibrate(a) => {
            let data = Dataset::open_all(&a.data)?;
            let c = tactile_pipeline::calibrate::calibrate_model(
                &a.model,
                &data,
                a.split.as_deref(),
                a.calibration_from.as_deref(),
            )?;
            for w in &c.warnings {
                tactile_core::note!("warning: {w}");
            }
            say!("{}", c.summary);
        }
        TrainCmd::Depth(a) => {
            let options = a.config.resolve(a.options)?;
            let ds = Dataset::open(&a.data)?;
            let fit = options.train(&ds, &a.out)?;
            say!("{}; model in {}", fit.describe("MAE (mm)"), a.out.display());
        }
    }
    Ok(())
}
