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
