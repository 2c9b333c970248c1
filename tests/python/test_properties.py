"""Property-based tests (Hypothesis) of the Python API over argument types, shapes, values and call orders: every call
either returns a result of the documented type and shape or raises a jointsim error (InputError, SolverError, ...), a
TypeError or a ValueError; none crashes the interpreter.

Each group of properties runs in a child interpreter (this file run as a script), so that a crash (a signal, an
abort) fails its test with the calls that led to it instead of taking pytest down: the child appends every call it
makes to a trace file, whose last lines the test shows. Hypothesis keeps nothing between runs (database=None) and
writes only below the test's tmp_path (HYPOTHESIS_STORAGE_DIRECTORY, the child's working directory). About 30 s in
all.
"""
import math
import os
import pathlib
import signal
import subprocess
import sys
import warnings

import numpy as np
import pytest

try:
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st
    from hypothesis.extra import numpy as hnp
except ImportError:  # pragma: no cover - the test requirements install it (scripts/python-test.sh)
    if __name__ == "__main__":
        raise
    pytest.skip("hypothesis is not installed (pip install hypothesis)", allow_module_level=True)

import jointsim

# What any call may raise besides returning: a jointsim error, or Python's own for a wrong type or value.
ALLOWED = (jointsim.InputError, jointsim.SolverError, jointsim.UnidentifiableError, TypeError, ValueError)

_TRACE = None


def trace(text: str) -> None:
    """Appends a call to the trace file (shown by the parent when the child dies)."""
    global _TRACE
    path = os.environ.get("JOINTSIM_PROPERTY_TRACE")
    if not path:
        return
    if _TRACE is None:
        _TRACE = open(path, "a", buffering=1)
    _TRACE.write(text[:400] + "\n")


def call(f, *args, **kwargs):
    """f(*args): (True, result) or (False, the allowed exception); anything else propagates (a failed property)."""
    trace(f"{getattr(f, '__qualname__', f)}{tuple(_short(a) for a in args)} {kwargs or ''}")
    try:
        return True, f(*args, **kwargs)
    except ALLOWED as e:
        return False, e


def _short(a):
    if isinstance(a, np.ndarray):
        return f"array(shape={a.shape}, dtype={a.dtype}, {a.ravel()[:4].tolist()!r})"
    return a


def common_settings(n):
    return settings(max_examples=n, deadline=None, database=None, derandomize=False, print_blob=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.filter_too_much])


# ------------------------------------------------------------------------------------------------ strategies
REALS = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0.0, -0.0, 1e-300, 5e-324, 1e308]))
SMALL_REALS = st.floats(min_value=-10.0, max_value=10.0, allow_nan=False)
DTYPES = st.sampled_from([np.float64, np.float32, np.int64, np.int8, np.bool_, np.complex128, np.uint16])


def arrays_around(n):
    """Arrays whose shapes are near the valid ones for n joints: (), (n,), (n±1,), (k, n), (k, n, 1), ..."""
    shapes = st.one_of(st.sampled_from([(), (0,), (n,), (n + 1,), (n - 1,), (1, n), (0, n), (n, 1), (2, n, 1), (1,)]),
                       st.tuples(st.integers(1, 4), st.just(n)), st.tuples(st.integers(1, 3), st.integers(0, n + 2)))
    numeric = st.tuples(DTYPES, shapes).flatmap(
        lambda ds: hnp.arrays(ds[0], ds[1], elements=_elements(ds[0])))
    odd = st.one_of(st.none(), st.text(max_size=3), st.lists(st.one_of(st.floats(), st.text(max_size=2), st.none()),
                                                             max_size=n + 1),
                    st.just(object()), st.integers(-3, 3), st.floats())
    return st.one_of(numeric, numeric, numeric, odd)


def _elements(dtype):
    if dtype in (np.float64, np.float32):
        return st.floats(width=32 if dtype is np.float32 else 64, allow_nan=True, allow_infinity=True)
    if dtype is np.complex128:
        return st.complex_numbers(max_magnitude=1e6, allow_nan=False)
    return None


