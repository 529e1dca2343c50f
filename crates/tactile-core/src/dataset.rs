//! The on-disk dataset layout of `datasets.md`: one folder with
//! `manifest.json`, `labels.csv` and the files it references. Opening a
//! dataset checks it first and names the file and line of anything wrong.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// The format tag every manifest carries.
pub const FORMAT: &str = "tactile-dataset/1";

/// Which sensor a dataset holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DatasetKind {
    /// TacTip frames (paper A), greyscale.
    Tactip,
    /// Visuo-tactile palpation frames (paper B), RGB, with masks and depth.
    Visuotactile,
}

impl DatasetKind {
    /// The required `labels.csv` columns, in order.
    pub fn columns(self) -> &'static [&'static str] {
        match self {
            DatasetKind::Tactip => &[
                "file",
                "shape",
                "x_mm",
                "y_mm",
                "theta_deg",
                "depth_mm",
                "force_n",
            ],
            DatasetKind::Visuotactile => &[
                "file",
                "mask",
                "depth",
                "tendon",
                "direction_deg",
                "path",
                "press_mm",
                "sequence",
                "frame_index",
            ],
        }
    }
}

/// `manifest.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    pub format: String,
    pub kind: DatasetKind,
    pub sensor_spec: String,
    pub width: u32,
    pub height: u32,
    pub generator: String,
    pub seed: Option<u64>,
    pub count: usize,
    /// Anything else a writer recorded (a generator's config, for instance).
    #[serde(flatten)]
    pub extra: serde_json::Map<String, serde_json::Value>,
}

/// One row of `labels.csv`: the raw cells by column name, with its line.
#[derive(Debug, Clone)]
pub struct LabelRow {
    /// 1-based line in `labels.csv` (the header is line 1).
    pub line: usize,
    cells: HashMap<String, String>,
}

impl LabelRow {
    /// The raw cell, `None` when the column is absent or the cell empty.
    pub fn get(&self, column: &str) -> Option<&str> {
        self.cells
            .get(column)
            .map(|s| s.trim())
            .filter(|s| !s.is_empty())
    }
}

/// A dataset folder, checked on open.
#[derive(Debug, Clone)]
pub struct Dataset {
    pub root: PathBuf,
    pub manifest: Manifest,
    pub rows: Vec<LabelRow>,
}

fn parse_number(labels: &Path, row: &LabelRow, column: &str) -> Result<Option<f64>> {
    match row.get(column) {
        None => Ok(None),
        Some(s) => match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            Ok(_) => Err(Error::dataset(
                labels,
                Some(row.line),
                format!("column '{column}': '{s}' is not a finite number"),
            )),
            Err(_) => Err(Error::dataset(
                labels,
                Some(row.line),
                format!("column '{column}': '{s}' is not a number"),
            )),
        },
    }
}

impl Dataset {
    /// Open and check a dataset folder: the manifest parses and has the
    /// right format, `labels.csv` has the kind's columns in order, every
    /// number parses and is finite, and every referenced file exists.
    pub fn open(root: impl AsRef<Path>) -> Result<Self> {
        let root = root.as_ref().to_path_buf();
        if !root.is_dir() {
            return Err(Error::dataset(&root, None, "dataset folder does not exist"));
        }
        let manifest_path = root.join("manifest.json");
        if !manifest_path.is_file() {
            return Err(Error::dataset(
                &manifest_path,
                None,
                "missing manifest.json",
            ));
        }
        let manifest: Manifest = crate::io::read_json(&manifest_path)?;
        if manifest.format != FORMAT {
            return Err(Error::dataset(
                &manifest_path,
                None,
                format!("format is '{}', expected '{FORMAT}'", manifest.format),
            ));
        }
        let labels = root.join("labels.csv");
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .flexible(false)
            .from_path(&labels)
            .map_err(|e| Error::dataset(&labels, None, format!("cannot read: {e}")))?;
        let header: Vec<String> = reader
            .headers()
            .map_err(|e| Error::dataset(&labels, Some(1), format!("bad header: {e}")))?
            .iter()
            .map(|s| s.trim().to_string())
            .collect();
        let required = manifest.kind.columns();
        if header.len() < required.len() || header[..required.len()] != *required {
            return Err(Error::dataset(
                &labels,
                Some(1),
                format!(
                    "header must start with {} (found {})",
                    required.join(","),
                    header.join(",")
                ),
            ));
        }
        let mut rows = Vec::new();
        for (i, rec) in reader.records().enumerate() {
            let line = i + 2;
            let rec = rec.map_err(|e| Error::dataset(&labels, Some(line), e.to_string()))?;
            let cells = header
                .iter()
                .cloned()
                .zip(rec.iter().map(str::to_string))
                .collect();
            rows.push(LabelRow { line, cells });
        }
        if rows.len() != manifest.count {
            return Err(Error::dataset(
                &manifest_path,
                None,
                format!(
                    "count is {} but labels.csv has {} rows",
                    manifest.count,
                    rows.len()
                ),
            ));
        }
        let ds = Dataset {
            root,
            manifest,
            rows,
        };
        ds.check_rows()?;
        Ok(ds)
    }

