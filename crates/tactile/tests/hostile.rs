#![allow(clippy::unwrap_used)]
//! The command line against careless and hostile input (issue 16): every
//! command runs under `ulimit -v 4000000` (about 4 GB of address space),
//! so an allocation sized from a file or a flag aborts the test instead of
//! passing; each case must end with a clear error (never a panic, an abort
//! or a hang), read nothing outside the dataset, and leave every file it
//! did not make as it was.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_tactile")
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The project's real sensor data (`../shared/real` beside the clone, or
/// TACTILE_SHARED_REAL).
fn shared_real() -> PathBuf {
    std::env::var_os("TACTILE_SHARED_REAL")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("../shared/real"))
}

/// One network of the shipped detector (its first member when it is an
/// ensemble), for tests that edit a detector's config.
fn shipped_network() -> PathBuf {
    let d = root().join("models/detector");
    match d.join("ensemble.json").is_file() {
        true => d.join("member-0"),
        false => d,
    }
}

/// Run `command`: its exit and its standard output then error as text.
fn run(command: &mut Command) -> (std::process::ExitStatus, String) {
    let out = command.output().unwrap();
    let msg = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status, msg)
}

/// Run `tactile args` under the address-space limit: (success, output).
fn tactile(args: &[&str]) -> (bool, String) {
    tactile_under("ulimit -v 4000000", args)
}

/// Run `tactile args` after the shell commands `limits` (`ulimit`s, a
/// `trap`): (success, output), never a panic, an abort or a signal.
fn tactile_under(limits: &str, args: &[&str]) -> (bool, String) {
    let (status, msg) = run(Command::new("bash")
        .arg("-c")
        .arg(format!("{limits}; exec \"$@\""))
        .arg("tactile")
        .arg(bin())
        .args(args));
    assert!(
        !msg.contains("panicked") && !msg.contains("memory allocation"),
        "{args:?} panicked or aborted:\n{msg}"
    );
    assert!(
        status.code().is_some(),
        "{args:?} died of a signal ({status:?}):\n{msg}"
    );
    (status.success(), msg)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn png(path: &Path, w: u32, h: u32) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    image::GrayImage::from_pixel(w, h, image::Luma([0u8]))
        .save(path)
        .unwrap();
}

/// A TacTip dataset of `n` black 300x300 frames with these label rows
/// (`file` first); `n` frames are written as frames/0.png...
fn tactip(dir: &Path, n: usize, rows: &[String]) {
    std::fs::create_dir_all(dir).unwrap();
    for i in 0..n {
        png(&dir.join(format!("frames/{i}.png")), 300, 300);
    }
    let mut labels = String::from("file,shape,x_mm,y_mm,theta_deg,depth_mm,force_n\n");
    for r in rows {
        labels.push_str(r);
        labels.push('\n');
    }
    std::fs::write(dir.join("labels.csv"), labels).unwrap();
    std::fs::write(
        dir.join("manifest.json"),
        format!(r#"{{"format":"tactile-dataset/1","kind":"tactip","sensor_spec":"test","width":300,"height":300,"generator":"test","seed":1,"count":{}}}"#, rows.len()),
    )
    .unwrap();
}

fn row(file: &str) -> String {
    format!("{file},sphere,0,0,0,1,1")
}

/// A small visuo-tactile dataset made by the virtual sensor.
fn palpations(dir: &Path, sequences: &str, frames: &str, seed: &str) {
    let (ok, msg) = tactile(&[
        "synth",
        "visuotactile",
        "--sequences",
        sequences,
        "--frames-per-sequence",
        frames,
        "--seed",
        seed,
        "--out",
        s(dir),
    ]);
    assert!(ok, "{msg}");
}

fn encode(data: &Path, out: &Path) -> (bool, String) {
    let model = root().join("models/cae-shapes");
    tactile(&[
        "encode",
        "--model",
        s(&model),
        "--data",
        s(data),
        "--out",
        s(out),
    ])
}

#[test]
fn reads_stay_inside_the_dataset_and_do_not_reveal_outside_files() {
    let tmp = tempfile::tempdir().unwrap();
    let outside = tmp.path().join("secret.png");
    png(&outside, 300, 300);
    let ds = tmp.path().join("ds");
    let out = tmp.path().join("f.csv");
    let cases: Vec<(String, &str)> = vec![
        ("../secret.png".into(), "goes up with '..'"),
        ("../missing.png".into(), "goes up with '..'"),
        (s(&outside).into(), "is absolute"),
        ("/definitely/not/here.png".into(), "is absolute"),
    ];
    for (file, why) in &cases {
        let _ = std::fs::remove_dir_all(&ds);
        tactip(&ds, 1, &[row("frames/0.png"), row(file)]);
        let (ok, msg) = encode(&ds, &out);
        assert!(
            !ok && msg.contains("labels.csv:3") && msg.contains(why),
            "{file}: {msg}"
        );
        assert!(!msg.contains("does not exist"), "{file}: {msg}");
        assert!(!out.exists());
    }
    // A symbolic link under frames/ that leaves: the same answer whether
    // its target exists or not.
    for target in [outside.clone(), tmp.path().join("missing.png")] {
        let _ = std::fs::remove_dir_all(&ds);
        tactip(&ds, 1, &[row("frames/0.png"), row("frames/link.png")]);
        std::os::unix::fs::symlink(&target, ds.join("frames/link.png")).unwrap();
        let (ok, msg) = encode(&ds, &out);
        assert!(
            !ok && msg.contains("labels.csv:3")
                && msg.contains("leaves the dataset folder")
                && msg.contains("move the whole dataset folder there and link to it"),
            "{msg}"
        );
        assert!(!msg.contains("does not exist"), "{msg}");
    }
    // What that error advises: a link to the whole dataset folder is read.
    let _ = std::fs::remove_dir_all(&ds);
    tactip(&ds, 1, &[row("frames/0.png")]);
    let linked = tmp.path().join("linked-dataset");
    std::os::unix::fs::symlink(&ds, &linked).unwrap();
    let (ok, msg) = encode(&linked, &out);
    assert!(ok && out.exists(), "{msg}");
    std::fs::remove_file(&out).unwrap();
    // A folder of frames without labels.csv bounds its reads alike: a link
    // out is refused by its name, a link to a frame beside it is read.
    let folder = tmp.path().join("folder");
    std::fs::create_dir_all(&folder).unwrap();
    png(&folder.join("0.png"), 300, 300);
    std::os::unix::fs::symlink("0.png", folder.join("1.png")).unwrap();
    let predict = |out: &Path| {
        let model = root().join("models/cae-shapes");
        tactile(&[
            "predict",
            "--model",
            s(&model),
            "--data",
            s(&folder),
            "--out",
            s(out),
        ])
    };
    let (ok, msg) = predict(&out);
    assert!(ok, "{msg}");
    let rows = std::fs::read_to_string(&out).unwrap().lines().count();
    assert_eq!(rows, 3, "a header and two frames");
    std::fs::remove_file(&out).unwrap();
    std::os::unix::fs::symlink(&outside, folder.join("2.png")).unwrap();
    let (ok, msg) = predict(&out);
    assert!(
        !ok && msg.contains("2.png") && msg.contains("leaves the folder"),
        "{msg}"
    );
    assert!(!out.exists());
    std::fs::remove_file(folder.join("2.png")).unwrap();
    // An output named like one of its frames (itself, through a link, or a
    // new one) is refused before any work; the frames stay as they were.
    let frame = std::fs::read(folder.join("0.png")).unwrap();
    for name in ["0.png", "1.png", "3.png"] {
        let (ok, msg) = predict(&folder.join(name));
        assert!(
            !ok && msg.contains(name) && msg.contains("named like a frame of the input folder"),
            "{msg}"
        );
    }
    assert_eq!(std::fs::read(folder.join("0.png")).unwrap(), frame);
    assert!(!folder.join("3.png").exists());
    // A column named twice is an error, not "the last one wins".
    let _ = std::fs::remove_dir_all(&ds);
    tactip(&ds, 1, &[row("frames/0.png")]);
    std::fs::write(
        ds.join("labels.csv"),
        "file,shape,x_mm,y_mm,theta_deg,depth_mm,force_n,file\nframes/0.png,sphere,0,0,0,1,1,../secret.png\n",
    )
    .unwrap();
    let (ok, msg) = encode(&ds, &out);
    assert!(
        !ok && msg.contains("labels.csv:1") && msg.contains("'file' appears twice"),
        "{msg}"
    );
}

#[test]
fn what_a_dataset_says_must_agree_with_what_it_holds() {
    let tmp = tempfile::tempdir().unwrap();
    // A TacTip frame of another size than the manifest's.
    let ds = tmp.path().join("ds");
    tactip(&ds, 2, &[row("frames/0.png"), row("frames/1.png")]);
    png(&ds.join("frames/1.png"), 320, 300);
    let (ok, msg) = encode(&ds, &tmp.path().join("f.csv"));
    assert!(
        !ok && msg.contains("frames/1.png")
            && msg.contains("320x300")
            && msg.contains("manifest.json says"),
        "{msg}"
    );
    // A transposed depth map and a mask of the wrong size beside 640x360 frames.
    let vt = tmp.path().join("vt");
    palpations(&vt, "1", "4", "3");
    let depth = vt.join("depth/000001.npy");
    let bytes = std::fs::read(&depth).unwrap();
    let at = bytes.windows(10).position(|w| w == b"(360, 640)").unwrap();
    let mut t = bytes.clone();
    t[at..at + 10].copy_from_slice(b"(640, 360)");
    std::fs::write(&depth, t).unwrap();
    let model = root().join("models/depth");
    let (ok, msg) = tactile(&["eval", "depth", "--model", s(&model), "--data", s(&vt)]);
    assert!(
        !ok && msg.contains("000001.npy") && msg.contains("360x640"),
        "{msg}"
    );
    std::fs::write(&depth, bytes).unwrap();
    image::GrayImage::from_pixel(320, 180, image::Luma([0u8]))
        .save(vt.join("masks/000002.png"))
        .unwrap();
    let (ok, msg) = tactile(&["eval", "depth", "--model", s(&model), "--data", s(&vt)]);
    assert!(
        !ok && msg.contains("masks/000002.png") && msg.contains("320x180"),
        "{msg}"
    );
}

/// An `.npy` header for a float32 array of `shape`, version 1.
fn npy_header(shape: &str) -> Vec<u8> {
    npy_header_of("<f4", shape)
}

/// The same of `descr` values (`|u1`: bytes).
fn npy_header_of(descr: &str, shape: &str) -> Vec<u8> {
    let mut h = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + h.len() + 1) % 64 != 0 {
        h.push(' ');
    }
    h.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend((h.len() as u16).to_le_bytes());
    out.extend(h.as_bytes());
    out
}

