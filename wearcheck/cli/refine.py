"""``wearcheck refine CASE.toml --solver mdr|fem|bem --out DIR``: a refinement study on Dask.

Runs the case at a sequence of resolutions (and optionally sliding steps),
one run directory per level in DIR, and writes ``refinement-<solver>.csv`` and
``.json`` (differences to the finest level, observed order, Richardson's
estimate, coarsest converged level) and the figures ``fig4_profiles.png``,
``fig4_force.png``, ``convergence.png`` and ``cost.png``. MDR and FEM studies
run into the same DIR coexist: ``refinement.csv`` holds every study found there
(a ``solver`` column first), and the figures show them all.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from wearcheck import registry

from ._common import (add_case_arguments, add_cluster_arguments, add_json_argument,
                      case_notes, load_case, print_json)
from . import Terminated


def add_parser(sub):
    p = sub.add_parser("refine", help="refinement study: one solver at several resolutions",
                       description=__doc__)
    add_case_arguments(p)
    p.add_argument("--solver", default="mdr", metavar="SOLVER",
                   help="which solver: " + ", ".join(registry.names()) + " (default: mdr)")
    p.add_argument("--out", type=Path, default=None, metavar="DIR",
                   help="study directory, shared by the MDR and FEM studies "
                        "(default: runs/<case name>-refine)")
    p.add_argument("--levels", type=_int_list, default=None, metavar="N1,N2,...",
                   help="resolutions: mdr.elements (default 100,200,400,800,1600,3200), "
                        "fem.contact_nodes (default 60,125,250,500,1000) or bem.grid "
                        "(default 32,64,128,256)")
    p.add_argument("--steps", type=_float_list, default=None, metavar="S1,S2,...",
                   help="sliding.step_hat per level (pairs with --levels; one value: all)")
    p.add_argument("--tolerance", type=float, default=0.01,
                   help="a level is converged when its profile (rel. depth d0) and force "
                        "(rel. F0) differ from the finest level's by at most this, and so do "
                        "all finer levels (default 0.01)")
    p.add_argument("--stage", type=float, default=None, metavar="S_HAT",
                   help="stage ŝ for the profile figure and Richardson's estimate "
                        "(default: the last stage every level reached)")
    add_cluster_arguments(p)
    add_json_argument(p, "the study's summary (as in refinement-SOLVER.json)")
    return p


def _int_list(text):
    values = [int(v) for v in text.split(",") if v.strip()]
    if not values or min(values) <= 0:
        raise ValueError(text)  # argparse: "invalid comma-separated positive integer value"
    return values


def _float_list(text):
    values = [float(v) for v in text.split(",") if v.strip()]
    if not values or not all(v > 0 and math.isfinite(v) for v in values):
        raise ValueError(text)
    return values


_int_list.__name__ = "comma-separated positive integer"  # argparse names it in its error
_float_list.__name__ = "comma-separated positive number"


def main(args) -> int:
    # the study (scipy.optimize, asyncio) is imported here, not for --help
    # (docs/performance.md, "Start-up")
    from wearcheck.studies.refine import refine, table
    case = load_case(args)
    out = args.out or Path("runs") / f"{args.case.stem}-refine"
    try:
        summary = refine(case, args.solver, out, levels=args.levels, steps=args.steps,
                         tolerance=args.tolerance, stage=args.stage,
                         scheduler=args.scheduler, workers=args.workers, quiet=args.quiet)
    except KeyboardInterrupt as exc:
        written = getattr(exc, "summary_written", False)
        print(f"wearcheck refine: {'terminated' if isinstance(exc, Terminated) else 'interrupted'}"
              f"; the levels finished are in {out}, "
              + ("the summary was written, the figures may be missing" if written
                 else "no summary was written"), file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
    case_notes(args, case)
    if args.json:
        print_json(summary)
    else:
        print(table(summary))
    return 0 if all(lv["status"] == "ok" for lv in summary["levels"]) else 1
