#!/usr/bin/env bash
# The surface set's shallow taps as a dataset of their own (issue 34): the
# rows of ../shared/real/tactip331-surface with depth_mm below 2.34 (the
# upper bound of `val`'s shallowest third in `tactile bench surface`'s
# tables; 1,965 `train` and 668 `val` frames), labels and split kept,
# written by `tactile dataset from-video` from the set's frame folder.
# A network trained on them alone (scripts/surface.sh, step p64-k9-shallow)
# says whether slide and twist are in shallow frames at all, not only
# drowned by the deep ones.
#
#   bash scripts/surface-shallow-set.sh [OUT]
#
# OUT defaults to $TACTILE_SURFACE_SHALLOW or ~/.cache/tactile-rs/surface-shallow,
# outside the project (the real frames are never copied into it). Prints
# OUT; an existing OUT is kept (idempotent), a new one is staged and renamed
# by the import.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${TACTILE_SHARED_REAL:-../shared/real}
OUT=${1:-${TACTILE_SURFACE_SHALLOW:-${XDG_CACHE_HOME:-$HOME/.cache}/tactile-rs/surface-shallow}}
MAX_DEPTH_MM=2.34
if [ ! -f "$OUT/labels.csv" ]; then
    cargo build --release -q -p tactile
    BIN="${CARGO_TARGET_DIR:-target}/release/tactile"
    labels=$(mktemp --suffix=.csv)
    trap 'rm -f "$labels"' EXIT
    # The import names each frame by its file name in a `frame` column.
    python3 - "$REAL/tactip331-surface/labels.csv" "$MAX_DEPTH_MM" "$labels" <<'PY'
import csv, sys
src, max_depth, out = sys.argv[1], float(sys.argv[2]), sys.argv[3]
with open(src, newline="") as f:
    rows = list(csv.DictReader(f))
cols = [c for c in rows[0] if c != "file"]
with open(out, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["frame"] + cols)
    for r in rows:
        if float(r["depth_mm"]) < max_depth:
            w.writerow([r["file"].rsplit("/", 1)[-1]] + [r[c] for c in cols])
PY
    mkdir -p "$(dirname "$OUT")"
    "$BIN" dataset from-video --video "$REAL/tactip331-surface/frames" --labels "$labels" --kind tactip \
        --sensor "tactip331-surface taps shallower than $MAX_DEPTH_MM mm (scripts/surface-shallow-set.sh)" \
        --out "$OUT" >&2
fi
echo "$OUT"
