"""``wearcheck sweep CASE.toml --vary section.key=v1,v2,... --solver mdr|fem|bem --out DIR``.

One run per value (the cartesian product of several ``--vary``), each in its
own run directory in DIR, on the same Dask runner as ``wearcheck refine``;
``sweep.csv`` summarises them. Values are written as for ``--set``; a value
the case rejects, or a run that fails, is a row with its error.
"""

from __future__ import annotations

import sys
from pathlib import Path

from wearcheck import registry

from ._common import (add_case_arguments, add_cluster_arguments, add_json_argument,
                      case_notes, load_case, print_json, study_exit, varied)
from . import Terminated


def add_parser(sub):
    p = sub.add_parser("sweep", help="one run per value of one or more case keys, on Dask",
                       description=__doc__)
    add_case_arguments(p)
    p.add_argument("--vary", action="append", required=True, metavar="SECTION.KEY=V1,V2,...",
                   help="a case key and its values (repeatable: all combinations run)")
    p.add_argument("--solver", default="mdr", metavar="SOLVER",
                   help="which solver: " + ", ".join(registry.names()) + " (default: mdr)")
    p.add_argument("--out", type=Path, default=None, metavar="DIR",
                   help="sweep directory (default: runs/<case name>-sweep)")
    add_cluster_arguments(p)
    add_json_argument(p, "the runs' rows (as in sweep.csv)")
    return p


def main(args) -> int:
    # the study (scipy.optimize, asyncio) is imported here, not for --help
    # (docs/performance.md, "Start-up")
    from wearcheck.studies.distributed import fmt
    from wearcheck.studies.sweep import sweep
    case = load_case(args)
    vary = varied(args)
    out = args.out or Path("runs") / f"{args.case.stem}-sweep"
    try:
        rows = sweep(case, vary, args.solver, out, scheduler=args.scheduler,
                     workers=args.workers, quiet=args.quiet)
    except KeyboardInterrupt as exc:
        print(f"wearcheck sweep: {'terminated' if isinstance(exc, Terminated) else 'interrupted'}"
              f"; the runs finished are in {out}, no sweep.csv was written", file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
    case_notes(args, case)
    if args.json:
        print_json(rows)
    else:
        print(f"{'run':<40} {'wall s':>8} {'final ŝ':>8} {'final F/F0':>10}  status")
        for r in rows:
            print(f"{r['run']:<40} {fmt(r['wall_seconds'], '.3g'):>8} "
                  f"{fmt(r['final_s_hat'], '.4g'):>8} {fmt(r['final_F_over_F0'], '.4g'):>10}  "
                  f"{r['status']}")
        print(f"-> {Path(out) / 'sweep.csv'} ({', '.join(vary)})")
    return study_exit(rows)
