"""Several processes: frames, results and datasets pickle whole and cross to
worker processes; what holds loaded models or an open stream says what to
make in each worker instead."""

from __future__ import annotations

import copy
import multiprocessing
import os
import pickle
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import tactile

# A worker process's pipeline, made once by its initializer.
_WORKER: tactile.Pipeline | None = None


def _worker_init(models: str) -> None:
    global _WORKER
    _WORKER = tactile.Pipeline(models, threads=1)


def _worker_process(frame: np.ndarray) -> tactile.FrameResult:
    assert _WORKER is not None
    return _WORKER.process(frame)


def decision(r: tactile.FrameResult) -> dict:
    """A result's record without its timings."""
    return {k: v for k, v in r.to_dict().items() if not k.startswith("ms_")}


def assert_same(a: tactile.FrameResult, b: tactile.FrameResult) -> None:
    assert a.to_dict() == b.to_dict()
    assert repr(a) == repr(b)
    assert a.mask.dtype == b.mask.dtype and np.array_equal(a.mask, b.mask)
    for x, y in [(a.depth_m, b.depth_m), (a.indentation_m, b.indentation_m)]:
        assert (x is None) == (y is None)
        if x is not None:
            assert x.dtype == y.dtype == np.float32 and np.array_equal(x, y)


def test_results_frames_and_datasets_pickle_whole(root, pipeline, palpation_frames, shared_real, tmp_path):
    pipeline.reset()
    results = [pipeline.process(f) for f in palpation_frames]
    assert 0 < sum(r.tendon for r in results) < len(results)
    for r in results:
        assert_same(r, pickle.loads(pickle.dumps(r)))
        assert_same(r, copy.deepcopy(r))
        assert_same(r, copy.copy(r))
    # A restored result writes the same messages as the one it was pickled
    # from: its mask and depth travel with it.
    restored = [pickle.loads(pickle.dumps(r)) for r in results]
    for name, rs in [("made.mcap", results), ("restored.mcap", restored)]:
        with tactile.McapWriter(tmp_path / name) as w:
            for i, r in enumerate(rs):
                w.write(r, stamp_ns=1_700_000_000_000_000_000 + i)
    assert (tmp_path / "made.mcap").read_bytes() == (tmp_path / "restored.mcap").read_bytes()

    # A calibrated sensor's indentation travels too.
    press = tactile.read_rgb(shared_real / "gelsight-ball" / "frames" / "press_01.png")
    sensor = tactile.Pipeline(root / "models" / "gelsight-r15")
    r = sensor.process(press)
    assert r.indentation_m is not None and r.indentation_peak_mm > 0.5
    assert_same(r, pickle.loads(pickle.dumps(r)))

    # Frames of a source, and a dataset (by its folder, made absolute).
    frames = list(tactile.frames(root / "samples" / "palpation"))
    for f in frames[:3]:
        g = pickle.loads(pickle.dumps(f))
        assert (g.name, g.sequence, g.tendon, g.age_ms, g.stamp_ns) == (f.name, f.sequence, f.tendon, f.age_ms, f.stamp_ns)
        assert np.array_equal(g.image, f.image) and g.image.dtype == np.uint8
    cwd = os.getcwd()
    try:
        os.chdir(root)
        ds = tactile.Dataset("samples/virtual-tactip")
        d2 = pickle.loads(pickle.dumps(ds))
    finally:
        os.chdir(cwd)
    assert d2.path == root / "samples" / "virtual-tactip" and len(d2) == len(ds)
    assert np.array_equal(d2.frame(0), ds.frame(0))


def test_what_holds_models_or_a_stream_is_refused_saying_what_to_make_in_a_worker(root, pipeline, tmp_path):
    holders = [
        (pipeline, "Pipeline"),
        (tactile.TactipEncoder(root / "models" / "cae-synth"), "TactipEncoder"),
        (tactile.PoseEstimator(root / "models" / "pose-edge"), "PoseEstimator"),
        (tactile.Reconstructor(root / "models" / "gelsight-r15"), "Reconstructor"),
    ]
    for obj, name in holders:
        for how in (pickle.dumps, copy.copy, copy.deepcopy):
            with pytest.raises(TypeError, match=rf"^tactile\.{name} cannot be pickled: it holds loaded models.*make one in each worker .*initializer: tactile\.{name}\("):
                how(obj)
    src = tactile.frames(root / "samples" / "palpation")
    with pytest.raises(TypeError, match=r"^tactile\.FrameSource cannot be pickled: it is an open stream .*Send its frames"):
        pickle.dumps(src)
    with tactile.McapWriter(tmp_path / "w.mcap") as w, pytest.raises(TypeError, match=r"^tactile\.McapWriter cannot be pickled"):
        pickle.dumps(w)


