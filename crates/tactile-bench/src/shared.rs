//! One encoder for many tasks (paper A's claim across data): every encoder
//! of a list encodes every task's frames, a cheap MLP is fitted on those
//! features per task, and each task's errors are set beside those of the
//! encoder trained for it, in one table.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_burn::{Artifact, DeviceKind, Runtime};
use tactile_cae::data::PinSet;
use tactile_cae::{CaeArtifact, TactipEncoder};
use tactile_core::dataset::{DEFAULT_SPLIT_SEED, Dataset, Provenance, Seen};
use tactile_estimate::Target;
use tactile_estimate::regressor::target_mae;
use tactile_pipeline::tactip::classes_of;
use tactile_preprocess::PreprocessConfig;

use crate::Result;
use crate::compare::{mlp_classification, mlp_regression};
use crate::output::folder_name;

/// Most tasks in one table.
pub const MAX_TASKS: usize = 16;

/// One task of the table, as `configs/bench/shared-encoder.json` lists it.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Task {
    /// Its name in the table.
    pub task: String,
    /// Dataset folder, relative to the real-data folder.
    pub data: String,
    /// Preprocessing of this dataset's frames for an encoder trained on
    /// other data (its side becomes the encoder's input side).
    pub preprocess: String,
    /// Regression targets (`NAME` or `NAME:PERIOD`).
    #[serde(default)]
    pub targets: Vec<String>,
    /// A class column to classify instead.
    #[serde(default)]
    pub classify: Option<String>,
    /// Folder name of the encoder trained for this task.
    pub own: String,
}

/// A task's result with one encoder.
#[derive(Debug, Clone, Serialize)]
pub struct Cell {
    /// Task name.
    pub task: String,
    /// Encoder folder name.
    pub encoder: String,
    /// Per metric (target MAE in its units, or `accuracy`), the value.
    pub values: Vec<(String, f64)>,
    /// True when the encoder trained on this task's test frames.
    pub saw_test_frames: bool,
}

/// `tactile bench shared-encoder`'s flags: the encoders and the tasks.
#[derive(Debug, Clone, clap::Args)]
pub struct SharedEncoderBench {
    /// Encoder folders, each run on every task.
    #[arg(long, num_args = 1.., required = true)]
    pub encoders: Vec<PathBuf>,
    /// The tasks: a JSON list of {task, data, preprocess, targets or classify, own}.
    #[arg(long, default_value = "configs/bench/shared-encoder.json")]
    pub tasks: PathBuf,
    /// Folder the tasks' datasets are in.
    #[arg(long, default_value = "../shared/real")]
    pub real: PathBuf,
}

impl SharedEncoderBench {
    /// Every encoder on every task: the cells and their table
    /// ([`read_tasks`], [`shared_encoders`], [`shared_markdown`]).
    pub fn run(&self) -> Result<(Vec<Cell>, String)> {
        let tasks = read_tasks(&self.tasks)?;
        let cells = shared_encoders(&self.encoders, &tasks, &self.real)?;
        let md = shared_markdown(&cells, &self.encoders, &tasks);
        Ok((cells, md))
    }
}

/// Read and check a task list.
pub fn read_tasks(path: &Path) -> Result<Vec<Task>> {
    let tasks: Vec<Task> = tactile_core::io::read_json(path)?;
    let bad = |m: String| tactile_core::Error::Config(format!("{}: {m}", path.display()));
    if tasks.is_empty() || tasks.len() > MAX_TASKS {
        return Err(bad(format!("1 to {MAX_TASKS} tasks, got {}", tasks.len())).into());
    }
    for t in &tasks {
        if t.targets.is_empty() == t.classify.is_none() {
            return Err(bad(format!(
                "task {}: give targets or classify, not both",
                t.task
            ))
            .into());
        }
    }
    Ok(tasks)
}

