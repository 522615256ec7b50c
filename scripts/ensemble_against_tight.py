#!/usr/bin/env python3
"""An ensemble's members against tight direct runs (issue 27, item 3).

Runs `lagc run MODEL --ensemble K -o CSV` at the given tolerance, then each
member's own direct integration from its initial row at rtol 1e-12 (and,
with --own, at the ensemble's rtol: direct integration's own error), and
prints the largest difference |a - b| / max(|b|, 1) over members, samples
and state components.

  scripts/ensemble_against_tight.py target/release/lagc \
      examples/spherical_pendulum.lag --ensemble 1000 --spread 1e-2 \
      --rtol 1e-8 --samples 2 [--own] [--init a=1.5707963267948966 ...]
"""

import argparse
import csv
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile


def model_binary(lagc, model, tmp):
    """The model's binary that `lagc run` builds with this checkout's
    runtime (found in lagc's cache by the runtime's sources), copied: a
    `lagc run` a process costs its derivation each time."""
    subprocess.run([lagc, "run", model, "--samples", "1", "--quiet"],
                   capture_output=True, check=True)
    cache = os.path.expanduser("~/.cache/lagc")
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "runtime", "src")
    runtimes = [
        d for d in os.listdir(cache) if d.startswith("runtime-")
        and subprocess.run(["diff", "-rq", here, os.path.join(cache, d, "src")],
                           capture_output=True).returncode == 0
    ]
    for crate in os.listdir(os.path.join(cache, "crates")):
        toml = open(os.path.join(cache, "crates", crate, "Cargo.toml")).read()
        if any(f'"../../{r}"' in toml for r in runtimes):
            stem = os.path.splitext(os.path.basename(model))[0].replace("_", "-")
            if crate.rsplit("-", 1)[0] == f"lag-{stem}":
                binary = os.path.join(tmp, crate)
                shutil.copy(os.path.join(cache, "target", "release", crate), binary)
                return binary
    sys.exit(f"no binary of {model} built with this runtime in {cache}")


def direct(binary, names, row, samples, rtol):
    inits = []
    for name, value in zip(names, row):
        inits += ["--init", f"{name}={value!r}"]
    out = subprocess.run(
        [binary, "--method", "direct", "--rtol", repr(rtol),
         "--atol", repr(rtol * 1e-2), "--samples", str(samples)] + inits,
        capture_output=True, text=True, check=True,
    ).stdout
    table = list(csv.reader(io.StringIO(out)))
    header = table[0]
    columns = [header.index(n) for n in names]
    return [[float(r[c]) for c in columns] for r in table[1:]]


def largest(a_rows, b_rows):
    worst = 0.0
    for a, b in zip(a_rows, b_rows):
        for u, v in zip(a, b):
            worst = max(worst, abs(u - v) / max(abs(v), 1.0))
    return worst


def main():
    p = argparse.ArgumentParser()
    p.add_argument("lagc")
    p.add_argument("model")
    p.add_argument("--ensemble", type=int, required=True)
    p.add_argument("--spread", required=True)
    p.add_argument("--rtol", type=float, required=True)
    p.add_argument("--samples", type=int, default=2)
    p.add_argument("--init", action="append", default=[])
    p.add_argument("--own", action="store_true")
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "members.csv")
        inits = [x for i in a.init for x in ("--init", i)]
        binary = model_binary(a.lagc, a.model, tmp)
        run = subprocess.run(
            [binary, "--ensemble", str(a.ensemble), "--spread",
             a.spread, "--rtol", repr(a.rtol), "--atol", repr(a.rtol * 1e-2),
             "--samples", str(a.samples), "--summary", "json", "-o", path] + inits,
            capture_output=True, text=True,
        )
        if run.returncode != 0:
            sys.exit(run.stderr)
        summary = json.loads(run.stderr.strip().splitlines()[-1])
        with open(path) as f:
            table = list(csv.reader(f))
        names = table[0][2:]
        members = {}
        for r in table[1:]:
            members.setdefault(int(r[0]), []).append([float(v) for v in r[2:]])
        tight = own = 0.0
        for m, rows in sorted(members.items()):
            reference = direct(binary, names, rows[0], a.samples, 1e-12)
            tight = max(tight, largest(rows, reference))
            if a.own:
                at_rtol = direct(binary, names, rows[0], a.samples, a.rtol)
                own = max(own, largest(at_rtol, reference))
    line = (f"{os.path.basename(a.model)} K={a.ensemble} spread={a.spread} "
            f"rtol={a.rtol:g} samples={a.samples}: ensemble - tight {tight:.2e}")
    if a.own:
        line += f", direct - tight {own:.2e}"
    line += (f"; {summary['along_field']} on shared steps, "
             f"{summary['on_their_own']} on their own")
    print(line)


if __name__ == "__main__":
    main()
