"""Fretting benchmark on cases/fretting.toml (issue 12, §4 and §6). Prints tables.

    python benchmarks/bench_fretting.py [--cycles 100000] [--reference-cycles 10000]
                                        [--tolerances 0.003,0.01,0.02,0.05] [--quick]
                                        [--sections 1,2,3,4]

1. Speed: the shipped case (N = 800, 10^5 cycles, cycle jumping at its
   jump_tolerance) — CPU and wall seconds, simulated cycles, jumps; the
   target is at most 10 s including cycle jumping.
2. Accuracy of cycle jumping: runs with several jump tolerances against
   the same case with every cycle simulated (jump_tolerance = 0), over
   --reference-cycles (default 10^4: without jumps 10^5 cycles at N = 800
   take about 340 s CPU; --reference-cycles 100000 runs the full one).
   Errors: max |Δw|/max w of the final wear profile, relative worn volume,
   relative depth.

3. The stick radius under force control (docs/fretting.md, §2.1): the
   paper's sphere as a paraboloid, u0 = 0.5 u*, k = 0.1 (1000 times the
   paper's: the limiting state within 1600 cycles, k n = 160; c is there by
   k n = 80, the depth only by 160). c∞/c0 against N = 200 to 1600 (and 3200
   at k = 0.01) with successive differences, their order and the Richardson
   limit; the limiting depth against Popov's d∞(c∞) and the mean raise of the
   1D profile over the stick zone that separates them, with the same
   convergence; against the time discretisation at N = 200 and 800 (k, jump
   tolerance, no jumps, increments per cycle); the closed-form bounds
   c0 <= c <= c_max.
4. The approach to Popov's limit as the cycles grow (depth control, where
   Popov's profile is exact): the force error against F∞ at k·n = 5 ... 100
   (k·n measures the wear done), split into the grid's floor (the error at
   the end) and the transient, with the transient's exponential rate per unit
   k·n, for N = 200, 800, 1600 and k = 0.1 (and k = 1 at N = 200).

Each run is timed as process CPU time in this process and as wall time. The
machine these numbers were taken on is shared (2 cores, several users): wall
times vary; CPU times are the steadier measure.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import time

import numpy as np

from wearcheck import cases, mdr
from wearcheck.mdr import fretting, transforms
from wearcheck.cases import SolverError
from wearcheck.cases import reference as ref
from wearcheck.cases import reference_fretting as rf

R, FORCE, MU = 0.01, 30.0, 0.3


@contextlib.contextmanager
def every_cycle_unlimited():
    """Lift the solver's refusal of a run without cycle jumping estimated to take more
    than ``mdr.fretting.EVERY_CYCLE_SECONDS``: the references here simulate every
    cycle on purpose (10⁵ cycles at N = 800 take 5–20 minutes)."""
    saved = fretting.EVERY_CYCLE_SECONDS
    fretting.EVERY_CYCLE_SECONDS = math.inf
    try:
        yield
    finally:
        fretting.EVERY_CYCLE_SECONDS = saved


def run(case_path, overrides):
    case = cases.load(case_path, overrides)
    t0, c0 = time.perf_counter(), time.process_time()
    with every_cycle_unlimited():
        res = mdr.solve(case)
    return case, res, time.process_time() - c0, time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=100000)
    ap.add_argument("--reference-cycles", type=int, default=10000)
    ap.add_argument("--tolerances", default="0.003,0.01,0.02,0.05")
    ap.add_argument("--elements", type=int, default=800)
    ap.add_argument("--quick", action="store_true", help="N = 200, 10^4 and 10^3 cycles")
    ap.add_argument("--sections", default="1,2,3,4")
    args = ap.parse_args(argv)
    if args.quick:
        args.elements, args.cycles, args.reference_cycles = 200, 10000, 1000
    sections = {int(v) for v in args.sections.split(",")}
    print("note: shared machine (2 cores, several users); CPU seconds are the steadier measure")
    if sections & {1, 2}:
        speed_and_jumps(args, sections)
    if 3 in sections:
        stick_radius_growth(args.quick)
    if 4 in sections:
        approach_in_cycles(args.quick)


def speed_and_jumps(args, sections):
    path = cases.shipped("fretting")
    N = args.elements
    if 1 in sections:
        print(f"\n1. Speed: {path.name}, N = {N}, {args.cycles} cycles (target: <= 10 s)")
        case, res, cpu, wall = run(path, [f"mdr.elements={N}", f"fretting.cycles={args.cycles}",
                                          f"fretting.stage_cycles=[0, {args.cycles}]"])
        i = res.info
        h = res.history
        print(f"{'tol':>6} {'cpu s':>7} {'wall s':>7} {'simulated':>9} {'jumps':>6} "
              f"{'rejected':>8} {'largest':>7} {'V [m^3]':>10} {'c/a0':>6}")
        a0 = h["contact_radius"][0]
        print(f"{case.fretting.jump_tolerance:>6g} {cpu:7.2f} {wall:7.2f} "
              f"{i['simulated_cycles']:9d} {i['jumps']:6d} {i['rejected_jumps']:8d} "
              f"{i['largest_jump']:7d} {h['wear_volume'][-1]:10.4g} "
              f"{h['stick_radius'][-1] / a0:6.4f}")
    if 2 not in sections:
        return
    C = args.reference_cycles
    print(f"\n2. Cycle jumping against every cycle simulated: N = {N}, {C} cycles")
    common = [f"mdr.elements={N}", f"fretting.cycles={C}", f"fretting.stage_cycles=[0, {C}]"]
    _, every, cpu0, wall0 = run(path, common + ["fretting.jump_tolerance=0"])
    w0 = every.f[-1] - every.f[0]
    print(f"{'tol':>6} {'cpu s':>7} {'wall s':>7} {'simulated':>9} {'max|dw|/max w':>14} "
          f"{'dV/V':>10} {'d depth/depth':>14}")
    print(f"{0:>6g} {cpu0:7.2f} {wall0:7.2f} {every.info['simulated_cycles']:9d} "
          f"{'(reference)':>14}")
    for tol in [float(t) for t in args.tolerances.split(",")]:
        _, r, cpu, wall = run(path, common + [f"fretting.jump_tolerance={tol}"])
        w = r.f[-1] - r.f[0]
        dw = np.max(np.abs(w - w0)) / np.max(np.abs(w0))
        dV = r.history["wear_volume"][-1] / every.history["wear_volume"][-1] - 1
        dd = r.history["depth"][-1] / every.history["depth"][-1] - 1
        print(f"{tol:>6g} {cpu:7.2f} {wall:7.2f} {r.info['simulated_cycles']:9d} {dw:14.3g} "
              f"{dV:10.3g} {dd:14.3g}")


def paraboloid(N, cycles, k=0.1, control="force", jump_tolerance=0.02, increments=20,
               stage_cycles=None):
    """The paper's sphere as a paraboloid at u0 = 0.5 u*; (case, u0, Hertz contact radius)."""
    E_star = 210e9 / (1 - 0.3**2)
    a = ref.hertz(E_star, R, force=FORCE)["contact_radius"]
    base = dict(indenter=dict(profile="paraboloid", radius=R, youngs_modulus=210e9,
                              poisson_ratio=0.3),
                wear=dict(k=k, mu=MU, hardness=2e9), mdr=dict(elements=N))
    probe = cases.from_dict(dict(base, loading=dict(control="force", force=FORCE),
                                 fretting=dict(amplitude=1e-9, cycles=1)))
    u0 = 0.5 * rf.gross_slip_displacement(MU, FORCE, probe.G_star, a)
    loading = (dict(control="force", force=FORCE) if control == "force"
               else dict(control="depth", depth=a * a / R))
    fr = dict(amplitude=u0, cycles=cycles, jump_tolerance=jump_tolerance,
              increments=increments, stage_cycles=stage_cycles or [0, cycles])
    return cases.from_dict(dict(base, loading=loading, fretting=fr)), u0, a


