"""``wearcheck reference NAME --out DIR``: a certified reference solution as a run
directory (case.toml, history.csv, stages.npz, meta.json), at the case's stages.

The references are shipped with wearcheck: each benchmark solved once at high
resolution, with its estimated error (meta.json ``reference.band``) and the
command and versions that made it (docs/benchmarks.md). ``--list`` lists them
with their largest band.
"""

from __future__ import annotations

import sys
from pathlib import Path

from wearcheck.cases import CaseError
from wearcheck.api import reference
from wearcheck.references import certified
from ._common import output


def add_parser(sub):
    p = sub.add_parser("reference", help="write a certified reference solution as a run "
                                         "directory", description=__doc__)
    p.add_argument("name", nargs="?", metavar="NAME",
                   help="the benchmark: a shipped case's name (hertz, truncated, paper, "
                        "ellipsoid, ball_on_flat, fretting)")
    p.add_argument("--out", type=Path, default=None,
                   help="output directory (default: runs/reference-<name>)")
    p.add_argument("--list", action="store_true", help="list the shipped references")
    p.add_argument("--quiet", action="store_true", help="no remarks")
    return p


def main(args) -> int:
    if args.list:
        for name in certified.names():
            ref = certified.load(name)
            print(f"{name}: {ref.meta.get('method')}; {len(ref.stage_s)} stored stage(s) to "
                  f"ŝ = {ref.last_s * ref.scales['s_hat_per_m']:.4g}")
        return 0
    if not args.name:
        raise CaseError("name a reference (wearcheck reference --list shows them)")
    result = reference(args.name)
    out = output(args, Path("runs") / f"reference-{result.certified.name}")
    path = result.write(out)
    if not args.quiet:
        print(f"reference {args.name}: {len(result.stages['s'])} stages -> {path}",
              file=sys.stderr)
    return 0
