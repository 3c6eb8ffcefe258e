"""The newcomer's tier (``pytest --newcomer``, what ``python3 dev.py test``
runs; tests/conftest.py ``NEWCOMER``): it names tests that exist, and covers
what a newcomer needs: the install, every golden file, and a kernel-vs-twin
test of each kernel family."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from conftest import NEWCOMER, _newcomer_ids, _select_newcomer
from golden_cases import CAMPAIGNS, GOLDEN, SCENARIOS

ROOT = Path(__file__).resolve().parents[1]


def test_the_tier_collects_exactly_the_tests_it_names():
    out = subprocess.run([sys.executable, "-m", "pytest", "--newcomer", "--collect-only", "-q",
                          "-p", "no:cacheprovider"], capture_output=True, text=True,
                         timeout=600, cwd=ROOT)
    assert out.returncode == 0, out.stdout + out.stderr
    collected = {line for line in out.stdout.splitlines() if line.startswith("tests/")}
    assert collected == _newcomer_ids()


def test_the_tier_holds_every_golden_file():
    """Every file of ``tests/golden/``: the campaigns' and scenarios' tables
    (``tests/test_golden.py``) and the recorded configs
    (``tests/test_config_equivalence.py``), and nothing else."""
    golden = NEWCOMER["every golden file"]
    files = sorted(GOLDEN.glob("*.parquet"))
    assert len(files) >= 2 * len(CAMPAIGNS) + len(SCENARIOS)
    for f in files:
        kind, name, _ = f.stem.split("-")
        assert f"test_golden.py::test_{kind}_is_golden[{name}]" in golden, f.name
    configs = sorted((GOLDEN / "configs").glob("*.json"))
    assert len(configs) >= 20
    for f in configs:
        assert (f"test_config_equivalence.py::test_shipped_config_resolves_as_recorded"
                f"[{f.stem}]") in golden, f.name
    assert "test_config_equivalence.py::test_every_shipped_config_has_a_record" in golden
    assert {p.name for p in GOLDEN.iterdir()} == {f.name for f in files} | {"configs"}
    assert len(golden) == len(CAMPAIGNS) + len(SCENARIOS) + len(configs) + 1


def test_the_tier_compares_each_kernel_family_with_its_twin():
    """One test per family, in a file that imports that family's NumPy twins
    (``tests/naive.py``, ``tests/naive_sixdof.py``), and the install's tests."""
    twins = {"longitudinal kernels against their NumPy twins": "naive",
             "6-DOF kernels against their NumPy twins": "naive_sixdof"}
    for family, module in twins.items():
        assert NEWCOMER[family], family
        for test_id in NEWCOMER[family]:
            tree = ast.parse((ROOT / "tests" / test_id.split("::")[0]).read_text())
            imported = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import)
                        for a in n.names}
            imported |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
            assert module in imported, (test_id, module)
    assert NEWCOMER["the install"]
    assert set(NEWCOMER) == set(twins) | {"the install", "every golden file"}


def _item(nodeid):
    return SimpleNamespace(nodeid=nodeid)


def test_a_tier_test_that_disappears_stops_the_run():
    """A test the tier names that its collected file no longer holds (renamed,
    parametrised otherwise) is a usage error, not a smaller tier; the other
    tests are deselected."""
    config = SimpleNamespace(getoption=lambda name: name == "newcomer",
                             hook=SimpleNamespace(pytest_deselected=lambda items: None))
    ids = sorted(_newcomer_ids())
    extra = _item("tests/test_golden.py::test_something_else")
    items = [_item(i) for i in ids] + [extra]
    _select_newcomer(config, items)
    assert [it.nodeid for it in items] == ids
    renamed = [_item(i) for i in ids if not i.endswith("[linear]")]
    renamed.append(_item("tests/test_golden.py::test_campaign_is_golden[linear_renamed]"))
    with pytest.raises(pytest.UsageError, match=r"test_campaign_is_golden\[linear\]"):
        _select_newcomer(config, renamed)
    off = SimpleNamespace(getoption=lambda name: False)
    items = [_item(i) for i in ids] + [extra]
    _select_newcomer(off, items)
    assert len(items) == len(ids) + 1
