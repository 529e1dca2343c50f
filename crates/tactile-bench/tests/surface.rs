#![allow(clippy::unwrap_used)]
//! The surface bench on 150 real `val` frames of the 331-pin TacTip
//! (`../shared/real/tactip331-surface`, copied to a temporary folder) with
//! the shipped `models/pose-surface`: the gain table says what the estimates
//! follow of each target by tap depth, and the shallow taps' twist, where
//! the skin slips on the surface, is followed least; an encoder's row
//! counts every member of its estimator.

mod common;

use std::path::Path;

use common::root;

use tactile_bench::models::ModelBench;
use tactile_bench::surface::bench_surface;

/// `from` and everything under it copied into a new `to`.
fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let dest = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_tree(&p, &dest);
        } else {
            std::fs::copy(&p, dest).unwrap();
        }
    }
}

/// Every `step`-th `val` row of the real set (its rows run by tap depth, so
/// the subset spans every depth); the number of `val` rows.
fn val_subset(dir: &Path, step: usize) -> usize {
    subset(dir, step, None)
}

/// Every `val_step`-th `val` row and every `train_step`-th `train` row;
/// the number of `val` rows.
fn subset(dir: &Path, val_step: usize, train_step: Option<usize>) -> usize {
    let real = root().join("../shared/real/tactip331-surface");
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    let text = std::fs::read_to_string(real.join("labels.csv")).unwrap();
    let mut lines = text.lines();
    let mut labels = format!("{}\n", lines.next().unwrap());
    let (mut n, mut count) = (0, 0);
    for (split, step) in [("val", Some(val_step)), ("train", train_step)] {
        let Some(step) = step else { continue };
        let rows = lines.clone().filter(|l| l.ends_with(&format!(",{split}")));
        for (k, l) in rows.enumerate() {
            if k % step == 0 {
                let file = l.split(',').next().unwrap();
                std::fs::copy(real.join(file), dir.join(file)).unwrap();
                labels.push_str(l);
                labels.push('\n');
                n += usize::from(split == "val");
                count += 1;
            }
        }
    }
    common::write_subset(&real, dir, &labels, count);
    n
}

/// The six target cells of `model`'s row for `third` in the table after
/// the heading that starts with `table`.
fn third_cells(markdown: &str, table: &str, model: &str, third: &str) -> Vec<f64> {
    let table = markdown.split(table).nth(1).unwrap();
    let row = table
        .lines()
        .find(|l| l.starts_with(&format!("| {model} | {third} |")))
        .unwrap();
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    cells[5..11].iter().map(|c| c.parse().unwrap()).collect()
}

/// The cells of the gain table's row for `third` (six targets).
fn gains(markdown: &str, third: &str) -> Vec<f64> {
    third_cells(markdown, "Gain by tap depth", "pose-surface", third)
}

#[test]
fn the_gain_table_shows_where_slide_and_twist_are_in_the_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("val");
    assert_eq!(val_subset(&data, 13), 154);
    let bench = ModelBench {
        models: vec![root().join("models/pose-surface")],
        data,
        select: None,
        extreme: None,
        runs: 1,
    };
    let table = bench_surface(&bench, None).unwrap();
    let (shallow, deep) = (
        gains(&table.markdown, "shallowest"),
        gains(&table.markdown, "deepest"),
    );
    // Deep taps: every estimate follows its truth.
    assert!(deep.iter().all(|g| (0.85..1.15).contains(g)), "{deep:?}");
    // Shallow taps: depth, roll and pitch still do; twist least of all.
    assert!(
        shallow[..3].iter().all(|g| (0.85..1.15).contains(g)),
        "{shallow:?}"
    );
    assert!(
        shallow[5] < 0.7 && shallow[5] < shallow[3].min(shallow[4]),
        "{shallow:?}"
    );
}

