"""dev.py's install step: editable, pip quiet but for its errors, repeated only
when pyproject.toml changes (README, Quick start)."""

from __future__ import annotations

import importlib.util
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def dev(tmp_path, monkeypatch):
    """dev.py loaded as a module, pointed at a scratch project whose ``.venv``
    python exists, with pip's calls recorded instead of run."""
    spec = importlib.util.spec_from_file_location("dev_under_test", ROOT / "dev.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    (tmp_path / "pyproject.toml").write_text("[project]\nname = 'x'\n")
    venv = tmp_path / ".venv"
    (venv / "bin").mkdir(parents=True)
    (venv / "bin" / "python").write_text("")
    monkeypatch.setattr(mod, "ROOT", tmp_path)
    monkeypatch.setattr(mod, "VENV", venv)
    monkeypatch.setattr(mod, "PY", venv / "bin" / "python")
    mod.calls, mod.returncode = [], 0

    def run(cmd, **kw):
        mod.calls.append(cmd)
        return subprocess.CompletedProcess(cmd, mod.returncode)

    monkeypatch.setattr(mod.subprocess, "run", run)
    return mod


def test_install_is_editable_quiet_and_once(dev, capsys):
    dev.ensure_venv("test")
    assert len(dev.calls) == 3
    upgrade, install, compile_ = dev.calls
    assert upgrade[1:] == ["-m", "pip", "install", "-qq", "--upgrade", "pip"]
    # editable (the tests import the sources in place), warnings not shown,
    # the bytecode compiled afterwards on every core
    assert install[1:] == ["-m", "pip", "install", "-qq", "--no-compile", "-e", ".[test]"]
    assert compile_[1:] == ["-c", dev.COMPILE_PACKAGES]
    assert capsys.readouterr().out.startswith("dev.py: installing ftc-mc[test]")
    dev.ensure_venv("test")
    assert len(dev.calls) == 3  # same pyproject.toml: nothing to do
    dev.ensure_venv("")
    assert dev.calls[-2][-2:] == ["-e", "."]  # the run command's own install
    (dev.ROOT / "pyproject.toml").write_text("[project]\nname = 'y'\n")
    dev.ensure_venv("test")
    assert len(dev.calls) == 9 and dev.calls[-2][-1] == ".[test]"


def test_the_packages_bytecode_is_compiled(tmp_path):
    """``COMPILE_PACKAGES`` writes the bytecode of a module in ``purelib``
    (pointed at a scratch folder), as pip's install would have, but not of
    the package's own test suite."""
    import sys

    spec = importlib.util.spec_from_file_location("dev_under_test", ROOT / "dev.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    (tmp_path / "pkg" / "tests").mkdir(parents=True)
    for f in ("m.py", "tests/test_m.py"):
        (tmp_path / "pkg" / f).write_text("X = 1\n")
    code = (f"import sysconfig; sysconfig.get_paths = lambda: {{'purelib': {str(tmp_path)!r}}}; "
            + mod.COMPILE_PACKAGES)
    subprocess.run([sys.executable, "-c", code], check=True)
    tag = sys.implementation.cache_tag
    assert (tmp_path / "pkg" / "__pycache__" / f"m.{tag}.pyc").exists()
    assert not (tmp_path / "pkg" / "tests" / "__pycache__").exists()  # a package's own tests


def test_a_failed_install_is_one_line_and_not_stamped(dev):
    dev.returncode = 1
    with pytest.raises(SystemExit) as exc:
        dev.ensure_venv("")
    assert str(exc.value).startswith("dev.py: 'pip install --upgrade pip' failed (exit code 1)")
    assert not list(dev.VENV.glob(".installed-*"))
    dev.returncode = 0
    dev.ensure_venv("")
    assert len(dev.calls) == 4  # tried again: upgrade, install, compile



def test_the_test_command_runs_the_tier_and_all_runs_the_suite(dev):
    """``python3 dev.py test`` runs the newcomer's tier; ``test --all`` the
    whole suite (CI's command), with more pytest arguments after it; other
    arguments go to pytest in place of either."""
    both = ["-q", "-n", "auto", "--dist", "worksteal"]
    assert dev.pytest_args([]) == both + ["--newcomer"]
    assert dev.pytest_args(["--all"]) == both
    assert dev.pytest_args(["--all", "-x"]) == both + ["-x"]
    assert dev.pytest_args(["tests/test_golden.py", "-x"]) == ["tests/test_golden.py", "-x"]
    assert dev.main(["test"]) == 0
    assert dev.calls[-1][1:] == ["-m", "pytest"] + both + ["--newcomer"]
    assert dev.main(["test", "--all"]) == 0
    assert dev.calls[-1][1:] == ["-m", "pytest"] + both


def test_ci_runs_the_whole_suite():
    run = (ROOT / ".ci" / "run").read_text()
    assert 'dev.py test --all' in run
