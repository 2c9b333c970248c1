"""Exceptions of jointsim, with the fields of the C++ errors they carry.

Bad input is a ``ValueError`` (``InputError``), so ``except ValueError`` catches it; a missing file is also a
``FileNotFoundError`` and an argument of the wrong type a ``TypeError``. A failed or stopped integration is a
``RuntimeError`` (``SolverError``). Ctrl-C during a long call raises Python's own ``KeyboardInterrupt``.
"""
from __future__ import annotations

import errno as _errno
from typing import Optional

__all__ = ["InputError", "InputFileNotFoundError", "InputTypeError", "UnidentifiableError", "SolverError",
           "ConcurrentUseError"]


class InputError(ValueError):
    """Bad input: a file, key or value that does not parse or validate, an argument of the wrong shape.

    Attributes (None where unknown):
        file (str): the file with the problem.
        line (int): its 1-based line.
        key_path (str): the key path in the file, e.g. ``"drives[2].friction.sigma0"``.
        reason (str): what was expected, without the location.
    """

    def __init__(self, message: str, *, file: str = "", line: int = 0, key_path: str = "", reason: str = ""):
        ValueError.__init__(self, message)
        self.file: Optional[str] = file or None
        self.line: Optional[int] = line or None
        self.key_path: Optional[str] = key_path or None
        self.reason: str = reason or message

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class InputFileNotFoundError(InputError, FileNotFoundError):
    """An input file that does not exist; also a ``FileNotFoundError``.

    Attributes: ``filename`` (and ``missing_path``) name the missing file; ``file``, ``line`` and ``key_path`` say
    where it was named (the experiment file and its key, e.g. ``robot``), or the missing file itself when it was
    given directly.
    """

    def __init__(self, message: str, *, missing_path: str = "", **fields):
        InputError.__init__(self, message, **fields)
        self.missing_path: Optional[str] = missing_path or self.file
        self.errno = _errno.ENOENT
        self.strerror = self.reason
        self.filename = self.missing_path

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class InputTypeError(InputError, TypeError):
    """An argument of the wrong type (e.g. a number where a path is expected); also a ``TypeError``."""


class UnidentifiableError(ValueError):
    """Data that cannot determine a requested parameter (e.g. a clamping curve that never crosses zero torque
    leaves the backlash unobservable)."""

    def __init__(self, message: str):
        ValueError.__init__(self, message)


class SolverError(RuntimeError):
    """A failed or stopped integration.

    Attributes:
        time (float): simulated time of the failure [s].
        flag (str): the solver flag, e.g. ``"CV_CONV_FAILURE"``, ``"CV_TOO_MUCH_WORK"``, or the limit that ended the
            call: ``"STEP_BUDGET"``, ``"WALL_TIME_BUDGET"``, ``"DIVERGED"``.
        component (str): the model or component involved (None when unknown).
    """

    def __init__(self, message: str, *, time: float = float("nan"), flag: str = "", component: str = ""):
        RuntimeError.__init__(self, message)
        self.time: float = float(time)
        self.flag: str = flag
        self.component: Optional[str] = component or None


class ConcurrentUseError(RuntimeError):
    """One object (a Simulator, an Experiment and the simulators made from it, a Model) used from two threads at
    once: the second call raises this instead of racing the first. Give each thread its own object, or hold a lock
    around the calls."""

    def __init__(self, message: str):
        RuntimeError.__init__(self, message)
