"""The project's own documentation: citations of docs/theory.md point at sections that
exist, and nothing cites notes outside the repository."""

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
THEORY = REPO / "docs" / "theory.md"
SOURCES = [p for pattern in ("*.py", "*.toml", "*.md")
           for p in REPO.rglob(pattern)
           if not any(part in {".git", "build", "dist", "runs", ".venv", "node_modules"}
                      or part.endswith(".egg-info") for part in p.relative_to(REPO).parts)]

pytestmark = pytest.mark.skipif(not THEORY.is_file(), reason="not run from a source checkout")


def _sections():
    return {int(m) for m in re.findall(r"^## §(\d+) ", THEORY.read_text(encoding="utf-8"),
                                       flags=re.M)}


def test_theory_sections_are_numbered_in_order():
    numbers = [int(m) for m in re.findall(r"^## §(\d+) ", THEORY.read_text(encoding="utf-8"),
                                          flags=re.M)]
    assert numbers == list(range(1, len(numbers) + 1))


def test_every_citation_of_the_theory_names_an_existing_section():
    sections = _sections()
    cited = 0
    for path in SOURCES:
        text = path.read_text(encoding="utf-8", errors="replace")
        # "docs/theory.md §4", "§7-8", "§7, §12"
        for m in re.finditer(r"docs/theory\.md ((?:§\d+(?:[-–]\d+)?(?:, )?)+)", text):
            for a, b in re.findall(r"§(\d+)(?:[-–](\d+))?", m.group(1)):
                for n in range(int(a), int(b or a) + 1):
                    cited += 1
                    assert n in sections, f"{path.relative_to(REPO)} cites docs/theory.md §{n}"
    assert cited > 10  # the code does cite it


# the working notes outside the repository, spelled so that this file does not cite them
OUTSIDE = ("physics" + ".md", "../" + "shared", "/work/" + "shared")


def test_nothing_cites_notes_outside_the_repository():
    offenders = [str(p.relative_to(REPO)) for p in SOURCES
                 if any(name in p.read_text(encoding="utf-8", errors="replace")
                        for name in OUTSIDE)]
    assert offenders == []
