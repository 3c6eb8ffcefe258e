"""Figures a reader can check: a number the README or a guide quotes from a
findings page is on that page, and every docs page is listed in the index.

What ``test_linked_figures_are_on_the_page`` checks. Over ``README.md`` and
``docs/guides/*.md`` (fenced code blocks left out), every Markdown link
``[text](target)`` whose target is a page of ``docs/findings/`` and whose text
holds a number: each number of the text must appear, as written, on the
linked page. "As written" means as a whole number token: ``27`` is not found
in ``27.1`` nor ``9`` in ``19``; ``0.8`` is found in ``0.8 %`` and in
``0.8-1.7``. Thousands separators are normalised on both sides (``24,048``,
``21 600`` and ``24048`` are one number), and so are non-breaking and thin
spaces. Units, signs and the words around a number are not compared: the test
catches a figure that is not on the page it links to, not a figure quoted in
the wrong place of it.

``test_readme_figures_are_in_the_summary`` is stricter for the README: a
number of a link text must be in the linked page's summary (its text before
the first ``##`` section), or, when the link names a section (``page.md#anchor``),
in that section. The rows of the README's table of the paper's Tables 2-3
beside ours are left to the whole-page test: it quotes every row of the page's full table,
which no summary of 15 lines holds.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from test_docs_layout import CODE_BLOCK, slug

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
FINDINGS = DOCS / "findings"
SOURCES = [ROOT / "README.md", *sorted((DOCS / "guides").glob("*.md"))]

LINK = re.compile(r"\[([^\]\n]*)\]\(([^)\s]+)\)")
NUMBER = re.compile(r"(?<![\w.])\d+(?:\.\d+)?(?:e[+-]?\d+)?(?![\w])")
"""A number token: digits, an optional decimal part and exponent (``3.4e4``)."""

TABLES_2_3 = "### The paper's Tables 2-3 beside ours"
"""The README section whose table is the whole of a findings page's table."""


def normalise(text: str) -> str:
    """Non-breaking and thin spaces to spaces, thousands separators dropped."""
    text = text.replace("\u00a0", " ").replace("\u202f", " ").replace("\u2009", " ")
    return re.sub(r"(?<![\d.])(\d{1,3})((?:[, ]\d{3})+)(?![\d.])",
                  lambda m: m.group(1) + re.sub(r"[, ]", "", m.group(2)), text)


def numbers(text: str) -> list[str]:
    return NUMBER.findall(normalise(text))


def holds(text: str, number: str) -> bool:
    """``number`` appears in ``text`` as a whole number token."""
    pattern = r"(?<![\w.])" + re.escape(number) + r"(?![\w]|\.\d)"
    return re.search(pattern, normalise(text)) is not None


def summary(page: Path) -> str:
    """A findings page's text before its first ``##`` section."""
    return re.split(r"^## ", page.read_text(), maxsplit=1, flags=re.M)[0]


def section(page: Path, anchor: str) -> str:
    """The text of the heading with this anchor, up to the next heading of the
    same or a higher level."""
    lines = page.read_text().splitlines()
    for i, line in enumerate(lines):
        m = re.match(r"^(#+)\s+(.*)$", line)
        if m and slug(m.group(2)) == anchor:
            level = len(m.group(1))
            end = next((j for j in range(i + 1, len(lines))
                        if (h := re.match(r"^(#+)\s", lines[j])) and len(h.group(1)) <= level),
                       len(lines))
            return "\n".join(lines[i:end])
    return ""


def findings_links(page: Path):
    """``(text, target page, anchor, line number, heading above, line)`` of each link to a findings page
    whose text holds a number."""
    text = CODE_BLOCK.sub(lambda m: "\n" * m.group(0).count("\n"), page.read_text())
    lines = text.splitlines()
    heading = ""
    for n, line in enumerate(lines, 1):
        if line.startswith("#"):
            heading = line
        for m in LINK.finditer(line):
            label, target = m.groups()
            path, _, anchor = target.partition("#")
            if not path or re.match(r"^[a-z]+:", path):
                continue
            dest = (page.parent / path).resolve()
            if dest.parent != FINDINGS.resolve() or not numbers(label):
                continue
            yield label, dest, anchor, n, heading, line


@pytest.mark.parametrize("page", SOURCES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_linked_figures_are_on_the_page(page):
    """Every number of a link text to a findings page is on that page."""
    missing = [f"line {n}: {num!r} of [{label}] not in {dest.name}"
               for label, dest, _, n, _, _ in findings_links(page)
               for num in numbers(label) if not holds(dest.read_text(), num)]
    assert not missing, f"{page.relative_to(ROOT)}:\n" + "\n".join(missing)


def test_readme_figures_are_in_the_summary():
    """A README figure is in the linked page's summary, or in the section the
    link names."""
    missing = []
    for label, dest, anchor, n, heading, line in findings_links(ROOT / "README.md"):
        if heading.startswith(TABLES_2_3) and line.startswith("|"):
            continue
        where = section(dest, anchor) if anchor else summary(dest)
        for num in numbers(label):
            if not holds(where, num):
                missing.append(f"line {n}: {num!r} of [{label}] not in "
                               f"{dest.name}{'#' + anchor if anchor else ' summary'}")
    assert not missing, "README:\n" + "\n".join(missing)


def test_index_lists_every_page():
    """docs/README.md links every Markdown page under docs/."""
    index = DOCS / "README.md"
    text = CODE_BLOCK.sub("", index.read_text())
    linked = {(index.parent / m.group(2).partition("#")[0]).resolve()
              for m in LINK.finditer(text)}
    pages = {p.resolve() for p in DOCS.rglob("*.md")} - {index.resolve()}
    unlisted = sorted(p.relative_to(DOCS.resolve()).as_posix() for p in pages - linked)
    assert not unlisted, f"docs/README.md does not list: {unlisted}"


def test_number_matching():
    """The matching rule of this module's docstring."""
    assert numbers("14 of 24,048 (0.058 %)") == ["14", "24048", "0.058"]
    assert numbers("21 600 flights, 3.4e4 per hour") == ["21600", "3.4e4"]
    assert holds("0.8 % mean", "0.8") and holds("85-89 %", "89")
    assert not holds("27.1 % unexplained", "27")
    assert not holds("19 seeds", "9") and not holds("1.7", "7")
