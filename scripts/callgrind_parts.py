#!/usr/bin/env python3
"""Instructions per solve by part of a generated binary's direct run, from
callgrind_annotate --inclusive=yes (BENCHMARKS §10i). Usage:
  valgrind --tool=callgrind --callgrind-out-file=OUT BIN --method direct \
      --integrator explicit --rtol R --atol R/100 --samples 11 --repeat 2000 --quiet
  python3 scripts/callgrind_parts.py [--solves N] OUT [OUT...]
Inclusive counts of the functions named (the crate built with line tables:
CARGO_PROFILE_RELEASE_DEBUG=line-tables-only); per solve = total / N,
N = 2001 (`--repeat 2000` and the first solve) unless `--solves N`
(BENCHMARKS §10m: pendulum_3 at `--repeat 100`). The samples' projection
is the inclusive count of the calls of `project_from` made from
`project_in_place` (§10i's pattern named 20,010 calls)."""
import re, subprocess, sys
PARTS = [
    ("set-up", [r"Integration::with \[", r"drop_in_place<lagc_runtime::run::integration::Integration> \[", r"Integration::into_spare \[", r"drop_in_place<lagc_runtime::run::integration::Spare> \["]),
    ("report", [r"Integration::finish \["]),
    ("steps (DOP853)", [r"Dop853 as lagc_runtime::ode::stepper::Stepper<S>>::step \["]),
    ("steps (bookkeeping)", [r"Direct as lagc_runtime::method::solver::Solver>::advance \["]),
    ("after steps (keeper)", [r"Integration::finish_step \["]),
    ("dense output", [r"Direct as lagc_runtime::method::solver::Solver>::dense \["]),
]
# The samples' projection: the call of `project_from` on the line of
# `project_in_place` that makes it (an output's or an event's projection;
# the keeper after steps calls it from `after_step`).
SAMPLE_CALL = "self.project_from(model, mode, t, x, judged, false)"
def inclusive(path):
    out = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", path], capture_output=True, text=True).stdout
    rows = []
    for line in out.splitlines():
        m = re.match(r"\s*([\d,]+) \(", line)
        if m:
            rows.append((int(m.group(1).replace(",", "")), line))
    return rows
args = sys.argv[1:]
solves = 2001
if args[:1] == ["--solves"]:
    solves, args = int(args[1]), args[2:]
for path in args:
    rows = inclusive(path)
    total = rows[0][0]
    got = {}
    for name, pats in PARTS:
        v = 0
        for p in pats:
            hits = [n for n, l in rows if re.search(p, l)]
            if hits:
                v += max(hits)
        got[name] = v
    got["steps (bookkeeping)"] -= got["steps (DOP853)"]
    got["samples' projection"] = 0
    for i, (n, l) in enumerate(rows):
        if SAMPLE_CALL in l:
            for n2, l2 in rows[i + 1 : i + 3]:
                if "=>" in l2 and "project_from" in l2:
                    got["samples' projection"] = n2
                    break
    per = lambda v: v / solves
    print(path, f"total/solve {per(total):.0f}", " | ".join(f"{k} {per(v):.0f} ({100*v/total:.1f}%)" for k, v in got.items()))
