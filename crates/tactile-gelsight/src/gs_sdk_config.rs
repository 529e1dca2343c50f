//! gs_sdk's sensor config, copied into a calibration folder.
//!
//! gs_sdk keeps a sensor's scale in a YAML file of its own
//! (`examples/configs/gsmini.yaml`), which every one of its calibration
//! scripts is given (`-c`):
//!
//! ```yaml
//! device_name: "GelSight Mini"
//! ppmm: 0.0634        # millimetres per pixel, despite its name
//! imgh: 240
//! imgw: 320
//! ```
//!
//! Copied beside `catalog.csv`, it gives the scale in place of a
//! `sensor.json`, and the frame size that scale is of. Only the top-level
//! keys are read, through `yaml-rust2`'s event parser: aliases (which its
//! document loader copies, so a few kilobytes can stand for gigabytes) are
//! refused, and nesting is cut off.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use yaml_rust2::Yaml;
use yaml_rust2::parser::{Event, Parser};
use yaml_rust2::scanner::TScalarStyle;

use crate::{Error, Result};

/// Largest config read, bytes (gs_sdk's are under 1 KB).
pub const MAX_CONFIG_FILE_BYTES: u64 = 64 << 10;
/// Deepest nesting read (gs_sdk's configs are flat).
const MAX_CONFIG_DEPTH: usize = 16;
/// Most YAML files a calibration folder's are looked through for the
/// config (gs_sdk's folder has none of its own).
const MAX_YAML_FILES: usize = 32;
/// Largest `imgw` or `imgh` taken (8K).
const MAX_CONFIG_SIDE_PX: i64 = 8192;

/// The scale a gs_sdk config gives.
#[derive(Debug, Clone, PartialEq)]
pub struct GsSdkConfig {
    /// The file it was read from.
    pub path: PathBuf,
    /// Its `device_name`, if any.
    pub device_name: Option<String>,
    /// Its `ppmm`: millimetres per pixel on the skin.
    pub mm_per_px: f64,
    /// Its `imgw` x `imgh`: the frames that scale is of, if it says.
    pub size: Option<(usize, usize)>,
    /// Its `raw_imgw` x `raw_imgh`: the camera's frames, which gs_sdk cuts
    /// and resizes to `size`, if it says.
    pub raw_size: Option<(usize, usize)>,
}

/// How gs_sdk turns the camera's frames into the sensor's (its
/// `resize_crop`): a seventh of the frame cut from each side, a row or
/// column more from the top or left to keep the sensor's aspect, then a
/// bilinear resize.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct CameraCut {
    /// The camera's frames, `(width, height)`.
    pub camera: (usize, usize),
    /// The part kept, `(width, height, left, top)`.
    pub crop: (usize, usize, usize, usize),
    /// The sensor's frames, `(width, height)`.
    pub size: (usize, usize),
}

impl CameraCut {
    /// gs_sdk's cut of `camera` frames to `size` ones; `None` where it
    /// leaves nothing.
    pub fn of(camera: (usize, usize), size: (usize, usize)) -> Option<Self> {
        let ((cw, ch), (w, h)) = (camera, size);
        // resize_crop: int(rows / 7) and floor(columns / 7).
        let (border_rows, border_cols) = (ch / 7, cw / 7);
        let (rows, cols) = (ch - 2 * border_rows, cw - 2 * border_cols);
        let (rows_f, cols_f) = (rows as f64, cols as f64);
        let aspect = w as f64 / h as f64;
        let (extra_rows, extra_cols) = if rows_f * aspect > cols_f + 1e-8 {
            ((rows_f - cols_f / aspect) as usize, 0)
        } else if rows_f * aspect < cols_f - 1e-8 {
            (0, (cols_f - rows_f * aspect) as usize)
        } else {
            (0, 0)
        };
        let (top, left) = (border_rows + extra_rows, border_cols + extra_cols);
        let (kept_h, kept_w) = (
            ch.checked_sub(border_rows + top)?,
            cw.checked_sub(border_cols + left)?,
        );
        (kept_h > 0 && kept_w > 0).then_some(Self {
            camera,
            crop: (kept_w, kept_h, left, top),
            size,
        })
    }

