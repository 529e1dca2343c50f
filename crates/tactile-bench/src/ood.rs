//! Frames of another sensor: how often the palpation pipeline flags
//! frames as out of distribution, and how often it still reports a
//! tendon, on fresh frames of its own sensor (new seeds, other sizes,
//! light and deep presses) and on frames that are not its sensor's
//! (virtual TacTip frames, uniform images, natural-looking images, the
//! camera outside its housing, the sensor's frames made grey).

use std::path::Path;

use serde::Serialize;
use tactile_burn::Runtime;
use tactile_core::image_io::{RgbImage, rgb_image};
use tactile_pipeline::palpation::Pipeline;

use crate::Result;

/// One set of frames.
#[derive(Debug, Clone, Serialize)]
pub struct OodRow {
    /// What the frames are.
    pub set: String,
    /// Whether they are the sensor's own frames.
    pub in_distribution: bool,
    /// Frames.
    pub frames: usize,
    /// Flagged as out of distribution.
    pub flagged: usize,
    /// Reported as showing a tendon.
    pub tendon: usize,
    /// Largest and smallest input score.
    pub score_range: [f32; 2],
}

fn vt_frames(
    seed: u64,
    sequences: u64,
    size: (u32, u32),
    press: Option<[f64; 2]>,
) -> Result<Vec<RgbImage>> {
    use datasets_synth::{VisuotactileConfig, visuotactile};
    let mut vc = VisuotactileConfig {
        width: size.0,
        height: size.1,
        frames_per_sequence: 10,
        ..Default::default()
    };
    if let Some([lo, hi]) = press {
        vc.press_mm = datasets_synth::Range::new(lo, hi);
    }
    let mut out = Vec::new();
    for s in 0..sequences {
        for f in 0..vc.frames_per_sequence {
            let (_, fr) = visuotactile::sample(&vc, seed, s, f);
            out.push(rgb_image(fr.width, fr.height, fr.rgb)?);
        }
    }
    Ok(out)
}

/// A deterministic pseudo-random number in [0, 1).
fn hash(mut x: u64) -> f32 {
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
    x ^= x >> 33;
    x = x.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    x ^= x >> 33;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// A natural-looking colour image: smooth random structure at several
/// scales (value noise, octaves with falling amplitude), like a scene.
fn natural(seed: u64, w: usize, h: usize) -> tactile_core::Result<RgbImage> {
    let mut rgb = vec![0u8; w * h * 3];
    for c in 0..3u64 {
        let mut v = vec![0f32; w * h];
        for octave in 0..6u32 {
            let cell = (w as f32 / 4.0 / 2f32.powi(octave as i32)).max(2.0);
            let amp = 0.6f32.powi(octave as i32);
            for y in 0..h {
                for x in 0..w {
                    let (fx, fy) = (x as f32 / cell, y as f32 / cell);
                    let (ix, iy) = (fx.floor() as u64, fy.floor() as u64);
                    let (tx, ty) = (fx.fract(), fy.fract());
                    let g = |i: u64, j: u64| {
                        hash(seed * 1_000_003 + c * 7919 + octave as u64 * 104_729 + i * 65_537 + j)
                    };
                    let top = g(ix, iy) * (1.0 - tx) + g(ix + 1, iy) * tx;
                    let bottom = g(ix, iy + 1) * (1.0 - tx) + g(ix + 1, iy + 1) * tx;
                    v[y * w + x] += amp * (top * (1.0 - ty) + bottom * ty);
                }
            }
        }
        let (lo, hi) = v
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        for (i, x) in v.iter().enumerate() {
            rgb[i * 3 + c as usize] = (255.0 * (x - lo) / (hi - lo).max(1e-6)) as u8;
        }
    }
    rgb_image(w, h, rgb)
}

/// The middle half of a frame enlarged to the whole: the camera seeing the
/// skin without the housing around it.
fn outside_housing(frame: &RgbImage) -> tactile_core::Result<RgbImage> {
    let (w, h) = (frame.width(), frame.height());
    let mut rgb = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        for x in 0..w {
            let (sx, sy) = (w / 4 + x / 2, h / 4 + y / 2);
            rgb.extend_from_slice(&frame.as_slice()[(sy * w + sx) * 3..(sy * w + sx) * 3 + 3]);
        }
    }
    rgb_image(w, h, rgb)
}

/// What the bench measured.
#[derive(Debug, Clone, Serialize)]
pub struct OodBench {
    /// One row per set.
    pub rows: Vec<OodRow>,
    /// The detector's input-profile threshold (None without a profile).
    pub threshold: Option<f32>,
}