#[test]
fn every_size_is_bounded_before_anything_is_allocated() {
    let tmp = tempfile::tempdir().unwrap();
    let vt = tmp.path().join("vt");
    palpations(&vt, "1", "3", "4");
    let model = root().join("models/depth");
    let eval_depth = || tactile(&["eval", "depth", "--model", s(&model), "--data", s(&vt)]);
    // A 200-byte .npy claiming 100000 x 100000 floats; a version-2 header
    // claiming 4 GB of header.
    let depth = vt.join("depth/000000.npy");
    std::fs::write(&depth, npy_header("(100000, 100000)")).unwrap();
    let (ok, msg) = eval_depth();
    assert!(!ok && msg.contains("000000.npy"), "{msg}");
    let mut v2 = b"\x93NUMPY\x02\x00".to_vec();
    v2.extend(u32::MAX.to_le_bytes());
    v2.extend([b' '; 100]);
    std::fs::write(&depth, v2).unwrap();
    let (ok, msg) = eval_depth();
    assert!(
        !ok && msg.contains("000000.npy") && msg.contains("header"),
        "{msg}"
    );
    // Depth values no camera sees: refused naming the file and the pixel.
    let mut far = npy_header("(360, 640)");
    for i in 0..360 * 640 {
        let v: f32 = if i == 7 { 1e36 } else { 0.015 };
        far.extend(v.to_le_bytes());
    }
    std::fs::write(&depth, far).unwrap();
    let (ok, msg) = eval_depth();
    assert!(
        !ok && msg.contains("000000.npy") && msg.contains("pixel (7, 0)"),
        "{msg}"
    );
    // A detector config with width 1e9: refused naming the file and the field.
    let det = tmp.path().join("det");
    std::fs::create_dir(&det).unwrap();
    let shipped = shipped_network();
    let text = std::fs::read_to_string(shipped.join("detector.json")).unwrap();
    std::fs::write(
        det.join("detector.json"),
        text.replace("\"width\": 0.5", "\"width\": 1e9"),
    )
    .unwrap();
    std::fs::copy(shipped.join("detector.bpk"), det.join("detector.bpk")).unwrap();
    let (ok, msg) = tactile(&["eval", "detector", "--model", s(&det), "--data", s(&vt)]);
    assert!(
        !ok && msg.contains("detector.json") && msg.contains("width"),
        "{msg}"
    );
    // A JSON file claiming a terabyte (sparse, so it costs nothing on
    // disk): refused by its size, naming it, before it is read.
    let sparse = |p: &Path, len: u64| std::fs::File::create(p).unwrap().set_len(len).unwrap();
    sparse(&det.join("detector.json"), 1 << 40);
    let (ok, msg) = tactile(&["eval", "detector", "--model", s(&det), "--data", s(&vt)]);
    assert!(
        !ok && msg.contains("detector.json") && msg.contains("too large"),
        "{msg}"
    );
    // Weights claiming 32 GB, under burn's own 100 GB bound: refused by
    // the toolkit's (1 GiB) before burn reads them.
    std::fs::write(det.join("detector.json"), &text).unwrap();
    sparse(&det.join("detector.bpk"), 1 << 35);
    let (ok, msg) = tactile(&["eval", "detector", "--model", s(&det), "--data", s(&vt)]);
    assert!(
        !ok && msg.contains("detector.bpk") && msg.contains("too large"),
        "{msg}"
    );
    // A labels.csv of a terabyte of zeros (no line end), refused at the
    // record bound, and a manifest.json claiming a terabyte, refused by its
    // size: each named.
    for (name, kept, why) in [
        ("labels.csv", "manifest.json", "a record longer than"),
        ("manifest.json", "labels.csv", "too large"),
    ] {
        let ds = tmp.path().join(format!("sparse-{name}"));
        std::fs::create_dir(&ds).unwrap();
        std::fs::copy(vt.join(kept), ds.join(kept)).unwrap();
        sparse(&ds.join(name), 1 << 40);
        let (ok, msg) = tactile(&["eval", "depth", "--model", s(&model), "--data", s(&ds)]);
        assert!(!ok && msg.contains(name) && msg.contains(why), "{msg}");
    }
    // Counts near 2^63 are refused, not wrapped.
    let out = tmp.path().join("huge");
    for args in [
        vec![
            "synth",
            "visuotactile",
            "--sequences",
            "9223372036854775807",
            "--out",
            s(&out),
        ],
        vec![
            "synth",
            "tactip",
            "--count",
            "9223372036854775807",
            "--out",
            s(&out),
        ],
        vec!["run", "--data", s(&vt), "--threads", "100000"],
    ] {
        let (ok, msg) = tactile(&args);
        assert!(!ok, "{args:?}: {msg}");
    }
    assert!(!out.exists());
    // So are timed runs and bench frames that would be held in memory (each
    // run's time until the median) or written to disk: before, `--runs
    // 4000000000` aborted on a 32 GB allocation.
    let detector = root().join("models/detector");
    let page = tmp.path().join("page.md");
    for (args, why) in [
        (
            vec![
                "bench",
                "detector",
                "--models",
                s(&detector),
                "--data",
                s(&vt),
                "--runs",
                "4000000000",
            ],
            "timed runs: must be 1 to 100000",
        ),
        (
            vec!["bench", "synth", "--frames", "1000000000000"],
            "frames: must be 1 to 10000",
        ),
        // A folder that is no calibration is named before any measurement.
        (
            vec![
                "bench",
                "synth",
                "--frames",
                "2",
                "--sensor",
                s(&vt),
                "--out",
                s(&page),
            ],
            "optics.json: no render model here",
        ),
        (
            vec!["report", "--runs", "1000000000000", "--out", s(&page)],
            "timed runs: must be 1 to 100000",
        ),
    ] {
        let (ok, msg) = tactile(&args);
        assert!(!ok && msg.contains(why), "{args:?}: {msg}");
    }
    assert!(!page.exists());
    // Frames named by nanosecond timestamps: the gap is counted, not listed.
    let video = tmp.path().join("video");
    std::fs::create_dir(&video).unwrap();
    for n in ["1700000000000000000", "1700000000033333333"] {
        std::fs::copy(vt.join("frames/000001.png"), video.join(format!("{n}.png"))).unwrap();
    }
    let models = root().join("models");
    let t0 = Instant::now();
    let (ok, msg) = tactile(&["run", "--data", s(&video), "--models", s(&models)]);
    assert!(ok && msg.contains("33333332 frame(s) missing"), "{msg}");
    assert!(t0.elapsed() < Duration::from_secs(60));
}

