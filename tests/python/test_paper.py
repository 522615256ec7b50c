"""The paper's example (examples/paper.lag) as the Python module `paper`."""

import pickle

import numpy as np
import pytest

import paper


def exact_velocities(t, alpha, v0=1.0):
    """The file's `exact` lines: q1' = v0 e^(alpha t)/sqrt(1 + t^2), q2' = t q1'."""
    q1 = v0 * np.exp(alpha * t) / np.sqrt(1 + t**2)
    return q1, t * q1


def test_names_and_params_are_the_models():
    m = paper.Model()
    assert m.params == {"M0": 1.0, "alpha": 0.5}
    assert m.state_names == ["q1", "q2", "q1'", "q2'"]
    assert m.output_names == []
    assert m.time_span == (0.0, 5.0)
    assert paper.Model(alpha=2.0).params == {"M0": 1.0, "alpha": 2.0}


@pytest.mark.parametrize("method", ["field", "direct"])
def test_within_1e_10_of_the_exact_solution(method):
    t = np.linspace(0.0, 5.0, 51)
    sol = paper.Model().solve(t=t, method=method, rtol=1e-12, atol=1e-14)
    q1, q2 = exact_velocities(t, 0.5)
    assert sol.t.shape == (51,) and sol.y.shape == (51, 4)
    assert np.array_equal(sol.t, t)
    error = max(np.max(np.abs(sol["q1'"] - q1) / np.maximum(np.abs(q1), 1)),
                np.max(np.abs(sol["q2'"] - q2) / np.maximum(np.abs(q2), 1)))
    assert error <= 1e-10, error
    # The same error the summary reports against the exact lines.
    assert sol.stats["exact_error"] <= 1e-10


@pytest.mark.parametrize("method", ["field", "direct"])
def test_a_solve_without_its_global_error_estimate_has_the_same_rows(method):
    m = paper.Model()
    with_estimate = m.solve(method=method, rtol=1e-9)
    without = m.solve(method=method, rtol=1e-9, global_error=False)
    assert np.array_equal(with_estimate.y, without.y)
    assert with_estimate.stats["global_error_estimate"] is not None
    assert without.stats["global_error_estimate"] is None
    assert without.stats["rhs_evaluations"] <= with_estimate.stats["rhs_evaluations"]
    batch = m.solve_batch(params=[{"alpha": 0.5}], method=method, rtol=1e-9, global_error=False)
    assert np.array_equal(batch[0].y, without.y)
    assert batch[0].stats["global_error_estimate"] is None


def test_changed_params_and_initial_values_follow_the_exact_solution():
    t = np.linspace(0.0, 3.0, 31)
    sol = paper.Model(alpha=0.8).solve(t=t, initial={"q1'": 2.0}, rtol=1e-12, atol=1e-14)
    q1, q2 = exact_velocities(t, 0.8, v0=2.0)
    assert np.max(np.abs(sol["q1'"] - q1) / np.maximum(np.abs(q1), 1)) <= 1e-10
    assert np.max(np.abs(sol["q2'"] - q2) / np.maximum(np.abs(q2), 1)) <= 1e-10


@pytest.mark.parametrize("method", ["field", "direct"])
def test_solve_equals_lagc_run_to_the_bit(run_cli, method):
    m = paper.Model(alpha=0.8)
    sol = m.solve(initial={"q1'": 2.0}, method=method)
    columns, rows, _ = run_cli(
        "examples/paper.lag", "--param", "alpha=0.8", "--init", "q1'=2", "--method", method
    )
    assert columns == ["t"] + m.state_names
    assert np.array_equal(sol.t, rows[:, 0])
    assert np.array_equal(sol.y, rows[:, 1:])
    # And at chosen times, with other tolerances.
    t = [0.0, 0.1, 1.7, 4.99]
    sol = m.solve(t=t, method=method, rtol=1e-8, atol=1e-10)
    _, rows, _ = run_cli(
        "examples/paper.lag", "--param", "alpha=0.8", "--method", method,
        "--times", ",".join(map(repr, t)), "--rtol", "1e-8", "--atol", "1e-10",
    )
    assert np.array_equal(sol.rows, rows)


def test_stats_are_the_summary_figures(run_cli):
    sol = paper.Model().solve()
    _, _, stderr = run_cli("examples/paper.lag", "--summary", "json", "--quiet")
    import json
    cli = json.loads(stderr.strip().splitlines()[-1])
    for key in ["method", "steps", "rejected_steps", "rhs_evaluations", "largest_condition",
                "reanchorings", "exact_error"]:
        assert sol.stats[key] == cli[key], key
    assert sol.stopped_at is None


def test_rhs_and_jacobian_are_the_equations_of_motion():
    # q1'' = (alpha - t/(1 + t^2)) q1', q2'' = (alpha t + 1/(1 + t^2)) q1'.
    m = paper.Model(alpha=0.3)
    t, x = 1.5, np.array([0.2, -0.1, 0.7, 1.05])
    a = 0.3 - t / (1 + t**2)
    b = 0.3 * t + 1 / (1 + t**2)
    assert np.allclose(m.rhs(t, x), [0.7, 1.05, a * 0.7, b * 0.7], rtol=1e-14)
    jac = m.jacobian(t, x)
    assert jac.shape == (4, 4)
    # Against central differences of rhs.
    h = 1e-6
    diff = np.array([(m.rhs(t, x + h * e) - m.rhs(t, x - h * e)) / (2 * h)
                     for e in np.eye(4)]).T
    assert np.allclose(jac, diff, atol=1e-8)


def test_unknown_names_raise_key_error_naming_the_known_ones():
    with pytest.raises(KeyError, match="M0, alpha"):
        paper.Model(beta=1.0)
    with pytest.raises(KeyError, match="q1, q2, q1', q2'"):
        paper.Model().solve(initial={"q3": 1.0})
    sol = paper.Model().solve()
    with pytest.raises(KeyError, match="q1'"):
        sol["nope"]


def test_bad_arguments_raise_value_error():
    m = paper.Model()
    with pytest.raises(ValueError, match="field"):
        m.solve(method="euler")
    with pytest.raises(ValueError, match="increasing"):
        m.solve(t=[1.0, 0.5])
    with pytest.raises(ValueError, match="before the start"):
        m.solve(t=[-1.0, 1.0])
    with pytest.raises(ValueError):
        m.rhs(0.0, [1.0, 2.0])


def test_pickle_round_trip_is_equal():
    m = paper.Model(alpha=0.9)
    back = pickle.loads(pickle.dumps(m))
    assert back == m and back.params == m.params and type(back) is paper.Model
    a, b = m.solve(), back.solve()
    assert np.array_equal(a.y, b.y)
    sol = pickle.loads(pickle.dumps(a))
    assert np.array_equal(sol.t, a.t) and np.array_equal(sol.y, a.y)
    assert sol.stats == a.stats and sol.state_names == a.state_names


def test_solve_batch_equals_serial_solves():
    m = paper.Model(M0=2.0)
    sets = [{"alpha": 0.05 * k} for k in range(40)]
    t = np.linspace(0, 5, 21)
    batch = m.solve_batch(t=t, params=sets, initial={"q1'": 1.5}, threads=2)
    assert len(batch) == 40
    for p, sol in zip(sets, batch):
        serial = paper.Model(M0=2.0, **p).solve(t=t, initial={"q1'": 1.5})
        assert np.array_equal(sol.y, serial.y)
    one_thread = m.solve_batch(t=t, params=sets, initial={"q1'": 1.5}, threads=1)
    assert all(np.array_equal(a.y, b.y) for a, b in zip(batch, one_thread))
