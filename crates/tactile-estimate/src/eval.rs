//! Every estimator of an encoder scored on a labelled dataset: shape
//! accuracy per class with the confusion matrix, and each target's mean
//! absolute error overall and per shape (angles the short way round).

use tactile_core::dataset::Dataset;

use crate::Result;
use crate::registry::{Column, Estimator, Estimators};
use crate::target::Target;

/// A number of frames and a score over them.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Group {
    /// The class or shape.
    pub name: String,
    /// Frames in it.
    pub frames: usize,
    /// The score over them.
    pub value: f64,
}

/// One regression target's mean absolute error, overall and per shape.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TargetScore {
    /// The target's column.
    pub target: String,
    /// Mean absolute error over every labelled frame.
    pub mae: f64,
    /// Labelled frames.
    pub frames: usize,
    /// The error per shape.
    pub per_shape: Vec<Group>,
    /// With uncertainty, how well its deviations hold on these frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coverage: Option<Coverage>,
}

/// The fraction of the scored frames whose error lies inside the model's
/// ±1 and ±1.96 standard deviation intervals: 68.3 % and 95 % when its
/// deviations are calibrated for frames like these (a Laplace-like error
/// gives nearer 90 % for the second).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Coverage {
    /// Inside ±1 deviation.
    pub within_1_std: f64,
    /// Inside ±1.96 deviations.
    pub within_1_96_std: f64,
}

/// Every estimator's score on one set of frames.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Scores {
    /// Frames scored.
    pub frames: usize,
    /// Shape accuracy and per-class accuracy, when there is a classifier.
    pub accuracy: Option<f64>,
    /// Accuracy per true class.
    pub per_class: Vec<Group>,
    /// `confusion[truth][predicted]` over the classifier's classes.
    pub confusion: Vec<Vec<usize>>,
    /// The classifier's classes.
    pub classes: Vec<String>,
    /// Labelled frames whose shape the classifier does not know, per such
    /// shape: they count as wrong and the confusion matrix leaves them out
    /// (a head trained on other shapes than the frames show).
    pub unknown_shapes: Vec<Group>,
    /// Every regressor target's errors.
    pub targets: Vec<TargetScore>,
    /// Contact position scored only where a frame shows it, when the
    /// estimators predict both `x_mm` and `y_mm`.
    pub position: Option<PositionScore>,
    /// Set when the model's notes say it trained on every frame scored
    /// (`tactile_burn::artifact::scored_on_fitted`): the words saying these are
    /// not held-out scores, for the front ends to show.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
    /// What the frames themselves suggest, as `predict` says it: frames
    /// smaller than the model's crop, blank ones, ones unlike its training
    /// frames (of another sensor?), which may explain large errors.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frame_warnings: Vec<String>,
}

/// Shallowest contact whose position is scored, mm: at zero depth the
/// object only touches, no pin moves, and nothing shows where it is.
pub const OBSERVABLE_DEPTH_MM: f64 = 0.5;

/// Contact position scored only where a frame can show it
/// (`sensors.md` section 1): a sphere's and a cuboid's x and y (and the
/// cuboid's offset across its long side, which often outreaches the
/// contact); for
/// cylinders and prisms only the offset across their axis (their position
/// along it changes nothing in the frame); for an edge its signed distance
/// along the normal (the `x_mm` label itself); nothing for a flat. Frames
/// shallower than [`OBSERVABLE_DEPTH_MM`] are left out.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PositionScore {
    /// One row per shape with an observable position.
    pub per_shape: Vec<PositionGroup>,
    /// Frames left out as too shallow.
    pub shallow: usize,
}

/// The observable position error of one shape.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PositionGroup {
    /// The shape.
    pub name: String,
    /// Frames scored.
    pub frames: usize,
    /// Mean absolute x and y errors, mm (spheres and cuboids).
    pub xy_mm: Option<[f64; 2]>,
    /// Mean absolute error across the axis (cylinders, prisms, cuboids) or
    /// along the edge's normal, mm.
    pub across_mm: Option<f64>,
}

/// What of the position a shape's frame shows.
enum Observable {
    /// x and y.
    Point,
    /// The offset across an axis along theta.
    Across,
    /// The signed distance along the normal: the `x_mm` label.
    EdgeDistance,
}

fn observable(shape: &str) -> Option<Observable> {
    match shape {
        "sphere" | "cuboid" => Some(Observable::Point),
        "cylinderR4" | "cylinderR8" | "prism" => Some(Observable::Across),
        "edge" => Some(Observable::EdgeDistance),
        _ => None,
    }
}

