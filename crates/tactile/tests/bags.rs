#![allow(clippy::unwrap_used)]
//! ROS 2 bags at the command line: `--list-topics`, a bag's frames decided
//! as the same PNG frames, results written as MCAP only when the run
//! succeeds, and hostile bags refused naming the file, topic and message.
//! (Bags written by independent implementations are read in the Python
//! suite, tests/test_robots.py.)

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use tactile_core::bag::messages::{Header, Image, to_cdr};

mod common;

const SAMPLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../samples/palpation");
const MODELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models");
const T0: i64 = 1_700_000_000_000_000_000;

fn tactile(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tactile"))
        .args(args)
        .output()
        .unwrap()
}

fn frames() -> Vec<(u32, u32, Vec<u8>)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(SAMPLES)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "png"))
        .collect();
    files.sort();
    files
        .iter()
        .map(|f| {
            let img = image::open(f).unwrap().to_rgb8();
            (img.width(), img.height(), img.into_raw())
        })
        .collect()
}

/// A bag with the sample frames as rgb8 Images on `/cam/image_raw` at
/// 20 Hz, and `extra` messages `(topic, schema name, bytes)` after them.
fn write_bag(path: &Path, extra: &[(&str, &str, Vec<u8>)]) {
    let mut bag = common::ImageBag::create(path, "/cam/image_raw", "cam");
    for (i, (width, height, px)) in frames().iter().enumerate() {
        bag.write(T0 + i as i64 * 50_000_000, (*width, *height, 3), "rgb8", px);
    }
    for (topic, schema_name, bytes) in extra {
        let w = &mut bag.writer;
        let s = w.add_schema(schema_name, "ros2msg", b"").unwrap();
        let c = w.add_channel(s, topic, "cdr", &BTreeMap::new()).unwrap();
        let header = mcap::records::MessageHeader {
            channel_id: c,
            sequence: 0,
            log_time: T0 as u64,
            publish_time: T0 as u64,
        };
        w.write_to_known_channel(&header, bytes).unwrap();
    }
    bag.finish();
}

/// `tactile run` on `data` with the shipped models, its records to `out`.
fn run_to(data: &str, out: &Path) -> Output {
    tactile(&[
        "run",
        "--models",
        MODELS,
        "--data",
        data,
        "--out",
        out.to_str().unwrap(),
    ])
}

/// [`run_to`], which must succeed.
fn run_ok(data: &str, out: &Path) {
    let o = run_to(data, out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn decisions(jsonl: &Path) -> Vec<(bool, String)> {
    std::fs::read_to_string(jsonl)
        .unwrap()
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            (v["tendon"].as_bool().unwrap(), format!("{:.5}", v["score"]))
        })
        .collect()
}

/// Each record's `stamp_ns` in a run's records.
fn stamps(jsonl: &Path) -> Vec<i64> {
    std::fs::read_to_string(jsonl)
        .unwrap()
        .lines()
        .map(|l| {
            serde_json::from_str::<serde_json::Value>(l).unwrap()["stamp_ns"]
                .as_i64()
                .unwrap()
        })
        .collect()
}

#[test]
fn a_bag_is_listed_and_decided_as_its_png_frames() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("rec.mcap");
    write_bag(&bag, &[]);
    let out = tactile(&["run", "--data", bag.to_str().unwrap(), "--list-topics"]);
    assert!(out.status.success());
    let listed = String::from_utf8_lossy(&out.stdout);
    assert!(
        listed.contains("/cam/image_raw  sensor_msgs/msg/Image  12 messages  20.0 Hz"),
        "{listed}"
    );
    let (a, b) = (dir.path().join("bag.jsonl"), dir.path().join("png.jsonl"));
    run_ok(bag.to_str().unwrap(), &a);
    run_ok(SAMPLES, &b);
    assert_eq!(decisions(&a), decisions(&b));
    let first: serde_json::Value =
        serde_json::from_str(std::fs::read_to_string(&a).unwrap().lines().nth(3).unwrap()).unwrap();
    assert_eq!(first["stamp_ns"].as_i64(), Some(T0 + 3 * 50_000_000));
}

