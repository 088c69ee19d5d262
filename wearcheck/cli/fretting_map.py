"""``wearcheck fretting-map CASE.toml --vary fretting.amplitude=... --vary loading.force=...``.

The running-condition map of a fretting case on Dask: one MDR run per
combination of the varied values (one or two keys), each kept as a run
directory in DIR; ``fretting_map.csv`` (regime, amplitude over u*, wear
volume per cycle) and ``fretting_map.png`` summarise them.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ._common import (add_case_arguments, add_cluster_arguments, add_json_argument,
                      case_notes, load_case, print_json, study_exit, varied)


def add_parser(sub):
    p = sub.add_parser("fretting-map", help="running-condition map of a fretting case "
                       "(partial/gross slip, wear per cycle), on Dask", description=__doc__)
    add_case_arguments(p)
    p.add_argument("--vary", action="append", required=True, metavar="SECTION.KEY=V1,V2,...",
                   help="a case key and its values (once or twice: the map's x and y axes)")
    p.add_argument("--out", type=Path, default=None, metavar="DIR",
                   help="map directory (default: runs/<case name>-fretting-map)")
    add_cluster_arguments(p)
    add_json_argument(p, "the runs' rows (as in fretting_map.csv)")
    return p


def main(args) -> int:
    # the study (scipy.optimize, asyncio) is imported here, not for --help
    # (docs/performance.md, "Start-up")
    from wearcheck.studies.distributed import fmt
    from wearcheck.studies.fretting_map import fretting_map
    case = load_case(args)
    vary = varied(args)
    out = args.out or Path("runs") / f"{args.case.stem}-fretting-map"
    try:
        rows = fretting_map(case, vary, out, scheduler=args.scheduler, workers=args.workers,
                            quiet=args.quiet)
    except KeyboardInterrupt:
        print(f"wearcheck fretting-map: interrupted; the runs finished are in {out}",
              file=sys.stderr)
        return 130
    case_notes(args, case)
    if args.json:
        print_json(rows)
    else:
        print(f"{'run':<56} {'regime':<13} {'u0/u*':>7} {'V/cycle m^3':>12}  status")
        for r in rows:
            print(f"{r['run']:<56} {r['regime']:<13} {fmt(r['amplitude_over_u_star'], '.3g'):>7} "
                  f"{fmt(r['wear_volume_per_cycle'], '.4g'):>12}  {r['status']}")
        print(f"-> {Path(out) / 'fretting_map.csv'}, {Path(out) / 'fretting_map.png'}")
    return study_exit(rows)
