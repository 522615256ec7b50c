"""Python module figures for docs/BENCHMARKS.md (issue 25).

Run with the Python of the test environment, after `cargo test --test it
python_modules` built and installed the modules there:

    target/python-tests/venv/bin/python scripts/python_bench.py

1. `solve` overhead: for each call, the wall time of `paper.Model().solve()`
   around the call minus the run's own wall time that the runtime measures
   inside it (`stats["wall_time_s"]`, the integration proper): what Python
   adds — argument conversion, the run's preparation (the initial state and
   its checks, which a Rust caller of `lagc_runtime::table::tabulate` pays
   too), the NumPy arrays. Median and 10th percentile over 3000 calls.
2. `solve_batch` of 1,000 parameter sets on 1 thread and on 2 threads,
   alternated, best of 15 each, with the CPU share the two threads got.
   `--batch N` times one batch on N threads (for pairing runs from outside).
3. (with --build) the wheel of a model not built before, with the libraries
   built already in the shared target directory (`lagc build --python` then
   `pip wheel`), as tests/it/python.rs builds them.
"""

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import paper

ROOT = Path(__file__).resolve().parents[1]


def overhead(calls=3000):
    m = paper.Model()
    for _ in range(300):
        m.solve()
    total, inside = [], []
    for _ in range(calls):
        start = time.perf_counter()
        sol = m.solve()
        total.append(time.perf_counter() - start)
        inside.append(sol.stats["wall_time_s"])
    total, inside = np.array(total) * 1e6, np.array(inside) * 1e6
    extra = total - inside
    print(f"solve: median {np.median(total):.1f} us, of which the run {np.median(inside):.1f} us; "
          f"Python adds median {np.median(extra):.1f} us (10th percentile "
          f"{np.percentile(extra, 10):.1f} us) over {calls} calls")


def batch(sets=1000, rounds=15):
    """Best wall time of `solve_batch` on 1 and 2 threads, alternated, and
    the largest CPU share the two threads got (CPU time / wall time: 2 when
    both cores were free)."""
    m = paper.Model()
    params = [{"alpha": a} for a in np.linspace(0.0, 1.0, sets)]
    best, share = {1: float("inf"), 2: float("inf")}, 0.0
    for _ in range(rounds):
        for threads in (1, 2):
            start, cpu = time.perf_counter(), time.process_time()
            m.solve_batch(params=params, threads=threads)
            wall = time.perf_counter() - start
            best[threads] = min(best[threads], wall)
            if threads == 2:
                share = max(share, (time.process_time() - cpu) / wall)
        time.sleep(0.5)
    print(f"solve_batch of {sets} sets: 1 thread {best[1]:.3f} s, 2 threads {best[2]:.3f} s, "
          f"speed-up {best[1] / best[2]:.2f}x; largest CPU share of the 2 threads {share:.2f}")


def build(model="examples/vertical_rocket.lag"):
    base = ROOT / "target/python-tests"
    project = base / "bench-project"
    shutil.rmtree(project, ignore_errors=True)
    env = dict(os.environ, CARGO_TARGET_DIR=str(base / "target"), RUSTFLAGS="-D warnings",
               PATH=f"{Path(sys.executable).parent}:{os.environ['PATH']}")
    lagc = os.environ.get("LAGC", str(ROOT / "target/debug/lagc"))
    start = time.perf_counter()
    subprocess.run([lagc, "build", "--python", str(ROOT / model), "-o", str(project),
                    "--runtime", str(base / "lagc-runtime"),
                    "--python-lib", str(base / "lagc-python")], check=True, env=env)
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                    "--no-build-isolation", "-w", str(project / "wheel"), str(project)],
                   check=True, env=env)
    print(f"a new model's wheel ({model}) after the first: {time.perf_counter() - start:.1f} s")


def batch_once(threads, sets=1000):
    """One `solve_batch` of `sets` sets on `threads` threads: its seconds."""
    m = paper.Model()
    params = [{"alpha": a} for a in np.linspace(0.0, 1.0, sets)]
    start, cpu = time.perf_counter(), time.process_time()
    m.solve_batch(params=params, threads=threads)
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    print(f"threads {threads}: {wall:.4f} s wall, {cpu:.4f} s cpu")


if __name__ == "__main__":
    if "--batch" in sys.argv:
        batch_once(int(sys.argv[sys.argv.index("--batch") + 1]))
        sys.exit(0)
    overhead()
    batch()
    if "--build" in sys.argv:
        build()