def timed(case):
    c0 = time.process_time()
    with every_cycle_unlimited():
        res = mdr.solve(case)
    return res, time.process_time() - c0


def stick_radius_growth(quick):
    case, u0, a = paraboloid(200, 1)
    c0, c_max = rf.stick_radius_bounds(FORCE, case.E_star, case.G_star, MU, u0, R)
    print(f"\n3. Stick radius under force control (u0 = 0.5 u*): Cattaneo–Mindlin c0 = "
          f"{c0 / a:.4f} a; closed-form bound c_max/c0 = {c_max / c0:.4f}")
    print(f"{'N':>5} {'k':>6} {'cycles':>6} {'cpu s':>6} {'c_inf/c0':>9} {'diff':>9} "
          f"{'order':>6} {'d/d_inf(c)-1':>12} {'order':>6} {'raise/d':>9} {'max c/c_max':>11}")
    Ns = [200, 400, 800] if quick else [200, 400, 800, 1600]
    vals, dvals = [], []
    for N in Ns + ([] if quick else [3200]):
        # k = 0.1 at N = 3200 is refused with 20 increments (increment wear number
        # 1.8 > 1.3) and, resolved, ends at 1.01655 (docs/fretting.md §5): k = 0.01 there
        k = 0.1 if N <= 1600 else 0.01
        case, _, _ = paraboloid(N, int(round(160 / k)), k=k)
        res, cpu = timed(case)
        h = res.history
        c, d = h["stick_radius"][-1], h["depth"][-1]
        vals.append(c / c0)
        dvals.append(d / rf.limiting_depth(FORCE, case.E_star, c, R) - 1)
        diff = vals[-1] - vals[-2] if len(vals) > 1 else float("nan")
        order = (math.log2(abs(vals[-3] - vals[-2]) / abs(diff)) if len(vals) > 2
                 else float("nan"))
        d_order = (math.log2(abs(dvals[-3] - dvals[-2]) / abs(dvals[-1] - dvals[-2]))
                   if len(dvals) > 2 else float("nan"))
        # the mean raise of the 1D profile over the stick zone, (1/c)∫_0^c (g - x²/R) dx:
        # in the limit (annulus unloaded) d = d_inf(c) + that, exactly
        x = res.r
        g = transforms.to_1d(res.f[-1])
        st = x <= c
        raise_ = np.trapezoid((g - x**2 / R)[st], x[st]) / c / d
        print(f"{N:5d} {k:6g} {h['cycles'][-1]:6.0f} {cpu:6.1f} {vals[-1]:9.5f} {diff:9.2e} "
              f"{order:6.2f} {dvals[-1]:12.4e} {d_order:6.2f} {raise_:9.2e} "
              f"{np.max(h['stick_radius']) / c_max:11.4f}")
    if len(vals) > 2:
        rich = vals[len(Ns) - 1] + (vals[len(Ns) - 1] - vals[len(Ns) - 2])  # first order
        d_rich = 2 * dvals[len(Ns) - 1] - dvals[len(Ns) - 2]
        print(f"Richardson (first order, N = {Ns[-2]}, {Ns[-1]}): c_inf/c0 -> {rich:.5f}, "
              f"d/d_inf(c) - 1 -> {d_rich:.2e}")
    print("\nTime discretisation (c_inf/c0; k only scales time, so cycles = 80/k):")
    print(f"{'N':>5} {'k':>6} {'tol':>6} {'incr':>5} {'simulated':>9} {'cpu s':>6} "
          f"{'c_inf/c0':>9}")
    # k = 1 with 20 increments per cycle is not resolved in time at N = 800 (the
    # solver refuses it, docs/fretting.md §5): 80 are
    variants = [dict(), dict(k=1.0), dict(k=1.0, increments=80), dict(k=0.01),
                dict(jump_tolerance=0.05),
                dict(jump_tolerance=0.005), dict(jump_tolerance=0.0), dict(increments=40),
                dict(increments=80)]
    for N in ([200] if quick else [200, 800]):
        for v in variants:
            kw = dict(dict(k=0.1, jump_tolerance=0.02, increments=20), **v)
            case, _, _ = paraboloid(N, int(round(80 / kw["k"])), **kw)
            try:
                res, cpu = timed(case)
            except SolverError as e:
                print(f"{N:5d} {kw['k']:6g} {kw['jump_tolerance']:6g} {kw['increments']:5d} "
                      f"refused: {str(e)[:70]}...")
                continue
            print(f"{N:5d} {kw['k']:6g} {kw['jump_tolerance']:6g} {kw['increments']:5d} "
                  f"{res.info['simulated_cycles']:9d} {cpu:6.1f} "
                  f"{res.history['stick_radius'][-1] / c0:9.5f}")