/// Whether an encoder (its notes, its folder `dir`) fitted any of the
/// `test` rows of `ds`: a dataset its notes name (main or further, found
/// as [`Dataset::open_recorded`] finds it) holds one of them among the rows
/// it fitted ([`Provenance::seen`]), the same file or a copy. An
/// encoder that left out other test rows than these, or fitted every
/// split, saw them; one trained on other frames did not.
fn saw_test(art: &CaeArtifact, dir: &Path, ds: &Dataset, test: &[usize]) -> bool {
    matches!(
        Provenance::read(&art.notes).seen(dir, ds, test),
        Seen::Some | Seen::All
    )
}

/// Every encoder on every task: features, an MLP per task on the training
/// frames (early stopping on the validation ones), scored on the test
/// frames of the task's split (its `split` column, else seed 7's 20 %).
pub fn shared_encoders(encoders: &[PathBuf], tasks: &[Task], real: &Path) -> Result<Vec<Cell>> {
    let dev = DeviceKind::Flex.device();
    let mut cells = Vec::new();
    for t in tasks {
        let ds = Dataset::open(real.join(&t.data))?;
        let split = ds.three_way_split(0.2, 0.2, DEFAULT_SPLIT_SEED)?;
        // The rows a classifier fits, and their frames (for its folds).
        let fitted: Vec<usize> = split.train.iter().chain(&split.val).copied().collect();
        let fitted_frames = ds.frame_of_rows(&fitted);
        let preset: PreprocessConfig = tactile_core::io::read_json(Path::new(&t.preprocess))?;
        let targets = t
            .targets
            .iter()
            .map(|s| s.parse::<Target>())
            .collect::<std::result::Result<Vec<_>, _>>()?;
        for enc in encoders {
            let mut art = CaeArtifact::read(enc)?;
            let name = folder_name(enc);
            if name != t.own {
                let side = art.model.input_px;
                art.preprocess = PreprocessConfig {
                    output_px: side,
                    ..preset.clone()
                };
            }
            art.preprocess.check()?;
            tactile_core::note!("{}: encoding {} frames with {name}", t.task, ds.len());
            let (_, net) = tactile_onnx::load_network::<CaeArtifact>(enc, Runtime::BurnFlex, 0)?;
            let mut encoder = TactipEncoder::from_network(art.clone(), net);
            let pins = PinSet::from_dataset(&ds, &art.preprocess)?;
            let feats = encoder.encode(&pins.images)?;
            let pick = |idx: &[usize]| -> Vec<Vec<f32>> {
                idx.iter().map(|&i| feats[i].clone()).collect()
            };
            let (tx, vx, sx) = (pick(&split.train), pick(&split.val), pick(&split.test));
            let values = if let Some(col) = &t.classify {
                let (classes, y) = classes_of(&ds, col)?;
                let x: Vec<Vec<f32>> = fitted.iter().map(|&i| feats[i].clone()).collect();
                let yy: Vec<usize> = fitted.iter().map(|&i| y[i]).collect();
                let pred = mlp_classification(
                    &classes,
                    (&x, &yy, &fitted_frames),
                    &sx,
                    DEFAULT_SPLIT_SEED,
                    &dev,
                )?;
                let truth: Vec<usize> = split.test.iter().map(|&i| y[i]).collect();
                vec![(
                    "accuracy".to_string(),
                    tactile_core::metrics::accuracy(&pred, &truth),
                )]
            } else {
                let labels = |idx: &[usize]| -> Result<Vec<Vec<f64>>> {
                    idx.iter()
                        .map(|&i| {
                            targets
                                .iter()
                                .map(|tg| Ok(ds.target(i, &tg.name)?))
                                .collect::<Result<Vec<f64>>>()
                        })
                        .collect()
                };
                let (ty, vy, sy) = (
                    labels(&split.train)?,
                    labels(&split.val)?,
                    labels(&split.test)?,
                );
                let pred = mlp_regression(
                    &targets,
                    [&tx, &vx, &sx],
                    (&ty, &vy),
                    (&[256, 128], DEFAULT_SPLIT_SEED),
                    &dev,
                )?;
                targets
                    .iter()
                    .zip(target_mae(&targets, &pred, &sy))
                    .map(|(tg, mae)| (tg.name.clone(), mae))
                    .collect()
            };
            cells.push(Cell {
                task: t.task.clone(),
                encoder: name,
                values,
                saw_test_frames: saw_test(&art, enc, &ds, &split.test),
            });
        }
    }
    Ok(cells)
}

