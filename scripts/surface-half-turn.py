#!/usr/bin/env python3
"""Would turning frames half a turn double issue 34's training data?

A half turn of the whole rig about the tip's axis maps a tap to another
tap: the tap depth and the twist stay, the slide (shear x, y) and the
surface's tilt (roll, pitch) change sign. (Conjugating by a half turn
about z turns a rotation about x or y into one by minus the angle and
leaves one about z, whatever the order of the Euler angles, and turns a
slide (x, y) into (-x, -y).) So if the tip and its picture were symmetric
under a half turn, each frame turned 180 degrees about the tip's centre,
with those four labels negated, would be a frame the rig could have
recorded: free data, exact labels.

This measures whether it is one. First the centre: the half turn about
which the mean `train` frame best matches itself (correlation, over
centres within 12 px of the picture's). Then a pose network trained on
`train` reads the SPLIT frames as recorded and turned about that centre;
its errors against the labels (turned as above) are printed beside the
no-frame estimate (each target's `train` median). If turned frames were
frames of the rig, its errors on them would be its errors on the frames
as recorded.

    python3 scripts/surface-half-turn.py --data ../shared/real/tactip331-surface --model data/surface/p64-k9

Needs the tactile package (`pip install crates/tactile-py`) and numpy;
writes nothing.
"""

import argparse
import sys

import numpy as np

import tactile

TARGETS = ["depth_mm", "roll_deg", "pitch_deg", "shear_x_mm", "shear_y_mm", "shear_theta_deg"]
# What a half turn does to each target.
HALF_TURN_SIGN = np.array([1.0, -1.0, -1.0, -1.0, -1.0, 1.0])


def half_turn(frame: np.ndarray, twice_centre: tuple) -> np.ndarray:
    """FRAME turned 180 degrees about (row, column) = TWICE_CENTRE / 2:
    pixel (i, j) comes from (2cy - i, 2cx - j); what comes from outside the
    frame is black, as the frames' background is."""
    h, w = frame.shape
    src_y, src_x = twice_centre[0] - np.arange(h), twice_centre[1] - np.arange(w)
    in_y, in_x = (src_y >= 0) & (src_y < h), (src_x >= 0) & (src_x < w)
    out = np.zeros_like(frame)
    out[np.ix_(in_y, in_x)] = frame[np.ix_(src_y[in_y], src_x[in_x])]
    return out


def best_centre(mean: np.ndarray, reach: int = 12) -> tuple:
    """The half-turn centre (as twice its row and column) within REACH px
    of the picture's centre about which MEAN best matches itself, with the
    correlation there and at the picture's centre."""
    h, w = mean.shape
    here = (h - 1, w - 1)

    def corr(twice):
        a, b = mean.ravel(), half_turn(mean, twice).ravel()
        return float(np.corrcoef(a, b)[0, 1])

    scored = [
        (corr((here[0] + dy, here[1] + dx)), (here[0] + dy, here[1] + dx))
        for dy in range(-2 * reach, 2 * reach + 1)
        for dx in range(-2 * reach, 2 * reach + 1)
    ]
    c, twice = max(scored)
    return twice, c, corr(here)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True, help="the TacTip-331 surface dataset folder")
    ap.add_argument("--model", required=True, help="a pose network (or ensemble) trained on its `train` split")
    ap.add_argument("--split", default="val", help="the frames to read (default: val)")
    ap.add_argument("--every", type=int, default=4, help="read every EVERY-th frame of the split (default: 4)")
    args = ap.parse_args()
    if args.every < 1:
        print(f"error: --every must be at least 1, got {args.every}", file=sys.stderr)
        return 2
    ds = tactile.Dataset(args.data)
    labels = ds.labels
    missing = [t for t in TARGETS + ["split"] if t not in labels]
    if missing:
        print(f"error: {args.data}/labels.csv has no {', '.join(missing)} column", file=sys.stderr)
        return 2
    split = labels["split"]
    train = [i for i, s in enumerate(split) if s == "train"]
    rows = [i for i, s in enumerate(split) if s == args.split][:: args.every]
    if not train or not rows:
        print(f"error: {args.data}/labels.csv: no `train` rows or no `{args.split}` rows", file=sys.stderr)
        return 2
    y = np.stack([np.asarray(labels[t], dtype=np.float64) for t in TARGETS], axis=1)

    mean = np.mean([ds.frame(i).astype(np.float32) for i in train[:: max(1, len(train) // 200)]], axis=0)
    twice, c_best, c_here = best_centre(mean)
    h, w = mean.shape
    print(
        f"half-turn centre (row, column): ({twice[0] / 2:.1f}, {twice[1] / 2:.1f}) px, "
        f"the picture's ({(h - 1) / 2:.1f}, {(w - 1) / 2:.1f}); the mean train frame "
        f"turned about it correlates {c_best:.3f} with itself (about the picture's centre: {c_here:.3f})"
    )

    pose = tactile.PoseEstimator(args.model)
    absent = [t for t in TARGETS if t not in pose.targets]
    if absent:
        print(f"error: {args.model} does not estimate {', '.join(absent)}", file=sys.stderr)
        return 2
    frames = [ds.frame(i) for i in rows]
    truth = y[rows]

    def errors(batch, sign):
        est = pose.estimate(batch)
        p = np.stack([np.asarray(est[t], dtype=np.float64) for t in TARGETS], axis=1) * sign
        return np.abs(p - truth).mean(axis=0)

    recorded = errors(frames, np.ones(len(TARGETS)))
    turned = errors([half_turn(f, twice) for f in frames], HALF_TURN_SIGN)
    no_frame = np.abs(np.median(y[train], axis=0) - truth).mean(axis=0)
    print(f"\n{len(rows)} `{args.split}` frames (every {args.every}-th), {args.model}: mean absolute error\n")
    print("| frames | " + " | ".join(TARGETS) + " |")
    print("|---|" + "---|" * len(TARGETS))
    for name, e in [
        ("as recorded", recorded),
        ("turned half a turn (labels turned)", turned),
        ("no frame (`train` median)", no_frame),
    ]:
        print(f"| {name} | " + " | ".join(f"{v:.3f}" for v in e) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
