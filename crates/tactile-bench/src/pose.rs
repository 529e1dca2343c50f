//! Edge pose on the real TacTip edge set: every candidate (pose networks,
//! encoders with their estimators) scored on the frames its training left
//! out, against its latency, beside the field's published figure.

use serde::Serialize;
use tactile_burn::Artifact;
use tactile_cae::CaeArtifact;
use tactile_core::dataset::{Dataset, Provenance, Seen, TestHoldout};
use tactile_core::plot::Series;
use tactile_pipeline::tactip::{Predictor, TactipModelKind};
use tactile_pose::{PoseArtifact, PoseEnsemble};

use crate::Result;
use crate::latency::{RuntimeMs, ms_cell};
use crate::models::ModelBench;
use crate::output::{BenchRow, Table, add_points, folder_name, header};

/// The targets scored, in the labels' units.
pub const TARGETS: [&str; 3] = ["x_mm", "theta_deg", "depth_mm"];

/// The field's best published result on this sensor's 2-D edge task (a
/// five-layer CNN on 128x128 images from the group that built the TacTip):
/// x and theta mean absolute errors.
pub const PUBLISHED: (f64, f64) = (0.15, 1.45);

/// The split every candidate is scored on when its folder names none.
pub const DEFAULT_HOLDOUT: TestHoldout = TestHoldout {
    test_fraction: 0.2,
    split_seed: tactile_core::dataset::DEFAULT_SPLIT_SEED,
};

/// A candidate's errors, for the JSON and the report.
#[derive(Debug, Clone, Serialize)]
pub struct PoseMetrics {
    /// Mean absolute error of x_mm, theta_deg and depth_mm on the test frames.
    pub mae: [f64; 3],
    /// Test frames scored.
    pub frames: usize,
    /// True when the model trained on every frame (its errors are then on
    /// frames it saw, not held-out ones).
    pub saw_test_frames: bool,
    /// `pose network`, `pose ensemble` or `encoder + estimators`.
    pub kind: String,
}

/// Whether a pose network never saw any frame of `ds`: its notes name the
/// datasets it trained on (`trained_on`, an ensemble's members'), each
/// opens from its folder `dir`, and none holds a frame of `ds` among the
/// rows it fitted (the same file or a copy). Other frames of the rig are
/// then all new to it, and all are scored. Without such a record it may
/// have seen them: it is scored on the test frames its split leaves.
fn never_saw(p: &Provenance, dir: &std::path::Path, ds: &Dataset) -> bool {
    let all: Vec<usize> = ds.every_row();
    p.seen(dir, ds, &all) == Seen::None
}

/// A model folder of a pose bench: what it is, its notes, its input side,
/// parameters and latencies.
pub(crate) struct Candidate {
    /// `pose network`, `pose ensemble` or `encoder + estimators`.
    pub kind: &'static str,
    /// Its provenance notes.
    pub notes: serde_json::Value,
    /// Its pin image, `128x128` (a multi-scale ensemble's each: `128x128 + 64x64`).
    pub input: String,
    /// Its parameters (an ensemble's summed).
    pub params: usize,
    /// Its latency per runtime (an ensemble's summed).
    pub ms: RuntimeMs,
    /// What it trained on: the dataset folders its notes (an ensemble's
    /// members' notes) record, none when they record none; the rows of
    /// them as its own notes say (an ensemble's: its members' together).
    pub provenance: Provenance,
}

