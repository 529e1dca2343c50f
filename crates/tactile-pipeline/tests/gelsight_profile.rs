#![allow(clippy::unwrap_used)]
//! The calibrated GelSight's input profile on real frames: its own ball
//! presses pass, the same presses as another unit would show them (LEDs in
//! another order, a darker and flatter gel) are foreign, and the
//! standalone ONNX export scores and gates every frame as the toolkit does
//! (the colour layout's statistics included).

use std::path::{Path, PathBuf};

use tactile_burn::Runtime;
use tactile_core::image_io::{RgbImage, load_rgb, rgb_image};
use tactile_detect::{Gate, TendonDetector};

mod common;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn recolour(f: &RgbImage, map: impl Fn([u8; 3]) -> [u8; 3]) -> RgbImage {
    let data: Vec<u8> = f
        .as_slice()
        .chunks_exact(3)
        .flat_map(|p| map([p[0], p[1], p[2]]))
        .collect();
    rgb_image(f.width(), f.height(), data).unwrap()
}

#[test]
fn real_presses_pass_other_units_are_foreign_and_the_export_agrees() {
    let dir = root().join("models/gelsight-r15/detector");
    let mut det = TendonDetector::load(&dir, Runtime::BurnFlex, 0).unwrap();
    let profile = det.artifact.input_profile.clone().unwrap();
    assert!(profile.layout.is_some(), "the shipped profile has a layout");
    let frames_dir = root().join("../shared/real/gelsight-ball/frames");
    let mut presses: Vec<PathBuf> = std::fs::read_dir(&frames_dir)
        .unwrap_or_else(|e| panic!("{}: {e}", frames_dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    presses.sort();
    let own: Vec<RgbImage> = presses
        .iter()
        .step_by(4)
        .map(|p| load_rgb(p).unwrap())
        .collect();
    assert!(own.len() >= 6);
    let mut frames: Vec<(String, bool, RgbImage)> = Vec::new();
    for (i, f) in own.iter().enumerate() {
        frames.push((format!("press {i}"), false, f.clone()));
        frames.push((
            format!("press {i}, LEDs rotated"),
            true,
            recolour(f, |[r, g, b]| [g, b, r]),
        ));
        frames.push((
            format!("press {i}, flatter gel"),
            true,
            recolour(f, |p| p.map(|v| (v as f32 * 0.5 + 40.0) as u8)),
        ));
    }
    let model = &det.artifact.model;
    let levels: Vec<u16> = frames
        .iter()
        .flat_map(|(_, _, f)| model.frame_levels(f).unwrap())
        .collect();
    let alone = common::run_standalone(&dir, model, levels, frames.len());
    let (gates, scores) = (alone.get("gate"), alone.get("input_score"));
    for (i, (name, foreign, frame)) in frames.iter().enumerate() {
        let a = det.assess(frame).unwrap();
        assert_eq!(
            a.gate == Some(Gate::Foreign),
            *foreign,
            "{name}: input score {:?}, threshold {}",
            a.input_score,
            profile.threshold
        );
        let s = a.input_score.unwrap();
        assert!(
            (scores[i] - s).abs() <= 1e-3 * s.max(1.0),
            "{name}: standalone input score {} vs {s}",
            scores[i]
        );
        assert_eq!(
            gates[i],
            common::gate_code(a.gate),
            "{name}: standalone gate"
        );
    }
}
