"""Set up the project's virtual environment and run its main job or its tests.

Only the Python standard library is used, so this works on a fresh machine with
nothing but Python 3.11::

    python3 dev.py run         # create .venv if needed, install, run the main job
    python3 dev.py test        # create .venv if needed, install with test extras, and run
                               # the newcomer's tier of the tests: the install works,
                               # every golden file holds, each kernel family agrees
                               # with its NumPy twin (pytest --newcomer, tests/conftest.py)
    python3 dev.py test --all  # the same install, then the whole test suite (CI runs it)

Both test commands run pytest with ``-q -n auto --dist worksteal``: one
pytest-xdist worker per core, idle ones take queued tests.  Extra arguments
after ``run`` go to ``ftc-mc``; after ``test`` they go to ``pytest`` in place
of the tier (``python3 dev.py test tests/test_golden.py -x``), and after
``test --all`` they are added to the whole suite's command.

The install is repeated only when ``pyproject.toml`` changes.  It is editable
(the sources stay in this folder, so an edit is run and tested at once), and
pip runs with ``-qq``: its errors are shown, its warnings are not (setuptools
boxes every editable install with a warning meant for package authors).  pip
installs with ``--no-compile``, and the packages' bytecode is then compiled on
every core by :mod:`compileall` (pip compiles on one: 32 s of install -> 15 s
plus 8 s here, measured on 2 cores).  The bytecode is needed before the first
run: where ``PYTHONDONTWRITEBYTECODE`` is set, as in this project's CI, Python
would otherwise compile every imported module again in every process (the test
suite took 245 s instead of 180 s).
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
BIN = VENV / ("Scripts" if os.name == "nt" else "bin")
PY = BIN / "python"

MAIN_JOB = ["run", "configs/paper_tables.yaml"]

# run by the venv's python: the bytecode of its installed packages, but for
# their own test suites (folders test/ and tests/, never imported by a run;
# 7081 files in 12.2 s -> 4378 in 7.9 s) and for pip, setuptools and
# pkg_resources, which only pip's own runs import (4378 -> 3718 files)
COMPILE_PACKAGES = ("import compileall, re, sysconfig; "
                    "compileall.compile_dir(sysconfig.get_paths()['purelib'], quiet=2, "
                    "workers=0, rx=re.compile(r'[/\\\\]tests?[/\\\\]|[/\\\\]site-packages"
                    "[/\\\\](pip|setuptools|pkg_resources)[/\\\\]'))")


def ensure_venv(extras: str) -> None:
    """Create ``.venv`` and install the package (editable) with ``extras``,
    unless already installed from this ``pyproject.toml``."""
    if sys.version_info < (3, 11):
        sys.exit(f"dev.py: Python >= 3.11 is required, this is {sys.version.split()[0]}")
    if not PY.exists():
        print(f"dev.py: creating {VENV}", flush=True)
        venv.EnvBuilder(with_pip=True).create(VENV)
    digest = hashlib.sha256((ROOT / "pyproject.toml").read_bytes()).hexdigest()
    stamp = VENV / f".installed-{extras or 'base'}"
    if stamp.exists() and stamp.read_text() == digest:
        return
    name = f"ftc-mc[{extras}]" if extras else "ftc-mc"
    print(f"dev.py: installing {name} into {VENV} (about half a minute)", flush=True)
    target = f".[{extras}]" if extras else "."
    # -qq: pip's errors only; --no-compile: see the module docstring
    for args in (["--upgrade", "pip"], ["--no-compile", "-e", target]):
        done = subprocess.run([str(PY), "-m", "pip", "install", "-qq", *args], cwd=ROOT)
        if done.returncode:
            sys.exit(f"dev.py: 'pip install {' '.join(args)}' failed (exit code "
                     f"{done.returncode}); pip's errors are above")
    # as pip would, on every core; like pip, a file that does not compile is
    # left to fail at its import
    subprocess.run([str(PY), "-c", COMPILE_PACKAGES], cwd=ROOT)
    stamp.write_text(digest)


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in ("run", "test"):
        print(__doc__)
        return 2
    cmd, rest = argv[0], argv[1:]
    if cmd == "run":
        ensure_venv("")
        args = [str(BIN / "ftc-mc")] + (rest or MAIN_JOB)
    else:
        ensure_venv("test")
        args = [str(PY), "-m", "pytest"] + pytest_args(rest)
    return subprocess.run(args, cwd=ROOT).returncode


# one worker per core; tests/conftest.py orders the tests so that the
# workers share the trial kernel's cold compile, and worksteal lets the
# other worker take the first one's queued tests meanwhile
PYTEST = ["-q", "-n", "auto", "--dist", "worksteal"]


def pytest_args(rest: list[str]) -> list[str]:
    """pytest's arguments for ``python3 dev.py test REST...``: the newcomer's
    tier, the whole suite (``--all``, then more arguments), or ``REST``."""
    if not rest:
        return PYTEST + ["--newcomer"]
    if rest[0] == "--all":
        return PYTEST + rest[1:]
    return rest


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
