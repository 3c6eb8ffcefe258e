"""``ftc-mc config show [CONFIG]``: the resolved config as commented YAML."""

from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

from ftc_mc.cli import cli
from ftc_mc.config import Config, ScenarioConfig, load_any

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = sorted((ROOT / "configs").glob("*.yaml"))


def _show(*args):
    return CliRunner().invoke(cli, ["config", "show", *map(str, args)])


def _field_lines(text):
    """``(section, field, comment)`` of every field line of a shown config."""
    out, section = [], None
    for line in text.splitlines():
        if line.startswith("#") or not line.strip() or line.startswith("    "):
            continue
        if not line.startswith(" "):
            section = line.split(":")[0]
        elif not line.lstrip().startswith("- "):
            name = line.strip().split(":")[0]
            out.append((section, name, line.partition("  # ")[2]))
    return out


@pytest.mark.parametrize("model,args", [(Config, ()), (ScenarioConfig, ("--scenario",))])
def test_defaults_every_field_with_a_description(model, args):
    res = _show(*args)
    assert res.exit_code == 0, res.output
    assert model.model_validate(yaml.safe_load(res.output)) == model()
    shown = {(s, f): doc for s, f, doc in _field_lines(res.output)}
    for section, info in model.model_fields.items():
        sub = getattr(model(), section)
        if isinstance(sub, dict):  # designs: empty, an example entry commented out
            assert f"{section}: {{}}  # " in res.output
            continue
        for name in type(sub).model_fields:
            doc = shown[(section, name)]
            assert doc and "\n" not in doc, (section, name)
    assert " [default: " not in "\n".join(res.output.splitlines()[3:])


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_every_shipped_config_reads_back_from_its_show(path):
    res = _show(path)
    assert res.exit_code == 0, res.output
    cfg = load_any(path)
    assert type(cfg).model_validate(yaml.safe_load(res.output)) == cfg
    assert res.output.startswith(f"# ftc-mc config show: {path}, a ")


def test_changed_values_say_their_default():
    out = _show(ROOT / "configs" / "sweep.yaml").output
    assert "  kind: nominal  # " in out and "[default: reconfiguring]" in out
    out = _show(ROOT / "configs" / "paper_scenario.yaml").output
    assert "a scenario config (ftc-mc scenario)" in out
    assert "    - {time_s: 10.0, fault: lock, actuator: engine, position: 0.2}" in out


def test_designs_are_shown_resolved():
    out = _show(ROOT / "configs" / "robust_moderate.yaml").output
    assert "  robust_excited:  # " in out and "<<" not in out
    assert "    innovation_clip: 4.0  # " in out


def test_scenario_flag_reads_a_file_as_a_scenario(tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text("plant:\n  kind: nonlinear\n")
    assert "a campaign config" in _show(p).output
    res = _show("--scenario", p)
    assert res.exit_code == 0 and "a scenario config" in res.output
    assert ScenarioConfig.model_validate(yaml.safe_load(res.output)).plant.kind == "nonlinear"


@pytest.mark.parametrize("text,field", [
    ("estimator:\n  t_q: -1\n", "estimator.t_q"),
    ("campaign:\n  bogus: 1\n", "campaign.bogus"),
    ("scenario:\n  duration_s: 0\n", "scenario.duration_s"),
    ("campaign: [\n", "malformed YAML"),
])
def test_bad_config_one_line_exit_2(tmp_path, text, field):
    p = tmp_path / "c.yaml"
    p.write_text(text)
    res = _show(p)
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ftc-mc: error: ") and field in lines[0]
    assert res.stdout == ""


def test_missing_file_exit_2(tmp_path):
    res = _show(tmp_path / "nope.yaml")
    assert res.exit_code == 2 and "no such file" in res.stderr
