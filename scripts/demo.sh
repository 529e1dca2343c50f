#!/usr/bin/env bash
# The demo, on shipped files only (nothing is downloaded):
# 1. paper A: the shipped CAE encoder and its 7-shape head classify virtual
#    TacTip frames, printing each frame's 16 features and class;
# 2. paper B: the palpation pipeline runs over a short shipped virtual
#    palpation video (12 frames): the detector on every frame, then the
#    segmenter, its direction and the depth network on the tendon frames,
#    printing a record per frame and the speed summary.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo run --release -p tactile -- demo "$@"
echo
echo "Paper B palpation pipeline on samples/palpation (burn flex):"
records="$(mktemp -d)/palpation.jsonl"
cargo run --release -q -p tactile -- run --data samples/palpation --runtime burn-flex --out "$records"
cut -c1-160 "$records"
