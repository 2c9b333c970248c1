"""The Python package against closed forms, the CLI (to the last bit), a Python controller around the UR5 twin,
and bad input."""
import json
import math
import subprocess
import time

import numpy as np
import pytest

import jointsim

L1, L2, M2 = 0.7, 0.5, 2.0  # tests/data/planar2.urdf: link lengths [m], link-2 mass [kg] (CoM 0.2 m out)


@pytest.fixture(scope="module")
def planar2(root):
    return jointsim.load_robot(str(root / "tests/data/planar2.urdf"))


def test_rigid_body_closed_forms(planar2):
    m = planar2
    assert m.nq == 2 and m.joint_names == ["joint1", "joint2"]
    q = np.array([0.4, -0.7])
    # Tool position (cos q1 (l1 + l2 cos q2), sin q1 (l1 + l2 cos q2), l2 sin q2).
    T = jointsim.frame_placement(m, q, "tip")
    r = L1 + L2 * math.cos(q[1])
    np.testing.assert_allclose(T[:3, 3], [math.cos(q[0]) * r, math.sin(q[0]) * r, L2 * math.sin(q[1])], atol=1e-14)
    # Gravity: none about the vertical joint 1; m2 g 0.2 cos q2 on joint 2.
    np.testing.assert_allclose(jointsim.gravity_torques(m, q), [0.0, M2 * 9.81 * 0.2 * math.cos(q[1])], atol=1e-12)
    # M22 = I2zz + m2 0.2² (constant); M symmetric.
    M = jointsim.crba(m, q)
    assert M.shape == (2, 2)
    assert M[1, 1] == pytest.approx(0.03 + M2 * 0.04, abs=1e-14)
    assert M[0, 1] == pytest.approx(M[1, 0], abs=1e-15)
    # RNEA and ABA are inverse to each other; RNEA(q, 0, qdd) - g = M qdd.
    qd, qdd = np.array([0.3, -1.1]), np.array([2.0, -0.5])
    tau = jointsim.rnea(m, q, qd, qdd)
    np.testing.assert_allclose(jointsim.aba(m, q, qd, tau), qdd, atol=1e-12)
    np.testing.assert_allclose(jointsim.rnea(m, q, np.zeros(2), qdd) - jointsim.gravity_torques(m, q), M @ qdd, atol=1e-12)
    # The Jacobian's linear rows against central differences of the tool position.
    J = jointsim.frame_jacobian(m, q, "tip")
    h = 1e-6
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        fd = (jointsim.frame_placement(m, q + e, "tip")[:3, 3] - jointsim.frame_placement(m, q - e, "tip")[:3, 3]) / (2 * h)
        np.testing.assert_allclose(J[:3, j], fd, atol=1e-8)
    # Lists and integer arrays convert.
    np.testing.assert_allclose(jointsim.rnea(m, [0.4, -0.7], [0, 0], [0, 0]), jointsim.gravity_torques(m, q))


def test_dynamics_derivatives_against_central_differences(root):
    m = jointsim.load_robot(str(root / "config/robots/ur5.yaml"))
    rng = np.random.default_rng(4)
    q, qd, qdd, tau = (rng.uniform(-2, 2, 6) for _ in range(4))
    dtau_dq, dtau_dqd, M = jointsim.rnea_derivatives(m, q, qd, qdd)
    dqdd_dq, dqdd_dqd, Minv = jointsim.aba_derivatives(m, q, qd, tau)
    h = 1e-6
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        fd = (jointsim.rnea(m, q + e, qd, qdd) - jointsim.rnea(m, q - e, qd, qdd)) / (2 * h)
        np.testing.assert_allclose(dtau_dq[:, j], fd, rtol=0, atol=1e-6 * max(1.0, np.abs(fd).max()))
        fd = (jointsim.rnea(m, q, qd + e, qdd) - jointsim.rnea(m, q, qd - e, qdd)) / (2 * h)
        np.testing.assert_allclose(dtau_dqd[:, j], fd, rtol=0, atol=1e-6 * max(1.0, np.abs(fd).max()))
        fd = (jointsim.aba(m, q + e, qd, tau) - jointsim.aba(m, q - e, qd, tau)) / (2 * h)
        np.testing.assert_allclose(dqdd_dq[:, j], fd, rtol=0, atol=1e-6 * max(1.0, np.abs(fd).max()))
        fd = (jointsim.aba(m, q, qd + e, tau) - jointsim.aba(m, q, qd - e, tau)) / (2 * h)
        np.testing.assert_allclose(dqdd_dqd[:, j], fd, rtol=0, atol=1e-6 * max(1.0, np.abs(fd).max()))
    np.testing.assert_allclose(M, jointsim.crba(m, q), atol=1e-12)
    np.testing.assert_allclose(Minv @ jointsim.crba(m, q), np.eye(6), atol=1e-9)


