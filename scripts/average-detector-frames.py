#!/usr/bin/env python3
"""Accuracy of two detectors' logits averaged, from their per-frame CSVs.

An analysis aid: the toolkit's own ensemble is `tactile train ensemble`
(one network averaging its members' logits), whose `tactile eval detector`
accuracy this reproduces; this adds how many frames both get wrong.

Each argument pair is the `--frames` CSV of `tactile eval detector` for
detector A and detector B on the same set (same frames, same order). Prints
each one's accuracy at probability 0.5 and that of the average of their
logits, with how many frames both get wrong. Usage:

    python3 scripts/average-detector-frames.py A.csv B.csv [A2.csv B2.csv ...]
"""
import csv
import math
import sys


def load(path):
    with open(path, newline="") as f:
        return [(row["file"], int(row["tendon"]), float(row["probability"])) for row in csv.DictReader(f)]


def logit(p):
    p = min(max(p, 1e-7), 1 - 1e-7)
    return math.log(p / (1 - p))


def main(paths):
    if len(paths) < 2 or len(paths) % 2:
        sys.exit(__doc__)
    print("| set | A | B | logits averaged | both wrong |")
    print("|---|---|---|---|---|")
    for a_path, b_path in zip(paths[::2], paths[1::2]):
        a, b = load(a_path), load(b_path)
        if [(f, y) for f, y, _ in a] != [(f, y) for f, y, _ in b]:
            sys.exit(f"{a_path} and {b_path} do not list the same frames and labels")
        right = lambda z, y: (z >= 0) == (y == 1)
        acc_a = sum(right(logit(p), y) for _, y, p in a) / len(a)
        acc_b = sum(right(logit(q), y) for _, y, q in b) / len(b)
        acc_avg = sum(right(logit(p) + logit(q), y) for (_, y, p), (_, _, q) in zip(a, b)) / len(a)
        both = sum(not right(logit(p), y) and not right(logit(q), y) for (_, y, p), (_, _, q) in zip(a, b))
        print(f"| {a_path} / {b_path} ({len(a)} frames) | {acc_a:.4f} | {acc_b:.4f} | {acc_avg:.4f} | {both} |")


if __name__ == "__main__":
    main(sys.argv[1:])
