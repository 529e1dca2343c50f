//! The calibration layout: a folder of ball presses of one sensor.
//!
//! ```text
//! DIR/
//!   sensor.json     {"ball_diameter_mm": 4.0, "mm_per_px": 0.0295,
//!                    "background": "background.png"}
//!   background.png  the skin at rest (no contact), 8-bit RGB
//!   frames/*.png    one press of the ball each, same size (PNG, JPEG, BMP, TIFF, WebP, PGM/PPM)
//!   presses.csv     optional: file,centre_x_px,centre_y_px,contact_radius_px
//!                   (annotated circles, to score the circle finder),
//!                   and optionally ball_diameter_mm (a press of another ball)
//! ```
//! Every path stays inside `DIR`; sizes are checked before pixels are read.
//! gs_sdk's own calibration folder (`catalog.csv`, a folder per press with
//! its `label.npz`) is read as it is ([`crate::gs_sdk`]).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_core::image_io::{RgbImage, load_rgb};

use crate::prepare::{
    PreparedBackground, WorkingGrid, check_colour, check_not_blank, is_colour_background,
};
use crate::{Error, Result};

/// Most presses one calibration reads.
pub const MAX_PRESSES: usize = 2_000;
/// Largest `sensor.json` read, bytes.
pub const MAX_SENSOR_FILE_BYTES: u64 = 64 << 10;
/// Largest `presses.csv` read, bytes.
pub const MAX_PRESSES_FILE_BYTES: u64 = 4 << 20;

/// `sensor.json`: the ball and the camera's scale.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorInfo {
    /// What sensor this is (free text).
    #[serde(default)]
    pub sensor: String,
    /// The pressed ball's diameter, mm.
    pub ball_diameter_mm: f64,
    /// Millimetres per pixel on the skin.
    pub mm_per_px: f64,
    /// The background frame, relative to the folder.
    #[serde(default = "default_background")]
    pub background: String,
}

fn default_background() -> String {
    "background.png".into()
}

/// The keys of `sensor.json` a calibration reads; others are notes.
const SENSOR_KEYS: [&str; 4] = ["sensor", "ball_diameter_mm", "mm_per_px", "background"];

impl SensorInfo {
    /// Read `sensor.json` (its `text`; `file` names it in errors) and check
    /// it. Keys it does not read are notes (the shared R1.5 folder has
    /// `count`, `circles`, `source`), but one spelt nearly as a key it reads
    /// (`backgroud`, `Background`, `mm_per_pixel`) is refused: read as a
    /// note, a misspelt `background` would calibrate against
    /// `background.png` instead of the rest frame it names.
    pub fn parse(text: &str, file: &Path) -> Result<Self> {
        let bad = |why: String| Error::Layout {
            path: file.to_path_buf(),
            why,
        };
        // Misspelt keys first: a misspelt required key is named as such,
        // not as a missing one.
        let keys = serde_json::from_str::<serde_json::Map<String, serde_json::Value>>(text)
            .unwrap_or_default();
        for key in keys.keys().filter(|k| !SENSOR_KEYS.contains(&k.as_str())) {
            let near = SENSOR_KEYS.iter().find(|known| {
                strsim::normalized_damerau_levenshtein(&key.to_lowercase(), known) >= 0.75
            });
            if let Some(known) = near {
                return Err(bad(format!(
                    "key {key:?} is not one a calibration reads: did you mean {known:?}? (it reads {}; other keys are kept as notes)",
                    SENSOR_KEYS.join(", ")
                )));
            }
        }
        let sensor: Self = serde_json::from_str(text)
            .map_err(|e| bad(format!("not a sensor description: {e}")))?;
        sensor.check(file)?;
        Ok(sensor)
    }

    fn check(&self, file: &Path) -> Result<()> {
        match self.problem() {
            Some(why) => Err(Error::Layout {
                path: file.to_path_buf(),
                why,
            }),
            None => Ok(()),
        }
    }

    /// The same check of a calibrated model's copy (its config names it).
    pub fn check_config(&self) -> tactile_core::Result<()> {
        match self.problem() {
            Some(why) => Err(tactile_core::Error::Config(format!("sensor: {why}"))),
            None => Ok(()),
        }
    }

