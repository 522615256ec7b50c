#!/usr/bin/env python3
"""lagc's direct integration (DOP853) against compiled peers at equal error:
GSL's rk8pd (Prince-Dormand 8(7), gsl_odeiv2 driver) and Boost odeint's
runge_kutta_fehlberg78 (controlled) and runge_kutta_dopri5 (dense output).
BENCHMARKS §10.

Outside `cargo test`. Needs g++, GSL and Boost headers (Debian: apt-get
install libgsl-dev libboost-dev) and the release build of lagc.

Models (the peers evaluate the same equations: each generated crate's `rhs`
translated line by line to C++ in scripts/bench_vs_gsl/peers.cpp, the
same expressions and libm calls, pendulum_3's L D L^T solve included):
  paper            n = 4, exact q1', q2'
  knife_edge       n = 6, exact in every component
  vertical_rocket  n = 2, variable mass, exact
  pendulum_3       n = 6 (scripts/gen_pendulum.py 3, benches/data), a 3x3
                   mass matrix solved per evaluation; no exact solution:
                   the reference is GSL rk8pd at rtol 1e-14, atol 1e-16,
                   checked against lagc at rtol 1e-13.

Both sides: the same tolerance ladder rtol = 1e-3 .. 1e-13, atol =
rtol*1e-2 (each side's own meaning of it: only equal error is compared),
the same 11 evenly spaced sample times (lagc: from its dense output, which
never changes its steps; GSL and odeint's rkf78: the driver steps onto each
sample time, they have no dense output; odeint's dopri5: dense output).
Error: the largest over the samples and the exact components of
|x - exact| / max(|exact|, 1) (the generated binary's measure). Time: the
smallest in-process wall time of R solves after a warm-up (R chosen so that
R solves take ~0.3 s), measured inside the generated binary (`--repeat`)
and inside peers.cpp. Cost at equal error: each method's lower envelope of
(error, time), interpolated in log-log at error levels 1e-4 .. 1e-11
(above the loosest run's error, that run's time: no looser run is cheaper;
below the tightest run's error, nothing: no extrapolation); ratio = lagc
time / peer time (< 1: lagc faster).

Usage: python3 scripts/bench_vs_gsl.py [--quick] [--json OUT] [--models a,b]
       [--step-to-times] [--no-global-error] [--samples N] [--baseline LAGC]
       [--matched]
--baseline LAGC: another lagc binary (main's) builds the same crates, which
  run as method "lagc-base" alternated with this tree's at every rtol (each
  rtol runs every method in turn), and a second table compares it.
--step-to-times: lagc steps onto the sample times too (as rk8pd, rkf78 do);
--samples 2: the final time only, a step end for every method.
--no-global-error: lagc without its global-error estimate (the peers
  estimate nothing): DOP853 alone.
--matched: lagc also runs with `--step-to-times` (method "lagc-stepped",
  and "lagc-base-stepped" with --baseline), in turn with the others, and a
  last table sets each peer against lagc sampling as that peer does (issue
  29): rk8pd and rkf78, which step onto the sample times, against
  lagc-stepped; dopri5, which interpolates, against lagc.
"""

import json
import math
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WORK = os.path.join(ROOT, "target", "bench-gsl")
PEERS_SRC = os.path.join(ROOT, "scripts", "bench_vs_gsl", "peers.cpp")
PEERS = os.path.join(WORK, "peers")
LAGC = os.path.join(
    os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release", "lagc"
)

