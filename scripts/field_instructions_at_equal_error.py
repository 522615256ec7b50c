#!/usr/bin/env python3
"""Load-free A/B of the quasilinear field on one model: callgrind instructions
per solve of two generated binaries of the same model (e.g. one built with
`lagc build MODEL -o DIR --runtime RT` against an older runtime), at equal
error against direct DOP853 of the first binary.

    python3 scripts/field_instructions_at_equal_error.py BASE_BIN NEW_BIN [RTOLS]

Per solve = (Ir of `--repeat 21` - Ir of `--repeat 1`) / 20. Error = largest
|x - ref| / max(|ref|, 1) over the samples and components, ref = direct at
rtol 1e-13 (atol = rtol * 1e-2 everywhere); direct's instructions over rtol
1e-5 ... 1e-12 are interpolated log-log at each field run's error. SAMPLES
(env, default 11, as `lagc report`) sets the sample count; ARGS (env, e.g.
`--no-global-error`) is added to every run of both methods; REFERENCE (env, a
CSV of the same samples with a header row, e.g. from
scripts/ball_on_varying_turntable_reference.py) replaces direct at rtol 1e-13
where that run is not accurate enough. Prints, per rtol
(default 1e-6,1e-9) and binary, the field's steps, rejections, windows,
evaluations, error, instructions, and the ratio to direct at that error.
(h-rocket, docs/BENCHMARKS.md section 0.)
"""
import json, math, os, subprocess, sys, tempfile

SAMPLES = os.environ.get("SAMPLES", "11")
ARGS = os.environ.get("ARGS", "").split()


def run(binary, method, rtol, repeat=None):
    args = [binary, "--method", method, "--rtol", str(rtol), "--atol", str(rtol * 1e-2),
            "--samples", SAMPLES, "--summary", "json"] + ARGS
    p = subprocess.run(args, capture_output=True, text=True, check=True)
    summary = json.loads([l for l in (p.stdout + p.stderr).split("\n") if l.startswith("{")][-1])
    rows = [list(map(float, l.split(","))) for l in p.stdout.split("\n")
            if l and l[0] in "0123456789-" and "," in l]
    return summary, rows


def error(rows, ref):
    return max((abs(a - b) / max(abs(b), 1.0) for r, q in zip(rows, ref)
                for a, b in zip(r[1:], q[1:])), default=0.0)


def instructions(binary, method, rtol, repeat):
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "cg")
        subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out, binary,
                        "--method", method, "--rtol", str(rtol), "--atol", str(rtol * 1e-2),
                        "--samples", SAMPLES, "--repeat", str(repeat)] + ARGS,
                       capture_output=True, check=True)
        for line in open(out):
            if line.startswith("summary:") or line.startswith("totals:"):
                return int(line.split()[1])
    raise RuntimeError("no callgrind totals")


def per_solve(binary, method, rtol):
    return (instructions(binary, method, rtol, 21) - instructions(binary, method, rtol, 1)) / 20


def main():
    base, new = sys.argv[1], sys.argv[2]
    rtols = [float(x) for x in (sys.argv[3] if len(sys.argv) > 3 else "1e-6,1e-9").split(",")]
    if os.environ.get("REFERENCE"):
        with open(os.environ["REFERENCE"]) as f:
            ref = [list(map(float, l.split(","))) for l in f.read().split("\n")[1:] if l]
    else:
        _, ref = run(base, "direct", 1e-13)
    direct = []
    for r in [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]:
        _, rows = run(base, "direct", r)
        direct.append((error(rows, ref), per_solve(base, "direct", r)))
    direct.sort()

    def at(e):
        for (e0, i0), (e1, i1) in zip(direct, direct[1:]):
            if e0 <= e <= e1 and e1 > e0:
                w = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
                return math.exp(math.log(i0) + w * (math.log(i1) - math.log(i0)))
        return float("nan")

    print("direct (error: Ir/solve):", " ".join(f"{e:.1e}: {i:.0f}" for e, i in direct))
    for r in rtols:
        # One binary given twice: its field alone (e.g. with ARGS).
        for name, b in (("base", base), ("new", new))[: 1 if new == base else 2]:
            s, rows = run(b, "field", r)
            e = error(rows, ref)
            i = per_solve(b, "field", r)
            d = at(e)
            print(f"rtol {r:.0e} {name}: {s['steps']} steps + {s['rejected_steps']} rejected, "
                  f"{s['windows']} windows, {s['rhs_evaluations']} evaluations, error {e:.2e}, "
                  f"Ir/solve {i:.0f}; direct at that error {d:.0f}; ratio {i / d:.1f}")


if __name__ == "__main__":
    main()
