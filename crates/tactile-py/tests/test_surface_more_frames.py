"""scripts/surface-more-frames.py (issue 34): the power law fitted to a
bench's errors by training frames, and the frames it says a goal needs."""

import json
import subprocess
import sys


def run(root, *args):
    return subprocess.run([sys.executable, str(root / "scripts" / "surface-more-frames.py"), *args],
                          capture_output=True, text=True)


def test_a_known_power_law_is_recovered(root, tmp_path):
    # Every target's error is 3 * frames^-0.1, but depth, which meets its
    # goal (0.13 mm) at every count.
    law = lambda n: 3.0 * n ** -0.1  # noqa: E731
    rows = [{"model": f"m{n}", "metrics": {"mae": [0.1] + [law(n)] * 5}} for n in (1000, 2000, 4000)]
    (tmp_path / "rows.json").write_text(json.dumps(rows))
    r = run(root, str(tmp_path / "rows.json"), "--frames", "m4000=4000", "m1000=1000", "m2000=2000")
    assert r.returncode == 0, r.stderr
    lines = {line.split(" | ")[0].strip("| "): line for line in r.stdout.splitlines()[2:]}
    cells = lines["shear_theta_deg"].strip("| ").split(" | ")
    # Columns in order of frames; the exponent; the law at 8,000 frames;
    # the goal; 0.9 = 3 n^-0.1 at n = (3 / 0.9)^10, about 169,000 frames.
    assert cells[1:4] == [f"{law(n):.3f}" for n in (1000, 2000, 4000)]
    assert cells[4] == "-0.100" and cells[5] == f"{law(8000):.3f}" and cells[6] == "0.9"
    assert abs(float(cells[7]) - (3 / 0.9) ** 10) / (3 / 0.9) ** 10 < 0.02, cells
    assert lines["depth_mm"].rstrip(" |").endswith("met")


def test_bad_input_is_named(root, tmp_path):
    rows = tmp_path / "rows.json"
    rows.write_text(json.dumps([{"model": "a", "metrics": {"mae": [0.1] * 6}}]))
    r = run(root, str(rows), "--frames", "b=100", "a=200")
    assert r.returncode != 0 and "no row for b" in r.stderr
    r = run(root, str(rows), "--frames", "a=100")
    assert r.returncode != 0 and "at least two numbers of frames" in r.stderr
    r = run(root, str(rows), "--frames", "a=many")
    assert r.returncode != 0 and "MODEL=FRAMES" in r.stderr
    (tmp_path / "bad.json").write_text("{")
    r = run(root, str(tmp_path / "bad.json"), "--frames", "a=1", "b=2")
    assert r.returncode != 0 and "not a surface bench's rows" in r.stderr