    fn check_rows(&self) -> Result<()> {
        let labels = self.labels_path();
        let file_columns: &[&str] = match self.manifest.kind {
            DatasetKind::Tactip => &["file"],
            DatasetKind::Visuotactile => &["file", "mask", "depth"],
        };
        let number_columns: &[&str] = match self.manifest.kind {
            DatasetKind::Tactip => &["x_mm", "y_mm", "theta_deg", "depth_mm", "force_n"],
            DatasetKind::Visuotactile => &[
                "tendon",
                "direction_deg",
                "press_mm",
                "sequence",
                "frame_index",
            ],
        };
        for row in &self.rows {
            let Some(_) = row.get("file") else {
                return Err(Error::dataset(
                    &labels,
                    Some(row.line),
                    "column 'file' is empty",
                ));
            };
            for col in file_columns {
                if let Some(rel) = row.get(col)
                    && !self.root.join(rel).is_file()
                {
                    return Err(Error::dataset(
                        &labels,
                        Some(row.line),
                        format!("column '{col}': file '{rel}' does not exist"),
                    ));
                }
            }
            for col in number_columns {
                parse_number(&labels, row, col)?;
            }
        }
        Ok(())
    }

    /// Path of `labels.csv`.
    pub fn labels_path(&self) -> PathBuf {
        self.root.join("labels.csv")
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True when the dataset has no frames.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Absolute path of the file named in `column` of row `i`.
    pub fn path_of(&self, i: usize, column: &str) -> Result<PathBuf> {
        self.text(i, column).map(|rel| self.root.join(rel))
    }

    /// A text label that the calling command needs; an empty cell is an error
    /// naming the line.
    pub fn text(&self, i: usize, column: &str) -> Result<&str> {
        let row = &self.rows[i];
        row.get(column).ok_or_else(|| {
            Error::dataset(
                self.labels_path(),
                Some(row.line),
                format!("column '{column}' is empty, but this command needs it"),
            )
        })
    }

    /// A text label, `None` when empty.
    pub fn text_opt(&self, i: usize, column: &str) -> Option<&str> {
        self.rows[i].get(column)
    }

    /// A numeric label that the calling command needs.
    pub fn number(&self, i: usize, column: &str) -> Result<f64> {
        let row = &self.rows[i];
        parse_number(&self.labels_path(), row, column)?.ok_or_else(|| {
            Error::dataset(
                self.labels_path(),
                Some(row.line),
                format!("column '{column}' is empty, but this command needs it"),
            )
        })
    }

    /// A numeric label, `None` when empty.
    pub fn number_opt(&self, i: usize, column: &str) -> Result<Option<f64>> {
        parse_number(&self.labels_path(), &self.rows[i], column)
    }

    /// Indices of the rows whose `split` column equals `split`; when the
    /// dataset has no `split` column, `None`.
    pub fn split_indices(&self, split: &str) -> Option<Vec<usize>> {
        if self.rows.first().map(|r| r.cells.contains_key("split")) != Some(true) {
            return None;
        }
        Some(
            (0..self.len())
                .filter(|&i| self.text_opt(i, "split") == Some(split))
                .collect(),
        )
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
        use rand::SeedableRng;
        use rand::seq::SliceRandom;
        if !(0.0..1.0).contains(&val_fraction) || val_fraction == 0.0 {
            return Err(Error::Config(format!(
                "validation fraction must be in (0, 1), got {val_fraction}"
            )));
        }
        let mut groups: std::collections::BTreeMap<String, Vec<usize>> = Default::default();
        for i in 0..self.len() {
            let key = match self.text_opt(i, "sequence") {
                Some(s) => format!("s{s}"),
                None => format!("f{i}"),
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
        keys.shuffle(&mut rand::rngs::StdRng::seed_from_u64(seed));
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

/// Writes a dataset folder: files first, `labels.csv` and `manifest.json`
/// last and atomically, so an interrupted write never looks complete.
pub struct DatasetWriter {
    root: PathBuf,
    kind: DatasetKind,
    extra_columns: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl DatasetWriter {
    /// Start writing into `root`. The folder must be absent or empty unless `force`.
    pub fn create(
        root: impl AsRef<Path>,
        kind: DatasetKind,
        extra_columns: &[&str],
        force: bool,
    ) -> Result<Self> {
        let root = root.as_ref().to_path_buf();
        if root.exists() {
            let non_empty = std::fs::read_dir(&root)
                .map_err(|e| Error::io(&root, e))?
                .next()
                .is_some();
            if non_empty && !force {
                return Err(Error::Invalid(format!(
                    "{}: output folder exists and is not empty (use --force to overwrite)",
                    root.display()
                )));
            }
        }
        crate::io::create_dir_all(&root)?;
        Ok(Self {
            root,
            kind,
            extra_columns: extra_columns.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
        })
    }

    /// The folder being written.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Add one row; cells in the kind's column order followed by the extra columns.
    pub fn push_row(&mut self, cells: Vec<String>) -> Result<()> {
        let want = self.kind.columns().len() + self.extra_columns.len();
        if cells.len() != want {
            return Err(Error::shape("labels row", want, cells.len()));
        }
        self.rows.push(cells);
        Ok(())
    }

    /// Write `labels.csv` and `manifest.json` (count is set from the rows).
    pub fn finish(self, mut manifest: Manifest) -> Result<PathBuf> {
        manifest.count = self.rows.len();
        manifest.kind = self.kind;
        let labels = self.root.join("labels.csv");
        let header: Vec<&str> = self
            .kind
            .columns()
            .iter()
            .copied()
            .chain(self.extra_columns.iter().map(String::as_str))
            .collect();
        crate::io::write_atomic_with(&labels, |w| {
            let mut csv = csv::Writer::from_writer(w);
            csv.write_record(&header)?;
            for r in &self.rows {
                csv.write_record(r)?;
            }
            csv.flush()
        })?;
        crate::io::write_json_atomic(self.root.join("manifest.json"), &manifest)?;
        Ok(self.root)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest(kind: DatasetKind, count: usize) -> Manifest {
        Manifest {
            format: FORMAT.into(),
            kind,
            sensor_spec: "test".into(),
            width: 4,
            height: 4,
            generator: "test".into(),
            seed: Some(1),
            count,
            extra: Default::default(),
        }
    }

    fn tiny(dir: &Path, labels: &str) {
        std::fs::create_dir_all(dir.join("frames")).unwrap();
        crate::image_io::save_grey_png(dir.join("frames/a.png"), 4, 4, &[0; 16]).unwrap();
        let n = labels.lines().count() - 1;
        crate::io::write_json_atomic(dir.join("manifest.json"), &manifest(DatasetKind::Tactip, n))
            .unwrap();
        std::fs::write(dir.join("labels.csv"), labels).unwrap();
    }

    const HEADER: &str = "file,shape,x_mm,y_mm,theta_deg,depth_mm,force_n\n";

    #[test]
    fn good_dataset_opens_and_reads_labels() {
        let d = tempfile::tempdir().unwrap();
        tiny(
            d.path(),
            &format!("{HEADER}frames/a.png,sphere,1.5,,0,2,3.4\n"),
        );
        let ds = Dataset::open(d.path()).unwrap();
        assert_eq!(ds.number(0, "x_mm").unwrap(), 1.5);
        assert_eq!(ds.number_opt(0, "y_mm").unwrap(), None);
        let e = ds.number(0, "y_mm").unwrap_err().to_string();
        assert!(e.contains("labels.csv:2") && e.contains("y_mm"), "{e}");
    }

    #[test]
    fn missing_file_and_bad_number_name_the_line() {
        let d = tempfile::tempdir().unwrap();
        tiny(
            d.path(),
            &format!("{HEADER}frames/a.png,sphere,1,0,0,2,3\nframes/gone.png,sphere,1,0,0,2,3\n"),
        );
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(e.contains("labels.csv:3") && e.contains("gone.png"), "{e}");
        tiny(
            d.path(),
            &format!("{HEADER}frames/a.png,sphere,abc,0,0,2,3\n"),
        );
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(e.contains("labels.csv:2") && e.contains("'abc'"), "{e}");
        tiny(
            d.path(),
            &format!("{HEADER}frames/a.png,sphere,NaN,0,0,2,3\n"),
        );
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(e.contains("finite"), "{e}");
    }

    #[test]
    fn wrong_header_and_manifest_are_named() {
        let d = tempfile::tempdir().unwrap();
        tiny(d.path(), "file,x_mm\nframes/a.png,1\n");
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(e.contains("labels.csv:1"), "{e}");
        std::fs::write(d.path().join("manifest.json"), "{ not json").unwrap();
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(e.contains("manifest.json"), "{e}");
    }

    #[test]
    fn writer_refuses_non_empty_folder_and_round_trips() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("keep.txt"), "x").unwrap();
        assert!(DatasetWriter::create(d.path(), DatasetKind::Tactip, &[], false).is_err());
        assert_eq!(
            std::fs::read_to_string(d.path().join("keep.txt")).unwrap(),
            "x"
        );
        let out = d.path().join("ds");
        let mut w = DatasetWriter::create(&out, DatasetKind::Tactip, &["split"], false).unwrap();
        crate::image_io::save_grey_png(out.join("a.png"), 4, 4, &[0; 16]).unwrap();
        w.push_row(vec![
            "a.png".into(),
            "flat".into(),
            "0".into(),
            "0".into(),
            "0".into(),
            "1".into(),
            "0.5".into(),
            "train".into(),
        ])
        .unwrap();
        w.finish(manifest(DatasetKind::Tactip, 0)).unwrap();
        let ds = Dataset::open(&out).unwrap();
        assert_eq!(ds.split_indices("train"), Some(vec![0]));
        assert_eq!(ds.manifest.count, 1);
    }
}
