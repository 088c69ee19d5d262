"""``wearcheck run CASE --solver NAME --out DIR``: one solver, one run directory."""

from __future__ import annotations

import sys
from pathlib import Path

from wearcheck.cases import CaseError

from wearcheck.outputs import atomic_directory, check_output
from wearcheck.resources import _estimator, check_export, check_memory
from wearcheck.comparisons.present.progress import ProgressBar
from wearcheck.rundir import write_run_files
from wearcheck import registry
from ._common import add_case_arguments, case_notes, load_case, output, print_json
from wearcheck.extras import need
from wearcheck.comparisons.present.vtk import export_run
from wearcheck.cases import reference
from wearcheck import layout


def add_parser(sub):
    p = sub.add_parser("run", help="run one solver on a case and write a run directory",
                       description=__doc__)
    add_case_arguments(p)
    p.add_argument("--solver", default="mdr", metavar="SOLVER",
                   help="which solver: " + ", ".join(registry.names()) + " (default: mdr)")
    p.add_argument("--out", type=Path, default=None,
                   help="output directory (default: runs/<case name>-<solver>)")
    p.add_argument("--vtk", action="store_true", help="also write ParaView files into DIR/vtk")
    p.add_argument("--revolve", type=int, default=0, metavar="N_SEGMENTS",
                   help="also revolve the FEM fields into a 3D solid of N >= 3 segments "
                        "(implies --vtk)")
    p.add_argument("--json", action="store_true",
                   help="print a summary (steps, stages, solve time, the last history row "
                        "with units, the scales) on stdout as JSON")  # (no table to replace)
    return p


def main(args) -> int:
    if args.revolve < 0 or 0 < args.revolve < 3:
        raise CaseError(f"--revolve {args.revolve}: need 0 (no solid) or at least 3 segments")
    args.vtk = args.vtk or args.revolve > 0
    if args.vtk:   # said before the solve
        need("pyvista", "writing ParaView files (--vtk)")
    case = load_case(args)
    out = output(args, Path("runs") / f"{args.case.stem}-{args.solver}")
    check_output(out, "run")  # before the solve: a path we may not write fails at once
    check_memory(case, args.solver)
    if args.revolve:
        est = _estimator(args.solver)
        if est is not None:
            check_export(getattr(est, "section_points", lambda c: 0)(case),
                         est.profile_points(case), args.revolve, len(case.stages.s_hat), out)
    bar = ProgressBar(f"{args.solver}", quiet=args.quiet)
    try:
        result = registry.solve(case, args.solver, progress=bar)
    finally:
        bar.close()
    with atomic_directory(out, "run") as tmp:
        write_run_files(tmp, case, result, args.solver)
        if args.vtk:
            export_run(tmp, revolve=args.revolve)
    case_notes(args, case)
    if not args.quiet:
        for text in result.info.get("warnings", []):   # the solver's remarks on the run
            print(f"note: {text}", file=sys.stderr)
    missing = [] if case.fretting is not None else list(case.stages.s_hat)[len(result.stage_s):]
    if missing and not args.quiet:
        # as the Python API warns: a stage the user asked for is not in stages.npz
        print(f"note: the run ended before the stages at {case.stages_from(len(result.stage_s))}"
              f" ({case.end_condition}); stages.npz does not hold them", file=sys.stderr)
    if args.json:
        print_json(dict(case=args.case, **summary(case, result, args.solver, out)))
    if not args.quiet:
        print(f"{args.solver}: {len(result.history['s']) - 1} steps, "
              f"{len(result.stage_s)} stages, solve {result.solve_seconds:.3g} s -> {out}",
              file=sys.stderr)
    return 0


def summary(case, result, solver: str, out: Path) -> dict:
    """What ``--json`` prints: the run's counts, the last history row (units
    from the run's data dictionary), the scales and, for a run with cycle
    jumping, its error estimate against every cycle simulated."""

    entry = registry.get(solver) if solver in registry.names() else None
    units = layout.run_dictionary(entry, list(result.history))["history_csv"]
    jumping = result.info.get("cycle_jumping") or {}
    extra = {"cycle_jumping": {k: jumping[k] for k in (
        "error_estimate", "tolerance", "simulated_cycles") if k in jumping}} if jumping else {}
    return dict(solver=solver, out=out, **extra,
                steps=len(result.history["s"]) - 1, stages_reached=len(result.stage_s),
                solve_seconds=result.solve_seconds,
                last={k: float(v[-1]) for k, v in result.history.items() if len(v)},
                units={k: units[k]["unit"] for k in result.history if k in units},
                scales={k: v for k, v in reference.scales(case).items()
                        if isinstance(v, (int, float))})
