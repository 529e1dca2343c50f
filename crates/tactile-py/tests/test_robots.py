"""ROS 2 bags in, MCAP results out, the Foxglove live view: checked against
independent implementations of the formats (`rosbags`, `mcap-ros2-support`,
a Foxglove WebSocket client written here on `websockets`)."""

from __future__ import annotations

import asyncio
import json
import math
import shutil
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, IndexType, Writer as McapWriter
from mcap_ros2.reader import read_ros2_messages
from mcap_ros2.writer import Writer as Ros2McapWriter
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Writer as Ros1Writer
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer as RosbagsWriter
from rosbags.typesys import Stores, get_typestore

import tactile

T0 = 1_700_000_000_000_000_000
PERIOD = 33_333_333

# What both image messages use, as `ros2 bag record` writes it after them.
HEADER_DEPS = """
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""

IMAGE_MSG = """std_msgs/Header header
uint32 height
uint32 width
string encoding
uint8 is_bigendian
uint32 step
uint8[] data""" + HEADER_DEPS

COMPRESSED_MSG = """std_msgs/Header header
string format
uint8[] data""" + HEADER_DEPS


def stamp(i: int) -> int:
    return T0 + i * PERIOD


def header(i: int) -> dict:
    t = stamp(i)
    return {"stamp": {"sec": t // 10**9, "nanosec": t % 10**9}, "frame_id": "gelsight"}


def run_records(tactile_bin: Path, root: Path, tmp: Path, *args: str) -> list[dict]:
    out = tmp / f"records-{len(list(tmp.iterdir()))}.jsonl"
    r = subprocess.run(
        [str(tactile_bin), "run", *args, "--out", str(out)], capture_output=True, text=True, cwd=root
    )
    assert r.returncode == 0, r.stderr
    return [json.loads(line) for line in out.read_text().splitlines()]


def decisions(records: list[dict]) -> list[tuple]:
    return [(r["tendon"], round(r["score"], 5), r["direction_deg"] and round(r["direction_deg"], 3)) for r in records]


@pytest.fixture(scope="module")
def rosbags_bag(tmp_path_factory, root, palpation_frames) -> Path:
    """A bag written by `rosbags` (MCAP storage): the sample frames as
    rgb8 Images, as bgr8 Images and as PNG CompressedImages."""
    ts = get_typestore(Stores.ROS2_HUMBLE)
    Image = ts.types["sensor_msgs/msg/Image"]
    Compressed = ts.types["sensor_msgs/msg/CompressedImage"]
    Header = ts.types["std_msgs/msg/Header"]
    Time = ts.types["builtin_interfaces/msg/Time"]
    folder = tmp_path_factory.mktemp("rosbags") / "bag"
    pngs = sorted((root / "samples" / "palpation").glob("*.png"))
    with RosbagsWriter(folder, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        raw = w.add_connection("/gelsight/image_raw", Image.__msgtype__, typestore=ts)
        bgr = w.add_connection("/gelsight/image_bgr", Image.__msgtype__, typestore=ts)
        png = w.add_connection("/gelsight/image_raw/compressed", Compressed.__msgtype__, typestore=ts)
        for i, (f, rgb) in enumerate(zip(pngs, palpation_frames)):
            t = stamp(i)
            h = Header(stamp=Time(sec=t // 10**9, nanosec=t % 10**9), frame_id="gelsight")
            height, width, _ = rgb.shape
            for conn, data, enc in [(raw, rgb, "rgb8"), (bgr, rgb[:, :, ::-1], "bgr8")]:
                msg = Image(
                    header=h, height=height, width=width, encoding=enc, is_bigendian=0,
                    step=width * 3, data=np.ascontiguousarray(data).reshape(-1),
                )
                w.write(conn, t, ts.serialize_cdr(msg, Image.__msgtype__))
            msg = Compressed(header=h, format="png", data=np.frombuffer(f.read_bytes(), np.uint8))
            w.write(png, t, ts.serialize_cdr(msg, Compressed.__msgtype__))
    bags = list(folder.glob("*.mcap"))
    assert len(bags) == 1
    return bags[0]


def test_rosbags_bag_gives_the_png_frames_with_their_stamps(rosbags_bag, palpation_frames):
    topics = {t["topic"]: t for t in tactile.bag_topics(rosbags_bag)}
    assert set(topics) == {"/gelsight/image_raw", "/gelsight/image_bgr", "/gelsight/image_raw/compressed"}
    assert topics["/gelsight/image_raw"]["count"] == 12
    assert topics["/gelsight/image_raw"]["rate_hz"] == pytest.approx(30.0, rel=1e-3)
    for topic in topics:
        frames = list(tactile.frames(rosbags_bag, topic=topic))
        assert len(frames) == 12
        for i, (f, want) in enumerate(zip(frames, palpation_frames)):
            np.testing.assert_array_equal(f.image, want, err_msg=topic)
            assert f.stamp_ns == stamp(i)
            assert f.name == f"{i:06d}"


def test_bag_runs_decide_as_the_png_folder(rosbags_bag, tactile_bin, root, tmp_path):
    want = decisions(run_records(tactile_bin, root, tmp_path, "--data", "samples/palpation"))
    for topic in ["/gelsight/image_raw", "/gelsight/image_bgr", "/gelsight/image_raw/compressed"]:
        recs = run_records(tactile_bin, root, tmp_path, "--data", str(rosbags_bag), "--topic", topic)
        assert decisions(recs) == want, topic
        assert [r["stamp_ns"] for r in recs] == [stamp(i) for i in range(12)]


def test_several_image_topics_must_be_named(rosbags_bag):
    with pytest.raises(ValueError, match=r"3 image topics; name one.*/gelsight/image_bgr"):
        list(tactile.frames(rosbags_bag))
    with pytest.raises(ValueError, match=r"topic /nope: not in the bag; its image topics: /gelsight"):
        list(tactile.frames(rosbags_bag, topic="/nope"))



def rosbags_convert(src: Path, dst: Path, *extra: str) -> Path:
    """`rosbags-convert` (from the `rosbags` package) to MCAP storage."""
    exe = Path(sys.executable).with_name("rosbags-convert")
    cmd = [str(exe), "--src", str(src), "--dst", str(dst), "--dst-storage", "mcap", *extra]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return dst


def assert_the_sample_frames(bag: Path, topic: str, palpation_frames, what: str) -> None:
    topics = {t["topic"]: t["count"] for t in tactile.bag_topics(bag)}
    assert topics == {topic: 12}, what
    frames = list(tactile.frames(bag))
    assert [f.stamp_ns for f in frames] == [stamp(i) for i in range(12)], what
    for f, want in zip(frames, palpation_frames):
        np.testing.assert_array_equal(f.image, want, err_msg=what)


def test_bags_as_ros2_bag_record_leaves_them(rosbags_bag, tmp_path, palpation_frames):
    """A bag folder (metadata.yaml beside its .mcap) is read as its file,
    and so are rosbag2's zstd compression of whole files (.mcap.zstd) and
    of single messages."""
    topic = "/gelsight/image_raw"
    folder = rosbags_convert(rosbags_bag.parent, tmp_path / "plain", "--include-topic", topic)
    assert (folder / "metadata.yaml").is_file()
    whole = rosbags_convert(folder, tmp_path / "whole", "--compress", "zstd", "--compress-mode", "file")
    (zstd_file,) = whole.glob("*.mcap.zstd")
    single = rosbags_convert(folder, tmp_path / "single", "--compress", "zstd", "--compress-mode", "message")
    for bag in [folder, whole, zstd_file, single]:
        assert_the_sample_frames(bag, topic, palpation_frames, str(bag))


def test_sqlite_bags_are_read_and_ros1_bags_name_the_command_that_converts_them(tmp_path, palpation_frames):
    """What `ros2 bag record` leaves on Humble and before (SQLite storage,
    rosbag2's schema versions 8 and 9 as `rosbags` writes them, and its
    zstd compression of single messages) is read as its frames, the folder
    and its .db3 alike; a .db3 compressed whole is refused saying to
    decompress it; a ROS 1 bag is refused with a `rosbags-convert` command,
    which gives a bag that reads as the frames."""
    ts2, ts1 = get_typestore(Stores.ROS2_HUMBLE), get_typestore(Stores.ROS1_NOETIC)
    humble, jazzy, ros1 = tmp_path / "humble", tmp_path / "jazzy", tmp_path / "noetic.bag"
    per_message, whole = tmp_path / "per-message", tmp_path / "whole"

    def compressed(path: Path, mode: CompressionMode) -> RosbagsWriter:
        w = RosbagsWriter(path, version=8, storage_plugin=StoragePlugin.SQLITE3)
        w.set_compression(mode, CompressionFormat.ZSTD)
        return w

    for ts, make in [(ts2, lambda: RosbagsWriter(humble, version=8, storage_plugin=StoragePlugin.SQLITE3)),
                     (ts2, lambda: RosbagsWriter(jazzy, version=9, storage_plugin=StoragePlugin.SQLITE3)),
                     (ts2, lambda: compressed(per_message, CompressionMode.MESSAGE)),
                     (ts2, lambda: compressed(whole, CompressionMode.FILE)),
                     (ts1, lambda: Ros1Writer(ros1))]:
        Image, Header, Time = (ts.types[t] for t in
                               ["sensor_msgs/msg/Image", "std_msgs/msg/Header", "builtin_interfaces/msg/Time"])
        with make() as w:
            c = w.add_connection("/cam/image_raw", Image.__msgtype__, typestore=ts)
            for i, rgb in enumerate(palpation_frames):
                t = stamp(i)
                when = Time(sec=t // 10**9, nanosec=t % 10**9)
                h = Header(seq=i, stamp=when, frame_id="g") if ts is ts1 else Header(stamp=when, frame_id="g")
                height, width, _ = rgb.shape
                msg = Image(header=h, height=height, width=width, encoding="rgb8", is_bigendian=0,
                            step=width * 3, data=np.ascontiguousarray(rgb).reshape(-1))
                data = ts.serialize_ros1(msg, Image.__msgtype__) if ts is ts1 else ts.serialize_cdr(msg, Image.__msgtype__)
                w.write(c, t, data)
    for folder in [humble, jazzy, per_message]:
        (db3,) = folder.glob("*.db3")
        for given in [folder, db3]:
            assert_the_sample_frames(given, "/cam/image_raw", palpation_frames, str(given))
    (zst,) = whole.glob("*.db3.zstd")
    for given in [whole, zst]:
        with pytest.raises(ValueError, match=r"whole\.db3\.zstd: an SQLite bag file rosbag2 compressed whole, .*decompress it first"):
            list(tactile.frames(given))
    hint = f"rosbags-convert --src {ros1} --dst NEW_FOLDER --dst-storage mcap"
    for read in [lambda: list(tactile.frames(ros1)), lambda: tactile.bag_topics(ros1)]:
        with pytest.raises(ValueError) as e:
            read()
        assert "a ROS 1 bag" in str(e.value) and hint in str(e.value), str(e.value)
    converted = rosbags_convert(ros1, tmp_path / "noetic-mcap")
    assert_the_sample_frames(converted, "/cam/image_raw", palpation_frames, "a ROS 1 bag")


def rgb8_bag(path: Path, frames: list[np.ndarray], **writer_options) -> None:
    """`frames` as rgb8 sensor_msgs/msg/Image messages on /cam, message i
    stamped `stamp(i)`, written by mcap-ros2-support with `writer_options`
    (chunk size, compression)."""
    with path.open("wb") as fh:
        w = Ros2McapWriter(fh, **writer_options)
        image = w.register_msgdef("sensor_msgs/msg/Image", IMAGE_MSG)
        for i, rgb in enumerate(frames):
            h, wd, _ = rgb.shape
            w.write_message("/cam", image, {"header": header(i), "height": h, "width": wd, "encoding": "rgb8",
                                            "is_bigendian": 0, "step": wd * 3, "data": rgb.tobytes()},
                            log_time=stamp(i))
        w.finish()


@pytest.mark.parametrize("storage", ["lz4", "uncompressed", "fastwrite"])
def test_a_bag_of_each_rosbag2_mcap_storage_setting_is_read(tmp_path, palpation_frames, storage):
    """rosbag2's MCAP storage compresses chunks with zstd (every other bag
    here) unless its configuration says `compression: Lz4` or none, and
    its `fastwrite` preset writes no chunks, no message indexes and no
    CRCs: each lists its topic and reads the same frames and stamps."""
    zstd = tmp_path / "zstd.mcap"
    compression = {"lz4": CompressionType.LZ4, "uncompressed": CompressionType.NONE}
    rgb8_bag(zstd, palpation_frames, compression=compression.get(storage, CompressionType.ZSTD))
    bag = zstd
    if storage == "fastwrite":
        # The same messages, byte for byte, as the preset lays them out.
        bag = tmp_path / "fastwrite.mcap"
        with zstd.open("rb") as fi, bag.open("wb") as fo:
            w = McapWriter(fo, use_chunking=False, enable_crcs=False, index_types=IndexType.NONE)
            w.start(profile="ros2", library="rosbag2")
            schemas, channels = {}, {}
            for schema, channel, m in make_reader(fi).iter_messages():
                if schema.id not in schemas:
                    schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
                if channel.id not in channels:
                    channels[channel.id] = w.register_channel(
                        channel.topic, channel.message_encoding, schemas[schema.id], channel.metadata)
                w.add_message(channels[channel.id], m.log_time, m.data, m.publish_time, m.sequence)
            w.finish()
    with bag.open("rb") as fh:
        chunks = {c.compression for c in make_reader(fh).get_summary().chunk_indexes}
    assert chunks == {"lz4": {"lz4"}, "uncompressed": {""}, "fastwrite": set()}[storage]
    assert [(t["topic"], t["count"]) for t in tactile.bag_topics(bag)] == [("/cam", 12)]
    got = list(tactile.frames(bag))
    assert [f.stamp_ns for f in got] == [stamp(i) for i in range(12)]
    assert all(np.array_equal(f.image, rgb) for f, rgb in zip(got, palpation_frames))


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="FFmpeg is installed by scripts/test.sh")
def test_mcap_ros2_bag_mono_and_jpeg(tmp_path, root, palpation_frames, tactile_bin):
    """A bag written by `mcap-ros2-support`: mono8 and big-endian mono16
    Images and JPEG CompressedImages, each as the toolkit reads the same
    pixels from files."""
    jpegs = tmp_path / "jpegs"
    jpegs.mkdir()
    for i, f in enumerate(sorted((root / "samples" / "palpation").glob("*.png"))):
        subprocess.run(
            ["ffmpeg", "-nostdin", "-loglevel", "error", "-i", str(f), "-q:v", "3", str(jpegs / f"{i:06d}.jpg")],
            check=True,
        )
    bag = tmp_path / "mono.mcap"
    with bag.open("wb") as fh:
        w = Ros2McapWriter(fh)
        image = w.register_msgdef("sensor_msgs/msg/Image", IMAGE_MSG)
        compressed = w.register_msgdef("sensor_msgs/msg/CompressedImage", COMPRESSED_MSG)
        for i, rgb in enumerate(palpation_frames):
            h, wd, _ = rgb.shape
            grey = rgb[:, :, 1].copy()
            w.write_message("/tac/mono8", image, {
                "header": header(i), "height": h, "width": wd, "encoding": "mono8",
                "is_bigendian": 0, "step": wd + 4,
                "data": np.pad(grey, ((0, 0), (0, 4))).tobytes(),
            }, log_time=stamp(i), publish_time=stamp(i))
            w.write_message("/tac/mono16", image, {
                "header": header(i), "height": h, "width": wd, "encoding": "mono16",
                "is_bigendian": 1, "step": wd * 2,
                "data": (grey.astype(">u2") * 257).tobytes(),
            }, log_time=stamp(i), publish_time=stamp(i))
            w.write_message("/tac/jpeg", compressed, {
                "header": header(i), "format": "rgb8; jpeg compressed bgr8",
                "data": (jpegs / f"{i:06d}.jpg").read_bytes(),
            }, log_time=stamp(i), publish_time=stamp(i))
        w.finish()
    for topic in ["/tac/mono8", "/tac/mono16"]:
        frames = list(tactile.frames(bag, topic=topic))
        assert [f.stamp_ns for f in frames] == [stamp(i) for i in range(12)]
        for f, rgb in zip(frames, palpation_frames):
            np.testing.assert_array_equal(f.image, np.repeat(rgb[:, :, 1:2], 3, axis=2), err_msg=topic)
    from_bag = [f.image for f in tactile.frames(bag, topic="/tac/jpeg")]
    from_files = [f.image for f in tactile.frames(jpegs)]
    assert len(from_bag) == 12
    for a, b in zip(from_bag, from_files):
        np.testing.assert_array_equal(a, b)
    want = decisions(run_records(tactile_bin, root, tmp_path, "--data", str(jpegs)))
    got = decisions(run_records(tactile_bin, root, tmp_path, "--data", str(bag), "--topic", "/tac/jpeg"))
    assert got == want


def test_frames_the_foxglove_sdk_records(tmp_path, root, palpation_frames, tactile_bin):
    """An MCAP recorded with the Foxglove SDK (foxglove.RawImage and
    foxglove.CompressedImage in protobuf), not a ROS 2 bag: the same
    frames, stamps and decisions as the PNG folder."""
    import foxglove
    from foxglove.channels import CompressedImageChannel, RawImageChannel
    from foxglove.messages import CompressedImage, RawImage, Timestamp

    bag = tmp_path / "sdk.mcap"
    pngs = sorted((root / "samples" / "palpation").glob("*.png"))
    ctx = foxglove.Context()
    with foxglove.open_mcap(bag, context=ctx):
        raw = RawImageChannel("/cam/raw", context=ctx)
        png = CompressedImageChannel("/cam/png", context=ctx)
        for i, (f, rgb) in enumerate(zip(pngs, palpation_frames)):
            t = stamp(i)
            ts = Timestamp(sec=t // 10**9, nsec=t % 10**9)
            h, w, _ = rgb.shape
            raw.log(RawImage(timestamp=ts, frame_id="cam", width=w, height=h, encoding="rgb8", step=w * 3,
                             data=rgb.tobytes()), log_time=t)
            png.log(CompressedImage(timestamp=ts, frame_id="cam", data=f.read_bytes(), format="png"), log_time=t)
    listed = {t["topic"]: (t["message_type"], t["count"]) for t in tactile.bag_topics(bag)}
    assert listed == {"/cam/raw": ("foxglove.RawImage", len(pngs)), "/cam/png": ("foxglove.CompressedImage", len(pngs))}
    for topic in listed:
        got = list(tactile.frames(bag, topic=topic))
        assert [f.stamp_ns for f in got] == [stamp(i) for i in range(len(pngs))]
        for f, rgb in zip(got, palpation_frames):
            assert np.array_equal(f.image, rgb), topic
    folder = run_records(tactile_bin, root, tmp_path, "--data", str(root / "samples" / "palpation"))
    recorded = run_records(tactile_bin, root, tmp_path, "--data", str(bag), "--topic", "/cam/raw")
    assert decisions(recorded) == decisions(folder)


def lossless_h264_packets(pngs: Path, tmp: Path) -> list[bytes]:
    """The PNG frames of `pngs` as lossless H.264 (RGB, no B-frames, a
    keyframe every 4 with its parameter sets): one packet per frame."""
    packets = tmp / "packets"
    packets.mkdir()
    subprocess.run(["ffmpeg", "-nostdin", "-loglevel", "error", "-i", str(pngs / "%06d.png"),
                    "-c:v", "libx264rgb", "-qp", "0", "-bf", "0", "-g", "4", "-x264-params", "repeat-headers=1",
                    "-f", "image2", str(packets / "%03d.h264")], check=True)
    return [p.read_bytes() for p in sorted(packets.glob("*.h264"))]


def foxglove_video(bag: Path, topic: str, packets: list[tuple[int, bytes]], fmt: str, image: bool = False) -> None:
    """`packets` (message i stamped `stamp(i)`) recorded on `topic` by the
    Foxglove SDK as foxglove.CompressedVideo of format `fmt`, or as
    foxglove.CompressedImage of that format when `image`."""
    import foxglove
    from foxglove.channels import CompressedImageChannel, CompressedVideoChannel
    from foxglove.messages import CompressedImage, CompressedVideo, Timestamp

    message, channel_type = (CompressedImage, CompressedImageChannel) if image else \
        (CompressedVideo, CompressedVideoChannel)
    ctx = foxglove.Context()
    with foxglove.open_mcap(bag, context=ctx):
        channel = channel_type(topic, context=ctx)
        for i, d in packets:
            t = stamp(i)
            channel.log(message(timestamp=Timestamp(sec=t // 10**9, nsec=t % 10**9), frame_id="cam", data=d,
                                format=fmt), log_time=t)


def test_h264_video_the_foxglove_sdk_records(tmp_path, root, palpation_frames, tactile_bin):
    """A camera recorded as foxglove.CompressedVideo (one H.264 frame per
    message, lossless here): the frames, stamps and decisions of the PNG
    folder, also as foxglove.CompressedImage of format h264; a recording
    begun mid-stream starts at its first keyframe and says so."""
    pngs = root / "samples" / "palpation"
    data = lossless_h264_packets(pngs, tmp_path)
    assert len(data) == len(palpation_frames)

    def record(bag: Path, first: int) -> None:
        foxglove_video(bag, "/cam/h264", list(enumerate(data))[first:], "h264")

    bag = tmp_path / "video.mcap"
    record(bag, 0)
    assert [(t["topic"], t["message_type"], t["count"]) for t in tactile.bag_topics(bag)] == [
        ("/cam/h264", "foxglove.CompressedVideo", len(data))]
    got = list(tactile.frames(bag))
    assert [f.stamp_ns for f in got] == [stamp(i) for i in range(len(data))]
    for f, rgb in zip(got, palpation_frames):
        assert np.array_equal(f.image, rgb)
    folder = run_records(tactile_bin, root, tmp_path, "--data", str(pngs))
    assert decisions(run_records(tactile_bin, root, tmp_path, "--data", str(bag))) == decisions(folder)
    # The same packets as foxglove.CompressedImage of format h264 (as
    # GStreamer's ROS 2 sink publishes them): read as video.
    images = tmp_path / "images.mcap"
    foxglove_video(images, "/cam/image", list(enumerate(data)), "h264", image=True)
    got = list(tactile.frames(images))
    assert [f.stamp_ns for f in got] == [stamp(i) for i in range(len(data))]
    assert all(np.array_equal(f.image, rgb) for f, rgb in zip(got, palpation_frames))
    # Begun at frame 2 of a group of 4: frames 4 on, with a warning.
    late = tmp_path / "late.mcap"
    record(late, 2)
    with pytest.warns(UserWarning, match=r"its first 2 messages come before the first keyframe of its h264 stream"):
        got = list(tactile.frames(late))
    assert [f.stamp_ns for f in got] == [stamp(i) for i in range(4, len(data))]
    assert all(np.array_equal(f.image, rgb) for f, rgb in zip(got, palpation_frames[4:]))


def test_foxglove_json_messages_the_python_sdk_logs(tmp_path, root, palpation_frames, tactile_bin):
    """Foxglove's image and video schemas logged as JSON (plain dicts,
    bytes in base64, as Foxglove's JSON schemas have them) through the
    Foxglove SDK's generic channel: the frames, stamps and decisions of
    the PNG folder."""
    import base64

    import foxglove

    pngs = root / "samples" / "palpation"
    files = sorted(pngs.glob("*.png"))
    video = lossless_h264_packets(pngs, tmp_path)
    b64 = lambda b: base64.b64encode(b).decode("ascii")  # noqa: E731

    def channel(ctx, topic: str, name: str):
        schema = foxglove.Schema(name=name, encoding="jsonschema", data=json.dumps({"type": "object"}).encode())
        return foxglove.Channel(topic, schema=schema, message_encoding="json", context=ctx)

    bag = tmp_path / "json.mcap"
    ctx = foxglove.Context()
    with foxglove.open_mcap(bag, context=ctx):
        raw = channel(ctx, "/cam/raw", "foxglove.RawImage")
        png = channel(ctx, "/cam/png", "foxglove.CompressedImage")
        h264 = channel(ctx, "/cam/h264", "foxglove.CompressedVideo")
        for i, (f, rgb) in enumerate(zip(files, palpation_frames)):
            t = stamp(i)
            ts = {"sec": t // 10**9, "nsec": t % 10**9}
            h, w, _ = rgb.shape
            raw.log({"timestamp": ts, "frame_id": "cam", "width": w, "height": h, "encoding": "rgb8",
                     "step": w * 3, "data": b64(rgb.tobytes())}, log_time=t)
            png.log({"timestamp": ts, "frame_id": "cam", "data": b64(f.read_bytes()), "format": "png"}, log_time=t)
            h264.log({"timestamp": ts, "frame_id": "cam", "data": b64(video[i]), "format": "h264"}, log_time=t)
    for topic in ["/cam/raw", "/cam/png", "/cam/h264"]:
        got = list(tactile.frames(bag, topic=topic))
        assert [f.stamp_ns for f in got] == [stamp(i) for i in range(len(files))], topic
        for f, rgb in zip(got, palpation_frames):
            assert np.array_equal(f.image, rgb), topic
    folder = run_records(tactile_bin, root, tmp_path, "--data", str(pngs))
    recorded = run_records(tactile_bin, root, tmp_path, "--data", str(bag), "--topic", "/cam/png")
    assert decisions(recorded) == decisions(folder)


def test_a_live_video_topic_decodes_each_packet_as_it_arrives(tmp_path, root, palpation_frames):
    """A node subscribed to a running camera's H.264 topic, joined in the
    middle of a group of pictures: `VideoDecoder.decode` skips the packets
    before the next keyframe and then gives each packet's own frame (the
    PNG, lossless) with its stamp, before the next packet is given."""
    data = lossless_h264_packets(root / "samples" / "palpation", tmp_path)
    decoder = tactile.VideoDecoder("h264", name="/cam/h264")
    got = []
    for i in range(2, len(data)):
        frames = decoder.decode(bytearray(data[i]), stamp(i))
        if i >= 4:
            assert [f.stamp_ns for f in frames] == [stamp(i)], i
        got += frames
    assert decoder.skipped == 2
    got += decoder.finish()
    assert [f.stamp_ns for f in got] == [stamp(i) for i in range(4, len(data))]
    assert all(np.array_equal(f.image, rgb) for f, rgb in zip(got, palpation_frames[4:]))
    with pytest.raises(ValueError, match="finished"):
        decoder.decode(data[0])
    with pytest.raises(ValueError, match=r'/cam: video in format "vp8"'):
        tactile.VideoDecoder("vp8", name="/cam")


def test_a_live_camera_with_b_frames_gives_each_frame_without_waiting(tmp_path, root, palpation_frames):
    """A camera whose encoder uses B-frames (x264 of the sample frames, two
    between references; lossless x264 makes none): packets come in
    decoding order, each stamped with the time its frame shows. The frames
    its decoder holds back are read from the first keyframe's parameters,
    so no `decode` waits out a second to learn them: after the first, each
    returns the next frame in display order with its own stamp and
    FFmpeg's pixels, the 12 within a second."""
    pngs = root / "samples" / "palpation"
    encoder = ["-i", str(pngs / "%06d.png"), "-c:v", "libx264rgb", "-qp", "1", "-threads", "1", "-g", "12",
               "-x264-params", "bframes=2:b-adapt=0:b-pyramid=none:repeat-headers=1"]
    packets = tmp_path / "packets"
    packets.mkdir()
    subprocess.run(["ffmpeg", "-nostdin", "-loglevel", "error", *encoder, "-f", "image2",
                    str(packets / "%03d.h264")], check=True)
    data = [p.read_bytes() for p in sorted(packets.glob("*.h264"))]
    # Each packet's display time, as the encoder gave it (decoding order).
    listed = subprocess.run(["ffmpeg", "-nostdin", "-loglevel", "error", *encoder, "-f", "framecrc", "-"],
                            check=True, capture_output=True, text=True).stdout
    pts = [int(line.split(",")[2]) for line in listed.splitlines() if not line.startswith("#")]
    shown = [sorted(pts).index(t) for t in pts]
    assert len(data) == 12 and shown != list(range(12)), "no B-frames"
    stream = tmp_path / "stream.h264"
    stream.write_bytes(b"".join(data))
    raw = subprocess.run(["ffmpeg", "-nostdin", "-loglevel", "error", "-i", str(stream), "-f", "rawvideo",
                          "-pix_fmt", "rgb24", "-"], check=True, capture_output=True).stdout
    decoded = np.frombuffer(raw, np.uint8).reshape(12, *palpation_frames[0].shape)
    decoder = tactile.VideoDecoder("h264", name="/cam")
    counts, got = [], []
    start = time.monotonic()
    for d, k in zip(data, shown):
        frames = decoder.decode(d, stamp(k))
        counts.append(len(frames))
        got += frames
    elapsed = time.monotonic() - start
    got += decoder.finish()
    assert counts == [0] + [1] * 11
    assert elapsed < 1.0, f"12 packets took {elapsed:.2f} s"
    assert [f.stamp_ns for f in got] == [stamp(k) for k in range(12)]
    assert all(np.array_equal(f.image, rgb) for f, rgb in zip(got, decoded))
    assert decoder.lost == 0


