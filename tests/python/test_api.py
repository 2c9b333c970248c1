"""The Python API as a Python user meets it: shipped files, paths, results as pandas, sweeps as dicts, exceptions
with fields, long calls that Ctrl-C interrupts, limits and divergence, batched rigid-body calls, docstrings and the
stubs of the extension module."""
import ast
import copy
import inspect
import os
import pathlib
import pickle
import re
import signal
import threading
import time

import numpy as np
import pandas as pd
import pytest

import jointsim
from jointsim import _core


class _SigintAfter:
    """Sends SIGINT to this process `seconds` after entering, from a timer thread; `sent` is the time it was sent.
    Leaving cancels a signal not yet sent (a call that ended early must not interrupt the next test)."""

    def __init__(self, seconds):
        self.seconds, self.sent = seconds, None
        self._timer = threading.Timer(seconds, self._fire)

    def _fire(self):
        self.sent = time.perf_counter()
        os.kill(os.getpid(), signal.SIGINT)

    def __enter__(self):
        self._timer.start()
        return self

    def __exit__(self, *exc):
        self._timer.cancel()
        self._timer.join()
        return False


# ------------------------------------------------------------------------------------------------ shipped files, paths
def test_shipped_files_run_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    root = jointsim.data_path()
    assert {"robots", "experiments", "sweeps"} <= {p.name for p in root.iterdir()}
    assert jointsim.data_path("robots", "ur5_drives.yaml") == jointsim.data_path("robots/ur5_drives.yaml")
    # An experiment that refers to a robot file by a relative path, loaded from elsewhere.
    e = jointsim.load_experiment(jointsim.data_path("experiments/ur5_excitation.yaml"), {"duration": 0.01})
    assert e.type == "tracking"
    with pytest.raises(FileNotFoundError):
        jointsim.data_path("robots/no_such_robot.yaml")


def test_every_path_argument_takes_a_pathlike(tmp_path):
    exp = jointsim.data_path("experiments/ur5_fall.yaml")  # a pathlib.Path
    assert isinstance(exp, pathlib.Path)
    model = jointsim.load_robot(jointsim.data_path("robots/ur5.urdf"))
    assert model.nq == 6
    r = jointsim.run_experiment(exp, {"duration": 0.05})
    report = jointsim.run_experiment_file(exp, tmp_path / "out", {"duration": 0.05})
    assert report["status"] == "ok" and pathlib.Path(report["csv_path"]).parent == tmp_path / "out"
    assert jointsim.validate_file(exp)["kind"] == "experiment"
    sim = jointsim.Simulator.from_robot(jointsim.data_path("robots/ur5_drives.yaml"))
    assert sim.dof == 6
    assert jointsim.Simulator.from_experiment(exp, {"duration": 0.05}).time == 0.0
    assert len(r["time"]) > 1
    with pytest.raises(TypeError, match="expected a path"):
        jointsim.load_robot(42)


# ------------------------------------------------------------------------------------------------ results
def test_results_as_pandas_with_units_apart():
    r = jointsim.run_experiment(jointsim.data_path("experiments/ur5_fall.yaml"), {"duration": 0.1, "log_rate": 100})
    # The result is a dict of the columns only: pandas takes it as it is.
    df = pd.DataFrame(r)
    assert list(df.columns) == [c.split("[")[0] for c in r.columns] and len(df) == 11
    d = r.to_dataframe()
    assert list(d.columns) == list(df.columns)
    assert d.attrs["units"]["q_elbow_joint"] == "rad" and d.attrs["units"]["time"] == "s"
    np.testing.assert_array_equal(d["q_elbow_joint"].to_numpy(), r["q_elbow_joint"])
    assert r.summary["status"] == "ok" and "summary" not in r and "units" not in r


