//! Writing a dataset folder.

use std::path::{Path, PathBuf};

use super::{DatasetKind, Manifest};
use crate::{Error, Result};

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
