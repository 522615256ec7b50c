#!/usr/bin/env python3
"""Instructions per solve of lagc's direct DOP853 and of the compiled peers
(GSL rk8pd, Boost odeint rkf78 and dopri5) at equal error: the load-free
side of BENCHMARKS §10's wall-time comparison (§10m).

Each (model, method, rtol) of §10's ladder runs once for its samples (the
error, as `bench_vs_gsl.py` measures it) and twice under callgrind, with
`--repeat R1` and `--repeat R2` solves after the first: instructions per
solve = (I(R2) − I(R1)) / (R2 − R1), so the process's start and the first,
printing solve cancel. Cost at an error level: each method's lower envelope
of (error, instructions), interpolated as `bench_vs_gsl.cost_at` does.

Usage: python3 scripts/peers_instructions.py --peers PEERS_BIN
         --lagc NAME=DIR [--lagc NAME=DIR ...] [--stepped NAME=DIR ...]
         [--models a,b] [--json OUT] [--from EARLIER.json] [--no-global-error]
--stepped NAME=DIR: lagc's runs with `--step-to-times` (each step cut at the
  sample times, as rk8pd and rkf78 do through GSL's driver). With both a
  `--lagc` and a `--stepped` entry, a last table ("matched") sets each peer
  against lagc in that peer's own way of sampling: rk8pd and rkf78 (they
  step onto the times) against the stepped entry, dopri5 (dense output)
  against the interpolating one: issue 29's criterion.
--no-global-error: lagc's runs without their global-error estimate (as
  bench_vs_gsl.py's flag; the peers estimate nothing).
--from: the points of every method that file holds are taken from it, not
  run again (the peers, or a baseline, measured once: instruction counts
  do not depend on the machine's load).
DIR holds the generated binaries (lag-paper, lag-knife-edge, ...), built
by `lagc build` and `cargo build --release` as bench_vs_gsl.py builds them;
PEERS_BIN is scripts/bench_vs_gsl/peers.cpp compiled with g++ -O2.
"""

import json
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_vs_gsl as B  # noqa: E402

BINARY = {
    "paper": "lag-paper",
    "knife_edge": "lag-knife-edge",
    "vertical_rocket": "lag-vertical-rocket",
    "pendulum_3": "lag-pendulum-3",
}
REPEATS = {"pendulum_3": (2, 12)}
DEFAULT_REPEATS = (20, 220)


# lagc entries run with `--step-to-times` (`--stepped NAME=DIR`).
STEPPED = set()
# Peers that step onto the sample times (GSL's driver, odeint's controlled
# rkf78); dopri5 reads its dense output.
STEPPING_PEERS = ["rk8pd", "rkf78"]


def command(binary, model, method, rtol, repeat, stepped=False):
    atol = rtol * 1e-2
    if method in B.PEER_METHODS:
        return [B.PEERS, model, method, repr(rtol), repr(atol), str(B.SAMPLES), str(repeat)]
    return [
        binary, "--method", "direct", "--integrator", "explicit", "--rtol", repr(rtol),
        "--atol", repr(atol), "--samples", str(B.SAMPLES), "--repeat", str(repeat),
        "--quiet",
    ] + (["--no-global-error"] if B.NO_GLOBAL_ERROR else []) + (
        ["--step-to-times"] if stepped else [])


def instructions(cmd):
    with tempfile.NamedTemporaryFile(suffix=".cg") as out:
        p = subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out.name}"] + cmd,
            capture_output=True, text=True,
        )
        m = re.search(r"Collected : (\d+)", p.stderr) or re.search(r"I\s+refs:\s+([\d,]+)", p.stderr)
        if p.returncode != 0 or not m:
            return None
        return int(m.group(1).replace(",", ""))


