//! Every trainer's options in one registry: the shape head's and the
//! regressor's (defined here, beside the paper-A composition that trains
//! them), and those the model crates define. The command line flattens
//! each into its flags, the Python package fills it from keywords, and the
//! generated Python stubs ([`python_stubs`]) type every keyword, so an
//! option is written once.

use serde::{Deserialize, Serialize};
use tactile_burn::DeviceKind;
use tactile_burn::nn::RegressionLoss;
use tactile_burn::options::{OptionDoc, Options};
use tactile_cae::RotateArgs;
use tactile_estimate::{HeadConfig, RegressorConfig, Target};

use crate::tactip::{RegressorPlan, RotationAugment};
use crate::{Error, Result};

/// Every option of shape-head training; each default is the head config's.
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone)]
pub struct HeadOptions {
    /// Ensemble members; each early-stops on its own fold of the train split.
    #[arg(long, default_value_t = HeadConfig::new(0, vec![]).folds)]
    pub folds: usize,
    /// Repeats of the k-fold split (members = folds x repeats).
    #[arg(long, default_value_t = HeadConfig::new(0, vec![]).repeats)]
    pub repeats: usize,
    /// Fold and weight seed.
    #[arg(long, default_value_t = HeadConfig::new(0, vec![]).schedule.seed)]
    pub seed: u64,
    /// Training device.
    #[arg(long, value_enum, default_value_t = DeviceKind::Flex)]
    pub device: DeviceKind,
    /// Rotation augmentation (needs an encoder, not a feature file).
    #[command(flatten)]
    #[serde(flatten)]
    pub rotate: RotateArgs,
}

impl HeadOptions {
    /// The head config and the rotation augmentation these options ask for.
    pub fn config(&self) -> Result<(HeadConfig, Option<RotationAugment>)> {
        let mut config = HeadConfig::new(0, vec![])
            .with_folds(self.folds)
            .with_repeats(self.repeats);
        config.schedule.seed = self.seed;
        Ok((config, self.rotate.augment(self.seed)?))
    }
}

/// Every option of regressor training (the targets are an input, like the
/// data); each default is the regressor plan's.
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone)]
pub struct RegressorOptions {
    /// Without a `split` column: fraction of frames held out for testing (0: none, every frame trains).
    #[arg(long, default_value_t = RegressorPlan::new(vec![]).test_fraction)]
    pub test_fraction: f64,
    /// Fraction of the training frames used for early stopping.
    #[arg(long, default_value_t = RegressorPlan::new(vec![]).val_fraction)]
    pub val_fraction: f64,
    /// Hidden layer widths (ReLU), e.g. 32,16 (the authors' force head).
    #[arg(long, value_delimiter = ',', num_args = 1.., default_values_t = RegressorPlan::new(vec![]).hidden)]
    pub hidden: Vec<usize>,
    /// Split and weight seed.
    #[arg(long, default_value_t = RegressorConfig::new(0, vec![]).schedule.seed)]
    pub seed: u64,
    /// Train on the frames of every split (`val`, `test` too; --val-fraction of them still stop it): the final model, its recipe chosen on a run that left them out.
    #[arg(long)]
    #[serde(default)]
    pub every_split: bool,
    /// Training device.
    #[arg(long, value_enum, default_value_t = DeviceKind::Flex)]
    pub device: DeviceKind,
    /// Use only frames where every target is labelled (e.g. theta_deg, empty for spheres and flats); otherwise an empty label is an error.
    #[arg(long)]
    pub only_labelled: bool,
    /// Train only on frames of these shapes: a specialised regressor (a sphere's position, say) that answers where the head sees them.
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub shapes: Vec<String>,
    /// The loss on the standardised targets, in training and for early stopping.
    #[arg(long, value_enum, default_value_t = RegressionLoss::Mse)]
    #[serde(default)]
    pub loss: RegressionLoss,
    /// Also give each target's uncertainty (a Laplace scale per target, calibrated on the early-stopping frames; linear targets only): `<target>_std` columns. Calibrate it again on frames it never fitted with `train calibrate --model ENCODER/FOLDER`.
    #[arg(long)]
    #[serde(default)]
    pub uncertainty: bool,
}