/// [`PositionScore`] of predicted `x` and `y` (mm, one per row of `ds`).
pub fn position_score(x: &[f64], y: &[f64], ds: &Dataset) -> Result<PositionScore> {
    let mut groups: Vec<(String, Vec<[f64; 3]>)> = Vec::new();
    let mut shallow = 0;
    for i in 0..ds.len().min(x.len()).min(y.len()) {
        let Some(shape) = ds.text_opt(i, "shape") else {
            continue;
        };
        let Some(kind) = observable(shape) else {
            continue;
        };
        let (Some(tx), Some(ty), Some(depth)) = (
            ds.target_opt(i, "x_mm")?,
            ds.target_opt(i, "y_mm")?,
            ds.number_opt(i, "depth_mm")?,
        ) else {
            continue;
        };
        if depth < OBSERVABLE_DEPTH_MM {
            shallow += 1;
            continue;
        }
        let (dx, dy) = (x[i] - tx, y[i] - ty);
        // Across the axis along theta: the component along n = (-sin, cos).
        let theta = ds.target_opt(i, "theta_deg")?;
        let across = theta.map_or(f64::NAN, |t| {
            let (s, c) = t.to_radians().sin_cos();
            (-s * dx + c * dy).abs()
        });
        let err = match kind {
            Observable::Point => [dx.abs(), dy.abs(), across],
            Observable::EdgeDistance => [f64::NAN, f64::NAN, dx.abs()],
            Observable::Across if across.is_finite() => [f64::NAN, f64::NAN, across],
            Observable::Across => continue,
        };
        match groups.iter_mut().find(|(n, _)| n == shape) {
            Some((_, v)) => v.push(err),
            None => groups.push((shape.to_string(), vec![err])),
        }
    }
    groups.sort_by(|a, b| a.0.cmp(&b.0));
    let per_shape = groups
        .into_iter()
        .map(|(name, errs)| {
            let mean = |k: usize| {
                let v: Vec<f64> = errs
                    .iter()
                    .map(|e| e[k])
                    .filter(|e| e.is_finite())
                    .collect();
                (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
            };
            PositionGroup {
                name,
                frames: errs.len(),
                xy_mm: mean(0).zip(mean(1)).map(|(a, b)| [a, b]),
                across_mm: mean(2),
            }
        })
        .collect();
    Ok(PositionScore { per_shape, shallow })
}

/// Score every estimator on `feats`, row `i` labelled by row `i` of `ds`.
/// Frames whose label of a target is empty (theta of a sphere) are left
/// out of that target; a shape the classifier does not know counts as wrong.
pub fn score(estimators: &Estimators, feats: &[Vec<f32>], ds: &Dataset) -> Result<Scores> {
    let (shapes, kinds) = shapes_of(ds);
    let mut out = Scores::of(feats.len());

    for (_, e) in &estimators.items {
        match e {
            Estimator::Classifier(h) => {
                let pred = h.predict(feats)?;
                let classes = h.classes();
                let truth: Vec<Option<usize>> = shapes
                    .iter()
                    .map(|s| s.and_then(|s| classes.iter().position(|c| c == s)))
                    .collect();
                let labelled: Vec<usize> =
                    (0..feats.len()).filter(|&i| shapes[i].is_some()).collect();
                if labelled.is_empty() {
                    return Err(tactile_core::Error::dataset(
                        ds.labels_path(),
                        None,
                        "no `shape` labels to score the classifier on",
                    )
                    .into());
                }
                let right =
                    |rows: &[usize]| rows.iter().filter(|&&i| truth[i] == Some(pred[i])).count();
                out.accuracy = Some(right(&labelled) as f64 / labelled.len() as f64);
                out.per_class = kinds
                    .iter()
                    .map(|k| {
                        let rows: Vec<usize> = labelled
                            .iter()
                            .copied()
                            .filter(|&i| shapes[i] == Some(k))
                            .collect();
                        Group {
                            name: k.to_string(),
                            frames: rows.len(),
                            value: right(&rows) as f64 / rows.len().max(1) as f64,
                        }
                    })
                    .collect();
                let mut confusion = vec![vec![0usize; classes.len()]; classes.len()];
                for &i in &labelled {
                    if let Some(t) = truth[i] {
                        confusion[t][pred[i]] += 1;
                    }
                }
                out.confusion = confusion;
                out.classes = classes.to_vec();
                out.unknown_shapes = out
                    .per_class
                    .iter()
                    .filter(|g| !classes.iter().any(|c| c == &g.name))
                    .map(|g| Group {
                        value: 0.0,
                        ..g.clone()
                    })
                    .collect();
            }
            Estimator::Regressor(r) => {
                let (pred, std) = r.predict_with_std(feats)?;
                let only = &r.artifact().shapes;
                let given = Given {
                    pred: &pred,
                    std: std.as_deref(),
                };
                out.targets.extend(target_scores(
                    r.targets(),
                    given,
                    only,
                    &shapes,
                    &kinds,
                    ds,
                )?);
            }
        }
    }
    // Position as the estimators answer together (a specialised
    // regressor where the head puts a frame in its shapes).
    let est = estimators.estimate(feats)?;
    if let (Some(Column::Number(x)), Some(Column::Number(y))) = (est.get("x_mm"), est.get("y_mm")) {
        let p = position_score(x, y, ds)?;
        out.position = (!p.per_shape.is_empty()).then_some(p);
    }
    Ok(out)
}

/// Each row's `shape` label, and the shapes there are, sorted.
fn shapes_of(ds: &Dataset) -> (Vec<Option<&str>>, Vec<&str>) {
    let shapes: Vec<Option<&str>> = (0..ds.len()).map(|i| ds.text_opt(i, "shape")).collect();
    let mut kinds: Vec<&str> = shapes.iter().flatten().copied().collect();
    kinds.sort_unstable();
    kinds.dedup();
    (shapes, kinds)
}

/// A model's estimates of a dataset's rows: `pred[i][j]` estimates target
/// `j` of row `i`, `std[i][j]` its standard deviation when it gives one.
#[derive(Clone, Copy)]
pub struct Given<'a> {
    /// The estimates.
    pub pred: &'a [Vec<f64>],
    /// Their standard deviations, with uncertainty.
    pub std: Option<&'a [Vec<f64>]>,
}

