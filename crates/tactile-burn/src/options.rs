//! The options layer: every trainer's options are one type (a
//! `clap::Args` whose defaults come from the model's config), which the
//! command line flattens into its flags and the Python package fills from
//! keyword arguments ([`Options::with_overrides`]), so an option, its
//! default and its help are written once and reach both front ends.

use std::fmt;
use std::str::FromStr;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use tactile_core::dataset::TestHoldout;
use tactile_core::{Error, Result};

/// One option as a front end shows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OptionDoc {
    /// Its name (Python keyword; `--name-with-dashes` on the command line).
    pub name: String,
    /// Its help text.
    pub help: String,
    /// Its default as JSON (null: the model's own default applies).
    pub default: Value,
}

/// A set of options both front ends fill: clap flags on the command line,
/// keyword arguments in Python. Implemented for every `clap::Args` type
/// whose fields all have defaults and that serialises with the same names.
pub trait Options: clap::Args + clap::FromArgMatches + Serialize + DeserializeOwned {
    /// Every option at its default (as the command line with no flag).
    fn defaults() -> Result<Self> {
        let cmd = Self::augment_args(clap::Command::new("options").no_binary_name(true));
        let m = cmd
            .try_get_matches_from(Vec::<String>::new())
            .map_err(|e| Error::Config(e.to_string()))?;
        Self::from_arg_matches(&m).map_err(|e| Error::Config(e.to_string()))
    }

    /// The defaults with `overrides` (name -> JSON value) set; an unknown
    /// name or a value of the wrong type is refused, naming the option and
    /// the options there are. A null value keeps the default.
    fn with_overrides(overrides: &Map<String, Value>) -> Result<Self> {
        let mut v =
            serde_json::to_value(Self::defaults()?).map_err(|e| Error::Config(e.to_string()))?;
        let known = v
            .as_object_mut()
            .ok_or_else(|| Error::Config("options must serialise as an object".into()))?;
        for (k, value) in overrides {
            if !known.contains_key(k) {
                let mut names: Vec<&String> = known.keys().collect();
                names.sort();
                let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
                return Err(Error::Config(format!(
                    "unknown option '{k}' (known: {})",
                    names.join(", ")
                )));
            }
            if !value.is_null() {
                known.insert(k.clone(), value.clone());
            }
        }
        serde_json::from_value(v).map_err(|e| {
            // Name the offending option: the first that fails on its own.
            let bad = overrides.iter().find(|(k, value)| {
                let mut one = serde_json::to_value(Self::defaults().ok()).unwrap_or_default();
                match one.as_object_mut() {
                    Some(o) if !value.is_null() => {
                        o.insert((*k).clone(), (*value).clone());
                        serde_json::from_value::<Self>(one).is_err()
                    }
                    _ => false,
                }
            });
            match bad {
                Some((k, value)) => Error::Config(format!("option '{k}' = {value}: {e}")),
                None => Error::Config(format!("options: {e}")),
            }
        })
    }

    /// Every option with its help and default, in flag order.
    fn docs() -> Result<Vec<OptionDoc>> {
        let defaults =
            serde_json::to_value(Self::defaults()?).map_err(|e| Error::Config(e.to_string()))?;
        let cmd = Self::augment_args(clap::Command::new("options"));
        Ok(cmd
            .get_arguments()
            .map(|a| {
                let name = a.get_id().as_str().to_string();
                OptionDoc {
                    help: a.get_help().map(|h| h.to_string()).unwrap_or_default(),
                    default: defaults.get(&name).cloned().unwrap_or(Value::Null),
                    name,
                }
            })
            .collect())
    }
}

impl<T: clap::Args + clap::FromArgMatches + Serialize + DeserializeOwned> Options for T {}

/// An image size `WIDTHxHEIGHT` (e.g. `160x120`): `--input 320x240` on the
/// command line, `input=(320, 240)` or `"320x240"` in Python and configs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Size(pub [usize; 2]);

impl fmt::Display for Size {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.0[0], self.0[1])
    }
}