/// A zip's end records alone, claiming a billion entries at a terabyte's
/// offset.
fn zip_claiming_a_billion_entries() -> Vec<u8> {
    let mut zip64_end = Vec::new();
    for (v, n) in [
        (0x0606_4b50u64, 4),
        (44, 8),
        (45, 2),
        (45, 2),
        (0, 4),
        (0, 4),
        (1_000_000_000, 8),
        (1_000_000_000, 8),
        (1_000_000, 8),
        (1_000_000_000_000, 8),
        (0x0706_4b50, 4),
        (0, 4),
        (0, 8),
        (1, 4),
        (0x0605_4b50, 4),
        (0, 2),
        (0, 2),
        (0xFFFF, 2),
        (0xFFFF, 2),
        (0xFFFF_FFFF, 4),
        (0xFFFF_FFFF, 4),
        (0, 2),
    ] {
        zip64_end.extend(&v.to_le_bytes()[..n]);
    }
    zip64_end
}

#[test]
fn a_gs_sdk_label_claiming_more_than_it_holds_is_refused_before_it_is_read() {
    // gs_sdk's calibration folder with each press's label.npz (a zip of
    // .npy arrays) crafted: a zip end record claiming a billion entries at
    // a terabyte's offset, an array that inflates to 60 MB, an array whose
    // header claims 2^62 x 2^62 values. Each is refused naming the label
    // (zip's and the array's sizes checked before anything is allocated),
    // and no model folder is made.
    use std::io::Write;
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("gs");
    let ball = shared_real().join("gelsight-ball");
    std::fs::create_dir_all(&d).unwrap();
    std::fs::copy(ball.join("background.png"), d.join("background.png")).unwrap();
    std::fs::write(d.join("sensor.json"), r#"{"mm_per_px": 0.0295}"#).unwrap();
    let mut catalog = String::from("experiment_reldir,diameter(mm)\n");
    let mut frames: Vec<PathBuf> = std::fs::read_dir(ball.join("frames"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    frames.sort();
    for (i, frame) in frames.iter().take(6).enumerate() {
        let press = d.join(format!("4.000mm/{i}"));
        std::fs::create_dir_all(&press).unwrap();
        std::fs::copy(frame, press.join("gelsight.png")).unwrap();
        catalog.push_str(&format!("4.000mm/{i},4.000\n"));
    }
    std::fs::write(d.join("catalog.csv"), catalog).unwrap();
    let label = d.join("4.000mm/2/label.npz");
    let zip64_end = zip_claiming_a_billion_entries();
    // An archive whose `center` is `bytes` (its `radius` one zero).
    let array = |method, bytes: &[u8]| {
        let mut z = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let opts = zip::write::SimpleFileOptions::default().compression_method(method);
        z.start_file("center.npy", opts).unwrap();
        z.write_all(bytes).unwrap();
        z.start_file("radius.npy", opts).unwrap();
        z.write_all(&[0]).unwrap();
        z.finish().unwrap().into_inner()
    };
    let mut huge = npy_header("(4611686018427387904, 4611686018427387904)");
    huge.extend([0u8; 16]);
    let inflating = array(zip::CompressionMethod::Deflated, &vec![0u8; 60 << 20]);
    assert!(inflating.len() < 64 << 10, "{}", inflating.len());
    calibration_refuses(
        &d,
        &label,
        "4.000mm/2/label.npz",
        vec![
            (zip64_end, "not a NumPy .npz archive"),
            (inflating, "its 'center':"),
            (
                array(zip::CompressionMethod::Stored, &huge),
                "its 'center': holds more numbers",
            ),
        ],
    );
}

/// `tactile calibrate ball --data data` with `file` holding each case's
/// bytes in turn: refused, naming `named` and saying the case's words, and
/// no model folder made.
fn calibration_refuses(data: &Path, file: &Path, named: &str, cases: Vec<(Vec<u8>, &str)>) {
    let out = data.with_file_name("model");
    for (bytes, said) in cases {
        std::fs::write(file, bytes).unwrap();
        let (ok, msg) = tactile(&["calibrate", "ball", "--data", s(data), "--out", s(&out)]);
        assert!(
            !ok && msg.contains(named) && msg.contains(said),
            "{said}: {msg}"
        );
        assert!(!out.exists());
    }
}

#[test]
fn a_taxim_pack_claiming_more_than_it_holds_is_refused_before_it_is_read() {
    // Taxim's dataPack.npz crafted: presses claimed by the terabyte, frames
    // of 12 GB in all, a header claiming 4 GB of itself, frames cut short,
    // a zip end record claiming a billion entries, circles inflating to
    // 60 MB. Each is refused naming the pack (every size checked before
    // anything is allocated), and no model folder is made.
    use std::io::Write;
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("taxim");
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(
        d.join("sensor.json"),
        r#"{"ball_diameter_mm": 4.0, "mm_per_px": 0.0295}"#,
    )
    .unwrap();
    let bg = image::open(shared_real().join("gelsight-ball/background.png"))
        .unwrap()
        .to_rgb8();
    let f0 = |w: u32, h: u32| {
        let mut v = npy_header_of("|u1", &format!("({h}, {w}, 3)"));
        let scaled = image::imageops::resize(&bg, w, h, image::imageops::FilterType::Triangle);
        v.extend(scaled.into_raw());
        v
    };
    let pack = |arrays: Vec<(&str, Vec<u8>)>| {
        let mut z = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        for (name, bytes) in arrays {
            z.start_file(format!("{name}.npy"), opts).unwrap();
            z.write_all(&bytes).unwrap();
        }
        z.finish().unwrap().into_inner()
    };
    let imgs = |shape: &str, frames: usize| {
        let mut v = npy_header_of("|u1", shape);
        v.extend(vec![128u8; frames * 640 * 480 * 3]);
        v
    };
    let mut wide_header = b"\x93NUMPY\x02\x00".to_vec();
    wide_header.extend(u32::MAX.to_le_bytes());
    let zip64_end = zip_claiming_a_billion_entries();
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (
            pack(vec![
                ("f0", f0(640, 480)),
                ("imgs", imgs("(1099511627776, 480, 640, 3)", 0)),
            ]),
            "its 'imgs': holds 1099511627776 presses, more than 2000",
        ),
        (
            pack(vec![
                ("f0", f0(1920, 1080)),
                ("imgs", npy_header_of("|u1", "(1000, 1080, 1920, 3)")),
            ]),
            "its 'imgs': holds 1000 frames of 1920x1080: more than 2 GB of presses",
        ),
        (
            pack(vec![("f0", f0(640, 480)), ("imgs", wide_header)]),
            "its 'imgs': its .npy header claims 4294967295 bytes",
        ),
        (
            pack(vec![
                ("f0", f0(640, 480)),
                ("imgs", imgs("(10, 480, 640, 3)", 2)),
            ]),
            "its 'imgs': ends after 2 of its 10 frames",
        ),
        (zip64_end, "not a NumPy .npz archive"),
        (
            pack(vec![
                ("f0", f0(640, 480)),
                ("imgs", imgs("(1, 480, 640, 3)", 1)),
                ("touch_center", vec![0u8; 60 << 20]),
                ("touch_radius", vec![0u8; 8]),
            ]),
            "its 'touch_center': 62914560 bytes: far more than 2 numbers",
        ),
    ];
    calibration_refuses(&d, &d.join("dataPack.npz"), "taxim/dataPack.npz", cases);
}

#[test]
fn nothing_panics_on_empty_datasets_bad_configs_or_a_closed_stdout() {
    let tmp = tempfile::tempdir().unwrap();
    let empty = tmp.path().join("empty");
    tactip(&empty, 0, &[]);
    let enc = root().join("models/cae-shapes");
    for args in [
        vec![
            "train",
            "head",
            "--encoder",
            s(&enc),
            "--data",
            s(&empty),
            "--out",
            s(&tmp.path().join("h")),
        ],
        vec!["bench", "cae", "--model", s(&enc), "--data", s(&empty)],
        vec!["evaluate", "--encoder", s(&enc), "--data", s(&empty)],
        vec![
            "train",
            "cae",
            "--data",
            s(&empty),
            "--out",
            s(&tmp.path().join("c")),
        ],
        vec![
            "compare",
            "--encoder",
            s(&enc),
            "--data",
            s(&empty),
            "--classify",
            "shape",
        ],
        vec![
            "train",
            "pose",
            "--data",
            s(&empty),
            "--out",
            s(&tmp.path().join("p")),
        ],
    ] {
        let (ok, msg) = tactile(&args);
        assert!(!ok, "{args:?}: {msg}");
    }
    // Zero widths are refused before a model is saved.
    let ds = tmp.path().join("ds");
    tactip(&ds, 2, &[row("frames/0.png"), row("frames/1.png")]);
    let cae = tmp.path().join("cae");
    let (ok, msg) = tactile(&[
        "train",
        "cae",
        "--data",
        s(&ds),
        "--out",
        s(&cae),
        "--widths",
        "0,8,8,4",
    ]);
    assert!(!ok && msg.contains("widths"), "{msg}");
    assert!(!cae.exists());
    // Channel statistics of the wrong length in a model config.
    let seg = tmp.path().join("seg");
    std::fs::create_dir(&seg).unwrap();
    let shipped = root().join("models/segmenter");
    let mut j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(shipped.join("segmenter.json")).unwrap())
            .unwrap();
    j["stats"]["mean"] = serde_json::json!([0.5, 0.5]);
    std::fs::write(seg.join("segmenter.json"), j.to_string()).unwrap();
    std::fs::copy(shipped.join("segmenter.bpk"), seg.join("segmenter.bpk")).unwrap();
    let vt = tmp.path().join("vt");
    palpations(&vt, "1", "4", "5");
    let (ok, msg) = tactile(&["eval", "segmenter", "--model", s(&seg), "--data", s(&vt)]);
    assert!(
        !ok && msg.contains("segmenter.json") && msg.contains("2 means"),
        "{msg}"
    );
    // A live-view wait that is no number of seconds is refused before
    // anything is served or read (it silently meant no wait).
    for wait in ["--view-wait=nan", "--view-wait=-1", "--view-wait=inf"] {
        let (ok, msg) = tactile(&[
            "run",
            "--data",
            s(&vt),
            "--models",
            s(&root().join("models")),
            "--view",
            "127.0.0.1:0",
            wait,
        ]);
        assert!(
            !ok && msg.contains("--view-wait: seconds must be a finite number >= 0")
                && !msg.contains("live view:"),
            "{wait}: {msg}"
        );
    }
    // A closed stdout ends the run quietly.
    let mut child = Command::new(bin())
        .args([
            "run",
            "--data",
            s(&vt),
            "--models",
            s(&root().join("models")),
        ])
        .args(["--runtime", "burn-flex"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && !err.contains("panicked"), "{err}");
}

#[test]
fn models_and_labels_are_checked_when_loaded() {
    let tmp = tempfile::tempdir().unwrap();
    let vt = tmp.path().join("vt");
    palpations(&vt, "1", "4", "6");
    let shipped = shipped_network();
    let json = std::fs::read_to_string(shipped.join("detector.json")).unwrap();
    let det = tmp.path().join("det");
    std::fs::create_dir(&det).unwrap();
    std::fs::copy(shipped.join("detector.bpk"), det.join("detector.bpk")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    for (field, to, why) in [
        ("/threshold", 1.5, "threshold"),
        ("/stats/std/0", 0.0, "standard deviation"),
    ] {
        let mut bad = json.clone();
        *bad.pointer_mut(field).unwrap() = to.into();
        std::fs::write(det.join("detector.json"), bad.to_string()).unwrap();
        let (ok, msg) = tactile(&["eval", "detector", "--model", s(&det), "--data", s(&vt)]);
        assert!(
            !ok && msg.contains("detector.json") && msg.contains(why),
            "{msg}"
        );
    }
    // A weight that is not a number: refused at load, naming the file.
    let seg = tmp.path().join("seg");
    std::fs::create_dir(&seg).unwrap();
    let shipped = root().join("models/segmenter");
    std::fs::copy(shipped.join("segmenter.json"), seg.join("segmenter.json")).unwrap();
    let mut w = std::fs::read(shipped.join("segmenter.bpk")).unwrap();
    let n = w.len();
    w[n - 4..].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(seg.join("segmenter.bpk"), w).unwrap();
    let (ok, msg) = tactile(&["eval", "segmenter", "--model", s(&seg), "--data", s(&vt)]);
    assert!(
        !ok && msg.contains("segmenter.bpk") && msg.contains("NaN"),
        "{msg}"
    );
    // The wrong folder for a model: what it holds is named (the model
    // inside it, or its own configuration).
    let (ok, msg) = tactile(&[
        "eval",
        "segmenter",
        "--model",
        s(&root().join("models")),
        "--data",
        s(&vt),
    ]);
    assert!(
        !ok && msg.contains(
            "not a segmenter folder (no segmenter.json; the folder segmenter in it is: pass it)"
        ),
        "{msg}"
    );
    let (ok, msg) = tactile(&["eval", "depth", "--model", s(&seg), "--data", s(&vt)]);
    assert!(
        !ok && msg.contains("no depth.json; it holds segmenter.json: a model of another kind"),
        "{msg}"
    );
    // A head trained on another encoder is refused by perceive.
    let synth = root().join("models/cae-synth");
    let shapes_head = root().join("models/cae-shapes/head");
    let frames = root().join("samples/virtual-tactip");
    let (ok, msg) = tactile(&[
        "perceive",
        "--encoder",
        s(&synth),
        "--heads",
        s(&shapes_head),
        "--data",
        s(&frames),
    ]);
    assert!(!ok && msg.contains("another encoder"), "{msg}");
}

#[test]
fn outputs_never_corrupt_destroy_or_half_exist() {
    let tmp = tempfile::tempdir().unwrap();
    // An output that is one of the inputs is refused before any work.
    let ds = tmp.path().join("ds");
    tactip(&ds, 1, &[row("frames/0.png")]);
    // `--out -` is standard output only where a command streams there;
    // elsewhere it was a file named `-` in the working folder.
    let (status, msg) = run(Command::new(bin())
        .current_dir(tmp.path())
        .args(["encode", "--model", s(&root().join("models/cae-shapes"))])
        .args(["--data", s(&ds), "--out", "-"]));
    assert!(
        !status.success() && msg.contains("-: this output cannot go to standard output"),
        "{msg}"
    );
    assert!(!tmp.path().join("-").exists());
    let labels = std::fs::read_to_string(ds.join("labels.csv")).unwrap();
    let (ok, msg) = encode(&ds, &ds.join("labels.csv"));
    assert!(!ok && msg.contains("part of the input dataset"), "{msg}");
    assert_eq!(
        std::fs::read_to_string(ds.join("labels.csv")).unwrap(),
        labels
    );
    // Nor does an output replace a model's config, notes or weights, named
    // or beside a bench page; its other files and new ones may be written.
    let m = tmp.path().join("m");
    std::fs::create_dir(&m).unwrap();
    for f in ["pose.json", "pose.bpk", "training.json", "curves.csv"] {
        std::fs::copy(root().join("models/pose-edge").join(f), m.join(f)).unwrap();
    }
    let config = std::fs::read(m.join("pose.json")).unwrap();
    let predict = |out: &Path| {
        tactile(&[
            "predict",
            "--model",
            s(&m),
            "--data",
            s(&ds),
            "--out",
            s(out),
        ])
    };
    for out in ["pose.json", "pose.bpk", "training.json"] {
        let (ok, msg) = predict(&m.join(out));
        assert!(
            !ok && msg.contains("is a file of the model in"),
            "{out}: {msg}"
        );
    }
    let (ok, msg) = tactile(&["export", "--model", s(&m), "--out", s(&m.join("pose.json"))]);
    assert!(!ok && msg.contains("is a file of the model in"), "{msg}");
    // A model folder that is not there, or holds no model, is named as a
    // model folder of the kinds the command reads (before, `export` and
    // the pose and surface benches fell back to a CAE: "CAE model folder
    // does not exist", "not a CAE model folder (no cae.json)").
    let missing = tmp.path().join("nowhere");
    let out = tmp.path().join("x.onnx");
    for (model, want) in [
        (&missing, "nowhere: model folder does not exist"),
        (
            &ds,
            "not a model folder (no cae.json, pose.json, detector.json",
        ),
    ] {
        let (ok, msg) = tactile(&["export", "--model", s(model), "--out", s(&out)]);
        assert!(!ok && msg.contains(want) && !msg.contains("CAE"), "{msg}");
    }
    // (`bench surface` reads its models as `bench pose` does.)
    for (model, want) in [
        (&missing, "nowhere: model folder does not exist"),
        (&ds, "not a TacTip model folder (no pose network"),
    ] {
        let page = tmp.path().join("never.md");
        let (ok, msg) = tactile(&[
            "bench",
            "pose",
            "--models",
            s(model),
            "--data",
            s(&ds),
            "--out",
            s(&page),
        ]);
        assert!(!ok && msg.contains(want) && !msg.contains("CAE"), "{msg}");
    }
    // A bench page of the pose network on `ds`, named `out`.
    let bench_page = |out: &Path| {
        tactile(&[
            "bench",
            "pose",
            "--models",
            s(&m),
            "--data",
            s(&ds),
            "--out",
            s(out),
        ])
    };
    // A page where it may go, of frames without shear columns: no table
    // of shear thirds (it was printed empty).
    let six = tmp.path().join("six");
    let rows: Vec<String> = (0..6).map(|i| row(&format!("frames/{i}.png"))).collect();
    tactip(&six, 6, &rows);
    let page = tmp.path().join("page.md");
    let (ok, msg) = tactile(&[
        "bench",
        "pose",
        "--models",
        s(&m),
        "--data",
        s(&six),
        "--runs",
        "2",
        "--out",
        s(&page),
    ]);
    assert!(ok, "{msg}");
    let text = std::fs::read_to_string(&page).unwrap();
    assert!(
        text.contains("| pose network | 128x128 |") && !text.contains("shear third"),
        "{text}"
    );
    let (ok, msg) = bench_page(&m.join("pose.md"));
    assert!(
        !ok && msg.contains("m/pose.json: is a file of the model"),
        "{msg}"
    );
    assert!(!m.join("pose.md").exists());
    assert_eq!(std::fs::read(m.join("pose.json")).unwrap(), config);
    // Nor a bench page the labels of the dataset it measures (a bench's
    // inputs are not all datasets: the output's place says it is one's).
    let (ok, msg) = bench_page(&ds.join("labels.csv"));
    assert!(
        !ok && msg.contains("labels.csv: this output is part of the dataset"),
        "{msg}"
    );
    assert_eq!(
        std::fs::read_to_string(ds.join("labels.csv")).unwrap(),
        labels
    );
    // Nor a page's plot (NAME.png) the rest frame of a calibration folder
    // or of a calibrated sensor's model.
    let cal = tmp.path().join("cal");
    let gel = tmp.path().join("gel");
    std::fs::create_dir_all(&cal).unwrap();
    std::fs::create_dir_all(&gel).unwrap();
    let gelsight = root().join("models/gelsight-r15");
    std::fs::write(
        cal.join("sensor.json"),
        r#"{"ball_diameter_mm": 4, "mm_per_px": 0.03}"#,
    )
    .unwrap();
    std::fs::copy(gelsight.join("background.png"), cal.join("background.png")).unwrap();
    for f in ["gelsight.json", "gelsight.bpk", "background.png"] {
        std::fs::copy(gelsight.join(f), gel.join(f)).unwrap();
    }
    let rest = std::fs::read(gelsight.join("background.png")).unwrap();
    for (dir, says) in [
        (&cal, "is part of the calibration folder"),
        (&gel, "is a file of the model in"),
    ] {
        let (ok, msg) = bench_page(&dir.join("background.md"));
        assert!(!ok && msg.contains(says), "{msg}");
        assert_eq!(std::fs::read(dir.join("background.png")).unwrap(), rest);
        assert!(!dir.join("background.md").exists());
    }
    for out in ["curves.csv", "estimates.csv"] {
        let (ok, msg) = predict(&m.join(out));
        assert!(ok, "{out}: {msg}");
    }
    // Nor is a model of another kind trained into its folder, over its
    // notes and curves.
    let notes = std::fs::read(m.join("training.json")).unwrap();
    let (ok, msg) = tactile(&[
        "train",
        "cae",
        "--data",
        s(&ds),
        "--out",
        s(&m),
        "--max-epochs",
        "1",
    ]);
    assert!(
        !ok && msg.contains("holds another model (pose.json)"),
        "{msg}"
    );
    assert_eq!(std::fs::read(m.join("training.json")).unwrap(), notes);
    assert!(!m.join("cae.json").exists());
    // A page is none of the files beside it: `--out x.json` wrote the page
    // over its own rows, `--out x.png` over its plot, and a report page
    // without an extension is the folder its tables go into.
    for name in ["x.json", "x.png"] {
        let page = tmp.path().join(name);
        let (ok, msg) = tactile(&["bench", "synth", "--frames", "1", "--out", s(&page)]);
        assert!(!ok && msg.contains("a page is Markdown"), "{msg}");
        assert!(!page.exists());
    }
    let page = tmp.path().join("results");
    let (ok, msg) = tactile(&["report", "--out", s(&page)]);
    assert!(!ok && msg.contains("would be the page itself"), "{msg}");
    assert!(!page.exists());
    // Nor are two outputs of one run one place: the second would replace
    // the first (before, `--frames` was lost under `--reliability`).
    let vt = tmp.path().join("vt-same");
    palpations(&vt, "1", "2", "4");
    let same = tmp.path().join("same.out");
    let detector = root().join("models/detector");
    let models = root().join("models");
    fn palpate<'a>(
        models: &'a Path,
        data: &'a Path,
        out: &'a Path,
        render: &'a Path,
    ) -> Vec<&'a str> {
        let (m, d, o, r) = (s(models), s(data), s(out), s(render));
        vec!["run", "--models", m, "--data", d, "--out", o, "--render", r]
    }
    // Records inside the new overlay folder, which must be new: refused
    // before the run, nothing made, as one place named twice is.
    let inside = same.join("records.jsonl");
    for (args, want) in [
        (
            vec![
                "eval",
                "detector",
                "--model",
                s(&detector),
                "--data",
                s(&vt),
                "--frames",
                s(&same),
                "--reliability",
                s(&same),
            ],
            "two outputs of this run name one place",
        ),
        (
            palpate(&models, &vt, &same, &same),
            "two outputs of this run name one place",
        ),
        (
            palpate(&models, &vt, &inside, &same),
            "one output of this run lies inside the other",
        ),
    ] {
        let (ok, msg) = tactile(&args);
        assert!(!ok && msg.contains(want), "{args:?}: {msg}");
        assert!(!same.exists(), "{args:?}");
    }
    // Two runs writing one folder at once never mix.
    let out = tmp.path().join("shared");
    let spawn = |seed: &str| {
        Command::new(bin())
            .args([
                "synth",
                "visuotactile",
                "--sequences",
                "2",
                "--frames-per-sequence",
                "6",
            ])
            .args(["--seed", seed, "--out", s(&out), "--force"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap()
    };
    let (mut a, mut b) = (spawn("1"), spawn("2"));
    let (sa, sb) = (a.wait().unwrap(), b.wait().unwrap());
    assert!(sa.success() || sb.success());
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    let seed = manifest["seed"].as_u64().unwrap().to_string();
    let clean = tmp.path().join("clean");
    let (ok, msg) = tactile(&[
        "synth",
        "visuotactile",
        "--sequences",
        "2",
        "--frames-per-sequence",
        "6",
        "--seed",
        &seed,
        "--out",
        s(&clean),
    ]);
    assert!(ok, "{msg}");
    for f in ["labels.csv", "frames/000007.png", "depth/000011.npy"] {
        assert_eq!(
            std::fs::read(out.join(f)).unwrap(),
            std::fs::read(clean.join(f)).unwrap(),
            "{f}"
        );
    }
    // Ctrl-C during synth: exit 130, no output, no staging folder.
    let big = tmp.path().join("big");
    let mut child = Command::new(bin())
        .args([
            "synth",
            "visuotactile",
            "--sequences",
            "400",
            "--out",
            s(&big),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    let left: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".big") || n == "big")
        .collect();
    assert!(left.is_empty(), "{left:?}");
    // After SIGKILL the next run removes the stale staging folder.
    let mut child = Command::new(bin())
        .args([
            "synth",
            "visuotactile",
            "--sequences",
            "400",
            "--out",
            s(&big),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    child.kill().unwrap();
    child.wait().unwrap();
    let (ok, msg) = tactile(&[
        "synth",
        "visuotactile",
        "--sequences",
        "1",
        "--out",
        s(&big),
    ]);
    assert!(ok, "{msg}");
    let stale = std::fs::read_dir(tmp.path())
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with(".big")
        })
        .count();
    assert_eq!(stale, 0);
    // A pipe named like a frame is refused, not read forever.
    let video = tmp.path().join("video");
    std::fs::create_dir(&video).unwrap();
    Command::new("mkfifo")
        .arg(video.join("000001.png"))
        .status()
        .unwrap();
    let t0 = Instant::now();
    let (ok, msg) = tactile(&[
        "run",
        "--data",
        s(&video),
        "--models",
        s(&root().join("models")),
    ]);
    assert!(
        !ok && msg.contains("000001.png") && msg.contains("not a regular file"),
        "{msg}"
    );
    assert!(t0.elapsed() < Duration::from_secs(30));
}

#[test]
fn interrupted_training_is_marked_and_resume_checks_its_checkpoint() {
    let tmp = tempfile::tempdir().unwrap();
    let vt = tmp.path().join("vt");
    palpations(&vt, "4", "8", "7");
    let det = tmp.path().join("det");
    let train = |extra: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = ["train", "detector", "--data", s(&vt), "--out", s(&det)]
            .iter()
            .map(|a| a.to_string())
            .collect();
        v.extend(
            [
                "--width",
                "0.25",
                "--input",
                "64x48",
                "--val-fraction",
                "0.25",
                "--patience",
                "400",
            ]
            .map(String::from),
        );
        v.extend(extra.iter().map(|a| a.to_string()));
        v
    };
    // Interrupted after its first epoch: the folder says it is incomplete.
    let mut child = Command::new(bin())
        .args(train(&["--max-epochs", "400"]))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = child.stderr.take().unwrap();
    let mut seen = String::new();
    let t0 = Instant::now();
    while !seen.contains("epoch 2/") && t0.elapsed() < Duration::from_secs(120) {
        let mut buf = [0u8; 256];
        let n = std::io::Read::read(&mut err, &mut buf).unwrap();
        if n == 0 {
            break;
        }
        seen.push_str(&String::from_utf8_lossy(&buf[..n]));
    }
    // A second run into the folder while it trains is refused, not mixed
    // in (its weights, curves and checkpoint with the first's).
    // So are a calibration and a refit of the input profile, which rewrite
    // its config.
    let rewrite =
        |what: &str| ["train", what, "--model", s(&det), "--data", s(&vt)].map(String::from);
    for args in [
        train(&["--max-epochs", "3"]),
        train(&["--max-epochs", "400", "--resume"]),
        rewrite("calibrate").to_vec(),
        rewrite("profile").to_vec(),
    ] {
        let (ok, msg) = tactile(&args.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(
            !ok && msg.contains("another run is writing this folder"),
            "{msg}"
        );
    }
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert_eq!(child.wait().unwrap().code(), Some(130), "{seen}");
    assert!(det.join("INCOMPLETE").is_file());
    let (ok, msg) = tactile(&["eval", "detector", "--model", s(&det), "--data", s(&vt)]);
    assert!(!ok && msg.contains("did not finish"), "{msg}");
    // Resuming with other settings is refused; with the same, it finishes.
    let args = train(&["--max-epochs", "3", "--resume", "--lr", "0.5"]);
    let (ok, msg) = tactile(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(!ok && msg.contains("other settings"), "{msg}");
    let args = train(&["--max-epochs", "3", "--resume"]);
    let (ok, msg) = tactile(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(ok, "{msg}");
    assert!(!det.join("INCOMPLETE").exists());
    let (ok, msg) = tactile(&["eval", "detector", "--model", s(&det), "--data", s(&vt)]);
    assert!(ok, "{msg}");
}

#[test]
fn a_pose_network_folder_is_checked_when_loaded() {
    let tmp = tempfile::tempdir().unwrap();
    let shipped = root().join("models/pose-edge");
    let text = std::fs::read_to_string(shipped.join("pose.json")).unwrap();
    let data = shared_real().join("tactip127-edge");
    for (name, from, to, says) in [
        (
            "huge",
            "\"input_px\": 128",
            "\"input_px\": 1000000000",
            "input side",
        ),
        (
            "wide",
            "\"hidden\": 256",
            "\"hidden\": 100000000",
            "hidden width",
        ),
        ("columns", "\"outputs\": 3", "\"outputs\": 5", "columns"),
    ] {
        let dir = tmp.path().join(name);
        std::fs::create_dir(&dir).unwrap();
        assert!(text.contains(from), "{from}");
        std::fs::write(dir.join("pose.json"), text.replace(from, to)).unwrap();
        std::fs::copy(shipped.join("pose.bpk"), dir.join("pose.bpk")).unwrap();
        let (ok, msg) = tactile(&["predict", "--model", s(&dir), "--data", s(&data)]);
        assert!(
            !ok && msg.contains("pose.json") && msg.contains(says),
            "{name}: {msg}"
        );
    }
}

/// Ctrl-C (or SIGTERM) during a long estimate over a dataset stops it
/// within a batch: exit 130, no estimates file, nothing staged left. Before,
/// decoding and the networks ran to the end and wrote the file anyway.
#[test]
fn a_long_prediction_stops_at_ctrl_c_and_writes_nothing() {
    let data = shared_real().join("tactip331-surface");
    let tmp = tempfile::tempdir().unwrap();
    // One signal stops the run in order; two, the second before it has
    // stopped, end it at once (no page is being written): 130 either way.
    let cases: [(&str, &[&str]); 3] = [
        ("pose-surface", &["-INT"]),
        ("cae-surface", &["-TERM"]),
        ("pose-surface", &["-INT", "-INT"]),
    ];
    for (k, (model, signals)) in cases.into_iter().enumerate() {
        let out = tmp.path().join(format!("{k}-{model}.csv"));
        let mut child = Command::new(bin())
            .args(["predict", "--model", s(&root().join("models").join(model))])
            .args(["--data", s(&data), "--out", s(&out)])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // 8,000 frames take half a minute or more: stop it in the middle.
        std::thread::sleep(Duration::from_millis(2500));
        let t0 = Instant::now();
        for &signal in signals {
            Command::new("kill")
                .args([signal, &child.id().to_string()])
                .status()
                .unwrap();
        }
        let status = child.wait().unwrap();
        let mut msg = String::new();
        std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut msg).unwrap();
        let case = format!("{model} {signals:?}");
        assert_eq!(status.code(), Some(130), "{case}: {msg}");
        assert!(!msg.contains("panicked"), "{case}: {msg}");
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "{case}: {:?}",
            t0.elapsed()
        );
        assert!(!out.exists(), "{case}");
        if signals.len() == 1 {
            assert!(msg.contains("interrupted"), "{case}: {msg}");
            let left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
            assert!(left.is_empty(), "{case}: {left:?}");
        }
    }
}

#[test]
fn pipes_in_place_of_a_file_read_or_written_are_refused_at_once() {
    // Opening a pipe blocks until something writes to it: each of these
    // would hang the command for ever. Each must be refused by name at once.
    let tmp = tempfile::tempdir().unwrap();
    let fifo = |p: &Path| {
        let _ = std::fs::remove_file(p);
        assert!(Command::new("mkfifo").arg(p).status().unwrap().success());
    };
    let refused = |args: &[&str], pipe: &Path| {
        let t0 = Instant::now();
        let (status, msg) = run(Command::new("timeout")
            .args(["-s", "KILL", "60", bin()])
            .args(args));
        assert_eq!(status.code(), Some(1), "{args:?} hung or crashed: {msg}");
        assert!(
            msg.contains(s(pipe)) && msg.contains("not a regular file"),
            "{args:?}: {msg}"
        );
        assert!(t0.elapsed() < Duration::from_secs(30), "{args:?}");
    };
    let ds = tmp.path().join("ds");
    tactip(&ds, 2, &[row("frames/0.png"), row("frames/1.png")]);
    let model = tmp.path().join("pose-edge");
    std::fs::create_dir(&model).unwrap();
    for f in ["pose.json", "pose.bpk"] {
        std::fs::copy(root().join("models/pose-edge").join(f), model.join(f)).unwrap();
    }
    let out = tmp.path().join("est.csv");
    let predict = [
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&ds),
        "--out",
        s(&out),
    ];
    // The dataset's manifest, then its labels; the model's config, then its weights.
    for (dir, file) in [
        (&ds, "manifest.json"),
        (&ds, "labels.csv"),
        (&model, "pose.json"),
        (&model, "pose.bpk"),
    ] {
        let keep = tmp.path().join("kept");
        std::fs::rename(dir.join(file), &keep).unwrap();
        fifo(&dir.join(file));
        refused(&predict, &dir.join(file));
        std::fs::remove_file(dir.join(file)).unwrap();
        std::fs::rename(&keep, dir.join(file)).unwrap();
    }
    assert!(!out.exists());
    // A pipe, or a link to one, named as the output is not replaced by the
    // estimates (renamed into its place); a link to a file writes the file.
    let pipe_out = tmp.path().join("est-pipe");
    fifo(&pipe_out);
    let link_out = tmp.path().join("est-link");
    std::os::unix::fs::symlink(&pipe_out, &link_out).unwrap();
    for o in [&pipe_out, &link_out] {
        let (status, msg) = run(Command::new("timeout")
            .args(["-s", "KILL", "60", bin(), "predict", "--model", s(&model)])
            .args(["--data", s(&ds), "--out", s(o)]));
        assert!(
            status.code() == Some(1) && msg.contains("is a pipe, a device or a socket"),
            "{msg}"
        );
    }
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata(&pipe_out).unwrap().file_type().is_fifo());
    std::fs::remove_file(&link_out).unwrap();
    std::os::unix::fs::symlink(&out, &link_out).unwrap();
    let (status, msg) = run(Command::new(bin())
        .args(["predict", "--model", s(&model), "--data", s(&ds)])
        .args(["--out", s(&link_out)]));
    assert!(status.success(), "{msg}");
    assert!(
        out.is_file()
            && std::fs::symlink_metadata(&link_out)
                .unwrap()
                .file_type()
                .is_symlink()
    );
    std::fs::remove_file(&out).unwrap();
    // A calibration folder's sensor description and press list, and an
    // options file.
    let ball = tmp.path().join("ball");
    std::fs::create_dir(&ball).unwrap();
    let real = shared_real().join("gelsight-ball");
    for f in ["sensor.json", "background.png"] {
        std::fs::copy(real.join(f), ball.join(f)).unwrap();
    }
    let cal = tmp.path().join("cal");
    let calibrate = ["calibrate", "ball", "--data", s(&ball), "--out", s(&cal)];
    fifo(&ball.join("presses.csv"));
    refused(&calibrate, &ball.join("presses.csv"));
    std::fs::rename(ball.join("sensor.json"), tmp.path().join("sensor.json")).unwrap();
    fifo(&ball.join("sensor.json"));
    refused(&calibrate, &ball.join("sensor.json"));
    let options = tmp.path().join("options.json");
    fifo(&options);
    refused(
        &[&calibrate[..], &["--config", s(&options)]].concat(),
        &options,
    );
    assert!(!cal.exists());
    // What the system said is said once ("Not a directory (os error 20)"),
    // not again as the error's cause.
    let (_, msg) = run(Command::new(bin()).args([
        "reconstruct",
        "--model",
        s(&root().join("models/gelsight-r15")),
        "--data",
        s(&options),
        "--out",
        s(&tmp.path().join("depth")),
    ]));
    assert_eq!(msg.matches("(os error").count(), 1, "{msg}");
}

/// A write that fails part-way (a full disk, a quota; here a file-size
/// limit of 2 KiB, `ulimit -f`, with its signal ignored so each write past
/// it fails as a full disk's does): each output names the file and the
/// system's reason, and nothing of it is left, neither the output nor a
/// temporary file beside it. Before, a failed MCAP write said only "I/O
/// error from writing, or reading a compression stream" (the `mcap` crate's
/// text, hiding the reason), and Python took it for bad input
/// (`ValueError`) in `tactile.run`.
#[test]
fn a_write_that_fails_part_way_names_the_file_and_leaves_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let limited = |args: &[&str]| {
        let (ok, msg) = tactile_under("trap '' XFSZ; ulimit -f 2", args);
        assert!(!ok, "{args:?} passed:\n{msg}");
        msg
    };
    let palpation = root().join("samples/palpation");
    let models = root().join("models");
    let (data, models) = (s(&palpation), s(&models));
    for (name, args) in [
        (
            "r.mcap",
            vec!["run", "--data", data, "--models", models, "--with-frames"],
        ),
        ("r.jsonl", vec!["run", "--data", data, "--models", models]),
    ] {
        let out = tmp.path().join("out");
        std::fs::create_dir_all(&out).unwrap();
        let target = out.join(name);
        let msg = limited(&[&args[..], &["--out", s(&target)]].concat());
        assert!(
            msg.contains(&format!(
                "{}: File too large (os error 27)",
                target.display()
            )),
            "{name}: {msg}"
        );
        let left: Vec<_> = std::fs::read_dir(&out).unwrap().flatten().collect();
        assert!(left.is_empty(), "{name}: left {left:?}");
    }
    // Folders of outputs: the staging folder goes, the folder never appears.
    let overlays = tmp.path().join("overlays");
    let msg = limited(&[
        "run",
        "--data",
        data,
        "--models",
        models,
        "--render",
        s(&overlays),
    ]);
    assert!(msg.contains("File too large (os error 27)"), "{msg}");
    let synth = tmp.path().join("synth");
    let msg = limited(&[
        "synth",
        "visuotactile",
        "--out",
        s(&synth),
        "--sequences",
        "1",
    ]);
    assert!(msg.contains("File too large (os error 27)"), "{msg}");
    let onnx = tmp.path().join("depth.onnx");
    let depth = root().join("models/depth");
    let msg = limited(&["export", "--model", s(&depth), "--out", s(&onnx)]);
    assert!(
        msg.contains(&format!("{}: File too large (os error 27)", onnx.display())),
        "{msg}"
    );
    let left: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(left, ["out"], "left beside the outputs");
}

