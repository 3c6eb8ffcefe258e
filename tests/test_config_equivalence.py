"""Every shipped config resolves to the same configuration as recorded.

``tests/golden/configs/<name>.json`` holds what ``configs/<name>.yaml`` resolved
to (``scripts/maintenance/make_config_golden.py``), recorded while the configs
still listed every field.  Editing a config's text (comments, dropping fields at
their default) must leave what it runs unchanged.
"""

import json
from pathlib import Path

import pytest

from ftc_mc.config import Config, ScenarioConfig, load_any

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "tests" / "golden" / "configs"
SHIPPED = sorted(p.stem for p in (ROOT / "configs").glob("*.yaml"))


def test_every_shipped_config_has_a_record():
    assert SHIPPED == sorted(p.stem for p in GOLDEN.glob("*.json"))
    assert len(SHIPPED) == 23


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_config_resolves_as_recorded(name):
    want = json.loads((GOLDEN / f"{name}.json").read_text(encoding="utf-8"))
    cfg = load_any(ROOT / "configs" / f"{name}.yaml")
    model = ScenarioConfig if want["kind"] == "scenario" else Config
    assert type(cfg) is model
    assert cfg.model_dump(mode="json") == want["config"]
    assert cfg == model.model_validate(want["config"])


def test_a_design_shipped_under_one_name_is_the_same_everywhere():
    """Several configs ship the same designs (robust, sixdof, ...) in their own
    file: a name means one design in every shipped config."""
    seen = {}
    for name in SHIPPED:
        cfg = load_any(ROOT / "configs" / f"{name}.yaml")
        for key, design in cfg.designs.items():
            first = seen.setdefault(key, (name, design))
            assert design == first[1], f"designs.{key} differs in {name}.yaml and {first[0]}.yaml"
    assert {"robust", "sixdof", "sixdof_selected"} <= set(seen)