impl RegressorOptions {
    /// The plan for `targets` (label columns, `NAME:PERIOD` for an angle).
    pub fn plan(&self, targets: &[String]) -> Result<RegressorPlan> {
        let targets = targets
            .iter()
            .map(|t| t.parse::<Target>())
            .collect::<std::result::Result<Vec<_>, _>>()?;
        if targets.is_empty() {
            return Err(tactile_core::Error::Config(
                "targets: give at least one label column".into(),
            )
            .into());
        }
        if self.uncertainty {
            tactile_estimate::uncertainty::check_linear(&targets)
                .map_err(tactile_core::Error::Config)?;
        }
        Ok(RegressorPlan {
            hidden: self.hidden.clone(),
            test_fraction: self.test_fraction,
            val_fraction: self.val_fraction,
            seed: self.seed,
            every_split: self.every_split,
            only_labelled: self.only_labelled,
            shapes: self.shapes.clone(),
            loss: self.loss,
            uncertainty: self.uncertainty,
            ..RegressorPlan::new(targets)
        })
    }
}

/// One trainer as both front ends show it.
pub struct Trainer {
    /// Its name: `tactile train NAME`, `tactile.train.NAME(...)`.
    pub name: &'static str,
    /// The native function's name in `tactile._tactile`.
    pub native: &'static str,
    /// The Python parameters before the options (inputs, not options;
    /// `*` where the keyword-only ones begin).
    pub inputs: &'static [&'static str],
    /// What it trains, for the stub's docstring.
    pub about: &'static str,
    /// The Python return type.
    pub returns: &'static str,
    /// The native function's parameters before the options (the
    /// Python-facing `inputs` unless the wrapper passes others).
    pub native_inputs: &'static [&'static str],
    /// The native function's return type.
    pub native_returns: &'static str,
    docs: fn() -> tactile_core::Result<Vec<OptionDoc>>,
    params: fn() -> tactile_core::Result<Vec<String>>,
    resolve: fn(&serde_json::Map<String, serde_json::Value>) -> tactile_core::Result<()>,
}

/// Whether `T` takes these keywords (name -> JSON value), and if not why.
fn takes<T: Options>(
    keywords: &serde_json::Map<String, serde_json::Value>,
) -> tactile_core::Result<()> {
    T::with_overrides(keywords).map(|_| ())
}

impl Trainer {
    const fn of<T: Options>(
        name: &'static str,
        native: &'static str,
        inputs: &'static [&'static str],
        about: &'static str,
    ) -> Self {
        Self {
            name,
            native,
            inputs,
            about,
            returns: "Dict[str, Any]",
            native_inputs: inputs,
            native_returns: "Dict[str, Any]",
            docs: T::docs,
            params: T::python_params,
            resolve: takes::<T>,
        }
    }

    /// Whether these keywords (name -> JSON value, as Python passes them)
    /// are options it takes with values they take.
    pub fn takes(&self, keywords: &serde_json::Map<String, serde_json::Value>) -> Result<()> {
        Ok((self.resolve)(keywords)?)
    }

    /// Every option with its help and default, in flag order.
    pub fn docs(&self) -> Result<Vec<OptionDoc>> {
        Ok((self.docs)()?)
    }

    /// The typed Python signature of the entry point (`tactile/train.pyi`,
    /// `tactile/synth.pyi`), up to the colon.
    pub fn python_def(&self) -> Result<String> {
        self.signature(self.name, self.inputs, self.returns)
    }

    /// The typed signature of its native function (`_tactile.pyi`), up to
    /// the colon.
    pub fn native_def(&self) -> Result<String> {
        self.signature(self.native, self.native_inputs, self.native_returns)
    }

    fn signature(&self, name: &str, inputs: &[&str], returns: &str) -> Result<String> {
        let mut s = format!("def {name}(\n");
        for i in inputs {
            s.push_str(&format!("    {i},\n"));
        }
        if !inputs.contains(&"*") {
            s.push_str("    *,\n");
        }
        s.push_str("    config: Optional[_Path] = None,\n");
        for p in (self.params)()? {
            s.push_str(&format!("    {p},\n"));
        }
        s.push_str(&format!(") -> {returns}:"));
        Ok(s)
    }

    /// The same entry point returning `returns` in Python.
    const fn returning(mut self, returns: &'static str) -> Self {
        self.returns = returns;
        self
    }

    /// The same entry point whose native function takes `inputs` and
    /// returns `returns` (a wrapper in Python between the two).
    const fn native_signature(
        mut self,
        inputs: &'static [&'static str],
        returns: &'static str,
    ) -> Self {
        self.native_inputs = inputs;
        self.native_returns = returns;
        self
    }
}

