//! The on-disk dataset layout of `datasets.md`: one folder with
//! `manifest.json`, `labels.csv` and the files it references. Opening a
//! dataset checks it first and names the file and line of anything wrong.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

mod copies;
mod paths;
mod provenance;
mod split;
mod writer;

pub use paths::{Escape, backslash_hint, expect_entry_inside, resolve_inside};
pub use provenance::{Provenance, Seen};
pub use split::{
    DEFAULT_SPLIT_SEED, FrameGroups, Splits, TestHoldout, check_every_split, check_val_fraction,
    hold_out,
};
pub use writer::DatasetWriter;

/// The format tag every manifest carries.
pub const FORMAT: &str = "tactile-dataset/1";

/// Most rows a `labels.csv` may have.
pub const MAX_ROWS: usize = 10_000_000;
/// Largest frame side a manifest may declare, pixels (8K UHD's width).
pub const MAX_SIDE: u32 = 7680;

/// Which sensor a dataset holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum DatasetKind {
    /// TacTip frames (paper A), greyscale.
    Tactip,
    /// Visuo-tactile palpation frames (paper B), RGB, with masks and depth.
    Visuotactile,
}

impl std::str::FromStr for DatasetKind {
    type Err = Error;
    /// The kind by its manifest name (`tactip`, `visuotactile`).
    fn from_str(s: &str) -> Result<Self> {
        [DatasetKind::Tactip, DatasetKind::Visuotactile]
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                Error::Config(format!(
                    "unknown dataset kind '{s}': expected tactip or visuotactile"
                ))
            })
    }
}

impl DatasetKind {
    /// The manifest's name of the kind.
    pub fn name(self) -> &'static str {
        match self {
            DatasetKind::Tactip => "tactip",
            DatasetKind::Visuotactile => "visuotactile",
        }
    }

    /// The kind in words.
    pub fn describe(self) -> &'static str {
        match self {
            DatasetKind::Tactip => "TacTip",
            DatasetKind::Visuotactile => "visuotactile",
        }
    }

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

/// A whole number written either way JSON writers write one: `300`, or
/// `300.0` (Python's `json.dump` of a float, a size read from YAML or
/// computed). A fraction, a negative or a number past `T` is refused, the
/// number named.
fn whole_number<'de, D, T>(d: D) -> std::result::Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
    T: TryFrom<u64>,
{
    use serde::de::Error as _;
    let n = serde_json::Number::deserialize(d)?;
    let whole = match (n.as_u64(), n.as_f64()) {
        (Some(u), _) => Some(u),
        // Within 2^53 a float holds every whole number exactly.
        (None, Some(f)) if f >= 0.0 && f.fract() == 0.0 && f <= (1u64 << 53) as f64 => {
            Some(f as u64)
        }
        _ => None,
    };
    whole.and_then(|u| T::try_from(u).ok()).ok_or_else(|| {
        D::Error::custom(format!(
            "{n} is not a whole number from 0 that fits (a size, a count or a seed)"
        ))
    })
}

/// The seed, a note no command needs: a whole number that fits in 64 bits
/// (written either way, as [`whole_number`] reads it); any other value (a
/// 128-bit entropy from numpy's `SeedSequence`, a negative, a string such
/// as `"none"` for a capture rig, `null`) is read as none rather than
/// refusing the frames over a note.
fn lenient_seed<'de, D>(d: D) -> std::result::Result<Option<u64>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    #[derive(Deserialize)]
    struct Whole(#[serde(deserialize_with = "whole_number")] u64);
    let value = serde_json::Value::deserialize(d)?;
    Ok(serde_json::from_value::<Whole>(value).ok().map(|w| w.0))
}

/// `manifest.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    /// Always [`FORMAT`].
    pub format: String,
    /// Which sensor.
    pub kind: DatasetKind,
    /// The sensor contract or free text for a real sensor.
    pub sensor_spec: String,
    /// Frame width, pixels.
    #[serde(deserialize_with = "whole_number")]
    pub width: u32,
    /// Frame height, pixels.
    #[serde(deserialize_with = "whole_number")]
    pub height: u32,
    /// Name and version of what wrote it, or how it was captured (a note:
    /// empty when a writer left it out).
    #[serde(default)]
    pub generator: String,
    /// The generator's seed, when there is one.
    #[serde(default, deserialize_with = "lenient_seed")]
    pub seed: Option<u64>,
    /// Number of rows of `labels.csv`.
    #[serde(deserialize_with = "whole_number")]
    pub count: usize,
    /// Anything else a writer recorded (a generator's config, for instance).
    #[serde(flatten)]
    pub extra: serde_json::Map<String, serde_json::Value>,
}

impl Manifest {
    /// What the depth maps hold: `"depth": "indentation"` for a calibrated
    /// sensor's data, else the virtual sensor's camera-to-skin distance.
    pub fn depth_maps(&self) -> crate::spec::DepthMaps {
        match self.extra.get("depth").and_then(|v| v.as_str()) {
            Some("indentation") => crate::spec::DepthMaps::Indentation,
            _ => crate::spec::DepthMaps::Distance,
        }
    }
}

/// A `split` cell as the toolkit names splits: `train`, `val` or `test`
/// in any case, and as other tools name them (`training`, `valid`,
/// `validation`, `dev`, `testing`); anything else as written, in no split
/// the toolkit makes.
pub fn split_name(cell: &str) -> String {
    match cell.trim().to_ascii_lowercase().as_str() {
        "train" | "training" => "train".into(),
        "val" | "valid" | "validation" | "dev" => "val".into(),
        "test" | "testing" => "test".into(),
        _ => cell.to_string(),
    }
}

/// One row of `labels.csv`: the raw cells by column name, with its line.
#[derive(Debug, Clone)]
pub struct LabelRow {
    /// 1-based line in `labels.csv` (the header is line 1).
    pub line: usize,
    cells: HashMap<String, String>,
}

impl LabelRow {
    /// `tendon` as `True` / `False` (any case), as Python's `csv` module
    /// writes a bool, is the layout's `1` / `0`.
    fn tendon_as_a_number(&mut self) {
        if let Some(t) = self.cells.get_mut("tendon") {
            match t.trim().to_ascii_lowercase().as_str() {
                "true" => *t = "1".into(),
                "false" => *t = "0".into(),
                _ => {}
            }
        }
    }

    /// A row without a tendon has no direction: the layout leaves its
    /// `direction_deg` empty, and a writer that keeps a float for every
    /// row (Python's `csv` module, numpy) writes `nan` there. Read as the
    /// empty cell it stands for. A tendon row's NaN stays a bad label.
    fn no_direction_without_a_tendon(&mut self) {
        let no_tendon = self.get("tendon").is_some_and(|t| t.parse() == Ok(0.0));
        if let Some(d) = self.cells.get_mut("direction_deg")
            && no_tendon
            && d.trim().parse::<f64>().is_ok_and(f64::is_nan)
        {
            d.clear();
        }
    }

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
    /// The dataset folder.
    pub root: PathBuf,
    /// `manifest.json`.
    pub manifest: Manifest,
    /// The columns of `labels.csv`, in header order.
    pub columns: Vec<String>,
    /// `labels.csv`, in order.
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

/// The error for `labels.csv` or `manifest.json` of a dataset (beside a
/// `labels.csv`) named where the dataset's folder was meant, naming the
/// folder; `None` for any other path.
pub fn file_of_a_dataset(path: &Path) -> Option<Error> {
    let named = |n: &str| path.file_name().is_some_and(|f| f == n);
    let is_file = (named("labels.csv") || named("manifest.json"))
        && path.is_file()
        && path.with_file_name("labels.csv").is_file();
    is_file.then(|| {
        Error::Invalid(format!(
            "{}: is a file of a dataset, not frames: pass the dataset's folder {}",
            path.display(),
            crate::io::folder_of(path).display()
        ))
    })
}

/// A dataset's frame must have the size its manifest declares: the one
/// refusal of every reader (the dataset's loaders, a run's frame list).
pub fn expect_manifest_size(
    path: &Path,
    (width, height): (usize, usize),
    (mw, mh): (usize, usize),
) -> Result<()> {
    if (width, height) != (mw, mh) {
        // Read again only to word the refusal; a file that is no picture
        // (a depth map) is not turned.
        let turned = || crate::image_io::image_header(path).is_ok_and(|h| h.turned_sideways);
        let why = if (height, width) == (mw, mh) && turned() {
            // A dataset written by a tool that reads pixels as stored
            // (PIL's `Image.open`) gave the stored size.
            format!(
                "is {width}x{height} as shown: its EXIF orientation turns the {height}x{width} \
                 pixels it stores, and frames are read as shown, as OpenCV reads them; but \
                 manifest.json says the frames are {mw}x{mh}. Save the frame upright (without \
                 the orientation), or make the manifest say {width}x{height}"
            )
        } else {
            format!("is {width}x{height}, but manifest.json says the frames are {mw}x{mh}")
        };
        return Err(Error::image(path, why));
    }
    Ok(())
}

impl Dataset {
    /// [`Self::open`] each of several folders (a model's training sets),
    /// stopping at the first that cannot be opened.
    pub fn open_all(roots: &[impl AsRef<Path>]) -> Result<Vec<Self>> {
        roots.iter().map(Self::open).collect()
    }