#[test]
fn the_depth_table_sets_every_error_beside_an_estimate_that_reads_no_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("set");
    assert_eq!(subset(&data, 40, Some(100)), 50);
    let bench = ModelBench {
        models: vec![
            root().join("models/pose-surface"),
            root().join("models/cae-surface-train"),
        ],
        data: data.clone(),
        select: None,
        extreme: None,
        runs: 1,
    };
    let out = tmp.path().join("table.md");
    let table = bench_surface(&bench, Some(&out)).unwrap();
    // The first model's error against depth, relative to reading no frame:
    // a picture of the page, drawn with it (under its lock), not before.
    assert!(table.markdown.contains("](table-by-depth.png)"));
    assert!(!tmp.path().join("table-by-depth.png").exists());
    table.write(&out).unwrap();
    assert!(
        tmp.path()
            .join("table-by-depth.png")
            .metadata()
            .unwrap()
            .len()
            > 10_000
    );
    let md = &table.markdown;
    let errors = |model: &str, third: &str| third_cells(md, "Errors by tap depth", model, third);
    let none = "`train` median (reads no frame)";
    // The reference's twist cell on the deepest third, recomputed here:
    // the median twist of the 60 `train` rows as every estimate.
    let ds = tactile_core::dataset::Dataset::open(&data).unwrap();
    let twist = |split: &str| -> Vec<(f64, f64)> {
        ds.split_indices(split)
            .unwrap()
            .iter()
            .map(|&i| {
                let n = |c: &str| ds.number_opt(i, c).unwrap().unwrap();
                (n("depth_mm"), n("shear_theta_deg"))
            })
            .collect()
    };
    let train: Vec<f64> = twist("train").iter().map(|r| r.1).collect();
    assert_eq!(train.len(), 60);
    let median = tactile_core::metrics::median(&train);
    let mut val = twist("val");
    val.sort_by(|a, b| a.0.total_cmp(&b.0));
    let deepest = &val[34..];
    let expected = deepest.iter().map(|r| (r.1 - median).abs()).sum::<f64>() / 16.0;
    assert!((errors(none, "deepest")[5] - expected).abs() < 0.0005);
    // Where the skin grips, the model is far below reading no frame on
    // every target; on the shallowest taps, roll and pitch still are.
    let (model, floor) = (errors("pose-surface", "deepest"), errors(none, "deepest"));
    assert!(
        model.iter().zip(&floor).all(|(m, f)| m < &(0.5 * f)),
        "{model:?} {floor:?}"
    );
    let (model, floor) = (
        errors("pose-surface", "shallowest"),
        errors(none, "shallowest"),
    );
    assert!(
        model[1] < 0.3 * floor[1] && model[2] < 0.3 * floor[2],
        "{model:?} {floor:?}"
    );
    // The fitted frames' table has the reference too.
    assert!(
        md.lines()
            .any(|l| l.starts_with(&format!("| {none} | 60 |")))
    );
    // The intervals by depth: only the model that never fitted these
    // frames, its twist deviation widest where the skin slips.
    let intervals = md.split("Intervals by tap depth").nth(1).unwrap();
    let intervals = intervals.split("Error agreement").next().unwrap();
    assert!(!intervals.contains("| pose-surface |"));
    let twist_std = |third: &str| -> f64 {
        let row = intervals
            .lines()
            .find(|l| l.starts_with(&format!("| cae-surface-train | {third} |")))
            .unwrap();
        let cell = row.split('|').nth(10).unwrap();
        cell.split(['(', ')']).nth(1).unwrap().parse().unwrap()
    };
    let (shallow, deep) = (twist_std("shallowest"), twist_std("deepest"));
    assert!(shallow > 2.0 * deep && deep > 0.0, "{shallow} {deep}");
}

