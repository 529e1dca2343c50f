#!/usr/bin/env bash
# Run every test of the workspace on a fresh machine: installs onnxruntime
# (and onnx, for onnx.checker) from PyPI when ORT_DYLIB_PATH is unset, then
# runs the whole test suite in the release profile (the one profile this
# project builds burn in).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${ORT_DYLIB_PATH:-}" ]; then
    eval "$(bash scripts/install-ort.sh)"
    export ORT_DYLIB_PATH TACTILE_PYTHONPATH
fi
cargo test --release --workspace "$@"