    /// Open and check a dataset folder: the manifest parses and has the
    /// right format, `labels.csv` has the kind's columns in order, every
    /// number parses and is finite, and every referenced file exists.
    pub fn open(root: impl AsRef<Path>) -> Result<Self> {
        let root = root.as_ref().to_path_buf();
        if let Some(e) = file_of_a_dataset(&root) {
            return Err(e);
        }
        crate::io::expect_folder(&root, "dataset folder")?;
        let manifest_path = root.join("manifest.json");
        // A pipe or folder named manifest.json is refused by `read_json`.
        if !manifest_path.exists() {
            return Err(Error::dataset(
                &manifest_path,
                None,
                "missing: this is not a dataset folder (docs/datasets.md); \
                 `tactile dataset from-video --video FOLDER --labels CSV` makes one of a folder of frames",
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
        let (w, h) = (manifest.width, manifest.height);
        if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
            return Err(Error::dataset(
                &manifest_path,
                None,
                format!("width and height must be 1 to {MAX_SIDE} pixels, found {w}x{h}"),
            ));
        }
        if manifest.count > MAX_ROWS {
            return Err(Error::dataset(
                &manifest_path,
                None,
                format!("count {} is more than {MAX_ROWS} frames", manifest.count),
            ));
        }
        let labels = root.join("labels.csv");
        let file = crate::io::open_regular(&labels).map_err(|e| match e {
            Error::Io { source, .. } => {
                Error::dataset(&labels, None, format!("cannot read: {source}"))
            }
            other => other,
        })?;
        let mut reader = crate::csv_lines::reader(
            csv::ReaderBuilder::new().has_headers(true).flexible(false),
            file,
        );
        let mut header: Vec<String> = crate::csv_lines::headers(&mut reader)
            .map_err(|why| Error::dataset(&labels, Some(1), why))?
            .iter()
            .map(|s| s.trim().to_string())
            .collect();
        // pandas' index (an unnamed first column) is dropped, as columns
        // the layout does not name are kept and ignored.
        let index_column = header.len() > 1 && crate::csv_lines::is_pandas_index(&header[0]);
        if index_column {
            header.remove(0);
        }
        if let Some((i, dup)) = header
            .iter()
            .enumerate()
            .find(|(i, c)| header[..*i].contains(c))
        {
            return Err(Error::dataset(
                &labels,
                Some(1),
                format!("column '{dup}' appears twice (again as column {})", i + 1),
            ));
        }
        // Cells are read by their column's name, so the layout's columns
        // may come in any order (a table saved by pandas or a spreadsheet
        // after its columns were moved); each must be there.
        let required = manifest.kind.columns();
        let missing: Vec<&str> = required
            .iter()
            .copied()
            .filter(|c| !header.iter().any(|h| h == c))
            .collect();
        if !missing.is_empty() {
            return Err(Error::dataset(
                &labels,
                Some(1),
                format!(
                    "no column {} in the header; a {} dataset's labels need {}, in any order \
                     (found {}){}",
                    missing
                        .iter()
                        .map(|c| format!("'{c}'"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    manifest.kind.name(),
                    required.join(","),
                    header.join(","),
                    match crate::csv_lines::separator_hint(header.iter().map(String::as_str)) {
                        "" =>
                            "; frames without labels need no labels.csv: pass the folder \
                               that holds them",
                        hint => hint,
                    }
                ),
            ));
        }
        let mut rows = Vec::new();
        for item in crate::csv_lines::records(&mut reader) {
            let (line, rec) = item.map_err(|(at, why)| Error::dataset(&labels, Some(at), why))?;
            if rows.len() >= MAX_ROWS {
                return Err(Error::dataset(
                    &labels,
                    Some(line),
                    format!("more than {MAX_ROWS} rows"),
                ));
            }
            let cells = header
                .iter()
                .cloned()
                .zip(
                    rec.iter()
                        .skip(usize::from(index_column))
                        .map(str::to_string),
                )
                .map(|(column, cell)| match column.as_str() {
                    "split" => (column, split_name(&cell)),
                    _ => (column, cell),
                })
                .collect();
            let mut row = LabelRow { line, cells };
            if manifest.kind == DatasetKind::Visuotactile {
                row.tendon_as_a_number();
                row.no_direction_without_a_tendon();
            }
            rows.push(row);
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
            columns: header,
            rows,
        };
        ds.check_rows()?;
        Ok(ds)
    }

    fn check_rows(&self) -> Result<()> {
        let labels = self.labels_path();
        let canonical = self
            .root
            .canonicalize()
            .map_err(|e| Error::io(&self.root, e))?;
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
        // Each frame's split and the line that first gives it one: a
        // `split` column that puts one frame in two splits would fit it and
        // score it (or validate on it) at once.
        let mut split_of: HashMap<PathBuf, (&str, usize)> = HashMap::new();
        for row in &self.rows {
            let Some(file) = row.get("file") else {
                return Err(Error::dataset(
                    &labels,
                    Some(row.line),
                    "column 'file' is empty",
                ));
            };
            // The frame file itself (through `./` and links).
            let mut frame = None;
            for col in file_columns {
                let Some(rel) = row.get(col) else { continue };
                let bad = |why: &str| {
                    Error::dataset(
                        &labels,
                        Some(row.line),
                        format!("column '{col}': '{rel}' {why}"),
                    )
                };
                let path = resolve_inside(&canonical, rel).map_err(|e| bad(e.describe()))?;
                match std::fs::metadata(&path) {
                    Err(_) => {
                        return Err(bad(&format!("does not exist{}", backslash_hint(rel))));
                    }
                    Ok(m) if !m.is_file() => {
                        return Err(bad("is not a regular file (a folder, a pipe or a device)"));
                    }
                    Ok(_) => {}
                }
                if *col == "file" {
                    frame = Some(path);
                }
            }
            if let (Some(split @ ("train" | "val" | "test")), Some(frame)) =
                (row.get("split"), frame)
            {
                match split_of.get(&frame) {
                    Some(&(first, line)) if first != split => {
                        return Err(Error::dataset(
                            &labels,
                            Some(row.line),
                            format!(
                                "frame '{file}' is in split '{split}', but line {line} puts it in \
                                 '{first}': a frame is in one split, or it is fitted and scored \
                                 at once (mend the split column, or drop it to split by --seed)"
                            ),
                        ));
                    }
                    Some(_) => {}
                    None => {
                        split_of.insert(frame, (split, row.line));
                    }
                }
            }
            for col in number_columns {
                let value = parse_number(&labels, row, col)?;
                // Every reader asks `tendon == 1`: a 2 or a 0.5 would read
                // as no tendon, silently.
                if *col == "tendon"
                    && let Some(v) = value.filter(|v| *v != 0.0 && *v != 1.0)
                {
                    return Err(Error::dataset(
                        &labels,
                        Some(row.line),
                        format!("column 'tendon': {v} is neither 0 nor 1 (nor true or false)"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Refuse a dataset of another kind than `kind`, naming its manifest.
    pub fn expect_kind(&self, kind: DatasetKind) -> Result<()> {
        if self.manifest.kind == kind {
            return Ok(());
        }
        Err(Error::wrong_kind(
            self.root.join("manifest.json"),
            format!("{} dataset", kind.describe()),
            format!("its kind is '{}'", self.manifest.kind.name()),
        ))
    }

    /// The frame of row `i` as RGB, refused (naming the file) when its
    /// size is not the manifest's. Every `load_*` returns `Interrupted`
    /// once a stop is requested, so a loader over thousands of rows stops
    /// at Ctrl-C instead of decoding them all.
    pub fn load_rgb(&self, i: usize) -> Result<crate::image_io::RgbImage> {
        self.load_sized(i, "file", |p| crate::image_io::load_rgb(p))
    }

    /// The greyscale image in `column` of row `i` (a tendon mask goes
    /// through [`Dataset::load_mask`]), refused (naming the file) when its
    /// size is not the manifest's.
    pub fn load_grey(&self, i: usize, column: &str) -> Result<crate::image_io::GreyImage> {
        self.load_sized(i, column, |p| crate::image_io::load_grey(p))
    }

    /// Whether row `i`'s mask is known: a file in its `mask` cell, or, in
    /// a row without a tendon whose cell is empty (a writer that saves no
    /// mask where there is nothing to mark), the mask that says so.
    pub fn has_mask(&self, i: usize) -> Result<bool> {
        Ok(self.text_opt(i, "mask").is_some() || self.number_opt(i, "tendon")? == Some(0.0))
    }

    /// The tendon mask of row `i` (`image_io::load_mask`: a 0/1 mask is
    /// refused), of the manifest's size; all background in a row without
    /// a tendon whose cell is empty ([`Self::has_mask`]).
    pub fn load_mask(&self, i: usize) -> Result<crate::image_io::GreyImage> {
        if self.text_opt(i, "mask").is_none() && self.has_mask(i)? {
            crate::interrupt::check()?;
            let (w, h) = (self.manifest.width as usize, self.manifest.height as usize);
            return crate::image_io::grey_image(w, h, vec![0; w * h]);
        }
        self.load_sized(i, "mask", |p| crate::image_io::load_mask(p))
    }

    /// The picture in `column` of row `i` read by `load`, once no stop is
    /// requested, refused (naming the file) when its size is not the
    /// manifest's: the one path of every `load_*` of a picture.
    fn load_sized<const C: usize>(
        &self,
        i: usize,
        column: &str,
        load: impl Fn(&Path) -> Result<kornia_image::Image<u8, C>>,
    ) -> Result<kornia_image::Image<u8, C>> {
        crate::interrupt::check()?;
        let path = self.path_of(i, column)?;
        let img = load(&path)?;
        self.expect_frame_size(&path, img.width(), img.height())?;
        Ok(img)
    }

    /// The depth map of row `i` in metres, `(width, height, values)`,
    /// refused (naming the file) when its size is not the manifest's.
    pub fn load_depth_m(&self, i: usize) -> Result<(usize, usize, Vec<f32>)> {
        crate::interrupt::check()?;
        let path = self.path_of(i, "depth")?;
        let (w, h, d) = crate::npy::read_depth_npy_of(&path, self.manifest.depth_maps())?;
        self.expect_frame_size(&path, w, h)?;
        Ok((w, h, d))
    }

    /// Refuse a file of `path` whose size is not the manifest's frame size.
    pub fn expect_frame_size(&self, path: &Path, width: usize, height: usize) -> Result<()> {
        let manifest = (self.manifest.width as usize, self.manifest.height as usize);
        expect_manifest_size(path, (width, height), manifest)
    }

    /// Read the frame header (`file`) of each of `rows` before any frame is
    /// decoded, refusing what loading them would
    /// ([`crate::image_io::rgb_frame_header`], the manifest's size): a bad
    /// frame late in a long dataset stops a chunked read before its first
    /// chunk, not after every chunk before it ([`Error::check_frames`]).
    pub fn check_frame_headers(&self, rows: &[usize]) -> Result<()> {
        Error::check_frames(rows, |&i| {
            let path = self.path_of(i, "file")?;
            let h = crate::image_io::rgb_frame_header(&path)?;
            self.expect_frame_size(&path, h.width as usize, h.height as usize)
        })
    }

    /// Refuse `out` as an output when writing it would change this dataset:
    /// the dataset folder itself, its manifest or labels, a file it
    /// references or a folder holding them (`encode --out DS/labels.csv`).
    pub fn refuse_as_output(&self, out: &Path) -> Result<()> {
        let (Some(root), Some(out_c)) = (canonical_output(&self.root), canonical_output(out))
        else {
            return Ok(());
        };
        let Ok(rel) = out_c.strip_prefix(&root) else {
            return Ok(());
        };
        let protected = |r: &Path| {
            r.as_os_str().is_empty()
                || r == Path::new("manifest.json")
                || r == Path::new("labels.csv")
                || self.rows.iter().any(|row| {
                    ["file", "mask", "depth"].iter().any(|c| {
                        row.get(c)
                            .is_some_and(|f| Path::new(f) == r || Path::new(f).starts_with(r))
                    })
                })
        };
        if protected(rel) {
            return Err(Error::Invalid(format!(
                "{}: this output is part of the input dataset {}; writing it would change the dataset, so nothing was done",
                out.display(),
                self.root.display()
            )));
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

    /// Every row's index, in order: the rows of a call that reads the
    /// whole dataset.
    pub fn every_row(&self) -> Vec<usize> {
        (0..self.rows.len()).collect()
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
        self.rows[i]
            .get(column)
            .ok_or_else(|| self.needed_but_empty(i, column))
    }

    /// The error of a label a command needs that row `i` lacks: the cell
    /// empty, or the column absent from `labels.csv` (a misspelt target),
    /// which is said so with the columns it has.
    fn needed_but_empty(&self, i: usize, column: &str) -> Error {
        if let Err(e) = self.expect_columns([column]) {
            return e;
        }
        Error::dataset(
            self.labels_path(),
            Some(self.rows[i].line),
            format!("column '{column}' is empty, but this command needs it"),
        )
    }

    /// A text label, `None` when empty.
    pub fn text_opt(&self, i: usize, column: &str) -> Option<&str> {
        self.rows[i].get(column)
    }

    /// A numeric label that the calling command needs.
    pub fn number(&self, i: usize, column: &str) -> Result<f64> {
        parse_number(&self.labels_path(), &self.rows[i], column)?
            .ok_or_else(|| self.needed_but_empty(i, column))
    }

    /// A target label of row `i` to learn or score: [`Self::number_opt`],
    /// but `None` where the row's shape has no such quantity
    /// ([`crate::spec::tactip::label_applies`]: a sphere's or a flat's
    /// theta, a flat's position), whatever was written there, so a set
    /// whose generator writes them is read as one that leaves them empty.
    pub fn target_opt(&self, i: usize, column: &str) -> Result<Option<f64>> {
        match self.text_opt(i, "shape") {
            Some(shape) if !crate::spec::tactip::label_applies(shape, column) => Ok(None),
            _ => self.number_opt(i, column),
        }
    }

    /// [`Self::target_opt`] that the calling command needs: a label a
    /// row's shape does not have is refused as an empty one is.
    pub fn target(&self, i: usize, column: &str) -> Result<f64> {
        if let Some(v) = self.target_opt(i, column)? {
            return Ok(v);
        }
        match (self.text_opt(i, "shape"), self.number_opt(i, column)?) {
            (Some(shape), Some(_)) => Err(Error::dataset(
                self.labels_path(),
                Some(self.rows[i].line),
                format!(
                    "column '{column}': a {shape} has no such quantity (sensors.md), so its \
                     value is no label, but this command needs it"
                ),
            )),
            _ => Err(self.needed_but_empty(i, column)),
        }
    }

    /// Check `labels.csv` has every one of `columns` (the targets a command
    /// was asked to learn or score), naming the first it lacks and the
    /// columns it has, before any frame is read: an absent column is a
    /// misspelt flag, not a frame without a label.
    pub fn expect_columns<'a>(&self, columns: impl IntoIterator<Item = &'a str>) -> Result<()> {
        match columns
            .into_iter()
            .find(|c| !self.columns.iter().any(|have| have == c))
        {
            None => Ok(()),
            Some(c) => Err(Error::dataset(
                self.labels_path(),
                Some(1),
                format!("no column '{c}' (its columns: {})", self.columns.join(", ")),
            )),
        }
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
        // A split asked for by another of its names (`--split validation`).
        let split = split_name(split);
        Some(
            (0..self.len())
                .filter(|&i| self.text_opt(i, "split") == Some(split.as_str()))
                .collect(),
        )
    }

    /// The rows of `split` ([`Self::split_indices`]), or, for a dataset
    /// without a `split` column, an error naming its labels.
    pub fn split_rows(&self, split: &str) -> Result<Vec<usize>> {
        self.split_indices(split).ok_or_else(|| {
            Error::dataset(
                self.labels_path(),
                None,
                format!("no 'split' column to take the '{split}' rows from"),
            )
        })
    }

    /// [`Self::open`], then, with `split`, the rows of that split alone
    /// ([`Self::only_split`]): what a scoring of one split reads.
    pub fn open_split(root: impl AsRef<Path>, split: Option<&str>) -> Result<Self> {
        let ds = Self::open(root)?;
        match split {
            Some(split) => ds.only_split(split),
            None => Ok(ds),
        }
    }

    /// The dataset of the rows of `split` alone, in order (a scoring of
    /// one split: `tactile evaluate --split val`); its lines still name
    /// `labels.csv`'s. A split with no row, or a dataset without a `split`
    /// column, is an error naming its labels.
    pub fn only_split(&self, split: &str) -> Result<Dataset> {
        let rows = self.split_rows(split)?;
        if rows.is_empty() {
            return Err(Error::dataset(
                self.labels_path(),
                None,
                format!(
                    "no row of its 'split' column is '{}'{}",
                    split_name(split),
                    self.split_hint()
                ),
            ));
        }
        Ok(self.only_rows(&rows))
    }

    /// The dataset of `rows` alone, in their order (the rows a pass could
    /// read, when it left out frames that cannot be decoded); its lines
    /// still name `labels.csv`'s. A row past the end is left out.
    pub fn only_rows(&self, rows: &[usize]) -> Dataset {
        let rows: Vec<LabelRow> = rows
            .iter()
            .filter_map(|&i| self.rows.get(i).cloned())
            .collect();
        Dataset {
            root: self.root.clone(),
            manifest: Manifest {
                count: rows.len(),
                ..self.manifest.clone()
            },
            columns: self.columns.clone(),
            rows,
        }
    }

    /// What a `split` column holds besides `train`, `val` and `test` (its
    /// values and how many rows each), for an error about too few rows to
    /// say why: empty without such values.
    pub fn split_hint(&self) -> String {
        let mut other: std::collections::BTreeMap<&str, usize> = Default::default();
        for i in 0..self.len() {
            match self.text_opt(i, "split") {
                None | Some("train" | "val" | "test") => {}
                Some(v) => *other.entry(v).or_default() += 1,
            }
        }
        if other.is_empty() {
            return String::new();
        }
        let values: Vec<String> = other
            .iter()
            .map(|(v, n)| format!("'{v}' ({n} rows)"))
            .collect();
        format!(
            " (its split column also holds {}, in no split: name them train, val or test)",
            values.join(", ")
        )
    }

    /// The rows the `split` column holds out for evaluation: its `test`
    /// rows, or its `val` rows when it names no test rows (an authors'
    /// train/val split, where the choices are made on `val`); `None`
    /// without a `split` column.
    pub fn evaluation_split(&self) -> Option<Vec<usize>> {
        self.split_indices(self.evaluation_split_name()?)
    }

    /// The dataset a model's notes name as it was recorded (`trained_on`,
    /// a calibration's `data`): a relative path is relative to the folder
    /// the training ran in, unknown now, so it is looked up from the
    /// current folder, then from each folder above `model_dir`. `None`
    /// when no such dataset opens.
    pub fn open_recorded(recorded: &str, model_dir: &Path) -> Option<Dataset> {
        let recorded = Path::new(recorded);
        if recorded.is_absolute() {
            return Dataset::open(recorded).ok();
        }
        let model_dir = model_dir.canonicalize().ok();
        std::iter::once(PathBuf::new())
            .chain(
                model_dir
                    .iter()
                    .flat_map(|d| d.ancestors().skip(1).map(Path::to_path_buf)),
            )
            .map(|base| base.join(recorded))
            .find(|p| p.join("manifest.json").is_file())
            .and_then(|p| Dataset::open(p).ok())
    }

    /// Whether every frame of `other`'s `rows` is one of this dataset's
    /// `within` rows (every row when `None`): the same file, or a copy of
    /// it (the same bytes, under any name in any folder). A subset copied
    /// out of a dataset is held by it; other frames of the same rig are
    /// not. It tells a bench whether a model fitted or calibrated on this
    /// dataset has seen the frames it scores. It stops at the first frame
    /// not held, reading only frames of a size it asks about.
    pub fn holds_frames(&self, other: &Dataset, rows: &[usize], within: Option<&[usize]>) -> bool {
        let within = within.map_or_else(|| (0..self.len()).collect(), <[usize]>::to_vec);
        let mut copies = self.frame_copies(&within);
        let theirs = other.frame_files();
        rows.iter().all(|&j| {
            theirs
                .get(j)
                .and_then(Option::as_deref)
                .is_some_and(|f| copies.holds(f))
        })
    }

    /// The name of the split [`Self::evaluation_split`] takes: `test`
    /// when the `split` column names test rows, else `val`.
    pub fn evaluation_split_name(&self) -> Option<&'static str> {
        let test = self.split_indices("test")?;
        Some(if test.is_empty() { "val" } else { "test" })
    }
}

/// What a results file holds, to check its name against
/// ([`refuse_misnamed_results`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResultsFormat {
    /// Comma-separated values: a header row, then a row per frame.
    Csv,
    /// JSON Lines: one JSON object per line.
    JsonLines,
}

impl ResultsFormat {
    fn describe(self) -> &'static str {
        match self {
            Self::Csv => {
                "comma-separated values (a header row, then one row per frame): name it .csv"
            }
            Self::JsonLines => {
                "JSON Lines (one JSON record per frame): name it .jsonl (pandas reads it with \
                 read_json(path, lines=True))"
            }
        }
    }
}

/// Refuse a results file `out` named as another format than the `format`
/// written: a reader chosen by the name (a spreadsheet, `pandas.read_csv`,
/// `json.load`) would misread it. JSON Lines may be named `.json`, as
/// loggers often do; a compressed bag (`.mcap.zstd`) is never written.
pub fn refuse_misnamed_results(out: &Path, format: ResultsFormat) -> Result<()> {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let ends = |suffixes: &[&str]| suffixes.iter().any(|s| name.ends_with(s));
    let named = if ends(&[".mcap.zstd"]) {
        "a compressed bag (outputs are written uncompressed, as .mcap where a command writes ROS 2 messages)"
    } else if ends(&[".xlsx", ".xls", ".ods"]) {
        "a spreadsheet workbook"
    } else if format == ResultsFormat::JsonLines && ends(&[".csv", ".tsv"]) {
        "a table"
    } else if format == ResultsFormat::Csv && ends(&[".tsv"]) {
        "tab-separated values"
    } else if format == ResultsFormat::Csv && ends(&[".json", ".jsonl", ".ndjson"]) {
        "JSON"
    } else {
        return Ok(());
    };
    Err(Error::Config(format!(
        "{}: named as {named}, but this writes {}",
        out.display(),
        format.describe()
    )))
}

/// Before any work: the output file `out` can be written, is none of the
/// files of the input `datasets`, none of a dataset, calibration folder
/// or bag it lies in ([`refuse_file_of_enclosing_input`]) and none a model is loaded
/// from ([`crate::io::refuse_model_file`]).
pub fn check_output_file(out: &Path, datasets: &[&Dataset]) -> Result<()> {
    for ds in datasets {
        ds.refuse_as_output(out)?;
    }
    let target = crate::io::output_path(out)?;
    crate::io::refuse_model_file(out, &target)?;
    refuse_file_of_enclosing_input(out, &target)?;
    crate::io::ensure_writable_parent(target)
}

/// Before any work: the output file `out` of a run over `input` (a
/// dataset, a folder of frames, a video or a bag; none for standard input)
/// is none of the input's files, the input's own refusal said first
/// because it says why ([`refuse_input_as_output`]: a bag's files are all
/// read as the bag, a frame of the folder read), then passes
/// [`check_output_file`]. `tactile run` and `tactile predict` check
/// their records file with it.
pub fn check_run_output(out: &Path, input: Option<&Path>, datasets: &[&Dataset]) -> Result<()> {
    if let Some(input) = input {
        refuse_input_as_output(out, input)?;
    }
    check_output_file(out, datasets)
}

/// Refuse an output `out` (written at `target`) that would change an input
/// folder it lies in, whether or not the run reads it: a dataset's
/// manifest, labels or a file its rows name, a calibration folder's
/// `sensor.json`, `presses.csv`, background frame and `frames/`, and a
/// ROS 2 bag folder's `metadata.yaml` and MCAP files. A bench
/// page `DS/labels.csv` would otherwise be written over the labels of the
/// dataset it measured, and a page `CAL/background.md` its plot over the
/// rest frame (a bench names no dataset to check against: its inputs are
/// models, bags and calibration folders too). A folder with a
/// `manifest.json` and a `labels.csv` is taken for a dataset (when it
/// does not open as one, its manifest and labels are still kept), one
/// with a `sensor.json` for a calibration folder (docs/datasets.md), one
/// with rosbag2's `metadata.yaml` for a bag ([`crate::bag::is_bag_folder`]).
/// New files beside theirs are results, and may be written.
pub fn refuse_file_of_enclosing_input(out: &Path, target: &Path) -> Result<()> {
    let Some(t) = canonical_output(target) else {
        return Ok(());
    };
    // Every folder above, to the root: a dataset's rows may name files
    // however deep (`DS/frames/session/run/take/x.png`), and the nearest
    // input folder decides.
    for dir in t.ancestors().skip(1) {
        let (manifest, labels) = (dir.join("manifest.json"), dir.join("labels.csv"));
        if manifest.is_file() && labels.is_file() {
            return match Dataset::open(dir) {
                Ok(ds) => ds
                    .refuse_as_output(&t)
                    .map_err(|_| input_file_error(out, "dataset", dir)),
                Err(_) if t == manifest || t == labels => {
                    Err(input_file_error(out, "dataset", dir))
                }
                Err(_) => Ok(()),
            };
        }
        // A bag's files are all read as the bag: a new MCAP file in its
        // folder would join the recording.
        if crate::bag::is_bag_folder(dir) {
            let in_bag = t.parent() == Some(dir)
                && (t.file_name() == Some(std::ffi::OsStr::new("metadata.yaml"))
                    || crate::bag::is_bag_input_file(&t));
            return match in_bag {
                true => Err(Error::Invalid(format!(
                    "{}: this output is part of the ROS 2 bag {}, whose MCAP files are all read as the bag; writing it would change the bag, so nothing was done",
                    out.display(),
                    dir.display()
                ))),
                false => Ok(()),
            };
        }
        let sensor = dir.join("sensor.json");
        if sensor.is_file() {
            // The background is named in sensor.json (default background.png).
            let background = crate::io::read_json::<serde_json::Value>(&sensor)
                .ok()
                .and_then(|v| v.get("background")?.as_str().map(PathBuf::from))
                .unwrap_or_else(|| PathBuf::from("background.png"));
            let rel = t.strip_prefix(dir).unwrap_or(&t);
            let kept = rel == Path::new("sensor.json")
                || rel == Path::new("presses.csv")
                || rel == background
                || rel.starts_with("frames");
            return match kept {
                true => Err(input_file_error(out, "calibration folder", dir)),
                false => Ok(()),
            };
        }
    }
    Ok(())
}

fn input_file_error(out: &Path, kind: &str, dir: &Path) -> Error {
    Error::Invalid(format!(
        "{}: this output is part of the {kind} {}; writing it would change the {kind}, so nothing was done",
        out.display(),
        dir.display()
    ))
}

/// `p` made absolute with its links resolved: itself when it exists, else
/// its folder's canonical path joined to its name (an output not yet
/// written; [`output_place`]). `None` when neither exists.
fn canonical_output(p: &Path) -> Option<PathBuf> {
    (p.exists() || crate::io::folder_of(p).exists()).then(|| output_place(p))
}

/// Where an output will be, however it is spelt: its deepest existing
/// ancestor resolved (links, `..`), the rest as given. The one resolution
/// of an output's place ([`canonical_output`] is it where the output or
/// its folder exists).
fn output_place(p: &Path) -> PathBuf {
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    for anc in abs.ancestors() {
        if let (Ok(c), Ok(rest)) = (anc.canonicalize(), abs.strip_prefix(anc)) {
            return match rest.as_os_str().is_empty() {
                true => c,
                false => c.join(rest),
            };
        }
    }
    abs
}

/// Before any work: two outputs of one run (`--frames` and
/// `--reliability`, `--out` and `--render`) name two places, neither inside
/// the other: written to one place, the second would silently replace the
/// first, and a new folder would hold (or, made second, fail over) the
/// output inside it.
pub fn refuse_same_output(first: &Path, second: &Path) -> Result<()> {
    let (a, b) = (output_place(first), output_place(second));
    let why = if a == b {
        "two outputs of this run name one place, and the second would replace the first"
    } else if a.starts_with(&b) || b.starts_with(&a) {
        "one output of this run lies inside the other, a new folder that would hold it"
    } else {
        return Ok(());
    };
    Err(Error::Invalid(format!(
        "{} and {}: {why}; give each its own place, so nothing was done",
        first.display(),
        second.display()
    )))
}

/// Before any work: the output file `out` is not the input file itself
/// (`--data rec.mcap --out rec.mcap`), which writing it would replace, nor
/// a frame of the input folder of frames (`--data frames --out
/// frames/0001.png`), which it would replace or join.
pub fn refuse_input_as_output(out: &Path, input: &Path) -> Result<()> {
    let (Some(o), Ok(i)) = (canonical_output(out), input.canonicalize()) else {
        return Ok(());
    };
    if o == i {
        return Err(Error::Invalid(format!(
            "{}: this output is the input; give another file, so nothing was done",
            out.display()
        )));
    }
    // The bag folder of the input, given whole or as one of its files.
    let bag_folder = match crate::bag::is_bag_folder(&i) {
        true => Some(i.as_path()),
        false => i.parent().filter(|p| crate::bag::is_bag_folder(p)),
    };
    if let Some(bag) = bag_folder.filter(|b| o.starts_with(b)) {
        return Err(Error::Invalid(format!(
            "{}: this output is inside the input bag folder {}, whose MCAP files are all read as the bag; give a file outside it, so nothing was done",
            out.display(),
            bag.display()
        )));
    }
    if i.is_dir() && o.parent() == Some(i.as_path()) && crate::source::is_frame_file(&o) {
        return Err(Error::Invalid(format!(
            "{}: this output is named like a frame of the input folder {}; writing it would change the frames, so nothing was done",
            out.display(),
            input.display()
        )));
    }
    Ok(())
}

/// Before a model with the config `config` is trained into `out`: as
/// [`check_output_dir`], and `out` holds no model of another kind
/// ([`crate::io::refuse_other_model`]).
pub fn check_model_dir(out: &Path, datasets: &[&Dataset], config: &str) -> Result<()> {
    check_output_dir(out, datasets)?;
    crate::io::refuse_other_model(out, config)
}

/// Before any work: the output folder `out` can be written and is not
/// part of the input `datasets`.
pub fn check_output_dir(out: &Path, datasets: &[&Dataset]) -> Result<()> {
    for ds in datasets {
        ds.refuse_as_output(out)?;
    }
    crate::io::ensure_writable_dir(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_named_as_another_format_are_refused() {
        use ResultsFormat::{Csv, JsonLines};
        for (name, format, named) in [
            ("est.jsonl", Csv, Some("JSON")),
            ("est.JSON", Csv, Some("JSON")),
            ("est.ndjson", Csv, Some("JSON")),
            ("est.tsv", Csv, Some("tab-separated")),
            ("est.xlsx", Csv, Some("a spreadsheet workbook")),
            ("r.mcap.zstd", Csv, Some("a compressed bag")),
            ("records.csv", JsonLines, Some("a table")),
            ("records.TSV", JsonLines, Some("a table")),
            ("records.ods", JsonLines, Some("a spreadsheet workbook")),
            ("r.mcap.zstd", JsonLines, Some("a compressed bag")),
            ("est.csv", Csv, None),
            ("est.txt", Csv, None),
            ("est", Csv, None),
            ("records.jsonl", JsonLines, None),
            ("records.json", JsonLines, None),
            ("csv", JsonLines, None),
        ] {
            let got = refuse_misnamed_results(Path::new("out").join(name).as_path(), format);
            match named {
                None => assert!(got.is_ok(), "{name}: {got:?}"),
                Some(n) => {
                    let e = got.unwrap_err().to_string();
                    assert!(
                        e.contains(name) && e.contains(&format!("named as {n}")),
                        "{name}: {e}"
                    );
                }
            }
        }
    }

    #[test]
    fn two_outputs_naming_one_place_are_refused_however_they_are_spelt() {
        let tmp = tempfile::tempdir().unwrap();
        let a = tmp.path().join("a.csv");
        let spelt = tmp.path().join("sub/../a.csv");
        std::fs::create_dir(tmp.path().join("sub")).unwrap();
        assert!(refuse_same_output(&a, &a).is_err());
        assert!(refuse_same_output(&a, &spelt).is_err(), "another spelling");
        std::os::unix::fs::symlink(&a, tmp.path().join("link.csv")).unwrap();
        std::fs::write(&a, b"x").unwrap();
        assert!(
            refuse_same_output(&a, &tmp.path().join("link.csv")).is_err(),
            "a link"
        );
        refuse_same_output(&a, &tmp.path().join("b.csv")).unwrap();
        // One inside the other, existing or not, however spelt: refused.
        let render = tmp.path().join("new/render");
        for inside in [
            render.join("x.jsonl"),
            tmp.path().join("new/./render/sub/x.jsonl"),
        ] {
            let e = refuse_same_output(&inside, &render)
                .unwrap_err()
                .to_string();
            assert!(e.contains("lies inside the other"), "{e}");
            assert!(refuse_same_output(&render, &inside).is_err());
        }
        assert!(refuse_same_output(&tmp.path().join("sub/../new/render"), &render).is_err());
        refuse_same_output(&tmp.path().join("new/records.jsonl"), &render).unwrap();
        refuse_same_output(&tmp.path().join("new/render-2"), &render).unwrap();
    }

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
    fn a_label_of_a_column_the_labels_lack_names_the_columns_they_have() {
        let d = tempfile::tempdir().unwrap();
        let ds = d.path().join("ds");
        tiny(&ds, &format!("{HEADER}frames/a.png,sphere,1.5,,0,2,3.4\n"));
        let ds = Dataset::open(&ds).unwrap();
        // A misspelt class or target column (`compare --classify shpae`).
        let want = "labels.csv:1: no column 'shpae' (its columns: file, shape, x_mm, y_mm, theta_deg, depth_mm, force_n)";
        let e = ds.text(0, "shpae").unwrap_err().to_string();
        assert!(e.ends_with(want), "{e}");
        let e = ds.number(0, "shpae").unwrap_err().to_string();
        assert!(e.ends_with(want), "{e}");
        // A column it has, empty on this row: the row's line.
        let e = ds.number(0, "y_mm").unwrap_err().to_string();
        assert!(
            e.ends_with("labels.csv:2: column 'y_mm' is empty, but this command needs it"),
            "{e}"
        );
    }

    /// Another implementation of the virtual TacTip may draw and write a
    /// sphere's theta and a flat's position: they are read as the empty
    /// cells the project's generator leaves, by every trainer and scorer.
    #[test]
    fn labels_a_shape_has_not_are_no_targets_whatever_was_written() {
        let d = tempfile::tempdir().unwrap();
        let ds = d.path().join("ds");
        tiny(
            &ds,
            &format!(
                "{HEADER}frames/a.png,sphere,1.5,-2,37,2,3.4\nframes/a.png,flat,4,5,120,1,9\n\
                 frames/a.png,edge,3,0,45,1,2\nframes/a.png,flat,,,,1,9\n"
            ),
        );
        let ds = Dataset::open(&ds).unwrap();
        // The sphere keeps its position, not its theta; the flat neither.
        assert_eq!(ds.target_opt(0, "x_mm").unwrap(), Some(1.5));
        assert_eq!(ds.target_opt(0, "theta_deg").unwrap(), None);
        assert_eq!(ds.number_opt(0, "theta_deg").unwrap(), Some(37.0));
        for c in ["x_mm", "y_mm", "theta_deg"] {
            assert_eq!(ds.target_opt(1, c).unwrap(), None, "{c}");
        }
        assert_eq!(ds.target_opt(1, "depth_mm").unwrap(), Some(1.0));
        assert_eq!(ds.target_opt(2, "theta_deg").unwrap(), Some(45.0));
        // A command that needs it says why, or that it is empty.
        let e = ds.target(0, "theta_deg").unwrap_err().to_string();
        assert!(
            e.ends_with("labels.csv:2: column 'theta_deg': a sphere has no such quantity (sensors.md), so its value is no label, but this command needs it"),
            "{e}"
        );
        let e = ds.target(3, "x_mm").unwrap_err().to_string();
        assert!(
            e.ends_with("labels.csv:5: column 'x_mm' is empty, but this command needs it"),
            "{e}"
        );
    }

    #[test]
    fn outputs_never_change_an_input_folder_they_lie_in_whether_or_not_it_is_read() {
        let d = tempfile::tempdir().unwrap();
        let ds = d.path().join("ds");
        tiny(&ds, &format!("{HEADER}frames/a.png,sphere,1.5,,0,2,3.4\n"));
        let labels = std::fs::read(ds.join("labels.csv")).unwrap();
        // Each of `files` in `dir` refused as an output, the error saying `says`.
        let refused = |dir: &Path, files: &[&str], says: &str| {
            for f in files {
                let e = check_output_file(&dir.join(f), &[])
                    .unwrap_err()
                    .to_string();
                assert!(e.contains(says), "{f}: {e}");
            }
        };
        // No dataset given: the output's own place says it is one's.
        refused(
            &ds,
            &["labels.csv", "manifest.json", "frames/a.png"],
            "is part of the dataset",
        );
        // Through a link, and from a folder of the dataset.
        std::os::unix::fs::symlink(ds.join("labels.csv"), d.path().join("page.md")).unwrap();
        assert!(check_output_file(&d.path().join("page.md"), &[]).is_err());
        // New files beside the dataset's, or in its folders, are results.
        check_output_file(&ds.join("estimates.csv"), &[]).unwrap();
        check_output_file(&ds.join("frames/b.png.md"), &[]).unwrap();
        check_output_file(&d.path().join("labels.csv"), &[]).unwrap();
        // A folder that looks like a dataset but does not open as one
        // keeps its manifest and labels.
        std::fs::write(ds.join("manifest.json"), "{ not json").unwrap();
        assert!(check_output_file(&ds.join("labels.csv"), &[]).is_err());
        check_output_file(&ds.join("frames/a.png"), &[]).unwrap();
        assert_eq!(std::fs::read(ds.join("labels.csv")).unwrap(), labels);
        // However deep a file its rows name lies (a recording's sessions,
        // runs and takes): the folders above an output are looked at up
        // to the root, not a fixed few.
        let deep = d.path().join("deep");
        let nested = "frames/s1/run2/take3/cam4/b.png";
        tiny(
            &deep,
            &format!("{HEADER}frames/a.png,sphere,1.5,,0,2,3.4\n{nested},sphere,1.5,,0,2,3.4\n"),
        );
        std::fs::create_dir_all(deep.join("frames/s1/run2/take3/cam4")).unwrap();
        crate::image_io::save_grey_png(deep.join(nested), 4, 4, &[0; 16]).unwrap();
        refused(&deep, &[nested], "is part of the dataset");
        check_output_file(&deep.join("frames/s1/run2/take3/cam4/b.md"), &[]).unwrap();
        // A calibration folder keeps its description, annotations, rest
        // frame (the one sensor.json names) and presses.
        let cal = d.path().join("cal");
        std::fs::create_dir_all(cal.join("frames/day1/ball4mm/take2")).unwrap();
        std::fs::write(cal.join("sensor.json"), r#"{"background": "rest.png"}"#).unwrap();
        for f in ["presses.csv", "rest.png", "frames/p1.png", "notes.md"] {
            std::fs::write(cal.join(f), b"x").unwrap();
        }
        refused(
            &cal,
            &[
                "sensor.json",
                "presses.csv",
                "rest.png",
                "frames/p1.png",
                "frames/new.md",
                "frames/day1/ball4mm/take2/p1.png",
            ],
            "is part of the calibration folder",
        );
        for f in ["notes.md", "page.md", "background.png"] {
            check_output_file(&cal.join(f), &[]).unwrap_or_else(|e| panic!("{f}: {e}"));
        }
        // A ROS 2 bag folder keeps its metadata and recordings, and takes
        // no new MCAP file, which would be read as part of the bag.
        let bag = d.path().join("bag");
        std::fs::create_dir_all(&bag).unwrap();
        std::fs::write(bag.join("metadata.yaml"), "rosbag2_bagfile_information:\n").unwrap();
        std::fs::write(bag.join("rec_0.mcap"), b"x").unwrap();
        refused(
            &bag,
            &[
                "metadata.yaml",
                "rec_0.mcap",
                "results.mcap",
                "rec_1.mcap.zstd",
            ],
            "is part of the ROS 2 bag",
        );
        check_output_file(&bag.join("page.md"), &[]).unwrap();
    }

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
    fn a_dataset_saved_by_windows_tools_opens() {
        // Notepad and Excel ("CSV UTF-8") begin a file with a UTF-8 byte
        // order mark, and end lines with CRLF. Before, the manifest was
        // refused: "manifest.json:1: expected value at line 1 column 1".
        let d = tempfile::tempdir().unwrap();
        let labels = format!("{HEADER}frames/a.png,sphere,1.5,,0,2,3.4\n").replace('\n', "\r\n");
        tiny(d.path(), &format!("\u{feff}{labels}"));
        let manifest = std::fs::read_to_string(d.path().join("manifest.json")).unwrap();
        let manifest = format!("\u{feff}{}", manifest.replace('\n', "\r\n"));
        std::fs::write(d.path().join("manifest.json"), manifest).unwrap();
        let ds = Dataset::open(d.path()).unwrap();
        assert_eq!((ds.len(), ds.number(0, "force_n").unwrap()), (1, 3.4));
    }

    #[test]
    fn a_labels_csv_saved_as_utf16_says_how_to_save_it() {
        // Excel's "Unicode Text": UTF-16 LE after its byte order mark.
        let d = tempfile::tempdir().unwrap();
        let utf16 = |text: &str| -> Vec<u8> {
            [0xfeff_u16]
                .into_iter()
                .chain(text.encode_utf16())
                .flat_map(u16::to_le_bytes)
                .collect()
        };
        let text = format!("{HEADER}frames/a.png,sphere,1.5,,0,2,3.4\n");
        tiny(d.path(), &text);
        std::fs::write(d.path().join("labels.csv"), utf16(&text)).unwrap();
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(
            e.contains("labels.csv:1: bad header:") && e.contains("(it is UTF-16 text, as Excel's \"Unicode Text\" saves it: save it as \"CSV UTF-8\""),
            "{e}"
        );
        // A manifest saved as UTF-16 says so too.
        std::fs::write(d.path().join("labels.csv"), &text).unwrap();
        let manifest = std::fs::read_to_string(d.path().join("manifest.json")).unwrap();
        std::fs::write(d.path().join("manifest.json"), utf16(&manifest)).unwrap();
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(
            e.contains("manifest.json") && e.contains("it is UTF-16 text"),
            "{e}"
        );
    }

    #[test]
    fn a_path_written_with_backslashes_is_named_with_its_slashes() {
        // labels.csv written on Windows by os.path.join: `frames\a.png`.
        let d = tempfile::tempdir().unwrap();
        tiny(
            d.path(),
            &format!("{HEADER}frames\\a.png,sphere,1.5,,0,2,3.4\n"),
        );
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(
            e.contains("labels.csv:2: column 'file': 'frames\\a.png' does not exist (a backslash is no folder separator here: write 'frames/a.png')"),
            "{e}"
        );
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
        // Files written with CRLF line endings (Python's csv module, Excel)
        // name the same physical lines as LF files.
        let crlf = |s: String| s.replace('\n', "\r\n");
        tiny(
            d.path(),
            &crlf(format!(
                "{HEADER}frames/a.png,sphere,1,0,0,2,3\nframes/a.png,sphere,abc,0,0,2,3\n"
            )),
        );
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(e.contains("labels.csv:3") && e.contains("'abc'"), "{e}");
        tiny(
            d.path(),
            &crlf(format!(
                "{HEADER}frames/a.png,sphere,1,0,0,2,3\nframes/a.png,sphere,1,0,0,2,3\nframes/gone.png,sphere,1,0,0,2,3\n"
            )),
        );
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(e.contains("labels.csv:4") && e.contains("gone.png"), "{e}");
    }

    /// Another writer's manifest: sizes written as floats (`300.0`, as
    /// Python's `json.dump` writes a float), a seed that 64 bits do not
    /// hold (numpy's 128-bit entropy) or that is not a number, no
    /// generator. The frames are read; a size that is no whole number is
    /// refused naming the file and the number.
    #[test]
    fn another_writers_manifest_is_read_by_what_it_means() {
        let d = tempfile::tempdir().unwrap();
        tiny(d.path(), &format!("{HEADER}frames/a.png,flat,0,0,0,1,1\n"));
        let path = d.path().join("manifest.json");
        let base = std::fs::read_to_string(&path).unwrap();
        let with = |from: &str, to: &str| {
            assert!(base.contains(from), "{from}");
            std::fs::write(&path, base.replacen(from, to, 1)).unwrap();
            Dataset::open(d.path())
        };
        let seed_128 = "\"seed\": 340282366920938463463374607431768211455";
        for (from, to, seed) in [
            ("\"width\": 4", "\"width\": 4.0", Some(1)),
            ("\"count\": 1", "\"count\": 1.0", Some(1)),
            ("\"seed\": 1", "\"seed\": 7.0", Some(7)),
            ("\"seed\": 1", seed_128, None),
            ("\"seed\": 1", "\"seed\": -5", None),
            ("\"seed\": 1", "\"seed\": \"none\"", None),
            ("\"generator\": \"test\",", "", Some(1)),
        ] {
            let ds = with(from, to).unwrap_or_else(|e| panic!("{to}: {e}"));
            assert_eq!(
                (ds.len(), ds.manifest.width, ds.manifest.seed),
                (1, 4, seed),
                "{to}"
            );
        }
        for (from, to, named) in [
            (
                "\"width\": 4",
                "\"width\": 4.5",
                "4.5 is not a whole number",
            ),
            (
                "\"height\": 4",
                "\"height\": -4",
                "-4 is not a whole number",
            ),
            (
                "\"width\": 4",
                "\"width\": 5e9",
                "5000000000.0 is not a whole number",
            ),
            ("\"width\": 4", "\"width\": \"4\"", "invalid type: string"),
        ] {
            let e = with(from, to).unwrap_err().to_string();
            assert!(
                e.contains("manifest.json") && e.contains(named),
                "{to}: {e}"
            );
        }
    }

    /// `labels.csv` as pandas' `to_csv` writes it by default: its index
    /// first, an unnamed column (`Unnamed: 0` once read and saved again).
    /// Read without it; an unnamed first column before anything else than
    /// `file` is still a wrong header.
    #[test]
    fn labels_with_pandas_index_column_first_are_read_without_it() {
        let d = tempfile::tempdir().unwrap();
        for index in ["", "Unnamed: 0"] {
            tiny(
                d.path(),
                &format!("{index},{HEADER}0,frames/a.png,flat,1.5,0,0,1,1\n"),
            );
            let ds = Dataset::open(d.path()).unwrap_or_else(|e| panic!("{index:?}: {e}"));
            assert_eq!(ds.columns[..2], ["file", "shape"], "{index:?}");
            assert_eq!(ds.number(0, "x_mm").unwrap(), 1.5, "{index:?}");
            assert_eq!(ds.text(0, "file").unwrap(), "frames/a.png", "{index:?}");
        }
        tiny(d.path(), ",shape,file\n0,flat,frames/a.png\n");
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(
            e.contains(
                "labels.csv:1: no column 'x_mm', 'y_mm', 'theta_deg', 'depth_mm', 'force_n'"
            ),
            "{e}"
        );
    }

    /// A table whose columns were moved (pandas' `df[cols].to_csv`, a
    /// spreadsheet), with the layout's columns among others: read by name,
    /// as the same table in the layout's order. Before, refused ("header
    /// must start with ...").
    #[test]
    fn the_layouts_columns_are_read_in_any_order() {
        let d = tempfile::tempdir().unwrap();
        let ordered = d.path().join("ordered");
        tiny(
            &ordered,
            &format!("{HEADER}frames/a.png,sphere,1.5,-2,,2,3.4\n"),
        );
        let moved = d.path().join("moved");
        tiny(
            &moved,
            ",force_n,split,depth_mm,shape,file,note,theta_deg,y_mm,x_mm\n\
             0,3.4,val,2,sphere,frames/a.png,\"a, b\",,-2,1.5\n",
        );
        let (a, b) = (
            Dataset::open(&ordered).unwrap(),
            Dataset::open(&moved).unwrap(),
        );
        for t in ["x_mm", "y_mm", "depth_mm", "force_n"] {
            assert_eq!(a.number(0, t).unwrap(), b.number(0, t).unwrap(), "{t}");
        }
        assert_eq!(b.text(0, "shape").unwrap(), "sphere");
        assert_eq!(b.number_opt(0, "theta_deg").unwrap(), None);
        assert_eq!(b.load_grey(0, "file").unwrap().width(), 4);
        assert_eq!(b.split_indices("val"), Some(vec![0]));
        // A column of the layout missing is named, with the rest of what
        // the labels need.
        tiny(
            &moved,
            "shape,file,x_mm,y_mm,depth_mm,force_n\nsphere,frames/a.png,1,2,3,4\n",
        );
        let e = Dataset::open(&moved).unwrap_err().to_string();
        assert!(
            e.contains(
                "labels.csv:1: no column 'theta_deg' in the header; a tactip dataset's labels \
                 need file,shape,x_mm,y_mm,theta_deg,depth_mm,force_n, in any order"
            ),
            "{e}"
        );
    }

    #[test]
    fn wrong_header_and_manifest_are_named() {
        let d = tempfile::tempdir().unwrap();
        tiny(d.path(), "file,x_mm\nframes/a.png,1\n");
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(e.contains("labels.csv:1"), "{e}");
        // Unlabelled frames listed by file alone: told to pass their folder.
        assert!(e.contains("pass the folder that holds them"), "{e}");
        // Labels saved by a spreadsheet with semicolons: told so.
        tiny(d.path(), "file;shape;x_mm\nframes/a.png;flat;1,5\n");
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(
            e.contains("labels.csv:1") && e.contains("holding ';'"),
            "{e}"
        );
        std::fs::write(d.path().join("manifest.json"), "{ not json").unwrap();
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(e.contains("manifest.json"), "{e}");
        // A folder of frames alone is told how to become a dataset.
        std::fs::remove_file(d.path().join("manifest.json")).unwrap();
        let e = Dataset::open(d.path()).unwrap_err().to_string();
        assert!(
            e.contains("manifest.json") && e.contains("from-video"),
            "{e}"
        );
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

    /// A dataset of `frames` 4x4 frames `frames/f{k}.png`, listed by
    /// `rows` (one row per entry, naming frame k as written).
    fn listed(dir: &Path, frames: usize, rows: &[String]) -> Dataset {
        std::fs::create_dir_all(dir.join("frames")).unwrap();
        for k in 0..frames {
            let path = dir.join(format!("frames/f{k}.png"));
            crate::image_io::save_grey_png(path, 4, 4, &[k as u8; 16]).unwrap();
        }
        let body: String = rows
            .iter()
            .map(|f| format!("{f},flat,0,0,0,1,0.5\n"))
            .collect();
        tiny(dir, &format!("{HEADER}{body}"));
        Dataset::open(dir).unwrap()
    }

    #[test]
    fn a_frame_listed_on_several_rows_is_never_on_both_sides_of_a_split() {
        // A user oversampling frames by repeating their rows: before, the
        // shuffles split rows, so a repeated frame could be fitted and
        // tested (or fitted and validated), flattering the test error.
        let d = tempfile::tempdir().unwrap();
        let once: Vec<String> = (0..20).map(|k| format!("frames/f{k}.png")).collect();
        // Frames 0-9 listed three times (once as `./frames/…`), 10-19 once.
        let mut rows = once.clone();
        for k in 0..10 {
            rows.push(format!("frames/f{k}.png"));
            rows.push(format!("./frames/f{k}.png"));
        }
        let frame = |ds: &Dataset, i: usize| {
            ds.text(i, "file")
                .unwrap()
                .trim_start_matches("./")
                .to_string()
        };
        let frames = |ds: &Dataset, r: &[usize]| -> std::collections::BTreeSet<String> {
            r.iter().map(|&i| frame(ds, i)).collect()
        };
        let all_once = |mut r: Vec<usize>, n: usize| {
            r.sort_unstable();
            assert_eq!(r, (0..n).collect::<Vec<_>>());
        };
        // Frames each listed once are split as the shuffles alone split
        // them (the splits every model and table so far were made with).
        let ds = listed(&d.path().join("once"), 20, &once);
        let s = ds.three_way_split(0.2, 0.2, 7).unwrap();
        assert_eq!(
            (s.train, s.val, s.test),
            (
                vec![12, 13, 6, 0, 7, 11, 18, 15, 17, 4, 14, 19, 5],
                vec![16, 8, 3],
                vec![2, 10, 1, 9]
            )
        );
        let every: Vec<usize> = (0..20).collect();
        assert_eq!(
            ds.hold_out(every.clone(), 0.2, 7).unwrap(),
            hold_out(every, 0.2, 7).unwrap()
        );
        assert_eq!(
            ds.split_by_sequence(0.2, 7).unwrap(),
            (
                vec![0, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14, 15, 16, 19],
                vec![1, 10, 17, 18]
            )
        );
        let ds = listed(&d.path().join("repeated"), 20, &rows);
        for seed in 0..20 {
            let s = ds.three_way_split(0.2, 0.2, seed).unwrap();
            let (tr, va, te) = (
                frames(&ds, &s.train),
                frames(&ds, &s.val),
                frames(&ds, &s.test),
            );
            assert!(
                tr.is_disjoint(&te) && tr.is_disjoint(&va) && va.is_disjoint(&te),
                "seed {seed}"
            );
            assert!(!s.val.is_empty() && !s.test.is_empty());
            all_once([s.train, s.val, s.test].concat(), rows.len());
            let (tr, va) = ds.hold_out((0..rows.len()).collect(), 0.2, seed).unwrap();
            assert!(
                frames(&ds, &tr).is_disjoint(&frames(&ds, &va)),
                "seed {seed}"
            );
            all_once([tr, va].concat(), rows.len());
            let (tr, va) = ds.split_by_sequence(0.2, seed).unwrap();
            assert!(
                frames(&ds, &tr).is_disjoint(&frames(&ds, &va)),
                "seed {seed}"
            );
            all_once([tr, va].concat(), rows.len());
        }
        // One frame on every row cannot be split: named by labels.csv.
        let one = vec!["frames/f0.png".to_string(); 6];
        let ds = listed(&d.path().join("one"), 1, &one);
        let e = ds.three_way_split(0.2, 0.2, 7).unwrap_err().to_string();
        assert!(
            e.contains("labels.csv") && e.contains("too few frames"),
            "{e}"
        );
        let e = ds
            .hold_out((0..6).collect(), 0.2, 7)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("labels.csv") && e.contains("need at least 2 training frames, found 1"),
            "{e}"
        );
    }

    /// A dataset whose rows list frame `frames/f{k}.png` in `split`, for
    /// each `(k, split)`.
    fn with_splits<'a>(dir: &Path, rows: impl Iterator<Item = (usize, &'a str)>) {
        std::fs::create_dir_all(dir.join("frames")).unwrap();
        let mut body = String::new();
        for (k, split) in rows {
            let path = dir.join(format!("frames/f{k}.png"));
            crate::image_io::save_grey_png(path, 4, 4, &[k as u8; 16]).unwrap();
            body.push_str(&format!("frames/f{k}.png,flat,0,0,0,1,0.5,{split}\n"));
        }
        let header = HEADER.replace('\n', ",split\n");
        tiny(dir, &format!("{header}{body}"));
    }

    #[test]
    fn a_split_column_that_puts_one_frame_in_two_splits_is_refused() {
        // A split column mended by hand, or two label files pasted
        // together: a frame on a `train` row and on a `test` row would be
        // fitted and scored at once. Before, it was taken as written.
        let d = tempfile::tempdir().unwrap();
        let dir = d.path().join("leaky");
        with_splits(
            &dir,
            [
                (0, "train"),
                (1, "train"),
                (2, "Test"),
                (1, "test"),
                (0, "train"),
            ]
            .into_iter(),
        );
        let e = Dataset::open(&dir).unwrap_err().to_string();
        assert!(
            e.contains("labels.csv")
                && e.contains(":5")
                && e.contains("frame 'frames/f1.png' is in split 'test'")
                && e.contains("line 3 puts it in 'train'"),
            "{e}"
        );
        // The same frame through `./` is the same frame.
        let labels = dir.join("labels.csv");
        let text = std::fs::read_to_string(&labels).unwrap();
        std::fs::write(
            &labels,
            text.replace(
                "frames/f1.png,flat,0,0,0,1,0.5,test",
                "./frames/f1.png,flat,0,0,0,1,0.5,val",
            ),
        )
        .unwrap();
        let e = Dataset::open(&dir).unwrap_err().to_string();
        assert!(e.contains("in split 'val', but line 3"), "{e}");
        // A frame listed twice in one split (oversampled), or in a split and
        // in a value that is no split, is one frame in one split.
        let dir = d.path().join("oversampled");
        with_splits(
            &dir,
            [
                (0, "train"),
                (0, "Train"),
                (1, "test"),
                (1, "fold1"),
                (2, "val"),
            ]
            .into_iter(),
        );
        let ds = Dataset::open(&dir).unwrap();
        assert_eq!(ds.split_indices("train"), Some(vec![0, 1]));
        assert_eq!(ds.split_indices("test"), Some(vec![2]));
    }

    #[test]
    fn split_names_of_other_tools_are_read_and_unknown_ones_are_named() {
        // A split column written by hand or by another tool: `Train`,
        // `Validation`, `TEST`, `training`, `dev`. Before, only the exact
        // `train`, `val` and `test` counted, so training found "0 training
        // frames" without saying why.
        let d = tempfile::tempdir().unwrap();
        let write = |dir: &Path, splits: &[&str]| {
            with_splits(dir, splits.iter().enumerate().map(|(k, s)| (k, *s)));
            Dataset::open(dir).unwrap()
        };
        let named = [
            "Train",
            "training",
            " TRAIN ",
            "Validation",
            "valid",
            "dev",
            "TEST",
            "testing",
            "",
        ];
        let ds = write(&d.path().join("named"), &named);
        assert_eq!(ds.split_indices("train"), Some(vec![0, 1, 2]));
        assert_eq!(ds.split_indices("val"), Some(vec![3, 4, 5]));
        assert_eq!(ds.split_indices("Validation"), Some(vec![3, 4, 5]));
        assert_eq!(ds.split_indices("test"), Some(vec![6, 7]));
        assert_eq!(ds.evaluation_split(), Some(vec![6, 7]));
        assert_eq!(ds.split_hint(), "");
        // Values the toolkit has no split for are kept as written, and an
        // error about too few rows names them.
        let ds = write(
            &d.path().join("folds"),
            &["fold1", "fold1", "fold2", "train"],
        );
        assert_eq!(ds.split_indices("train"), Some(vec![3]));
        let e = ds.hold_out(vec![3], 0.2, 7).unwrap_err().to_string();
        assert!(
            e.contains("labels.csv")
                && e.contains("'fold1' (2 rows), 'fold2' (1 rows)")
                && e.contains("name them train, val or test"),
            "{e}"
        );
        let e = ds.three_way_split(0.2, 0.2, 7).unwrap_err().to_string();
        assert!(e.contains("too few frames") && e.contains("'fold1'"), "{e}");
    }
}
