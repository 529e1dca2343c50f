//! Which frames a model fitted, as its notes record them. Every trainer
//! writes these keys through [`Provenance::notes`] and every reader (a
//! bench asking whether a model saw the frames it scores, a calibration
//! asking whether it fits training errors) reads them through
//! [`Provenance::read`], so the two never drift apart.

use std::path::Path;

use super::{Dataset, TestHoldout};

/// Most distinct datasets whose frames are looked up for one model; a
/// model's notes naming more read as [`Seen::Unknown`] beyond them (a
/// trainer takes a handful: the detector's soft labels, two or three).
pub const MAX_RECORDED_DATASETS: usize = 16;

/// The datasets a model trained on and which of their rows it fitted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Provenance {
    /// The dataset folders as given to the trainer: the first is noted as
    /// `trained_on`, the rest as `also_trained_on`.
    pub datasets: Vec<String>,
    /// It fitted the rows of every split (`val` and `test` too): a final
    /// model, or a trainer that splits by sequence and ignores the column.
    pub every_split: bool,
    /// Without a `split` column: the test rows it left out for a later
    /// evaluation.
    pub excluded_test: Option<TestHoldout>,
}

impl Provenance {
    /// Trained on `datasets` (the first is the main one), their training
    /// rows only until [`Self::every_split`] or [`Self::excluding_test`]
    /// say otherwise.
    pub fn of(datasets: &[&Dataset]) -> Self {
        Self {
            datasets: datasets
                .iter()
                .map(|d| d.root.display().to_string())
                .collect(),
            every_split: false,
            excluded_test: None,
        }
    }

    /// With `every_split`: it fitted every row of every split.
    pub fn every_split(mut self, every_split: bool) -> Self {
        self.every_split = every_split;
        self
    }

    /// It left out the test rows of `holdout`.
    pub fn excluding_test(mut self, holdout: Option<TestHoldout>) -> Self {
        self.excluded_test = holdout;
        self
    }

    /// The notes a trainer saves: these keys, then `extra`'s (an object:
    /// the device, the trainer's own choices).
    pub fn notes(&self, extra: serde_json::Value) -> serde_json::Value {
        let mut notes = serde_json::json!({
            "every_split": self.every_split,
            "excluded_test": self.excluded_test,
        });
        if let Some((main, further)) = self.datasets.split_first() {
            notes["trained_on"] = main.as_str().into();
            if !further.is_empty() {
                notes["also_trained_on"] = further.into();
            }
        }
        if let (Some(n), serde_json::Value::Object(extra)) = (notes.as_object_mut(), extra) {
            n.extend(extra);
        }
        notes
    }

    /// What `notes` record. Notes without these keys (written before a
    /// trainer recorded them) read as no dataset, training rows only.
    pub fn read(notes: &serde_json::Value) -> Self {
        let text = |v: &serde_json::Value| v.as_str().map(str::to_string);
        let further = notes
            .get("also_trained_on")
            .and_then(|v| v.as_array())
            .into_iter()
            .flatten();
        Self {
            datasets: notes
                .get("trained_on")
                .into_iter()
                .chain(further)
                .filter_map(text)
                .collect(),
            every_split: notes.get("every_split").and_then(|v| v.as_bool()) == Some(true),
            excluded_test: notes
                .get("excluded_test")
                .and_then(|v| serde_json::from_value(v.clone()).ok()),
        }
    }

    /// The datasets as one line, for a message ("a + b").
    pub fn names(&self) -> String {
        self.datasets.join(" + ")
    }

    /// Each dataset its notes name, found from its folder `model_dir` (see
    /// [`Dataset::open_recorded`]), with the rows it fitted of it
    /// ([`Dataset::rows_to_fit`]); `None` for one that does not open here.
    /// A name given twice is opened once, and past the first
    /// [`MAX_RECORDED_DATASETS`] names one `None` stands for the rest, so
    /// notes naming a dataset a million times cost one opening, not a
    /// million.
    fn fitted_sets(&self, model_dir: &Path) -> impl Iterator<Item = Option<(Dataset, Vec<usize>)>> {
        let mut names: Vec<&String> = Vec::new();
        for d in &self.datasets {
            if !names.contains(&d) {
                names.push(d);
            }
            if names.len() > MAX_RECORDED_DATASETS {
                break;
            }
        }
        let more = names.len() > MAX_RECORDED_DATASETS;
        names.truncate(MAX_RECORDED_DATASETS);
        names
            .into_iter()
            .map(move |d| {
                let trained = Dataset::open_recorded(d, model_dir)?;
                let fitted = trained
                    .rows_to_fit(self.every_split, self.excluded_test)
                    .ok()?;
                Some((trained, fitted))
            })
            .chain(more.then_some(None))
    }