/// The virtual sensors' generators, options written once in their configs
/// (`tactile synth NAME`, `tactile.synth.NAME(...)`): the same registry
/// entry as a trainer's.
pub const GENERATORS: &[Trainer] = &[
    Trainer::of::<datasets_synth::TactipConfig>(
        "tactip",
        "synth_tactip",
        &[
            "count: int",
            "seed: int = 1234",
            "out: Optional[_Path] = None",
            "*",
            "force: bool = False",
            "progress: bool = True",
        ],
        "Virtual TacTip frames (paper A): arrays (frames, labels), or a dataset folder with out=.",
    )
    .returning("Union[Tuple[npt.NDArray[np.uint8], Dict[str, Any]], Path]")
    .native_signature(
        &[
            "count: int",
            "seed: int",
            "out: Optional[str]",
            "force: bool",
            "progress: bool",
        ],
        "Any",
    ),
    Trainer::of::<datasets_synth::VisuotactileConfig>(
        "visuotactile",
        "synth_visuotactile",
        &[
            "count: Optional[int] = None",
            "seed: int = 1234",
            "out: Optional[_Path] = None",
            "*",
            "sequences: Optional[int] = None",
            "force: bool = False",
            "progress: bool = True",
        ],
        "Virtual visuo-tactile palpation videos (paper B): a dict of arrays, or a dataset folder with out=.",
    )
    .returning("Union[Dict[str, Any], Path]")
    .native_signature(
        &[
            "count: Optional[int]",
            "sequences: Optional[int]",
            "seed: int",
            "out: Optional[str]",
            "force: bool",
            "progress: bool",
        ],
        "Any",
    ),
    Trainer::of::<datasets_synth::CalibratedConfig>(
        "gelsight",
        "synth_gelsight",
        &[
            "sensor: _Path",
            "count: Optional[int] = None",
            "seed: int = 1234",
            "out: Optional[_Path] = None",
            "*",
            "sequences: Optional[int] = None",
            "force: bool = False",
            "progress: bool = True",
        ],
        "A calibrated GelSight-like sensor's own palpation videos (tactile calibrate ball's folder), rendered through its optics and gel with indentation maps: a dict of arrays, or a dataset folder with out=.",
    )
    .returning("Union[Dict[str, Any], Path]")
    .native_signature(
        &[
            "sensor: str",
            "count: Optional[int]",
            "sequences: Optional[int]",
            "seed: int",
            "out: Optional[str]",
            "force: bool",
            "progress: bool",
        ],
        "Any",
    ),
];

/// Every trainer with options, in the command line's order.
pub const TRAINERS: &[Trainer] = &[
    Trainer::of::<tactile_cae::CaeOptions>(
        "cae",
        "train_cae",
        &["data: _Path", "out: _Path"],
        "Paper A's convolutional autoencoder on a TacTip dataset.",
    ),
    Trainer::of::<HeadOptions>(
        "head",
        "train_head_py",
        &[
            "data: _Path",
            "*",
            "encoder: Optional[_Path] = None",
            "features: Optional[_Path] = None",
            "out: Optional[_Path] = None",
            "test: Optional[_Path] = None",
        ],
        "Paper A's shape head on an encoder's features (or a feature CSV).",
    ),
    Trainer::of::<RegressorOptions>(
        "regressor",
        "train_regressor_py",
        &[
            "data: _Path",
            "targets: Sequence[str]",
            "*",
            "encoder: Optional[_Path] = None",
            "features: Optional[_Path] = None",
            "out: Optional[_Path] = None",
        ],
        "A regressor (pose, depth, force; angles on the circle) on an encoder's features.",
    ),
    Trainer::of::<tactile_pose::PoseOptions>(
        "pose",
        "train_pose",
        &["data: _Path", "out: _Path"],
        "A supervised pose network (CNN on grey pin images) on TacTip frames.",
    ),
    Trainer::of::<tactile_detect::DetectorOptions>(
        "detector",
        "train_detector",
        &["data: Union[_Path, Sequence[_Path]]", "out: _Path"],
        "Paper B's tendon detector on one or more visuo-tactile datasets.",
    ),
    Trainer::of::<tactile_segment::SegmenterOptions>(
        "segmenter",
        "train_segmenter",
        &["data: _Path", "out: _Path"],
        "Paper B's U-Net tendon segmenter.",
    ),
    Trainer::of::<tactile_depth::DepthOptions>(
        "depth",
        "train_depth",
        &["data: _Path", "out: _Path"],
        "Paper B's depth U-Net with a DenseNet encoder.",
    ),
];