/// Run the pipeline in `models` over every set; one row per set.
pub fn bench_ood(models: &Path, runtime: Runtime) -> Result<OodBench> {
    use datasets_synth::{TactipConfig, tactip};
    let mut pipeline = Pipeline::load(models, runtime, 1)?;
    let mut sets: Vec<(String, bool, Vec<RgbImage>)> = vec![
        (
            "visuo-tactile 640x360, new seed".into(),
            true,
            vt_frames(900, 30, (640, 360), None)?,
        ),
        (
            "visuo-tactile 960x540".into(),
            true,
            vt_frames(901, 10, (960, 540), None)?,
        ),
        (
            "visuo-tactile 320x180".into(),
            true,
            vt_frames(902, 10, (320, 180), None)?,
        ),
        (
            "visuo-tactile, light presses 0.05-0.4 mm".into(),
            true,
            vt_frames(903, 10, (640, 360), Some([0.05, 0.4]))?,
        ),
        (
            "visuo-tactile, deep presses 3.5-4 mm".into(),
            true,
            vt_frames(904, 10, (640, 360), Some([3.5, 4.0]))?,
        ),
    ];
    let tc = TactipConfig::default();
    let tactip_frames = (0..100u64)
        .map(|i| {
            let (_, frame) = tactip::sample(&tc, 905, i);
            let rgb = tactile_core::image_io::grey_to_rgb(&frame.pixels);
            rgb_image(300, 300, rgb)
        })
        .collect::<tactile_core::Result<Vec<_>>>()?;
    sets.push(("virtual TacTip frames".into(), false, tactip_frames));
    let uniform = (0..40u64)
        .map(|i| {
            let c = [0u64, 1, 2].map(|k| (hash(906 + i * 3 + k) * 255.0) as u8);
            rgb_image(
                640,
                360,
                c.iter().copied().cycle().take(640 * 360 * 3).collect(),
            )
        })
        .collect::<tactile_core::Result<Vec<_>>>()?;
    sets.push(("uniform colours".into(), false, uniform));
    let scenes = (0..40u64)
        .map(|i| natural(907 + i, 320, 180))
        .collect::<tactile_core::Result<Vec<_>>>()?;
    sets.push(("natural-looking images".into(), false, scenes));
    let outside = vt_frames(908, 10, (640, 360), None)?
        .iter()
        .map(outside_housing)
        .collect::<tactile_core::Result<Vec<_>>>()?;
    sets.push(("camera outside the housing".into(), false, outside));
    // A camera in a mono mode (a bag of mono8 Images): the sensor's own
    // frames without their colour, whose statistics the profile scores
    // near the training frames'.
    let grey = vt_frames(909, 10, (640, 360), None)?
        .iter()
        .map(|f| {
            let rgb = tactile_core::image_io::grey_to_rgb(&tactile_core::image_io::rgb_to_grey(
                f.as_slice(),
            ));
            rgb_image(f.width(), f.height(), rgb)
        })
        .collect::<tactile_core::Result<Vec<_>>>()?;
    sets.push((
        "visuo-tactile frames made grey (a camera in a mono mode)".into(),
        false,
        grey,
    ));
    let mut rows = Vec::new();
    for (set, in_distribution, frames) in sets {
        tactile_core::note!("{set}: {} frames", frames.len());
        let (mut flagged, mut tendon) = (0, 0);
        let mut range = [f32::INFINITY, f32::NEG_INFINITY];
        for f in &frames {
            tactile_core::interrupt::check()?;
            let r = pipeline.process("frame", f)?;
            flagged += usize::from(r.out_of_distribution);
            tendon += usize::from(r.tendon);
            let s = r.input_score.unwrap_or(f32::NAN);
            range = [range[0].min(s), range[1].max(s)];
        }
        rows.push(OodRow {
            set,
            in_distribution,
            frames: frames.len(),
            flagged,
            tendon,
            score_range: range,
        });
    }
    let threshold = pipeline
        .detector()
        .and_then(|d| d.artifact.input_profile.as_ref())
        .map(|p| p.threshold);
    Ok(OodBench { rows, threshold })
}

/// The table.
pub fn ood_markdown(bench: &OodBench) -> String {
    let (rows, threshold) = (&bench.rows, bench.threshold);
    let mut md = format!(
        "The palpation pipeline's input profile (the detector's training frames' input statistics, \
         saved in the detector's `detector.json`, its first member's for an ensemble) flags frames whose score exceeds {}; flagged frames get no \
         tendon, direction or depth. Sets rendered in process with fixed seeds.\n\n\
         | frames | own sensor | frames | flagged | flagged (%) | tendon reported | input score (min - max) |\n\
         |---|---|---|---|---|---|---|\n",
        threshold.map_or("-".into(), |t| format!("{t:.1}"))
    );
    for r in rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {:.1} | {} | {:.1} - {:.1} |\n",
            r.set,
            if r.in_distribution { "yes" } else { "no" },
            r.frames,
            r.flagged,
            100.0 * r.flagged as f64 / r.frames.max(1) as f64,
            r.tendon,
            r.score_range[0],
            r.score_range[1]
        ));
    }
    md
}
