"""docs/reference/cli.md is the command line's own --help: it fails here when stale."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "maintenance" / "make_cli_reference.py"


def _script():
    spec = importlib.util.spec_from_file_location("make_cli_reference", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_cli_reference_is_current():
    mod = _script()
    assert mod.PAGE.read_text() == mod.render(), (
        "docs/reference/cli.md is stale: run "
        ".venv/bin/python scripts/maintenance/make_cli_reference.py")


def test_cli_reference_lists_every_command():
    import click

    from ftc_mc.cli import cli

    text = (ROOT / "docs" / "reference" / "cli.md").read_text()
    ctx = click.Context(cli, info_name="ftc-mc")
    for name in cli.list_commands(ctx):
        assert f"## `ftc-mc {name}`" in text
