//! The palpation pipeline at the sensor's native resolution against the
//! virtual sensor's 640 x 360: the same scenes rendered at each size, every
//! stage timed per frame (the one downsample to the working frame
//! included), and how fast FFmpeg decodes a native H.264 stream.

use std::path::Path;

use serde::Serialize;
use tactile_burn::Runtime;
use tactile_core::bench::Machine;
use tactile_core::image_io::{RgbImage, rgb_image};
use tactile_core::metrics::median;
use tactile_pipeline::palpation::{FrameRecord, Pipeline};

use crate::Result;

/// Median milliseconds per stage over the tendon frames of one size.
#[derive(Debug, Clone, Serialize)]
pub struct ResolutionRow {
    /// `WIDTHxHEIGHT`.
    pub size: String,
    /// Tendon frames timed (frames x repeats).
    pub samples: usize,
    /// The downsample to the working frame.
    pub prepare_ms: f64,
    /// The detector.
    pub detect_ms: f64,
    /// Segmenter and direction.
    pub segment_ms: f64,
    /// Depth.
    pub depth_ms: f64,
    /// The whole frame.
    pub total_ms: f64,
}

/// What the bench measured.
#[derive(Debug, Clone, Serialize)]
pub struct ResolutionBench {
    /// One row per size, the first the reference.
    pub rows: Vec<ResolutionRow>,
    /// Where the networks ran.
    pub runtime: Runtime,
    /// One 1920x1080 frame to 640x360, ms (median): `fast_image_resize`'s
    /// box filter (the working frame) and the toolkit's own area resize
    /// (`visuo::resize_rgb`, what each model did to the full frame before).
    pub downsample_ms: Option<[f64; 2]>,
    /// Frames per second FFmpeg decoded a 1920 x 1080 H.264 stream at, one
    /// decoding thread, when FFmpeg is installed.
    pub decode_fps_1080p: Option<f64>,
}

impl ResolutionBench {
    /// The Markdown table: per stage and size, and each size's whole frame
    /// against the first's.
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "Machine: {}. Runtime: {}, 1 intra-op thread. The same tendon scenes rendered by the virtual \
             sensor at each size; every stage timed per frame in process (decoding excluded), median \
             over frames x repeats.\n\n\
             | frame | samples | prepare (ms) | detect (ms) | segment + direction (ms) | depth (ms) | whole frame (ms) | vs {} |\n\
             |---|---|---|---|---|---|---|---|\n",
            Machine::detect().describe(),
            self.runtime.name(),
            self.rows.first().map_or("", |r| r.size.as_str()),
        );
        let base = self.rows.first().map_or(1.0, |r| r.total_ms);
        for r in &self.rows {
            md.push_str(&format!(
                "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2}x |\n",
                r.size,
                r.samples,
                r.prepare_ms,
                r.detect_ms,
                r.segment_ms,
                r.depth_ms,
                r.total_ms,
                r.total_ms / base
            ));
        }
        if let Some([fir, area]) = self.downsample_ms {
            md.push_str(&format!(
                "\nOne 1920x1080 frame to 640x360: fast_image_resize's box filter {fir:.2} ms, \
                 the toolkit's own area resize (to floats) {area:.2} ms; before the working frame, \
                 each of the three models resized the full frame itself.\n"
            ));
        }
        if let Some(fps) = self.decode_fps_1080p {
            md.push_str(&format!(
                "\nDecoding a 1920x1080 H.264 stream with FFmpeg (one decoding thread, rgb24 out, \
                 read through the toolkit's video source): {fps:.1} frames/s.\n"
            ));
        }
        md
    }
}

/// Render `frames` tendon frames (one per sequence, at its peak press) at
/// `width x height`.
fn tendon_frames(width: u32, height: u32, frames: usize) -> Result<Vec<RgbImage>> {
    use datasets_synth::{VisuotactileConfig, visuotactile};
    let vc = VisuotactileConfig {
        width,
        height,
        ..Default::default()
    };
    let mut out = Vec::new();
    let mut sequence = 0u64;
    // Scenes without a tendon are skipped; the generator's share of
    // tendon scenes makes this end quickly.
    while out.len() < frames && sequence < 64 * frames as u64 + 64 {
        let (_, f) = visuotactile::sample(&vc, 7, sequence, vc.frames_per_sequence / 2);
        sequence += 1;
        if f.tendon {
            out.push(rgb_image(f.width, f.height, f.rgb)?);
        }
    }
    Ok(out)
}

