"""The cost of one fmi2DoStep against the same dense output in `lagc run`
(issue 26), side by side in one process: the paper's example at rtol 1e-10,
5000 communication steps of 1e-3 over its span [0, 5] against `lagc run
--samples 5001` (the same 5001 rows from the same integration: the FMU's
steps are lagc run's, tests/it/fmu.rs checks it).

    target/fmpy-venv/bin/python scripts/fmu_bench.py LAGC PAPER.fmu [ROUNDS]

Each round, in turn:
- `lagc run examples/paper.lag --rtol 1e-10 --samples 5001 --quiet
  --repeat 5 --summary json`: the fastest of 5 solves, timed inside the
  model's binary (`wall_time_s`: the integration and its 5001 samples
  read from the dense output, no CSV written);
- the FMU through ctypes (no FMPy loop): 5000 × (fmi2DoStep of 1e-3 and
  fmi2GetReal of the 4 state components, what an importer reads), the
  fastest of 5 fresh instances, only the stepping loop timed;
- the same 5000 pairs of calls on a null instance (refused at once): what
  Python and ctypes cost around the FMU's own work.
Prints every round and the medians.
"""

import ctypes
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import fmpy
from fmpy.fmi2 import FMU2Slave

ROOT = Path(__file__).resolve().parents[1]
N = 5000
H = 1e-3
RTOL = 1e-10


def lagc_run(lagc):
    done = subprocess.run(
        [lagc, "run", str(ROOT / "examples/paper.lag"), "--rtol", "1e-10", "--samples", "5001",
         "--quiet", "--repeat", "5", "--summary", "json"],
        capture_output=True, text=True, check=True,
    )
    summary = json.loads(done.stderr.strip().splitlines()[-1])
    return summary["wall_time_s"], summary["steps"]


def fmu_loop(path, md, unzipped):
    refs = {v.name: v.valueReference for v in md.modelVariables}
    vrs = (ctypes.c_uint * 4)(*[refs[n] for n in ["q1", "q2", "der(q1)", "der(q2)"]])
    values = (ctypes.c_double * 4)()
    best = float("inf")
    for _ in range(5):
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
        fmu.instantiate()
        fmu.setupExperiment(tolerance=RTOL, startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        do_step = fmu.dll.fmi2DoStep
        do_step.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
        get_real = fmu.dll.fmi2GetReal
        get_real.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint), ctypes.c_size_t,
                             ctypes.POINTER(ctypes.c_double)]
        component = fmu.component
        start = time.perf_counter()
        for i in range(N):
            if do_step(component, i * H, H, 1) != 0 or get_real(component, vrs, 4, values) != 0:
                raise RuntimeError(f"the FMU failed at step {i}")
        best = min(best, time.perf_counter() - start)
        fmu.terminate()
        fmu.freeInstance()
    return best


def ctypes_floor(path, md, unzipped):
    """The same loop of the same two calls on a null instance, which both
    refuse at once: what Python and ctypes cost around the FMU's work."""
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="floor")
    do_step = fmu.dll.fmi2DoStep
    do_step.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
    get_real = fmu.dll.fmi2GetReal
    get_real.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint), ctypes.c_size_t,
                         ctypes.POINTER(ctypes.c_double)]
    vrs = (ctypes.c_uint * 4)(0, 1, 2, 3)
    values = (ctypes.c_double * 4)()
    best = float("inf")
    for _ in range(5):
        start = time.perf_counter()
        for i in range(N):
            if do_step(None, i * H, H, 1) != 3 or get_real(None, vrs, 4, values) != 3:
                raise RuntimeError("a null instance was not refused")
        best = min(best, time.perf_counter() - start)
    return best


def main():
    lagc, path = sys.argv[1], sys.argv[2]
    rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 7
    md = fmpy.read_model_description(path)
    unzipped = fmpy.extract(path)
    rows = []
    for r in range(rounds):
        run, steps = lagc_run(lagc)
        fmu = fmu_loop(path, md, unzipped)
        floor = ctypes_floor(path, md, unzipped)
        rows.append((run, fmu, floor))
        print(f"round {r + 1}: lagc run {run * 1e3:.3f} ms ({steps} steps), FMU loop {fmu * 1e3:.3f} ms, "
              f"ctypes floor {floor * 1e3:.3f} ms; ratio {fmu / run:.2f}")
    run = statistics.median(r[0] for r in rows)
    fmu = statistics.median(r[1] for r in rows)
    floor = statistics.median(r[2] for r in rows)
    ratio = statistics.median(r[1] / r[0] for r in rows)
    print(f"median over {rounds} rounds: lagc run {run / N * 1e6:.3f} us a row, FMU {fmu / N * 1e6:.3f} us a "
          f"fmi2DoStep + fmi2GetReal, of which {floor / N * 1e6:.3f} us the calls from Python: "
          f"{(fmu - floor) / N * 1e6:.3f} us in the FMU; ratio FMU/lagc run {ratio:.2f} with the calls, "
          f"{statistics.median((r[1] - r[2]) / r[0] for r in rows):.2f} without")


if __name__ == "__main__":
    main()
