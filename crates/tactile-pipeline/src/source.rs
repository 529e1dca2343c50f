//! Where frames come from: a dataset (frames in `labels.csv` order, with
//! their sequences and labels) or a folder of numbered frames (a video).

use std::path::{Path, PathBuf};

use tactile_core::dataset::Dataset;
use tactile_core::{Error, Result};

/// One frame to process.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameEntry {
    /// The image file.
    pub path: PathBuf,
    /// Its palpation sequence, when known (a hysteresis restarts per sequence).
    pub sequence: Option<String>,
    /// Its `tendon` label, when known.
    pub tendon: Option<bool>,
}

/// The frames of a dataset or a folder, in order.
#[derive(Debug, Clone)]
pub struct FrameList {
    /// The frames.
    pub frames: Vec<FrameEntry>,
    /// True for a dataset, whose rows say what it holds; false for a
    /// folder of frames, which may have dropped some.
    pub is_dataset: bool,
}

impl FrameList {
    /// The frames of `dir`: a dataset when it has `labels.csv`, else its
    /// PNG files in name order.
    pub fn open(dir: &Path) -> Result<Self> {
        if dir.join("labels.csv").is_file() {
            let ds = Dataset::open(dir)?;
            let frames = (0..ds.len())
                .map(|i| {
                    Ok(FrameEntry {
                        path: ds.path_of(i, "file")?,
                        sequence: ds.text_opt(i, "sequence").map(str::to_string),
                        tendon: ds.number_opt(i, "tendon")?.map(|v| v == 1.0),
                    })
                })
                .collect::<Result<_>>()?;
            return Ok(Self {
                frames,
                is_dataset: true,
            });
        }
        let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| Error::io(dir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("png")))
            .collect();
        v.sort();
        if v.is_empty() {
            return Err(Error::Invalid(format!(
                "{}: no labels.csv and no PNG frames",
                dir.display()
            )));
        }
        Ok(Self {
            frames: v
                .into_iter()
                .map(|path| FrameEntry {
                    path,
                    sequence: None,
                    tendon: None,
                })
                .collect(),
            is_dataset: false,
        })
    }

    /// Keep the first `n` frames.
    pub fn truncate(&mut self, n: usize) {
        self.frames.truncate(n);
    }

    /// Frame numbers missing from a folder of numbered frames
    /// (`000007.png`): the gaps between consecutive numbers, in order. A
    /// dataset lists what it has, so it has none.
    pub fn missing_frames(&self) -> Vec<u64> {
        if self.is_dataset {
            return Vec::new();
        }
        let number = |p: &Path| -> Option<u64> {
            let stem = p.file_stem()?.to_str()?;
            let digits: String = stem
                .chars()
                .rev()
                .take_while(char::is_ascii_digit)
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
                .collect();
            digits.parse().ok()
        };
        let nums: Vec<u64> = self.frames.iter().filter_map(|f| number(&f.path)).collect();
        if nums.len() != self.frames.len() {
            return Vec::new();
        }
        nums.windows(2)
            .flat_map(|w| (w[0] + 1..w[1]).collect::<Vec<_>>())
            .collect()
    }
}
