//! The models composed into what a robot runs. Paper B's palpation
//! pipeline ([`Pipeline`]): the detector on every frame, the segmenter,
//! direction and depth only on tendon frames, on burn or onnxruntime, with
//! a run loop over datasets and folders of frames ([`run`]). Paper A's
//! perception ([`tactip`]): one encoder, every estimator of its folder on
//! one encoding, and the training of those estimators.

#![deny(missing_docs)]

pub mod calibrate;
pub mod ensemble;
mod error;
pub mod export;
pub mod hysteresis;
pub mod options;
pub mod overlay;
pub mod palpation;
pub mod run;
pub mod tactip;

pub use error::{Error, Result};
pub use hysteresis::Hysteresis;
pub use overlay::{FrameViews, SensorView, TendonView};
pub use palpation::{FrameRecord, PalpationModels, Pipeline};
pub use run::{
    ContactSummary, Flow, RunItem, RunOptions, RunOutcome, RunSummary, run, run_collect,
};
pub use tactile_burn::Runtime;
pub use tactile_core::source::{
    Frame, FrameEntry, FrameList, FrameSource, MissingFrames, SourceKind, SourceOptions, SourceSpec,
};

/// What a folder that is not the model a command wants holds, for its
/// error: the subfolders that are (`is_model`: a user who named the folder
/// above the models), or the configuration files it has, said to be
/// `other` (a model of another kind).
pub(crate) fn folder_hint(
    dir: &std::path::Path,
    is_model: impl Fn(&std::path::Path) -> bool,
    other: &str,
) -> String {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return String::new();
    };
    let (mut models, mut configs) = (Vec::new(), Vec::new());
    for e in entries.take(1000).flatten() {
        let (path, name) = (e.path(), e.file_name().to_string_lossy().into_owned());
        if path.is_dir() && is_model(&path) {
            models.push(name);
        } else if name.ends_with(".json") && !name.starts_with("training") {
            configs.push(name);
        }
    }
    models.sort();
    configs.sort();
    let list = |v: &[String]| {
        let mut s = v[..v.len().min(6)].join(", ");
        if v.len() > 6 {
            s.push_str(", ...");
        }
        s
    };
    if models.len() == 1 {
        format!("; the folder {} in it is: pass it", models[0])
    } else if !models.is_empty() {
        format!("; the folders {} in it are: pass one", list(&models))
    } else if !configs.is_empty() {
        format!("; it holds {}: {other}", list(&configs))
    } else {
        String::new()
    }
}