/// What a file holds is quoted in messages escaped, never obeyed: a frame
/// name or a label cell with terminal controls (clear the screen, retitle
/// the window, a bell, a right-to-left override) shows them as `\x1b`,
/// `\u{202e}`, on standard error and on standard output alike.
#[test]
fn messages_show_what_a_file_holds_escaped_not_obeyed() {
    let tmp = tempfile::tempdir().unwrap();
    let hostile = "\u{1b}[2J\u{1b}]0;owned\u{7}\u{202e}gnp";
    let shown = "\\x1b[2J\\x1b]0;owned\\x07\\u{202e}gnp";
    let obeyed = |msg: &str| {
        msg.chars()
            .any(|c| c.is_control() && c != '\n' && c != '\t' || c == '\u{202e}')
    };
    // A label cell naming a frame that is not there: the error quotes it.
    let ds = tmp.path().join("ds");
    tactip(
        &ds,
        1,
        &[row("frames/0.png"), row(&format!("frames/{hostile}.png"))],
    );
    let model = root().join("models/pose-edge");
    let out = tmp.path().join("e.csv");
    let (ok, msg) = tactile(&[
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&ds),
        "--out",
        s(&out),
    ]);
    assert!(!ok && msg.contains(&format!("frames/{shown}.png")), "{msg}");
    assert!(!obeyed(&msg), "{msg:?}");
    // A frame of that name in a folder: its row of the table printed on
    // standard output.
    let folder = tmp.path().join("frames");
    png(&folder.join("0.png"), 300, 300);
    png(&folder.join(format!("1{hostile}.png")), 300, 300);
    let (ok, msg) = tactile(&[
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&folder),
        "--out",
        s(&out),
    ]);
    assert!(ok && msg.contains(&format!("1{shown}.png")), "{msg}");
    assert!(!obeyed(&msg), "{msg:?}");
    // One that is not a picture: the refusal on standard error.
    std::fs::write(folder.join(format!("2{hostile}.png")), "not a picture").unwrap();
    let models = root().join("models");
    let (ok, msg) = tactile(&["run", "--models", s(&models), "--data", s(&folder)]);
    assert!(!ok && msg.contains(&format!("2{shown}.png")), "{msg}");
    assert!(!obeyed(&msg), "{msg:?}");
}