def test_a_live_camera_that_sent_its_parameter_sets_only_at_its_start_is_told(tmp_path, root):
    """An encoder that sends H.264's SPS and PPS once, with its first
    keyframe (x264's `repeat-headers=0` where the stream has no other
    place for them), joined after it: its later keyframes cannot start a
    stream. `keyframes_without_parameters` counts them as they come, for a
    node to log, and `finish` names them with the cure. Before, only "none
    of its 11 messages is a keyframe"."""
    def without_parameter_sets(packet: bytes) -> bytes:
        units = [u.rstrip(b"\x00") for u in packet.split(b"\x00\x00\x01")[1:]]
        return b"".join(b"\x00\x00\x01" + u for u in units if u and u[0] & 0x1F not in (7, 8))

    whole = lossless_h264_packets(root / "samples" / "palpation", tmp_path)
    data = [whole[0]] + [without_parameter_sets(p) for p in whole[1:]]
    decoder = tactile.VideoDecoder("h264", name="/cam")
    for i in range(1, len(data)):
        assert decoder.decode(data[i], stamp(i)) == [], i
        assert decoder.keyframes_without_parameters == (i >= 4) + (i >= 8), i
    assert decoder.skipped == len(data) - 1
    with pytest.raises(ValueError, match=r"messages 3, 7 are keyframes without their sequence parameter "
                       r"set: the encoder sent it only at its start, before the first of these messages, "
                       r"so have it repeat it at every keyframe \(x264's and x265's `repeat-headers=1`"):
        decoder.finish()
    # From its start, the first keyframe carries them: every frame comes,
    # each with its own stamp.
    decoder = tactile.VideoDecoder("h264", name="/cam")
    got = [f for i, d in enumerate(data) for f in decoder.decode(d, stamp(i))] + decoder.finish()
    assert [f.stamp_ns for f in got] == [stamp(i) for i in range(len(data))]
    assert decoder.keyframes_without_parameters == 0