/// The table: one row per task metric, one column per encoder, each cell
/// with its ratio to the task's own encoder (an error ratio above 1, or an
/// accuracy ratio below 1, is what sharing costs).
pub fn shared_markdown(cells: &[Cell], encoders: &[PathBuf], tasks: &[Task]) -> String {
    let names: Vec<String> = encoders.iter().map(|e| folder_name(e)).collect();
    let mut md = format!(
        "Machine: {}\n\nEach encoder encodes every task's frames (with the task's preprocessing at the encoder's input side; the task's own encoder with its own). An MLP (256-128 regressor, or paper A's 16-64-32 head) is fitted per task and encoder on the training frames, stopped early on the validation frames, and scored on the test frames (the `split` column's, else seed 7's 20 %). Errors are mean absolute errors in the labels' units; in brackets, the ratio to the task's own encoder. A dagger marks an encoder that trained on that task's test frames.\n\n| task | metric | own encoder |",
        tactile_core::bench::Machine::detect().describe()
    );
    for n in &names {
        md.push_str(&format!(" {n} |"));
    }
    md.push_str("\n|---|---|---|");
    md.push_str(&"---|".repeat(names.len()));
    md.push('\n');
    for t in tasks {
        let of = |enc: &str| cells.iter().find(|c| c.task == t.task && c.encoder == enc);
        let Some(first) = of(&names[0]) else { continue };
        for (k, (metric, _)) in first.values.iter().enumerate() {
            md.push_str(&format!("| {} | {metric} | {} |", t.task, t.own));
            let own = of(&t.own).map(|c| c.values[k].1);
            for n in &names {
                let Some(c) = of(n) else {
                    md.push_str(" - |");
                    continue;
                };
                let v = c.values[k].1;
                let cell = if metric == "accuracy" {
                    format!("{:.1} %", 100.0 * v)
                } else {
                    format!("{v:.3}")
                };
                let ratio = own.map_or(String::new(), |o| format!(" ({:.2})", v / o));
                let dagger = if c.saw_test_frames { " †" } else { "" };
                md.push_str(&format!(" {cell}{ratio}{dagger} |"));
            }
            md.push('\n');
        }
    }
    md.push_str(&cost_markdown(cells, &names, tasks));
    md
}

