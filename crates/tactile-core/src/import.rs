//! Bring your own sensor: a video (or a folder of frames) and a CSV of
//! labels become a dataset of the documented layout (`docs/datasets.md`)
//! that every command reads.
//!
//! The labels CSV has a `frame` column naming each labelled frame: its
//! number in the video (0-based), or a file name of the folder. Its other
//! columns are the kind's labels (`docs/datasets.md`); a label column it
//! lacks is left empty (unknown), and columns the kind does not know are
//! kept. For visuo-tactile data, `mask` and `depth` cells name files
//! relative to the labels CSV's folder (kept inside it), copied into the
//! dataset. Frames without a row are not written.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::dataset::resolve_inside;
use crate::dataset::{Dataset, DatasetKind, DatasetWriter, FORMAT, MAX_ROWS, Manifest};
use crate::io::StagedDir;
use crate::{Error, Result};

use crate::source::{FrameList, FrameSource, SourceOptions, SourceSpec};

/// What to import (`tactile dataset from-video`'s flags).
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct ImportOptions {
    /// The video file (anything FFmpeg decodes), a ROS 2 bag (its folder, or
    /// one .mcap or .db3; a frame's number is its index on --topic) or a folder of
    /// frames (a frame's number is its place when ordered by the numbers in
    /// the names), or a TIFF of many pages (a stack: a frame's number is its
    /// page's).
    #[cfg_attr(feature = "clap", arg(long = "video", value_name = "VIDEO"))]
    pub frames: PathBuf,
    /// A bag's image topic (without it, the bag's only image topic).
    #[cfg_attr(feature = "clap", arg(long))]
    pub topic: Option<String>,
    /// Labels CSV: a `frame` column and the kind's label columns
    /// (docs/datasets.md); `mask` and `depth` name files beside it.
    #[cfg_attr(feature = "clap", arg(long))]
    pub labels: PathBuf,
    /// Which sensor the frames are from (TacTip frames are saved grey).
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub kind: DatasetKind,
    /// The dataset folder to write.
    #[cfg_attr(feature = "clap", arg(long))]
    pub out: PathBuf,
    /// The manifest's `sensor_spec`: your rig and camera, in words.
    #[cfg_attr(feature = "clap", arg(long, default_value = "real sensor"))]
    pub sensor: String,
    /// Replace an existing dataset at --out.
    #[cfg_attr(feature = "clap", arg(long))]
    pub force: bool,
}

/// What an import wrote.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ImportSummary {
    /// The dataset folder.
    pub out: PathBuf,
    /// Frames written (one per labels row).
    pub frames: usize,
    /// Frames of the source read through.
    pub frames_read: u64,
    /// Frame width and height.
    pub size: (usize, usize),
    /// What the user should know of the labels, each beginning
    /// `warning: ` (`one_based_warning`).
    pub warnings: Vec<String>,
}

impl ImportSummary {
    /// One line: what was written where.
    pub fn describe(&self) -> String {
        format!(
            "{} labelled frames ({}x{}) of {} read written to {}",
            self.frames,
            self.size.0,
            self.size.1,
            self.frames_read,
            self.out.display()
        )
    }
}

/// The labels CSV: its header and, per frame key, the line and the cells.
struct Labels {
    header: Vec<String>,
    rows: LabelRows,
}

/// Each labelled frame's line of the CSV and cells.
type LabelRows = BTreeMap<FrameKey, (usize, Vec<String>)>;

#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
enum FrameKey {
    Number(u64),
    Name(String),
}

impl std::fmt::Display for FrameKey {
    /// As the labels CSV wrote it: a number plain, a name quoted.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FrameKey::Number(n) => write!(f, "{n}"),
            FrameKey::Name(s) => write!(f, "{s:?}"),
        }
    }
}

/// A `frame` cell: a number (`17`, or `17.0` as pandas writes a column
/// of numbers that once held an empty cell), else a file name.
fn frame_key(cell: &str) -> FrameKey {
    let whole = cell.strip_suffix(".0").unwrap_or(cell);
    match whole.parse::<u64>() {
        Ok(n) if whole.bytes().all(|b| b.is_ascii_digit()) => FrameKey::Number(n),
        _ => FrameKey::Name(cell.to_string()),
    }
}