def test_a_damaged_packet_leaves_every_other_frame_its_own_stamp(tmp_path, root, palpation_frames):
    """A packet damaged on the way (message 5, in a group of pictures)
    gives no frame: every other frame keeps its own stamp, in a recording
    (with a warning naming the message) and live (each later packet's frame
    from its own `decode`). Before, each frame after it was stamped as the
    packet before it."""
    data = lossless_h264_packets(root / "samples" / "palpation", tmp_path)
    lost = 5
    damaged = list(data)
    damaged[lost] = b"\x00\x00\x01\x65\xff\xff"
    kept = [i for i in range(len(data)) if i != lost]
    bag = tmp_path / "damaged.mcap"
    foxglove_video(bag, "/cam", list(enumerate(damaged)), "h264")
    with pytest.warns(UserWarning, match=r"messages that gave none: 5; every frame carries its own packet's stamp"):
        got = list(tactile.frames(bag))
    assert [f.stamp_ns for f in got] == [stamp(i) for i in kept]
    # Frames that do not refer to the lost one are the PNGs (lossless).
    for f, i in zip(got, kept):
        if i < lost or i >= 8:
            assert np.array_equal(f.image, palpation_frames[i]), i
    decoder = tactile.VideoDecoder("h264", name="/cam")
    for i, d in enumerate(damaged):
        started = time.monotonic()
        frames = decoder.decode(d, stamp(i))
        assert [f.stamp_ns for f in frames] == ([] if i == lost else [stamp(i)]), i
        # FFmpeg's error says the packet is lost: no second's wait for it.
        assert time.monotonic() - started < 0.5, i
        # Counted once a later frame came.
        assert decoder.lost == int(i > lost), i
    assert decoder.finish() == []
    assert (decoder.skipped, decoder.lost) == (0, 1)


