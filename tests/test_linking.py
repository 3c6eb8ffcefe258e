"""Kernels that call a stage by address (core/linking.py) instead of linking
its code: the caller keeps no copy of the stage, a caller loaded from the disk
cache in a new process registers the stages it calls before it runs, and
results and exceptions pass as through a linked call."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from ftc_mc.core import jit, linking

ROOT = Path(__file__).resolve().parents[1]

SOURCE = textwrap.dedent('''
    from ftc_mc.core.jit import kernel

    @kernel(by_address=True)
    def stage(a, s):
        t = 0.0
        for i in range(a.shape[0]):
            a[i] = a[i] * s + 1.0
            t += a[i]
        if t < 0.0:
            raise ValueError("negative total")
        return t

    @kernel
    def caller(a, s):
        x = 0.0
        for _ in range(3):
            x += stage(a, s)
        return x
''')

RUN = textwrap.dedent('''
    import json, sys
    import numpy as np
    sys.path.insert(0, sys.argv[1])
    import by_address_probe as m
    a = np.ones(4)
    total = m.caller(a, 2.0)
    try:
        m.caller(np.full(2, -10.0), 1.0)
        raised = ""
    except ValueError as exc:
        raised = str(exc)
    print(json.dumps({"total": total, "a": a.tolist(), "raised": raised,
                      "loaded": sum(m.caller.stats.cache_hits.values())}))
''')


def _reference(a, s):
    """The caller's arithmetic in plain Python."""
    x = 0.0
    for _ in range(3):
        a[:] = a * s + 1.0
        x += float(a.sum())
    return x


def _run(folder: Path) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(folder / "cache"))
    done = subprocess.run([sys.executable, "-c", RUN, str(folder)], env=env, cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr  # a caller calling an unregistered symbol crashes
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.skipif(not jit.CACHE, reason="FTC_MC_NUMBA_CACHE=0")
def test_a_cached_caller_registers_its_stages_in_a_new_process(tmp_path):
    (tmp_path / "by_address_probe.py").write_text(SOURCE)
    a = np.ones(4)
    expected = _reference(a, 2.0)
    first = _run(tmp_path)  # compiles both kernels and caches them
    second = _run(tmp_path)  # loads the caller, whose stage this process has not called
    assert first["loaded"] == 0 and second["loaded"] == 1
    for out in (first, second):
        assert out["total"] == expected and out["a"] == a.tolist()
        assert out["raised"] == "negative total"


def test_the_caller_keeps_no_copy_of_the_stage(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(tmp_path))
    (tmp_path / "by_address_probe_ir.py").write_text(SOURCE)
    import by_address_probe_ir as m
    a = np.ones(3)
    assert m.caller(a, 0.5) == _reference(np.ones(3), 0.5)
    (sig,) = m.caller.signatures
    ir = m.caller.inspect_llvm(sig)
    (stage_sig,) = m.stage.signatures
    name = linking.symbol_name(m.stage, stage_sig)
    stage_code = m.stage.overloads[stage_sig].fndesc.mangled_name
    assert re.search(rf'declare i32 @"?{re.escape(name)}"?\(', ir)
    assert stage_code not in ir  # linked, the stage's definition would be here
    assert linking.stages_called(m.caller.overloads[sig].library) == (
        ("by_address_probe_ir", "stage", stage_sig),)
