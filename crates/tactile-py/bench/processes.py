"""Frames per second of paper B's pipeline from Python: one process against
a pool of worker processes, each with its own pipeline.

The frames are a rendered palpation set (every stage runs on its tendon
frames). Each way is timed over every frame, in rounds that alternate the
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
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

import tactile

_WORKER: tactile.Pipeline | None = None


def _init(models: str, threads: int) -> None:
    global _WORKER
    _WORKER = tactile.Pipeline(models, threads=threads)


def _process(frame: np.ndarray) -> tactile.FrameResult:
    assert _WORKER is not None
    return _WORKER.process(frame)


def cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", default="models")
    ap.add_argument("--frames", type=int, default=240)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--out", help="also write the table to this Markdown file")
    a = ap.parse_args()

    per = 30
    v = tactile.synth.visuotactile(sequences=-(-a.frames // per), frames_per_sequence=per, seed=11, progress=False)
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
    ways = {f"one process, {t} thread(s)": (lambda p=p: [p.process(f) for f in frames]) for t, p in one.items()}
    ways[f"{a.workers} worker processes, 1 thread each"] = lambda: list(pool.map(_process, frames, chunksize=chunk))
    times: dict[str, list[float]] = {k: [] for k in ways}
    results = {}
    for _ in range(a.rounds):
        for k, run in ways.items():
            t = time.perf_counter()
            results[k] = run()
            times[k].append(time.perf_counter() - t)
    pool.shutdown()
    base = next(iter(results.values()))
    for k, rs in results.items():
        assert [r.tendon for r in rs] == [r.tendon for r in base], f"{k}: other decisions"

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
        f"\nStarting the pool ({a.workers} spawned workers, each importing `tactile` and loading the "
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