/// `tactile compare`'s and `tactile.study.compare`'s options (the study
/// itself is `tactile_bench::compare`'s): the targets, the split and the
/// estimators.
#[derive(Debug, Clone, clap::Args, Serialize, Deserialize)]
pub struct CompareOptions {
    /// Regression targets, e.g. x_mm,theta_deg:180,depth_mm (give these, a class column, or both).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub targets: Vec<String>,
    /// A class column to classify too (e.g. shape).
    #[arg(long)]
    pub classify: Option<String>,
    /// Without a `split` column: fraction of frames held out for testing.
    #[arg(long, default_value_t = 0.2)]
    pub test_fraction: f64,
    /// Fraction of the training frames for early stopping.
    #[arg(long, default_value_t = 0.2)]
    pub val_fraction: f64,
    /// Split and weight seed.
    #[arg(long, default_value_t = tactile_core::dataset::DEFAULT_SPLIT_SEED)]
    pub seed: u64,
    /// Preprocess with this preset or JSON file instead of the encoder's
    /// own (an encoder trained on one dataset applied to another).
    #[arg(long)]
    pub preprocess: Option<String>,
    /// Hidden widths of the regression MLP (the same for every feature set).
    #[arg(long, value_delimiter = ',', num_args = 1.., default_values_t = [256, 128])]
    pub hidden: Vec<usize>,
}

/// `tactile sweep`'s and `tactile.study.sweep`'s options (the study is
/// `tactile_bench::sweep`'s).
#[derive(Debug, Clone, clap::Args, Serialize, Deserialize)]
pub struct SweepOptions {
    /// Class column for the accuracy.
    #[arg(long, default_value = "shape")]
    pub classify: String,
    /// Split and head seed.
    #[arg(long, default_value_t = tactile_core::dataset::DEFAULT_SPLIT_SEED)]
    pub seed: u64,
    /// Timed runs per latency measurement.
    #[arg(long, default_value_t = 30)]
    pub runs: usize,
}

/// `tactile robustness`'s and `tactile.study.robustness`'s options (the
/// study is `tactile_bench::robustness`'s).
#[derive(Debug, Clone, clap::Args, Serialize, Deserialize)]
pub struct RobustnessOptions {
    /// Estimator folders (default: every folder in ENCODER with head.json, regressor.json or ensemble.json).
    #[arg(long, num_args = 1..)]
    pub heads: Vec<std::path::PathBuf>,
    /// Use at most this many frames (the first ones).
    #[arg(long)]
    pub limit: Option<usize>,
    /// Seed of the perturbations.
    #[arg(long, default_value_t = 11)]
    pub seed: u64,
}

/// Paper A's studies of an encoder (`tactile compare|sweep|robustness`,
/// `tactile.study.NAME(...)`), each returning its page and rows.
pub const STUDIES: &[Trainer] = &[
    Trainer::of::<CompareOptions>(
        "compare",
        "study_compare",
        &[
            "encoder: _Path",
            "data: _Path",
            "*",
            "out: Optional[_Path] = None",
        ],
        "Feature sets (the encoder's, PCA, raw pixels, pin tracking) against estimators on one split: the page (markdown), its regression and classification rows, and its warnings.",
    ),
    Trainer::of::<SweepOptions>(
        "sweep",
        "study_sweep",
        &[
            "encoders: Union[_Path, Sequence[_Path]]",
            "data: _Path",
            "*",
            "out: Optional[_Path] = None",
        ],
        "Paper A's feature-count search: each encoder's reconstruction error, shape accuracy and speed per runtime (the page and its rows).",
    ),
    Trainer::of::<RobustnessOptions>(
        "robustness",
        "study_robustness",
        &[
            "encoder: _Path",
            "data: _Path",
            "*",
            "out: Optional[_Path] = None",
        ],
        "Every estimator's errors on clean frames and on copies with more noise, an illumination gradient, a light blob or a rotation (the page and its rows).",
    ),
];

