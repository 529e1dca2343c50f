//! Surface pose and shear on the real 331-pin TacTip set: every candidate
//! (pose networks, encoders with their estimators) scored on the split the
//! authors held out, per target against their own CNN, with the coverage
//! of its uncertainty intervals where it gives one, against its latency.

use serde::Serialize;
use tactile_burn::ensemble::CALIBRATION_NOTE;
use tactile_core::dataset::{Dataset, Seen};
use tactile_core::plot::{ScatterPanel, Series, scatter_grid};
use tactile_estimate::Column;
use tactile_estimate::uncertainty::{ONE_SIGMA, Z95, coverage, cross_fitted_coverage_at};
use tactile_pipeline::tactip::Predictor;

use crate::Result;
use crate::latency::ms_cell;
use crate::models::ModelBench;
use crate::output::{BenchRow, Picture, Table, add_points, folder_name, header, picture_beside};
use crate::pose::Candidate;

/// The targets, in the labels' units, with the authors' CNN's mean
/// absolute error on their `val` split (four conv layers, 128x128 input).
pub const AUTHORS_CNN: [(&str, f64); 6] = [
    ("depth_mm", 0.175),
    ("roll_deg", 1.34),
    ("pitch_deg", 1.41),
    ("shear_x_mm", 0.55),
    ("shear_y_mm", 0.55),
    ("shear_theta_deg", 1.21),
];

/// The reference row of the estimate that reads no frame: each target's
/// median over the `train` frames.
const TRAIN_MEDIAN: &str = "`train` median (reads no frame)";

/// The goal: at least this much below the authors' error on every target.
pub const GOAL_FRACTION: f64 = 0.75;

/// A candidate's errors, for the JSON and the page.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceMetrics {
    /// Mean absolute error per target of [`AUTHORS_CNN`], labels' units.
    pub mae: Vec<f64>,
    /// Each error over the authors' CNN's.
    pub ratio: Vec<f64>,
    /// Frames scored.
    pub frames: usize,
    /// True when the model trained on the scored frames too.
    pub saw_scored_frames: bool,
    /// `pose network`, `pose ensemble` or `encoder + estimators`.
    pub kind: String,
    /// Fraction of errors inside ±1 standard deviation, per target, when
    /// the model gives one.
    pub coverage_68: Option<Vec<f64>>,
    /// Fraction inside ±1.96 standard deviations.
    pub coverage_95: Option<Vec<f64>>,
    /// Per target, the correlation of this model's errors with the first
    /// model's on the scored frames (none for the first model).
    pub error_correlation: Option<Vec<f64>>,
}

/// The rows scored and the split they are: the `split` column's held-out
/// rows (`test`, else the authors' `val`), or every row (no split named)
/// when the labels hold none.
fn scored_rows(ds: &Dataset) -> (Vec<usize>, Option<&'static str>) {
    match ds.evaluation_split().filter(|r| !r.is_empty()) {
        Some(rows) => (rows, ds.evaluation_split_name()),
        None => (ds.every_row(), None),
    }
}

/// The coverage of a model whose deviations were calibrated on the scored
/// frames themselves (`tactile train calibrate --split`: the same split of
/// the dataset its note names, or frames copied out of it): measured there
/// it would be 68.3 % by construction, so its cross-fitted coverage
/// (calibrated on one half of the split, measured on the other) stands
/// instead. On any other frames the coverage is measured. Where the
/// dataset the note names cannot be opened (moved, or never recorded), the
/// scored frames may be the calibration's: the cross-fitted coverage
/// stands, as [`saw_scored`] takes such a model to have seen them, so a
/// coverage of 68.3 % by construction is never shown as measured. `u` is
/// the model's calibration note ([`CALIBRATION_NOTE`]).
fn cross_fitted(
    u: Option<&serde_json::Value>,
    model_dir: &std::path::Path,
    ds: &Dataset,
    rows: &[usize],
    split: Option<&str>,
) -> Option<[Vec<f64>; 2]> {
    let (u, split) = (u?, split?);
    if u.get("split").and_then(|s| s.as_str()) != Some(split) {
        return None;
    }
    let calibrated_on = u
        .get("data")
        .and_then(|d| d.as_str())
        .and_then(|d| Dataset::open_recorded(d, model_dir));
    if let Some(calibrated_on) = calibrated_on {
        let within = calibrated_on.split_indices(split)?;
        if !calibrated_on.holds_frames(ds, rows, Some(&within)) {
            return None;
        }
    }
    serde_json::from_value(u.get("coverage_cross_fitted")?.clone()).ok()
}

