"""Accounting of the springs at a cycle jump (docs/fretting.md, §4). Prints tables.

    python benchmarks/bench_fretting_jumps.py [--quick]

A jump extrapolates the wear per cycle W over n - 1 cycles. The jumped
cycles' wear lowers the spring limits L = μq_z/G* in the slip annulus, and
each of those cycles ends with its sliding springs at its own lowered limit:
the slip by which they follow the limits down (and its wear, dissipation)
is in W. The solver puts the springs on the new limits at the jump, without
wear ("now"). Before, it left them at the old limits ("before", emulated
here by restoring the springs after the jump), and the cycle after the jump
re-clipped them with the increments' own accounting.

1. Per jump: the simulated cycle after each jump taken twice from the same
   state, springs as "before" and as "now"; the difference of its worn
   volume over W (the worn volume of the cycle before the jump), also over
   (n - 1)·W (per jumped cycle).
2. End to end: jumped runs ("before", "now") against the same case with
   every cycle simulated (jump_tolerance = 0), at the run's end: worn volume
   ΔV/V, dissipated energy ΔE/E (∫τ·Δslip dA) and ΔE1d/E1d (the springs' own),
   the worn profile max|Δw|/max w, the stick radius Δc/c0; and over all
   simulated cycles the largest error of the energy per cycle against the
   reference's same cycle, over tol·X, X = max|E(c) - E(1)| the energy per
   cycle's largest change over the run (tests/test_fretting_jumps.py asserts
   <= 1: to first order a jump's error is a fraction tol of the change it
   jumps over, by its acceptance test).

The machine these numbers were taken on is shared (2 cores, several
users); the CPU seconds are indicative only.
"""

from __future__ import annotations

import argparse
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from wearcheck import cases
from wearcheck.cases import reference as ref
from wearcheck.cases import reference_fretting as rf
from wearcheck.mdr import fretting, transforms

R, FORCE, MU, HARDNESS = 0.01, 30.0, 0.3, 2e9
SHIPPED = Path(__file__).resolve().parents[1] / "cases" / "fretting.toml"


def make_case(N, k, frac, cycles, tol, control="force", increments=20):
    """The paper's sphere as a paraboloid at u0 = frac·u*."""
    E_star = 210e9 / (1 - 0.3**2)
    hz = ref.hertz(E_star, R, force=FORCE)
    base = dict(indenter=dict(profile="paraboloid", radius=R, youngs_modulus=210e9,
                              poisson_ratio=0.3),
                wear=dict(k=k, mu=MU, hardness=HARDNESS), mdr=dict(elements=N))
    probe = cases.from_dict(dict(base, loading=dict(control="force", force=FORCE),
                                 fretting=dict(amplitude=1e-9, cycles=1)))
    u_star = rf.gross_slip_displacement(MU, FORCE, probe.G_star, hz["contact_radius"])
    loading = (dict(control="force", force=FORCE) if control == "force"
               else dict(control="depth", depth=hz["depth"]))
    fr = dict(amplitude=frac * u_star, cycles=cycles, jump_tolerance=tol,
              increments=increments, stage_cycles=[0, cycles])
    return cases.from_dict(dict(base, loading=loading, fretting=fr))


def shipped(cycles, tol, N=None):
    over = [f"fretting.cycles={cycles}", f"fretting.jump_tolerance={tol}",
            f"fretting.stage_cycles=[0, {cycles}]"]
    if N is not None:
        over.append(f"mdr.elements={N}")
    return cases.load(SHIPPED, over)


@contextmanager
def springs_before():
    """The accounting before: the springs stay at the limits from before the jump."""
    original = fretting._extrapolate

    def extrapolate(model, st, totals, W, sums, jump):
        v, Q = st.v.copy(), st.Q
        original(model, st, totals, W, sums, jump)
        st.v, st.Q = v, Q

    fretting._extrapolate = extrapolate
    try:
        yield
    finally:
        fretting._extrapolate = original


def per_jump(label, case):
    """Section 1 for one case: the cycle after each jump tried (accepted or not),
    springs as before and as now."""
    log, last = [], {}
    extrapolate, run_path = fretting._extrapolate, fretting.run_path

    def ext(model, st, totals, W, sums, jump):
        before = (st.v.copy(), st.Q)
        extrapolate(model, st, totals, W, sums, jump)
        last.update(n=jump, W=transforms.volume(W, model.dt), before=before)

    def rp(model, st, path, loop=False):
        if last and len(path) == model.increments:
            old = st.copy()
            old.v, old.Q = last["before"]
            V_old = transforms.volume(run_path(model, old, path)["wear"], model.dt)
            acc = run_path(model, st, path, loop)
            log.append((last["n"], last["W"], V_old - transforms.volume(acc["wear"], model.dt)))
            last.clear()
            return acc
        return run_path(model, st, path, loop)

    fretting._extrapolate, fretting.run_path = ext, rp
    try:
        fretting.solve(case)
    finally:
        fretting._extrapolate, fretting.run_path = extrapolate, run_path
    n, W, d = (np.array(c, dtype=float) for c in zip(*log))
    x, y = d / W, d / W / (n - 1)
    print(f"{label:<44} {len(n):5d} {int(n.max()):6d} {x.min():+10.2e} {np.median(x):+10.2e} "
          f"{x.max():+10.2e} {np.median(y):+10.2e} {np.mean(x > 0):6.2f}", flush=True)


