#!/usr/bin/env bash
# Rows of the surface set (../shared/real/tactip331-surface) as a dataset of
# their own (issue 34), labels and split kept, written by `tactile dataset
# from-video` from the set's frame folder:
#
#   bash scripts/surface-subset.sh shallow [OUT]
#       The taps shallower than 2.34 mm (the upper bound of `val`'s
#       shallowest third in `tactile bench surface`'s tables; 1,965 `train`
#       and 668 `val` frames). A network trained on them alone
#       (scripts/surface.sh, step p64-k9-shallow) says whether slide and
#       twist are in shallow frames at all, not only drowned by the deep
#       ones. OUT defaults to $TACTILE_SURFACE_SHALLOW or
#       ~/.cache/tactile-rs/surface-shallow.
#   bash scripts/surface-subset.sh train N [OUT]
#       N `train` rows drawn at random (seed 7, kept in the set's order) and
#       every `val` row. Networks on 1,500 and 3,000 of the 6,000 `train`
#       frames (steps p64-k9-n1500 and p64-k9-n3000) say how the errors on
#       `val` fall with more frames. OUT defaults to
#       ~/.cache/tactile-rs/surface-train-N.
#
# OUT is outside the project (the real frames are never copied into it).
# Prints OUT; an existing OUT is kept (idempotent), a new one is staged and
# renamed by the import.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${TACTILE_SHARED_REAL:-../shared/real}
CACHE=${XDG_CACHE_HOME:-$HOME/.cache}/tactile-rs
usage="usage: surface-subset.sh shallow [OUT] | train N [OUT]"
case "${1:-}" in
    shallow)
        MAX_DEPTH_MM=2.34
        FILTER=(shallow "$MAX_DEPTH_MM")
        SENSOR="tactip331-surface taps shallower than $MAX_DEPTH_MM mm (scripts/surface-subset.sh shallow)"
        OUT=${2:-${TACTILE_SURFACE_SHALLOW:-$CACHE/surface-shallow}}
        ;;
    train)
        N=${2:?$usage}
        [[ "$N" =~ ^[1-9][0-9]*$ ]] || { echo "N must be a whole number of train frames, got '$N'" >&2; exit 2; }
        FILTER=(train "$N")
        SENSOR="tactip331-surface: $N train frames drawn at random (seed 7) and every val frame (scripts/surface-subset.sh train $N)"
        OUT=${3:-$CACHE/surface-train-$N}
        ;;
    *)
        echo "$usage" >&2
        exit 2
        ;;
esac
if [ ! -f "$OUT/labels.csv" ]; then
    cargo build --release -q -p tactile
    BIN="${CARGO_TARGET_DIR:-target}/release/tactile"
    labels=$(mktemp --suffix=.csv)
    trap 'rm -f "$labels"' EXIT
    # The import names each frame by its file name in a `frame` column.
    python3 - "$REAL/tactip331-surface/labels.csv" "$labels" "${FILTER[@]}" <<'PY'
import csv, random, sys
src, out, mode, arg = sys.argv[1:5]
with open(src, newline="") as f:
    rows = list(csv.DictReader(f))
if mode == "shallow":
    keep = {i for i, r in enumerate(rows) if float(r["depth_mm"]) < float(arg)}
else:
    train = [i for i, r in enumerate(rows) if r["split"] == "train"]
    if int(arg) > len(train):
        sys.exit(f"N = {arg}: the set has {len(train)} train frames")
    chosen = set(random.Random(7).sample(train, int(arg)))
    keep = {i for i, r in enumerate(rows) if r["split"] != "train" or i in chosen}
cols = [c for c in rows[0] if c != "file"]
with open(out, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["frame"] + cols)
    for i, r in enumerate(rows):
        if i in keep:
            w.writerow([r["file"].rsplit("/", 1)[-1]] + [r[c] for c in cols])
PY
    mkdir -p "$(dirname "$OUT")"
    "$BIN" dataset from-video --video "$REAL/tactip331-surface/frames" --labels "$labels" --kind tactip \
        --sensor "$SENSOR" --out "$OUT" >&2
fi
echo "$OUT"