# ------------------------------------------------------------------------------------------------ sweeps as dicts
def test_a_sweep_given_as_a_dict_equals_the_same_sweep_from_a_file(tmp_path):
    experiment = jointsim.data_path("experiments/ur5_fall.yaml")
    sweep = {
        "sweep": {"name": "fall_pair", "experiment": str(experiment), "set": {"duration": 0.1, "log_rate": 50}},
        "runs": [{"name": "nominal"}, {"name": "spin", "set": {"initial_state.qd[0]": 0.6}}],
    }
    from_dict = jointsim.run_batch(sweep, tmp_path / "dict", jobs=2)
    assert from_dict["ok"] == 2 and from_dict["failed"] == 0
    # The same sweep written as YAML text into a file.
    f = tmp_path / "fall_pair.yaml"
    f.write_text("sweep: {name: fall_pair, experiment: %s, set: {duration: 0.1, log_rate: 50}}\n"
                 "runs: [{name: nominal}, {name: spin, set: {'initial_state.qd[0]': 0.6}}]\n" % experiment)
    from_file = jointsim.run_batch(f, tmp_path / "file")
    for run in ("nominal", "spin"):
        a = (tmp_path / "dict" / run / "ur5_fall.csv").read_bytes()
        assert a == (tmp_path / "file" / run / "ur5_fall.csv").read_bytes()
    assert [x["overrides"] for x in from_dict["records"]] == [x["overrides"] for x in from_file["records"]]
    # Relative paths in a dict are relative to base_dir.
    rel = dict(sweep, sweep=dict(sweep["sweep"], experiment="experiments/ur5_fall.yaml"))
    out = jointsim.run_batch(rel, tmp_path / "rel", base_dir=jointsim.data_path())
    assert out["ok"] == 2 and out["skipped"] == 0
    # Bad input in a dict names the key.
    with pytest.raises(jointsim.InputError) as err:
        jointsim.run_batch({"sweep": {"name": "x", "experiment": str(experiment)}, "runz": []}, tmp_path / "bad")
    assert "runz" in str(err.value)
    assert not (tmp_path / "bad").exists()


def test_read_dataset_decodes_labels_and_matches_the_logs(tmp_path):
    sweep = {
        "sweep": {"name": "fall_set", "experiment": str(jointsim.data_path("experiments/ur5_excitation.yaml")),
                  "set": {"duration": 0.05}},
        "runs": [{"name": "nominal"},
                 {"name": "stiff", "faults": [{"type": "gear_stiffness_scale", "joint": "elbow_joint",
                                               "value": 0.5}]}],
    }
    jointsim.run_batch(sweep, tmp_path / "runs", jobs=2)
    info = jointsim.write_dataset(sweep, tmp_path / "set.h5", tmp_path / "runs")
    assert info["runs_with_data"] == 2
    ds = jointsim.read_dataset(tmp_path / "set.h5")
    assert list(ds.labels["run"]) == ["nominal", "stiff"]  # str, not bytes
    assert list(ds.labels["fault_type"]) == ["", "gear_stiffness_scale"]
    assert list(ds.labels["fault_joint"]) == ["", "elbow_joint"]
    assert ds.labels["fault_severity"].iloc[1] == 0.5
    assert sorted(ds.runs) == ["nominal", "stiff"]
    df = ds.run("stiff")
    csv = pd.read_csv(tmp_path / "runs" / "stiff" / "ur5_excitation.csv")
    assert len(df) == len(csv)
    for column in csv.columns:
        name, unit = column.split("[")[0], column.split("[")[1].rstrip("]")
        np.testing.assert_array_equal(df[name].to_numpy(), csv[column].to_numpy())
        assert df.attrs["units"][name] == unit
    with pytest.raises(jointsim.InputError, match="no run"):
        ds.run("missing")
    with pytest.raises(FileNotFoundError):
        jointsim.read_dataset(tmp_path / "none.h5")


