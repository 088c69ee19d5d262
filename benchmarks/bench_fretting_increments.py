"""Resolution of the fretting increments (docs/fretting.md, §5). Prints tables.

    python benchmarks/bench_fretting_increments.py [--quick] [--sections 1,2,3]

Each row runs one case twice, with ``fretting.increments`` = 20 and with 4x
as many (80), and gives the difference of the first against the second at
the run's end: stick radius Δc/c0, worn volume ΔV/V, worn profile
max|Δw|/max w. Both runs have the solver's resolution check switched off
(``mdr.fretting.WEAR_NUMBER_LIMIT = inf``) so that what it would refuse is
measured too; the column "check" says what the solver does with the run:
"ok" (returned) or "refused" (SolverError naming fretting.increments).

Measures of the run with 20 increments (largest over all increments):
  Λ        the increment wear number (k/σ0) μ E* |Δslip|/Δr (the wear of
           an increment over the elastic indentation p Δr/E* of one grid
           cell; mdr/fretting.py, the quantity the solver checks)
  Δf/w_c   the largest wear of an increment over the stick compression
           w_c = G* u0/(μE*) (the candidate of issue 12's last note)

1. Calibration: the paper's sphere as a paraboloid, u0 = 0.2, 0.5, 0.8 u*,
   k = 1e-4 (the paper's) to 1, N = 200, 400, 800, normal force and depth
   control; 80/k cycles (at most 10^5: the paper's k reaches k·n = 10, the
   others the limiting state), jump tolerance 0.02.
2. Onset: k chosen so that Λ (estimated from a resolved run) is 1 to 4,
   for several grids, amplitudes and controls, including a tangential
   force amplitude (fretting.force_amplitude, same Q* as u0 = 0.5 u*) and
   gross slip (u0 = 2u*, k·n = 0.5; there Δc/c0 means nothing).
3. The linear stability limit: the largest eigenvalue β_max of
   (Δr/E*)·(−∂p/∂f) (the pressure's response to the height of the worn
   profile, on the nodes in contact, depth held) on the unworn contact;
   forward Euler in the wear is stable at the grid scale while Λ β_max <= 2.

The machine these numbers were taken on is shared (2 cores, several
users); the CPU seconds are indicative only.
"""

from __future__ import annotations

import argparse
import math
import time
from contextlib import contextmanager

import numpy as np

from wearcheck import cases
from wearcheck.cases import SolverError
from wearcheck.cases import reference as ref
from wearcheck.cases import reference_fretting as rf
from wearcheck.mdr import fretting

R, FORCE, MU, HARDNESS = 0.01, 30.0, 0.3, 2e9
INCREMENTS = 20


def make_case(N, k, frac, normal="force", tangential="displacement", increments=INCREMENTS,
              cycles=None, kn=80.0):
    """The paper's sphere as a paraboloid at u0 = frac·u*; (case, u0, c0)."""
    E_star = 210e9 / (1 - 0.3**2)
    a = ref.hertz(E_star, R, force=FORCE)["contact_radius"]
    base = dict(indenter=dict(profile="paraboloid", radius=R, youngs_modulus=210e9,
                              poisson_ratio=0.3),
                wear=dict(k=k, mu=MU, hardness=HARDNESS), mdr=dict(elements=N))
    probe = cases.from_dict(dict(base, loading=dict(control="force", force=FORCE),
                                 fretting=dict(amplitude=1e-9, cycles=1)))
    u_star = rf.gross_slip_displacement(MU, FORCE, probe.G_star, a)
    u0 = frac * u_star
    loading = (dict(control="force", force=FORCE) if normal == "force"
               else dict(control="depth", depth=a * a / R))
    cycles = cycles or int(min(max(round(kn / k), 1), 100_000))
    fr = dict(cycles=cycles, jump_tolerance=0.02, increments=increments,
              stage_cycles=[0, cycles])
    if tangential == "displacement":
        fr["amplitude"] = u0
    else:
        fr["force_amplitude"] = float(rf.tangential_force(u0, MU, FORCE, u_star))
    case = cases.from_dict(dict(base, loading=loading, fretting=fr))
    return case, u0, rf.stick_radius(a, R, case.E_star, case.G_star, MU, u0)


