"""The paper case as users run it, against the paper's explicit scheme (issue 26 §2).

    python benchmarks/bench_paper.py [--rounds 7] [--other PYTHON]

Alternates, in fresh processes round by round, the baseline — the paper's
explicit scheme in plain vectorised numpy at N = 800 (``bench_mdr.py``'s
``paper_explicit``, BLAS single-threaded as the MDR's solve is) — and
``wearcheck run paper --solver mdr``: the shipped case, stages included,
cold (the first solve of its process), from the command line. Prints, per
command, the time of the computation as the process measured it (the
baseline's stepping loop; the run's ``solve_seconds`` from its
``meta.json``), the command's wall and CPU seconds, and the ratio of the
computations per round; and the same first solve in a fresh process timed
in CPU seconds as well (the load of a shared machine inflates wall times
unevenly; the solver imported before, as when ``solve_seconds`` starts).
Target: ``solve_seconds`` <= 0.1 of the baseline.

``--other PYTHON``: also time ``wearcheck run paper --solver mdr`` of another
environment (e.g. one with the main branch installed), in the same rounds.

Every process gets a bytecode cache in a temporary folder (as an installed
package has its modules compiled), also where ``PYTHONDONTWRITEBYTECODE`` is set.
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import sys
import tempfile
from pathlib import Path

import harness

HERE = Path(__file__).resolve().parent


def baseline_child() -> None:
    """Run the paper's explicit scheme at N = 800 here and print its timings as JSON."""
    from threadpoolctl import threadpool_limits

    sys.path.insert(0, str(HERE))
    from bench_mdr import paper_explicit

    with threadpool_limits(limits=1, user_api="blas"):
        out = paper_explicit(800)
    print(json.dumps({"seconds": out["wall"], "cpu": out["cpu"], "steps": out["steps"]}))


def solve_child() -> None:
    """The shipped paper case's first solve in this process, as ``wearcheck run``
    calls it (the registry), and print its wall and CPU seconds as JSON.

    The solver's modules are imported first: ``solve_seconds`` starts after
    the run has imported them (the registry imports them on its first call),
    so timing their import here would not time the same thing. What the CPU
    seconds include beyond ``solve_seconds``: the registry's checks and the
    BLAS thread limit (``mdr.linalg.single_threaded_blas``; its first use finds
    the process's thread pools, a few milliseconds).
    """
    import importlib
    import time

    from wearcheck import cases
    from wearcheck import registry

    case = cases.load(cases.shipped("paper"))
    registry.get("mdr").supports(case)      # its package imported, as the run's memory check does
    importlib.import_module("wearcheck.mdr.solver")
    wall, cpu = time.perf_counter(), time.process_time()
    result = registry.solve(case, "mdr")
    print(json.dumps({"seconds": time.perf_counter() - wall, "cpu": time.process_time() - cpu,
                      "solve_seconds": result.solve_seconds}))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--baseline-child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--solve-child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--other", metavar="PYTHON",
                    help="also time the wearcheck command of this interpreter's environment")
    args = ap.parse_args()
    if args.baseline_child:
        baseline_child()
        return
    if args.solve_child:
        solve_child()
        return
    py = sys.executable
    wc = harness.wearcheck_command()
    out = Path(tempfile.mkdtemp(prefix="bench-paper-"))
    run_dir = out / "paper-mdr"

    def run_parse(_stdout):
        meta = json.loads((run_dir / "meta.json").read_text(encoding="utf-8"))
        info = meta["info"]
        return {"seconds": meta["solve_seconds"], "steps": info["steps"],
                "gmres": info.get("gmres_iterations"), "stages": meta["stages_reached"]}

    commands = [
        ("paper explicit, numpy (baseline)", [py, __file__, "--baseline-child"],
         lambda stdout: json.loads(stdout.strip().splitlines()[-1])),
        ("wearcheck run paper --solver mdr", [*wc, "run", "paper", "--solver", "mdr",
                                              "--quiet", "--out", str(run_dir)], run_parse),
        ("the same first solve (solver imported), timed in CPU seconds",
         [py, __file__, "--solve-child"],
         lambda stdout: json.loads(stdout.strip().splitlines()[-1])),
    ]
    if args.other:
        other_dir = out / "other"

        def other_parse(_stdout):
            meta = json.loads((other_dir / "meta.json").read_text(encoding="utf-8"))
            return {"seconds": meta["solve_seconds"]}
        commands.append((f"{args.other}: wearcheck run paper --solver mdr",
                         [*harness.wearcheck_command(args.other), "run", "paper", "--solver",
                          "mdr", "--quiet", "--out", str(other_dir)], other_parse))
    print(f"# bench_paper: {harness.load()} (before)\n")
    try:
        timed = harness.alternate(commands, args.rounds)
    finally:
        shutil.rmtree(out, ignore_errors=True)
    base, run, cpu = timed[:3]
    b = [e["seconds"] for e in base.extra]
    r = [e["seconds"] for e in run.extra]
    b_cpu, r_cpu = [e["cpu"] for e in base.extra], [e["cpu"] for e in cpu.extra]
    print("| command | computation wall s, median (min–max) | computation CPU s, median "
          "(min–max) | process wall s, median | process CPU s, median |")
    print("|---|---|---|---|---|")
    for t, v, c in ((base, b, b_cpu), (run, r, None), (cpu, [e["seconds"] for e in cpu.extra],
                                                       r_cpu)):
        print(f"| {t.name} | {harness.spread(v)} | {harness.spread(c) if c else '—'} | "
              f"{statistics.median(t.wall):.3f} | {statistics.median(t.cpu):.3f} |")
    for t in timed[3:]:
        v = [e["seconds"] for e in t.extra]
        print(f"| {t.name} | {harness.spread(v)} | — | {statistics.median(t.wall):.3f} | "
              f"{statistics.median(t.cpu):.3f} |")
        print(f"\n(its solve_seconds / baseline per round: {harness.spread(harness.ratios(v, b))})")
    last = run.extra[-1]
    print(f"\nsolve_seconds / baseline per round: {harness.spread(harness.ratios(r, b))} "
          f"(target <= 0.1); in CPU seconds: {harness.spread(harness.ratios(r_cpu, b_cpu))}; "
          f"whole command wall / baseline computation: "
          f"{harness.spread(harness.ratios(run.wall, b))}. The run: {last['steps']} steps, "
          f"{last['stages']} stages, {last['gmres']} GMRES iterations; the baseline "
          f"{base.extra[-1]['steps']} steps. {args.rounds} rounds after one warm-up round; "
          f"{harness.load()} (after).")


if __name__ == "__main__":
    main()
