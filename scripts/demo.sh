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
# The binary is built with the features of the whole workspace, as
# `scripts/test.sh` builds it: `cargo run -p tactile` would unify features
# over `tactile` alone (the Python crate's macros switch on one more feature
# of `syn`, under burn's derive macros), so a fresh machine would compile
# burn twice, once for the demo and once for the tests.
tactile="$(cargo build --release --workspace --bin tactile --message-format=json-render-diagnostics |
    python3 -c '
import json, sys
for line in sys.stdin:
    message = json.loads(line)
    if message.get("reason") == "compiler-artifact" and message["target"]["name"] == "tactile" and message.get("executable"):
        print(message["executable"])')"
if [ -z "$tactile" ]; then
    echo "demo: cargo built no 'tactile' binary" >&2
    exit 1
fi
"$tactile" demo "$@"
echo
echo "Paper B palpation pipeline on samples/palpation (burn flex):"
records_dir="$(mktemp -d)"
trap 'rm -rf "$records_dir"' EXIT
records="$records_dir/palpation.jsonl"
"$tactile" run --data samples/palpation --runtime burn-flex --out "$records"
cut -c1-160 "$records"
