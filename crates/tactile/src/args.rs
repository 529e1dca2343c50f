//! Argument types shared by several verbs.

use std::path::Path;
use std::str::FromStr;
use std::sync::OnceLock;

use clap::ArgMatches;
use clap::parser::ValueSource;
use serde_json::{Map, Value};
use tactile_burn::options::Options;

use tactile_preprocess::PreprocessConfig;

pub(crate) use tactile_burn::options::Size;

/// A preprocessing preset or JSON file, with its name for messages.
#[derive(Debug, Clone)]
pub(crate) struct Preprocess {
    pub name: String,
    pub config: PreprocessConfig,
}

impl FromStr for Preprocess {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(Preprocess {
            name: s.to_string(),
            config: PreprocessConfig::preset(s).map_err(|e| e.to_string())?,
        })
    }
}

/// The parsed command line's innermost subcommand, for [`resolve`].
static LEAF: OnceLock<ArgMatches> = OnceLock::new();

/// Keep the matches of the command line, so [`resolve`] can tell a flag
/// the user gave from one left at its default.
pub(crate) fn keep_matches(mut m: ArgMatches) {
    while let Some((_, sub)) = m.remove_subcommand() {
        m = sub;
    }
    let _ = LEAF.set(m);
}

/// Options of another type `T` made from the flags of `parsed` given on the
/// command line (by name; a given flag `T` does not have is refused),
/// with `--config FILE` (of `T`'s options) under them: how `synth
/// visuotactile --sensor` takes the calibrated generator's options.
pub(crate) fn resolve_as<P: serde::Serialize, T: Options>(
    parsed: &P,
    config: Option<&Path>,
) -> anyhow::Result<T> {
    let Value::Object(values) = serde_json::to_value(parsed)? else {
        anyhow::bail!("options must serialise as an object");
    };
    let Value::Object(known) = serde_json::to_value(T::defaults()?)? else {
        anyhow::bail!("options must serialise as an object");
    };
    let mut given = Map::new();
    if let Some(m) = LEAF.get() {
        for (k, v) in values {
            let on_line = m.try_get_raw(&k).is_ok_and(|v| v.is_some())
                && m.value_source(&k) == Some(ValueSource::CommandLine);
            if !on_line {
                continue;
            }
            if !known.contains_key(&k) {
                anyhow::bail!(
                    "--{} does not apply here (the options are: {})",
                    k.replace('_', "-"),
                    known.keys().cloned().collect::<Vec<_>>().join(", ")
                );
            }
            given.insert(k, v);
        }
    }
    Ok(T::resolve(config, &given)?)
}

/// The options a verb parsed, with `--config FILE` under them: the file's
/// options replace the defaults, and the flags given on the command line
/// replace the file's (the library's [`Options::resolve`], as Python's
/// `config=` does it).
pub(crate) fn resolve<T: Options>(parsed: T, config: Option<&Path>) -> anyhow::Result<T> {
    let Some(config) = config else {
        return Ok(parsed);
    };
    let Value::Object(values) = serde_json::to_value(&parsed)? else {
        anyhow::bail!("options must serialise as an object");
    };
    let given: Map<String, Value> = match LEAF.get() {
        Some(m) => values
            .into_iter()
            .filter(|(k, _)| {
                m.try_get_raw(k).is_ok_and(|v| v.is_some())
                    && m.value_source(k) == Some(ValueSource::CommandLine)
            })
            .collect(),
        None => Map::new(),
    };
    Ok(T::resolve(Some(config), &given)?)
}
