#!/usr/bin/env bash
# Run every test of the project on a fresh machine:
#  1. installs onnxruntime (and onnx, for onnx.checker) from PyPI when
#     ORT_DYLIB_PATH is unset;
#  2. runs the Rust workspace's tests in the release profile (the one
#     profile this project builds burn in);
#  3. builds the Python package (crates/tactile-py, with maturin from PyPI)
#     into a fresh virtual environment, sharing the cargo target folder so
#     burn is not built again (with rosbags, mcap-ros2-support and
#     websockets from PyPI), and runs its pytest suite against the
#     `tactile` binary built in step 2.
#  0. installs FFmpeg from the distribution's packages when missing (video
#     sources are tested through it);
# Arguments go to `cargo test`.
set -euo pipefail
cd "$(dirname "$0")/.."
root="$(pwd)"
bash scripts/install-ffmpeg.sh
if [ -z "${ORT_DYLIB_PATH:-}" ]; then
    eval "$(bash scripts/install-ort.sh)"
    export ORT_DYLIB_PATH TACTILE_PYTHONPATH
fi
cargo test --release --workspace "$@"

target="${CARGO_TARGET_DIR:-$root/target}"
venv="$(mktemp -d "${TMPDIR:-/tmp}/tactile-venv.XXXXXX")"
trap 'rm -rf "$venv"' EXIT
echo "Python package: building into a fresh virtual environment ($venv)" >&2
python3 -m venv "$venv"
export PATH="$venv/bin:$PATH" VIRTUAL_ENV="$venv"
pip=("$venv/bin/python" -m pip --disable-pip-version-check --quiet)
# (Pillow: scripts/gelsight_independent.py reads the real ball presses.)
"${pip[@]}" install "maturin>=1.16,<2" "numpy>=1.21" "pytest>=7" "pillow>=10"
# Independent readers and writers of ROS 2 bags, the Foxglove SDK (its MCAP
# recordings) and a WebSocket client, for
# the robot I/O checks (tests/test_robots.py).
"${pip[@]}" install "mcap-ros2-support==0.6.0" "rosbags==0.11.9" "websockets==17.4" "foxglove-sdk==0.30.3"
"${pip[@]}" install --no-build-isolation "$root/crates/tactile-py"
TACTILE_BIN="$target/release/tactile" "$venv/bin/python" -m pytest -q "$root/crates/tactile-py/tests"
