"""``wearcheck compare CASE [--out DIR]``: every solver that supports the case against a
reference solver (default MDR), with figures, metrics and a report.

Exit code 0 when every check is within the case's [compare] tolerances, 1 when
the comparison fails (DIR is still written, with the failing verdict).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wearcheck import registry
from wearcheck.comparisons.present.compare_report import print_summary
from wearcheck.studies.compare import compare
from wearcheck.studies.sphere_sweep import SPHERE_RATIOS
from ._common import (add_case_arguments, case_notes, load_case, output, print_json,
                      verdict)
from wearcheck.comparisons.analysis import diagnosis


def _ratios(text):
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': expected numbers separated by commas, "
                                         "e.g. 0.005,0.01,0.02") from None
    if not values or any(not 0 < v < 1 for v in values):
        raise argparse.ArgumentTypeError(f"'{text}': each a0/R must be in (0, 1)")
    return values


def _names(text):
    return [n.strip() for n in text.split(",") if n.strip()]


def add_parser(sub):
    p = sub.add_parser("compare", help="run every solver that supports a case and compare them",
                       description=__doc__)
    add_case_arguments(p)
    p.add_argument("--solvers", type=_names, default=None, metavar="NAME,NAME,...",
                   help="the solvers to compare (default: every one that supports the case; "
                        "registered: " + ", ".join(registry.names()) + ")")
    p.add_argument("--reference", default=None, metavar="NAME",
                   help="the solver the others are compared with (default: mdr, or the "
                        "first exact solver where mdr solved an approximation)")
    p.add_argument("--out", type=Path, default=None,
                   help="output directory (default: runs/<case name>)")
    p.add_argument("--edge-study", action="store_true",
                   help="also run both solvers on a coarser and a finer grid and a smaller "
                        "step, and say whether the edge pressure peak is converged")
    p.add_argument("--sphere-sweep", action="store_true",
                   help="also run the FEM unworn at several a0/R and compare its force with "
                        "the half-space value")
    p.add_argument("--sphere-ratios", type=_ratios, default=SPHERE_RATIOS, metavar="R1,R2,...",
                   help="a0/R of the sphere sweep (default: "
                        + ",".join(f"{v:g}" for v in SPHERE_RATIOS) + ")")
    p.add_argument("--no-render", action="store_true",
                   help="do not render pictures of the run directories")
    p.add_argument("--json", action="store_true",
                   help="print the verdict on stdout as JSON (passed, reference, each "
                        "solver's verdict, the skipped solvers, the most likely fix, the "
                        "path of metrics.json) instead of the summary")
    return p


def main(args) -> int:
    case = load_case(args)
    out = output(args, Path("runs") / args.case.stem)
    m = compare(case, out, solvers=args.solvers, reference_solver=args.reference,
                edge=args.edge_study, sphere=args.sphere_sweep,
                sphere_ratios=args.sphere_ratios, quiet=args.quiet,
                render=not args.no_render)
    case_notes(args, case)
    if args.json:
        print_json(verdict(m, out))
    elif not args.quiet:
        print_summary(m, out)
        for note in m.get("render_notes", []):
            print(f"note: {note}", file=sys.stderr)
        if "edge_study" in m:
            print(f"edge peak: {m['edge_study']['summary']}", file=sys.stderr)
    if not m["passed"]:
        print(f"wearcheck compare: the comparison FAILED (see {out}/report.md)", file=sys.stderr)
        if args.quiet and m.get("diagnosis"):   # the summary, which names it, was not printed
            print(f"most likely fix: {diagnosis.sentence(m['diagnosis'])}", file=sys.stderr)
        return 1
    return 0

