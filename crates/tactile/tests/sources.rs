#![allow(clippy::unwrap_used)]
//! Every source `tactile run` reads: a video file (H.264 and MJPEG, decoded
//! by FFmpeg), a network stream's URL, raw frames on stdin, a folder of
//! JPEG frames, and the live
//! queue that drops the oldest frames when the models fall behind. Each is
//! checked against the run over the shipped PNG frames.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use serde_json::Value;

const SAMPLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../samples/palpation");
const MODELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models");

fn tactile() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tactile"))
}

/// Records (stdout, `--out -`) and the summary (last line of stderr).
fn run(args: &[&str], stdin: Option<Vec<u8>>) -> (Vec<Value>, Value, String) {
    let mut cmd = tactile();
    cmd.args(["run", "--models", MODELS, "--out", "-"])
        .args(args);
    cmd.stdin(if stdin.is_some() {
        Stdio::piped()
    } else {
        Stdio::null()
    })
    .stdout(Stdio::piped())
    .stderr(Stdio::piped());
    let mut child = cmd.spawn().unwrap();
    if let Some(bytes) = stdin {
        let mut pipe = child.stdin.take().unwrap();
        std::thread::spawn(move || {
            let _ = pipe.write_all(&bytes);
        });
    }
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "tactile run {args:?} failed: {err}");
    let records = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let summary = serde_json::from_str(err.lines().last().unwrap()).unwrap();
    (records, summary, err)
}

fn sample_frames() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(SAMPLES)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "png"))
        .collect();
    v.sort();
    v
}

fn images() -> Vec<tactile_core::image_io::RgbImage> {
    sample_frames()
        .iter()
        .map(|p| tactile_core::image_io::load_rgb(p).unwrap())
        .collect()
}

fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(180.0);
    d.min(180.0 - d)
}

/// Same decisions on every frame, and directions within `tol_deg`.
fn assert_agree(reference: &[Value], other: &[Value], tol_deg: f64) {
    assert_eq!(reference.len(), other.len());
    for (i, (a, b)) in reference.iter().zip(other).enumerate() {
        assert_eq!(a["tendon"], b["tendon"], "frame {i}: {a} vs {b}");
        match (a["direction_deg"].as_f64(), b["direction_deg"].as_f64()) {
            (Some(x), Some(y)) => assert!(
                angle_diff(x, y) <= tol_deg,
                "frame {i}: direction {x} vs {y} (tolerance {tol_deg} deg)"
            ),
            (x, y) => assert_eq!(
                x.is_some(),
                y.is_some(),
                "frame {i}: direction {x:?} vs {y:?}"
            ),
        }
    }
}

fn reference() -> Vec<Value> {
    run(&["--data", SAMPLES], None).0
}

#[test]
fn a_video_file_gives_the_decisions_and_directions_of_its_frames() {
    use tactile_core::video::{VideoCodec, encode};
    let dir = tempfile::tempdir().unwrap();
    let imgs = images();
    let refs: Vec<_> = imgs.iter().collect();
    let expected = reference();
    // (codec, file, direction tolerance in degrees): lossless RGB decodes to
    // the very frames, so records match exactly; visually lossless H.264
    // and best-quality MJPEG move pixels, and with them the direction a
    // little (measured: 0.7 and 3.8 degrees at most; compression at
    // FFmpeg's default crf 23 moves it up to 4 degrees).
    for (codec, name, tol) in [
        (VideoCodec::H264LosslessRgb, "lossless.mp4", 0.0),
        (VideoCodec::H264 { crf: 6 }, "palpation.mkv", 2.0),
        (VideoCodec::Mjpeg, "palpation.avi", 5.0),
    ] {
        let video = dir.path().join(name);
        encode(&refs, 30, codec, &video).unwrap();
        let (records, summary, err) = run(&["--data", video.to_str().unwrap()], None);
        assert!(!err.contains("cut short"), "a whole file: {err}");
        assert_eq!(summary["source"], "video");
        assert_eq!(
            summary["frames"],
            imgs.len() as u64,
            "every frame, none dropped"
        );
        assert_eq!(summary["dropped_frames"], 0);
        assert_agree(&expected, &records, tol);
        assert_eq!(records[3]["frame"], "000003");
        if tol == 0.0 {
            for (a, b) in expected.iter().zip(&records) {
                assert_eq!(a["score"], b["score"], "{name}");
                assert_eq!(a["depth_max_mm"], b["depth_max_mm"], "{name}");
            }
        }
    }
}

