"""scripts/surface-shift-average.py (issue 34): frames moved under the tip,
and the table of estimates averaged over moved copies."""

import subprocess
import sys

import numpy as np

from conftest import script


def test_a_moved_frame_keeps_its_pixels_and_fills_the_edge_black():
    sa = script("surface-shift-average")
    frames = np.arange(2 * 5 * 7, dtype=np.uint8).reshape(2, 5, 7) + 1
    right = sa.moved(frames, 2, 0)
    assert np.array_equal(right[:, :, 2:], frames[:, :, :5]) and not right[:, :, :2].any()
    up = sa.moved(frames, 0, -3)
    assert np.array_equal(up[:, :2], frames[:, 3:]) and not up[:, 2:].any()
    assert np.array_equal(sa.moved(sa.moved(frames, 1, 1), -1, -1)[:, :4, :6], frames[:, :4, :6])


def test_the_script_averages_moved_copies_of_held_out_frames(root, shared_real):
    script = str(root / "scripts" / "surface-shift-average.py")
    out = subprocess.run(
        [sys.executable, script, "--model", str(root / "models" / "cae-surface-train"),
         "--data", str(shared_real / "tactip331-surface"), "--shifts", "8", "--every", "100"],
        capture_output=True, text=True, check=True,
    ).stdout
    rows = {line.split("|")[2].strip(): [float(v) for v in line.split("|")[3:-1]]
            for line in out.splitlines() if line.startswith("| cae-surface-train |")}
    assert list(rows) == ["the frame as it is", "one copy moved 8 px right", "average of five, 8 px"]
    assert "20 `val` frames (every 100-th)" in out
    # A model that never saw these frames reads them far better than no
    # frame would (twist 2.44 deg, slide 2.5 mm); five reads take longer.
    plain, average = rows["the frame as it is"], rows["average of five, 8 px"]
    assert plain[5] < 2.0 and plain[3] < 1.0
    assert average[-1] > plain[-1]
    bad = subprocess.run([sys.executable, script, "--model", "m", "--data", "d", "--shifts", "0,8"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "each shift must be 1 to 64 pixels" in bad.stderr


def test_a_pose_network_is_read_through_its_own_estimator(root, shared_real):
    # The shipped pair trained on every frame, so only that it runs is
    # asserted here, not its errors.
    out = subprocess.run(
        [sys.executable, str(root / "scripts" / "surface-shift-average.py"), "--model", str(root / "models" / "pose-surface"),
         "--data", str(shared_real / "tactip331-surface"), "--shifts", "4", "--every", "200"],
        capture_output=True, text=True, check=True,
    ).stdout
    assert "10 `val` frames (every 200-th)" in out and "| pose-surface | average of five, 4 px |" in out
