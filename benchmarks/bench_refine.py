"""Processes or threads for the refinement runner? Times one MDR study both ways.

    python benchmarks/bench_refine.py [--solver mdr] [--levels 100,200,...] [--workers 2]

Prints the wall time of the whole study (cluster start excluded) on a
LocalCluster of worker processes and one of threads, each single-threaded
workers, plus the sum of the per-level times (what one worker would take).
"""

from __future__ import annotations

import argparse
import tempfile
import time

from wearcheck import cases
from wearcheck.studies.distributed import Task, run_cases
from wearcheck.comparisons.analysis.convergence import levels


def study(solver, lvls, scheduler, out):
    tasks = [Task(lv.name, solver, lv.changes) for lv in lvls]
    t0 = time.perf_counter()
    outcomes = run_cases(cases.load(cases.shipped("paper")), tasks, out, scheduler=scheduler,
                         quiet=True)
    wall = time.perf_counter() - t0
    assert all(o.ok for o in outcomes), [o.message for o in outcomes if not o.ok]
    return wall, sum(o.wall_seconds for o in outcomes), outcomes


def main():
    from distributed import LocalCluster
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--solver", default="mdr")
    ap.add_argument("--levels", default=None)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    lvls = levels(args.solver, [int(v) for v in args.levels.split(",")] if args.levels else None)
    print(f"{'mode':<10} {'study wall s':>12} {'sum of levels s':>16}  per level s")
    for processes in (True, False):
        # threads talk in-process (inproc://); processes over loopback TCP
        net = dict(host="127.0.0.1") if processes else {}
        with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=processes,
                          dashboard_address=None, **net) as cluster, \
                tempfile.TemporaryDirectory() as out:
            study(args.solver, lvls[:1], cluster.scheduler_address, out)  # warm the imports
            wall, total, outcomes = study(args.solver, lvls, cluster.scheduler_address, out)
        mode = "processes" if processes else "threads"
        per = " ".join(f"{o.wall_seconds:.2f}" for o in outcomes)
        print(f"{mode:<10} {wall:>12.2f} {total:>16.2f}  {per}")


if __name__ == "__main__":
    main()
