"""docs/reference/config.md is current, and the schema's descriptions are one line."""

import importlib.util
import inspect
import re
from pathlib import Path

from pydantic import BaseModel

from ftc_mc.config import schema

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "reference" / "config.md"
MAX_DESCRIPTION = 150
"""Longest field description [characters], its docs pointer included."""


def _script():
    path = ROOT / "scripts" / "maintenance" / "make_config_reference.py"
    spec = importlib.util.spec_from_file_location("make_config_reference", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _fields():
    """``(model.field, description)`` of every field of the schema's models, but
    the section fields of the two file models (their sections' docstrings say it)."""
    for _, model in inspect.getmembers(schema, inspect.isclass):
        if not issubclass(model, BaseModel) or model.__module__ != schema.__name__:
            continue
        for name, info in model.model_fields.items():
            if model in (schema.Config, schema.ScenarioConfig) and name != "designs":
                continue
            yield f"{model.__name__}.{name}", info.description or ""


def test_reference_page_is_current():
    current = PAGE.read_text(encoding="utf-8")
    script = _script()
    assert script.NOTES_MARKER in current
    assert script.page(current) == current, (
        "docs/reference/config.md is stale: run "
        ".venv/bin/python scripts/maintenance/make_config_reference.py")


def test_reference_page_opens_with_how_to_read_it():
    lines = PAGE.read_text(encoding="utf-8").splitlines()
    assert lines[0] == "# Configuration reference"
    assert lines[2].startswith("How to read this page") and "ftc-mc config show" in lines[3]


def test_every_field_has_a_one_line_description():
    fields = list(_fields())
    assert len(fields) > 100
    for name, doc in fields:
        assert doc.strip(), f"{name}: no description"
        assert "\n" not in doc, f"{name}: the description is more than one line"
        assert len(doc) <= MAX_DESCRIPTION, f"{name}: {len(doc)} characters"


def test_description_pointers_lead_to_a_notes_section():
    page = PAGE.read_text(encoding="utf-8")
    slugs = {re.sub(r"[^\w\- ]", "", h.strip("# ").lower()).replace(" ", "-")
             for h in page.splitlines() if h.startswith("#")}
    pointers = {m for _, doc in _fields()
                for m in re.findall(r"docs/reference/config\.md#([\w-]+)", doc)}
    assert pointers and pointers <= slugs, pointers - slugs


def test_no_ticket_numbers_in_the_config_package_configs_and_reference():
    ticket = re.compile(r"\b(issue|stop)s? \d+", re.IGNORECASE)
    files = [*(ROOT / "ftc_mc" / "config").glob("*.py"), *(ROOT / "configs").glob("*.yaml"), PAGE]
    for path in files:
        for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            assert not ticket.search(line), f"{path.relative_to(ROOT)}:{i}: {line.strip()}"
