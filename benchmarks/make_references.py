"""Make the certified reference solutions shipped in ``references/data/``.

    python benchmarks/make_references.py [NAME ...] [--out DIR]

For each benchmark (default: every plan of ``references/derive.py``: hertz,
truncated, paper, ellipsoid, ball_on_flat, fretting) this solves the case at
the plan's levels (each level in this process, one after the other), estimates
the finest run's error, runs the other solvers at the case's settings for their
spread, writes ``DIR/NAME.npz`` (default: the package's ``references/data``)
and prints the band per stored stage relative to the stage's own scale, as the
verdict judges. The file records this command, the versions and the time.
The whole set takes about an hour on a shared 2-core machine (the BEM's
512² ellipsoid and the MDR's fretting at N = 3200 are the long ones).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from wearcheck import rundir
from wearcheck.references import certified, derive


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("names", nargs="*", default=list(derive.PLANS))
    p.add_argument("--out", type=Path, default=certified.DATA_DIR)
    args = p.parse_args(argv)
    rundir.set_command(["python", "benchmarks/make_references.py", *(argv or sys.argv[1:])])
    args.out.mkdir(parents=True, exist_ok=True)
    for name in args.names:
        plan = derive.PLANS[name]
        t0 = time.perf_counter()
        print(f"{name}: {plan.solver}", flush=True)
        data = derive.derive(plan)
        data["meta"]["provenance"] = rundir.provenance()
        data["meta"]["seconds"] = time.perf_counter() - t0
        path = certified.write(args.out / f"{name}.npz", data)
        ref = certified.read(path)
        print(f"{name}: {path} ({path.stat().st_size / 1024:.0f} kB, "
              f"{data['meta']['seconds']:.0f} s); orders {data['meta'].get('orders')}")
        print("  band relative to the stage's scale: ŝ | " + " | ".join(certified.BAND_CHECKS))
        for row in ref.relative_bands():
            print(f"  {row['s_hat']:.4g} | " + " | ".join(f"{row[c]:.1e}"
                                                       for c in certified.BAND_CHECKS))
        for solver, sp in data["meta"]["spread"].items():
            if "skipped" in sp:
                print(f"  spread {solver}: skipped ({sp['skipped']})")
                continue
            worst = {c: max(v) for c, v in sp["checks"].items() if v}
            print(f"  spread {solver} (largest over the stages): "
                  + ", ".join(f"{c} {v:.2g}" for c, v in worst.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
