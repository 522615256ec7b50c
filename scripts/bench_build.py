#!/usr/bin/env python3
"""Build latency of `lagc run` (issue 11): the first build into an empty
cache (the runtime and one model), a model never built before once the
runtime is built, and an unchanged model. Models are N-link pendulums from
scripts/gen_pendulum.py; a "new" model is the 5-link pendulum with another
value of g (a different source, so a different crate).

Usage: python3 scripts/bench_build.py [LAGC] [REPEATS]
  LAGC     the lagc binary (default target/release/lagc; build it first)
  REPEATS  new-model builds to time (default 5); their median and range

Each `lagc run` is timed whole, from start to exit (`--samples 2`, so the
integration itself is a few milliseconds). Cargo's dependencies must be
present (the runtime has none).
"""

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gen_pendulum import model  # noqa: E402


def timed_run(lagc: str, path: str, cache: str) -> float:
    env = dict(os.environ, LAGC_CACHE_DIR=cache)
    start = time.monotonic()
    done = subprocess.run(
        [lagc, "run", path, "--samples", "2", "--quiet"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    elapsed = time.monotonic() - start
    if done.returncode != 0:
        sys.exit(f"lagc run {path} failed ({done.returncode}):\n{done.stderr}")
    return elapsed


def main() -> None:
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    lagc = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "target/release/lagc")
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    work = tempfile.mkdtemp(prefix="lagc-build-latency-")
    cache = os.path.join(work, "cache")
    try:
        def write(name: str, text: str) -> str:
            path = os.path.join(work, name)
            with open(path, "w") as f:
                f.write(text)
            return path

        first = timed_run(lagc, write("pendulum_3.lag", model(3)), cache)
        five = write("pendulum_5.lag", model(5))
        new = [timed_run(lagc, five, cache)]
        unchanged = [timed_run(lagc, five, cache) for _ in range(repeats)]
        for k in range(1, repeats):
            text = model(5).replace("g = 9.81", f"g = 9.8{k}")
            new.append(timed_run(lagc, write(f"pendulum_5_{k}.lag", text), cache))
    finally:
        shutil.rmtree(work, ignore_errors=True)

    def row(what: str, times: list) -> str:
        return (
            f"| {what} | {statistics.median(times):.2f} s | "
            f"{min(times):.2f}–{max(times):.2f} s | {len(times)} |"
        )

    print("| `lagc run`, --samples 2 | median | range | runs |")
    print("|---|---|---|---|")
    print(row("first build, empty cache (runtime + 3-link pendulum)", [first]))
    print(row("a 5-link pendulum never built before", new))
    print(row("the same model again, unchanged", unchanged))


if __name__ == "__main__":
    main()