    /// The FFmpeg line that streams a V4L2 camera's frames so cut to
    /// `tactile run` on the model folder `model` (its path quoted for the
    /// shell where it needs to be).
    pub fn ffmpeg_command(&self, model: &Path) -> String {
        let ((cw, ch), (kw, kh, x, y), (w, h)) = (self.camera, self.crop, self.size);
        let model = model.to_string_lossy();
        let model = shlex::try_quote(&model).unwrap_or_else(|_| model.replace('\0', "").into());
        format!(
            "ffmpeg -f v4l2 -video_size {cw}x{ch} -i /dev/video0 -vf crop={kw}:{kh}:{x}:{y},scale={w}:{h}:flags=bilinear -f rawvideo -pix_fmt rgb24 - | tactile run --stdin --size {w}x{h} --models {model}"
        )
    }
}

impl GsSdkConfig {
    /// How gs_sdk cuts the camera's frames to the sensor's, where the
    /// config gives both sizes.
    pub fn camera_cut(&self) -> Option<CameraCut> {
        CameraCut::of(self.raw_size?, self.size?)
    }

    /// Its file's name (`gsmini.yaml`), for messages.
    pub fn file_name(&self) -> String {
        crate::layout::file_name_of(&self.path)
    }
}

/// A top-level value: its text (`None` for a list or a mapping), whether
/// it was quoted, and its line.
struct TopValue {
    text: Option<String>,
    quoted: bool,
    line: usize,
}

/// The top-level keys of the YAML mapping `text` and their values.
fn top_level(path: &Path, text: &str) -> Result<HashMap<String, TopValue>> {
    let mut parser = Parser::new_from_str(text);
    let mut values: HashMap<String, TopValue> = HashMap::new();
    let mut depth = 0usize;
    // At depth 1: whether the next node is a key, the key read, and
    // whether a list or mapping opened at depth 1 was a key.
    let mut expect_key = true;
    let mut key: Option<(String, usize)> = None;
    let mut compound_was_key = false;
    let mut seen_mapping = false;
    loop {
        let (event, mark) = parser
            .next_token()
            .map_err(|e| Error::layout(path, format!("is not YAML: {e}")))?;
        let line = mark.line();
        match event {
            Event::StreamEnd | Event::DocumentEnd => break,
            Event::Alias(_) => {
                return Err(Error::layout(
                    path,
                    format!(
                        "line {line}: uses a YAML alias (*name), which a sensor config has no \
                         need of and which is not read"
                    ),
                ));
            }
            Event::MappingStart(..) | Event::SequenceStart(..) => {
                if depth == 0 {
                    if !matches!(event, Event::MappingStart(..)) {
                        return Err(Error::layout(
                            path,
                            "is not a gs_sdk config: a list, not keys and values",
                        ));
                    }
                    seen_mapping = true;
                } else if depth == 1 {
                    compound_was_key = expect_key;
                    if let (false, Some((k, l))) = (expect_key, key.take()) {
                        insert(path, &mut values, k, None, false, l)?;
                    }
                }
                depth += 1;
                if depth > MAX_CONFIG_DEPTH {
                    return Err(Error::layout(
                        path,
                        format!("line {line}: nested more than {MAX_CONFIG_DEPTH} deep"),
                    ));
                }
            }
            Event::MappingEnd | Event::SequenceEnd => {
                depth = depth.saturating_sub(1);
                if depth == 1 {
                    // A compound key is followed by its value; a
                    // compound value by the next key.
                    expect_key = !compound_was_key;
                }
            }
            Event::Scalar(..) if depth == 0 => {
                return Err(Error::layout(
                    path,
                    "is not a gs_sdk config: one value, not keys and values",
                ));
            }
            Event::Scalar(v, style, ..) if depth == 1 => {
                if expect_key {
                    key = Some((v, line));
                } else if let Some((k, l)) = key.take() {
                    insert(
                        path,
                        &mut values,
                        k,
                        Some(v),
                        !matches!(style, TScalarStyle::Plain),
                        l,
                    )?;
                }
                expect_key = !expect_key;
            }
            _ => {}
        }
    }
    if !seen_mapping {
        return Err(Error::layout(path, "is not a gs_sdk config: it is empty"));
    }
    Ok(values)
}

