//! The estimators of an encoder folder: every sub-folder holding a
//! classifier head (`head.json`) or a regressor (`regressor.json`), run on
//! one encoding per frame (paper A's simultaneous deployment).

use std::path::{Path, PathBuf};

use burn::tensor::Device;
use tactile_burn::Artifact;

use crate::ensemble::RegressorEnsemble;
use crate::head::{ClassifierHead, HeadArtifact};
use crate::{Error, Result};

/// A trained estimator on an encoder's features.
pub enum Estimator {
    /// A shape classifier.
    Classifier(Box<ClassifierHead>),
    /// A regressor of one or more targets, or an ensemble of them.
    Regressor(RegressorEnsemble),
}

/// The name of a classifier's output column.
pub const CLASS_COLUMN: &str = "shape";

impl Estimator {
    /// True when `dir` holds an estimator.
    pub fn is_in(dir: &Path) -> bool {
        HeadArtifact::is_in(dir) || RegressorEnsemble::is_in(dir)
    }

    /// Load the estimator in `dir`.
    pub fn load(dir: &Path, device: &Device) -> Result<Self> {
        if HeadArtifact::is_in(dir) {
            Ok(Self::Classifier(Box::new(ClassifierHead::load(
                dir, device,
            )?)))
        } else if RegressorEnsemble::is_in(dir) {
            Ok(Self::Regressor(RegressorEnsemble::load(dir, device)?))
        } else {
            // An ensemble.json of another kind (a detector's) is named as
            // a model of another kind, not said to be absent.
            let hint =
                tactile_burn::artifact::folder_hint(dir, Self::is_in, "a model of another kind");
            Err(tactile_core::Error::wrong_kind(
                dir,
                "estimator folder",
                format!("no head.json, regressor.json or ensemble of regressors{hint}"),
            )
            .into())
        }
    }

    /// Feature count it takes.
    pub fn inputs(&self) -> usize {
        match self {
            Self::Classifier(h) => h.artifact.model.inputs,
            Self::Regressor(r) => r.artifact().model.inputs,
        }
    }

    /// Fingerprint of the encoder it was trained on, when recorded.
    pub fn encoder(&self) -> Option<&str> {
        match self {
            Self::Classifier(h) => h.artifact.encoder.as_deref(),
            Self::Regressor(r) => r.artifact().encoder.as_deref(),
        }
    }

    /// Its weights and biases (an ensemble's summed).
    pub fn parameters(&self) -> usize {
        use burn::module::Module;
        match self {
            Self::Classifier(h) => h.net.num_params(),
            Self::Regressor(r) => r.members().iter().map(|m| m.mlp.num_params()).sum(),
        }
    }

    /// Names of its output columns.
    pub fn columns(&self) -> Vec<String> {
        match self {
            Self::Classifier(_) => vec![CLASS_COLUMN.to_string()],
            Self::Regressor(r) => {
                let names = r.targets().iter().map(|t| t.name.clone());
                let std = r
                    .targets()
                    .iter()
                    .filter(|_| r.has_uncertainty())
                    .map(|t| std_column(&t.name));
                names.chain(std).collect()
            }
        }
    }
}

/// The name of the column of a target's standard deviation.
pub fn std_column(target: &str) -> String {
    format!("{target}_std")
}

/// A regressor's columns on `feats`: each target's values, then with
/// uncertainty each one's standard deviation ([`std_column`]).
fn regressor_columns(r: &RegressorEnsemble, feats: &[Vec<f32>]) -> Result<Vec<(String, Vec<f64>)>> {
    let (values, std) = r.predict_with_std(feats)?;
    let column = |rows: &[Vec<f64>], j: usize| rows.iter().map(|row| row[j]).collect();
    let mut out: Vec<(String, Vec<f64>)> = r
        .targets()
        .iter()
        .enumerate()
        .map(|(j, t)| (t.name.clone(), column(&values, j)))
        .collect();
    if let Some(std) = &std {
        out.extend(
            r.targets()
                .iter()
                .enumerate()
                .map(|(j, t)| (std_column(&t.name), column(std, j))),
        );
    }
    Ok(out)
}

/// Values of one output column, one per frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    /// Class names.
    Class(Vec<String>),
    /// Numbers in the label's own units.
    Number(Vec<f64>),
}

/// Every estimator's outputs for a set of feature vectors.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Estimates {
    /// `(name, values)`, in estimator order.
    pub columns: Vec<(String, Column)>,
}

impl Estimates {
    /// The column called `name`.
    pub fn get(&self, name: &str) -> Option<&Column> {
        self.columns.iter().find(|c| c.0 == name).map(|c| &c.1)
    }

    /// Append the rows of `more`, a later batch of frames through the same
    /// estimators (its columns the same, in the same order); the first
    /// batch appended to an empty `Estimates` gives its columns.
    pub fn append(&mut self, more: Estimates) -> crate::Result<()> {
        if self.columns.is_empty() {
            *self = more;
            return Ok(());
        }
        let names = |e: &Estimates| e.columns.iter().map(|c| c.0.clone()).collect::<Vec<_>>();
        if names(self) != names(&more) {
            return Err(tactile_core::Error::Invalid(format!(
                "estimates of columns {:?} cannot follow columns {:?}",
                names(&more),
                names(self)
            ))
            .into());
        }
        for ((name, to), (_, from)) in self.columns.iter_mut().zip(more.columns) {
            match (to, from) {
                (Column::Class(a), Column::Class(b)) => a.extend(b),
                (Column::Number(a), Column::Number(b)) => a.extend(b),
                _ => {
                    return Err(tactile_core::Error::Invalid(format!(
                        "estimate column '{name}' is a class in one batch and a number in another"
                    ))
                    .into());
                }
            }
        }
        Ok(())
    }

