#!/usr/bin/env python3
"""Averaging over shifted copies at test time (issue 34): does reading each
frame several times, moved by a few pixels, take the slide and twist errors
down on frames no model saw?

The surface models train with the pin image shifted by up to 5 % of its
side (`--shift 0.05`), so a copy of a frame moved by a few pixels is a frame
of their training kind. For each SHIFT (pixels of the 445x440 frame; the
56 px pin image moves by an eighth of that), every `val` frame is estimated
as it is and moved SHIFT pixels right, left, down and up (the edge filled
with black, as outside the tip); the five estimates are averaged. Prints a
Markdown table of the mean absolute error per target: as it is, one copy
moved right, and the average of five, per SHIFT.

The model (an encoder folder with its estimators, or a pose network) must
not have trained on `val`: `models/cae-surface-train` (the CAE route's
encoder and its five MLPs, trained on `train` alone) is one, and so is
`data/surface/p64-k9-long` (`SURFACE_STEPS=p64-k9-long bash scripts/surface.sh`).

    pip install ./crates/tactile-py
    python3 scripts/surface-shift-average.py --model models/cae-surface-train data/surface/p64-k9-long \\
        --data ../shared/real/tactip331-surface --shifts 4,8,16
"""

import argparse
import os
import sys
import time

import numpy as np

import tactile

TARGETS = ["depth_mm", "roll_deg", "pitch_deg", "shear_x_mm", "shear_y_mm", "shear_theta_deg"]


def shifts(text: str) -> list[int]:
    try:
        values = [int(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give whole numbers of pixels, such as 4,8,16")
    if not values or any(not 1 <= v <= 64 for v in values):
        raise argparse.ArgumentTypeError(f"{text!r}: each shift must be 1 to 64 pixels")
    return values


def moved(frames: np.ndarray, dx: int, dy: int) -> np.ndarray:
    """FRAMES (N, H, W) moved DX pixels right and DY down, black filling in."""
    out = np.zeros_like(frames)
    h, w = frames.shape[1:]
    out[:, max(dy, 0):h + min(dy, 0), max(dx, 0):w + min(dx, 0)] = frames[
        :, max(-dy, 0):h + min(-dy, 0), max(-dx, 0):w + min(-dx, 0)
    ]
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True, nargs="+",
                    help="encoder folders with their estimators, or pose networks, none trained on SPLIT")
    ap.add_argument("--data", required=True, help="the TacTip-331 surface dataset folder")
    ap.add_argument("--split", default="val", help="the rows to score (default: val)")
    ap.add_argument("--shifts", type=shifts, default=[4, 8, 16], help="pixels, comma-separated")
    ap.add_argument("--every", type=int, default=1, help="score every N-th row of the split (a quick look)")
    a = ap.parse_args()
    if a.every < 1:
        ap.error("--every must be at least 1")

    # The toolkit's own loader: the layout checked, reads kept inside DATA.
    ds = tactile.Dataset(a.data)
    labels = ds.labels
    missing = [t for t in TARGETS + ["split"] if t not in labels]
    if missing:
        sys.exit(f"error: {a.data}/labels.csv has no {', '.join(missing)} column")
    rows = [i for i, s in enumerate(labels["split"]) if s == a.split][:: a.every]
    if not rows:
        sys.exit(f"error: {a.data}/labels.csv has no rows of split {a.split!r}")
    truth = np.stack([np.asarray(labels[t], dtype=np.float64)[rows] for t in TARGETS], axis=1)
    frames = np.stack([ds.frame(i) for i in rows])
    every = f" (every {a.every}-th)" if a.every > 1 else ""
    print(f"{len(frames)} `{a.split}` frames{every} of {a.data}.\n")
    print("| model | estimate | " + " | ".join(TARGETS) + " | ms/frame |")
    print("|---|---|" + "---|" * (len(TARGETS) + 1))
    for path in a.model:
        # An encoder folder (cae.json) reads the frame through its features
        # and estimators; a pose network or an ensemble of them reads it itself.
        model = (tactile.TactipEncoder(path) if os.path.isfile(os.path.join(path, "cae.json"))
                 else tactile.PoseEstimator(path))

        def estimate(batch: np.ndarray) -> np.ndarray:
            e = model.estimate(batch)
            return np.stack([np.asarray(e[t], float) for t in TARGETS], axis=1)

        def row(name: str, est: np.ndarray, ms: float) -> str:
            errors = np.abs(est - truth).mean(axis=0)
            return f"| {os.path.basename(os.path.normpath(path))} | {name} | " + " | ".join(
                f"{e:.3f}" for e in errors) + f" | {ms:.2f} |"

        t0 = time.perf_counter()
        plain = estimate(frames)
        ms_one = 1e3 * (time.perf_counter() - t0) / len(frames)
        print(row("the frame as it is", plain, ms_one))
        for s in a.shifts:
            t0 = time.perf_counter()
            copies = [plain] + [estimate(moved(frames, dx, dy)) for dx, dy in [(s, 0), (-s, 0), (0, s), (0, -s)]]
            ms = ms_one + 1e3 * (time.perf_counter() - t0) / len(frames)
            print(row(f"one copy moved {s} px right", copies[1], ms_one))
            print(row(f"average of five, {s} px", np.mean(copies, axis=0), ms))
    return 0


if __name__ == "__main__":
    sys.exit(main())