    /// What is wrong with the ball or the scale, if anything.
    fn problem(&self) -> Option<String> {
        if !is_ball_diameter(self.ball_diameter_mm) {
            return Some(format!(
                "ball_diameter_mm = {:?} is no ball of 0.1-100 mm",
                self.ball_diameter_mm
            ));
        }
        if !(self.mm_per_px.is_finite() && (1e-4..=1.0).contains(&self.mm_per_px)) {
            return Some(format!(
                "mm_per_px = {:?} is not a scale of 0.0001-1 mm per pixel",
                self.mm_per_px
            ));
        }
        None
    }
}

/// A contact circle in frame pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Circle {
    /// Centre column.
    pub centre_x_px: f64,
    /// Centre row.
    pub centre_y_px: f64,
    /// Contact radius.
    pub radius_px: f64,
}

impl Circle {
    /// Whether the edge of a `(w, h)` frame cuts the circle (a press near
    /// the edge, its contact seen in part).
    pub fn cut_by_edge(&self, (w, h): (usize, usize)) -> bool {
        let (x, y, r) = (self.centre_x_px, self.centre_y_px, self.radius_px);
        x - r < 0.0 || y - r < 0.0 || x + r > w as f64 || y + r > h as f64
    }
}

/// Where a folder's annotated circles are written, for messages that say
/// where to mend or add one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Annotations {
    /// The toolkit's `presses.csv`, a line per press.
    PressesCsv,
    /// gs_sdk's `label.npz` beside each press's `gelsight.png`.
    LabelNpz,
    /// Taxim's `dataPack.npz`, its `touch_center` and `touch_radius`.
    DataPack,
}

impl Annotations {
    /// The file that holds them.
    pub fn file(self) -> &'static str {
        match self {
            Self::PressesCsv => "presses.csv",
            Self::LabelNpz => "label.npz",
            Self::DataPack => crate::taxim::PACK_FILE,
        }
    }

    /// How a user gives a press its circle (`many`: several presses').
    pub fn how_to_give(self, many: bool) -> String {
        let which = match many {
            true => "their circles",
            false => "the press's circle",
        };
        match self {
            Self::PressesCsv => {
                format!("give {which} in presses.csv (centre_x_px, centre_y_px, contact_radius_px)")
            }
            Self::LabelNpz => format!(
                "label {which} with gs_sdk's label_data.py (a label.npz beside each gelsight.png)"
            ),
            Self::DataPack => format!(
                "label {which} with Taxim's generateDataPack.py (touch_center and touch_radius in \
                 dataPack.npz)"
            ),
        }
    }

    /// What most likely put an annotation far from its contact, and how to
    /// mend it.
    pub fn how_to_mend(self) -> &'static str {
        match self {
            Self::PressesCsv => {
                "a mistyped line (centre_x_px is the column, centre_y_px the row)? Correct it, remove the press's line"
            }
            Self::LabelNpz => {
                "a circle saved before it was moved onto the contact? Label the press again, remove its label.npz"
            }
            Self::DataPack => {
                "touch_center saved as [row, column] (Taxim's is [x, y]), or a circle saved before it was moved onto the contact? Save touch_center as [x, y] or label the presses again with Taxim's generateDataPack.py"
            }
        }
    }
}

/// One press: its frame file and, when `presses.csv` gives one, the
/// annotated circle.
#[derive(Debug, Clone)]
pub struct Press {
    /// Relative to the folder (`frames/press_01.png`).
    pub file: String,
    /// The annotated contact circle.
    pub annotated: Option<Circle>,
    /// The ball pressed, mm, where it is not `sensor.json`'s: a folder may
    /// hold presses of several balls (`presses.csv`'s `ball_diameter_mm`,
    /// gs_sdk's catalog).
    pub ball_diameter_mm: Option<f64>,
}

/// A calibration folder, read and checked.
#[derive(Clone)]
pub struct BallPresses {
    /// The folder.
    pub root: PathBuf,
    /// `sensor.json`.
    pub sensor: SensorInfo,
    /// The file the scale was read from: `sensor.json`, or gs_sdk's config
    /// copied into the folder.
    pub scale_file: PathBuf,
    /// gs_sdk's config copied into the folder, if one is (its scale, or a
    /// check of `sensor.json`'s; how its camera's frames are cut).
    pub gs_sdk_config: Option<crate::gs_sdk_config::GsSdkConfig>,
    /// The skin at rest.
    pub background: RgbImage,
    /// Every press, in file order.
    pub presses: Vec<Press>,
    /// What a user should know about the folder: files in `frames/` that
    /// are not frame files, or frames there that `presses.csv`
    /// does not list, and so are no presses.
    pub warnings: Vec<String>,
    /// The background is a colour sensor's ([`is_colour_background`]):
    /// grey presses are refused. Told once, when the folder is opened.
    pub colour: bool,
    /// Where the annotated circles are written.
    pub annotations: Annotations,
    /// The presses' frames where the folder holds them in one file (Taxim's
    /// `dataPack.npz`), by press; `None` where each press is a file.
    pub held: Option<std::sync::Arc<Vec<RgbImage>>>,
}

