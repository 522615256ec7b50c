"""Shared set-up of the Python module's tests (tests/it/python.rs runs them).

They run against the *installed* modules `paper` (examples/paper.lag),
`rocket_outputs` (tests/data/rocket_outputs.lag) and `driven_oscillator`
(tests/data/driven_oscillator.lag, an input), and for `Model.linearize`
(test_linearize.py) `spherical_pendulum`, `double_pendulum_energy`,
`rolling_disk`, `knife_edge`, `rolling_disk_3d`, `cartesian_pendulum`,
`chaplygin_sleigh`, `particle_on_circle`, `four_bar_closure`,
`third_order_constraint` (examples/), `spherical_pendulum_cartesian`
(tests/data/v2/) and
`steered_spring` (tests/data/), built by
`lagc build --python` and pip-installed into a virtual environment of their
own. The environment gives:

- LAGC: the `lagc` binary, for the runs these tests compare with;
- LAGC_ROOT: the repository;
- LAGC_WHEELS: the folder holding each model's wheel (one folder a model).
"""

import csv
import io
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(os.environ.get("LAGC_ROOT", Path(__file__).resolve().parents[2]))


def lagc_run(model, *args):
    """`lagc run MODEL ARGS`: (columns, rows as a float array, stderr)."""
    lagc = os.environ["LAGC"]
    done = subprocess.run(
        [lagc, "run", str(ROOT / model), *args],
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        raise AssertionError(f"lagc run failed ({done.returncode}):\n{done.stderr}")
    reader = csv.reader(io.StringIO(done.stdout))
    columns = next(reader, [])
    rows = np.array([[float(v) for v in row] for row in reader])
    return columns, rows, done.stderr


@pytest.fixture
def run_cli():
    return lagc_run
