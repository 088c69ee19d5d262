"""``wearcheck export RUN_DIR [--revolve N]``: ParaView files of a run, in RUN_DIR/vtk."""

from __future__ import annotations

import sys
from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("export", help="write ParaView files (VTU/PVD) of a run directory",
                       description=__doc__)
    p.add_argument("run_dir", type=Path, metavar="RUN_DIR", help="a run directory")
    p.add_argument("--revolve", type=int, default=0, metavar="N_SEGMENTS",
                   help="also revolve the FEM fields into a 3D solid of N segments")
    p.add_argument("--quiet", action="store_true", help="print nothing on success")
    return p


def main(args) -> int:
    from wearcheck.comparisons.present.vtk import export_run
    out = export_run(args.run_dir, revolve=args.revolve)
    if not any(out.glob("*.pvd")):
        print("export: note: the run stored no stage; nothing to export", file=sys.stderr)
    elif args.revolve and not (out / "solid.pvd").exists():
        print("export: note: the run has no FEM fields; --revolve applies to them only "
              "(the worn surface used it)", file=sys.stderr)
    if not args.quiet:
        series = sorted(p.name for p in out.glob("*.pvd"))
        print(f"export: {', '.join(series)} -> {out}", file=sys.stderr)
    return 0
