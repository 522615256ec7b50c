"""Inputs from Python (issue 26): `solve(inputs=..., input_interp=...)` and
`Integration.set_input`, on the driven oscillator (tests/data/
driven_oscillator.lag: m x'' + k x = F, F an input, m = 2, k = 8),
against `lagc run --input` (to the bit) and the motion known by pieces."""

import json

import numpy as np
import pytest

import driven_oscillator as osc
import lagc

MODEL = "tests/data/driven_oscillator.lag"
# F steps at t = 1 and t = 3 (rows repeating a value are no change).
SIGNAL_T = [0.0, 1.0, 2.0, 3.0, 4.5]
SIGNAL_F = [1.0, -2.0, -2.0, 0.5, 0.5]


def oscillator(pieces, t, m=2.0, k=8.0):
    """x, x' at t from rest at 0, F = c + r (t - tau) on each piece."""
    w = np.sqrt(k / m)
    x = v = 0.0
    for i, (tau, c, r) in enumerate(pieces):
        if tau > t:
            break
        end = min(pieces[i + 1][0] if i + 1 < len(pieces) else np.inf, t)
        a, b, s = x - c / k, (v - r / k) / w, end - tau
        x = (c + r * s) / k + a * np.cos(w * s) + b * np.sin(w * s)
        v = r / k - a * w * np.sin(w * s) + b * w * np.cos(w * s)
    return x, v


def write_signal(path, times, values):
    path.write_text("t,F\n" + "".join(f"{t!r},{v!r}\n" for t, v in zip(times, values)))
    return str(path)


@pytest.mark.parametrize("method", ["field", "direct"])
@pytest.mark.parametrize("interp", ["hold", "linear"])
def test_solve_with_inputs_equals_lagc_run_input_to_the_bit(run_cli, tmp_path, method, interp):
    m = osc.Model()
    assert m.input_names == ["F"]
    sol = m.solve(
        inputs={"F": (np.array(SIGNAL_T), SIGNAL_F)}, input_interp=interp, method=method
    )
    csv = write_signal(tmp_path / "F.csv", SIGNAL_T, SIGNAL_F)
    columns, rows, stderr = run_cli(
        MODEL, "--input", f"F={csv}", "--input-interp", interp, "--method", method,
        "--summary", "json",
    )
    assert columns == ["t"] + m.state_names + m.output_names
    assert np.array_equal(sol.t, rows[:, 0])
    assert np.array_equal(sol.y, rows[:, 1:3])
    assert np.array_equal(sol.outputs["force"], rows[:, 3])
    # The same work (the restarts included: a run without them differs).
    cli = json.loads(stderr.strip().splitlines()[-1])
    for key in ["steps", "rejected_steps", "rhs_evaluations", "jacobian_evaluations"]:
        assert sol.stats[key] == cli[key], key
    plain = m.solve(method=method)
    assert not np.array_equal(plain.y, sol.y)
    # solve_batch drives every set the same way.
    batch = m.solve_batch(
        params=[{}, {"k": 8.0}], inputs={"F": (SIGNAL_T, SIGNAL_F)}, input_interp=interp,
        method=method,
    )
    assert all(np.array_equal(b.y, sol.y) for b in batch)


def test_a_held_step_is_the_motion_by_pieces():
    sol = osc.Model().solve(
        t=np.linspace(0.0, 5.0, 41), inputs={"F": (SIGNAL_T, SIGNAL_F)}, rtol=1e-10, atol=1e-12
    )
    pieces = [(0.0, 1.0, 0.0), (1.0, -2.0, 0.0), (3.0, 0.5, 0.0)]
    exact = np.array([oscillator(pieces, t) for t in sol.t])
    error = np.max(np.abs(sol.y - exact) / np.maximum(np.abs(exact), 1.0))
    assert error <= 10 * 1e-10, error
    # The output reads the input as held: F just after each change.
    assert sol.outputs["force"][sol.t == 1.0][0] == -2.0
    assert sol.outputs["force"][-1] == 0.5


