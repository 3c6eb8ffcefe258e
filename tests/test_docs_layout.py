"""The docs stay navigable: every relative link and anchor leads somewhere, no
page outgrows a reader, and each findings page opens with its summary.

Limits are those of the docs' own layout (``docs/README.md``): README at most
300 lines, any docs page at most 600, a findings page's summary (the text
before its first ``##`` section) at most 15 lines.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = sorted([ROOT / "README.md", *DOCS.rglob("*.md"), *(ROOT / "scripts").rglob("*.md")])
LINK = re.compile(r"\]\(([^)\s]+)\)")
CODE_BLOCK = re.compile(r"^(```|~~~).*?^\1", re.M | re.S)


def slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading: lower case, punctuation but
    hyphens and underscores dropped, spaces to hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    text = CODE_BLOCK.sub("", page.read_text())
    return {slug(m.group(1)) for m in re.finditer(r"^#+\s+(.*)$", text, re.M)}


def links(page: Path):
    text = CODE_BLOCK.sub("", page.read_text())
    text = re.sub(r"`[^`\n]*`", "", text)  # inline code is not a link
    for m in LINK.finditer(text):
        target = m.group(1)
        if not re.match(r"^[a-z]+:", target):
            yield target


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_links_resolve(page):
    """A relative link names a file of the tree and, with ``#``, a heading of it."""
    bad = []
    for target in links(page):
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            bad.append(f"{target}: no such file")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            bad.append(f"{target}: no heading with this anchor")
    assert not bad, f"{page.relative_to(ROOT)}: " + "; ".join(bad)


def test_slug_matches_github():
    """The anchor rule on headings of this tree's kind (checked by hand
    against GitHub's rendering of docs/findings/)."""
    assert slug("Survival after a lock") == "survival-after-a-lock"
    assert slug("`robust_excited`: `robust_clip` with a periodic excitation") == \
        "robust_excited-robust_clip-with-a-periodic-excitation"
    assert slug("c0 and c1 (coupled): measured, not adopted") == \
        "c0-and-c1-coupled-measured-not-adopted"


def test_page_lengths():
    """README at most 300 lines, every docs page at most 600."""
    assert len((ROOT / "README.md").read_text().splitlines()) <= 300
    long = {p.relative_to(ROOT).as_posix(): n for p in DOCS.rglob("*.md")
            if (n := len(p.read_text().splitlines())) > 600}
    assert not long, f"pages over 600 lines: {long}"


@pytest.mark.parametrize("page", sorted((DOCS / "findings").glob("*.md")),
                         ids=lambda p: p.name)
def test_findings_open_with_summary(page):
    """A findings page opens with a summary of at most 15 lines, before its
    first section."""
    lines = page.read_text().splitlines()
    assert lines[0].startswith("# ")
    body = []
    for line in lines[1:]:
        if line.startswith("## "):
            break
        body.append(line)
    paragraph = "\n".join(body).strip().split("\n\n")[0]
    assert paragraph.startswith("**Summary.**"), f"{page.name} opens without a summary"
    assert len(paragraph.splitlines()) <= 15, f"{page.name}: summary over 15 lines"
