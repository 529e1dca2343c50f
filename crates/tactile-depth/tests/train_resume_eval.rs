#![allow(clippy::unwrap_used)]
//! The depth network's library path on tiny data, without the command
//! line: options -> training (refusing metres) -> resume -> evaluation
//! with heat maps; the photometric augmentation of its training frames.

use serde_json::json;
use tactile_burn::Runtime;
use tactile_burn::options::Options;
use tactile_core::dataset::Dataset;
use tactile_depth::DepthEstimator;
use tactile_depth::DepthOptions;
use tactile_depth::data::DepthSet;
use tactile_depth::eval::{EvalOptions, evaluate_folder, evaluate_in_chunks, predict_mm, score};
use tactile_detect::augment::PhotometricAugment;

fn options(extra: serde_json::Value) -> DepthOptions {
    let mut kw = json!({
        "encoder": "tiny", "input": [64, 32], "decoder_width": 16,
        "max_epochs": 1, "val_fraction": 0.34,
    });
    kw.as_object_mut()
        .unwrap()
        .extend(extra.as_object().unwrap().clone());
    DepthOptions::with_overrides(kw.as_object().unwrap()).unwrap()
}

/// `frames` visuo-tactile frames of 320x180, `per_sequence` to a video,
/// written into `dir` from `seed`.
fn small_set(dir: &std::path::Path, frames: usize, per_sequence: usize, seed: u64) -> Dataset {
    let cfg = datasets_synth::VisuotactileConfig {
        width: 320,
        height: 180,
        frames_per_sequence: per_sequence,
        ..Default::default()
    };
    datasets_synth::write_visuotactile(&cfg, frames, seed, dir, Default::default()).unwrap();
    Dataset::open(dir).unwrap()
}

#[test]
fn depth_trains_in_millimetres_resumes_and_evaluates_with_heat_maps() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("vt");
    let ds = small_set(&data, 18, 6, 8);
    let out = tmp.path().join("depth");

    // Metres: the targets barely vary; refused before training, and why.
    let e = options(json!({ "unit_mm": 1000.0 }))
        .train(&ds, &out)
        .unwrap_err()
        .to_string();
    assert!(e.contains("stall") && e.contains("millimetres"), "{e}");
    assert!(!out.join("depth.bpk").exists());

    let recipe =
        json!({ "loss": "l1-grad-ssim", "head": "custom", "with_mask": true, "augment": true });
    let first = options(recipe.clone()).train(&ds, &out).unwrap();
    assert_eq!(first.epochs_run, 1);
    // The augmentation is in the training record, as trained.
    let record = std::fs::read_to_string(out.join("training.json")).unwrap();
    let record: serde_json::Value = serde_json::from_str(&record).unwrap();
    assert!(
        record["config"]["augment"]["exposure"].as_f64().unwrap() > 0.0,
        "{record}"
    );
    let mut more = recipe.clone();
    more.as_object_mut().unwrap().extend(
        json!({ "max_epochs": 2, "resume": true })
            .as_object()
            .unwrap()
            .clone(),
    );
    let resumed = options(more).train(&ds, &out).unwrap();
    assert_eq!(resumed.epochs_run, 2, "resume continues the run");

    let png = tmp.path().join("png");
    let o = EvalOptions {
        save_png: Some(png.clone()),
        png_frames: 2,
    };
    let e = evaluate_folder(&out, &data, Runtime::BurnFlex, &o).unwrap();
    assert_eq!(e.scores.frames, ds.len());
    assert!(e.scores.mae_mm.is_finite() && e.scores.mae_mm >= 0.0);
    assert!((-1.0..=1.0).contains(&e.scores.ssim));
    assert_eq!(e.heat_maps, 2);
    assert!(png.join("depth-000.png").is_file() && png.join("depth-001.png").is_file());
    // Read a few rows at a time (as a large dataset is), the scores are
    // those of the whole set at once.
    let mut est = DepthEstimator::load(&out, Runtime::BurnFlex, 0).unwrap();
    let whole =
        DepthSet::from_dataset(&ds, &(0..ds.len()).collect::<Vec<_>>(), [64, 32], None).unwrap();
    let preds = predict_mm(&mut est, &whole).unwrap();
    let (chunked, _, undecodable) = evaluate_in_chunks(&mut est, &ds, 5).unwrap();
    assert_eq!(undecodable, None);
    assert_eq!(chunked, score(&whole, &preds));
    assert_eq!(chunked, e.scores);
    // A folder that already holds files is left alone, before any work.
    let e = evaluate_folder(&out, &data, Runtime::BurnFlex, &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("already holds files"), "{e}");
    assert_eq!(std::fs::read_dir(&png).unwrap().count(), 2);
    // Heat maps over the dataset's own frames are refused, naming it.
    let before = std::fs::read_dir(data.join("frames")).unwrap().count();
    let inside = EvalOptions {
        save_png: Some(data.join("frames")),
        png_frames: 1,
    };
    let e = evaluate_folder(&out, &data, Runtime::BurnFlex, &inside)
        .unwrap_err()
        .to_string();
    assert!(e.contains("frames"), "{e}");
    assert_eq!(
        std::fs::read_dir(data.join("frames")).unwrap().count(),
        before
    );
    // A folder for heat maps and none of them: refused, no folder made.
    let none = EvalOptions {
        save_png: Some(tmp.path().join("none")),
        png_frames: 0,
    };
    let e = evaluate_folder(&out, &data, Runtime::BurnFlex, &none)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("png_frames: must be 1 to 10000 heat maps"),
        "{e}"
    );
    assert!(!tmp.path().join("none").exists());
    // A count of heat maps with no folder for them would be ignored:
    // refused (before, the scores came back and no map was written).
    let nowhere = EvalOptions {
        save_png: None,
        png_frames: 3,
    };
    let e = evaluate_folder(&out, &data, Runtime::BurnFlex, &nowhere)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("png_frames 3: the heat maps save_png writes, and no save_png folder is given"),
        "{e}"
    );
}

