"""The paper case as users run it, against the paper's explicit scheme (issue 26 §2).

    python benchmarks/bench_paper.py [--rounds 7]

Alternates, in fresh processes round by round, the baseline — the paper's
explicit scheme in plain vectorised numpy at N = 800 (``bench_mdr.py``'s
``paper_explicit``, BLAS single-threaded as the MDR's solve is) — and
``wearcheck run paper --solver mdr``: the shipped case, stages included,
cold (the first solve of its process), from the command line. Prints, per
command, the time of the computation as the process measured it (the
baseline's stepping loop; the run's ``solve_seconds`` from its
``meta.json``), the command's wall and CPU seconds, and the ratio of the
computations per round. Target: ``solve_seconds`` <= 0.1 of the baseline.

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

import fresh

HERE = Path(__file__).resolve().parent


def baseline_child() -> None:
    """Run the paper's explicit scheme at N = 800 here and print its timings as JSON."""
    from threadpoolctl import threadpool_limits

    sys.path.insert(0, str(HERE))
    from bench_mdr import paper_explicit

    with threadpool_limits(limits=1, user_api="blas"):
        out = paper_explicit(800)
    print(json.dumps({"seconds": out["wall"], "cpu": out["cpu"], "steps": out["steps"]}))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--baseline-child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.baseline_child:
        baseline_child()
        return
    py = sys.executable
    wc = fresh.wearcheck_command()
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
    ]
    print(f"# bench_paper: {fresh.load()} (before)\n")
    try:
        timed = fresh.alternate(commands, args.rounds)
    finally:
        shutil.rmtree(out, ignore_errors=True)
    base, run = timed
    b = [e["seconds"] for e in base.extra]
    r = [e["seconds"] for e in run.extra]
    print("| command | computation s, median (min–max) | wall s, median | CPU s, median |")
    print("|---|---|---|---|")
    for t, v in ((base, b), (run, r)):
        print(f"| {t.name} | {fresh.spread(v)} | {statistics.median(t.wall):.3f} | "
              f"{statistics.median(t.cpu):.3f} |")
    last = run.extra[-1]
    print(f"\nsolve_seconds / baseline per round: {fresh.spread(fresh.ratios(r, b))} "
          f"(target <= 0.1); whole command wall / baseline computation: "
          f"{fresh.spread(fresh.ratios(run.wall, b))}. The run: {last['steps']} steps, "
          f"{last['stages']} stages, {last['gmres']} GMRES iterations; the baseline "
          f"{base.extra[-1]['steps']} steps. {args.rounds} rounds after one warm-up round; "
          f"{fresh.load()} (after).")


if __name__ == "__main__":
    main()
