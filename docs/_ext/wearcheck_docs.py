"""Pages generated from the code at every docs build, so that they cannot go stale.

Writes into ``docs/_generated/`` (not kept in git), included by the pages:

- ``case-keys.md``: every case key with unit, default and meaning (``cases/schema.py``);
- ``case-rules.md``: every rule between keys, and who checks it (``cases/rules.py``);
- ``layout-NAME.md``: the tables of what a run or a comparison writes
  (``wearcheck/layout.py``);
- ``cli.md``: ``wearcheck --help`` and every subcommand's help, from the argument parser;
- ``reference-bands.md`` and ``reference-NAME.png``: the certified references' error
  bands, orders and spreads, and their curves, from the shipped files
  (``references/data``).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

#: the tutorials in reading order (the rest follow by name)
TUTORIALS = ("lab_rig_to_case.py", "g133_sheet_to_K.py", "friction_and_wear.py",
             "mu_sweep_on_dask.py", "fem_fields_in_paraview.py", "verify_an_fe_result.py")


def tutorial_order(filename: str):
    """sphinx-gallery's sort key: TUTORIALS first, in their order."""
    name = Path(filename).name
    return (TUTORIALS.index(name) if name in TUTORIALS else len(TUTORIALS), name)


def cli_reference() -> str:
    """Every command's ``--help``, as the terminal shows it (80 columns)."""
    from wearcheck.cli import build_parser
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
    from wearcheck import layout
    pages = {"case-keys.md": key_reference() + "\n", "case-rules.md": rules.reference() + "\n",
             "cli.md": cli_reference()}
    for name, table in layout.doc_tables().items():
        pages[f"layout-{name}.md"] = table + "\n"
    return pages


def _cell(x) -> str:
    return "—" if x is None or x != x else f"{x:.1e}"


def reference_bands() -> str:
    """Per shipped reference: how it was made, its largest band per check (relative to
    the stage's own scale, as the verdict judges), the orders observed and the other
    solvers' largest differences from it."""
    from wearcheck.comparisons.analysis import metrics
    from wearcheck.references import certified
    checks = certified.BAND_CHECKS
    labels = [metrics.CHECK_BY_COLUMN[c].label for c in checks]
    parts = ["| reference | method | " + " | ".join(labels) + " |",
             "|---|---|" + "---|" * len(checks)]
    details = []
    for name in certified.names():
        ref = certified.load(name)
        rows = ref.relative_bands()
        worst = {c: max(row[c] for row in rows) for c in checks}
        solver = ref.meta.get("solver", "")
        levels = "; ".join(f"{k} {v['key']} {', '.join(f'{x:g}' for x in v['levels'])}"
                           for k, v in (ref.meta.get("dimensions") or {}).items())
        parts.append(f"| `{name}` | {solver}{': ' + levels if levels else ''} | "
                     + " | ".join(_cell(worst[c]) for c in checks) + " |")
        lines = [f"**{name}**: {len(ref.stage_s)} stored stage(s), "
                 f"{len(ref.history['s'])} history samples."]
        orders = ref.meta.get("orders") or {}
        for dim, per in orders.items():
            lines.append(f"Observed order ({dim}): " + ", ".join(
                f"{metrics.CHECK_BY_COLUMN[c].label} {v:.2f}" for c, v in per.items()
                if v == v) + ".")
        mdr = ref.meta.get("mdr_against_closed_form")
        if mdr:
            lines.append("MDR against the closed form at N = "
                         + ", ".join(str(int(r["elements"])) for r in mdr["levels"])
                         + ": force " + ", ".join(f"{r['force']:.1e}" for r in mdr["levels"])
                         + " F0, interior pressure "
                         + ", ".join(f"{r['pressure']:.1e}" for r in mdr["levels"]) + " p0.")
        for solver_name, sp in (ref.meta.get("spread") or {}).items():
            if "skipped" in sp:
                lines.append(f"{solver_name.upper()}: not run ({sp['skipped']}).")
                continue
            worst_sp = {c: max(v) for c, v in sp.get("checks", {}).items() if v}
            settings = ", ".join(f"{k} = {v}" for k, v in (sp.get("settings") or {}).items())
            lines.append(f"{solver_name.upper()} ({settings}) against it, largest over the "
                         "case's stages: " + ", ".join(
                             f"{metrics.CHECK_BY_COLUMN[c].label} {v:.1e}"
                             for c, v in worst_sp.items())
                         + (" (an approximation of the case)" if sp.get("approximate")
                            else "") + ".")
        prov = ref.meta.get("provenance") or {}
        if prov:
            lines.append(f"Made by `{prov.get('command')}` (wearcheck "
                         f"{prov.get('wearcheck_version')}, revision "
                         f"{prov.get('git_revision')}, {prov.get('created')}, "
                         f"{ref.meta.get('seconds', float('nan')):.0f} s).")
        details.append(" ".join(lines))
    return "\n".join(parts) + "\n\n" + "\n\n".join(details) + "\n"


def reference_figures(out: Path) -> None:
    """reference-NAME.png for each shipped reference (redrawn when its file is newer)."""
    from wearcheck.comparisons.present.reference_figure import draw
    from wearcheck.references import certified
    for name in certified.names():
        src = certified.DATA_DIR / f"{name}.npz"
        png = out / f"reference-{name}.png"
        if not png.is_file() or png.stat().st_mtime < src.stat().st_mtime:
            draw(certified.load(name), png)


def write_generated(app) -> None:
    out = Path(app.srcdir) / "_generated"
    out.mkdir(exist_ok=True)
    pages = generated_pages()
    pages["reference-bands.md"] = reference_bands()
    for name, text in pages.items():
        path = out / name
        # rewritten only when changed, so that Sphinx re-reads only what changed
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
    reference_figures(out)


def setup(app):
    app.connect("builder-inited", write_generated)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
