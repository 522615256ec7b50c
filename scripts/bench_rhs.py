#!/usr/bin/env python3
"""The generated right side against SymPy + cse → C (issue 11, "a lean
right side"): µs per evaluation and operation counts of the N-link planar
pendulum's right side x' = f(x), N in {2, 3, 5, 8, 12, 20}.

SymPy side: the pendulum of scripts/gen_pendulum.py by
`LagrangesMethod.form_lagranges_equations()`; the mass matrix (lower
triangle, the upper one copied) and the forcing go through `sympy.cse` and
`ccode` into one C function; the harness solves `M q'' = F` with the same
fixed-size LU with partial pivoting lagc's runtime uses
(`runtime/src/linalg.rs::solve_fixed`), or the same L D Lᵀ as
`linalg::ldlt_fixed` (L D Lᵀ) when lagc's generated crate uses it. Compiled with `gcc -O2`, the right side in its own
translation unit (nothing hoisted out of the timing loop).

lagc side: `lagc build` writes each N's crate (one shared runtime copy
under target/bench-rhs/); a small harness crate calls `Model::rhs` through
the `lagc_runtime::model::Model` trait, `std::hint::black_box` on input
and output.

Both sides are timed at the same state (th_i = 0.1·i, th_i' = 0.3 − 0.07·i),
the smallest of 7 repeats of a loop of evaluations in each of 3 runs of
the timing program; the two answers are
compared (largest relative difference, printed).

Operation count: one rule for both texts — every `+ - * /` (unary minus
included) outside numeric literals, and every call of a math function
(`sin`, `cos`, `pow`/`powi`, `sqrt`, …; lagc's `sin_cos` is two, as
gcc's `sincos` for a C `sin` and `cos` of one argument); assignments and
array indexing count nothing. Counted over the emitted expressions (C: the cse'd function;
lagc: `mass_system`, or `rhs` when lagc solved the 2×2 system
symbolically), plus the linear solve's operations as a formula (the
same algorithm on both sides — L D Lᵀ when lagc uses it for a
symmetric mass matrix, else LU; the C side is timed with both solvers and
the faster counts — plus lagc's n negations of `g` in
`a z = −g`; 0 when lagc's right side is explicit).

Usage: python3 scripts/bench_rhs.py [N ...]  (default: 2 3 5 8 12 20)
Needs: sympy, gcc, cargo. Writes everything under target/bench-rhs/;
SymPy's C code is cached there (delete target/bench-rhs/c to redo it).
"""

import os
import re
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "target", "bench-rhs")
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import gen_pendulum  # noqa: E402

REPEATS = 7
# Each timing program runs this many times; the smallest time counts.
PROCESSES = 3


def state(n):
    th = [0.1 * (i + 1) for i in range(n)]
    w = [0.3 - 0.07 * (i + 1) for i in range(n)]
    return th + w


def evaluations(n):
    """Loop length: about 0.1 s per repeat."""
    return max(200, int(4e6 / (n * n * 10)))


# ---------------------------------------------------------------- counting

NUMBER = re.compile(r"(?<![A-Za-z_0-9])\d+(\.\d*)?([eE][+-]?\d+)?(_f64|_f32|_usize|_i32)?")
CALL = re.compile(r"\b(sin|cos|tan|exp|log|ln|sqrt|pow|powi|powf|recip|atan2|atan|asin|acos|sinh|cosh|tanh|abs|fabs)\s*\(")


def count_ops(text):
    """`+ - * /` outside numeric literals, and math-function calls."""
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"\[[^\[\]]*\]", "", text)  # indices: x[3], a[1][2]
    text = NUMBER.sub("0", text)
    arith = sum(text.count(c) for c in "+-*/")
    # lagc's `sin_cos(u)` is two functions, as gcc's `sincos` for C's
    # `sin(u)` and `cos(u)`.
    return arith + len(CALL.findall(text)) + 2 * len(re.findall(r"\bsin_cos\s*\(", text))


def lu_ops(n):
    """Operations of solve_fixed (partial pivoting, no fill checks)."""
    ops = 0
    for k in range(n):
        for _ in range(k + 1, n):
            ops += 1 + 2 * (n - k - 1) + 2  # l, row update, b update
    for k in range(n):
        ops += 2 * (n - k - 1) + 1
    return ops


def ldlt_ops(n):
    """Operations of ldlt_fixed: L D Lᵀ, two unit triangular solves, the scaling."""
    ops = 0
    for j in range(n):
        ops += 3 * j + 1  # w_k = l_jk d_k, d_j = a_jj − Σ l_jk w_k, 1/d_j
        for _ in range(j + 1, n):
            ops += 2 * j + 1  # (a_ij − Σ l_ik w_k) · (1/d_j)
    for i in range(n):
        ops += 2 * i  # forward
    ops += n  # times 1/d
    for i in range(n):
        ops += 2 * (n - i - 1)  # backward
    return ops