/// Rekey each frame of `rows` named by a path (`frames/0001.png`, `./0001.png`,
/// an absolute path: a CSV that lists paths, as the dataset layout's
/// own `file` column does) by the name of the listed frame it is, the
/// path read from the CSV's folder `labels_dir`, then from the frames'
/// folder `frames_dir`. A path that is no listed frame is refused,
/// naming its line (`labels` is the CSV).
fn name_paths(
    rows: &mut LabelRows,
    list: &FrameList,
    labels_dir: &Path,
    frames_dir: &Path,
    labels: &Path,
) -> Result<()> {
    let is_path = |s: &str| s.contains(['/', '\\']);
    if !rows
        .keys()
        .any(|k| matches!(k, FrameKey::Name(s) if is_path(s)))
    {
        return Ok(());
    }
    // Each listed frame by where it is (links and `..` resolved).
    let frames: BTreeMap<PathBuf, String> = list
        .frames
        .iter()
        .filter_map(|e| {
            let name = e.path.file_name()?.to_string_lossy().into_owned();
            Some((std::fs::canonicalize(&e.path).ok()?, name))
        })
        .collect();
    for (key, (line, cells)) in std::mem::take(rows) {
        let key = match key {
            FrameKey::Name(path) if is_path(&path) => {
                // A Windows tool's `frames\\0001.png` too.
                let given = Path::new(&path).to_path_buf();
                let slashed = PathBuf::from(path.replace('\\', "/"));
                let found = [given, slashed]
                    .iter()
                    .flat_map(|p| [labels_dir.join(p), frames_dir.join(p)])
                    .filter_map(|p| std::fs::canonicalize(p).ok())
                    .find_map(|p| frames.get(&p).cloned());
                match found {
                    Some(name) => FrameKey::Name(name),
                    None => {
                        return Err(Error::Dataset {
                            path: labels.to_path_buf(),
                            line: Some(line),
                            message: format!(
                                "frame {path:?} is not a frame of {} (a path is read from \
                                     the labels' folder, then from the frames' folder); name a \
                                     frame by its file name or its number",
                                frames_dir.display()
                            ),
                        });
                    }
                }
            }
            key => key,
        };
        insert_label(rows, key, (line, cells), labels)?;
    }
    Ok(())
}

/// Add a frame's row (its line of the CSV `labels` and its cells) to
/// `rows`, refusing a frame labelled on another line already: the later
/// line is named, and the earlier one.
fn insert_label(
    rows: &mut LabelRows,
    key: FrameKey,
    (line, cells): (usize, Vec<String>),
    labels: &Path,
) -> Result<()> {
    if let Some((first, _)) = rows.get(&key) {
        let (first, second) = (line.min(*first), line.max(*first));
        return Err(Error::Dataset {
            path: labels.to_path_buf(),
            line: Some(second),
            message: format!("frame {key} is labelled twice (also on line {first})"),
        });
    }
    rows.insert(key, (line, cells));
    Ok(())
}

fn read_labels(path: &Path) -> Result<Labels> {
    let bad = |line: usize, message: String| Error::Dataset {
        path: path.to_path_buf(),
        line: Some(line),
        message,
    };
    let mut csv = crate::csv_lines::reader(
        csv::ReaderBuilder::new().trim(csv::Trim::All),
        crate::io::open_regular(path)?,
    );
    let mut header: Vec<String> = crate::csv_lines::headers(&mut csv)
        .map_err(|why| bad(1, why))?
        .iter()
        .map(str::to_string)
        .collect();
    // pandas' index is no label: dropped, not copied into the dataset.
    let index_column = header.len() > 1 && crate::csv_lines::is_pandas_index(&header[0]);
    if index_column {
        header.remove(0);
    }
    for (i, h) in header.iter().enumerate() {
        if header[..i].contains(h) {
            return Err(bad(1, format!("column {h:?} appears twice")));
        }
    }
    let Some(frame_col) = header.iter().position(|h| h == "frame") else {
        return Err(bad(
            1,
            format!(
                "no `frame` column{}: name each labelled frame by its number in the video \
                 (from 0) or its file name",
                crate::csv_lines::separator_hint(header.iter().map(String::as_str))
            ),
        ));
    };
    if header.iter().any(|h| h == "file") {
        return Err(bad(
            1,
            "a `file` column: the dataset names its own frame files; give `frame` instead".into(),
        ));
    }
    let mut rows = BTreeMap::new();
    for item in crate::csv_lines::records(&mut csv) {
        let (line, rec) = item.map_err(|(line, why)| bad(line, why))?;
        if rows.len() >= MAX_ROWS {
            return Err(bad(line, format!("more than {MAX_ROWS} rows")));
        }
        let cells: Vec<String> = rec
            .iter()
            .skip(usize::from(index_column))
            .map(str::to_string)
            .collect();
        let key = &cells[frame_col];
        if key.is_empty() {
            return Err(bad(line, "empty `frame`".into()));
        }
        insert_label(&mut rows, frame_key(key), (line, cells), path)?;
    }
    if rows.is_empty() {
        return Err(bad(2, "no labelled frames".into()));
    }
    Ok(Labels { header, rows })
}