/// `--augment` changes what the network sees of a frame's colours, drawn
/// again each round, and nothing of its fourth channel or its targets (the
/// mask, or the calibration's reconstruction of the frame as recorded).
#[test]
fn augmentation_changes_the_colours_alone_and_is_drawn_again_each_round() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = small_set(&tmp.path().join("vt"), 3, 3, 3);
    let set = DepthSet::from_dataset(&ds, &[0, 1, 2], [64, 32], None).unwrap();
    let o = options(json!({ "with_mask": true, "augment": true }));
    let config = o.config();
    let a = config.augment.clone().unwrap();
    assert_eq!(a, PhotometricAugment::new());
    assert!(options(json!({})).config().augment.is_none());
    let mut model = config.model.clone();
    model.in_channels = 4;
    let images: Vec<_> = (0..set.len()).map(|i| set.image(i)).collect();
    let stats = tactile_preprocess::visuo::ChannelStats::from_images(images.iter()).unwrap();
    let scale = tactile_depth::DepthScale {
        offset_mm: 0.0,
        unit_mm: 1.0,
    };
    let dev = tactile_burn::DeviceKind::Flex.device();
    let idx = [0, 1, 2];
    let values = |t: burn::tensor::Tensor<4>| t.into_data().try_to_vec::<f32>().unwrap();
    let (x, y) = set.batch(&idx, &stats, &scale, &model, &dev).unwrap();
    let (x, y) = (values(x), values(y));
    let augmented = |round| {
        let (x, y) = set
            .augmented_batch(&idx, &stats, &scale, &model, (&a, (7, round)), &dev)
            .unwrap();
        (values(x), values(y))
    };
    let (x1, y1) = augmented(1);
    let hw = 64 * 32;
    let per_frame =
        |x: &[f32], f: usize, c: usize| x[(f * 4 + c) * hw..(f * 4 + c + 1) * hw].to_vec();
    for f in 0..idx.len() {
        let moved = per_frame(&x, f, 0)
            .iter()
            .zip(per_frame(&x1, f, 0))
            .map(|(a, b)| (a - b).abs())
            .fold(0f32, f32::max);
        assert!(moved > 1e-3, "frame {f}: colours unchanged ({moved})");
        assert_eq!(
            per_frame(&x, f, 3),
            per_frame(&x1, f, 3),
            "frame {f}: mask changed"
        );
    }
    assert_eq!(y, y1, "targets changed");
    assert_eq!(augmented(1), (x1.clone(), y1), "the same draw twice");
    assert_ne!(augmented(2).0, x1, "another round, another draw");
}