def av1_temporal_units(stream: bytes) -> list[bytes]:
    """An AV1 low overhead stream split before each temporal delimiter
    (OBU type 2): one temporal unit, a frame here, each."""
    units, at = [], 0
    while at < len(stream):
        header = stream[at]
        p = at + 1 + ((header >> 2) & 1)
        size, shift = 0, 0
        while True:
            b = stream[p]
            p, size, shift = p + 1, size | (b & 0x7F) << shift, shift + 7
            if b < 0x80:
                break
        if (header >> 3) & 0x0F == 2:
            units.append(b"")
        units[-1] += stream[at:p + size]
        at = p + size
    return units


def ivf_frames(data):
    """The frames of an IVF file (a 32-byte file header, then each frame
    after its 32-bit size and 64-bit place), as FFmpeg's ivf muxer writes VP9."""
    assert data[:4] == b"DKIF" and data[8:12] == b"VP90"
    frames, at = [], 32
    while at < len(data):
        size = int.from_bytes(data[at:at + 4], "little")
        frames.append(data[at + 12:at + 12 + size])
        at += 12 + size
    return frames


@pytest.mark.parametrize("codec", ["av1", "vp9"])
def test_video_decodes_live_and_from_a_foxglove_recording(tmp_path, root, codec):
    """AV1 (libaom, a temporal unit per message) and VP9 (libvpx, a frame
    per message) as the Foxglove SDK records them and as a live topic gives
    them: every frame FFmpeg's decode of the whole stream, each live one
    back from its own `decode`."""
    encoder, muxer, split = {
        "av1": (["libaom-av1", "-cpu-used", "8", "-lag-in-frames", "0"], "obu", av1_temporal_units),
        "vp9": (["libvpx-vp9", "-threads", "1"], "ivf", ivf_frames),
    }[codec]
    stream = tmp_path / f"{codec}.{muxer}"
    subprocess.run(["ffmpeg", "-nostdin", "-loglevel", "error", "-f", "lavfi", "-i", "testsrc=size=96x64:rate=10",
                    "-frames:v", "6", "-pix_fmt", "yuv420p", "-c:v", *encoder, "-g", "3",
                    "-f", muxer, str(stream)], check=True)
    raw = subprocess.run(["ffmpeg", "-nostdin", "-loglevel", "error", "-i", str(stream), "-f", "rawvideo",
                          "-pix_fmt", "rgb24", "-"], check=True, capture_output=True).stdout
    want = np.frombuffer(raw, np.uint8).reshape(6, 64, 96, 3)
    units = split(stream.read_bytes())
    assert len(units) == 6
    decoder = tactile.VideoDecoder(codec, name=f"/cam/{codec}")
    for i, unit in enumerate(units):
        frames = decoder.decode(unit, stamp(i))
        assert [f.stamp_ns for f in frames] == [stamp(i)], i
        assert np.array_equal(frames[0].image, want[i]), i
    assert decoder.finish() == []
    bag = tmp_path / f"{codec}.mcap"
    foxglove_video(bag, f"/cam/{codec}", list(enumerate(units)), codec)
    got = list(tactile.frames(bag))
    assert [f.stamp_ns for f in got] == [stamp(i) for i in range(6)]
    assert all(np.array_equal(f.image, w) for f, w in zip(got, want))