/// Each of `targets` scored on the estimates `given` of the rows of `ds`,
/// over the frames of the shapes `only` (every frame when empty) whose
/// label is not empty; overall and per shape of `kinds`, and with
/// deviations their intervals' coverage. A target with no labelled frame
/// is refused, unless `only` names shapes the set does not hold (nothing
/// to score: left out).
fn target_scores(
    targets: &[Target],
    given: Given<'_>,
    only: &[String],
    shapes: &[Option<&str>],
    kinds: &[&str],
    ds: &Dataset,
) -> Result<Vec<TargetScore>> {
    let mine = |i: usize| only.is_empty() || shapes[i].is_some_and(|s| only.iter().any(|k| k == s));
    let pred = given.pred;
    let mut out = Vec::new();
    for (j, t) in targets.iter().enumerate() {
        let truth = (0..ds.len())
            .map(|i| ds.target_opt(i, &t.name))
            .collect::<Result<Vec<_>, _>>()?;
        let mae_of = |rows: &mut dyn Iterator<Item = usize>| {
            let (mut sum, mut n) = (0.0, 0usize);
            for i in rows.filter(|&i| mine(i)) {
                if let Some(v) = truth[i] {
                    sum += t.error(pred[i][j], v);
                    n += 1;
                }
            }
            (if n > 0 { sum / n as f64 } else { f64::NAN }, n)
        };
        let (mae, frames) = mae_of(&mut (0..pred.len()));
        // A specialised regressor on a set without its shapes has nothing
        // to score; a general one, an empty column.
        if frames == 0 && !only.is_empty() {
            continue;
        }
        if frames == 0 {
            let why = match ds.columns.contains(&t.name) {
                true => format!("column '{}' is empty on every frame", t.name),
                false => format!(
                    "no column '{}', a target the model estimates, to score it against (its columns: {})",
                    t.name,
                    ds.columns.join(", ")
                ),
            };
            return Err(tactile_core::Error::dataset(ds.labels_path(), None, why).into());
        }
        let per_shape = kinds
            .iter()
            .filter_map(|k| {
                let (value, frames) =
                    mae_of(&mut (0..pred.len()).filter(|&i| shapes[i] == Some(k)));
                (frames > 0).then(|| Group {
                    name: k.to_string(),
                    frames,
                    value,
                })
            })
            .collect();
        // Errors (angles the short way round) and deviations of the scored
        // frames, one column.
        let coverage = given.std.map(|std| {
            let (errors, stds): (Vec<Vec<f64>>, Vec<Vec<f64>>) = (0..pred.len())
                .filter(|&i| mine(i))
                .filter_map(|i| truth[i].map(|v| (vec![t.error(pred[i][j], v)], vec![std[i][j]])))
                .unzip();
            let within = |z: f64| crate::uncertainty::coverage(&errors, &stds, z)[0];
            Coverage {
                within_1_std: within(1.0),
                within_1_96_std: within(crate::uncertainty::Z95),
            }
        });
        out.push(TargetScore {
            target: match only.is_empty() {
                true => t.name.clone(),
                false => format!("{} ({})", t.name, only.join(", ")),
            },
            mae,
            frames,
            per_shape,
            coverage,
        });
    }
    Ok(out)
}