/// Import `options.frames` with `options.labels` into a new dataset at
/// `options.out`, written in a staging folder, checked by reading it back
/// as every command will, then moved into place.
pub fn import_dataset(options: &ImportOptions) -> Result<ImportSummary> {
    let out = &options.out;
    if !options.force && std::fs::read_dir(out).is_ok_and(|mut entries| entries.next().is_some()) {
        return Err(Error::Invalid(format!(
            "{}: output folder exists and is not empty (use --force to replace a dataset)",
            out.display()
        )));
    }
    let mut labels = read_labels(&options.labels)?;
    let parent = match options.labels.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let labels_dir = std::fs::canonicalize(parent).map_err(|e| Error::io(parent, e))?;
    let kind_cols = options.kind.columns();
    // Columns the kind does not know are kept after its own.
    let extra: Vec<&str> = labels
        .header
        .iter()
        .map(String::as_str)
        .filter(|h| *h != "frame" && !kind_cols.contains(h))
        .collect();
    let col = |name: &str| labels.header.iter().position(|h| h == name);
    let spec = match &options.topic {
        Some(t) => SourceSpec::Bag {
            path: options.frames.clone(),
            topic: Some(t.clone()),
        },
        None => SourceSpec::Path(options.frames.clone()),
    };
    let mut source = FrameSource::open(&spec, SourceOptions::default())?;
    // A live source drops frames when the work falls behind, so a label's
    // frame number would name another frame.
    if source.kind().is_live() {
        return Err(Error::Invalid(format!(
            "{}: a live source (a camera or a network stream), whose frames are dropped when \
             the work falls behind, so the labels' frame numbers would not name them: record \
             it to a file first (`ffmpeg -i SOURCE -c copy recording.mkv`), then give the file",
            crate::source::shown(&options.frames)
        )));
    }
    // Files (a folder, an image) can be labelled by name; stream frames by number.
    let is_folder = source.list().is_some();
    // Frames labelled by number in a folder whose files count from 1.
    let one_based = match source.list() {
        Some(list) if labels.rows.keys().any(|k| matches!(k, FrameKey::Number(_))) => {
            one_based_warning(list, &options.labels)
        }
        _ => None,
    };
    if let Some(list) = source.list() {
        // A single picture's folder is where its name is read from.
        let frames_dir = match options.frames.is_dir() {
            true => options.frames.as_path(),
            false => options.frames.parent().unwrap_or(Path::new(".")),
        };
        name_paths(
            &mut labels.rows,
            list,
            &labels_dir,
            frames_dir,
            &options.labels,
        )?;
    }
    let staged = StagedDir::new(&options.out)?;
    let root = staged.path().to_path_buf();
    let mut writer = DatasetWriter::create(&root, options.kind, &extra, true)?;
    for sub in ["frames", "masks", "depth"] {
        crate::io::create_dir_all(root.join(sub))?;
    }
    let mut size = None;
    let (mut written, mut read) = (0usize, 0u64);
    let mut done = std::collections::BTreeSet::new();
    // The labels CSV's line of each row written, to name a bad label there.
    let mut written_lines = Vec::new();
    let pb = crate::progress::progress_bar(labels.rows.len() as u64, "import");
    while done.len() < labels.rows.len() {
        let Some(frame) = source.next_frame()? else {
            break;
        };
        // A frame's number is its place in its source (a bag's: its message
        // on the topic), kept when a frame before it could not be decoded.
        let number = frame.index_in_source.unwrap_or(read);
        read += 1;
        let key_num = FrameKey::Number(number);
        let key_name = FrameKey::Name(frame.name.clone());
        let (key, (line, cells)) = match (
            labels.rows.get_key_value(&key_num),
            is_folder
                .then(|| labels.rows.get_key_value(&key_name))
                .flatten(),
        ) {
            // One frame labelled by its number and by its name.
            (Some((_, (first, _))), Some((_, (second, _)))) => {
                let (first, second) = (*first.min(second), *first.max(second));
                return Err(Error::Dataset {
                    path: options.labels.clone(),
                    line: Some(second),
                    message: format!(
                        "frame {number} ({:?}) is labelled twice, by its number and by its name (also on line {first})",
                        frame.name
                    ),
                });
            }
            (Some(hit), None) | (None, Some(hit)) => hit,
            (None, None) => continue,
        };
        let (w, h) = (frame.image.width(), frame.image.height());
        match size {
            None => size = Some((w, h)),
            Some(s) if s != (w, h) => {
                return Err(Error::image(
                    &options.frames,
                    format!(
                        "frame {} is {w}x{h}, the first was {}x{}",
                        frame.name, s.0, s.1
                    ),
                ));
            }
            Some(_) => {}
        }
        let file = format!("frames/{written:06}.png");
        match options.kind {
            DatasetKind::Visuotactile => {
                crate::image_io::save_rgb_png(root.join(&file), w, h, frame.image.as_slice())?
            }
            DatasetKind::Tactip => {
                let grey = crate::image_io::rgb_to_grey(frame.image.as_slice());
                crate::image_io::save_grey_png(root.join(&file), w, h, &grey)?
            }
        }
        let mut row = Vec::with_capacity(kind_cols.len() + extra.len());
        for c in kind_cols {
            let cell = col(c).map(|i| cells[i].clone()).unwrap_or_default();
            row.push(match *c {
                "file" => file.clone(),
                "mask" | "depth" if !cell.is_empty() => {
                    let from =
                        resolve_inside(&labels_dir, &cell).map_err(|why| Error::Dataset {
                            path: options.labels.clone(),
                            line: Some(*line),
                            message: format!("{c} {cell:?} {}", why.describe()),
                        })?;
                    let ext = if *c == "mask" { "png" } else { "npy" };
                    let dir = if *c == "mask" { "masks" } else { "depth" };
                    let to = format!("{dir}/{:06}.{ext}", written);
                    crate::io::expect_regular(&from)?;
                    if *c == "mask" {
                        // Read now, not when training: a 0/1 mask or one of
                        // another size is named before the dataset exists.
                        let at_line = |message: String| Error::Dataset {
                            path: options.labels.clone(),
                            line: Some(*line),
                            message: format!("mask {cell:?}: {message}"),
                        };
                        let m = crate::image_io::load_mask(&from)
                            .map_err(|e| at_line(e.to_string()))?;
                        if (m.width(), m.height()) != (w, h) {
                            return Err(at_line(format!(
                                "is {}x{}, its frame {w}x{h}",
                                m.width(),
                                m.height()
                            )));
                        }
                    }
                    std::fs::copy(&from, root.join(&to)).map_err(|e| Error::io(&from, e))?;
                    to
                }
                "frame_index" if cell.is_empty() => number.to_string(),
                _ => cell,
            });
        }
        for c in &extra {
            row.push(col(c).map(|i| cells[i].clone()).unwrap_or_default());
        }
        writer.push_row(row)?;
        written_lines.push(*line);
        done.insert(key.clone());
        written += 1;
        pb.inc(1);
    }
    pb.finish_and_clear();
    if let Some((key, (line, _))) = labels.rows.iter().find(|(k, _)| !done.contains(*k)) {
        // A name that differs from a frame's only in case (a CSV typed by
        // hand, or made on a system whose names ignore case).
        let other_case = match (key, source.list()) {
            (FrameKey::Name(name), Some(list)) => list
                .frames
                .iter()
                .filter_map(|e| e.path.file_name()?.to_str())
                .find(|f| f.eq_ignore_ascii_case(name))
                .map(|f| format!(" (the folder has {f:?}: names differ by case)")),
            _ => None,
        };
        return Err(Error::Dataset {
            path: options.labels.clone(),
            line: Some(*line),
            message: format!(
                "frame {key} is not in {} ({read} frames read){}{}{}",
                options.frames.display(),
                other_case.unwrap_or_default(),
                one_based
                    .as_deref()
                    .map(|w| format!("; {}", w.trim_start_matches("warning: ")))
                    .unwrap_or_default(),
                source
                    .late_warnings()
                    .iter()
                    .map(|w| format!("; {}", w.trim_start_matches("warning: ")))
                    .collect::<String>()
            ),
        });
    }
    let (w, h) = size.unwrap_or((0, 0));
    writer.finish(Manifest {
        format: FORMAT.into(),
        kind: options.kind,
        sensor_spec: options.sensor.clone(),
        width: w as u32,
        height: h as u32,
        generator: format!(
            "tactile dataset from-video {} (tactile-rs {})",
            options
                .frames
                .file_name()
                .unwrap_or_default()
                .to_string_lossy(),
            env!("CARGO_PKG_VERSION")
        ),
        seed: None,
        count: written,
        extra: Default::default(),
    })?;
    // Read back as every command will: a bad label fails here, not later,
    // named at its line of the user's labels CSV (not the staged copy's).
    let staged_labels = root.join("labels.csv");
    Dataset::open(&root).map_err(|e| match e {
        Error::Dataset {
            path,
            line: Some(l),
            message,
        } if path == staged_labels => Error::Dataset {
            path: options.labels.clone(),
            line: l
                .checked_sub(2)
                .and_then(|row| written_lines.get(row))
                .copied(),
            message,
        },
        e => e,
    })?;
    let out = staged.commit(options.force)?;
    Ok(ImportSummary {
        out,
        frames: written,
        frames_read: read,
        size: (w, h),
        warnings: one_based.into_iter().collect(),
    })
}

