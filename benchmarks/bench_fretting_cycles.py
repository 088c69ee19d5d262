"""Cost of fretting runs in the cycle count: ROS2 cycle jumping against the old jumps.

    python benchmarks/bench_fretting_cycles.py [--cycles 1e5,1e6,1e8]
        [--baseline-rev eee255d] [--no-baseline] [--every-cycle FILE.npz]

The shipped case (`cases/fretting.toml`, N = 800, jump_tolerance 0.02) run to
each cycle count, each run in a fresh process (imports and the first call's
set-up included in the wall time, the solve's CPU time reported apart), by
this checkout's solver ("ros2": error-controlled ROS2 steps, docs/fretting.md
§4) and by the solver of ``--baseline-rev`` ("baseline": mdr/fretting.py at
that revision, with its numerics/cycle_jumping.py where it has one, loaded
from ``git show`` into the installed package; eee255d, the default, has the
forward-Euler jumps). The stage cycles are the decades up to the count.

Errors against references that neither solver computes:
- every cycle simulated (``--every-cycle FILE``: the profiles at the decades
  of a run with jump_tolerance = 0, written by ``--write-every-cycle FILE
  --cycles 1e5``; about 6 min of CPU at 10⁵ cycles): max|f − f_ref| over
  max|f_ref − f0| at the run's last cycle, where the file has it;
- Popov's limit (docs/fretting.md §2): the depth against
  d∞(c) = F/(2E*c) + c²/(3R) at the run's own stick radius c; in the limit
  the grid's floor at N = 800 is −6.9e-4 (§2), well before it the depth is
  short of it by the wear still to come.

The machine is shared (2 cores, several users): quote ``uptime`` with the table.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "cases" / "fretting.toml"
#: the last revision of main with the forward-Euler jumps
BASELINE_REV = "eee255d"


def decades(cycles: int) -> list[int]:
    out, c = [0], 1
    while c < cycles:
        out.append(c)
        c *= 10
    return out + [cycles]


def load_case(cycles: int, tol: float):
    from wearcheck import cases

    over = [f"fretting.cycles={cycles}", f"fretting.jump_tolerance={tol}",
            f"fretting.stage_cycles={decades(cycles)}"]
    return cases.load(SHIPPED, over)


def _module_at(rev: str, path: str, name: str):
    """The file ``path`` at ``rev`` as the module ``name`` of the installed package,
    or None where ``rev`` has no such file."""
    out = subprocess.run(["git", "-C", str(ROOT), "show", f"{rev}:{path}"],
                         capture_output=True, text=True)
    if out.returncode:
        return None
    file = Path(tempfile.mkdtemp()) / (name.rsplit(".", 1)[-1] + ".py")
    file.write_text(out.stdout)
    spec = importlib.util.spec_from_file_location(name, file)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def baseline_module(rev: str):
    """mdr/fretting.py at ``rev`` as a module of the installed package, with the
    cycle jumping of ``rev`` (numerics/cycle_jumping.py) where it has one."""
    import wearcheck.mdr  # noqa: F401  (the parent package of the relative imports)
    import wearcheck.numerics  # noqa: F401

    jumping = _module_at(rev, "numerics/cycle_jumping.py",
                         "wearcheck.numerics.cycle_jumping_baseline")
    module = _module_at(rev, "mdr/fretting.py", "wearcheck.mdr.fretting_baseline")
    if jumping is not None:
        # looked up when the solver runs: the baseline's fretting on its own jumps
        module.cycle_jumping = jumping
    return module


def worker(kind: str, cycles: int, rev: str, tol: float, write: str | None) -> dict:
    """One run in this (fresh) process; a JSON line on stdout."""
    from wearcheck.cases import reference_fretting as rf

    from bench_fretting import every_cycle_unlimited   # benchmarks/ is on the path

    if kind == "old":
        solver = baseline_module(rev)
    else:
        from wearcheck.mdr import fretting as solver
    case = load_case(cycles, tol)
    cpu = time.process_time()
    with every_cycle_unlimited():   # --write-every-cycle: 10⁵ cycles, 5–20 minutes
        res = solver.solve(case)
    cpu = time.process_time() - cpu
    h = res.history
    c, d = float(h["stick_radius"][-1]), float(h["depth"][-1])
    d_inf = rf.limiting_depth(case.loading.force, case.E_star, c, case.indenter.radius)
    jumping = res.info.get("cycle_jumping", {})
    if write:
        np.savez(write, stage_cycles=np.asarray(res.info["stage_cycles"]), f=res.f, r=res.r)
    return dict(kind=kind, cycles=cycles, cpu=cpu, rows=int(len(h["cycles"])),
                simulated=int(res.info["simulated_cycles"]), c=c, depth=d,
                popov=d / d_inf - 1.0, f=res.f[-1].tolist(), f0=res.f[0].tolist(),
                error_estimate=jumping.get("error_estimate"))


def spawn(kind: str, cycles: int, rev: str) -> dict:
    wall = time.perf_counter()
    out = subprocess.run([sys.executable, __file__, "--worker", kind, "--cycles", str(cycles),
                          "--baseline-rev", rev], check=True, capture_output=True, text=True)
    row = json.loads(out.stdout.strip().splitlines()[-1])
    row["wall"] = time.perf_counter() - wall
    return row


def every_cycle_error(row: dict, path: str | None) -> float | None:
    if not path:
        return None
    ref = np.load(path)
    at = np.flatnonzero(ref["stage_cycles"] == row["cycles"])
    if not len(at):
        return None
    f_ref, f0 = ref["f"][at[0]], ref["f"][0]
    return float(np.max(np.abs(np.asarray(row["f"]) - f_ref)) / np.max(np.abs(f_ref - f0)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", default="1e5,1e6,1e8")
    ap.add_argument("--baseline-rev", default=BASELINE_REV)
    ap.add_argument("--no-baseline", action="store_true")
    ap.add_argument("--every-cycle", help="npz of a run with every cycle simulated")
    ap.add_argument("--write-every-cycle", help="run every cycle to --cycles, write the npz")
    ap.add_argument("--worker", choices=("ros2", "old"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    counts = [int(float(c)) for c in args.cycles.split(",")]
    if args.every_cycle and not Path(args.every_cycle).is_file():
        ap.error(f"--every-cycle {args.every_cycle}: no such file (write it with "
                 f"--write-every-cycle {args.every_cycle})")
    if args.worker:
        row = worker(args.worker, counts[0], args.baseline_rev, load_tol(), None)
        print(json.dumps(row))
        return
    if args.write_every_cycle:
        row = worker("ros2", counts[0], args.baseline_rev, 0.0, args.write_every_cycle)
        print(f"every cycle to {counts[0]}: {row['cpu']:.1f} s CPU, written "
              f"{args.write_every_cycle}")
        return
    print(subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    kinds = ["ros2"] + ([] if args.no_baseline else ["old"])
    print("| cycles | solver | wall s | solve CPU s | rows | simulated cycles | "
          "error estimate | vs every cycle | d/d∞(c) − 1 |")
    print("|---|---|---|---|---|---|---|---|---|")
    for cycles in counts:
        for kind in kinds:
            row = spawn(kind, cycles, args.baseline_rev)
            ec = every_cycle_error(row, args.every_cycle)
            est = row["error_estimate"]
            label = kind if kind == "ros2" else f"baseline ({args.baseline_rev})"
            print(f"| {cycles:.0e} | {label} | {row['wall']:.1f} | {row['cpu']:.1f} | "
                  f"{row['rows']} | {row['simulated']} | "
                  f"{'—' if est is None else f'{est:.2e}'} | "
                  f"{'—' if ec is None else f'{ec:.2e}'} | {row['popov']:+.3e} |", flush=True)
    print(subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())


def load_tol() -> float:
    """The shipped case's jump tolerance."""
    from wearcheck import cases

    return cases.load(SHIPPED).fretting.jump_tolerance


if __name__ == "__main__":
    main()
