"""A model with outputs, `stop when` and a failure at run time
(tests/data/rocket_outputs.lag) as the Python module `rocket_outputs`."""

import os
import pickle
import subprocess

import numpy as np
import pytest

import lagc
import rocket_outputs as rocket
from conftest import ROOT


def test_outputs_by_name_and_the_stop():
    m = rocket.Model()
    assert m.output_names == ["mass", "energy"]
    sol = m.solve(t=np.linspace(0, 200, 201))
    assert set(sol.outputs) == {"mass", "energy"}
    # The mass law and the specific energy, from the state.
    t, z, v = sol.t, sol["z"], sol["z'"]
    assert np.allclose(sol.outputs["mass"], np.where(t < 30, 1000 - 10 * t, 700), rtol=1e-14)
    assert np.allclose(sol["energy"], v**2 / 2 + 9.81 * z, rtol=1e-12, atol=1e-9)
    # Landing: stop when z < 0, after burn-out at 30 s; the last row is there.
    assert sol.stopped_at is not None and 100 < sol.stopped_at < 200
    assert sol.t[-1] == sol.stopped_at
    assert sol.stats["stopped_at"] == sol.stopped_at
    assert sol.stats["steps"] > 0 and sol.stats["events"] >= 2


def test_outputs_equal_lagc_run_to_the_bit(run_cli):
    sol = rocket.Model(w=2100.0).solve()
    columns, rows, _ = run_cli("tests/data/rocket_outputs.lag", "--param", "w=2100")
    assert columns == sol.columns == ["t", "z", "z'", "mass", "energy"]
    assert np.array_equal(sol.rows, rows)


def test_a_failure_raises_with_its_time_quantity_and_rows():
    t = np.linspace(0, 200, 41)
    with pytest.raises(lagc.IntegrationError) as caught:
        rocket.Model(tb=150.0).solve(t=t)
    e = caught.value
    assert isinstance(e, RuntimeError) and isinstance(e, rocket.IntegrationError)
    assert abs(e.t - 100.0) < 1e-6
    assert e.quantity == "M"
    assert "the mass `M` reaches zero" in str(e) and e.message == str(e)
    # The rows before the failure: t = 0, 5, ..., 95, as the CLI writes them.
    assert np.array_equal(e.solution.t, t[t < 100])
    assert e.rows.shape == (20, 5) and e.columns == ["t", "z", "z'", "mass", "energy"]
    assert e.solution.stats is None
    done = subprocess.run(
        [os.environ["LAGC"], "run", str(ROOT / "tests/data/rocket_outputs.lag"),
         "--param", "tb=150", "--times", ",".join(str(float(v)) for v in t)],
        capture_output=True, text=True, check=False)
    assert done.returncode == 3
    assert f"error: {e.message}" in done.stderr
    cli_rows = np.array([[float(v) for v in line.split(",")]
                         for line in done.stdout.splitlines()[1:]])
    assert np.array_equal(e.rows, cli_rows)
    # It pickles (a Dask worker sends it back).
    back = pickle.loads(pickle.dumps(e))
    assert back.t == e.t and back.quantity == "M" and np.array_equal(back.rows, e.rows)


def test_batch_failures_raise_or_stand_in_place():
    m = rocket.Model()
    sets = [{"tb": 20.0}, {"tb": 150.0}, {"tb": 40.0}]
    with pytest.raises(lagc.IntegrationError):
        m.solve_batch(params=sets)
    results = m.solve_batch(params=sets, errors="return")
    assert isinstance(results[1], lagc.IntegrationError)
    assert results[0].stopped_at is not None and results[2].stopped_at is not None


def test_every_models_error_is_one_class():
    import paper
    assert paper.IntegrationError is rocket.IntegrationError is lagc.IntegrationError
