"""The install a newcomer gets from ``python3 dev.py run`` or ``test``: the
``ftc-mc`` command beside the interpreter runs, the package's data files are
installed, and the Numba installed is one ``pyproject.toml`` allows, as is the
one the shipped compile plan was recorded with."""

from __future__ import annotations

import pickle
import subprocess
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import numba
from packaging.requirements import Requirement

import ftc_mc
from ftc_mc.sim.compile_helper import PLAN_FILE

ROOT = Path(__file__).resolve().parents[1]


def _requirement(name: str) -> Requirement:
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    [req] = [Requirement(d) for d in deps if Requirement(d).name == name]
    return req


def test_the_command_is_installed_and_runs():
    """``ftc-mc`` (the console script of the interpreter's environment) answers
    ``--help`` and ``airframes`` (no kernel compiled), and the metadata of the
    installed distribution is this source's."""
    exe = Path(sys.executable).parent / ("ftc-mc.exe" if sys.platform == "win32" else "ftc-mc")
    assert exe.is_file(), f"{exe}: not installed (python3 dev.py test installs it)"
    out = subprocess.run([str(exe), "--help"], capture_output=True, text=True, timeout=120,
                         cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert "run" in out.stdout and "scenario" in out.stdout
    out = subprocess.run([str(exe), "airframes"], capture_output=True, text=True, timeout=120,
                         cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert "x8-gryte2018" in out.stdout
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert metadata.version("ftc-mc") == project["version"]
    assert Path(ftc_mc.__file__).resolve().parent == ROOT / "ftc_mc"  # editable: these sources


def test_numba_is_a_tested_version():
    """The installed Numba, and the one the compile plan was recorded with,
    are within ``pyproject.toml``'s bound (the versions tested): a newer Numba
    needs the suite run on it and the plan recorded again
    (``scripts/maintenance/make_compile_plan.py``) before the bound moves."""
    req = _requirement("numba")
    assert req.specifier, "numba is bounded to the versions tested"
    assert any(s.operator == "<" for s in req.specifier), "numba has an upper bound"
    assert req.specifier.contains(numba.__version__), (numba.__version__, str(req.specifier))
    with open(PLAN_FILE, "rb") as f:
        plan = pickle.load(f)
    assert req.specifier.contains(plan["numba"]), (plan["numba"], str(req.specifier))