/// `docs/hard-cases.md` stays true to the tests: every test its last
/// column names (a backticked `snake_case` name of three or more words)
/// is a function (`fn` or `def`) or a test file of the repository. A test
/// renamed or merged without its row fails here, not in a reader's search.
#[test]
fn every_test_the_hard_cases_page_names_exists() {
    fn sources(dir: &Path, out: &mut String) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.is_dir() && !name.starts_with('.') && name != "target" {
                sources(&p, out);
            } else if [".rs", ".py", ".sh"].iter().any(|x| name.ends_with(x)) {
                out.push_str(&format!("\nfile {}\n", name.rsplit_once('.').unwrap().0));
                out.push_str(&std::fs::read_to_string(&p).unwrap_or_default());
            }
        }
    }
    let mut code = String::new();
    for dir in [
        "crates",
        "datasets-synth",
        "scripts",
        "examples",
        "src",
        "tests",
        "fuzz",
    ] {
        sources(&root().join(dir), &mut code);
    }
    let page = std::fs::read_to_string(root().join("docs/hard-cases.md")).unwrap();
    let mut named = 0;
    let mut missing = Vec::new();
    for row in page.lines().filter(|l| l.starts_with('|')) {
        let cells: Vec<&str> = row.split('|').collect();
        let Some(tests) = cells.len().checked_sub(2).map(|i| cells[i]) else {
            continue;
        };
        for name in tests.split('`').skip(1).step_by(2) {
            let name = name.rsplit("::").next().unwrap_or(name);
            let is_name = name.matches('_').count() >= 2
                && name
                    .chars()
                    .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
            if !is_name {
                continue;
            }
            named += 1;
            let found = [
                format!("fn {name}("),
                format!("def {name}("),
                format!("\nfile {name}\n"),
            ]
            .iter()
            .any(|p| code.contains(p.as_str()));
            if !found {
                missing.push(name.to_string());
            }
        }
    }
    assert!(
        named > 200,
        "only {named} tests named in docs/hard-cases.md"
    );
    assert!(
        missing.is_empty(),
        "docs/hard-cases.md names tests that do not exist: {missing:?}"
    );
}