/// Time the pipeline in `models` on `frames` tendon frames at each of
/// `sizes` (the first is the reference), `repeats` passes, sizes
/// interleaved so they share the machine's state.
pub fn bench_resolution(
    models: &Path,
    runtime: Runtime,
    sizes: &[(u32, u32)],
    frames: usize,
    repeats: usize,
) -> Result<ResolutionBench> {
    let mut pipeline = Pipeline::load(models, runtime, 1)?;
    let sets: Vec<Vec<RgbImage>> = sizes
        .iter()
        .map(|&(w, h)| {
            tactile_core::note!("rendering {frames} tendon frames at {w}x{h}");
            tendon_frames(w, h, frames)
        })
        .collect::<Result<_>>()?;
    let mut records: Vec<Vec<FrameRecord>> = vec![Vec::new(); sizes.len()];
    // One untimed pass warms every path.
    for set in &sets {
        for f in set {
            pipeline.process("warm-up", f)?;
        }
    }
    let pb = tactile_core::progress::progress_bar((repeats * frames * sizes.len()) as u64, "bench");
    for _ in 0..repeats {
        for i in 0..frames {
            for (s, set) in sets.iter().enumerate() {
                let Some(f) = set.get(i) else { continue };
                tactile_core::interrupt::check()?;
                let r = pipeline.process("frame", f)?;
                if r.tendon {
                    records[s].push(r);
                }
                pb.inc(1);
            }
        }
    }
    pb.finish_and_clear();
    let rows = sizes
        .iter()
        .zip(&records)
        .map(|(&(w, h), rs)| {
            let m = |f: &dyn Fn(&FrameRecord) -> f64| median(&rs.iter().map(f).collect::<Vec<_>>());
            ResolutionRow {
                size: format!("{w}x{h}"),
                samples: rs.len(),
                prepare_ms: m(&|r| r.ms_prepare),
                detect_ms: m(&|r| r.ms_detect),
                segment_ms: m(&|r| r.ms_segment.unwrap_or(0.0)),
                depth_ms: m(&|r| r.ms_depth.unwrap_or(0.0)),
                total_ms: m(&|r| r.ms_total),
            }
        })
        .collect();
    let downsample_ms = match sizes.iter().position(|&s| s == (1920, 1080)) {
        Some(k) if !sets[k].is_empty() => {
            let f = &sets[k][0];
            let fir = tactile_core::bench::median_seconds(3, 30, || {
                let _ = tactile_preprocess::visuo::working_frame(f, 360);
            });
            let area = tactile_core::bench::median_seconds(3, 30, || {
                let _ = tactile_preprocess::visuo::resize_rgb(f, 640, 360);
            });
            Some([1e3 * fir, 1e3 * area])
        }
        _ => None,
    };
    let decode_fps_1080p = match sizes.iter().position(|&s| s == (1920, 1080)) {
        Some(k) => decode_rate(&sets[k])?,
        None => None,
    };
    Ok(ResolutionBench {
        rows,
        runtime,
        downsample_ms,
        decode_fps_1080p,
    })
}

/// Frames/s of decoding `frames`, encoded as a 30 fps H.264 stream (FFmpeg's
/// default quality) and
/// looped to at least 300 frames, through [`tactile_core::source`]'s
/// video reader; `None` without FFmpeg.
fn decode_rate(frames: &[RgbImage]) -> Result<Option<f64>> {
    use tactile_core::video;
    if !video::ffmpeg_available() || frames.is_empty() {
        return Ok(None);
    }
    let dir = tempdir()?;
    let file = dir.join("native.mp4");
    let loops = 300usize.div_ceil(frames.len());
    let all: Vec<&RgbImage> = (0..loops).flat_map(|_| frames.iter()).collect();
    video::encode(&all, 30, video::VideoCodec::H264 { crf: 23 }, &file)?;
    let start = std::time::Instant::now();
    let mut reader = video::VideoReader::open(
        &video::VideoInput::File(file.clone()),
        video::DecodeOptions { threads: 1 },
    )?;
    let mut n = 0usize;
    while reader.next_frame()?.is_some() {
        n += 1;
    }
    let fps = n as f64 / start.elapsed().as_secs_f64();
    std::fs::remove_dir_all(&dir).ok();
    Ok(Some(fps))
}

fn tempdir() -> Result<std::path::PathBuf> {
    let dir = std::env::temp_dir().join(format!("tactile-bench-decode-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| tactile_core::Error::io(&dir, e))?;
    Ok(dir)
}
