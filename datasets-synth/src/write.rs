//! Writing synthetic datasets in the layout of `datasets.md`.
//!
//! Samples are rendered in parallel (rayon) into a hidden staging folder
//! next to the output, which is renamed into place only when every file and
//! the labels are written: an interrupted run leaves no half dataset.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use tactile_core::Error;
use tactile_core::dataset::{DatasetKind, DatasetWriter, FORMAT, Manifest};
use tactile_core::image_io::{save_grey_png, save_rgb_png};

use crate::Result;

use crate::calibrated::{self, CalibratedConfig, CalibratedSensor, RealFrames};
use crate::tactip::{self, FRAME_PX, TactipConfig};
use crate::visuotactile::{self, NATIVE, VisuotactileConfig};

/// Name and version of this generator, recorded in every manifest.
pub const GENERATOR: &str = concat!("datasets-synth ", env!("CARGO_PKG_VERSION"));

/// How to write.
#[derive(Debug, Clone, Copy, Default)]
pub struct WriteOptions {
    /// Replace an existing non-empty output folder.
    pub force: bool,
    /// Show a progress bar on stderr.
    pub progress: bool,
}

/// Check the output folder before any work: a non-empty folder is refused
/// without `force`, and even with it unless it is a dataset (it has a
/// `manifest.json`): `--force` replaces a dataset, never other files.
pub fn check_output(out: &Path, force: bool) -> Result<()> {
    if out.exists() && !out.is_dir() {
        return Err(crate::Error::OutputIsFile {
            path: out.to_path_buf(),
        });
    }
    let non_empty = std::fs::read_dir(out)
        .map(|mut d| d.next().is_some())
        .unwrap_or(false);
    if non_empty && !force {
        return Err(crate::Error::OutputNotEmpty {
            path: out.to_path_buf(),
        });
    }
    if non_empty && !out.join("manifest.json").is_file() {
        return Err(crate::Error::NotADataset {
            path: out.to_path_buf(),
        });
    }
    Ok(())
}

/// Render rows in parallel into a staging folder of this run's own, then
/// move it to `out` whole: an interrupted run leaves nothing, and two runs
/// into one folder never mix.
fn write_dataset<F>(
    out: &Path,
    extra_columns: &[&str],
    count: usize,
    manifest: Manifest,
    options: WriteOptions,
    subdirs: &[&str],
    row: F,
) -> Result<PathBuf>
where
    F: Fn(&Path, usize) -> tactile_core::Result<Vec<String>> + Sync,
{
    check_output(out, options.force)?;
    let staged = tactile_core::io::StagedDir::new(out)?;
    let staging = staged.path().to_path_buf();
    let mut writer = DatasetWriter::create(&staging, manifest.kind, extra_columns, true)?;
    for d in subdirs {
        tactile_core::io::create_dir_all(staging.join(d))?;
    }
    let rows = render_frames(count, options.progress, |i| row(&staging, i))?;
    for r in rows {
        writer.push_row(r)?;
    }
    writer.finish(manifest)?;
    // Checked again: another run may have filled the folder meanwhile.
    check_output(out, options.force)?;
    Ok(staged.commit(options.force)?)
}

/// `render(i)` for every frame `i` of `0..count`, in parallel on rayon's
/// threads, in order, with a progress bar when `progress`, ended by a stop
/// request (Ctrl-C): what a dataset's writer and the sets Python's
/// `tactile.synth` returns in memory share.
pub fn render_frames<T: Send>(
    count: usize,
    progress: bool,
    render: impl Fn(usize) -> tactile_core::Result<T> + Sync,
) -> tactile_core::Result<Vec<T>> {
    let pb = tactile_core::progress::progress_bar_if(count as u64, "synth", progress);
    let frames = (0..count)
        .into_par_iter()
        .map(|i| {
            tactile_core::interrupt::check()?;
            let r = render(i);
            pb.inc(1);
            r
        })
        .collect::<tactile_core::Result<_>>()?;
    pb.finish_and_clear();
    Ok(frames)
}