#[test]
fn an_encoder_row_counts_every_member_of_its_estimator() {
    // models/cae-surface-train's estimator averages five MLPs: its row in
    // the table counts all of them beside the encoder, four more than the
    // same encoder with its first member alone, whose estimates differ.
    let shipped = root().join("models/cae-surface-train");
    let tmp = tempfile::tempdir().unwrap();
    let single = tmp.path().join("one-mlp");
    std::fs::create_dir_all(single.join("pose")).unwrap();
    for f in ["cae.json", "cae.bpk"] {
        std::fs::copy(shipped.join(f), single.join(f)).unwrap();
    }
    for f in ["regressor.json", "regressor.bpk"] {
        std::fs::copy(
            shipped.join("pose/member-0").join(f),
            single.join("pose").join(f),
        )
        .unwrap();
    }
    let data = tmp.path().join("val");
    assert_eq!(val_subset(&data, 100), 20);
    let bench = ModelBench {
        models: vec![shipped, single],
        data,
        select: None,
        extreme: None,
        runs: 1,
    };
    let table = bench_surface(&bench, None).unwrap();
    let row = |name: &str| -> Vec<String> {
        let l = table
            .markdown
            .lines()
            .find(|l| l.starts_with(&format!("| {name} |")))
            .unwrap();
        l.split('|').map(|c| c.trim().to_string()).collect()
    };
    let (five, one) = (row("cae-surface-train"), row("one-mlp"));
    let params = |r: &[String]| r[4].parse::<usize>().unwrap();
    let hidden: Vec<_> = [512, 256, 128]
        .into_iter()
        .map(|w| (w, tactile_estimate::Activation::Relu))
        .collect();
    // Six estimates and their six log scales.
    let member = tactile_estimate::mlp::parameters(32, &hidden, 12) as usize;
    assert_eq!(params(&five), params(&one) + 4 * member, "{five:?} {one:?}");
    assert_eq!(five[2], "encoder + estimators");
    assert_ne!(five[5..11], one[5..11]);
    // Its deviations were calibrated on the authors' `val`, so its
    // coverage is the cross-fitted one; the lone member's, calibrated on
    // its early-stopping rows, is measured on these frames.
    assert!(five[12].ends_with("cross-fitted"), "{five:?}");
    assert!(
        one[12].contains('%') && !one[12].contains("cross"),
        "{one:?}"
    );
    // The lone member errs much as the five do, frame by frame: its row of
    // the error agreement table (correlation with the first model's errors).
    let agreement = table
        .markdown
        .split("Error agreement with `cae-surface-train`")
        .nth(1)
        .unwrap();
    let rho: Vec<f64> = agreement
        .lines()
        .find(|l| l.starts_with("| one-mlp | all |"))
        .unwrap()
        .split('|')
        .skip(3)
        .take(6)
        .map(|c| c.trim().parse().unwrap())
        .collect();
    assert!(rho.iter().all(|r| (0.6..=1.0).contains(r)), "{rho:?}");
    let json = table.rows[1].metrics.error_correlation.as_ref().unwrap();
    assert!(json.iter().zip(&rho).all(|(j, r)| (j - r).abs() <= 0.005));
    assert!(table.rows[0].metrics.error_correlation.is_none());
}

