"""`tactile.frames`: a video file made by FFmpeg, a folder and a dataset give
the frames `tactile run` reads, and the pipeline's decisions on them."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import tactile


def test_folder_frames_are_the_files(root, palpation_frames):
    src = tactile.frames(root / "samples" / "palpation")
    assert src.kind == "folder"
    got = list(src)
    assert [f.name for f in got] == [f"{i:06d}.png" for i in range(12)]
    for f, expected in zip(got, palpation_frames):
        assert f.image.dtype == np.uint8 and f.image.shape == (180, 320, 3)
        assert np.array_equal(f.image, expected)
        assert f.age_ms is None and f.tendon is None


def test_a_folder_numbered_without_zeros_comes_in_time(root, tmp_path, palpation_frames):
    # frame_10.png after frame_9.png, not after frame_1.png; hidden files
    # (macOS's ._ copies, not pictures) are not read.
    for i in range(12):
        shutil.copy(root / "samples" / "palpation" / f"{i:06d}.png", tmp_path / f"frame_{i}.png")
    (tmp_path / "._frame_3.png").write_bytes(b"\0\x05\x16\x07resource fork")
    # What was not read is said, as the command line says it.
    with pytest.warns(UserWarning, match=r"1 hidden file\(s\).*were not read: \._frame_3\.png"):
        got = list(tactile.frames(tmp_path))
    assert [f.name for f in got] == [f"frame_{i}.png" for i in range(12)]
    assert all(np.array_equal(f.image, e) for f, e in zip(got, palpation_frames))


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="FFmpeg is installed by scripts/test.sh")
def test_a_folder_of_bmp_tiff_and_ppm_frames_reads_as_the_png_folder(root, tmp_path, palpation_frames):
    # Lab cameras' tools often save BMP or TIFF; OpenCV's imread
    # reads them, and so does every folder here (before: "no PNG or JPEG
    # frames"). One is named .png, and is read by its bytes.
    names = []
    for i in range(12):
        ext, codec = [("bmp", "bmp"), ("tiff", "tiff"), ("ppm", "ppm")][i % 3]
        name = f"{i:06d}.{ext}" if i != 4 else f"{i:06d}.png"
        subprocess.run(
            ["ffmpeg", "-nostdin", "-loglevel", "error", "-i",
             str(root / "samples" / "palpation" / f"{i:06d}.png"),
             "-c:v", codec, "-pix_fmt", "rgb24", "-f", "image2", str(tmp_path / name)],
            check=True,
        )
        names.append(name)
    got = list(tactile.frames(tmp_path))
    assert [f.name for f in got] == names
    assert all(np.array_equal(f.image, e) for f, e in zip(got, palpation_frames))
    # A JPEG of a coding that is not read says which (before: "Number of
    # components cannot be zero").
    lossless = tmp_path / "lossless" / "000000.jpg"
    lossless.parent.mkdir()
    subprocess.run(
        ["ffmpeg", "-nostdin", "-loglevel", "error", "-i",
         str(root / "samples" / "palpation" / "000000.png"),
         "-c:v", "ljpeg", "-pix_fmt", "bgr24", "-strict", "-1", str(lossless)],
        check=True,
    )
    with pytest.raises(ValueError, match=r"000000\.jpg: a lossless JPEG \(SOF3\), a JPEG coding that is not read"):
        list(tactile.frames(lossless.parent))


def _tiff(pages: list[np.ndarray]) -> bytes:
    """Uncompressed RGB pages as one little-endian TIFF (TIFF 6.0, a
    baseline RGB image per page), as ImageJ saves a stack."""
    import struct

    out = bytearray(b"II*\0" + struct.pack("<I", 0))
    link = 4  # where the offset of the next page's directory goes
    for page in pages:
        h, w, _ = page.shape
        pixels = len(out)
        out += page.tobytes()
        bits = len(out)
        out += struct.pack("<3H", 8, 8, 8)
        entries = [(256, 4, 1, w), (257, 4, 1, h), (258, 3, 3, bits), (259, 3, 1, 1),
                   (262, 3, 1, 2), (273, 4, 1, pixels), (277, 3, 1, 3), (278, 4, 1, h),
                   (279, 4, 1, w * h * 3), (284, 3, 1, 1)]
        if len(out) % 2:
            out += b"\0"
        struct.pack_into("<I", out, link, len(out))
        out += struct.pack("<H", len(entries))
        for tag, kind, count, value in entries:
            packed = struct.pack("<H", value) + b"\0\0" if kind == 3 and count == 1 else struct.pack("<I", value)
            out += struct.pack("<HHI", tag, kind, count) + packed
        link = len(out)
        out += struct.pack("<I", 0)
    return bytes(out)


def test_a_tiff_stack_is_read_page_by_page_alone_and_refused_as_one_frame(tmp_path, palpation_frames):
    # A TIFF of several pages holds several frames. Given alone it is read
    # page by page, as a video is; read as one frame (in a folder, or by
    # read_rgb: its first page, as OpenCV's imread and PIL read it), the
    # rest would be lost without a word, so it is refused.
    one = tmp_path / "one" / "000000.tif"
    one.parent.mkdir()
    one.write_bytes(_tiff(palpation_frames[:1]))
    got = list(tactile.frames(one.parent))
    assert len(got) == 1 and np.array_equal(got[0].image, palpation_frames[0])
    stack = tmp_path / "stack" / "000000.tif"
    stack.parent.mkdir()
    stack.write_bytes(_tiff(palpation_frames[:3]))
    with pytest.raises(ValueError, match=r"000000\.tif: a TIFF of 3 pages \(a stack of frames in one file\)"):
        list(tactile.frames(stack.parent))
    with pytest.raises(ValueError, match=r"a TIFF of 3 pages"):
        tactile.read_rgb(stack)
    src = tactile.frames(stack)
    assert src.kind == "stack" and src.size == (320, 180)
    got = list(src)
    assert [f.name for f in got] == ["000000", "000001", "000002"]
    for f, expected in zip(got, palpation_frames[:3]):
        assert np.array_equal(f.image, expected)


def lossless_palpation_clip(root: Path, out: Path) -> Path:
    """The sample palpation frames as a lossless RGB H.264 video at `out`:
    decoded, the same pixels."""
    subprocess.run(
        ["ffmpeg", "-nostdin", "-loglevel", "error", "-framerate", "30",
         "-i", str(root / "samples" / "palpation" / "%06d.png"),
         "-c:v", "libx264rgb", "-qp", "0", str(out)],
        check=True,
    )
    return out


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="FFmpeg is installed by scripts/test.sh")
def test_lossless_video_gives_the_pipeline_the_same_frames(root, tmp_path, pipeline, palpation_frames):
    video = lossless_palpation_clip(root, tmp_path / "palpation.mp4")
    src = tactile.frames(video)
    assert src.kind == "video" and src.size == (320, 180)
    got = list(src)
    assert len(got) == 12 and got[5].name == "000005"
    for f, expected in zip(got, palpation_frames):
        assert np.array_equal(f.image, expected)
    pipeline.reset()
    decisions = [pipeline.process(f.image).tendon for f in got]
    assert decisions == [pipeline.process(x).tendon for x in palpation_frames]


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="FFmpeg is installed by scripts/test.sh")
def test_a_video_cut_short_gives_its_frames_with_a_warning(root, tmp_path):
    # 36 frames of Motion JPEG in Matroska, which declares its length up
    # front; a copy stopped half-way decodes to fewer, and says so.
    whole = tmp_path / "whole.mkv"
    subprocess.run(
        ["ffmpeg", "-nostdin", "-loglevel", "error", "-stream_loop", "2", "-framerate", "30",
         "-i", str(root / "samples" / "palpation" / "%06d.png"),
         "-c:v", "mjpeg", "-q:v", "2", str(whole)],
        check=True,
    )
    assert len(list(tactile.frames(whole))) == 36
    cut = tmp_path / "cut.mkv"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size // 2])
    with pytest.warns(UserWarning, match=r"cut\.mkv: its container says 1\.20 s .* the file may be cut short"):
        got = list(tactile.frames(cut))
    assert 5 < len(got) < 32


def test_limit_and_bad_sources(root, tmp_path):
    assert len(list(tactile.frames(root / "samples" / "palpation", limit=3))) == 3
    with pytest.raises(ValueError, match="limit: must be at least 1, got 0"):
        tactile.frames(root / "samples" / "palpation", limit=0)
    with pytest.raises(FileNotFoundError, match="missing"):
        tactile.frames(tmp_path / "missing")
    bad = tmp_path / "clip.mp4"
    bad.write_bytes(b"not a video")
    with pytest.raises(ValueError, match="clip.mp4"):
        tactile.frames(bad)
    with pytest.raises(ValueError, match="stdin_size"):
        tactile.frames()
    # "-" (the shell's name for standard input) says how it is read; a URL
    # of a protocol that is no stream's says what is read.
    with pytest.raises(ValueError, match=r"-: no file of that name; .*tactile.frames\(stdin_size=\(w, h\)\)"):
        tactile.frames("-")
    with pytest.raises(ValueError, match=r"ftp://lab/video.mkv: ftp:// URLs are not read: a stream is read from rtsp://"):
        tactile.frames("ftp://lab/video.mkv")
    # A live queue for a recorded folder would be ignored: refused.
    with pytest.raises(ValueError, match="live_queue 8: .* and this folder source is recorded"):
        tactile.frames(root / "samples" / "palpation", live_queue=8)
    # A topic for raw frames on stdin would be ignored: refused.
    with pytest.raises(ValueError, match="topic picks a ROS 2 bag's images, and raw frames on stdin"):
        tactile.frames(stdin_size=(320, 180), topic="/cam")


def test_a_folder_bounds_its_reads(root, tmp_path):
    folder = tmp_path / "frames"
    folder.mkdir()
    first = root / "samples" / "palpation" / "000000.png"
    shutil.copy(first, folder / "000000.png")
    (folder / "000001.png").symlink_to("000000.png")
    assert [f.name for f in tactile.frames(folder)] == ["000000.png", "000001.png"]
    (folder / "000002.png").symlink_to(first)
    with pytest.raises(ValueError, match=r"000002\.png: is a symbolic link that leaves the folder"):
        tactile.frames(folder)


def test_stdin_cut_inside_a_frame_keeps_the_whole_frames(tmp_path, palpation_frames):
    # A piped camera killed mid-write: the whole frames before the cut come,
    # then a warning says what was dropped; less than a frame is an error.
    import sys
    script = (
        "import warnings, tactile\n"
        "with warnings.catch_warnings(record=True) as w:\n"
        "    warnings.simplefilter('always')\n"
        "    try:\n"
        "        got = [f.image.sum() for f in tactile.frames(stdin_size=(320, 180), live_queue=64)]\n"
        "        print(len(got), *got)\n"
        "    except ValueError as e:\n"
        "        print('error', e)\n"
        "    print('warnings', *[str(x.message) for x in w], sep='|')\n"
    )
    three = b"".join(f.tobytes() for f in palpation_frames[:3])
    cut = palpation_frames[3].tobytes()[:1000]
    out = subprocess.run([sys.executable, "-c", script], input=three + cut, capture_output=True, check=True).stdout
    lines = out.decode().splitlines()
    assert lines[0].split() == ["3"] + [str(int(f.sum())) for f in palpation_frames[:3]], lines
    assert "stdin ended inside a frame: 1000 of 172800 bytes" in lines[1] and "after 3 whole frames" in lines[1], lines
    out = subprocess.run([sys.executable, "-c", script], input=cut, capture_output=True, check=True).stdout
    assert "error" in out.decode() and "before any whole frame" in out.decode(), out


def test_ctrl_c_stops_a_wait_for_the_next_live_frame(palpation_frames):
    """A loop over a live source (a camera, stdin) whose next frame does not
    come (a stalled camera, a writer that paused) stops at Ctrl-C with
    KeyboardInterrupt, with the stream still open. Before, the wait ignored
    Ctrl-C for as long as no frame came."""
    import signal
    import sys
    import time
    script = (
        "import signal, tactile\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "for f in tactile.frames(stdin_size=(320, 180)):\n"
        "    print('frame', flush=True)\n"
    )
    p = subprocess.Popen([sys.executable, "-c", script], stdin=subprocess.PIPE,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        p.stdin.write(palpation_frames[0].tobytes())
        p.stdin.flush()
        assert p.stdout.readline() == b"frame\n"
        time.sleep(0.5)
        t0 = time.time()
        p.send_signal(signal.SIGINT)
        p.wait(timeout=10)
        assert time.time() - t0 < 3
        err = p.stderr.read().decode()
        assert p.returncode != 0 and "KeyboardInterrupt" in err, err
    finally:
        if p.poll() is None:
            p.kill()
        p.stdin.close()


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="FFmpeg is installed by scripts/test.sh")
def test_a_streams_url_gives_its_frames(root, tmp_path, palpation_frames):
    # A file served over HTTP (a length: every frame, as the file's) and a
    # camera's MJPEG stream (no length: live). Before, a URL was refused.
    import http.server
    import threading

    clip = lossless_palpation_clip(root, tmp_path / "clip.mkv")
    live = subprocess.run(
        ["ffmpeg", "-nostdin", "-loglevel", "error", "-i", str(clip),
         "-c:v", "mjpeg", "-q:v", "2", "-f", "mpjpeg", "-"],
        check=True, capture_output=True,
    ).stdout

    class Handler(http.server.SimpleHTTPRequestHandler):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, directory=str(tmp_path), **kwargs)

        def do_GET(self):
            if self.path != "/live.mjpg":
                return super().do_GET()
            self.send_response(200)
            self.send_header("Content-Type", "multipart/x-mixed-replace;boundary=ffmpeg")
            self.end_headers()
            self.wfile.write(live)

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    base = f"http://127.0.0.1:{server.server_address[1]}"
    try:
        src = tactile.frames(f"{base}/clip.mkv")
        assert src.kind == "video" and src.size == (320, 180)
        got = list(src)
        assert len(got) == len(palpation_frames)
        for f, expected in zip(got, palpation_frames):
            assert np.array_equal(f.image, expected)

        src = tactile.frames(f"{base}/live.mjpg")
        assert src.kind == "stream"
        got = list(src)
        assert 1 <= len(got) <= len(palpation_frames)
        assert all(f.age_ms is not None for f in got)

        with pytest.raises(ValueError, match=r"http://robot:\*\*\*@127\.0\.0\.1:\d+/none\.mkv: cannot read the stream") as e:
            tactile.frames(f"http://robot:s3cret@{base[len('http://'):]}/none.mkv")
        assert "s3cret" not in str(e.value)

        # Through pathlib (argparse's type=Path) a URL loses a slash of its
        # `//`: said so, not "does not exist".
        mangled = Path(f"http://robot:s3cret@{base[len('http://'):]}/clip.mkv")
        assert str(mangled).startswith("http:/robot")
        with pytest.raises(ValueError, match=r"http:/robot:\*\*\*@.*a slash of its `http://` was lost .*give the URL as a str") as e:
            tactile.frames(mangled)
        assert "s3cret" not in str(e.value)
    finally:
        server.shutdown()
