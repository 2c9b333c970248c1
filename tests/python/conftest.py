"""Shared paths of the Python tests (run by scripts/test.sh in build/pyenv after `pip install .`)."""
import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    """The jointsim command-line tool of the C++ build (JOINTSIM_CLI, default build/jointsim)."""
    path = pathlib.Path(os.environ.get("JOINTSIM_CLI", ROOT / "build" / "jointsim"))
    if not path.exists():
        pytest.fail(f"the CLI {path} is not built (set JOINTSIM_CLI)")
    return path