def _cli_log(cli, config, overrides, tmp_path):
    args = [str(cli), "run", str(config), "-o", str(tmp_path)]
    for o in overrides:
        args += ["--set", o]
    subprocess.run(args, check=True, capture_output=True)
    csv = next(p for p in tmp_path.glob("*.csv"))
    header = csv.read_text().splitlines()[0].split(",")
    return header, np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2), json.loads((tmp_path / "summary.json").read_text())


@pytest.mark.parametrize("config,overrides", [
    ("config/experiments/ur5_fall.yaml", {"duration": 0.2}),
    ("config/experiments/ur5_excitation.yaml", {"duration": 0.05}),
    ("config/experiments/msl_friction.yaml", {}),
])
def test_results_equal_the_cli_to_the_last_bit(root, cli, tmp_path, config, overrides):
    r = jointsim.run_experiment(str(root / config), overrides)
    header, values, summary = _cli_log(cli, root / config, [f"{k}={v}" for k, v in overrides.items()], tmp_path)
    assert r.columns == header
    for j, column in enumerate(header):
        name = column.split("[")[0]
        assert np.array_equal(r[name], values[:, j]), f"{column} differs"
    assert r.summary["status"] == "ok"
    assert r.summary["parameters"] == summary["parameters"]


def test_overrides_and_experiment_objects(root):
    e = jointsim.load_experiment(str(root / "config/experiments/ur5_fall.yaml"), ["duration=0.1", "log_rate=100"])
    assert e.type == "passive_robot" and e.name == "ur5_fall"
    r = e.run()
    assert r["time"][-1] == pytest.approx(0.1) and len(r["time"]) == 11
    assert r.units["q_shoulder_pan_joint"] == "rad"


@pytest.mark.parametrize("method", ["bdf", "rosenbrock", "rosenbrock-adaptive"])
def test_python_pd_controller_tracks_a_step_on_the_ur5_twin(root, method):
    """A PD law with gravity feed-forward, in Python at 1 kHz, commands the six motor voltages of the UR5 twin;
    every joint steps by 0.1 rad at 0.2 s and is within 5 mrad of its reference from 1.7 s on (the C++ example
    examples/pd_voltage_ur5.cpp does the same, with the same solver settings: rtol 1e-4, see docs/performance.md). The
    damping acts on the motor speed (collocated with the voltage). With BDF and with the fixed-step method at one
    step per 1 ms period (the C++ example's `2 1e-4 1e-3`), there also with the Jacobian kept while it describes the
    steps (`2 1e-4 1e-3 adaptive`)."""
    q0 = np.array([0.0, -1.2, 1.2, -1.5, -1.5708, 0.0])
    fixed = {"method": "rosenbrock", "step": 1e-3} if method.startswith("rosenbrock") else {}
    if method == "rosenbrock-adaptive":
        fixed["jacobian_every"] = "adaptive"
    sim = jointsim.Simulator.from_robot(str(root / "config/robots/ur5_drives.yaml"), q0=q0, rtol=1e-4,
                                        max_gamma_change=0.5, **fixed)
    ratios = sim.gear_ratios
    model = sim.model()
    for k in range(6):
        sim.set_port(k, "voltage")
    Kp, Kd, dt = 200.0, 5.0, 1e-3
    q_ref = q0.copy()
    worst = 0.0
    wall0 = time.perf_counter()
    ff = _gravity_voltage_gains(root)
    while sim.time < 2.0 - 1e-9:
        if sim.time >= 0.2 - 1e-9:
            q_ref = q0 + 0.1
        q = sim.joint_positions
        V = ff * jointsim.gravity_torques(model, q) + Kp * (q_ref - q) - Kd * sim.motor_velocities / ratios
        sim.set_commands(V)
        sim.advance(dt)
        if sim.time >= 1.7 - 1e-9:
            worst = max(worst, float(np.max(np.abs(q_ref - sim.joint_positions))))
    wall = time.perf_counter() - wall0
    stats = sim.solver_stats
    if method == "rosenbrock":
        assert stats["jac_evals"] == stats["steps"]
    elif method == "rosenbrock-adaptive":
        assert stats["jac_evals"] < stats["steps"] / 2  # measured 637 of 2,280 (C++ example)
    print(f"Python PD loop at 1 kHz ({method}): 2 s simulated in {wall:.2f} s (real-time factor {2.0 / wall:.2f}), "
          f"largest error from 1.7 s on {1e3 * worst:.3f} mrad")
    assert worst < 5e-3