def main():
    args = sys.argv[1:]
    B.NO_GLOBAL_ERROR = "--no-global-error" in args
    compilers, models, out_json, earlier = [], list(BINARY), None, None
    for i, a in enumerate(args):
        if a == "--peers":
            B.PEERS = os.path.abspath(args[i + 1])
        if a in ("--lagc", "--stepped"):
            name, d = args[i + 1].split("=", 1)
            compilers.append((name, os.path.abspath(d)))
            if a == "--stepped":
                STEPPED.add(name)
        if a == "--models":
            models = args[i + 1].split(",")
        if a == "--json":
            out_json = args[i + 1]
        if a == "--from":
            earlier = json.load(open(args[i + 1]))["points"]
    methods = [name for name, _ in compilers] + B.PEER_METHODS
    ladder = [10.0 ** -k for k in range(3, 14)]
    results = {}
    for model in models:
        r1, r2 = REPEATS.get(model, DEFAULT_REPEATS)
        lagc_bin = {name: os.path.join(d, BINARY[model]) for name, d in compilers}
        first = lagc_bin[compilers[0][0]]
        reference = None
        if B.exact(model, 0.0) is None:
            reference = B.solve(first, model, "rk8pd", 1e-14, 1e-16, 1)[0]
        per = {m: [] for m in methods}
        for m in methods:
            if earlier and m in earlier.get(model, {}):
                per[m] = earlier[model][m]
        for rtol in ladder:
            for method in methods:
                if per[method] and earlier and method in earlier.get(model, {}):
                    continue
                binary = lagc_bin.get(method, first)
                kind = method if method in B.PEER_METHODS else "lagc"
                stepped = method in STEPPED
                B.STEP_TO_TIMES = stepped
                got = B.solve(binary, model, kind, rtol, rtol * 1e-2, 1)
                B.STEP_TO_TIMES = False
                if got is None:
                    continue
                err = B.error(model, got[0], reference)
                i1 = instructions(command(binary, model, kind, rtol, r1, stepped))
                i2 = instructions(command(binary, model, kind, rtol, r2, stepped))
                if i1 is None or i2 is None:
                    continue
                per_solve = (i2 - i1) / (r2 - r1)
                per[method].append(
                    {"rtol": rtol, "error": err, "instructions": per_solve, "rhs": got[2]}
                )
                print(
                    f"{model:16} {method:10} rtol {rtol:.0e}: error {err:.2e} "
                    f"instructions {per_solve:12.0f}  rhs {got[2]}",
                    file=sys.stderr, flush=True,
                )
        results[model] = per
    tables = {}
    for name, _ in compilers:
        tables[name] = table(models, results, name)
    interpolating = [n for n, _ in compilers if n not in STEPPED]
    stepping = [n for n, _ in compilers if n in STEPPED]
    if interpolating and stepping:
        tables["matched"] = matched(models, results, interpolating[0], stepping[0])
    if out_json:
        with open(out_json, "w") as f:
            json.dump({"points": results, "tables": tables}, f, indent=1)


def table(models, results, key):
    print(f"\n{key}: instructions per solve at equal error, ratio = {key} / peer")
    print("| model | error | " + key + " | " + " | ".join(f"{m} | ratio" for m in B.PEER_METHODS) + " | / best |")
    print("|---|---|---|" + "---|---|" * len(B.PEER_METHODS) + "---|")
    rows = {}
    for model in models:
        curves = {m: [(p["error"], p["instructions"]) for p in results[model][m]] for m in results[model]}
        rows[model] = []
        for level in B.LEVELS:
            mine = B.cost_at(curves[key], level)
            peers = {m: B.cost_at(curves[m], level) for m in B.PEER_METHODS}
            known = [v for v in peers.values() if v]
            if mine is None or not known:
                continue
            cells = [f"{peers[m]:,.0f} | {mine / peers[m]:.2f}" if peers[m] else "– | –" for m in B.PEER_METHODS]
            best = mine / min(known)
            rows[model].append({"level": level, key: mine, **peers, "best_ratio": best})
            print(f"| {model} | {level:.0e} | {mine:,.0f} | " + " | ".join(cells) + f" | {best:.2f} |")
    for model in models:
        r = [row["best_ratio"] for row in rows[model]]
        if r:
            print(f"{model}: {key} / best peer (instructions): {min(r):.2f} .. {max(r):.2f}")
    return rows


def matched(models, results, interpolating, stepping):
    """Each peer against lagc sampling as that peer does (issue 29): the
    stepping peers against `stepping`, dopri5 against `interpolating`."""
    print(f"\nmatched: {stepping} against rk8pd, rkf78; {interpolating} against dopri5")
    print("| model | error | " + " | ".join(f"lagc | {m} | ratio" for m in B.PEER_METHODS) + " | worst |")
    print("|---|---|" + "---|---|---|" * len(B.PEER_METHODS) + "---|")
    rows = {}
    for model in models:
        curves = {m: [(p["error"], p["instructions"]) for p in results[model][m]] for m in results[model]}
        rows[model] = []
        for level in B.LEVELS:
            cells, ratios = [], []
            for m in B.PEER_METHODS:
                mine = B.cost_at(curves[stepping if m in STEPPING_PEERS else interpolating], level)
                peer = B.cost_at(curves[m], level)
                if mine is None or peer is None:
                    cells.append("– | – | –")
                    continue
                ratios.append(mine / peer)
                cells.append(f"{mine:,.0f} | {peer:,.0f} | {mine / peer:.2f}")
            if not ratios:
                continue
            rows[model].append({"level": level, "best_ratio": max(ratios)})
            print(f"| {model} | {level:.0e} | " + " | ".join(cells) + f" | {max(ratios):.2f} |")
    for model in models:
        r = [row["best_ratio"] for row in rows[model]]
        if r:
            print(f"{model}: matched lagc / best peer (instructions): {min(r):.2f} .. {max(r):.2f}")
    return rows


if __name__ == "__main__":
    main()