    /// How many of `rows` of `ds` it fitted: each dataset its notes name
    /// (found from its folder `model_dir`, see [`Dataset::open_recorded`])
    /// holds them among the rows it fitted, the same file or a copy (the
    /// same bytes under any name). The one rule of the benches' marks and
    /// the calibration's warning.
    pub fn seen(&self, model_dir: &Path, ds: &Dataset, rows: &[usize]) -> Seen {
        let asked: std::collections::HashSet<usize> = rows.iter().copied().collect();
        let mut held = std::collections::HashSet::new();
        let mut unknown = self.datasets.is_empty();
        for set in self.fitted_sets(model_dir) {
            match set {
                Some((trained, fitted)) => {
                    held.extend(trained.rows_sharing_frames_among(&fitted, ds, rows))
                }
                None => unknown = true,
            }
        }
        match held.len() {
            n if n > 0 && n == asked.len() => Seen::All,
            n if n > 0 => Seen::Some,
            _ if unknown => Seen::Unknown,
            _ => Seen::None,
        }
    }

    /// Whether it fitted every frame of `ds` (one dataset its notes name
    /// holds them all among the rows it fitted, the same files or copies;
    /// see [`Self::seen`]). It stops at the first frame not held, so a
    /// set it never saw costs a look at one frame.
    pub fn fitted_every(&self, model_dir: &Path, ds: &Dataset) -> bool {
        let all: Vec<usize> = ds.every_row();
        !all.is_empty()
            && self
                .fitted_sets(model_dir)
                .flatten()
                .any(|(trained, fitted)| trained.holds_frames(ds, &all, Some(&fitted)))
    }
}

