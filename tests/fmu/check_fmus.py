"""FMUs that lagc builds, through FMPy (the reference importer), against
closed forms. Run by tests/it/fmu.rs in a venv with fmpy 0.3.32 and scipy:

    python check_fmus.py CASE DIR

where DIR holds paper.fmu, damped_oscillator.fmu, driven_oscillator.fmu,
stepped_oscillator.fmu, rocket_burnout_landing.fmu and newton_no_root.fmu. Prints what it
measured; exits non-zero (an assertion) when a check fails.
"""

import sys
import warnings

import fmpy
import numpy as np
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from scipy.integrate import quad

RTOL = 1e-10

# quad notes rounding at its 1e-14 request; its error is still far below
# the tolerances checked.
warnings.filterwarnings("ignore", message=".*roundoff error.*")


def paper_exact(t, alpha=0.5, v0=1.0):
    """SPEC 1.6: q1' = v0 e^(alpha t)/sqrt(1 + t^2), q2' = t q1'."""
    opts = dict(epsabs=1e-15, epsrel=1e-14, limit=200)
    q1 = v0 * quad(lambda s: np.exp(alpha * s) / np.sqrt(1 + s * s), 0, t, **opts)[0]
    q2 = v0 * quad(lambda s: s * np.exp(alpha * s) / np.sqrt(1 + s * s), 0, t, **opts)[0]
    v = v0 * np.exp(alpha * t) / np.sqrt(1 + t * t)
    return [q1, q2, v, t * v]


def largest_error(result, names, exact):
    return max(
        abs(result[n][i] - e) / max(1.0, abs(e))
        for i in range(len(result))
        for n, e in zip(names, exact(result["time"][i]))
    )


def oscillator(m, k, pieces, t):
    """m x'' + k x = F, F = c + r (t - tau) on each piece, from rest at 0."""
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


def paper(d):
    names = ["q1", "q2", "der(q1)", "der(q2)"]
    r = fmpy.simulate_fmu(f"{d}/paper.fmu", relative_tolerance=RTOL, output_interval=0.05, output=names)
    assert r["time"][-1] == 5.0, r["time"][-1]
    error = largest_error(r, names, paper_exact)
    print(f"paper: {len(r)} points, largest error {error:.3e}")
    assert error < 10 * RTOL, error
    # Params and initial values set as start values change the motion as
    # --param and --init do; der(q2) is calculated (the constraint fixes it).
    r = fmpy.simulate_fmu(
        f"{d}/paper.fmu",
        relative_tolerance=RTOL,
        output_interval=0.05,
        output=names,
        start_values={"alpha": 0.2, "der(q1)": 2.0},
    )
    error = largest_error(r, names, lambda t: paper_exact(t, 0.2, 2.0))
    print(f"paper, alpha = 0.2, der(q1)(0) = 2: largest error {error:.3e}")
    assert error < 10 * RTOL, error
    # The method and the integrator as structural parameters.
    for method, integrator in [(1, 0), (1, 3), (0, 4)]:
        messages = []
        r = fmpy.simulate_fmu(
            f"{d}/paper.fmu",
            relative_tolerance=RTOL,
            output_interval=0.05,
            output=names,
            start_values={"lagc.method": method, "lagc.integrator": integrator},
            debug_logging=True,
            logger=lambda e, n, s, c, m: messages.append(m.decode()),
        )
        error = largest_error(r, names, paper_exact)
        work = [m for m in messages if " steps (+" in m][-1]
        print(f"paper, lagc.method {method}, lagc.integrator {integrator}: {work}; largest error {error:.3e}")
        # The accuracy examples/paper.lag states for each method.
        assert error < 1e-8, error
        assert ("direct" in work) == (method == 1), work