/// What sharing costs, per encoder and task: the worst of the task's
/// metrics as a factor on its own encoder's (an error ratio, or own over
/// shared accuracy), and the encoder whose worst factor over every task is
/// smallest, said plainly.
fn cost_markdown(cells: &[Cell], names: &[String], tasks: &[Task]) -> String {
    // Per encoder: per task its worst factor and that metric.
    let mut worst: Vec<Vec<Option<(f64, String)>>> = Vec::new();
    for n in names {
        let mut row = Vec::new();
        for t in tasks {
            let of = |enc: &str| cells.iter().find(|c| c.task == t.task && c.encoder == enc);
            let w = match (of(n), of(&t.own)) {
                (Some(c), Some(own)) => c
                    .values
                    .iter()
                    .zip(&own.values)
                    .map(|((metric, v), (_, o))| {
                        let f = if metric == "accuracy" { o / v } else { v / o };
                        (f, metric.clone())
                    })
                    .filter(|(f, _)| f.is_finite())
                    // The first of equal factors names the metric.
                    .reduce(|a, b| if b.0 > a.0 { b } else { a }),
                _ => None,
            };
            row.push(w);
        }
        worst.push(row);
    }
    let mut md = String::from(
        "\nWhat one encoder for every task costs: per task, its worst metric as a factor on the task's own encoder (1.00: nothing lost).\n\n| encoder |",
    );
    for t in tasks {
        md.push_str(&format!(" {} |", t.task));
    }
    md.push_str(" worst |\n|---|");
    md.push_str(&"---|".repeat(tasks.len() + 1));
    md.push('\n');
    let mut best: Option<(f64, usize, usize)> = None;
    for (e, row) in worst.iter().enumerate() {
        md.push_str(&format!("| {} |", names[e]));
        let mut top: Option<(f64, usize)> = None;
        for (k, w) in row.iter().enumerate() {
            match w {
                Some((f, metric)) => {
                    md.push_str(&format!(" {f:.2} ({metric}) |"));
                    if top.is_none_or(|(t, _)| *f > t) {
                        top = Some((*f, k));
                    }
                }
                None => md.push_str(" - |"),
            }
        }
        let complete = row.iter().all(Option::is_some);
        match top {
            Some((f, k)) if complete => {
                md.push_str(&format!(" {f:.2} |\n"));
                if best.is_none_or(|(b, _, _)| f < b) {
                    best = Some((f, e, k));
                }
            }
            _ => md.push_str(" - |\n"),
        }
    }
    if let Some((f, e, k)) = best {
        let (_, metric) = worst[e][k].clone().unwrap_or((f, String::new()));
        md.push_str(&format!(
            "\nThe one encoder that costs least over all {} tasks is {}: at worst {f:.2}x its own encoder's {metric} on the {} task.\n",
            tasks.len(),
            names[e],
            tasks[k].task
        ));
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    fn task(name: &str, own: &str) -> Task {
        Task {
            task: name.into(),
            data: name.into(),
            preprocess: String::new(),
            targets: vec!["x_mm".into()],
            classify: None,
            own: own.into(),
        }
    }

    fn cell(task: &str, encoder: &str, values: &[(&str, f64)]) -> Cell {
        Cell {
            task: task.into(),
            encoder: encoder.into(),
            values: values.iter().map(|(m, v)| (m.to_string(), *v)).collect(),
            saw_test_frames: false,
        }
    }

    #[test]
    fn an_encoder_saw_the_test_frames_of_its_main_or_further_datasets() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/virtual-tactip");
        let ds = Dataset::open(&root).unwrap();
        let here = root.display().to_string();
        let test = ds
            .three_way_split(0.2, 0.2, DEFAULT_SPLIT_SEED)
            .unwrap()
            .test;
        let art = |notes: serde_json::Value| CaeArtifact {
            model: tactile_cae::CaeConfig::new(),
            preprocess: PreprocessConfig::binary_frames(),
            input_profile: None,
            notes,
        };
        let saw = |notes: &serde_json::Value, ds: &Dataset, test: &[usize]| {
            saw_test(&art(notes.clone()), &root, ds, test)
        };
        // The frames again, each under another name in another folder.
        let tmp = tempfile::tempdir().unwrap();
        let copy = tmp.path().join("copy");
        std::fs::create_dir_all(copy.join("frames")).unwrap();
        std::fs::copy(root.join("manifest.json"), copy.join("manifest.json")).unwrap();
        let mut labels = String::new();
        for (k, line) in std::fs::read_to_string(root.join("labels.csv"))
            .unwrap()
            .lines()
            .enumerate()
        {
            match line.split_once(',') {
                Some((file, rest)) if k > 0 => {
                    let name = format!("frames/copy-{k}.png");
                    std::fs::copy(root.join(file), copy.join(&name)).unwrap();
                    labels.push_str(&format!("{name},{rest}\n"));
                }
                _ => labels.push_str(&format!("{line}\n")),
            }
        }
        std::fs::write(copy.join("labels.csv"), labels).unwrap();
        let copy = copy.display().to_string();
        // Another seed's test frames are not these: it fitted some of them.
        let other_seed = ds.three_way_split(0.2, 0.2, 1).unwrap().test;
        assert_ne!(other_seed, test);
        for (notes, expected) in [
            (serde_json::json!({"trained_on": here}), true),
            (
                serde_json::json!({"trained_on": "elsewhere", "also_trained_on": [here]}),
                true,
            ),
            (serde_json::json!({"trained_on": copy}), true),
            (
                serde_json::json!({"trained_on": "elsewhere", "also_trained_on": ["nowhere"]}),
                false,
            ),
            (
                serde_json::json!({"trained_on": here, "excluded_test": {"test_fraction": 0.2, "split_seed": DEFAULT_SPLIT_SEED}}),
                false,
            ),
            (
                serde_json::json!({"trained_on": here, "excluded_test": {"test_fraction": 0.2, "split_seed": 1}}),
                true,
            ),
            (serde_json::json!({}), false),
        ] {
            assert_eq!(saw(&notes, &ds, &test), expected, "{notes}");
        }
        // A folder whose split column keeps the test frames apart: an
        // encoder saw them only when it fitted every split (a final one).
        let split = tmp.path().join("split");
        std::fs::create_dir_all(split.join("frames")).unwrap();
        std::fs::copy(root.join("manifest.json"), split.join("manifest.json")).unwrap();
        let mut labels =
            String::from("file,shape,x_mm,y_mm,theta_deg,depth_mm,force_n,radius_mm,split\n");
        for (i, line) in std::fs::read_to_string(root.join("labels.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .enumerate()
        {
            let file = line.split(',').next().unwrap();
            std::fs::copy(root.join(file), split.join(file)).unwrap();
            labels.push_str(&format!(
                "{line},{}\n",
                if i < 10 { "train" } else { "test" }
            ));
        }
        std::fs::write(split.join("labels.csv"), labels).unwrap();
        let split_ds = Dataset::open(&split).unwrap();
        let split_test = split_ds
            .three_way_split(0.2, 0.2, DEFAULT_SPLIT_SEED)
            .unwrap()
            .test;
        assert_eq!(split_test, [10, 11, 12, 13]);
        let there = split.display().to_string();
        for (notes, expected) in [
            (serde_json::json!({"trained_on": there}), false),
            (
                serde_json::json!({"trained_on": there, "every_split": true}),
                true,
            ),
        ] {
            assert_eq!(saw(&notes, &split_ds, &split_test), expected, "{notes}");
        }
    }

    #[test]
    fn the_cheapest_shared_encoder_is_named_with_its_worst_cost() {
        let tasks = [task("edge", "a"), task("shapes", "b")];
        let cells = [
            cell("edge", "a", &[("x_mm", 0.1), ("theta_deg", 1.0)]),
            cell("edge", "b", &[("x_mm", 0.3), ("theta_deg", 1.5)]),
            cell("shapes", "a", &[("accuracy", 0.5)]),
            cell("shapes", "b", &[("accuracy", 0.9)]),
        ];
        let md = shared_markdown(&cells, &[PathBuf::from("a"), PathBuf::from("b")], &tasks);
        // a loses accuracy on shapes (0.9 / 0.5 = 1.8); b triples edge x.
        assert!(
            md.contains("| a | 1.00 (x_mm) | 1.80 (accuracy) | 1.80 |"),
            "{md}"
        );
        assert!(
            md.contains("| b | 3.00 (x_mm) | 1.00 (accuracy) | 3.00 |"),
            "{md}"
        );
        assert!(
            md.contains("costs least over all 2 tasks is a: at worst 1.80x its own encoder's accuracy on the shapes task"),
            "{md}"
        );
    }
}