# ------------------------------------------------------------------------------------------------ exceptions
def test_exceptions_have_python_types_and_fields(tmp_path):
    missing = tmp_path / "missing.yaml"
    with pytest.raises(FileNotFoundError) as e:
        jointsim.load_experiment(missing)
    assert isinstance(e.value, jointsim.InputError) and isinstance(e.value, ValueError)
    assert e.value.file == str(missing) and e.value.filename == str(missing)
    # A robot file named inside an experiment file that does not exist: the C++ reader's error, same types.
    exp = tmp_path / "exp.yaml"
    exp.write_text(jointsim.data_path("experiments/ur5_fall.yaml").read_text().replace("../robots/ur5.yaml",
                                                                                       str(tmp_path / "no.yaml")))
    with pytest.raises(FileNotFoundError, match="no.yaml") as e:
        jointsim.run_experiment(exp)
    assert e.value.filename == str(tmp_path / "no.yaml") and e.value.missing_path == e.value.filename
    assert e.value.file == str(exp) and e.value.key_path == "robot" and e.value.line > 1
    # A bad value in a file: file, line and key path.
    bad = tmp_path / "bad.yaml"
    bad.write_text(jointsim.data_path("experiments/ur5_fall.yaml").read_text()
                   .replace("../robots/ur5.yaml", str(jointsim.data_path("robots/ur5.yaml")))
                   .replace("duration: ", "duration: -"))
    with pytest.raises(jointsim.InputError) as e:
        jointsim.load_experiment(bad)
    assert e.value.file == str(bad) and e.value.key_path == "duration" and e.value.line > 1
    assert e.value.reason and e.value.reason in str(e.value)
    # An override of a key the file lacks: the key path, and no command-line wording.
    with pytest.raises(jointsim.InputError) as e:
        jointsim.load_experiment(jointsim.data_path("experiments/ur5_fall.yaml"), {"solver.nope": 1})
    assert e.value.key_path == "solver.nope" and "--set" not in str(e.value)
    # Wrong types: TypeError.
    with pytest.raises(TypeError):
        jointsim.run_batch(jointsim.data_path("sweeps/ur5_faults.yaml"), tmp_path / "x", jobs="2")
    with pytest.raises(jointsim.InputTypeError, match="joint"):
        jointsim.Simulator.from_robot(jointsim.data_path("robots/ur5_drives.yaml")).set_port(1.5, "voltage")
    with pytest.raises(TypeError):
        jointsim.Simulator.from_robot(jointsim.data_path("robots/ur5_drives.yaml"), rtol="tight")
    with pytest.raises(jointsim.InputError, match="jobs"):
        jointsim.run_batch(jointsim.data_path("sweeps/ur5_faults.yaml"), tmp_path / "x", jobs=0)
    # A solver failure: time, flag and component.
    sim = jointsim.Simulator.from_experiment(jointsim.data_path("experiments/ur5_excitation.yaml"))
    sim.set_limits(max_steps=5)
    with pytest.raises(jointsim.SolverError) as e:
        sim.advance(1.0)
    assert isinstance(e.value, RuntimeError)
    assert e.value.flag == "STEP_BUDGET" and 0.0 <= e.value.time < 1.0 and "ur5_twin" in e.value.component


# ------------------------------------------------------------------------------------------------ long calls
def test_one_long_advance_completes_and_ctrl_c_interrupts_it_promptly():
    """advance(300.0) on the UR5 twin (Fourier excitation, ~800,000 solver steps: more than CVODE's per-call cap of
    500,000) completes in one call; Ctrl-C during it raises KeyboardInterrupt within 0.2 s and the simulator goes on
    from where it stood."""
    sim = jointsim.Simulator.from_experiment(jointsim.data_path("experiments/ur5_excitation.yaml"), {"duration": 300})
    with _SigintAfter(0.5) as sigint, pytest.raises(KeyboardInterrupt):
        sim.advance(300.0)
    latency = time.perf_counter() - sigint.sent
    print(f"KeyboardInterrupt {1e3 * latency:.1f} ms after SIGINT, at t = {sim.time:.3f} s")
    assert latency < 0.2
    t_stop = sim.time
    assert 0.0 < t_stop < 300.0
    assert sim.advance(0.5) == pytest.approx(t_stop + 0.5, abs=1e-12)
    assert sim.advance_to(300.0) == 300.0
    assert sim.steps > 500_000
    assert abs(sim.signal("q_elbow_joint") - sim.signal("q_set_elbow_joint")) < 0.01


def test_ctrl_c_interrupts_run_experiment_and_run_batch(tmp_path):
    exp = jointsim.data_path("experiments/ur5_excitation.yaml")
    with _SigintAfter(0.3) as sigint, pytest.raises(KeyboardInterrupt):
        jointsim.run_experiment(exp, {"duration": 300})
    assert time.perf_counter() - sigint.sent < 0.2
    # A batch: its runs are stopped (interrupted, resumable) and the call raises.
    sweep = {"sweep": {"name": "long", "experiment": str(exp), "set": {"duration": 300}},
             "runs": [{"name": "a"}, {"name": "b"}, {"name": "c"}]}
    with _SigintAfter(1.0) as sigint, pytest.raises(KeyboardInterrupt):
        jointsim.run_batch(sweep, tmp_path / "runs", jobs=2)
    assert time.perf_counter() - sigint.sent < 1.0  # the runs end at their next step and write their summaries
    statuses = {p.parent.name: p.read_text() for p in (tmp_path / "runs").glob("*/summary.json")}
    assert statuses and all('"interrupted"' in s for s in statuses.values())
    # Afterwards everything works as before.
    assert jointsim.run_experiment(exp, {"duration": 0.01}).summary["status"] == "ok"


