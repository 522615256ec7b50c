"""The FMI cross-check files of lagc's FMUs, made from `lagc run` and
checked by FMPy's cross-check validation (fmpy.cross_check, the route the
Modelica FMI cross-check repository used).

    python cross_check.py LAGC REPO FMUS OUT

LAGC is the lagc binary, REPO the repository (the models), FMUS a folder
holding NAME.fmu for every model below, OUT the folder the cross-check tree
is written into:

    OUT/fmus/2.0/cs/linux64/lagc/VERSION/NAME/{NAME.fmu, NAME_ref.csv, NAME_ref.opt[, NAME_in.csv]}
    OUT/results/2.0/cs/linux64/FMPy/FMPY_VERSION/lagc/VERSION/NAME/{NAME_out.csv, passed}

For every model: `_ref.csv` (quoted FMI names, every state component and
output) and `_ref.opt` (StartTime, StopTime, StepSize, RelTol) from
`lagc run` at RelTol, `_in.csv` for a driven one (its input signal); the
FMU folder checked by `validate_test_fmu`; FMPy simulates the FMU as a
cross-check importer does (the options file's span, step and tolerance,
the `_in.csv` input) into `_out.csv`, checked against `_ref.csv` by
`validate_cross_check_result` (the epsilon band, at most 10 % outliers)
and, tighter, to 10 RelTol at every row. A perturbed reference must fail
the same validation (the check can fail). Prints what it measured; exits
non-zero (an assertion) when a check fails.
"""

import csv
import io
import os
import shutil
import subprocess
import sys

import fmpy
import numpy as np
from fmpy.cross_check import validate_result
from fmpy.cross_check.validate_vendor_repo import (
    read_csv,
    validate_cross_check_result,
    validate_test_fmu,
)
from fmpy.util import read_ref_opt_file

RTOL = 1e-10
ROWS = 501

# (name, the model under the repository, input signal rows (t, value) or None)
MODELS = [
    # Variable mass and a non-holonomic constraint (SPEC 1.6).
    ("paper", "examples/paper.lag", None),
    # A knife edge turning: a non-holonomic constraint of the state.
    ("knife_edge_turning", "examples/knife_edge_turning.lag", None),
    # A rocket burning its mass down (a mass law), no stop.
    ("vertical_rocket", "examples/vertical_rocket.lag", None),
    # A force set from outside, stepping twice (`_in.csv`).
    (
        "driven_oscillator",
        "tests/data/driven_oscillator.lag",
        ("F", [(0.0, 1.0), (1.0, -2.0), (3.0, 0.5)]),
    ),
]


def fmi_name(column):
    """lagc's CSV column (`q1''`) as the FMU names it (`der(q1,2)`)."""
    q = column.rstrip("'")
    order = len(column) - len(q)
    return q if order == 0 else f"der({q})" if order == 1 else f"der({q},{order})"


def lagc_run(lagc, model, args):
    done = subprocess.run([lagc, "run", model, *args], capture_output=True, text=True, check=False)
    assert done.returncode == 0, f"lagc run {model} failed:\n{done.stderr}"
    reader = csv.reader(io.StringIO(done.stdout))
    header = next(reader)
    rows = np.array([[float(v) for v in row] for row in reader])
    return header, rows


def write_csv(path, names, rows):
    """A CSV as the cross-check rules want it: quoted names, time first."""
    with open(path, "w") as f:
        f.write(",".join(f'"{n}"' for n in names) + "\n")
        for row in rows:
            f.write(",".join(repr(float(v)) for v in row) + "\n")


def version(lagc):
    done = subprocess.run([lagc, "--version"], capture_output=True, text=True, check=True)
    return done.stdout.split()[-1]