# ---------------------------------------------------------------- SymPy → C


def sympy_c(n):
    import sympy as sp
    from sympy.physics.mechanics import LagrangesMethod

    lagrangian, th, g, t = gen_pendulum.sympy_lagrangian(n)
    start = time.perf_counter()
    method = LagrangesMethod(lagrangian, th)
    method.form_lagranges_equations()
    mass = method.mass_matrix
    forcing = method.forcing
    q = sp.symbols(f"q0:{n}")
    u = sp.symbols(f"u0:{n}")
    plain = {sp.diff(th[i], t): u[i] for i in range(n)}
    plain2 = {th[i]: q[i] for i in range(n)}

    def flat(e):
        e = e.xreplace(plain).xreplace(plain2)
        return e.xreplace({r: sp.Float(r, 17) for r in e.atoms(sp.Rational) if not r.is_Integer})

    exprs = [flat(mass[i, j]) for i in range(n) for j in range(i + 1)]
    exprs += [flat(forcing[i]) for i in range(n)]
    subs, reduced = sp.cse(exprs)
    derive_s = time.perf_counter() - start
    lines = [f"    const double q{i} = x[{i}], u{i} = x[{n + i}];" for i in range(n)]
    lines.append("    const double g = 9.81;")
    for s, e in subs:
        lines.append(f"    const double {s} = {sp.ccode(e, standard='C99')};")
    k = 0
    for i in range(n):
        for j in range(i + 1):
            lines.append(f"    M[{i * n + j}] = {sp.ccode(reduced[k], standard='C99')};")
            k += 1
    for i in range(n):
        lines.append(f"    F[{i}] = {sp.ccode(reduced[k], standard='C99')};")
        k += 1
    body = "\n".join(lines)
    source = (
        "#include <math.h>\n"
        f"/* N = {n}: SymPy LagrangesMethod + cse, lower triangle of M and F. */\n"
        "void mass_forcing(const double *x, double *M, double *F) {\n"
        + body
        + "\n}\n"
    )
    return source, count_ops(body), derive_s


HARNESS_C = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#define N %(n)d
void mass_forcing(const double *x, double *M, double *F);

/* The right side: M q'' = F solved by %(solver)s. */
__attribute__((noinline)) void rhs(const double *x, double *dx) {
    double a[N * N], b[N];
    mass_forcing(x, a, b);
    for (int i = 0; i < N; i++)
        for (int j = i + 1; j < N; j++) a[i * N + j] = a[j * N + i];
    for (int i = 0; i < N; i++) dx[i] = x[N + i];
#if %(ldlt)d
    /* L D L^T, as lagc_runtime::linalg::ldlt_fixed. */
    double d[N], inverse[N], w[N];
    for (int j = 0; j < N; j++) {
        double pivot = a[j * N + j];
        for (int k = 0; k < j; k++) {
            double v = a[j * N + k] * d[k];
            w[k] = v;
            pivot -= a[j * N + k] * v;
        }
        d[j] = pivot;
        double r = 1.0 / pivot;
        inverse[j] = r;
        for (int i = j + 1; i < N; i++) {
            double s = a[i * N + j];
            for (int k = 0; k < j; k++) s -= a[i * N + k] * w[k];
            a[i * N + j] = s * r;
        }
    }
    for (int i = 0; i < N; i++) {
        double s = b[i];
        for (int k = 0; k < i; k++) s -= a[i * N + k] * b[k];
        b[i] = s;
    }
    for (int i = 0; i < N; i++) b[i] *= inverse[i];
    for (int i = N - 1; i >= 0; i--) {
        double s = b[i];
        for (int k = i + 1; k < N; k++) s -= a[k * N + i] * b[k];
        b[i] = s;
    }
#else
    for (int k = 0; k < N; k++) {
        int p = k;
        for (int i = k + 1; i < N; i++)
            if (fabs(a[i * N + k]) > fabs(a[p * N + k])) p = i;
        if (p != k) {
            for (int j = 0; j < N; j++) {
                double t = a[k * N + j]; a[k * N + j] = a[p * N + j]; a[p * N + j] = t;
            }
            double t = b[k]; b[k] = b[p]; b[p] = t;
        }
        double pivot = a[k * N + k];
        for (int i = k + 1; i < N; i++) {
            double l = a[i * N + k] / pivot;
            if (l != 0.0) {
                for (int j = k + 1; j < N; j++) a[i * N + j] -= l * a[k * N + j];
                b[i] -= l * b[k];
            }
        }
    }
    for (int k = N - 1; k >= 0; k--) {
        double s = b[k];
        for (int j = k + 1; j < N; j++) s -= a[k * N + j] * b[j];
        b[k] = s / a[k * N + k];
    }
#endif
    for (int i = 0; i < N; i++) dx[N + i] = b[i];
}

