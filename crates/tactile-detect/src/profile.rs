//! The detector's input profile: the training frames' input statistics,
//! saved in `detector.json`, against which a frame of another sensor is
//! recognised and refused ([`tactile_preprocess::profile`]).

use std::path::Path;

use tactile_burn::Artifact;
use tactile_core::dataset::Dataset;
use tactile_preprocess::profile::{InputProfile, LAYOUT_GRID, descriptor, is_grey, layout_cells};

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
/// its grid, the colour layout; grey frames when most of them are grey.
fn fit<'a>(frames: impl Iterator<Item = (&'a DetectionSet, usize)>) -> Result<InputProfile> {
    let (mut descriptors, mut cells) = (Vec::new(), Vec::new());
    let (mut layout, mut grey) = (true, 0usize);
    for (s, i) in frames {
        let img = s.image(i);
        descriptors.push(descriptor(&img)?);
        grey += usize::from(is_grey(&img));
        layout &= img.width >= LAYOUT_GRID.0 && img.height >= LAYOUT_GRID.1;
        if layout {
            cells.push(layout_cells(&img, LAYOUT_GRID)?);
        }
    }
    let cells = layout.then_some((cells.as_slice(), LAYOUT_GRID));
    let mut profile = InputProfile::fit_frames(&descriptors, cells, PROFILE_MARGIN)?;
    profile.grey_frames = 2 * grey > descriptors.len();
    Ok(profile)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::DetectorConfig;
    use tactile_core::image_io::{grey_to_rgb, rgb_to_grey};

    /// `n` 80 x 60 frames (8-bit levels) of the virtual sensor, in colour
    /// or each made grey.
    fn set(n: usize, grey: bool) -> DetectionSet {
        let detector = DetectorConfig::new().with_input_size([80, 60]);
        let cfg = datasets_synth::VisuotactileConfig {
            width: 80,
            height: 60,
            ..Default::default()
        };
        let frames = (0..n)
            .map(|i| {
                let (_, f) = datasets_synth::visuotactile::sample(&cfg, 5, i as u64, 3);
                let rgb = match grey {
                    true => grey_to_rgb(&rgb_to_grey(&f.rgb)),
                    false => f.rgb,
                };
                rgb.into_iter().map(u16::from).collect()
            })
            .collect();
        DetectionSet {
            width: 80,
            height: 60,
            detector,
            files: (0..n).map(|i| format!("{i}")).collect(),
            frames,
            tendon: vec![false; n],
            transition: vec![false; n],
            ridge_mm: vec![None; n],
        }
    }

    /// A detector trained on a mono camera's frames keeps them: its
    /// profile says so, and a colour frame is the other mode to it; one
    /// trained in colour tells a grey frame.
    #[test]
    fn the_profile_keeps_the_training_frames_camera_mode() {
        let (colour, grey) = (set(24, false), set(24, true));
        let of_colour = fit_input_profile(&[&colour]).unwrap();
        let of_grey = fit_input_profile(&[&grey]).unwrap();
        assert!(!of_colour.grey_frames && of_grey.grey_frames);
        assert!(of_colour.other_camera_mode(&grey.image(0)));
        assert!(!of_colour.other_camera_mode(&colour.image(0)));
        assert!(of_grey.other_camera_mode(&colour.image(0)));
        assert!(!of_grey.other_camera_mode(&grey.image(0)));
    }
}