fn num(v: f64, decimals: usize) -> String {
    format!("{v:.decimals$}")
}

fn opt(v: Option<f64>, decimals: usize) -> String {
    v.map(|v| num(v, decimals)).unwrap_or_default()
}

/// Refuse a frame count of 0 or more than a dataset may hold.
pub fn check_count(count: usize) -> Result<()> {
    let max = tactile_core::dataset::MAX_ROWS;
    if count == 0 || count > max {
        return Err(Error::Config(format!("count: must be 1 to {max} frames, got {count}")).into());
    }
    Ok(())
}

/// The labels of one virtual TacTip frame, as `labels.csv` holds them
/// (the columns a shape does not have are `None`).
#[derive(Debug, Clone, PartialEq)]
pub struct TactipLabels {
    /// Shape name.
    pub shape: &'static str,
    /// Contact x, mm (shapes with a position).
    pub x_mm: Option<f64>,
    /// Contact y, mm (shapes with a position).
    pub y_mm: Option<f64>,
    /// Orientation, degrees (shapes with an orientation).
    pub theta_deg: Option<f64>,
    /// Indentation, mm.
    pub depth_mm: f64,
    /// Force with the load-cell noise, N.
    pub force_n: f64,
    /// Sphere radius, mm (spheres).
    pub radius_mm: Option<f64>,
}

impl TactipLabels {
    /// The labels of a rendered sample.
    pub fn of(scene: &tactip::TactipScene, frame: &tactip::TactipFrame) -> Self {
        let s = &scene.shape;
        Self {
            shape: s.name(),
            x_mm: s.has_position().then_some(scene.x_mm),
            y_mm: s.has_position().then_some(scene.y_mm),
            theta_deg: s.has_orientation().then_some(scene.theta_deg),
            depth_mm: scene.depth_mm,
            force_n: frame.force_n,
            radius_mm: match s {
                tactip::Shape::Sphere { radius_mm } => Some(*radius_mm),
                _ => None,
            },
        }
    }
}

/// Write `count` virtual TacTip frames with their labels to `out`.
pub fn write_tactip(
    config: &TactipConfig,
    count: usize,
    seed: u64,
    out: &Path,
    options: WriteOptions,
) -> Result<PathBuf> {
    config.validate()?;
    check_count(count)?;
    let mut extra = serde_json::Map::new();
    extra.insert(
        "config".into(),
        serde_json::to_value(config).map_err(|e| Error::Invalid(e.to_string()))?,
    );
    let manifest = Manifest {
        format: FORMAT.into(),
        kind: DatasetKind::Tactip,
        sensor_spec: "virtual-tactip/1".into(),
        width: FRAME_PX as u32,
        height: FRAME_PX as u32,
        generator: GENERATOR.into(),
        seed: Some(seed),
        count,
        extra,
    };
    write_dataset(
        out,
        &["radius_mm"],
        count,
        manifest,
        options,
        &["frames"],
        |root, i| {
            let (scene, frame) = tactip::sample(config, seed, i as u64);
            let file = format!("frames/{i:06}.png");
            save_grey_png(root.join(&file), FRAME_PX, FRAME_PX, &frame.pixels)?;
            let l = TactipLabels::of(&scene, &frame);
            Ok(vec![
                file,
                l.shape.to_string(),
                opt(l.x_mm, 4),
                opt(l.y_mm, 4),
                opt(l.theta_deg, 3),
                num(l.depth_mm, 4),
                num(l.force_n, 4),
                opt(l.radius_mm, 4),
            ])
        },
    )
}

/// Sequence and frame within it of row `i` of a visuo-tactile dataset.
pub fn visuotactile_position(config: &VisuotactileConfig, i: usize) -> (usize, usize) {
    video_position(config.frames_per_sequence, i)
}

