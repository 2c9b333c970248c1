"""jointsim: high-fidelity robot joint and multibody simulation (C++ core, NumPy in and out).

SI units everywhere: rad, rad/s, m, s, N*m, A, V. Bad input raises ValueError (or TypeError for a value of the wrong
type) with the library's one-line message naming the file, line and key; a failed integration raises
jointsim.SolverError (a RuntimeError) naming the simulated time and the component.

Rigid-body algorithms (a Model carries its own workspace)::

    model = jointsim.load_robot("config/robots/ur5.urdf")
    tau = jointsim.rnea(model, q, qd, qdd)          # N*m
    qdd = jointsim.aba(model, q, qd, tau)           # rad/s^2

Experiment files, as `jointsim run` does, in memory::

    r = jointsim.run_experiment("config/experiments/ur5_fall.yaml", {"duration": 0.5})
    r["q_shoulder_pan_joint"], r["summary"]["solver"]

A user's controller around the UR5 twin (command ports: setpoint, motor_velocity, current, voltage, motor_torque)::

    sim = jointsim.Simulator.from_robot("config/robots/ur5_drives.yaml", q0=q0)
    for k in range(6): sim.set_port(k, "voltage")
    while sim.time < 1.0:
        sim.set_commands(kp * (q_ref - sim.joint_positions))
        sim.advance(1e-3)
"""
from __future__ import annotations

import json
import math
from typing import Any, Dict, Iterable, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from ._core import (
    Model,
    SolverError,
    UnidentifiableError,
    aba,
    aba_derivatives,
    crba,
    fit_friction_map,
    frame_jacobian,
    frame_placement,
    gravity_torques,
    identify_clamping,
    load_robot,
    rnea,
    rnea_derivatives,
)

__version__ = _core.__version__

__all__ = [
    "Model", "SolverError", "UnidentifiableError", "Experiment", "Simulator", "aba", "aba_derivatives", "crba",
    "fit_friction_map",
    "frame_jacobian", "frame_placement", "gravity_torques", "identify_clamping", "load_experiment", "load_robot",
    "rnea", "rnea_derivatives", "run_experiment", "run_experiment_file", "PORTS", "export_fmu", "validate_file", "run_batch", "write_dataset",
]

#: The command ports of a drive (Simulator.set_port).
PORTS = ("setpoint", "motor_velocity", "current", "voltage", "motor_torque")

Overrides = Union[None, Mapping[str, Any], Sequence[str]]


def _format_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"override value {v!r}: expected a finite number")
        return repr(v)
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_format_value(x) for x in v) + "]"
    return str(v)


def _overrides(overrides: Overrides) -> list:
    """{'key.path': value} or ['key.path=value'] -> the C++ list of 'key.path=value'."""
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        return [f"{k}={_format_value(v)}" for k, v in overrides.items()]
    if isinstance(overrides, str):
        raise TypeError("overrides: expected a dict {key.path: value} or a list of 'key.path=value', got a str")
    return [str(o) for o in overrides]


def _split(column: str):
    if column.endswith("]") and "[" in column:
        i = column.index("[")
        return column[:i], column[i + 1 : -1]
    return column, ""


class Experiment:
    """An experiment file loaded (and its overrides applied): the model and its run settings.

    Attributes: name, type (the registry's experiment type), file, columns (the log's column names with units).
    """

    def __init__(self, core: "_core.Experiment"):
        self._core = core

    name = property(lambda self: self._core.name)
    type = property(lambda self: self._core.type)
    file = property(lambda self: self._core.file)
    columns = property(lambda self: list(self._core.columns))

    def run(self) -> Dict[str, Any]:
        """Runs the experiment in memory (nothing written); see run_experiment for the result."""
        return _result(_core.run_in_memory(self._core))

    def simulator(self) -> "Simulator":
        """A stepping Simulator over this experiment's model, with its solver settings."""
        return Simulator(_core.Simulator.from_experiment(self._core))

    def __repr__(self) -> str:
        return f"<jointsim.Experiment '{self.name}' of type {self.type}>"


