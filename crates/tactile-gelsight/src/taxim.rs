//! Taxim's calibration pack, read as it is.
//!
//! Taxim's `generateDataPack.py` (and the tools built on it) keeps the
//! presses, the background and the hand-labelled circles in one NumPy
//! archive; the ball and the scale stay in its `Basics/sensorParams.py`:
//!
//! ```text
//! DIR/
//!   dataPack.npz   f0            the skin at rest, H x W x 3 uint8, BGR (as OpenCV reads it)
//!                  imgs          the presses, N x H x W x 3 uint8, BGR
//!                  touch_center  N x 2, each press's contact centre [x, y], pixels
//!                  touch_radius  N, its contact radius, pixels
//!                  names         N file names (optional; captions)
//!   sensor.json    written by hand: {"ball_diameter_mm": 4.0, "mm_per_px": 0.0295}
//!                  (twice sensorParams.py's ball_radius, and its pixmm)
//! ```
//!
//! The presses are held in memory (their size checked before any is
//! read): a press is named `dataPack.npz:<name>` in messages and reports.

use std::path::{Path, PathBuf};

use tactile_core::image_io::{MAX_IMAGE_PIXELS, RgbImage, rgb_image};

use crate::layout::{Annotations, BallPresses, Circle, MAX_PRESSES, Press, SensorInfo};
use crate::npz::{Npz, element_count};
use crate::{Error, Result};

/// The pack Taxim's `generateDataPack.py` saves in its data folder.
pub const PACK_FILE: &str = "dataPack.npz";
/// Most bytes of presses a pack may hold: they are held in memory (2,000
/// presses of 640x480 are 1.8 GB).
pub const MAX_PACK_FRAME_BYTES: u64 = 2 << 30;
/// Largest `touch_center`, `touch_radius` or `names` entry read, bytes.
const MAX_LABEL_BYTES: u64 = 1 << 20;
/// Longest press name kept, characters.
const MAX_NAME_CHARS: usize = 64;

/// Whether `root` is Taxim's data folder: `dataPack.npz` and none of the
/// toolkit's `presses.csv` or `frames/`, nor gs_sdk's `catalog.csv`.
pub fn is_taxim_folder(root: &Path) -> bool {
    root.join(PACK_FILE).is_file()
        && !root.join("presses.csv").exists()
        && !root.join("frames").exists()
        && !root.join(crate::gs_sdk::CATALOG_FILE).exists()
}

/// `sensor.json` beside a pack: the ball and the scale, which Taxim keeps
/// in its code. The background is the pack's own.
fn sensor(root: &Path, pack: &str) -> Result<SensorInfo> {
    let file = root.join("sensor.json");
    if !file.exists() {
        return Err(Error::layout(
            &file,
            "missing: Taxim keeps the ball and the scale in Basics/sensorParams.py, not in \
             dataPack.npz; write sensor.json beside it, such as {\"ball_diameter_mm\": 4.0, \
             \"mm_per_px\": 0.0295} (twice its ball_radius, and its pixmm: those are Taxim's \
             GelSight R1.5 at 640x480)",
        ));
    }
    let text = crate::layout::read_text(&file, crate::layout::MAX_SENSOR_FILE_BYTES)?;
    let keys = serde_json::from_str::<serde_json::Map<String, serde_json::Value>>(&text)
        .unwrap_or_default();
    if keys.contains_key("background") {
        return Err(Error::layout(
            &file,
            format!(
                "names a background, but {pack} holds its own (f0): remove \"background\", or \
                 lay the presses out as frames/ and presses.csv to calibrate against another"
            ),
        ));
    }
    let mut sensor = SensorInfo::parse(&text, &file)?;
    sensor.background = format!("{pack}:f0");
    Ok(sensor)
}