    /// Cell `i` of every column as text (numbers with 4 decimals).
    pub fn row(&self, i: usize) -> Vec<String> {
        self.columns
            .iter()
            .map(|(_, c)| match c {
                Column::Class(v) => v[i].clone(),
                Column::Number(v) => format!("{:.4}", v[i]),
            })
            .collect()
    }
}

/// Several estimators over one feature space.
pub struct Estimators {
    /// Folder and estimator, in name order.
    pub items: Vec<(PathBuf, Estimator)>,
}

impl Estimators {
    /// The estimators in `dirs`, or, when `dirs` is empty, every estimator
    /// folder inside `encoder` (in name order).
    pub fn load(encoder: &Path, dirs: &[PathBuf], device: &Device) -> Result<Self> {
        let mut dirs = dirs.to_vec();
        if dirs.is_empty()
            && let Ok(entries) = std::fs::read_dir(encoder)
        {
            dirs = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|d| Estimator::is_in(d))
                .collect();
            dirs.sort();
        }
        if dirs.is_empty() {
            return Err(Error::NoEstimators(format!(
                "{} has no folder with head.json, regressor.json or ensemble.json; name estimator folders explicitly",
                encoder.display()
            )));
        }
        let items = dirs
            .into_iter()
            .map(|d| Ok((d.clone(), Estimator::load(&d, device)?)))
            .collect::<Result<_>>()?;
        Ok(Self { items })
    }

    /// How many there are.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Their weights and biases, summed.
    pub fn parameters(&self) -> usize {
        self.items.iter().map(|(_, e)| e.parameters()).sum()
    }

    /// Where the first regressor with a calibrated uncertainty was
    /// calibrated on frames it never fitted (see
    /// [`RegressorEnsemble::calibration`]).
    pub fn calibration(&self) -> Option<&serde_json::Value> {
        self.items.iter().find_map(|(_, e)| match e {
            Estimator::Regressor(r) => r.calibration(),
            Estimator::Classifier(_) => None,
        })
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Refuse estimators trained on another encoder than the one whose
    /// fingerprint is `encoder` (when they record one), or on features of
    /// another length than its `features`, naming the estimator's folder.
    pub fn check_encoder(&self, encoder: &str, features: usize) -> Result<()> {
        for (dir, e) in &self.items {
            if let Some(fp) = e.encoder()
                && fp != encoder
            {
                return Err(tactile_core::Error::model(
                    dir,
                    "this estimator was trained on another encoder's features (its encoder fingerprint differs): retrain it on this encoder",
                )
                .into());
            }
            if e.inputs() != features {
                return Err(tactile_core::Error::model(
                    dir,
                    format!(
                        "this estimator takes {} features, the encoder gives {features}: it was trained on another encoder",
                        e.inputs()
                    ),
                )
                .into());
            }
        }
        Ok(())
    }

    /// Every estimator on the same feature vectors.
    pub fn estimate(&self, feats: &[Vec<f32>]) -> Result<Estimates> {
        let mut columns = Vec::new();
        let mut specialised = Vec::new();
        for (_, e) in &self.items {
            match e {
                Estimator::Classifier(h) => {
                    let p = h.predict(feats)?;
                    let names = p.iter().map(|&c| h.classes()[c].clone()).collect();
                    columns.push((CLASS_COLUMN.to_string(), Column::Class(names)));
                }
                Estimator::Regressor(r) if !r.artifact().shapes.is_empty() => specialised.push(r),
                Estimator::Regressor(r) => columns.extend(
                    regressor_columns(r, feats)?
                        .into_iter()
                        .map(|(name, v)| (name, Column::Number(v))),
                ),
            }
        }
        // A regressor trained on some shapes answers for the frames the
        // shape head puts in them (every frame without a head), replacing
        // a general regressor's value of the same column there.
        let shapes = match columns.iter().find(|c| c.0 == CLASS_COLUMN) {
            Some((_, Column::Class(names))) => Some(names.clone()),
            _ => None,
        };
        for r in specialised {
            let applies = |i: usize| {
                shapes
                    .as_ref()
                    .is_none_or(|s| r.artifact().shapes.contains(&s[i]))
            };
            for (name, p) in regressor_columns(r, feats)? {
                match columns.iter_mut().find(|c| c.0 == name) {
                    Some((_, Column::Number(v))) => {
                        for (i, x) in v.iter_mut().enumerate() {
                            if applies(i) {
                                *x = p[i];
                            }
                        }
                    }
                    _ => {
                        let v = (0..p.len())
                            .map(|i| if applies(i) { p[i] } else { f64::NAN })
                            .collect();
                        columns.push((name, Column::Number(v)));
                    }
                }
            }
        }
        Ok(Estimates { columns })
    }
}