/// Points of the coverage curve: z from 0.25 to 3 in these steps.
const COVERAGE_STEPS: usize = 12;

fn coverage_z(step: usize) -> f64 {
    0.25 * step as f64
}

/// The fraction of a normal variable within ±z standard deviations.
fn normal_coverage(z: f64) -> f64 {
    libm::erf(z / std::f64::consts::SQRT_2)
}

/// Per z of [`coverage_z`], the fraction of `|error| <= z * std`, mean
/// over the targets (`(|error|, std)` per row, per target). Cross-fitted:
/// each half of the rows counted under the factors that make ±1 hold
/// 68.3 % of the other half, the two halves averaged.
fn coverage_curve(targets: &[Vec<(f64, f64)>], cross_fit: bool) -> Vec<(f64, f64)> {
    let zs: Vec<f64> = (1..=COVERAGE_STEPS).map(coverage_z).collect();
    let mut sum = vec![0.0; zs.len()];
    for rows in targets {
        let (errors, std): (Vec<Vec<f64>>, Vec<Vec<f64>>) =
            rows.iter().map(|&(e, s)| (vec![e], vec![s])).unzip();
        let at: Vec<f64> = if cross_fit {
            cross_fitted_coverage_at(&errors, &std, &zs)
                .into_iter()
                .map(|c| c[0])
                .collect()
        } else {
            zs.iter().map(|&z| coverage(&errors, &std, z)[0]).collect()
        };
        sum.iter_mut().zip(at).for_each(|(total, c)| *total += c);
    }
    let n = targets.len().max(1) as f64;
    zs.into_iter().zip(sum).map(|(z, s)| (z, s / n)).collect()
}

/// The header and rule of a markdown table: the `leading` columns, one
/// per target of [`AUTHORS_CNN`], then the `trailing` ones.
fn per_target_header(leading: &[&str], trailing: &[&str]) -> String {
    let names = leading
        .iter()
        .copied()
        .chain(AUTHORS_CNN.iter().map(|(t, _)| *t))
        .chain(trailing.iter().copied());
    let columns = leading.len() + AUTHORS_CNN.len() + trailing.len();
    format!(
        "| {} |\n|{}\n",
        names.collect::<Vec<_>>().join(" | "),
        "---|".repeat(columns)
    )
}

/// Whether a model trained on the scored rows: a dataset its notes name
/// holds every one of them among the rows it fitted (its `train` rows, or
/// every row when it fitted every split; the same file or a copy). One
/// trained on every split without a record of its dataset, or whose
/// dataset cannot be opened, is taken to have seen them.
fn saw_scored(c: &Candidate, model_dir: &std::path::Path, ds: &Dataset, rows: &[usize]) -> bool {
    let p = &c.provenance;
    match p.seen(model_dir, ds, rows) {
        Seen::All => true,
        Seen::Unknown => p.every_split,
        Seen::None | Seen::Some => false,
    }
}

