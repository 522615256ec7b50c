"""`Model.linearize(at=..., params=..., inputs=..., t=...)` against
`lagc linearize FILE --format json` (issue 27): the same state, ignorable
coordinates, A, B_params, B_inputs, eigenvalues, residual, point and fixed
components to 1e-12, on every example `tests/it/linearize.rs` linearizes
and a few constrained ones more: constrained ones with ignorable
coordinates (paper, rolling_disk, knife_edge, steered_spring, the last
with an input; rolling_disk_3d, whose highest derivatives are an implicit
system solved at the point, across its critical spin; chaplygin_sleigh, two
candidate modes, the one chosen as the command line chooses it), holonomic
ones (cartesian_pendulum, particle_on_circle, four_bar_closure,
spherical_pendulum_cartesian: the dependent positions put on the
constraints by Newton and followed through their slopes), and
unconstrained ones (spherical and double pendulum, driven_oscillator).
Unknown names raise KeyError; a model whose module carries none
(third_order_constraint, k = 3: the consistency of (4) fixes x'', y'')
raises ValueError naming `lagc linearize`."""

import importlib
import json
import os
import subprocess

import numpy as np
import pytest

from conftest import ROOT

# (module, file, [(at, params, inputs, t), ...]): the points of
# tests/it/linearize.rs and a few more (a param override that moves a
# stated initial value and the params computed from it, a time).
CASES = [
    ("paper", "examples/paper.lag", [
        ({}, {}, {}, None),
        ({"q1'": 2.0}, {}, {}, 0.5),
        ({"q1'": 0.0}, {"alpha": 0.8}, {}, None),
    ]),
    ("spherical_pendulum", "examples/spherical_pendulum.lag", [
        ({}, {}, {}, None),
        ({"a": 0.2, "b": 0.0, "a'": 0.0, "b'": 0.0}, {}, {}, None),
        ({"a": 0.0, "b": 0.0, "a'": 0.0, "b'": 0.0}, {"l": 2.0}, {}, None),
    ]),
    ("double_pendulum_energy", "examples/double_pendulum_energy.lag", [
        ({}, {}, {}, None),
        ({"a": 0.0, "b": 0.0}, {"m2": 2.0, "l1": 0.5}, {}, None),
        ({"a": np.pi, "b": np.pi}, {}, {}, None),
    ]),
    ("rolling_disk", "examples/rolling_disk.lag", [
        ({"phi'": 4.0}, {}, {}, None),
        ({}, {"m": 2.0}, {}, None),
        ({"theta": 0.4, "theta'": 0.0}, {"R": 0.3, "Ia": 0.1}, {}, 1.5),
    ]),
    ("knife_edge", "examples/knife_edge.lag", [
        ({}, {}, {}, None),
        ({"theta": 0.3, "x'": 0.7, "theta'": 0.2}, {}, {}, None),
        ({}, {"theta0": 0.7, "v0": 2.0}, {}, None),
    ]),
    ("rolling_disk_3d", "examples/rolling_disk_3d.lag", [
        ({}, {}, {}, None),
        ({"th": 0.0, "th'": 0.0, "phi'": 0.0, "psi'": -4.0}, {}, {}, None),
        ({"th": 0.0, "th'": 0.0, "phi'": 0.0, "psi'": -1.0}, {"R": 0.5}, {}, None),
        ({"th": 0.2, "th'": 0.3, "phi'": 0.4, "psi'": -2.0}, {"m": 2.0}, {}, None),
    ]),
    ("chaplygin_sleigh", "examples/chaplygin_sleigh.lag", [
        ({}, {}, {}, None),
        ({"th": 0.0, "x'": 1.0, "th'": 0.0}, {}, {}, None),
        ({"th": 0.0, "x'": -2.0, "th'": 0.0}, {"a": 0.05}, {}, None),
        # y' given: the mode that has x' dependent.
        ({"th": 1.5707963267948966, "y'": 1.0, "th'": 0.0}, {}, {}, None),
        ({"th": 0.3, "y'": 0.5}, {}, {}, None),
    ]),
    ("cartesian_pendulum", "examples/cartesian_pendulum.lag", [
        ({}, {}, {}, None),
        ({"x": 0.6, "x'": 0.3}, {}, {}, None),
        ({"x": 0.0, "x'": 0.0}, {"l": 2.0}, {}, None),
        # x' given near the side: the mode with x' free and y dependent.
        ({"x": 0.99, "x'": 0.1}, {}, {}, None),
    ]),
    ("particle_on_circle", "examples/particle_on_circle.lag", [
        ({}, {}, {}, None),
        ({"x": 0.3, "x'": 0.5}, {}, {}, None),
    ]),
    ("four_bar_closure", "examples/four_bar_closure.lag", [
        ({}, {}, {}, None),
        ({"a": 0.8, "a'": 0.5}, {}, {}, None),
    ]),
    ("spherical_pendulum_cartesian", "tests/data/v2/spherical_pendulum_cartesian.lag", [
        ({}, {}, {}, None),
        ({"x": 0.2, "y": -0.1, "x'": 0.3, "y'": 0.1}, {"g": 3.0}, {}, None),
    ]),
    ("driven_oscillator", "tests/data/driven_oscillator.lag", [
        ({}, {}, {}, None),
        ({"x": 0.5}, {}, {"F": 1.5}, None),
    ]),
    ("steered_spring", "tests/data/steered_spring.lag", [
        ({}, {}, {}, None),
        ({"y": 0.1, "x'": 2.0}, {"k": 3.0}, {"u": -0.4}, None),
    ]),
]


