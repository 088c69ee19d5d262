"""``wearcheck render RUN_DIR``: off-screen pictures of a run, in RUN_DIR/render."""

from __future__ import annotations

import sys
from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("render", help="render PNG pictures of a run directory (no display "
                       "needed)", description=__doc__)
    p.add_argument("run_dir", type=Path, metavar="RUN_DIR", help="a run directory")
    p.add_argument("--quiet", action="store_true", help="print nothing on success")
    return p


def main(args) -> int:
    from wearcheck.comparisons.present.render import render_run
    paths = render_run(args.run_dir)
    if not paths:
        print("render: note: the run stored no stage; nothing to draw", file=sys.stderr)
    if not args.quiet:
        for path in paths:
            print(path)
    return 0