def test_a_divergent_controller_stops_within_2_s_with_a_clear_error():
    """Positive feedback on the motor torques: the arm runs away. The default state bound ends the call at once with
    SolverError DIVERGED naming the state, instead of minutes of ever smaller steps."""
    sim = jointsim.Simulator.from_robot(jointsim.data_path("robots/ur5_drives.yaml"))
    for k in range(sim.dof):
        sim.set_port(k, "motor_torque")
    q0 = sim.joint_positions
    wall, cpu = time.perf_counter(), time.process_time()
    with pytest.raises(jointsim.SolverError) as e:
        while sim.time < 5.0:
            sim.set_commands(50.0 * (sim.joint_positions - q0 + 0.01))
            sim.advance(1e-3)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    print(f"diverged after {wall:.2f} s of wall time ({cpu:.2f} s of CPU time): {e.value}")
    # The work it takes (CPU time: the wall time of an otherwise idle machine; the suite may share the machine).
    assert cpu < 2.0
    assert e.value.flag == "DIVERGED" and "max_state" in str(e.value) and "[rad/s]" in str(e.value)
    assert f"after t = {e.value.time:.10g} s" in str(e.value)  # the time the simulator stands at, in the message
    assert np.all(np.isfinite(sim.state)) and 0.0 < e.value.time < 1.0


def test_wall_time_and_step_limits_per_call():
    sim = jointsim.Simulator.from_experiment(jointsim.data_path("experiments/ur5_excitation.yaml"), {"duration": 300})
    sim.set_limits(max_wall_time=0.2)
    assert sim.limits["max_wall_time"] == 0.2 and sim.limits["max_state"] == jointsim.Simulator.DEFAULT_MAX_STATE
    wall = time.perf_counter()
    with pytest.raises(jointsim.SolverError) as e:
        sim.advance(300.0)
    assert e.value.flag == "WALL_TIME_BUDGET" and time.perf_counter() - wall < 0.5
    t = sim.time
    assert t > 0.0
    sim.set_limits(max_wall_time=0, max_steps=200)
    with pytest.raises(jointsim.SolverError) as e:
        sim.advance(300.0)
    assert e.value.flag == "STEP_BUDGET" and sim.time > t
    sim.set_limits(max_steps=0)
    t = sim.time
    assert sim.advance(0.1) == pytest.approx(t + 0.1, abs=1e-12)
    with pytest.raises(jointsim.InputError):
        sim.set_limits(max_wall_time=-1.0)
    c = copy.copy(sim)  # an independent simulator (its own state), with the same limits
    assert c.time == sim.time and c.limits == sim.limits


# ------------------------------------------------------------------------------------------------ arguments
def test_export_fmu_takes_one_input_as_a_string(tmp_path):
    exp = jointsim.data_path("experiments/ur5_excitation.yaml")
    one = jointsim.export_fmu(exp, tmp_path / "a.fmu", inputs="voltage", outputs="q_elbow_joint")
    many = jointsim.export_fmu(exp, tmp_path / "b.fmu", inputs=["voltage"], outputs=["q_elbow_joint"])
    names = lambda d: [(v["name"], v["causality"]) for v in d["variables"]]  # noqa: E731
    assert names(one) == names(many)
    assert sum(1 for _, c in names(one) if c == "input") == 6


def test_batched_rigid_body_calls_equal_one_call_per_state():
    model = jointsim.load_robot(jointsim.data_path("robots/ur5.yaml"))
    rng = np.random.default_rng(7)
    Q, QD, QDD = (rng.uniform(-2, 2, (50, 6)) for _ in range(3))
    tau = jointsim.rnea(model, Q, QD, QDD)
    assert tau.shape == (50, 6)
    M = jointsim.crba(model, Q)
    assert M.shape == (50, 6, 6)
    g = jointsim.gravity_torques(model, Q)
    qdd = jointsim.aba(model, Q, QD, tau)
    for i in range(50):
        np.testing.assert_array_equal(tau[i], jointsim.rnea(model, Q[i], QD[i], QDD[i]))
        np.testing.assert_array_equal(M[i], jointsim.crba(model, Q[i]))
        np.testing.assert_array_equal(g[i], jointsim.gravity_torques(model, Q[i]))
    np.testing.assert_allclose(qdd, QDD, atol=1e-9)  # ABA inverts RNEA, state by state
    with pytest.raises(jointsim.InputError, match=r"qd: expected the shape of q, \(50, 6\), got shape \(10, 6\)"):
        jointsim.rnea(model, Q, QD[:10], QDD)


# ------------------------------------------------------------------------------------------------ documentation
def _public_members():
    for name in jointsim.__all__:
        obj = getattr(jointsim, name)
        yield name, obj
        if inspect.isclass(obj) and not issubclass(obj, BaseException):
            for attr, member in vars(obj).items():
                if not attr.startswith("_"):
                    yield f"{name}.{attr}", member