impl Candidate {
    /// Read the model in `m` and time it over `runs` runs.
    pub fn read(m: &std::path::Path, runs: usize) -> Result<Self> {
        let trained_on = |notes: &serde_json::Value| Provenance::read(notes).datasets;
        let mut sets = Vec::new();
        let pose = TactipModelKind::of(m, "a model this bench does not score")?
            == TactipModelKind::PoseNetwork;
        let (kind, notes, input, params, ms) = if pose && PoseEnsemble::is_in(m) {
            // Members run one after another: latencies and sizes add up.
            let e = PoseEnsemble::read(m)?;
            let (mut p, mut ms, mut sides) = (0, Vec::new(), Vec::<usize>::new());
            for d in e.member_dirs(m) {
                let member = PoseArtifact::read(&d)?;
                sets.extend(trained_on(&member.notes));
                let s = member.model.input_px;
                if !sides.contains(&s) {
                    sides.push(s);
                }
                p += crate::models::parameters::<PoseArtifact>(&d)?;
                ms.push(crate::latency::model_latencies::<PoseArtifact>(
                    &d,
                    [1, 1, s, s],
                    runs,
                )?);
            }
            let input = sides
                .iter()
                .map(|s| format!("{s}x{s}"))
                .collect::<Vec<_>>()
                .join(" + ");
            ("pose ensemble", e.notes, input, p, RuntimeMs::sum(&ms))
        } else if pose {
            let a = PoseArtifact::read(m)?;
            sets.extend(trained_on(&a.notes));
            let s = a.model.input_px;
            let p = crate::models::parameters::<PoseArtifact>(m)?;
            let ms = crate::latency::model_latencies::<PoseArtifact>(m, [1, 1, s, s], runs)?;
            ("pose network", a.notes, format!("{s}x{s}"), p, ms)
        } else {
            // The encoder, then its estimators on its features.
            let a = CaeArtifact::read(m)?;
            sets.extend(trained_on(&a.notes));
            let s = a.model.input_px;
            let p = crate::models::parameters::<CaeArtifact>(m)?;
            let ms = crate::latency::model_latencies::<CaeArtifact>(m, [1, 1, s, s], runs)?;
            let (pe, mse) = crate::latency::estimator_latencies(m, runs)?;
            let ms = RuntimeMs::sum(&[ms, mse]);
            (
                "encoder + estimators",
                a.notes,
                format!("{s}x{s}"),
                p + pe,
                ms,
            )
        };
        // An ensemble's members mostly share one dataset: look it up once.
        sets.sort();
        sets.dedup();
        Ok(Self {
            kind,
            provenance: Provenance {
                datasets: sets,
                ..Provenance::read(&notes)
            },
            notes,
            input,
            params,
            ms,
        })
    }
}