def one(lagc, repo, fmus, out, tool_version, name, model, signal):
    fmu_dir = os.path.join(out, "fmus", "2.0", "cs", "linux64", "lagc", tool_version, name)
    result_dir = os.path.join(
        out, "results", "2.0", "cs", "linux64", "FMPy", fmpy.__version__, "lagc", tool_version, name
    )
    for d in (fmu_dir, result_dir):
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
    fmu = os.path.join(fmu_dir, f"{name}.fmu")
    shutil.copy(os.path.join(fmus, f"{name}.fmu"), fmu)

    # The reference from lagc run: ROWS evenly spaced rows over the span.
    args = ["--rtol", repr(RTOL), "--atol", repr(RTOL * 1e-2), "--samples", str(ROWS)]
    input_rows = None
    if signal is not None:
        input_name, steps = signal
        lagc_signal = os.path.join(fmu_dir, f"{name}_lagc_input.csv")
        with open(lagc_signal, "w") as f:
            f.write(f"t,{input_name}\n" + "".join(f"{t!r},{v!r}\n" for t, v in steps))
        args += ["--input", f"{input_name}={lagc_signal}"]
    header, rows = lagc_run(lagc, os.path.join(repo, model), args)
    if signal is not None:
        os.remove(lagc_signal)
        # The same steps as the cross-check input: a step is two rows at
        # one time (FMPy holds between rows of equal value).
        t1 = float(rows[-1, 0])
        input_rows = []
        for k, (t, v) in enumerate(steps):
            if k > 0:
                input_rows.append((t, steps[k - 1][1]))
            input_rows.append((t, v))
        input_rows.append((t1, steps[-1][1]))
        write_csv(os.path.join(fmu_dir, f"{name}_in.csv"), ["time", input_name], input_rows)
    names = ["time"] + [fmi_name(c) for c in header[1:]]
    write_csv(os.path.join(fmu_dir, f"{name}_ref.csv"), names, rows)
    t0, t1 = float(rows[0, 0]), float(rows[-1, 0])
    step = (t1 - t0) / (ROWS - 1)
    with open(os.path.join(fmu_dir, f"{name}_ref.opt"), "w") as f:
        f.write(f"StartTime,{t0!r}\nStopTime,{t1!r}\nStepSize,{step!r}\nRelTol,{RTOL!r}\n")

    problems = validate_test_fmu(fmu_dir)
    assert problems == [], problems

    # As a cross-check importer: the options file's span, step and
    # tolerance, the `_in.csv` input, the `_ref.csv` columns as outputs.
    opt = read_ref_opt_file(os.path.join(fmu_dir, f"{name}_ref.opt"))
    reference = read_csv(os.path.join(fmu_dir, f"{name}_ref.csv"))
    inputs = None
    if signal is not None:
        inputs = read_csv(os.path.join(fmu_dir, f"{name}_in.csv"))
    result = fmpy.simulate_fmu(
        fmu,
        start_time=opt["StartTime"],
        stop_time=opt["StopTime"],
        output_interval=opt["StepSize"],
        relative_tolerance=opt["RelTol"],
        input=inputs,
        output=list(reference.dtype.names[1:]),
    )
    write_csv(
        os.path.join(result_dir, f"{name}_out.csv"),
        result.dtype.names,
        [list(r) for r in result],
    )
    open(os.path.join(result_dir, "passed"), "w").close()
    problems = validate_cross_check_result(result_dir)
    assert problems == [], problems

    # Tighter than the band: every row within 10 RelTol of lagc run,
    # except at an input's change times, where the two read an output of
    # the input on either side of the step (lagc's row after it, FMPy's
    # before it sets the next input): those rows pass the band only.
    assert len(result) == len(reference), (len(result), len(reference))
    changes = [t for t, _ in signal[1][1:]] if signal is not None else []
    compared = ~np.isin(reference["time"], changes)
    assert np.count_nonzero(~compared) == len(changes), changes
    worst = max(
        float(
            np.max(
                np.abs(result[n][compared] - reference[n][compared])
                / np.maximum(1.0, np.abs(reference[n][compared]))
            )
        )
        for n in reference.dtype.names
    )
    assert worst <= 10 * RTOL, worst

    # The validation can fail: one signal moved by a fifth of its range
    # is outside the band almost everywhere.
    moved = reference.copy()
    column = reference.dtype.names[-1]
    spread = max(float(np.ptp(moved[column])), 1.0)
    moved[column] = moved[column] + 0.2 * spread
    problem = validate_result(result=result, reference=moved, t_start=opt["StartTime"], t_stop=opt["StopTime"])
    assert problem is not None and column in problem, problem
    print(
        f"{name}: {len(names) - 1} columns at {len(rows)} rows; validate_test_fmu and "
        f"validate_cross_check_result: no problems; largest difference from lagc run {worst:.3e}; "
        f"`{column}` moved by {0.2 * spread:.3g}: {problem}"
    )


if __name__ == "__main__":
    lagc, repo, fmus, out = sys.argv[1:5]
    tool_version = version(lagc)
    for name, model, signal in MODELS:
        one(lagc, repo, fmus, out, tool_version, name, model, signal)