/// A network that gives its targets itself (a pose network), scored as an
/// encoder's regressors are: `given` holds one estimate per target for each
/// row of `ds`; each target's error overall and per shape (with deviations,
/// their coverage), and the contact position where it estimates both
/// `x_mm` and `y_mm`.
pub fn score_targets(targets: &[Target], given: Given<'_>, ds: &Dataset) -> Result<Scores> {
    // One row of one value per target for each row of `ds`.
    let fits =
        |rows: &[Vec<f64>]| rows.len() == ds.len() && rows.iter().all(|r| r.len() == targets.len());
    if !fits(given.pred) || given.std.is_some_and(|s| !fits(s)) {
        return Err(tactile_core::Error::shape(
            "estimates to score",
            format!("{} rows of {} values", ds.len(), targets.len()),
            format!("{} rows", given.pred.len()),
        )
        .into());
    }
    let (shapes, kinds) = shapes_of(ds);
    let values = given.pred;
    let mut out = Scores::of(values.len());
    out.targets = target_scores(targets, given, &[], &shapes, &kinds, ds)?;
    let column = |name: &str| {
        let j = targets.iter().position(|t| t.name == name)?;
        Some(values.iter().map(|v| v[j]).collect::<Vec<f64>>())
    };
    if let (Some(x), Some(y)) = (column("x_mm"), column("y_mm")) {
        let p = position_score(&x, &y, ds)?;
        out.position = (!p.per_shape.is_empty()).then_some(p);
    }
    Ok(out)
}

impl Scores {
    /// Every warning the front ends show, each starting "warning: ": those
    /// of the frames, then that the model trained on them.
    pub fn warnings(&self) -> Vec<String> {
        tactile_core::io::scoring_warnings(&self.frame_warnings, &self.warning)
    }

    /// No score yet, over `frames` frames.
    fn of(frames: usize) -> Self {
        Self {
            frames,
            accuracy: None,
            per_class: Vec::new(),
            confusion: Vec::new(),
            classes: Vec::new(),
            unknown_shapes: Vec::new(),
            targets: Vec::new(),
            position: None,
            warning: None,
            frame_warnings: Vec::new(),
        }
    }
}

impl Scores {
    /// What to tell a reader when some frames are of shapes the
    /// classifier does not know.
    pub fn unknown_shapes_note(&self) -> Option<String> {
        if self.unknown_shapes.is_empty() {
            return None;
        }
        let frames: usize = self.unknown_shapes.iter().map(|g| g.frames).sum();
        let names: Vec<&str> = self
            .unknown_shapes
            .iter()
            .map(|g| g.name.as_str())
            .collect();
        Some(format!(
            "{frames} of these frames are of shapes the classifier does not know ({}): they count as wrong, and the confusion matrix leaves them out. It knows {}.",
            names.join(", "),
            self.classes.join(", ")
        ))
    }
}

