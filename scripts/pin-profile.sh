#!/usr/bin/env bash
# Frames of another sensor given to paper A's models (docs/bench-pin-profile.md):
# the shipped TacTip models' pin profiles against the real TacTip sets, the
# real GelSight ball presses and fresh virtual TacTip frames (a seed none of
# the models trained on). Then, to see frames no profile was fitted on, a
# copy of models/pose-surface profiled on the surface set's `train` rows
# alone (as models/cae-surface-train is), against the 2,000 `val` frames
# neither saw.
#
#   bash scripts/pin-profile.sh [DATA_DIR]
#
# DATA_DIR (default data/pin-profile) holds the virtual frames and the copy.
set -euo pipefail
cd "$(dirname "$0")/.."
data="${1:-data/pin-profile}"
real="${TACTILE_SHARED_REAL:-../shared/real}"
cargo build --release -p tactile
tactile="${CARGO_TARGET_DIR:-target}/release/tactile"
rm -rf "$data"
mkdir -p "$data"
"$tactile" synth tactip --count 400 --seed 4242 --out "$data/virtual-tactip"
sets=("$real/tactip331-surface" "$real/tactip127-edge" "$real/polic-shapes"
      "$real/gelsight-ball/frames" "$data/virtual-tactip")
"$tactile" bench pin-profile \
    --models models/cae-synth models/cae-shapes models/cae-edge models/pose-edge models/cae-surface models/pose-surface \
    --data "${sets[@]}" --frames 400 --out docs/bench-pin-profile.md
cp -r models/pose-surface "$data/pose-surface-train"
"$tactile" train profile --model "$data/pose-surface-train" --data "$real/tactip331-surface" --split train
"$tactile" bench pin-profile --models "$data/pose-surface-train" models/cae-surface-train --data "$real/tactip331-surface" --split val \
    --frames 8000 --out docs/bench-pin-profile-heldout.md
