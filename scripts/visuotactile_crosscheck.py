"""Paper B's shipped models on two implementations of the virtual
visuo-tactile sensor: the project's generator (`tactile synth
visuotactile`) and `scripts/visuotactile_independent.py`, written from
`sensors.md` alone. Writes a Markdown page (the table in `docs/synth.md`).

    python scripts/visuotactile_crosscheck.py OUT.md [SEQUENCES SEED]
    python scripts/visuotactile_crosscheck.py OUT.md --detectors D... --sets S...

Each set has SEQUENCES palpation videos of 12 frames (default 50, seed 21);
the independent implementation gives two, the second with every tendon's
centre line crossing the window.
The detector's frames are also scored by kind (from the labels), so a kind
of frame one implementation makes and the other does not is seen apart.
With `--detectors`, the page is instead those detectors' accuracy by kind
on each of the `--sets`.
Needs the `tactile` package (`pip install crates/tactile-py`).
"""
import argparse
import csv
import json
import os
import sys
import tempfile
from pathlib import Path

import tactile

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
import visuotactile_independent  # noqa: E402

FRAMES = visuotactile_independent.FRAMES


NO_CONTACT, IN_VIEW = "no contact", "tendon in view"
RIM = "tendon whose centre line is outside the window (its ridge reaches in)"
OUTSIDE = "centre line outside the window, no ridge over the mask's threshold in it"
LIGHT = "touching, ridge under 0.03 mm"
KINDS = [NO_CONTACT, IN_VIEW, RIM, OUTSIDE, LIGHT]


def kind(row, all_out_of_view=False):
    """What a frame shows, from its labels (the independent set's
    `outside_window_w` column says where its centre line is; in a set of
    this generator's made with `out_of_view_fraction` 1, every one is)."""
    if float(row["press_mm"] or 0) <= 0:
        return NO_CONTACT
    if row["tendon"] == "1":
        return RIM if all_out_of_view or row.get("outside_window_w") else IN_VIEW
    return OUTSIDE if float(row["ridge_mm"]) >= 0.03 else LIGHT


def by_kind(data, frames_csv):
    """Frames and accuracy of the detector per kind of frame."""
    with open(data / "labels.csv") as f:
        labels = {r["file"]: r for r in csv.DictReader(f)}
    config = json.loads((data / "manifest.json").read_text()).get("config", {})
    all_out = config.get("out_of_view_fraction") == 1.0
    counts = {}
    with open(frames_csv) as f:
        for r in csv.DictReader(f):
            k = kind(labels[r["file"]], all_out)
            n, right = counts.get(k, (0, 0))
            counts[k] = (n + 1, right + (r["predicted"] == r["tendon"]))
    return counts


def detector_by_kind(detector, data, tmp):
    """A detector's scores on `data` and its accuracy per kind of frame
    (from its per-frame CSV, written in `tmp`)."""
    frames_csv = tmp / f"{Path(detector).name}-{data.name}-frames.csv"
    det = tactile.eval.detector(detector, data, frames=str(frames_csv))
    return det, by_kind(data, frames_csv)