/// How many of some frames a model fitted ([`Provenance::seen`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seen {
    /// Its notes name no dataset, or one that does not open here, and the
    /// others hold none of the frames: it may have fitted them.
    Unknown,
    /// None of them.
    None,
    /// Some of them, not all.
    Some,
    /// Every one of them.
    All,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn notes_written_are_read_back_with_every_dataset_and_the_trainers_own_keys() {
        let p = Provenance {
            datasets: vec!["data/a".into(), "data/b".into()],
            every_split: true,
            excluded_test: Some(TestHoldout {
                test_fraction: 0.2,
                split_seed: 7,
            }),
        };
        let notes = p.notes(serde_json::json!({"device": "flex"}));
        assert_eq!(notes["trained_on"], "data/a");
        assert_eq!(notes["also_trained_on"], serde_json::json!(["data/b"]));
        assert_eq!(notes["device"], "flex");
        assert_eq!(Provenance::read(&notes), p);
        // One dataset: no `also_trained_on`, as the notes always had it.
        let one = Provenance {
            datasets: vec!["data/a".into()],
            ..Default::default()
        };
        let notes = one.notes(serde_json::json!({}));
        assert!(notes.get("also_trained_on").is_none());
        assert_eq!(notes["excluded_test"], serde_json::Value::Null);
        assert_eq!(Provenance::read(&notes), one);
    }

    #[test]
    fn notes_of_older_models_read_as_no_dataset_and_training_rows_only() {
        // A model trained before its trainer recorded anything.
        let old = serde_json::json!({"device": "flex"});
        assert_eq!(Provenance::read(&old), Provenance::default());
        let pose = serde_json::json!({
            "trained_on": "../shared/real/x", "every_split": false, "excluded_test": null, "all_rows": true
        });
        let p = Provenance::read(&pose);
        assert_eq!(p.datasets, ["../shared/real/x"]);
        assert!(!p.every_split && p.excluded_test.is_none());
    }

    #[test]
    fn seen_counts_the_asked_frames_among_the_rows_it_fitted() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/virtual-tactip");
        let ds = Dataset::open(&root).unwrap();
        let all: Vec<usize> = ds.every_row();
        let holdout = TestHoldout {
            test_fraction: 0.2,
            split_seed: 7,
        };
        let test = ds.three_way_split(0.2, 0.2, 7).unwrap().test;
        let here = Provenance::of(&[&ds]);
        assert_eq!(here.seen(&root, &ds, &all), Seen::All);
        let held_out = here.clone().excluding_test(Some(holdout));
        assert_eq!(held_out.seen(&root, &ds, &test), Seen::None);
        assert_eq!(held_out.seen(&root, &ds, &all), Seen::Some);
        assert_eq!(
            held_out.clone().every_split(true).seen(&root, &ds, &test),
            Seen::All
        );
        let nowhere = Provenance {
            datasets: vec!["nowhere".into()],
            ..Default::default()
        };
        assert_eq!(nowhere.seen(&root, &ds, &all), Seen::Unknown);
        assert_eq!(Provenance::default().seen(&root, &ds, &all), Seen::Unknown);
    }

    /// `seen` on another thread, failing the test instead of hanging it.
    fn seen_within(p: Provenance, model_dir: &Path, ds: &Dataset, secs: u64) -> Seen {
        let (tx, rx) = std::sync::mpsc::channel();
        let (dir, ds) = (model_dir.to_path_buf(), ds.clone());
        std::thread::spawn(move || {
            let all: Vec<usize> = ds.every_row();
            let _ = tx.send(p.seen(&dir, &ds, &all));
        });
        rx.recv_timeout(std::time::Duration::from_secs(secs))
            .expect("seen did not answer in time")
    }

    #[test]
    fn hostile_notes_read_as_what_they_can_say_and_never_hang() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../samples/virtual-tactip")
            .canonicalize()
            .unwrap();
        let ds = Dataset::open(&root).unwrap();
        let here = root.display().to_string();
        // Keys of the wrong type name no dataset.
        let wrong = serde_json::json!({"trained_on": 5, "also_trained_on": "x", "every_split": "yes",
            "excluded_test": {"test_fraction": 0.2, "split_seed": -1}});
        assert_eq!(Provenance::read(&wrong), Provenance::default());
        // One dataset named 200,000 times is opened once.
        let many =
            serde_json::json!({"trained_on": here, "also_trained_on": vec![here.clone(); 200_000]});
        let t0 = std::time::Instant::now();
        assert_eq!(
            seen_within(Provenance::read(&many), &root, &ds, 30),
            Seen::All
        );
        assert!(
            t0.elapsed() < std::time::Duration::from_secs(5),
            "{:?}",
            t0.elapsed()
        );
        // Past the first MAX_RECORDED_DATASETS names nothing is looked up:
        // the frames may have been fitted.
        let mut names: Vec<String> = (0..40).map(|i| format!("nowhere-{i}")).collect();
        names.push(here.clone());
        let far = Provenance {
            datasets: names,
            ..Default::default()
        };
        assert_eq!(seen_within(far, &root, &ds, 30), Seen::Unknown);
        // A test fraction no split takes: its fitted rows are unknown.
        let odd = serde_json::json!({"trained_on": here,
            "excluded_test": {"test_fraction": 1e300, "split_seed": 7}});
        assert_eq!(
            seen_within(Provenance::read(&odd), &root, &ds, 30),
            Seen::Unknown
        );
        // A dataset whose manifest or labels are pipes is never read (a
        // pipe blocks whoever opens it until something writes to it).
        for pipe in ["manifest.json", "labels.csv"] {
            let tmp = tempfile::tempdir().unwrap();
            let fake = tmp.path().join("fake");
            std::fs::create_dir_all(&fake).unwrap();
            for f in ["manifest.json", "labels.csv"] {
                if f != pipe {
                    std::fs::copy(root.join(f), fake.join(f)).unwrap();
                }
            }
            let made = std::process::Command::new("mkfifo")
                .arg(fake.join(pipe))
                .status()
                .unwrap();
            assert!(made.success());
            let notes = serde_json::json!({"trained_on": fake.display().to_string()});
            assert_eq!(
                seen_within(Provenance::read(&notes), &root, &ds, 10),
                Seen::Unknown,
                "{pipe}"
            );
            let e = Dataset::open(&fake).unwrap_err().to_string();
            assert!(e.contains(pipe) && e.contains("not a regular file"), "{e}");
        }
    }
}