#[test]
fn a_video_file_cut_short_gives_its_frames_and_says_so() {
    // A copy stopped half-way: FFmpeg decodes the frames that are there
    // and says nothing, so the run compares them with the length and rate
    // the container declares (Matroska writes its duration up front).
    use tactile_core::video::{VideoCodec, encode};
    let dir = tempfile::tempdir().unwrap();
    let imgs = images();
    let refs: Vec<_> = imgs.iter().cycle().take(40).collect();
    let whole = dir.path().join("whole.mkv");
    encode(&refs, 30, VideoCodec::Mjpeg, &whole).unwrap();
    let bytes = std::fs::read(&whole).unwrap();
    let cut = dir.path().join("cut.mkv");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let (records, summary, err) = run(&["--data", cut.to_str().unwrap()], None);
    let n = records.len();
    assert!((5..35).contains(&n), "{n} frames of a half file");
    assert_eq!(summary["frames"], n as u64);
    assert!(
        err.contains(
            "cut.mkv: its container says 1.33 s at 30.00 frames per second (about 40 frames)"
        ) && err.contains(&format!("and {n} were decoded: the file may be cut short")),
        "{err}"
    );
    let (records, _, err) = run(&["--data", whole.to_str().unwrap()], None);
    assert_eq!(records.len(), 40);
    assert!(!err.contains("cut short"), "{err}");
}

#[test]
fn raw_frames_on_stdin_give_the_same_records_as_the_files() {
    let expected = reference();
    let imgs = images();
    let bytes: Vec<u8> = imgs.iter().flat_map(|i| i.as_slice().to_vec()).collect();
    // A queue as long as the input: nothing dropped, so every frame compares.
    let (records, summary, _) = run(
        &["--stdin", "--size", "320x180", "--live-queue", "64"],
        Some(bytes),
    );
    assert_eq!(summary["source"], "stdin");
    assert_eq!(
        records.len() as u64 + summary["dropped_frames"].as_u64().unwrap(),
        12
    );
    if summary["dropped_frames"] == 0 {
        assert_agree(&expected, &records, 0.0);
    }
    assert!(
        records
            .iter()
            .all(|r| r["latency_ms"].as_f64().is_some_and(|v| v >= 0.0))
    );
}

#[test]
fn stdin_that_ends_inside_a_frame_keeps_the_whole_frames_before_it() {
    // A piped camera killed mid-write: the three whole frames before the
    // cut are kept, as a bag cut short keeps its messages, with a warning.
    let imgs = images();
    let mut bytes: Vec<u8> = imgs[..3]
        .iter()
        .flat_map(|i| i.as_slice().to_vec())
        .collect();
    bytes.extend_from_slice(&imgs[3].as_slice()[..1000]);
    let (records, summary, err) = run(
        &["--stdin", "--size", "320x180", "--live-queue", "64"],
        Some(bytes),
    );
    assert_eq!(records.len(), 3, "{err}");
    assert_eq!(summary["frames"], 3);
    assert_agree(&reference()[..3], &records, 0.0);
    assert!(
        err.contains("stdin ended inside a frame: 1000 of 172800 bytes")
            && err.contains("after 3 whole frames"),
        "{err}"
    );

    // Less than one frame is no stream of that size: an error, no records.
    let mut child = tactile()
        .args(["run", "--models", MODELS, "--stdin", "--size", "320x180"])
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(&imgs[0].as_slice()[..1000])
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("stdin ended inside a frame") && err.contains("before any whole frame"),
        "{err}"
    );
}

