//! Train, validation and test rows of a dataset: its `split` column when it
//! has one, else seeded shuffles; palpation videos are split by sequence,
//! never by frame. Every command and the Python package split through these,
//! so one seed means one split everywhere.

use rand::SeedableRng;
use rand::rngs::StdRng;
use rand::seq::SliceRandom;

use super::Dataset;
use crate::{Error, Result};

/// Train, validation and test rows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Splits {
    /// Rows to fit on.
    pub train: Vec<usize>,
    /// Rows for early stopping and choices.
    pub val: Vec<usize>,
    /// Rows to report on.
    pub test: Vec<usize>,
}

/// The seed of the split every comparison, sweep and held-out test uses
/// unless told otherwise: one seed means one split everywhere.
pub const DEFAULT_SPLIT_SEED: u64 = 7;

/// The test rows a later evaluation holds out (a `compare` or `train
/// regressor` with this test fraction and seed), so an encoder trained
/// before it never sees them.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TestHoldout {
    /// Fraction of the frames held out for testing.
    pub test_fraction: f64,
    /// Seed of that split.
    pub split_seed: u64,
}

impl TestHoldout {
    /// The holdout an `exclude_test` fraction and its `split_seed` ask for:
    /// none without a fraction.
    pub fn excluding(test_fraction: Option<f64>, split_seed: u64) -> Option<Self> {
        test_fraction.map(|test_fraction| Self {
            test_fraction,
            split_seed,
        })
    }
}

fn check_fraction(name: &str, f: f64) -> Result<()> {
    if f > 0.0 && f < 1.0 {
        Ok(())
    } else {
        Err(Error::Config(format!(
            "{name} must be in (0, 1), got {f:?}"
        )))
    }
}

/// Check a validation fraction (`--val-fraction`) is in `[0, 1)`, so a
/// trainer can refuse it before preprocessing a single frame.
pub fn check_val_fraction(val_fraction: f64) -> Result<()> {
    if (0.0..1.0).contains(&val_fraction) {
        Ok(())
    } else {
        Err(Error::Config(format!(
            "validation fraction must be in [0, 1), got {val_fraction:?}"
        )))
    }
}

/// Check a trainer is not asked both to fit every row (`every_split`,
/// the final model) and to leave test rows out (`exclude_test`): it would
/// fit the rows it then scores as never trained on.
pub fn check_every_split(every_split: bool, holdout: Option<TestHoldout>) -> Result<()> {
    if every_split && holdout.is_some() {
        return Err(Error::Config(
            "every_split trains on the test frames that exclude_test leaves out: give one".into(),
        ));
    }
    Ok(())
}

/// Shuffle `rows` with `seed` and hold out the last `val_fraction` of them
/// (at least one, and at least one left): `(train, validation)`.
pub fn hold_out(
    mut rows: Vec<usize>,
    val_fraction: f64,
    seed: u64,
) -> Result<(Vec<usize>, Vec<usize>)> {
    check_val_fraction(val_fraction)?;
    if rows.len() < 2 {
        return Err(Error::Invalid(format!(
            "need at least 2 training frames, found {}",
            rows.len()
        )));
    }
    rows.shuffle(&mut StdRng::seed_from_u64(seed));
    let n_val = ((rows.len() as f64 * val_fraction).round() as usize).clamp(1, rows.len() - 1);
    let val = rows.split_off(rows.len() - n_val);
    Ok((rows, val))
}

/// Rows grouped by the frame they were read from: a frame listed on several
/// rows (or a frame and its turned copies) is split, or put in a fold, as
/// one. For rows that are each their own frame it is the identity, so they
/// are split as before.
#[derive(Debug, Clone)]
pub struct FrameGroups {
    /// One row per frame: the first of its rows, in the order given.
    pub frames: Vec<usize>,
    /// Every row of each frame, in the order given, by its first row.
    rows: std::collections::HashMap<usize, Vec<usize>>,
}

impl FrameGroups {
    /// Group `(row, frame)` pairs by frame (any key naming it, such as
    /// [`Dataset::first_listings`] of the row).
    pub fn new(rows: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let mut by_frame: std::collections::HashMap<usize, Vec<usize>> = Default::default();
        let mut frames = Vec::new();
        for (row, frame) in rows {
            let group = by_frame.entry(frame).or_default();
            if group.is_empty() {
                frames.push(row);
            }
            group.push(row);
        }
        let rows = by_frame.into_values().map(|g| (g[0], g)).collect();
        Self { frames, rows }
    }

    /// Every row of the frame whose first row is `frame` (none for a row
    /// that is no frame's first).
    pub fn rows(&self, frame: usize) -> &[usize] {
        self.rows.get(&frame).map_or(&[], Vec::as_slice)
    }

