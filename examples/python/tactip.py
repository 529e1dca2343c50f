"""Paper A from Python: one encoder, every estimator, on virtual TacTip frames.

    pip install ./crates/tactile-py
    python examples/python/tactip.py [--encoder models/cae-synth] [--count 200]

Renders frames of the virtual TacTip (the labels are exact), encodes them
once, runs the shape head and the regressors on the same features, and
prints the accuracy and errors against the labels.
"""

from __future__ import annotations

import argparse

import numpy as np

import tactile


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--encoder", default="models/cae-synth")
    ap.add_argument("--count", type=int, default=200)
    ap.add_argument("--seed", type=int, default=900)
    a = ap.parse_args()

    frames, labels = tactile.synth.tactip(a.count, seed=a.seed, progress=False)
    enc = tactile.TactipEncoder(a.encoder)
    print(enc)
    features = enc.encode(frames)
    print(f"{len(frames)} frames -> features {features.shape} {features.dtype}")
    est = enc.estimate(frames)
    for name, values in est.items():
        if name == "shape":
            truth = np.array(labels["shape"])
            print(f"shape accuracy: {np.mean(values == truth) * 100:.1f} %")
        elif name in labels:
            truth = np.asarray(labels[name], dtype=float)
            ok = ~np.isnan(truth)
            err = np.abs(values[ok] - truth[ok])
            if name.startswith("theta"):
                err = np.minimum(err, 180 - err)  # orientation is periodic
            print(f"{name}: mean absolute error {err.mean():.3f} over {ok.sum()} frames")
        else:
            print(f"{name}: {values[:5]} ...")


if __name__ == "__main__":
    main()
