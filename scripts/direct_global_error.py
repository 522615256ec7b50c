#!/usr/bin/env python3
"""Direct integration's global error against its tolerance (issue 29).

Runs every example with `exact` lines by direct integration (the model's
integrator, as `lagc run` chooses it) at rtol 1e-6, 1e-8, 1e-10, 1e-12
(atol = rtol/100) and reads the summary: the largest error against the
exact solution over 101 samples, the global error estimate the run
carried (`global_error_estimate`, absent before it existed), the steps,
evaluations and the smallest wall time of `--repeat` solves.

    python3 scripts/direct_global_error.py --lagc target/release/lagc [--json OUT]
        [--compare OTHER.json] [--repeat 20] [--rtols 1e-6,1e-10]
        [--method field] [NAMES...]

`--method field` runs the field method instead (its estimate is carried
the same way since h-gerr).

With --compare, prints the cost (evaluations, time) of this run against
an earlier one (e.g. the binary before a change), model by model.
"""

import argparse
import glob
import json
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXACT = re.compile(r"^\s*exact\s", re.M)


def examples(names):
    found = []
    for path in sorted(glob.glob(os.path.join(ROOT, "examples", "*.lag"))):
        name = os.path.basename(path)[:-4]
        if names and name not in names:
            continue
        if EXACT.search(open(path).read()):
            found.append((name, path))
    return found


def run(lagc, path, rtol, repeat, extra, binaries=None, method="direct"):
    if binaries:
        # Binaries built beforehand (`lagc build`, one target directory).
        name = os.path.basename(path)[:-4].replace("_", "-")
        head = [os.path.join(binaries, f"lag-{name}")]
    else:
        head = [lagc, "run", path]
    args = head + ["--method", method, "--rtol", repr(rtol),
            "--atol", repr(rtol / 100), "--summary", "json", "--samples", "101",
            "--repeat", str(repeat)] + extra
    p = subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    line = next((l for l in p.stderr.splitlines() if l.startswith("{")), None)
    if p.returncode != 0 or line is None:
        return {"exit": p.returncode, "stderr": p.stderr.strip().splitlines()[-1:]}
    s = json.loads(line)
    s["exit"] = 0
    s["warned"] = "passes 10·rtol" in p.stderr
    return s


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lagc", default=os.path.join(ROOT, "target/release/lagc"))
    ap.add_argument("--json")
    ap.add_argument("--compare")
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--rtols", default="1e-6,1e-8,1e-10,1e-12")
    ap.add_argument("--extra", default="", help="more flags for every run")
    ap.add_argument("--binaries", help="run DIR/lag-NAME instead of `lagc run`")
    ap.add_argument("--method", default="direct", help="direct or field")
    ap.add_argument("names", nargs="*")
    a = ap.parse_args()
    rtols = [float(r) for r in a.rtols.split(",")]
    extra = a.extra.split()
    results = {}
    for name, path in examples(set(a.names)):
        for rtol in rtols:
            s = run(a.lagc, path, rtol, a.repeat, extra, a.binaries, a.method)
            results[f"{name} {rtol:g}"] = s
            if s["exit"] != 0:
                print(f"{name:34s} {rtol:7.0e}  exit {s['exit']} {s.get('stderr')}", flush=True)
                continue
            err = s.get("exact_error")
            est = s.get("global_error_estimate")
            flag = " OVER" if err is not None and err > 10 * rtol else ""
            warn = " warned" if s["warned"] else ""
            print(f"{name:34s} {rtol:7.0e}  error/rtol {fmt(err, rtol):>8s}  "
                  f"estimate/rtol {fmt(est, rtol):>8s}  steps {s['steps']:6d}  "
                  f"evals {s['rhs_evaluations']:7d}  {s['wall_time_s'] * 1e3:9.3f} ms"
                  f"{flag}{warn}", flush=True)
    if a.json:
        json.dump(results, open(a.json, "w"), indent=1)
    summarize(results, rtols)
    if a.compare:
        compare(results, json.load(open(a.compare)))


def fmt(v, rtol):
    return "-" if v is None else f"{v / rtol:.3g}"


def summarize(results, rtols):
    print("\nper tolerance: runs, error > 10 rtol, warned, warned while error <= 10 rtol, "
          "over and not warned, median and largest estimate/error")
    for rtol in rtols:
        rows = [s for k, s in results.items() if k.endswith(f" {rtol:g}") and s["exit"] == 0]
        over = [s for s in rows if s.get("exact_error") is not None
                and s["exact_error"] > 10 * rtol]
        warned = [s for s in rows if s.get("warned")]
        false = [s for s in warned if s not in over]
        missed = [s for s in over if not s.get("warned")]
        ratios = sorted(s["global_error_estimate"] / s["exact_error"] for s in rows
                        if s.get("global_error_estimate") and s.get("exact_error"))
        med = ratios[len(ratios) // 2] if ratios else float("nan")
        lo = ratios[0] if ratios else float("nan")
        hi = ratios[-1] if ratios else float("nan")
        print(f"  rtol {rtol:g}: {len(rows)} runs, {len(over)} over, {len(warned)} warned, "
              f"{len(false)} warned within, {len(missed)} over not warned; "
              f"estimate/error median {med:.3g}, range {lo:.3g} .. {hi:.3g}")


def compare(after, before):
    print("\ncost after/before (evaluations, smallest wall time), per model and tolerance")
    ev, tm = [], []
    for key, s in after.items():
        b = before.get(key)
        if not b or s["exit"] != 0 or b["exit"] != 0:
            continue
        e = s["rhs_evaluations"] / b["rhs_evaluations"]
        t = s["wall_time_s"] / b["wall_time_s"]
        ev.append(e)
        tm.append(t)
        print(f"  {key:40s} evals {e:6.3f}  time {t:6.3f}  "
              f"error {b.get('exact_error') or 0:.2e} -> {s.get('exact_error') or 0:.2e}")
    for label, v in (("evaluations", ev), ("time", tm)):
        v = sorted(v)
        if v:
            print(f"{label}: median {v[len(v) // 2]:.3f}, range {v[0]:.3f} .. {v[-1]:.3f}")


if __name__ == "__main__":
    sys.exit(main())
