//! `tactile train profile`: the input profile of a trained model, fitted
//! on its training frames and saved in its config (the weights are not
//! touched), so `predict` and the pipeline name frames of another sensor.
//! A detector's reads colour frames ([`tactile_detect::profile`]); a
//! TacTip model's (an encoder, a pose network, each member of a pose
//! ensemble) reads its pin images ([`InputProfile::fit_pins`]).

use std::path::Path;

use tactile_burn::Artifact;
use tactile_cae::CaeArtifact;
use tactile_cae::data::{DATASET_CHUNK, PinSet};
use tactile_core::dataset::Dataset;
use tactile_pose::{PoseArtifact, PoseEnsemble};
use tactile_preprocess::PreprocessConfig;
use tactile_preprocess::profile::{InputProfile, PIN_PROFILE_MARGIN, pin_spectra};

use crate::Result;
use crate::tactip::TactipModelKind;

/// Fit and save the input profile of the model in `dir` on `datasets`
/// (its training data): a detector's, or a TacTip model's (on the rows of
/// `split` alone when given). Returns the profile (an ensemble's first
/// member's, the one it reads frames with).
pub fn add_input_profile(
    dir: &Path,
    datasets: &[Dataset],
    split: Option<&str>,
) -> Result<InputProfile> {
    let detector = tactile_detect::DetectorArtifact::is_in(dir)
        || tactile_detect::DetectorEnsembleArtifact::read(dir).is_ok();
    if detector {
        if let Some(s) = split {
            return Err(tactile_core::Error::Config(format!(
                "a detector's profile is fitted on whole datasets: leave out the split ({s})"
            ))
            .into());
        }
        return Ok(tactile_detect::profile::add_input_profile(dir, datasets)?);
    }
    TactipModelKind::of(
        dir,
        "a model without an input profile (a detector or a TacTip model has one)",
    )?;
    let rows = datasets
        .iter()
        .map(|ds| rows_of(ds, split))
        .collect::<Result<Vec<_>>>()?;
    add_pin_profile(dir, datasets, &rows)
}

/// The rows of `ds` in `split` (every row without one); a split the
/// dataset does not have is refused naming its labels.
pub fn rows_of(ds: &Dataset, split: Option<&str>) -> Result<Vec<usize>> {
    let Some(s) = split else {
        return Ok(ds.every_row());
    };
    let rows = ds.split_rows(s)?;
    if rows.is_empty() {
        return Err(tactile_core::Error::dataset(
            ds.labels_path(),
            None,
            format!("no row's split is '{s}'"),
        )
        .into());
    }
    Ok(rows)
}

/// The pin profile of the TacTip model in `dir`, fitted on every frame of
/// `rows` of `datasets` that is not flat, saved in its config atomically.
fn add_pin_profile(dir: &Path, datasets: &[Dataset], rows: &[Vec<usize>]) -> Result<InputProfile> {
    if PoseEnsemble::is_in(dir) {
        let mut first = None;
        for d in PoseEnsemble::read(dir)?.member_dirs(dir) {
            let p = add_pin_profile(&d, datasets, rows)?;
            first.get_or_insert(p);
        }
        return first.ok_or_else(|| {
            tactile_core::Error::Invalid("an ensemble without members".into()).into()
        });
    }
    if PoseArtifact::is_in(dir) {
        refit::<PoseArtifact>(dir, datasets, rows, |a| {
            (&a.preprocess, &mut a.input_profile)
        })
    } else {
        refit::<CaeArtifact>(dir, datasets, rows, |a| {
            (&a.preprocess, &mut a.input_profile)
        })
    }
}

/// Fit the pin profile of the model `A` in `dir` through its
/// preprocessing and save it in its config atomically (`fields` gives
/// both), under the folder's lock.
fn refit<A: Artifact>(
    dir: &Path,
    datasets: &[Dataset],
    rows: &[Vec<usize>],
    fields: impl Fn(&mut A) -> (&PreprocessConfig, &mut Option<InputProfile>),
) -> Result<InputProfile> {
    // Its config is rewritten: never while another run writes it.
    let _lock = tactile_core::io::FolderLock::of_existing(dir)?;
    let mut a = A::read(dir)?;
    let (cfg, slot) = fields(&mut a);
    let p = pin_profile_of(datasets, rows, cfg)?;
    *slot = Some(p.clone());
    tactile_core::io::write_json_atomic(dir.join(A::CONFIG_FILE), &a)?;
    Ok(p)
}

/// The pin profile of the frames of `datasets` through `cfg`, a chunk at
/// a time (only the spectra are kept), the rows `rows` of each; flat
/// frames are left out.
fn pin_profile_of(
    datasets: &[Dataset],
    rows: &[Vec<usize>],
    cfg: &PreprocessConfig,
) -> Result<InputProfile> {
    let mut spectra = Vec::new();
    for (ds, rows) in datasets.iter().zip(rows) {
        let cfgs = std::slice::from_ref(cfg);
        PinSet::for_each_chunk_of(ds, rows, cfgs, DATASET_CHUNK, |sets| {
            let set = &sets[0];
            let pins: Vec<_> = set
                .images
                .iter()
                .zip(set.flat_mask())
                .filter(|(_, flat)| !flat)
                .map(|(p, _)| p)
                .collect();
            spectra.extend(pin_spectra(&pins));
            Ok::<(), crate::Error>(())
        })?;
    }
    if spectra.len() < InputProfile::MIN_FRAMES {
        let names: Vec<String> = datasets
            .iter()
            .map(|d| d.root.display().to_string())
            .collect();
        return Err(tactile_core::Error::Invalid(format!(
            "{}: {} frames with pins to read{}, and a pin profile needs at least {} to tell their spread; give the model's training data",
            names.join(", "),
            spectra.len(),
            split_words(rows, datasets),
            InputProfile::MIN_FRAMES
        ))
        .into());
    }
    Ok(InputProfile::fit_pins(&spectra, PIN_PROFILE_MARGIN)?)
}

/// " (of 40 rows)" when `rows` leave out some of `datasets`' rows (a
/// split), else nothing.
fn split_words(rows: &[Vec<usize>], datasets: &[Dataset]) -> String {
    let taken: usize = rows.iter().map(Vec::len).sum();
    let all: usize = datasets.iter().map(Dataset::len).sum();
    match taken < all {
        true => format!(" (the split's {taken} of {all} rows)"),
        false => String::new(),
    }
}

/// The preprocessing and the pin profile of the TacTip model in `dir`
/// (an ensemble's first member's); a model without one is refused
/// saying how to give it one.
pub fn model_pin_profile(dir: &Path) -> Result<(PreprocessConfig, InputProfile)> {
    let kind = TactipModelKind::of(dir, "a model without a pin profile")?;
    let (cfg, profile) = match kind {
        TactipModelKind::PoseNetwork => {
            let first = match PoseEnsemble::is_in(dir) {
                true => PoseEnsemble::read(dir)?
                    .member_dirs(dir)
                    .into_iter()
                    .next()
                    .unwrap_or_else(|| dir.to_path_buf()),
                false => dir.to_path_buf(),
            };
            let a = PoseArtifact::read(&first)?;
            (a.preprocess, a.input_profile)
        }
        TactipModelKind::Encoder => {
            let a = CaeArtifact::read(dir)?;
            (a.preprocess, a.input_profile)
        }
    };
    let profile = profile.ok_or_else(|| {
        tactile_core::Error::model(
            dir,
            "has no pin profile (trained before it): add one with `tactile train profile --model DIR --data ITS_TRAINING_DATA`",
        )
    })?;
    Ok((cfg, profile))
}