MODELS = {
    "paper": ("examples/paper.lag", 4),
    "knife_edge": ("examples/knife_edge.lag", 6),
    "vertical_rocket": ("examples/vertical_rocket.lag", 2),
    "pendulum_3": ("benches/data/pendulum_3.lag", 6),
}
PEER_METHODS = ["rk8pd", "rkf78", "dopri5"]
SAMPLES = 11
# `--step-to-times`: lagc cuts its steps to land on the sample times, as
# rk8pd and rkf78 do (issue 29); `--samples 2`: only the final time, where
# every method's sample is a step end.
STEP_TO_TIMES = False
# `--no-global-error`: lagc's runs without the summary's global-error
# estimate, which the peers do not make.
NO_GLOBAL_ERROR = False
# `--baseline LAGC`: the crates built by that lagc too, run as "lagc-base".
BASELINE = None
# `--matched`: lagc run both ways, each peer against lagc sampling as it does.
MATCHED = False
STEPPING_PEERS = ["rk8pd", "rkf78"]
LEVELS = [10.0 ** -k for k in range(4, 12)]


def exact(model, t):
    """The exact state at t (None where the model gives none)."""
    if model == "paper":
        v = math.exp(0.5 * t) / math.sqrt(1.0 + t * t)
        return [None, None, v, t * v]
    if model == "knife_edge":
        theta0, omega, v0 = 0.0, 0.5, 1.0
        big_v = v0 / math.cos(theta0)
        th = theta0 + omega * t
        return [
            big_v * (math.sin(th) - math.sin(theta0)) / omega,
            -big_v * (math.cos(th) - math.cos(theta0)) / omega,
            th,
            big_v * math.cos(th),
            big_v * math.sin(th),
            omega,
        ]
    if model == "vertical_rocket":
        m0, mu, w, g = 1000.0, 10.0, 2000.0, 9.81
        m = m0 - mu * t
        return [
            -g * t * t / 2 + w * (t + m / mu * math.log(m / m0)),
            w * math.log(m0 / m) - g * t,
        ]
    return None


def run(cmd, **kw):
    return subprocess.run(cmd, check=True, capture_output=True, text=True, **kw)


def build():
    os.makedirs(WORK, exist_ok=True)
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "--bin", "lagc"], cwd=ROOT, check=True
    )
    subprocess.run(
        ["g++", "-O2", "-std=c++17", PEERS_SRC, "-o", PEERS, "-lgsl", "-lgslcblas", "-lm"],
        check=True,
    )
    binaries = {}
    compilers = [("lagc", LAGC, "")] + ([("lagc-base", BASELINE, "-base")] if BASELINE else [])
    for method, lagc, suffix in compilers:
        binaries[method] = {}
        for model, (path, _) in MODELS.items():
            crate = os.path.join(WORK, model + suffix)
            run([lagc, "build", os.path.join(ROOT, path), "-o", crate])
            target = os.path.join(WORK, "target" + suffix)
            env = dict(os.environ, CARGO_TARGET_DIR=target)
            subprocess.run(
                ["cargo", "build", "--release", "--quiet"], cwd=crate, env=env, check=True
            )
            name = [
                line.split("=")[1].strip().strip('"')
                for line in open(os.path.join(crate, "Cargo.toml"))
                if line.startswith("name")
            ][0]
            binaries[method][model] = os.path.join(target, "release", name)
    return binaries


def parse_csv(text, n):
    rows = []
    for line in text.splitlines():
        if not line or not (line[0].isdigit() or line[0] in "-."):
            continue
        values = [float(v) for v in line.split(",")]
        rows.append((values[0], values[1 : 1 + n]))
    return rows