def driven(d):
    # A force stepping at t = 1 and t = 3 (communication points of the
    # 0.25 grid): FMPy sets the input at each point, the FMU restarts its
    # integration where the value changed.
    signal = np.array(
        [(0.0, 1.0), (1.0, 1.0), (1.0, -2.0), (3.0, -2.0), (3.0, 0.5), (5.0, 0.5)],
        dtype=[("time", np.float64), ("F", np.float64)],
    )
    r = fmpy.simulate_fmu(
        f"{d}/driven_oscillator.fmu",
        relative_tolerance=RTOL,
        output_interval=0.25,
        input=signal,
        output=["x", "der(x)", "force"],
    )
    pieces = [(0.0, 1.0, 0.0), (1.0, -2.0, 0.0), (3.0, 0.5, 0.0)]
    error = largest_error(r, ["x", "der(x)"], lambda t: oscillator(2.0, 8.0, pieces, t))
    print(f"driven oscillator, input steps through FMPy: largest error {error:.3e}")
    assert error < 10 * RTOL, error
    # The output column reads the input as the FMU holds it.
    assert r["force"][0] == 1.0 and r["force"][-1] == 0.5, r["force"]
    # The same steps written into the model as `if t < 1 then … else …`
    # (switches located as events, no input): the same motion.
    s = fmpy.simulate_fmu(
        f"{d}/stepped_oscillator.fmu",
        relative_tolerance=RTOL,
        output_interval=0.25,
        output=["x", "der(x)", "force"],
    )
    assert np.array_equal(s["time"], r["time"]), (s["time"], r["time"])
    difference = max(
        abs(s[n][i] - r[n][i]) / max(abs(r[n][i]), 1.0) for i in range(len(r)) for n in ["x", "der(x)"]
    )
    print(f"driven oscillator, input steps against the steps written with if: largest difference {difference:.3e}")
    assert difference < 10 * RTOL, difference
    # Without an input signal the default (0.5) holds.
    r = fmpy.simulate_fmu(f"{d}/driven_oscillator.fmu", relative_tolerance=RTOL, output_interval=0.25)
    error = largest_error(r, ["x", "der(x)"], lambda t: oscillator(2.0, 8.0, [(0.0, 0.5, 0.0)], t))
    print(f"driven oscillator, default input: largest error {error:.3e}")
    assert error < 10 * RTOL, error


def stop_and_failure(d):
    # `stop when`: fmi2DoStep returns fmi2Discard with fmi2Terminated, and
    # FMPy's last row is at the stop time (lagc run: t = 127.27665911452041).
    r = fmpy.simulate_fmu(f"{d}/rocket_burnout_landing.fmu", relative_tolerance=RTOL, output_interval=0.5)
    print(f"rocket: the simulation ended at t = {r['time'][-1]!r}, z = {r['z'][-1]:.3e}")
    assert abs(r["time"][-1] - 127.27665911452041) < 1e-6, r["time"][-1]
    assert abs(r["z"][-1]) < 1e-6, r["z"][-1]
    # A numerical failure: fmi2Error (an exception in FMPy, not a crash),
    # and lagc's message with the time and the quantity through the logger.
    messages = []

    def logger(env, name, status, category, message):
        messages.append((status, category.decode(), message.decode()))

    try:
        fmpy.simulate_fmu(f"{d}/newton_no_root.fmu", logger=logger, output_interval=0.01)
        raise AssertionError("the failing model did not fail")
    except FMICallException as e:
        print(f"newton_no_root: {e}; logged {messages}")
        assert e.status == 3, e.status
    assert any(
        s == 3 and "at t = 1e0" in m and "Newton's method found no highest derivatives" in m
        for s, _, m in messages
    ), messages


def slave(d, name, instance):
    md = fmpy.read_model_description(f"{d}/{name}.fmu")
    unzipped = fmpy.extract(f"{d}/{name}.fmu")
    fmu = FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipped,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName=instance,
    )
    refs = {v.name: v.valueReference for v in md.modelVariables}
    return fmu, refs