fn insert(
    path: &Path,
    values: &mut HashMap<String, TopValue>,
    key: String,
    text: Option<String>,
    quoted: bool,
    line: usize,
) -> Result<()> {
    if let Some(first) = values.get(&key) {
        return Err(Error::layout(
            path,
            format!(
                "line {line}: key {key} a second time (first on line {})",
                first.line
            ),
        ));
    }
    values.insert(key, TopValue { text, quoted, line });
    Ok(())
}

/// The number `key` holds, if it is there.
fn number(path: &Path, values: &HashMap<String, TopValue>, key: &str) -> Result<Option<f64>> {
    let Some(v) = values.get(key) else {
        return Ok(None);
    };
    let not_number = |what: &str| {
        Error::layout(
            path,
            format!("line {}: {key} is {what}, not a number", v.line),
        )
    };
    let text = v
        .text
        .as_deref()
        .ok_or_else(|| not_number("a list or keys"))?;
    if v.quoted {
        return Err(not_number(&format!("the text {text:?}")));
    }
    match Yaml::from_str(text) {
        Yaml::Real(_) => Yaml::from_str(text)
            .as_f64()
            .map(Some)
            .ok_or_else(|| not_number(&format!("{text:?}"))),
        Yaml::Integer(i) => Ok(Some(i as f64)),
        _ => Err(not_number(&format!("{text:?}"))),
    }
}

/// Read gs_sdk's config at `path`: `ppmm` (required, checked as a scale),
/// `imgw` and `imgh` (both or neither), `device_name`. `Ok(None)` where the
/// file is YAML without `ppmm` (some other file).
pub fn read_config(path: &Path) -> Result<Option<GsSdkConfig>> {
    let text = crate::layout::read_text(path, MAX_CONFIG_FILE_BYTES)?;
    let values = top_level(path, &text)?;
    let Some(mm_per_px) = number(path, &values, "ppmm")? else {
        return Ok(None);
    };
    let line = values["ppmm"].line;
    if !(mm_per_px.is_finite() && (1e-4..=1.0).contains(&mm_per_px)) {
        return Err(Error::layout(
            path,
            format!(
                "line {line}: ppmm = {mm_per_px} is not a scale of 0.0001-1 mm per pixel \
                 (gs_sdk's ppmm is millimetres per pixel despite its name: 0.0634 for a \
                 GelSight Mini at 320x240)"
            ),
        ));
    }
    let side = |key: &str| -> Result<Option<usize>> {
        match number(path, &values, key)? {
            None => Ok(None),
            Some(v) if v.fract() == 0.0 && (1.0..=MAX_CONFIG_SIDE_PX as f64).contains(&v) => {
                Ok(Some(v as usize))
            }
            Some(v) => Err(Error::layout(
                path,
                format!(
                    "line {}: {key} = {v} is no frame side of 1-{MAX_CONFIG_SIDE_PX} pixels",
                    values[key].line
                ),
            )),
        }
    };
    let pair = |w_key: &str, h_key: &str, what: &str| -> Result<Option<(usize, usize)>> {
        match (side(w_key)?, side(h_key)?) {
            (Some(w), Some(h)) => Ok(Some((w, h))),
            (None, None) => Ok(None),
            (w, _) => {
                let (has, lacks) = match w {
                    Some(_) => (w_key, h_key),
                    None => (h_key, w_key),
                };
                Err(Error::layout(
                    path,
                    format!(
                        "line {}: gives {has} without {lacks}: {what} needs both",
                        values[has].line
                    ),
                ))
            }
        }
    };
    let size = pair("imgw", "imgh", "the frame size its ppmm is of")?;
    let raw_size = pair("raw_imgw", "raw_imgh", "the camera's frame size")?;
    let device_name = values
        .get("device_name")
        .and_then(|v| v.text.clone())
        .map(|s| s.chars().take(200).collect());
    Ok(Some(GsSdkConfig {
        path: path.to_path_buf(),
        device_name,
        mm_per_px,
        size,
        raw_size,
    }))
}

