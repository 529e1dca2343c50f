//! gs_sdk's calibration folder, read as it is.
//!
//! gs_sdk's `collect_data.py` and `label_data.py` (the latter rewritten
//! from Taxim's labelling tool) keep ball presses so:
//!
//! ```text
//! DIR/
//!   background.png            the skin at rest
//!   catalog.csv               experiment_reldir,diameter(mm)
//!                             4.000mm/0,4.000
//!   4.000mm/0/gelsight.png    one press
//!   4.000mm/0/label.npz       its circle, from label_data.py: center [x, y]
//!                             and radius, in pixels (optional)
//!   sensor.json               written by hand: {"mm_per_px": 0.0634}
//! ```
//!
//! gs_sdk keeps the scale in the sensor's config (`ppmm`, millimetres per
//! pixel despite its name), not in the folder, so `sensor.json` gives it.
//! Each press's ball is read from `catalog.csv`: a catalog may list presses
//! of several balls, and each press is fitted with its own. A
//! `ball_diameter_mm` in `sensor.json` chooses one ball: the presses of the
//! others are left out, named in a warning.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

use crate::gs_sdk_config::{ConfigsFound, GsSdkConfig};
use crate::layout::{Circle, MAX_PRESSES, MAX_PRESSES_FILE_BYTES, Press, SensorInfo};
use crate::{Error, Result};

/// gs_sdk's list of presses.
pub const CATALOG_FILE: &str = "catalog.csv";
/// Each press's frame, in its own folder.
pub const FRAME_FILE: &str = "gelsight.png";
/// Each press's labelled circle, beside its frame.
pub const LABEL_FILE: &str = "label.npz";
/// Largest `label.npz` read, bytes (gs_sdk's are under 1 KB).
pub const MAX_LABEL_FILE_BYTES: u64 = 64 << 10;
/// Largest array read from a `label.npz`, bytes.
const MAX_LABEL_ARRAY_BYTES: u64 = 4 << 10;
/// Diameters in `catalog.csv` are written to a thousandth of a millimetre.
const SAME_BALL_MM: f64 = 5e-4;

/// Whether `root` is a gs_sdk calibration folder: `catalog.csv` and none
/// of the toolkit's own `presses.csv` or `frames/`.
pub fn is_gs_sdk_folder(root: &Path) -> bool {
    root.join(CATALOG_FILE).is_file()
        && !root.join("presses.csv").exists()
        && !root.join("frames").exists()
}

/// One row of `catalog.csv`.
#[derive(Debug, Clone)]
struct CatalogRow {
    /// Its line in the file.
    line: usize,
    /// The press's folder, relative to the calibration folder, with `/`.
    folder: String,
    /// The ball's diameter, mm.
    diameter_mm: f64,
}

/// The catalog's presses to calibrate: all, or those of the ball
/// `sensor.json` chooses.
#[derive(Debug)]
pub(crate) struct Catalog {
    path: PathBuf,
    rows: Vec<CatalogRow>,
    /// Every press folder the catalog lists, of any ball.
    listed: Vec<String>,
    /// Presses of other balls left out.
    pub(crate) warnings: Vec<String>,
    /// gs_sdk's config copied into the folder, if one is.
    config: Option<GsSdkConfig>,
    /// Whether the scale is the config's (no `sensor.json`).
    scale_from_config: bool,
}

