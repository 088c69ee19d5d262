"""Pages generated from the code at every docs build, so that they cannot go stale.

Writes into ``docs/_generated/`` (not kept in git), included by the pages:

- ``case-keys.md``: every case key with unit, default and meaning (``cases/schema.py``);
- ``case-rules.md``: every rule between keys, and who checks it (``cases/rules.py``);
- ``layout-NAME.md``: the tables of what a run or a comparison writes
  (``comparisons/layout.py``);
- ``cli.md``: ``wearcheck --help`` and every subcommand's help, from the argument parser.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

#: the tutorials in reading order (the rest follow by name)
TUTORIALS = ("lab_rig_to_case.py", "friction_and_wear.py", "mu_sweep_on_dask.py",
             "fem_fields_in_paraview.py")


def tutorial_order(filename: str):
    """sphinx-gallery's sort key: TUTORIALS first, in their order."""
    name = Path(filename).name
    return (TUTORIALS.index(name) if name in TUTORIALS else len(TUTORIALS), name)


def cli_reference() -> str:
    """Every command's ``--help``, as the terminal shows it (80 columns)."""
    from wearcheck.comparisons.cli import build_parser
    saved = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "80"
    try:
        parser = build_parser()
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parts = ["## `wearcheck`", "", "```text", parser.format_help().rstrip(), "```", ""]
        for name, p in sub.choices.items():
            parts += [f"## `wearcheck {name}`", "", "```text", p.format_help().rstrip(), "```", ""]
    finally:
        if saved is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = saved
    return "\n".join(parts)


def generated_pages() -> dict[str, str]:
    """File name in ``_generated/`` -> Markdown."""
    from wearcheck.cases import key_reference, rules
    from wearcheck.comparisons import layout
    pages = {"case-keys.md": key_reference() + "\n", "case-rules.md": rules.reference() + "\n",
             "cli.md": cli_reference()}
    for name, table in layout.doc_tables().items():
        pages[f"layout-{name}.md"] = table + "\n"
    return pages


def write_generated(app) -> None:
    out = Path(app.srcdir) / "_generated"
    out.mkdir(exist_ok=True)
    for name, text in generated_pages().items():
        path = out / name
        # rewritten only when changed, so that Sphinx re-reads only what changed
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")


def setup(app):
    app.connect("builder-inited", write_generated)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
