//! Argument types shared by several verbs.

use std::fmt;
use std::str::FromStr;

use tactile_preprocess::PreprocessConfig;

/// `WIDTHxHEIGHT`, e.g. `160x120`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Size(pub [usize; 2]);

impl fmt::Display for Size {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.0[0], self.0[1])
    }
}

impl FromStr for Size {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (w, h) = s
            .split_once(['x', 'X'])
            .ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT, e.g. 160x120"))?;
        let p = |v: &str| {
            v.trim()
                .parse::<usize>()
                .ok()
                .filter(|&n| n >= 16)
                .ok_or_else(|| format!("'{s}': sizes must be whole numbers of at least 16 pixels"))
        };
        Ok(Size([p(w)?, p(h)?]))
    }
}

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