def test_jacobian_policy_of_the_fixed_step_from_python(root):
    robot = str(root / "config/robots/ur5_drives.yaml")
    for bad in ("sometimes", 0, "2.5"):
        with pytest.raises(jointsim.InputError, match="jacobian_every"):
            jointsim.Simulator.from_robot(robot, method="rosenbrock", step=1e-3, jacobian_every=bad)
    with pytest.raises(TypeError, match="jacobian_every"):
        jointsim.Simulator.from_robot(robot, method="rosenbrock", step=1e-3, jacobian_every=1.5)
    with pytest.raises(jointsim.InputError, match="only with method='rosenbrock'"):
        jointsim.Simulator.from_robot(robot, jacobian_every="adaptive")
    sim = jointsim.Simulator.from_robot(robot, method="rosenbrock", step=1e-3, jacobian_every=np.int64(3))
    sim.advance_to(0.03)
    assert sim.solver_stats["steps"] == 30 and sim.solver_stats["jac_evals"] == 10
    # oscillations="resolve": the oscillatory rows' factorisation beside the plain one.
    sim = jointsim.Simulator.from_robot(robot, method="rosenbrock", step=1e-3, jacobian_every="adaptive",
                                        oscillations="resolve")
    sim.advance_to(0.03)
    stats = sim.solver_stats
    assert stats["steps"] == 30 and 0 < stats["jac_evals"] < 30 and stats["lin_setups"] == 2 * stats["jac_evals"]
    with pytest.raises(jointsim.InputError, match="'damp' or 'resolve'"):
        jointsim.Simulator.from_robot(robot, method="rosenbrock", step=1e-3, oscillations="sometimes")
    with pytest.raises(jointsim.InputError, match="oscillations: only with method='rosenbrock'"):
        jointsim.Simulator.from_robot(robot, oscillations="resolve")
    with pytest.raises(jointsim.InputError, match="jacobian_every 1 or adaptive"):
        jointsim.Simulator.from_robot(robot, method="rosenbrock", step=1e-3, jacobian_every=3, oscillations="resolve")
    with pytest.raises(TypeError, match="oscillations"):
        jointsim.Simulator.from_robot(robot, method="rosenbrock", step=1e-3, oscillations=True)


def _gravity_voltage_gains(root):
    """R / (N k_t) per joint [V/(N*m)], the steady voltage per joint torque, read off the twin itself: at rest
    holding gravity its drives apply voltage = R i and gear torque = N k_t i (no back-EMF)."""
    sim = jointsim.Simulator.from_robot(str(root / "config/robots/ur5_drives.yaml"),
                                        q0=[0.0, -1.2, 1.2, -1.5, -1.5708, 0.0])
    s = sim.signals()
    gains = []
    for j in sim.joint_names:
        gains.append(s[f"voltage_{j}"] / s[f"gear_torque_{j}"] if abs(s[f"gear_torque_{j}"]) > 1e-6 else 0.0)
    return np.array(gains)


def test_port_switch_setpoint_voltage_setpoint_from_python(root):
    q0 = np.array([0.0, -1.2, 1.2, -1.5, -1.5708, 0.0])
    sim = jointsim.Simulator.from_robot(str(root / "config/robots/ur5_drives.yaml"), q0=q0)
    sim.hold_setpoints(q0)
    sim.advance_to(0.1)
    v = sim.signal("voltage_elbow_joint")
    sim.set_port("elbow_joint", "voltage")
    sim.set_command("elbow_joint", v)
    sim.advance_to(0.15)
    assert sim.port(2) == "voltage"
    v_open = sim.signal("voltage_elbow_joint")
    sim.set_port("elbow_joint", "setpoint")
    sim.advance(1e-7)
    assert sim.signal("voltage_elbow_joint") == pytest.approx(v_open, abs=1e-3)  # bumpless
    sim.advance_to(0.6)
    assert abs(sim.joint_positions[2] - q0[2]) < 1e-4


def test_identification_from_python(root):
    # Clamping: the KR300 rig (stiffness 25.7 N*m/rad, backlash 0.0102 rad, friction 1.91 N*m) over 5 half-cycles.
    r = jointsim.run_experiment(str(root / "config/experiments/kr300_joint1_clamping.yaml"), {"duration": 100})
    fit = jointsim.identify_clamping(r["time"], r["motor_angle"], r["motor_torque"])
    assert fit["stiffness"]["value"] == pytest.approx(25.7, rel=0.02)
    assert fit["backlash"]["value"] == pytest.approx(0.0102, rel=0.03)
    assert fit["friction"]["value"] == pytest.approx(1.91, rel=0.02)
    # Friction map: exact points of alpha0 + alpha1 exp(-(v/v_s)^2) + alpha2 v are recovered.
    a0, a1, a2, vs = 7.97, 1.45, 4.93, 0.0363
    v = np.concatenate([np.geomspace(1e-3, 1.0, 30), -np.geomspace(1e-3, 1.0, 30)])
    tau = np.sign(v) * (a0 + a1 * np.exp(-(np.abs(v) / vs) ** 2)) + a2 * v
    f = jointsim.fit_friction_map(v, tau)
    for d in ("positive", "negative"):
        assert f[d]["alpha0"]["value"] == pytest.approx(a0, rel=1e-6)
        assert f[d]["alpha1"]["value"] == pytest.approx(a1, rel=1e-6)
        assert f[d]["v_s"]["value"] == pytest.approx(vs, rel=1e-6)