#[test]
fn hostile_bags_are_refused_by_name_and_leave_no_results() {
    let dir = tempfile::tempdir().unwrap();
    let results = dir.path().join("out").join("results.mcap");
    let check = |bag: &Path, topic: &str, want: &[&str]| {
        let o = tactile(&[
            "run",
            "--models",
            MODELS,
            "--data",
            bag.to_str().unwrap(),
            "--topic",
            topic,
            "--out",
            results.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{topic}: {err}");
        for w in want {
            assert!(err.contains(w), "wanted {w:?} in: {err}");
        }
        // Nothing half-written: no results file, no temporary beside it.
        let left: Vec<_> = std::fs::read_dir(results.parent().unwrap())
            .map(|d| d.map(|e| e.unwrap().file_name()).collect())
            .unwrap_or_default();
        assert!(left.is_empty(), "{left:?}");
    };
    let wide = Image {
        header: Header::default(),
        height: 100_000,
        width: 100_000,
        encoding: "rgb8".into(),
        is_bigendian: 0,
        step: 300_000,
        data: &[1, 2, 3],
    };
    let bag = dir.path().join("hostile.mcap");
    write_bag(
        &bag,
        &[
            ("/wide", "sensor_msgs/msg/Image", to_cdr(&wide).unwrap()),
            ("/garbage", "sensor_msgs/msg/Image", vec![0, 1, 0, 0, 9]),
            ("/imu", "sensor_msgs/msg/Imu", vec![0, 1, 0, 0]),
        ],
    );
    check(
        &bag,
        "/wide",
        &[
            "hostile.mcap: topic /wide, message 0",
            "100000x100000",
            "8K",
        ],
    );
    check(
        &bag,
        "/garbage",
        &["topic /garbage, message 0: not a valid message"],
    );
    check(&bag, "/imu", &["topic /imu: carries sensor_msgs/msg/Imu"]);
    check(
        &bag,
        "/none",
        &[
            "topic /none: not in the bag",
            "/cam/image_raw, /garbage, /wide",
        ],
    );
    // A topic declared with no message (a recorder subscribed to a camera
    // that never published): refused by name, where before it ran on no
    // frame, wrote an empty results file and succeeded.
    let silent = dir.path().join("silent.mcap");
    let bag = common::ImageBag::create(&silent, "/cam/silent", "cam");
    bag.finish();
    check(
        &silent,
        "/cam/silent",
        &[
            "silent.mcap: topic /cam/silent: has no messages",
            "other image topics: none",
        ],
    );
    // (A bag cut inside its data is a recording cut short, read up to
    // the cut: a_recording_cut_short_gives_its_complete_frames_and_says_so.)
    // A record claiming a terabyte: refused before anything is allocated.
    let mut huge = b"\x89MCAP0\r\n".to_vec();
    huge.push(0x06); // a chunk
    huge.extend((1u64 << 40).to_le_bytes());
    huge.extend([0u8; 64]);
    let huge_bag = dir.path().join("huge.mcap");
    std::fs::write(&huge_bag, huge).unwrap();
    check(
        &huge_bag,
        "/cam/image_raw",
        &["huge.mcap: not a readable MCAP bag"],
    );
}

/// `tactile dataset from-video` of `topic` of `bag` with `labels`, a
/// visuotactile dataset to `out`.
fn import_bag(bag: &Path, topic: &str, labels: &Path, out: &Path) -> Output {
    tactile(&[
        "dataset",
        "from-video",
        "--kind",
        "visuotactile",
        "--video",
        bag.to_str().unwrap(),
        "--topic",
        topic,
        "--labels",
        labels.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn a_labelled_bag_becomes_a_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("rec.mcap");
    write_bag(&bag, &[]);
    // Messages 2-9 press on the tendon; 10 and 11 are left unlabelled.
    let mut csv = String::from("frame,tendon,sequence\n");
    for i in 0..10 {
        csv.push_str(&format!("{i},{},0\n", u8::from((2..=9).contains(&i))));
    }
    let labels = dir.path().join("labels.csv");
    std::fs::write(&labels, csv).unwrap();
    let out = dir.path().join("ds");
    let o = import_bag(&bag, "/cam/image_raw", &labels, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ds = tactile_core::dataset::Dataset::open(&out).unwrap();
    assert_eq!(ds.len(), 10);
    let f5 = tactile_core::image_io::load_rgb(ds.path_of(5, "file").unwrap()).unwrap();
    assert_eq!(f5.as_slice(), frames()[5].2.as_slice());
    assert_eq!(ds.number_opt(5, "tendon").unwrap(), Some(1.0));
}

/// An empty bag folder at `folder`: its `metadata.yaml` names it one by
/// rosbag2's key; its storage files are the caller's.
fn bag_folder(folder: &Path) {
    std::fs::create_dir(folder).unwrap();
    std::fs::write(
        folder.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n",
    )
    .unwrap();
}

/// A bag folder as `ros2 bag record` splits a recording: `metadata.yaml`
/// and `rec_0.mcap` … `rec_11.mcap`, one sample frame each. In odd files a
/// `/chatter` channel comes first, so the image channel's id differs from
/// file to file, and a `/chatter` message precedes the frame.
fn write_split_bag(folder: &Path) {
    bag_folder(folder);
    for (i, (width, height, px)) in frames().iter().enumerate() {
        let others: &[&str] = if i % 2 == 1 { &["/chatter"] } else { &[] };
        let path = folder.join(format!("rec_{i}.mcap"));
        let mut bag = common::ImageBag::create_after(&path, others, "/cam/image_raw", "cam");
        let t = T0 + i as i64 * 50_000_000;
        if i % 2 == 1 {
            let header = mcap::records::MessageHeader {
                channel_id: 1,
                sequence: 0,
                log_time: t as u64,
                publish_time: t as u64,
            };
            let hello = [0, 1, 0, 0, 6, 0, 0, 0, b'h', b'e', b'l', b'l', b'o', 0];
            bag.writer.write_to_known_channel(&header, &hello).unwrap();
        }
        bag.write(t, (*width, *height, 3), "rgb8", px);
        bag.finish();
    }
}

#[test]
fn a_split_bag_folder_is_read_in_the_order_of_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("rec");
    write_split_bag(&folder);
    let data = folder.to_str().unwrap();
    let out = tactile(&["run", "--data", data, "--list-topics"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let listed = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        listed.trim(),
        "/cam/image_raw  sensor_msgs/msg/Image  12 messages  20.0 Hz"
    );
    let (a, b) = (dir.path().join("bag.jsonl"), dir.path().join("png.jsonl"));
    run_ok(data, &a);
    run_ok(SAMPLES, &b);
    assert_eq!(decisions(&a), decisions(&b));
    // rec_2 … rec_9 before rec_10: the stamps go in time.
    let want: Vec<i64> = (0..12).map(|i| T0 + i * 50_000_000).collect();
    assert_eq!(stamps(&a), want);
    // Results written into the bag folder would join the bag.
    let inside = folder.join("results.mcap");
    let o = run_to(data, &inside);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("inside the input bag folder"),
        "{err}"
    );
    // One split alone is read, and said to be one of twelve.
    let one = dir.path().join("one.jsonl");
    let o = run_to(folder.join("rec_3.mcap").to_str().unwrap(), &one);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("rec_3.mcap is one of the 12 files of the bag folder"),
        "{err}"
    );
    assert_eq!(decisions(&one).len(), 1);
    // Results inside the bag folder are refused for one of its files too.
    let o = run_to(folder.join("rec_3.mcap").to_str().unwrap(), &inside);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("inside the input bag folder"),
        "{err}"
    );
    assert!(!inside.exists());
}

#[test]
fn bags_this_toolkit_does_not_read_are_refused_with_the_command_that_converts_them() {
    let dir = tempfile::tempdir().unwrap();
    // A ROS 1 bag, whatever its name.
    let ros1 = dir.path().join("noetic.bin");
    std::fs::write(&ros1, b"#ROSBAG V2.0\n and its records").unwrap();
    let cases = [(
        ros1.to_str().unwrap().to_string(),
        "a ROS 1 bag",
        ros1.to_str().unwrap().to_string(),
    )];
    for (data, what, src) in &cases {
        for extra in [&[][..], &["--list-topics"][..]] {
            let mut args = vec!["run", "--models", MODELS, "--data", data.as_str()];
            args.extend(extra);
            let o = tactile(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(!o.status.success(), "{data}: {err}");
            assert!(err.contains(what), "{data}: {err}");
            let convert =
                format!("rosbags-convert --src {src} --dst NEW_FOLDER --dst-storage mcap");
            assert!(err.contains(&convert), "{data}: {err}");
        }
    }
    // MCAP files in a folder that is not a bag folder: pass one of them.
    let loose = dir.path().join("recordings");
    std::fs::create_dir(&loose).unwrap();
    write_bag(&loose.join("monday.mcap"), &[]);
    let o = tactile(&["run", "--models", MODELS, "--data", loose.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("without the metadata.yaml of a ROS 2 bag folder: pass one, as"),
        "{err}"
    );
    // Frames beside another tool's metadata.yaml stay a folder of frames.
    let shots = dir.path().join("shots");
    std::fs::create_dir(&shots).unwrap();
    std::fs::write(shots.join("metadata.yaml"), "camera: gelsight mini\n").unwrap();
    for name in ["000000.png", "000001.png"] {
        std::fs::copy(Path::new(SAMPLES).join(name), shots.join(name)).unwrap();
    }
    let spec = tactile_core::source::SourceSpec::Path(shots.clone());
    let mut source = tactile_core::source::FrameSource::open(&spec, Default::default()).unwrap();
    assert_eq!(source.kind(), tactile_core::source::SourceKind::Folder);
    assert!(source.next_frame().unwrap().is_some());
    // A topic asked of a folder that is not a bag.
    let o = tactile(&[
        "run",
        "--models",
        MODELS,
        "--data",
        SAMPLES,
        "--topic",
        "/cam/image_raw",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("a folder without the metadata.yaml of a ROS 2 bag folder (rosbag2_bagfile_information); a topic is read from a ROS 2 bag"), "{err}");
}

#[test]
fn an_unstamped_frame_takes_its_log_time() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("unstamped.mcap");
    let mut bag = common::ImageBag::create(&path, "/cam/image_raw", "cam");
    let (width, height, px) = &frames()[0];
    for i in 0..3i64 {
        // Frame 1 as a publisher that does not stamp leaves it.
        let stamp = if i == 1 { 0 } else { T0 + i * 50_000_000 };
        let logged = (T0 + i * 50_000_000 + 2_000_000) as u64;
        bag.write_logged(stamp, logged, (*width, *height, 3), "rgb8", px);
    }
    bag.finish();
    let mut images = tactile_core::bag::BagImages::open(&path, "/cam/image_raw").unwrap();
    let mut stamps = Vec::new();
    while let Some(f) = images.next_frame().unwrap() {
        stamps.push(f.stamp_ns);
    }
    assert_eq!(stamps, [T0, T0 + 52_000_000, T0 + 100_000_000]);
}

#[test]
fn a_recording_cut_short_gives_its_complete_frames_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("rec.mcap");
    write_bag(&bag, &[]);
    // Cut in the middle of its last chunk, as a recorder killed while
    // writing it leaves the file: no summary, no footer.
    let bytes = std::fs::read(&bag).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let chunks = &summary.chunk_indexes;
    assert!(chunks.len() > 1, "{} chunks", chunks.len());
    let last = chunks.last().unwrap();
    let cut = last.chunk_start_offset + last.chunk_length / 2;
    std::fs::write(&bag, &bytes[..cut as usize]).unwrap();
    let data = bag.to_str().unwrap();
    let listed = tactile(&["run", "--data", data, "--list-topics"]);
    let stderr = String::from_utf8_lossy(&listed.stderr);
    assert!(
        listed.status.success()
            && stderr.contains(&format!("{data} ends without its MCAP footer"))
            && stderr.contains("its messages up to the last complete record are counted"),
        "{stderr}"
    );
    let (a, b) = (dir.path().join("bag.jsonl"), dir.path().join("png.jsonl"));
    let o = run_to(data, &a);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("{data} ends without its MCAP footer")),
        "{stderr}"
    );
    run_ok(SAMPLES, &b);
    let (kept, all) = (decisions(&a), decisions(&b));
    assert!(
        !kept.is_empty() && kept.len() < all.len(),
        "{} of {}",
        kept.len(),
        all.len()
    );
    assert_eq!(kept, all[..kept.len()]);
    assert!(
        String::from_utf8_lossy(&listed.stdout)
            .contains(&format!("sensor_msgs/msg/Image  {} messages", kept.len())),
        "{}",
        String::from_utf8_lossy(&listed.stdout)
    );
    // A pipe named as a split of a bag folder: refused by name, not
    // opened (opening it would wait for a writer for ever).
    let fifo_bag = dir.path().join("fifo");
    bag_folder(&fifo_bag);
    let status = Command::new("mkfifo")
        .arg(fifo_bag.join("rec_0.mcap"))
        .status()
        .unwrap();
    assert!(status.success());
    for extra in [&["--list-topics"][..], &[][..]] {
        let mut args = vec!["run", "--data", fifo_bag.to_str().unwrap()];
        args.extend(extra);
        let o = tactile(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success()
                && stderr.contains("rec_0.mcap")
                && stderr.contains("not a regular file"),
            "{stderr}"
        );
    }
    // A bag whose bytes are damaged, not cut, is still refused.
    let mut damaged = bytes.clone();
    let first = &chunks[0];
    damaged[(first.chunk_start_offset + 60) as usize
        ..(first.chunk_start_offset + first.chunk_length) as usize]
        .fill(0xAB);
    std::fs::write(&bag, &damaged).unwrap();
    let o = run_to(data, &a);
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("not a readable MCAP bag"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn a_video_bag_begun_mid_stream_is_run_and_labelled_by_its_messages() {
    let dir = tempfile::tempdir().unwrap();
    // The sample frames as lossless H.264, a keyframe every 4, one packet
    // per frame; the recording begins at packet 2, so its messages 0 and
    // 1 precede the first keyframe and message m holds frame m + 2.
    let packets = dir.path().join("packets");
    std::fs::create_dir(&packets).unwrap();
    let status = Command::new("ffmpeg")
        .args(["-nostdin", "-loglevel", "error", "-i"])
        .arg(Path::new(SAMPLES).join("%06d.png"))
        .args(["-c:v", "libx264rgb", "-qp", "0", "-bf", "0", "-g", "4"])
        .args(["-x264-params", "repeat-headers=1", "-f", "image2"])
        .arg(packets.join("%03d.h264"))
        .status()
        .unwrap();
    assert!(status.success());
    let bag = dir.path().join("video.mcap");
    let mut out = std::io::Cursor::new(Vec::new());
    let mut w = mcap::Writer::new(&mut out).unwrap();
    let s = w
        .add_schema("foxglove_msgs/msg/CompressedVideo", "ros2msg", b"")
        .unwrap();
    let c = w
        .add_channel(s, "/cam/video", "cdr", &BTreeMap::new())
        .unwrap();
    for i in 2..12 {
        let data = std::fs::read(packets.join(format!("{:03}.h264", i + 1))).unwrap();
        let t = T0 + i as i64 * 50_000_000;
        let m = tactile_core::bag::messages::CompressedVideo {
            timestamp: tactile_core::bag::messages::Time::from_nanos(t),
            frame_id: "cam".into(),
            data: &data,
            format: "h264".into(),
        };
        let header = mcap::records::MessageHeader {
            channel_id: c,
            sequence: i,
            log_time: t as u64,
            publish_time: t as u64,
        };
        w.write_to_known_channel(&header, &to_cdr(&m).unwrap())
            .unwrap();
    }
    w.finish().unwrap();
    drop(w);
    std::fs::write(&bag, out.into_inner()).unwrap();

    // Run: frames 4 to 11, decided as the PNG folder decides them, the
    // skipped packets said.
    let (png, video) = (dir.path().join("png.jsonl"), dir.path().join("v.jsonl"));
    run_ok(SAMPLES, &png);
    let o = run_to(bag.to_str().unwrap(), &video);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(decisions(&video), decisions(&png)[4..]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("its first 2 messages come before the first keyframe of its h264 stream"),
        "{stderr}"
    );

    // Labels count messages on the topic: message 5 is frame 7.
    let labels = dir.path().join("labels.csv");
    let import = |rows: std::ops::Range<u32>, out: &Path| {
        let mut csv = String::from("frame,tendon,sequence\n");
        for i in rows {
            csv.push_str(&format!("{i},0,0\n"));
        }
        std::fs::write(&labels, csv).unwrap();
        import_bag(&bag, "/cam/video", &labels, out)
    };
    let ds_dir = dir.path().join("ds");
    let o = import(2..10, &ds_dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ds = tactile_core::dataset::Dataset::open(&ds_dir).unwrap();
    assert_eq!(ds.len(), 8);
    // Rows 0 to 7 are messages 2 to 9: message 5 is row 3.
    let f = tactile_core::image_io::load_rgb(ds.path_of(3, "file").unwrap()).unwrap();
    assert_eq!(f.as_slice(), frames()[7].2.as_slice());
    // A label on a message before the first keyframe: named, with why.
    let o = import(0..4, &dir.path().join("ds0"));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("frame 0 is not in") && stderr.contains("before the first keyframe"),
        "{stderr}"
    );
    assert!(!dir.path().join("ds0").exists());
}

/// The channels an MCAP file declares, by topic.
fn declared_topics(path: &Path) -> Vec<String> {
    let bytes = std::fs::read(path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let mut topics: Vec<String> = summary.channels.values().map(|c| c.topic.clone()).collect();
    topics.sort();
    topics
}

#[test]
fn a_results_file_declares_only_the_topics_its_run_can_write() {
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name);
    let run = |models: &str, data: &str, out: &Path, extra: &[&str]| {
        let mut args = vec!["run", "--models", models, "--data", data, "--out"];
        args.push(out.to_str().unwrap());
        args.extend(extra);
        let o = tactile(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        declared_topics(out)
    };
    let palpation = [
        "/tactile/annotations",
        "/tactile/depth",
        "/tactile/result",
        "/tactile/tendon_mask",
    ];
    // Paper B's models: no indentation (no calibrated sensor), no input
    // frames unless asked.
    assert_eq!(run(MODELS, SAMPLES, &out("b.mcap"), &[]), palpation);
    let mut with_frames = palpation.to_vec();
    with_frames.insert(2, "/tactile/image");
    assert_eq!(
        run(MODELS, SAMPLES, &out("f.mcap"), &["--with-frames"]),
        with_frames
    );
    // Frames asked for where they have no place (JSON Lines records, no
    // live view): refused, nothing written. Before, silently dropped.
    let o = tactile(&[
        "run",
        "--models",
        MODELS,
        "--data",
        SAMPLES,
        "--out",
        out("f.jsonl").to_str().unwrap(),
        "--with-frames",
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && e.contains("with_frames: the input frames go to an .mcap out or to the live view"),
        "{e}"
    );
    assert!(!out("f.jsonl").exists());
    // A calibrated sensor alone: its indentation, no tendon topics.
    let shipped = Path::new(MODELS).join("gelsight-r15");
    let sensor = out("sensor");
    std::fs::create_dir(&sensor).unwrap();
    for entry in std::fs::read_dir(&shipped).unwrap() {
        let path = entry.unwrap().path();
        if path.is_file() {
            std::fs::copy(&path, sensor.join(path.file_name().unwrap())).unwrap();
        }
    }
    let rest = shipped.join("background.png");
    let rest = rest.to_str().unwrap();
    assert_eq!(
        run(sensor.to_str().unwrap(), rest, &out("s.mcap"), &[]),
        [
            "/tactile/annotations",
            "/tactile/indentation",
            "/tactile/result"
        ]
    );
    // Both: every topic but the frames.
    let mut both = palpation.to_vec();
    both.insert(2, "/tactile/indentation");
    assert_eq!(
        run(shipped.to_str().unwrap(), rest, &out("g.mcap"), &[]),
        both
    );
}

/// rosbag2's SQLite schema, as `ros2 bag record` creates it on Humble.
const ROSBAG2_SQLITE_SCHEMA: &str = "
CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);
CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
    serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,
    timestamp INTEGER NOT NULL, data BLOB NOT NULL);
CREATE INDEX timestamp_idx ON messages (timestamp ASC);
INSERT INTO schema VALUES (3, 'humble');
";

/// A ROS 2 bag in SQLite storage as `ros2 bag record` leaves it on Humble:
/// `metadata.yaml` and `rec_0.db3`, `rec_1.db3`, the sample frames as
/// rgb8 Images on `/cam/image_raw` at 20 Hz split between them, topic ids
/// 7 (`/chatter`, a String before each frame) and 3, and each file's
/// messages inserted last first (rosbag2 reads them by their timestamp).
fn write_sqlite_bag(folder: &Path) {
    use tactile_core::bag::messages::Time;
    bag_folder(folder);
    let frames = frames();
    for (part, chunk) in frames.chunks(frames.len() / 2).enumerate() {
        let db = rusqlite::Connection::open(folder.join(format!("rec_{part}.db3"))).unwrap();
        db.execute_batch(ROSBAG2_SQLITE_SCHEMA).unwrap();
        db.execute_batch(
            "INSERT INTO topics VALUES (7, '/chatter', 'std_msgs/msg/String', 'cdr', '');
             INSERT INTO topics VALUES (3, '/cam/image_raw', 'sensor_msgs/msg/Image', 'cdr', '');",
        )
        .unwrap();
        for (k, (width, height, px)) in chunk.iter().enumerate().rev() {
            let i = part * (frames.len() / 2) + k;
            let t = T0 + i as i64 * 50_000_000;
            let msg = Image {
                header: Header {
                    stamp: Time::from_nanos(t),
                    frame_id: "cam".into(),
                },
                height: *height,
                width: *width,
                encoding: "rgb8".into(),
                is_bigendian: 0,
                step: width * 3,
                data: px,
            };
            let hello = [0u8, 1, 0, 0, 6, 0, 0, 0, b'h', b'e', b'l', b'l', b'o', 0];
            let insert = "INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)";
            db.execute(insert, rusqlite::params![3, t, to_cdr(&msg).unwrap()])
                .unwrap();
            db.execute(insert, rusqlite::params![7, t - 1, hello.to_vec()])
                .unwrap();
        }
    }
}

#[test]
fn a_bag_in_sqlite_storage_is_listed_and_decided_as_its_png_frames() {
    // Before, a .db3 bag (ROS 2 Humble's default) was refused with the
    // command that converts it to MCAP.
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("humble");
    write_sqlite_bag(&bag);
    let data = bag.to_str().unwrap();
    let out = tactile(&["run", "--data", data, "--list-topics"]);
    let listed = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success()
            && listed.contains("/cam/image_raw  sensor_msgs/msg/Image  12 messages  20.0 Hz"),
        "{listed}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (a, b) = (dir.path().join("bag.jsonl"), dir.path().join("png.jsonl"));
    run_ok(data, &a);
    run_ok(SAMPLES, &b);
    assert_eq!(decisions(&a), decisions(&b));
    let want: Vec<i64> = (0..12).map(|i| T0 + i * 50_000_000).collect();
    assert_eq!(stamps(&a), want, "in log-time order, file after file");
    // One file of the folder: its own frames.
    let one = bag.join("rec_1.db3");
    run_ok(one.to_str().unwrap(), &a);
    assert_eq!(decisions(&a), decisions(&b)[6..]);
    // In WAL mode (rosbag2's `resilient` preset), closed by its writer: read
    // with nothing added beside it (SQLite left a -shm and a -wal before).
    rusqlite::Connection::open(&one)
        .unwrap()
        .pragma_update(None, "journal_mode", "WAL")
        .unwrap();
    let before: Vec<_> = std::fs::read_dir(&bag)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    run_ok(data, &a);
    assert_eq!(decisions(&a), decisions(&b));
    let after: Vec<_> = std::fs::read_dir(&bag)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(before.len(), after.len(), "{after:?}");
}

#[test]
fn hostile_sqlite_bags_are_refused_naming_the_file_and_damage_keeps_the_frames_before_it() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good");
    write_sqlite_bag(&good);
    let db3 = good.join("rec_0.db3");
    let copy = |name: &str, sql: &str| {
        let p = dir.path().join(name);
        std::fs::copy(&db3, &p).unwrap();
        if !sql.is_empty() {
            rusqlite::Connection::open(&p)
                .unwrap()
                .execute_batch(sql)
                .unwrap();
        }
        p
    };
    let other = dir.path().join("other.db3");
    rusqlite::Connection::open(&other)
        .unwrap()
        .execute_batch("CREATE TABLE x(a);")
        .unwrap();
    let not_sqlite = dir.path().join("junk.db3");
    std::fs::write(&not_sqlite, b"SQLite format 3\0 and the rest of a database").unwrap();
    let zstd_folder = dir.path().join("zstd");
    bag_folder(&zstd_folder);
    std::fs::write(zstd_folder.join("rec_0.db3.zstd"), b"(\xb5/\xfd").unwrap();
    let cases: Vec<(PathBuf, &str)> = vec![
        (
            other.clone(),
            "other.db3: not a readable ROS 2 bag in SQLite storage: no such table: topics (rosbag2 keeps its topics in a table `topics`",
        ),
        (
            copy("nomessages.db3", "DROP TABLE messages;"),
            "nomessages.db3: not a readable ROS 2 bag in SQLite storage: no such table: messages (rosbag2 keeps",
        ),
        (
            not_sqlite,
            "junk.db3: not a readable ROS 2 bag in SQLite storage: file is not a database",
        ),
        (
            copy("renamed.sqlite", ""),
            "renamed.sqlite: an SQLite database: a ROS 2 bag in SQLite storage is read as rosbag2 names it (a .db3 file, or its bag folder)",
        ),
        (
            copy(
                "stray.db3",
                "UPDATE messages SET topic_id = 99 WHERE topic_id = 3;",
            ),
            "stray.db3: not a readable ROS 2 bag in SQLite storage: message id 11 is on topic id 99, which `topics` does not list",
        ),
        (
            copy(
                "text.db3",
                "UPDATE messages SET data = 'pixels' WHERE topic_id = 3;",
            ),
            "text.db3: not a readable ROS 2 bag in SQLite storage: message id 11: its data is Text, not the bytes of a message",
        ),
        (
            copy(
                "early.db3",
                "UPDATE messages SET timestamp = -5 WHERE id = 1;",
            ),
            "early.db3: not a readable ROS 2 bag in SQLite storage: message id 1 has a negative timestamp -5",
        ),
        (
            zstd_folder,
            "rec_0.db3.zstd: an SQLite bag file rosbag2 compressed whole, which SQLite cannot read in place: decompress it first",
        ),
    ];
    for (path, want) in &cases {
        let out = dir.path().join("out.mcap");
        let o = run_to(path.to_str().unwrap(), &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(want),
            "{}: {err}",
            path.display()
        );
        assert!(!out.exists(), "{}: no results", path.display());
    }
    // Pages of later messages zeroed, as damage leaves them: the frames
    // before it are run, and the damage said.
    let damaged = copy("damaged.db3", "");
    let mut bytes = std::fs::read(&damaged).unwrap();
    let len = bytes.len();
    bytes[len * 3 / 4..len * 3 / 4 + 32768].fill(0);
    std::fs::write(&damaged, bytes).unwrap();
    let out = dir.path().join("damaged.jsonl");
    let o = run_to(damaged.to_str().unwrap(), &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("damaged.db3 is damaged past some of its messages (SQLite: database disk image is malformed), as a recording cut short leaves it"),
        "{err}"
    );
    let kept = decisions(&out);
    assert!(!kept.is_empty() && kept.len() < 6, "{}", kept.len());
    let png = dir.path().join("png.jsonl");
    run_ok(SAMPLES, &png);
    assert_eq!(kept, decisions(&png)[..kept.len()]);
}
