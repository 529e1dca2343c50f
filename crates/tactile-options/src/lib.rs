//! The options layer: every trainer's and generator's options are one type
//! (a `clap::Args` whose defaults come from the model's or generator's
//! config), which the command line flattens into its flags and the Python
//! package fills from keyword arguments ([`Options::with_overrides`]), so
//! an option, its default and its help are written once and reach both
//! front ends. Burn-free: the virtual sensors use it as the trainers do.

#![deny(missing_docs)]

pub mod command_line;

use std::fmt;
use std::path::Path;
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

/// The options `T` of `defaults` with `key` alone set to `value`: whether
/// that value is one the option takes, and if not, why.
fn alone<T: DeserializeOwned>(
    defaults: &Map<String, Value>,
    key: &str,
    value: &Value,
) -> std::result::Result<T, serde_json::Error> {
    let mut one = defaults.clone();
    one.insert(key.to_string(), value.clone());
    serde_json::from_value(Value::Object(one))
}

/// The items one string gives an option that takes a list: what its
/// commas separate, each trimmed (`"x_mm, y_mm"` is `x_mm` and `y_mm`), as
/// Python's keywords and options files may give a list flag's value.
pub fn list_items(text: &str) -> impl Iterator<Item = &str> {
    text.split(',').map(str::trim)
}

/// `value`, or, when it is a string the option does not take as it is but
/// takes as a list, the list its commas separate (numbers as numbers), as
/// the flag reads it: `targets="x_mm,y_mm"` as `--targets x_mm,y_mm`.
fn listed<T>(
    value: &Value,
    takes: impl Fn(&Value) -> std::result::Result<T, serde_json::Error>,
) -> Value {
    let Value::String(s) = value else {
        return value.clone();
    };
    if takes(value).is_ok() {
        return value.clone();
    }
    let list = Value::Array(
        list_items(s)
            .map(|p| match serde_json::from_str::<Value>(p) {
                Ok(n @ Value::Number(_)) => n,
                _ => Value::String(p.to_string()),
            })
            .collect(),
    );
    if takes(&list).is_ok() {
        list
    } else {
        value.clone()
    }
}

/// How a whole number that no 64-bit integer holds is refused, by both
/// front ends: JSON reads it as a float, whose own wording ("invalid type:
/// floating point `1.1805916207174113e21`, expected u64") names a number
/// the user never wrote.
pub const BEYOND_64_BITS: &str = "a whole number beyond 64 bits";