def solve(binary, model, method, rtol, atol, repeat):
    """(rows, wall time, rhs evaluations)."""
    n = MODELS[model][1]
    if method.startswith("lagc"):
        stepped = STEP_TO_TIMES or method.endswith("-stepped")
        cmd = [
            binary, "--method", "direct", "--integrator", "explicit",
            "--rtol", repr(rtol), "--atol", repr(atol), "--samples", str(SAMPLES),
            "--repeat", str(repeat), "--summary", "json",
        ] + (["--step-to-times"] if stepped else []) + (
            ["--no-global-error"] if NO_GLOBAL_ERROR else [])
    else:
        cmd = [PEERS, model, method, repr(rtol), repr(atol), str(SAMPLES), str(repeat)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return None
    summary = json.loads(p.stderr.strip().splitlines()[-1])
    return parse_csv(p.stdout, n), summary["wall_time_s"], summary["rhs_evaluations"]


def error(model, rows, reference):
    worst = 0.0
    for i, (t, x) in enumerate(rows):
        truth = exact(model, t) if reference is None else reference[i][1]
        for v, e in zip(x, truth):
            if e is not None:
                worst = max(worst, abs(v - e) / max(abs(e), 1.0))
    return worst


def envelope(points):
    """The lower envelope of (error, time): sorted by error, keeping a point
    only when it is cheaper than every point of smaller error."""
    points = sorted(p for p in points if p[0] > 0)
    kept = []
    for e, t in points:
        if not kept or t < kept[-1][1]:
            kept.append((e, t))
    return kept


def cost_at(points, level):
    """The cost of reaching error <= level: the envelope interpolated in
    log-log between two ladder points that bracket it; at a level above the
    loosest run's error, that run's time (no cheaper run reaches it: the
    solver cannot be loosened further, e.g. a driver stepping onto every
    sample time); None below the tightest run's error (no extrapolation)."""
    env = envelope(points)
    if not env or level < env[0][0]:
        return None
    if level >= env[-1][0]:
        return env[-1][1]
    for (e0, t0), (e1, t1) in zip(env, env[1:]):
        if e0 <= level <= e1:
            if e1 == e0:
                return t0
            f = (math.log(level) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
    return None


def main():
    global SAMPLES, STEP_TO_TIMES, BASELINE, NO_GLOBAL_ERROR, MATCHED
    quick = "--quick" in sys.argv
    MATCHED = "--matched" in sys.argv
    STEP_TO_TIMES = "--step-to-times" in sys.argv
    NO_GLOBAL_ERROR = "--no-global-error" in sys.argv
    out_json = None
    models = list(MODELS)
    args = sys.argv[1:]
    for i, a in enumerate(args):
        if a == "--json":
            out_json = args[i + 1]
        if a == "--models":
            models = args[i + 1].split(",")
        if a == "--samples":
            SAMPLES = int(args[i + 1])
        if a == "--baseline":
            BASELINE = os.path.abspath(args[i + 1])
    binaries = build()
    budget = 0.1 if quick else 0.3
    ladder = [10.0 ** -k for k in range(3, 14)]
    results = {}
    for model in models:
        reference = None
        if exact(model, 0.0) is None:
            ref = solve(binaries["lagc"][model], model, "rk8pd", 1e-14, 1e-16, 1)
            check = solve(binaries["lagc"][model], model, "lagc", 1e-13, 1e-15, 1)
            reference = ref[0]
            gap = error(model, check[0], reference)
            print(f"{model}: reference GSL rk8pd 1e-14 vs lagc 1e-13: {gap:.1e}", file=sys.stderr)
        own = ["lagc"] + (["lagc-base"] if BASELINE else [])
        methods = [m for o in own for m in ([o, o + "-stepped"] if MATCHED else [o])]
        methods += PEER_METHODS
        per_method = {method: [] for method in methods}
        # Every method in turn at each rtol: a drift of the machine's speed
        # reaches all of them alike.
        for rtol in ladder:
            for method in methods:
                points = per_method[method]
                binary = binaries["lagc-base" if method.startswith("lagc-base") else "lagc"][model]
                atol = rtol * 1e-2
                probe = solve(binary, model, method, rtol, atol, 3)
                if probe is None:
                    continue
                repeat = max(5, min(20000, int(budget / max(probe[1], 1e-7))))
                got = solve(binary, model, method, rtol, atol, repeat)
                if got is None:
                    continue
                rows, wall, evals = got
                err = error(model, rows, reference)
                points.append(
                    {"rtol": rtol, "error": err, "time": wall, "rhs": evals, "repeat": repeat}
                )
                print(
                    f"{model:16} {method:9} rtol {rtol:.0e}: error {err:.2e} "
                    f"time {wall * 1e6:9.1f} us  rhs {evals}",
                    file=sys.stderr,
                )
        results[model] = per_method
    table = equal_error_table(models, results, "lagc")
    tables = {"lagc": table}
    if BASELINE:
        tables["lagc-base"] = equal_error_table(models, results, "lagc-base")
    if MATCHED:
        for own in ["lagc"] + (["lagc-base"] if BASELINE else []):
            tables[own + "-matched"] = matched_table(models, results, own, own + "-stepped")
    if out_json:
        with open(out_json, "w") as f:
            json.dump({"points": results, "table": table, "tables": tables}, f, indent=1)


def equal_error_table(models, results, lagc_key):
    """Prints and returns, for each model, `lagc_key`'s cost and each
    peer's at the error levels, and the ratios to the best peer."""
    # The table: cost at equal error.
    table = {}
    print()
    print(f"{lagc_key}:")
    print("| model | error | lagc (µs) | " + " | ".join(f"{m} (µs) | ratio" for m in PEER_METHODS) + " |")
    print("|---|---|---|" + "---|---|" * len(PEER_METHODS))
    for model in models:
        curves = {
            m: [(p["error"], p["time"]) for p in results[model][m]] for m in results[model]
        }
        curves["lagc"] = curves[lagc_key]
        table[model] = []
        for level in LEVELS:
            lagc = cost_at(curves["lagc"], level)
            peers = {m: cost_at(curves[m], level) for m in PEER_METHODS}
            if lagc is None or all(v is None for v in peers.values()):
                continue
            cells = []
            for m in PEER_METHODS:
                v = peers[m]
                cells.append(f"{v * 1e6:.1f} | {lagc / v:.2f}" if v else "– | –")
            row = {"level": level, "lagc": lagc, **{m: peers[m] for m in PEER_METHODS}}
            table[model].append(row)
            print(f"| {model} | {level:.0e} | {lagc * 1e6:.1f} | " + " | ".join(cells) + " |")
    print()
    for model in models:
        ratios = [
            r["lagc"] / min(r[m] for m in PEER_METHODS if r[m])
            for r in table[model]
            if any(r[m] for m in PEER_METHODS)
        ]
        if ratios:
            print(
                f"{model}: {lagc_key} / best peer at equal error: "
                f"{min(ratios):.2f} .. {max(ratios):.2f} (worst over {len(ratios)} levels)"
            )
    return table


def matched_table(models, results, interpolating, stepping):
    """Each peer against lagc sampling as that peer does: rk8pd and rkf78
    (they step onto the sample times) against `stepping`, dopri5 (dense
    output) against `interpolating`; per level the worst of the ratios."""
    print()
    print(f"{interpolating} matched ({stepping} against rk8pd, rkf78):")
    print("| model | error | " + " | ".join(f"lagc (µs) | {m} (µs) | ratio" for m in PEER_METHODS) + " | worst |")
    print("|---|---|" + "---|---|---|" * len(PEER_METHODS) + "---|")
    table = {}
    for model in models:
        curves = {m: [(p["error"], p["time"]) for p in results[model][m]] for m in results[model]}
        table[model] = []
        for level in LEVELS:
            cells, ratios = [], []
            for m in PEER_METHODS:
                mine = cost_at(curves[stepping if m in STEPPING_PEERS else interpolating], level)
                peer = cost_at(curves[m], level)
                if mine is None or peer is None:
                    cells.append("– | – | –")
                    continue
                ratios.append(mine / peer)
                cells.append(f"{mine * 1e6:.1f} | {peer * 1e6:.1f} | {mine / peer:.2f}")
            if ratios:
                table[model].append({"level": level, "worst": max(ratios)})
                print(f"| {model} | {level:.0e} | " + " | ".join(cells) + f" | {max(ratios):.2f} |")
    print()
    for model in models:
        worst = [r["worst"] for r in table[model]]
        if worst:
            print(f"{model}: {interpolating} matched / best peer: {min(worst):.2f} .. {max(worst):.2f}")
    return table


if __name__ == "__main__":
    main()
