"""Frames per second of paper B's pipeline from Python: one pipeline in one
thread, against a pipeline per thread (the interpreter lock is released
while a frame is processed) and a pool of worker processes, each with its
own pipeline.

The frames are a rendered palpation set (every stage runs on its tendon
frames), in memory; the last rows run ``tactile.run`` (``tactile run``) over
the same set written as a dataset, decoding its PNG frames ahead on another
thread, with one pipeline and with several (``pipelines=``). Each way is timed over every frame, in rounds that alternate the
ways so drift hits all alike; the table gives the median round. A pool is
started once (spawned workers import the package and load the models in
its initializer: the start-up row) and then fed the frames in chunks; each
result comes back pickled whole (mask, depth), which the pickling rows
time.

    python crates/tactile-py/bench/processes.py [--models models] [--frames 240] [--rounds 5] [--out FILE]

Prints a Markdown table with the machine, the runtime and its threads.
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import pickle
import platform
import statistics
import tempfile
import threading
import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path

import numpy as np

import tactile
from overhead import cpu_name  # this folder's other bench: the machine named alike

_WORKER: tactile.Pipeline | None = None
_THREAD = threading.local()


def _init(models: str, threads: int) -> None:
    global _WORKER
    _WORKER = tactile.Pipeline(models, threads=threads)


def _process(frame: np.ndarray) -> tactile.FrameResult:
    assert _WORKER is not None
    return _WORKER.process(frame)


def _process_in_thread(frame: np.ndarray, models: str) -> tactile.FrameResult:
    if not hasattr(_THREAD, "pipe"):
        _THREAD.pipe = tactile.Pipeline(models, threads=1)
    return _THREAD.pipe.process(frame)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", default="models")
    ap.add_argument("--frames", type=int, default=240)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--out", help="also write the table to this Markdown file")
    a = ap.parse_args()

    per = 30
    sequences = -(-a.frames // per)
    v = tactile.synth.visuotactile(sequences=sequences, frames_per_sequence=per, seed=11, progress=False)
    scratch = tempfile.TemporaryDirectory()
    dataset = tactile.synth.visuotactile(
        sequences=sequences, frames_per_sequence=per, seed=11, out=Path(scratch.name) / "set", progress=False
    )
    frames = list(v["frames"][: a.frames])
    tendon = int(np.asarray(v["tendon"][: a.frames]).sum())
    h, w = frames[0].shape[:2]

    one = {t: tactile.Pipeline(a.models, threads=t) for t in sorted({1, a.workers})}
    spawn = multiprocessing.get_context("spawn")
    t0 = time.perf_counter()
    pool = ProcessPoolExecutor(a.workers, mp_context=spawn, initializer=_init, initargs=(a.models, 1))
    list(pool.map(_process, frames[: a.workers], chunksize=1))
    start_s = time.perf_counter() - t0

    chunk = max(1, len(frames) // (4 * a.workers))
    threads = ThreadPoolExecutor(a.workers)
    list(threads.map(lambda f: _process_in_thread(f, a.models), frames[: 4 * a.workers]))
    ways = {
        f"one pipeline, {t} onnxruntime thread(s)": (lambda p=p: [p.process(f) for f in frames])
        for t, p in one.items()
    }
    ways[f"one pipeline shared by {a.workers} Python threads"] = lambda: list(
        threads.map(one[1].process, frames)
    )
    ways[f"{a.workers} Python threads, a pipeline each"] = lambda: list(
        threads.map(lambda f: _process_in_thread(f, a.models), frames)
    )
    ways[f"{a.workers} worker processes, a pipeline each"] = lambda: list(pool.map(_process, frames, chunksize=chunk))
    limit = len(frames)
    for n in sorted({1, a.workers, a.workers + 1}):
        ways[f"`tactile.run` over the PNG files, pipelines={n}"] = lambda n=n: tactile.run(
            dataset, models=a.models, pipelines=n, limit=limit
        )
    times: dict[str, list[float]] = {k: [] for k in ways}
    results = {}
    for _ in range(a.rounds):
        for k, run in ways.items():
            t = time.perf_counter()
            results[k] = run()
            spent = time.perf_counter() - t
            if isinstance(results[k], dict):  # the run's own clock: loading the models left out
                spent = results[k]["frames"] / results[k]["fps"]
            times[k].append(spent)
    pool.shutdown()
    threads.shutdown()
    base = next(iter(results.values()))
    for k, rs in results.items():
        if isinstance(rs, dict):  # tactile.run's summary
            assert rs["frames"] == len(frames) and rs["tendon_frames"] == sum(r.tendon for r in base), k
            continue
        assert [r.tendon for r in rs] == [r.tendon for r in base], f"{k}: other decisions"
    scratch.cleanup()

    made = [r for r in base if r.tendon]
    sizes = [len(pickle.dumps(r)) for r in made]
    dump = [statistics.median(_timed(lambda: pickle.dumps(r)) for _ in range(20)) for r in made[:20]]
    load_bytes = [pickle.dumps(r) for r in made[:20]]
    load = [statistics.median(_timed(lambda b=b: pickle.loads(b)) for _ in range(20)) for b in load_bytes]

    head = (
        f"Machine: {cpu_name()}, {os.cpu_count()} logical CPUs; runtime onnx; {len(frames)} rendered "
        f"{w}x{h} frames ({tendon} with a tendon), median of {a.rounds} rounds; "
        f"tactile {tactile.__version__}, Python {platform.python_version()}.\n\n"
        "| way | frames/s | s for the frames |\n|---|---|---|\n"
    )
    rows = "".join(
        f"| {k} | {len(frames) / statistics.median(ts):.0f} | {statistics.median(ts):.2f} |\n"
        for k, ts in times.items()
    )
    tail = (
        "\nEvery pipeline runs onnxruntime on 1 thread but the second row's; `tactile.run`'s "
        "rows are its summary's `fps`: reading and decoding the frames in, loading the models out. "
        "Starting the "
        f"process pool ({a.workers} spawned workers, each importing `tactile` and loading the "
        f"models once): {start_s:.2f} s. A tendon frame's result pickled: "
        f"{statistics.median(sizes) / 1024:.0f} KiB (median), {1e3 * statistics.median(dump):.2f} ms to "
        f"pickle and {1e3 * statistics.median(load):.2f} ms to unpickle (median of {len(dump)} results).\n"
    )
    table = head + rows + tail
    print(table, end="")
    if a.out:
        Path(a.out).write_text(
            f"<!-- Written by: python crates/tactile-py/bench/processes.py --out {a.out} -->\n\n{table}"
        )


def _timed(f) -> float:
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


if __name__ == "__main__":
    main()