@contextmanager
def unchecked():
    """The solver without its resolution check (to measure what it refuses)."""
    saved = fretting.WEAR_NUMBER_LIMIT
    fretting.WEAR_NUMBER_LIMIT = math.inf
    try:
        yield
    finally:
        fretting.WEAR_NUMBER_LIMIT = saved


def solve(case):
    c0 = time.process_time()
    try:
        with unchecked():
            return fretting.solve(case), time.process_time() - c0
    except SolverError as e:
        return e, time.process_time() - c0


HEADER = (f"{'N':>5} {'k':>7} {'u0/u*':>5} {'normal':>6} {'tang.':>5} {'Λ':>6} "
          f"{'Δf/w_c':>8} {'c_ref/c0':>9} {'Δc/c0':>9} {'ΔV/V':>9} {'max|Δw|/w':>9} "
          f"{'check':>7} {'cpu s':>6}")


def row(N, k, frac, normal="force", tangential="displacement", kn=80.0):
    """Run the pair, print its row; the numbers as a dict."""
    case, u0, c0 = make_case(N, k, frac, normal, tangential, kn=kn)
    c0 = c0 if c0 > 0.0 else math.nan      # gross slip: no stick zone
    ref_case, _, _ = make_case(N, k, frac, normal, tangential, increments=4 * INCREMENTS, kn=kn)
    (res, t1), (good, t2) = solve(case), solve(ref_case)
    head = f"{N:5d} {k:7.3g} {frac:5.2f} {normal:>6} {tangential[:5]:>5}"
    if isinstance(good, Exception):
        print(f"{head}  reference failed: {good}")
        return None
    if isinstance(res, Exception):
        # the run stopped itself (e.g. the monotone-load guard of §3)
        print(f"{head} {'':>6} {'':>8} {good.history['stick_radius'][-1] / c0:9.5f} "
              f"{'SolverError: ' + str(res)[:60]}")
        return dict(N=N, k=k, frac=frac, normal=normal, tangential=tangential,
                    number=math.nan, failed=True)
    h, hr = res.history, good.history
    u_amp = h["displacement_amplitude"][-1]
    wc = rf.stick_compression(case.E_star, case.G_star, MU, u_amp)
    number = res.info["increment_wear_number"]
    w, wr = res.f[-1] - res.f[0], good.f[-1] - good.f[0]
    out = dict(N=N, k=k, frac=frac, normal=normal, tangential=tangential, number=number,
               wear_over_wc=res.info["largest_wear_per_increment"] / wc,
               dc=(h["stick_radius"][-1] - hr["stick_radius"][-1]) / c0,
               dV=h["wear_volume"][-1] / hr["wear_volume"][-1] - 1.0,
               dw=float(np.max(np.abs(w - wr)) / np.max(np.abs(wr))), failed=False)
    check = "refused" if number > fretting.WEAR_NUMBER_LIMIT else "ok"
    print(f"{head} {number:6.2f} {out['wear_over_wc']:8.2e} "
          f"{hr['stick_radius'][-1] / c0:9.5f} {out['dc']:9.1e} {out['dV']:9.1e} "
          f"{out['dw']:9.1e} {check:>7} {t1 + t2:6.1f}", flush=True)
    return out


def summary(rows):
    """Largest errors among the runs the check returns and smallest among those it refuses."""
    rows = [r for r in rows if r is not None]
    lim = fretting.WEAR_NUMBER_LIMIT
    ok = [r for r in rows if not r["failed"] and r["number"] <= lim]
    bad = [r for r in rows if not r["failed"] and r["number"] > lim]
    print(f"\nreturned (Λ <= {lim:g}): {len(ok)} runs; refused: {len(bad)}; stopped by "
          f"another guard: {sum(r['failed'] for r in rows)}")
    for name, label in (("dc", "|Δc/c0|"), ("dV", "|ΔV/V|"), ("dw", "max|Δw|/w"),
                        ("wear_over_wc", "Δf/w_c")):
        parts = []
        if ok:
            parts.append(f"returned up to {max(abs(r[name]) for r in ok):.2e}")
        if bad:
            parts.append(f"refused {min(abs(r[name]) for r in bad):.2e} to "
                         f"{max(abs(r[name]) for r in bad):.2e}")
        print(f"  {label:>10}: " + "; ".join(parts))


