"""Fretting benchmark on cases/fretting.toml (issue 12, §6). Prints tables.

    python benchmarks/bench_fretting.py [--cycles 100000] [--reference-cycles 10000]
                                        [--tolerances 0.003,0.01,0.02,0.05] [--quick]

1. Speed: the shipped case (N = 800, 10^5 cycles, cycle jumping at its
   jump_tolerance) — CPU and wall seconds, simulated cycles, jumps; the
   target is at most 10 s including cycle jumping.
2. Accuracy of cycle jumping: runs with several jump tolerances against
   the same case with every cycle simulated (jump_tolerance = 0), over
   --reference-cycles (default 10^4: without jumps 10^5 cycles at N = 800
   take about 340 s CPU; --reference-cycles 100000 runs the full one).
   Errors: max |Δw|/max w of the final wear profile, relative worn volume,
   relative depth.

Each run is timed as process CPU time in this process and as wall time. The
machine these numbers were taken on is shared (2 cores, several users): wall
times vary; CPU times are the steadier measure.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from wearcheck import cases, mdr


def run(case_path, overrides):
    case = cases.load(case_path, overrides)
    t0, c0 = time.perf_counter(), time.process_time()
    res = mdr.solve(case)
    return case, res, time.process_time() - c0, time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=100000)
    ap.add_argument("--reference-cycles", type=int, default=10000)
    ap.add_argument("--tolerances", default="0.003,0.01,0.02,0.05")
    ap.add_argument("--elements", type=int, default=800)
    ap.add_argument("--quick", action="store_true", help="N = 200, 10^4 and 10^3 cycles")
    args = ap.parse_args(argv)
    if args.quick:
        args.elements, args.cycles, args.reference_cycles = 200, 10000, 1000
    path = cases.shipped("fretting")
    N = args.elements
    print("note: shared machine (2 cores, several users); CPU seconds are the steadier measure")
    print(f"\n1. Speed: {path.name}, N = {N}, {args.cycles} cycles (target: <= 10 s)")
    case, res, cpu, wall = run(path, [f"mdr.elements={N}", f"fretting.cycles={args.cycles}",
                                      f"fretting.stage_cycles=[0, {args.cycles}]"])
    i = res.info
    h = res.history
    print(f"{'tol':>6} {'cpu s':>7} {'wall s':>7} {'simulated':>9} {'jumps':>6} {'rejected':>8} "
          f"{'largest':>7} {'V [m^3]':>10} {'c/a0':>6}")
    a0 = h["contact_radius"][0]
    print(f"{case.fretting.jump_tolerance:>6g} {cpu:7.2f} {wall:7.2f} {i['simulated_cycles']:9d} "
          f"{i['jumps']:6d} {i['rejected_jumps']:8d} {i['largest_jump']:7d} "
          f"{h['wear_volume'][-1]:10.4g} {h['stick_radius'][-1] / a0:6.4f}")

    C = args.reference_cycles
    print(f"\n2. Cycle jumping against every cycle simulated: N = {N}, {C} cycles")
    common = [f"mdr.elements={N}", f"fretting.cycles={C}", f"fretting.stage_cycles=[0, {C}]"]
    _, ref, cpu0, wall0 = run(path, common + ["fretting.jump_tolerance=0"])
    w0 = ref.f[-1] - ref.f[0]
    print(f"{'tol':>6} {'cpu s':>7} {'wall s':>7} {'simulated':>9} {'max|dw|/max w':>14} "
          f"{'dV/V':>10} {'d depth/depth':>14}")
    print(f"{0:>6g} {cpu0:7.2f} {wall0:7.2f} {ref.info['simulated_cycles']:9d} {'(reference)':>14}")
    for tol in [float(t) for t in args.tolerances.split(",")]:
        _, r, cpu, wall = run(path, common + [f"fretting.jump_tolerance={tol}"])
        w = r.f[-1] - r.f[0]
        dw = np.max(np.abs(w - w0)) / np.max(np.abs(w0))
        dV = r.history["wear_volume"][-1] / ref.history["wear_volume"][-1] - 1
        dd = r.history["depth"][-1] / ref.history["depth"][-1] - 1
        print(f"{tol:>6g} {cpu:7.2f} {wall:7.2f} {r.info['simulated_cycles']:9d} {dw:14.3g} "
              f"{dV:10.3g} {dd:14.3g}")


if __name__ == "__main__":
    main()