def test_a_camera_restarted_at_another_size_keeps_each_frames_size(tmp_path):
    """A foxglove.CompressedVideo topic whose camera restarts at another
    size (lossless H.264 at 64x48, then a keyframe with a new SPS at
    96x64): every frame at its own size with FFmpeg's pixels, read from the
    recording (with a warning naming the message) and live."""
    packets, want = [], []
    for w, h in [(64, 48), (96, 64)]:
        folder = tmp_path / f"{w}x{h}"
        folder.mkdir()
        source = ["-f", "lavfi", "-i", f"testsrc=size={w}x{h}:rate=10", "-frames:v", "3"]
        subprocess.run(["ffmpeg", "-nostdin", "-loglevel", "error", *source, "-c:v", "libx264rgb", "-qp", "0",
                        "-bf", "0", "-f", "image2", str(folder / "%03d.h264")], check=True)
        packets += [p.read_bytes() for p in sorted(folder.glob("*.h264"))]
        raw = subprocess.run(["ffmpeg", "-nostdin", "-loglevel", "error", *source, "-f", "rawvideo",
                              "-pix_fmt", "rgb24", "-"], check=True, capture_output=True).stdout
        want += list(np.frombuffer(raw, np.uint8).reshape(3, h, w, 3))
    bag = tmp_path / "restarted.mcap"
    foxglove_video(bag, "/cam/h264", list(enumerate(packets)), "h264")
    with pytest.warns(UserWarning, match=r"its h264 stream's parameters change at message 3"):
        got = list(tactile.frames(bag))
    assert [f.stamp_ns for f in got] == [stamp(i) for i in range(6)]
    assert all(np.array_equal(f.image, w) for f, w in zip(got, want))
    decoder = tactile.VideoDecoder("h264", name="/cam/h264")
    for i, d in enumerate(packets):
        frames = decoder.decode(d, stamp(i))
        assert [f.image.shape for f in frames] == [want[i].shape], i
        assert np.array_equal(frames[0].image, want[i]), i
    assert decoder.finish() == []
    # Its change of size got its own decoder: no frame was scaled.
    assert (decoder.lost, decoder.scaled) == (0, 0)


def test_ros2_video_topics_written_by_another_cdr_writer(tmp_path, root, palpation_frames):
    """ROS 2's video messages (foxglove_msgs CompressedVideo,
    ffmpeg_image_transport's FFMPEGPacket and h264_image_transport's
    h264_msgs Packet) serialised by mcap-ros2-support from their message
    definitions: the frames and stamps of the PNGs."""
    data = lossless_h264_packets(root / "samples" / "palpation", tmp_path)
    time_deps = "\n================================================================================\n" \
        "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
    bag = tmp_path / "ros-video.mcap"
    with bag.open("wb") as fh:
        w = Ros2McapWriter(fh)
        video = w.register_msgdef("foxglove_msgs/msg/CompressedVideo",
                                  "builtin_interfaces/Time timestamp\nstring frame_id\nuint8[] data\nstring format"
                                  + time_deps)
        packet = w.register_msgdef("ffmpeg_image_transport_msgs/msg/FFMPEGPacket",
                                   "std_msgs/Header header\nint32 width\nint32 height\nstring encoding\n"
                                   "uint64 pts\nuint8 flags\nbool is_bigendian\nuint8[] data" + HEADER_DEPS)
        h264 = w.register_msgdef("h264_msgs/msg/Packet", "std_msgs/Header header\nint64 seq\nuint8[] data" + HEADER_DEPS)
        for i, d in enumerate(data):
            h, wd, _ = palpation_frames[i].shape
            w.write_message("/cam/video", video, {"timestamp": header(i)["stamp"], "frame_id": "cam", "data": d,
                                                  "format": "h264"}, log_time=stamp(i), publish_time=stamp(i))
            w.write_message("/cam/ffmpeg", packet, {"header": header(i), "width": wd, "height": h,
                                                    "encoding": "h264;gbrp;rgb8;rgb8", "pts": i,
                                                    "flags": int(i % 4 == 0), "is_bigendian": False, "data": d},
                            log_time=stamp(i), publish_time=stamp(i))
            w.write_message("/cam/h264", h264, {"header": header(i), "seq": 1000 + i, "data": d},
                            log_time=stamp(i), publish_time=stamp(i))
        w.finish()
    listed = {t["topic"]: t["message_type"] for t in tactile.bag_topics(bag)}
    assert listed == {"/cam/video": "foxglove_msgs/msg/CompressedVideo",
                      "/cam/ffmpeg": "ffmpeg_image_transport_msgs/msg/FFMPEGPacket",
                      "/cam/h264": "h264_msgs/msg/Packet"}
    for topic in listed:
        got = list(tactile.frames(bag, topic=topic))
        assert [f.stamp_ns for f in got] == [stamp(i) for i in range(len(data))], topic
        for f, rgb in zip(got, palpation_frames):
            assert np.array_equal(f.image, rgb), topic