impl FromStr for Size {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let (w, h) = s
            .split_once(['x', 'X'])
            .ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT, e.g. 160x120"))?;
        let p = |v: &str| v.trim().parse::<usize>().ok();
        Size::checked(
            p(w).ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT, e.g. 160x120"))?,
            p(h).ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT, e.g. 160x120"))?,
        )
    }
}

impl Size {
    /// A size of at least 16 pixels a side.
    pub fn checked(w: usize, h: usize) -> std::result::Result<Self, String> {
        if w >= 16 && h >= 16 {
            Ok(Size([w, h]))
        } else {
            Err(format!(
                "{w}x{h}: sizes must be whole numbers of at least 16 pixels"
            ))
        }
    }
}

impl Serialize for Size {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

impl<'de> Deserialize<'de> for Size {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Form {
            Pair([usize; 2]),
            Text(String),
        }
        match Form::deserialize(d)? {
            Form::Pair([w, h]) => Size::checked(w, h),
            Form::Text(t) => t.parse(),
        }
        .map_err(serde::de::Error::custom)
    }
}

/// A front end's schedule flags for one model (`--max-epochs`,
/// `--patience`, `--batch-size`, `--lr`, `--lr-decay`, `--seed`,
/// `--device`, `--resume`), their defaults from that model's training
/// config: `schedule_args!(Name, Config::new().schedule)` defines `Name`
/// with `schedule(default_lr)` and the public fields `device` and `resume`.
#[macro_export]
macro_rules! schedule_args {
    ($name:ident, $default:expr) => {
        /// The schedule flags, the device and resuming, with this model's defaults.
        #[derive(clap::Args, serde::Serialize, serde::Deserialize, Debug, Clone)]
        pub struct $name {
            /// Upper bound on epochs.
            #[arg(long, default_value_t = $default.max_epochs)]
            pub max_epochs: usize,
            /// Epochs without a better validation loss before stopping.
            #[arg(long, default_value_t = $default.patience)]
            pub patience: usize,
            /// Items per optimiser step.
            #[arg(long, default_value_t = $default.batch_size)]
            pub batch_size: usize,
            /// Learning rate of the first epoch [default: the model's; for the
            /// CAE, Adadelta 1.0 or Adam 0.003].
            #[arg(long)]
            pub lr: Option<f64>,
            /// Learning-rate factor per epoch.
            #[arg(long, default_value_t = $default.lr_decay)]
            pub lr_decay: f64,
            /// Seeds the weights, every shuffle and every split.
            #[arg(long, default_value_t = $default.seed)]
            pub seed: u64,
            /// Training device.
            #[arg(long, value_enum, default_value_t = $crate::DeviceKind::Flex)]
            pub device: $crate::DeviceKind,
            /// Continue from the checkpoint in the output folder.
            #[arg(long)]
            pub resume: bool,
        }

        impl $name {
            /// The schedule, `default_lr` when no `--lr` was given.
            pub fn schedule(&self, default_lr: f64) -> $crate::train::Schedule {
                $crate::train::Schedule::new(
                    self.batch_size,
                    self.max_epochs,
                    self.patience,
                    self.lr.unwrap_or(default_lr),
                )
                .with_lr_decay(self.lr_decay)
                .with_seed(self.seed)
            }
        }
    };
}

/// `--exclude-test` and `--split-seed` for every trainer that can leave
/// out a later evaluation's test frames.
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone, Copy)]
pub struct TestHoldoutArgs {
    /// Without a `split` column: leave out the test frames that `tactile compare`/`train regressor` with this test fraction and --split-seed hold out, so the model never sees them.
    #[arg(long)]
    pub exclude_test: Option<f64>,
    /// The seed of that split (compare's --seed).
    #[arg(long, default_value_t = 7)]
    pub split_seed: u64,
}

impl TestHoldoutArgs {
    /// The holdout these flags ask for.
    pub fn holdout(&self) -> Option<TestHoldout> {
        TestHoldout::excluding(self.exclude_test, self.split_seed)
    }
}