def test_a_pickled_result_that_does_not_fit_is_refused(pipeline, palpation_frames):
    pipeline.reset()
    r = next(r for r in map(pipeline.process, palpation_frames) if r.tendon)
    restore, (version, state) = r.__reduce__()
    assert restore is tactile._tactile._frame_result
    with pytest.raises(ValueError, match=r"^a FrameResult pickled by tactile 0\.0\.1, read by tactile \S+: pickle and unpickle results with one version of tactile$"):
        restore("tactile 0.0.1", state)
    # What a pickle holds is quoted with its terminal controls escaped.
    with pytest.raises(ValueError, match=r"^a FrameResult pickled by tactile \\x1b\[2J\\x07, read by") as told:
        restore("tactile \x1b[2J\x07", state)
    assert "\x1b" not in str(told.value) and "\x07" not in str(told.value)
    with pytest.raises(ValueError, match=r"^a pickled FrameResult that cannot be read: "):
        restore(version, state[: len(state) // 2])
    # The frame's size (MessagePack's [320, 180] last) made 100,000 wide: a
    # mask of that size is never allocated.
    tail = bytes([0x92, 0xCD, 0x01, 0x40, 0xCC, 0xB4])
    assert state.endswith(tail)
    wide = state[: -len(tail)] + bytes([0x92, 0xCE, 0x00, 0x01, 0x86, 0xA0, 0xCC, 0xB4])
    with pytest.raises(ValueError, match=r"frame views for a 100000x180 frame: each side must be 1 to 7680"):
        restore(version, wide)
    assert_same(r, restore(version, state))


def test_worker_processes_give_the_results_of_one_process(root, pipeline, palpation_frames):
    """The pattern docs/python.md gives: a pipeline per worker, made by the
    pool's initializer; frames go out and results come back pickled."""
    frames = palpation_frames[:6]
    pipeline.reset()
    here = [pipeline.process(f) for f in frames]
    spawn = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(1, mp_context=spawn, initializer=_worker_init, initargs=(str(root / "models"),)) as pool:
        there = list(pool.map(_worker_process, frames, chunksize=3))
    for a, b in zip(here, there):
        da, db = decision(a), decision(b)
        assert abs(da.pop("score") - db.pop("score")) < 1e-5
        assert da == db
        assert np.array_equal(a.mask, b.mask)


def test_a_pipeline_per_thread_gives_the_results_of_one_thread(root, pipeline, palpation_frames):
    """The threads pattern docs/python.md gives: each thread's own pipeline,
    the frames processed in parallel (the interpreter lock released)."""
    import threading
    from concurrent.futures import ThreadPoolExecutor

    local = threading.local()
    made: list[tactile.Pipeline] = []

    def process(frame):
        if not hasattr(local, "pipe"):
            local.pipe = tactile.Pipeline(root / "models", threads=1)
            made.append(local.pipe)
        return local.pipe.process(frame)

    pipeline.reset()
    here = [pipeline.process(f) for f in palpation_frames]
    with ThreadPoolExecutor(2) as pool:
        there = list(pool.map(process, palpation_frames))
    assert 1 <= len(made) <= 2
    for a, b in zip(here, there):
        da, db = decision(a), decision(b)
        da.pop("frame"), db.pop("frame")  # each pipeline numbers its own frames
        assert abs(da.pop("score") - db.pop("score")) < 1e-5
        assert da == db
        assert np.array_equal(a.mask, b.mask)


def test_tactile_run_on_several_pipelines_writes_the_records_of_one(root, tmp_path):
    def records(path):
        import json

        return [
            {k: v for k, v in json.loads(line).items() if not k.startswith("ms_") and k != "latency_ms"}
            for line in path.read_text().splitlines()
        ]

    runs = {}
    for n in (1, 2):
        out = tmp_path / f"r{n}.jsonl"
        summary = tactile.run(root / "samples" / "palpation", models=root / "models", pipelines=n, out=out)
        assert summary["pipelines"] == n and summary["frames"] == 12
        runs[n] = records(out)
    assert runs[1] == runs[2]
    out = tmp_path / "refused.jsonl"
    with pytest.raises(ValueError, match=r"^pipelines 2 with a hysteresis: "):
        tactile.run(root / "samples" / "palpation", models=root / "models", pipelines=2,
                    hysteresis=(0.6, 0.3), out=out)
    assert not out.exists()