    /// Every row of `frames` (first rows), frame by frame.
    pub fn rows_of(&self, frames: &[usize]) -> Vec<usize> {
        frames.iter().flat_map(|&f| self.rows(f)).copied().collect()
    }
}

impl Dataset {
    /// Each row's frame file as the filesystem finds it (through `./` and
    /// links inside the folder); `None` where it cannot be resolved.
    pub(crate) fn frame_files(&self) -> Vec<Option<std::path::PathBuf>> {
        let root = self.root.canonicalize().ok();
        (0..self.len())
            .map(|i| {
                let rel = self.text_opt(i, "file")?;
                super::resolve_inside(root.as_deref()?, rel).ok()
            })
            .collect()
    }

    /// The frame files of `rows`, to find frames (or copies of them)
    /// among.
    pub(crate) fn frame_copies(&self, rows: &[usize]) -> super::copies::FrameCopies {
        let files = self.frame_files();
        super::copies::FrameCopies::new(rows.iter().filter_map(|&i| files.get(i)?.clone()))
    }

    /// For each row, the first row that lists the same frame file (itself
    /// when no row before it does): a frame listed twice, as a user
    /// oversampling a class by repeating rows does, is one frame to split
    /// (here, and in the folds of a shape head's ensemble).
    pub fn first_listings(&self) -> Vec<usize> {
        let mut first: std::collections::HashMap<std::path::PathBuf, usize> = Default::default();
        self.frame_files()
            .into_iter()
            .enumerate()
            .map(|(i, file)| {
                // The text as written where the file cannot be resolved.
                let key = file.or_else(|| self.text_opt(i, "file").map(Into::into));
                match key {
                    Some(key) => *first.entry(key).or_insert(i),
                    None => i,
                }
            })
            .collect()
    }

    /// The frame of each of `rows` (its [`Self::first_listings`] row), to
    /// keep a frame's rows together in a model's folds.
    pub fn frame_of_rows(&self, rows: &[usize]) -> Vec<usize> {
        let first = self.first_listings();
        rows.iter().map(|&i| first[i]).collect()
    }

    /// The rows of `other` whose frame is the file of one of `rows` here,
    /// however each dataset names it, or a copy of it (the same bytes, in
    /// another folder or under another name): a test set holding them
    /// would score frames a model fitted.
    pub fn rows_sharing_frames(&self, rows: &[usize], other: &Dataset) -> Vec<usize> {
        let all: Vec<usize> = (0..other.len()).collect();
        self.rows_sharing_frames_among(rows, other, &all)
    }

    /// [`Self::rows_sharing_frames`] of `other`'s `among` rows only (its
    /// test rows, say), reading no other frame of it.
    pub fn rows_sharing_frames_among(
        &self,
        rows: &[usize],
        other: &Dataset,
        among: &[usize],
    ) -> Vec<usize> {
        let mut copies = self.frame_copies(rows);
        let theirs = other.frame_files();
        among
            .iter()
            .copied()
            .filter(|&j| {
                theirs
                    .get(j)
                    .and_then(Option::as_deref)
                    .is_some_and(|f| copies.holds(f))
            })
            .collect()
    }

    /// [`hold_out`] of this dataset's `rows`: too few of them is named by
    /// its labels file; a bad fraction is the flag's error, not the file's.
    /// A frame listed on several rows is one frame: its rows validate or
    /// train together.
    pub fn hold_out(
        &self,
        rows: Vec<usize>,
        val_fraction: f64,
        seed: u64,
    ) -> Result<(Vec<usize>, Vec<usize>)> {
        let too_few = |e: Error| match e {
            Error::Config(_) => e,
            e => Error::dataset(
                self.labels_path(),
                None,
                format!("{e}{}", self.split_hint()),
            ),
        };
        let first = self.first_listings();
        let groups = FrameGroups::new(rows.iter().map(|&i| (i, first[i])));
        let (train, val) = hold_out(groups.frames.clone(), val_fraction, seed).map_err(too_few)?;
        let (train, val) = (groups.rows_of(&train), groups.rows_of(&val));
        Ok((train, val))
    }

