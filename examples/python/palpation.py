"""Paper B's palpation pipeline on a video or a camera, from Python.

    pip install ./crates/tactile-py opencv-python-headless matplotlib
    python examples/python/palpation.py VIDEO.mp4 [--models models] [--plot out.png]
    python examples/python/palpation.py 0        # the first camera

Reads frames with OpenCV (BGR), gives them to the pipeline as RGB, prints a
line per frame (tendon, direction, depth, milliseconds) and, with --plot,
draws the detector's score, the direction and the depth over time.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

import tactile


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("video", help="a video file, or a camera index such as 0")
    ap.add_argument("--models", default="models")
    ap.add_argument("--runtime", default="onnx")
    ap.add_argument("--hysteresis", type=float, nargs=2, metavar=("ON", "OFF"))
    ap.add_argument("--limit", type=int, default=0, help="stop after this many frames")
    ap.add_argument("--plot", help="write a plot of the run to this PNG")
    a = ap.parse_args()

    try:
        import cv2
    except ImportError:
        sys.exit("this example reads video with OpenCV: pip install opencv-python-headless")

    source = int(a.video) if a.video.isdigit() else a.video
    cap = cv2.VideoCapture(source)
    if not cap.isOpened():
        sys.exit(f"{a.video}: OpenCV cannot open it")
    pipe = tactile.Pipeline(a.models, a.runtime, hysteresis=tuple(a.hysteresis) if a.hysteresis else None)

    t, score, direction, depth = [], [], [], []
    i = 0
    while True:
        ok, bgr = cap.read()
        if not ok or (a.limit and i >= a.limit):
            break
        r = pipe.process(bgr[:, :, ::-1])  # a BGR -> RGB view; copied once inside
        stats = r.depth_mm_stats
        print(
            f"{i:6d} tendon={int(r.tendon)} score={r.score:.3f} "
            f"direction={'-' if r.direction_deg is None else f'{r.direction_deg:6.1f}'} "
            f"depth_mean={'-' if stats is None else f'{stats[1]:.2f} mm'} "
            f"{r.ms['total']:.1f} ms"
        )
        t.append(i)
        score.append(r.score)
        direction.append(np.nan if r.direction_deg is None else r.direction_deg)
        depth.append(np.nan if stats is None else stats[1])
        i += 1
    cap.release()
    if not t:
        sys.exit(f"{a.video}: no frames read")

    if a.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(3, 1, sharex=True, figsize=(8, 6))
        ax[0].plot(t, score)
        ax[0].axhline(pipe.threshold, ls="--", c="grey")
        ax[0].set_ylabel("tendon score")
        ax[1].plot(t, direction, ".")
        ax[1].set_ylabel("direction (deg)")
        ax[2].plot(t, depth)
        ax[2].set_ylabel("mean depth (mm)")
        ax[2].set_xlabel("frame")
        fig.tight_layout()
        fig.savefig(a.plot, dpi=120)
        print(f"plot: {a.plot}")


if __name__ == "__main__":
    main()