def as_float_array(x):
    """What jointsim's argument conversion makes of x: a float64 array, or None when NumPy cannot read it."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return np.asarray(x, dtype=np.float64)
        except (TypeError, ValueError):
            return None


# ------------------------------------------------------------------------------------------------ dynamics
MODEL = None


def model():
    global MODEL
    if MODEL is None:
        MODEL = jointsim.load_robot(jointsim.data_path("robots/ur5.yaml"))
    return MODEL


NQ = 6  # the UR5


@common_settings(150)
@given(fn=st.sampled_from(["rnea", "aba"]), a=arrays_around(NQ), b=arrays_around(NQ), c=arrays_around(NQ),
       same=st.booleans())
def prop_inverse_and_forward_dynamics(fn, a, b, c, same):
    m = model()
    if same:  # the three arguments of one valid-looking shape more often than chance gives
        b = c = a
    ok, r = call(getattr(jointsim, fn), m, a, b, c)
    conv = [as_float_array(x) for x in (a, b, c)]
    if any(x is None for x in conv):
        assert not ok and isinstance(r, TypeError), r
        return
    shapes = {x.shape for x in conv}
    valid = len(shapes) == 1 and next(iter(shapes)) in {(NQ,)} | {(k, NQ) for k in range(1, 5)}
    if valid:
        assert ok, f"{fn} refused valid arguments of shape {shapes}: {r}"
    if ok:
        assert isinstance(r, np.ndarray) and r.dtype == np.float64 and r.shape == conv[0].shape, (r, shapes)


@common_settings(120)
@given(fn=st.sampled_from(["gravity_torques", "crba", "frame_placement", "frame_jacobian"]), q=arrays_around(NQ),
       frame=st.one_of(st.none(), st.sampled_from(["tool0", "base", "elbow_joint", "nope", ""]), st.integers(0, 3)))
def prop_single_argument_functions(fn, q, frame):
    m = model()
    f = getattr(jointsim, fn)
    ok, r = call(f, m, q, frame) if fn.startswith("frame") else call(f, m, q)
    conv = as_float_array(q)
    if conv is None:
        assert not ok and isinstance(r, TypeError), r
        return
    batch = conv.ndim == 2 and conv.shape[1] == NQ
    if not ok:
        return
    expected = {
        "gravity_torques": {(NQ,): (NQ,)},
        "crba": {(NQ,): (NQ, NQ)},
        "frame_placement": {(NQ,): (4, 4)},
        "frame_jacobian": {(NQ,): (6, NQ)},
    }[fn]
    if batch and fn == "gravity_torques":
        assert r.shape == conv.shape
    elif batch and fn == "crba":
        assert r.shape == (conv.shape[0], NQ, NQ)
    else:
        assert conv.shape in expected and r.shape == expected[conv.shape], (fn, conv.shape, r.shape)
    assert r.dtype == np.float64


@common_settings(60)
@given(fn=st.sampled_from(["rnea_derivatives", "aba_derivatives"]), a=arrays_around(NQ), same=st.booleans(),
       b=arrays_around(NQ))
def prop_derivatives(fn, a, same, b):
    ok, r = call(getattr(jointsim, fn), model(), a, a if same else b, a)
    if ok:
        assert isinstance(r, tuple) and len(r) == 3
        assert all(isinstance(x, np.ndarray) and x.shape == (NQ, NQ) for x in r)


@common_settings(60)
@given(arg=st.one_of(st.none(), st.integers(), st.floats(), st.binary(max_size=8), st.text(max_size=12),
                     st.just("a\0b"), st.just("."), st.just(pathlib.Path("no/such/file.yaml")),
                     st.sampled_from(["robots/ur5.yaml", "robots", "experiments/ur5_fall.yaml"])),
       fn=st.sampled_from(["load_robot", "load_experiment", "validate_file", "data_path"]))
def prop_path_arguments(arg, fn):
    if isinstance(arg, str) and arg.startswith(("robots", "experiments")):
        arg = jointsim.data_path(arg)  # a real file or folder: of the wrong kind for some functions
    ok, r = call(getattr(jointsim, fn), arg)
    if ok:
        assert r is not None


# ------------------------------------------------------------------------------------------------ simulators
RIG = "experiments/ur5_swg_joint_velocity.yaml"


JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint"]


def _joint():
    """Mostly a joint of the UR5 (index or name), else one it lacks or of the wrong type."""
    return st.one_of(st.integers(0, NQ - 1), st.sampled_from(JOINTS),
                     st.one_of(st.integers(-2, 7), st.sampled_from(["nope", ""]), st.none(), st.floats(0, 2),
                               st.booleans()))


def _ops():
    dt = st.one_of(st.floats(min_value=1e-6, max_value=5e-3), st.floats(min_value=1e-6, max_value=5e-3),
                   st.one_of(st.sampled_from([0.0, -1e-3, math.nan, math.inf, 1e-300]), st.integers(-1, 1),
                             st.text(max_size=2)))
    vec = st.one_of(hnp.arrays(np.float64, NQ, elements=st.floats(-3, 3)), arrays_around(NQ))
    port = st.one_of(st.sampled_from(jointsim.PORTS), st.sampled_from(jointsim.PORTS),
                     st.one_of(st.text(max_size=6), st.none()))
    name = st.one_of(st.sampled_from(["motor_velocity", "motor_velocity[rad/s]", "motor_torque[N·m]", "q_elbow_joint",
                                      "q_elbow_joint[rad]", "q_fb_wrist_1_joint", "tcp_roll[rad]"]),
                     st.one_of(st.sampled_from(["time", "nope", "q_elbow_joint[deg]", ""]), st.text(max_size=8),
                               st.integers()))
    value = st.one_of(SMALL_REALS, SMALL_REALS, REALS, st.text(max_size=2))
    return st.one_of(
        st.tuples(st.just("advance"), dt),
        st.tuples(st.just("advance_to_offset"), dt),
        st.tuples(st.just("reset")),
        st.tuples(st.just("set_state"), st.one_of(vec, st.floats(-1e3, 1e3))),
        st.tuples(st.just("perturb_state"), REALS, st.floats(-10, 10)),
        st.tuples(st.just("state_name"), st.one_of(st.integers(-3, 100), st.integers(), st.floats(), st.text(max_size=2))),
        st.tuples(st.just("set_limits"), st.one_of(st.none(), st.integers(-5, 10 ** 6), st.floats()),
                  st.one_of(st.none(), st.floats()), st.one_of(st.none(), st.floats(), st.integers(-1, 10))),
        st.tuples(st.just("signal"), name),
        st.tuples(st.just("signal_index"), name),
        st.tuples(st.just("signal_values")),
        st.tuples(st.just("signals")),
        st.tuples(st.just("properties")),
        st.tuples(st.just("set_port"), _joint(), port),
        st.tuples(st.just("port"), _joint()),
        st.tuples(st.just("set_command"), _joint(), value),
        st.tuples(st.just("set_commands"), vec),
        st.tuples(st.just("set_setpoint"), _joint(), SMALL_REALS, value, SMALL_REALS),
        st.tuples(st.just("hold_setpoints"), vec, st.one_of(st.none(), vec), st.one_of(st.none(), vec)),
        st.tuples(st.just("release_setpoints")),
        st.tuples(st.just("set_external_wrench"), st.one_of(st.sampled_from(["tool0", "wrist_3_link", "nope"]),
                                                            st.integers()),
                  st.one_of(hnp.arrays(np.float64, 6, elements=st.floats(-100, 100)), arrays_around(6))),
    )


WALL = 0.2  # [s] the wall-clock limit of every advance, so that no program runs long


def run_program(sim, program):
    n_state = len(sim.state)
    n_signals = len(sim.signal_names)
    sim.set_limits(max_wall_time=WALL)
    for op in program:
        name, args = op[0], op[1:]
        before = sim.time
        if name == "advance":
            ok, r = call(sim.advance, *args)
            if ok:
                assert r == sim.time and r >= before and math.isfinite(r)
        elif name == "advance_to_offset":
            target = before + args[0] if isinstance(args[0], (int, float)) and not isinstance(args[0], bool) else args[0]
            ok, r = call(sim.advance_to, target)
            if ok:
                assert r == sim.time and r >= before
        elif name == "reset":
            ok, r = call(sim.reset)
            assert ok, r
            assert sim.time == 0.0
        elif name == "set_state":
            ok, r = call(sim.set_state, args[0])
            if ok:
                assert len(sim.state) == n_state
        elif name == "perturb_state":  # the current state scaled and shifted: a state of the right size
            with np.errstate(all="ignore"):
                y = sim.state * (1.0 + args[1]) + args[0]
            ok, r = call(sim.set_state, y)
        elif name == "state_name":
            ok, r = call(sim.state_name, args[0])
            if ok:
                assert isinstance(r, str)
        elif name == "set_limits":
            ok, r = call(sim.set_limits, *args)
            sim.set_limits(max_wall_time=WALL)  # the harness's own bound, whatever the program set
            if ok:
                lim = sim.limits
                assert set(lim) == {"max_steps", "max_wall_time", "max_state"}
        elif name in ("signal", "signal_index"):
            ok, r = call(getattr(sim, name), args[0])
            if ok and name == "signal":
                assert isinstance(r, float)
            if ok and name == "signal_index":
                assert isinstance(r, int) and 0 <= r < n_signals
        elif name == "signal_values":
            ok, r = call(sim.signal_values)
            assert ok, r
            assert r.shape == (n_signals,)
        elif name == "signals":
            ok, r = call(sim.signals)
            assert ok and len(r) == n_signals, r
        elif name == "properties":
            for prop in ("name", "time", "state", "restarts", "steps", "dof", "joint_names", "joint_positions",
                         "joint_velocities", "gear_ratios", "motor_velocities", "limits", "signal_names"):
                ok, r = call(getattr, sim, prop)
                if ok and prop in ("joint_positions", "joint_velocities", "gear_ratios", "motor_velocities"):
                    assert r.shape == (sim.dof,)
            ok, r = call(sim.model)
            if ok:
                assert r.nq == sim.dof
        elif name == "port":
            ok, r = call(sim.port, args[0])
            if ok:
                assert r in jointsim.PORTS
        else:
            ok, r = call(getattr(sim, name), *args)
            if ok:
                assert r is None
        # Whatever happened, the simulator stands at a finite time with a state of its size.
        assert math.isfinite(sim.time) and len(sim.state) == n_state


@common_settings(150)
@given(program=st.lists(_ops(), max_size=12))
def prop_rig_simulator_call_orders(program):
    run_program(jointsim.Simulator.from_experiment(jointsim.data_path(RIG)), program)


@common_settings(120)
@given(program=st.lists(_ops(), max_size=12), rtol=st.sampled_from([1e-4, 1e-6]))
def prop_robot_simulator_call_orders(program, rtol):
    sim = jointsim.Simulator.from_robot(jointsim.data_path("robots/ur5_drives.yaml"), rtol=rtol, max_gamma_change=0.5)
    run_program(sim, program)


def _or_valid(valid, odd):
    """Mostly a valid value, so that a call with several arguments is valid often enough."""
    return st.one_of(st.sampled_from(valid), st.sampled_from(valid), st.sampled_from(valid), odd)


@common_settings(80)
@given(q0=st.one_of(st.none(), hnp.arrays(np.float64, NQ, elements=st.floats(-3, 3)),
                   hnp.arrays(np.float64, NQ, elements=st.floats(-3, 3)), arrays_around(NQ)),
       rtol=_or_valid([1e-6, 1e-4], REALS), atol=_or_valid([1e-9, 1e-6], REALS),
       max_order=_or_valid([1, 2, 5], st.one_of(st.integers(-2, 8), st.floats())),
       max_step=_or_valid([0.0, 1e-3], REALS), gamma=_or_valid([0.3, 0.5], REALS),
       max_state=_or_valid([1e6, 0.0], REALS))
def prop_robot_simulator_arguments(q0, rtol, atol, max_order, max_step, gamma, max_state):
    ok, sim = call(jointsim.Simulator.from_robot, jointsim.data_path("robots/ur5_drives.yaml"), q0, rtol, atol,
                   max_order, max_step, gamma, max_state)
    if ok:
        assert sim.dof == NQ and sim.time == 0.0
        sim.set_limits(max_wall_time=WALL, max_steps=2000)
        ok, r = call(sim.advance, 1e-3)
        if ok:
            assert r == sim.time


# ------------------------------------------------------------------------------------------------ experiments
RIG_KEYS = ["duration", "log_rate", "load.inertia", "solver.rtol", "solver.atol", "solver.max_order",
            "input.controller.ki", "input.controller.kp", "input.profile.values", "input.profile.times",
            "friction.model.f_c", "friction.side", "transmission.size", "experiment.name", "motor.preset",
            "+solver.max_num_steps", "+nonexistent.key", "nonexistent", "solver", "input.profile.values[1]"]
OVERRIDE_VALUES = st.one_of(st.sampled_from([0.01, 0.002, 1.5, 20, 100, 1e-7, "A", "B", [0, 1, 2, 3, 4, 5, 6]]),
                            st.floats(0.001, 50), st.integers(-10 ** 12, 10 ** 12), st.floats(), st.text(max_size=8),
                            st.booleans(), st.lists(st.floats(-200, 200), max_size=8), st.none())


@common_settings(150)
@given(overrides=st.one_of(
    st.dictionaries(st.sampled_from(RIG_KEYS), OVERRIDE_VALUES, max_size=4),
    st.dictionaries(st.one_of(st.sampled_from(RIG_KEYS), st.text(max_size=10)), OVERRIDE_VALUES, max_size=4),
    st.lists(st.one_of(st.text(max_size=20), st.builds(lambda k, v: f"{k}={v}", st.sampled_from(RIG_KEYS),
                                                       st.text(max_size=8))), max_size=3),
    st.none(), st.text(max_size=5), st.integers()),
    duration=st.one_of(st.none(), st.sampled_from([0.0, 0.002, 0.01, -1.0, math.nan])))
def prop_load_experiment_with_overrides(overrides, duration):
    if duration is not None and isinstance(overrides, dict):
        overrides = dict(overrides, duration=duration)
    ok, e = call(jointsim.load_experiment, jointsim.data_path(RIG), overrides)
    if not ok:
        return
    assert isinstance(e.name, str) and e.type == "joint_rig"
    assert e.columns and e.columns[0] == "time[s]" and all(isinstance(c, str) for c in e.columns)
    # validate_file also makes the run's checks (the log grid, the budgets): it may refuse what loads.
    ok, v = call(jointsim.validate_file, jointsim.data_path(RIG), overrides)
    if not ok or not v["duration"] <= 0.01:
        return
    assert v["kind"] == "experiment" and v["runs"] == 1 and v["type"] == "joint_rig"
    # Short enough to run: under a budget of 0.5 s and 20000 log rows (whatever log_rate the overrides set).
    budget = {"+limits.wall_time": 0.5, "+limits.log_rows": 20000}
    bounded = (dict(overrides or {}, **budget) if not isinstance(overrides, list)
               else overrides + [f"{k}={x}" for k, x in budget.items()])
    ok, e = call(jointsim.load_experiment, jointsim.data_path(RIG), bounded)
    if not ok:
        return
    ok, r = call(e.run)
    if ok:
        n = len(r["time"])
        assert n >= 1 and all(len(col) == n for col in r.values())
        assert np.all(np.diff(r["time"]) >= 0)
        assert list(r.columns) == e.columns


def _mutated_text(draw_lines, text):
    lines = text.splitlines()
    for kind, i, extra in draw_lines:
        if not lines:
            break
        i %= len(lines)
        if kind == 0:
            del lines[i]
        elif kind == 1:
            lines.insert(i, extra)
        elif kind == 2:
            lines[i] = lines[i][: len(lines[i]) // 2] + extra
        else:
            lines[i], lines[-1 - i] = lines[-1 - i], lines[i]
    return "\n".join(lines) + "\n"


@common_settings(100)
@given(edits=st.lists(st.tuples(st.integers(0, 3), st.integers(0, 1000),
                                st.one_of(st.text(max_size=20), st.sampled_from(
                                    ["duration: 0.005", "log_rate: 1e9", "  inertia: -1", "&a [*a]", "{", "- x",
                                     "type: clamping", "solver: {rtol: 0}", "load: 3", "!!binary AAAA"]))),
                      min_size=1, max_size=4),
       overrides=st.one_of(st.none(), st.dictionaries(st.sampled_from(RIG_KEYS), OVERRIDE_VALUES, max_size=2)))
def prop_experiment_text(edits, overrides):
    """A load_experiment_text equivalent: an edited copy of the rig's file written to a folder of this test's own."""
    text = _mutated_text(edits, jointsim.data_path(RIG).read_text())
    work = pathlib.Path(os.environ["JOINTSIM_PROPERTY_TMP"])
    path = work / "edited.yaml"
    path.write_text(text)
    ok, e = call(jointsim.load_experiment, path, overrides)
    if ok:
        assert isinstance(e.type, str) and e.columns[0] == "time[s]"


# ------------------------------------------------------------------------------------------------ identification
def _curve(n):
    return hnp.arrays(np.float64, st.integers(0, n), elements=st.one_of(st.floats(-1e3, 1e3),
                                                                        st.sampled_from([math.nan, math.inf, 0.0])))


def _friction_curve():
    """Samples of a Stribeck curve over both directions with noise, or arrays of any length and content."""
    def curve(n, a0, a1, vs, a2, noise, seed):
        v = np.linspace(-2.0, 2.0, n)
        tau = np.sign(v) * (a0 + a1 * np.exp(-(v / vs) ** 2)) + a2 * v
        return v, tau + noise * np.random.default_rng(seed).standard_normal(n)
    made = st.builds(curve, st.integers(4, 60), st.floats(0.1, 5), st.floats(0, 3), st.floats(0.01, 1),
                     st.floats(0, 2), st.floats(0, 0.5), st.integers(0, 2 ** 32 - 1))
    return st.one_of(made, made, st.tuples(_curve(40), _curve(40)))


@common_settings(60)
@given(data=_friction_curve(), same=st.booleans())
def prop_fit_friction_map(data, same):
    v, tau = data
    if same:
        tau = np.resize(tau, v.shape) if tau.size else np.zeros(v.shape)
    ok, r = call(jointsim.fit_friction_map, v, tau)
    if ok:
        assert isinstance(r, dict) and {"positive", "negative"} <= set(r)


@common_settings(60)
@given(t=_curve(40), a=_curve(40), tau=_curve(40), fixed=st.one_of(st.none(), REALS, st.text(max_size=2)))
def prop_identify_clamping(t, a, tau, fixed):
    ok, r = call(jointsim.identify_clamping, t, a, tau, fixed)
    if ok:
        assert isinstance(r, dict) and {"stiffness", "backlash", "friction"} <= set(r)


GROUPS = {
    "dynamics": [prop_inverse_and_forward_dynamics, prop_single_argument_functions, prop_derivatives,
                 prop_path_arguments],
    "simulators": [prop_rig_simulator_call_orders, prop_robot_simulator_call_orders, prop_robot_simulator_arguments],
    "experiments": [prop_load_experiment_with_overrides, prop_experiment_text],
    "identification": [prop_fit_friction_map, prop_identify_clamping],
}


@pytest.mark.parametrize("group", sorted(GROUPS))
def test_properties(group, tmp_path):
    """The group's properties in a child interpreter: it must exit 0 (a failed property: its falsifying example on
    stderr; a crash: the signal and the last calls)."""
    work = tmp_path / "work"
    work.mkdir()
    trace_file = tmp_path / "trace.txt"
    env = dict(os.environ, HYPOTHESIS_STORAGE_DIRECTORY=str(tmp_path / "hypothesis"),
               JOINTSIM_PROPERTY_TMP=str(work), JOINTSIM_PROPERTY_TRACE=str(trace_file), PYTHONFAULTHANDLER="1")
    r = subprocess.run([sys.executable, __file__, group], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=600)
    if r.returncode != 0:
        how = (f"killed by {signal.Signals(-r.returncode).name}" if r.returncode < 0 else f"exit {r.returncode}")
        last = trace_file.read_text().splitlines()[-8:] if trace_file.exists() else []
        pytest.fail(f"properties '{group}': the child interpreter ended ({how})\nlast calls:\n  " + "\n  ".join(last) +
                    f"\nstderr (end):\n{r.stderr[-6000:]}", pytrace=False)


if __name__ == "__main__":
    for prop in GROUPS[sys.argv[1]]:
        prop()