#[test]
fn frames_no_model_fitted_are_scored_as_unseen_and_unlabelled_ones_are_refused() {
    // The same 20 `val` frames three times: as copied out of the real set
    // (frames every shipped model of `every_split` fitted, and on which
    // cae-surface-train's deviations were calibrated), copied under other
    // names (still those frames), and as other frames of the same rig would
    // come: other names, other bytes (a corner pixel outside the skin
    // flipped).
    let tmp = tempfile::tempdir().unwrap();
    let (copied, renamed, other) = (
        tmp.path().join("copied"),
        tmp.path().join("renamed"),
        tmp.path().join("other"),
    );
    assert_eq!(val_subset(&copied, 100), 20);
    let text = std::fs::read_to_string(copied.join("labels.csv")).unwrap();
    for (dir, flip) in [(&renamed, false), (&other, true)] {
        std::fs::create_dir_all(dir.join("frames")).unwrap();
        std::fs::copy(copied.join("manifest.json"), dir.join("manifest.json")).unwrap();
        let mut labels = String::new();
        for (k, l) in text.lines().enumerate() {
            if k == 0 {
                labels.push_str(l);
            } else {
                let (file, rest) = l.split_once(',').unwrap();
                let name = format!("frames/rig-b-{k:04}.png");
                if flip {
                    let frame = tactile_core::image_io::load_grey(copied.join(file)).unwrap();
                    let (w, h) = (frame.width(), frame.height());
                    let mut pixels = frame.as_slice().to_vec();
                    pixels[0] = 255 - pixels[0];
                    tactile_core::image_io::save_grey_png(dir.join(&name), w, h, &pixels).unwrap();
                } else {
                    std::fs::copy(copied.join(file), dir.join(&name)).unwrap();
                }
                labels.push_str(&format!("{name},{rest}"));
            }
            labels.push('\n');
        }
        std::fs::write(dir.join("labels.csv"), &labels).unwrap();
    }
    let bench = |data: &Path| ModelBench {
        models: vec![
            root().join("models/pose-surface"),
            root().join("models/cae-surface-train"),
        ],
        data: data.to_path_buf(),
        select: None,
        extreme: None,
        runs: 1,
    };
    let row = |markdown: &str, name: &str| -> Vec<String> {
        let l = markdown
            .lines()
            .find(|l| l.starts_with(&format!("| {name}")))
            .unwrap();
        l.split('|').map(|c| c.trim().to_string()).collect()
    };
    let seen = bench_surface(&bench(&copied), None).unwrap();
    let unseen = bench_surface(&bench(&other), None).unwrap();
    assert_eq!(
        row(&seen.markdown, "pose-surface")[1],
        "pose-surface (trained on these frames)"
    );
    // Renamed copies are the frames it fitted and calibrated on.
    let seen_renamed = bench_surface(&bench(&renamed), None).unwrap();
    assert_eq!(
        row(&seen_renamed.markdown, "pose-surface")[1],
        "pose-surface (trained on these frames)"
    );
    assert!(
        row(&seen_renamed.markdown, "cae-surface-train")[12].ends_with("cross-fitted"),
        "{}",
        seen_renamed.markdown
    );
    assert_eq!(row(&unseen.markdown, "pose-surface")[1], "pose-surface");
    assert!(seen.rows[0].metrics.saw_scored_frames && !unseen.rows[0].metrics.saw_scored_frames);
    // Calibrated on these very frames, the coverage is the cross-fitted one
    // of its note; on other frames it is measured, and so it differs.
    let (a, b) = (
        row(&seen.markdown, "cae-surface-train"),
        row(&unseen.markdown, "cae-surface-train"),
    );
    assert!(a[12].ends_with("cross-fitted"), "{a:?}");
    assert!(
        b[12].contains('%') && !b[12].contains("cross") && b[12] != a[12],
        "{b:?}"
    );
    // The errors are the same frames' either way.
    assert_eq!(a[5..11], b[5..11]);
    // Calibrated on a dataset that has since moved (its note names a
    // folder that is not there): the scored frames may be the
    // calibration's, so the cross-fitted coverage stands, not one that
    // would be 68.3 % by construction.
    let moved = tmp.path().join("cae-surface-moved");
    copy_tree(&root().join("models/cae-surface-train"), &moved);
    let note = moved.join("pose/ensemble.json");
    let recorded = "\"../shared/real/tactip331-surface\"";
    let text = std::fs::read_to_string(&note).unwrap();
    assert!(text.contains(recorded), "{text}");
    std::fs::write(
        &note,
        text.replace(recorded, "\"moved-away/tactip331-surface\""),
    )
    .unwrap();
    let moved_bench = ModelBench {
        models: vec![moved],
        ..bench(&other)
    };
    let m = row(
        &bench_surface(&moved_bench, None).unwrap().markdown,
        "cae-surface-moved",
    );
    assert_eq!(m[12], a[12], "{m:?}");
    // Frames without the targets are refused by name, not scored as exact.
    let unlabelled = tmp.path().join("unlabelled");
    std::fs::create_dir_all(&unlabelled).unwrap();
    for f in ["manifest.json", "frames"] {
        std::fs::rename(other.join(f), unlabelled.join(f)).unwrap();
    }
    let labels = std::fs::read_to_string(other.join("labels.csv")).unwrap();
    let mut lines = labels.lines();
    let head = lines.next().unwrap();
    let mut blank = format!("{head}\n");
    for l in lines {
        blank.push_str(l.split(',').take(5).collect::<Vec<_>>().join(",").as_str());
        blank.push_str(&",".repeat(head.split(',').count() - 5));
        blank.push('\n');
    }
    std::fs::write(unlabelled.join("labels.csv"), blank).unwrap();
    let Err(e) = bench_surface(&bench(&unlabelled), None) else {
        panic!("frames without labels were scored");
    };
    let e = e.to_string();
    assert!(
        e.contains("labels.csv") && e.contains("depth_mm label"),
        "{e}"
    );
}

#[test]
fn a_model_scored_on_copies_of_its_training_rows_is_marked() {
    // 20 `train` frames of the surface set, the split column dropped:
    // `cae-surface-train` fitted them (it left `val` out), `pose-surface`
    // too (every split).
    let real = root().join("../shared/real/tactip331-surface");
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("train-copies");
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    let text = std::fs::read_to_string(real.join("labels.csv")).unwrap();
    let mut lines = text.lines();
    let head = lines.next().unwrap();
    let mut labels = format!("{}\n", head.strip_suffix(",split").unwrap());
    for l in lines.filter(|l| l.ends_with(",train")).step_by(300) {
        let file = l.split(',').next().unwrap();
        std::fs::copy(real.join(file), dir.join(file)).unwrap();
        labels.push_str(&format!("{}\n", l.strip_suffix(",train").unwrap()));
    }
    common::write_subset(&real, &dir, &labels, 20);
    let table = bench_surface(
        &ModelBench {
            models: vec![
                root().join("models/cae-surface-train"),
                root().join("models/pose-surface"),
            ],
            data: dir,
            select: None,
            extreme: None,
            runs: 1,
        },
        None,
    )
    .unwrap();
    for name in ["cae-surface-train", "pose-surface"] {
        assert!(
            table
                .markdown
                .lines()
                .any(|l| l.starts_with(&format!("| {name} (trained on these frames) |"))),
            "{name}: {}",
            table.markdown
        );
    }
    assert!(table.rows.iter().all(|r| r.metrics.saw_scored_frames));
}