/// Whether `value`, or a value in it (a list's, an object's), is a whole
/// number outside both `i64` and `u64`: what JSON makes of such a number
/// written in an options file (a float, as it makes of `1e30`).
fn beyond_64_bits(value: &Value) -> bool {
    // 2^63 and 2^64, exact as floats.
    const I64_MIN: f64 = -9_223_372_036_854_775_808.0;
    const U64_END: f64 = 18_446_744_073_709_551_616.0;
    match value {
        Value::Number(n) => {
            n.is_f64()
                && n.as_f64().is_some_and(|x| {
                    x.is_finite() && x.fract() == 0.0 && !(I64_MIN..U64_END).contains(&x)
                })
        }
        Value::Array(items) => items.iter().any(beyond_64_bits),
        Value::Object(m) => m.values().any(beyond_64_bits),
        _ => false,
    }
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
        Self::resolve(None, overrides)
    }

    /// The defaults, then the options of a `config` file (a JSON object of
    /// option names, as `--config FILE` and Python's `config=` give it),
    /// then `overrides` (the flags given on the command line, or the
    /// keyword arguments): each later one wins. An unknown name is refused,
    /// naming the file where it came from one.
    fn resolve(config: Option<&Path>, overrides: &Map<String, Value>) -> Result<Self> {
        let defaults =
            serde_json::to_value(Self::defaults()?).map_err(|e| Error::Config(e.to_string()))?;
        let Value::Object(defaults) = defaults else {
            return Err(Error::Config("options must serialise as an object".into()));
        };
        // Every flag is an option, also one its type leaves out of the
        // serialised defaults (`skip_serializing_if`: a manifest that stays
        // as it was while the option is at its default).
        let names: std::collections::BTreeSet<String> = defaults
            .keys()
            .cloned()
            .chain(
                Self::augment_args(clap::Command::new("options"))
                    .get_arguments()
                    .map(|a| a.get_id().to_string()),
            )
            .collect();
        let known = names.iter().cloned().collect::<Vec<_>>().join(", ");
        let file = match config {
            Some(p) => match read_options_file(p)? {
                Value::Object(m) => Some((p, m)),
                _ => {
                    return Err(Error::Config(format!(
                        "{}: an options file is a JSON object of option names (known: {known})",
                        p.display()
                    )));
                }
            },
            None => None,
        };
        // Each layer with where a refused name or value came from: a
        // file, or nothing (flags, keywords).
        let layers: Vec<(String, &Map<String, Value>)> = file
            .iter()
            .map(|(p, m)| (format!("{}: ", p.display()), m))
            .chain(std::iter::once((String::new(), overrides)))
            .collect();
        // Unknown names first, in every layer, then the values.
        for (at, layer) in &layers {
            if let Some(k) = layer.keys().find(|k| !names.contains(*k)) {
                return Err(Error::Config(format!(
                    "{at}unknown option '{k}' (known: {known})"
                )));
            }
        }
        let mut merged = defaults.clone();
        for (at, layer) in &layers {
            for (k, value) in *layer {
                if !value.is_null() {
                    let value = listed(value, |v| alone::<Self>(&defaults, k, v));
                    // Each value is checked on its own where it is given,
                    // with its own error (not another option's): a file's
                    // value is refused even when a flag or keyword sets the
                    // option again, as the file would be wrong the next
                    // time it is used.
                    if let Err(e) = alone::<Self>(&defaults, k, &value) {
                        let why = match beyond_64_bits(&value) {
                            true => BEYOND_64_BITS.to_string(),
                            false => e.to_string(),
                        };
                        return Err(Error::Config(format!("{at}option '{k}' = {value}: {why}")));
                    }
                    merged.insert(k.clone(), value);
                }
            }
        }
        serde_json::from_value(Value::Object(merged))
            .map_err(|e| Error::Config(format!("options: {e}")))
    }

    /// Each option's clap argument with its default as JSON, in flag
    /// order: what [`Options::docs`] and [`Options::python_params`] show.
    fn each_with_default<R>(show: impl Fn(&clap::Arg, Value) -> R) -> Result<Vec<R>> {
        let defaults =
            serde_json::to_value(Self::defaults()?).map_err(|e| Error::Config(e.to_string()))?;
        let cmd = Self::augment_args(clap::Command::new("options"));
        Ok(cmd
            .get_arguments()
            .map(|a| {
                let default = defaults.get(a.get_id().as_str()).cloned();
                show(a, default.unwrap_or(Value::Null))
            })
            .collect())
    }

    /// Every option with its help and default, in flag order.
    fn docs() -> Result<Vec<OptionDoc>> {
        Self::each_with_default(|a, default| OptionDoc {
            name: a.get_id().as_str().to_string(),
            help: a.get_help().map(|h| h.to_string()).unwrap_or_default(),
            default,
        })
    }

    /// Every option as a typed Python keyword parameter
    /// (`name: Type = default`), in flag order: what the generated stubs
    /// (`_tactile.pyi`, `tactile/train.pyi`) declare, so an option added
    /// here reaches editors and type checkers without being written again.
    fn python_params() -> Result<Vec<String>> {
        Self::each_with_default(|a, default| {
            let ty = python_type(a, &default);
            let ty = if default.is_null() {
                format!("Optional[{ty}]")
            } else {
                ty
            };
            format!("{}: {ty} = {}", a.get_id(), python_literal(&default))
        })
    }
}

impl<T: clap::Args + clap::FromArgMatches + Serialize + DeserializeOwned> Options for T {}

/// Largest options file read, bytes: options are a few hundred bytes, so
/// anything near this is not an options file.
pub const MAX_OPTIONS_FILE_BYTES: u64 = 1 << 20;