def load_experiment(path: str, overrides: Overrides = None) -> Experiment:
    """Loads an experiment file (YAML) and applies overrides ({'key.path': value} or ['key.path=value']).

    Raises ValueError naming the file, line and key for bad input (an unknown key among them).
    """
    return Experiment(_core.load_experiment(str(path), _overrides(overrides)))


def _result(raw: dict) -> Dict[str, Any]:
    values = raw["values"]
    out: Dict[str, Any] = {}
    units: Dict[str, str] = {}
    for j, column in enumerate(raw["columns"]):
        name, unit = _split(column)
        out[name] = values[:, j].copy()
        units[name] = unit
    out["units"] = units
    out["columns"] = list(raw["columns"])
    out["summary"] = json.loads(raw["summary_json"])
    out["extras"] = {
        suffix: {_split(c)[0]: table[:, j].copy() for j, c in enumerate(cols)} for suffix, (cols, table) in raw["extras"].items()
    }
    return out


def run_experiment(experiment: Union[str, Experiment], overrides: Overrides = None) -> Dict[str, Any]:
    """Runs an experiment (a file path or a loaded Experiment) in memory: what `jointsim run` writes, as NumPy.

    Returns a dict: one float64 array per log column by its name without unit ("time", "q_elbow_joint", ...), the
    same numbers as the CLI's CSV to the last bit; "units" (name -> unit), "columns" (the CSV header), "summary"
    (summary.json as a dict) and "extras" (extra tables such as clamping curves, by suffix).
    """
    if not isinstance(experiment, Experiment):
        experiment = load_experiment(experiment, overrides)
    elif overrides:
        raise ValueError("overrides apply when loading: pass them to load_experiment")
    return experiment.run()


def run_experiment_file(path: str, output_dir: Optional[str] = None, overrides: Overrides = None) -> Dict[str, Any]:
    """As `jointsim run`: writes DIR/<name>.csv and DIR/summary.json (each renamed into place when complete; bad
    input writes nothing). Returns status, csv_path, summary_path, sim_time_s, wall_time_s, real_time_factor."""
    return dict(_core.run_experiment_file(str(path), "" if output_dir is None else str(output_dir), _overrides(overrides)))


def validate_file(path: str, overrides: Overrides = None) -> Dict[str, Any]:
    """As `jointsim validate`: checks an experiment or sweep file completely (every key, every referenced file,
    every run of a sweep with its settings) without running it; raises ValueError (the C++ InputError: file, line,
    key path) for the first problem. Returns kind ("experiment"/"sweep"), name, type, runs, states, signals,
    duration [s] and files (every file read)."""
    return dict(_core.validate_file(str(path), _overrides(overrides)))


def run_batch(sweep: str, output_dir: Optional[str] = None, jobs: int = 1, shard: Tuple[int, int] = (0, 1),
              collect: bool = False) -> Dict[str, Any]:
    """As `jointsim batch SWEEP [-j JOBS] [--shard I/N] [-o DIR] [--collect]`: runs a sweep, each run in its own child
    process, into DIR/<run>/ with DIR/manifest.csv (docs/batch.md); finished runs are skipped (resume). Returns
    manifest_path, ok, failed, skipped, wall_time_s [s] and records (one dict per run: run, status, labels, ...).
    Bad sweep input raises ValueError; failed runs are reported in the records, not raised. While it runs, Ctrl-C
    reaches Python only when it returns."""
    index, count = shard
    return dict(_core.run_batch(str(sweep), "" if output_dir is None else str(output_dir), int(jobs), int(index),
                                int(count), bool(collect)))


def write_dataset(sweep: str, path: str, output_dir: Optional[str] = None) -> Dict[str, Any]:
    """As `jointsim batch SWEEP --collect -o DIR --dataset PATH` without rewriting the manifest: every run's log and
    the labels of the sweep's results in DIR as one HDF5 file (layout in docs/batch.md; read it with h5py). Written
    under a temporary name and renamed into place. Returns path, runs, runs_with_data, samples."""
    return dict(_core.write_dataset(str(sweep), str(path), "" if output_dir is None else str(output_dir)))


