"""jointsim: high-fidelity robot joint and multibody simulation (C++ core, NumPy in and out).

SI units everywhere: rad, rad/s, m, s, N*m, A, V. Every path argument takes a str or an os.PathLike. Bad input
raises jointsim.InputError (a ValueError; a missing file also a FileNotFoundError, a wrong type a TypeError) with
the file, line and key path as fields; a failed integration raises jointsim.SolverError (a RuntimeError) with the
simulated time, the solver flag and the component. Ctrl-C interrupts any long call with KeyboardInterrupt.

The robot, experiment and sweep files shipped with the package are under data_path()::

    model = jointsim.load_robot(jointsim.data_path("robots/ur5.urdf"))
    tau = jointsim.rnea(model, q, qd, qdd)          # N*m; q of shape (6,) or a batch of shape (N, 6)

Experiment files, as `jointsim run` does, in memory::

    r = jointsim.run_experiment(jointsim.data_path("experiments/ur5_fall.yaml"), {"duration": 0.5})
    r["q_shoulder_pan_joint"], r.units["q_shoulder_pan_joint"], r.summary["solver_stats"], r.to_dataframe()

A user's controller around the UR5 twin (command ports: setpoint, motor_velocity, current, voltage, motor_torque)::

    sim = jointsim.Simulator.from_robot(jointsim.data_path("robots/ur5_drives.yaml"), rtol=1e-4, max_gamma_change=0.5)
    for k in range(sim.dof): sim.set_port(k, "voltage")
    while sim.time < 1.0:
        sim.set_commands(kp * (q_ref - sim.joint_positions) - kd * sim.motor_velocities)
        sim.advance(1e-3)
"""
from __future__ import annotations

import json
import math
import numbers
import os
import pathlib
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from .errors import (ConcurrentUseError, InputError, InputFileNotFoundError, InputTypeError, SolverError,
                     UnidentifiableError)

__version__ = _core.__version__

__all__ = [
    "PORTS", "Model", "Experiment", "RunResult", "Simulator", "Snapshot", "Dataset",
    "InputError", "InputFileNotFoundError", "InputTypeError", "SolverError", "UnidentifiableError",
    "ConcurrentUseError",
    "data_path", "load_robot", "rnea", "aba", "crba", "gravity_torques", "rnea_derivatives", "aba_derivatives",
    "frame_placement", "frame_jacobian", "load_experiment", "run_experiment", "run_experiment_file", "validate_file",
    "run_batch", "write_dataset", "read_dataset", "export_fmu", "identify_clamping", "fit_friction_map", "agreement",
    "identify_currents", "view", "ViewPage",
]

#: The command ports of a drive (Simulator.set_port).
PORTS = ("setpoint", "motor_velocity", "current", "voltage", "motor_torque")

PathLike = Union[str, "os.PathLike[str]"]
Overrides = Union[None, Mapping[str, Any], Sequence[str]]
Model = _core.Model

_DATA = pathlib.Path(__file__).resolve().parent / "data"


# ------------------------------------------------------------------------------------------------ arguments
def _path(value: Any, what: str) -> str:
    """A path argument as str (str or os.PathLike; TypeError otherwise)."""
    if isinstance(value, (bytes, bytearray)):
        value = os.fsdecode(bytes(value))
    try:
        path = os.fspath(value)
    except TypeError:
        raise InputTypeError(f"{what}: expected a path (str or os.PathLike), got {type(value).__name__}") from None
    if not isinstance(path, str):
        path = os.fsdecode(path)
    if "\0" in path:
        raise InputError(f"{what}: a path cannot contain a NUL character, got {path!r}", reason="NUL in a path")
    return path


def _input_file(value: Any, what: str) -> str:
    """A path argument that must name an existing file (InputFileNotFoundError otherwise)."""
    path = _path(value, what)
    if not os.path.exists(path):
        raise InputFileNotFoundError(f"{path}: cannot open {what} for reading: no such file", file=path,
                                     reason="no such file")
    return path


def _optional_path(value: Any, what: str) -> str:
    return "" if value is None else _path(value, what)


def _names(value: Any, what: str) -> List[str]:
    """A str or a sequence of str as a list (a single str is one name, not its characters)."""
    if value is None:
        return []
    if isinstance(value, str):
        return [value] if value else []
    if isinstance(value, Mapping) or not isinstance(value, Iterable):
        raise InputTypeError(f"{what}: expected a str or a list of str, got {type(value).__name__}")
    out = list(value)
    for v in out:
        if not isinstance(v, str):
            raise InputTypeError(f"{what}: expected a str or a list of str, got an entry of type {type(v).__name__}")
    return out


