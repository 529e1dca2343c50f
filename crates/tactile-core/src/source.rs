//! Where frames come from: a dataset (frames in `labels.csv` order, with
//! their sequences and labels), a folder of frame files, a video
//! file, an image topic of a ROS 2 bag (with each frame's header stamp), a
//! V4L2 camera, a network stream's URL, or raw RGB frames on stdin
//! ([`FrameSource`]).
//!
//! Recorded sources (datasets, folders, files, a file served over HTTP)
//! give every frame, decoded on a second thread ahead of the models when
//! asked. Live sources (a camera, an IP camera's stream, stdin) are read
//! as frames arrive into a small queue; when the models fall behind, the
//! oldest waiting frame is dropped and counted, so memory stays bounded
//! and results stay current. Each live frame carries
//! its arrival time, from which a record's latency is measured.

use std::collections::VecDeque;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use crate::dataset::Dataset;
use crate::image_io::{MAX_IMAGE_PIXELS, RgbImage};
use crate::{Error, Result};

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
    pub fn load(&self) -> Result<crate::image_io::RgbImage> {
        let img = crate::image_io::load_rgb(&self.path)?;
        self.check_size((img.width(), img.height()))?;
        Ok(img)
    }

    /// Read the frame's header only, refusing what [`Self::load`] would:
    /// a file that is no picture (or cut before its header ends), larger
    /// than 8K, of another depth than 8 bits, or of another size than its
    /// dataset's manifest says.
    pub fn check_header(&self) -> Result<()> {
        let h = crate::image_io::rgb_frame_header(&self.path)?;
        self.check_size((h.width as usize, h.height as usize))
    }

    /// A frame of a dataset must have the size its manifest declares.
    fn check_size(&self, size: (usize, usize)) -> Result<()> {
        match self.size {
            Some(manifest) => crate::dataset::expect_manifest_size(&self.path, size, manifest),
            None => Ok(()),
        }
    }
}

/// The frames of a dataset or a folder, in order.
#[derive(Debug, Clone)]
pub struct FrameList {
    /// The frames.
    pub frames: Vec<FrameEntry>,
    /// The dataset the frames are the rows of (whose rows say what it
    /// holds); `None` for a folder of frames, which may have dropped some.
    pub dataset: Option<Dataset>,
    /// Files of a folder of frames that are not frame files, or are
    /// hidden (sorted; they are reported, not read).
    pub ignored: Vec<PathBuf>,
}

/// Extensions of the frame files a folder may hold: the picture formats
/// OpenCV's `imread` reads that the `image` crate decodes (lab cameras'
/// tools often save BMP or TIFF). A file is decoded by what its bytes are,
/// not by its name.
pub const FRAME_EXTENSIONS: [&str; 9] = [
    "png", "jpg", "jpeg", "bmp", "tif", "tiff", "webp", "pgm", "ppm",
];

/// The frame formats, as messages and help name them.
pub const FRAME_FORMATS: &str = "PNG, JPEG, BMP, TIFF, WebP or PGM/PPM";

/// The error of a source path that names nothing: how to read standard
/// input when it is `-` (the shell's name for it), else that it does not
/// exist (a URL is a stream: [`stream_url`]).
fn not_found(path: &Path) -> Error {
    let text = path.to_string_lossy();
    if text == "-" {
        return Error::Invalid(
            "-: no file of that name; standard input is read as raw rgb24 frames with \
             `--stdin --size WxH` (Python: `tactile.frames(stdin_size=(w, h))`)"
                .into(),
        );
    }
    crate::video::collapsed_url_error(&text).unwrap_or_else(|| Error::not_found(path, "input"))
}

/// True for a file named like a frame ([`FRAME_EXTENSIONS`]).
pub fn is_frame_file(p: &Path) -> bool {
    p.extension()
        .and_then(|x| x.to_str())
        .is_some_and(|x| FRAME_EXTENSIONS.iter().any(|e| x.eq_ignore_ascii_case(e)))
}

/// True for a file whose name starts with a dot: macOS leaves `._frame.png`
/// resource forks (not pictures) beside every frame copied to a shared or
/// FAT drive, and `.DS_Store`; a folder of frames reads none of them.
pub fn is_hidden_file(p: &Path) -> bool {
    p.file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.starts_with('.'))
}

/// True for a file a folder of frames reads: a frame file that is not
/// hidden. The one rule of [`FrameList::open`] and its hint.
fn is_listed_frame(p: &Path) -> bool {
    is_frame_file(p) && !is_hidden_file(p)
}

/// True for a folder (not a link) that is a dataset or has a frame file
/// among its first thousand entries: a hint for a user who named the
/// folder above the frames.
fn folder_holds_frames(p: &Path) -> bool {
    let is_dir = std::fs::symlink_metadata(p).is_ok_and(|m| m.is_dir());
    is_dir
        && (p.join("labels.csv").is_file()
            || std::fs::read_dir(p).is_ok_and(|rd| {
                rd.take(1000)
                    .filter_map(|e| e.ok())
                    .any(|e| is_listed_frame(&e.path()))
            }))
}

/// Frames a warning names one by one before it only counts the rest.
pub const FRAMES_NAMED: usize = 3;

/// The frames of a warning: the first [`FRAMES_NAMED`] of `frames` named,
/// the rest counted ("a.png, b.png, c.png, and 4 more"), and "this
/// frame" or "these frames" for the words after them.
pub fn named_frames(frames: &[String]) -> (String, &'static str) {
    let named: Vec<&str> = frames
        .iter()
        .take(FRAMES_NAMED)
        .map(String::as_str)
        .collect();
    let more = match frames.len() - named.len() {
        0 => String::new(),
        n => format!(", and {n} more"),
    };
    let these = match frames.len() {
        1 => "this frame",
        _ => "these frames",
    };
    (format!("{}{more}", named.join(", ")), these)
}