/// Score every model folder of `b.models` (pose networks and encoder
/// folders with estimators) on `b.data` (the real edge set).
pub fn bench_pose(b: &ModelBench) -> Result<Table<PoseMetrics>> {
    tactile_core::bench::check_runs(b.runs)?;
    let ds = Dataset::open(&b.data)?;
    let mut md = header("Mean absolute error of edge pose", &b.data, b.runs);
    md.push_str(&format!(
        "Each model is scored on the test frames its own training left out (split seed {}, fraction {} unless its folder names another); a model trained on every frame is marked, its errors being on frames it saw. A pose network whose notes name the datasets it trained on, none of which holds any of these frames (by file or copy), is scored on every frame. An encoder's parameters and latency include its estimators' (run on burn's Flex beside onnxruntime).\n\n",
        DEFAULT_HOLDOUT.split_seed, DEFAULT_HOLDOUT.test_fraction
    ));
    md.push_str("| model | kind | input | parameters | test frames | x MAE (mm) | theta MAE (deg) | depth MAE (mm) | burn ndarray ms | burn flex ms | onnxruntime ms |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
    let (mut series, mut rows) = (Vec::new(), Vec::new());
    let mut slowest: f64 = 0.0;
    let mut shear_md = String::from(
        "| model | shear third | shear (mm) | frames | x MAE (mm) | theta MAE (deg) | depth MAE (mm) |\n|---|---|---|---|---|---|---|\n",
    );
    for m in &b.models {
        let Candidate {
            kind,
            input,
            params,
            ms,
            provenance,
            ..
        } = Candidate::read(m, b.runs)?;
        let holdout = provenance.excluded_test;
        // An encoder's estimators may record no dataset: only pose
        // networks are taken to have never seen a set.
        let network = kind != "encoder + estimators";
        let (saw, test) = if network && never_saw(&provenance, m, &ds) {
            (false, ds.every_row())
        } else {
            let split = ds.three_way_split(
                holdout.unwrap_or(DEFAULT_HOLDOUT).test_fraction,
                0.2,
                holdout.unwrap_or(DEFAULT_HOLDOUT).split_seed,
            )?;
            (holdout.is_none(), split.test)
        };
        let mut predictor = Predictor::load(m, &[], tactile_burn::Runtime::BurnFlex)?;
        let all = predictor.perceive(&ds)?;
        // Per test frame: |error| of each target (NaN when unlabelled).
        let mut errors = vec![[f64::NAN; 3]; test.len()];
        for (k, name) in TARGETS.iter().enumerate() {
            let Some(tactile_estimate::Column::Number(v)) = all.estimates.get(name) else {
                continue;
            };
            for (e, &i) in errors.iter_mut().zip(&test) {
                if let Ok(Some(truth)) = ds.target_opt(i, name) {
                    e[k] = (v[i] - truth).abs();
                }
            }
        }
        let mean = |sel: &[usize], k: usize| {
            let v: Vec<f64> = sel
                .iter()
                .map(|&j| errors[j][k])
                .filter(|e| e.is_finite())
                .collect();
            // No labelled frame (or no such estimate): no error, not 0.
            if v.is_empty() {
                f64::NAN
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        // An error cell: `-` where there is none.
        let cell = |e: f64, decimals: usize| {
            if e.is_finite() {
                format!("{e:.decimals$}")
            } else {
                "-".to_string()
            }
        };
        let every: Vec<usize> = (0..errors.len()).collect();
        let mae = [0, 1, 2].map(|k| mean(&every, k));
        // Errors against the unlabelled shear of the frames, in thirds.
        let shear: Vec<Option<f64>> = test
            .iter()
            .map(|&i| {
                let (x, y) = (
                    ds.number_opt(i, "shear_x_mm").ok()??,
                    ds.number_opt(i, "shear_y_mm").ok()??,
                );
                Some(x.hypot(y))
            })
            .collect();
        let mut order: Vec<usize> = (0..shear.len()).filter(|&j| shear[j].is_some()).collect();
        order.sort_by(|&a, &b| shear[a].unwrap_or(0.0).total_cmp(&shear[b].unwrap_or(0.0)));
        for (t, third) in order.chunks(order.len().div_ceil(3).max(1)).enumerate() {
            let lo = third.first().and_then(|&j| shear[j]).unwrap_or(f64::NAN);
            let hi = third.last().and_then(|&j| shear[j]).unwrap_or(f64::NAN);
            shear_md.push_str(&format!(
                "| {} | {} | {lo:.2}-{hi:.2} | {} | {} | {} | {} |\n",
                folder_name(m),
                ["lowest", "middle", "highest"][t.min(2)],
                third.len(),
                cell(mean(third, 0), 3),
                cell(mean(third, 1), 2),
                cell(mean(third, 2), 3)
            ));
        }
        md.push_str(&format!(
            "| {}{} | {kind} | {input} | {params} | {} | {} | {} | {} | {} | {} | {} |\n",
            folder_name(m),
            if saw { " (trained on every frame)" } else { "" },
            test.len(),
            cell(mae[0], 3),
            cell(mae[1], 2),
            cell(mae[2], 3),
            ms_cell(ms.ndarray),
            ms_cell(ms.flex),
            ms_cell(ms.onnxruntime),
        ));
        slowest = ms
            .named()
            .iter()
            .filter_map(|v| v.1)
            .fold(slowest, f64::max);
        if !saw && mae[0].is_finite() {
            add_points(&mut series, &ms, mae[0]);
        }
        rows.push(BenchRow::new(
            m,
            PoseMetrics {
                mae,
                frames: test.len(),
                saw_test_frames: saw,
                kind: kind.to_string(),
            },
            ms,
        ));
    }
    series.push(Series {
        name: format!(
            "published 5-layer CNN, 128x128 (x {} mm; latency not published)",
            PUBLISHED.0
        ),
        points: vec![(0.0, PUBLISHED.0), (slowest.max(0.1), PUBLISHED.0)],
    });
    // Frames without shear columns (a researcher's own edge set) get no
    // table of shear thirds, not an empty one.
    if shear_md.lines().count() > 2 {
        md.push_str(&format!(
            "\nErrors against the frames' shear (unlabelled perturbations the rig applied; `shear_x_mm`, `shear_y_mm`), test frames in thirds of the shear magnitude:\n\n{shear_md}"
        ));
    }
    md.push_str(&format!(
        "\nThe field's best published result on this task: x {} mm, theta {} deg (a five-layer CNN on 128x128 images). Targets here: x <= 0.15 mm, theta <= 1.45 deg, depth <= 0.05 mm at <= 1 ms through onnxruntime; the CAE route within 1.5x of the best model on every target.\n",
        PUBLISHED.0, PUBLISHED.1
    ));
    Ok(Table {
        markdown: md,
        title: "Edge pose: x error against latency".into(),
        y_label: "x MAE (mm)".into(),
        series,
        rows,
        pictures: Vec::new(),
        after_plot: String::new(),
    })
}
