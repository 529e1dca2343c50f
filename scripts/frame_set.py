"""A dataset derived frame by frame from another (issue 34's representation
experiments, scripts/surface-*.py): the labels and split are copied, each
frame replaced by a picture made from it, and the manifest's size updated.

Reads stay inside the source folder; the new set is written into a staging
folder of its own beside OUT and renamed to OUT at the end, so concurrent
runs never mix and an interrupted one leaves no OUT.
"""

import csv
import json
import os
import shutil
import sys
import tempfile
from typing import Callable, Dict, List, Optional

import numpy as np
from PIL import Image


def check_new(out: str) -> None:
    """Exit with a message if OUT exists: a derived set is never written over."""
    if os.path.exists(out):
        raise SystemExit(f"error: {out} exists; give a new folder")


def read_rows(data: str) -> List[Dict[str, str]]:
    """The rows of DATA/labels.csv."""
    with open(os.path.join(data, "labels.csv"), newline="") as f:
        return list(csv.DictReader(f))


def read_frame(data: str, row: Dict[str, str]) -> np.ndarray:
    """A row's frame as grey uint8, refused if its path leaves DATA."""
    root = os.path.realpath(data)
    path = os.path.realpath(os.path.join(root, row["file"]))
    if not path.startswith(root + os.sep):
        raise SystemExit(f"error: {data}/labels.csv: {row['file']} lies outside {data}")
    return np.asarray(Image.open(path).convert("L"))


def write_set(
    data: str,
    out: str,
    convert: Callable[[np.ndarray], np.ndarray],
    rows: Optional[List[Dict[str, str]]] = None,
    extras: Optional[Dict[str, np.ndarray]] = None,
) -> int:
    """Write OUT: every frame of DATA through CONVERT (grey uint8 in and
    out), DATA's labels and manifest (its width and height those of the
    converted frames), and EXTRAS (file name to grey image) beside them.
    Returns the number of frames, or exits with a message naming the
    problem."""
    check_new(out)
    rows = read_rows(data) if rows is None else rows
    if not rows:
        raise SystemExit(f"error: {data}/labels.csv lists no frame")
    parent = os.path.dirname(os.path.abspath(out))
    os.makedirs(parent, exist_ok=True)
    stage = tempfile.mkdtemp(prefix=os.path.basename(out.rstrip("/")) + ".partial-", dir=parent)
    try:
        size = None
        for i, r in enumerate(rows):
            picture = convert(read_frame(data, r))
            if picture.dtype != np.uint8 or picture.ndim != 2:
                raise SystemExit(f"error: {r['file']}: the conversion gave {picture.dtype} {picture.shape}, not grey uint8")
            size = size or (picture.shape[1], picture.shape[0])
            dest = os.path.join(stage, r["file"])
            os.makedirs(os.path.dirname(dest), exist_ok=True)
            Image.fromarray(picture).save(dest)
            if i % 1000 == 0:
                print(f"{i}/{len(rows)} frames", file=sys.stderr)
        shutil.copy(os.path.join(data, "labels.csv"), os.path.join(stage, "labels.csv"))
        with open(os.path.join(data, "manifest.json")) as f:
            manifest = json.load(f)
        if size is not None:
            manifest["width"], manifest["height"] = size
        with open(os.path.join(stage, "manifest.json"), "w") as f:
            json.dump(manifest, f, indent=1)
        for name, picture in (extras or {}).items():
            Image.fromarray(picture).save(os.path.join(stage, name))
        os.rename(stage, out)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    return len(rows)
