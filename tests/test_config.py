"""Configuration: defaults, shipped files, and one-line errors for bad input."""

from pathlib import Path

import pytest
import yaml

from ftc_mc.config import Config, load_config, load_scenario, parse_config
from ftc_mc.errors import UserError

ROOT = Path(__file__).resolve().parents[1]


def test_shipped_configs_say_what_they_run_and_how():
    """Each shipped config is hand-written: a header saying what it runs and the
    command, then only the fields it sets (what they resolve to:
    tests/test_config_equivalence.py)."""
    files = sorted((ROOT / "configs").glob("*.yaml"))
    assert len(files) == 23
    for path in files:
        text = path.read_text(encoding="utf-8")
        head = text.split("\n\n")[0]
        assert head.startswith("# "), path
        assert f"configs/{path.name}" in head and "ftc-mc " in head, path
        assert "ftc-mc config show" in head, path
    assert (ROOT / "configs" / "elevon_lock.yaml").stat().st_size <= 1024
    assert sum(p.stat().st_size for p in files) <= 40 * 1024
    assert load_scenario(ROOT / "configs" / "paper_scenario.yaml").scenario.duration_s == 100.0


def test_the_fast_loader_reads_what_pyyaml_s_python_loader_reads():
    """``read_yaml`` parses with libyaml where PyYAML has it (its wheels do);
    every shipped config reads to the same data as with the
    pure-Python ``SafeLoader``."""
    from ftc_mc.io.yamlfile import SAFE_LOADER, read_yaml

    assert SAFE_LOADER is (yaml.CSafeLoader if yaml.__with_libyaml__ else yaml.SafeLoader)
    files = sorted((ROOT / "configs").glob("*.yaml"))
    assert len(files) > 10
    for path in files:
        assert read_yaml(path) == yaml.load(path.read_text(encoding="utf-8"),
                                            Loader=yaml.SafeLoader), path


def test_sweep_config():
    cfg = load_config(ROOT / "configs" / "sweep.yaml")
    assert len(cfg.campaign.transitions) == 8 and cfg.controller.kind == "nominal"


def test_paper_tables_has_all_eight_rows():
    cfg = load_config(ROOT / "configs" / "paper_tables.yaml")
    assert len(cfg.campaign.transitions) == 8


def test_paper_defaults():
    cfg = Config()
    assert cfg.estimator.t_q == cfg.estimator.t_nx == 25.0
    assert cfg.controller.discount == 0.999
    assert cfg.controller.r_lqr == 0.1
    assert cfg.timing.reconfiguration_period_s == 1.0


def test_scientific_notation_is_a_number(tmp_path):
    # PyYAML reads 1e-3 as a string; validation must turn it into a float.
    p = tmp_path / "c.yaml"
    p.write_text("estimator:\n  sigma_qb: 1e-3\n")
    assert load_config(p).estimator.sigma_qb == 1e-3


@pytest.mark.parametrize("text,field", [
    ("campaign:\n  trials: -5\n", "campaign.trials"),
    ("campaign:\n  trials: many\n", "campaign.trials"),
    ("campaign:\n  bogus: 1\n", "campaign.bogus"),
    ("estimator:\n  t_q: .nan\n", "estimator.t_q"),
    ("estimator:\n  t_nx: .inf\n", "estimator.t_nx"),
    ("estimator:\n  t_q: 0\n", "estimator.t_q"),
    ("campaign:\n  transitions: [elevon_flutter]\n", "campaign.transitions"),
    ("campaign:\n  transitions: []\n", "campaign.transitions"),
    ("timing:\n  fault_time_s: 20.05\n", "timing.fault_time_s"),
    ("timing:\n  duration_s: 5\n", "timing.duration_s"),
    ("draws:\n  engine_lock_range: [0.5, 1.5]\n", "draws.engine_lock_range"),
    ("campaign: 3\n", "campaign"),
    ("- a\n- b\n", "mapping"),
    ("", "empty"),
    ("campaign: [\n", "malformed YAML"),
    ("!!python/object/apply:os.system ['true']\n", "malformed YAML"),
])
def test_bad_config_names_the_field(tmp_path, text, field):
    p = tmp_path / "c.yaml"
    p.write_text(text)
    with pytest.raises(UserError) as exc:
        load_config(p)
    msg = str(exc.value)
    assert field in msg
    assert "\n" not in msg


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(UserError, match="no such file"):
        load_config(tmp_path / "nope.yaml")
    with pytest.raises(UserError, match="not a regular file"):
        load_config(tmp_path)


def test_non_utf8(tmp_path):
    p = tmp_path / "c.yaml"
    p.write_bytes(b"campaign:\n  seed: \xff\xfe\n")
    with pytest.raises(UserError, match="UTF-8"):
        load_config(p)


def test_parse_roundtrip():
    cfg = Config()
    assert parse_config(yaml.safe_load(yaml.safe_dump(cfg.model_dump(mode="json")))) == cfg


AT_DEFAULT_ON_PURPOSE = {("elevon_lock", "campaign", "transitions"),
                         ("paper_scenario", "scenario", "schedule")}
"""Fields a shipped config sets to their default, to say what it runs (a file
must hold at least one section)."""


def test_shipped_configs_set_only_what_they_change():
    from ftc_mc.config import load_any
    from ftc_mc.config.schema import DesignConfig
    from ftc_mc.io.yamlfile import read_yaml

    design_default = DesignConfig().model_dump(mode="json")
    for path in sorted((ROOT / "configs").glob("*.yaml")):
        cfg = load_any(path)
        defaults = type(cfg)().model_dump(mode="json")
        resolved = cfg.model_dump(mode="json")
        for section, fields in read_yaml(path).items():
            if section == "designs":
                for name, design in fields.items():
                    for field in design:
                        assert resolved["designs"][name][field] != design_default[field], (
                            f"{path.name}: designs.{name}.{field} is at its default")
                continue
            for field in fields:
                if (path.stem, section, field) in AT_DEFAULT_ON_PURPOSE:
                    continue
                assert resolved[section][field] != defaults[section][field], (
                    f"{path.name}: {section}.{field} is at its default")
