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
import sys

import cv2
import numpy as np

from frame_set import check_new, write_set


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True, help="the TacTip-331 surface dataset folder")
    ap.add_argument("--out", required=True, help="new dataset folder (must not exist)")
    ap.add_argument("--centre", default="222,220", help="the tip's centre in the frame, x,y pixels")
    ap.add_argument("--radius", type=float, default=215.0, help="the tip's radius, pixels")
    ap.add_argument("--side", type=int, default=880, help="side of the polar image, pixels (64-2048)")
    args = ap.parse_args()
    check_new(args.out)
    if not 64 <= args.side <= 2048:
        print(f"error: --side {args.side} is not 64-2048", file=sys.stderr)
        return 2
    if not 1.0 <= args.radius <= 10000.0:
        print(f"error: --radius {args.radius} is not 1-10000 pixels", file=sys.stderr)
        return 2
    try:
        cx, cy = (float(v) for v in args.centre.split(","))
    except ValueError:
        print(f"error: --centre {args.centre!r} is not x,y", file=sys.stderr)
        return 2

    def polar(frame: np.ndarray) -> np.ndarray:
        flags = cv2.INTER_LINEAR | cv2.WARP_FILL_OUTLIERS
        return cv2.warpPolar(frame, (args.side, args.side), (cx, cy), args.radius, flags)

    n = write_set(args.data, args.out, polar)
    print(f"{n} polar frames ({args.side}x{args.side}) in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