def test_every_public_function_and_property_has_a_docstring():
    missing = []
    for name, obj in _public_members():
        if isinstance(obj, (str, tuple, float, int)):
            continue
        doc = obj.__doc__ if not isinstance(obj, staticmethod) else obj.__func__.__doc__
        if not doc or len(doc.strip()) < 10:
            missing.append(name)
    assert not missing, f"no docstring: {missing}"
    # Units and shapes are stated where arrays and quantities go in or out.
    for f in (jointsim.rnea, jointsim.aba, jointsim.crba, jointsim.gravity_torques, jointsim.frame_jacobian):
        assert "shape" in f.__doc__ and "[" in f.__doc__, f.__name__


def _runtime_signature(obj):
    """Parameter names of a pybind11 function or method from its docstring signature (self excluded)."""
    first = (obj.__doc__ or "").strip().splitlines()[0]
    inside = first[first.index("(") + 1: first.rindex(")")]
    names, depth, cur = [], 0, ""
    for ch in inside + ",":
        if ch in "[(":
            depth += 1
        elif ch in "])":
            depth -= 1
        if ch == "," and depth == 0:
            names.append(cur.split(":")[0].strip())
            cur = ""
        else:
            cur += ch
    return [n for n in names if n and n != "self"]


def test_the_stubs_name_every_member_of_the_extension_with_its_parameters():
    stub = ast.parse((pathlib.Path(_core.__file__).parent / "_core.pyi").read_text())

    def params(fn):
        return [a.arg for a in fn.args.args if a.arg != "self"]

    stubbed = {}
    for node in stub.body:
        if isinstance(node, ast.FunctionDef):
            stubbed[node.name] = params(node)
        elif isinstance(node, ast.ClassDef):
            stubbed[node.name] = None
            for f in node.body:
                if isinstance(f, ast.FunctionDef):
                    is_property = any(isinstance(d, ast.Name) and d.id == "property" for d in f.decorator_list)
                    stubbed[f"{node.name}.{f.name}"] = "property" if is_property else params(f)
    runtime = {}
    for name, obj in vars(_core).items():
        if name.startswith("_"):
            continue
        if inspect.isclass(obj):
            runtime[name] = None
            for attr, member in vars(obj).items():
                if attr.startswith("_"):
                    continue
                runtime[f"{name}.{attr}"] = "property" if isinstance(member, property) else _runtime_signature(
                    getattr(obj, attr))
        elif callable(obj):
            runtime[name] = _runtime_signature(obj)
    assert set(stubbed) == set(runtime), (set(stubbed) ^ set(runtime))
    for name in runtime:
        assert stubbed[name] == runtime[name], f"{name}: stub {stubbed[name]} vs module {runtime[name]}"


# ------------------------------------------------------------------------------------------------ threads and processes
def _python(code, tmp_path, timeout=120):
    """Runs `code` in a fresh interpreter (a hang or an abort there cannot take the test session with it)."""
    import subprocess
    import sys
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    return subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=timeout)


def test_a_batch_from_a_process_with_busy_python_threads_completes(tmp_path):
    """The runs of a batch are forked from the calling thread: they must not ask the parent's Python for its
    signals (in the child nobody would ever release the GIL another thread held at the fork)."""
    p = _python(f"""
import threading, jointsim
stop = False
def spin():
    x = 0
    while not stop:
        x += 1
threading.Thread(target=spin, daemon=True).start()
sweep = {{"sweep": {{"name": "busy", "experiment": str(jointsim.data_path("experiments/msl_friction.yaml"))}},
         "runs": [{{"name": "a"}}, {{"name": "b"}}, {{"name": "c"}}]}}
r = jointsim.run_batch(sweep, {str(tmp_path / 'runs')!r}, jobs=1)
stop = True
print(r["ok"], r["failed"])
""", tmp_path)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["3", "0"]


def test_a_long_call_in_a_daemon_thread_does_not_abort_the_interpreter_at_exit(tmp_path):
    p = _python("""
import threading, time, jointsim
sim = jointsim.Simulator.from_experiment(jointsim.data_path("experiments/ur5_excitation.yaml"), {"duration": 300})
threading.Thread(target=lambda: sim.advance(300.0), daemon=True).start()
time.sleep(0.5)
print("main thread done")
""", tmp_path)
    assert p.returncode == 0, (p.returncode, p.stderr)
    assert "main thread done" in p.stdout and "terminate" not in p.stderr


