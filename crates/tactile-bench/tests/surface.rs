#![allow(clippy::unwrap_used)]
//! The surface bench on 150 real `val` frames of the 331-pin TacTip
//! (`../shared/real/tactip331-surface`, copied to a temporary folder) with
//! the shipped `models/pose-surface`: the gain table says what the estimates
//! follow of each target by tap depth, and the shallow taps' twist, where
//! the skin slips on the surface, is followed least; an encoder's row
//! counts every member of its estimator.

use std::path::{Path, PathBuf};

use tactile_bench::models::ModelBench;
use tactile_bench::surface::bench_surface;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every `step`-th `val` row of the real set (its rows run by tap depth, so
/// the subset spans every depth).
fn val_subset(dir: &Path, step: usize) -> usize {
    let real = root().join("../shared/real/tactip331-surface");
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    let text = std::fs::read_to_string(real.join("labels.csv")).unwrap();
    let mut lines = text.lines();
    let mut labels = format!("{}\n", lines.next().unwrap());
    let mut n = 0;
    for (k, l) in lines.filter(|l| l.ends_with(",val")).enumerate() {
        if k % step == 0 {
            let file = l.split(',').next().unwrap();
            std::fs::copy(real.join(file), dir.join(file)).unwrap();
            labels.push_str(l);
            labels.push('\n');
            n += 1;
        }
    }
    std::fs::write(dir.join("labels.csv"), labels).unwrap();
    let manifest = std::fs::read_to_string(real.join("manifest.json")).unwrap();
    let mut m: serde_json::Value = serde_json::from_str(&manifest).unwrap();
    m["count"] = n.into();
    std::fs::write(dir.join("manifest.json"), m.to_string()).unwrap();
    n
}

/// The cells of the gain table's row for `third` (six targets).
fn gains(markdown: &str, third: &str) -> Vec<f64> {
    let table = markdown.split("Gain by tap depth").nth(1).unwrap();
    let row = table
        .lines()
        .find(|l| l.starts_with(&format!("| pose-surface | {third} |")))
        .unwrap();
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    cells[5..11].iter().map(|c| c.parse().unwrap()).collect()
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
