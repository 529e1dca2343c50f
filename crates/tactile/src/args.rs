//! Argument types shared by several verbs.

use std::str::FromStr;

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
