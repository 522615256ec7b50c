"""Stepping: `Model.integration`, `advance_to`, `t`, `state`."""

import numpy as np
import pytest

import lagc
import paper
import rocket_outputs as rocket


@pytest.mark.parametrize("method", ["field", "direct"])
def test_ten_pieces_equal_one_solve_to_rtol(method):
    m = paper.Model(alpha=0.7)
    rtol = 1e-10
    times = np.linspace(0.0, 5.0, 11)
    it = m.integration(method=method, rtol=rtol, atol=1e-12)
    assert it.t == 0.0 and np.array_equal(it.state, m.solve(t=[0.0]).y[0])
    states = [it.state]
    for t in times[1:]:
        assert it.advance_to(t) == t and it.t == t
        states.append(it.state)
    whole = m.solve(t=times, method=method, rtol=rtol, atol=1e-12)
    states = np.array(states)
    difference = np.max(np.abs(states - whole.y) / np.maximum(np.abs(whole.y), 1))
    assert difference <= rtol, difference
    assert it.stats["steps"] > 0


def test_advance_stops_where_the_motion_ends_and_fails_with_its_time():
    it = rocket.Model().integration()
    reached = it.advance_to(200.0)
    assert reached < 200.0 and it.stopped_at == reached and it.t == reached
    assert set(it.outputs) == {"mass", "energy"}
    failing = rocket.Model(tb=150.0).integration()
    assert failing.advance_to(50.0) == 50.0
    with pytest.raises(lagc.IntegrationError) as caught:
        failing.advance_to(120.0)
    assert abs(caught.value.t - 100.0) < 1e-6 and caught.value.quantity == "M"


def test_restart_from_a_given_state():
    m = paper.Model()
    it = m.integration()
    it.advance_to(1.0)
    state = it.state
    state[2] *= 2.0  # twice q1'; the constraint q2' = t q1' no longer holds
    with pytest.raises(lagc.IntegrationError) as caught:
        it.restart(1.0, state)
    assert caught.value.quantity == "q2'"
    # Projected onto q2' = t q1' as the run keeps it (along the normal:
    # q1' = q2' = 1.5 q1'(1) at t = 1).
    it.restart(1.0, state, project=True)
    assert it.t == 1.0
    assert it.state[3] == pytest.approx(it.state[2], rel=1e-12)
    assert it.state[2] == pytest.approx(1.5 * (state[2] / 2.0), rel=1e-12)
    # From there the motion is the paper's scaled: its velocities are
    # linear in q1'(1).
    scale = it.state[2] / (state[2] / 2.0)
    it.advance_to(2.0)
    whole = m.solve(t=[1.0, 2.0])
    assert it.state[2] == pytest.approx(scale * whole["q1'"][1], rel=1e-9)