def cli(file, at, params, inputs, t):
    """`lagc linearize FILE ... --format json`, parsed."""
    args = [os.environ["LAGC"], "linearize", str(ROOT / file), "--format", "json"]
    pairs = lambda d: ",".join(f"{k}={v!r}" for k, v in d.items())
    if at:
        args += ["--at", pairs(at)]
    if params:
        args += ["--param", pairs(params)]
    if inputs:
        args += ["--input", pairs(inputs)]
    if t is not None:
        args += ["--t", repr(t)]
    done = subprocess.run(args, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def close(python, expected, what):
    """Equal to 1e-12, relative to the largest entry (at least 1)."""
    python = np.asarray(python, dtype=float)
    expected = np.asarray(expected, dtype=float).reshape(python.shape)
    scale = max(1.0, float(np.max(np.abs(expected), initial=0.0)))
    error = float(np.max(np.abs(python - expected), initial=0.0))
    assert error <= 1e-12 * scale, (what, error, python, expected)


def same_eigenvalues(got, expected, what):
    """The same eigenvalues to 1e-12 (relative to the largest |λ|, at least
    1), each matched once: their order is by real parts, which for a pair
    at rest are rounding (1e-16 against 1e-31) and may sort either way."""
    expected = [complex(re, im) for re, im in expected]
    assert len(got) == len(expected), what
    scale = max([1.0] + [abs(z) for z in expected])
    left = list(got)
    for z in expected:
        k = min(range(len(left)), key=lambda i: abs(left[i] - z))
        assert abs(left[k] - z) <= 1e-12 * scale, (what, z, got)
        left.pop(k)


@pytest.mark.parametrize("module, file, points", CASES, ids=[c[0] for c in CASES])
def test_linearize_is_the_command_lines(module, file, points):
    Model = importlib.import_module(module).Model
    for at, params, inputs, t in points:
        what = f"{module} at {at} params {params} inputs {inputs} t {t}"
        expected = cli(file, at, params, inputs, t)
        got = Model(**params).linearize(at=at, inputs=inputs, t=t)
        assert got["state"] == expected["state"], what
        assert got["ignorable"] == expected["ignorable"], what
        assert got["params"] == expected["params"], what
        assert got["fixed"].keys() == expected["fixed"].keys(), what
        close(list(got["fixed"].values()), list(expected["fixed"].values()), what)
        close(got["A"], expected["A"], what + " A")
        close(got["B_params"], expected["B_params"], what + " B_params")
        if "B_inputs" in expected:
            assert got["inputs"] == expected["inputs"], what
            close(got["B_inputs"], expected["B_inputs"], what + " B_inputs")
        else:
            assert "B_inputs" not in got, what
        close(got["residual"], expected["residual"], what + " residual")
        close(got["point"], expected["point"], what + " point")
        close(got["ignorable_values"], expected["ignorable_values"], what)
        assert got["t"] == expected["t"], what
        assert got["equilibrium"] == expected["equilibrium"], what
        same_eigenvalues(got["eigenvalues"], expected["eigenvalues"], what)


def test_params_given_to_the_model_and_to_linearize_are_one_override():
    import rolling_disk

    both = rolling_disk.Model(m=2.0).linearize(params={"R": 0.3})
    once = rolling_disk.Model().linearize(params={"m": 2.0, "R": 0.3})
    expected = cli("examples/rolling_disk.lag", {}, {"m": 2.0, "R": 0.3}, {}, None)
    for got in (both, once):
        close(got["B_params"], expected["B_params"], "B_params")
        close(got["A"], expected["A"], "A")


def test_unknown_names_raise_key_error_naming_the_known_ones():
    import steered_spring

    m = steered_spring.Model()
    with pytest.raises(KeyError, match="the state components are"):
        m.linearize(at={"z": 1.0})
    with pytest.raises(KeyError, match="the params are: m, k"):
        m.linearize(params={"c": 1.0})
    with pytest.raises(KeyError, match="the inputs are: u"):
        m.linearize(inputs={"v": 1.0})


def test_a_fixed_component_off_its_constraint_is_a_value_error():
    import knife_edge

    with pytest.raises(ValueError, match="violates the constraints"):
        knife_edge.Model().linearize(at={"theta": 0.3, "y'": 5.0})
    # On the constraint it is accepted: y' = tan(theta) x'.
    at = {"theta": 0.3, "x'": 0.7, "y'": np.tan(0.3) * 0.7}
    assert knife_edge.Model().linearize(at=at)["fixed"]["y'"] == pytest.approx(at["y'"])


def test_a_module_without_the_linearization_says_so():
    import third_order_constraint

    with pytest.raises(ValueError, match="lagc linearize"):
        third_order_constraint.Model().linearize()


def test_a_dependent_position_off_the_holonomic_constraint_is_a_value_error():
    import cartesian_pendulum

    with pytest.raises(ValueError, match="off the holonomic constraints"):
        cartesian_pendulum.Model().linearize(at={"x": 0.0, "y": -2.0})