def test_hostile_bags_name_the_topic_and_message(tmp_path, palpation_frames):
    bag = tmp_path / "hostile.mcap"
    with bag.open("wb") as fh:
        w = Ros2McapWriter(fh)
        image = w.register_msgdef("sensor_msgs/msg/Image", IMAGE_MSG)
        compressed = w.register_msgdef("sensor_msgs/msg/CompressedImage", COMPRESSED_MSG)
        header_only = w.register_msgdef("std_msgs/msg/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"
                                        "================================================================================\n"
                                        "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n")
        rgb = palpation_frames[0]
        h, wd, _ = rgb.shape
        good = {"header": header(0), "height": h, "width": wd, "encoding": "rgb8", "is_bigendian": 0,
                "step": wd * 3, "data": rgb.tobytes()}
        w.write_message("/wide", image, good, log_time=stamp(0))
        w.write_message("/wide", image, {**good, "width": 100_000, "height": 100_000, "step": 300_000},
                        log_time=stamp(1))
        w.write_message("/fake_jpeg", compressed, {"header": header(0), "format": "jpeg", "data": b"not a picture"},
                        log_time=stamp(0))
        w.write_message("/nv21", image, {**good, "encoding": "nv21"}, log_time=stamp(0))
        w.write_message("/header", header_only, header(0), log_time=stamp(0))
        w.finish()
    wide = tactile.frames(bag, topic="/wide")
    assert next(wide).image.shape == (h, wd, 3)
    with pytest.raises(ValueError, match=r"hostile.mcap: topic /wide, message 1: image is 100000x100000"):
        next(wide)
    with pytest.raises(ValueError, match=r"topic /fake_jpeg, message 0: .*not a picture in a format frames are read in"):
        list(tactile.frames(bag, topic="/fake_jpeg"))
    with pytest.raises(ValueError, match=r"topic /nv21, message 0: encoding \"nv21\""):
        list(tactile.frames(bag, topic="/nv21"))
    with pytest.raises(ValueError, match=r"topic /header: carries std_msgs/msg/Header"):
        list(tactile.frames(bag, topic="/header"))
    damaged = tmp_path / "damaged.mcap"
    data = bytearray(bag.read_bytes())
    data[len(data) // 3: len(data) // 2] = b"\xab" * (len(data) // 2 - len(data) // 3)
    damaged.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=r"damaged.mcap: not a readable MCAP bag"):
        list(tactile.frames(damaged, topic="/wide"))