impl FrameList {
    /// The frames of `dir`: a dataset when it has `labels.csv`, else its
    /// frame files in the order of the numbers in their names
    /// (anything else, and hidden files, are listed in
    /// [`FrameList::ignored`]).
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
                dataset: Some(ds),
                ignored: Vec::new(),
            });
        }
        // As many files as a dataset may have rows, counted before they
        // are all held.
        let limit = crate::dataset::MAX_ROWS;
        let (mut v, mut ignored): (Vec<PathBuf>, Vec<PathBuf>) = std::fs::read_dir(dir)
            .map_err(|e| Error::io(dir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .take(limit + 1)
            .partition(|p| is_listed_frame(p));
        if v.len() + ignored.len() > limit {
            return Err(Error::Invalid(format!(
                "{}: more than {limit} files; a folder of frames holds at most that many",
                dir.display()
            )));
        }
        // A pipe or a device named like a frame would block the reader; a
        // link out of the folder would read what the user did not name.
        for p in &v {
            crate::dataset::expect_entry_inside(dir, p)?;
            crate::io::expect_regular(p)?;
        }
        // By the numbers in the names, as a file browser shows them:
        // `frame_2.png` before `frame_10.png` (zero-padded names keep
        // their order), so a run's frames and its hysteresis go in time.
        alphanumeric_sort::sort_path_slice(&mut v);
        alphanumeric_sort::sort_path_slice(&mut ignored);
        if v.is_empty() {
            return Err(Error::Invalid(format!(
                "{}: no labels.csv and no frames ({FRAME_FORMATS}){}{}",
                dir.display(),
                match ignored.len() {
                    0 => String::new(),
                    n => format!(" ({n} other files)"),
                },
                match (
                    ignored.iter().find(|p| folder_holds_frames(p)),
                    ignored.iter().find(|p| crate::bag::is_bag_input_file(p)),
                ) {
                    (Some(sub), _) => format!(
                        "; the folder {} holds frames: pass it instead",
                        sub.display()
                    ),
                    // A bag folder holds metadata.yaml; without it, each
                    // MCAP file is a bag of its own.
                    (None, Some(bag)) => format!(
                        "; it holds bag files (MCAP or SQLite) without the metadata.yaml of a ROS 2 bag folder: pass one, as {}",
                        bag.display()
                    ),
                    (None, None) => String::new(),
                }
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
            dataset: None,
            ignored,
        })
    }

    /// Check the header of each of the first `limit` frames (all of them
    /// without a limit) before any frame is decoded
    /// ([`FrameEntry::check_header`]), so a folder's bad frame stops a run
    /// before its first frame, not after every frame before it. One bad
    /// frame gives its own refusal; several, the first's and how many
    /// ([`Error::UnreadableFrames`]). A frame whose pixels are cut short
    /// behind a whole header is found only when it is decoded: the source
    /// skips it then, with a warning ([`FrameSource::late_warnings`]).
    pub fn check_headers(&self, limit: Option<u64>) -> Result<()> {
        Error::check_frames(self.first(limit), FrameEntry::check_header)
    }

    /// The first `limit` frames (all of them without a limit): those a run
    /// with that limit reads.
    pub fn first(&self, limit: Option<u64>) -> &[FrameEntry] {
        let n = limit.map_or(self.frames.len(), |l| {
            (self.frames.len()).min(usize::try_from(l).unwrap_or(usize::MAX))
        });
        &self.frames[..n]
    }

    /// What a user should know before the run: frames missing from the
    /// numbering, files that are not frames.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        let missing = self.missing_frames();
        if missing.count > 0 {
            w.push(format!(
                "warning: {} frame(s) missing from the numbering, e.g. {:?}",
                missing.count, missing.first
            ));
        }
        w.extend(self.ignored_warning());
        w.extend(self.unreadable_names_warning());
        w
    }

    /// The warning naming frames whose file names are not UTF-8 (written
    /// on a system with another encoding): records, CSV rows and overlay
    /// names are text, so they show such a name with U+FFFD in place of
    /// its bad bytes, and two names can read alike there.
    pub fn unreadable_names_warning(&self) -> Option<String> {
        let bad: Vec<_> = (self.frames.iter())
            .filter_map(|f| f.path.file_name().filter(|n| n.to_str().is_none()))
            .collect();
        let first = bad.first()?;
        Some(format!(
            "warning: {} frame name(s) are not UTF-8 (e.g. {first:?}); the outputs name them with \
             U+FFFD in place of the bytes that are not, so rename them if two could \
             read alike",
            bad.len()
        ))
    }

    /// The warning naming the files of a folder of frames that were not read
    /// (the first five of each kind): those that are not frame files,
    /// and hidden ones, when there are any.
    pub fn ignored_warning(&self) -> Option<String> {
        if self.ignored.is_empty() {
            return None;
        }
        let (hidden, other): (Vec<&PathBuf>, Vec<&PathBuf>) =
            self.ignored.iter().partition(|p| is_hidden_file(p));
        let names = |v: &[&PathBuf]| {
            let first: Vec<_> = (v.iter().take(5))
                .map(|p| p.file_name().unwrap_or_default().to_string_lossy())
                .collect();
            format!(
                "{}{}",
                first.join(", "),
                if v.len() > 5 { ", ..." } else { "" }
            )
        };
        let mut parts = Vec::new();
        if !other.is_empty() {
            parts.push(format!(
                "{} file(s) that are not frames ({FRAME_FORMATS}) were not read: {}",
                other.len(),
                names(&other)
            ));
        }
        if !hidden.is_empty() {
            parts.push(format!(
                "{} hidden file(s) (a name starting with '.', as macOS's ._ copies) were not read: {}",
                hidden.len(),
                names(&hidden)
            ));
        }
        Some(format!("warning: {}", parts.join("; ")))
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
        if self.dataset.is_some() {
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

/// What a source is; recorded kinds give every frame, live kinds drop the
/// oldest waiting frames when processing falls behind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SourceKind {
    /// A dataset (labels.csv).
    Dataset,
    /// A folder of frame files, or one frame file.
    Folder,
    /// A video file decoded by FFmpeg.
    Video,
    /// A TIFF of many pages given alone, read page by page
    /// ([`crate::stack`]).
    Stack,
    /// An image topic of a ROS 2 bag (MCAP).
    Bag,
    /// A V4L2 camera, live.
    Camera,
    /// A network stream without a length (an IP camera's `rtsp://…`),
    /// live. A served file with a length is a [`SourceKind::Video`].
    Stream,
    /// Raw rgb24 frames on stdin, live.
    Stdin,
}

impl SourceKind {
    /// True for sources read as frames arrive.
    pub fn is_live(self) -> bool {
        matches!(
            self,
            SourceKind::Camera | SourceKind::Stream | SourceKind::Stdin
        )
    }
}

impl Frame {
    /// The frame named in a message: a file by its path (`frames/a.png`,
    /// as the folder was given), a stream's frame by its number (`frame
    /// 000042`).
    pub fn label(&self) -> String {
        match &self.path {
            Some(p) => p.display().to_string(),
            None => format!("frame {}", self.name),
        }
    }

    /// The frame made grey with OpenCV's weights, as a colour PNG in a
    /// dataset is.
    pub fn grey(&self) -> Result<crate::image_io::GreyImage> {
        let (w, h) = (self.image.width(), self.image.height());
        let g = crate::image_io::rgb_to_grey(self.image.as_slice());
        crate::image_io::grey_image(w, h, g)
    }
}

/// Where to read frames from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SourceSpec {
    /// A dataset, a folder of frames, one image, a video file, a camera
    /// device (`/dev/videoN`) or, when no file has that name, a network
    /// stream's URL (`rtsp://…`), told apart by what the path is.
    Path(PathBuf),
    /// An image topic of a ROS 2 bag (a bag folder holding `metadata.yaml`,
    /// or one `.mcap` file); `None` reads its only image topic (a bag with
    /// several is refused, naming them). A plain [`SourceSpec::Path`] to a
    /// bag is the same as `None`.
    Bag {
        /// The bag.
        path: PathBuf,
        /// The topic (`/gelsight/image_raw`).
        topic: Option<String>,
    },
    /// Raw frames on stdin: `width * height * 3` bytes each, rgb24.
    Stdin {
        /// Width, pixels.
        width: usize,
        /// Height, pixels.
        height: usize,
    },
}

/// How a source is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SourceOptions {
    /// Decode recorded frames on a second thread ahead of the models.
    pub overlap: bool,
    /// Live sources: frames that may wait; more arriving drop the oldest.
    pub live_queue: usize,
    /// Give at most this many frames.
    pub limit: Option<u64>,
}

impl Default for SourceOptions {
    fn default() -> Self {
        Self {
            overlap: true,
            live_queue: 2,
            limit: None,
        }
    }
}

/// The largest live queue allowed (frames of up to 8K each wait in it).
pub const MAX_LIVE_QUEUE: usize = 64;

/// One frame from a source.
pub struct Frame {
    /// The pixels.
    pub image: RgbImage,
    /// The file name, or the frame's number in a stream (`000042`).
    pub name: String,
    /// The file it was read from (a folder's or a dataset's frame).
    pub path: Option<PathBuf>,
    /// Its palpation sequence, when a dataset says.
    pub sequence: Option<String>,
    /// Its `tendon` label, when a dataset says.
    pub tendon: Option<bool>,
    /// When a live frame arrived (read whole from the camera or stdin).
    pub arrived: Option<Instant>,
    /// A bag's frame: its message's header stamp (else its log time),
    /// nanoseconds since the epoch.
    pub stamp_ns: Option<i64>,
    /// The frame's number in its source, by which labels name it, where it
    /// can differ from the count of frames given before it: a folder's or
    /// dataset's frame keeps its place when one before it was skipped as
    /// undecodable, a stack's its page, a bag's frame is its message's
    /// index on its topic (a video topic's first frame may come past 0:
    /// its packets before the first keyframe give none).
    pub index_in_source: Option<u64>,
}

/// Reads one frame after another.
trait Reader: Send {
    fn next_frame(&mut self) -> Result<Option<Frame>>;
}

/// Frames of a folder that could not be decoded past a whole header, over
/// a run that skips them: which refusals are skipped, the one wording of
/// their warning and of the refusal when no frame could be decoded, for
/// every reader of a folder ([`FrameSource`], `tactile reconstruct`).
#[derive(Debug)]
pub struct UndecodableFrames {
    /// Frames the run reads.
    total: usize,
    /// Frames skipped so far.
    skipped: usize,
    /// Why the first skipped frame could not be decoded, naming it.
    first: Option<Error>,
}

impl UndecodableFrames {
    /// None skipped yet, of `total` frames read.
    pub fn new(total: usize) -> Self {
        Self {
            total,
            skipped: 0,
            first: None,
        }
    }

    /// A frame as its decoder gave it: `Some` when decoded; `None` when
    /// its content was refused (an image error), the frame counted as
    /// skipped. Any other error (the file gone, the disk failing) is
    /// returned: it stops the run.
    pub fn decoded<T>(&mut self, frame: Result<T>) -> Result<Option<T>> {
        match frame {
            Ok(frame) => Ok(Some(frame)),
            Err(why @ Error::Image { .. }) => {
                self.skipped += 1;
                self.first.get_or_insert(why);
                Ok(None)
            }
            Err(other) => Err(other),
        }
    }

    /// A frame as its decoder gave it to a pass that may skip: with
    /// `skipped`, [`Self::decoded`] (an undecodable frame counted there and
    /// `None`); without, every error returned, so the pass stops at it (a
    /// training set's frames, fitted whole).
    pub fn decoded_or_stop<T>(skipped: Option<&mut Self>, frame: Result<T>) -> Result<Option<T>> {
        match skipped {
            Some(skipped) => skipped.decoded(frame),
            None => frame.map(Some),
        }
    }

    /// The warning naming the first skipped frame and counting them;
    /// `None` while none is.
    pub fn warning(&self) -> Option<String> {
        let first = self.first.as_ref()?;
        Some(format!(
            "warning: {} of the {} frames could not be decoded past their header and got no \
             result; the other frames' results were kept. The first: {first}",
            self.skipped, self.total
        ))
    }

    /// Frames skipped so far.
    pub fn count(&self) -> usize {
        self.skipped
    }

    /// At the end of a run that gave `given` frames: when it gave none and
    /// skipped some, nothing is kept, so the run fails with the first
    /// frame's refusal (alone, or with how many: [`Error::UnreadableFrames`]).
    pub fn finish(&mut self, given: usize) -> Result<()> {
        match (given, self.first.take()) {
            (0, Some(first)) if self.skipped == 1 => Err(first),
            (0, Some(first)) => Err(Error::UnreadableFrames {
                first: Box::new(first),
                count: self.skipped,
                total: self.total,
            }),
            _ => Ok(()),
        }
    }
}

/// The frames of a folder or dataset, or a stack's pages. Their headers
/// were read when the source opened ([`FrameList::check_headers`],
/// [`crate::stack::StackFrames::open`]); a frame that still cannot be
/// decoded (its pixel data cut short or corrupt behind a whole header, as
/// a copy stopped half-way leaves it, or pixels that are not opaque) is
/// skipped and named in a late warning, so the frames around it keep their
/// results, as a video or bag cut short keeps its frames. It keeps its
/// number ([`Frame::index_in_source`]), so labels by number stay on their
/// frames. When no frame at all can be decoded, the source ends with the
/// error instead. Any other error (the file gone, the disk failing) stops
/// the run.
struct ListReader {
    /// Each frame, decoded as it is asked for.
    entries: Box<dyn Iterator<Item = Result<Frame>> + Send>,
    /// Frames given.
    given: usize,
    /// Frames skipped, of those the run reads (the limit's first ones).
    skipped: UndecodableFrames,
    late: LateWarnings,
    /// Where this reader's warning stands in `late`, once written.
    slot: Option<usize>,
    /// The count, shared with the source ([`FrameSource::undecodable`]).
    undecodable: Arc<AtomicU64>,
}

impl ListReader {
    /// The `total` frames `entries` decodes.
    fn new(
        entries: impl Iterator<Item = Result<Frame>> + Send + 'static,
        total: usize,
        late: LateWarnings,
        undecodable: Arc<AtomicU64>,
    ) -> Self {
        Self {
            skipped: UndecodableFrames::new(total),
            entries: Box::new(entries),
            given: 0,
            late,
            slot: None,
            undecodable,
        }
    }

    /// A folder's or dataset's frames, each named by its file.
    fn of_files(entries: Vec<FrameEntry>, late: LateWarnings, undecodable: Arc<AtomicU64>) -> Self {
        let total = entries.len();
        let frames = entries.into_iter().enumerate().map(|(i, e)| {
            let image = e.load()?;
            Ok(Frame {
                image,
                name: (e.path.file_name().unwrap_or_default())
                    .to_string_lossy()
                    .into_owned(),
                path: Some(e.path),
                sequence: e.sequence,
                tendon: e.tendon,
                arrived: None,
                stamp_ns: None,
                index_in_source: Some(i as u64),
            })
        });
        Self::new(frames, total, late, undecodable)
    }

    /// A stack's pages, each named by its number, as a video's frames.
    fn of_stack(
        stack: crate::stack::StackFrames,
        late: LateWarnings,
        undecodable: Arc<AtomicU64>,
    ) -> Self {
        let total = stack.len();
        let frames = (0..total).map(move |i| {
            Ok(Frame {
                image: stack.load(i)?,
                name: format!("{i:06}"),
                path: None,
                sequence: None,
                tendon: None,
                arrived: None,
                stamp_ns: None,
                index_in_source: Some(i as u64),
            })
        });
        Self::new(frames, total, late, undecodable)
    }

    /// After a frame was skipped: its count and warning brought up to
    /// date at once (a run stopped after it still says so).
    fn tell_skipped(&mut self) {
        self.undecodable.fetch_add(1, Ordering::Relaxed);
        let Some(text) = self.skipped.warning() else {
            return;
        };
        if let Ok(mut late) = self.late.lock() {
            match self.slot {
                Some(i) if i < late.len() => late[i] = text,
                _ => {
                    late.push(text);
                    self.slot = Some(late.len() - 1);
                }
            }
        }
    }
}

impl Reader for ListReader {
    fn next_frame(&mut self) -> Result<Option<Frame>> {
        let frame = loop {
            let Some(frame) = self.entries.next() else {
                // Not one frame given: nothing to keep, so the run fails.
                self.skipped.finish(self.given)?;
                return Ok(None);
            };
            match self.skipped.decoded(frame)? {
                Some(frame) => break frame,
                None => self.tell_skipped(),
            }
        };
        self.given += 1;
        Ok(Some(frame))
    }
}

/// Frames of a stream, named by their number.
struct StreamReader<R> {
    read: R,
    number: u64,
    live: bool,
}

impl<R: FnMut() -> Result<Option<RgbImage>> + Send> Reader for StreamReader<R> {
    fn next_frame(&mut self) -> Result<Option<Frame>> {
        let Some(image) = (self.read)()? else {
            return Ok(None);
        };
        let name = format!("{:06}", self.number);
        self.number += 1;
        Ok(Some(Frame {
            image,
            name,
            path: None,
            sequence: None,
            tendon: None,
            arrived: self.live.then(Instant::now),
            stamp_ns: None,
            index_in_source: None,
        }))
    }
}

/// Warnings found while reading, shared with the thread that reads.
type LateWarnings = Arc<Mutex<Vec<String>>>;

/// The frames of a bag's image topic, named by their index on it; at the
/// end, its warnings (a file cut short) join the source's.
struct BagReader(crate::bag::BagImages, LateWarnings);

impl Reader for BagReader {
    fn next_frame(&mut self) -> Result<Option<Frame>> {
        let Some(f) = self.0.next_frame()? else {
            if let Ok(mut late) = self.1.lock() {
                late.extend(self.0.warnings());
            }
            return Ok(None);
        };
        Ok(Some(Frame {
            image: f.image,
            name: format!("{:06}", f.index),
            path: None,
            sequence: None,
            tendon: None,
            arrived: None,
            stamp_ns: Some(f.stamp_ns),
            index_in_source: Some(f.index),
        }))
    }
}

/// What [`FrameSource::open`] builds before choosing how to feed it.
type Opened = (
    SourceKind,
    Option<FrameList>,
    Box<dyn Reader>,
    Option<(usize, usize)>,
    Option<crate::video::VideoStopper>,
);

/// A video file, a camera or a network stream, decoded by FFmpeg. A
/// stream with a length (a file served over HTTP) is recorded, every frame
/// given; one without (an IP camera) is live.
fn open_video(input: crate::video::VideoInput, late: &LateWarnings) -> Result<Opened> {
    use crate::video::{DecodeOptions, VideoInput, VideoReader};
    let mut v = VideoReader::open(&input, DecodeOptions::default())?;
    let info = v.info();
    let kind = match input {
        VideoInput::File(_) => SourceKind::Video,
        VideoInput::Camera(_) => SourceKind::Camera,
        VideoInput::Stream(_) if info.duration_s.is_some() => SourceKind::Video,
        VideoInput::Stream(_) => SourceKind::Stream,
    };
    let stopper = v.stopper();
    let late = Arc::clone(late);
    let r = StreamReader {
        read: move || {
            let frame = v.next_frame()?;
            if frame.is_none()
                && let Some(w) = v.take_shortfall_warning()
                && let Ok(mut late) = late.lock()
            {
                late.push(w);
            }
            Ok(frame)
        },
        number: 0,
        live: kind.is_live(),
    };
    let size = Some((info.width, info.height));
    Ok((
        kind,
        None,
        Box::new(r) as Box<dyn Reader>,
        size,
        Some(stopper),
    ))
}

/// The stream a source path names when it is a URL that names no file
/// (a file of that name is read as a file).
fn stream_url(path: &Path) -> Result<Option<crate::video::StreamUrl>> {
    let Some(text) = path.to_str() else {
        return Ok(None);
    };
    use std::io::ErrorKind;
    match std::fs::symlink_metadata(path) {
        // A part longer than a file name may be (a camera's token of 300
        // characters), or under a file, names no file either.
        Err(e)
            if matches!(
                e.kind(),
                ErrorKind::NotFound | ErrorKind::InvalidFilename | ErrorKind::NotADirectory
            ) =>
        {
            crate::video::StreamUrl::parse(text)
        }
        _ => Ok(None),
    }
}

/// A source's path as messages show it: a stream's URL with its password
/// hidden, anything else as it is.
pub fn shown(path: &Path) -> String {
    match stream_url(path) {
        Ok(Some(url)) => url.shown().display().to_string(),
        _ => path.display().to_string(),
    }
}

/// A bag's image topic (its only one when `topic` is `None`).
fn open_bag(path: &Path, topic: Option<String>, late: &LateWarnings) -> Result<Opened> {
    let topic = match topic {
        Some(t) => t,
        None => crate::bag::only_image_topic(path)?,
    };
    let r = BagReader(crate::bag::BagImages::open(path, &topic)?, Arc::clone(late));
    Ok((SourceKind::Bag, None, Box::new(r), None, None))
}

/// A limit on the frames read must leave one: a run of none would end as
/// if the source were empty and say it succeeded (leave the limit out to
/// read every frame).
pub fn check_limit(limit: Option<u64>) -> Result<()> {
    match limit {
        Some(0) => Err(Error::Config(
            "limit: must be at least 1 frame, got 0 (leave it out to read every frame)".into(),
        )),
        _ => Ok(()),
    }
}

/// Raw rgb24 frames of a fixed size from `input`. A stream that ends
/// inside a frame after whole ones (a piped camera killed mid-write) ends
/// there: the frames before it are kept and the partial one is told in
/// `late`, as a bag cut short is. One that ends before its first whole
/// frame is an error.
fn raw_frames(
    mut input: impl Read + Send,
    width: usize,
    height: usize,
    late: LateWarnings,
) -> impl FnMut() -> Result<Option<RgbImage>> + Send {
    let mut whole = 0u64;
    move || {
        let len = width * height * 3;
        let mut buf = vec![0u8; len];
        let got =
            crate::video::read_full(&mut input, &mut buf).map_err(|e| Error::io("<stdin>", e))?;
        match got {
            0 => Ok(None),
            n if n == len => {
                whole += 1;
                crate::image_io::rgb_image(width, height, buf).map(Some)
            }
            // Not one whole frame: not a stream of this size at all.
            n if whole == 0 => Err(Error::Invalid(format!(
                "stdin ended inside a frame: {n} of {len} bytes ({width}x{height} rgb24), before any whole frame; is --size the camera's?"
            ))),
            n => {
                if let Ok(mut late) = late.lock() {
                    late.push(format!(
                        "warning: stdin ended inside a frame: {n} of {len} bytes ({width}x{height} rgb24) after {whole} whole frames; the frames before it were kept, that part of one dropped"
                    ));
                }
                Ok(None)
            }
        }
    }
}

/// What live frames wait in: at most `capacity`, the oldest dropped.
struct LiveQueue {
    state: Mutex<LiveState>,
    ready: Condvar,
    capacity: usize,
}

struct LiveState {
    items: VecDeque<Result<Frame>>,
    finished: bool,
    dropped: u64,
}

impl LiveQueue {
    fn push(&self, item: Result<Frame>, last: bool) {
        let Ok(mut s) = self.state.lock() else { return };
        while s.items.len() >= self.capacity {
            s.items.pop_front();
            s.dropped += 1;
        }
        s.items.push_back(item);
        s.finished |= last;
        self.ready.notify_one();
    }

    fn finish(&self) {
        if let Ok(mut s) = self.state.lock() {
            s.finished = true;
            self.ready.notify_one();
        }
    }

    fn pop(&self) -> Result<Option<Frame>> {
        let mut s = self
            .state
            .lock()
            .map_err(|_| Error::Invalid("the live frame queue's lock was poisoned".into()))?;
        loop {
            if let Some(item) = s.items.pop_front() {
                return item.map(Some);
            }
            if s.finished {
                return Ok(None);
            }
            // Wake now and then to honour Ctrl-C while a camera is silent.
            crate::interrupt::check()?;
            s = self
                .ready
                .wait_timeout(s, Duration::from_millis(100))
                .map_err(|_| Error::Invalid("the live frame queue's lock was poisoned".into()))?
                .0;
        }
    }
}

enum Feed {
    Direct(Box<dyn Reader>),
    Prefetched(std::sync::mpsc::Receiver<Result<Frame>>),
    Live(Arc<LiveQueue>),
}

/// Frames from any [`SourceSpec`], in order, one at a time.
pub struct FrameSource {
    kind: SourceKind,
    list: Option<FrameList>,
    /// What the user should know of a bag (one split read alone).
    notes: Vec<String>,
    /// What was found while reading (a bag file cut short).
    late: LateWarnings,
    /// A folder's frames skipped as they could not be decoded.
    undecodable: Arc<AtomicU64>,
    feed: Feed,
    limit: Option<u64>,
    given: u64,
    size: Option<(usize, usize)>,
    stopper: Option<crate::video::VideoStopper>,
    /// How many frames a recorded source of known length gives.
    known: Option<u64>,
}

impl FrameSource {
    /// Open `spec`: a folder (a dataset with labels.csv, a ROS 2 bag with
    /// rosbag2's metadata.yaml, else its frame files), one frame
    /// file, an `.mcap` (or `.mcap.zstd`) file as a ROS 2 bag, a character
    /// device (a V4L2 camera, live), any other file as a video through
    /// FFmpeg, a URL that names no file as a network stream through FFmpeg
    /// (live unless it has a length), or stdin (live).
    pub fn open(spec: &SourceSpec, options: SourceOptions) -> Result<Self> {
        check_limit(options.limit)?;
        if options.live_queue == 0 || options.live_queue > MAX_LIVE_QUEUE {
            return Err(Error::Config(format!(
                "live queue: must be 1 to {MAX_LIVE_QUEUE} frames, got {}",
                options.live_queue
            )));
        }
        use crate::video::VideoInput;
        let late = LateWarnings::default();
        let undecodable = Arc::<AtomicU64>::default();
        // A stack's pages, known from its header pass.
        let mut stack_pages = None;
        // A path that names no file but a URL is a network stream.
        let stream = match spec {
            SourceSpec::Path(path) => stream_url(path)?,
            _ => None,
        };
        let (kind, list, reader, size, stopper): Opened = match (spec, stream) {
            (_, Some(url)) => open_video(VideoInput::Stream(url), &late)?,
            (SourceSpec::Bag { path, topic }, None) => open_bag(path, topic.clone(), &late)?,
            (SourceSpec::Stdin { width, height }, None) => {
                let (w, h) = (*width, *height);
                if w == 0 || h == 0 || (w as u64).saturating_mul(h as u64) > MAX_IMAGE_PIXELS {
                    return Err(Error::Config(format!(
                        "stdin frame size {w}x{h}: frames must be 1 to {MAX_IMAGE_PIXELS} pixels (8K)"
                    )));
                }
                let read = raw_frames(std::io::stdin(), w, h, Arc::clone(&late));
                let r = StreamReader {
                    read,
                    number: 0,
                    live: true,
                };
                (
                    SourceKind::Stdin,
                    None,
                    Box::new(r) as Box<dyn Reader>,
                    Some((w, h)),
                    None,
                )
            }
            (SourceSpec::Path(path), None) => {
                let meta = std::fs::metadata(path).map_err(|e| match e.kind() {
                    std::io::ErrorKind::NotFound => not_found(path),
                    _ => Error::io(path, e),
                })?;
                use std::os::unix::fs::FileTypeExt;
                if (meta.is_file() && crate::bag::is_bag_input_file(path))
                    || (meta.is_dir() && crate::bag::is_bag_folder(path))
                {
                    open_bag(path, None, &late)?
                } else if meta.is_file()
                    && is_frame_file(path)
                    && let Some(stack) = crate::stack::StackFrames::open(path, options.limit)?
                {
                    // A stack given alone: its pages one after another,
                    // named by their number, as a video's frames.
                    let size = Some(stack.size());
                    stack_pages = Some(stack.len() as u64);
                    if let Some(w) = stack.cut_short_warning()
                        && let Ok(mut late) = late.lock()
                    {
                        late.push(w.to_string());
                    }
                    let r =
                        ListReader::of_stack(stack, Arc::clone(&late), Arc::clone(&undecodable));
                    (
                        SourceKind::Stack,
                        None,
                        Box::new(r) as Box<dyn Reader>,
                        size,
                        None,
                    )
                } else if meta.is_dir() || (meta.is_file() && is_frame_file(path)) {
                    let list = match meta.is_dir() {
                        true => FrameList::open(path)?,
                        false => FrameList {
                            frames: vec![FrameEntry {
                                path: path.clone(),
                                sequence: None,
                                tendon: None,
                                size: None,
                            }],
                            dataset: None,
                            ignored: Vec::new(),
                        },
                    };
                    let kind = match list.dataset.is_some() {
                        true => SourceKind::Dataset,
                        false => SourceKind::Folder,
                    };
                    list.check_headers(options.limit)?;
                    let size = list.frames.first().and_then(|f| f.size);
                    // A limit reads the folder's first frames, those whose
                    // headers were read.
                    let first = list.first(options.limit).to_vec();
                    let r =
                        ListReader::of_files(first, Arc::clone(&late), Arc::clone(&undecodable));
                    (kind, Some(list), Box::new(r) as Box<dyn Reader>, size, None)
                } else if let Some(e) = crate::dataset::file_of_a_dataset(path) {
                    return Err(e);
                } else if let Some(e) = meta
                    .is_file()
                    .then(|| crate::bag::other_bag_format(path))
                    .flatten()
                {
                    return Err(e);
                } else if meta.file_type().is_char_device() || meta.is_file() {
                    // A character device is a camera, read live; a file a video.
                    match meta.is_file() {
                        true => open_video(VideoInput::File(path.clone()), &late)?,
                        false => open_video(VideoInput::Camera(path.clone()), &late)?,
                    }
                } else {
                    return Err(Error::image(
                        path,
                        "is a pipe or a socket; give a file, a folder, a camera device, a \
                         stream's URL or --stdin",
                    ));
                }
            }
        };
        // Options of the other kind of source would do nothing: refused
        // (the reader just opened is dropped, its decoder stopped).
        let defaults = SourceOptions::default();
        let what = format!("{kind:?}").to_lowercase();
        if !kind.is_live() && options.live_queue != defaults.live_queue {
            return Err(Error::Config(format!(
                "live_queue {}: the frames a live source (a camera, a stream, stdin) may hold while the \
                 models run, and this {what} source is recorded (every frame is kept): leave \
                 live_queue out",
                options.live_queue
            )));
        }
        if kind.is_live() && options.overlap != defaults.overlap {
            return Err(Error::Config(format!(
                "no overlap (--no-overlap, prefetch=False) decodes a recorded source's frames just \
                 before the models, and this {what} source is live (read as frames arrive): \
                 leave it out"
            )));
        }
        let feed = if kind.is_live() {
            let queue = Arc::new(LiveQueue {
                state: Mutex::new(LiveState {
                    items: VecDeque::new(),
                    finished: false,
                    dropped: 0,
                }),
                ready: Condvar::new(),
                capacity: options.live_queue,
            });
            let q = Arc::clone(&queue);
            let mut reader = reader;
            std::thread::spawn(move || {
                loop {
                    // The consumer gone (only its handle left): stop reading.
                    if Arc::strong_count(&q) == 1 {
                        break;
                    }
                    match reader.next_frame() {
                        Ok(Some(f)) => q.push(Ok(f), false),
                        Ok(None) => break,
                        Err(e) => {
                            q.push(Err(e), true);
                            break;
                        }
                    }
                }
                q.finish();
            });
            Feed::Live(queue)
        } else if options.overlap {
            // A queue of 4 decoded frames ahead of the models.
            let (tx, rx) = std::sync::mpsc::sync_channel::<Result<Frame>>(4);
            let mut reader = reader;
            std::thread::spawn(move || {
                loop {
                    let item = reader.next_frame();
                    let end = !matches!(item, Ok(Some(_)));
                    match item.transpose() {
                        Some(item) => {
                            if tx.send(item).is_err() {
                                break;
                            }
                        }
                        None => break,
                    }
                    if end {
                        break;
                    }
                }
            });
            Feed::Prefetched(rx)
        } else {
            Feed::Direct(reader)
        };
        let notes = match spec {
            SourceSpec::Bag { path, .. } | SourceSpec::Path(path) if kind == SourceKind::Bag => {
                crate::bag::split_read_alone(path).into_iter().collect()
            }
            _ => Vec::new(),
        };
        let known = list
            .as_ref()
            .map(|l| l.first(options.limit).len() as u64)
            .or(stack_pages);
        Ok(Self {
            known,
            kind,
            list,
            notes,
            late,
            undecodable,
            feed,
            limit: options.limit,
            given: 0,
            size,
            stopper,
        })
    }

    /// What the source is.
    pub fn kind(&self) -> SourceKind {
        self.kind
    }

    /// What a user should know of the source before the run: a folder's
    /// gaps in the numbering and files that are not frames, one split of a
    /// bag read alone. What reading finds is in
    /// [`FrameSource::late_warnings`], asked once the frames have ended
    /// (frames decoded ahead of the run may have found it already, so it
    /// is not here, where it would be told twice).
    pub fn warnings(&self) -> Vec<String> {
        let mut w = self
            .list
            .as_ref()
            .map(FrameList::warnings)
            .unwrap_or_default();
        w.extend(self.notes.iter().cloned());
        w
    }

    /// What was found while reading, known once the frames have ended: a
    /// bag file cut short (its frames read up to its last complete
    /// record), stdin ended inside a frame.
    pub fn late_warnings(&self) -> Vec<String> {
        self.late.lock().map(|l| l.clone()).unwrap_or_default()
    }

    /// The frames of a dataset or folder source.
    pub fn list(&self) -> Option<&FrameList> {
        self.list.as_ref()
    }

    /// How many frames the source gives when that is known before they
    /// are read (a dataset's, a folder's or a stack's, within the limit),
    /// for a progress bar's total; `None` for a stream.
    pub fn known_frames(&self) -> Option<u64> {
        self.known
    }

    /// The dataset read, as it was opened (so outputs are checked against
    /// the very rows the run reads).
    pub fn dataset(&self) -> Option<&Dataset> {
        self.list.as_ref()?.dataset.as_ref()
    }

    /// The frame size, when known before reading (streams, datasets).
    pub fn size(&self) -> Option<(usize, usize)> {
        self.size
    }

    /// Frames given so far.
    pub fn given(&self) -> u64 {
        self.given
    }

    /// True when frames are read on another thread while the models run.
    pub fn overlapped(&self) -> bool {
        !matches!(self.feed, Feed::Direct(_))
    }

    /// A folder's or dataset's frames skipped so far because they could
    /// not be decoded behind a whole header (each named by the late
    /// warning).
    pub fn undecodable(&self) -> u64 {
        self.undecodable.load(Ordering::Relaxed)
    }

    /// Live frames dropped so far because processing fell behind.
    pub fn dropped(&self) -> u64 {
        match &self.feed {
            Feed::Live(q) => q.state.lock().map_or(0, |s| s.dropped),
            _ => 0,
        }
    }

    /// The next frame, or `None` at the end (or after the limit).
    pub fn next_frame(&mut self) -> Result<Option<Frame>> {
        if self.limit.is_some_and(|n| self.given >= n) {
            self.stop();
            return Ok(None);
        }
        crate::interrupt::check()?;
        let frame = match &mut self.feed {
            Feed::Direct(r) => r.next_frame()?,
            Feed::Prefetched(rx) => match rx.recv() {
                Ok(item) => Some(item?),
                Err(_) => None,
            },
            Feed::Live(q) => q.pop()?,
        };
        if frame.is_some() {
            self.given += 1;
        }
        Ok(frame)
    }

    /// Stop a decoder or camera early.
    fn stop(&self) {
        if let Some(s) = &self.stopper {
            s.stop();
        }
    }
}

impl Iterator for FrameSource {
    type Item = Result<Frame>;

    fn next(&mut self) -> Option<Self::Item> {
        self.next_frame().transpose()
    }
}

impl Drop for FrameSource {
    fn drop(&mut self) {
        self.stop();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder's frame whose pixel data is cut short behind a whole
    /// header (a copy stopped half-way) is skipped when it is decoded and
    /// named in a warning; the frames around it are given, prefetched or
    /// not, and a limit counts the folder's first frames, the cut one
    /// among them.
    #[test]
    fn a_frame_cut_short_behind_its_header_is_skipped_and_named() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let (w, h) = (64, 48);
        let pixels: Vec<u8> = (0..w * h * 3).map(|i| (i * 37 % 251) as u8).collect();
        for name in ["1.png", "2.png", "3.png", "4.png"] {
            crate::image_io::save_rgb_png(d.join(name), w, h, &pixels).unwrap();
        }
        let whole = std::fs::read(d.join("2.png")).unwrap();
        std::fs::write(d.join("2.png"), &whole[..whole.len() / 2]).unwrap();
        let list = FrameList::open(d).unwrap();
        list.check_headers(None).unwrap();
        for overlap in [true, false] {
            for (limit, given) in [
                (None, vec!["1.png", "3.png", "4.png"]),
                (Some(3), vec!["1.png", "3.png"]),
            ] {
                let options = SourceOptions {
                    overlap,
                    limit,
                    ..SourceOptions::default()
                };
                let mut source =
                    FrameSource::open(&SourceSpec::Path(d.to_path_buf()), options).unwrap();
                let names: Vec<String> = (&mut source).map(|f| f.unwrap().name).collect();
                assert_eq!(names, given, "overlap {overlap}, limit {limit:?}");
                let late = source.late_warnings();
                assert_eq!(late.len(), 1, "{late:?}");
                assert!(
                    late[0].starts_with("warning: 1 of the ")
                        && late[0].contains("could not be decoded past their header")
                        && late[0].contains(&d.join("2.png").display().to_string()),
                    "{}",
                    late[0]
                );
                // Told once: not among the warnings before the run.
                assert!(source.warnings().is_empty());
                assert_eq!(source.undecodable(), 1);
            }
        }
        // Past the cut frame, the frames read have no warning.
        let options = SourceOptions {
            limit: Some(1),
            ..SourceOptions::default()
        };
        let mut source = FrameSource::open(&SourceSpec::Path(d.to_path_buf()), options).unwrap();
        assert_eq!((&mut source).count(), 1);
        assert!(source.late_warnings().is_empty());
        // When no frame can be decoded, nothing is kept: the source ends
        // with the refusal, alone or counted.
        let cut = tempfile::tempdir().unwrap();
        let half = std::fs::read(d.join("2.png")).unwrap();
        std::fs::write(cut.path().join("a.png"), &half).unwrap();
        let read = |dir: &Path| -> Result<usize> {
            let spec = SourceSpec::Path(dir.to_path_buf());
            let mut source = FrameSource::open(&spec, SourceOptions::default())?;
            source.try_fold(0, |n, f| f.map(|_| n + 1))
        };
        let e = read(cut.path()).unwrap_err();
        assert!(matches!(e, Error::Image { .. }), "{e}");
        std::fs::write(cut.path().join("b.png"), &half).unwrap();
        let e = read(cut.path()).unwrap_err();
        assert!(
            matches!(
                e,
                Error::UnreadableFrames {
                    count: 2,
                    total: 2,
                    ..
                }
            ) && e.to_string().contains("a.png: cannot decode image"),
            "{e}"
        );
        assert_eq!(read(d).unwrap(), 3);
    }

    /// Every frame a reader would refuse is found from its header, before
    /// any frame is decoded: named alone, or the first named and all
    /// counted; frames past the limit are not looked at.
    #[test]
    fn frames_that_cannot_be_read_are_found_from_their_headers() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let good = |name: &str, w: usize, h: usize| {
            crate::image_io::save_rgb_png(d.join(name), w, h, &vec![90; w * h * 3]).unwrap()
        };
        good("1.png", 8, 6);
        good("2.png", 8, 6);
        let list = FrameList::open(d).unwrap();
        list.check_headers(None).unwrap();

        std::fs::write(d.join("3.png"), b"").unwrap();
        std::fs::write(d.join("4.jpg"), b"not a picture").unwrap();
        image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(2, 2, vec![0u16; 12])
            .unwrap()
            .save(d.join("5.png"))
            .unwrap();
        let list = FrameList::open(d).unwrap();
        let e = list.check_headers(None).unwrap_err();
        assert!(
            matches!(
                e,
                Error::UnreadableFrames {
                    count: 3,
                    total: 5,
                    ..
                }
            ),
            "{e}"
        );
        let text = e.to_string();
        assert!(
            text.starts_with(&format!(
                "{}: cannot read the image header",
                d.join("3.png").display()
            )) && text.contains("3 of the 5 frames cannot be read"),
            "{text}"
        );
        let e = list.check_headers(Some(3)).unwrap_err();
        assert!(matches!(e, Error::Image { .. }), "{e}");
        list.check_headers(Some(2)).unwrap();
        // The 16-bit frame alone is refused as decoding it would be, with
        // what to do.
        let deep = FrameEntry {
            path: d.join("5.png"),
            sequence: None,
            tendon: None,
            size: None,
        };
        let (early, late) = (deep.check_header().unwrap_err(), deep.load().err().unwrap());
        assert_eq!(early.to_string(), late.to_string());
        assert!(
            early
                .to_string()
                .contains("16-bit RGB image; expected 8-bit RGB")
        );
        // A dataset's frame of another size than its manifest's.
        let row = FrameEntry {
            path: d.join("1.png"),
            size: Some((6, 8)),
            ..deep
        };
        let (early, late) = (row.check_header().unwrap_err(), row.load().err().unwrap());
        assert_eq!(early.to_string(), late.to_string());
        assert!(
            early
                .to_string()
                .contains("is 8x6, but manifest.json says the frames are 6x8")
        );
    }
}
