#![allow(clippy::unwrap_used)]
//! The command line on bad input: a clear error naming the file (and line),
//! a non-zero exit, and no partial output file.

use std::path::Path;
use std::process::Command;

mod common;

fn tactile(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tactile"))
        .args(args)
        .output()
        .expect("run tactile");
    (
        out.status.success(),
        format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ),
    )
}

/// The project's real TacTip data (`../shared/real` beside the clone, or
/// TACTILE_SHARED_REAL).
fn shared_real() -> std::path::PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let real = std::env::var_os("TACTILE_SHARED_REAL")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join("../shared/real"));
    assert!(
        real.join("polic-shapes/manifest.json").is_file(),
        "real TacTip data not found at {} (set TACTILE_SHARED_REAL)",
        real.display()
    );
    real
}

/// The last line of a command's output that is JSON (its result).
fn last_json(msg: &str) -> serde_json::Value {
    msg.lines()
        .rev()
        .find_map(|l| serde_json::from_str(l).ok())
        .unwrap()
}

/// Copy a model folder with its subfolders (an ensemble's members).
fn copy_model(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        match e.file_type().unwrap().is_dir() {
            true => copy_model(&e.path(), &to.join(e.file_name())),
            false => drop(std::fs::copy(e.path(), to.join(e.file_name())).unwrap()),
        }
    }
}

/// A copy of the dataset `from` at `to` whose label rows are edited by
/// `edit`, given the header's column names and a row's cells.
fn copy_relabelled(from: &Path, to: &Path, edit: impl Fn(&[&str], &mut Vec<&str>)) {
    copy_model(from, to);
    let labels = std::fs::read_to_string(from.join("labels.csv")).unwrap();
    let mut lines = labels.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut out = vec![header.join(",")];
    for line in lines {
        let mut cells: Vec<&str> = line.split(',').collect();
        edit(&header, &mut cells);
        out.push(cells.join(","));
    }
    std::fs::write(to.join("labels.csv"), out.join("\n") + "\n").unwrap();
}

/// The place of the column `name` in `header`.
fn col(header: &[&str], name: &str) -> usize {
    header.iter().position(|&c| c == name).unwrap()
}

fn write_png(path: &Path, w: u32, h: u32) {
    image::GrayImage::from_pixel(w, h, image::Luma([0u8]))
        .save(path)
        .unwrap();
}

fn encode(model: &Path, data: &Path, out: &Path) -> (bool, String) {
    tactile(&[
        "encode",
        "--model",
        model.to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

fn train_one_epoch(data: &Path, out: &Path) -> (bool, String) {
    let [d, o] = [data, out].map(|p| p.to_str().unwrap());
    tactile(&["train", "cae", "--data", d, "--out", o, "--max-epochs", "1"])
}

/// A tiny TacTip dataset with `n` valid 300x300 frames.
fn dataset(dir: &Path, n: usize) {
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    let mut labels = String::from("file,shape,x_mm,y_mm,theta_deg,depth_mm,force_n\n");
    for i in 0..n {
        write_png(&dir.join(format!("frames/{i}.png")), 300, 300);
        labels.push_str(&format!("frames/{i}.png,sphere,0,0,0,1,1\n"));
    }
    std::fs::write(dir.join("labels.csv"), labels).unwrap();
    std::fs::write(
        dir.join("manifest.json"),
        format!(r#"{{"format":"tactile-dataset/1","kind":"tactip","sensor_spec":"test","width":300,"height":300,"generator":"test","seed":1,"count":{n}}}"#),
    )
    .unwrap();
}

/// `tactile synth visuotactile` into `out`: `sequences` palpation videos
/// of `frames` frames each, from `seed`.
fn synth_visuotactile(out: &Path, sequences: usize, frames: usize, seed: u64) {
    let (ok, msg) = tactile(&[
        "synth",
        "visuotactile",
        "--sequences",
        &sequences.to_string(),
        "--frames-per-sequence",
        &frames.to_string(),
        "--seed",
        &seed.to_string(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
}

/// A model folder with fresh weights, made by training for one epoch.
fn model(dir: &Path, data: &Path) {
    let (ok, out) = tactile(&[
        "train",
        "cae",
        "--data",
        data.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--max-epochs",
        "1",
        "--val-fraction",
        "0.5",
    ]);
    assert!(ok, "{out}");
}

#[test]
fn encode_warns_of_frames_smaller_than_the_encoders_crop() {
    // The surface encoder reads the central 440 px of 445x440 frames; the
    // virtual TacTip's 300x300 frames reach it at another scale: encoded,
    // with a warning naming the dataset.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("features.csv");
    let data = root.join("samples/virtual-tactip");
    let (ok, msg) = encode(&root.join("models/cae-surface"), &data, &out);
    assert!(ok && out.exists(), "{msg}");
    assert!(
        msg.contains("warning") && msg.contains("300x300, smaller than the model's 440x440 crop"),
        "{msg}"
    );
    // The encoder made for them says nothing.
    let (ok, msg) = encode(&root.join("models/cae-synth"), &data, &out);
    assert!(ok && !msg.contains("warning"), "{msg}");
}

#[test]
fn encode_names_corrupt_wrong_size_and_deep_frames_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("ds");
    dataset(&data, 2);
    let m = tmp.path().join("model");
    model(&m, &data);
    let out = tmp.path().join("features.csv");

    // A frame cut short behind its whole header (a copy stopped half-way):
    // found only when decoded, left out and named, the other frame's
    // features written.
    let bytes = std::fs::read(data.join("frames/1.png")).unwrap();
    std::fs::write(data.join("frames/1.png"), &bytes[..bytes.len() / 3]).unwrap();
    let (ok, msg) = encode(&m, &data, &out);
    assert!(
        ok && msg.contains("1 of the 2 frames could not be decoded")
            && msg.contains("frames/1.png: cannot decode"),
        "{msg}"
    );
    let written = std::fs::read_to_string(&out).unwrap();
    assert_eq!(written.lines().count(), 2, "{written}");
    assert!(written.lines().nth(1).unwrap().starts_with("frames/0.png,"));
    std::fs::remove_file(&out).unwrap();
    // Every frame cut short: nothing decoded, refused naming the first.
    let first = std::fs::read(data.join("frames/0.png")).unwrap();
    std::fs::write(data.join("frames/0.png"), &first[..first.len() / 3]).unwrap();
    let (ok, msg) = encode(&m, &data, &out);
    assert!(
        !ok && msg.contains("frames/0.png") && msg.contains("2 of the 2"),
        "{msg}"
    );
    assert!(!out.exists(), "partial output left behind");
    std::fs::write(data.join("frames/0.png"), first).unwrap();

    // A frame smaller than the pin image.
    write_png(&data.join("frames/1.png"), 20, 20);
    let (ok, msg) = encode(&m, &data, &out);
    assert!(
        !ok && msg.contains("frames/1.png") && msg.contains("20x20"),
        "{msg}"
    );

    // A 16-bit PNG.
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(300, 300, vec![0u16; 90000])
        .unwrap()
        .save(data.join("frames/1.png"))
        .unwrap();
    let (ok, msg) = encode(&m, &data, &out);
    assert!(
        !ok && msg.contains("frames/1.png") && msg.contains("16-bit"),
        "{msg}"
    );
    assert!(!out.exists());

    // Several frames no reader takes: found from their headers before the
    // first chunk is encoded, the first named and all counted.
    let first = std::fs::read(data.join("frames/0.png")).unwrap();
    std::fs::write(data.join("frames/0.png"), b"").unwrap();
    let (ok, msg) = encode(&m, &data, &out);
    assert!(
        !ok && msg.contains("frames/0.png: cannot read the image header")
            && msg.contains("2 of the 2 frames cannot be read"),
        "{msg}"
    );
    assert!(!out.exists());
    std::fs::write(data.join("frames/0.png"), first).unwrap();

    // Valid again: the output appears, complete.
    write_png(&data.join("frames/1.png"), 300, 300);
    let (ok, msg) = encode(&m, &data, &out);
    assert!(ok, "{msg}");
    assert_eq!(std::fs::read_to_string(&out).unwrap().lines().count(), 3);
}

#[test]
fn labels_with_missing_file_or_bad_number_name_the_line() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("ds");
    dataset(&data, 2);
    let labels = data.join("labels.csv");
    let text = std::fs::read_to_string(&labels).unwrap();
    std::fs::write(
        &labels,
        text.replace("frames/1.png,sphere,0", "frames/9.png,sphere,0"),
    )
    .unwrap();
    let out = tmp.path().join("m");
    let (ok, msg) = train_one_epoch(&data, &out);
    assert!(
        !ok && msg.contains("labels.csv:3") && msg.contains("frames/9.png"),
        "{msg}"
    );
    std::fs::write(
        &labels,
        text.replace("frames/1.png,sphere,0,0", "frames/1.png,sphere,0,zero"),
    )
    .unwrap();
    let (ok, msg) = train_one_epoch(&data, &out);
    assert!(
        !ok && msg.contains("labels.csv:3") && msg.contains("'zero'"),
        "{msg}"
    );
    // NaN and infinity in a label are refused, naming the line and the value.
    for bad in ["NaN", "inf", "-inf"] {
        std::fs::write(
            &labels,
            text.replace(
                "frames/1.png,sphere,0,0",
                &format!("frames/1.png,sphere,0,{bad}"),
            ),
        )
        .unwrap();
        let (ok, msg) = train_one_epoch(&data, &out);
        assert!(
            !ok && msg.contains("labels.csv:3") && msg.contains("not a finite number"),
            "{bad}: {msg}"
        );
    }
    assert!(!out.exists(), "nothing may be written for a bad dataset");
}

/// Files and folders directly in `dir` (sorted), to show nothing was written.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn synth_rejects_bad_configuration_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ds");
    let o = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["synth", "tactip", "--count", "-3", "--out", o], "-3"),
        (vec!["synth", "tactip", "--count", "0", "--out", o], "count"),
        (
            vec![
                "synth",
                "tactip",
                "--count",
                "2",
                "--out",
                o,
                "--depth-mm",
                "4,1",
            ],
            "inverted",
        ),
        (
            vec![
                "synth",
                "tactip",
                "--count",
                "2",
                "--out",
                o,
                "--shapes",
                "cube,sphere",
            ],
            "unknown shape 'cube'",
        ),
        (
            vec![
                "synth",
                "visuotactile",
                "--count",
                "2",
                "--out",
                o,
                "--width",
                "500",
                "--height",
                "300",
            ],
            "integer fraction",
        ),
        (
            vec![
                "synth",
                "visuotactile",
                "--count",
                "2",
                "--out",
                o,
                "--paths",
                "zigzag",
            ],
            "zigzag",
        ),
    ];
    for (args, expect) in cases {
        let (ok, msg) = tactile(&args);
        assert!(!ok && msg.contains(expect), "{args:?}: {msg}");
        assert!(
            listing(tmp.path()).is_empty(),
            "{args:?} left {:?}",
            listing(tmp.path())
        );
    }
    // A config file with an unknown key names the file.
    let cfg = tmp.path().join("gen.json");
    let c = cfg.to_str().unwrap();
    let with_config = |flags: &[&str]| {
        let mut args = vec!["synth", "tactip", "--count", "2", "--out", o];
        args.extend(flags);
        args.extend(["--config", c]);
        tactile(&args)
    };
    std::fs::write(&cfg, r#"{"depth_mm": {"min": 0, "max": 2}, "colour": 3}"#).unwrap();
    let (ok, msg) = with_config(&[]);
    assert!(
        !ok && msg.contains("gen.json") && msg.contains("colour"),
        "{msg}"
    );
    // A value the option does not take is refused in the file, naming
    // both, even when a flag sets the option again.
    std::fs::write(&cfg, r#"{"noise_sigma": "loud"}"#).unwrap();
    let (ok, msg) = with_config(&["--noise-sigma", "3,8"]);
    assert!(
        !ok && msg.contains("gen.json: option 'noise_sigma' = \"loud\""),
        "{msg}"
    );
    assert_eq!(listing(tmp.path()), vec!["gen.json"]);
}

#[test]
fn the_ideal_detector_writes_its_bounds_outside_the_set_and_refuses_real_data() {
    let tmp = tempfile::tempdir().unwrap();
    let vt = tmp.path().join("vt");
    let v = vt.to_str().unwrap();
    let (ok, msg) = tactile(&[
        "synth",
        "visuotactile",
        "--count",
        "4",
        "--width",
        "320",
        "--height",
        "180",
        "--frames-per-sequence",
        "4",
        "--out",
        v,
    ]);
    assert!(ok, "{msg}");
    let csv = tmp.path().join("bound.csv");
    let (ok, msg) = tactile(&[
        "synth",
        "ideal-detector",
        "--data",
        v,
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(ok && msg.contains("expected accuracy"), "{msg}");
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 5);
    // Never over the dataset's own files.
    let labels = vt.join("labels.csv");
    let before = std::fs::read_to_string(&labels).unwrap();
    let (ok, msg) = tactile(&[
        "synth",
        "ideal-detector",
        "--data",
        v,
        "--out",
        labels.to_str().unwrap(),
    ]);
    assert!(!ok && msg.contains("part of the input dataset"), "{msg}");
    assert_eq!(std::fs::read_to_string(&labels).unwrap(), before);
    // A set whose scenes cannot be drawn again: the real edge set.
    let real = shared_real().join("tactip127-edge");
    if real.is_dir() {
        let (ok, msg) = tactile(&["synth", "ideal-detector", "--data", real.to_str().unwrap()]);
        assert!(!ok && msg.contains("manifest.json"), "{msg}");
    }
}

#[test]
fn synth_keeps_a_non_empty_folder_unless_forced() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ds");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let o = out.to_str().unwrap();
    let (ok, msg) = tactile(&["synth", "tactip", "--count", "2", "--out", o]);
    assert!(
        !ok && msg.contains("not empty") && msg.contains("--force"),
        "{msg}"
    );
    // --force replaces a dataset, never a folder of the user's own files.
    let (ok, msg) = tactile(&["synth", "tactip", "--count", "2", "--out", o, "--force"]);
    assert!(!ok && msg.contains("not a dataset"), "{msg}");
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
    assert_eq!(listing(tmp.path()), vec!["ds"]);
    let ds = tmp.path().join("ds2");
    let d = ds.to_str().unwrap();
    let (ok, msg) = tactile(&["synth", "tactip", "--count", "2", "--out", d]);
    assert!(ok, "{msg}");
    // Three frames into `out`, with these flags.
    let synth3 = |out: &Path, flags: &[&str]| {
        let base = ["synth", "tactip", "--count", "3", "--out"];
        tactile(&[&base[..], &[out.to_str().unwrap()], flags].concat())
    };
    let preview = tmp.path().join("preview.png");
    let (ok, msg) = synth3(&ds, &["--force", "--preview", preview.to_str().unwrap()]);
    assert!(ok, "{msg}");
    assert_eq!(listing(&ds), vec!["frames", "labels.csv", "manifest.json"]);
    assert_eq!(std::fs::read_dir(ds.join("frames")).unwrap().count(), 3);
    assert!(image::open(&preview).unwrap().width() > 300);
    assert_eq!(listing(tmp.path()), vec!["ds", "ds2", "preview.png"]);
    // A contact sheet of no frames, or of a million, is refused before a
    // dataset is written for it.
    for n in ["0", "1000000"] {
        let sheet = tmp.path().join("p3.png");
        let flags = ["--preview", sheet.to_str().unwrap(), "--preview-frames", n];
        let (ok, msg) = synth3(&tmp.path().join("ds3"), &flags);
        assert!(
            !ok && msg.contains(&format!(
                "preview_frames: a contact sheet shows 1 to 400 frames, got {n}"
            )),
            "{msg}"
        );
        assert_eq!(listing(tmp.path()), vec!["ds", "ds2", "preview.png"]);
    }
    // Frames for a sheet no --preview asks for: refused, not ignored.
    let (ok, msg) = synth3(&tmp.path().join("ds4"), &["--preview-frames", "5"]);
    assert!(
        !ok && msg.contains("the following required arguments were not provided")
            && msg.contains("--preview <PREVIEW>"),
        "{msg}"
    );
    assert_eq!(listing(tmp.path()), vec!["ds", "ds2", "preview.png"]);
}

#[test]
fn demo_runs_on_the_shipped_model_and_samples() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let (ok, msg) = tactile(&[
        "demo",
        "--model",
        root.join("models/cae-synth").to_str().unwrap(),
        "--data",
        root.join("samples/virtual-tactip").to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    // Every shown frame prints 16 features; the shipped head beats chance (1 in 7).
    let rows: Vec<&str> = msg.lines().filter(|l| l.contains("features [")).collect();
    assert!(rows.len() >= 7, "{msg}");
    assert!(rows.iter().all(|l| {
        l.split("features [")
            .nth(1)
            .unwrap()
            .split_whitespace()
            .count()
            == 16
    }));
    let right = rows.iter().filter(|l| {
        let w: Vec<&str> = l.split_whitespace().collect();
        w[2] == w[4]
    });
    assert!(right.count() * 7 > rows.len() * 2, "{msg}");
    // No frame per class shows nothing: refused, not "0/0 frames classified".
    let (ok, msg) = tactile(&["demo", "--per-class", "0"]);
    assert!(
        !ok && msg
            .contains("invalid value '0' for '--per-class <PER_CLASS>': 0 is not in 1..=10000"),
        "{msg}"
    );
}

/// Synthetic TacTip frames in `data` (`synth tactip` with `flags`) with a
/// `split` column: the first `train` rows `train`, the others `rest`.
fn synth_with_split(data: &Path, flags: &[&str], train: usize, rest: &str) {
    let out = ["--out", data.to_str().unwrap()];
    let (ok, msg) = tactile(&[&["synth", "tactip"][..], flags, &out[..]].concat());
    assert!(ok, "{msg}");
    let labels = std::fs::read_to_string(data.join("labels.csv")).unwrap();
    let mut text = String::new();
    for (i, l) in labels.lines().enumerate() {
        let split = match i {
            0 => "split",
            i if i <= train => "train",
            _ => rest,
        };
        text.push_str(&format!("{l},{split}\n"));
    }
    std::fs::write(data.join("labels.csv"), text).unwrap();
}

#[test]
fn every_split_trains_the_final_cae_and_regressor_on_val_frames_too() {
    // 12 synthetic frames with the authors' kind of `split` column: 8
    // `train`, 4 `val`.
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("set");
    let d = data.to_str().unwrap();
    synth_with_split(&data, &["--count", "12"], 8, "val");
    let frames = |dir: &Path| -> u64 {
        let t: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("training.json")).unwrap())
                .unwrap();
        t["train_frames"].as_u64().unwrap() + t["val_frames"].as_u64().unwrap()
    };
    let cae = |out: &Path, extra: &[&str]| {
        let base = ["train", "cae", "--data", d, "--out", out.to_str().unwrap()];
        tactile(
            &[
                &base[..],
                &["--max-epochs", "1", "--val-fraction", "0.25"],
                extra,
            ]
            .concat(),
        )
    };
    let (validated, all) = (tmp.path().join("validated"), tmp.path().join("all"));
    let (ok, msg) = cae(&validated, &[]);
    assert!(ok, "{msg}");
    assert_eq!(
        frames(&validated),
        8,
        "the validated run reads `train` alone"
    );
    let (ok, msg) = cae(&all, &["--every-split"]);
    assert!(ok, "{msg}");
    assert_eq!(frames(&all), 12, "the final run reads `val` too");
    let art: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(all.join("cae.json")).unwrap()).unwrap();
    assert_eq!(art["notes"]["every_split"], true);
    // Leaving test frames out and training on every split contradict.
    let bad = tmp.path().join("bad");
    let (ok, msg) = cae(&bad, &["--every-split", "--exclude-test", "0.2"]);
    assert!(
        !ok && msg.contains("every_split trains on the test frames that exclude_test leaves out"),
        "{msg}"
    );
    assert!(!bad.join("cae.json").exists());
    // Its estimator: scored on `val` when validated; with --every-split
    // every frame trains and nothing is left to test.
    let reg_on = |encoder: &Path, out: &Path, extra: &[&str]| {
        let base = [
            "train",
            "regressor",
            "--encoder",
            encoder.to_str().unwrap(),
            "--data",
            d,
            "--targets",
            "depth_mm",
            "--val-fraction",
            "0.25",
            "--out",
            out.to_str().unwrap(),
        ];
        tactile(&[&base[..], extra].concat())
    };
    let reg = |out: &Path, extra: &[&str]| reg_on(&all, out, extra);
    let (ok, msg) = reg(&tmp.path().join("reg"), &[]);
    assert!(ok && msg.contains("4 test"), "{msg}");
    // The final encoder fitted those 4 `val` frames: said, with the cure.
    assert!(
        msg.contains("warning: the encoder trained on every one of these 4 test frames")
            && msg.contains("train the encoder on the `train` rows only (without --every-split)"),
        "{msg}"
    );
    // The validated encoder left them out: nothing to say.
    let (ok, msg) = reg_on(&validated, &tmp.path().join("reg-validated"), &[]);
    assert!(
        ok && msg.contains("4 test") && !msg.contains("warning"),
        "{msg}"
    );
    let (ok, msg) = reg(&all.join("pose"), &["--every-split"]);
    assert!(
        ok && msg.contains("every frame trained (3 for early stopping)"),
        "{msg}"
    );
}

#[test]
fn a_head_tested_on_frames_its_encoder_fitted_says_so() {
    // 30 synthetic frames, 20 `train` and 10 `test`; a final encoder fitted
    // every split, the test rows too.
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("set");
    let d = data.to_str().unwrap();
    synth_with_split(&data, &["--count", "30", "--seed", "4"], 20, "test");
    let head = |encoder: &Path, out: &str| {
        tactile(&[
            "train",
            "head",
            "--encoder",
            encoder.to_str().unwrap(),
            "--data",
            d,
            "--folds",
            "2",
            "--repeats",
            "1",
            "--out",
            tmp.path().join(out).to_str().unwrap(),
        ])
    };
    let all = tmp.path().join("all");
    let (ok, msg) = tactile(&[
        "train",
        "cae",
        "--data",
        d,
        "--out",
        all.to_str().unwrap(),
        "--max-epochs",
        "1",
        "--every-split",
    ]);
    assert!(ok, "{msg}");
    let (ok, msg) = head(&all, "head-all");
    assert!(
        ok && msg.contains("warning: the encoder trained on every one of these 10 test frames")
            && msg.contains("so the accuracy is on frames its features fitted"),
        "{msg}"
    );
    // An encoder of other frames: its accuracy is a held-out one.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let (ok, msg) = head(&root.join("models/cae-synth"), "head-other");
    assert!(
        ok && msg.contains("test shape accuracy") && !msg.contains("warning"),
        "{msg}"
    );
}

/// A target the labels do not have, or a validation fraction out of range,
/// is the user's flag: every trainer names it (the column with the columns
/// there are; the fraction as a configuration error, not as the labels
/// file's) before a frame is preprocessed, and makes nothing.
#[test]
fn a_misspelt_target_or_fraction_is_refused_before_any_frame_is_read() {
    let tmp = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let data = root.join("samples/virtual-tactip");
    let d = data.to_str().unwrap();
    let out = tmp.path().join("out");
    let o = out.to_str().unwrap();
    let encoder = root.join("models/cae-synth");
    let runs: [&[&str]; 3] = [
        &[
            "train",
            "pose",
            "--data",
            d,
            "--out",
            o,
            "--max-epochs",
            "1",
        ],
        &["train", "cae", "--data", d, "--out", o, "--max-epochs", "1"],
        &[
            "train",
            "regressor",
            "--encoder",
            encoder.to_str().unwrap(),
            "--data",
            d,
            "--out",
            o,
        ],
    ];
    for (k, run) in runs.iter().enumerate() {
        let targets = if k == 1 {
            "--joint-targets"
        } else {
            "--targets"
        };
        let (ok, msg) = tactile(&[run, &[targets, "depth_mm,dpeth_mm"][..]].concat());
        assert!(
            !ok && msg.contains("labels.csv:1: no column 'dpeth_mm' (its columns: file, shape,")
                && !msg.contains("preprocessing"),
            "{run:?}: {msg}"
        );
        if k < 2 {
            let (ok, msg) = tactile(&[run, &["--val-fraction", "1.5"][..]].concat());
            assert!(
                !ok && msg.contains("validation fraction must be in [0, 1), got 1.5")
                    && !msg.contains("labels.csv")
                    && !msg.contains("preprocessing"),
                "{run:?}: {msg}"
            );
            // Far out of range: said as written, not in 301 digits.
            let (ok, msg) = tactile(&[run, &["--val-fraction", "1e300"][..]].concat());
            assert!(
                !ok && msg.contains("validation fraction must be in [0, 1), got 1e300")
                    && msg.len() < 400,
                "{run:?}: {msg}"
            );
        }
        assert!(!out.exists(), "{run:?} made {o}");
    }
}

#[test]
fn regressor_names_a_missing_label_and_a_bad_target() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("spheres");
    let d = data.to_str().unwrap();
    let (ok, msg) = tactile(&[
        "synth", "tactip", "--count", "12", "--shapes", "sphere", "--out", d,
    ]);
    assert!(ok, "{msg}");
    let csv = tmp.path().join("f.csv");
    let mut text = String::from("file,f0,f1\n");
    for i in 0..12 {
        text.push_str(&format!("frames/{i:06}.png,{i},{}\n", i % 3));
    }
    std::fs::write(&csv, text).unwrap();
    let out = tmp.path().join("reg");
    let base = [
        "train",
        "regressor",
        "--features",
        csv.to_str().unwrap(),
        "--data",
        d,
        "--out",
        out.to_str().unwrap(),
    ];
    // Spheres have no orientation: the theta column is empty.
    let (ok, msg) = tactile(&[&base[..], &["--targets", "depth_mm,theta_deg:180"]].concat());
    assert!(
        !ok && msg.contains("labels.csv:2") && msg.contains("theta_deg"),
        "{msg}"
    );
    // Leaving unlabelled frames out leaves nothing here, and says so.
    let (ok, msg) = tactile(
        &[
            &base[..],
            &["--targets", "depth_mm,theta_deg:180", "--only-labelled"],
        ]
        .concat(),
    );
    assert!(
        !ok && msg.contains("too few frames with every target labelled"),
        "{msg}"
    );
    let (ok, msg) = tactile(&[&base[..], &["--targets", "theta_deg:zero"]].concat());
    assert!(!ok && msg.contains("period"), "{msg}");
    assert!(!out.exists());
    // A shape head on frames of one shape has nothing to tell apart
    // (before, it was trained and scored 100 %); so has `compare
    // --classify`.
    let head = tmp.path().join("head");
    let (ok, msg) = tactile(&[
        "train",
        "head",
        "--features",
        csv.to_str().unwrap(),
        "--data",
        d,
        "--out",
        head.to_str().unwrap(),
    ]);
    assert!(
        !ok && msg.contains("labels.csv")
            && msg.contains("column 'shape': every one of its 12 frames is 'sphere'"),
        "{msg}"
    );
    assert!(!head.exists());
    // Depth is labelled everywhere: a regressor is trained and scored.
    let (ok, msg) = tactile(
        &[
            &base[..],
            &["--targets", "depth_mm,force_n", "--test-fraction", "0.25"],
        ]
        .concat(),
    );
    assert!(
        ok && msg.contains("depth_mm") && msg.contains("force_n"),
        "{msg}"
    );
    assert!(out.join("regressor.json").is_file() && out.join("regressor.bpk").is_file());
    // Another seed's regressor is averaged with it as one estimator; one
    // answering other targets is refused, and nothing is made.
    let more = |dir: &Path, extra: &[&str]| {
        let at = base.iter().position(|a| *a == "--out").unwrap();
        let mut args = base.to_vec();
        args[at + 1] = dir.to_str().unwrap();
        args.extend(["--test-fraction", "0.25"]);
        args.extend(extra);
        tactile(&args)
    };
    let (seed8, other) = (tmp.path().join("seed8"), tmp.path().join("depth-only"));
    // A list flag takes its values as the help shows its default, space
    // separated, as well as comma separated: the same targets (before,
    // "unexpected argument 'force_n' found").
    let (ok, msg) = more(&seed8, &["--targets", "depth_mm", "force_n", "--seed", "8"]);
    assert!(ok, "{msg}");
    let (ok, msg) = more(&other, &["--targets", "depth_mm"]);
    assert!(ok, "{msg}");
    let assemble = |members: &[&Path], to: &Path| {
        let mut args = vec![
            "train",
            "ensemble",
            "--out",
            to.to_str().unwrap(),
            "--members",
        ];
        args.extend(members.iter().map(|m| m.to_str().unwrap()));
        tactile(&args)
    };
    let ens = tmp.path().join("ensemble");
    let (ok, msg) = assemble(&[&out, &seed8], &ens);
    assert!(ok && msg.contains("2 regressors averaged"), "{msg}");
    assert!(ens.join("ensemble.json").is_file() && ens.join("member-1/regressor.bpk").is_file());
    let refused = tmp.path().join("refused");
    let (ok, msg) = assemble(&[&out, &other], &refused);
    assert!(
        !ok && msg.contains("answers other targets") && msg.contains("depth-only"),
        "{msg}"
    );
    assert!(!refused.exists());
}

#[test]
fn perceive_runs_every_shipped_estimator_on_one_encoding() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("estimates.csv");
    let encoder = root.join("models/cae-synth");
    let encoder = encoder.to_str().unwrap();
    let samples = root.join("samples/virtual-tactip");
    let samples = samples.to_str().unwrap();
    let (ok, msg) = tactile(&[
        "perceive",
        "--encoder",
        encoder,
        "--data",
        samples,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    let text = std::fs::read_to_string(&out).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "file,shape,x_mm,y_mm,depth_mm,force_n,theta_deg");
    assert_eq!(lines.len(), 15);
    // Depth estimates stay near the 0-5 mm the sensor was trained on.
    for l in &lines[1..] {
        let depth: f64 = l.split(',').nth(4).unwrap().parse().unwrap();
        assert!((-1.0..6.0).contains(&depth), "{l}");
    }
    let (ok, msg) = tactile(&[
        "perceive",
        "--encoder",
        encoder,
        "--heads",
        tmp.path().to_str().unwrap(),
        "--data",
        samples,
    ]);
    assert!(
        !ok && msg.contains(
            "not an estimator folder (no head.json, regressor.json or ensemble of regressors"
        ),
        "{msg}"
    );
    // A detector ensemble's folder given as an estimator is named as the
    // model of another kind it is.
    let (ok, msg) = tactile(&[
        "robustness",
        "--encoder",
        encoder,
        "--heads",
        root.join("models/detector").to_str().unwrap(),
        "--data",
        samples,
    ]);
    assert!(
        !ok && msg.contains("detector: not an estimator folder (no head.json, regressor.json or ensemble of regressors; it holds ensemble.json: a model of another kind)"),
        "{msg}"
    );
}

#[test]
fn evaluate_and_robustness_score_the_shipped_estimators() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let enc = root.join("models/cae-synth");
    let data = root.join("samples/virtual-tactip");
    // `evaluate` or `robustness` of an encoder's estimators on the sample.
    let scored = |command: &str, encoder: &Path, more: &[&str]| {
        let head = [command, "--encoder", encoder.to_str().unwrap()];
        tactile(&[&head[..], &["--data", data.to_str().unwrap()], more].concat())
    };
    let (ok, msg) = scored("evaluate", &enc, &[]);
    assert!(ok, "{msg}");
    let json: serde_json::Value = serde_json::from_str(msg.lines().last().unwrap()).unwrap();
    let acc = json["accuracy"].as_f64().unwrap();
    // 7 shapes: chance is 1/7; the shipped head must at least double it.
    assert!(acc >= 2.0 / 7.0, "{msg}");
    let per_class: u64 = json["per_class"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g["frames"].as_u64().unwrap())
        .sum();
    assert_eq!(per_class, 14);
    let depth = json["targets"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["target"] == "depth_mm")
        .unwrap();
    // Depth is drawn from 0-5 mm: guessing the middle gives about 1.25 mm.
    assert!(depth["mae"].as_f64().unwrap() < 0.8, "{msg}");
    // The real shapes set's head knows four of the seven shapes: the
    // frames of the other three are said to count as wrong.
    let (ok, msg) = scored("evaluate", &root.join("models/cae-shapes"), &[]);
    assert!(ok, "{msg}");
    assert!(
        msg.contains("4 of these frames are of shapes the classifier does not know (edge, flat, sphere): they count as wrong, and the confusion matrix leaves them out. It knows cuboid, cylinderR4, cylinderR8, prism."),
        "{msg}"
    );
    // The JSON is the last line of standard output; the notes (these
    // frames unlike the real set's) come after it on standard error.
    let json = last_json(&msg);
    assert_eq!(
        json["unknown_shapes"].as_array().unwrap().len(),
        3,
        "{json}"
    );

    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("robust.md");
    let (ok, msg) = scored("robustness", &enc, &["--out", out.to_str().unwrap()]);
    assert!(ok, "{msg}");
    let table = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<&str> = table
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| condition"))
        .collect();
    assert_eq!(rows.len(), 13, "{table}");
    // The clean row is what `evaluate` measured.
    assert!(
        rows[0].contains(&format!("{:.1} %", 100.0 * acc)),
        "{table}"
    );
    assert!(tmp.path().join("robust.png").is_file());
    // The encoder turns the frames of a sensor mounted turned back (the
    // pin alignment in its cae.json): 5 degrees cost at most 2 of the 14
    // shapes (without it, a 2 degree turn costs most of them).
    let accuracy = |row: &str| -> f64 {
        let cell = row.split('|').nth(2).unwrap().trim();
        cell.trim_end_matches('%').trim().parse().unwrap()
    };
    let turned = rows.iter().find(|r| r.contains("rotated 5 deg")).unwrap();
    assert!(
        accuracy(rows[0]) - accuracy(turned) <= 100.0 * 2.0 / 14.0 + 0.1,
        "{table}"
    );
    // No frame to perturb is said as such (it was "no `shape` labels").
    let (ok, msg) = scored("robustness", &enc, &["--limit", "0"]);
    assert!(
        !ok && msg.contains("limit: must be at least 1 frame, got 0"),
        "{msg}"
    );
}

