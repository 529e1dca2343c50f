#!/usr/bin/env python3
"""How the surface errors fall with more training frames (issue 34).

Reads the rows `tactile bench surface` wrote for networks of one recipe
trained on different numbers of `train` frames (the JSON beside its page;
scripts/surface.sh steps p64-k9-n1500, p64-k9-n3000 and p64-k9) and fits,
per target, a power law error = a * frames^b by least squares on the logs.
Prints a Markdown table: each network's error, the exponent b, the error
the law gives at 8,000 frames (the set's every frame, as the shipped model
trains on), and how many frames the law says the goal (25 % below the
authors' CNN) would need. Standard library only.

    python3 scripts/surface-more-frames.py docs/paper-a/surface-more-frames.json \
        --frames p64-k9-n1500=1500 p64-k9-n3000=3000 p64-k9=6000
"""

import argparse
import json
import math
import sys

TARGETS = ["depth_mm", "roll_deg", "pitch_deg", "shear_x_mm", "shear_y_mm", "shear_theta_deg"]
# The authors' CNN on `val`, less 25 % (issue 34's goals).
GOALS = [0.13, 1.0, 1.0, 0.41, 0.41, 0.9]


def model_frames(item: str) -> tuple[str, int]:
    name, sep, count = item.rpartition("=")
    if not sep or not name or not count.isdigit() or int(count) < 1:
        raise argparse.ArgumentTypeError(f"{item!r}: give MODEL=FRAMES, FRAMES a whole number >= 1")
    return name, int(count)


def power_law(points: list[tuple[int, float]]) -> tuple[float, float]:
    """(a, b) of error = a * frames^b, least squares on the logs."""
    xs = [math.log(n) for n, _ in points]
    ys = [math.log(e) for _, e in points]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    return math.exp(my - b * mx), b


def frames_needed(a: float, b: float, goal: float) -> str:
    if b >= 0:
        return "never (no fall)"
    n = (goal / a) ** (1 / b)
    return f"{n:.2g}".replace("e+0", "e").replace("e+", "e")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("rows", help="the bench's JSON (NAME.json beside its page)")
    p.add_argument("--frames", nargs="+", type=model_frames, required=True,
                   help="MODEL=FRAMES: each network's training frames")
    a = p.parse_args()
    try:
        with open(a.rows, encoding="utf-8") as f:
            rows = {r["model"]: r["metrics"]["mae"] for r in json.load(f)}
    except (OSError, ValueError, KeyError, TypeError) as e:
        sys.exit(f"{a.rows}: not a surface bench's rows: {e}")
    missing = [m for m, _ in a.frames if m not in rows]
    if missing:
        sys.exit(f"{a.rows}: no row for {', '.join(missing)} (rows: {', '.join(rows)})")
    if len({n for _, n in a.frames}) < 2:
        sys.exit("--frames: a law needs networks trained on at least two numbers of frames")
    runs = sorted(a.frames, key=lambda mf: mf[1])
    head = " | ".join(f"{m} ({n} frames)" for m, n in runs)
    print(f"| target | {head} | exponent b | law at 8000 frames | goal | frames the law needs for it |")
    print("|---|" + "---|" * (len(runs) + 4))
    for t, name in enumerate(TARGETS):
        points = [(n, rows[m][t]) for m, n in runs]
        if any(not (e > 0 and math.isfinite(e)) for _, e in points):
            sys.exit(f"{a.rows}: {name}: errors must be positive numbers")
        ca, b = power_law(points)
        cells = " | ".join(f"{e:.3f}" for _, e in points)
        need = "met" if points[-1][1] <= GOALS[t] else frames_needed(ca, b, GOALS[t])
        print(f"| {name} | {cells} | {b:.3f} | {ca * 8000 ** b:.3f} | {GOALS[t]} | {need} |")


if __name__ == "__main__":
    main()