/// An options file's JSON, its size checked before it is read.
fn read_options_file(path: &Path) -> Result<Value> {
    tactile_core::io::read_json_limited(path, MAX_OPTIONS_FILE_BYTES)
}

/// The Python type of one option's values: from its clap action and value
/// parser (what the command line accepts), a list when it takes several.
fn python_type(arg: &clap::Arg, default: &Value) -> String {
    use std::any::TypeId;
    if matches!(arg.get_action(), clap::ArgAction::SetTrue) {
        return "bool".into();
    }
    let id = arg.get_value_parser().type_id();
    let one = if id == TypeId::of::<Size>() {
        "Tuple[int, int]"
    } else if id == TypeId::of::<tactile_core::rng::Range>() {
        "Tuple[float, float]"
    } else if [TypeId::of::<f64>(), TypeId::of::<f32>()]
        .iter()
        .any(|t| id == *t)
    {
        "float"
    } else if [
        TypeId::of::<usize>(),
        TypeId::of::<u64>(),
        TypeId::of::<u32>(),
        TypeId::of::<u8>(),
        TypeId::of::<i64>(),
        TypeId::of::<i32>(),
    ]
    .iter()
    .any(|t| id == *t)
    {
        "int"
    } else if id == TypeId::of::<bool>() {
        "bool"
    } else {
        "str"
    };
    let many = arg.get_value_delimiter().is_some()
        || matches!(arg.get_action(), clap::ArgAction::Append)
        || default.is_array() && id != TypeId::of::<Size>();
    if many {
        format!("Sequence[{one}]")
    } else {
        one.into()
    }
}

/// A JSON default as Python source.
fn python_literal(v: &Value) -> String {
    match v {
        Value::Null => "None".into(),
        Value::Bool(b) => if *b { "True" } else { "False" }.into(),
        Value::Number(n) => match (n.as_f64(), n.is_f64()) {
            (Some(f), true) if f.fract() == 0.0 && f.abs() < 1e15 => format!("{f:.1}"),
            _ => n.to_string(),
        },
        Value::String(t) => serde_json::to_string(t).unwrap_or_default(),
        Value::Array(a) => format!(
            "({}{})",
            a.iter().map(python_literal).collect::<Vec<_>>().join(", "),
            if a.len() == 1 { "," } else { "" }
        ),
        // A range {min, max} is a pair in Python.
        Value::Object(m) => match (m.get("min"), m.get("max"), m.len()) {
            (Some(a), Some(b), 2) => format!("({}, {})", python_literal(a), python_literal(b)),
            _ => "None".into(),
        },
    }
}

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

/// `--exclude-test` and `--split-seed` for every trainer that can leave
/// out a later evaluation's test frames.
#[derive(clap::Args, Serialize, Deserialize, Debug, Clone, Copy)]
pub struct TestHoldoutArgs {
    /// Without a `split` column: leave out the test frames that `tactile compare`/`train regressor` with this test fraction and --split-seed hold out, so the model never sees them.
    #[arg(long)]
    pub exclude_test: Option<f64>,
    /// The seed of that split (compare's --seed).
    #[arg(long, default_value_t = tactile_core::dataset::DEFAULT_SPLIT_SEED)]
    pub split_seed: u64,
}

impl TestHoldoutArgs {
    /// The holdout these flags ask for. A split seed without a test
    /// fraction would pick nothing, so it is refused rather than ignored.
    pub fn holdout(&self) -> tactile_core::Result<Option<TestHoldout>> {
        if self.exclude_test.is_none()
            && self.split_seed != tactile_core::dataset::DEFAULT_SPLIT_SEED
        {
            return Err(tactile_core::Error::Config(format!(
                "split_seed {} picks the test frames that exclude_test leaves out, and no \
                 exclude_test is given: give exclude_test too, or leave split_seed out",
                self.split_seed
            )));
        }
        Ok(TestHoldout::excluding(self.exclude_test, self.split_seed))
    }
}
