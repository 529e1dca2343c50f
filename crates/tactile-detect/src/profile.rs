//! The detector's input profile: the training frames' input statistics,
//! saved in `detector.json`, against which a frame of another sensor is
//! recognised and refused ([`tactile_preprocess::profile`]).

use std::path::Path;

use tactile_burn::Artifact;
use tactile_core::dataset::Dataset;
use tactile_preprocess::profile::{InputProfile, LAYOUT_GRID, descriptor, layout_cells};

use crate::{DetectionSet, DetectorArtifact, Result};

/// How far above the training frames' 99.9th-percentile score the
/// threshold sits: room for renderings and captures that differ within the
/// sensor's specification.
pub const PROFILE_MARGIN: f32 = 1.5;

/// The input profile of every frame of `sets`, as the detector sees them.
pub fn fit_input_profile(sets: &[&DetectionSet]) -> Result<InputProfile> {
    fit(sets
        .iter()
        .flat_map(|s| (0..s.frames.len()).map(move |i| (*s, i))))
}

/// The input profile of the frames `idx` of `set` (a training split).
pub fn fit_input_profile_of(set: &DetectionSet, idx: &[usize]) -> Result<InputProfile> {
    fit(idx.iter().map(|&i| (set, i)))
}

/// The nine statistics of each frame and, on frames at least as large as
/// its grid, the colour layout.
fn fit<'a>(frames: impl Iterator<Item = (&'a DetectionSet, usize)>) -> Result<InputProfile> {
    let (mut descriptors, mut cells) = (Vec::new(), Vec::new());
    let mut layout = true;
    for (s, i) in frames {
        let img = s.image(i);
        descriptors.push(descriptor(&img)?);
        layout &= img.width >= LAYOUT_GRID.0 && img.height >= LAYOUT_GRID.1;
        if layout {
            cells.push(layout_cells(&img, LAYOUT_GRID)?);
        }
    }
    let cells = layout.then_some((cells.as_slice(), LAYOUT_GRID));
    Ok(InputProfile::fit_frames(
        &descriptors,
        cells,
        PROFILE_MARGIN,
    )?)
}

/// Fit the input profile of the detector in `dir` on `datasets` (its
/// training data) and save it in the detector's config, atomically; the
/// weights are not touched. For an ensemble, every member's (the first
/// member's is the one used).
pub fn add_input_profile(dir: &Path, datasets: &[Dataset]) -> Result<InputProfile> {
    if crate::DetectorEnsembleArtifact::is_in(dir) {
        let e = tactile_burn::ensemble::Ensemble::read::<DetectorArtifact>(dir)?;
        let mut first = None;
        for d in e.member_dirs(dir) {
            let p = add_input_profile(&d, datasets)?;
            first.get_or_insert(p);
        }
        return first.ok_or_else(|| {
            tactile_core::Error::Invalid("an ensemble without members".into()).into()
        });
    }
    // Its config is rewritten: never while another run writes it (a lost
    // update of `train calibrate`'s threshold, say).
    let _lock = tactile_core::io::FolderLock::of_existing(dir)?;
    let mut artifact = DetectorArtifact::read(dir)?;
    let sets = datasets
        .iter()
        .map(|d| DetectionSet::from_dataset(d, &artifact.model))
        .collect::<Result<Vec<_>>>()?;
    let profile = fit_input_profile(&sets.iter().collect::<Vec<_>>())?;
    artifact.input_profile = Some(profile.clone());
    tactile_core::io::write_json_atomic(dir.join(DetectorArtifact::CONFIG_FILE), &artifact)?;
    Ok(profile)
}
