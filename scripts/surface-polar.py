#!/usr/bin/env python3
"""The "polar pin image" representation of issue 34, as a dataset the pose
trainer reads unchanged.

A twist turns the pins that grip the surface about the tip's centre: in
Cartesian pixels that is a slide whose direction and size change with
every pin's place, in polar pixels (angle down the rows, radius along the
columns) it is one shift down the rows of the gripped region against the
rest, which a convolution reads alike everywhere. Every frame is resampled
about the tip's centre (OpenCV's warpPolar, bilinear) to a square of SIDE
pixels: row k is the angle 360 k / SIDE degrees, column j the radius
RADIUS j / SIDE pixels. Labels and split are copied.

    pip install numpy pillow opencv-python-headless
    python3 scripts/surface-polar.py --data ../shared/real/tactip331-surface --out /tmp/surface-polar
    tactile train pose --data /tmp/surface-polar --crop-px 880 --mask-radius-px 1000 ... (the p64-k9 recipe of scripts/surface.sh)

docs/paper-a.md reports the measured result. Writes into a staging folder
renamed at the end.
"""

import argparse
import csv
import json
import os
import shutil
import sys

import cv2
import numpy as np
from PIL import Image


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True, help="the TacTip-331 surface dataset folder")
    ap.add_argument("--out", required=True, help="new dataset folder (must not exist)")
    ap.add_argument("--centre", default="222,220", help="the tip's centre in the frame, x,y pixels")
    ap.add_argument("--radius", type=float, default=215.0, help="the tip's radius, pixels")
    ap.add_argument("--side", type=int, default=880, help="side of the polar image, pixels (64-2048)")
    args = ap.parse_args()
    if not 64 <= args.side <= 2048:
        print(f"error: --side {args.side} is not 64-2048", file=sys.stderr)
        return 2
    try:
        cx, cy = (float(v) for v in args.centre.split(","))
    except ValueError:
        print(f"error: --centre {args.centre!r} is not x,y", file=sys.stderr)
        return 2
    if os.path.exists(args.out):
        print(f"error: {args.out} exists; give a new folder", file=sys.stderr)
        return 2
    with open(os.path.join(args.data, "labels.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    root = os.path.realpath(args.data)
    stage = args.out.rstrip("/") + ".partial"
    shutil.rmtree(stage, ignore_errors=True)
    os.makedirs(os.path.join(stage, "frames"))
    for i, r in enumerate(rows):
        path = os.path.realpath(os.path.join(root, r["file"]))
        if not path.startswith(root + os.sep):
            raise SystemExit(f"error: labels.csv: {r['file']} lies outside {args.data}")
        frame = np.asarray(Image.open(path).convert("L"))
        polar = cv2.warpPolar(
            frame, (args.side, args.side), (cx, cy), args.radius, cv2.INTER_LINEAR | cv2.WARP_FILL_OUTLIERS
        )
        out = os.path.join(stage, r["file"])
        os.makedirs(os.path.dirname(out), exist_ok=True)
        Image.fromarray(polar).save(out)
        if i % 1000 == 0:
            print(f"{i}/{len(rows)} frames", file=sys.stderr)
    shutil.copy(os.path.join(args.data, "labels.csv"), os.path.join(stage, "labels.csv"))
    with open(os.path.join(args.data, "manifest.json")) as f:
        m = json.load(f)
    m["width"] = m["height"] = args.side
    with open(os.path.join(stage, "manifest.json"), "w") as f:
        json.dump(m, f, indent=1)
    os.rename(stage, args.out)
    print(f"{len(rows)} polar frames ({args.side}x{args.side}) in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