impl std::fmt::Debug for BallPresses {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BallPresses")
            .field("root", &self.root)
            .field("sensor", &self.sensor)
            .field("size", &self.size())
            .field("presses", &self.presses.len())
            .finish()
    }
}

/// The last part of `path` as text (`gsmini.yaml`), for messages.
pub(crate) fn file_name_of(path: &Path) -> String {
    path.file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned()
}

/// The UTF-8 text of `path`, at most `limit` bytes (a byte-order mark
/// dropped).
pub(crate) fn read_text(path: &Path, limit: u64) -> Result<String> {
    let bytes = tactile_core::io::read_limited(path, limit)?;
    let text = tactile_core::io::without_byte_order_mark(&bytes);
    String::from_utf8(text.to_vec()).map_err(|_| Error::Layout {
        path: path.to_path_buf(),
        why: format!("is not UTF-8 text{}", tactile_core::io::utf16_hint(&bytes)),
    })
}

/// `rel` joined to `root`, and the file it names (through `./` and links,
/// to tell a file listed twice); refused (with the reason) when it leaves
/// `root` by its name or through a symbolic link (`canonical` is `root`'s
/// canonical path, resolved once per folder).
pub(crate) fn inside(
    root: &Path,
    canonical: &Path,
    rel: &str,
) -> std::result::Result<(PathBuf, PathBuf), String> {
    use tactile_core::dataset::Escape;
    // `./frames/a.png` is `frames/a.png`, as a dataset's labels.csv reads it.
    let p = Path::new(rel);
    match tactile_core::dataset::resolve_inside(canonical, p) {
        Ok(resolved) => Ok((root.join(p), resolved)),
        Err(Escape::Absolute | Escape::Parent) => Err(format!(
            "'{rel}' is not a path inside the calibration folder"
        )),
        Err(Escape::Loop) => Err(format!("'{rel}' passes through too many symbolic links")),
        Err(Escape::Empty) => Err("a file name is empty".into()),
        Err(Escape::Link) => Err(format!(
            "'{rel}' passes through a symbolic link that leaves the calibration folder"
        )),
    }
}

