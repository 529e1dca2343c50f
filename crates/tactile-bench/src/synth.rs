//! How fast the virtual sensors render and write datasets.

use std::path::PathBuf;

use tactile_core::bench::Machine;

use crate::Result;

/// Median single-thread render time per frame over distinct samples.
fn median_render(n: usize, mut render: impl FnMut(usize)) -> f64 {
    let mut t: Vec<f64> = (0..n.max(1))
        .map(|i| {
            let s = std::time::Instant::now();
            render(i);
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Frames/s of writing a whole dataset (render + PNG/NPY encode + disk), all threads.
fn write_rate(
    n: usize,
    write: impl Fn(&std::path::Path) -> datasets_synth::Result<PathBuf>,
) -> Result<f64> {
    let dir = std::env::temp_dir().join(format!("tactile-bench-synth-{}", std::process::id()));
    let mut rates = Vec::new();
    for _ in 0..3 {
        let out = dir.join("ds");
        let s = std::time::Instant::now();
        write(&out)?;
        rates.push(n as f64 / s.elapsed().as_secs_f64());
        std::fs::remove_dir_all(&dir).ok();
    }
    rates.sort_by(f64::total_cmp);
    Ok(rates[1])
}

/// Frames one measurement of [`bench_synth`] renders and writes.
pub const MAX_SYNTH_BENCH_FRAMES: usize = 10_000;

/// Frames/s of both virtual sensors, and of a calibrated sensor's renderer
/// when `sensor` names its calibration folder (`tactile calibrate ball`'s,
/// with the default scene mix the own-sensor loop renders): render (one
/// thread) and write (all threads), `frames` per measurement (fewer at
/// 1920x1080); the Markdown.
pub fn bench_synth(frames: usize, sensor: Option<&std::path::Path>) -> Result<String> {
    if !(1..=MAX_SYNTH_BENCH_FRAMES).contains(&frames) {
        return Err(tactile_core::Error::Config(format!(
            "frames: must be 1 to {MAX_SYNTH_BENCH_FRAMES} per measurement (each written to disk), got {frames}"
        ))
        .into());
    }
    use datasets_synth::{
        CalibratedConfig, CalibratedSensor, TactipConfig, VisuotactileConfig, WriteOptions, tactip,
        visuotactile,
    };
    // Loaded before any measurement, so a bad folder is named at once.
    let calibrated = sensor.map(CalibratedSensor::load).transpose()?;
    let threads = rayon::current_num_threads();
    let opts = WriteOptions::default();
    let mut rows = Vec::new();
    let tc = TactipConfig::default();
    tactile_core::note!("virtual TacTip 300x300");
    let t1 = median_render(frames, |i| {
        let _ = tactip::sample(&tc, 1, i as u64);
    });
    let w = write_rate(frames, |out| {
        datasets_synth::write_tactip(&tc, frames, 1, out, opts)
    })?;
    rows.push(("virtual TacTip", "300x300".to_string(), t1, w));
    for (wd, ht, n) in [(640u32, 360u32, frames), (1920, 1080, (frames / 8).max(3))] {
        tactile_core::note!("virtual visuo-tactile {wd}x{ht}");
        let vc = VisuotactileConfig {
            width: wd,
            height: ht,
            ..Default::default()
        };
        let f = vc.frames_per_sequence;
        let t1 = median_render(n, |i| {
            let _ = visuotactile::sample(&vc, 1, (i / f) as u64, i % f);
        });
        let w = write_rate(n, |out| {
            datasets_synth::write_visuotactile(&vc, n, 1, out, opts)
        })?;
        rows.push(("virtual visuo-tactile", format!("{wd}x{ht}"), t1, w));
    }
    if let Some(cs) = &calibrated {
        let (wd, ht) = (cs.width(), cs.height());
        tactile_core::note!("calibrated sensor {} {wd}x{ht}", cs.dir.display());
        let cc = CalibratedConfig::default();
        let f = cc.frames_per_sequence;
        let t1 = median_render(frames, |i| {
            let _ = datasets_synth::calibrated::sample(cs, &cc, 1, (i / f) as u64, i % f);
        });
        let none = datasets_synth::calibrated::RealFrames::default();
        let w = write_rate(frames, |out| {
            datasets_synth::write_calibrated(cs, &cc, frames, 1, out, opts, &none)
        })?;
        rows.push(("calibrated sensor", format!("{wd}x{ht}"), t1, w));
    }
    let mut md = format!(
        "Machine: {}\n\nRender: one frame with its labels in memory, one thread, median over distinct samples. \
         Write: a whole dataset to disk (render, PNG and NPY encoding, files) with {threads} rayon threads, median of 3 runs.\n\n\
         | sensor | size | render, 1 thread (ms/frame) | render, 1 thread (frames/s) | write, {threads} threads (frames/s) |\n|---|---|---|---|---|\n",
        Machine::detect().describe()
    );
    for (name, size, t1, w) in &rows {
        md.push_str(&format!(
            "| {name} | {size} | {:.1} | {:.1} | {:.1} |\n",
            t1 * 1e3,
            1.0 / t1,
            w
        ));
    }
    Ok(md)
}
