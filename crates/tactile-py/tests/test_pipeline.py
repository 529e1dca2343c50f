"""The palpation pipeline from Python: the same answers as `tactile run`,
frame-resolution outputs, bad input, threads and memory."""

from __future__ import annotations

import json
import shutil
import threading
from pathlib import Path

import numpy as np
import pytest

import tactile
from conftest import run_cli

# Python and the command line run the same code on the same pixels; only
# float formatting through JSON can differ.
DIRECTION_TOL_DEG = 1e-9
DEPTH_TOL_MM = 1e-5
SCORE_TOL = 1e-6


def test_process_matches_tactile_run(tactile_bin, root, tmp_path, pipeline, palpation_frames):
    out = tmp_path / "records.jsonl"
    run_cli(tactile_bin, "run", "--data", "samples/palpation", "--models", "models",
            "--runtime", "onnx", "--out", str(out))
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert len(records) == len(palpation_frames)
    pipeline.reset()
    tendon_frames = 0
    for rec, frame in zip(records, palpation_frames):
        r = pipeline.process(frame)
        assert r.tendon == rec["tendon"]
        assert abs(r.score - rec["score"]) <= SCORE_TOL
        assert r.mask_area_px == rec["mask_area_px"]
        if rec["direction_deg"] is None:
            assert r.direction_deg is None
        else:
            assert abs(r.direction_deg - rec["direction_deg"]) <= DIRECTION_TOL_DEG
        if rec["tendon"]:
            tendon_frames += 1
            lo, mean, hi = r.depth_mm_stats
            assert abs(lo - rec["depth_min_mm"]) <= DEPTH_TOL_MM
            assert abs(mean - rec["depth_mean_mm"]) <= DEPTH_TOL_MM
            assert abs(hi - rec["depth_max_mm"]) <= DEPTH_TOL_MM
        d = r.to_dict()
        for key in ("tendon", "tendon_raw", "mask_area_px", "no_direction"):
            assert d[key] == rec[key]
    assert tendon_frames == 8, "the sample video has 8 tendon frames"


# Keys of a record that time the run rather than say what it found.
TIMING_KEYS = {"latency_ms"}


def _found(record: dict) -> dict:
    return {k: v for k, v in record.items() if not k.startswith("ms_") and k not in TIMING_KEYS}