def two_instances(d):
    # Two models and two instances of one model in one process, stepped in
    # turn: each follows its own closed form.
    a, ra = slave(d, "paper", "paper_a")
    b, rb = slave(d, "paper", "paper_b")
    c, rc = slave(d, "driven_oscillator", "oscillator")
    for fmu in (a, b, c):
        fmu.instantiate()
    b.setReal([rb["alpha"]], [0.25])
    for fmu in (a, b, c):
        fmu.setupExperiment(tolerance=RTOL, startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
    c.setReal([rc["F"]], [-1.0])
    # An output of an input reads the new value at once (direct
    # feedthrough), before the next step.
    assert c.getReal([rc["force"]]) == [-1.0], c.getReal([rc["force"]])
    t, h, worst = 0.0, 0.125, 0.0
    for _ in range(24):
        for fmu in (a, b, c):
            fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t += h
        qa = a.getReal([ra["q1"], ra["der(q1)"]])
        qb = b.getReal([rb["q1"], rb["der(q1)"]])
        xc = c.getReal([rc["x"], rc["der(x)"]])
        ea, eb = paper_exact(t), paper_exact(t, 0.25)
        ec = oscillator(2.0, 8.0, [(0.0, -1.0, 0.0)], t)
        for got, want in [(qa, [ea[0], ea[2]]), (qb, [eb[0], eb[2]]), (xc, ec)]:
            worst = max(worst, max(abs(g - w) / max(1.0, abs(w)) for g, w in zip(got, want)))
    print(f"three instances, two models, in turn to t = {t}: largest error {worst:.3e}")
    assert worst < 10 * RTOL, worst
    # fmi2Reset: the instance starts over with the model's values.
    b.reset()
    b.setupExperiment(tolerance=RTOL, startTime=0.0)
    b.enterInitializationMode()
    b.exitInitializationMode()
    b.doStep(currentCommunicationPoint=0.0, communicationStepSize=1.0)
    got = b.getReal([rb["q1"]])[0]
    assert abs(got - paper_exact(1.0)[0]) < 10 * RTOL, got
    # Saved and restored states: a step taken again (the integration
    # restarted from the saved state) gives the same state to the tolerance.
    saved = a.getFMUState()
    a.doStep(currentCommunicationPoint=t, communicationStepSize=h)
    first = a.getReal([ra["q1"]])[0]
    a.setFMUState(saved)
    a.doStep(currentCommunicationPoint=t, communicationStepSize=h)
    again = a.getReal([ra["q1"]])[0]
    assert abs(again - first) < 10 * RTOL * max(1.0, abs(first)), (again, first)
    assert abs(again - paper_exact(t + h)[0]) < 10 * RTOL, again
    a.freeFMUState(saved)
    # Bad calls are errors, not crashes: an unknown value reference, a
    # step from the wrong time, a param set after initialization.
    for call in [
        lambda: a.getReal([999]),
        lambda: a.doStep(currentCommunicationPoint=t + 7.0, communicationStepSize=h),
        lambda: c.setReal([rc["k"]], [1.0]),
    ]:
        try:
            call()
            raise AssertionError("a bad call succeeded")
        except FMICallException as e:
            assert e.status == 3, e.status
    # After fmi2Error an instance may only be reset or freed (FMI 2.0).
    for fmu in (b, c):
        fmu.terminate()
    for fmu in (a, b, c):
        fmu.freeInstance()
    print("reset, saved states and bad calls: as specified")


def damped(t, x0, v0, m=1.0, k=4.0, c=0.4):
    """m x'' + c x' + k x = 0 from (x0, v0) at 0 (underdamped or undamped)."""
    gam, w0 = c / (2 * m), np.sqrt(k / m)
    wd = np.sqrt(w0 * w0 - gam * gam)
    e = np.exp(-gam * t)
    x = e * (x0 * np.cos(wd * t) + (v0 + gam * x0) / wd * np.sin(wd * t))
    v = e * (v0 * np.cos(wd * t) - (gam * v0 + w0 * w0 * x0) / wd * np.sin(wd * t))
    return x, v


def tuning(d):
    # examples/damped_oscillator.lag: m x'' + c x' + k x = 0. The damping c
    # enters only a force: tunable; m and k enter the Lagrangian: fixed.
    md = fmpy.read_model_description(f"{d}/damped_oscillator.fmu")
    variability = {v.name: v.variability for v in md.modelVariables if v.causality == "parameter"}
    assert (variability["c"], variability["m"], variability["k"]) == ("tunable", "fixed", "fixed"), variability
    fmu, refs = slave(d, "damped_oscillator", "tuned")
    fmu.instantiate()
    fmu.setupExperiment(tolerance=RTOL, startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    xv = [refs["x"], refs["der(x)"]]

    def steps(t, n, h=0.125):
        for _ in range(n):
            fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            t += h
        return t

    def error(got, want):
        return max(abs(g - w) / max(1.0, abs(w)) for g, w in zip(got, want))

    t = steps(0.0, 8)
    x1, v1 = fmu.getReal(xv)
    worst = error([x1, v1], damped(1.0, 1.0, 0.0))
    # c tuned to 0 at t = 1: from there the undamped motion from (x1, v1).
    fmu.setReal([refs["c"]], [0.0])
    assert fmu.getReal([refs["c"], refs["gam"]]) == [0.0, 0.0]
    saved = fmu.getFMUState()
    t = steps(t, 8)
    first = fmu.getReal(xv)
    worst = max(worst, error(first, damped(1.0, x1, v1, c=0.0)))
    print(f"damped oscillator, c tuned from 0.4 to 0 at t = 1 through FMPy: largest error {worst:.3e}")
    assert worst < 10 * RTOL, worst
    # A saved state goes back with its param values: tuned again after
    # the save, c is 0 once the state is set, and the steps after it are
    # the same restart from the same state, bit for bit.
    fmu.setReal([refs["c"]], [0.4])
    fmu.setFMUState(saved)
    assert fmu.getReal([refs["c"]]) == [0.0]
    steps(1.0, 8)
    assert fmu.getReal(xv) == first, (fmu.getReal(xv), first)
    # Serialized and read back: the same again.
    serial = fmu.serializeFMUstate(saved)
    fmu.freeFMUState(saved)
    again = fmu.deSerializeFMUstate(serial)
    fmu.setFMUState(again)
    steps(1.0, 8)
    assert fmu.getReal(xv) == first, (fmu.getReal(xv), first)
    fmu.freeFMUState(again)
    # And on another instance, only instantiated: it steps on from there.
    other, _ = slave(d, "damped_oscillator", "other")
    other.instantiate()
    state = other.deSerializeFMUstate(serial)
    other.setFMUState(state)
    t = 1.0
    for _ in range(8):
        other.doStep(currentCommunicationPoint=t, communicationStepSize=0.125)
        t += 0.125
    assert other.getReal(xv) == first, (other.getReal(xv), first)
    assert other.getReal([refs["c"]]) == [0.0]
    other.freeFMUState(state)
    other.terminate()
    other.freeInstance()
    print(f"saved state (and its {len(serial)} serialized bytes, on this instance and another): the same steps again, bit for bit")
    # Foreign bytes are refused with an error, not misread.
    try:
        fmu.deSerializeFMUstate(b"not a state of this FMU")
        raise AssertionError("foreign bytes were read as a state")
    except FMICallException as e:
        assert e.status == 3, e.status
    fmu.freeInstance()
    # A fixed param set after initialization: an error naming why.
    fmu, refs = slave(d, "damped_oscillator", "fixed")
    fmu.instantiate()
    fmu.setupExperiment(tolerance=RTOL, startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    try:
        fmu.setReal([refs["k"]], [5.0])
        raise AssertionError("a fixed param was set after initialization")
    except FMICallException as e:
        assert e.status == 3, e.status
    fmu.freeInstance()
    print("a fixed param set after initialization: fmi2Error")


def steps(d):
    # A communication step of 1e-3 over the paper's span: the FMU logs its
    # integrator's work at fmi2Terminate (debug logging on); tests/it/fmu.rs
    # compares it with lagc run's at the same tolerance and output times.
    messages = []

    def logger(env, name, status, category, message):
        messages.append(message.decode())

    r = fmpy.simulate_fmu(
        f"{d}/paper.fmu", relative_tolerance=RTOL, output_interval=1e-3, debug_logging=True, logger=logger
    )
    assert len(r) == 5001, len(r)
    print([m for m in messages if " steps (+" in m][-1])
    # The cost of one fmi2DoStep through ctypes alone (no FMPy loop).
    import ctypes
    import time

    fmu, refs = slave(d, "paper", "timed")
    fmu.instantiate()
    fmu.setupExperiment(tolerance=RTOL, startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    do_step = fmu.dll.fmi2DoStep
    do_step.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
    start = time.perf_counter()
    for i in range(5000):
        assert do_step(fmu.component, i * 1e-3, 1e-3, 1) == 0
    elapsed = time.perf_counter() - start
    print(f"5000 fmi2DoStep calls of 1e-3 through ctypes: {elapsed * 1e3:.2f} ms, {elapsed / 5000 * 1e6:.2f} us each")
    fmu.terminate()
    fmu.freeInstance()


def versus_run(fmu, csv):
    """The FMU through FMPy against `lagc run` at the same tolerance and
    output times (the CSV): every state column and output, relative to
    max(1, |value|)."""
    with open(csv) as f:
        header = f.readline().strip().split(",")
    rows = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
    t0, t1 = rows[0, 0], rows[-1, 0]
    h = (t1 - t0) / (len(rows) - 1)

    def fmi_name(column):
        q = column.rstrip("'")
        order = len(column) - len(q)
        return q if order == 0 else f"der({q})" if order == 1 else f"der({q},{order})"

    names = [fmi_name(c) for c in header[1:]]
    r = fmpy.simulate_fmu(fmu, relative_tolerance=RTOL, output_interval=h, output=names)
    assert len(r) == len(rows), (len(r), len(rows))
    worst = 0.0
    for k, name in enumerate(names):
        a, b = r[name], rows[:, k + 1]
        worst = max(worst, float(np.max(np.abs(a - b) / np.maximum(1.0, np.abs(b)))))
    print(f"{fmu}: {len(names)} columns at {len(rows)} times, largest difference from lagc run {worst:.3e}")
    assert worst <= 10 * RTOL, worst


if __name__ == "__main__":
    if sys.argv[1] == "versus_run":
        versus_run(sys.argv[2], sys.argv[3])
        sys.exit(0)
    {"steps": steps, "paper": paper, "driven": driven, "stop_and_failure": stop_and_failure, "two_instances": two_instances, "tuning": tuning}[
        sys.argv[1]
    ](sys.argv[2])