def test_one_simulator_from_four_threads_raises_instead_of_crashing():
    """Four threads on one Simulator (advance releases the GIL): every call either completes or raises
    ConcurrentUseError, never a crash or a corrupted state; the simulator is right afterwards. Independent
    simulators in threads give the same numbers as one after the other."""
    sim = jointsim.Simulator.from_robot(jointsim.data_path("robots/ur5_drives.yaml"))
    for k in range(sim.dof):
        sim.set_port(k, "voltage")
    errors, done = [], []

    def hammer(seed):
        rng = np.random.default_rng(seed)
        for _ in range(200):
            try:
                if rng.random() < 0.5:
                    sim.advance(1e-3)
                else:
                    sim.set_commands(rng.uniform(-1, 1, 6))
                    sim.signals()
                done.append(1)
            except jointsim.ConcurrentUseError as e:
                errors.append(str(e))

    threads = [threading.Thread(target=hammer, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(done) + len(errors) == 800 and len(done) > 0
    assert all("two threads at once" in e for e in errors)
    assert np.all(np.isfinite(sim.state))
    t = sim.time
    assert sim.advance(1e-3) == pytest.approx(t + 1e-3, abs=1e-12)

    # An experiment and the simulators made from it share only the constant model: each has its own state, so a
    # simulator stepping in a thread neither blocks nor changes the experiment's own run.
    exp = jointsim.load_experiment(jointsim.data_path("experiments/ur5_excitation.yaml"), {"duration": 0.3})
    alone = exp.run()
    ssim = exp.simulator()
    ssim.set_port(2, "voltage")
    ssim.set_command(2, 4.0)
    worker = threading.Thread(target=lambda: ssim.advance(0.3))
    worker.start()
    beside = exp.run()
    worker.join()
    assert ssim.time == pytest.approx(0.3, abs=1e-12)
    for name in ("q_elbow_joint", "voltage_elbow_joint"):
        np.testing.assert_array_equal(beside[name], alone[name])

    # Independent simulators in threads: the same numbers as one after the other.
    def run_one(out, key):
        s = jointsim.Simulator.from_robot(jointsim.data_path("robots/ur5_drives.yaml"))
        s.set_port(2, "voltage")
        s.set_command(2, 3.0)
        s.advance(0.2)
        out[key] = s.state

    sequential, parallel = {}, {}
    run_one(sequential, 0)
    threads = [threading.Thread(target=run_one, args=(parallel, k)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k in range(4):
        np.testing.assert_array_equal(parallel[k], sequential[0])


def test_two_simulators_of_one_experiment_in_two_threads_equal_the_sequential_runs():
    """One loaded experiment, two simulators stepped in two threads (advance releases the GIL): the constant model
    is evaluated with two states at once, and each run equals its sequential twin bit for bit (also under
    ThreadSanitizer in CI: scripts/tsan-python.sh runs the tests named *thread*)."""
    exp = jointsim.load_experiment(jointsim.data_path("experiments/ur5_excitation.yaml"), {"duration": 1.0})

    def run(voltage, out=None, key=None):
        s = exp.simulator()
        if voltage:
            s.set_port(1, "voltage")
            s.set_command(1, voltage)
        for _ in range(40):
            s.advance(5e-3)
        if out is not None:
            out[key] = s.state
        return s.state

    a, b = run(0.0), run(3.0)
    assert not np.array_equal(a, b)
    out = {}
    threads = [threading.Thread(target=run, args=(v, out, k)) for k, v in enumerate((0.0, 3.0))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    np.testing.assert_array_equal(out[0], a)
    np.testing.assert_array_equal(out[1], b)


def test_snapshots_restore_copy_and_pickle_continue_bit_for_bit():
    """snapshot() at 0.1 s, on to 0.2 s, restore(), on to 0.2 s again: identical; the same through a pickled
    snapshot into another simulator of the same experiment, through save_state()/load_state(), and for a copy
    (copy.deepcopy) whose inputs do not reach the original."""
    exp = jointsim.load_experiment(jointsim.data_path("experiments/ur5_excitation.yaml"), {"duration": 1.0})
    sim = exp.simulator()
    sim.set_port(0, "voltage")
    sim.set_command(0, 1.5)
    sim.advance_to(0.1)
    snap = sim.snapshot()
    data = sim.save_state()
    assert snap.time == 0.1 and isinstance(data, bytes)
    sim.advance_to(0.2)
    end = sim.state
    sim.restore(snap)
    assert sim.time == 0.1 and sim.port(0) == "voltage"
    sim.advance_to(0.2)
    np.testing.assert_array_equal(sim.state, end)
    other = exp.simulator()
    other.restore(pickle.loads(pickle.dumps(snap)))
    other.advance_to(0.2)
    np.testing.assert_array_equal(other.state, end)
    third = jointsim.Simulator.from_experiment(jointsim.data_path("experiments/ur5_excitation.yaml"),
                                               {"duration": 1.0})
    third.load_state(data)
    third.advance_to(0.2)
    np.testing.assert_array_equal(third.state, end)
    # A copy is independent.
    sim.restore(snap)
    c = copy.deepcopy(sim)
    c.set_command(0, -1.5)
    c.advance_to(0.2)
    sim.advance_to(0.2)
    np.testing.assert_array_equal(sim.state, end)
    assert not np.array_equal(c.state, end)
    # Bad input: another model's state, garbage, a non-snapshot.
    rig = jointsim.Simulator.from_experiment(jointsim.data_path("experiments/msl_backlash.yaml"))
    with pytest.raises(jointsim.InputError, match="not of this plant"):
        rig.load_state(data)
    with pytest.raises(jointsim.InputError):
        sim.load_state(b"garbage")
    with pytest.raises(TypeError):
        sim.restore(data)
    with pytest.raises(TypeError, match="snapshot"):
        pickle.dumps(sim)


def test_reset_clears_the_inputs_and_takes_a_start_pose():
    sim = jointsim.Simulator.from_robot(jointsim.data_path("robots/ur5_drives.yaml"))
    sim.advance(0.02)
    fresh = sim.state
    sim.set_port(2, "voltage")
    sim.set_command(2, 6.0)
    sim.set_external_wrench("tool0", [0, 0, -10, 0, 0, 0])
    sim.advance(0.02)
    sim.reset()
    assert sim.time == 0.0 and sim.port(2) == "setpoint"
    sim.advance(0.02)
    np.testing.assert_array_equal(sim.state, fresh)
    q0 = np.array([0.1, -1.0, 1.0, -1.5, -1.5708, 0.2])
    qd0 = np.array([0.0, 0.0, 0.3, 0.0, 0.0, 0.0])
    sim.reset(q0=q0, qd0=qd0)
    np.testing.assert_array_equal(sim.joint_positions, q0)
    np.testing.assert_array_equal(sim.joint_velocities, qd0)
    names = sim.state_names
    assert len(names) == len(sim.state) and names[0] == "q_shoulder_pan_joint [rad]"
    with pytest.raises(jointsim.InputError):
        sim.reset(q0=[0.0, 1.0])


def test_inputs_are_listed_with_units_and_set_by_name_like_the_ports():
    a = jointsim.Simulator.from_robot(jointsim.data_path("robots/ur5_drives.yaml"))
    b = a.copy()
    inputs = {i["name"]: i for i in a.inputs}
    assert inputs["elbow_joint.voltage"]["unit"] == "V" and inputs["elbow_joint.voltage"]["group"] == "elbow_joint"
    assert inputs["elbow_joint.q"]["mode"] == "setpoint" and inputs["elbow_joint.q"]["active"]
    assert not inputs["elbow_joint.current"]["active"]
    a.set_input("elbow_joint.voltage", 6.0)
    b.set_port("elbow_joint", "voltage")
    b.set_command("elbow_joint", 6.0)
    assert a.port(2) == "voltage" and a.input("elbow_joint.voltage") == 6.0
    a.advance(0.05)
    b.advance(0.05)
    np.testing.assert_array_equal(a.state, b.state)
    with pytest.raises(jointsim.InputError, match="elbow_joint.voltage"):  # the message lists the inputs
        a.set_input("elbow_joint.volts", 1.0)


@pytest.mark.parametrize("experiment,port,unit", [
    ("msl_friction.yaml", "inertia1.load_torque", "N·m"),
    ("robotr3_one_axis.yaml", "axis.current", "A"),
    ("robotr3_full_robot.yaml", "r2.load_torque", "N·m"),
    ("irb140_clamping.yaml", "joint2.motor_torque", "N·m"),
    ("ur5_fall.yaml", "elbow_joint.torque", "N·m"),
    ("ur5_pick_and_place.yaml", "elbow_joint.load_torque", "N·m"),
])
def test_every_experiment_type_has_input_ports_in_python(experiment, port, unit):
    """Input ports reach every model, not only the robot with drives and the rig: listed with units, set by name,
    in effect (the run differs from one without the input)."""
    path = jointsim.data_path("experiments/" + experiment)
    a = jointsim.Simulator.from_experiment(path)
    b = jointsim.Simulator.from_experiment(path)
    inputs = {i["name"]: i for i in a.inputs}
    assert inputs[port]["unit"] == unit
    a.set_input(port, 0.5)
    assert a.input(port) == 0.5 and {i["name"]: i for i in a.inputs}[port]["active"]
    a.advance(0.05)
    b.advance(0.05)
    assert not np.array_equal(a.state, b.state)
    with pytest.raises(jointsim.InputError, match=re.escape(port)):
        a.set_input(port, float("nan"))
    a.release_input(port)  # back to the model's own source
    replaces = port in ("axis.current", "joint2.motor_torque")  # in place of a controller: out of effect again
    assert a.input(port) == 0.0 and {i["name"]: i for i in a.inputs}[port]["active"] != replaces


def test_drive_parameter_tables_and_the_drives_key_that_changes_them():
    path = jointsim.data_path("experiments/ur5_pick_and_place.yaml")
    nominal = jointsim.Simulator.from_experiment(path).drive_parameters("elbow_joint")
    km = next(r for r in nominal["transmission"] if r["key"] == "K_m")
    assert km["unit"] == "N/m" and km["role"] == "stiffness" and km["min"] == 0.0 and km["min_open"]
    assert {r["key"] for r in nominal["motor"]} == {"R", "L", "kt", "ke", "J_M", "V_supply"}
    changed = jointsim.Simulator.from_experiment(
        path, {"+drives.elbow_joint.transmission.K_m": 2 * km["value"], "+duration": 0.02}).drive_parameters(2)
    assert next(r for r in changed["transmission"] if r["key"] == "K_m")["value"] == 2 * km["value"]
    with pytest.raises(jointsim.InputError, match="K_WG"):  # an unknown key lists the table's keys
        jointsim.load_experiment(path, {"+drives.elbow_joint.transmission.K_x": 1.0})


def _ignore(error, call):
    try:
        call()
    except error:
        pass


def test_frames_and_paths_of_the_wrong_kind_are_input_errors():
    model = jointsim.load_robot(jointsim.data_path("robots/ur5.urdf"))
    with pytest.raises(TypeError, match="frame"):
        jointsim.frame_placement(model, np.zeros(6), 3)
    with pytest.raises(jointsim.InputError, match="NUL"):
        jointsim.load_robot(str(jointsim.data_path("robots/ur5.urdf")) + "\0.yaml")


def test_fixed_step_method_from_a_robot_file_and_from_an_experiment():
    """method="rosenbrock": a fixed number of steps per advance (the grid of `step`), the same motion as BDF to far
    below the drives' resolution; from an experiment file through its solver keys; bad choices raise."""
    path = jointsim.data_path("robots/ur5_drives.yaml")
    q0 = [0.3, -1.2, 1.2, -1.5, -1.5708, 0.0]
    fixed = jointsim.Simulator.from_robot(path, q0, method="rosenbrock", step=2.5e-5)
    ref = jointsim.Simulator.from_robot(path, q0, rtol=1e-10, atol=1e-12)
    for sim in (fixed, ref):
        for k in range(sim.dof):
            sim.set_port(k, "voltage")
        sim.set_commands([2.0, -1.0, 1.0, 0.5, -0.5, 1.0])  # V
    fixed.advance(0.02)
    ref.advance(0.02)
    assert fixed.steps == 800  # 0.02 s / 25 µs, no more
    np.testing.assert_allclose(fixed.joint_positions, ref.joint_positions, atol=1e-6)
    assert np.abs(fixed.joint_positions - np.array(q0)).max() > 1e-4  # it moved
    exp = jointsim.data_path("experiments/ur5_excitation.yaml")
    sampled = jointsim.Simulator.from_experiment(
        exp, {"+control.rate": 20000, "solver.method": "rosenbrock", "duration": 0.01})
    sampled.advance(0.01)
    assert sampled.steps == 200  # one step per 50 µs control period
    w = sampled.period_wall_times
    assert w["periods"] == 198  # 201 samples at k·50 µs: the one at reset and the first after it start the clock
    assert 0.0 < w["p50"] <= w["p99"] <= w["max"]
    with pytest.raises(jointsim.InputError, match="integer fraction"):
        jointsim.Simulator.from_experiment(
            exp, {"+control.rate": 20000, "solver.method": "rosenbrock", "+solver.step": 3e-5})
    with pytest.raises(jointsim.InputError, match="'bdf' or 'rosenbrock'"):
        jointsim.Simulator.from_robot(path, method="rk4")
    with pytest.raises(jointsim.InputError, match="needs its step"):
        jointsim.Simulator.from_robot(path, method="rosenbrock")  # continuous control: no period to take