def test_run_writes_what_tactile_run_writes(tactile_bin, root, tmp_path):
    """`tactile.run` is `tactile run`: the same records, overlays and
    summary counts, and the same refusals before anything is written."""
    cli_out, cli_render = tmp_path / "cli.jsonl", tmp_path / "cli-render"
    stdout = run_cli(tactile_bin, "run", "--data", "samples/palpation", "--models", "models",
                     "--hysteresis", "0.6,0.3", "--out", str(cli_out), "--render", str(cli_render))
    cli_summary = json.loads(stdout.splitlines()[-1])
    py_out, py_render = tmp_path / "py.jsonl", tmp_path / "py-render"
    s = tactile.run(root / "samples/palpation", models=root / "models", hysteresis=(0.6, 0.3),
                    out=py_out, render=py_render)
    cli_records = [json.loads(line) for line in cli_out.read_text().splitlines()]
    py_records = [json.loads(line) for line in py_out.read_text().splitlines()]
    assert len(py_records) == len(cli_records) == s["frames"] == cli_summary["frames"]
    for c, p in zip(cli_records, py_records):
        c, p = _found(c), _found(p)
        assert c.keys() == p.keys()
        for key in c:
            if isinstance(c[key], float):
                assert abs(c[key] - p[key]) <= max(SCORE_TOL, DEPTH_TOL_MM), key
            else:
                assert c[key] == p[key], key
    for key in ("tendon_frames", "gated_out", "decision_changes", "hysteresis", "source"):
        assert s[key] == cli_summary[key], key
    assert s["tendon_frames"] == 8
    assert sorted(x.name for x in py_render.iterdir()) == sorted(x.name for x in cli_render.iterdir())
    assert len(list(py_render.iterdir())) == 8
    assert s["records"] == str(py_out) and s["render"] == str(py_render)
    assert s["mcap"] is None and s["live_sent"] is None

    # ROS 2 messages for an .mcap name.
    m = tactile.run(root / "samples/palpation", models=root / "models", out=tmp_path / "r.mcap",
                    limit=5)
    assert m["mcap"] == str(tmp_path / "r.mcap") and m["mcap_frames"] == 5 == m["frames"]
    assert m["records"] is None and (tmp_path / "r.mcap").stat().st_size > 0

    # Refused before any model loads, nothing written: two outputs in one
    # place, an output over the input, a render folder holding files and
    # bad hysteresis (both checked before the missing models folder), and
    # frames that cannot be read, from their headers.
    cut = tmp_path / "cut"
    cut.mkdir()
    for f in sorted((root / "samples/palpation").glob("*.png"))[:3]:
        shutil.copy(f, cut / f.name)
    (cut / "000003.png").write_bytes(b"")
    (cut / "000004.png").write_text("not a picture")
    before = sorted(p.name for p in tmp_path.iterdir())
    with pytest.raises(ValueError, match=r"000003\.png: cannot read the image header.*; 2 of the 5 frames cannot be read"):
        tactile.run(cut, models=tmp_path / "no-models", out=tmp_path / "never.jsonl")
    with pytest.raises(ValueError, match="two outputs of this run name one place"):
        tactile.run(root / "samples/palpation", models=root / "models",
                    out=tmp_path / "same", render=tmp_path / "same")
    with pytest.raises(ValueError, match="000003.png"):
        tactile.run(root / "samples/palpation", models=root / "models",
                    out=root / "samples/palpation/000003.png")
    with pytest.raises(ValueError, match=r"records\.csv: named as a table, but this writes JSON Lines"):
        tactile.run(root / "samples/palpation", models=root / "models", out=tmp_path / "records.csv")
    with pytest.raises(ValueError, match="cli-render: already holds files"):
        tactile.run(root / "samples/palpation", models=tmp_path / "no-models", render=cli_render)
    with pytest.raises(ValueError, match="hysteresis"):
        tactile.run(root / "samples/palpation", models=tmp_path / "no-models",
                    hysteresis=(0.2, 0.6))
    with pytest.raises(FileNotFoundError, match="no-models"):
        tactile.run(root / "samples/palpation", models=tmp_path / "no-models",
                    out=tmp_path / "never.jsonl")
    with pytest.raises(ValueError, match="threads"):
        tactile.run(root / "samples/palpation", threads=0)
    with pytest.raises(ValueError, match="view_wait"):
        tactile.run(root / "samples/palpation", view="127.0.0.1:0", view_wait=float("nan"))
    # Options that would do nothing in this run: refused, not ignored.
    with pytest.raises(ValueError, match="view_wait: waits for a viewer of the live view, and this run serves none"):
        tactile.run(root / "samples/palpation", view_wait=5.0)
    with pytest.raises(ValueError, match="with_frames: the input frames go to an .mcap out or to the live view"):
        tactile.run(root / "samples/palpation", out=tmp_path / "never.jsonl", with_frames=True)
    with pytest.raises(ValueError, match="stdin_size"):
        tactile.run()
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    assert len(list(cli_render.iterdir())) == 8

    # A frame cut short behind a whole header is found when decoded: it is
    # skipped with a warning naming it, and the other frames' records kept.
    whole = (cut / "000002.png").read_bytes()
    (cut / "000003.png").write_bytes(whole[: len(whole) // 2])
    (cut / "000004.png").unlink()
    with pytest.warns(UserWarning, match=r"1 of the 4 frames could not be decoded.*000003\.png: cannot decode") as told:
        s = tactile.run(cut, models=root / "models", out=tmp_path / "kept.jsonl")
    assert sum("could not be decoded" in str(w.message) for w in told) == 1
    kept = [json.loads(line)["frame"] for line in (tmp_path / "kept.jsonl").read_text().splitlines()]
    assert kept == ["000000.png", "000001.png", "000002.png"] and s["frames"] == 3
    assert s["undecodable_frames"] == 1 and s["missing_frames"] == 0


def _segmenter_side(root) -> int:
    cfg = json.loads((root / "models/segmenter/segmenter.json").read_text())
    return int(cfg["model"]["side"])


def test_outputs_at_frame_resolution(root, pipeline, palpation_frames):
    pipeline.reset()
    r = pipeline.process(palpation_frames[5])
    assert r.tendon
    h, w = palpation_frames[5].shape[:2]
    assert r.mask.shape == (h, w) and r.mask.dtype == np.bool_
    assert r.depth_m.shape == (h, w) and r.depth_m.dtype == np.float32
    # The depth map upsampled to the frame keeps the window's statistics.
    lo, mean, hi = r.depth_mm_stats
    centre = r.depth_m[h // 2 - 10 : h // 2 + 10, w // 2 - 10 : w // 2 + 10] * 1000
    assert lo - 0.05 <= centre.min() and centre.max() <= hi + 0.05
    assert 5.0 < mean < 30.0
    # The mask at frame resolution covers the window's tendon area, scaled.
    side = _segmenter_side(root)
    scale = np.ceil(side * np.sqrt(2)) / h
    expected = r.mask_area_px / scale**2
    assert abs(r.mask.sum() - expected) / expected < 0.05
    assert set(r.ms) == {"prepare", "detect", "segment", "depth", "total"}


def test_gated_out_frame_has_no_depth(pipeline, palpation_frames):
    r = pipeline.process(palpation_frames[0])
    assert not r.tendon
    assert r.depth_m is None and r.depth_mm_stats is None and r.direction_deg is None
    assert not r.mask.any()
    assert set(r.ms) == {"prepare", "detect", "total"}


def test_non_contiguous_and_batched_input(pipeline, palpation_frames):
    frame = palpation_frames[4]
    bgr = np.ascontiguousarray(frame[:, :, ::-1])
    rgb_view = bgr[:, :, ::-1]  # a view OpenCV users make; not contiguous
    assert not rgb_view.flags["C_CONTIGUOUS"]
    a, b = pipeline.process(frame), pipeline.process(rgb_view)
    assert a.score == b.score and a.direction_deg == b.direction_deg
    stack = np.stack(palpation_frames[:4])
    many = pipeline.process_many(stack)
    one = [pipeline.process(f) for f in palpation_frames[:4]]
    assert [m.score for m in many] == [o.score for o in one]
    assert len(pipeline.process_many(iter(palpation_frames[:3]))) == 3
    # One (H, W, 3) frame is one frame, not H rows.
    single = pipeline.process_many(frame)
    assert len(single) == 1 and single[0].score == a.score
    # A frame with an opaque alpha channel is the frame; one with
    # transparent pixels, or grey, is one frame refused as such; a bad
    # frame in a batch is named by its index.
    opaque = pipeline.process_many(np.dstack([frame, np.full(frame.shape[:2], 255, np.uint8)]))
    assert len(opaque) == 1 and opaque[0].score == a.score
    with pytest.raises(ValueError, match=r"^frame: an RGBA frame of shape .* with 1 of its"):
        see_through = np.dstack([frame, np.full(frame.shape[:2], 255, np.uint8)])
        see_through[5, 7, 3] = 0
        pipeline.process_many(see_through)
    with pytest.raises(ValueError, match=r"^frame: .*\(a grey frame"):
        pipeline.process_many(frame[:, :, 0])
    with pytest.raises(ValueError, match=r"^frames\[1\]: .*got shape \(5, 5\)"):
        pipeline.process_many([frame, np.zeros((5, 5), np.uint8)])
    # A batch of channels-first frames (torch's NCHW) names its first frame.
    with pytest.raises(ValueError, match=r"^frames\[0\]: .*\(channels first, .*numpy.transpose"):
        pipeline.process_many(np.stack([frame, frame]).transpose(0, 3, 1, 2))


def test_every_layout_of_a_frame_reads_as_its_c_ordered_copy(root, pipeline, palpation_frames):
    """A frame is its pixels whatever numpy layout holds them: flipped views
    (each axis, OpenCV's BGR reversed to RGB), Fortran order (MATLAB's
    arrays through scipy, a grey frame's `.T`), slices and a broadcast all
    give the detector and the encoder the input of their C-ordered copy.
    Before, a Fortran-ordered frame was read in place as if in C order: its
    columns as rows, without an error."""
    frame = palpation_frames[4]
    views = [frame[::fy, ::fx, ::fc] for fy in (1, -1) for fx in (1, -1) for fc in (1, -1)]
    views += [np.asfortranarray(frame), frame[1:-1, 2:-2], frame[::2, ::3],
              np.broadcast_to(frame[:1], frame.shape)]
    for v in views:
        assert np.array_equal(pipeline.detector_frame(v), pipeline.detector_frame(np.ascontiguousarray(v)))
    fortran = pipeline.process(np.asfortranarray(frame))
    assert fortran.score == pipeline.process(frame).score
    enc = tactile.TactipEncoder(root / "models/cae-synth")
    grey = tactile.Dataset(root / "samples/virtual-tactip").frame(0)
    for v in [grey.T, grey[::-1], grey[:, ::-1], np.asfortranarray(grey)]:
        assert np.array_equal(enc.encode(v), enc.encode(np.ascontiguousarray(v)))


def test_hysteresis_and_reset(root, palpation_frames):
    p = tactile.Pipeline(root / "models", hysteresis=(0.6, 0.3))
    first = [p.process(f).tendon for f in palpation_frames]
    p.reset()
    again = [p.process(f).tendon for f in palpation_frames]
    assert first == again
    assert p.hysteresis == pytest.approx((0.6, 0.3))


@pytest.mark.parametrize(
    "frame, error, words",
    [
        (np.zeros((180, 320, 3), np.float32), TypeError, "float32"),
        (np.zeros((180, 320, 3), np.uint16), TypeError, "uint16"),
        # The conversion each dtype needs, told by its values: a float image
        # of 0 to 1 (skimage, torchvision) cast as it is would be black.
        (np.full((180, 320, 3), 0.5, np.float32), TypeError,
         "its values lie in 0.500..0.500, as a float image of 0 to 1 has: (frame * 255).round().astype(numpy.uint8)"),
        (np.full((180, 320, 3), 200.0), TypeError, "float64 array of shape (180, 320, 3) (its values lie in 200..200: frame.round()"),
        (np.full((180, 320, 3), 4095, np.uint16), TypeError, "its values lie in 4095..4095, past 8 bits: scale the levels"),
        (np.full((180, 320, 3), 9, np.int64), TypeError, "its values lie in 9..9: frame.astype(numpy.uint8))"),
        (np.ones((180, 320, 3), bool), TypeError, "a mask? frames are levels 0-255"),
        (np.linspace(-2.1, 2.6, 180 * 320 * 3, dtype=np.float32).reshape(180, 320, 3), TypeError,
         "its values lie in -2.100..2.600, below 0: a normalised image? undo the normalisation"),
        (np.zeros((180, 320, 3), np.complex64), TypeError, "(convert it to uint8 levels 0-255)"),
        (np.broadcast_to(np.float32(0.5), (100_000, 100_000, 3)), TypeError, "(convert it to uint8 levels 0-255)"),
        (np.zeros((180, 320, 4), np.uint8), ValueError, "an RGBA frame of shape (180, 320, 4) with 57600 of its 57600 pixels not opaque"),
        (np.zeros((180, 320, 2), np.uint8), ValueError, "(180, 320, 2) (a grey frame: repeat it to RGB"),
        (np.zeros((180, 320), np.uint8), ValueError, "(180, 320) (a grey frame: repeat it to RGB"),
        (np.zeros((180, 320, 1), np.uint8), ValueError, "(180, 320, 1) (a grey frame: repeat it to RGB"),
        # Channels first (torchvision's read_image) or a batch, where one
        # frame is read: the shape says how to make it one frame.
        (np.zeros((3, 180, 320), np.uint8), ValueError,
         "(3, 180, 320) (channels first, as a torch tensor has them: numpy.transpose(frame, (1, 2, 0))"),
        (np.zeros((1, 180, 320, 3), np.uint8), ValueError, "(1, 180, 320, 3) (a batch of one frame: pass frame[0])"),
        (np.zeros((5, 180, 320, 3), np.uint8), ValueError, "(a stack of 5 frames: pass one at a time, frames[i])"),
        (np.zeros((2, 3, 180, 320), np.uint8), ValueError, "(a batch of channels-first frames: numpy.transpose(frames[i], (1, 2, 0))"),
        (None, TypeError, "got a NoneType"),
        (np.zeros((0, 320, 3), np.uint8), ValueError, "320x0"),
        (np.zeros((9000, 2, 3), np.uint8), ValueError, "7680"),
        ([[1, 2, 3]], TypeError, "list"),
        ("frame.png", TypeError, "str"),
    ],
)
def test_bad_frames_raise_clear_errors(pipeline, frame, error, words):
    with pytest.raises(error) as e:
        pipeline.process(frame)
    assert words in str(e.value)
    assert "frame" in str(e.value)


def test_bad_construction(root, tmp_path):
    with pytest.raises(FileNotFoundError) as e:
        tactile.Pipeline(tmp_path / "no-models")
    assert "no-models" in str(e.value)
    with pytest.raises(ValueError, match="unknown runtime 'gpu'"):
        tactile.Pipeline(root / "models", "gpu")
    with pytest.raises(ValueError, match="threads"):
        tactile.Pipeline(root / "models", threads=0)
    with pytest.raises(ValueError, match="hysteresis"):
        tactile.Pipeline(root / "models", hysteresis=(0.2, 0.6))
    # A segmenter where the detector should be: the kind is named.
    bad = tmp_path / "models"
    bad.mkdir()
    for name in ("detector", "segmenter", "depth"):
        (bad / name).symlink_to(root / "models" / ("segmenter" if name == "detector" else name))
    with pytest.raises(ValueError) as e:
        tactile.Pipeline(bad)
    assert "detector" in str(e.value)


def test_two_threads_give_the_same_results(root, palpation_frames):
    p = tactile.Pipeline(root / "models")
    expected = [(r.tendon, r.score, r.direction_deg) for r in map(p.process, palpation_frames)]
    results: dict[int, list] = {}
    errors: list[BaseException] = []

    def work(k: int) -> None:
        try:
            got = []
            for _ in range(5):
                got.extend((r.tendon, r.score, r.direction_deg) for r in map(p.process, palpation_frames))
            results[k] = got
        except BaseException as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    for k in range(2):
        assert results[k] == expected * 5


def _rss_mb() -> float:
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    import os

    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def test_memory_does_not_grow(pipeline, palpation_frames):
    frame = palpation_frames[5]
    for _ in range(200):  # warm up allocators and caches
        r = pipeline.process(frame)
        r.mask, r.depth_m
    before = _rss_mb()
    for _ in range(2000):
        r = pipeline.process(frame)
        r.mask, r.depth_m
    grown = _rss_mb() - before
    assert grown < 16, f"resident memory grew by {grown:.1f} MB over 2000 calls"
