#![allow(clippy::unwrap_used)]
//! One answer per frame: `tactile eval detector` (the library's
//! `evaluate`) and `tactile run` (the pipeline) give the same decision and
//! the same gate to the same frames, blank and foreign ones included.

use std::path::{Path, PathBuf};

use tactile_burn::Runtime;
use tactile_core::image_io::RgbImage;
use tactile_detect::{DetectionSet, Gate, TendonDetector};
use tactile_pipeline::Pipeline;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn rgb(w: usize, h: usize, f: impl Fn(usize, usize, usize) -> u8) -> RgbImage {
    let data: Vec<u8> = (0..w * h * 3)
        .map(|i| f(i / 3 % w, i / 3 / w, i % 3))
        .collect();
    tactile_core::image_io::rgb_image(w, h, data).unwrap()
}

/// The sample palpation video, blank frames (black, saturated, one colour)
/// and frames of other kinds (a virtual TacTip frame, stripes, noise).
fn frames() -> Vec<(String, RgbImage)> {
    let mut v: Vec<(String, RgbImage)> = (0..12)
        .map(|i| {
            let p = root().join(format!("samples/palpation/{i:06}.png"));
            (
                format!("palpation {i}"),
                tactile_core::image_io::load_rgb(p).unwrap(),
            )
        })
        .collect();
    v.push(("black".into(), rgb(320, 180, |_, _, _| 0)));
    v.push(("white".into(), rgb(320, 180, |_, _, _| 255)));
    v.push((
        "green".into(),
        rgb(320, 180, |_, _, c| if c == 1 { 200 } else { 30 }),
    ));
    v.push((
        "stripes".into(),
        rgb(320, 180, |x, _, _| if (x / 8) % 2 == 0 { 240 } else { 20 }),
    ));
    v.push((
        "noise".into(),
        rgb(320, 180, |x, y, c| {
            ((x * 7919 + y * 104729 + c * 31) % 251) as u8
        }),
    ));
    let tactip = std::fs::read_dir(root().join("samples/virtual-tactip/frames"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .min()
        .unwrap();
    v.push((
        "virtual TacTip".into(),
        tactile_core::image_io::load_rgb(tactip).unwrap(),
    ));
    v
}

#[test]
fn eval_and_run_give_every_frame_the_same_answer() {
    let models = root().join("models");
    let mut det = TendonDetector::load(models.join("detector"), Runtime::BurnFlex, 0).unwrap();
    let frames = frames();
    // The evaluation's set: each frame as the detector holds a dataset's
    // frame (resized to its input, in its bits), labelled "no tendon".
    let bits = det.artifact.model.bits();
    let [width, height] = det.artifact.model.input_size;
    let n = frames.len();
    let set = DetectionSet {
        width,
        height,
        detector: det.artifact.model.clone(),
        files: frames.iter().map(|(name, _)| name.clone()).collect(),
        frames: frames
            .iter()
            .map(|(_, f)| det.artifact.frame_image(f).unwrap().to_levels(bits))
            .collect(),
        tendon: vec![false; n],
        transition: vec![false; n],
        ridge_mm: vec![None; n],
    };
    let scores = tactile_detect::evaluate(&mut det, &set).unwrap();
    let mut pipe = Pipeline::load(&models, Runtime::BurnFlex, 0).unwrap();
    let mut gates = [0usize; 2];
    for (i, (name, frame)) in frames.iter().enumerate() {
        let rec = pipe.process(name, frame).unwrap();
        let assessed = det.assess(frame).unwrap();
        assert_eq!(rec.tendon_raw, scores.decisions[i], "{name}: run vs eval");
        assert_eq!(
            assessed.tendon, scores.decisions[i],
            "{name}: assess vs eval"
        );
        assert_eq!(rec.gate, assessed.gate, "{name}: gates");
        assert!(
            (rec.score - scores.probabilities[i]).abs() < 1e-5,
            "{name}: probability {} vs {}",
            rec.score,
            scores.probabilities[i]
        );
        match rec.gate {
            Some(Gate::Blank) => gates[0] += 1,
            Some(Gate::Foreign) => gates[1] += 1,
            None => {}
        }
        if rec.gate.is_some() {
            assert!(
                !rec.tendon && rec.score == 0.0,
                "{name}: a gated frame says tendon"
            );
        }
    }
    // The blank frames are stopped, and every frame of another kind is.
    assert_eq!(gates.iter().sum::<usize>(), 6, "gates {gates:?}");
    assert_eq!(scores.gated_blank + scores.gated_foreign, 6);
    // The sample video passes through the network (its tendon frames say so).
    assert!(scores.decisions[..12].iter().any(|&d| d));
}