def approach_in_cycles(quick):
    kn_stages = [0, 5, 10, 20, 30, 40, 60, 100]
    print("\n4. Approach to Popov's limit as the cycles grow (depth control, u0 = 0.5 u*):")
    print("   force error F/F_inf - 1 at k·n (k·n measures the wear done; the paper's "
          "k = 1e-4 needs n = 10^4 k·n cycles)")
    print(f"{'N':>5} {'k':>5} {'cpu s':>6} " + " ".join(f"{'kn=' + str(v):>9}" for v in kn_stages)
          + f" {'rate':>6} {'prof@40':>8} {'prof end':>8}")
    runs = [(200, 1.0), (200, 0.1), (800, 0.1)] + ([] if quick else [(1600, 0.1)])
    for N, k in runs:
        case, u0, a = paraboloid(N, int(round(100 / k)), k=k, control="depth",
                                 jump_tolerance=0.0,
                                 stage_cycles=[int(round(v / k)) for v in kn_stages])
        res, cpu = timed(case)
        h = res.history
        d = case.loading.depth
        c0 = rf.stick_radius(a, R, case.E_star, case.G_star, MU, u0)
        err = h["force"] / (2 * case.E_star * c0 * (d - c0**2 / (3 * R))) - 1
        kn = k * h["cycles"]
        at = [err[np.searchsorted(kn, v)] for v in kn_stages]
        tr = err - err[-1]
        sel = (kn >= 10) & (kn <= 40)
        rate = -np.polyfit(kn[sel], np.log(tr[sel]), 1)[0]
        b = math.sqrt(R * d)
        f_inf = rf.limiting_profile_3d(res.r, R, c0, d)
        prof = [np.max(np.abs(f - f_inf)[res.r <= b]) / d for f in res.f]
        print(f"{N:5d} {k:5g} {cpu:6.1f} " + " ".join(f"{v:9.2e}" for v in at)
              + f" {rate:6.3f} {prof[5]:8.4f} {prof[-1]:8.4f}")
    print("rate: exponential rate of the transient err - err_end per unit k·n over "
          "10 <= k·n <= 40; prof: max|f - f_inf|/d")


if __name__ == "__main__":
    main()