def test_a_recording_cut_short_gives_its_complete_frames(tmp_path, palpation_frames):
    """A bag as a recorder killed mid-write leaves it (no summary, no
    footer, its last chunk half written): the frames of its complete
    chunks, and a warning saying what was lost; `ros2 bag record` is
    often stopped so on a robot."""
    bag = tmp_path / "killed.mcap"
    rgb8_bag(bag, palpation_frames, chunk_size=1)  # a chunk per frame
    with bag.open("rb") as fh:
        chunks = make_reader(fh).get_summary().chunk_indexes
    last = chunks[-1]
    data = bag.read_bytes()
    bag.write_bytes(data[: last.chunk_start_offset + last.chunk_length // 2])
    kept = len(palpation_frames) - 1
    with pytest.warns(UserWarning, match=rf"killed.mcap ends without its MCAP footer.*\({kept} on /cam"):
        got = list(tactile.frames(bag))
    with pytest.warns(UserWarning, match=r"killed.mcap ends without its MCAP footer.*messages up to the last"):
        listed = tactile.bag_topics(bag)
    assert len(got) == kept and listed[0]["count"] == kept
    for f, rgb in zip(got, palpation_frames):
        assert np.array_equal(f.image, rgb)
    assert got[-1].stamp_ns == stamp(len(got) - 1)


def read_back(path: Path) -> dict[str, list]:
    out: dict[str, list] = {}
    for m in read_ros2_messages(str(path)):
        out.setdefault(m.channel.topic, []).append(m)
    return out


def nan_or(v):
    return float("nan") if v is None else v


def same(a, b) -> bool:
    return (isinstance(a, float) and math.isnan(a) and b is None) or a == pytest.approx(nan_or(b), rel=1e-6)


def test_results_mcap_is_read_back_by_both_readers(rosbags_bag, tactile_bin, root, tmp_path, palpation_frames):
    topic = "/gelsight/image_raw"
    records = run_records(tactile_bin, root, tmp_path, "--data", str(rosbags_bag), "--topic", topic)
    out = tmp_path / "results.mcap"
    r = subprocess.run(
        [str(tactile_bin), "run", "--data", str(rosbags_bag), "--topic", topic, "--out", str(out), "--with-frames"],
        capture_output=True, text=True, cwd=root,
    )
    assert r.returncode == 0, r.stderr
    got = read_back(out)
    tendon = sum(rec["tendon"] for rec in records)
    assert {k: len(v) for k, v in got.items()} == {
        "/tactile/image": 12, "/tactile/result": 12, "/tactile/annotations": 12,
        "/tactile/tendon_mask": tendon, "/tactile/depth": tendon,
    }
    for m, rec, rgb in zip(got["/tactile/result"], records, palpation_frames):
        msg = m.ros_msg
        t = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        assert t == rec["stamp_ns"] == m.log_time_ns
        assert msg.frame == rec["frame"]
        assert (msg.tendon, msg.tendon_raw, msg.mask_area_px) == (rec["tendon"], rec["tendon_raw"], rec["mask_area_px"])
        for field in ["score", "direction_deg", "anisotropy", "depth_min_mm", "depth_mean_mm", "depth_max_mm"]:
            assert same(getattr(msg, field), rec[field]), field
        assert msg.has_direction == (rec["direction_deg"] is not None)
    for m, rgb in zip(got["/tactile/image"], palpation_frames):
        img = m.ros_msg
        assert (img.encoding, img.height, img.width) == ("rgb8", *rgb.shape[:2])
        np.testing.assert_array_equal(np.frombuffer(bytes(img.data), np.uint8).reshape(rgb.shape), rgb)
    for m in got["/tactile/depth"]:
        d = np.frombuffer(bytes(m.ros_msg.data), "<f4")
        assert m.ros_msg.encoding == "32FC1" and d.size == m.ros_msg.width * m.ros_msg.height
        assert np.isfinite(d).all() and 5 < d.mean() < 30
    masks = [np.frombuffer(bytes(m.ros_msg.data), np.uint8) for m in got["/tactile/tendon_mask"]]
    assert [int((k == 255).sum()) for k in masks] == [rec["mask_area_px"] for rec in records if rec["tendon"]]
    lines = [m.ros_msg.points for m in got["/tactile/annotations"]]
    assert sum(len(p) for p in lines) == sum(rec["direction_deg"] is not None for rec in records)
    # rosbags reads the same file with its own CDR decoder and the schemas in it.
    with AnyReader([out], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        results = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()
                   if c.topic == "/tactile/result"]
    assert [(m.tendon, m.frame) for m in results] == [(rec["tendon"], rec["frame"]) for rec in records]


def test_python_writes_the_same_results_mcap(tmp_path, pipeline, palpation_frames):
    out = tmp_path / "py.mcap"
    pipeline.reset()
    with tactile.McapWriter(out) as w:
        results = []
        for i, f in enumerate(palpation_frames):
            res = pipeline.process(f)
            results.append(res)
            w.write(res, f if i == 0 else None, stamp_ns=stamp(i))
        assert not out.exists()
    got = read_back(out)
    assert len(got["/tactile/image"]) == 1
    # Paper B's topics declared at once, the frames when first written; no
    # indentation without a calibrated sensor.
    from mcap.reader import make_reader
    with open(out, "rb") as fh:
        declared = {c.topic for c in make_reader(fh).get_summary().channels.values()}
    assert declared == {"/tactile/result", "/tactile/tendon_mask", "/tactile/depth", "/tactile/annotations",
                        "/tactile/image"}
    assert [m.ros_msg.tendon for m in got["/tactile/result"]] == [r.tendon for r in results]
    assert [m.log_time_ns for m in got["/tactile/result"]] == [stamp(i) for i in range(12)]
    # A stamp a message cannot hold (before 1970: MCAP's times are
    # unsigned; past 2038: a header's seconds are an int32) is refused, not
    # written as another time; live too, a viewer watching or not.
    with tactile.McapWriter(tmp_path / "stamps.mcap") as w:
        for s in (-1, 2**31 * 10**9, 2**62):
            with pytest.raises(ValueError, match=rf"^frame \S+: stamp_ns {s}: a stamp must be 0 \(1970\) to 2147483647999999999"):
                w.write(results[0], stamp_ns=s)
        w.write(results[0], stamp_ns=2**31 * 10**9 - 1)
    assert [m.log_time_ns for m in read_back(tmp_path / "stamps.mcap")["/tactile/result"]] == [2**31 * 10**9 - 1]
    with tactile.LiveView("127.0.0.1:0") as view, pytest.raises(ValueError, match=r"stamp_ns -1: a stamp must be"):
        view.publish(results[0], stamp_ns=-1)
    # An error inside the block leaves no file.
    bad = tmp_path / "bad.mcap"
    with pytest.raises(RuntimeError):
        with tactile.McapWriter(bad) as w:
            w.write(results[0])
            raise RuntimeError("stop")
    assert not bad.exists() and not list(tmp_path.glob(".tactile-*"))
    # An empty name (a blank setting) is refused when the writer is made,
    # not after every frame was written to it.
    with pytest.raises(ValueError, match=r"^'' \(an empty path\): give a file name for this output$"):
        tactile.McapWriter("")


async def _watch(port: int, started: threading.Event, want: set[str], timeout: float,
                 advertised: set[str] | None = None) -> dict[str, int]:
    """Messages seen per topic; `advertised` gets every topic offered."""
    import websockets

    seen: dict[str, int] = {}
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"],
                                  max_size=None) as ws:
        channels: dict[int, dict] = {}
        subs: dict[int, str] = {}
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                msg = await asyncio.wait_for(ws.recv(), timeout=0.5)
            except asyncio.TimeoutError:
                continue
            if isinstance(msg, str):
                op = json.loads(msg)
                if op.get("op") == "advertise":
                    new = []
                    for c in op["channels"]:
                        channels[c["id"]] = c
                        if advertised is not None:
                            advertised.add(c["topic"])
                        sid = len(subs) + 1
                        subs[sid] = c["topic"]
                        new.append({"id": sid, "channelId": c["id"]})
                        assert c["encoding"] == "cdr" and c["schemaEncoding"] == "ros2msg" and c["schema"]
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": new}))
                    if want <= {c["topic"] for c in channels.values()}:
                        started.set()
            else:
                assert msg[0] == 1  # message data
                sid, _ts = struct.unpack_from("<IQ", msg, 1)
                seen[subs[sid]] = seen.get(subs[sid], 0) + 1
                if want <= set(seen):
                    return seen
    return seen


def test_live_view_serves_every_channel(tactile_bin, root, palpation_frames):
    pytest.importorskip("websockets")
    h, w, _ = palpation_frames[0].shape
    proc = subprocess.Popen(
        [str(tactile_bin), "run", "--stdin", "--size", f"{w}x{h}", "--view", "127.0.0.1:0", "--with-frames",
         "--live-queue", "64"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=root,
    )
    try:
        port = None
        assert proc.stderr is not None
        for _ in range(50):
            line = proc.stderr.readline().decode()
            if "ws://" in line:
                port = int(line.split("ws://")[1].split()[0].rsplit(":", 1)[1])
                break
        assert port, "the live view's address was not printed"
        started = threading.Event()
        want = {"/tactile/image", "/tactile/result", "/tactile/annotations", "/tactile/tendon_mask",
                "/tactile/depth"}
        result: dict = {}
        advertised: set[str] = set()

        def watch():
            result.update(asyncio.run(_watch(port, started, want, 60, advertised)))

        t = threading.Thread(target=watch)
        t.start()
        assert started.wait(30), "no channels advertised"
        time.sleep(0.3)  # the subscription reaches the server
        assert proc.stdin is not None
        for _ in range(3):
            for f in palpation_frames:
                proc.stdin.write(f.tobytes())
                proc.stdin.flush()
                time.sleep(0.03)
        t.join(60)
        out, err = proc.communicate(timeout=60)
        assert proc.returncode == 0, err.decode()
        assert want <= set(result), result
        # The topics the run can write, no other: no indentation without a
        # calibrated sensor (before, every topic was offered).
        assert advertised == want, advertised
        summary = [line for line in out.decode().splitlines() if line.startswith("live view:")]
        assert summary and int(summary[0].split()[2]) >= result["/tactile/result"], out.decode()
    finally:
        proc.kill()


def test_python_live_view_waits_for_no_one(pipeline, palpation_frames):
    with pytest.raises(ValueError, match=r"live view at 127.0.0.1:99999: the port is not a number"):
        tactile.LiveView("127.0.0.1:99999")
    with tactile.LiveView("127.0.0.1:0") as view:
        assert view.port > 0 and not view.watched
        assert view.url == f"ws://127.0.0.1:{view.port}"
        # No viewer comes: the wait ends when asked, without one.
        t0 = time.monotonic()
        assert view.wait_for_viewer(0.3) is False
        assert 0.25 <= time.monotonic() - t0 < 5
        with pytest.raises(ValueError, match="seconds must be a finite number"):
            view.wait_for_viewer(float("nan"))
        res = pipeline.process(palpation_frames[3])
        # Nobody subscribed: nothing is encoded or queued.
        assert view.publish(res, palpation_frames[3]) is False
        assert (view.sent, view.dropped) == (0, 0)


def test_hostile_viewers_leave_the_live_view_serving(pipeline, palpation_frames):
    """The live view is a WebSocket server any program on the network may
    reach: clients that speak no Foxglove, send garbage, subscribe to
    channels that do not exist, flood it with connections or stall in the
    handshake must not stop the frames, nor keep a well-behaved viewer
    from every topic."""
    pytest.importorskip("websockets")
    import os
    import socket

    import websockets
    from websockets.exceptions import ConnectionClosed, InvalidStatus

    frame = palpation_frames[6]
    res = pipeline.process(frame)
    with tactile.LiveView("127.0.0.1:0") as view:
        url = f"ws://127.0.0.1:{view.port}"
        stop, published = threading.Event(), [0]

        def publish():
            while not stop.is_set():
                view.publish(res, frame, stamp_ns=1_700_000_000_000_000_000 + published[0] * 33_000_000)
                published[0] += 1
                time.sleep(0.01)

        pub = threading.Thread(target=publish)
        pub.start()

        async def hostile() -> list[str]:
            said: list[str] = []
            with pytest.raises(InvalidStatus):
                await websockets.connect(url)  # no Foxglove subprotocol
            # A viewer offering only the subprotocol's old name is refused at
            # the handshake (docs/robots.md says which viewers connect); one
            # offering both names, as Lichtblick does since it added the new
            # one, is served.
            with pytest.raises(InvalidStatus):
                await websockets.connect(url, subprotocols=["foxglove.websocket.v1"])
            async with websockets.connect(url, subprotocols=["foxglove.websocket.v1", "foxglove.sdk.v1"]) as both:
                assert both.subprotocol == "foxglove.sdk.v1"
                assert json.loads(await asyncio.wait_for(both.recv(), 5))["op"] == "serverInfo"
            async with websockets.connect(url, subprotocols=["foxglove.sdk.v1"], max_size=None) as ws:
                for m in ["{{{", "null", '{"op": 5}', '{"op": "callService"}',
                          json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": 99999}]}),
                          json.dumps({"op": "unsubscribe", "subscriptionIds": [99999999999]}),
                          json.dumps({"op": "advertise", "channels": [{"id": 1, "topic": "/x", "encoding": "json",
                                                                       "schemaName": "a"}]}),
                          os.urandom(1000), b"\x01", b"\x02\xff\xff\xff\xff", b"\x01" + bytes(8 << 20)]:
                    await ws.send(m)
                try:
                    while True:
                        m = await asyncio.wait_for(ws.recv(), 1.0)
                        if isinstance(m, str) and json.loads(m).get("op") == "status":
                            said.append(json.loads(m)["message"])
                except (asyncio.TimeoutError, ConnectionClosed):
                    pass
            idle = [await websockets.connect(url, subprotocols=["foxglove.sdk.v1"]) for _ in range(50)]
            for c in idle:
                await c.close()
            return said

        try:
            said = asyncio.run(hostile())
            raw = socket.create_connection(("127.0.0.1", view.port))
            raw.sendall(os.urandom(5000))
            raw.close()
            stalled = socket.create_connection(("127.0.0.1", view.port))
            stalled.sendall(b"GET / HTTP/1.1\r\nHost: x\r\n")  # a handshake never finished
            before = published[0]
            started = threading.Event()
            want = {"/tactile/image", "/tactile/result", "/tactile/tendon_mask", "/tactile/depth"}
            seen = asyncio.run(_watch(view.port, started, want, timeout=20))
            stalled.close()
        finally:
            stop.set()
            pub.join()
        # The server told the bad client what was wrong, and kept serving.
        assert any("Invalid message" in m for m in said), said
        assert want <= set(seen), seen
        assert published[0] > before
        assert view.sent > 0


def test_paper_a_estimates_as_mcap_match_the_csv(tactile_bin, root, tmp_path):
    import csv

    est_csv, est_mcap = tmp_path / "est.csv", tmp_path / "est.mcap"
    for out in (est_csv, est_mcap):
        r = subprocess.run([str(tactile_bin), "perceive", "--encoder", "models/cae-synth", "--data",
                            "samples/virtual-tactip", "--out", str(out), "--show", "0"],
                           capture_output=True, text=True, cwd=root)
        assert r.returncode == 0, r.stderr
    rows = list(csv.DictReader(est_csv.open()))
    msgs = [m.ros_msg for m in read_ros2_messages(str(est_mcap))]
    assert len(msgs) == len(rows) == 14
    stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in msgs]
    assert stamps == sorted(set(stamps))
    for m, row in zip(msgs, rows):
        assert m.frame == row["file"]
        assert dict(zip(m.class_names, m.classes)) == {"shape": row["shape"]}
        for name, value in zip(m.names, m.values):
            assert value == pytest.approx(float(row[name]), abs=1e-4), name


def test_a_tactip_bag_gives_the_folders_estimates_stamped_like_its_frames(root, tmp_path, shared_real):
    """A TacTip recorded as `ros2 bag record` would (mono8 Images, written by
    `rosbags`): `tactile.predict` on the bag gives each frame the estimates
    of the same PNG frames in a folder, with the message's stamp, and its
    MCAP output (read by `mcap-ros2-support`) stamps each estimate so."""
    src = shared_real / "tactip331-surface" / "frames"
    if not src.is_dir():
        pytest.skip("the real TacTip surface set is in ../shared/real")
    folder = tmp_path / "frames"
    folder.mkdir()
    pngs = [src / f"val_image_{i}.png" for i in (1, 2, 3, 4, 5, 6)]
    for f in pngs:
        shutil.copy(f, folder / f.name)
    ts = get_typestore(Stores.ROS2_HUMBLE)
    Image = ts.types["sensor_msgs/msg/Image"]
    Header = ts.types["std_msgs/msg/Header"]
    Time = ts.types["builtin_interfaces/msg/Time"]
    bag_dir = tmp_path / "bag"
    with RosbagsWriter(bag_dir, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection("/tactip/image_raw", Image.__msgtype__, typestore=ts)
        for i, f in enumerate(pngs):
            grey = tactile.read_grey(f)
            t = stamp(i)
            h = Header(stamp=Time(sec=t // 10**9, nanosec=t % 10**9), frame_id="tactip")
            msg = Image(header=h, height=grey.shape[0], width=grey.shape[1], encoding="mono8",
                        is_bigendian=0, step=grey.shape[1], data=grey.reshape(-1))
            w.write(conn, t, ts.serialize_cdr(msg, Image.__msgtype__))
    bag = next(bag_dir.glob("*.mcap"))
    model = root / "models" / "pose-surface"
    want = tactile.predict(model, folder)
    out = tmp_path / "estimates.mcap"
    got = tactile.predict(model, bag, out)
    assert got["file"] == [f"{i:06}" for i in range(6)]
    assert list(got["stamp_ns"]) == [stamp(i) for i in range(6)]
    targets = [k for k in want if k not in ("file", "ms_per_frame")]
    for k in targets:
        assert np.allclose(got[k], want[k], atol=1e-9), k
    msgs = [m.ros_msg for m in read_ros2_messages(str(out))]
    assert [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in msgs] == [stamp(i) for i in range(6)]
    for i, m in enumerate(msgs):
        assert m.frame == f"{i:06}"
        for name, value in zip(m.names, m.values):
            assert value == pytest.approx(want[name][i], abs=1e-9), name


def test_a_calibrated_sensor_writes_its_indentation(tactile_bin, root, tmp_path, shared_real):
    """With a calibrated sensor (models/gelsight-r15) on real ball presses,
    /tactile/indentation holds each frame's indentation in mm, its peak the
    record's."""
    frames = shared_real / "gelsight-ball" / "frames"
    if not frames.is_dir():
        pytest.skip("the real GelSight ball presses are in ../shared/real")
    out = tmp_path / "presses.mcap"
    records = run_records(tactile_bin, root, tmp_path, "--models", "models/gelsight-r15", "--data", str(frames),
                          "--limit", "3")
    r = subprocess.run([str(tactile_bin), "run", "--models", "models/gelsight-r15", "--data", str(frames),
                        "--limit", "3", "--out", str(out)], capture_output=True, text=True, cwd=root)
    assert r.returncode == 0, r.stderr
    got = read_back(out)
    assert len(got["/tactile/indentation"]) == 3
    for m, rec in zip(got["/tactile/indentation"], records):
        img = m.ros_msg
        d = np.frombuffer(bytes(img.data), "<f4").reshape(img.height, img.width)
        assert img.encoding == "32FC1"
        assert float(d.max()) == pytest.approx(rec["indentation_peak_mm"], rel=1e-4)
    for m, rec in zip(got["/tactile/result"], records):
        assert m.ros_msg.indentation_peak_mm == pytest.approx(rec["indentation_peak_mm"], rel=1e-6)
        assert not m.ros_msg.tendon


def test_a_write_that_fails_part_way_is_an_oserror_and_leaves_nothing(root, pipeline, palpation_frames, tmp_path):
    """A full disk or a quota (here a 2 KiB file-size limit, its signal
    ignored, so each write past it fails as a full disk's does): the
    system's reason as an ``OSError`` naming the file, from ``McapWriter``
    and ``tactile.run`` alike, and no file left. Before, ``tactile.run``
    raised a ``ValueError`` whose message hid the reason ("I/O error from
    writing, or reading a compression stream")."""
    import resource
    import signal

    out = tmp_path / "out"
    out.mkdir()
    result = pipeline.process(palpation_frames[5])
    old_limit = resource.getrlimit(resource.RLIMIT_FSIZE)
    old_handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (2048, old_limit[1]))
    try:
        with pytest.raises(OSError, match=r"out\.mcap: File too large \(os error 27\)"):
            with tactile.McapWriter(out / "out.mcap") as w:
                for _ in range(50):
                    w.write(result, palpation_frames[5])
        with pytest.raises(OSError, match=r"run\.mcap: File too large \(os error 27\)"):
            tactile.run(root / "samples" / "palpation", models=root / "models", out=out / "run.mcap", with_frames=True)
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, old_limit)
        signal.signal(signal.SIGXFSZ, old_handler)
    assert list(out.iterdir()) == []
