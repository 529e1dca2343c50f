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
import sys

import numpy as np

from frame_set import check_new, read_frame, read_rows, write_set


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True, help="the TacTip-331 surface dataset folder")
    ap.add_argument("--out", required=True, help="new dataset folder (must not exist)")
    ap.add_argument("--max-depth", type=float, default=1.0, help="taps shallower than this (mm) make the rest frame")
    args = ap.parse_args()
    check_new(args.out)
    rows = read_rows(args.data)
    shallow = [r for r in rows if r.get("split") == "train" and float(r["depth_mm"]) < args.max_depth]
    if not shallow:
        print(f"error: no train frame shallower than {args.max_depth} mm", file=sys.stderr)
        return 2
    rest = np.median(np.stack([read_frame(args.data, r).astype(np.float32) for r in shallow]), axis=0)

    def difference(frame: np.ndarray) -> np.ndarray:
        return np.clip(128 + (frame.astype(np.float32) - rest) / 2, 0, 255).astype(np.uint8)

    write_set(args.data, args.out, difference, rows, extras={"rest.png": rest.astype(np.uint8)})
    print(f"{len(rows)} difference frames against the median of {len(shallow)} shallow taps in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
