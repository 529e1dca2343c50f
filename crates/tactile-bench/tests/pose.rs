#![allow(clippy::unwrap_used)]
//! The edge pose bench on 63 real frames of the 127-pin TacTip edge set
//! (`../shared/real/tactip127-edge`, copied to a temporary folder) with
//! the shipped `models/pose-edge`: a target the frames do not label has no
//! error, rather than an error of zero.

mod common;

use common::root;

use tactile_bench::models::ModelBench;
use tactile_bench::pose::bench_pose;

#[test]
fn a_target_no_frame_labels_gets_no_error_not_zero() {
    let real = root().join("../shared/real/tactip127-edge");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("edge");
    let text = std::fs::read_to_string(real.join("labels.csv")).unwrap();
    let mut lines = text.lines();
    let head = lines.next().unwrap();
    let theta = head.split(',').position(|c| c == "theta_deg").unwrap();
    let mut labels = format!("{head}\n");
    let mut count = 0;
    for l in lines.step_by(60) {
        let mut cells: Vec<&str> = l.split(',').collect();
        let file = cells[0];
        let to = data.join(file);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(real.join(file), to).unwrap();
        cells[theta] = "";
        labels.push_str(&cells.join(","));
        labels.push('\n');
        count += 1;
    }
    common::write_subset(&real, &data, &labels, count);
    let bench = ModelBench {
        models: vec![root().join("models/pose-edge")],
        data,
        select: None,
        extreme: None,
        runs: 1,
    };
    let table = bench_pose(&bench).unwrap();
    let row: Vec<&str> = table
        .markdown
        .lines()
        .find(|l| l.starts_with("| pose-edge (trained on every frame) |"))
        .unwrap()
        .split('|')
        .map(str::trim)
        .collect();
    // x and depth are scored; theta, unlabelled, is not.
    let x: f64 = row[6].parse().unwrap();
    let depth: f64 = row[8].parse().unwrap();
    assert!(x > 0.0 && x < 1.0 && depth > 0.0 && depth < 0.5, "{row:?}");
    assert_eq!(row[7], "-", "{row:?}");
    let mae = table.rows[0].metrics.mae;
    assert!(mae[0].is_finite() && mae[1].is_nan(), "{mae:?}");
}

#[test]
fn a_pose_network_scores_every_frame_of_a_set_it_never_saw() {
    // 38 frames of the edge set, as copied out of it (frames the shipped
    // network, trained on every frame, fitted) and as other frames of the
    // rig would come: other names, other bytes (a corner pixel flipped).
    let real = root().join("../shared/real/tactip127-edge");
    let tmp = tempfile::tempdir().unwrap();
    let (copied, other) = (tmp.path().join("copied"), tmp.path().join("other"));
    let text = std::fs::read_to_string(real.join("labels.csv")).unwrap();
    let mut lines = text.lines();
    let head = lines.next().unwrap();
    let (mut same, mut new) = (format!("{head}\n"), format!("{head}\n"));
    let mut count = 0;
    for d in [&copied, &other] {
        std::fs::create_dir_all(d.join("frames")).unwrap();
    }
    for (k, l) in lines.step_by(100).enumerate() {
        let (file, rest) = l.split_once(',').unwrap();
        std::fs::copy(real.join(file), copied.join(file)).unwrap();
        same.push_str(&format!("{l}\n"));
        let name = format!("frames/rig-b-{k:03}.png");
        let frame = tactile_core::image_io::load_grey(real.join(file)).unwrap();
        let mut pixels = frame.as_slice().to_vec();
        pixels[0] = 255 - pixels[0];
        tactile_core::image_io::save_grey_png(
            other.join(&name),
            frame.width(),
            frame.height(),
            &pixels,
        )
        .unwrap();
        new.push_str(&format!("{name},{rest}\n"));
        count += 1;
    }
    common::write_subset(&real, &copied, &same, count);
    common::write_subset(&real, &other, &new, count);
    let bench = |data: &std::path::Path| {
        bench_pose(&ModelBench {
            models: vec![root().join("models/pose-edge")],
            data: data.to_path_buf(),
            select: None,
            extreme: None,
            runs: 1,
        })
        .unwrap()
    };
    let row = |markdown: &str| -> Vec<String> {
        markdown
            .lines()
            .find(|l| l.starts_with("| pose-edge"))
            .unwrap()
            .split('|')
            .map(|c| c.trim().to_string())
            .collect()
    };
    let (seen, unseen) = (bench(&copied), bench(&other));
    // On its own frames: marked, and scored on the split's test frames.
    let r = row(&seen.markdown);
    assert_eq!(r[1], "pose-edge (trained on every frame)", "{r:?}");
    assert!(seen.rows[0].metrics.saw_test_frames);
    assert!(seen.rows[0].metrics.frames < count, "{r:?}");
    // On frames it never fitted: every frame, unmarked.
    let r = row(&unseen.markdown);
    assert_eq!(r[1], "pose-edge", "{r:?}");
    assert_eq!(unseen.rows[0].metrics.frames, count, "{r:?}");
    assert!(!unseen.rows[0].metrics.saw_test_frames);
    let x: f64 = r[6].parse().unwrap();
    assert!(x > 0.0 && x < 1.0, "{r:?}");
}