/// Sequence and frame within it of rendered row `i` of a calibrated
/// sensor's dataset.
pub fn calibrated_position(config: &CalibratedConfig, i: usize) -> (usize, usize) {
    video_position(config.frames_per_sequence, i)
}

/// Sequence and frame within it of frame `i` of videos of
/// `frames_per_sequence` frames.
fn video_position(frames_per_sequence: usize, i: usize) -> (usize, usize) {
    let fps = frames_per_sequence.max(1);
    (i / fps, i % fps)
}

/// Frames and sequences of a visuo-tactile dataset: `count` frames in
/// videos of `config.frames_per_sequence` (the last one may be cut short).
pub fn write_visuotactile(
    config: &VisuotactileConfig,
    count: usize,
    seed: u64,
    out: &Path,
    options: WriteOptions,
) -> Result<PathBuf> {
    config.validate()?;
    check_count(count)?;
    let fps = config.frames_per_sequence;
    let sequences = count.div_ceil(fps);
    let mut extra = serde_json::Map::new();
    extra.insert(
        "config".into(),
        serde_json::to_value(config).map_err(|e| Error::Invalid(e.to_string()))?,
    );
    extra.insert(
        "native".into(),
        serde_json::json!({ "width": NATIVE.0, "height": NATIVE.1,
            "scale": format!("1/{}", config.scale_divisor()), "fps": visuotactile::FPS }),
    );
    extra.insert("sequences".into(), sequences.into());
    let manifest = Manifest {
        format: FORMAT.into(),
        kind: DatasetKind::Visuotactile,
        sensor_spec: visuotactile::SENSOR_SPEC.into(),
        width: config.width,
        height: config.height,
        generator: GENERATOR.into(),
        seed: Some(seed),
        count,
        extra,
    };
    write_dataset(
        out,
        &["tendon_radius_mm", "burial_mm", "ridge_mm"],
        count,
        manifest,
        options,
        &["frames", "masks", "depth"],
        |root, i| {
            let (seq, f) = visuotactile_position(config, i);
            let (scene, frame) = visuotactile::sample(config, seed, seq as u64, f);
            let [file, mask, depth] = write_frame_files(
                root,
                i,
                (frame.width, frame.height),
                &frame.rgb,
                &frame.mask,
                &frame.depth_m,
            )?;
            Ok(vec![
                file,
                mask,
                depth,
                u8::from(frame.tendon).to_string(),
                opt(frame.direction_deg, 3),
                scene.path.name().to_string(),
                num(frame.press_mm, 4),
                seq.to_string(),
                f.to_string(),
                num(scene.tendon_radius_mm, 4),
                num(scene.burial_mm, 4),
                num(frame.ridge_mm, 5),
            ])
        },
    )
}