int main(int argc, char **argv) {
    long evals = atol(argv[1]);
    double x[2 * N], dx[2 * N];
    for (int i = 0; i < 2 * N; i++) x[i] = atof(argv[2 + i]);
    double best = 1e300, sink = 0.0;
    for (int r = 0; r < %(repeats)d + 1; r++) {
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        for (long e = 0; e < evals; e++) {
            rhs(x, dx);
            sink += dx[2 * N - 1];
            x[0] += 0.0 * dx[N];
        }
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double us = ((t1.tv_sec - t0.tv_sec) * 1e9 + (t1.tv_nsec - t0.tv_nsec)) * 1e-3 / evals;
        if (r > 0 && us < best) best = us;
    }
    rhs(x, dx);
    printf("%%.6f", best);
    for (int i = 0; i < N; i++) printf(" %%.17g", dx[N + i]);
    printf("\n");
    return sink == 12345.678 ? 1 : 0;
}
"""


def c_side(n, ldlt):
    cdir = os.path.join(OUT, "c")
    os.makedirs(cdir, exist_ok=True)
    src = os.path.join(cdir, f"mass_forcing_{n}.c")
    meta = os.path.join(cdir, f"mass_forcing_{n}.txt")
    if not (os.path.exists(src) and os.path.exists(meta)):
        source, ops, derive_s = sympy_c(n)
        with open(src, "w") as f:
            f.write(source)
        with open(meta, "w") as f:
            f.write(f"{ops} {derive_s}\n")
    with open(meta) as f:
        ops, derive_s = f.read().split()
    harness = os.path.join(cdir, f"harness_{n}_{int(ldlt)}.c")
    with open(harness, "w") as f:
        f.write(
            HARNESS_C
            % {
                "n": n,
                "repeats": REPEATS,
                "ldlt": int(ldlt),
                "solver": "L D L^T" if ldlt else "LU with partial pivoting",
            }
        )
    exe = os.path.join(cdir, f"rhs_{n}_{int(ldlt)}")
    subprocess.run(["gcc", "-O2", "-o", exe, harness, src, "-lm"], check=True)
    runs = [
        subprocess.run(
            [exe, str(evaluations(n))] + [repr(v) for v in state(n)],
            check=True,
            capture_output=True,
            text=True,
        ).stdout.split()
        for _ in range(PROCESSES)
    ]
    out = runs[0]
    best = min(float(r[0]) for r in runs)
    return best, [float(v) for v in out[1:]], int(ops), float(derive_s)


# ---------------------------------------------------------------- lagc


def lagc_side(sizes):
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    lagc = os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release", "lagc")
    models = os.path.join(OUT, "models")
    os.makedirs(models, exist_ok=True)
    counts = {}
    solver = {}
    deps = []
    for n in sizes:
        lag = os.path.join(models, f"pendulum_{n}.lag")
        with open(lag, "w") as f:
            f.write(gen_pendulum.model(n))
        crate = os.path.join(models, f"pendulum_{n}")
        subprocess.run(
            [lagc, "build", lag, "-o", crate, "--runtime", os.path.join(models, "lagc-runtime"), "--force"],
            check=True,
            capture_output=True,
        )
        with open(os.path.join(crate, "src", "lib.rs")) as f:
            lib = f.read()
        counts[n], solver[n] = rust_ops(lib, n)
        deps.append(f'lag-pendulum-{n} = {{ path = "../models/pendulum_{n}" }}')
    harness = os.path.join(OUT, "harness")
    os.makedirs(os.path.join(harness, "src"), exist_ok=True)
    with open(os.path.join(harness, "Cargo.toml"), "w") as f:
        f.write(
            '[package]\nname = "bench-rhs"\nversion = "0.1.0"\nedition = "2021"\npublish = false\n\n'
            "[dependencies]\n"
            'lagc-runtime = { path = "../models/lagc-runtime" }\n'
            + "\n".join(deps)
            + "\n\n[profile.release]\ndebug = false\n\n[workspace]\n"
        )
    calls = []
    for n in sizes:
        calls.append(
            f"    time::<lag_pendulum_{n}::Model>({n}, {evaluations(n)}, &{state(n)!r});"
        )
    main = (
        "use lagc_runtime::model::Model;\n"
        "use std::hint::black_box;\n"
        "use std::time::Instant;\n\n"
        "fn time<M: Model>(n: usize, evals: usize, x: &[f64]) {\n"
        "    let model = M::new(&M::parameters(&[]));\n"
        "    let x = x.to_vec();\n"
        "    let mut dx = vec![0.0; 2 * n];\n"
        "    let mut best = f64::INFINITY;\n"
        f"    for r in 0..{REPEATS + 1} {{\n"
        "        let start = Instant::now();\n"
        "        for _ in 0..evals {\n"
        "            model.rhs(0.0, black_box(&x), black_box(&mut dx)).unwrap();\n"
        "        }\n"
        "        let us = start.elapsed().as_secs_f64() * 1e6 / evals as f64;\n"
        "        if r > 0 && us < best { best = us; }\n"
        "    }\n"
        "    model.rhs(0.0, &x, &mut dx).unwrap();\n"
        '    print!("{n} {best:.6}");\n'
        '    for v in &dx[n..] { print!(" {v:e}"); }\n'
        "    println!();\n"
        "}\n\n"
        "fn main() {\n" + "\n".join(calls) + "\n}\n"
    )
    with open(os.path.join(harness, "src", "main.rs"), "w") as f:
        f.write(main)
    env = dict(os.environ)
    env["CARGO_TARGET_DIR"] = os.path.join(OUT, "harness-target")
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=harness, check=True, env=env)
    exe = os.path.join(OUT, "harness-target", "release", "bench-rhs")
    results = {}
    for _ in range(PROCESSES):
        for line in subprocess.run([exe], check=True, capture_output=True, text=True).stdout.splitlines():
            parts = line.split()
            n, us = int(parts[0]), float(parts[1])
            if n not in results or us < results[n][0]:
                results[n] = (us, [float(v) for v in parts[2:]])
    return results, counts, solver


def function_body(lib, name):
    start = lib.index(f"fn {name}(")
    brace = lib.index("{", lib.index(")", start))
    depth = 0
    for i in range(brace, len(lib)):
        if lib[i] == "{":
            depth += 1
        elif lib[i] == "}":
            depth -= 1
            if depth == 0:
                return lib[brace + 1 : i]
    raise ValueError(name)


def rust_ops(lib, n):
    """Operations of the emitted expressions, and the solver lagc uses."""
    if "fn mass_system(" in lib:
        body = function_body(lib, "mass_system")
        solver = "ldlt" if "symmetric" in function_body(lib, "highest") else "lu"
    else:
        body = function_body(lib, "rhs")
        solver = "explicit"
    body = re.sub(r"let p = &self\.params;", "", body)
    body = re.sub(r"let mut a = \[\[0\.0; \d+\]; \d+\];", "", body)
    body = re.sub(r"-> *\(", "(", body)
    return count_ops(body), solver


# ---------------------------------------------------------------- table


def main():
    sizes = [int(a) for a in sys.argv[1:]] or [2, 3, 5, 8, 12, 20]
    os.makedirs(OUT, exist_ok=True)
    lagc, rust_counts, solver = lagc_side(sizes)
    rows = []
    for n in sizes:
        ldlt = solver[n] == "ldlt"
        c_us, c_z, c_ops, _ = c_side(n, ldlt)
        # The C side with the other solver too: the bar is against the faster.
        other_us = c_side(n, not ldlt)[0]
        r_us, r_z = lagc[n]
        solve = ldlt_ops(n) if ldlt else lu_ops(n)
        c_total = c_ops + solve
        # lagc solves `a z = −g`: n negations more.
        r_total = rust_counts[n] + (0 if solver[n] == "explicit" else solve + n)
        diff = max(abs(a - b) / max(abs(a), abs(b), 1e-300) for a, b in zip(c_z, r_z))
        ldlt_us, lu_us = (c_us, other_us) if ldlt else (other_us, c_us)
        rows.append(
            (n, ldlt_us, lu_us, r_us, c_ops, rust_counts[n], solve, c_total, r_total, solver[n], diff)
        )
    print(
        "| N | SymPy-cse C, LDLᵀ [µs] | SymPy-cse C, LU [µs] | lagc [µs] | lagc / faster C"
        " | SymPy-cse ops | lagc ops | solve ops | total SymPy-cse | total lagc | ops ratio"
        " | lagc solve | largest rel. diff |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for n, ldlt_us, lu_us, r_us, c_ops, r_ops, solve, c_total, r_total, how, diff in rows:
        print(
            f"| {n} | {ldlt_us:.3f} | {lu_us:.3f} | {r_us:.3f} | {r_us / min(ldlt_us, lu_us):.2f}"
            f" | {c_ops} | {r_ops} | {solve} | {c_total} | {r_total} | {r_total / c_total:.2f}"
            f" | {how} | {diff:.1e} |"
        )


if __name__ == "__main__":
    main()
