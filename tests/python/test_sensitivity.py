"""`solve(..., sensitivity=True)`: Solution.sensitivity against central
differences of solves (one Richardson step), on examples/paper.lag (a
non-holonomic constraint with a variable mass: q2' is fixed by the
constraint and has no column) and examples/particle_on_circle.lag (a
holonomic constraint whose dependent changes at run time)."""

import pickle

import numpy as np

import paper

TIGHT = dict(method="direct", rtol=1e-12, atol=1e-14)
COLUMNS = ["q10", "q20", "q1'0", "M0", "alpha"]
BASE = [0.0, 0.0, 1.0, 1.0, 0.5]


def moved(t, c, v):
    """The state at t with column c's initial value or param at v."""
    if c < 3:
        name = ["q1", "q2", "q1'"][c]
        return paper.Model().solve(t=t, initial={name: v}, **TIGHT).y
    return paper.Model(**{COLUMNS[c]: v}).solve(t=t, **TIGHT).y


def test_sensitivity_agrees_with_differences_of_solves():
    t = np.array([1.0, 2.5, 5.0])
    sol = paper.Model().solve(t=t, sensitivity=True, **TIGHT)
    assert sol.sensitivity_names == COLUMNS
    assert sol.sensitivity.shape == (3, 4, 5)
    for c, base in enumerate(BASE):
        h = 1e-3 * abs(base) if base else 1e-3

        def central(h):
            return (moved(t, c, base + h) - moved(t, c, base - h)) / (2 * h)

        reference = (4 * central(h / 2) - central(h)) / 3
        difference = np.max(np.abs(sol.sensitivity[:, :, c] - reference))
        scale = np.max(np.abs(reference))
        error = difference / scale if scale > 1e-9 else difference
        assert error < 1e-6, (COLUMNS[c], error)


def test_sensitivity_is_none_unless_asked_and_survives_pickling():
    t = np.array([1.0, 2.0])
    assert paper.Model().solve(t=t).sensitivity is None
    sol = paper.Model().solve(t=t, sensitivity=True)
    again = pickle.loads(pickle.dumps(sol))
    assert np.array_equal(again.sensitivity, sol.sensitivity)
    assert again.sensitivity_names == sol.sensitivity_names



CIRCLE_COLUMNS = ["x0", "y0", "x'0", "l", "w"]
CIRCLE_BASE = [0.0, -1.0, 2.0, 1.0, 2.0]


def test_sensitivity_of_a_holonomic_model_with_run_time_candidates():
    """examples/particle_on_circle.lag: x^2 + y^2 = l^2, the dependent
    chosen at run time and changed four times a turn (the particle turns
    almost twice by t = 6); y0 only seeds Newton on the closure (a zero
    column), l moves the start through it and through y0 = -l, x'0 = l w."""
    import particle_on_circle

    t = np.array([1.0, 3.5, 6.0])

    def moved(c, v):
        if c < 3:
            name = ["x", "y", "x'"][c]
            model = particle_on_circle.Model()
            return model.solve(t=t, initial={name: v}, **TIGHT).y
        model = particle_on_circle.Model(**{CIRCLE_COLUMNS[c]: v})
        return model.solve(t=t, **TIGHT).y

    sol = particle_on_circle.Model().solve(t=t, sensitivity=True, **TIGHT)
    assert sol.sensitivity_names == CIRCLE_COLUMNS
    assert sol.sensitivity.shape == (3, 4, 5)
    for c, base in enumerate(CIRCLE_BASE):
        h = 1e-3 * abs(base) if base else 1e-3

        def central(h):
            return (moved(c, base + h) - moved(c, base - h)) / (2 * h)

        reference = (4 * central(h / 2) - central(h)) / 3
        difference = np.max(np.abs(sol.sensitivity[:, :, c] - reference))
        scale = np.max(np.abs(reference))
        error = difference / scale if scale > 1e-9 else difference
        assert error < 1e-6, (CIRCLE_COLUMNS[c], error)