def kinds_page(detectors, sets, tmp):
    """The detectors' accuracy by kind of frame on each set, as Markdown."""
    lines = ["Each detector's accuracy by kind of frame (frames) on each set. Made by "
             f"`python scripts/visuotactile_crosscheck.py OUT.md --detectors {' '.join(d.name for d in detectors)} "
             f"--sets {' '.join(s.name for s in sets)}` (folder names; `just detector-near-rim`).", "",
             "| detector | set | accuracy | " + " | ".join(KINDS) + " |", "|---|---|---|" + "---|" * len(KINDS)]
    for d in detectors:
        for s in sets:
            det, k = detector_by_kind(d, s, tmp)
            cells = [f"{k[c][1] / k[c][0]:.3f} ({k[c][0]})" if c in k else "-" for c in KINDS]
            lines.append(f"| {d.name} | {s.name} | {det['all']['accuracy']:.4f} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def score(data, tmp, detector=ROOT / "models" / "detector"):
    """The detector's (by kind of frame), segmenter's and depth network's
    scores on `data`."""
    det, kinds = detector_by_kind(detector, data, tmp)
    seg = tactile.eval.segmenter(ROOT / "models" / "segmenter", data)
    dep = tactile.eval.depth(ROOT / "models" / "depth", data)
    return det, seg, dep, kinds


def page(sequences, seed, scores):
    names = list(scores)
    lines = [
        f"Paper B's shipped models on {sequences} palpation videos of {FRAMES} frames (640 x 360, seed {seed}) "
        "from each implementation of the virtual visuo-tactile sensor. "
        f"Made by `python scripts/visuotactile_crosscheck.py OUT.md {sequences} {seed}`.",
        "",
        "| | " + " | ".join(names) + " |",
        "|---|" + "---|" * len(names),
    ]

    def row(label, f):
        lines.append(f"| {label} | " + " | ".join(f(*scores[n]) for n in names) + " |")

    row("detector accuracy (frames with a tendon)",
        lambda d, s, p, k: f"{d['all']['accuracy']:.4f} ({d['all']['true_pos'] + d['all']['false_neg']})")
    row("detector recall / precision",
        lambda d, s, p, k: f"{d['all']['recall']:.4f} / {d['all']['precision']:.4f}")
    row("segmenter mean IoU, all paths",
        lambda d, s, p, k: f"{s['paths'][0]['mean_iou']:.4f}")
    row("direction error median / p90 (deg)",
        lambda d, s, p, k: f"{s['paths'][0]['direction']['median_deg']:.2f} / {s['paths'][0]['direction']['p90_deg']:.2f}")
    row("depth MAE in the window / over the tendon (mm)",
        lambda d, s, p, k: f"{p['scores']['mae_mm']:.4f} / {p['scores']['mae_tendon_mm']:.4f}")
    kinds = sorted({k for n in names for k in scores[n][3]})
    lines += ["", "The detector by kind of frame (frames, accuracy):", "",
              "| kind of frame | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for k in kinds:
        cells = []
        for n in names:
            total, right = scores[n][3].get(k, (0, 0))
            cells.append(f"{total}, {right / total:.4f}" if total else "-")
        lines.append(f"| {k} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_page(out, make):
    """`make(tmp)`'s Markdown written to `out` through a staged file, with
    a scratch folder beside it that is removed at the end."""
    out = Path(out)
    if not out.parent.is_dir():
        raise FileNotFoundError(f"{out}: its folder {out.parent} does not exist")
    with tempfile.TemporaryDirectory(prefix=".crosscheck-", dir=out.parent) as t:
        tmp = Path(t)
        staged = tmp / "page.md"
        staged.write_text(make(tmp))
        os.replace(staged, out)


def main(out, sequences, seed):
    def make(tmp):
        own = tactile.synth.visuotactile(sequences=sequences, frames_per_sequence=FRAMES, seed=seed,
                                         out=tmp / "own", progress=False)
        ind, in_view = tmp / "independent", tmp / "independent-in-view"
        visuotactile_independent.main(str(ind), sequences, seed)
        visuotactile_independent.main(str(in_view), sequences, seed, out_of_view=0.0)
        scores = {"`tactile synth visuotactile`": score(Path(own), tmp),
                  "`scripts/visuotactile_independent.py`": score(ind, tmp),
                  "the same, every tendon in view": score(in_view, tmp)}
        return page(sequences, seed, scores)

    write_page(out, make)


if __name__ == "__main__":
    cli = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    cli.add_argument("out", help="the Markdown page to write")
    cli.add_argument("sequences", nargs="?", type=int, default=50)
    cli.add_argument("seed", nargs="?", type=int, default=21)
    cli.add_argument("--detectors", nargs="+", type=Path,
                     help="instead: these detectors' accuracy by kind of frame on --sets")
    cli.add_argument("--sets", nargs="+", type=Path)
    a = cli.parse_args()
    if a.detectors and not a.sets:
        cli.error("--detectors needs --sets")
    try:
        if a.detectors:
            write_page(a.out, lambda tmp: kinds_page(a.detectors, a.sets, tmp))
        else:
            main(a.out, a.sequences, a.seed)
    except (OSError, ValueError) as e:
        sys.exit(f"error: {e}")
    except KeyboardInterrupt:
        sys.exit(130)
