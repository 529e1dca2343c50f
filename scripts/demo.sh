#!/usr/bin/env bash
# The demo: the shipped CAE encoder and shape head classify TacTip frames
# of paper A's shapes set, printing each frame's 16 features and class.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo run --release -p tactile -- demo "$@"
