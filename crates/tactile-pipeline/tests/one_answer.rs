#![allow(clippy::unwrap_used)]
//! One answer per frame: `tactile eval detector` (the library's
//! `evaluate`), `tactile run` (the pipeline, which the Python package
//! wraps) and the standalone ONNX export give the same decision and the
//! same gate to the same 202 frames, blank, foreign and grey ones included.

use std::path::{Path, PathBuf};

use tactile_burn::Runtime;
use tactile_core::image_io::RgbImage;
use tactile_detect::{DetectionSet, Gate, TendonDetector};
use tactile_pipeline::Pipeline;

mod common;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn rgb(w: usize, h: usize, f: impl Fn(usize, usize, usize) -> u8) -> RgbImage {
    let data: Vec<u8> = (0..w * h * 3)
        .map(|i| f(i / 3 % w, i / 3 / w, i % 3))
        .collect();
    tactile_core::image_io::rgb_image(w, h, data).unwrap()
}

/// Rendered palpation frames (seeded sequences of the virtual sensor,
/// every other one darker or brighter), the sample palpation video, blank
/// frames (black, saturated, one colour) and frames of other kinds (a
/// virtual TacTip frame, stripes, noise) and grey copies of two colour
/// frames: 202 in all.
fn frames() -> Vec<(String, RgbImage)> {
    let cfg = datasets_synth::VisuotactileConfig {
        width: 320,
        height: 180,
        ..Default::default()
    };
    let fps = cfg.frames_per_sequence;
    let mut rendered: Vec<(String, RgbImage)> = (0..182)
        .map(|i| {
            let (seq, f) = (i / fps, i % fps);
            let (_, frame) = datasets_synth::visuotactile::sample(&cfg, 31, seq as u64, f);
            let gain = [1.0, 0.8, 1.15][seq % 3];
            let data = frame
                .rgb
                .iter()
                .map(|&v| (v as f32 * gain).round().min(255.0) as u8)
                .collect();
            let img = tactile_core::image_io::rgb_image(frame.width, frame.height, data).unwrap();
            (format!("rendered {seq}/{f}"), img)
        })
        .collect();
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
    // Grey copies of colour frames (a camera in a mono mode, a bag of
    // mono8 Images): their statistics stay near the colour frames', but
    // the colour the models read is gone.
    let colour = [v[6].clone(), rendered[3 * fps + 4].clone()];
    assert_eq!(
        [&*colour[0].0, &*colour[1].0],
        ["palpation 6", "rendered 3/4"]
    );
    for (name, frame) in colour {
        use tactile_core::image_io::{grey_to_rgb, rgb_to_grey};
        let grey = grey_to_rgb(&rgb_to_grey(frame.as_slice()));
        let grey = tactile_core::image_io::rgb_image(frame.width(), frame.height(), grey).unwrap();
        v.push((format!("grey {name}"), grey));
    }
    rendered.extend(v);
    assert_eq!(rendered.len(), 202);
    rendered
}

#[test]
fn eval_and_run_give_every_frame_the_same_answer() {
    let models = root().join("models");
    let mut det = TendonDetector::load(models.join("detector"), Runtime::BurnFlex, 0).unwrap();
    let frames = frames();
    // The evaluation's set: each frame as the detector holds a dataset's
    // frame (resized to its input, in its bits), labelled "no tendon".
    let [width, height] = det.artifact.model.input_size;
    let n = frames.len();
    let set = DetectionSet {
        width,
        height,
        detector: det.artifact.model.clone(),
        files: frames.iter().map(|(name, _)| name.clone()).collect(),
        frames: frames
            .iter()
            .map(|(_, f)| det.artifact.model.frame_levels(f).unwrap())
            .collect(),
        tendon: vec![false; n],
        transition: vec![false; n],
        ridge_mm: vec![None; n],
    };
    let scores = tactile_detect::evaluate(&mut det, &set).unwrap();
    let mut pipe = Pipeline::load(&models, Runtime::BurnFlex, 0).unwrap();
    // The standalone model on every frame's levels at once.
    let alone = common::run_standalone(
        &models.join("detector"),
        &det.artifact.model,
        set.frames.concat(),
        n,
    );
    let output = |name: &str| alone.get(name);
    let (alone_p, alone_gate, alone_tendon, alone_score) = (
        output("tendon_probability"),
        output("gate"),
        output("tendon"),
        output("input_score"),
    );
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
        // The standalone graph: the same gate, decision and probability.
        assert_eq!(
            alone_gate[i],
            common::gate_code(rec.gate),
            "{name}: standalone gate"
        );
        assert_eq!(
            alone_tendon[i] == 1.0,
            rec.tendon_raw,
            "{name}: standalone decision"
        );
        assert!(
            (alone_p[i] - rec.score).abs() < 1e-4,
            "{name}: standalone probability {} vs {}",
            alone_p[i],
            rec.score
        );
        if let Some(s) = rec.input_score {
            assert!(
                (alone_score[i] - s).abs() <= 1e-3 * s.max(1.0),
                "{name}: standalone input score {} vs {s}",
                alone_score[i]
            );
        }
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
    // The blank frames are stopped, and every frame of another kind is,
    // grey copies of the sensor's own frames among them.
    assert_eq!(gates.iter().sum::<usize>(), 8, "gates {gates:?}");
    assert_eq!(scores.gated_blank + scores.gated_foreign, 8);
    for (i, (name, _)) in frames.iter().enumerate().skip(200) {
        assert_eq!(alone_gate[i], 2.0, "{name}: foreign");
    }
    // The rendered and sample videos pass through the network (their
    // tendon frames say so).
    assert!(scores.decisions[..194].iter().filter(|&&d| d).count() > 20);
}