#[test]
fn an_option_of_the_other_kind_of_source_is_refused() {
    // A live queue for a recorded folder, or decoding without overlap for
    // live stdin, would do nothing. Before, both were taken and ignored.
    for (args, want) in [
        (
            &[
                "run",
                "--models",
                MODELS,
                "--data",
                SAMPLES,
                "--live-queue",
                "8",
            ][..],
            "live_queue 8: the frames a live source (a camera, a stream, stdin) may hold while the models run, and this folder source is recorded",
        ),
        (
            &[
                "run",
                "--models",
                MODELS,
                "--stdin",
                "--size",
                "320x180",
                "--no-overlap",
            ][..],
            "and this stdin source is live (read as frames arrive): leave it out",
        ),
        // `--data -` (the shell's name for standard input) says how it
        // is read; before, "-: input does not exist".
        (
            &["run", "--models", MODELS, "--data", "-"][..],
            "-: no file of that name; standard input is read as raw rgb24 frames with `--stdin --size WxH`",
        ),
    ] {
        let out = tactile().args(args).stdin(Stdio::null()).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(want),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn a_limit_of_no_frames_is_refused_not_run() {
    // Before, `run --limit 0` read nothing and succeeded with an empty
    // summary; `predict` said only "no frames to estimate".
    for args in [
        &["run", "--models", MODELS, "--data", SAMPLES, "--limit", "0"][..],
        &[
            "predict",
            "--model",
            concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/pose-edge"),
            "--data",
            SAMPLES,
            "--limit",
            "0",
        ][..],
    ] {
        let out = tactile().args(args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success()
                && err.contains(
                    "limit: must be at least 1 frame, got 0 (leave it out to read every frame)"
                ),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn a_live_source_that_outruns_the_models_drops_the_oldest_frames_in_bounded_memory() {
    // 200 native 1920x1080 frames (1.2 GB) pushed as fast as a pipe takes
    // them: the models cannot keep up, so most are dropped from a queue of 2.
    let small = image::open(&sample_frames()[4]).unwrap().to_rgb8();
    let frame = image::imageops::resize(&small, 1920, 1080, image::imageops::FilterType::Triangle)
        .into_raw();
    let n = 200usize;
    let mut child = tactile()
        .args([
            "run",
            "--models",
            MODELS,
            "--out",
            "-",
            "--stdin",
            "--size",
            "1920x1080",
        ])
        .args(["--live-queue", "2"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut pipe = child.stdin.take().unwrap();
    let writer = std::thread::spawn(move || {
        for _ in 0..n {
            pipe.write_all(&frame).unwrap();
        }
    });
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let summary: Value = serde_json::from_str(err.lines().last().unwrap()).unwrap();
    let (frames, dropped) = (
        summary["frames"].as_u64().unwrap(),
        summary["dropped_frames"].as_u64().unwrap(),
    );
    assert_eq!(frames + dropped, n as u64, "{summary}");
    assert!(dropped > 0, "the models kept up with a pipe? {summary}");
    assert!(err.contains("dropped while the models were busy"), "{err}");
    // Models, runtime and a few frames take well under 300 MB; keeping
    // every frame would take 1.2 GB.
    let rss = summary["peak_rss_mb"].as_f64().unwrap();
    assert!(rss < 300.0, "peak memory {rss} MB");
    let lines = String::from_utf8_lossy(&out.stdout).lines().count() as u64;
    assert_eq!(lines, frames);
}

#[test]
fn a_folder_of_jpeg_frames_runs_and_other_files_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    for (i, p) in sample_frames().iter().enumerate() {
        let img = image::open(p).unwrap().to_rgb8();
        let out = std::fs::File::create(dir.path().join(format!("{i:06}.jpg"))).unwrap();
        image::codecs::jpeg::JpegEncoder::new_with_quality(out, 95)
            .encode_image(&img)
            .unwrap();
    }
    std::fs::write(dir.path().join("notes.txt"), "recorded on day 3").unwrap();
    // What macOS leaves beside frames copied to a shared drive: resource
    // forks named like frames that are not pictures, and .DS_Store.
    std::fs::write(
        dir.path().join("._000001.jpg"),
        b"\0\x05\x16\x07resource fork",
    )
    .unwrap();
    std::fs::write(dir.path().join(".DS_Store"), b"\0\0\0\x01Bud1").unwrap();
    let (records, summary, err) = run(&["--data", dir.path().to_str().unwrap()], None);
    assert_eq!(summary["source"], "folder");
    assert!(
        err.contains(
            "1 file(s) that are not frames (PNG, JPEG, BMP, TIFF, WebP or PGM/PPM) were not read: notes.txt; \
             2 hidden file(s) (a name starting with '.', as macOS's ._ copies) were not read: \
             .DS_Store, ._000001.jpg"
        ),
        "{err}"
    );
    assert_agree(&reference(), &records, 2.0);
}

#[test]
fn frame_names_that_are_not_utf8_are_run_and_reported() {
    // A frame saved on a system whose file names are Latin-1 ("é" as the
    // byte 0xE9): its name cannot be written as it is in a JSON record.
    use std::os::unix::ffi::OsStrExt;
    let dir = tempfile::tempdir().unwrap();
    for (i, p) in sample_frames().iter().enumerate() {
        let name = match i {
            1 => std::ffi::OsStr::from_bytes(b"000001-\xe9.png").to_os_string(),
            _ => format!("{i:06}.png").into(),
        };
        std::fs::copy(p, dir.path().join(name)).unwrap();
    }
    let (records, summary, err) = run(&["--data", dir.path().to_str().unwrap()], None);
    assert_eq!(summary["frames"].as_u64().unwrap() as usize, records.len());
    assert_eq!(records[1]["frame"], "000001-\u{fffd}.png");
    assert!(
        err.contains("1 frame name(s) are not UTF-8 (e.g. \"000001-\\xE9.png\")"),
        "{err}"
    );
    assert_agree(&reference(), &records, 2.0);
}

#[test]
fn a_folder_numbered_without_zeros_runs_in_time() {
    // Frames saved as frame_0.png ... frame_11.png: by name, frame_10 and
    // frame_11 would come before frame_2, and the run's hysteresis would
    // see the palpation out of order.
    let dir = tempfile::tempdir().unwrap();
    for (i, p) in sample_frames().iter().enumerate() {
        std::fs::copy(p, dir.path().join(format!("frame_{i}.png"))).unwrap();
    }
    let (records, summary, err) = run(&["--data", dir.path().to_str().unwrap()], None);
    let names: Vec<_> = records
        .iter()
        .map(|r| r["frame"].as_str().unwrap())
        .collect();
    let expected: Vec<_> = (0..names.len()).map(|i| format!("frame_{i}.png")).collect();
    assert_eq!(names, expected);
    assert_eq!(summary["missing_frames"], 0, "{err}");
    assert!(!err.contains("missing from the numbering"), "{err}");
    assert_agree(&reference(), &records, 0.0);
}

#[test]
fn a_file_that_is_not_a_video_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("clip.mp4");
    std::fs::write(&f, b"not a video at all").unwrap();
    let out = tactile()
        .args(["run", "--models", MODELS, "--data", f.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("clip.mp4") && err.contains("cannot read as video"),
        "{err}"
    );
    // A dataset's labels file named instead of its folder: the folder is
    // named, not FFmpeg's "Invalid data".
    let ds = dir.path().join("my-dataset");
    std::fs::create_dir(&ds).unwrap();
    let labels = ds.join("labels.csv");
    std::fs::write(&labels, "file,split\n").unwrap();
    let out = tactile()
        .args([
            "run",
            "--models",
            MODELS,
            "--data",
            labels.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("labels.csv: is a file of a dataset")
            && err.contains(&format!("pass the dataset's folder {}", ds.display())),
        "{err}"
    );
    // A device that is no camera: said to be read as one. Before, "cannot
    // read as video: /dev/null: Inappropriate ioctl for device".
    let out = tactile()
        .args(["run", "--models", MODELS, "--data", "/dev/null"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("/dev/null: cannot read as a camera (a device is read as a V4L2 camera, such as /dev/video0)"),
        "{err}"
    );
}

#[test]
fn records_on_stdout_stop_quietly_when_the_reader_goes() {
    let mut child = tactile()
        .args(["run", "--models", MODELS, "--data", SAMPLES, "--out", "-"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read one record, then close the pipe.
    let mut stdout = child.stdout.take().unwrap();
    let mut first = [0u8; 16];
    std::io::Read::read_exact(&mut stdout, &mut first).unwrap();
    drop(stdout);
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("panicked") && !err.contains("error"), "{err}");
}

#[test]
fn a_video_and_a_labels_csv_become_a_dataset_every_command_reads() {
    use tactile_core::video::{VideoCodec, encode};
    let dir = tempfile::tempdir().unwrap();
    let imgs = images();
    let refs: Vec<_> = imgs.iter().collect();
    let video = dir.path().join("clip.mp4");
    encode(&refs, 30, VideoCodec::H264LosslessRgb, &video).unwrap();
    // Frames 2-9 press on the tendon; frame 11 is left unlabelled.
    let mut csv = String::from("frame,tendon,direction_deg,sequence,operator\n");
    for i in 0..11 {
        let t = (2..=9).contains(&i);
        let d = if t { "117.3" } else { "" };
        csv.push_str(&format!("{i},{},{d},0,ana\n", u8::from(t)));
    }
    let labels = dir.path().join("labels.csv");
    std::fs::write(&labels, csv).unwrap();
    let out = dir.path().join("ds");
    let import = |frames: &Path, labels: &Path, out: &Path| {
        tactile()
            .args(["dataset", "from-video", "--kind", "visuotactile"])
            .args([
                "--video",
                frames.to_str().unwrap(),
                "--labels",
                labels.to_str().unwrap(),
            ])
            .args(["--out", out.to_str().unwrap()])
            .output()
            .unwrap()
    };
    let r = import(&video, &labels, &out);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let ds = tactile_core::dataset::Dataset::open(&out).unwrap();
    assert_eq!(ds.len(), 11);
    assert_eq!(ds.columns.last().map(String::as_str), Some("operator"));
    assert_eq!(ds.text_opt(4, "operator"), Some("ana"));
    // The frames are the video's, bit for bit (lossless), and the run over
    // the dataset scores its decisions against the labels.
    let f3 = tactile_core::image_io::load_rgb(ds.path_of(3, "file").unwrap()).unwrap();
    assert_eq!(f3.as_slice(), imgs[3].as_slice());
    let (_, summary, _) = run(&["--data", out.to_str().unwrap()], None);
    assert_eq!(summary["detector_accuracy"], 1.0, "{summary}");
    // A second import over it is refused; a frame beyond the video and a
    // mask outside the labels' folder are errors naming the line.
    let r = import(&video, &labels, &out);
    assert!(String::from_utf8_lossy(&r.stderr).contains("exists and is not empty"));
    let bad = dir.path().join("bad.csv");
    // The error of importing `frames` with the labels `csv` as `bad.csv`.
    let refused = |frames: &Path, csv: &str| {
        std::fs::write(&bad, csv).unwrap();
        let r = import(frames, &bad, &dir.path().join("ds2"));
        String::from_utf8_lossy(&r.stderr).into_owned()
    };
    let err = refused(&video, "frame,tendon\n3,1\n40,1\n");
    assert!(err.contains("bad.csv:3: frame 40 is not in"), "{err}");
    // Labels saved with CRLF endings and a blank line name the same lines.
    let err = refused(&video, "frame,tendon\r\n3,1\r\n\r\n40,1\r\n");
    assert!(err.contains("bad.csv:4: frame 40 is not in"), "{err}");
    // Saved by a spreadsheet that separates with semicolons.
    let err = refused(&video, "frame;tendon\n3;1\n");
    assert!(
        err.contains("bad.csv:1: no `frame` column (the header is one cell holding ';'"),
        "{err}"
    );
    // A frame labelled twice is named as written; a label the dataset
    // cannot read is named at its line of these labels, not of the
    // dataset's staged copy.
    let err = refused(&video, "frame,tendon\n3,1\n3,0\n");
    assert!(
        err.contains("bad.csv:3: frame 3 is labelled twice (also on line 2)"),
        "{err}"
    );
    let err = refused(&video, "frame,tendon\n2,0\n5,yes\n");
    assert!(
        err.contains("bad.csv:3: column 'tendon': 'yes' is not a number")
            && !err.contains("partial"),
        "{err}"
    );
    // From a folder, a frame labelled by its number and by its file name.
    let folder = dir.path().join("frames");
    std::fs::create_dir(&folder).unwrap();
    for (i, img) in imgs.iter().take(3).enumerate() {
        let (w, h) = (img.width(), img.height());
        tactile_core::image_io::save_rgb_png(
            folder.join(format!("{i:06}.png")),
            w,
            h,
            img.as_slice(),
        )
        .unwrap();
    }
    let err = refused(&folder, "frame,tendon\n1,1\n000001.png,0\n");
    assert!(
        err.contains("bad.csv:3: frame 1 (\"000001.png\") is labelled twice, by its number and by its name (also on line 2)"),
        "{err}"
    );
    // Frames named by paths (as a dataset's own `file` column, a Windows
    // tool's backslashes, `./`, absolute), read from the labels' folder or
    // the frames' folder, are the frames they name; a path to no frame of
    // the folder is refused at its line (before, every path was "not in"
    // the folder, as a name no frame has).
    let absolute = folder.join("000000.png");
    let csv = format!(
        "frame,tendon\nframes/000001.png,1\n./000002.png,0\n{},1\n",
        absolute.display()
    );
    std::fs::write(&bad, &csv).unwrap();
    let by_path = dir.path().join("by-path");
    let r = import(&folder, &bad, &by_path);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let ds = tactile_core::dataset::Dataset::open(&by_path).unwrap();
    let tendons: Vec<_> = (0..ds.len())
        .map(|i| ds.number_opt(i, "tendon").unwrap())
        .collect();
    assert_eq!(tendons, [Some(1.0), Some(1.0), Some(0.0)]);
    let r = import(
        &folder,
        &{
            std::fs::write(&bad, "frame,tendon\nframes\\000001.png,1\n").unwrap();
            bad.clone()
        },
        &dir.path().join("backslash"),
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let err = refused(&folder, "frame,tendon\n0,1\nelsewhere/000001.png,1\n");
    assert!(
        err.contains("bad.csv:3: frame \"elsewhere/000001.png\" is not a frame of")
            && err.contains("name a frame by its file name or its number"),
        "{err}"
    );
    // Files numbered from 1 (img_1.png, ...) labelled by number: a frame's
    // number is its place from 0, so the import warns that a column of the
    // files' own numbers would be one frame off, and says so in the error
    // of a number past the end (before, both said nothing of it).
    let from_1 = dir.path().join("from-1");
    std::fs::create_dir(&from_1).unwrap();
    for i in 0..3 {
        std::fs::copy(
            folder.join(format!("{i:06}.png")),
            from_1.join(format!("img_{}.png", i + 1)),
        )
        .unwrap();
    }
    std::fs::write(&bad, "frame,tendon\n1,1\n2,0\n").unwrap();
    let r = import(&from_1, &bad, &dir.path().join("from-1-ds"));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{err}");
    assert!(
        err.contains("warning: ")
            && err.contains("bad.csv: a `frame` number is the frame's place in the folder counted from 0 (frame 0 is img_1.png, frame 1 is img_2.png), and the files are numbered from 1"),
        "{err}"
    );
    let err = refused(&from_1, "frame,tendon\n3,1\n");
    assert!(
        err.contains("bad.csv:2: frame 3 is not in")
            && err.contains("(3 frames read); ")
            && err.contains("and the files are numbered from 1"),
        "{err}"
    );
    // By name, or from files counted from 0, nothing to warn of.
    std::fs::write(&bad, "frame,tendon\nimg_1.png,1\n").unwrap();
    let r = import(&from_1, &bad, &dir.path().join("from-1-names"));
    assert!(r.status.success() && !String::from_utf8_lossy(&r.stderr).contains("numbered from 1"));
    let err = refused(&folder, "frame,tendon\n000001.PNG,1\n");
    assert!(
        err.contains("bad.csv:2: frame \"000001.PNG\" is not in")
            && err
                .contains("(3 frames read) (the folder has \"000001.png\": names differ by case)"),
        "{err}"
    );
    let err = refused(&folder, "frame,tendon\n000001.png,1\nframes/000001.png,0\n");
    assert!(
        err.contains("bad.csv:3: frame \"000001.png\" is labelled twice (also on line 2)"),
        "{err}"
    );
    // A labelled frame cut short behind its header is skipped by the
    // reader, so its row is refused as not read, with why.
    let whole = std::fs::read(folder.join("000002.png")).unwrap();
    let cut = dir.path().join("cut");
    std::fs::create_dir(&cut).unwrap();
    std::fs::copy(folder.join("000000.png"), cut.join("000000.png")).unwrap();
    std::fs::write(cut.join("000001.png"), &whole[..whole.len() / 2]).unwrap();
    let err = refused(&cut, "frame,tendon\n0,0\n1,1\n");
    assert!(
        err.contains("bad.csv:3: frame 1 is not in")
            && err.contains("(1 frames read); 1 of the 2 frames could not be decoded")
            && err.contains("000001.png: cannot decode image"),
        "{err}"
    );
    assert!(!dir.path().join("ds2").exists());
    let err = refused(&video, "frame,tendon,mask\n3,1,../../etc/passwd\n");
    assert!(
        err.contains("bad.csv:2") && err.contains("goes up with '..'"),
        "{err}"
    );
    // A 0/1 mask (as numpy's astype(uint8) saves one) would be read as
    // empty; a mask of another size would be resized into a wrong label.
    let (w, h) = (imgs[3].width(), imgs[3].height());
    let mut px = vec![0u8; w * h];
    px[w * 90..w * 91].fill(1);
    tactile_core::image_io::save_grey_png(dir.path().join("m01.png"), w, h, &px).unwrap();
    tactile_core::image_io::save_grey_png(dir.path().join("small.png"), 8, 8, &[255; 64]).unwrap();
    for (mask, why) in [
        (
            "m01.png",
            "largest value is 1: masks are 0 = background and 255 = tendon",
        ),
        ("small.png", &format!("is 8x8, its frame {w}x{h}")),
    ] {
        let err = refused(&video, &format!("frame,tendon,mask\n3,1,{mask}\n"));
        assert!(err.contains("bad.csv:2") && err.contains(why), "{err}");
    }
    assert!(
        !dir.path().join("ds2").exists(),
        "nothing left by a failed import"
    );
}

/// A file an HTTP server in this test serves: its path, content type,
/// bytes, and whether it says its length (a file) or not (a camera's
/// endless MJPEG stream, sent then closed).
struct Served {
    path: &'static str,
    content_type: &'static str,
    body: Vec<u8>,
    with_length: bool,
}

/// An HTTP server on a free port of 127.0.0.1 serving `files` (anything
/// else 404), each request on its own thread, for the rest of the test
/// process. Returns the port.
fn serve(files: Vec<Served>) -> u16 {
    use std::io::Read;
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let files = std::sync::Arc::new(files);
    std::thread::spawn(move || {
        for conn in listener.incoming() {
            let Ok(mut conn) = conn else { continue };
            let files = std::sync::Arc::clone(&files);
            std::thread::spawn(move || {
                let mut request = Vec::new();
                let mut buf = [0u8; 1024];
                while !request.windows(4).any(|w| w == b"\r\n\r\n") && request.len() < 16384 {
                    match conn.read(&mut buf) {
                        Ok(0) | Err(_) => return,
                        Ok(n) => request.extend_from_slice(&buf[..n]),
                    }
                }
                let request = String::from_utf8_lossy(&request);
                // The query (a camera's token) is not part of the file.
                let target = request.split(' ').nth(1).unwrap_or("");
                let path = target.split('?').next().unwrap_or("");
                let reply = match files.iter().find(|f| f.path == path) {
                    Some(f) if f.with_length => format!(
                        "HTTP/1.1 200 OK\r\nContent-Type: {}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                        f.content_type,
                        f.body.len()
                    ),
                    Some(f) => format!(
                        "HTTP/1.0 200 OK\r\nContent-Type: {}\r\nConnection: close\r\n\r\n",
                        f.content_type
                    ),
                    None => {
                        "HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"
                            .to_string()
                    }
                };
                let _ = conn.write_all(reply.as_bytes());
                if let Some(f) = files.iter().find(|f| f.path == path) {
                    let _ = conn.write_all(&f.body);
                }
            });
        }
    });
    port
}

#[test]
fn a_stream_served_to_one_client_once_is_refused_saying_how_to_read_it() {
    // ffprobe reads the stream for its size, and FFmpeg opens it again to
    // decode: a server that lets one client in (`ffmpeg … ?listen`) refuses
    // the second. Before, the error said only "Connection refused".
    use tactile_core::video::{VideoCodec, encode};
    let dir = tempfile::tempdir().unwrap();
    let imgs = images();
    let refs: Vec<_> = imgs.iter().collect();
    let clip = dir.path().join("clip.mkv");
    encode(&refs, 30, VideoCodec::Mjpeg, &clip).unwrap();
    let bytes = std::fs::read(&clip).unwrap();
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    std::thread::spawn(move || {
        let conn = listener.accept();
        // Closed before the first client is served: the next is refused.
        drop(listener);
        if let Ok((mut conn, _)) = conn {
            let _ = conn.write_all(&bytes);
        }
    });
    let out = tactile()
        .args(["run", "--models", MODELS, "--out", "-", "--data"])
        .arg(format!("tcp://127.0.0.1:{port}"))
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    let (w, h) = (imgs[0].width(), imgs[0].height());
    assert!(!out.status.success() && out.stdout.is_empty(), "{err}");
    assert!(
        err.contains("the stream answered ffprobe but not FFmpeg after it")
            && err.contains(&format!("tactile run --stdin --size {w}x{h}")),
        "{err}"
    );
}

#[test]
fn a_streams_url_is_read_through_ffmpeg_every_frame_when_it_has_a_length() {
    // Before, a URL was refused ("a URL, not a file; … through FFmpeg on
    // standard input").
    use tactile_core::video::{VideoCodec, encode};
    let dir = tempfile::tempdir().unwrap();
    let imgs = images();
    let refs: Vec<_> = imgs.iter().collect();
    let clip = dir.path().join("clip.mkv");
    encode(&refs, 30, VideoCodec::H264LosslessRgb, &clip).unwrap();
    // A camera's MJPEG over HTTP (mjpg-streamer's, FFmpeg's `mpjpeg`): no
    // length, so live.
    let live = dir.path().join("live.mjpg");
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(&clip)
        .args(["-c:v", "mjpeg", "-q:v", "2", "-f", "mpjpeg"])
        .arg(&live)
        .status()
        .unwrap();
    assert!(status.success());
    // A playlist that points at a file of this machine.
    let sneaky = format!(
        "#EXTM3U\n#EXT-X-TARGETDURATION:2\n#EXTINF:2,\nfile://{}\n#EXT-X-ENDLIST\n",
        clip.display()
    );
    let port = serve(vec![
        Served {
            path: "/clip.mkv",
            content_type: "video/x-matroska",
            body: std::fs::read(&clip).unwrap(),
            with_length: true,
        },
        Served {
            path: "/live.mjpg",
            content_type: "multipart/x-mixed-replace;boundary=ffmpeg",
            body: std::fs::read(&live).unwrap(),
            with_length: false,
        },
        Served {
            path: "/list.m3u8",
            content_type: "application/vnd.apple.mpegurl",
            body: sneaky.into_bytes(),
            with_length: true,
        },
    ]);
    let url = |path: &str| format!("http://127.0.0.1:{port}{path}");
    let expected = reference();

    // A file served over HTTP: recorded, every frame, the same records.
    let (records, summary, _) = run(&["--data", &url("/clip.mkv")], None);
    assert_eq!(summary["source"], "video");
    assert_eq!(summary["frames"], imgs.len() as u64, "every frame");
    assert_agree(&expected, &records, 0.0);

    // A URL longer than a path may be (a signed URL's tokens) is still a
    // URL (before, "File name too long").
    let token = format!("/clip.mkv?token={}", "t".repeat(5000));
    let (records, summary, _) = run(&["--data", &url(&token)], None);
    assert_eq!(summary["source"], "video");
    assert_agree(&expected, &records, 0.0);

    // A camera's stream: live, each frame given or counted as dropped,
    // each given one decided as its own frame was.
    let (records, summary, _) = run(&["--data", &url("/live.mjpg")], None);
    assert_eq!(summary["source"], "stream");
    let given = summary["frames"].as_u64().unwrap();
    let dropped = summary["dropped_frames"].as_u64().unwrap();
    assert!(
        given >= 1 && given + dropped == imgs.len() as u64,
        "{summary}"
    );
    for r in &records {
        let i: usize = r["frame"].as_str().unwrap().parse().unwrap();
        assert_eq!(r["tendon"], expected[i]["tendon"], "frame {i}");
    }

    // A live stream cannot become a dataset: its dropped frames would
    // shift the labels' frame numbers.
    let labels = dir.path().join("labels.csv");
    std::fs::write(&labels, "frame,tendon\n0,1\n").unwrap();
    let ds = dir.path().join("ds");
    let out = tactile()
        .args(["dataset", "from-video", "--kind", "visuotactile", "--video"])
        .arg(url("/live.mjpg"))
        .arg("--labels")
        .arg(&labels)
        .arg("--out")
        .arg(&ds)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success()
            && err
                .contains("a live source (a camera or a network stream), whose frames are dropped")
            && !ds.exists(),
        "{err}"
    );

    // Refused, naming the URL with its password hidden, FFmpeg's words
    // included; a playlist that leads to a file reads nothing.
    for (data, want) in [
        (
            format!("http://robot:s3cret@127.0.0.1:{port}/none.mkv"),
            format!("http://robot:***@127.0.0.1:{port}/none.mkv: cannot read the stream"),
        ),
        (url("/list.m3u8"), format!("{}: cannot read the stream", url("/list.m3u8"))),
        (
            "file:///tmp/frames.mkv".into(),
            "file:///tmp/frames.mkv: file:// URLs are not read: give the file's path itself".into(),
        ),
        (
            "ftp://lab/frames.mkv".into(),
            "ftp://lab/frames.mkv: ftp:// URLs are not read: a stream is read from rtsp://, rtsps://, http://".into(),
        ),
        (
            "rtsp://127.0.0.1:1/stream".into(),
            "rtsp://127.0.0.1:1/stream: cannot read the stream".into(),
        ),
    ] {
        let out = tactile()
            .args(["run", "--models", MODELS, "--out", "-", "--data", &data])
            .stdin(Stdio::null())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{data}: {err}");
        assert!(out.stdout.is_empty(), "{data}: no records");
        assert!(err.contains(&want), "{data}: {err}");
        assert!(!err.contains("s3cret"), "{data}: {err}");
    }
}