/// Score every model folder of `b.models` on `b.data` (the surface set);
/// with `out`, the first model's predictions against the truth, its error
/// by tap depth and the intervals' coverage are pictures of the page,
/// drawn beside it when the table is written.
pub fn bench_surface(
    b: &ModelBench,
    out: Option<&std::path::Path>,
) -> Result<Table<SurfaceMetrics>> {
    tactile_core::bench::check_runs(b.runs)?;
    let ds = Dataset::open(&b.data)?;
    let (rows, split) = scored_rows(&ds);
    // Before any model runs: every target labelled on some scored frame (an
    // error over no frame would read as an exact estimate).
    for (t, _) in AUTHORS_CNN {
        let mut labelled = false;
        for &i in &rows {
            labelled |= ds.number_opt(i, t)?.is_some();
        }
        if !labelled {
            return Err(tactile_core::Error::dataset(
                ds.labels_path(),
                None,
                format!("no scored frame has a {t} label: the bench needs the targets it scores"),
            )
            .into());
        }
    }
    let mut md = header(
        "Mean absolute error of surface pose and shear",
        &b.data,
        b.runs,
    );
    md.push_str(&format!(
        "Scored on {}; a model trained on them too is marked. \
         Each error cell gives the error and, in brackets, its ratio to the authors' CNN (goal: at most {GOAL_FRACTION}). \
         Coverage: the fraction of frames whose error lies inside the model's ±1 and ±1.96 standard deviation intervals (68.3 % and 95 % when calibrated), mean over the targets (range); \
         for a model whose deviations were calibrated on these frames (`tactile train calibrate --split`), cross-fitted: calibrated on one half, measured on the other, both ways (marked \"cross-fitted\"). \
         An encoder's parameters and latency include its estimators' (an ensemble's every member), which run on burn's Flex beside onnxruntime.\n\n",
        match split {
            Some("val") => format!("the {} frames of the authors' held-out split", rows.len()),
            Some(name) => format!("the {} frames of the `{name}` split", rows.len()),
            None => format!("all {} frames (the labels name no held-out split)", rows.len()),
        }
    ));
    md.push_str(&per_target_header(
        &["model", "kind", "input", "parameters"],
        &[
            "worst ratio",
            "68 % interval",
            "95 % interval",
            "burn flex ms",
            "onnxruntime ms",
        ],
    ));
    md.push_str("| authors' CNN (reference) | 4 conv layers | 128x128 | - |");
    for (_, e) in AUTHORS_CNN {
        md.push_str(&format!(" {e} (1.00) |"));
    }
    md.push_str(" 1.00 | - | - | - | - |\n");
    let (mut series, mut table_rows) = (Vec::new(), Vec::new());
    let mut coverage_series = Vec::new();
    // The scored frames in thirds of their tap depth: shear shows in the
    // pins only once the skin grips the surface.
    let depth_of = |i: usize| ds.number_opt(i, "depth_mm").ok().flatten();
    let mut by_depth: Vec<usize> = (0..rows.len())
        .filter(|&k| depth_of(rows[k]).is_some())
        .collect();
    by_depth.sort_by(|&a, &b| {
        let d = |k: usize| depth_of(rows[k]).unwrap_or(0.0);
        d(a).total_cmp(&d(b))
    });
    let thirds: Vec<&[usize]> = by_depth.chunks(by_depth.len().div_ceil(3).max(1)).collect();
    let mut depth_md =
        per_target_header(&["model", "tap depth third", "depth (mm)", "frames"], &[]);
    // The same thirds, the gain of each estimate on its truth: how much of a
    // commanded slide or twist the estimates follow where the skin slips.
    let mut gain_md = depth_md.clone();
    // The frames the candidates fitted: how far their errors there fall
    // below the held-out ones says whether a target is learnt or left as
    // noise (a target no network fits on its own training frames is not
    // in the frame).
    let fitted: Vec<usize> = ds
        .split_indices("train")
        .map(|r| r.to_vec())
        .unwrap_or_default();
    let mut fit_md = per_target_header(&["model", "frames"], &[]);
    // Per target, the median truth of the fitted frames: an estimate that
    // reads no frame, against which the tables show what a model learnt
    // (empty without a `train` split).
    let mut train_median = Vec::new();
    if !fitted.is_empty() {
        for (t, _) in AUTHORS_CNN {
            let mut truth = Vec::with_capacity(fitted.len());
            for &i in &fitted {
                truth.extend(ds.number_opt(i, t)?);
            }
            train_median.push(tactile_core::metrics::median(&truth));
        }
    }
    // A depth third's leading cells: who, which third, its depths, frames.
    let third_head = |name: &str, n: usize, third: &[usize]| {
        let depth_at = |k: Option<&usize>| k.and_then(|&k| depth_of(rows[k])).unwrap_or(f64::NAN);
        format!(
            "| {name} | {} | {:.2}-{:.2} | {} |",
            ["shallowest", "middle", "deepest"][n.min(2)],
            depth_at(third.first()),
            depth_at(third.last()),
            third.len()
        )
    };
    // Per target, how alike each model's errors are to the first model's:
    // errors two unlike models share are in the frames, not the models.
    let mut agreement_md = per_target_header(&["model", "tap depth third"], &[]);
    // Per depth third, how the deviations follow the error: a robot should
    // learn from them where a target cannot be read (shallow twist).
    let mut depth_coverage_md =
        per_target_header(&["model", "tap depth third", "depth (mm)", "frames"], &[]);
    // The first model's signed errors per target and scored row.
    let mut reference_errors: Option<Vec<Vec<f64>>> = None;
    let mut first_panels = None;
    // The first model's (truth, estimate) per target and scored row: its
    // error against tap depth, drawn beside the table.
    let mut first_pairs: Option<Vec<Vec<(f64, f64)>>> = None;
    for m in &b.models {
        let c = Candidate::read(m, b.runs)?;
        let saw = saw_scored(&c, m, &ds, &rows);
        let mut predictor = Predictor::load(m, &[], tactile_burn::Runtime::BurnFlex)?;
        let all = predictor.perceive(&ds)?;
        let number = |name: &str| match all.estimates.get(name) {
            Some(Column::Number(v)) => Some(v),
            _ => None,
        };
        let (mut mae, mut ratio, mut panels) = (Vec::new(), Vec::new(), Vec::new());
        let (mut cov68, mut cov95) = (Vec::new(), Vec::new());
        // Per target with a deviation, (|error|, deviation) per scored row:
        // the coverage curve.
        let mut errors_and_std: Vec<Vec<(f64, f64)>> = Vec::new();
        // Per target, the deviation per scored row (NaN when unlabelled),
        // for a model that gives one: the coverage by depth third.
        let mut std_by_target: Vec<Vec<f64>> = Vec::new();
        // Per target and scored row, (truth, estimate); NaN when unlabelled:
        // the depth thirds' errors and gains.
        let mut pairs_by_target: Vec<Vec<(f64, f64)>> = Vec::new();
        // Per target, the MAE on the fitted frames.
        let mut fit_mae = Vec::new();
        for (t, authors) in AUTHORS_CNN {
            let Some(pred) = number(t) else {
                return Err(tactile_core::Error::Invalid(format!(
                    "{}: the model does not estimate {t}",
                    m.display()
                ))
                .into());
            };
            let std = number(&tactile_estimate::registry::std_column(t));
            let mut points = Vec::with_capacity(rows.len());
            let mut pairs = Vec::with_capacity(rows.len());
            let mut deviations = Vec::new();
            let (mut inside68, mut inside95) = (0usize, 0usize);
            for &i in &rows {
                let Some(truth) = ds.number_opt(i, t)? else {
                    pairs.push((f64::NAN, f64::NAN));
                    continue;
                };
                let e = (pred[i] - truth).abs();
                pairs.push((truth, pred[i]));
                points.push((truth, pred[i]));
                if let Some(s) = std {
                    deviations.push((e, s[i]));
                    inside68 += usize::from(e <= s[i]);
                    inside95 += usize::from(e <= Z95 * s[i]);
                }
            }
            pairs_by_target.push(pairs);
            let mut fit_errors = Vec::with_capacity(fitted.len());
            for &i in &fitted {
                if let Some(truth) = ds.number_opt(i, t)? {
                    fit_errors.push((pred[i] - truth).abs());
                }
            }
            fit_mae.push(fit_errors.iter().sum::<f64>() / fit_errors.len().max(1) as f64);
            let n = points.len().max(1) as f64;
            let e = points.iter().map(|p| (p.1 - p.0).abs()).sum::<f64>() / n;
            mae.push(e);
            ratio.push(e / authors);
            if let Some(s) = std {
                std_by_target.push(rows.iter().map(|&i| s[i]).collect());
                cov68.push(inside68 as f64 / n);
                cov95.push(inside95 as f64 / n);
                errors_and_std.push(deviations);
            }
            panels.push(ScatterPanel {
                title: format!("{t}: MAE {e:.3} (authors {authors})"),
                points,
            });
        }
        if !fitted.is_empty() {
            fit_md.push_str(&format!("| {} | {} |", folder_name(m), fitted.len()));
            for e in &fit_mae {
                fit_md.push_str(&format!(" {e:.3} |"));
            }
            fit_md.push('\n');
        }
        // An encoder's deviations are its regressor's, calibrated there.
        let calibration = match &predictor {
            Predictor::Encoder(p) => p.estimators.calibration(),
            Predictor::PoseNetwork(_) => c.notes.get(CALIBRATION_NOTE),
        };
        let cross = cross_fitted(calibration, m, &ds, &rows, split);
        if let Some([c68, c95]) = &cross {
            (cov68, cov95) = (c68.clone(), c95.clone());
        }
        if !errors_and_std.is_empty() && !saw {
            coverage_series.push(Series {
                name: format!(
                    "{}{}",
                    folder_name(m),
                    if cross.is_some() {
                        " (cross-fitted)"
                    } else {
                        ""
                    }
                ),
                points: coverage_curve(&errors_and_std, cross.is_some()),
            });
        }
        let errors: Vec<Vec<f64>> = pairs_by_target
            .iter()
            .map(|pairs| pairs.iter().map(|(t, e)| e - t).collect())
            .collect();
        // Per target, the correlation with the reference's errors over the
        // scored rows at these positions.
        let agreement = |reference: &[Vec<f64>], at: &[usize]| {
            reference
                .iter()
                .zip(&errors)
                .map(|(r, e)| {
                    let (r, e): (Vec<f64>, Vec<f64>) = at
                        .iter()
                        .map(|&k| (r[k], e[k]))
                        .filter(|(r, e)| r.is_finite() && e.is_finite())
                        .unzip();
                    tactile_core::metrics::correlation(&r, &e)
                })
                .collect::<Vec<f64>>()
        };
        let error_correlation = reference_errors
            .as_deref()
            .map(|reference| agreement(reference, &(0..rows.len()).collect::<Vec<_>>()));
        if let (Some(reference), Some(all)) = (reference_errors.as_deref(), &error_correlation) {
            let name = format!(
                "{}{}",
                folder_name(m),
                if saw {
                    " (trained on these frames)"
                } else {
                    ""
                }
            );
            let by_third = thirds
                .iter()
                .zip(["shallowest", "middle", "deepest"])
                .map(|(third, label)| (label, agreement(reference, third)));
            for (label, rho) in std::iter::once(("all", all.clone())).chain(by_third) {
                agreement_md.push_str(&format!("| {name} | {label} |"));
                for r in rho {
                    agreement_md.push_str(&format!(" {r:.2} |"));
                }
                agreement_md.push('\n');
            }
        } else {
            reference_errors = Some(errors);
        }
        let worst = ratio.iter().copied().fold(0.0, f64::max);
        for (n, third) in thirds.iter().enumerate() {
            let row_head = third_head(&folder_name(m), n, third);
            depth_md.push_str(&row_head);
            gain_md.push_str(&row_head);
            for pairs in &pairs_by_target {
                let (truth, est): (Vec<f64>, Vec<f64>) = third
                    .iter()
                    .map(|&k| pairs[k])
                    .filter(|(t, _)| t.is_finite())
                    .unzip();
                depth_md.push_str(&format!(
                    " {:.3} |",
                    tactile_core::metrics::mae(&est, &truth)
                ));
                gain_md.push_str(&format!(
                    " {:.2} |",
                    tactile_core::metrics::gain(&est, &truth)
                ));
            }
            depth_md.push('\n');
            gain_md.push('\n');
            // A model that fitted these frames has no honest interval here.
            if std_by_target.len() == pairs_by_target.len() && !saw {
                // Frame by frame (the frames labelled on every target), the
                // signed errors and the deviations.
                let labelled: Vec<usize> = third
                    .iter()
                    .copied()
                    .filter(|&k| pairs_by_target.iter().all(|p| p[k].0.is_finite()))
                    .collect();
                let errors: Vec<Vec<f64>> = labelled
                    .iter()
                    .map(|&k| pairs_by_target.iter().map(|p| p[k].1 - p[k].0).collect())
                    .collect();
                let deviations: Vec<Vec<f64>> = labelled
                    .iter()
                    .map(|&k| std_by_target.iter().map(|s| s[k]).collect())
                    .collect();
                let (c68, c95) = (
                    coverage(&errors, &deviations, 1.0),
                    coverage(&errors, &deviations, Z95),
                );
                let n = labelled.len().max(1) as f64;
                depth_coverage_md.push_str(&row_head);
                for (j, (c68, c95)) in c68.iter().zip(&c95).enumerate() {
                    let mean_std = deviations.iter().map(|d| d[j]).sum::<f64>() / n;
                    depth_coverage_md.push_str(&format!(
                        " {:.0} / {:.0} % ({mean_std:.3}) |",
                        100.0 * c68,
                        100.0 * c95
                    ));
                }
                depth_coverage_md.push('\n');
            }
        }
        let cov_cell = |v: &[f64]| {
            if v.is_empty() {
                return "-".to_string();
            }
            let (lo, hi) = v
                .iter()
                .fold((1f64, 0f64), |(a, b), x| (a.min(*x), b.max(*x)));
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            format!(
                "{:.1} % ({:.1}-{:.1})",
                100.0 * mean,
                100.0 * lo,
                100.0 * hi
            )
        };
        md.push_str(&format!(
            "| {}{} | {} | {} | {} |",
            folder_name(m),
            if saw {
                " (trained on these frames)"
            } else {
                ""
            },
            c.kind,
            c.input,
            c.params,
        ));
        for (e, r) in mae.iter().zip(&ratio) {
            md.push_str(&format!(" {e:.3} ({r:.2}) |"));
        }
        md.push_str(&format!(
            " {worst:.2} | {} | {} | {} | {} |\n",
            cov_cell(&cov68)
                + if cross.is_some() {
                    ", cross-fitted"
                } else {
                    ""
                },
            cov_cell(&cov95)
                + if cross.is_some() {
                    ", cross-fitted"
                } else {
                    ""
                },
            ms_cell(c.ms.flex),
            ms_cell(c.ms.onnxruntime)
        ));
        if !saw {
            add_points(&mut series, &c.ms, worst);
        }
        if first_panels.is_none() {
            first_panels = Some((folder_name(m), panels));
            first_pairs = Some(pairs_by_target.clone());
        }
        table_rows.push(BenchRow::new(
            m,
            SurfaceMetrics {
                mae,
                ratio,
                frames: rows.len(),
                saw_scored_frames: saw,
                kind: c.kind.to_string(),
                coverage_68: (!cov68.is_empty()).then_some(cov68),
                coverage_95: (!cov95.is_empty()).then_some(cov95),
                error_correlation,
            },
            c.ms,
        ));
    }
    // The estimate that reads no frame, on the same thirds and fitted frames.
    let constant_mae = |at: &[usize]| -> Result<Vec<f64>> {
        let mut out = Vec::with_capacity(train_median.len());
        for ((t, _), &median) in AUTHORS_CNN.iter().zip(&train_median) {
            let mut truth = Vec::with_capacity(at.len());
            for &i in at {
                truth.extend(ds.number_opt(i, t)?);
            }
            out.push(tactile_core::metrics::mae(
                &vec![median; truth.len()],
                &truth,
            ));
        }
        Ok(out)
    };
    if !train_median.is_empty() {
        for (n, third) in thirds.iter().enumerate() {
            depth_md.push_str(&third_head(TRAIN_MEDIAN, n, third));
            for e in constant_mae(&third.iter().map(|&k| rows[k]).collect::<Vec<_>>())? {
                depth_md.push_str(&format!(" {e:.3} |"));
            }
            depth_md.push('\n');
        }
        fit_md.push_str(&format!("| {TRAIN_MEDIAN} | {} |", fitted.len()));
        for e in constant_mae(&fitted)? {
            fit_md.push_str(&format!(" {e:.3} |"));
        }
        fit_md.push('\n');
    }
    // The first model's error against tap depth, per target as a fraction of
    // reading no frame: one picture, whatever each target's unit.
    let mut relative_plot = None;
    let mut pictures = Vec::new();
    if let (Some(pairs), Some(out), false) = (&first_pairs, out, train_median.is_empty()) {
        let tenths: Vec<&[usize]> = by_depth
            .chunks(by_depth.len().div_ceil(10).max(1))
            .collect();
        // Per tenth, once: its mean depth and the no-frame error per target.
        let mut depths = Vec::with_capacity(tenths.len());
        let mut references = Vec::with_capacity(tenths.len());
        for tenth in &tenths {
            let d: Vec<f64> = tenth.iter().filter_map(|&k| depth_of(rows[k])).collect();
            depths.push(d.iter().sum::<f64>() / d.len().max(1) as f64);
            references.push(constant_mae(
                &tenth.iter().map(|&k| rows[k]).collect::<Vec<_>>(),
            )?);
        }
        let depth_range = depths
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &d| {
                (lo.min(d), hi.max(d))
            });
        let mut series = Vec::with_capacity(AUTHORS_CNN.len());
        // Depth itself is left out: within a tenth of the depths, reading no
        // frame is as good as the tenth is narrow.
        for (j, (t, _)) in AUTHORS_CNN
            .iter()
            .enumerate()
            .filter(|(_, (t, _))| *t != "depth_mm")
        {
            let points = tenths
                .iter()
                .zip(depths.iter().zip(&references))
                .map(|(tenth, (&depth, reference))| {
                    let (truth, est): (Vec<f64>, Vec<f64>) = tenth
                        .iter()
                        .map(|&k| pairs[j][k])
                        .filter(|(t, _)| t.is_finite())
                        .unzip();
                    (
                        depth,
                        tactile_core::metrics::mae(&est, &truth) / reference[j],
                    )
                })
                .collect();
            series.push(Series {
                name: (*t).to_string(),
                points,
            });
        }
        series.push(Series {
            name: "reading no frame (the `train` median)".into(),
            points: vec![(depth_range.0, 1.0), (depth_range.1, 1.0)],
        });
        let (path, link) = picture_beside(out, "by-depth");
        pictures.push(Picture::lines(
            path,
            "Error against tap depth, as a fraction of reading no frame",
            "tap depth (mm; mean of each tenth of the scored frames)",
            "MAE / MAE of each target's train median",
            series,
        ));
        relative_plot = Some(link);
    }
    md.push_str(&format!(
        "\nErrors by tap depth (mean absolute error of the scored frames in thirds of their depth): shear and twist show in the pins only where the skin grips the surface. \
         The last rows are what reading no frame gives: each target's median on the `train` frames as every estimate.\n\n{depth_md}"
    ));
    if let (Some(link), Some(m)) = (&relative_plot, b.models.first()) {
        md.push_str(&format!(
            "\nThe error of `{}` against tap depth, in tenths of the scored frames, each target's as a fraction of reading no frame (0: exact; 1: the frame told it nothing; depth left out, since the tenths are by depth):\n\n![error against tap depth]({link})\n",
            folder_name(m)
        ));
    }
    md.push_str(&format!(
        "\nGain by tap depth (the least-squares slope of each estimate on its truth in the same thirds; 1: the estimates follow the truth, 0: they ignore it): where the skin slips, a slide or twist shows only in part.\n\n{gain_md}"
    ));
    if depth_coverage_md.lines().count() > 2 {
        md.push_str(&format!(
            "\nIntervals by tap depth, for the models that give a deviation and never fitted the scored frames: per target, the share of errors inside ±1 and ±1.96 standard deviations \
             (68.3 % and 95 % when calibrated; each target has one factor, calibrated over every depth at once, for the models marked cross-fitted above on all of these frames) and, in brackets, the mean deviation in the target's unit. \
             A deviation that grows where a target cannot be read tells a robot not to trust it there.\n\n{depth_coverage_md}"
        ));
    }
    if let (Some(first), true) = (b.models.first(), b.models.len() > 1) {
        md.push_str(&format!(
            "\nError agreement with `{}` (the correlation of each model's signed errors with its errors on the scored frames, per target): \
             errors that models of unlike inputs and training share are in the frames or their labels, not in either model; \
             what one model gets wrong alone, another can get right (an ensemble's members share its errors in part by construction).\n\n{agreement_md}",
            folder_name(first)
        ));
    }
    if !fitted.is_empty() {
        md.push_str(&format!(
            "\nErrors on the {} `train` frames, which every candidate fitted (but for the 10 % that stopped it early): what a model leaves unexplained even on frames it learnt from (the last row reads no frame).\n\n{fit_md}",
            fitted.len()
        ));
    }
    if let (false, Some(out)) = (coverage_series.is_empty(), out) {
        let z: Vec<f64> = (1..=COVERAGE_STEPS).map(coverage_z).collect();
        coverage_series.push(Series {
            name: "normal errors (95 % at 1.96)".into(),
            points: z.iter().map(|&z| (z, normal_coverage(z))).collect(),
        });
        coverage_series.push(Series {
            name: "Laplace errors, 68.3 % at 1".into(),
            points: z
                .iter()
                .map(|&z| (z, 1.0 - (1.0 - ONE_SIGMA).powf(z)))
                .collect(),
        });
        let (path, link) = picture_beside(out, "coverage");
        pictures.push(Picture::lines(
            path,
            "Interval coverage on frames the models never fitted",
            "interval half-width (standard deviations)",
            "fraction of errors inside (mean over targets)",
            coverage_series,
        ));
        md.push_str(&format!(
            "
How often the error lies inside ±z standard deviations, for z from 0.25 to 3, mean over the targets, for the models that give a deviation and never fitted the scored frames (cross-fitted where they were calibrated on them: factors from one half, counted on the other), beside what normal and Laplace errors would give:

![interval coverage]({link})
"
        ));
    }
    if let (Some((name, panels)), Some(out)) = (first_panels, out) {
        let (path, link) = picture_beside(out, "scatter");
        md.push_str(&format!(
            "\nPredicted against true values of `{name}` on the scored frames, each point coloured by its error (dark: exact; yellow: the target's 95th percentile error or worse):\n\n![{name} predictions]({link})\n"
        ));
        pictures.push(Picture::new(path, move |path| {
            Ok(scatter_grid(path, &panels, 3)?)
        }));
    }
    series.push(Series {
        name: "goal: every target at most 0.75x the authors' CNN".into(),
        points: vec![(0.0, GOAL_FRACTION), (1.0, GOAL_FRACTION)],
    });
    Ok(Table {
        markdown: md,
        title: "Surface pose and shear: worst error ratio to the authors' CNN against latency"
            .into(),
        y_label: "worst target MAE / authors' CNN".into(),
        series,
        rows: table_rows,
        pictures,
        after_plot: String::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_coverage_curve_of_laplace_errors_follows_the_laplace_reference() {
        assert!((normal_coverage(1.0) - 0.682_689).abs() < 1e-6);
        assert!((normal_coverage(tactile_estimate::uncertainty::Z95) - 0.95).abs() < 1e-6);
        // Laplace errors of scale 1 under a deviation of 2: cross-fitted,
        // ±1 holds 68.3 % and ±z the Laplace's 1 - 0.317^z, not a normal's.
        let mut rng = tactile_core::rng::SampleRng::new(5, 0, 0);
        let rows: Vec<(f64, f64)> = (0..20_000)
            .map(|_| {
                let u: f64 = rng.uniform();
                (-(1.0 - u).max(1e-12).ln(), 2.0)
            })
            .collect();
        let curve = coverage_curve(std::slice::from_ref(&rows), true);
        for &(z, c) in &curve {
            let laplace = 1.0 - (1.0 - ONE_SIGMA).powf(z);
            assert!((c - laplace).abs() < 0.015, "z {z}: {c} against {laplace}");
        }
        // Uncalibrated, the too-wide deviation covers more than that.
        let raw = coverage_curve(&[rows], false);
        assert!(raw[3].1 > 0.8, "{raw:?}");
    }
}
