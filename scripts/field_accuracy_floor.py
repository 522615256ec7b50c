#!/usr/bin/env python3
"""No accuracy floor (issue 29): every example with an exact solution, run
by the field method at rtol 1e-12 (atol 1e-14, 101 samples), its largest
error against the exact solution (the runtime's measure: absolute where
|x| < 1, relative otherwise) over 10·rtol or not; and the same for direct
DOP853 beside it. Prints a Markdown table (docs/BENCHMARKS.md, section 0).

Usage (from the repository root, after `cargo build --release -p lagc`):

    python3 scripts/field_accuracy_floor.py [--rtol 1e-12] [examples/NAME.lag ...]

Exit status 0 when every field run is within 10·rtol.
"""

import glob
import json
import os
import subprocess
import sys


def summary(model, method, rtol):
    run = subprocess.run(
        [os.environ.get("LAGC", "target/release/lagc"), "run", model, "--", "--method", method,
         "--rtol", str(rtol), "--atol", str(rtol * 1e-2), "--samples", "101",
         "--quiet", "--summary", "json"],
        capture_output=True, text=True)
    lines = [l for l in run.stderr.splitlines() if l.startswith("{")]
    if not lines:
        tail = run.stderr.strip().splitlines()[-1:] or ["?"]
        return None, f"exit {run.returncode}: {tail[0]}"
    return json.loads(lines[-1]), None


def main():
    args = sys.argv[1:]
    rtol = 1e-12
    if args[:1] == ["--rtol"]:
        rtol, args = float(args[1]), args[2:]
    models = args or sorted(m for m in glob.glob("examples/*.lag")
                            if any(l.startswith("exact") for l in open(m)))
    print(f"| example | field error | field / rtol | field steps (+rejected), windows | DOP853 error | verdict |")
    print("|---|---|---|---|---|---|")
    over = 0
    for model in models:
        name = model.split("/")[-1][:-4]
        field, why = summary(model, "field", rtol)
        direct, _ = summary(model, "direct", rtol)
        derr = f"{direct['exact_error']:.2e}" if direct and direct.get("exact_error") is not None else "-"
        if field is None or field.get("exact_error") is None:
            print(f"| {name} | - | - | - | {derr} | **failed** ({why}) |")
            over += 1
            continue
        e = field["exact_error"]
        windows = field.get("windows")
        verdict = "within" if e <= 10 * rtol else "**over**"
        over += e > 10 * rtol
        print(f"| {name} | {e:.2e} | {e / rtol:.1f} | {field['steps']} (+{field['rejected_steps']}), "
              f"{windows if windows is not None else '-'} | {derr} | {verdict} |")
    print()
    print(f"{len(models) - over} of {len(models)} within 10·rtol at rtol {rtol:g}.")
    sys.exit(1 if over else 0)


if __name__ == "__main__":
    main()
