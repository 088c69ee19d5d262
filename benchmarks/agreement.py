"""Three-solver agreement on every shipped case: the table behind ``[compare]``'s defaults.

    python benchmarks/agreement.py OUT

runs ``wearcheck compare`` on each shipped case into ``OUT/<case>`` (a case whose
directory is there already is read, not re-run) and prints, per case and solver
pair, the largest difference of each check over the stages, relative to the
stage's own scale as the verdict judges it, with the stage where it occurs. Every
pair of solvers is listed, the one without the reference too (its differences
are computed from the run directories as ``compare`` computes the others).
A case that cannot be compared (fewer than two solvers can run it) is listed
with the reason.
"""

from __future__ import annotations

import json
import sys
from itertools import combinations
from pathlib import Path

import wearcheck
from wearcheck import cases
from wearcheck.cases import RunResult
from wearcheck import rundir
from wearcheck.comparisons.analysis import metrics
from wearcheck.studies import compare as compare_mod


def read_result(path) -> tuple:
    """A run directory as (case, RunResult)."""
    run = rundir.Run(path)
    st = run.stages
    return run.case, RunResult(history=run.history, stage_s=st["s"], r=st["r"], f=st["f"],
                               p=st["p"], solve_seconds=0.0, info=run.meta.get("info", {}))


def rows_of(directory: Path) -> list[list[str]]:
    m = json.loads((directory / "metrics.json").read_text())
    results = {}
    for name in m["solvers"]:
        case, results[name] = read_result(directory / name)
    ref = m["reference"]
    others = [n for n in m["solvers"] if n != ref]
    pairs = [(ref, n) for n in others] + list(combinations(others, 2))
    rows = []
    for a, b in pairs:
        pair = compare_mod.analyse(case, {a: results[a], b: results[b]}, a)["pairs"][b]
        cells, floors = [], 0
        for c in metrics.CHECKS:
            checks = [(st["checks"][c.column], st["index"]) for st in pair["stages"]]
            floors += sum(x["scale_from"] == "floor" for x, _ in checks)
            x, k = max(checks, key=lambda t: t[0]["value"])
            cells.append(f"{100 * x['value']:.2g} % (stage {k})"
                         + ("" if x["passed"] else f" > {100 * x['tolerance']:g} %"))
        skipped = "; ".join(f"{n} skipped" for n in m.get("skipped", {}))
        rows.append([directory.name, f"{b} vs {a}", str(pair["stages_compared"])] + cells
                    + ["pass" if pair["passed"] else "FAIL", str(floors), skipped])
    # the truncated paraboloid: each solver against the quadrature of paper Eqs. 13/19
    for name, row in m.get("truncated_reference", {}).get("solvers", {}).items():
        c = row["checks"]
        cells = ["—"] + [f"{100 * c[k]['value']:.2g} %" for k in
                         ("force", "pressure_interior_max", "contact_radius")]
        rows.append([directory.name, f"{name} vs quadrature", "1"] + cells
                    + ["pass" if row["passed"] else "FAIL",
                       str(sum(x["scale_from"] == "floor" for x in c.values())), ""])
    return rows


def main(out) -> None:
    out = Path(out)
    header = ["case", "pair", "stages", "profile", "force", "pressure", "contact radius",
              "verdict", "floors used", "note"]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for name, path in cases.shipped_cases().items():
        directory = out / name
        if not (directory / "metrics.json").is_file():
            try:
                wearcheck.compare(str(path), directory, render=False)
            except cases.CaseError as exc:
                lines.append(f"| {name} | — | — | not compared: {exc} |" + " |" * 6)
                continue
        lines += ["| " + " | ".join(r) + " |" for r in rows_of(directory)]
    print("\n".join(lines))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
