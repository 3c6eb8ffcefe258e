"""No issue or stop numbers where a user reads: a user cannot follow "issue 25" or
"stop 42" to the project's tracker, so the package, the configs, the docs, the
README, the scripts and the tests say the thing itself or link a docs page."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

PLACES = ("ftc_mc", "configs", "docs", "scripts", "tests", "README.md")
"""What a user reads: folders searched recursively, and single files."""

TEXT_SUFFIXES = {".py", ".md", ".yaml", ".yml", ".toml", ".txt", ".json", ".cfg", ".rst"}

TRACKER = re.compile(
    r"(?<![\w-])issues?\s+#?\d+"                      # issue 24, issues 23 and 25, issue #7
    r"|(?<![\w-])stop\s+#?\d+"                       # stop 42, measured stop 39
    r"|(?<![\w-])stops\s+\d+\s*(?:,|and|to|-)\s*\d+"  # stops 44 and 45, not "stops 9 trials"
    r"|(?:^|(?<=[\s(\[]))#\d{1,4}\b",                 # (#13)
    re.IGNORECASE | re.MULTILINE)
"""A reference to the tracker; "stops 9 more trials" and "#!/usr/bin" are not."""

NAME = re.compile(r"(issue|stop|ticket)_?\d+", re.IGNORECASE)
"""A tracker number in a test file's or a test function's name."""


def text_files():
    for place in PLACES:
        path = ROOT / place
        files = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
        for p in files:
            if p.suffix in TEXT_SUFFIXES and "__pycache__" not in p.parts:
                yield p


def tracker_references(text: str) -> list[tuple[int, str]]:
    """(line number, the match) of every tracker reference in ``text``."""
    return [(text.count("\n", 0, m.start()) + 1, m.group(0)) for m in TRACKER.finditer(text)]


def test_the_pattern_finds_tracker_numbers_and_leaves_phrases():
    found = [m for _, m in tracker_references(
        "(issue 13) issue 26, item 5; issues 23 and 25; measured stop 42;\n"
        "at Stop 45; stops 44 and 45; see #12.")]
    assert found == ["issue 13", "issue 26", "issues 23", "stop 42", "Stop 45",
                     "stops 44 and 45", "#12"]
    assert tracker_references(
        "`engine_unlock` stops 9 more trials; the issue is the lag; stop at 4 s;\n"
        "#!/usr/bin/env python; tissue 3; non-stop 2 laps") == []


def test_no_tracker_numbers_in_the_text_a_user_reads():
    bad = [f"{p.relative_to(ROOT)}:{line}: {m}"
           for p in text_files() if p != Path(__file__).resolve()
           for line, m in tracker_references(p.read_text(errors="replace"))]
    assert not bad, (f"{len(bad)} issue or stop numbers (say the thing itself, or link a "
                     "docs page):\n" + "\n".join(bad[:60]))


def test_no_tracker_numbers_in_test_names():
    bad = []
    for p in sorted((ROOT / "tests").rglob("test_*.py")):
        if NAME.search(p.name):
            bad.append(str(p.relative_to(ROOT)))
        for node in ast.walk(ast.parse(p.read_text())):
            if (isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
                    and node.name.lower().startswith("test") and NAME.search(node.name)):
                bad.append(f"{p.relative_to(ROOT)}::{node.name}")
    assert not bad, "tracker numbers in test names: " + ", ".join(bad)
