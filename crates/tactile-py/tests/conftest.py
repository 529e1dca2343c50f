"""Shared fixtures: the repository's shipped models and samples, and the
`tactile` command line the package is compared against."""

from __future__ import annotations

import functools
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import tactile

ROOT = Path(__file__).resolve().parents[3]
# The project's real sensor data (`../shared/real` beside the clone, or
# TACTILE_SHARED_REAL).
SHARED_REAL = Path(os.environ.get("TACTILE_SHARED_REAL", ROOT.parent / "shared" / "real"))


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def shared_real() -> Path:
    return SHARED_REAL


@pytest.fixture(scope="session")
def tactile_bin() -> Path:
    """The `tactile` binary built from the same tree (TACTILE_BIN, or the
    release build in the cargo target folder)."""
    env = os.environ.get("TACTILE_BIN")
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    candidates = [Path(env)] if env else [target / "release" / "tactile"]
    for c in candidates:
        if c.is_file():
            return c
    found = shutil.which("tactile")
    if found:
        return Path(found)
    pytest.fail(
        "the tactile binary was not found: build it (cargo build --release -p tactile) "
        "or set TACTILE_BIN"
    )


def run_cli(binary: Path, *args: str) -> str:
    r = subprocess.run([str(binary), *args], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, f"tactile {' '.join(args)} failed:\n{r.stderr}"
    return r.stdout


def run_python(call: str) -> subprocess.Popen:
    """`call` in a new interpreter that turns Ctrl-C into KeyboardInterrupt
    (a shell's background job inherits SIGINT ignored, and Python then
    installs no handler: restored, as at a terminal)."""
    code = (
        "import signal, tactile\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        f"{call}\n"
    )
    return subprocess.Popen([sys.executable, "-c", code], stderr=subprocess.PIPE, text=True)


def interrupt(p: subprocess.Popen) -> str:
    """Ctrl-C to `p`; its standard error once it ended with KeyboardInterrupt."""
    p.send_signal(signal.SIGINT)
    try:
        _, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        raise
    assert p.returncode != 0 and "KeyboardInterrupt" in err, err
    return err


def interrupt_after(p: subprocess.Popen, running_s: float, within_s: float) -> str:
    """Ctrl-C to `p` once it has run `running_s` seconds (and still runs),
    which must end it with KeyboardInterrupt within `within_s` seconds;
    its standard error."""
    time.sleep(running_s)
    assert p.poll() is None, p.stderr.read()
    t0 = time.time()
    err = interrupt(p)
    assert time.time() - t0 < within_s, f"stopped {time.time() - t0:.1f} s after Ctrl-C"
    return err


@pytest.fixture(scope="session")
def palpation_frames(root: Path) -> list[np.ndarray]:
    """The shipped sample video (12 frames, 320x180), as RGB arrays."""
    files = sorted((root / "samples" / "palpation").glob("*.png"))
    assert len(files) == 12
    return [tactile.read_rgb(f) for f in files]


@pytest.fixture(scope="session")
def pipeline(root: Path) -> tactile.Pipeline:
    return tactile.Pipeline(root / "models", "onnx")


@pytest.fixture(scope="session")
def tendon_frame_640(root: Path) -> np.ndarray:
    """A 640x360 tendon frame of the virtual sensor at full press."""
    v = tactile.synth.visuotactile(sequences=1, frames_per_sequence=9, seed=5, progress=False)
    tendon = np.flatnonzero(v["tendon"])
    assert tendon.size > 0
    return v["frames"][tendon[len(tendon) // 2]]


def write_png(path: Path, pixels: np.ndarray) -> None:
    """An 8-bit grey `(H, W)` or RGB `(H, W, 3)` PNG, written with the
    standard library alone (the tests install no image library): the
    independent TacTip's writer."""
    script("tactip_independent").write_png(path, pixels)


@functools.cache
def script(name: str):
    """`scripts/<name>.py` (such as `tactip_independent`, the virtual TacTip
    written from the spec alone), loaded once (every `write_png` call uses
    that one)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def stand_in_tools(box: Path, fake_tactile: str, **env: str) -> dict:
    """The environment in which a script of `scripts/` run in the sandbox
    `box` finds `fake_tactile` (a Python program's text, its first line
    `#!PYTHON`) as its release `tactile` and a `cargo` that builds nothing,
    each call logged to `box/log` by the stand-in; `env` adds variables."""
    bin_dir, release = box / "bin", box / "target" / "release"
    bin_dir.mkdir()
    release.mkdir(parents=True)
    (bin_dir / "cargo").write_text("#!/bin/sh\nexit 0\n")
    (release / "tactile").write_text(fake_tactile.replace("PYTHON", sys.executable, 1))
    for f in [bin_dir / "cargo", release / "tactile"]:
        f.chmod(0o755)
    return dict(os.environ, PATH=f"{bin_dir}:{os.environ['PATH']}", CARGO_TARGET_DIR=str(box / "target"),
                ORT_DYLIB_PATH="unused", PYTHON=sys.executable, FAKE_LOG=str(box / "log"), **env)
