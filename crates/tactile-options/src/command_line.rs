//! How a command line's words become options: which flags the user gave
//! (so an options file fills only the others), and numbers below zero
//! kept as the values of their flags.

use std::ffi::OsString;
use std::path::Path;

use clap::ArgMatches;
use clap::parser::ValueSource;
use serde::Serialize;
use serde_json::{Map, Value};
use tactile_core::{Error, Result};

use crate::Options;

/// The options of `parsed` that the command line `matches` gave, by name,
/// as JSON values: `--config FILE` goes under them, the defaults under
/// that.
fn given<P: Serialize>(parsed: &P, matches: &ArgMatches) -> Result<Map<String, Value>> {
    let Value::Object(values) =
        serde_json::to_value(parsed).map_err(|e| Error::Config(e.to_string()))?
    else {
        return Err(Error::Config("options must serialise as an object".into()));
    };
    Ok(values
        .into_iter()
        .filter(|(k, _)| {
            matches.try_get_raw(k).is_ok_and(|v| v.is_some())
                && matches.value_source(k) == Some(ValueSource::CommandLine)
        })
        .collect())
}

/// The options a verb parsed, with `config` (`--config FILE`) under them:
/// the file's options replace the defaults, and the flags given on the
/// command line (`matches`) replace the file's ([`Options::resolve`], as
/// Python's `config=` does it).
pub fn resolve<T: Options>(parsed: T, config: Option<&Path>, matches: &ArgMatches) -> Result<T> {
    match config {
        None => Ok(parsed),
        Some(config) => T::resolve(Some(config), &given(&parsed, matches)?),
    }
}

/// Options of another type `T` made from the flags of `parsed` given on
/// the command line `matches` (by name; a given flag `T` does not have is
/// refused, naming it), with `config` under them: how `synth visuotactile
/// --sensor` takes the calibrated generator's options.
pub fn resolve_as<P: Serialize, T: Options>(
    parsed: &P,
    config: Option<&Path>,
    matches: &ArgMatches,
) -> Result<T> {
    let Value::Object(known) =
        serde_json::to_value(T::defaults()?).map_err(|e| Error::Config(e.to_string()))?
    else {
        return Err(Error::Config("options must serialise as an object".into()));
    };
    let given = given(parsed, matches)?;
    if let Some(k) = given.keys().find(|k| !known.contains_key(*k)) {
        return Err(Error::Config(format!(
            "--{} does not apply here (the options are: {})",
            k.replace('_', "-"),
            known.keys().cloned().collect::<Vec<_>>().join(", ")
        )));
    }
    T::resolve(config, &given)
}

/// The command line's words, each value that starts with `-` and a digit
/// or a point (`--x-mm -6,6`, the default its help shows; `--rotate-deg
/// -5`, `--hysteresis -0.5,0.3`, `--seed -1`) attached to the flag before
/// it (`--x-mm=-6,6`). Clap reads such a word as a cluster of short flags
/// (`-6`) otherwise, and says "unexpected argument"; attached, it reaches
/// the flag's parser or check, which names the flag. Only a number-like
/// word is attached, so `--lr --epochs 5` is still a missing value, not a
/// learning rate of `--epochs`; nothing after `--` is touched.
pub fn attach_negative_values(args: impl IntoIterator<Item = OsString>) -> Vec<OsString> {
    let number_like = |w: &str| {
        let mut c = w.chars();
        c.next() == Some('-') && matches!(c.next(), Some('0'..='9' | '.'))
    };
    let mut words: Vec<OsString> = Vec::new();
    let mut positional = false;
    for word in args {
        if !positional {
            if let (Some(value), Some(flag)) = (
                word.to_str().filter(|w| number_like(w)),
                words.last_mut().filter(|f| {
                    f.to_str()
                        .is_some_and(|f| f.len() > 2 && f.starts_with("--") && !f.contains('='))
                }),
            ) {
                flag.push("=");
                flag.push(value);
                continue;
            }
            positional = word == "--";
        }
        words.push(word);
    }
    words
}

#[cfg(test)]
mod tests {
    use std::ffi::OsString;

    use clap::{Args, Command, FromArgMatches};
    use serde::{Deserialize, Serialize};

    /// Two options, as a trainer's are.
    #[derive(Args, Serialize, Deserialize, Debug, PartialEq)]
    struct Two {
        /// First.
        #[arg(long, default_value_t = 1)]
        a: u32,
        /// Second.
        #[arg(long, default_value_t = 2)]
        b: u32,
    }

    /// Only the first, as another generator's options.
    #[derive(Args, Serialize, Deserialize, Debug, PartialEq)]
    struct One {
        /// First.
        #[arg(long, default_value_t = 10)]
        a: u32,
    }

    fn parse(words: &[&str]) -> (Two, clap::ArgMatches) {
        let m = Two::augment_args(Command::new("t").no_binary_name(true))
            .try_get_matches_from(words)
            .unwrap();
        (Two::from_arg_matches(&m).unwrap(), m)
    }

    #[test]
    fn flags_given_win_over_the_options_file_and_the_file_over_defaults() {
        let dir = std::env::temp_dir().join(format!("tactile-options-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("o.json");
        std::fs::write(&file, r#"{"a": 5, "b": 6}"#).unwrap();
        let (parsed, m) = parse(&["--b", "9"]);
        let got = super::resolve(parsed, Some(&file), &m).unwrap();
        assert_eq!(got, Two { a: 5, b: 9 });
        // A flag at its default value, given on the line, still wins.
        let (parsed, m) = parse(&["--a", "1"]);
        assert_eq!(
            super::resolve(parsed, Some(&file), &m).unwrap(),
            Two { a: 1, b: 6 }
        );
        // No file: the flags as parsed.
        let (parsed, m) = parse(&["--b", "9"]);
        assert_eq!(
            super::resolve(parsed, None, &m).unwrap(),
            Two { a: 1, b: 9 }
        );
        // Another type takes the flags it has, and refuses one it has not,
        // naming it.
        let (parsed, m) = parse(&["--a", "4"]);
        let one: One = super::resolve_as(&parsed, None, &m).unwrap();
        assert_eq!(one, One { a: 4 });
        let (parsed, m) = parse(&["--b", "4"]);
        let e = super::resolve_as::<Two, One>(&parsed, None, &m)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--b does not apply here (the options are: a)"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_number_below_zero_is_attached_to_its_flag_but_not_after_a_double_dash() {
        let words = super::attach_negative_values(
            [
                "tactile", "--a", "-1", "--b=2", "-.5", "-x", "--", "--c", "-2",
            ]
            .map(OsString::from),
        );
        assert_eq!(
            words,
            ["tactile", "--a=-1", "--b=2", "-.5", "-x", "--", "--c", "-2"]
        );
    }
}
