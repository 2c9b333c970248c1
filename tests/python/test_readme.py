"""The README's Python snippets run as pasted, from a folder outside the repository, with the installed package
(the blocks are found by tests/readme/snippets.py, which CTest's readme_shell_snippets uses for the shell ones)."""
import importlib.util
import os
import subprocess
import sys

import pytest

from conftest import ROOT

_spec = importlib.util.spec_from_file_location("snippets", ROOT / "tests" / "readme" / "snippets.py")
snippets = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(snippets)

PYTHON_BLOCKS = [(line, code) for lang, line, code, skip in snippets.blocks(ROOT / "README.md")
                 if lang == "python" and not skip]


def test_the_readme_has_python_snippets():
    assert PYTHON_BLOCKS


@pytest.mark.parametrize("line,code", PYTHON_BLOCKS, ids=[f"README.md:{line}" for line, _ in PYTHON_BLOCKS])
def test_readme_python_snippet_runs_as_pasted(tmp_path, line, code):
    assert not str(tmp_path.resolve()).startswith(str(ROOT.resolve()))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, f"README.md:{line}: the snippet failed:\n{p.stdout}\n{p.stderr}"
    print(p.stdout)