impl BallPresses {
    /// Read the folder `root`: `sensor.json`, the background, the presses
    /// (from `presses.csv` when there is one, else every frame file in
    /// `frames/`); or gs_sdk's folder ([`crate::gs_sdk`]); or Taxim's
    /// folder, or its pack itself (`root` a `.npz` file:
    /// [`crate::taxim`]).
    pub fn open(root: impl AsRef<Path>) -> Result<Self> {
        let root = root.as_ref().to_path_buf();
        if root.is_file()
            && root
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("npz"))
        {
            let pack = file_name_of(&root);
            let dir = tactile_core::io::folder_of(&root).to_path_buf();
            return crate::taxim::open(dir, &pack);
        }
        tactile_core::io::expect_folder(&root, "calibration folder")?;
        if crate::taxim::is_taxim_folder(&root) {
            return crate::taxim::open(root, crate::taxim::PACK_FILE);
        }
        let sensor_file = root.join("sensor.json");
        let mut scale_file = sensor_file.clone();
        let mut gs_sdk_config = None;
        let (sensor, catalog) = match crate::gs_sdk::is_gs_sdk_folder(&root) {
            true => {
                let (sensor, catalog) = crate::gs_sdk::sensor_and_catalog(&root)?;
                scale_file = catalog.scale_file();
                gs_sdk_config = catalog.config().cloned();
                (sensor, Some(catalog))
            }
            false if !sensor_file.exists() => {
                return Err(Error::Layout {
                    path: sensor_file,
                    why: format!(
                        "missing: a calibration folder has sensor.json (ball_diameter_mm, \
                         mm_per_px){}",
                        crate::taxim::pack_hint(&root)
                    ),
                });
            }
            false => {
                let text = read_text(&sensor_file, MAX_SENSOR_FILE_BYTES)?;
                (SensorInfo::parse(&text, &sensor_file)?, None)
            }
        };
        let canonical = root
            .canonicalize()
            .map_err(|e| tactile_core::Error::io(&root, e))?;
        let (bg_path, _) =
            inside(&root, &canonical, &sensor.background).map_err(|why| Error::Layout {
                path: sensor_file.clone(),
                why,
            })?;
        if !bg_path.exists() {
            return Err(Error::Layout {
                path: bg_path,
                why: format!(
                    "missing: the background frame (the skin at rest, no contact){}",
                    crate::taxim::pack_hint(&root)
                ),
            });
        }
        let background = load_rgb(&bg_path)?;
        // A blank rest frame would make every press's colour change its
        // own picture, and the sensor grey whatever the camera.
        check_not_blank(&bg_path, &background)?;
        let csv_path = root.join("presses.csv");
        let size = (background.width(), background.height());
        let annotations = match catalog {
            Some(_) => Annotations::LabelNpz,
            None => Annotations::PressesCsv,
        };
        let (presses, warnings) = if let Some(mut catalog) = catalog {
            catalog.check_scale(&sensor, &bg_path, size)?;
            catalog.presses(&root, &canonical, &sensor, size)?
        } else if csv_path.exists() {
            let (presses, listed) = read_presses_csv(&root, &canonical, &csv_path, &sensor, size)?;
            (presses, unlisted_frames_warning(&root, &listed))
        } else {
            list_frames(&root)?
        };
        Ok(Self {
            root,
            sensor,
            scale_file,
            gs_sdk_config,
            colour: is_colour_background(&background),
            background,
            presses,
            warnings,
            annotations,
            held: None,
        })
    }

    /// The name of the file the scale was read from (`sensor.json`,
    /// `gsmini.yaml`), for reports.
    pub fn scale_from(&self) -> String {
        file_name_of(&self.scale_file)
    }

    /// `(width, height)` of the sensor's frames.
    pub fn size(&self) -> (usize, usize) {
        (self.background.width(), self.background.height())
    }

    /// The frame of press `i`, its size checked against the background's,
    /// and in colour when the background is.
    pub fn frame(&self, i: usize) -> Result<RgbImage> {
        let path = self.press_path(i);
        let img = self.frame_as_saved(i)?;
        let found = (img.width(), img.height());
        if found != self.size() {
            return Err(Error::FrameSize {
                path,
                expected: self.size(),
                found,
            });
        }
        check_colour(&path, &img, self.colour)?;
        // A press in BGR order beside a background in RGB (saved by
        // another tool) would be fitted as a skin mirrored.
        if self.colour {
            let (w, h) = found;
            let factor = if w.min(h) >= 32 { 4 } else { 1 };
            let grid = WorkingGrid {
                frame_width: w,
                frame_height: h,
                factor,
            };
            let bg = PreparedBackground::new(&self.background, grid)?;
            bg.check_channel_order(&bg.matched(&img)?, &path)?;
        }
        Ok(img)
    }

    /// The frame of press `i` as its file (or the pack) holds it,
    /// unchecked: [`Self::frame`] checks it.
    pub fn frame_as_saved(&self, i: usize) -> Result<RgbImage> {
        match &self.held {
            Some(frames) => frames.get(i).cloned().ok_or_else(|| {
                Error::from(tactile_core::Error::Invalid(format!(
                    "press {i}: the folder holds {} presses",
                    frames.len()
                )))
            }),
            None => Ok(load_rgb(self.press_path(i))?),
        }
    }

    /// Press `i`'s frame file, to name it (a press held in a pack:
    /// `DIR/dataPack.npz:<name>`).
    pub fn press_path(&self, i: usize) -> PathBuf {
        let file = self.presses.get(i).map_or("", |p| p.file.as_str());
        self.root.join(file)
    }

    /// The background's file, to name it (in a pack: `DIR/dataPack.npz:f0`).
    pub fn background_path(&self) -> PathBuf {
        self.root.join(&self.sensor.background)
    }

    /// Write the background to `to` as a model keeps it: its file's bytes,
    /// or a PNG of the frame a pack holds.
    pub fn save_background(&self, to: &Path) -> Result<()> {
        match self.held {
            Some(_) => {
                let (w, h) = self.size();
                tactile_core::image_io::save_rgb_png(to, w, h, self.background.as_slice())?;
            }
            None => {
                // Copied as bytes: the folder's own file, writable
                // whatever the source's permissions.
                let bytes = tactile_core::io::read_limited(
                    self.background_path(),
                    tactile_core::image_io::MAX_IMAGE_FILE_BYTES,
                )?;
                tactile_core::io::write_atomic(to, &bytes)?;
            }
        }
        Ok(())
    }

    /// The diameter of the ball of press `i`, mm.
    pub fn ball_diameter_mm(&self, i: usize) -> f64 {
        (self.presses.get(i))
            .and_then(|p| p.ball_diameter_mm)
            .unwrap_or(self.sensor.ball_diameter_mm)
    }

    /// The radius of the ball of press `i`, pixels.
    pub fn ball_radius_px(&self, i: usize) -> f64 {
        self.ball_diameter_mm(i) / 2.0 / self.sensor.mm_per_px
    }

    /// The balls pressed, mm, smallest first.
    pub fn balls_mm(&self) -> Vec<f64> {
        let mut balls: Vec<f64> = (0..self.presses.len().max(1))
            .map(|i| self.ball_diameter_mm(i))
            .collect();
        balls.sort_by(f64::total_cmp);
        balls.dedup();
        balls
    }

    /// Press `i` in a few characters, for captions: its file's name
    /// (`press_01.png`), or where every press has the same name (gs_sdk's
    /// `gelsight.png`) the folder that tells it (`4.000mm/3`).
    pub fn press_name(&self, i: usize) -> String {
        let Some(p) = self.presses.get(i) else {
            return String::new();
        };
        if let Some(name) = crate::taxim::held_press_name(&p.file) {
            return name.to_string();
        }
        let path = Path::new(&p.file);
        let name = path.file_name().map(|f| f.to_string_lossy().into_owned());
        let name = name.unwrap_or_else(|| p.file.clone());
        let shared = (self.presses.iter())
            .filter(|q| Path::new(&q.file).file_name() == path.file_name())
            .take(2)
            .count()
            > 1;
        match (shared, path.parent()) {
            (true, Some(dir)) if !dir.as_os_str().is_empty() => dir.to_string_lossy().into_owned(),
            _ => name,
        }
    }

    /// Where press `i`'s ball and the scale are written, for a message
    /// that asks to check them.
    fn where_the_scale_is(&self, i: usize) -> String {
        let own = self
            .presses
            .get(i)
            .is_some_and(|p| p.ball_diameter_mm.is_some());
        self.ball_words(own).1
    }

    /// Where the presses' balls and the scale are written, for messages on
    /// them all: `("sensor.json gives", "ball_diameter_mm and mm_per_px in
    /// sensor.json")` where every press has `sensor.json`'s ball;
    /// `gsmini.yaml's ppmm` where gs_sdk's config gave the scale.
    pub fn where_the_balls_are(&self) -> (String, String) {
        self.ball_words(self.presses.iter().any(|p| p.ball_diameter_mm.is_some()))
    }

    /// [`Self::where_the_balls_are`] of presses with balls of their own
    /// (`own`) or `sensor.json`'s.
    fn ball_words(&self, own: bool) -> (String, String) {
        let from = self.scale_from();
        let scale = match from.as_str() {
            "sensor.json" => "sensor.json's mm_per_px".to_string(),
            config => format!("{config}'s ppmm"),
        };
        match (own, self.annotations) {
            // A pack's presses are all of sensor.json's ball.
            (false, _) | (_, Annotations::DataPack) => (
                format!("{from} gives"),
                "ball_diameter_mm and mm_per_px in sensor.json".to_string(),
            ),
            (true, Annotations::PressesCsv) => (
                format!("{from} and presses.csv give"),
                format!("presses.csv's ball_diameter_mm and {scale}"),
            ),
            (true, Annotations::LabelNpz) => (
                format!("{from} and catalog.csv give"),
                format!("catalog.csv's diameter(mm) and {scale}"),
            ),
        }
    }

    /// The balls in words: `a 4 mm ball`, `balls of 4, 6 mm`.
    pub fn describe_balls(&self) -> String {
        match self.balls_mm()[..] {
            [one] => format!("a {one} mm ball"),
            ref many => format!(
                "balls of {} mm",
                many.iter()
                    .map(f64::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }

    /// Refuse a circle of press `i` centred off the frame or wider than
    /// its ball.
    pub fn check_circle(&self, i: usize, path: &Path, c: &Circle) -> Result<()> {
        match circle_problem(&self.sensor, self.ball_diameter_mm(i), self.size(), c) {
            None => Ok(()),
            Some(why) => Err(Error::Press {
                path: path.to_path_buf(),
                why,
            }),
        }
    }

    /// [`Self::check_circle`] of a circle the toolkit found, not one a
    /// user wrote: said to a tenth of a pixel, and with what to do (the
    /// finder mistook the contact, or `sensor.json` scales every press).
    pub fn check_found_circle(&self, i: usize, path: &Path, c: &Circle) -> Result<()> {
        let ball = self.ball_diameter_mm(i);
        let Some(mut why) = circle_problem(&self.sensor, ball, self.size(), c) else {
            return Ok(());
        };
        let tenth = |v: f64| (v * 10.0).round() / 10.0;
        let said = Circle {
            centre_x_px: tenth(c.centre_x_px),
            centre_y_px: tenth(c.centre_y_px),
            radius_px: tenth(c.radius_px),
        };
        if let Some(rounded) = circle_problem(&self.sensor, ball, self.size(), &said) {
            why = rounded;
        }
        Err(Error::Press {
            path: path.to_path_buf(),
            why: format!(
                "the contact circle found in it: {why}; {}, or check {}, which scale every press",
                self.annotations.how_to_give(false),
                self.where_the_scale_is(i)
            ),
        })
    }
}

/// Whether `d` is a ball's diameter, mm (0.1-100), as `sensor.json`, a
/// column of `presses.csv` or gs_sdk's catalog gives it.
pub(crate) fn is_ball_diameter(d: f64) -> bool {
    d.is_finite() && (0.1..=100.0).contains(&d)
}

/// Record that the press `what` (the file it names, `resolved`) is listed
/// on `line` of its list; refused when an earlier line listed it: a press
/// listed twice would be fitted twice, and could be fitted and held out at
/// once.
pub(crate) fn listed_once(
    listed: &mut std::collections::HashMap<PathBuf, usize>,
    resolved: PathBuf,
    line: usize,
    what: &str,
) -> std::result::Result<(), String> {
    match listed.insert(resolved, line) {
        Some(first) => Err(format!(
            "line {line}: {what} is listed already on line {first}: a press is one row \
             (delete one of the two)"
        )),
        None => Ok(()),
    }
}

/// What makes `c` no contact circle of a ball of `ball_diameter_mm` on a
/// `(w, h)` frame of `sensor`: not a finite number, too small, wider than
/// the ball, or centred off the frame (a circle the frame's edge cuts is a
/// press near the edge, and is read).
pub(crate) fn circle_problem(
    sensor: &SensorInfo,
    ball_diameter_mm: f64,
    (w, h): (usize, usize),
    c: &Circle,
) -> Option<String> {
    let (x, y, r) = (c.centre_x_px, c.centre_y_px, c.radius_px);
    if !(x.is_finite() && y.is_finite() && r.is_finite()) {
        return Some(format!(
            "contact circle at ({x:?}, {y:?}) radius {r:?} px is not a finite number"
        ));
    }
    if r < 2.0 {
        return Some(format!("contact radius {r:?} px is no contact"));
    }
    let ball_radius_px = ball_diameter_mm / 2.0 / sensor.mm_per_px;
    if r >= ball_radius_px {
        return Some(format!(
            "contact radius {r:?} px is not smaller than the ball's radius {ball_radius_px:.1} px ({} mm at {} mm/px): a ball cannot touch wider than itself",
            ball_diameter_mm / 2.0,
            sensor.mm_per_px
        ));
    }
    // A press near the edge keeps the part of its contact the frame shows:
    // every target and score is taken pixel by pixel over the frame.
    if !(0.0..w as f64).contains(&x) || !(0.0..h as f64).contains(&y) {
        return Some(format!(
            "contact circle at ({x:?}, {y:?}) radius {r:?} px: its centre is off the {w}x{h} frame"
        ));
    }
    None
}

/// The presses `presses.csv` lists, each annotated circle checked against
/// the sensor and the `frame_size`; a bad one is named by its line.
fn read_presses_csv(
    root: &Path,
    canonical: &Path,
    path: &Path,
    sensor: &SensorInfo,
    frame_size: (usize, usize),
) -> Result<(Vec<Press>, std::collections::HashSet<PathBuf>)> {
    let text = read_text(path, MAX_PRESSES_FILE_BYTES)?;
    let mut rd = tactile_core::csv_lines::reader(&csv::ReaderBuilder::new(), text.as_bytes());
    let headers = rd
        .headers()
        .map_err(|e| Error::Layout {
            path: path.to_path_buf(),
            why: format!("cannot read the header: {e}"),
        })?
        .clone();
    let col = |name: &str| headers.iter().position(|h| h.trim() == name);
    let file_col = col("file").ok_or_else(|| Error::Layout {
        path: path.to_path_buf(),
        why: format!(
            "no 'file' column{}",
            tactile_core::csv_lines::separator_hint(headers.iter())
        ),
    })?;
    let circle_cols = match (
        col("centre_x_px"),
        col("centre_y_px"),
        col("contact_radius_px"),
    ) {
        (Some(x), Some(y), Some(r)) => Some([x, y, r]),
        (None, None, None) => None,
        _ => {
            return Err(Error::Layout {
                path: path.to_path_buf(),
                why: "give all of centre_x_px, centre_y_px, contact_radius_px or none".into(),
            });
        }
    };
    let ball_col = col("ball_diameter_mm");
    let mut out = Vec::new();
    // The line each frame is listed on ([`listed_once`]).
    let mut listed: std::collections::HashMap<PathBuf, usize> = Default::default();
    for item in tactile_core::csv_lines::records(&mut rd) {
        let (line, rec) = item.map_err(|(line, why)| Error::Layout {
            path: path.to_path_buf(),
            why: format!("line {line}: {why}"),
        })?;
        if out.len() >= MAX_PRESSES {
            return Err(Error::Layout {
                path: path.to_path_buf(),
                why: format!("more than {MAX_PRESSES} presses"),
            });
        }
        let file = rec.get(file_col).unwrap_or("").trim().to_string();
        let (frame, the_file) = inside(root, canonical, &file).map_err(|why| Error::Layout {
            path: path.to_path_buf(),
            why: format!("line {line}: {why}"),
        })?;
        if !frame.exists() {
            return Err(Error::Layout {
                path: path.to_path_buf(),
                why: format!(
                    "line {line}: frame '{file}' does not exist{}",
                    tactile_core::dataset::backslash_hint(&file)
                ),
            });
        }
        listed_once(&mut listed, the_file, line, &format!("frame '{file}'")).map_err(|why| {
            Error::Layout {
                path: path.to_path_buf(),
                why,
            }
        })?;
        // A press of another ball than sensor.json's names it; an empty cell
        // is sensor.json's.
        let ball_diameter_mm = match ball_col.map(|c| rec.get(c).unwrap_or("").trim()) {
            None | Some("") => None,
            Some(d) => {
                let bad = |why: String| Error::Layout {
                    path: path.to_path_buf(),
                    why: format!("line {line}: {why}"),
                };
                let v = (d.parse::<f64>())
                    .map_err(|_| bad(format!("'{d}' in ball_diameter_mm is not a number")))?;
                if !is_ball_diameter(v) {
                    return Err(bad(format!(
                        "ball_diameter_mm = {d} is no ball of 0.1-100 mm"
                    )));
                }
                Some(v)
            }
        };
        let ball = ball_diameter_mm.unwrap_or(sensor.ball_diameter_mm);
        let annotated = match circle_cols {
            None => None,
            Some(cols) => {
                let mut v = [0.0; 3];
                for (k, c) in cols.iter().enumerate() {
                    let s = rec.get(*c).unwrap_or("").trim();
                    v[k] = s.parse::<f64>().map_err(|_| Error::Layout {
                        path: path.to_path_buf(),
                        why: format!("line {line}: '{s}' in {} is not a number", &headers[*c]),
                    })?;
                }
                let c = Circle {
                    centre_x_px: v[0],
                    centre_y_px: v[1],
                    radius_px: v[2],
                };
                if let Some(why) = circle_problem(sensor, ball, frame_size, &c) {
                    return Err(Error::Layout {
                        path: path.to_path_buf(),
                        why: format!("line {line}: {file}: {why}"),
                    });
                }
                Some(c)
            }
        };
        out.push(Press {
            file,
            annotated,
            ball_diameter_mm,
        });
    }
    Ok((out, listed.into_keys().collect()))
}

/// The warning naming the frames in `root/frames` that `presses.csv` does
/// not list (`listed`: the files its rows name, resolved): they are no
/// presses, and a press added to the folder without its row would
/// otherwise be left out of the fit without a word.
fn unlisted_frames_warning(
    root: &Path,
    listed: &std::collections::HashSet<PathBuf>,
) -> Vec<String> {
    let dir = root.join("frames");
    let Ok(list) = tactile_core::source::FrameList::open(&dir) else {
        return Vec::new();
    };
    let unlisted: Vec<String> = (list.frames.iter())
        .filter(|f| (f.path.canonicalize()).is_ok_and(|p| !listed.contains(&p)))
        .map(|f| file_name_of(&f.path))
        .collect();
    if unlisted.is_empty() {
        return Vec::new();
    }
    let (named, these) = tactile_core::source::named_frames(&unlisted);
    vec![format!(
        "warning: {}: {} of its {} frames are not listed in presses.csv, so they are no presses \
         and are not fitted ({named}): add a row for each of {these}, or move {them} out of frames/",
        dir.display(),
        unlisted.len(),
        list.frames.len(),
        them = if unlisted.len() == 1 { "it" } else { "them" },
    )]
}

/// Every frame file in `root/frames`, in the order of the numbers in
/// their names, read as every folder of frames is
/// (`core::source::FrameList`), and the warning naming
/// the files there that are not frames (a press saved in another format
/// would otherwise be left out without a word).
fn list_frames(root: &Path) -> Result<(Vec<Press>, Vec<String>)> {
    let dir = root.join("frames");
    if !dir.is_dir() {
        return Err(Error::Layout {
            path: dir,
            why: format!(
                "missing: a calibration folder has frames/ with one frame file per press{}",
                crate::taxim::pack_hint(root)
            ),
        });
    }
    let list = tactile_core::source::FrameList::open(&dir)?;
    if list.frames.len() > MAX_PRESSES {
        return Err(Error::Layout {
            path: dir,
            why: format!("more than {MAX_PRESSES} presses"),
        });
    }
    let presses = list
        .frames
        .iter()
        .map(|f| Press {
            file: format!(
                "frames/{}",
                f.path.file_name().unwrap_or_default().to_string_lossy()
            ),
            annotated: None,
            ball_diameter_mm: None,
        })
        .collect();
    Ok((presses, list.ignored_warning().into_iter().collect()))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// Notes are kept, a misspelt key is named with the key it nearly is.
    #[test]
    fn sensor_json_keeps_notes_and_names_a_misspelt_key() {
        let file = Path::new("cal/sensor.json");
        let parse = |text: &str| SensorInfo::parse(text, file);
        // The shared R1.5 folder's keys: three notes beside the four read.
        let r15 = r#"{"sensor": "R1.5", "ball_diameter_mm": 4.0, "mm_per_px": 0.0295,
            "count": 32, "background": "rest.png", "circles": "annotated", "source": "taxim"}"#;
        let s = parse(r15).unwrap();
        assert_eq!(
            (s.background.as_str(), s.ball_diameter_mm),
            ("rest.png", 4.0)
        );
        for (key, meant) in [
            ("backgroud", "background"),
            ("Background", "background"),
            ("mm_per_pixel", "mm_per_px"),
            ("bal_diameter_mm", "ball_diameter_mm"),
            ("sensors", "sensor"),
        ] {
            let text = r15.replace("\"background\"", "\"background_note\"");
            let text = match meant {
                "background" => text.replace("\"background_note\"", &format!("{key:?}")),
                _ => text.replace(&format!("{meant:?}"), &format!("{key:?}")),
            };
            let e = parse(&text).unwrap_err().to_string();
            assert!(
                e.contains("cal/sensor.json")
                    && e.contains(&format!("key {key:?} is not one a calibration reads"))
                    && e.contains(&format!("did you mean {meant:?}")),
                "{key}: {e}"
            );
        }
        // Not an object at all: the description's own error.
        let e = parse("[1, 2]").unwrap_err().to_string();
        assert!(e.contains("not a sensor description"), "{e}");
    }
}
