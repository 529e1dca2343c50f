#!/usr/bin/env bash
# Install what the ONNX side needs, from PyPI only, into .ort/ (or $TACTILE_ORT_DIR):
#  - onnxruntime==1.31.1, whose wheel carries onnxruntime/capi/libonnxruntime.so.1.31.1
#    (loaded by the `ort` crate through ORT_DYLIB_PATH);
#  - onnx (with numpy and protobuf) for `onnx.checker` full checks in the tests.
# Prints the `export` line for ORT_DYLIB_PATH and PYTHONPATH; idempotent.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
dir="${TACTILE_ORT_DIR:-$root/.ort}"
lib="$dir/onnxruntime/capi/libonnxruntime.so.1.31.1"
if [ ! -f "$lib" ]; then
    echo "installing onnxruntime==1.31.1 (PyPI wheel) into $dir" >&2
    python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore --no-deps --target "$dir" onnxruntime==1.31.1 >&2
fi
if [ ! -d "$dir/onnx" ]; then
    echo "installing onnx (for onnx.checker) into $dir" >&2
    python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore --target "$dir" onnx==1.23.2 >&2
fi
[ -f "$lib" ] || { echo "error: $lib missing after install" >&2; exit 1; }
echo "export ORT_DYLIB_PATH='$lib' TACTILE_PYTHONPATH='$dir'"