def test_bad_input_raises_with_a_clear_message_and_writes_nothing(root, planar2, tmp_path):
    cfg = str(root / "config/experiments/ur5_fall.yaml")
    with pytest.raises(ValueError, match="no_such_key"):
        jointsim.load_experiment(cfg, {"no_such_key": 1})
    with pytest.raises(ValueError, match="duration"):
        jointsim.load_experiment(cfg, {"duration": -1})
    with pytest.raises(ValueError, match=r"q: expected an array of shape \(2,\) or \(N, 2\), got shape \(3,\)"):
        jointsim.rnea(planar2, np.zeros(3), np.zeros(2), np.zeros(2))
    with pytest.raises(ValueError, match="shape"):
        jointsim.rnea(planar2, np.zeros((2, 2)), np.zeros(2), np.zeros(2))
    with pytest.raises(TypeError):
        jointsim.rnea(planar2, ["a", "b"], np.zeros(2), np.zeros(2))
    with pytest.raises(ValueError, match="unknown frame"):
        jointsim.frame_placement(planar2, np.zeros(2), "nowhere")
    with pytest.raises(ValueError):
        jointsim.load_robot(str(tmp_path / "missing.urdf"))
    # A run with a bad override writes nothing.
    out = tmp_path / "out"
    with pytest.raises(ValueError, match="log_rate"):
        jointsim.run_experiment_file(cfg, str(out), {"log_rate": 0})
    assert not out.exists() or not any(out.iterdir())
    # Simulator commands.
    sim = jointsim.Simulator.from_robot(str(root / "config/robots/ur5_drives.yaml"))
    with pytest.raises(ValueError, match="setpoint port"):
        sim.set_command(0, 1.0)
    sim.set_port(0, "voltage")
    with pytest.raises(ValueError, match="finite"):
        sim.set_command(0, float("nan"))
    with pytest.raises(ValueError, match="unknown command port"):
        sim.set_port(0, "pwm")
    with pytest.raises(ValueError, match="unknown joint"):
        sim.set_port("no_joint", "voltage")
    with pytest.raises(ValueError, match="shape"):
        sim.set_commands(np.zeros(5))
    with pytest.raises(ValueError):
        sim.advance(-1.0)
    with pytest.raises(ValueError):
        sim.advance(float("nan"))
    # A port that the drive lacks: a torque-controlled drive has no voltage or current port.
    robot = tmp_path / "torque_drives.yaml"
    robot.write_text(
        f"name: pan_elbow\nmultibody: {root / 'tests/data/planar2.urdf'}\ndrives:\n"
        + "".join(f"  - joint: joint{k}\n    motor: {{preset: ur5_joint1}}\n    electrics: false\n"
                  f"    transmission: {{type: rigid, ratio: 10}}\n" for k in (1, 2)))
    tsim = jointsim.Simulator.from_robot(str(robot))
    with pytest.raises(ValueError, match="needs motor electrics"):
        tsim.set_port(0, "voltage")
    with pytest.raises(ValueError, match="current loop"):
        tsim.set_port(1, "current")
    tsim.set_port(1, "motor_torque")
    tsim.set_command(1, 0.5)
    tsim.advance(0.01)
    # The wrong kind of model for per-joint ports.
    rig = jointsim.Simulator.from_experiment(str(root / "config/experiments/kr300_joint1_clamping.yaml"))
    with pytest.raises(ValueError, match="no per-joint command ports"):
        rig.set_port(0, "voltage")


def test_validate_file_and_added_keys(root):
    """validate_file checks without running; '+key=value' adds a key the file lacks (here a solver block)."""
    report = jointsim.validate_file(root / "config" / "sweeps" / "ur5_faults.yaml")
    assert report["kind"] == "sweep" and report["runs"] == 25 and report["type"] == "tracking"
    assert any(f.endswith("ur5_drives_elastic.yaml") for f in report["files"])
    fall = root / "config" / "experiments" / "ur5_fall.yaml"
    with pytest.raises(ValueError, match=r"to add it, override \+solver.max_step=0.002"):
        jointsim.validate_file(fall, ["solver.max_step=0.002"])
    base = jointsim.run_experiment(fall, {"duration": 0.1})
    added = jointsim.run_experiment(fall, ["duration=0.1", "+solver.max_step=0.002"])
    steps = lambda r: r.summary["solver_stats"]["steps"]  # noqa: E731
    assert steps(added) >= 50 > steps(base)
