"""scripts/surface-half-turn.py (issue 34): the half turn, its centre and
the table it prints."""

import subprocess
import sys

import numpy as np

from conftest import script


def test_the_half_turn_and_its_centre_are_found():
    ht = script("surface-half-turn")
    # Blobs in pairs symmetric about (row 31, column 27.5) of a 60x66
    # picture (its own centre is (29.5, 32.5)), plus a lone blob that breaks
    # the symmetry a little.
    h, w = 60, 66
    yy, xx = np.mgrid[0:h, 0:w]
    picture = np.zeros((h, w), np.float32)
    rng = np.random.default_rng(3)
    for _ in range(12):
        y, x = rng.uniform(8, 52), rng.uniform(8, 46)
        for cy, cx in [(y, x), (62 - y, 55 - x)]:
            picture += np.exp(-((yy - cy) ** 2 + (xx - cx) ** 2) / 4.0)
    picture += 0.3 * np.exp(-((yy - 10) ** 2 + (xx - 60) ** 2) / 4.0)
    twice, c_best, c_here = ht.best_centre(picture, reach=6)
    assert twice == (62, 55)
    assert c_best > 0.9 and c_here < c_best
    # Pixel (i, j) comes from (62 - i, 55 - j): turned twice, the pixels whose
    # source lies inside are back where they were.
    frame = (rng.uniform(0, 255, (h, w))).astype(np.uint8)
    turned = ht.half_turn(frame, twice)
    assert turned[10, 20] == frame[52, 35] and turned[0, 0] == 0
    back = ht.half_turn(turned, twice)
    assert np.array_equal(back[3:60, 0:56], frame[3:60, 0:56])
    assert not back[0:3].any() and not back[:, 56:].any()
    assert ht.HALF_TURN_SIGN.tolist() == [1, -1, -1, -1, -1, 1]


def test_the_script_scores_a_pose_network_on_recorded_and_turned_frames(root, shared_real):
    out = subprocess.run(
        [sys.executable, str(root / "scripts" / "surface-half-turn.py"),
         "--data", str(shared_real / "tactip331-surface"),
         "--model", str(root / "models" / "pose-surface"), "--every", "100"],
        capture_output=True, text=True, check=True,
    ).stdout
    rows = {line.split("|")[1].strip(): [float(v) for v in line.split("|")[2:-1]]
            for line in out.splitlines() if line.startswith("| ") and not line.startswith("| frames")}
    assert list(rows) == ["as recorded", "turned half a turn (labels turned)", "no frame (`train` median)"]
    assert "20 `val` frames (every 100-th)" in out
    # The shipped network (it fitted these frames) against reading none:
    # every target far better; a bad --every is refused.
    assert all(r < n / 2 for r, n in zip(rows["as recorded"], rows["no frame (`train` median)"]))
    bad = subprocess.run([sys.executable, str(root / "scripts" / "surface-half-turn.py"), "--data", "x",
                          "--model", "y", "--every", "0"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--every must be at least 1" in bad.stderr
