#!/usr/bin/env python3
"""Give every numeric flag of every `tactile` command a value far out of
range (1e300, or `1e300,1e301` for a range; `--value` and `--pair` give
others, such as -0.5 or nan) and print what each says.

A probe, not a test: it finds refusals that print a number in hundreds of
digits, flags that are accepted and ignored (exit 0), and messages that do
not name the flag. Each line: LONG when a message holds a run of 16 zeros,
the exit status, the command, the flag and the message's last error line.

    python3 scripts/probe-flags.py [--bin target/release/tactile]

It makes a tiny TacTip and visuo-tactile dataset in a temporary folder and
runs there, so nothing is written beside the repository.
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    default_bin = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "release/tactile"
    ap.add_argument("--bin", default=str(default_bin), help="the tactile binary")
    ap.add_argument("--timeout", type=float, default=120, help="seconds per command")
    ap.add_argument("--value", default="1e300",
                    help="the value given to each numeric flag (e.g. -0.5 or nan)")
    ap.add_argument("--pair", default="1e300,1e301",
                    help="the value given to each numeric list flag (e.g. -0.5,0.3)")
    args = ap.parse_args()
    tactile = str(Path(args.bin).resolve())
    if not Path(tactile).is_file():
        sys.exit(f"{tactile}: no tactile binary (cargo build --release -p tactile, or give --bin)")

    def call(argv, cwd):
        return subprocess.run([tactile, *argv], capture_output=True, text=True, cwd=cwd,
                              timeout=args.timeout)

    def commands(path):
        text = call([*path, "--help"], ROOT).stdout
        m = re.search(r"Commands:\n(.*?)\n\n", text, re.S)
        if not m:
            return [path]
        names = [line.split()[0] for line in m.group(1).splitlines() if line.strip()]
        return [c for n in names if n != "help" for c in commands([*path, n])]

    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for argv in (["synth", "tactip", "--count", "40", "--out", "tactip"],
                     ["synth", "visuotactile", "--sequences", "4", "--out", "vt"]):
            r = call(argv, work)
            if r.returncode:
                sys.exit(f"tactile {' '.join(argv)}: {r.stderr.strip()}")
        models = ROOT / "models"
        for path in commands([]):
            cmd = " ".join(path)
            help_text = call([*path, "--help"], ROOT).stdout
            paper_b = any(k in cmd for k in ("detector", "segmenter", "depth", "visuotactile",
                                              "gelsight", "eval", "run"))
            calibration = "calibrat" in cmd

            def value(flag):
                if flag == "data":
                    if calibration:
                        return str(ROOT.parent / "shared/real/gelsight-ball")
                    return str(work / ("vt" if paper_b else "tactip"))
                if flag == "out":
                    return str(work / "out" / "x")
                if flag in ("model", "encoder"):
                    return str(models / ("detector" if paper_b else "cae-synth"))
                return str(work / "missing")

            usage = re.search(r"Usage: (.*)", help_text).group(1)
            required = re.findall(r"--([a-z-]+) <", usage.split("[OPTIONS]")[-1])
            base = ["--count", "8"] if path[:1] == ["synth"] else []
            for flag in required:
                base += [f"--{flag}", value(flag)]
            for m in re.finditer(r"^\s+--([a-z0-9-]+) <[A-Z_0-9]+>(.*?)(?=^\s+-|\Z)",
                                 help_text, re.S | re.M):
                flag, body = m.group(1), m.group(2)
                default = re.search(r"\[default: ([^\]]*)\]", body)
                if not default or not re.fullmatch(r"-?[0-9]*\.?[0-9]+(e-?[0-9]+)?(,.*)?",
                                                   default.group(1).split()[0]):
                    continue
                given = args.pair if "," in default.group(1) else args.value
                try:
                    r = call([*path, *base, f"--{flag}", given], work)
                except subprocess.TimeoutExpired:
                    print(f"     TIMEOUT {cmd} --{flag}")
                    continue
                lines = (r.stderr + r.stdout).strip().splitlines()
                long = any("0" * 16 in line for line in lines)
                errors = [line for line in lines if "rror" in line] or lines[-1:] or ["?"]
                print(f"{'LONG' if long else '    '} {r.returncode} {cmd} --{flag} | {errors[-1][:200]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