/// The pack's frame `name` (`f0` or `imgs`), `N x H x W x 3` or `H x W x
/// 3` uint8, as RGB images (`bgr`: its channels in OpenCV's order), its
/// size checked before any pixel is read: `(w, h)` where a size is known.
fn frames<R: std::io::Read + std::io::Seek>(
    npz: &mut Npz<R>,
    name: &str,
    size: Option<(usize, usize)>,
    bgr: bool,
) -> std::result::Result<Vec<RgbImage>, String> {
    let many = name == "imgs";
    let check = |shape: &[usize]| -> std::result::Result<(), String> {
        let (n, rest) = match (many, shape) {
            (true, [n, rest @ ..]) => (*n, rest),
            (false, rest) => (1, rest),
            (true, []) => return Err("is a single number, not N frames".into()),
        };
        let [h, w, 3] = rest else {
            let want = if many {
                "N x height x width x 3"
            } else {
                "height x width x 3"
            };
            return Err(format!(
                "has shape {shape:?}, not {want} (8-bit colour frames, as Taxim saves them)"
            ));
        };
        if (*w as u64).saturating_mul(*h as u64) > MAX_IMAGE_PIXELS || *w < 8 || *h < 8 {
            return Err(format!(
                "frames of {w}x{h}: no camera's (8x8 to 8K, {MAX_IMAGE_PIXELS} pixels)"
            ));
        }
        if let Some((bw, bh)) = size
            && (*w, *h) != (bw, bh)
        {
            return Err(format!(
                "frames of {w}x{h}, the background (f0) is {bw}x{bh}: every press is a frame of \
                 the same camera"
            ));
        }
        if many && n == 0 {
            return Err("holds no press".into());
        }
        if n > MAX_PRESSES {
            return Err(format!("holds {n} presses, more than {MAX_PRESSES}"));
        }
        let bytes = element_count(shape).map(|b| b as u64);
        if bytes.is_none_or(|b| b > MAX_PACK_FRAME_BYTES) {
            return Err(format!(
                "holds {n} frames of {w}x{h}: more than {} GB of presses, which are held in \
                 memory; calibrate with fewer",
                MAX_PACK_FRAME_BYTES >> 30
            ));
        }
        Ok(())
    };
    let read = |shape: &[usize], r: &mut dyn std::io::Read| {
        let (n, h, w) = match shape {
            [n, h, w, _] => (*n, *h, *w),
            [h, w, _] => (1, *h, *w),
            _ => return Err("has no frame's shape".to_string()),
        };
        let mut out = Vec::with_capacity(n);
        for k in 0..n {
            let mut px = vec![0u8; w * h * 3];
            r.read_exact(&mut px).map_err(|e| {
                format!("ends after {k} of its {n} frames ({e}): the archive is cut short")
            })?;
            if bgr {
                px.chunks_exact_mut(3).for_each(|p| p.swap(0, 2));
            }
            out.push(rgb_image(w, h, px).map_err(|e| e.to_string())?);
        }
        Ok(out)
    };
    let missing = match many {
        true => "missing: Taxim's generateDataPack.py saves the presses as imgs",
        false => {
            "missing: Taxim's generateDataPack.py saves the background (the skin at rest) as f0"
        }
    };
    npz.with_bytes(name, missing, check, read)
}

/// The press names of a pack: its `names` where each is a file's name and
/// they differ (`None` else: [`PackFrames::name`] names them by place).
fn press_names<R: std::io::Read + std::io::Seek>(
    npz: &mut Npz<R>,
    n: usize,
) -> Option<Vec<String>> {
    let names = npz.strings("names", n, MAX_LABEL_BYTES)?;
    let names: Vec<String> = (names.iter())
        .map(|s| {
            let base = s.rsplit(['/', '\\']).next().unwrap_or("").trim();
            base.chars()
                .filter(|c| !c.is_control())
                .take(MAX_NAME_CHARS)
                .collect()
        })
        .collect();
    let distinct: std::collections::HashSet<&String> = names.iter().collect();
    let usable = distinct.len() == n && names.iter().all(|s| !s.is_empty() && !s.starts_with('#'));
    usable.then_some(names)
}

/// The frames of a pack, in RGB: its background and its presses, and the
/// presses' names (`press_names`).
pub struct PackFrames {
    /// `f0`: the skin at rest.
    pub background: RgbImage,
    /// `imgs`: the presses.
    pub presses: Vec<RgbImage>,
    /// Each press's `names` entry, where the pack names them usably.
    pub names: Option<Vec<String>>,
}

impl PackFrames {
    /// Press `i`'s name: its `names` entry, or its place (`#3`).
    pub fn name(&self, i: usize) -> String {
        match &self.names {
            Some(names) => names[i].clone(),
            None => format!("#{i}"),
        }
    }
}

/// A press of the pack `pack` named `name`, as messages and reports name
/// it (`dataPack.npz:press_02.png`; [`held_press_name`] reads it back).
pub(crate) fn press_file(pack: &str, name: &str) -> String {
    format!("{pack}:{name}")
}

/// The error of the array `name` of the pack `path`.
fn named(path: &Path, name: &str) -> impl Fn(String) -> Error + use<> {
    let (path, name) = (path.to_path_buf(), name.to_string());
    move |why: String| Error::layout(&path, format!("its '{name}': {why}"))
}