/// `count` frames of a calibrated sensor's palpation videos (videos of
/// `config.frames_per_sequence`; the last may be cut short), rendered
/// through the calibration in `sensor`: depth maps are the skin's
/// indentation (the manifest says `"depth": "indentation"`).
pub fn write_calibrated(
    sensor: &CalibratedSensor,
    config: &CalibratedConfig,
    count: usize,
    seed: u64,
    out: &Path,
    options: WriteOptions,
    real: &RealFrames,
) -> Result<PathBuf> {
    config.validate()?;
    check_count(count)?;
    real.validate(sensor)?;
    let total = count + real.rows();
    check_count(total)?;
    let fps = config.frames_per_sequence;
    let rendered_sequences = count.div_ceil(fps.max(1));
    let mut extra = serde_json::Map::new();
    extra.insert(
        "config".into(),
        serde_json::to_value(config).map_err(|e| Error::Invalid(e.to_string()))?,
    );
    extra.insert(
        "depth".into(),
        tactile_core::spec::DepthMaps::Indentation.name().into(),
    );
    extra.insert(
        "calibration".into(),
        serde_json::json!({
            "folder": sensor.dir.display().to_string(),
            "sensor": sensor.model.sensor,
            "mm_per_px": sensor.model.mm_per_px,
        }),
    );
    extra.insert(
        "sequences".into(),
        (rendered_sequences + real.frames.len()).into(),
    );
    if !real.frames.is_empty() {
        extra.insert(
            "real_frames".into(),
            serde_json::to_value(real.record()).map_err(|e| Error::Invalid(e.to_string()))?,
        );
    }
    let manifest = Manifest {
        format: FORMAT.into(),
        kind: DatasetKind::Visuotactile,
        sensor_spec: format!("calibrated: {}", sensor.model.sensor),
        width: sensor.width() as u32,
        height: sensor.height() as u32,
        generator: GENERATOR.into(),
        seed: Some(seed),
        count: total,
        extra,
    };
    write_dataset(
        out,
        &["ridge_mm", "peak_mm"],
        total,
        manifest,
        options,
        &["frames", "masks", "depth"],
        |root, i| {
            if i >= count {
                let size = (sensor.width(), sensor.height());
                return write_real_row(
                    root,
                    real,
                    config,
                    size,
                    seed,
                    (i, i - count),
                    rendered_sequences,
                );
            }
            let (seq, f) = calibrated_position(config, i);
            let (scene, frame) = calibrated::sample(sensor, config, seed, seq as u64, f);
            let [file, mask, depth] = write_frame_files(
                root,
                i,
                (frame.width, frame.height),
                &frame.rgb,
                &frame.mask,
                &frame.indentation_m,
            )?;
            Ok(vec![
                file,
                mask,
                depth,
                u8::from(frame.tendon).to_string(),
                opt(frame.direction_deg, 3),
                scene.contact.name().to_string(),
                num(frame.press_mm, 4),
                seq.to_string(),
                f.to_string(),
                num(frame.ridge_mm, 5),
                num(frame.peak_mm, 5),
            ])
        },
    )
}

/// Row `i` of a calibrated set of a `width` x `height` sensor, real row `r`: copy `r % copies` of a real
/// frame, its own video after the `rendered` renders' videos.
fn write_real_row(
    root: &Path,
    real: &RealFrames,
    config: &CalibratedConfig,
    (width, height): (usize, usize),
    seed: u64,
    (i, r): (usize, usize),
    rendered: usize,
) -> tactile_core::Result<Vec<String>> {
    let copies = real.copies.max(1);
    let (frame, rgb) = real.copy(config, seed, r);
    let [file, mask, depth] = write_frame_files(
        root,
        i,
        (width, height),
        &rgb,
        &vec![0u8; width * height],
        &frame.indentation_m,
    )?;
    let peak_mm = frame.indentation_m.iter().copied().fold(0f32, f32::max) as f64 * 1e3;
    Ok(vec![
        file,
        mask,
        depth,
        "0".into(),
        String::new(),
        calibrated::REAL_PRESS_PATH.to_string(),
        num(peak_mm, 4),
        (rendered + r / copies).to_string(),
        (r % copies).to_string(),
        num(0.0, 5),
        num(peak_mm, 5),
    ])
}

/// Write row `i`'s RGB frame, mask and depth map (metres) of a `width` x
/// `height` visuo-tactile sample under `root`; returns their paths
/// relative to it (the `file`, `mask` and `depth` columns).
fn write_frame_files(
    root: &Path,
    i: usize,
    (width, height): (usize, usize),
    rgb: &[u8],
    mask: &[u8],
    depth_m: &[f32],
) -> tactile_core::Result<[String; 3]> {
    let stem = format!("{i:06}");
    let paths = [
        format!("frames/{stem}.png"),
        format!("masks/{stem}.png"),
        format!("depth/{stem}.npy"),
    ];
    save_rgb_png(root.join(&paths[0]), width, height, rgb)?;
    save_grey_png(root.join(&paths[1]), width, height, mask)?;
    crate::npy::write_depth_npy(root.join(&paths[2]), width, height, depth_m)?;
    Ok(paths)
}
