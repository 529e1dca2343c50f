#!/usr/bin/env python3
"""The "image differences against a rest frame" representation of issue 34,
as a dataset the pose trainer reads unchanged.

The surface set has no frame without contact, so the rest frame is the
per-pixel median of the shallowest `train` taps (depth below --max-depth,
485 frames below 1 mm), where only a small patch of pins has moved and the
median over many patches is the pins at rest. Every frame becomes
128 + (frame - rest) / 2: pins that did not move vanish into mid grey, a
slid pin shows as a bright and a dark crescent. Labels and split are copied.

    pip install numpy pillow
    python3 scripts/surface-rest-difference.py --data ../shared/real/tactip331-surface --out /tmp/surface-diff
    tactile train pose --data /tmp/surface-diff ... (the p64 recipe of scripts/surface.sh)

docs/paper-a-surface.md reports the measured result (worse than the frames
themselves on every target). Writes into a staging folder renamed at the end.
"""

import argparse
import csv
import os
import shutil
import sys

import numpy as np
from PIL import Image


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True, help="the TacTip-331 surface dataset folder")
    ap.add_argument("--out", required=True, help="new dataset folder (must not exist)")
    ap.add_argument("--max-depth", type=float, default=1.0, help="taps shallower than this (mm) make the rest frame")
    args = ap.parse_args()
    if os.path.exists(args.out):
        print(f"error: {args.out} exists; give a new folder", file=sys.stderr)
        return 2
    with open(os.path.join(args.data, "labels.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    root = os.path.realpath(args.data)

    def frame(row: dict) -> np.ndarray:
        path = os.path.realpath(os.path.join(root, row["file"]))
        if not path.startswith(root + os.sep):
            raise SystemExit(f"error: labels.csv: {row['file']} lies outside {args.data}")
        return np.asarray(Image.open(path).convert("L"), dtype=np.float32)

    shallow = [r for r in rows if r.get("split") == "train" and float(r["depth_mm"]) < args.max_depth]
    if not shallow:
        print(f"error: no train frame shallower than {args.max_depth} mm", file=sys.stderr)
        return 2
    rest = np.median(np.stack([frame(r) for r in shallow]), axis=0)
    stage = args.out.rstrip("/") + ".partial"
    shutil.rmtree(stage, ignore_errors=True)
    os.makedirs(os.path.join(stage, "frames"))
    for i, r in enumerate(rows):
        diff = np.clip(128 + (frame(r) - rest) / 2, 0, 255).astype(np.uint8)
        out = os.path.join(stage, r["file"])
        os.makedirs(os.path.dirname(out), exist_ok=True)
        Image.fromarray(diff).save(out)
        if i % 1000 == 0:
            print(f"{i}/{len(rows)} frames", file=sys.stderr)
    for name in ("labels.csv", "manifest.json"):
        shutil.copy(os.path.join(args.data, name), os.path.join(stage, name))
    Image.fromarray(rest.astype(np.uint8)).save(os.path.join(stage, "rest.png"))
    os.rename(stage, args.out)
    print(f"{len(rows)} difference frames against the median of {len(shallow)} shallow taps in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