@pytest.mark.parametrize("method", ["field", "direct"])
def test_set_input_restarts_where_it_stands_as_a_signal_does(method):
    # Stepping to the change times and setting F there is the run a held
    # signal makes: the same restarts at the same states, bit for bit.
    m = osc.Model()
    times = np.linspace(0.0, 5.0, 21)
    whole = m.solve(t=times, inputs={"F": (SIGNAL_T, SIGNAL_F)}, method=method)
    it = m.integration(method=method)
    assert it.inputs == {"F": 0.5}  # the file's default until set
    it.set_input("F", 1.0)
    states = []
    for t in times:
        for tau, value in [(1.0, -2.0), (3.0, 0.5)]:
            if it.t < tau <= t:
                it.advance_to(tau)
                it.set_input("F", value)
        if t > it.t:
            it.advance_to(t)
        states.append(it.state)
    assert it.inputs == {"F": 0.5}
    assert np.array_equal(np.array(states), whole.y)
    # Setting the value it holds changes nothing; a new one restarts
    # from where the integration stands, with the motion continuous.
    before = it.stats["steps"]
    it.set_input("F", 0.5)
    assert it.stats["steps"] == before


def test_input_misuse_is_refused_in_words():
    m = osc.Model()
    with pytest.raises(KeyError, match="the inputs are: F"):
        m.solve(inputs={"G": ([0.0], [1.0])})
    with pytest.raises(ValueError, match="hold"):
        m.solve(inputs={"F": ([0.0], [1.0])}, input_interp="cubic")
    with pytest.raises(ValueError, match="must increase"):
        m.solve(inputs={"F": ([0.0, 0.0], [1.0, 2.0])})
    with pytest.raises(ValueError, match="at least one row"):
        m.solve(inputs={"F": ([0.0, 1.0], [1.0])})
    with pytest.raises(ValueError, match="pair"):
        m.solve(inputs={"F": 1.0})
    it = m.integration()
    with pytest.raises(KeyError, match="the inputs are: F"):
        it.set_input("G", 1.0)
    with pytest.raises(ValueError, match="finite"):
        it.set_input("F", float("nan"))
    import paper

    with pytest.raises(KeyError, match="the model has no inputs"):
        paper.Model().solve(inputs={"u": ([0.0], [1.0])})


def test_times_past_the_end_are_refused_and_integration_may_go_on():
    m = osc.Model()
    assert m.time_span == (0.0, 5.0)
    with pytest.raises(ValueError, match="past the end of the time span"):
        m.solve(t=[0.0, 6.0])
    assert m.solve(t=[0.0, 5.0]).t[-1] == 5.0
    # An integration may be asked for a later end explicitly.
    it = m.integration(t_end=6.0)
    assert it.end == 6.0 and it.advance_to(6.0) == 6.0
    x, v = oscillator([(0.0, 0.5, 0.0)], 6.0)
    assert abs(it.state[0] - x) < 1e-8 and abs(it.state[1] - v) < 1e-8
    with pytest.raises(ValueError, match="t_end"):
        m.integration(t_end=-1.0)
    with pytest.raises(lagc.IntegrationError):
        m.integration().advance_to(6.0)


def test_sensitivities_of_a_driven_run_are_refused_in_words():
    """Sensitivities do not follow an input's changes yet: asking for both
    raises ValueError (as `lagc run --sensitivity --input` exits 2), never
    columns that ignore the signal; undriven, the same model has them."""
    m = osc.Model()
    with pytest.raises(ValueError, match="inputs"):
        m.solve(t=[0.0, 1.0, 2.0], inputs={"F": (SIGNAL_T, SIGNAL_F)}, sensitivity=True)
    sol = m.solve(t=[0.0, 1.0, 2.0], sensitivity=True)
    assert sol.sensitivity.shape[0] == 3