def _int(value: Any, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InputTypeError(f"{what}: expected an int, got {type(value).__name__}")
    return int(value)


def _joint(value: Any) -> Union[int, str]:
    """A joint given by index (int) or name (str)."""
    if isinstance(value, str) or (isinstance(value, numbers.Integral) and not isinstance(value, bool)):
        return value if isinstance(value, str) else int(value)
    raise InputTypeError(f"joint: expected an index (int) or a joint name (str), got {type(value).__name__}")


def _float(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputTypeError(f"{what}: expected a number, got {type(value).__name__}")
    return float(value)


def _array(value: Any, what: str) -> np.ndarray:
    """A float64 array of any shape (TypeError for what NumPy cannot read as numbers)."""
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputTypeError(f"{what}: expected an array of numbers, got {type(value).__name__}") from None


def _format_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        if not math.isfinite(v):
            raise InputError(f"override value {v!r}: expected a finite number")
        return repr(v)
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_format_value(x) for x in v) + "]"
    if isinstance(v, os.PathLike):
        return os.fspath(v)
    return str(v)


def _overrides(overrides: Overrides) -> list:
    """{'key.path': value} or ['key.path=value'] -> the C++ list of 'key.path=value'."""
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        return [f"{k}={_format_value(v)}" for k, v in overrides.items()]
    if isinstance(overrides, str):
        raise InputTypeError("overrides: expected a dict {key.path: value} or a list of 'key.path=value', got a str")
    return [str(o) for o in overrides]


def _split(column: str) -> Tuple[str, str]:
    if column.endswith("]") and "[" in column:
        i = column.rindex("[")
        return column[:i], column[i + 1: -1]
    return column, ""


def _sweep(sweep: Any, base_dir: Optional[PathLike]) -> Tuple[str, str]:
    """A sweep file, or a sweep given as a dict: (source, text) for the core (text empty for a file)."""
    if isinstance(sweep, Mapping):
        base = os.path.abspath(_path(base_dir, "base_dir") if base_dir is not None else os.getcwd())
        name = str(sweep.get("sweep", {}).get("name", "sweep")) if isinstance(sweep.get("sweep"), Mapping) else "sweep"
        try:
            text = json.dumps(sweep, indent=1, default=_json_default, allow_nan=False)
        except ValueError as e:
            raise InputError(f"sweep (dict): {e}") from None
        return os.path.join(base, f"{name} (dict)"), text
    if base_dir is not None:
        raise InputError("base_dir: applies to a sweep given as a dict; a sweep file's paths are relative to the file")
    return _input_file(sweep, "sweep file"), ""


def _json_default(v: Any) -> Any:
    if isinstance(v, os.PathLike):
        return os.fspath(v)
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    raise InputTypeError(f"sweep (dict): a value of type {type(v).__name__} cannot be written as YAML")


# ------------------------------------------------------------------------------------------------ shipped files
def data_path(*parts: PathLike) -> pathlib.Path:
    """The robot, experiment and sweep files shipped with the package: ``data_path()`` is the folder (with
    ``robots/``, ``experiments/``, ``sweeps/``), ``data_path("robots/ur5_drives.yaml")`` or
    ``data_path("robots", "ur5_drives.yaml")`` a file in it. Raises InputFileNotFoundError (a FileNotFoundError)
    when it does not exist. The experiment files refer to the robot files by relative paths, so they work from
    any working directory."""
    p = _DATA.joinpath(*[_path(x, "data_path") for x in parts])
    if not p.exists():
        raise InputFileNotFoundError(f"{p}: no such file among jointsim's shipped files (see data_path())",
                                     file=str(p), reason="no such file")
    return p


# ------------------------------------------------------------------------------------------------ multibody
def load_robot(path: PathLike) -> Model:
    """Loads a robot model: a URDF (.urdf) or a jointsim robot YAML (Hayati DH or tree; docs/robot_format.md).

    Returns a Model with its own workspace: name, nq (number of joints), joint_names, frame_names, tip_frame and
    gravity [m/s^2], shape (3,). Joint order is the order of the movable joints from base to tip.
    """
    return _core.load_robot(_input_file(path, "robot file"))


def rnea(model: Model, q: Any, qd: Any, qdd: Any) -> np.ndarray:
    """Inverse dynamics (recursive Newton-Euler): tau = M(q) qdd + C(q, qd) qd + g(q) [N*m].

    q [rad], qd [rad/s], qdd [rad/s^2]: each of shape (nq,) for one state, or (N, nq) for N states in one call
    (returns (N, nq)). Rotor inertias of the model (armature) are included.
    """
    return _core.rnea(model, _array(q, "q"), _array(qd, "qd"), _array(qdd, "qdd"))


def aba(model: Model, q: Any, qd: Any, tau: Any) -> np.ndarray:
    """Forward dynamics (articulated-body algorithm): qdd [rad/s^2] for q [rad], qd [rad/s], tau [N*m].

    Each argument of shape (nq,), or (N, nq) for N states (returns (N, nq)).
    """
    return _core.aba(model, _array(q, "q"), _array(qd, "qd"), _array(tau, "tau"))


def crba(model: Model, q: Any) -> np.ndarray:
    """Joint-space mass matrix M(q) [kg*m^2 for revolute joints]: shape (nq, nq) for q of shape (nq,) [rad], or
    (N, nq, nq) for q of shape (N, nq)."""
    return _core.crba(model, _array(q, "q"))


def gravity_torques(model: Model, q: Any) -> np.ndarray:
    """Gravity torques g(q) [N*m] for q [rad]: shape (nq,), or (N, nq) for q of shape (N, nq)."""
    return _core.gravity_torques(model, _array(q, "q"))


def rnea_derivatives(model: Model, q: Any, qd: Any, qdd: Any) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Analytic derivatives of inverse dynamics at (q [rad], qd [rad/s], qdd [rad/s^2]), each of shape (nq,):
    (dtau/dq [N*m/rad], dtau/dqd [N*m*s/rad], M = dtau/dqdd [kg*m^2]), each of shape (nq, nq)."""
    return _core.rnea_derivatives(model, _array(q, "q"), _array(qd, "qd"), _array(qdd, "qdd"))


def aba_derivatives(model: Model, q: Any, qd: Any, tau: Any) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Analytic derivatives of forward dynamics at (q [rad], qd [rad/s], tau [N*m]), each of shape (nq,):
    (dqdd/dq [1/s^2], dqdd/dqd [1/s], dqdd/dtau = M^-1 [1/(kg*m^2)]), each of shape (nq, nq)."""
    return _core.aba_derivatives(model, _array(q, "q"), _array(qd, "qd"), _array(tau, "tau"))


def _frame(frame: Any) -> Optional[str]:
    if frame is None or isinstance(frame, str):
        return frame
    raise InputTypeError(f"frame: expected a frame name (str; see Model.frame_names) or None, got {type(frame).__name__}")


def frame_placement(model: Model, q: Any, frame: Optional[str] = None) -> np.ndarray:
    """4x4 homogeneous pose of a frame (default: the model's tip_frame) in the base frame at q [rad], shape (nq,):
    rotation and position [m]."""
    return _core.frame_placement(model, _array(q, "q"), _frame(frame))


def frame_jacobian(model: Model, q: Any, frame: Optional[str] = None) -> np.ndarray:
    """Frame Jacobian at q [rad] (shape (nq,)), shape (6, nq): rows [v; w] in world axes at the frame's origin,
    [m/s per rad/s] and [rad/s per rad/s]."""
    return _core.frame_jacobian(model, _array(q, "q"), _frame(frame))


# ------------------------------------------------------------------------------------------------ experiments
class RunResult(dict):
    """The log of a run: a dict of the logged signals by name without unit ("time", "q_elbow_joint", ...), each a
    float64 array of shape (rows,), so ``pandas.DataFrame(result)`` works; the rest is in attributes.

    Attributes:
        units (dict): signal name -> unit ("rad", "N*m", ...).
        columns (list): the CSV header, names with units ("q_elbow_joint[rad]").
        summary (dict): summary.json of the run (status, solver statistics, parameters, input hashes, ...).
        extras (dict): extra tables of the experiment type by suffix (e.g. clamping curves), each a dict of arrays.
    """

    def __init__(self, columns: Dict[str, np.ndarray], units: Dict[str, str], header: List[str],
                 summary: Dict[str, Any], extras: Dict[str, Dict[str, np.ndarray]]):
        super().__init__(columns)
        self.units = units
        self.columns = header
        self.summary = summary
        self.extras = extras

    def to_dataframe(self):
        """The log as a pandas DataFrame: one column per signal (names without unit), the units in
        ``df.attrs["units"]``; the summary stays on the result. Needs pandas."""
        import pandas as pd
        df = pd.DataFrame({name: values for name, values in self.items()})
        df.attrs["units"] = dict(self.units)
        return df

    def __repr__(self) -> str:
        rows = len(next(iter(self.values()))) if self else 0
        return f"<jointsim.RunResult: {len(self)} signals x {rows} rows, status {self.summary.get('status')!r}>"


def _result(raw: dict) -> RunResult:
    values = raw["values"]
    columns: Dict[str, np.ndarray] = {}
    units: Dict[str, str] = {}
    for j, column in enumerate(raw["columns"]):
        name, unit = _split(column)
        columns[name] = values[:, j].copy()
        units[name] = unit
    extras = {suffix: {_split(c)[0]: table[:, j].copy() for j, c in enumerate(cols)}
              for suffix, (cols, table) in raw["extras"].items()}
    return RunResult(columns, units, list(raw["columns"]), json.loads(raw["summary_json"]), extras)


class Experiment:
    """An experiment file loaded (and its overrides applied): the model and its run settings.

    Attributes: name, type (the registry's experiment type), file (the file it was read from), columns (the
    log's column names with units, time first).
    """

    def __init__(self, core: "_core.Experiment"):
        self._core = core

    name = property(lambda self: self._core.name, doc="Name of the experiment (the log's file stem).")
    type = property(lambda self: self._core.type, doc="Experiment type (tracking, joint_rig, clamping, ...).")
    file = property(lambda self: self._core.file, doc="The experiment file it was read from.")
    columns = property(lambda self: list(self._core.columns), doc="Log column names with units, time[s] first.")

    def run(self) -> RunResult:
        """Runs the experiment in memory (nothing written); see run_experiment for the result."""
        return _result(_core.run_in_memory(self._core))

    def simulator(self) -> "Simulator":
        """A stepping Simulator over this experiment's model, with its solver settings (and the limit max_state =
        Simulator.DEFAULT_MAX_STATE, see Simulator.set_limits)."""
        sim = Simulator(_core.Simulator.from_experiment(self._core))
        sim.set_limits(max_state=Simulator.DEFAULT_MAX_STATE)
        return sim

    def __repr__(self) -> str:
        return f"<jointsim.Experiment '{self.name}' of type {self.type}>"


def load_experiment(path: PathLike, overrides: Overrides = None) -> Experiment:
    """Loads an experiment file (YAML) and applies overrides: a dict {"key.path": value} or a list of
    "key.path=value" ("+key.path=value" adds a key the file lacks). Raises InputError naming the file, line and key
    for bad input (an unknown key among them), InputFileNotFoundError for a missing file."""
    return Experiment(_core.load_experiment(_input_file(path, "experiment file"), _overrides(overrides)))


def run_experiment(experiment: Union[PathLike, Experiment], overrides: Overrides = None) -> RunResult:
    """Runs an experiment (a file path or a loaded Experiment) in memory: what `jointsim run` writes, as NumPy.

    Returns a RunResult: a dict of float64 arrays by signal name without unit ("time", "q_elbow_joint", ...), the
    same numbers as the CLI's CSV to the last bit, with .units, .columns (the CSV header), .summary (summary.json as
    a dict), .extras (extra tables such as clamping curves) and .to_dataframe().
    """
    if not isinstance(experiment, Experiment):
        experiment = load_experiment(experiment, overrides)
    elif overrides:
        raise InputError("overrides apply when loading: pass them to load_experiment")
    return experiment.run()


def run_experiment_file(path: PathLike, output_dir: Optional[PathLike] = None,
                        overrides: Overrides = None) -> Dict[str, Any]:
    """As `jointsim run`: writes DIR/<name>.csv and DIR/summary.json (default DIR: out/<name>/; each renamed into
    place when complete; bad input writes nothing). Returns status, csv_path, summary_path, sim_time_s [s],
    wall_time_s [s], real_time_factor and warnings."""
    return dict(_core.run_experiment_file(_input_file(path, "experiment file"),
                                          _optional_path(output_dir, "output_dir"), _overrides(overrides)))


def validate_file(path: PathLike, overrides: Overrides = None) -> Dict[str, Any]:
    """As `jointsim validate`: checks an experiment or sweep file completely (every key, every referenced file,
    every run of a sweep with its settings) without running it; raises InputError (file, line, key path) for the
    first problem. Returns kind ("experiment"/"sweep"), name, type, runs, states, signals, duration [s] and files
    (every file read)."""
    return dict(_core.validate_file(_input_file(path, "experiment or sweep file"), _overrides(overrides)))


# ------------------------------------------------------------------------------------------------ sweeps
def run_batch(sweep: Union[PathLike, Mapping[str, Any]], output_dir: Optional[PathLike] = None, jobs: int = 1,
              shard: Tuple[int, int] = (0, 1), collect: bool = False,
              base_dir: Optional[PathLike] = None) -> Dict[str, Any]:
    """As `jointsim batch SWEEP [-j JOBS] [--shard I/N] [-o DIR] [--collect]`: runs a sweep, each run in its own child
    process, into DIR/<run>/ with DIR/manifest.csv (default DIR: out/<sweep name>/; docs/batch.md); finished runs
    are skipped (resume).

    sweep: a sweep file, or the same content as a dict ({"sweep": {"name", "experiment", "set"}, "runs": [...],
    "grid": ..., "faults": ..., "sample": ...}) whose relative paths are relative to base_dir (default: the working
    directory). Returns manifest_path, ok, failed, skipped, wall_time_s [s] and records (one dict per run: run,
    status, labels, ...). Bad sweep input raises InputError; failed runs are reported in the records, not raised.
    Ctrl-C stops the runs (they end "interrupted", resumable) and raises KeyboardInterrupt.
    """
    source, text = _sweep(sweep, base_dir)
    index, count = shard
    jobs, index, count = _int(jobs, "jobs"), _int(index, "shard index"), _int(count, "shard count")
    if jobs < 1:
        raise InputError(f"jobs: expected at least 1 run at a time, got {jobs}")
    return dict(_core.run_batch(source, text, _optional_path(output_dir, "output_dir"), jobs, index, count,
                                bool(collect)))


def write_dataset(sweep: Union[PathLike, Mapping[str, Any]], path: PathLike, output_dir: Optional[PathLike] = None,
                  base_dir: Optional[PathLike] = None) -> Dict[str, Any]:
    """As `jointsim batch SWEEP --collect -o DIR --dataset PATH` without rewriting the manifest: every run's log and
    the labels of the sweep's results in DIR as one HDF5 file (layout in docs/batch.md; read it with read_dataset).
    sweep: a file or a dict (see run_batch). Written under a temporary name and renamed into place. Returns path,
    runs, runs_with_data, samples."""
    source, text = _sweep(sweep, base_dir)
    return dict(_core.write_dataset(source, text, _path(path, "path"), _optional_path(output_dir, "output_dir")))


class Dataset:
    """A sweep's HDF5 data set read into pandas (read_dataset).

    Attributes:
        labels (pandas.DataFrame): one row per run (run, status, fault_type, fault_joint, fault_severity,
            fault_onset_s, fault_count, design, seed), strings decoded.
        runs (list of str): the runs with logged data.
        attributes (dict): run -> its attributes (settings, overrides, faults, input hashes, summary, ...).
        path (str): the file.
    """

    def __init__(self, path: str, labels, runs: List[str], attributes: Dict[str, Dict[str, Any]]):
        self.path = path
        self.labels = labels
        self.runs = runs
        self.attributes = attributes

    def run(self, name: str):
        """One run's log as a pandas DataFrame (one float64 column per signal, names without unit; the units in
        ``df.attrs["units"]``, the run's attributes in ``df.attrs["attributes"]``)."""
        import h5py
        import pandas as pd
        if name not in self.runs:
            raise InputError(f"{self.path}: no run {name!r} with data (runs: {', '.join(self.runs) or 'none'})",
                             file=self.path, key_path=f"runs/{name}")
        with h5py.File(self.path, "r") as f:
            g = f["runs"][name]
            columns = {k: np.asarray(g[k][...], dtype=np.float64) for k in g.keys()}
            units = {k: _text(g[k].attrs.get("unit", "")) for k in g.keys()}
        order = ["time"] + sorted(k for k in columns if k != "time") if "time" in columns else sorted(columns)
        df = pd.DataFrame({k: columns[k] for k in order})
        df.attrs["units"] = {k: units[k] for k in order}
        df.attrs["attributes"] = self.attributes.get(name, {})
        return df

    def __iter__(self):
        """(name, DataFrame) of every run with data, in file order."""
        for name in self.runs:
            yield name, self.run(name)

    def __repr__(self) -> str:
        return f"<jointsim.Dataset {self.path!r}: {len(self.labels)} runs, {len(self.runs)} with data>"


def _text(v: Any) -> Any:
    if isinstance(v, bytes):
        return v.decode("utf-8")
    if isinstance(v, np.ndarray) and v.dtype.kind in "SO":
        return [_text(x) for x in v.tolist()]
    if isinstance(v, np.generic):
        return v.item()
    return v


def read_dataset(path: PathLike) -> Dataset:
    """Reads a sweep's HDF5 data set (written by `jointsim batch --dataset` or write_dataset) into pandas: the
    labels table with its strings decoded, the list of runs with data and each run's attributes; Dataset.run(name)
    reads one run's log. Needs h5py and pandas (pip install h5py pandas)."""
    import h5py
    import pandas as pd
    p = _input_file(path, "data set")
    try:
        f = h5py.File(p, "r")
    except OSError as e:
        raise InputError(f"{p}: not an HDF5 data set of jointsim ({e})", file=p, reason="not an HDF5 file") from None
    with f:
        if "labels" not in f:
            raise InputError(f"{p}: no /labels table: not a data set of jointsim", file=p, key_path="labels")
        table = f["labels"][...]
        labels = pd.DataFrame({name: [_text(x) for x in table[name]] for name in table.dtype.names})
        runs = list(f["runs"].keys()) if "runs" in f else []
        attributes = {r: {k: _text(v) for k, v in f["runs"][r].attrs.items()} for r in runs}
    return Dataset(p, labels, runs, attributes)


# ------------------------------------------------------------------------------------------------ viewer
class ViewPage(str):
    """The HTML text of a `jointsim view` page (a str). In Jupyter it displays inline, in an iframe of its own
    (the page's scripts and styles stay apart from the notebook's). save(path) writes it."""

    def _repr_html_(self) -> str:
        import html as _html
        return ('<iframe style="width:100%;height:900px;border:1px solid #ccc" sandbox="allow-scripts" srcdoc="'
                + _html.escape(str(self), quote=True) + '"></iframe>')

    def save(self, path: PathLike) -> pathlib.Path:
        """Writes the page to path (through a temporary file renamed into place); returns the path."""
        target = pathlib.Path(_path(path, "path"))
        tmp = target.with_name(f".{target.name}.tmp.{os.getpid()}")
        try:
            tmp.write_text(str(self), encoding="utf-8")
            os.replace(tmp, target)
        finally:
            if tmp.exists():
                tmp.unlink()
        return target


def view(run_dir: PathLike, output: Optional[PathLike] = None, columns: int = 1000, frames: int = 20000,
         title: Optional[str] = None, mesh_bytes: int = 50_000_000) -> ViewPage:
    """As `jointsim view RUN_DIR`: one self-contained HTML page of a run folder or sweep folder (the arm animated in
    3D, interactive plots of the experiment type's figures, the summary; docs/view.md), returned as a ViewPage (a str
    that Jupyter displays inline) and, with output, also written there. columns: slices per plotted series (each
    keeps its minimum and maximum rows); frames: most animation samples per run; mesh_bytes: most bytes of URDF
    meshes embedded. Raises InputError."""
    page = ViewPage(_core.view_html(_path(run_dir, "run_dir"), _int(columns, "columns"), _int(frames, "frames"),
                                    "" if title is None else str(title), _int(mesh_bytes, "mesh_bytes")))
    if output is not None:
        page.save(output)
    return page


# ------------------------------------------------------------------------------------------------ FMU export
def export_fmu(config: PathLike, fmu_path: PathLike, inputs: Union[str, Sequence[str]] = (),
               outputs: Union[str, Sequence[str]] = (), overrides: Overrides = None,
               binary_dir: Optional[PathLike] = None, step_size: float = 1e-3) -> Dict[str, Any]:
    """As `jointsim fmu`: writes an FMI 2.0 Co-Simulation FMU of an experiment file (any type).

    inputs: command ports, "PORT" (every joint) or "JOINT:PORT" (voltage, current, motor_torque, motor_velocity,
    setpoint) for a robot, "command" for a joint rig; a str or a list of str. outputs: signal names (default all),
    a str or a list. overrides: as for load_experiment. binary_dir: the FMU binary's folder (default: the one
    shipped in this package). step_size: the FMU's default communication step [s]. Returns the FMU's description
    (model identifier, GUID, variables with their value references = their indices).
    """
    if binary_dir is None:
        here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fmu", "linux64")
        binary_dir = here if os.path.isfile(os.path.join(here, "jointsim_fmu.so")) else ""
    raw = _core.export_fmu(_input_file(config, "experiment file"), _path(fmu_path, "fmu_path"),
                           _names(inputs, "inputs"), _names(outputs, "outputs"), _overrides(overrides),
                           _path(binary_dir, "binary_dir"), _float(step_size, "step_size"))
    return json.loads(raw)


# ------------------------------------------------------------------------------------------------ identification
def _table(source: Any, what: str) -> Tuple[List[str], np.ndarray, str]:
    """(header, values, name) of a CSV path, a run folder, a RunResult or a mapping of equal-length columns."""
    if isinstance(source, RunResult):
        header = list(source.columns)
        names = [_split(c)[0] for c in header]
        return header, np.column_stack([np.asarray(source[n], dtype=float) for n in names]), f"{what} (RunResult)"
    if isinstance(source, Mapping):
        header = [str(k) for k in source.keys()]
        try:
            cols = [np.asarray(v, dtype=float).reshape(-1) for v in source.values()]
        except (TypeError, ValueError) as e:
            raise InputTypeError(f"{what}: every column must be an array of numbers ({e})") from None
        if not cols or any(len(c) != len(cols[0]) for c in cols):
            raise InputTypeError(f"{what}: expected columns of equal length")
        return header, np.column_stack(cols), f"{what} (mapping)"
    path = pathlib.Path(_input_file(source, what)) if not pathlib.Path(_path(source, what)).is_dir() else None
    if path is None:  # a run folder: its CSV log
        folder = pathlib.Path(_path(source, what))
        summary = folder / "summary.json"
        if not summary.is_file():
            raise InputFileNotFoundError(f"{folder}: a folder without summary.json: give the run's CSV log or a run folder",
                                         file=str(summary), reason="no summary.json")
        csv = pathlib.Path(json.loads(summary.read_text())["csv"])
        path = csv if csv.is_file() else folder / csv.name
    header, values = _core.read_csv(str(path))
    return list(header), np.asarray(values), str(path)


def agreement(predicted: Any, measured: Any, pairs: Union[str, Sequence[Any]],
              joint_names: Optional[Sequence[str]] = None, time_offset: float = 0.0, max_lag: float = 0.05,
              t_begin: float = -math.inf, t_end: float = math.inf) -> Dict[str, Any]:
    """How well a run reproduces a measured log (docs/replay.md; the CLI's ``jointsim agreement``).

    predicted, measured: a CSV path, a run folder, a RunResult (in memory) or a mapping column -> array (with a time
    column: ``time``, ``t_s`` or the first). pairs: "PREDICTED=MEASURED" strings or (predicted, measured) tuples;
    ``{joint}``, ``{j}`` (1..n) and ``{i}`` (0..n-1) expand over ``joint_names``. time_offset [s]: log time of the
    run's t = 0; max_lag [s]: lags searched; t_begin, t_end [s]: the window in log time.
    Returns {"pairs": [{"predicted", "measured", "samples", "range", "rms", "rms_percent", "bias", "max_abs",
    "correlation", "lag_s", "rms_percent_at_lag"}, ...], "t_begin_s", "t_end_s", ...}. Raises InputError."""
    if isinstance(pairs, str):
        pairs = [pairs]
    names = _names(joint_names, "joint_names") if joint_names is not None else []
    expanded: List[Tuple[str, str]] = []
    for p in pairs:
        text = f"{p[0]}={p[1]}" if isinstance(p, (tuple, list)) and len(p) == 2 else p
        if not isinstance(text, str):
            raise InputTypeError(f"pairs: expected 'PREDICTED=MEASURED' strings or (predicted, measured) tuples, got {p!r}")
        placeholders = any(k in text for k in ("{joint}", "{j}", "{i}"))
        if placeholders and not names:
            raise InputError(f"pairs: '{text}' has {{joint}}, {{j}} or {{i}} placeholders: give joint_names too")
        texts = ([text.replace("{joint}", n).replace("{j}", str(k + 1)).replace("{i}", str(k))
                  for k, n in enumerate(names)] if placeholders else [text])
        for t in texts:
            parts = [x.strip() for x in t.split("=")]
            if len(parts) != 2 or not parts[0] or not parts[1]:
                raise InputError(f"pairs: expected PREDICTED=MEASURED (a column of the run, one of the measured log), "
                                 f"got '{t}'")
            expanded.append((parts[0], parts[1]))
    ph, pv, pn = _table(predicted, "predicted")
    mh, mv, mn = _table(measured, "measured")
    raw = _core.agreement(ph, pv, pn, mh, mv, mn, expanded, _float(time_offset, "time_offset"),
                          _float(max_lag, "max_lag"), float(t_begin), float(t_end))
    return json.loads(raw)


def identify_currents(robot: PathLike, log: PathLike, output: Optional[PathLike] = None, *, time: str = "",
                      q: str = "q_actual_{j}", qd: str = "qd_target_{j}", qdd: str = "qdd_target_{j}",
                      current: str = "i_actual_{j}", ur_rtde: bool = False, t_begin: float = -math.inf,
                      t_end: float = math.inf, min_speed: float = 0.01, scale_bound: float = 0.4,
                      fit_offset: bool = False, refine: Optional[PathLike] = None, refine_set: Sequence[str] = (),
                      refine_iterations: int = 5) -> Dict[str, Any]:
    """Calibrates the drives of a robot-with-drives file from a measured log's motor currents (the CLI's
    ``jointsim identify currents``; docs/replay.md): per joint the torque-constant scale and the Coulomb and viscous
    friction of each direction (or, fit_offset, a symmetric Coulomb friction and a current offset). Column patterns
    with {j} (1..n) or {i} (0..n-1); ur_rtde: the UR RTDE names. ``refine``: a tracking experiment file replaying
    this log from its first sample (e.g. config/experiments/ur5_measured_replay.yaml): the values are then refined
    against the full twin (``refine_set``: overrides "key.path=value" of that experiment). Writes the calibrated
    robot-with-drives file to ``output`` when given. Returns {"samples", "joints": [{"joint", "kt_scale": {"value", "std_error"}, ...}],
    "drives_yaml": text}. Raises InputError, UnidentifiableError."""
    raw, yaml = _core.identify_currents(_input_file(robot, "robot"), _input_file(log, "log"),
                                        _optional_path(output, "output"), time, q, qd, qdd, current, bool(ur_rtde),
                                        float(t_begin), float(t_end), _float(min_speed, "min_speed"),
                                        _float(scale_bound, "scale_bound"), bool(fit_offset),
                                        "" if refine is None else _input_file(refine, "refine"),
                                        [str(x) for x in refine_set], int(refine_iterations))
    out = json.loads(raw)
    out["drives_yaml"] = yaml
    return out


def identify_clamping(time: Any, angle: Any, torque: Any, fixed_backlash: Optional[float] = None) -> Dict[str, Any]:
    """Identifies stiffness, backlash and Coulomb friction from a clamping curve ([KR300Thesis, Algorithm II] with
    Ceres): time [s], motor-side angle [rad] and torque [N*m], each of shape (n,). fixed_backlash [rad] fixes the
    backlash instead of fitting it.

    Returns stiffness [N*m/rad], backlash [rad], friction [N*m] and center [rad], each a dict (value, std_error,
    fitted, initial), plus rms_residual [N*m] and points. Raises UnidentifiableError when the curve cannot
    determine a parameter (e.g. it never crosses zero torque).
    """
    fb = None if fixed_backlash is None else _float(fixed_backlash, "fixed_backlash")
    return _core.identify_clamping(_array(time, "time"), _array(angle, "angle"), _array(torque, "torque"), fb)


def fit_friction_map(velocity: Any, torque: Any) -> Dict[str, Any]:
    """Fits the static friction map tau = alpha0 + alpha1 exp(-(v/v_s)^2) + alpha2 v per direction
    ([Hauschild2003]) to velocity [rad/s] and friction torque [N*m] samples, each of shape (n,).

    Returns positive and negative (each: alpha0 [N*m], alpha1 [N*m], alpha2 [N*m*s/rad], v_s [rad/s] as dicts of
    value, std_error, initial; points; rms_residual [N*m]) and delta, the asymmetry.
    """
    return _core.fit_friction_map(_array(velocity, "velocity"), _array(torque, "torque"))


# ------------------------------------------------------------------------------------------------ simulator
class Snapshot:
    """The complete state of a Simulator at one time (Simulator.snapshot()). Restore it with Simulator.restore();
    it pickles (as the bytes of Simulator.save_state()), so a state can go to another process that made a simulator
    from the same model."""

    def __init__(self, core: "_core.Snapshot"):
        self._p = core

    time = property(lambda self: self._p.time, doc="Simulated time of the snapshot [s].")

    def to_bytes(self) -> bytes:
        """The snapshot serialised (as Simulator.save_state())."""
        return self._p.to_bytes()

    @staticmethod
    def _from_bytes(data: bytes, time: float) -> "Snapshot":
        return Snapshot(_core.Snapshot.from_bytes(data, time))

    def __reduce__(self):
        return (Snapshot._from_bytes, (self._p.to_bytes(), self._p.time))

    def __repr__(self) -> str:
        return f"<jointsim.Snapshot at t = {self.time} s>"


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

    One advance may be as long as wanted (advance(300.0) runs the whole 300 s); it ends early only by its limits
    (set_limits: steps, wall-clock time, a bound on the state, which catches an unstable controller within a
    fraction of a second), by a solver failure, or by Ctrl-C (KeyboardInterrupt). After any of these the simulator
    is usable at the last internal step it completed.
    """

    #: Default bound on the magnitude of every state but the joint and motor angles (max_state of set_limits), for
    #: the simulators of from_robot and from_experiment: far beyond any physical joint or motor speed [rad/s],
    #: current [A], gear deflection or controller state of a robot.
    DEFAULT_MAX_STATE = 1e6

    def __init__(self, core: "_core.Simulator"):
        self._s = core

    @staticmethod
    def from_experiment(experiment: Union[PathLike, Experiment], overrides: Overrides = None) -> "Simulator":
        """A simulator over an experiment's model (a file path or a loaded Experiment) with its solver settings."""
        if not isinstance(experiment, Experiment):
            experiment = load_experiment(experiment, overrides)
        elif overrides:
            raise InputError("overrides apply when loading: pass them to load_experiment")
        return experiment.simulator()

    @staticmethod
    def from_robot(path: PathLike, q0: Optional[Sequence[float]] = None, rtol: float = 1e-6, atol: float = 1e-9,
                   max_order: int = 2, max_step: float = 0.0, max_gamma_change: float = 0.3,
                   max_state: float = DEFAULT_MAX_STATE, method: str = "bdf", step: float = 0.0,
                   jacobian_every: Union[int, str] = 1, oscillations: str = "damp") -> "Simulator":
        """A simulator over a robot-with-drives file (e.g. data_path("robots/ur5_drives.yaml")) starting at rest at
        q0 [rad], shape (dof,) (default zeros), with the drives holding it; BDF of order <= max_order with rtol and
        atol [state units], steps of at most max_step [s] (0: unlimited), a new Newton matrix when h*beta0 changes by
        more than max_gamma_change (relative; 0.5 suits a 1 kHz loop, docs/performance.md). max_state: the bound on
        every state's magnitude (see set_limits; 0: none). method="rosenbrock": the fixed-step method instead of BDF
        (ROS2, steps of `step` [s] on the grid k*step; docs/design.md "Fixed-step integration"), for a loop closed
        in Python at a fixed period: a step that divides the period keeps every advance() at the same cost.
        jacobian_every (fixed step only): renew the Jacobian every that many steps, or "adaptive": keep it while it
        describes the steps (renewed where a linearisation defect shows it moved; docs/design.md "Jacobian reuse").
        oscillations (fixed step only): "damp" (default) or "resolve": the drive trains' motor, current and gear
        states and the joint angles are stepped with ROS2's other L-stable gamma, 1 - 1/sqrt(2), so that their lightly
        damped kHz modes keep their amplitude instead of being damped (what noise-driven statistics of sampled control
        need; docs/design.md "Resolving the drive trains' oscillations"); it needs jacobian_every 1 or "adaptive"."""
        q = None if q0 is None else _array(q0, "q0")
        if not isinstance(method, str):
            raise TypeError(f"method: expected 'bdf' or 'rosenbrock', got {type(method).__name__}")
        if isinstance(jacobian_every, bool) or not isinstance(jacobian_every, (numbers.Integral, str)):
            raise TypeError(f"jacobian_every: expected a number of steps or 'adaptive', got "
                            f"{type(jacobian_every).__name__}")
        if not isinstance(oscillations, str):
            raise TypeError(f"oscillations: expected 'damp' or 'resolve', got {type(oscillations).__name__}")
        if method != "rosenbrock" and not (isinstance(jacobian_every, numbers.Integral) and jacobian_every == 1):
            raise InputError("Simulator.from_robot: jacobian_every: only with method='rosenbrock'")
        core = _core.Simulator.from_robot(_input_file(path, "robot file"), q, _float(rtol, "rtol"),
                                          _float(atol, "atol"), _int(max_order, "max_order"),
                                          _float(max_step, "max_step"), _float(max_gamma_change, "max_gamma_change"),
                                          method, _float(step, "step"),
                                          int(jacobian_every) if isinstance(jacobian_every, numbers.Integral)
                                          else jacobian_every, oscillations)
        sim = Simulator(core)
        sim.set_limits(max_state=max_state)
        return sim

    # --- time and state
    name = property(lambda self: self._s.name, doc="Name of the simulated model.")
    time = property(lambda self: self._s.time, doc="Simulated time [s].")
    state = property(lambda self: self._s.state, doc="Continuous state vector, shape (n,) (a copy; units per state, "
                                                     "see state_name).")
    restarts = property(lambda self: self._s.restarts, doc="Integrator restarts so far.")
    steps = property(lambda self: self._s.steps, doc="Internal solver steps so far.")
    solver_stats = property(lambda self: json.loads(self._s.solver_stats_json),
                            doc="Solver counters so far (dict: steps, rhs_evals, rhs_evals_jacobian, jac_evals, "
                                "lin_setups, error_test_failures, split_steps, retaken_steps, ...; the run summary's "
                                "solver_stats).")
    period_wall_times = property(
        lambda self: self._s.period_wall_times,
        doc="Wall-clock time per control period of a sampled plant, from one sample to the next (the caller's work "
            "between advance() calls included): dict periods, p50, p99, max [s]; p50/p99 from a log histogram, at "
            "most 2.3 % above the true quantile. Zeros without a sampled part.")

    def advance(self, dt: float) -> float:
        """Integrates over dt [s] > 0; returns the time reached [s]. Raises SolverError when the integration fails
        or a limit of set_limits ends it (flag STEP_BUDGET, WALL_TIME_BUDGET, DIVERGED), KeyboardInterrupt on
        Ctrl-C; the simulator then stands at the last internal step it completed."""
        return self._s.advance(_float(dt, "dt"))

    def advance_to(self, t: float) -> float:
        """Integrates to time t [s] >= time; returns the time reached [s]. Errors as advance()."""
        return self._s.advance_to(_float(t, "t"))

    def reset(self, q0: Optional[Sequence[float]] = None, qd0: Optional[Sequence[float]] = None) -> None:
        """Back to t = 0 with a fresh run state: command ports, commands, held setpoints and external wrenches
        cleared, controllers, sensors and noise generator as at the start. Without arguments the model's initial
        state; for a robot with drives q0 [rad] and qd0 [rad/s], shapes (dof,), start it elsewhere (at q0 with the
        drives holding it, joints moving at qd0)."""
        conv = lambda a, what: None if a is None else _array(a, what)
        self._s.reset(conv(q0, "q0"), conv(qd0, "qd0"))

    def snapshot(self) -> "Snapshot":
        """The complete state now (time, continuous state, inputs, controllers, sensor memory, noise generator,
        modes, faults). restore() it here or into a copy() to continue bit for bit as this simulator continues; it
        pickles (as bytes) for another process with the same model."""
        return Snapshot(self._s.snapshot())

    def restore(self, snapshot: "Snapshot") -> None:
        """Back to a snapshot of this model (InputError for one of another model; the simulator is then
        unchanged)."""
        if not isinstance(snapshot, Snapshot):
            raise TypeError("restore: expected a jointsim.Snapshot (from snapshot()), got " + type(snapshot).__name__)
        self._s.restore(snapshot._p)

    def save_state(self) -> bytes:
        """The complete state as bytes (snapshot() serialised)."""
        return self._s.save_state()

    def load_state(self, data: bytes) -> None:
        """Back to a state from save_state() (InputError for bytes of another model or truncated ones)."""
        if not isinstance(data, (bytes, bytearray)):
            raise TypeError("load_state: expected bytes, got " + type(data).__name__)
        self._s.load_state(bytes(data))

    def copy(self) -> "Simulator":
        """An independent simulator on the same model in the same complete state (inputs included); both continue
        alike, bit for bit, and neither sees the other's inputs."""
        c = Simulator(self._s.copy())
        return c

    @property
    def state_names(self) -> List[str]:
        """What each continuous state is, with its unit (as state_name(i))."""
        return list(self._s.state_names)

    def set_state(self, y: Sequence[float]) -> None:
        """Replaces the continuous state (shape like state); the integrator restarts."""
        self._s.set_state(_array(y, "state"))

    def state_name(self, i: int) -> str:
        """What state i is, with its unit ("q_elbow_joint [rad]"); "" when the model does not say."""
        return self._s.state_name(_int(i, "i"))

    def set_limits(self, max_steps: Optional[int] = None, max_wall_time: Optional[float] = None,
                   max_state: Optional[float] = None) -> None:
        """Limits of every following advance()/advance_to() call; an argument left None keeps its value, 0 means
        none. max_steps: internal solver steps per call; max_wall_time: wall-clock time per call [s]; max_state: bound
        on the magnitude of every continuous state [its own unit] (an unstable controller makes states run away:
        the call ends at once with SolverError flag DIVERGED naming the state, instead of minutes of ever smaller
        steps). Exceeding a limit raises SolverError (flag STEP_BUDGET, WALL_TIME_BUDGET or DIVERGED)."""
        steps, wall, bound = self._s.limits()
        self._s.set_limits(steps if max_steps is None else _int(max_steps, "max_steps"),
                           wall if max_wall_time is None else _float(max_wall_time, "max_wall_time"),
                           bound if max_state is None else _float(max_state, "max_state"))

    @property
    def limits(self) -> Dict[str, float]:
        """The limits of each advance call: max_steps, max_wall_time [s], max_state (0: none)."""
        steps, wall, bound = self._s.limits()
        return {"max_steps": steps, "max_wall_time": wall, "max_state": bound}

    # --- signals
    @property
    def signal_names(self) -> List[str]:
        """Signal names with units, as the CSV columns after time[s]."""
        return list(self._s.signal_names)

    def signal(self, name: str) -> float:
        """One signal at the current time, by name with or without its unit (in the signal's unit)."""
        return self._s.signal(name)

    def signals(self) -> Dict[str, float]:
        """All signals at the current time, by name without unit."""
        v = self._s.signal_values()
        return {_split(n)[0]: float(x) for n, x in zip(self._s.signal_names, v)}

    def signal_values(self) -> np.ndarray:
        """All signals at the current time in signal_names order, shape (len(signal_names),)."""
        return self._s.signal_values()

    def signal_index(self, name: str) -> int:
        """Index of a signal (name with or without unit) in signal_names, for repeated use with signal_values()."""
        return self._s.signal_index(name)

    # --- inputs of any plant (the command ports of a robot's drives, a joint rig's command and load torque)
    inputs = property(lambda self: self._s.inputs,
                      doc="The plant's inputs: a list of dicts with name, unit (SI), min, max, description, group, "
                          "mode, active (in effect now) and value (the held value).")

    def set_input(self, name: str, value: float) -> None:
        """Holds input `name` (one of inputs, e.g. "elbow_joint.voltage" [V], "elbow_joint.q" [rad], "command")
        at `value` from now on; an input of a group (a joint) selects its mode there (e.g. the voltage port)."""
        self._s.set_input(name, _float(value, "value"))

    def release_input(self, name: str) -> None:
        """Input `name` no longer held: back to the model's own source (its profile from the file, its controller, or
        0 for a load torque). A robot's command ports switch with set_port instead."""
        self._s.release_input(name)

    def input(self, name: str) -> float:
        """The value held at input `name`."""
        return self._s.input(name)

    # --- robot with drives
    dof = property(lambda self: self._s.dof, doc="Number of joints (robot with drives).")
    joint_names = property(lambda self: list(self._s.joint_names), doc="Joint names, base to tip.")
    joint_positions = property(lambda self: self._s.joint_positions, doc="Joint angles q [rad], shape (dof,) (copy).")
    joint_velocities = property(lambda self: self._s.joint_velocities,
                                doc="Joint rates qd [rad/s], shape (dof,) (copy).")
    gear_ratios = property(lambda self: self._s.gear_ratios,
                           doc="Gear ratio N per joint [-], shape (dof,) (motor angle = N * joint angle, rigid gear).")
    motor_velocities = property(lambda self: self._s.motor_velocities,
                                doc="Motor shaft speeds [rad/s], shape (dof,) (copy): what the motor encoders measure.")

    def model(self) -> Model:
        """The robot's rigid-body model (with the reflected rotor inertias), for rnea/aba/... in a controller."""
        return self._s.model()

    def drive_parameters(self, joint: Union[int, str]) -> Dict[str, List[Dict[str, Any]]]:
        """The parameter tables of a joint's drive (the robot file's values): {"motor": [...], "transmission":
        [...], "friction": [...]}, each row a dict with key, unit (SI), value, min, max, min_open, max_open, role and
        description. The keys are those of an experiment's `drives:` mapping (docs/experiments.md)."""
        return self._s.drive_parameters(_joint(joint))

    def set_port(self, joint: Union[int, str], port: str) -> None:
        """Chooses the command port of a joint (by index or name; one of PORTS); InputError if the drive lacks it."""
        self._s.set_port(_joint(joint), port)

    def port(self, joint: Union[int, str]) -> str:
        """The command port of a joint (by index or name)."""
        return self._s.port(_joint(joint))

    def set_command(self, joint: Union[int, str], value: float) -> None:
        """The command of a joint's port: rad/s, A, V or N*m (InputError for NaN or under the setpoint port)."""
        self._s.set_command(_joint(joint), _float(value, "value"))

    def set_commands(self, values: Sequence[float]) -> None:
        """Commands of every joint, shape (dof,); entries of joints under the setpoint port are ignored."""
        self._s.set_commands(_array(values, "commands"))

    def set_setpoint(self, joint: Union[int, str], q: float, qd: float = 0.0, qdd: float = 0.0) -> None:
        """Holds a joint's reference at q [rad], qd [rad/s], qdd [rad/s^2] in place of the trajectory."""
        self._s.set_setpoint(_joint(joint), _float(q, "q"), _float(qd, "qd"), _float(qdd, "qdd"))

    def hold_setpoints(self, q: Sequence[float], qd: Optional[Sequence[float]] = None,
                       qdd: Optional[Sequence[float]] = None) -> None:
        """Holds the references of every joint: q [rad], qd [rad/s], qdd [rad/s^2], shapes (dof,)."""
        conv = lambda a, what: None if a is None else _array(a, what)
        self._s.hold_setpoints(_array(q, "q"), conv(qd, "qd"), conv(qdd, "qdd"))

    def release_setpoints(self) -> None:
        """Back to the experiment's trajectory for every joint."""
        self._s.release_setpoints()

    def set_external_wrench(self, frame: str, wrench: Sequence[float]) -> None:
        """Holds a wrench [fx, fy, fz (N), nx, ny, nz (N*m)], shape (6,), in world axes at a frame's origin (zeros
        remove it)."""
        self._s.set_external_wrench(frame, _array(wrench, "wrench"))

    def __copy__(self):
        return self.copy()

    def __deepcopy__(self, memo):
        return self.copy()

    def __reduce__(self):
        raise TypeError("a jointsim.Simulator does not pickle (its model is not kept as data): pickle "
                        "sim.snapshot() and restore() it into a simulator made from the same model")

    def __repr__(self) -> str:
        return f"<jointsim.Simulator of {self.name} at t = {self.time} s>"