#[test]
fn robustness_leaves_a_frame_cut_short_out_as_evaluate_does() {
    // The 14 sample frames with the 4th cut to half its bytes behind a
    // whole header (a copy stopped half-way): the study scores the other
    // 13 under every condition, exactly as on the set without that row,
    // and says so. Before, it stopped at the frame. Every frame cut:
    // refused, naming the first, and no page written.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let enc = root.join("models/cae-synth");
    let sample = root.join("samples/virtual-tactip");
    let tmp = tempfile::tempdir().unwrap();
    let labels = std::fs::read_to_string(sample.join("labels.csv")).unwrap();
    let lines: Vec<&str> = labels.lines().collect();
    // The sample's frames, with the labels' rows `keep` keeps.
    let copy = |name: &str, keep: &dyn Fn(usize) -> bool| {
        let data = tmp.path().join(name);
        std::fs::create_dir_all(data.join("frames")).unwrap();
        let mut text = format!("{}\n", lines[0]);
        let mut count = 0;
        for (_, l) in lines[1..].iter().enumerate().filter(|(i, _)| keep(*i)) {
            let file = l.split(',').next().unwrap();
            std::fs::copy(sample.join(file), data.join(file)).unwrap();
            text += &format!("{l}\n");
            count += 1;
        }
        std::fs::write(data.join("labels.csv"), text).unwrap();
        let manifest = std::fs::read_to_string(sample.join("manifest.json")).unwrap();
        let manifest = manifest.replace("\"count\": 14", &format!("\"count\": {count}"));
        std::fs::write(data.join("manifest.json"), manifest).unwrap();
        data
    };
    let cut = copy("cut", &|_| true);
    let less = copy("less", &|i| i != 3);
    let file = |i: usize| lines[i + 1].split(',').next().unwrap().to_string();
    let cut_frame = |i: usize| {
        let path = cut.join(file(i));
        let whole = std::fs::read(&path).unwrap();
        std::fs::write(&path, &whole[..whole.len() / 2]).unwrap();
    };
    cut_frame(3);
    let study = |data: &Path, out: &Path| {
        tactile(&[
            "robustness",
            "--encoder",
            enc.to_str().unwrap(),
            "--data",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let table = |page: &str| -> Vec<String> {
        page.lines()
            .filter(|l| l.starts_with("| "))
            .map(str::to_string)
            .collect()
    };
    let (ok, msg) = study(&cut, &tmp.path().join("cut.md"));
    assert!(ok, "{msg}");
    assert!(
        msg.contains("1 of the 14 frames could not be decoded past their header"),
        "{msg}"
    );
    assert!(msg.contains(&file(3)), "{msg}");
    let page = std::fs::read_to_string(tmp.path().join("cut.md")).unwrap();
    assert!(page.contains(" on 13 of the first 14 frames of "), "{page}");
    assert!(
        page.contains("could not be decoded past their header"),
        "{page}"
    );
    let (ok, msg) = study(&less, &tmp.path().join("less.md"));
    assert!(ok, "{msg}");
    let whole = std::fs::read_to_string(tmp.path().join("less.md")).unwrap();
    assert!(whole.contains(" on the first 13 frames of "), "{whole}");
    assert_eq!(table(&page), table(&whole));
    assert_eq!(table(&page).len(), 14, "{page}");

    for i in 0..14 {
        if i != 3 {
            cut_frame(i);
        }
    }
    let out = tmp.path().join("none.md");
    let (ok, msg) = study(&cut, &out);
    assert!(!ok, "{msg}");
    assert!(msg.contains("14 of the 14"), "{msg}");
    assert!(msg.contains(&file(0)), "{msg}");
    assert!(!out.exists() && !out.with_extension("json").exists());
}

#[test]
fn compare_writes_a_table_of_every_feature_set_and_estimator() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("tt");
    let d = data.to_str().unwrap();
    let (ok, msg) = tactile(&[
        "synth", "tactip", "--count", "120", "--seed", "3", "--out", d,
    ]);
    assert!(ok, "{msg}");
    let m = tmp.path().join("cae");
    let (ok, msg) = tactile(&[
        "train",
        "cae",
        "--data",
        d,
        "--out",
        m.to_str().unwrap(),
        "--max-epochs",
        "1",
        "--preprocess",
        "lighting-compensated",
    ]);
    assert!(ok, "{msg}");
    let out = tmp.path().join("table.md");
    let (ok, msg) = tactile(&[
        "compare",
        "--encoder",
        m.to_str().unwrap(),
        "--data",
        d,
        "--targets",
        "depth_mm,force_n",
        "--classify",
        "shape",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    let table = std::fs::read_to_string(&out).unwrap();
    // The encoder trained on every frame, the test frames too: said in the
    // table and on standard error, with the flags that would hold them out.
    let saw = "The encoder trained on every one of these 24 test frames";
    assert!(
        table.contains(saw) && table.contains("--exclude-test 0.2 --split-seed 7"),
        "{table}"
    );
    assert!(msg.contains(&format!("warning: {saw}")), "{msg}");
    let rows: Vec<&str> = table
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| features"))
        .collect();
    // Five feature sets x three estimators, for regression and for classification.
    assert_eq!(rows.len(), 30, "{table}");
    assert!(table.contains("Gaussian naive Bayes") && table.contains("accuracy"));
    // Tiny data (96 training frames), yet the best feature set and estimator
    // must clearly beat guessing: depth is uniform on 0-5 mm (predicting the
    // mean errs by 1.25 mm), and there are 7 shapes (chance 14 %).
    let cell = |row: &str, col: usize| -> f64 {
        row.split('|')
            .nth(col)
            .unwrap()
            .trim()
            .trim_end_matches(" %")
            .parse()
            .unwrap()
    };
    let (reg, cls) = rows.split_at(15);
    let best_depth = reg.iter().map(|r| cell(r, 3)).fold(f64::INFINITY, f64::min);
    let best_acc = cls.iter().map(|r| cell(r, 3)).fold(0.0, f64::max);
    assert!(best_depth < 0.9, "{table}");
    assert!(best_acc > 2.0 * 100.0 / 7.0, "{table}");
    assert!(
        table.contains("Machine:")
            && table.contains("PCA-16")
            && table.contains("raw 28x28")
            && table.contains("pin tracking")
    );
    // Its rows are written beside it (what `tactile.study.compare` returns),
    // the same numbers as the table's cells.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.with_extension("json")).unwrap())
            .unwrap();
    let regression = json["regression"].as_array().unwrap();
    assert_eq!(regression.len(), 15, "{json}");
    assert_eq!(json["classification"].as_array().unwrap().len(), 15);
    for (row, line) in regression.iter().zip(reg) {
        let depth = row["values"][0][1].as_f64().unwrap();
        assert_eq!(row["values"][0][0], "depth_mm");
        assert_eq!(format!("{depth:.3}"), format!("{:.3}", cell(line, 3)));
    }
    // An MLP layer of width 0 is refused before any frame is read.
    let (ok, msg) = tactile(&[
        "compare",
        "--encoder",
        m.to_str().unwrap(),
        "--data",
        d,
        "--targets",
        "depth_mm",
        "--hidden",
        "64,0",
    ]);
    assert!(
        !ok && msg.contains("hidden width 0: must be 1 to 4096") && !msg.contains("preprocessing"),
        "{msg}"
    );
}

#[test]
fn compare_on_a_small_dataset_leaves_out_only_what_it_cannot_fit() {
    // The shipped 14-frame sample: 9 training frames are fewer than PCA's
    // 16 and 64 components, and a split of 1 training and 6 validation
    // frames leaves 7 for the 10-fold shape head. Each such row is left
    // out and said; every other row is there.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let (encoder, data) = (
        root.join("models/cae-shapes"),
        root.join("samples/virtual-tactip"),
    );
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("table.md");
    let args = |fractions: &[&'static str]| {
        let mut a = vec![
            "compare",
            "--encoder",
            encoder.to_str().unwrap(),
            "--data",
            data.to_str().unwrap(),
            "--targets",
            "depth_mm",
            "--classify",
            "shape",
            "--out",
            out.to_str().unwrap(),
        ];
        a.extend_from_slice(fractions);
        a
    };
    let rows = |table: &str| {
        table
            .lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| features"))
            .count()
    };
    let (ok, msg) = tactile(&args(&[]));
    assert!(ok, "{msg}");
    let table = std::fs::read_to_string(&out).unwrap();
    for k in [16, 64] {
        let note = format!(
            "PCA-{k} is left out: PCA with {k} components needs at least {k} training frames, got 9."
        );
        assert!(
            table.contains(&note) && msg.contains(&note),
            "{table}\n{msg}"
        );
    }
    // CAE, raw pixels and pin tracking, three estimators each, twice.
    assert_eq!(rows(&table), 18, "{table}");
    std::fs::remove_file(&out).unwrap();
    let (ok, msg) = tactile(&args(&["--test-fraction", "0.5", "--val-fraction", "0.9"]));
    assert!(ok, "{msg}");
    let table = std::fs::read_to_string(&out).unwrap();
    for set in ["CAE-16", "raw 28x28", "pin tracking (127 pins)"] {
        let note = format!(
            "{set} + MLP 16-64-32 (10-fold) is left out: classifier needs at least 10 labelled samples, got 7"
        );
        assert!(table.contains(&note), "{table}");
    }
    assert_eq!(rows(&table), 15, "{table}");
    // A split the dataset cannot give fails before any frame is read.
    std::fs::remove_file(&out).unwrap();
    let (ok, msg) = tactile(&args(&["--test-fraction", "0.9"]));
    assert!(
        !ok && msg.contains("too few frames (14)") && !msg.contains("preprocessing"),
        "{msg}"
    );
    assert!(!out.exists());
}

#[test]
fn sweep_tabulates_and_plots_every_encoder() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("tt");
    let d = data.to_str().unwrap();
    let (ok, msg) = tactile(&[
        "synth", "tactip", "--count", "60", "--seed", "5", "--out", d,
    ]);
    assert!(ok, "{msg}");
    let mut encoders = Vec::new();
    for f in ["8", "16"] {
        let m = tmp.path().join(format!("cae-{f}"));
        let mut args = vec![
            "train",
            "cae",
            "--data",
            d,
            "--out",
            m.to_str().unwrap(),
            "--max-epochs",
            "1",
            "--features",
            f,
            "--preprocess",
            "lighting-compensated",
        ];
        // The 8-feature encoder leaves out the sweep's test frames (its
        // split: 20 %, seed 7); the 16-feature one fits them.
        if f == "8" {
            args.extend(["--exclude-test", "0.2"]);
        }
        let (ok, msg) = tactile(&args);
        assert!(ok, "{msg}");
        encoders.push(m.to_str().unwrap().to_string());
    }
    let sweep = |out: &Path| {
        let mut args = vec![
            "sweep",
            "--data",
            d,
            "--runs",
            "2",
            "--out",
            out.to_str().unwrap(),
            "--encoders",
        ];
        args.extend(encoders.iter().map(String::as_str));
        tactile(&args)
    };
    let out = tmp.path().join("sweep.md");
    let (ok, msg) = sweep(&out);
    assert!(ok, "{msg}");
    let table = std::fs::read_to_string(&out).unwrap();
    assert!(
        table.contains("| cae-8 | 8 |")
            && table.contains("| cae-16 (trained on test frames) | 16 |")
            && table.contains("partly on frames it was trained on"),
        "{table}"
    );
    assert!(tmp.path().join("sweep-features.png").is_file());
    assert!(tmp.path().join("sweep-latency.png").is_file());
    // Its rows go beside it, so a page named as its own rows is refused
    // before any encoder is run, as every page is (it was written, then
    // replaced by the rows).
    let page = tmp.path().join("page.json");
    let (ok, msg) = sweep(&page);
    assert!(!ok && msg.contains("a page is Markdown"), "{msg}");
    assert!(!page.exists());
}

#[test]
fn the_shipped_detector_holds_on_light_presses_of_the_second_renderer() {
    // Light presses (peak 0.05-0.4 mm, ridges near the 0.03 mm label
    // threshold) drawn by the alternate renderer, which no training set
    // uses; 320x180 to keep it quick (the detector reads 80x60 anyway).
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("light-alt");
    let d = data.to_str().unwrap();
    let (ok, msg) = tactile(&[
        "synth",
        "visuotactile",
        "--sequences",
        "16",
        "--frames-per-sequence",
        "25",
        "--seed",
        "4343",
        "--press-mm",
        "0.05,0.4",
        "--renderer",
        "alternate",
        "--width",
        "320",
        "--height",
        "180",
        "--out",
        d,
    ]);
    assert!(ok, "{msg}");
    let (ok, msg) = tactile(&[
        "eval",
        "detector",
        "--model",
        root.join("models/detector").to_str().unwrap(),
        "--data",
        d,
    ]);
    assert!(ok, "{msg}");
    let scores = last_json(&msg);
    // The target is 0.98 on 3,000 such frames; on 400 one standard error
    // is about 0.007, so two of them below it.
    let acc = scores["all"]["accuracy"].as_f64().unwrap();
    assert!(acc >= 0.965, "{msg}");
    assert!(
        scores["calibration"]["ece"].as_f64().unwrap() < 0.05,
        "{msg}"
    );
}

#[test]
fn shipped_detector_and_segmenter_meet_their_targets_on_fresh_palpations() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("vt");
    let d = data.to_str().unwrap();
    // Six palpation videos of a seed no model has seen, every tendon path.
    synth_visuotactile(&data, 6, 20, 4242);
    let frames_csv = tmp.path().join("decisions.csv");
    let (ok, msg) = tactile(&[
        "eval",
        "detector",
        "--model",
        root.join("models/detector").to_str().unwrap(),
        "--data",
        d,
        "--frames",
        frames_csv.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    let acc = last_json(&msg)["all"]["accuracy"].as_f64().unwrap();
    // The target is 0.99 on 1000 held-out frames; 120 frames are noisier.
    assert!(acc >= 0.95, "{msg}");
    // The live pipeline sees each frame exactly as eval does (same device):
    // the same probability, so eval's accuracy is the pipeline's.
    let records = tmp.path().join("run.jsonl");
    let (ok, msg) = tactile(&[
        "run",
        "--data",
        d,
        "--models",
        root.join("models").to_str().unwrap(),
        "--runtime",
        "burn-flex",
        "--out",
        records.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    let live: std::collections::HashMap<String, f64> = std::fs::read_to_string(&records)
        .unwrap()
        .lines()
        .map(|l| {
            let r: serde_json::Value = serde_json::from_str(l).unwrap();
            (
                r["frame"].as_str().unwrap().to_string(),
                r["score"].as_f64().unwrap(),
            )
        })
        .collect();
    let csv = std::fs::read_to_string(&frames_csv).unwrap();
    let mut compared = 0;
    for line in csv.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        let name = Path::new(cols[0]).file_name().unwrap().to_str().unwrap();
        let p: f64 = cols[2].parse().unwrap();
        let q = live[name];
        // eval writes six decimals.
        assert!((p - q).abs() <= 2e-6, "{name}: eval {p}, run {q}");
        compared += 1;
    }
    assert_eq!(compared, 120);
    let (ok, msg) = tactile(&[
        "eval",
        "segmenter",
        "--model",
        root.join("models/segmenter").to_str().unwrap(),
        "--data",
        d,
    ]);
    assert!(ok, "{msg}");
    let all = &last_json(&msg)["paths"][0];
    assert_eq!(all["path"], "all");
    assert!(all["mean_iou"].as_f64().unwrap() >= 0.85, "{msg}");
    // The centre-line direction: on every tendon frame, within the targets
    // (98 % coverage, median 2, p90 5 degrees).
    let dir = &all["direction"];
    assert!(dir["coverage"].as_f64().unwrap() >= 0.98, "{msg}");
    assert!(dir["median_deg"].as_f64().unwrap() <= 2.0, "{msg}");
    assert!(dir["p90_deg"].as_f64().unwrap() <= 5.0, "{msg}");
    assert!(msg.contains("principal axis (baseline)"), "{msg}");
}

#[test]
fn detector_and_segmenter_train_resume_and_evaluate_on_tiny_data() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("vt");
    let d = data.to_str().unwrap();
    synth_visuotactile(&data, 4, 8, 5);
    let det = tmp.path().join("det");
    let args = |epochs: &str| {
        vec![
            "train".to_string(),
            "detector".into(),
            "--data".into(),
            d.into(),
            "--out".into(),
            det.to_str().unwrap().into(),
            "--width".into(),
            "0.25".into(),
            "--input".into(),
            "64x48".into(),
            "--max-epochs".into(),
            epochs.into(),
            "--val-fraction".into(),
            "0.25".into(),
        ]
    };
    let run = |v: Vec<String>| tactile(&v.iter().map(String::as_str).collect::<Vec<_>>());
    let (ok, msg) = run(args("1"));
    assert!(ok, "{msg}");
    // Not a terminal: one line per epoch instead of a hidden progress bar.
    assert!(
        msg.contains("epoch 1/1: train loss") && msg.contains("ETA"),
        "{msg}"
    );
    // One more epoch from the checkpoint.
    let mut more = args("2");
    more.push("--resume".into());
    let (ok, msg) = run(more);
    assert!(ok && msg.contains("of 2"), "{msg}");
    for f in [
        "detector.json",
        "detector.bpk",
        "curves.csv",
        "curves.png",
        "training.json",
    ] {
        assert!(det.join(f).is_file(), "{f}");
    }
    let (ok, msg) = tactile(&[
        "eval",
        "detector",
        "--model",
        det.to_str().unwrap(),
        "--data",
        d,
    ]);
    assert!(ok, "{msg}");
    let v = last_json(&msg);
    assert_eq!(v["all"]["frames"], 32);
    let seg = tmp.path().join("seg");
    let (ok, msg) = tactile(&[
        "train",
        "segmenter",
        "--data",
        d,
        "--out",
        seg.to_str().unwrap(),
        "--side",
        "32",
        "--base",
        "4",
        "--copies",
        "2",
        "--max-epochs",
        "1",
        "--val-fraction",
        "0.25",
    ]);
    assert!(ok, "{msg}");
    let (ok, msg) = tactile(&[
        "eval",
        "segmenter",
        "--model",
        seg.to_str().unwrap(),
        "--data",
        d,
    ]);
    assert!(ok, "{msg}");
    let v = last_json(&msg);
    let iou = v["paths"][0]["mean_iou"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&iou));
    // Wrong kind of dataset: a clear error naming the manifest.
    let tt = tmp.path().join("tt");
    let (ok, msg) = tactile(&[
        "synth",
        "tactip",
        "--count",
        "4",
        "--out",
        tt.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    // Each paper B model scored on TacTip frames, or trained on them: the
    // dataset's kind named.
    let trained = tmp.path().join("seg-on-tactip");
    let (tt, trained) = (tt.to_str().unwrap(), trained.to_str().unwrap());
    let (det, seg) = (det.to_str().unwrap(), seg.to_str().unwrap());
    for args in [
        ["train", "segmenter", "--data", tt, "--out", trained],
        ["eval", "detector", "--model", det, "--data", tt],
        ["eval", "segmenter", "--model", seg, "--data", tt],
    ] {
        let (ok, msg) = tactile(&args);
        assert!(
            !ok && msg.contains("manifest.json: not a visuotactile dataset (its kind is 'tactip')"),
            "{args:?}: {msg}"
        );
    }
    assert!(!Path::new(trained).exists());
    // Frames of one class (a researcher's presses, none over a tendon):
    // refused before any epoch, naming the labels; no folder made. Before,
    // it trained to say "no tendon" to every frame, at accuracy 1.
    for (value, said) in [
        ("0", "tendon = 0 (no tendon)"),
        ("1", "tendon = 1 (a tendon)"),
    ] {
        let one = tmp.path().join(format!("one-class-{value}"));
        copy_relabelled(&data, &one, |h, cells| cells[col(h, "tendon")] = value);
        let out = tmp.path().join(format!("det-{value}"));
        let (ok, msg) = tactile(&[
            "train",
            "detector",
            "--data",
            one.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--width",
            "0.25",
            "--input",
            "64x48",
            "--max-epochs",
            "1",
        ]);
        assert!(
            !ok && msg.contains("labels.csv: every one of the 24 training frames is labelled ")
                && msg.contains(said)
                && msg.contains("a detector learns nothing from one class"),
            "{msg}"
        );
        assert!(!out.exists());
    }
    // Sequences of one class each (recordings over a tendon and beside
    // it): the validation sequence is of one class. Trained, with a
    // warning, and the threshold stays at a half.
    let apart = tmp.path().join("apart");
    copy_relabelled(&data, &apart, |h, cells| {
        cells[col(h, "tendon")] = if cells[col(h, "sequence")] < "2" {
            "1"
        } else {
            "0"
        };
    });
    let out = tmp.path().join("det-apart");
    let (ok, msg) = tactile(&[
        "train",
        "detector",
        "--data",
        apart.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--width",
        "0.25",
        "--input",
        "64x48",
        "--max-epochs",
        "1",
        "--val-fraction",
        "0.25",
    ]);
    assert!(
        ok && msg.contains("warning: ")
            && msg.contains(
                "validation frames (whole sequences, split by `sequence`) is labelled tendon = "
            )
            && msg.contains("the threshold stays at 0.5")
            && msg.contains("at the chosen threshold 0.50"),
        "{msg}"
    );
    let record = std::fs::read_to_string(out.join("training.json")).unwrap();
    assert!(record.contains("the threshold stays at 0.5"), "{record}");
}

#[test]
fn train_depth_refuses_metres_and_an_unknown_loss_by_their_flags() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("vt");
    let d = data.to_str().unwrap();
    synth_visuotactile(&data, 3, 6, 8);
    let out = tmp.path().join("depth");
    let o = out.to_str().unwrap();
    let base = [
        "train",
        "depth",
        "--data",
        d,
        "--out",
        o,
        "--encoder",
        "tiny",
        "--input",
        "64x32",
        "--decoder-width",
        "16",
        "--max-epochs",
        "1",
        "--val-fraction",
        "0.34",
    ];
    // Metres: the targets barely vary; refused before training, and why.
    let (ok, msg) = tactile(&[&base[..], &["--unit-mm", "1000"]].concat());
    assert!(
        !ok && msg.contains("stall") && msg.contains("millimetres"),
        "{msg}"
    );
    assert!(!out.join("depth.bpk").exists());
    let (ok, msg) = tactile(&["train", "depth", "--data", d, "--out", o, "--loss", "huber"]);
    assert!(!ok && msg.contains("huber"), "{msg}");
    // A frozen encoder that was never trained: said, as the run goes on
    // (a baseline of random features is a choice, an oversight likelier).
    let (ok, msg) = tactile(&[&base[..], &["--freeze-encoder"]].concat());
    assert!(
        ok && msg.contains(
            "warning: freeze_encoder without pretrained weights: only the decoder trains"
        ),
        "{msg}"
    );
}

#[test]
fn run_gates_frames_and_agrees_across_runtimes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("vt");
    let d = data.to_str().unwrap();
    synth_visuotactile(&data, 2, 12, 61);
    let mut flags = Vec::new();
    for rt in ["onnx", "burn-flex", "burn-ndarray"] {
        let out = tmp.path().join(format!("{rt}.jsonl"));
        let render = tmp.path().join(format!("render-{rt}"));
        let (ok, msg) = tactile(&[
            "run",
            "--data",
            d,
            "--models",
            root.join("models").to_str().unwrap(),
            "--runtime",
            rt,
            "--out",
            out.to_str().unwrap(),
            "--render",
            render.to_str().unwrap(),
        ]);
        assert!(ok, "{rt}: {msg}");
        let recs: Vec<serde_json::Value> = std::fs::read_to_string(&out)
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(recs.len(), 24);
        for r in &recs {
            // A frame without a tendon costs one detector pass, nothing more.
            let tendon = r["tendon"].as_bool().unwrap();
            assert_eq!(r["ms_segment"].is_null(), !tendon, "{r}");
            assert_eq!(r["ms_depth"].is_null(), !tendon, "{r}");
            if tendon {
                let mean = r["depth_mean_mm"].as_f64().unwrap();
                assert!((12.0..18.0).contains(&mean), "{r}");
            }
        }
        // One overlay per tendon frame, none for the others.
        let overlays = std::fs::read_dir(&render).map_or(0, |r| r.count());
        let tendon_frames = recs
            .iter()
            .filter(|r| r["tendon"].as_bool().unwrap())
            .count();
        assert_eq!(overlays, tendon_frames);
        // Before first touch (frame 0 of each video): no tendon.
        assert!(!recs[0]["tendon"].as_bool().unwrap() && !recs[12]["tendon"].as_bool().unwrap());
        flags.push(
            recs.iter()
                .map(|r| r["tendon"].as_bool().unwrap())
                .collect::<Vec<_>>(),
        );
    }
    assert!(
        flags.windows(2).all(|w| w[0] == w[1]),
        "runtimes disagree: {flags:?}"
    );
    let (ok, msg) = tactile(&["run", "--data", d, "--runtime", "tensorflow"]);
    assert!(!ok && msg.contains("tensorflow"), "{msg}");
}

#[test]
fn several_pipelines_give_the_records_of_one_in_order() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let models = root.join("models");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("vt");
    // 14 frames: batches of 3 leave a short one at the end.
    synth_visuotactile(&data, 2, 7, 63);
    let run = |pipelines: &str, extra: &[&str], out: &Path| {
        let mut args = vec![
            "run",
            "--data",
            data.to_str().unwrap(),
            "--models",
            models.to_str().unwrap(),
            "--pipelines",
            pipelines,
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        tactile(&args)
    };
    let records = |out: &Path| -> Vec<serde_json::Value> {
        std::fs::read_to_string(out)
            .unwrap()
            .lines()
            .map(|l| {
                let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
                let o = v.as_object_mut().unwrap();
                o.retain(|k, _| !k.starts_with("ms_") && k != "latency_ms");
                v
            })
            .collect()
    };
    let (one, three) = (tmp.path().join("1.jsonl"), tmp.path().join("3.jsonl"));
    let (ok, msg) = run("1", &[], &one);
    assert!(ok, "{msg}");
    let (ok, msg3) = run("3", &[], &three);
    assert!(ok, "{msg3}");
    let (a, b) = (records(&one), records(&three));
    assert_eq!(a.len(), 14);
    assert!(a.iter().any(|r| r["tendon"] == true) && a.iter().any(|r| r["tendon"] == false));
    assert_eq!(
        a, b,
        "three pipelines must give one's records, in the source's order"
    );
    assert_eq!(last_json(&msg)["pipelines"], 1);
    assert_eq!(last_json(&msg3)["pipelines"], 3);
    assert!(
        msg3.contains("frames/s, onnx on 3 pipelines, decoding included"),
        "{msg3}"
    );
    assert!(msg.contains("frames/s, onnx, decoding included"), "{msg}");
    assert_eq!(
        last_json(&msg)["detector_accuracy"],
        last_json(&msg3)["detector_accuracy"]
    );
    // Refused before any model loads, nothing written: a hysteresis (it
    // decides each frame after the one before) and a count out of range.
    for (n, extra, says) in [
        (
            "2",
            &["--hysteresis", "0.6,0.3"][..],
            "pipelines 2 with a hysteresis: the hysteresis decides each frame after the one before it",
        ),
        ("0", &[][..], "pipelines: must be 1 to 64, got 0"),
        ("65", &[][..], "pipelines: must be 1 to 64, got 65"),
    ] {
        let out = tmp.path().join(format!("refused-{n}.jsonl"));
        let (ok, msg) = run(n, extra, &out);
        assert!(!ok && msg.contains(says), "{msg}");
        assert!(!out.exists());
    }
}

#[test]
fn run_on_a_video_folder_with_a_dropped_frame_reports_it() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("vt");
    synth_visuotactile(&data, 1, 6, 62);
    // A 30 fps video as numbered PNGs, frame 3 lost.
    let video = data.join("frames");
    std::fs::remove_file(video.join("000003.png")).unwrap();
    let (ok, msg) = tactile(&[
        "run",
        "--data",
        video.to_str().unwrap(),
        "--models",
        root.join("models").to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    assert!(msg.contains("1 frame(s) missing"), "{msg}");
    // The run's summary: its one JSON line.
    let summary = |msg: &str| -> serde_json::Value {
        let json = msg.lines().find(|l| l.starts_with('{')).unwrap();
        serde_json::from_str(json).unwrap()
    };
    let v = summary(&msg);
    assert_eq!(v["frames"], 5);
    assert_eq!(v["missing_frames"], 1);
    // Frames that cannot be read (a 16-bit frame, an empty file, text
    // named .png) are found from their headers when the folder is opened:
    // named and counted before any model loads (the models folder here
    // does not exist), not after every frame before them.
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(4, 4, vec![0u16; 16])
        .unwrap()
        .save(video.join("000006.png"))
        .unwrap();
    std::fs::write(video.join("000007.png"), b"").unwrap();
    std::fs::write(video.join("000008.png"), b"not a picture").unwrap();
    let out = tmp.path().join("r.jsonl");
    let run_models = |models: &Path, limit: &str| {
        tactile(&[
            "run",
            "--data",
            video.to_str().unwrap(),
            "--models",
            models.to_str().unwrap(),
            "--limit",
            limit,
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let none = tmp.path().join("no-models");
    let (ok, msg) = run_models(&none, "100");
    assert!(
        !ok && msg.contains("000006.png: 16-bit greyscale image")
            && msg.contains("3 of the 8 frames cannot be read")
            && !msg.contains("no-models"),
        "{msg}"
    );
    let (ok, msg) = run_models(&none, "6");
    assert!(
        !ok && msg.contains("000006.png: 16-bit") && !msg.contains("of the"),
        "{msg}"
    );
    assert!(!out.exists());
    // Frames past --limit are not read, so not checked either.
    let (ok, msg) = run_models(&root.join("models"), "5");
    assert!(ok && out.exists(), "{msg}");
    // A frame cut short behind a whole header (a copy stopped half-way)
    // is found only when decoded: it is skipped and named, and the other
    // frames' records are written.
    let whole = std::fs::read(video.join("000005.png")).unwrap();
    std::fs::write(video.join("000006.png"), &whole[..whole.len() / 2]).unwrap();
    std::fs::copy(video.join("000005.png"), video.join("000007.png")).unwrap();
    std::fs::remove_file(video.join("000008.png")).unwrap();
    std::fs::remove_file(&out).unwrap();
    let (ok, msg) = run_models(&root.join("models"), "100");
    assert!(ok, "{msg}");
    assert!(
        msg.contains("warning: 1 of the 7 frames could not be decoded past their header")
            && msg.matches("could not be decoded").count() == 1
            && msg.contains(&format!(
                "{}: cannot decode image",
                video.join("000006.png").display()
            )),
        "{msg}"
    );
    let names: Vec<String> = std::fs::read_to_string(&out)
        .unwrap()
        .lines()
        .map(|l| {
            serde_json::from_str::<serde_json::Value>(l).unwrap()["frame"]
                .as_str()
                .unwrap()
                .to_string()
        })
        .collect();
    assert_eq!(
        names,
        [
            "000000.png",
            "000001.png",
            "000002.png",
            "000004.png",
            "000005.png",
            "000007.png"
        ]
    );
    let v = summary(&msg);
    assert_eq!(
        (v["frames"].as_u64(), v["undecodable_frames"].as_u64()),
        (Some(6), Some(1))
    );
    // A folder with no frames at all is an error naming it.
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let (ok, msg) = tactile(&["run", "--data", empty.to_str().unwrap()]);
    assert!(
        !ok && msg.contains("no frames (PNG, JPEG, BMP, TIFF, WebP or PGM/PPM)"),
        "{msg}"
    );
    // Naming the folder above the frames is told which folder holds them.
    std::fs::create_dir(empty.join("frames")).unwrap();
    std::fs::copy(video.join("000000.png"), empty.join("frames/0.png")).unwrap();
    let (ok, msg) = tactile(&["run", "--data", empty.to_str().unwrap()]);
    let hint = format!("the folder {} holds frames", empty.join("frames").display());
    assert!(!ok && msg.contains(&hint), "{msg}");
}

#[test]
fn the_demo_palpation_video_is_detected_segmented_and_pointed() {
    // samples/palpation: 12 frames of one virtual palpation over an arc
    // tendon whose direction label is 117.3 degrees; frames 0 and 11 are
    // before and after contact.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("r.jsonl");
    let (ok, msg) = tactile(&[
        "run",
        "--data",
        root.join("samples/palpation").to_str().unwrap(),
        "--models",
        root.join("models").to_str().unwrap(),
        "--runtime",
        "burn-flex",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    let recs: Vec<serde_json::Value> = std::fs::read_to_string(&out)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(recs.len(), 12);
    assert!(!recs[0]["tendon"].as_bool().unwrap() && !recs[11]["tendon"].as_bool().unwrap());
    for r in &recs[3..=8] {
        assert!(r["tendon"].as_bool().unwrap(), "{r}");
        let d = r["direction_deg"].as_f64().unwrap();
        assert!((d - 117.3).abs() < 5.0, "{r}");
    }
}

/// A folder this process cannot write in: a read-only (0555) temporary
/// folder, or, under root (which ignores permission bits), `/sys`, which
/// refuses new files even to root. None when neither exists here.
fn unwritable_folder(tmp: &Path) -> Option<std::path::PathBuf> {
    use std::os::unix::fs::PermissionsExt;
    let writable = |d: &Path| {
        let p = d.join(".tactile-test-probe");
        let ok = std::fs::write(&p, b"x").is_ok();
        let _ = std::fs::remove_file(&p);
        ok
    };
    let ro = tmp.join("read-only");
    std::fs::create_dir(&ro).unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    if !writable(&ro) {
        return Some(ro);
    }
    let sys = Path::new("/sys");
    (sys.join("kernel").is_dir() && !writable(sys)).then(|| sys.to_path_buf())
}

/// A results file named as another format than the command writes (a
/// spreadsheet would open a `.csv`, `pandas.read_json` a `.jsonl`) is
/// refused before any work, nothing written: `run` writes JSON Lines (or
/// MCAP for `.mcap`), `predict`, `encode`, `eval detector --frames` and
/// `synth ideal-detector` write CSV. Before, each wrote its format under
/// the name.
#[test]
fn results_named_as_another_format_are_refused_before_any_work() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let (palpation, tactip) = (
        s(&root.join("samples/palpation")),
        s(&root.join("samples/virtual-tactip")),
    );
    let models = root.join("models");
    let (all, encoder) = (s(&models), s(&models.join("cae-synth")));
    let out = |name: &str| s(&tmp.path().join(name));
    let run = vec!["run", "--data", &palpation, "--models", &all, "--out"];
    for (args, name, says) in [
        (run.clone(), "records.csv", "named as a table"),
        (run.clone(), "Records.TSV", "named as a table"),
        (run.clone(), "run.mcap.zstd", "named as a compressed bag"),
        (
            vec!["predict", "--model", &encoder, "--data", &tactip, "--out"],
            "est.jsonl",
            "named as JSON",
        ),
        (
            vec!["encode", "--model", &encoder, "--data", &tactip, "--out"],
            "features.xlsx",
            "named as a spreadsheet workbook",
        ),
        (
            vec![
                "eval",
                "detector",
                "--model",
                &s(&models.join("detector")),
                "--data",
                &tactip,
                "--frames",
            ],
            "frames.json",
            "named as JSON",
        ),
    ] {
        let mut cmd = args.clone();
        let path = out(name);
        cmd.push(&path);
        let (ok, msg) = tactile(&cmd);
        assert!(
            !ok && msg.contains(says) && msg.contains(name),
            "{name}: {msg}"
        );
    }
    assert_eq!(
        std::fs::read_dir(tmp.path()).unwrap().count(),
        0,
        "something was written"
    );
}

#[test]
fn run_refuses_an_unwritable_output_folder_before_any_work() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let Some(ro) = unwritable_folder(tmp.path()) else {
        eprintln!("no unwritable folder on this machine; nothing to test");
        return;
    };
    let before = listing(&ro);
    let samples = root.join("samples/palpation");
    let models = root.join("models");
    let records = ro.join("records.jsonl");
    let renders = ro.join("overlays");
    for args in [
        vec!["--out", records.to_str().unwrap()],
        vec!["--render", renders.to_str().unwrap()],
        vec!["--render", ro.to_str().unwrap()],
    ] {
        let mut cmd = vec![
            "run",
            "--data",
            samples.to_str().unwrap(),
            "--models",
            models.to_str().unwrap(),
        ];
        cmd.extend(args);
        let (ok, msg) = tactile(&cmd);
        assert!(!ok, "{msg}");
        assert!(
            msg.contains(ro.to_str().unwrap()),
            "the folder is not named: {msg}"
        );
        assert!(!msg.contains("frames/s"), "it ran before failing: {msg}");
    }
    // Training fails before loading its data, not at its first checkpoint.
    let model = ro.join("detector");
    let (ok, msg) = tactile(&[
        "train",
        "detector",
        "--data",
        samples.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(!ok && msg.contains(ro.to_str().unwrap()), "{msg}");
    assert!(!msg.contains("loading"), "{msg}");
    assert_eq!(listing(&ro), before, "something was written");
}

#[test]
fn report_regenerates_the_results_page_and_the_readme_headline() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let real = shared_real();
    let tmp = tempfile::tempdir().unwrap();
    let readme = tmp.path().join("README.md");
    let out = tmp.path().join("docs/results.md");
    let before = "# A project\n\nintro\n\n<!-- headline:begin -->\nstale table\n<!-- headline:end -->\n\nthe rest\n";
    std::fs::write(&readme, before).unwrap();
    let args = |readme: &Path| {
        vec![
            "report".to_string(),
            "--real".into(),
            real.to_str().unwrap().into(),
            "--models".into(),
            root.join("models").to_str().unwrap().into(),
            "--work".into(),
            tmp.path().join("work").to_str().unwrap().into(),
            "--out".into(),
            out.to_str().unwrap().into(),
            "--readme".into(),
            readme.to_str().unwrap().into(),
            "--sequences".into(),
            "2".into(),
            "--extreme-sequences".into(),
            "1".into(),
            "--runs".into(),
            "2".into(),
        ]
    };
    // A README without the markers is refused before any work, untouched.
    let bare = tmp.path().join("BARE.md");
    std::fs::write(&bare, "# no markers\n").unwrap();
    let a = args(&bare);
    let (ok, msg) = tactile(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(
        !ok && msg.contains("BARE.md") && msg.contains("headline:begin"),
        "{msg}"
    );
    assert_eq!(std::fs::read_to_string(&bare).unwrap(), "# no markers\n");
    assert!(
        !out.exists() && !tmp.path().join("work").exists(),
        "work done before the check"
    );
    // So is a real-data or models folder that is not there, before the
    // held-out sets are rendered and before any folder is made (before,
    // after 25 s of rendering and the CAE bench's start).
    let missing = tmp.path().join("nowhere");
    for flag in ["--real", "--models"] {
        let mut a = args(&readme);
        let at = a.iter().position(|x| x == flag).unwrap();
        a[at + 1] = missing.to_str().unwrap().into();
        let (ok, msg) = tactile(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(
            !ok && msg.contains("nowhere/") && msg.contains("does not exist"),
            "{flag}: {msg}"
        );
        assert!(
            !tmp.path().join("docs").exists() && !tmp.path().join("work").exists(),
            "{flag}: work done before the check"
        );
    }

    let a = args(&readme);
    let (ok, msg) = tactile(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(ok, "{msg}");
    let page = std::fs::read_to_string(&out).unwrap();
    // Every section, the machine, and a plot per model bench.
    for needle in [
        "Machine:",
        "## Headline",
        "## The palpation pipeline",
        "| onnx |",
        "| burn-flex |",
        "| burn-ndarray |",
        "| hysteresis ON 0.6, OFF 0.3 |",
        "## Tendon detector",
        "## Tendon segmenter",
        "## Depth",
    ] {
        assert!(page.contains(needle), "{needle} missing from:\n{page}");
    }
    for png in ["detector.png", "segmenter.png", "depth.png"] {
        assert!(tmp.path().join("docs/results").join(png).is_file(), "{png}");
    }
    // The README's block is the headline table, with numbers; the rest kept.
    let text = std::fs::read_to_string(&readme).unwrap();
    assert!(
        text.starts_with("# A project\n\nintro\n\n<!-- headline:begin -->\n| stage |"),
        "{text}"
    );
    assert!(
        text.ends_with("<!-- headline:end -->\n\nthe rest\n"),
        "{text}"
    );
    assert!(!text.contains("stale table"), "{text}");
    let detector = text
        .lines()
        .find(|l| l.starts_with("| paper B: tendon detector"))
        .unwrap();
    let cells: Vec<&str> = detector.split('|').map(str::trim).collect();
    // accuracy on the 50 held-out frames, then onnxruntime / flex / ndarray ms.
    let acc: f64 = cells[2]
        .trim_start_matches("accuracy ")
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(acc > 0.8, "{detector}");
    for ms in &cells[4..7] {
        let v: f64 = ms.parse().unwrap_or_else(|_| panic!("{detector}"));
        assert!(v > 0.0 && v < 1000.0, "{detector}");
    }
    assert!(
        text.lines()
            .any(|l| l.starts_with("| pipeline, tendon frame") && l.contains("tendon frames/s")),
        "{text}"
    );
}

#[test]
fn detector_trains_on_two_datasets_with_soft_labels_and_lists_its_decisions() {
    let tmp = tempfile::tempdir().unwrap();
    let synth = |name: &str, seed: &str, press: &str| {
        let out = tmp.path().join(name);
        let (ok, msg) = tactile(&[
            "synth",
            "visuotactile",
            "--sequences",
            "4",
            "--frames-per-sequence",
            "6",
            "--seed",
            seed,
            "--press-mm",
            press,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{msg}");
        out
    };
    let a = synth("a", "7", "0.0,4.0");
    let b = synth("b", "8", "0.1,0.6");
    let det = tmp.path().join("det");
    let train = |data: &[&Path], soft: &str| {
        let mut args = vec!["train", "detector", "--data"];
        args.extend(data.iter().map(|p| p.to_str().unwrap()));
        args.extend([
            "--out",
            det.to_str().unwrap(),
            "--width",
            "0.25",
            "--input",
            "64x48",
            "--max-epochs",
            "1",
            "--val-fraction",
            "0.25",
            "--soft-labels",
            soft,
        ]);
        tactile(&args)
    };
    let (ok, msg) = train(&[&a, &b], "0.2");
    assert!(ok, "{msg}");
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(det.join("training.json")).unwrap()).unwrap();
    // 3 of 4 sequences of each dataset train: 2 x 3 x 6 frames.
    assert_eq!(t["train_frames"], 36, "{t}");
    assert_eq!(t["config"]["soft_labels"]["width"], 0.2, "{t}");
    assert_eq!(t["config"]["soft_labels"]["threshold_mm"], 0.03, "{t}");
    // Its notes name both datasets, each a folder a reader can open (they
    // were one text joined by " + "), and say it fitted every split: it
    // splits by sequence whatever a split column says.
    let art: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(det.join("detector.json")).unwrap()).unwrap();
    let notes = &art["notes"];
    assert_eq!(notes["trained_on"], a.display().to_string(), "{notes}");
    assert_eq!(
        notes["also_trained_on"],
        serde_json::json!([b.display().to_string()]),
        "{notes}"
    );
    assert_eq!(notes["every_split"], true, "{notes}");
    // Per-frame decisions, one line per frame.
    let csv = tmp.path().join("decisions.csv");
    let (ok, msg) = tactile(&[
        "eval",
        "detector",
        "--model",
        det.to_str().unwrap(),
        "--data",
        a.to_str().unwrap(),
        "--frames",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    // It trained on every frame of `a` (split by sequence, every split):
    // its scores there are on frames it fitted, and it says so.
    assert!(
        msg.contains("warning: the model trained on every one of these 24 frames")
            && msg.contains("so these scores are on frames it fitted"),
        "{msg}"
    );
    // The record printed last keeps it, for a script reading the scores.
    let record = last_json(&msg);
    assert!(
        record["warning"]
            .as_str()
            .is_some_and(|w| w.contains("every one of these 24 frames")),
        "{record}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "file,tendon,probability,predicted,onset_release");
    assert_eq!(lines.len(), 1 + 24);
    for l in &lines[1..] {
        let p: f64 = l.split(',').nth(2).unwrap().parse().unwrap();
        assert!((0.0..=1.0).contains(&p), "{l}");
    }
    // Soft labels need the ridge amplitude: a dataset without it is named.
    let labels = b.join("labels.csv");
    let stripped: String = std::fs::read_to_string(&labels)
        .unwrap()
        .lines()
        .map(|l| l.rsplit_once(',').unwrap().0.to_string() + "\n")
        .collect();
    assert!(!stripped.contains("ridge_mm"));
    std::fs::write(&labels, stripped).unwrap();
    let (ok, msg) = train(&[&a, &b], "0.2");
    assert!(
        !ok && msg.contains("ridge_mm") && msg.contains(labels.to_str().unwrap()),
        "{msg}"
    );
    let (ok, msg) = train(&[&a], "0");
    assert!(
        !ok && msg.contains("soft-label width must be positive, got 0"),
        "{msg}"
    );
}

/// `tactile predict --model MODEL --data DATA --out OUT` with `extra`
/// flags, asserting that it succeeds; what it said.
fn predict(model: &Path, data: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "predict",
        "--model",
        model.to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let (ok, msg) = tactile(&args);
    assert!(ok, "{msg}");
    msg
}

/// Every third frame of the real edge set (1,254 of 3,762, its rows in
/// order), as a dataset made once per test binary in a folder that lives
/// as long as it: at a third of the time, its mean errors are the whole
/// set's to within 3 % (`models/pose-edge`: 0.0760 mm, 0.705 deg, 0.0151
/// mm against 0.0737, 0.717, 0.0154 over all 3,762; `models/cae-edge`
/// 0.1153, 1.001, 0.0221 against 0.1119, 1.015, 0.0222).
fn edge_thirds() -> &'static Path {
    static SUBSET: Subset = std::sync::OnceLock::new();
    kept_subset(&SUBSET, |dir| {
        real_subset("tactip127-edge", dir, |_| true, 3, usize::MAX)
    })
}

/// A real subset made once per test binary, kept in its temporary folder
/// as long as the binary runs.
type Subset = std::sync::OnceLock<(tempfile::TempDir, std::path::PathBuf)>;

/// `cell`'s subset, made by `make` in a new temporary folder the first
/// time it is asked for.
fn kept_subset(
    cell: &'static Subset,
    make: impl FnOnce(&Path) -> std::path::PathBuf,
) -> &'static Path {
    let (_, data) = cell.get_or_init(|| {
        let tmp = tempfile::tempdir().unwrap();
        let data = make(tmp.path());
        (tmp, data)
    });
    data
}

/// `tactile predict` with `model` over the real edge set's thirds
/// ([`edge_thirds`]): the mean absolute error of each target, the CSV's
/// header checked.
fn predict_edge_errors(model: &Path) -> [f64; 3] {
    let data = edge_thirds();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("estimates.csv");
    predict(model, data, &out, &[]);
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("file,x_mm,theta_deg,depth_mm"));
    let labels: std::collections::HashMap<String, Vec<f64>> =
        std::fs::read_to_string(data.join("labels.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| {
                let c: Vec<&str> = l.split(',').collect();
                let n = |i: usize| c[i].parse::<f64>().unwrap();
                (c[0].to_string(), vec![n(2), n(4), n(5)])
            })
            .collect();
    let mut err = [0.0f64; 3];
    let mut n = 0;
    for l in lines {
        let c: Vec<&str> = l.split(',').collect();
        let truth = &labels[c[0]];
        for k in 0..3 {
            err[k] += (c[k + 1].parse::<f64>().unwrap() - truth[k]).abs();
        }
        n += 1;
    }
    assert_eq!(n, 1254);
    err.map(|e| e / n as f64)
}

#[test]
fn predict_writes_every_estimate_of_an_encoder_folder_in_the_labels_units() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    // Mean absolute error over every frame, all of them its training or
    // validation frames (0.112 mm, 1.01 deg, 0.022 mm when shipped): the
    // estimates are in the labels' units and ranges, and the jointly
    // trained 112 px features carry the pose (paper A's unsupervised
    // CAE-16 is about 0.4 mm, 4 deg; the same recipe scored 0.194 mm,
    // 1.87 deg, 0.042 mm on the frames it never saw).
    let [x, theta, depth] = predict_edge_errors(&root.join("models/cae-edge"));
    assert!(
        x < 0.16 && theta < 1.5 && depth < 0.03,
        "{x} mm, {theta} deg, {depth} mm"
    );
}

#[test]
fn predict_runs_the_shipped_pose_network_in_the_labels_units() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    // Over every frame, all of them trained on (its recipe scored x 0.137
    // mm, theta 1.32 deg, depth 0.031 mm on the frames of the split seed 7,
    // 0.2 it never saw): well inside the CAE route's errors.
    let [x, theta, depth] = predict_edge_errors(&root.join("models/pose-edge"));
    assert!(
        x < 0.16 && theta < 1.5 && depth < 0.03,
        "{x} mm, {theta} deg, {depth} mm"
    );
}

/// A dataset in `dir/NAME` of the rows of the real set `NAME` that `keep`
/// (a labels line) takes, every `every`th of them up to `count`, their
/// frames copied into its `frames/`.
fn real_subset(
    name: &str,
    dir: &Path,
    keep: impl Fn(&str) -> bool,
    every: usize,
    count: usize,
) -> std::path::PathBuf {
    let real = shared_real().join(name);
    let data = dir.join(name);
    std::fs::create_dir_all(data.join("frames")).unwrap();
    let labels = std::fs::read_to_string(real.join("labels.csv")).unwrap();
    let mut lines = labels.lines();
    let mut text = format!("{}\n", lines.next().unwrap());
    let mut kept = 0usize;
    for l in lines.filter(|l| keep(l)).step_by(every).take(count) {
        let file = l.split(',').next().unwrap();
        std::fs::copy(real.join(file), data.join(file)).unwrap();
        text += &format!("{l}\n");
        kept += 1;
    }
    std::fs::write(data.join("labels.csv"), text).unwrap();
    let mut manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(real.join("manifest.json")).unwrap())
            .unwrap();
    manifest["count"] = kept.into();
    std::fs::write(data.join("manifest.json"), manifest.to_string()).unwrap();
    data
}

/// A dataset in `dir/tactip331-surface` of `count` real surface `val`
/// frames (every `every`th).
fn surface_val_subset(dir: &Path, every: usize, count: usize) -> std::path::PathBuf {
    real_subset(
        "tactip331-surface",
        dir,
        |l| l.ends_with(",val"),
        every,
        count,
    )
}

/// A CSV's rows (header first), split at commas.
fn csv_rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// Each target's error in `evaluate`'s `json` is the mean absolute
/// difference between `predict`'s `estimates` and the `labels` over the CSV
/// lines `lines` (1 is the first row after the header), to the 4 decimals
/// `predict` writes.
fn assert_errors_are_predicts(
    json: &serde_json::Value,
    estimates: &[Vec<String>],
    labels: &[Vec<String>],
    lines: &[usize],
) {
    let column = |rows: &[Vec<String>], name: &str| rows[0].iter().position(|c| c == name).unwrap();
    for t in json["targets"].as_array().unwrap() {
        let name = t["target"].as_str().unwrap();
        let (e, l) = (column(estimates, name), column(labels, name));
        let mean = lines
            .iter()
            .map(|&i| {
                let truth: f64 = labels[i][l].parse().unwrap();
                (estimates[i][e].parse::<f64>().unwrap() - truth).abs()
            })
            .sum::<f64>()
            / lines.len() as f64;
        assert!(
            (t["mae"].as_f64().unwrap() - mean).abs() < 1e-3,
            "{name}: {t}"
        );
    }
}

#[test]
fn evaluate_scores_a_pose_network_on_one_split_of_a_dataset() {
    // 16 rows of the surface set, every 500th: 12 of its `train` split and
    // 4 of `val`. `evaluate --split val` scores the 4 alone: each target's
    // error is the mean of `predict`'s estimates against their labels.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let model = root.join("models/pose-surface");
    let tmp = tempfile::tempdir().unwrap();
    let data = real_subset("tactip331-surface", tmp.path(), |_| true, 500, 16);
    let est = tmp.path().join("estimates.csv");
    predict(&model, &data, &est, &[]);
    let (estimates, labels) = (csv_rows(&est), csv_rows(&data.join("labels.csv")));
    let column = |rows: &[Vec<String>], name: &str| rows[0].iter().position(|c| c == name).unwrap();
    let split = column(&labels, "split");
    let val: Vec<usize> = (1..labels.len())
        .filter(|&i| labels[i][split] == "val")
        .collect();
    assert_eq!(val.len(), 4);
    let scored = |extra: &[&str]| {
        let mut args = vec!["evaluate", "--model", model.to_str().unwrap()];
        args.extend_from_slice(&["--data", data.to_str().unwrap()]);
        args.extend_from_slice(extra);
        tactile(&args)
    };
    let (ok, msg) = scored(&["--split", "validation"]);
    assert!(ok, "{msg}");
    assert!(msg.contains("(its 'val' split, 4 frames)"), "{msg}");
    assert!(
        msg.contains("the model trained on every one of these 4 frames"),
        "{msg}"
    );
    let json = last_json(&msg);
    assert_eq!(json["frames"], 4);
    assert_errors_are_predicts(&json, &estimates, &labels, &val);
    for t in json["targets"].as_array().unwrap() {
        assert!(t["coverage"]["within_1_std"].as_f64().is_some(), "{t}");
    }
    // A split the column does not hold, and a dataset without the column.
    let (ok, msg) = scored(&["--split", "nope"]);
    assert!(
        !ok && msg.contains("labels.csv: no row of its 'split' column is 'nope'"),
        "{msg}"
    );
    let (ok, msg) = tactile(&[
        "evaluate",
        "--model",
        model.to_str().unwrap(),
        "--data",
        root.join("samples/virtual-tactip").to_str().unwrap(),
        "--split",
        "val",
    ]);
    assert!(
        !ok && msg.contains("no 'split' column to take the 'val' rows from"),
        "{msg}"
    );
}

#[test]
fn evaluate_leaves_a_frame_cut_short_out_of_its_scores() {
    // 8 rows of the surface set with the 3rd frame cut to half its bytes
    // behind a whole header (a copy stopped half-way): either kind of model
    // scores the other 7, each target's error the mean of `predict`'s
    // estimates of those 7 against their labels, with the warning naming
    // the frame. Every frame cut: refused, naming the first.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let data = real_subset("tactip331-surface", tmp.path(), |_| true, 997, 8);
    let labels = csv_rows(&data.join("labels.csv"));
    let file = labels[0].iter().position(|c| c == "file").unwrap();
    let frame = |i: usize| data.join(&labels[i + 1][file]);
    for model in ["models/pose-surface", "models/cae-surface"] {
        let model = root.join(model);
        let est = tmp.path().join("estimates.csv");
        predict(&model, &data, &est, &[]);
        let estimates = csv_rows(&est);
        let whole = std::fs::read(frame(2)).unwrap();
        std::fs::write(frame(2), &whole[..whole.len() / 2]).unwrap();
        let (ok, msg) = tactile(&[
            "evaluate",
            "--model",
            model.to_str().unwrap(),
            "--data",
            data.to_str().unwrap(),
        ]);
        std::fs::write(frame(2), &whole).unwrap();
        assert!(ok, "{msg}");
        assert!(
            msg.contains("1 of the 8 frames could not be decoded past their header"),
            "{msg}"
        );
        assert!(msg.contains(&labels[3][file]), "{msg}");
        let json = last_json(&msg);
        assert_eq!(json["frames"], 7, "{json}");
        // The title says so too (it said "8 frames" over tables of 7).
        assert!(msg.contains(" (7 of its 8 frames scored)."), "{msg}");
        assert_errors_are_predicts(&json, &estimates, &labels, &[1, 2, 4, 5, 6, 7, 8]);
    }
    for i in 0..8 {
        let whole = std::fs::read(frame(i)).unwrap();
        std::fs::write(frame(i), &whole[..whole.len() / 2]).unwrap();
    }
    let (ok, msg) = tactile(&[
        "evaluate",
        "--model",
        root.join("models/pose-surface").to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
    ]);
    assert!(!ok, "{msg}");
    assert!(msg.contains("8 of the 8"), "{msg}");
    assert!(msg.contains(&labels[1][file]), "{msg}");
}

#[test]
fn paper_b_evals_leave_a_frame_cut_short_out_of_their_scores() {
    // The first tendon frame of 20 cut to half its bytes behind a whole
    // header (a copy stopped half-way): each of `eval detector`,
    // `segmenter` and `depth` scores the other frames, with the warning
    // naming it. The detector's other decisions are the uncut run's, their
    // onset and release flags those of the whole sequences. Every frame
    // cut: refused, naming the first.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("vt");
    synth_visuotactile(&data, 2, 10, 3);
    let labels = csv_rows(&data.join("labels.csv"));
    let column = |name: &str| labels[0].iter().position(|c| c == name).unwrap();
    let (file, tendon) = (column("file"), column("tendon"));
    let tendons = (1..labels.len())
        .filter(|&i| labels[i][tendon] == "1")
        .count();
    let k = (1..labels.len())
        .find(|&i| labels[i][tendon] == "1")
        .unwrap();
    assert!((2..20).contains(&tendons), "{tendons} tendon frames");
    let eval = |model: &str, extra: &[&str]| {
        let mut args = vec!["eval", model, "--model"];
        let dir = root.join("models").join(model);
        args.push(dir.to_str().unwrap());
        args.extend_from_slice(&["--data", data.to_str().unwrap()]);
        args.extend_from_slice(extra);
        tactile(&args)
    };
    let uncut = tmp.path().join("uncut.csv");
    let (ok, msg) = eval("detector", &["--frames", uncut.to_str().unwrap()]);
    assert!(ok, "{msg}");
    let frame = data.join(&labels[k][file]);
    let whole = std::fs::read(&frame).unwrap();
    std::fs::write(&frame, &whole[..whole.len() / 2]).unwrap();
    let named = |msg: &str, of: usize| {
        let told = format!("warning: 1 of the {of} frames could not be decoded past their header");
        assert!(msg.contains(&told), "{msg}");
        assert!(
            msg.contains(&format!("{}: cannot decode image", labels[k][file])),
            "{msg}"
        );
    };

    let cut = tmp.path().join("cut.csv");
    let (ok, msg) = eval("detector", &["--frames", cut.to_str().unwrap()]);
    assert!(ok, "{msg}");
    named(&msg, 20);
    assert_eq!(last_json(&msg)["all"]["frames"], 19);
    let (before, after) = (csv_rows(&uncut), csv_rows(&cut));
    let kept: Vec<&Vec<String>> = (0..before.len())
        .filter(|&i| i != k)
        .map(|i| &before[i])
        .collect();
    assert_eq!(after.len(), kept.len());
    for (a, b) in after.iter().zip(kept) {
        // file, tendon, onset_release alike; the probability to the CSV's 6 decimals.
        assert_eq!((&a[0], &a[1], &a[4]), (&b[0], &b[1], &b[4]));
        if a[0] != "file" {
            let (pa, pb): (f64, f64) = (a[2].parse().unwrap(), b[2].parse().unwrap());
            assert!((pa - pb).abs() < 1e-5, "{a:?} {b:?}");
        }
    }

    let (ok, msg) = eval("segmenter", &[]);
    assert!(ok, "{msg}");
    named(&msg, tendons);
    let json = last_json(&msg);
    assert_eq!(json["paths"][0]["path"], "all");
    assert_eq!(json["paths"][0]["frames"], tendons - 1);
    // Every tendon of this seed is straight: the curved row has no score
    // (before, an IoU of -0.0000 and NaN degrees).
    assert_eq!(json["paths"][1]["frames"], 0);
    assert!(
        msg.contains("| curved (arc + s-curve) | 0 | - | - | - | - | - |"),
        "{msg}"
    );
    assert!(!msg.contains("NaN"), "{msg}");

    let maps = tmp.path().join("maps");
    let (ok, msg) = eval(
        "depth",
        &[
            "--save-png",
            maps.to_str().unwrap(),
            "--png-frames",
            &(k + 1).to_string(),
        ],
    );
    assert!(ok, "{msg}");
    named(&msg, 20);
    let json = last_json(&msg);
    assert_eq!(json["scores"]["frames"], 19);
    // The frame after the first `k + 1` is drawn instead of the cut one.
    assert_eq!(json["heat_maps"], k + 1);
    assert_eq!(std::fs::read_dir(&maps).unwrap().count(), k + 1);

    for row in &labels[1..] {
        let f = data.join(&row[file]);
        let whole = std::fs::read(&f).unwrap();
        std::fs::write(&f, &whole[..whole.len() / 2]).unwrap();
    }
    let first_tendon = &labels[k][file];
    for (model, first, of) in [
        ("detector", &labels[1][file], 20),
        ("segmenter", first_tendon, tendons),
        ("depth", &labels[1][file], 20),
    ] {
        let (ok, msg) = eval(model, &[]);
        assert!(!ok, "{model}: {msg}");
        assert!(
            msg.contains(&format!("{first}: cannot decode image")),
            "{model}: {msg}"
        );
        assert!(
            msg.contains(&format!("{of} of the {of} frames")),
            "{model}: {msg}"
        );
    }
}

#[test]
fn evaluate_says_what_predict_says_of_frames_of_another_sensor() {
    // The real edge set's pose network scored on virtual TacTip frames: its
    // errors, with the warning `predict` gives that the frames are unlike
    // its training frames, in the notes and the JSON, for either kind of
    // model. A target the labels do not hold is refused naming it.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let data = root.join("samples/virtual-tactip");
    for model in ["models/pose-edge", "models/cae-edge"] {
        let (ok, msg) = tactile(&[
            "evaluate",
            "--model",
            root.join(model).to_str().unwrap(),
            "--data",
            data.to_str().unwrap(),
        ]);
        assert!(ok, "{model}: {msg}");
        assert!(
            msg.contains("warning: frames/000000.png, frames/000001.png"),
            "{msg}"
        );
        let json = last_json(&msg);
        let said = json["frame_warnings"][0].as_str().unwrap();
        assert!(
            said.contains("pins spaced unlike those of the 3762 frames"),
            "{json}"
        );
    }
    let (ok, msg) = tactile(&[
        "evaluate",
        "--model",
        root.join("models/pose-surface").to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
    ]);
    assert!(
        !ok && msg.contains("labels.csv: no column 'roll_deg', a target the model estimates"),
        "{msg}"
    );
}

#[test]
fn predict_reads_a_folder_of_frames_and_a_ros_bag_as_it_reads_a_dataset() {
    // A robot records its TacTip as a bag (mono8 Images) or saves frames
    // to a folder: `predict --data` reads both, each frame's estimates the
    // dataset's to the CSV's 4 decimals (1e-4: the batches differ), a
    // bag's frames keep their stamps (a `stamp_ns` column; MCAP messages
    // stamped like their frames).
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let model = root.join("models/pose-surface");
    let tmp = tempfile::tempdir().unwrap();
    let data = surface_val_subset(tmp.path(), 150, 12);
    let by_file = |rows: Vec<Vec<String>>| {
        let header = rows[0].clone();
        let body: std::collections::BTreeMap<String, Vec<f64>> = rows[1..]
            .iter()
            .map(|r| {
                let name = Path::new(&r[0]).file_name().unwrap().to_str().unwrap();
                let v = r[1..].iter().map(|c| c.parse().unwrap()).collect();
                (name.to_string(), v)
            })
            .collect();
        (header, body)
    };
    let out = tmp.path().join("dataset.csv");
    predict(&model, &data, &out, &[]);
    let (want_header, want) = by_file(csv_rows(&out));
    assert_eq!(want.len(), 12);
    let same =
        |what: &str, header: &[String], got: &std::collections::BTreeMap<String, Vec<f64>>| {
            assert_eq!(header, want_header, "{what}: the dataset's columns");
            assert_eq!(
                got.keys().collect::<Vec<_>>(),
                want.keys().collect::<Vec<_>>(),
                "{what}"
            );
            for (file, v) in got {
                for (j, (a, b)) in v.iter().zip(&want[file]).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-4,
                        "{what} {file} {}: {a} against {b}",
                        header[j + 1]
                    );
                }
            }
        };
    // The frames folder alone: no manifest, no labels.
    let out = tmp.path().join("folder.csv");
    predict(&model, &data.join("frames"), &out, &[]);
    let (header, got) = by_file(csv_rows(&out));
    same("folder", &header, &got);
    // A frame named with a tab and a newline: the CSV keeps its name, and
    // the table printed keeps one line per frame, every line the header's
    // columns (before, the name broke its row in two).
    let odd = tmp.path().join("odd");
    std::fs::create_dir(&odd).unwrap();
    let first = std::fs::read_dir(data.join("frames"))
        .unwrap()
        .next()
        .unwrap();
    let first = first.unwrap().path();
    std::fs::copy(&first, odd.join("a\tb\nc.png")).unwrap();
    std::fs::copy(&first, odd.join("plain.png")).unwrap();
    // What `predict` prints of `data` with `--out out` and `extra`.
    let printed = |data: &Path, out: &Path, extra: &[&str]| {
        let r = Command::new(env!("CARGO_BIN_EXE_tactile"))
            .args(["predict", "--model", model.to_str().unwrap(), "--data"])
            .args([data, Path::new("--out"), out])
            .args(extra)
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        String::from_utf8_lossy(&r.stdout).into_owned()
    };
    let table = printed(&odd, &tmp.path().join("odd.csv"), &[]);
    let rows: Vec<&str> = table.lines().take(3).collect();
    assert!(
        rows[1].starts_with("a\\x09b\\x0ac.png\t") && rows[2].starts_with("plain.png\t"),
        "{table}"
    );
    for r in &rows {
        assert_eq!(r.split('\t').count(), header.len(), "{table}");
    }
    // (quoted by the CSV's rules)
    let csv = std::fs::read_to_string(tmp.path().join("odd.csv")).unwrap();
    assert!(
        csv.contains("\n\"a\tb\nc.png\",") && csv.contains("\nplain.png,"),
        "{csv}"
    );
    // Streamed (`--out -`): one JSON object per frame on stdout, as it is
    // estimated, the same values; `--limit` keeps the first frames.
    let lines: Vec<serde_json::Value> =
        printed(&data.join("frames"), Path::new("-"), &["--limit", "5"])
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
    assert_eq!(lines.len(), 5);
    for v in &lines {
        let file = v["file"].as_str().unwrap();
        for (name, x) in want_header[1..].iter().zip(&got[file]) {
            let y = v[name.as_str()].as_f64().unwrap();
            assert!(
                (x - y).abs() <= 1e-4,
                "streamed {file} {name}: {y} against {x}"
            );
        }
    }
    // The same frames as a ROS 2 bag of mono8 Images, 30 Hz.
    let t0: i64 = 1_700_000_000_000_000_000;
    let bag = tmp.path().join("tactip.mcap");
    let mut names = Vec::new();
    let mut w = common::ImageBag::create(&bag, "/tactip/image_raw", "tactip");
    for (i, file) in want.keys().enumerate() {
        let img = image::open(data.join("frames").join(file))
            .unwrap()
            .to_luma8();
        let t = t0 + i as i64 * 33_333_333;
        w.write(t, (img.width(), img.height(), 1), "mono8", img.as_raw());
        names.push((format!("{i:06}"), file.clone(), t));
    }
    w.finish();
    let out = tmp.path().join("bag.csv");
    predict(&model, &bag, &out, &["--topic", "/tactip/image_raw"]);
    let rows = csv_rows(&out);
    assert_eq!(rows[0][..2], ["file".to_string(), "stamp_ns".to_string()]);
    // Without the stamps, each frame named by its file.
    let header = [vec![rows[0][0].clone()], rows[0][2..].to_vec()].concat();
    let renamed: Vec<Vec<String>> = std::iter::once(header)
        .chain(rows[1..].iter().zip(&names).map(|(r, (number, file, t))| {
            assert_eq!(
                (&r[0], &r[1]),
                (number, &t.to_string()),
                "the frame's number and stamp"
            );
            [vec![file.clone()], r[2..].to_vec()].concat()
        }))
        .collect();
    let (header, got) = by_file(renamed);
    same("bag", &header, &got);
    // As ROS 2 messages: one per frame, stamped like it.
    let out = tmp.path().join("estimates.mcap");
    predict(&model, &bag, &out, &[]);
    let bytes = std::fs::read(&out).unwrap();
    let stamps: Vec<u64> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == "/tactile/estimates")
        .map(|m| m.log_time)
        .collect();
    assert_eq!(stamps, names.iter().map(|n| n.2 as u64).collect::<Vec<_>>());
    // The input as the output, or a topic of a dataset: refused, nothing written.
    let before = std::fs::read(&bag).unwrap();
    for (data, extra) in [
        (&bag, vec![]),
        (&data, vec!["--topic", "/tactip/image_raw"]),
    ] {
        let mut args = vec!["predict", "--model", model.to_str().unwrap()];
        args.extend([
            "--data",
            data.to_str().unwrap(),
            "--out",
            bag.to_str().unwrap(),
        ]);
        args.extend(extra);
        let (ok, msg) = tactile(&args);
        assert!(
            !ok && (msg.contains("this output is the input")
                || msg.contains("is a dataset folder")),
            "{msg}"
        );
    }
    assert_eq!(std::fs::read(&bag).unwrap(), before);
    // The recorder killed after the last frame's chunk (no indexes, no
    // footer): every frame estimated, to a file or streamed, and a
    // warning that the file was cut short.
    let summary = mcap::Summary::read(&before).unwrap().unwrap();
    let last = summary.chunk_indexes.last().unwrap();
    let cut = tmp.path().join("killed.mcap");
    std::fs::write(
        &cut,
        &before[..(last.chunk_start_offset + last.chunk_length) as usize],
    )
    .unwrap();
    for out in [tmp.path().join("killed.csv").to_str().unwrap(), "-"] {
        let args = [
            "predict",
            "--model",
            model.to_str().unwrap(),
            "--data",
            cut.to_str().unwrap(),
            "--out",
            out,
        ];
        let (ok, msg) = tactile(&args);
        assert!(
            ok && msg.contains("killed.mcap ends without its MCAP footer")
                && msg.contains(&format!("({} on /tactip/image_raw in all)", names.len())),
            "{out}: {msg}"
        );
    }
    assert_eq!(csv_rows(&tmp.path().join("killed.csv")), rows);
    // A bag whose image topic holds no message: refused alike whether the
    // estimates go to a file or stream out, naming the topic (before,
    // "no frames to estimate").
    let empty = tmp.path().join("empty.mcap");
    common::ImageBag::create(&empty, "/tactip/image_raw", "tactip").finish();
    for out in [tmp.path().join("none.csv").to_str().unwrap(), "-"] {
        let (ok, msg) = tactile(&[
            "predict",
            "--model",
            model.to_str().unwrap(),
            "--data",
            empty.to_str().unwrap(),
            "--topic",
            "/tactip/image_raw",
            "--out",
            out,
        ]);
        assert!(
            !ok && msg.contains("empty.mcap: topic /tactip/image_raw: has no messages"),
            "{out}: {msg}"
        );
    }
    assert!(!tmp.path().join("none.csv").exists());
    // A frame of another camera among them (a third of the size, smaller
    // than the model's 440 px crop): still estimated, with a warning that
    // names it.
    let mixed = tmp.path().join("mixed");
    std::fs::create_dir(&mixed).unwrap();
    for (i, file) in want.keys().take(2).enumerate() {
        let img = image::open(data.join("frames").join(file)).unwrap();
        let img = if i == 1 { img.thumbnail(148, 147) } else { img };
        img.save(mixed.join(format!("{i:04}.png"))).unwrap();
    }
    let predict_mixed = |out: &Path| {
        tactile(&[
            "predict",
            "--model",
            model.to_str().unwrap(),
            "--data",
            mixed.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let out = tmp.path().join("mixed.csv");
    let (ok, msg) = predict_mixed(&out);
    assert!(ok, "{msg}");
    assert_eq!(csv_rows(&out).len(), 3);
    let warned: Vec<&str> = msg.lines().filter(|l| l.contains("warning")).collect();
    assert_eq!(warned.len(), 1, "{msg}");
    assert!(
        warned[0].contains(&mixed.join("0001.png").display().to_string())
            && warned[0].contains("smaller than the model's 440x440 crop"),
        "{msg}"
    );
    // A frame too small for even the pin image cannot be estimated: the
    // error names its file, says it once, and no estimates are written.
    image::open(data.join("frames").join(want.keys().next().unwrap()))
        .unwrap()
        .resize_exact(12, 12, image::imageops::FilterType::Triangle)
        .save(mixed.join("0002.png"))
        .unwrap();
    let out = tmp.path().join("tiny.csv");
    let (ok, msg) = predict_mixed(&out);
    assert!(!ok && !out.exists(), "{msg}");
    // Named by its path as the folder was given (before, "0002.png"
    // alone, whichever folder it was in).
    let tiny = mixed.join("0002.png");
    assert!(
        msg.contains(&format!(
            "{}: frame is 12x12, smaller than the",
            tiny.display()
        )) && msg.matches("frame is 12x12").count() == 1,
        "{msg}"
    );
    // In a stream (here a bag), by its number.
    let tiny_bag = tmp.path().join("tiny.mcap");
    let mut w = common::ImageBag::create(&tiny_bag, "/tactip/image_raw", "tactip");
    let rest = image::open(data.join("frames").join(want.keys().next().unwrap()))
        .unwrap()
        .to_luma8();
    w.write(t0, (rest.width(), rest.height(), 1), "mono8", rest.as_raw());
    w.write(t0 + 33_333_333, (12, 12, 1), "mono8", &[0; 144]);
    w.finish();
    let (ok, msg) = tactile(&[
        "predict",
        "--model",
        model.to_str().unwrap(),
        "--data",
        tiny_bag.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok && !out.exists(), "{msg}");
    assert!(
        msg.contains("frame 000001: frame is 12x12, smaller than the"),
        "{msg}"
    );
}

#[test]
fn predict_through_onnxruntime_gives_the_burn_estimates() {
    // The deployment path the latency goals are timed on: `--runtime onnx`
    // runs each network's ONNX export. On 12 real surface frames, the
    // shipped pose ensemble and the CAE route give burn's estimates and
    // deviations within 2e-3 of each target's unit.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let data = surface_val_subset(tmp.path(), 150, 12);
    let estimates = |model: &str, runtime: &str| -> Vec<Vec<String>> {
        let out = tmp.path().join(format!("{model}-{runtime}.csv"));
        predict(
            &root.join("models").join(model),
            &data,
            &out,
            &["--runtime", runtime],
        );
        csv_rows(&out)
    };
    for model in ["pose-surface", "cae-surface"] {
        let (onnx, flex) = (estimates(model, "onnx"), estimates(model, "burn-flex"));
        assert_eq!(onnx.len(), 13, "{model}");
        assert_eq!(onnx[0], flex[0], "{model}: the same columns");
        assert!(
            onnx[0].iter().any(|c| c == "shear_theta_deg_std"),
            "{model}"
        );
        for (a, b) in onnx[1..].iter().zip(&flex[1..]) {
            assert_eq!(a[0], b[0], "{model}: the same frames in the same order");
            for (j, (x, y)) in a[1..].iter().zip(&b[1..]).enumerate() {
                let (x, y): (f64, f64) = (x.parse().unwrap(), y.parse().unwrap());
                assert!(
                    (x - y).abs() <= 2e-3,
                    "{model} {} on {}: onnx {x}, burn {y}",
                    onnx[0][j + 1],
                    a[0]
                );
            }
        }
    }
    // --device and --runtime name the same choice: both at once is refused.
    let (ok, msg) = tactile(&[
        "predict",
        "--model",
        root.join("models/pose-surface").to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--device",
        "flex",
        "--runtime",
        "onnx",
    ]);
    assert!(!ok && msg.contains("--runtime"), "{msg}");
}

#[test]
fn a_pose_network_trains_scores_its_held_out_frames_and_predicts() {
    let data = shared_real().join("tactip127-edge");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("pose");
    let (ok, msg) = tactile(&[
        "train",
        "pose",
        "--data",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--input-px",
        "32",
        "--exclude-test",
        "0.2",
        "--max-epochs",
        "3",
    ]);
    assert!(ok, "{msg}");
    assert!(out.join("pose.json").is_file() && out.join("curves.png").is_file());
    // The 752 frames of the split were never trained on; three epochs of a
    // 32 px network already beat guessing the mean (x spans +-5 mm).
    let line = msg
        .lines()
        .find(|l| l.contains("held-out test frames"))
        .unwrap();
    assert!(line.starts_with("752 "), "{line}");
    let x: f64 = line
        .split("x_mm ")
        .nth(1)
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(x < 1.5, "{line}");
    let [x, theta, depth] = predict_edge_errors(&out);
    assert!(
        x < 1.5 && theta < 15.0 && depth < 0.4,
        "{x} {theta} {depth}"
    );
    // A network that cannot be built is refused before any frame is read.
    let (ok, msg) = tactile(&[
        "train",
        "pose",
        "--data",
        data.to_str().unwrap(),
        "--out",
        tmp.path().join("p2").to_str().unwrap(),
        "--input-px",
        "30",
    ]);
    assert!(!ok && msg.contains("input side 30"), "{msg}");
    assert!(!tmp.path().join("p2").join("pose.json").exists());
}

#[test]
fn calibrating_the_detector_keeps_every_decision_and_lowers_its_calibration_error() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    // The shipped detector as it is: one network or an ensemble.
    let model = tmp.path().join("detector");
    copy_model(&root.join("models/detector"), &model);
    let (fit, test) = (tmp.path().join("fit"), tmp.path().join("test"));
    for (dir, seed) in [(&fit, "5151"), (&test, "5252")] {
        let (ok, msg) = tactile(&[
            "synth",
            "visuotactile",
            "--sequences",
            "6",
            "--frames-per-sequence",
            "20",
            "--press-mm",
            "0.05,1.0",
            "--seed",
            seed,
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(ok, "{msg}");
    }
    let decisions = |name: &str| {
        let csv = tmp.path().join(name);
        let (ok, msg) = tactile(&[
            "eval",
            "detector",
            "--model",
            model.to_str().unwrap(),
            "--data",
            test.to_str().unwrap(),
            "--frames",
            csv.to_str().unwrap(),
        ]);
        assert!(ok, "{msg}");
        assert!(msg.contains("expected calibration error"), "{msg}");
        let rows: Vec<(String, f64)> = std::fs::read_to_string(&csv)
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| {
                let c: Vec<&str> = l.split(',').collect();
                (c[3].to_string(), c[2].parse().unwrap())
            })
            .collect();
        rows
    };
    let before = decisions("before.csv");
    // A set with one class (no contact: no tendon) cannot be fitted:
    // refused, the model untouched.
    let none = tmp.path().join("none");
    let (ok, msg) = tactile(&[
        "synth",
        "visuotactile",
        "--count",
        "30",
        "--press-mm",
        "0,0",
        "--out",
        none.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    // Every weights file of the folder (an ensemble's members' too).
    let weights = || -> Vec<Vec<u8>> {
        let mut files = vec![model.join("detector.bpk")];
        files.extend((0..8).map(|k| model.join(format!("member-{k}/detector.bpk"))));
        files
            .iter()
            .filter(|f| f.is_file())
            .map(|f| std::fs::read(f).unwrap())
            .collect()
    };
    let before_weights = weights();
    assert!(!before_weights.is_empty());
    let (ok, msg) = tactile(&[
        "train",
        "calibrate",
        "--model",
        model.to_str().unwrap(),
        "--data",
        none.to_str().unwrap(),
    ]);
    assert!(!ok && msg.contains("with and without"), "{msg}");
    assert_eq!(weights(), before_weights);
    let (ok, msg) = tactile(&[
        "train",
        "calibrate",
        "--model",
        model.to_str().unwrap(),
        "--data",
        fit.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    assert!(msg.contains("decisions unchanged"), "{msg}");
    let after = decisions("after.csv");
    assert_eq!(before.len(), after.len());
    let moved: f64 = before
        .iter()
        .zip(&after)
        .map(|(a, b)| (a.1 - b.1).abs())
        .sum();
    assert!(moved > 0.0, "the probabilities did not change");
    for (a, b) in before.iter().zip(&after) {
        assert_eq!(a.0, b.0, "a decision changed: {a:?} -> {b:?}");
    }
    let config = ["ensemble.json", "detector.json"]
        .map(|f| model.join(f))
        .into_iter()
        .find(|f| f.is_file())
        .unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(config).unwrap()).unwrap();
    assert!(json["notes"]["calibration"]["scale"].as_f64().unwrap() > 0.0);
}

#[test]
fn a_sphere_position_regressor_answers_for_spheres_and_evaluate_scores_what_frames_show() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let enc = root.join("models/cae-synth");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("ds");
    let d = data.to_str().unwrap();
    let (ok, msg) = tactile(&[
        "synth", "tactip", "--count", "70", "--seed", "5", "--out", d,
    ]);
    assert!(ok, "{msg}");
    let reg = tmp.path().join("position-sphere");
    let train = |shapes: &str| {
        tactile(&[
            "train",
            "regressor",
            "--encoder",
            enc.to_str().unwrap(),
            "--data",
            d,
            "--targets",
            "x_mm,y_mm",
            "--shapes",
            shapes,
            "--out",
            reg.to_str().unwrap(),
        ])
    };
    let (ok, msg) = train("teapot");
    assert!(!ok && msg.contains("shapes asked for"), "{msg}");
    let (ok, msg) = train("sphere");
    assert!(ok, "{msg}");
    let json = std::fs::read_to_string(reg.join("regressor.json")).unwrap();
    assert!(
        json.contains("\"shapes\"") && json.contains("sphere"),
        "{json}"
    );
    let (ok, msg) = tactile(&[
        "evaluate",
        "--encoder",
        enc.to_str().unwrap(),
        "--data",
        d,
        "--heads",
        enc.join("head").to_str().unwrap(),
        enc.join("position").to_str().unwrap(),
        reg.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    // The specialised regressor is scored on spheres alone; position only
    // where a frame shows it (no flat row; cylinders across their axis).
    assert!(msg.contains("x_mm (sphere)"), "{msg}");
    let section = msg
        .split("Contact position where the frame shows it")
        .nth(1)
        .unwrap();
    let table: Vec<&str> = section
        .lines()
        .take_while(|l| !l.starts_with('{'))
        .collect();
    assert!(table.iter().any(|l| l.starts_with("| sphere |")), "{msg}");
    assert!(!table.iter().any(|l| l.starts_with("| flat |")), "{msg}");
    let json = msg.lines().last().unwrap();
    assert!(json.contains("\"position\":{\"per_shape\""), "{json}");
    // On frames without a sphere it has nothing to score, and that is no error.
    let edges = tmp.path().join("edges");
    let e = edges.to_str().unwrap();
    let (ok, msg) = tactile(&[
        "synth", "tactip", "--count", "8", "--shapes", "edge", "--out", e,
    ]);
    assert!(ok, "{msg}");
    let (ok, msg) = tactile(&[
        "evaluate",
        "--encoder",
        enc.to_str().unwrap(),
        "--data",
        e,
        "--heads",
        enc.join("position").to_str().unwrap(),
        reg.to_str().unwrap(),
    ]);
    assert!(ok && !msg.contains("x_mm (sphere)"), "{msg}");
}

#[test]
fn a_head_trains_on_turned_copies_and_records_the_augmentation() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let enc = root.join("models/cae-synth");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("ds");
    let d = data.to_str().unwrap();
    let (ok, msg) = tactile(&[
        "synth", "tactip", "--count", "30", "--seed", "6", "--out", d,
    ]);
    assert!(ok, "{msg}");
    let out = tmp.path().join("head");
    let head_tested = |copies: &str, deg: &str, test: &[&str]| {
        tactile(
            &[
                &[
                    "train",
                    "head",
                    "--encoder",
                    enc.to_str().unwrap(),
                    "--data",
                    d,
                    "--folds",
                    "2",
                    "--repeats",
                    "1",
                    "--rotate-copies",
                    copies,
                    "--rotate-deg",
                    deg,
                    "--out",
                    out.to_str().unwrap(),
                ][..],
                test,
            ]
            .concat(),
        )
    };
    let head = |copies: &str, deg: &str| head_tested(copies, deg, &[]);
    let (ok, msg) = head("2", "90");
    assert!(!ok && msg.contains("at most 45 degrees"), "{msg}");
    // A turn without copies would do nothing: refused, not ignored (before,
    // the head trained without a turned frame, and any angle passed).
    for deg in ["10", "1e300"] {
        let (ok, msg) = head("0", deg);
        assert!(
            !ok && msg.contains("turns the rotated copies, and rotate_copies is 0"),
            "{msg}"
        );
    }
    assert!(!out.exists());
    // Tested on its own training frames (the folder again): refused before
    // a frame is encoded, naming the test set's labels and the first frame.
    let (ok, msg) = head_tested("2", "5", &["--test", d]);
    assert!(
        !ok && msg.contains("labels.csv:2")
            && msg.contains("30 of its 30 frames are frames the head trains on")
            && msg.contains("this one: 'frames/000000.png'"),
        "{msg}"
    );
    assert!(!out.exists());
    // A test set of other frames holding one copy of a training frame,
    // under another name in another folder: found by its bytes.
    let other = tmp.path().join("other");
    let (ok, msg) = tactile(&[
        "synth",
        "tactip",
        "--count",
        "10",
        "--seed",
        "7",
        "--out",
        other.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    std::fs::copy(
        data.join("frames/000003.png"),
        other.join("frames/000004.png"),
    )
    .unwrap();
    let (ok, msg) = head_tested("2", "5", &["--test", other.to_str().unwrap()]);
    assert!(
        !ok && msg.contains("labels.csv:6")
            && msg.contains("1 of its 10 frames are frames the head trains on")
            && msg.contains("this one: 'frames/000004.png'"),
        "{msg}"
    );
    assert!(!out.exists());
    let (ok, msg) = head("2", "5");
    assert!(ok && msg.contains("on 90 frames"), "{msg}");
    let json = std::fs::read_to_string(out.join("head.json")).unwrap();
    assert!(
        json.contains("rotation_augment") && json.contains("\"max_deg\": 5.0"),
        "{json}"
    );
    // Which frames it fitted, as every trainer records them.
    let notes = &serde_json::from_str::<serde_json::Value>(&json).unwrap()["notes"];
    assert_eq!(notes["trained_on"], d, "{notes}");
    assert_eq!(notes["every_split"], false, "{notes}");
}

/// The first `n` frames of the real edge set as a dataset of their own.
fn edge_subset(dir: &Path, n: usize) {
    let real = shared_real().join("tactip127-edge");
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    let text = std::fs::read_to_string(real.join("labels.csv")).unwrap();
    let mut lines = text.lines();
    let mut labels = format!("{}\n", lines.next().unwrap());
    for l in lines.take(n) {
        let file = l.split(',').next().unwrap();
        std::fs::copy(real.join(file), dir.join(file)).unwrap();
        labels.push_str(l);
        labels.push('\n');
    }
    std::fs::write(dir.join("labels.csv"), labels).unwrap();
    std::fs::write(
        dir.join("manifest.json"),
        format!(r#"{{"format":"tactile-dataset/1","kind":"tactip","sensor_spec":"test","width":256,"height":256,"generator":"test","seed":null,"count":{n}}}"#),
    )
    .unwrap();
}

#[test]
fn joint_training_keeps_the_pose_in_the_features() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("edge");
    edge_subset(&data, 300);
    let edge_area = |px: &str| {
        let name = format!("configs/preprocess/tactip127-edge-area{px}.json");
        root.join(name).to_str().unwrap().to_string()
    };
    let pre28 = edge_area("");
    let train = |out: &Path, pre: &str, extra: &[&str]| {
        let mut args = vec![
            "train",
            "cae",
            "--data",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--preprocess",
            pre,
            "--linear-latent",
            "--optimizer",
            "adam",
            "--batch-size",
            "32",
        ];
        args.extend(extra);
        tactile(&args)
    };
    // 28 px pin images, small widths, 30 epochs.
    let train28 = |out: &Path, extra: &[&str]| {
        let quick = [
            "--widths",
            "16,16,8,4",
            "--max-epochs",
            "30",
            "--patience",
            "30",
        ];
        train(out, &pre28, &[&quick[..], extra].concat())
    };
    let joint = tmp.path().join("joint");
    let (ok, msg) = train28(&joint, &["--joint-targets", "x_mm,theta_deg:180,depth_mm"]);
    assert!(ok, "{msg}");
    // The head's validation error (standardised columns: 1 is guessing
    // the mean) on 60 frames it never trained on.
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(joint.join("training.json")).unwrap())
            .unwrap();
    let metric = record["summary"]["best_val_metric"].as_f64().unwrap();
    assert!(metric < 0.5, "joint head validation MSE {metric}");
    assert_eq!(record["config"]["joint"]["targets"][1]["name"], "theta_deg");
    // Only the autoencoder is saved: an ordinary encoder folder.
    let feats = tmp.path().join("features.csv");
    let (ok, msg) = encode(&joint, &data, &feats);
    assert!(ok, "{msg}");
    let header = std::fs::read_to_string(&feats).unwrap();
    assert_eq!(header.lines().next().unwrap().split(',').count(), 17);
    // Its estimator, trained on every frame (the final model: no test frames).
    let (ok, msg) = tactile(&[
        "train",
        "regressor",
        "--encoder",
        joint.to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--targets",
        "x_mm,theta_deg:180,depth_mm",
        "--test-fraction",
        "0",
        "--out",
        joint.join("pose").to_str().unwrap(),
    ]);
    assert!(
        ok && msg.contains("every frame trained (60 for early stopping)"),
        "{msg}"
    );
    assert!(joint.join("pose/regressor.json").is_file());
    // A target the labels do not have, and a weight out of range, are
    // refused before training, naming what is wrong; nothing is saved.
    let bad = tmp.path().join("bad");
    let (ok, msg) = train28(&bad, &["--joint-targets", "teapot_mm"]);
    assert!(!ok && msg.contains("teapot_mm"), "{msg}");
    let (ok, msg) = train28(&bad, &["--joint-targets", "x_mm", "--joint-weight", "1e9"]);
    assert!(!ok && msg.contains("weight"), "{msg}");
    // A head setting without targets would be ignored: refused, naming it.
    let (ok, msg) = train28(&bad, &["--joint-weight", "-5", "--joint-loss", "l1"]);
    assert!(
        !ok && msg.contains(
            "joint_weight, joint_loss set the joint head, and no joint_targets (nor also_tasks)"
        ),
        "{msg}"
    );
    assert!(!bad.join("cae.json").exists());
    // 56 px pin images (a stem block in front of Table I's encoder) with
    // the head on the L1 loss: 32 features, the pin side from the
    // preprocessing; a side the decoder cannot give back is refused.
    let pre56 = edge_area("-56");
    let train56 = |out: &Path, pre: &str| {
        let head = [
            "--joint-targets",
            "x_mm,theta_deg:180,depth_mm",
            "--joint-loss",
            "l1",
        ];
        train(
            out,
            pre,
            &[&["--features", "32", "--max-epochs", "2"][..], &head].concat(),
        )
    };
    let big = tmp.path().join("joint56");
    let (ok, msg) = train56(&big, &pre56);
    assert!(ok, "{msg}");
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(big.join("training.json")).unwrap()).unwrap();
    assert_eq!(record["config"]["joint"]["loss"], "l1");
    assert_eq!(record["config"]["model"]["input_px"], 56);
    let feats56 = tmp.path().join("features56.csv");
    let (ok, msg) = encode(&big, &data, &feats56);
    assert!(ok, "{msg}");
    let header = std::fs::read_to_string(&feats56).unwrap();
    assert_eq!(header.lines().next().unwrap().split(',').count(), 33);
    let pre64 = tmp.path().join("pre64.json");
    let text = std::fs::read_to_string(root.join("configs/preprocess/tactip127-edge-area.json"))
        .unwrap()
        .replace("\"output_px\": 28", "\"output_px\": 64");
    std::fs::write(&pre64, text).unwrap();
    let (ok, msg) = train56(&bad, pre64.to_str().unwrap());
    assert!(!ok && msg.contains("input_px 64"), "{msg}");
    assert!(!bad.join("cae.json").exists());
}

/// Six shared ball presses in a calibration folder of their own.
fn ball_subset(dir: &Path) {
    let ball = shared_real().join("gelsight-ball");
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    for f in ["sensor.json", "background.png"] {
        std::fs::copy(ball.join(f), dir.join(f)).unwrap();
    }
    let csv = std::fs::read_to_string(ball.join("presses.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().take(7).collect();
    for l in &lines[1..] {
        let file = l.split(',').next().unwrap();
        std::fs::copy(ball.join(file), dir.join(file)).unwrap();
    }
    std::fs::write(dir.join("presses.csv"), lines.join("\n") + "\n").unwrap();
}

#[test]
fn a_calibration_says_what_its_folder_holds_before_it_trains() {
    // A warning about the folder (here a frame presses.csv does not list)
    // and what is being calibrated come before the epochs, not only in the
    // summary a minute later.
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("presses");
    ball_subset(&data);
    std::fs::copy(
        data.join("frames/press_01.png"),
        data.join("frames/press_99.png"),
    )
    .unwrap();
    let model = tmp.path().join("model");
    let out = Command::new(env!("CARGO_BIN_EXE_tactile"))
        .args(["calibrate", "ball", "--data"])
        .arg(&data)
        .arg("--out")
        .arg(&model)
        .args(["--factor", "8", "--val-presses", "2", "--max-epochs", "1"])
        .args(["--kernels", "3,1,1"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let at = |text: &str| {
        stderr
            .find(text)
            .unwrap_or_else(|| panic!("{text:?} not in {stderr}"))
    };
    let first_epoch = at("epoch 1/1");
    assert!(at("1 of its 7 frames are not listed in presses.csv") < first_epoch);
    assert!(
        at(
            "calibrating on 4 presses (2 held out to choose the epoch): a 4 mm ball, 0.0295 mm per pixel (from sensor.json), working grid 80x60"
        ) < first_epoch
    );
}

#[test]
fn a_calibrated_sensor_runs_through_calibrate_reconstruct_and_run() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("presses");
    ball_subset(&data);
    let model = tmp.path().join("model");
    let [d, m] = [&data, &model].map(|p| p.to_str().unwrap().to_string());
    let (ok, msg) = tactile(&[
        "calibrate",
        "ball",
        "--data",
        &d,
        "--out",
        &m,
        "--factor",
        "8",
        "--val-presses",
        "2",
        "--max-epochs",
        "3",
        "--kernels",
        "3,1,1",
    ]);
    assert!(ok, "{msg}");
    assert!(
        msg.contains("circles found on 6 annotated presses"),
        "{msg}"
    );
    let c = last_json(&msg);
    assert_eq!(c["train_presses"], 4);
    // The run loop on the calibration folder: indentation in every record,
    // a picture per frame, the summary's contact line.
    let records = tmp.path().join("records.jsonl");
    let render = tmp.path().join("pictures");
    let frames = data.join("frames");
    let run_into = |records: &Path| {
        tactile(&[
            "run",
            "--models",
            &m,
            "--data",
            frames.to_str().unwrap(),
            "--out",
            records.to_str().unwrap(),
            "--render",
            render.to_str().unwrap(),
            "--runtime",
            "burn-flex",
        ])
    };
    let (ok, msg) = run_into(&records);
    assert!(ok, "{msg}");
    assert!(msg.contains("indentation only"), "{msg}");
    let text = std::fs::read_to_string(&records).unwrap();
    let recs: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(recs.len(), 6);
    for r in &recs {
        assert_eq!(r["tendon"], false);
        assert!(r["indentation_peak_mm"].as_f64().unwrap() > 0.05, "{r}");
        assert!(r["contact_area_mm2"].as_f64().unwrap() > 1.0, "{r}");
    }
    let pictures = std::fs::read_dir(&render).unwrap().count();
    assert_eq!(pictures, 6);
    // Another run into the same pictures folder is refused before a frame
    // is processed: the first run's pictures are not written over.
    let newest = || {
        std::fs::read_dir(&render)
            .unwrap()
            .map(|e| {
                std::fs::metadata(e.unwrap().path())
                    .unwrap()
                    .modified()
                    .unwrap()
            })
            .max()
    };
    let first = newest();
    let again = tmp.path().join("again.jsonl");
    let (ok, msg) = run_into(&again);
    assert!(
        !ok && msg.contains("pictures: already holds files (left alone); choose a new folder"),
        "{msg}"
    );
    assert!(!again.exists(), "a refused run left {}", again.display());
    assert_eq!(
        (std::fs::read_dir(&render).unwrap().count(), newest()),
        (6, first)
    );
    // The same maps as tactile reconstruct writes.
    let maps = tmp.path().join("maps");
    let (ok, msg) = tactile(&[
        "reconstruct",
        "--model",
        &m,
        "--data",
        frames.to_str().unwrap(),
        "--out",
        maps.to_str().unwrap(),
        "--runtime",
        "burn-flex",
    ]);
    assert!(ok, "{msg}");
    let peak = last_json(&msg)["peak_mm"].as_f64().unwrap();
    let most = recs
        .iter()
        .map(|r| r["indentation_peak_mm"].as_f64().unwrap())
        .fold(0f64, f64::max);
    assert!((peak - most).abs() < 1e-3, "{peak} against {most}");
    // A frame of another size is another sensor's (or camera mode's): the
    // run goes on past it, gives it nothing and says why.
    let odd = tmp.path().join("odd");
    std::fs::create_dir_all(&odd).unwrap();
    let mut presses: Vec<_> = std::fs::read_dir(&frames)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    presses.sort();
    std::fs::copy(&presses[0], odd.join("a.png")).unwrap();
    write_png(&odd.join("small.png"), 320, 240);
    let (ok, msg) = tactile(&[
        "run",
        "--models",
        &m,
        "--data",
        odd.to_str().unwrap(),
        "--out",
        "-",
    ]);
    assert!(ok, "{msg}");
    let recs: Vec<serde_json::Value> = msg
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v.get("frame").is_some())
        .collect();
    assert_eq!(recs.len(), 2, "{msg}");
    assert_eq!(recs[1]["frame"], "small.png");
    assert_eq!(recs[1]["out_of_distribution"], true, "{msg}");
    assert!(recs[1]["indentation_peak_mm"].is_null(), "{msg}");
    assert!(
        recs[0]["indentation_peak_mm"].as_f64().unwrap() > 0.0,
        "{msg}"
    );
    assert!(
        recs[1]["unreadable"]
            .as_str()
            .is_some_and(|w| w.contains("small.png") && w.contains("(640, 480)")),
        "{msg}"
    );
    assert!(
        msg.contains("warning: 1 of 2 frames cannot be read by this calibrated sensor (blank, or frames of another sensor or camera mode): they got no indentation. The first: small.png: frame is (320, 240)"),
        "{msg}"
    );
    assert_eq!(last_json(&msg)["unreadable"]["frames"], 1, "{msg}");
}

/// The own-sensor loop in miniature: calibrate, render the sensor's own
/// frames, train the three palpation models on them, run the pipeline on
/// the folder; frames of another size are foreign, not errors.
#[test]
fn a_calibrated_sensor_trains_and_runs_its_own_pipeline() {
    let tmp = tempfile::tempdir().unwrap();
    let presses = tmp.path().join("presses");
    ball_subset(&presses);
    let m = tmp.path().join("model");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let run = |args: &[&str]| {
        let (ok, msg) = tactile(args);
        assert!(ok, "tactile {}: {msg}", args.join(" "));
        msg
    };
    run(&[
        "calibrate",
        "ball",
        "--data",
        &s(&presses),
        "--out",
        &s(&m),
        "--factor",
        "8",
        "--val-presses",
        "2",
        "--max-epochs",
        "2",
        "--kernels",
        "3,1,1",
    ]);
    assert!(m.join("optics.json").is_file());
    // The alias refuses what the calibrated sensor does not take.
    let data = tmp.path().join("renders");
    let (ok, msg) = tactile(&[
        "synth",
        "visuotactile",
        "--sensor",
        &s(&m),
        "--count",
        "4",
        "--width",
        "320",
        "--out",
        &s(&data),
    ]);
    assert!(!ok && msg.contains("--width"), "{msg}");
    assert!(!data.exists());
    run(&[
        "synth",
        "gelsight",
        "--sensor",
        &s(&m),
        "--sequences",
        "6",
        "--frames-per-sequence",
        "8",
        "--press-mm",
        "0.3,1.2",
        "--seed",
        "4",
        "--out",
        &s(&data),
        "--real-presses",
        &s(&presses),
        "--real-copies",
        "2",
        "--real-held-out",
        "2",
    ]);
    let manifest = std::fs::read_to_string(data.join("manifest.json")).unwrap();
    assert!(
        manifest.contains("\"depth\": \"indentation\""),
        "{manifest}"
    );
    // Four of the six presses joined as real negatives, two copies each,
    // labelled by the calibration's reconstruction (the ball pushes in, even
    // through this two-epoch calibration).
    let ds = tactile_core::dataset::Dataset::open(&data).unwrap();
    assert_eq!(ds.len(), 48 + 8);
    let real = &ds.manifest.extra["real_frames"];
    assert_eq!(real["used"].as_array().unwrap().len(), 4, "{real}");
    assert_eq!(real["held_out"].as_array().unwrap().len(), 2, "{real}");
    let (_, _, press) = ds.load_depth_m(48).unwrap();
    let peak = press.iter().copied().fold(0f32, f32::max);
    assert!(peak > 0.05e-3, "a ball press reconstructs to {peak} m");
    // Holding every press out leaves none: refused, naming the folder.
    let (ok, msg) = tactile(&[
        "synth",
        "gelsight",
        "--sensor",
        &s(&m),
        "--count",
        "4",
        "--out",
        &s(&tmp.path().join("none")),
        "--real-presses",
        &s(&presses),
        "--real-held-out",
        "6",
    ]);
    assert!(
        !ok && msg.contains("real_held_out") && msg.contains("presses"),
        "{msg}"
    );
    assert!(!tmp.path().join("none").exists());
    run(&[
        "train",
        "detector",
        "--data",
        &s(&data),
        "--out",
        &s(&m.join("detector")),
        "--input",
        "40x30",
        "--width",
        "0.25",
        "--max-epochs",
        "1",
        "--soft-labels",
        "0.2",
    ]);
    run(&[
        "train",
        "segmenter",
        "--data",
        &s(&data),
        "--out",
        &s(&m.join("segmenter")),
        "--side",
        "32",
        "--max-epochs",
        "1",
    ]);
    let depth_args = |out: &Path, prior: &Path| {
        [
            "train",
            "depth",
            "--data",
            &s(&data),
            "--out",
            &s(out),
            "--encoder",
            "small",
            "--input",
            "64x32",
            "--max-epochs",
            "1",
            "--prior-calibration",
            &s(prior),
        ]
        .map(String::from)
    };
    let said = "a network would learn to correct another sensor's reconstruction of them";
    let msg = run(&depth_args(&m.join("depth"), &m)
        .each_ref()
        .map(String::as_str));
    assert!(!msg.contains(said), "{msg}");
    // The prior of another sensor (a calibration whose render model names
    // another unit): said before the first epoch, kept in the record.
    let other = tmp.path().join("other-sensor");
    copy_model(&m, &other);
    let optics = other.join("optics.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&optics).unwrap()).unwrap();
    v["sensor"] = "another unit".into();
    std::fs::write(&optics, v.to_string()).unwrap();
    let out = tmp.path().join("depth-other");
    let msg = run(&depth_args(&out, &other).each_ref().map(String::as_str));
    assert!(
        msg.contains("warning: ")
            && msg.contains(said)
            && msg.contains("and the prior is the calibration of \"another unit\""),
        "{msg}"
    );
    let record = std::fs::read_to_string(out.join("training.json")).unwrap();
    assert!(record.contains(said), "{record}");
    // The depth network corrects the calibration's reconstruction, found
    // beside it (`..`), so the folder can move.
    let depth = std::fs::read_to_string(m.join("depth/depth.json")).unwrap();
    assert!(depth.contains("\"depth_maps\": \"indentation\""), "{depth}");
    let art: serde_json::Value = serde_json::from_str(&depth).unwrap();
    assert_eq!(art["prior"]["calibration"], "..", "{depth}");
    assert_eq!(art["model"]["in_channels"], 4, "{depth}");
    let moved = tmp.path().join("moved");
    std::fs::rename(&m, &moved).unwrap();
    let m = moved;
    // The whole pipeline on the sensor's frames: every record has the
    // calibration's indentation; tendon frames the depth network's, as
    // indentation.
    let msg = run(&[
        "run",
        "--models",
        &s(&m),
        "--data",
        &s(&data),
        "--out",
        "-",
        "--runtime",
        "burn-flex",
    ]);
    let recs: Vec<serde_json::Value> = msg
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .filter(|v: &serde_json::Value| v.get("frame").is_some())
        .collect();
    assert_eq!(recs.len(), 56, "{msg}");
    // Its own frames: a profile of this test's few training frames calls
    // at most a tenth of them another sensor's (2 of 56).
    let foreign = recs.iter().filter(|r| r["gate"] == "foreign").count();
    assert!(
        foreign * 10 <= recs.len(),
        "{foreign} of {} foreign",
        recs.len()
    );
    for r in &recs {
        // A frame the detector's profile calls another sensor's gets no
        // reconstruction either.
        let foreign = r["gate"] == "foreign";
        assert_eq!(r["indentation_peak_mm"].as_f64().is_some(), !foreign, "{r}");
        if r["tendon"] == true {
            assert_eq!(r["depth_maps"], "indentation", "{r}");
        }
    }
    // A frame of another size is foreign to this sensor, not an error.
    let odd = tmp.path().join("odd");
    std::fs::create_dir_all(&odd).unwrap();
    write_png(&odd.join("small.png"), 320, 240);
    let msg = run(&["run", "--models", &s(&m), "--data", &s(&odd), "--out", "-"]);
    let rec: serde_json::Value = msg
        .lines()
        .find_map(|l| {
            serde_json::from_str(l)
                .ok()
                .filter(|v: &serde_json::Value| v.get("frame").is_some())
        })
        .unwrap();
    assert_eq!(rec["out_of_distribution"], true, "{rec}");
    assert_eq!(rec["tendon"], false);
    assert!(rec["unreadable"].as_str().is_some(), "{rec}");
    // No detector pass was spent on it.
    assert!(
        msg.contains("0 without a tendon cost one detector pass, 1 unreadable none"),
        "{msg}"
    );
}

/// The real surface set's six targets, in `tactile predict`'s column order.
const SURFACE_TARGETS: [&str; 6] = [
    "depth_mm",
    "roll_deg",
    "pitch_deg",
    "shear_x_mm",
    "shear_y_mm",
    "shear_theta_deg",
];

/// The authors' `val` split of the real surface set (2,000 frames) as a
/// dataset of its own ([`surface_val_subset`]), made once per test binary
/// in a folder that lives as long as it: every claim the surface tests
/// check is on `val`, and predicting the other 6,000 frames too tripled
/// their time.
fn surface_val() -> &'static Path {
    static SUBSET: Subset = std::sync::OnceLock::new();
    kept_subset(&SUBSET, |dir| surface_val_subset(dir, 1, 2000))
}

/// `tactile predict --model models/MODEL` over the real surface set's
/// `val` frames ([`surface_val`]): the set's folder and the CSV's text.
/// Each model runs once per test binary: the tests that read the same
/// model's estimates share them.
fn predict_surface(model: &str) -> (std::path::PathBuf, String) {
    static RUNS: std::sync::Mutex<std::collections::BTreeMap<String, String>> =
        std::sync::Mutex::new(std::collections::BTreeMap::new());
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let data = surface_val().to_path_buf();
    let mut runs = RUNS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(text) = runs.get(model) {
        return (data, text.clone());
    }
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("estimates.csv");
    predict(
        &root.join("models").join(model),
        &data,
        &out,
        &["--show", "0"],
    );
    let text = std::fs::read_to_string(&out).unwrap();
    runs.insert(model.to_string(), text.clone());
    (data, text)
}

/// Each `val` frame's [`SURFACE_TARGETS`] from `data`'s labels.
fn surface_val_truth(data: &Path) -> std::collections::HashMap<String, Vec<f64>> {
    let labels = std::fs::read_to_string(data.join("labels.csv")).unwrap();
    let mut lab = labels.lines();
    let names: Vec<&str> = lab.next().unwrap().split(',').collect();
    let col = |n: &str| names.iter().position(|c| *c == n).unwrap();
    lab.map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|c| c[col("split")] == "val")
        .map(|c| {
            let v = SURFACE_TARGETS
                .iter()
                .map(|t| c[col(t)].parse().unwrap())
                .collect();
            (c[0].to_string(), v)
        })
        .collect()
}

#[test]
fn the_cae_route_on_surface_frames_it_never_saw_is_within_1_5x_of_the_best() {
    // models/cae-surface-train, the CAE route trained on the authors'
    // `train` split alone; on their `val`, each target within 1.5x of the
    // best model's error there (ms-k-long in docs/paper-a/surface-long.md:
    // issue 34's "one encoder" goal). models/cae-surface is the same recipe
    // on every frame, as models/pose-surface is ms-k-long's.
    let notes = |m: &str| -> serde_json::Value {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../models/{m}/cae.json"));
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(p).unwrap()).unwrap()
            ["notes"]
            .clone()
    };
    assert_eq!(notes("cae-surface")["every_split"], true);
    assert_ne!(notes("cae-surface-train")["every_split"], true);
    let mae = |model: &str| {
        let (data, text) = predict_surface(model);
        let truth = surface_val_truth(&data);
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let at = |n: &str| header.iter().position(|c| *c == n).unwrap();
        let (mut err, mut n) = ([0f64; 6], 0usize);
        for l in lines {
            let c: Vec<&str> = l.split(',').collect();
            let Some(y) = truth.get(c[0]) else { continue };
            for (k, t) in SURFACE_TARGETS.iter().enumerate() {
                err[k] += (c[at(t)].parse::<f64>().unwrap() - y[k]).abs();
            }
            n += 1;
        }
        assert_eq!(n, 2000);
        err.map(|e| e / n as f64)
    };
    // Every target of `cae` within `factor` times `reference`'s error.
    let within = |what: &str, cae: [f64; 6], factor: f64, reference: [f64; 6]| {
        for k in 0..6 {
            assert!(
                cae[k] <= factor * reference[k],
                "{}: {what} {} against {}",
                SURFACE_TARGETS[k],
                cae[k],
                reference[k]
            );
        }
    };
    let best = [0.099, 0.438, 0.496, 0.531, 0.533, 1.206];
    within(
        "the validated CAE route's",
        mae("cae-surface-train"),
        1.5,
        best,
    );
    // The shipped pair, both trained on these frames too, stand alike: the
    // CAE route's averaged estimator keeps it well inside 1.5x (1.15x on
    // roll, the widest, in docs/paper-a/surface-long.md).
    within(
        "the shipped CAE route's",
        mae("cae-surface"),
        1.3,
        mae("pose-surface"),
    );
    // Both CAE routes give each estimate's deviation, the validated one's
    // calibrated on `val` (the shipped one takes its factors): there ±1
    // holds 68.3 % of the errors, and ±1.96 most of them.
    for model in ["cae-surface-train", "cae-surface"] {
        let (data, text) = predict_surface(model);
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let mut want = vec!["file".to_string()];
        want.extend(SURFACE_TARGETS.iter().map(|t| t.to_string()));
        want.extend(SURFACE_TARGETS.iter().map(|t| format!("{t}_std")));
        assert_eq!(header, want, "{model}");
        if model != "cae-surface-train" {
            continue;
        }
        let truth = surface_val_truth(&data);
        let (mut inside, mut n) = ([[0usize; 2]; 6], 0usize);
        for l in lines {
            let c: Vec<&str> = l.split(',').collect();
            let Some(y) = truth.get(c[0]) else { continue };
            for k in 0..6 {
                let (p, s): (f64, f64) = (c[1 + k].parse().unwrap(), c[7 + k].parse().unwrap());
                assert!(s > 0.0 && s.is_finite(), "{l}");
                inside[k][0] += usize::from((p - y[k]).abs() <= s);
                inside[k][1] += usize::from((p - y[k]).abs() <= 1.96 * s);
            }
            n += 1;
        }
        for (k, [one, two]) in inside.iter().enumerate() {
            let (one, two) = (*one as f64 / n as f64, *two as f64 / n as f64);
            assert!(
                (0.67..=0.70).contains(&one) && (0.85..=1.0).contains(&two),
                "{}: {one} {two}",
                SURFACE_TARGETS[k]
            );
        }
    }
}

#[test]
fn predict_writes_surface_pose_shear_and_their_deviations() {
    let (data, text) = predict_surface("pose-surface");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut want = vec!["file".to_string()];
    want.extend(SURFACE_TARGETS.iter().map(|t| t.to_string()));
    want.extend(SURFACE_TARGETS.iter().map(|t| format!("{t}_std")));
    assert_eq!(header, want);
    let truth = surface_val_truth(&data);
    let (mut err, mut inside, mut n) = ([0f64; 6], [0usize; 6], 0usize);
    for l in lines {
        let c: Vec<&str> = l.split(',').collect();
        let y = &truth[c[0]];
        for k in 0..6 {
            let (p, s): (f64, f64) = (c[1 + k].parse().unwrap(), c[7 + k].parse().unwrap());
            assert!(s > 0.0 && s.is_finite(), "{l}");
            err[k] += (p - y[k]).abs();
            inside[k] += usize::from((p - y[k]).abs() <= 1.96 * s);
        }
        n += 1;
    }
    assert_eq!(n, 2000);
    // Over the `val` frames, which the shipped network trained on too (it
    // was trained on all 8,000 at the end): within the authors' CNN's
    // held-out errors, and the 95 % intervals hold most errors.
    let authors = [0.175, 1.34, 1.41, 0.55, 0.55, 1.21];
    for k in 0..6 {
        let mae = err[k] / n as f64;
        let cover = inside[k] as f64 / n as f64;
        assert!(mae < authors[k], "{}: {mae}", SURFACE_TARGETS[k]);
        assert!(
            (0.85..=1.0).contains(&cover),
            "{}: {cover}",
            SURFACE_TARGETS[k]
        );
    }
}

/// A blank frame among a TacTip dataset's (a covered or failed camera) is
/// still estimated, as the interface writes a row per frame, but named in
/// a warning: there are no pins to read. Before, its estimates came out
/// like any other's without a word. The dataset and its folder of frames
/// (two paths through the predictor) say the same; the frames with pins
/// are not named.
#[test]
fn a_blank_frame_is_estimated_and_named_as_one_with_no_pins() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("tt");
    let (ok, msg) = tactile(&[
        "synth",
        "tactip",
        "--count",
        "6",
        "--out",
        data.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    write_png(&data.join("frames/000002.png"), 300, 300);
    let model = root.join("models/cae-synth");
    for (input, named) in [
        (data.clone(), "frames/000002.png".to_string()),
        (
            data.join("frames"),
            data.join("frames/000002.png").display().to_string(),
        ),
    ] {
        let out = tmp.path().join("est.csv");
        let msg = predict(&model, &input, &out, &[]);
        assert_eq!(csv_rows(&out).len(), 7, "a header and a row per frame");
        let warned: Vec<&str> = msg.lines().filter(|l| l.contains("grey level")).collect();
        assert_eq!(warned.len(), 1, "{msg}");
        assert!(
            warned[0].contains(&format!(
                "warning: {named}: one grey level throughout the crop"
            )) && warned[0].contains("no pins to read"),
            "{msg}"
        );
    }
}

/// A grey frame of another sensor, resized to `w x h`, saved at `to`.
fn foreign_frame(from: &Path, to: &Path, (w, h): (u32, u32)) {
    let grey = image::open(from).unwrap().to_luma8();
    image::imageops::resize(&grey, w, h, image::imageops::FilterType::Triangle)
        .save(to)
        .unwrap();
}

#[test]
fn a_frame_of_another_sensor_is_estimated_and_named_as_unlike_the_training_frames() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let real = shared_real();
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("tt");
    let (ok, msg) = tactile(&[
        "synth",
        "tactip",
        "--count",
        "24",
        "--out",
        data.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    // Two frames of other sensors at the virtual TacTip's size: a TacTip
    // of 127 pins (the real edge set) and a GelSight's ball press.
    let frame = |n: usize| data.join(format!("frames/{n:06}.png"));
    foreign_frame(
        &real.join("tactip127-edge/frames/frame_0_0.png"),
        &frame(3),
        (300, 300),
    );
    foreign_frame(
        &real.join("gelsight-ball/frames/press_01.png"),
        &frame(5),
        (300, 300),
    );
    let unlike = |model: &Path, input: &Path| {
        let out = tmp.path().join("est.csv");
        let msg = predict(model, input, &out, &[]);
        assert_eq!(csv_rows(&out).len(), 25, "a header and a row per frame");
        msg.lines()
            .filter(|l| l.contains("pins spaced unlike"))
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    // The shipped encoder's profile names both, from a dataset in one
    // warning, from a folder as they come; none of the virtual frames.
    let shipped = root.join("models/cae-synth");
    let warned = unlike(&shipped, &data);
    assert_eq!(warned.len(), 1, "{warned:?}");
    assert!(
        warned[0].starts_with("warning: frames/000003.png, frames/000005.png: pins spaced unlike those of the 3000 frames this model was trained on")
            && warned[0].contains("another sensor"),
        "{warned:?}"
    );
    // `encode` writes every frame's features and names the two alike.
    let feats = tmp.path().join("features.csv");
    let (ok, msg) = encode(&shipped, &data, &feats);
    assert!(ok, "{msg}");
    assert_eq!(csv_rows(&feats).len(), 25, "a header and a row per frame");
    assert!(
        msg.contains("warning: frames/000003.png, frames/000005.png: pins spaced unlike"),
        "{msg}"
    );
    let warned = unlike(&shipped, &data.join("frames"));
    assert_eq!(warned.len(), 2, "{warned:?}");
    for (w, n) in warned.iter().zip([3, 5]) {
        assert!(
            w.starts_with(&format!("warning: {}: ", frame(n).display())),
            "{w}"
        );
    }
    // A copy without its profile (a model trained before it) warns of
    // nothing; `train profile` on its training frames makes one.
    let copy = tmp.path().join("m");
    copy_model(&shipped, &copy);
    let cfg = copy.join("cae.json");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cfg).unwrap()).unwrap();
    json.as_object_mut().unwrap().remove("input_profile");
    std::fs::write(&cfg, json.to_string()).unwrap();
    assert!(unlike(&copy, &data).is_empty());
    let own = tmp.path().join("own");
    let (ok, msg) = tactile(&[
        "synth",
        "tactip",
        "--count",
        "40",
        "--seed",
        "9",
        "--out",
        own.to_str().unwrap(),
    ]);
    assert!(ok, "{msg}");
    let profile = |extra: &[&str]| {
        let mut args = vec![
            "train",
            "profile",
            "--model",
            copy.to_str().unwrap(),
            "--data",
            own.to_str().unwrap(),
        ];
        args.extend(extra);
        tactile(&args)
    };
    let (ok, msg) = profile(&["--split", "train"]);
    assert!(
        !ok && msg.contains("labels.csv") && msg.contains("no 'split' column"),
        "{msg}"
    );
    let (ok, msg) = profile(&[]);
    assert!(ok && msg.contains("input profile of 40 frames"), "{msg}");
    let warned = unlike(&copy, &data);
    assert_eq!(warned.len(), 1, "{warned:?}");
    assert!(
        warned[0].starts_with("warning: frames/000003.png, frames/000005.png: ")
            && warned[0].contains("the 40 frames this model was trained on"),
        "{warned:?}"
    );
    // A detector's profile in an encoder's config is refused by name.
    let det: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("models/detector/member-0/detector.json")).unwrap(),
    )
    .unwrap();
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cfg).unwrap()).unwrap();
    json["input_profile"] = det["input_profile"].clone();
    std::fs::write(&cfg, json.to_string()).unwrap();
    let out = tmp.path().join("never.csv");
    let (ok, msg) = tactile(&[
        "predict",
        "--model",
        copy.to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        !ok && msg.contains("cae.json") && msg.contains("one of colour frames (a detector's)"),
        "{msg}"
    );
    assert!(!out.exists());
}

#[test]
fn trainers_find_frames_that_cannot_be_read_before_loading_any() {
    // A dataset with two frames no reader takes: every palpation trainer
    // names the first and counts them before it decodes a frame, and
    // makes no model folder.
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("vt");
    synth_visuotactile(&data, 6, 6, 62);
    // Two frames with a tendon (every trainer reads those), in two
    // sequences.
    let labels = std::fs::read_to_string(data.join("labels.csv")).unwrap();
    let mut lines = labels.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let (file, tendon, sequence) = (col("file"), col("tendon"), col("sequence"));
    let mut files: Vec<&str> = Vec::new();
    let mut seen = Vec::new();
    for cells in lines.map(|l| l.split(',').collect::<Vec<_>>()) {
        if cells[tendon] == "1" && !seen.contains(&cells[sequence]) {
            seen.push(cells[sequence]);
            files.push(cells[file]);
        }
    }
    std::fs::write(data.join(files[0]), b"").unwrap();
    std::fs::write(data.join(files[1]), b"not a picture").unwrap();
    for kind in ["detector", "segmenter", "depth"] {
        let out = tmp.path().join(kind);
        let (ok, msg) = tactile(&[
            "train",
            kind,
            "--data",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--max-epochs",
            "1",
        ]);
        assert!(
            !ok && msg.contains(&format!("{}: cannot read the image header", files[0]))
                && msg.contains("frames cannot be read"),
            "{kind}: {msg}"
        );
        assert!(!out.exists(), "{kind}: a model folder was left");
    }
}

/// A label column that holds one value on every frame a model fits (a
/// column the rig never varied, or one filled with zeros for want of a
/// sensor) teaches nothing: every trainer of targets names it, the pose
/// network as it starts and in its record, the regressor and a CAE's joint
/// head alike; a target that varies is not named.
#[test]
fn a_target_labelled_alike_on_every_frame_is_named_by_every_trainer() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("d");
    // y_mm is 0 on every frame that has one (a flat has none).
    copy_relabelled(&root.join("samples/virtual-tactip"), &data, |h, cells| {
        let y = col(h, "y_mm");
        if !cells[y].is_empty() {
            cells[y] = "0.0000";
        }
    });
    let d = data.to_str().unwrap();
    let said = |msg: &str| {
        msg.contains("y_mm is 0 on every one of the")
            && msg.contains("learns nothing of a value that never changes")
    };
    let pose = tmp.path().join("pose");
    let (ok, msg) = tactile(&[
        "train",
        "pose",
        "--data",
        d,
        "--out",
        pose.to_str().unwrap(),
        "--targets",
        "x_mm,y_mm",
        "--input-px",
        "32",
        "--max-epochs",
        "1",
    ]);
    assert!(ok && said(&msg) && !msg.contains("x_mm is"), "{msg}");
    // Said (on standard error, after the summary's stdout here) before the
    // first epoch, and kept in the training record.
    assert!(
        msg.find("y_mm is 0").unwrap() < msg.find("Pose network training").unwrap(),
        "{msg}"
    );
    let record = std::fs::read_to_string(pose.join("training.json")).unwrap();
    assert!(record.contains("y_mm is 0 on every one of the"), "{record}");
    let (ok, msg) = tactile(&[
        "train",
        "regressor",
        "--encoder",
        root.join("models/cae-synth").to_str().unwrap(),
        "--data",
        d,
        "--targets",
        "y_mm,x_mm",
        "--val-fraction",
        "0.25",
        "--only-labelled",
        "--out",
        tmp.path().join("reg").to_str().unwrap(),
    ]);
    assert!(ok && said(&msg) && msg.contains("warning: "), "{msg}");
    let (ok, msg) = tactile(&[
        "train",
        "cae",
        "--data",
        d,
        "--out",
        tmp.path().join("cae").to_str().unwrap(),
        "--max-epochs",
        "1",
        "--joint-targets",
        "x_mm,y_mm",
    ]);
    assert!(ok && said(&msg), "{msg}");
    // The column as the samples have it varies: nothing to say.
    let (ok, msg) = tactile(&[
        "train",
        "regressor",
        "--encoder",
        root.join("models/cae-synth").to_str().unwrap(),
        "--data",
        root.join("samples/virtual-tactip").to_str().unwrap(),
        "--targets",
        "y_mm",
        "--val-fraction",
        "0.25",
        "--only-labelled",
        "--out",
        tmp.path().join("reg2").to_str().unwrap(),
    ]);
    assert!(ok && !msg.contains("never changes"), "{msg}");
}
