//! Every estimator of an encoder scored on a labelled dataset: shape
//! accuracy per class with the confusion matrix, and each target's mean
//! absolute error overall and per shape (angles the short way round).

use tactile_core::dataset::Dataset;

use crate::Result;
use crate::registry::{Estimator, Estimators};

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
    /// Every regressor target's errors.
    pub targets: Vec<TargetScore>,
}

/// Score every estimator on `feats`, row `i` labelled by row `i` of `ds`.
/// Frames whose label of a target is empty (theta of a sphere) are left
/// out of that target; a shape the classifier does not know counts as wrong.
pub fn score(estimators: &Estimators, feats: &[Vec<f32>], ds: &Dataset) -> Result<Scores> {
    let shapes: Vec<Option<&str>> = (0..ds.len()).map(|i| ds.text_opt(i, "shape")).collect();
    let mut kinds: Vec<&str> = shapes.iter().flatten().copied().collect();
    kinds.sort_unstable();
    kinds.dedup();
    let mut out = Scores {
        frames: feats.len(),
        accuracy: None,
        per_class: Vec::new(),
        confusion: Vec::new(),
        classes: Vec::new(),
        targets: Vec::new(),
    };
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
            }
            Estimator::Regressor(r) => {
                let pred = r.predict(feats)?;
                for (j, t) in r.targets().iter().enumerate() {
                    let truth = (0..ds.len())
                        .map(|i| ds.number_opt(i, &t.name))
                        .collect::<Result<Vec<_>, _>>()?;
                    let mae_of = |rows: &mut dyn Iterator<Item = usize>| {
                        let (mut sum, mut n) = (0.0, 0usize);
                        for i in rows {
                            if let Some(v) = truth[i] {
                                sum += t.error(pred[i][j], v);
                                n += 1;
                            }
                        }
                        (if n > 0 { sum / n as f64 } else { f64::NAN }, n)
                    };
                    let (mae, frames) = mae_of(&mut (0..feats.len()));
                    if frames == 0 {
                        return Err(tactile_core::Error::dataset(
                            ds.labels_path(),
                            None,
                            format!("column '{}' is empty on every frame", t.name),
                        )
                        .into());
                    }
                    let per_shape = kinds
                        .iter()
                        .filter_map(|k| {
                            let (value, frames) =
                                mae_of(&mut (0..feats.len()).filter(|&i| shapes[i] == Some(k)));
                            (frames > 0).then(|| Group {
                                name: k.to_string(),
                                frames,
                                value,
                            })
                        })
                        .collect();
                    out.targets.push(TargetScore {
                        target: t.name.clone(),
                        mae,
                        frames,
                        per_shape,
                    });
                }
            }
        }
    }
    Ok(out)
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
    }
    md
}