def export_fmu(config: str, fmu_path: str, inputs: Sequence[str] = (), outputs: Sequence[str] = (),
               overrides: Overrides = None, binary_dir: Optional[str] = None, step_size: float = 1e-3) -> Dict[str, Any]:
    """As `jointsim fmu`: writes an FMI 2.0 Co-Simulation FMU of an experiment file (types tracking, joint_rig).

    inputs: command ports, "PORT" (every joint) or "JOINT:PORT" (voltage, current, motor_torque, motor_velocity,
    setpoint) for a robot, "command" for a joint rig; outputs: signal names (default all); overrides: as --set.
    binary_dir: the FMU binary's folder (default: the one shipped in this package). Returns the FMU's description
    (model identifier, GUID, variables with their value references = their indices).
    """
    import os
    if binary_dir is None:
        here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fmu", "linux64")
        binary_dir = here if os.path.isfile(os.path.join(here, "jointsim_fmu.so")) else ""
    raw = _core.export_fmu(str(config), str(fmu_path), list(inputs), list(outputs), _overrides(overrides),
                           str(binary_dir), float(step_size))
    return json.loads(raw)


class Simulator:
    """Steps a simulated model: advance(dt) / advance_to(t) with events and samples handled inside; inputs
    (command ports) may change between steps, and the integrator restarts only where an input actually jumps.

    Make one with Simulator.from_experiment(path_or_experiment, overrides) or Simulator.from_robot(file, q0).
    Signals are named as the CSV columns (signal("q_elbow_joint") [rad]).

    Command ports of a robot with drives (per joint, by index or name, changeable between steps):
      "setpoint"       joint reference through the drive's cascade (set_setpoint / hold_setpoints)
      "motor_velocity" motor speed reference [rad/s]
      "current"        current reference [A] (drives with electrics and a current loop)
      "voltage"        motor voltage [V] (the PWM saturation at +-V_supply applies)
      "motor_torque"   electromagnetic torque [N*m] (electrics bypassed)
    Switching back to a controller port is bumpless (its integrators continue from the applied output).
    """

    def __init__(self, core: "_core.Simulator"):
        self._s = core

    @staticmethod
    def from_experiment(experiment: Union[str, Experiment], overrides: Overrides = None) -> "Simulator":
        """A simulator over an experiment's model (a file path or a loaded Experiment) with its solver settings."""
        if not isinstance(experiment, Experiment):
            experiment = load_experiment(experiment, overrides)
        return experiment.simulator()

    @staticmethod
    def from_robot(path: str, q0: Optional[Sequence[float]] = None, rtol: float = 1e-6, atol: float = 1e-9,
                   max_order: int = 2, max_step: float = 0.0, max_gamma_change: float = 0.3) -> "Simulator":
        """A simulator over a robot-with-drives file (e.g. config/robots/ur5_drives.yaml) starting at rest at q0
        [rad] (default zeros) with the drives holding it; BDF of order <= max_order with rtol, atol [state units],
        steps of at most max_step [s] (0: unlimited), a new Newton matrix when h*beta0 changes by more than
        max_gamma_change (relative; 0.5 suits sampled control, see docs/design.md)."""
        q = None if q0 is None else np.asarray(q0, dtype=np.float64)
        return Simulator(_core.Simulator.from_robot(str(path), q, rtol, atol, max_order, max_step, max_gamma_change))

    # --- time and state
    name = property(lambda self: self._s.name, doc="Name of the simulated model.")
    time = property(lambda self: self._s.time, doc="Simulated time [s].")
    state = property(lambda self: self._s.state, doc="Continuous state vector (copy).")
    restarts = property(lambda self: self._s.restarts, doc="Integrator restarts so far.")
    steps = property(lambda self: self._s.steps, doc="Internal solver steps so far.")

    def advance(self, dt: float) -> float:
        """Integrates over dt [s] > 0; returns the time reached [s]."""
        return self._s.advance(dt)

    def advance_to(self, t: float) -> float:
        """Integrates to time t [s] >= time; returns the time reached [s]."""
        return self._s.advance_to(t)

    def reset(self) -> None:
        """Back to the initial state at t = 0."""
        self._s.reset()

    def set_state(self, y: Sequence[float]) -> None:
        """Replaces the continuous state (shape like state); the integrator restarts."""
        self._s.set_state(np.asarray(y, dtype=np.float64))

    # --- signals
    @property
    def signal_names(self) -> list:
        """Signal names with units, as the CSV columns after time[s]."""
        return list(self._s.signal_names)

    def signal(self, name: str) -> float:
        """One signal at the current time, by name with or without its unit."""
        return self._s.signal(name)

    def signals(self) -> Dict[str, float]:
        """All signals at the current time, by name without unit."""
        v = self._s.signal_values()
        return {_split(n)[0]: float(x) for n, x in zip(self._s.signal_names, v)}

    def signal_values(self) -> np.ndarray:
        """All signals at the current time in signal_names order (float64 array)."""
        return self._s.signal_values()

    def signal_index(self, name: str) -> int:
        return self._s.signal_index(name)

    # --- robot with drives
    dof = property(lambda self: self._s.dof, doc="Number of joints (robot with drives).")
    joint_names = property(lambda self: list(self._s.joint_names))
    joint_positions = property(lambda self: self._s.joint_positions, doc="Joint angles q [rad] (copy).")
    joint_velocities = property(lambda self: self._s.joint_velocities, doc="Joint rates qd [rad/s] (copy).")
    gear_ratios = property(lambda self: self._s.gear_ratios,
                           doc="Gear ratio N per joint [-] (motor angle = N * joint angle for a rigid gear).")
    motor_velocities = property(lambda self: self._s.motor_velocities,
                                doc="Motor shaft speeds [rad/s] (copy): what the motor encoders measure.")

    def model(self) -> Model:
        """The robot's rigid-body model (with the reflected rotor inertias), for rnea/aba/... in a controller."""
        return self._s.model()

    def set_port(self, joint: Union[int, str], port: str) -> None:
        """Chooses the command port of a joint (one of PORTS); ValueError if the drive lacks it."""
        self._s.set_port(joint, port)

    def port(self, joint: Union[int, str]) -> str:
        return self._s.port(joint)

    def set_command(self, joint: Union[int, str], value: float) -> None:
        """The command of a joint's port: rad/s, A, V or N*m (ValueError for NaN or under the setpoint port)."""
        self._s.set_command(joint, float(value))

    def set_commands(self, values: Sequence[float]) -> None:
        """Commands of every joint (shape (dof,)); entries of joints under the setpoint port are ignored."""
        self._s.set_commands(np.asarray(values, dtype=np.float64))

    def set_setpoint(self, joint: Union[int, str], q: float, qd: float = 0.0, qdd: float = 0.0) -> None:
        """Holds a joint's reference at q [rad], qd [rad/s], qdd [rad/s^2] in place of the trajectory."""
        self._s.set_setpoint(joint, float(q), float(qd), float(qdd))

    def hold_setpoints(self, q: Sequence[float], qd: Optional[Sequence[float]] = None,
                       qdd: Optional[Sequence[float]] = None) -> None:
        """Holds the references of every joint (shapes (dof,))."""
        conv = lambda a: None if a is None else np.asarray(a, dtype=np.float64)
        self._s.hold_setpoints(conv(q), conv(qd), conv(qdd))

    def release_setpoints(self) -> None:
        """Back to the experiment's trajectory for every joint."""
        self._s.release_setpoints()

    def set_external_wrench(self, frame: str, wrench: Sequence[float]) -> None:
        """Holds a wrench [fx, fy, fz (N), nx, ny, nz (N*m)] in world axes at a frame's origin (zeros remove it)."""
        self._s.set_external_wrench(frame, np.asarray(wrench, dtype=np.float64))

    def __repr__(self) -> str:
        return f"<jointsim.Simulator of {self.name} at t = {self.time} s>"
