#!/usr/bin/env python3
"""Are the field's windows independent of units (issue 29)? Each model is
run as written and with one coordinate in other units (the coordinate
replaced by `q / s`, its initial values multiplied by s), by the field
and by direct DOP853, at rtol 1e-9 ... 1e-12 with a negligible atol
(1e-20: the absolute tolerance is the one part of the error control that
units do change). Prints the field's windows (and steps) and direct's
steps, as written / rescaled. S = 1024 (a power of two: the rescaled
arithmetic is the original's up to the linear solves' rounding).

Usage (from the repository root, after `cargo build --release -p lagc`):

    python3 scripts/field_units.py [S]
"""

import json
import os
import subprocess
import sys
import tempfile

S = sys.argv[1] if len(sys.argv) > 1 else "1024"
LAGC = os.environ.get("LAGC", "target/release/lagc")
RTOLS = ["1e-9", "1e-10", "1e-11", "1e-12"]

MODELS = {
    "stiff_joint (b)": (
        "tests/data/stiff_joint.lag",
        [("coord a, b;", f"param s = {S};\ncoord a, bs;\nlet b = bs / s;"),
         ("b = 1.001, a' = 0, b' = 0", f"bs = 1.001 * {S}, a' = 0, bs' = 0")]),
    "pendulum_2 (th2)": (
        "benches/data/pendulum_2.lag",
        [("coord th1, th2;", f"param s = {S};\ncoord th1, th2s;\nlet th2 = th2s / s;"),
         ("th2 = 0.2, th1' = 0, th2' = 0", f"th2s = 0.2 * {S}, th1' = 0, th2s' = 0")]),
    "double_pendulum_mass_loss (a)": (
        "benches/data/double_pendulum_mass_loss.lag",
        [("coord a, b;", f"param s = {S};\ncoord as_, b;\nlet a = as_ / s;"),
         ("initial a = 1, b = 0.5, a' = 0", f"initial as_ = {S}, b = 0.5, as_' = 0")]),
}


def summary(model, method, rtol):
    p = subprocess.run(
        [LAGC, "run", model, "--", "--method", method, "--rtol", rtol,
         "--atol", "1e-20", "--samples", "2", "--summary", "json"],
        capture_output=True, text=True)
    if p.returncode != 0:
        return None
    return json.loads([l for l in p.stderr.splitlines() if l.startswith("{")][-1])


def main():
    print("| model | rtol | field windows | field steps (+rej.) | direct steps |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, (path, edits) in MODELS.items():
            text = open(path).read()
            for old, new in edits:
                assert old in text, (path, old)
                text = text.replace(old, new)
            rescaled = os.path.join(tmp, os.path.basename(path))
            with open(rescaled, "w") as f:
                f.write(text)
            for rtol in RTOLS:
                pair = [summary(m, "field", rtol) for m in (path, rescaled)]
                cells = [" / ".join("fail" if s is None else str(s["windows"]) for s in pair),
                         " / ".join("fail" if s is None else
                                    f"{s['steps']} (+{s['rejected_steps']})" for s in pair)]
                pair = [summary(m, "direct", rtol) for m in (path, rescaled)]
                cells.append(" / ".join("fail" if s is None else str(s["steps"]) for s in pair))
                print(f"| {name} | {rtol} | " + " | ".join(cells) + " |", flush=True)


main()
