"""Instructions of the paper case's MDR solve, counted by valgrind's callgrind (issue 26 §2).

    python benchmarks/instructions_paper.py [--out DIR]

Wall and CPU seconds of a 0.2 s solve move by ±30 % with the load of a
shared machine; instructions do not. This runs, under ``valgrind
--tool=callgrind --dump-before=getppid``, a child that loads the shipped
paper case, imports the solver (the registry's checks), and solves it twice
as ``wearcheck run`` does, each solve's window (what ``solve_seconds``
times: ``mdr.solver._solve``) bracketed by ``os.getppid()`` calls, so the
count splits into parts: part 2 is the first solve of the process (the one
``wearcheck run`` times, cold), part 4 a second one (warm). Prints the
instructions of each part, in millions, and a line of the history (steps,
contact iterations, the last force, the central wear summed over the rows)
that shows whether a change moved the results. ``--out``: keep the callgrind
files there (``callgrind_annotate --inclusive=yes DIR/cg.out.2``). Needs
valgrind (Debian: ``apt-get install valgrind``); about 75 s.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path


def child() -> None:
    """The two solves, each bracketed by getppid(), and the history line."""
    import importlib
    import os
    import warnings

    import numpy as np

    from wearcheck import cases, registry

    warnings.simplefilter("ignore")
    case = cases.load(cases.shipped("paper"))
    registry.get("mdr").supports(case)
    solver = importlib.import_module("wearcheck.mdr.solver")
    inner = solver._solve

    def bracketed(*args, **kwargs):
        os.getppid()
        try:
            return inner(*args, **kwargs)
        finally:
            os.getppid()

    solver._solve = bracketed
    for _ in range(2):
        result = registry.solve(case, "mdr")
    h = result.history
    print(f"steps {result.info.get('steps')} contact_iterations "
          f"{result.info.get('contact_iterations')} F_end {float(h['force'][-1])!r} "
          f"sum wear_center {float(np.sum(h['wear_center']))!r}")


def _instructions(path: Path) -> int:
    for line in path.read_text().splitlines():
        if line.startswith(("summary:", "totals:")):
            return int(line.split()[1])
    raise SystemExit(f"no instruction count in {path}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="keep the callgrind files here")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child()
        return
    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind is not installed (Debian: apt-get install valgrind)")
    out = args.out or Path(tempfile.mkdtemp(prefix="instructions-paper-"))
    out.mkdir(parents=True, exist_ok=True)
    run = subprocess.run(["valgrind", "--tool=callgrind", "--dump-before=getppid",
                          f"--callgrind-out-file={out / 'cg.out'}", sys.executable,
                          __file__, "--child"], capture_output=True, text=True)
    if run.returncode != 0:
        raise SystemExit(f"valgrind failed ({run.returncode}):\n{run.stderr[-2000:]}")
    parts = {int(p.suffix[1:]): _instructions(p) for p in out.glob("cg.out.*")}
    print(run.stdout.strip().splitlines()[-1])
    print("| part | what | instructions (M) |\n|---|---|---|")
    for n, what in ((2, "the first solve (solve_seconds' window)"), (4, "a second solve")):
        if n in parts:
            print(f"| {n} | {what} | {parts[n] / 1e6:.0f} |")
    if args.out is None:
        shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