/// The warning for a labels CSV (`labels`) that gives frames of `list` by
/// number when the files are numbered from 1 (`img_1.png`, `img_2.png`,
/// ..., each file's last number its place plus one): a frame's number is
/// its place from 0, so a column holding the files' own numbers would
/// put every label one frame off without an error. `None` when the names
/// do not count so.
fn one_based_warning(list: &FrameList, labels: &Path) -> Option<String> {
    // The last run of digits in a file's stem.
    let number = |p: &Path| -> Option<u64> {
        let stem = p.file_stem()?.to_str()?;
        let end = stem.rfind(|c: char| c.is_ascii_digit())? + 1;
        let start = stem[..end]
            .rfind(|c: char| !c.is_ascii_digit())
            .map_or(0, |i| i + 1);
        stem[start..end].parse().ok()
    };
    let names: Vec<&Path> = list.frames.iter().map(|e| e.path.as_path()).collect();
    let counted_from_1 = list.dataset.is_none()
        && names.len() >= 2
        && names
            .iter()
            .enumerate()
            .all(|(i, p)| number(p) == Some(i as u64 + 1));
    if !counted_from_1 {
        return None;
    }
    let name = |i: usize| names[i].file_name().unwrap_or_default().to_string_lossy();
    Some(format!(
        "warning: {}: a `frame` number is the frame's place in the folder counted from 0 \
         (frame 0 is {}, frame 1 is {}), and the files are numbered from 1: if the column \
         holds the files' own numbers, every label is one frame off; give the file names \
         ({}, ...) to be sure",
        labels.display(),
        name(0),
        name(1),
        name(0)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Import `frames` with labels on frames 0 and 2, and give the
    /// pixels of the dataset's two frames.
    fn import_frames_0_and_2(frames: &Path, dir: &Path) -> (ImportSummary, Vec<Vec<u8>>) {
        let labels = dir.join("labels-in.csv");
        std::fs::write(&labels, "frame,tendon\n0,0\n2,1\n").unwrap();
        let out = dir.join(format!(
            "ds-{}",
            frames.file_name().unwrap().to_string_lossy()
        ));
        let summary = import_dataset(&ImportOptions {
            frames: frames.to_path_buf(),
            topic: None,
            labels,
            kind: DatasetKind::Visuotactile,
            out: out.clone(),
            sensor: String::new(),
            force: false,
        })
        .unwrap();
        let pixels = ["000000.png", "000001.png"]
            .iter()
            .map(|f| {
                (crate::image_io::load_rgb(out.join("frames").join(f)).unwrap())
                    .as_slice()
                    .to_vec()
            })
            .collect();
        (summary, pixels)
    }

    /// A labels CSV pandas wrote with its defaults: the index first (an
    /// unnamed column, `Unnamed: 0` once read and saved again) and frame
    /// numbers as floats (a column that once held an empty cell). The
    /// index is no label and `2.0` is frame 2; a name stays a name.
    #[test]
    fn labels_pandas_wrote_are_read_by_what_they_mean() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("labels.csv");
        for index in ["", "Unnamed: 0"] {
            std::fs::write(
                &path,
                format!("{index},frame,tendon\n0,0.0,0\n1,2.0,1\n2,000003.png,1\n"),
            )
            .unwrap();
            let labels = read_labels(&path).unwrap();
            assert_eq!(labels.header, ["frame", "tendon"], "{index:?}");
            let keys: Vec<&FrameKey> = labels.rows.keys().collect();
            assert_eq!(
                keys,
                [
                    &FrameKey::Number(0),
                    &FrameKey::Number(2),
                    &FrameKey::Name("000003.png".into())
                ]
            );
            assert_eq!(labels.rows[&FrameKey::Number(2)].1, ["2.0", "1"]);
        }
        for (cell, key) in [
            ("7", FrameKey::Number(7)),
            ("7.5", FrameKey::Name("7.5".into())),
            ("-1.0", FrameKey::Name("-1.0".into())),
            (".0", FrameKey::Name(".0".into())),
        ] {
            assert_eq!(frame_key(cell), key, "{cell}");
        }
    }

    #[test]
    fn a_frame_skipped_as_undecodable_keeps_the_numbers_of_the_frames_after_it() {
        // A frame whose pixels cannot be decoded behind a whole header is
        // skipped; the frames after it keep their numbers, so a label by
        // number stays on its frame. Before, frame 2's label went to the
        // frame after it, without a word.
        let (w, h) = (24usize, 16usize);
        let page = |k: usize| -> Vec<u8> {
            (0..w * h * 3)
                .map(|i| ((i * 7 + k * 53) % 251) as u8)
                .collect()
        };
        let dir = tempfile::tempdir().unwrap();
        // A folder whose frame 1 is cut short behind its header.
        let folder = dir.path().join("folder");
        std::fs::create_dir(&folder).unwrap();
        for k in 0..4 {
            let f = folder.join(format!("{k:06}.png"));
            crate::image_io::save_rgb_png(&f, w, h, &page(k)).unwrap();
            if k == 1 {
                let bytes = std::fs::read(&f).unwrap();
                std::fs::write(&f, &bytes[..bytes.len() / 2]).unwrap();
            }
        }
        // A stack whose page 1's compressed pixels are corrupt.
        use tiff::encoder::{Compression, DeflateLevel, TiffEncoder, colortype::RGB8};
        let mut bytes = std::io::Cursor::new(Vec::new());
        let mut tiff = TiffEncoder::new(&mut bytes)
            .unwrap()
            .with_compression(Compression::Deflate(DeflateLevel::Balanced));
        for k in 0..4 {
            tiff.write_image::<RGB8>(w as u32, h as u32, &page(k))
                .unwrap();
        }
        let mut bytes = bytes.into_inner();
        // Each page's zlib stream starts 0x78; the second is page 1's.
        let starts: Vec<usize> = (0..bytes.len() - 1)
            .filter(|&i| bytes[i] == 0x78 && [0x01, 0x5E, 0x9C, 0xDA].contains(&bytes[i + 1]))
            .collect();
        assert!(starts.len() >= 4, "{starts:?}");
        for b in &mut bytes[starts[1] + 2..starts[1] + 40] {
            *b = 0xFF;
        }
        let stack = dir.path().join("stack.tif");
        std::fs::write(&stack, &bytes).unwrap();
        for frames in [folder, stack] {
            let (summary, pixels) = import_frames_0_and_2(&frames, dir.path());
            assert_eq!(summary.frames, 2, "{frames:?}");
            assert!(pixels[0] == page(0), "{frames:?}: frame 0");
            assert!(
                pixels[1] == page(2),
                "{frames:?}: frame 2's label on another frame"
            );
        }
    }
}