def solve(case, before=False):
    t0 = time.process_time()
    if before:
        with springs_before():
            res = fretting.solve(case)
    else:
        res = fretting.solve(case)
    return res, time.process_time() - t0


def end_to_end(label, make, tols):
    """Section 2 for one case: the jumped runs against every cycle simulated."""
    refr, t_ref = solve(make(0.0))
    h0 = refr.history
    w0 = refr.f[-1] - refr.f[0]
    E0 = h0["energy_per_cycle"]
    X = float(np.max(np.abs(E0[1:] - E0[1])))
    c0 = h0["stick_radius"][0]
    print(f"\n{label}: reference {int(h0['cycles'][-1])} cycles simulated in {t_ref:.0f} s cpu, "
          f"X/E(1) = {X / E0[1]:.3g}")
    print(f"{'tol':>6} {'springs':>7} {'jumps':>5} {'sim.':>5} {'ΔV/V':>10} {'ΔE/E':>10} "
          f"{'ΔE1d/E1d':>10} {'max|Δw|/w':>10} {'Δc/c0':>10} {'ΔEc/(tol X)':>11} {'cpu s':>6}")
    for tol in tols:
        for before in (True, False):
            res, t = solve(make(tol), before)
            h = res.history
            w = res.f[-1] - res.f[0]
            cyc = h["cycles"].astype(int)[1:]
            ec = np.max(np.abs(h["energy_per_cycle"][1:] - E0[cyc]))
            rel = {k: h[k][-1] / h0[k][-1] - 1 for k in ("wear_volume", "dissipated_energy",
                                                        "dissipated_energy_1d")}
            print(f"{tol:6.3f} {'before' if before else 'now':>7} {res.info['jumps']:5d} "
                  f"{res.info['simulated_cycles']:5d} {rel['wear_volume']:+10.2e} "
                  f"{rel['dissipated_energy']:+10.2e} {rel['dissipated_energy_1d']:+10.2e} "
                  f"{np.max(np.abs(w - w0)) / np.max(w0):10.2e} "
                  f"{(h['stick_radius'][-1] - h0['stick_radius'][-1]) / c0:+10.2e} "
                  f"{ec / (tol * X):11.3f} {t:6.1f}", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the fast cases only")
    args = ap.parse_args(argv)
    print("note: shared machine (2 cores, several users); CPU seconds are indicative only")

    print("\n1. The cycle after a jump, springs as before minus as now: its worn volume over W")
    print(f"{'case':<44} {'tried':>5} {'max n':>6} {'min':>10} {'median':>10} {'max':>10} "
          f"{'med/(n-1)':>10} {'>0':>6}")
    per_jump("N=200 k=0.01 u0=0.5u* 200 cyc tol=0.02", make_case(200, 0.01, 0.5, 200, 0.02))
    per_jump("N=200 k=0.01 u0=0.2u* 200 cyc tol=0.05", make_case(200, 0.01, 0.2, 200, 0.05))
    per_jump("N=200 k=0.1 u0=0.5u* 800 cyc tol=0.02", make_case(200, 0.1, 0.5, 800, 0.02))
    per_jump("N=200 k=4 u0=0.5u* 20 cyc inc=160 tol=0.1",
             make_case(200, 4.0, 0.5, 20, 0.1, increments=160))
    if not args.quick:
        per_jump("N=200 k=0.01 u0=0.5u* 4000 cyc inc=320 tol=0.1",
                 make_case(200, 0.01, 0.5, 4000, 0.1, increments=320))
        per_jump("shipped case, 10^5 cycles", shipped(100_000, 0.02))

    print("\n2. Jumped runs against every cycle simulated, at the run's end")
    for control in ("force", "depth"):
        end_to_end(f"N=200 k=0.01 u0=0.2u* 200 cycles, {control} control",
                   lambda tol, c=control: make_case(200, 0.01, 0.2, 200, tol, c),
                   (0.02, 0.05, 0.1, 0.2))
    end_to_end("N=200 k=0.01 u0=0.5u* 200 cycles, force control",
               lambda tol: make_case(200, 0.01, 0.5, 200, tol), (0.02, 0.05, 0.1, 0.2))
    end_to_end("N=200 k=0.1 u0=0.5u* 800 cycles (limiting state), force control",
               lambda tol: make_case(200, 0.1, 0.5, 800, tol), (0.02, 0.05, 0.1))
    if not args.quick:
        end_to_end("N=200 k=1e-4 u0=0.5u* 2·10^4 cycles (the paper's k), force control",
                   lambda tol: make_case(200, 1e-4, 0.5, 20_000, tol), (0.02, 0.05))
        end_to_end("shipped case (N=800), 2·10^4 cycles",
                   lambda tol: shipped(20_000, tol), (0.02, 0.05))


if __name__ == "__main__":
    main()
