"""The project's own documentation: citations of docs/theory.md point at sections that
exist, and nothing cites notes outside the repository."""

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
THEORY = REPO / "docs" / "theory.md"
SOURCES = [p for pattern in ("*.py", "*.toml", "*.md")
           for p in REPO.rglob(pattern)
           if not any(part in {".git", "build", "_build", "_generated", "tutorials", "dist",
                               "runs", ".venv", "node_modules"}
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


README = REPO / "README.md"
DOCS = REPO / "docs"


def test_readme_is_an_entry_point():
    text = README.read_text(encoding="utf-8")
    # issue 27: at most ~12 KB (it was 86 KB); the rest lives in docs/
    assert len(text.encode("utf-8")) <= 12 * 1024
    # the two set-up commands, unchanged, and the one command that builds the docs
    # (the first installs the extras the main job needs: docs/getting-started.md)
    for command in ('pip install ".[fem,plot,vtk]" && wearcheck compare cases/paper.toml '
                    '--out runs/paper',
                    'pip install -e ".[test]" && python -m pytest -q',
                    'pip install -e ".[docs]" && python -m sphinx -W --keep-going -b html '
                    'docs docs/_build/html'):
        assert command in text, command
    # every relative link of the README reaches a file of the repository
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text)
    local = [link for link in links if "://" not in link]
    assert len(local) > 15
    for link in local:
        assert (REPO / link).exists(), link


def test_every_command_is_in_the_readme_table():
    from wearcheck.cli import build_parser
    import argparse
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    table = README.read_text(encoding="utf-8").split("## Commands", 1)[1]
    for name in sub.choices:
        assert f"`wearcheck {name} " in table, name


def _toctree_entries():
    entries = set()
    for page in DOCS.rglob("*.md"):
        text = page.read_text(encoding="utf-8")
        for block in re.findall(r"```\{toctree\}\n(.*?)```", text, re.S):
            for line in block.splitlines():
                line = line.strip()
                if line and not line.startswith(":"):
                    entries.add((page.parent / line).relative_to(DOCS).as_posix())
    return entries


def test_every_docs_page_is_in_the_site():
    # Sphinx (-W) fails on a page outside every toctree; this says so without building
    entries = _toctree_entries()
    pages = {p.relative_to(DOCS).with_suffix("").as_posix() for p in DOCS.rglob("*.md")
             if not p.relative_to(DOCS).parts[0].startswith("_")
             and p.relative_to(DOCS).parts[0] != "tutorials"} - {"index"}
    assert pages - entries == set()


def test_cli_reference_has_every_command():
    import sys
    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        import wearcheck_docs
    finally:
        sys.path.remove(str(DOCS / "_ext"))
    from wearcheck.cli import build_parser
    import argparse
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    text = wearcheck_docs.cli_reference()
    for name, p in sub.choices.items():
        assert f"## `wearcheck {name}`" in text
        # each option the parser knows appears in its help
        for action in p._actions:
            for flag in action.option_strings:
                assert flag in text, (name, flag)
    # every tutorial the gallery orders is an example script
    assert {p.name for p in (REPO / "examples").glob("*.py")} == set(wearcheck_docs.TUTORIALS)