/// The YAML files directly in `root` (regular files, not links), sorted.
fn yaml_files(root: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(root).map_err(|e| tactile_core::Error::io(root, e))?;
    let mut files = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| tactile_core::Error::io(root, e))?;
        let path = entry.path();
        let is_yaml = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"));
        if is_yaml && entry.file_type().is_ok_and(|t| t.is_file()) {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// What the YAML files in `root` say of the sensor.
pub(crate) enum ConfigsFound {
    /// None is a gs_sdk config (the names of YAML files without `ppmm`).
    None(Vec<String>),
    /// One is.
    One(GsSdkConfig),
}

/// gs_sdk's config copied into `root`: the one YAML file there with a
/// `ppmm`. Two such files are refused (which sensor made the presses is
/// not known). YAML files that cannot be read are left alone beside the
/// one config; without one, the first is refused where the config is
/// `needed` (no `sensor.json` gives the scale): it may be the config.
pub(crate) fn config_in(root: &Path, needed: bool) -> Result<ConfigsFound> {
    let files = yaml_files(root)?;
    if files.len() > MAX_YAML_FILES {
        return match needed {
            true => Err(Error::layout(
                root,
                format!(
                    "holds {} YAML files, more than the {MAX_YAML_FILES} looked through for \
                     gs_sdk's config: keep its config here and move the others out, or write \
                     sensor.json",
                    files.len()
                ),
            )),
            false => Ok(ConfigsFound::None(Vec::new())),
        };
    }
    let (mut configs, mut others, mut unread) = (Vec::new(), Vec::new(), Vec::new());
    for path in files {
        match read_config(&path) {
            Ok(Some(c)) => configs.push(c),
            Ok(None) => others.push(crate::layout::file_name_of(&path)),
            Err(e) => unread.push(e),
        }
    }
    match (configs.len(), needed) {
        (1, _) => Ok(ConfigsFound::One(configs.remove(0))),
        (0, true) if !unread.is_empty() => Err(unread.remove(0)),
        (0, _) => Ok(ConfigsFound::None(others)),
        (_, false) => Ok(ConfigsFound::None(Vec::new())),
        (_, true) => {
            let names: Vec<String> = configs.iter().map(GsSdkConfig::file_name).collect();
            Err(Error::layout(
                root,
                format!(
                    "holds {} gs_sdk configs ({}): keep the one of the sensor that made these \
                     presses, or write sensor.json with its scale",
                    names.len(),
                    names.join(", ")
                ),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tactile_core::rng::SampleRng;

    const CONFIG: &str = "# Device Name\ndevice_name: \"GelSight Mini\"\n# Pixel Per Millimeter\nppmm: 0.0634\nimgh: 240\nimgw: 320\nraw_imgh: 2464\nraw_imgw: 3280\nframerate: 25\n";

    #[test]
    fn the_camera_is_cut_as_gs_sdk_cuts_it() {
        // gs_sdk's resize_crop worked by hand: the GelSight Mini's 3280x2464
        // to 320x240 (rows 352 + 2 extra to 2112, columns 468 to 2812), its
        // DIGIT's 640x480 to 320x240 (rows 68 to 412, columns 91 to 549).
        let cut = |c, s| CameraCut::of(c, s).map(|c| c.crop);
        assert_eq!(cut((3280, 2464), (320, 240)), Some((2344, 1758, 468, 354)));
        assert_eq!(cut((640, 480), (320, 240)), Some((458, 344, 91, 68)));
        // A wide camera to a square sensor: columns cut for the aspect.
        // (rows 154 to 926; columns 274 + 600 to 1646).
        assert_eq!(cut((1920, 1080), (240, 240)), Some((772, 772, 874, 154)));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gsmini.yaml");
        std::fs::write(&path, CONFIG).unwrap();
        let c = read_config(&path).unwrap().unwrap();
        assert_eq!(
            c.camera_cut()
                .unwrap()
                .ffmpeg_command(Path::new("models/mini")),
            "ffmpeg -f v4l2 -video_size 3280x2464 -i /dev/video0 -vf crop=2344:1758:468:354,scale=320:240:flags=bilinear -f rawvideo -pix_fmt rgb24 - | tactile run --stdin --size 320x240 --models models/mini"
        );
        // A folder whose name the shell would split or expand.
        let line = c
            .camera_cut()
            .unwrap()
            .ffmpeg_command(Path::new("my models/it's $HOME"));
        let quoted = line.split_once("--models ").unwrap().1;
        let said = std::process::Command::new("sh")
            .args(["-c", &format!("printf %s {quoted}")])
            .output()
            .unwrap();
        assert_eq!(
            String::from_utf8_lossy(&said.stdout),
            "my models/it's $HOME"
        );
    }

    #[test]
    fn a_config_damaged_anywhere_is_read_or_refused_never_a_panic() {
        // Bytes flipped, dropped, repeated and YAML's own punctuation
        // thrown in: each read gives a config or an error naming the file.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gsmini.yaml");
        let punctuation = b"&*!|>'\"{}[],:-?#%@` \n\t";
        let runs: usize = std::env::var("TACTILE_FUZZ_RUNS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(3000);
        let (mut read, mut refused) = (0, 0);
        for k in 0..runs {
            let mut rng = SampleRng::new(11, 0, k as u64);
            let mut bytes = CONFIG.as_bytes().to_vec();
            for _ in 0..1 + rng.index(6) {
                let at = rng
                    .index(bytes.len() + 1)
                    .min(bytes.len().saturating_sub(1));
                match rng.index(4) {
                    0 => bytes[at] = rng.index(256) as u8,
                    1 => {
                        bytes.remove(at);
                    }
                    2 => bytes.insert(at, punctuation[rng.index(punctuation.len())]),
                    _ => {
                        let end = (at + 1 + rng.index(40)).min(bytes.len());
                        let copy = bytes[at..end].to_vec();
                        bytes.splice(at..at, copy.iter().cycle().take(copy.len() * 50).copied());
                    }
                }
            }
            std::fs::write(&path, &bytes).unwrap();
            match read_config(&path) {
                Ok(_) => read += 1,
                Err(e) => {
                    assert!(e.to_string().contains("gsmini.yaml"), "{e}");
                    refused += 1;
                }
            }
        }
        assert!(read > 0 && refused > 0, "{read} read, {refused} refused");
        // Nests 30,000 deep, of either kind, and numbers past any type.
        for text in [
            format!("ppmm: 0.0634\nx: {}", "[".repeat(30_000)),
            format!("ppmm: 0.0634\nx: {}", "{a: ".repeat(10_000)),
            (1..300).map(|i| format!("{}k:\n", " ".repeat(i))).collect(),
        ] {
            std::fs::write(&path, text).unwrap();
            let e = read_config(&path).unwrap_err().to_string();
            assert!(
                e.contains("nested more than 16 deep") || e.contains("not YAML"),
                "{e}"
            );
        }
        for (value, said) in [
            ("99999999999999999999999", None),
            ("1e400", Some("is not a scale")),
            (".nan", Some("is not a scale")),
            ("-0.0634", Some("is not a scale")),
            ("0x10", Some("is not a scale")),
            ("~", Some("not a number")),
        ] {
            std::fs::write(&path, format!("ppmm: {value}\n")).unwrap();
            match (read_config(&path), said) {
                (Err(e), Some(said)) => assert!(e.to_string().contains(said), "{value}: {e}"),
                (Err(e), None) => assert!(e.to_string().contains("gsmini.yaml"), "{value}: {e}"),
                (Ok(c), _) => panic!("{value}: read as {c:?}"),
            }
        }
    }
}