/// The frames of the pack at `path`, and the archive, to read its circles.
fn read_pack(path: &Path) -> Result<(PackFrames, Npz<std::io::BufReader<std::fs::File>>)> {
    let file = tactile_core::io::open_regular(path)?;
    let mut npz =
        Npz::new(std::io::BufReader::new(file)).map_err(|why| Error::layout(path, why))?;
    // Taxim saves what OpenCV read: BGR. Packs of other tools may say
    // otherwise in `color_order`.
    let bgr = !matches!(
        npz.strings("color_order", 1, 1 << 10).as_deref(),
        Some([order]) if order.eq_ignore_ascii_case("rgb")
    );
    let mut f0 = frames(&mut npz, "f0", None, bgr).map_err(named(path, "f0"))?;
    let background = f0
        .pop()
        .ok_or_else(|| Error::layout(path, "its 'f0' holds no frame"))?;
    let size = (background.width(), background.height());
    let presses = frames(&mut npz, "imgs", Some(size), bgr).map_err(named(path, "imgs"))?;
    let names = press_names(&mut npz, presses.len());
    let pack = PackFrames {
        background,
        presses,
        names,
    };
    Ok((pack, npz))
}

/// The frames of Taxim's pack at `path`, every size checked before it is
/// read; its circles and `sensor.json` are not read (`tactile reconstruct`
/// of a pack's presses).
pub fn read_frames(path: &Path) -> Result<PackFrames> {
    Ok(read_pack(path)?.0)
}

/// Read Taxim's pack `pack` in the folder `root`, with the `sensor.json`
/// beside it.
pub(crate) fn open(root: PathBuf, pack: &str) -> Result<BallPresses> {
    let sensor = sensor(&root, pack)?;
    let path = root.join(pack);
    let (frames, mut npz) = read_pack(&path)?;
    let size = (frames.background.width(), frames.background.height());
    let bg_path = root.join(&sensor.background);
    crate::prepare::check_not_blank(&bg_path, &frames.background)?;
    let n = frames.presses.len();
    let circles = match (npz.has("touch_center"), npz.has("touch_radius")) {
        (false, false) => None,
        (true, true) => {
            let c = npz
                .numbers("touch_center", n * 2, MAX_LABEL_BYTES, "missing")
                .map_err(named(&path, "touch_center"))?;
            let r = npz
                .numbers("touch_radius", n, MAX_LABEL_BYTES, "missing")
                .map_err(named(&path, "touch_radius"))?;
            Some((c, r))
        }
        _ => {
            return Err(Error::layout(
                &path,
                "holds one of touch_center and touch_radius without the other: a labelled \
                 circle is both (or neither, to have each press's circle found)",
            ));
        }
    };
    let mut presses = Vec::with_capacity(n);
    for i in 0..n {
        let name = frames.name(i);
        let annotated = match &circles {
            None => None,
            Some((c, r)) => {
                let circle = Circle {
                    centre_x_px: c[2 * i],
                    centre_y_px: c[2 * i + 1],
                    radius_px: r[i],
                };
                let problem =
                    crate::layout::circle_problem(&sensor, sensor.ball_diameter_mm, size, &circle);
                if let Some(why) = problem {
                    // Some tools built on Taxim save [row, column].
                    let (w, h) = (size.0 as f64, size.1 as f64);
                    let (x, y) = (circle.centre_x_px, circle.centre_y_px);
                    let on = |x: f64, y: f64| (0.0..w).contains(&x) && (0.0..h).contains(&y);
                    let order = match !on(x, y) && on(y, x) {
                        true => " (saved as [row, column]? Taxim's touch_center is [x, y])",
                        false => "",
                    };
                    return Err(Error::layout(
                        &path,
                        format!(
                            "press {i} ({name}): its touch_center and touch_radius: {why}{order}; \
                             label it again, or check ball_diameter_mm and mm_per_px in \
                             sensor.json"
                        ),
                    ));
                }
                Some(circle)
            }
        };
        presses.push(Press {
            file: press_file(pack, &name),
            annotated,
            ball_diameter_mm: None,
        });
    }
    Ok(BallPresses {
        scale_file: root.join("sensor.json"),
        gs_sdk_config: None,
        root,
        sensor,
        colour: crate::prepare::is_colour_background(&frames.background),
        background: frames.background,
        presses,
        warnings: Vec::new(),
        annotations: Annotations::DataPack,
        held: Some(std::sync::Arc::new(frames.presses)),
    })
}

/// Where `root` holds an archive that may be Taxim's pack under another
/// name than `dataPack.npz` (Taxim's repository ships
/// `dataPack_small.npz`), how to give it: read as a folder, it is not.
pub(crate) fn pack_hint(root: &Path) -> String {
    let Ok(entries) = std::fs::read_dir(root) else {
        return String::new();
    };
    let pack = (entries.flatten().take(10_000))
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .find(|n| n.to_ascii_lowercase().ends_with(".npz"));
    match pack {
        Some(name) => format!(
            "; if {name} here is Taxim's calibration pack, give it itself (--data {}) with \
             sensor.json beside it",
            root.join(&name).display()
        ),
        None => String::new(),
    }
}

/// The name of a press held in a pack (`frame_3.jpg` of
/// `dataPack.npz:frame_3.jpg`).
pub(crate) fn held_press_name(file: &str) -> Option<&str> {
    file.split_once(".npz:").map(|(_, name)| name)
}