/// `4.000 mm: 30 presses, 6.000 mm: 25` of `rows`.
fn balls(rows: &[&CatalogRow]) -> String {
    let mut count: BTreeMap<i64, usize> = BTreeMap::new();
    for r in rows {
        *count
            .entry((r.diameter_mm * 1e3).round() as i64)
            .or_default() += 1;
    }
    count
        .iter()
        .map(|(d, n)| {
            let s = if *n == 1 { "" } else { "es" };
            format!("{:.3} mm: {n} press{s}", *d as f64 / 1e3)
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Read `catalog.csv`; every row checked (its folder a path inside the
/// calibration folder, its diameter a ball's).
fn read_catalog(path: &Path) -> Result<Vec<CatalogRow>> {
    let text = crate::layout::read_text(path, MAX_PRESSES_FILE_BYTES)?;
    let mut rd = tactile_core::csv_lines::reader(&csv::ReaderBuilder::new(), text.as_bytes());
    let headers = rd
        .headers()
        .map_err(|e| Error::layout(path, format!("cannot read the header: {e}")))?
        .clone();
    let col = |name: &str| headers.iter().position(|h| h.trim() == name);
    let (Some(folder_col), Some(diameter_col)) = (col("experiment_reldir"), col("diameter(mm)"))
    else {
        return Err(Error::layout(
            path,
            format!(
                "not gs_sdk's ball catalog: it has the columns experiment_reldir and diameter(mm) \
                 (gs_sdk's collect_data.py writes them); found {}{}",
                headers.iter().collect::<Vec<_>>().join(", "),
                tactile_core::csv_lines::separator_hint(headers.iter())
            ),
        ));
    };
    let mut rows = Vec::new();
    for item in tactile_core::csv_lines::records(&mut rd) {
        let (line, rec) =
            item.map_err(|(line, why)| Error::layout(path, format!("line {line}: {why}")))?;
        if rows.len() >= MAX_PRESSES {
            return Err(Error::layout(
                path,
                format!("more than {MAX_PRESSES} presses"),
            ));
        }
        // gs_sdk joins the folder with os.path.join: backslashes on Windows.
        let folder = rec.get(folder_col).unwrap_or("").trim().replace('\\', "/");
        let folder = folder.trim_end_matches('/').to_string();
        let d = rec.get(diameter_col).unwrap_or("").trim();
        let diameter_mm = d.parse::<f64>().map_err(|_| {
            Error::layout(
                path,
                format!("line {line}: '{d}' in diameter(mm) is not a number"),
            )
        })?;
        if !crate::layout::is_ball_diameter(diameter_mm) {
            return Err(Error::layout(
                path,
                format!("line {line}: diameter(mm) = {d} is no ball of 0.1-100 mm"),
            ));
        }
        rows.push(CatalogRow {
            line,
            folder,
            diameter_mm,
        });
    }
    if rows.is_empty() {
        return Err(Error::layout(path, "lists no press"));
    }
    Ok(rows)
}

/// `sensor.json` of a gs_sdk folder, its ball the first press's where it
/// names none, and the catalog's presses: all of them, or those of the
/// ball it names.
pub(crate) fn sensor_and_catalog(root: &Path) -> Result<(SensorInfo, Catalog)> {
    let catalog_path = root.join(CATALOG_FILE);
    let rows = read_catalog(&catalog_path)?;
    let sensor_file = root.join("sensor.json");
    let has_sensor_file = sensor_file.exists();
    let found = crate::gs_sdk_config::config_in(root, !has_sensor_file)?;
    let (text, scale_from, config) = match (has_sensor_file, found) {
        (true, found) => {
            let text =
                crate::layout::read_text(&sensor_file, crate::layout::MAX_SENSOR_FILE_BYTES)?;
            let config = match found {
                ConfigsFound::One(c) => Some(c),
                ConfigsFound::None(_) => None,
            };
            (text, sensor_file.clone(), config)
        }
        (false, ConfigsFound::One(c)) => {
            let mut map = serde_json::Map::new();
            map.insert("mm_per_px".into(), c.mm_per_px.into());
            if let Some(name) = &c.device_name {
                map.insert("sensor".into(), name.clone().into());
            }
            let text = serde_json::Value::Object(map).to_string();
            (text, c.path.clone(), Some(c))
        }
        (false, ConfigsFound::None(others)) => {
            let beside = match &others[..] {
                [] => String::new(),
                names => format!(
                    " ({} here {} no ppmm)",
                    names.join(", "),
                    if names.len() == 1 { "has" } else { "have" }
                ),
            };
            return Err(Error::layout(
                &sensor_file,
                format!(
                    "missing: gs_sdk keeps the sensor's scale in its config file, not in the \
                     calibration folder; copy that config here (such as gs_sdk's \
                     examples/configs/gsmini.yaml: its ppmm and imgw x imgh are read){beside}, \
                     or write sensor.json here with the scale, such as {{\"mm_per_px\": 0.0634}} \
                     (the config's ppmm, millimetres per pixel: 0.0634 is gs_sdk's GelSight Mini \
                     at 320x240). The ball's diameter is read from catalog.csv"
                ),
            ));
        }
    };
    let all: Vec<&CatalogRow> = rows.iter().collect();
    let mut map = serde_json::from_str::<serde_json::Map<String, serde_json::Value>>(&text)
        .unwrap_or_default();
    let chosen = map.is_empty() || map.contains_key("ball_diameter_mm");
    let text = match chosen {
        true => text,
        false => {
            map.insert("ball_diameter_mm".into(), rows[0].diameter_mm.into());
            serde_json::Value::Object(map).to_string()
        }
    };
    let sensor = SensorInfo::parse(&text, &scale_from)?;
    let (mine, others): (Vec<&CatalogRow>, Vec<&CatalogRow>) = rows
        .iter()
        .partition(|r| !chosen || (r.diameter_mm - sensor.ball_diameter_mm).abs() <= SAME_BALL_MM);
    if mine.is_empty() {
        return Err(Error::layout(
            &catalog_path,
            format!(
                "lists no press of a {} mm ball (sensor.json's ball_diameter_mm), only {}",
                sensor.ball_diameter_mm,
                balls(&all)
            ),
        ));
    }
    let warnings = match others.is_empty() {
        true => Vec::new(),
        false => vec![format!(
            "warning: {}: the presses of other balls are left out ({}): sensor.json's \
             ball_diameter_mm chooses the {} mm ball (without it, every press is fitted with \
             its own ball)",
            catalog_path.display(),
            balls(&others),
            sensor.ball_diameter_mm
        )],
    };
    let catalog = Catalog {
        listed: rows.iter().map(|r| r.folder.clone()).collect(),
        rows: mine.into_iter().cloned().collect(),
        path: catalog_path,
        warnings,
        scale_from_config: !has_sensor_file,
        config,
    };
    Ok((sensor, catalog))
}

impl Catalog {
    /// gs_sdk's config copied into the folder, if one is.
    pub(crate) fn config(&self) -> Option<&GsSdkConfig> {
        self.config.as_ref()
    }

    /// The file the scale was read from: `sensor.json`, or the config.
    pub(crate) fn scale_file(&self) -> PathBuf {
        match (&self.config, self.scale_from_config) {
            (Some(c), true) => c.path.clone(),
            _ => self.path.with_file_name("sensor.json"),
        }
    }

    /// The config's scale checked against the frames' `size` (the
    /// background's, at `background`): refused where the scale is the
    /// config's and its `imgw` x `imgh` is another size; a warning where
    /// `sensor.json`'s scale is not the config's (at the frames' size).
    pub(crate) fn check_scale(
        &mut self,
        sensor: &SensorInfo,
        background: &Path,
        (w, h): (usize, usize),
    ) -> Result<()> {
        let Some(c) = &self.config else {
            return Ok(());
        };
        let name = c.file_name();
        let at_frames = match c.size {
            Some((cw, _)) => c.mm_per_px * cw as f64 / w as f64,
            None => c.mm_per_px,
        };
        match (self.scale_from_config, c.size) {
            (true, Some(size)) if size != (w, h) => Err(Error::layout(
                background,
                format!(
                    "{w}x{h}, but {name}'s ppmm {} is the scale of frames of {}x{} (its imgw x \
                     imgh): copy in the config these presses were collected with, or write \
                     sensor.json with their scale (if they are the config's frames resized, \
                     {{\"mm_per_px\": {:.5}}})",
                    c.mm_per_px, size.0, size.1, at_frames
                ),
            )),
            (false, _) if (sensor.mm_per_px / at_frames - 1.0).abs() > 0.02 => {
                self.warnings.push(format!(
                    "warning: sensor.json's mm_per_px {} is not the scale gs_sdk's config {} \
                     gives these {w}x{h} frames ({at_frames:.5} mm per pixel): sensor.json's is \
                     used; remove the one that is not this sensor's",
                    sensor.mm_per_px,
                    c.path.display()
                ));
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// The presses: each frame checked to exist inside `root`
    /// (`canonical`, its canonical path), each `label.npz` read and its
    /// circle checked against the `sensor` and the frame's `size`; and
    /// the warnings (presses of other balls; press folders not listed).
    pub(crate) fn presses(
        self,
        root: &Path,
        canonical: &Path,
        sensor: &SensorInfo,
        size: (usize, usize),
    ) -> Result<(Vec<Press>, Vec<String>)> {
        let path = &self.path;
        let mut out = Vec::with_capacity(self.rows.len());
        let mut listed = HashMap::new();
        for row in &self.rows {
            let line = row.line;
            let file = format!("{}/{FRAME_FILE}", row.folder);
            let (frame, resolved) = crate::layout::inside(root, canonical, &file)
                .map_err(|why| Error::layout(path, format!("line {line}: {why}")))?;
            if !frame.is_file() {
                return Err(Error::layout(
                    path,
                    format!(
                        "line {line}: press folder '{}' has no {FRAME_FILE}",
                        row.folder
                    ),
                ));
            }
            let what = format!("press folder '{}'", row.folder);
            crate::layout::listed_once(&mut listed, resolved, line, &what)
                .map_err(|why| Error::layout(path, why))?;
            let label_rel = format!("{}/{LABEL_FILE}", row.folder);
            let (label, _) = crate::layout::inside(root, canonical, &label_rel)
                .map_err(|why| Error::layout(path, format!("line {line}: {why}")))?;
            let annotated = match label.exists() {
                false => None,
                true => {
                    let c = read_label(&label)?;
                    if let Some(why) =
                        crate::layout::circle_problem(sensor, row.diameter_mm, size, &c)
                    {
                        return Err(Error::layout(&label, why));
                    }
                    Some(c)
                }
            };
            out.push(Press {
                file,
                annotated,
                ball_diameter_mm: Some(row.diameter_mm),
            });
        }
        let unlisted = self.unlisted_warning(root);
        let mut warnings = self.warnings;
        warnings.extend(unlisted);
        Ok((out, warnings))
    }

    /// The warning naming press folders beside the listed ones that hold a
    /// frame and are not in the catalog: they are no presses, and a press
    /// whose row was lost would otherwise be left out without a word.
    fn unlisted_warning(&self, root: &Path) -> Option<String> {
        let listed: HashSet<&str> = self.listed.iter().map(String::as_str).collect();
        let parents: HashSet<&str> = (self.listed.iter())
            .filter_map(|f| f.rsplit_once('/').map(|(p, _)| p))
            .collect();
        let mut unlisted = Vec::new();
        for parent in parents {
            let Ok(entries) = std::fs::read_dir(root.join(parent)) else {
                continue;
            };
            // A press folder per press: as many as a catalog may list.
            // Folders only, not links, so nothing outside is looked at.
            for entry in entries.flatten().take(MAX_PRESSES * 4) {
                let name = entry.file_name().to_string_lossy().into_owned();
                let folder = format!("{parent}/{name}");
                let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
                if is_dir
                    && !listed.contains(folder.as_str())
                    && entry.path().join(FRAME_FILE).is_file()
                {
                    unlisted.push(folder);
                }
            }
        }
        if unlisted.is_empty() {
            return None;
        }
        alphanumeric_sort::sort_str_slice(&mut unlisted);
        let (named, _) = tactile_core::source::named_frames(&unlisted);
        Some(format!(
            "warning: {}: {} press folders hold a {FRAME_FILE} and are not listed, so they are \
             no presses and are not fitted ({named}): add a row for each, or move them out",
            self.path.display(),
            unlisted.len(),
        ))
    }
}

/// The circle gs_sdk's `label_data.py` saved in `path`: `center` (x, y)
/// and `radius`, pixels, as numbers of any NumPy dtype; an archive stored
/// (`numpy.savez`) or deflated (`savez_compressed`). Each array's size is
/// checked before it is read.
pub fn read_label(path: &Path) -> Result<Circle> {
    let bytes = tactile_core::io::read_limited(path, MAX_LABEL_FILE_BYTES)?;
    let mut npz = crate::npz::Npz::new(std::io::Cursor::new(bytes))
        .map_err(|why| Error::layout(path, why))?;
    let missing =
        "missing: gs_sdk's label_data.py saves the contact circle as center (x, y) and radius";
    let mut numbers = |name: &str, count: usize| {
        npz.numbers(name, count, MAX_LABEL_ARRAY_BYTES, missing)
            .map_err(|why| Error::layout(path, format!("its '{name}': {why}")))
    };
    let centre = numbers("center", 2)?;
    let radius = numbers("radius", 1)?;
    Ok(Circle {
        centre_x_px: centre[0],
        centre_y_px: centre[1],
        radius_px: radius[0],
    })
}
