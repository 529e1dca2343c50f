#!/usr/bin/env bash
# A share of the surface set's `train` frames as a dataset of its own
# (issue 34): N `train` rows of ../shared/real/tactip331-surface drawn at
# random (seed 7, kept in the set's order) and every `val` row, labels and
# split kept, written by `tactile dataset from-video` from the set's frame
# folder. Networks trained on 1,500 and 3,000 of the 6,000 `train` frames
# (scripts/surface.sh, steps p64-k9-n1500 and p64-k9-n3000) say how the
# errors on `val` fall with more frames: whether more taps of this rig
# would bring shear and twist to the goal.
#
#   bash scripts/surface-train-subset.sh N [OUT]
#
# OUT defaults to $TACTILE_CACHE or ~/.cache/tactile-rs, /surface-train-N,
# outside the project (the real frames are never copied into it). Prints
# OUT; an existing OUT is kept (idempotent), a new one is staged and renamed
# by the import.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${TACTILE_SHARED_REAL:-../shared/real}
N=${1:?usage: surface-train-subset.sh N [OUT]}
[[ "$N" =~ ^[1-9][0-9]*$ ]] || { echo "N must be a whole number of train frames, got '$N'" >&2; exit 2; }
CACHE=${TACTILE_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tactile-rs}
OUT=${2:-$CACHE/surface-train-$N}
if [ ! -f "$OUT/labels.csv" ]; then
    cargo build --release -q -p tactile
    BIN="${CARGO_TARGET_DIR:-target}/release/tactile"
    labels=$(mktemp --suffix=.csv)
    trap 'rm -f "$labels"' EXIT
    # The import names each frame by its file name in a `frame` column.
    python3 - "$REAL/tactip331-surface/labels.csv" "$N" "$labels" <<'PY'
import csv, random, sys
src, n, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
with open(src, newline="") as f:
    rows = list(csv.DictReader(f))
train = [i for i, r in enumerate(rows) if r["split"] == "train"]
if n > len(train):
    sys.exit(f"N = {n}: the set has {len(train)} train frames")
keep = set(random.Random(7).sample(train, n))
cols = [c for c in rows[0] if c != "file"]
with open(out, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["frame"] + cols)
    for i, r in enumerate(rows):
        if r["split"] != "train" or i in keep:
            w.writerow([r["file"].rsplit("/", 1)[-1]] + [r[c] for c in cols])
PY
    mkdir -p "$(dirname "$OUT")"
    "$BIN" dataset from-video --video "$REAL/tactip331-surface/frames" --labels "$labels" --kind tactip \
        --sensor "tactip331-surface: $N train frames drawn at random (seed 7) and every val frame (scripts/surface-train-subset.sh)" \
        --out "$OUT" >&2
fi
echo "$OUT"