/// Markdown: accuracy per class with the confusion matrix, then the
/// targets' errors per shape.
pub fn scores_markdown(s: &Scores) -> String {
    let mut md = String::new();
    if let Some(acc) = s.accuracy {
        md.push_str(&format!(
            "Shape accuracy {:.1} % over {} frames (chance {:.1} %).\n\n| shape | frames | accuracy |\n|---|---|---|\n",
            100.0 * acc,
            s.frames,
            100.0 / s.classes.len().max(1) as f64
        ));
        for g in &s.per_class {
            md.push_str(&format!(
                "| {} | {} | {:.1} % |\n",
                g.name,
                g.frames,
                100.0 * g.value
            ));
        }
        if let Some(note) = s.unknown_shapes_note() {
            md.push_str(&format!("\n{note}\n"));
        }
        md.push_str("\nConfusion (rows: true shape, columns: predicted):\n\n| | ");
        md.push_str(&s.classes.join(" | "));
        md.push_str(" |\n|---|");
        md.push_str(&"---|".repeat(s.classes.len()));
        md.push('\n');
        for (c, row) in s.classes.iter().zip(&s.confusion) {
            let cells: Vec<String> = row.iter().map(usize::to_string).collect();
            md.push_str(&format!("| {c} | {} |\n", cells.join(" | ")));
        }
        md.push('\n');
    }
    if !s.targets.is_empty() {
        let mut shapes: Vec<&str> = s
            .targets
            .iter()
            .flat_map(|t| t.per_shape.iter().map(|g| g.name.as_str()))
            .collect();
        shapes.sort_unstable();
        shapes.dedup();
        md.push_str("Mean absolute error per target (angles the short way round), overall and per shape:\n\n| shape |");
        for t in &s.targets {
            md.push_str(&format!(" {} |", t.target));
        }
        md.push_str("\n|---|");
        md.push_str(&"---|".repeat(s.targets.len()));
        md.push_str("\n| **all** |");
        for t in &s.targets {
            md.push_str(&format!(" **{:.3}** ({}) |", t.mae, t.frames));
        }
        md.push('\n');
        for k in shapes {
            md.push_str(&format!("| {k} |"));
            for t in &s.targets {
                match t.per_shape.iter().find(|g| g.name == k) {
                    Some(g) => md.push_str(&format!(" {:.3} |", g.value)),
                    None => md.push_str(" - |"),
                }
            }
            md.push('\n');
        }
        md.push('\n');
        let covered: Vec<(&TargetScore, Coverage)> = s
            .targets
            .iter()
            .filter_map(|t| t.coverage.map(|c| (t, c)))
            .collect();
        if !covered.is_empty() {
            md.push_str("Frames whose error lies inside the estimate's ±1 and ±1.96 standard deviations (68.3 % and 95 % when the deviations are calibrated for frames like these; an error with heavier tails than a normal's gives nearer 90 % for the second):\n\n| target | ±1 deviation | ±1.96 deviations |\n|---|---|---|\n");
            for (t, c) in covered {
                md.push_str(&format!(
                    "| {} | {:.1} % | {:.1} % |\n",
                    t.target,
                    100.0 * c.within_1_std,
                    100.0 * c.within_1_96_std
                ));
            }
            md.push('\n');
        }
    }
    if let Some(p) = &s.position {
        md.push_str(&format!(
            "Contact position where the frame shows it: x and y of spheres and cuboids, the offset across the axis of cylinders, prisms and cuboids, an edge's distance along its normal; frames shallower than {OBSERVABLE_DEPTH_MM} mm left out ({} frames). Mean absolute error, mm:\n\n| shape | frames | x | y | across |\n|---|---|---|---|---|\n",
            p.shallow
        ));
        let cell = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
        for g in &p.per_shape {
            md.push_str(&format!(
                "| {} | {} | {} | {} | {} |\n",
                g.name,
                g.frames,
                cell(g.xy_mm.map(|v| v[0])),
                cell(g.xy_mm.map(|v| v[1])),
                cell(g.across_mm)
            ));
        }
        md.push('\n');
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A TacTip dataset of labels alone (the frames are empty files).
    fn labels(rows: &[&str]) -> (tempfile::TempDir, Dataset) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("manifest.json"),
            r#"{"format": "tactile-dataset/1", "kind": "tactip", "sensor_spec": "virtual-tactip/1", "width": 300, "height": 300, "generator": "test", "seed": 0, "count": 5}"#,
        )
        .unwrap();
        std::fs::create_dir(dir.path().join("frames")).unwrap();
        let mut csv = String::from("file,shape,x_mm,y_mm,theta_deg,depth_mm,force_n\n");
        for (i, r) in rows.iter().enumerate() {
            std::fs::write(dir.path().join(format!("frames/{i}.png")), b"").unwrap();
            csv.push_str(&format!("frames/{i}.png,{r}\n"));
        }
        std::fs::write(dir.path().join("labels.csv"), csv).unwrap();
        let ds = Dataset::open(dir.path()).unwrap();
        (dir, ds)
    }

    #[test]
    fn position_is_scored_only_where_the_frame_shows_it() {
        let (_dir, ds) = labels(&[
            "sphere,1.0,2.0,,3.0,1.0",
            // Along a cylinder's axis (theta 0: the x axis) nothing shows.
            "cylinderR4,0.0,1.0,0.0,2.0,1.0",
            // An edge's x is its distance along the normal.
            "edge,1.5,0.0,90.0,2.0,1.0",
            "flat,0.0,0.0,,2.0,1.0",
            // Too shallow to move a pin.
            "sphere,0.0,0.0,,0.1,0.0",
        ]);
        // Predictions: sphere off by (0.2, -0.1); cylinder off by 5 mm along
        // its axis and 0.3 across; edge off by 0.4; the rest wildly wrong.
        let x = [1.2, 5.0, 1.9, 9.0, 9.0];
        let y = [1.9, 1.3, 7.0, 9.0, 9.0];
        let p = position_score(&x, &y, &ds).unwrap();
        assert_eq!(p.shallow, 1);
        let by = |n: &str| p.per_shape.iter().find(|g| g.name == n).unwrap();
        let sphere = by("sphere").xy_mm.unwrap();
        assert!((sphere[0] - 0.2).abs() < 1e-9 && (sphere[1] - 0.1).abs() < 1e-9);
        assert!((by("cylinderR4").across_mm.unwrap() - 0.3).abs() < 1e-9);
        assert!(by("cylinderR4").xy_mm.is_none());
        assert!((by("edge").across_mm.unwrap() - 0.4).abs() < 1e-9);
        assert!(p.per_shape.iter().all(|g| g.name != "flat"));
    }

    #[test]
    fn a_network_giving_its_targets_is_scored_as_regressors_are() {
        let (_dir, ds) = labels(&[
            "edge,1.0,,170.0,2.0,1.0",
            "edge,2.0,,-170.0,2.0,1.0",
            "sphere,3.0,,,2.0,1.0",
            "sphere,4.0,,,2.0,1.0",
            // Unlabelled: left out of both.
            "flat,,,,2.0,1.0",
        ]);
        let targets = [Target::linear("x_mm"), Target::angle("theta_deg", 360.0)];
        // x off by 0.1, 0.3, 0.5, 2.0; theta off by 20 deg the short way
        // round across ±180, on the edges alone (the spheres' is empty).
        let pred = vec![
            vec![1.1, -170.0],
            vec![2.3, 170.0],
            vec![3.5, 0.0],
            vec![2.0, 0.0],
            vec![9.0, 9.0],
        ];
        let std = vec![
            vec![0.2, 30.0],
            vec![0.2, 10.0],
            vec![0.2, 1.0],
            vec![1.1, 1.0],
            vec![1.0, 1.0],
        ];
        let given = Given {
            pred: &pred,
            std: Some(&std),
        };
        let s = score_targets(&targets, given, &ds).unwrap();
        let (x, theta) = (&s.targets[0], &s.targets[1]);
        assert!((x.mae - 0.725).abs() < 1e-9 && x.frames == 4, "{x:?}");
        assert!(
            (theta.mae - 20.0).abs() < 1e-9 && theta.frames == 2,
            "{theta:?}"
        );
        let sphere = x.per_shape.iter().find(|g| g.name == "sphere").unwrap();
        assert!((sphere.value - 1.25).abs() < 1e-9);
        // Inside ±1: x's first (0.1 <= 0.2); inside ±1.96 (0.392, 2.156):
        // its second and last too. Theta's first in both (20 <= 30), its
        // second in neither (20 > 19.6).
        let c = x.coverage.unwrap();
        assert!((c.within_1_std - 0.25).abs() < 1e-9 && (c.within_1_96_std - 0.75).abs() < 1e-9);
        let c = theta.coverage.unwrap();
        assert!((c.within_1_std - 0.5).abs() < 1e-9 && (c.within_1_96_std - 0.5).abs() < 1e-9);
        // Without deviations, none; without both x and y, no position.
        let given = Given {
            pred: &pred,
            std: None,
        };
        let s = score_targets(&targets, given, &ds).unwrap();
        assert!(s.targets.iter().all(|t| t.coverage.is_none()) && s.position.is_none());
        // Estimates that do not fit the rows are refused, not indexed past.
        let short = Given {
            pred: &pred[..4],
            std: None,
        };
        assert!(score_targets(&targets, short, &ds).is_err());
        let narrow = Given {
            pred: &pred,
            std: Some(&pred[..3]),
        };
        assert!(score_targets(&targets, narrow, &ds).is_err());
    }
}
