#!/usr/bin/env python3
"""Instructions per solve by part of a generated binary's quasilinear field
run, from callgrind_annotate --inclusive=yes (h-qstep, docs/BENCHMARKS.md
section 0). Usage:
  valgrind --tool=callgrind --dump-instr=no --callgrind-out-file=OUT BIN \
      --method field --rtol R --atol R/100 --samples 11 --repeat K --quiet [--no-global-error]
  python3 scripts/field_callgrind_parts.py --solves K+1 OUT [OUT...]
The crate built with line tables (CARGO_PROFILE_RELEASE_DEBUG=line-tables-only).
Inclusive counts of the functions named; the parts nest (the window's steps
hold the coefficients' right side, which holds the linearisation, which holds
the predictor and the model's linearize; the error measure holds the
conditions), so they do not add up. Allocation is every caller's."""
import re, subprocess, sys
PARTS = [
    ("advance", [r"QuasilinearField as lagc_runtime::method::solver::Solver>::advance"]),
    ("window steps", [r"window::Window::step"]),
    ("coefficients' rates", [r"ProjectiveCoefficients<I> as lagc_runtime::ode::system::System>::rhs"]),
    ("linearisation", [r"LinearizedCoefficients<I>::linearize"]),
    ("predictor (live)", [r"LivePath as lagc_runtime::method::field::coefficients::Iterate>::eval"]),
    ("model linearize", [r"<M as lagc_runtime::model::DynModel>::linearize"]),
    ("adjoint rates", [r"coefficients::adjoint_rates"]),
    ("error measure", [r"StateMeasure<F> as lagc_runtime::ode::stepper::ErrorMeasure>::measure"]),
    ("conditions (LU)", [r"conditions::solve_conditions"]),
    ("window set-up", [r"window::Window::open"]),
    ("integrator starts", [r"lagc_runtime::ode::Integrator::start"]),
    ("output between steps", [r"QuasilinearField as lagc_runtime::method::solver::Solver>::dense"]),
    ("allocation", [r"__rustc::__rust_alloc", r"__rustc::__rust_alloc_zeroed", r"__rustc::__rust_dealloc", r"__rustc::__rust_realloc"]),
]
args = sys.argv[1:]
solves = 1
if args[:1] == ["--solves"]:
    solves, args = int(args[1]), args[2:]
for path in args:
    out = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", path],
                         capture_output=True, text=True).stdout
    rows = []
    for line in out.splitlines():
        m = re.match(r"\s*([\d,]+) \(.*?\)\s+(\S.*)$", line)
        if m:
            rows.append((int(m.group(1).replace(",", "")), m.group(2)))
    total = next(n for n, name in rows if "PROGRAM TOTALS" in name)
    print(f"{path}: {total / solves:,.0f} instructions a solve")
    for part, patterns in PARTS:
        n = 0
        for p in patterns:
            # The function's own entry (the largest count of its name),
            # not the lines of code inlined into it from elsewhere.
            hits = [c for c, name in rows
                    if not name.startswith("=>") and name.split(" [")[0].rstrip().endswith(p)]
            n += max(hits, default=0)
        print(f"  {part:22s} {n / solves:12,.0f}  {100 * n / total:5.1f} %")