def calibration(quick):
    print("\n1. Calibration: 20 increments per cycle against 80 (errors at the run's end)")
    print(HEADER)
    ks = [1e-4, 1e-2, 0.1, 0.3, 1.0]
    Ns = [200, 400] if quick else [200, 400, 800]
    rows = []
    for normal in ("force", "depth"):
        for frac in (0.2, 0.5, 0.8):
            for N in Ns:
                for k in ks:
                    if quick and k == 1e-4:
                        continue
                    rows.append(row(N, k, frac, normal))
    summary(rows)


def onset(quick):
    print("\n2. Onset of the explicit wear's instability: k set for Λ ≈ 1 ... 4 "
          "(from a resolved run)")
    print(HEADER)
    # (N, u0/u*, normal, tangential, k·n): gross slip (u0 = 2u*) over k·n = 0.5,
    # where the wear of a cycle is already 13-19 % of the depth
    setups = [(800, 0.5, "force", "displacement", 80), (800, 0.2, "force", "displacement", 80),
              (800, 0.8, "force", "displacement", 80), (800, 0.5, "depth", "displacement", 80),
              (800, 0.5, "force", "force", 80), (400, 0.5, "force", "displacement", 80),
              (200, 0.5, "force", "displacement", 80), (200, 2.0, "force", "displacement", 0.5)]
    if quick:
        setups = setups[-3:]
    rows = []
    for N, frac, normal, tangential, kn in setups:
        # Λ ∝ k along the same path in k·n: a resolved probe gives Λ per unit k
        k_probe = 0.2 if frac < 1 else 0.02
        probe, _, _ = make_case(N, k_probe, frac, normal, tangential, kn=kn)
        res, _ = solve(probe)
        per_k = res.info["increment_wear_number"] / k_probe
        for target in (1.0, 1.5, 2.0, 2.5, 3.0, 4.0):
            rows.append(row(N, round(target / per_k, 4), frac, normal, tangential, kn=kn))
    summary(rows)


def linear_limit():
    from wearcheck.mdr import transforms
    print("\n3. Linear stability of the explicit wear: β_max = largest eigenvalue of "
          "(Δr/E*)·(−∂p/∂f) on the contact")
    print(f"{'N':>5} {'u0/u*':>5} {'nodes':>5} {'β_max':>7} {'slip annulus':>12} {'2/β_max':>8}")
    for N in (200, 400, 800):
        for frac in (0.2, 0.5, 0.8):
            case, _, c0 = make_case(N, 0.1, frac, cycles=1)
            model, _ = fretting.build_model(case)
            st = fretting.initial_state(model)
            loaded = np.flatnonzero(st.normal["q"] > 0.0)
            n = loaded[-1] + 1
            # ∂p/∂f column by column: unit height at node j -> g -> q = E*(d - g) -> p
            S = np.empty((n, n))
            for j in range(n):
                e = np.zeros(n)
                e[j] = 1.0
                S[:, j] = transforms.pressure(model.E_star * transforms.to_1d(e), model.dt)
            A = (model.h[:n, None] / model.E_star) * S
            beta = float(np.max(np.linalg.eigvals(A).real))
            ann = np.flatnonzero(model.x[:n] > c0)
            beta_ann = float(np.max(np.linalg.eigvals(A[np.ix_(ann, ann)]).real))
            print(f"{N:5d} {frac:5.1f} {n:5d} {beta:7.4f} {beta_ann:12.4f} {2 / beta:8.4f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N = 200 and 400 only")
    ap.add_argument("--sections", default="1,2,3")
    args = ap.parse_args(argv)
    sections = {int(v) for v in args.sections.split(",")}
    print("note: shared machine (2 cores, several users); CPU seconds are indicative only")
    print(f"solver's limit on Λ: WEAR_NUMBER_LIMIT = {fretting.WEAR_NUMBER_LIMIT:g}")
    if 1 in sections:
        calibration(args.quick)
    if 2 in sections:
        onset(args.quick)
    if 3 in sections:
        linear_limit()


if __name__ == "__main__":
    main()