/// Every evaluation with options (`tactile eval NAME`,
/// `tactile.eval.NAME(...)`): what each writes beside its scores.
pub const EVALUATORS: &[Trainer] = &[
    Trainer::of::<tactile_detect::eval::EvalOptions>(
        "detector",
        "eval_detector",
        &["model: _Path", "data: _Path", "*", "runtime: str = \"burn-flex\""],
        "Accuracy, precision, recall, F1 and the onset/release frames of a tendon detector on a labelled visuo-tactile dataset, gated and ungated.",
    )
    .native_signature(
        &["model: str", "data: str", "*", "runtime: str = \"burn-flex\""],
        "Dict[str, Any]",
    ),
    Trainer::of::<tactile_depth::eval::EvalOptions>(
        "depth",
        "eval_depth",
        &["model: _Path", "data: _Path", "*", "runtime: str = \"burn-flex\""],
        "MAE (sensing window and tendon), RMSE and SSIM of a depth network, mm.",
    )
    .native_signature(
        &["model: str", "data: str", "*", "runtime: str = \"burn-flex\""],
        "Dict[str, Any]",
    ),
];

/// Sensor calibrations (`tactile calibrate NAME`,
/// `tactile.calibrate.NAME(...)`).
pub const CALIBRATORS: &[Trainer] = &[Trainer::of::<tactile_gelsight::BallOptions>(
    "ball",
    "calibrate_ball",
    &["data: _Path", "out: _Path"],
    "Calibrate a GelSight-like sensor from presses of a ball of known radius (the calibration layout of docs/datasets.md) into a new model folder.",
)];

/// The trainer called `name`, or an error naming those there are.
pub fn trainer(name: &str) -> Result<&'static Trainer> {
    TRAINERS.iter().find(|t| t.name == name).ok_or_else(|| {
        let known: Vec<&str> = TRAINERS.iter().map(|t| t.name).collect();
        Error::from(tactile_core::Error::Config(format!(
            "no trainer '{name}' (known: {})",
            known.join(", ")
        )))
    })
}

/// The marker lines around the generated part of a stub file.
pub const STUB_BEGIN: &str = "# --- generated by tactile_pipeline::options (TACTILE_BLESS=1 cargo test --release --workspace --test options): do not edit ---";
/// See [`STUB_BEGIN`].
pub const STUB_END: &str = "# --- end of generated part ---";

/// The generated parts of the Python stubs, each between [`STUB_BEGIN`]
/// and [`STUB_END`].
#[derive(Debug, Clone, PartialEq)]
pub struct PythonStubs {
    /// The typed native functions of `_tactile.pyi`.
    pub native: String,
    /// The typed trainers of `tactile/train.pyi`.
    pub train: String,
    /// The typed generators of `tactile/synth.pyi`.
    pub synth: String,
    /// The typed evaluations of `tactile/eval.pyi`.
    pub eval: String,
    /// The typed calibrations of `tactile/calibrate.pyi`.
    pub calibrate: String,
    /// The typed studies of `tactile/study.pyi`.
    pub study: String,
}

/// The generated parts of the Python stubs ([`PythonStubs`]).
pub fn python_stubs() -> Result<PythonStubs> {
    let mut native = format!("{STUB_BEGIN}\n");
    let mut train = format!("{STUB_BEGIN}\n");
    let mut synth = format!("{STUB_BEGIN}\n");
    let mut eval = format!("{STUB_BEGIN}\n");
    let mut calibrate = format!("{STUB_BEGIN}\n");
    let mut study = format!("{STUB_BEGIN}\n");
    for (entries, own) in [
        (TRAINERS, &mut train),
        (GENERATORS, &mut synth),
        (EVALUATORS, &mut eval),
        (CALIBRATORS, &mut calibrate),
        (STUDIES, &mut study),
    ] {
        for t in entries {
            native.push_str(&t.native_def()?);
            native.push_str(" ...\n");
            own.push_str(&t.python_def()?);
            own.push_str(&format!("\n    \"\"\"{}\"\"\"\n\n", t.about));
        }
    }
    for part in [
        &mut native,
        &mut train,
        &mut synth,
        &mut eval,
        &mut calibrate,
        &mut study,
    ] {
        part.push_str(STUB_END);
        part.push('\n');
    }
    Ok(PythonStubs {
        native,
        train,
        synth,
        eval,
        calibrate,
        study,
    })
}
