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
    /// The size its dataset's manifest declares, when it comes from one.
    pub size: Option<(usize, usize)>,
}

impl FrameEntry {
    /// Decode the frame as RGB; a frame of a dataset of another size than
    /// its manifest says is refused, naming the file.
    pub fn load(&self) -> Result<tactile_core::image_io::RgbImage> {
        let img = tactile_core::image_io::load_rgb(&self.path)?;
        if let Some((w, h)) = self.size
            && (img.width(), img.height()) != (w, h)
        {
            return Err(Error::image(
                &self.path,
                format!(
                    "is {}x{}, but manifest.json says the frames are {w}x{h}",
                    img.width(),
                    img.height()
                ),
            ));
        }
        Ok(img)
    }
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
                        size: Some((ds.manifest.width as usize, ds.manifest.height as usize)),
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
        // A pipe or a device named like a frame would block the reader.
        for p in &v {
            tactile_core::image_io::expect_regular_file(p)?;
        }
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
                    size: None,
                })
                .collect(),
            is_dataset: false,
        })
    }

    /// Keep the first `n` frames.
    pub fn truncate(&mut self, n: usize) {
        self.frames.truncate(n);
    }

    /// Frames missing from a folder of numbered frames (`000007.png`): how
    /// many numbers the gaps between consecutive frames skip, and the first
    /// few of them. A dataset lists what it has, so it has none. Counted,
    /// not listed: frames named by nanosecond timestamps skip billions.
    pub fn missing_frames(&self) -> MissingFrames {
        let none = MissingFrames::default();
        if self.is_dataset {
            return none;
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
            return none;
        }
        let mut m = none;
        for w in nums.windows(2) {
            let gap = w[1].saturating_sub(w[0]).saturating_sub(1);
            m.count = m.count.saturating_add(gap);
            let room = MissingFrames::EXAMPLES.saturating_sub(m.first.len()) as u64;
            m.first.extend(w[0] + 1..w[0] + 1 + gap.min(room));
        }
        m
    }
}

/// Frames a numbered folder skips.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MissingFrames {
    /// How many numbers are skipped.
    pub count: u64,
    /// The first of them (at most [`MissingFrames::EXAMPLES`]).
    pub first: Vec<u64>,
}

impl MissingFrames {
    /// How many skipped numbers are kept as examples.
    pub const EXAMPLES: usize = 5;
}
