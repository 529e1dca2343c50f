"""What the Python call costs over the Rust pipeline, and frames/s from Python.

For a 640x360 tendon frame (every stage runs) and a frame the detector gates
out, the same loaded pipeline is timed two ways, interleaved in rounds so
drift hits both alike: ``Pipeline.time_in_rust`` (the Rust loop over the
library's pipeline, no Python in between) and a Python loop over
``Pipeline.process``. The overhead is the difference of the medians over
the Rust median. A third row adds reading the full-resolution ``mask`` and
``depth_m`` arrays, which a caller pays only when it asks for them.

    python crates/tactile-py/bench/overhead.py [--models models] [--rounds 20] [--out FILE]

Prints a Markdown table with the machine, the runtime and its threads.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np

import tactile


def cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def python_ms(pipe: tactile.Pipeline, frame: np.ndarray, n: int, outputs: bool) -> list[float]:
    out = []
    for _ in range(n):
        t = time.perf_counter()
        r = pipe.process(frame)
        if outputs:
            r.mask, r.depth_m
        out.append(1e3 * (time.perf_counter() - t))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", default="models")
    ap.add_argument("--runtime", default="onnx")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--rounds", type=int, default=20)
    ap.add_argument("--per-round", type=int, default=50)
    ap.add_argument("--out", help="also write the table to this Markdown file")
    a = ap.parse_args()

    v = tactile.synth.visuotactile(sequences=1, frames_per_sequence=9, seed=5, progress=False)
    tendon = v["frames"][int(np.flatnonzero(v["tendon"])[4])]
    gated = v["frames"][int(np.flatnonzero(~v["tendon"])[0])]
    pipe = tactile.Pipeline(a.models, a.runtime, threads=a.threads)
    assert pipe.process(tendon).tendon, "the tendon frame must run every stage"
    assert not pipe.process(gated).tendon, "the gated frame must stop at the detector"

    rows = []
    for name, frame, outputs in [
        ("640x360 tendon frame", tendon, False),
        ("640x360 tendon frame, with mask and depth_m", tendon, True),
        ("640x360 frame gated out", gated, False),
    ]:
        rust, py = [], []
        python_ms(pipe, frame, a.per_round, outputs)  # warm-up
        for _ in range(a.rounds):
            rust += pipe.time_in_rust(frame, a.per_round)
            py += python_ms(pipe, frame, a.per_round, outputs)
        r, p = statistics.median(rust), statistics.median(py)
        rows.append((name, r, p, 100 * (p - r) / r, 1e3 / p))

    head = (
        f"Machine: {cpu_name()}, {os.cpu_count()} logical CPUs; runtime {pipe.runtime}, "
        f"{pipe.threads} onnxruntime thread(s); median of {a.rounds} x {a.per_round} calls each; "
        f"tactile {tactile.__version__}, Python {platform.python_version()}.\n\n"
        "| frame | Rust pipeline (ms) | Python call (ms) | overhead | frames/s from Python |\n"
        "|---|---|---|---|---|\n"
    )
    table = head + "".join(
        f"| {n} | {r:.3f} | {p:.3f} | {o:+.1f} % | {f:.0f} |\n" for n, r, p, o, f in rows
    )
    print(table, end="")
    if a.out:
        Path(a.out).write_text(
            "<!-- Written by: python crates/tactile-py/bench/overhead.py --out "
            f"{a.out} -->\n\n{table}"
        )


if __name__ == "__main__":
    main()