    /// `(train, validation, test)` rows: the `split` column's train and
    /// evaluation rows ([`Dataset::evaluation_split`]) when it has both, else a seeded shuffle with
    /// `test_fraction` held out; then `val_fraction` of the training rows
    /// validate.
    pub fn three_way_split(
        &self,
        test_fraction: f64,
        val_fraction: f64,
        seed: u64,
    ) -> Result<Splits> {
        check_fraction("test fraction", test_fraction)?;
        check_fraction("validation fraction", val_fraction)?;
        let mut rng = StdRng::seed_from_u64(seed);
        // A frame listed on several rows is one frame: its rows are fitted,
        // validated or tested together.
        let first = self.first_listings();
        let (train, test) = match (self.split_indices("train"), self.evaluation_split()) {
            (Some(tr), Some(te)) => (tr, te),
            _ => {
                let groups = FrameGroups::new(first.iter().copied().enumerate());
                let mut all = groups.frames.clone();
                all.shuffle(&mut rng);
                let n_test = ((all.len() as f64 * test_fraction).round() as usize).max(1);
                let test = all.split_off(all.len().saturating_sub(n_test));
                (groups.rows_of(&all), groups.rows_of(&test))
            }
        };
        let groups = FrameGroups::new(train.iter().map(|&i| (i, first[i])));
        let mut train = groups.frames.clone();
        train.shuffle(&mut rng);
        let n_val = ((train.len() as f64 * val_fraction).round() as usize).max(1);
        if train.len() <= n_val || test.is_empty() {
            return Err(Error::dataset(
                self.labels_path(),
                None,
                format!(
                    "too few frames ({}) for train, validation and test sets{}",
                    self.len(),
                    self.split_hint()
                ),
            ));
        }
        let val = train.split_off(train.len() - n_val);
        let (train, val) = (groups.rows_of(&train), groups.rows_of(&val));
        Ok(Splits { train, val, test })
    }

    /// The rows a model may train on: the `split` column's `train` rows
    /// when there is one; otherwise every row, less the test rows of
    /// `holdout` when given.
    pub fn training_rows(&self, holdout: Option<TestHoldout>) -> Result<Vec<usize>> {
        Ok(match (self.split_indices("train"), holdout) {
            (Some(train), _) => train,
            (None, Some(h)) => {
                let s = self.three_way_split(h.test_fraction, 0.2, h.split_seed)?;
                let mut rows = [s.train, s.val].concat();
                rows.sort_unstable();
                rows
            }
            (None, None) => (0..self.len()).collect(),
        })
    }

    /// The rows a trainer fits: every row with `every_split` (the final
    /// model, the `split` column's `val` and `test` rows too), else
    /// [`Dataset::training_rows`].
    pub fn rows_to_fit(
        &self,
        every_split: bool,
        holdout: Option<TestHoldout>,
    ) -> Result<Vec<usize>> {
        if every_split {
            Ok((0..self.len()).collect())
        } else {
            self.training_rows(holdout)
        }
    }

    /// Rows of `rows` whose `tendon` label is 1; a dataset of another kind
    /// than visuo-tactile (TacTip frames have no tendon) is named as such.
    pub fn tendon_rows(&self, rows: &[usize]) -> Result<Vec<usize>> {
        self.expect_kind(super::DatasetKind::Visuotactile)?;
        let mut out = Vec::new();
        for &i in rows {
            if self.number(i, "tendon")? == 1.0 {
                out.push(i);
            }
        }
        Ok(out)
    }

    /// `(train, validation)` rows split by the `sequence` column, never by
    /// frame, so no palpation video leaks across the split: the sequences
    /// are shuffled with `seed` and the last `val_fraction` of them (at
    /// least one) validate. Rows with no sequence are each their own group.
    pub fn split_by_sequence(
        &self,
        val_fraction: f64,
        seed: u64,
    ) -> Result<(Vec<usize>, Vec<usize>)> {
        check_fraction("validation fraction", val_fraction)?;
        let mut groups: std::collections::BTreeMap<String, Vec<usize>> = Default::default();
        for (i, first) in self.first_listings().into_iter().enumerate() {
            // A frame listed on several rows without a sequence is one
            // group (named by its first row, as a frame listed once is).
            let key = match self.text_opt(i, "sequence") {
                Some(s) => format!("s{s}"),
                None => format!("f{first}"),
            };
            groups.entry(key).or_default().push(i);
        }
        let mut keys: Vec<&String> = groups.keys().collect();
        if keys.len() < 2 {
            return Err(Error::dataset(
                self.labels_path(),
                None,
                format!(
                    "{} sequence(s): need at least 2 to split by sequence",
                    keys.len()
                ),
            ));
        }
        keys.shuffle(&mut StdRng::seed_from_u64(seed));
        let n_val = ((keys.len() as f64 * val_fraction).round() as usize).clamp(1, keys.len() - 1);
        let (tr, va) = keys.split_at(keys.len() - n_val);
        let rows = |ks: &[&String]| -> Vec<usize> {
            let mut r: Vec<usize> = ks.iter().flat_map(|k| groups[*k].iter().copied()).collect();
            r.sort_unstable();
            r
        };
        Ok((rows(tr), rows(va)))
    }
}
