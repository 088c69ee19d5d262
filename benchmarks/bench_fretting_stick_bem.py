"""The stick radius's growth under force control seen by the 3D BEM (docs/fretting.md, §2.1).

    python benchmarks/bench_fretting_stick_bem.py [--n 129] [--elements 800] [--quick]

The MDR runs the paraboloid of tests/test_fretting_stick_growth.py (the
paper's sphere, F = 30 N, u0 = 0.5 u*, k = 0.1, force control) to its
limiting state and keeps the worn profiles at several cycle counts. On each
profile, under the same normal force F and the cycle ±u0:

- MDR: ramp and one cycle on the held profile (wear off),
  :func:`wearcheck.studies.fretting3d.mdr_fretting`;
- BEM: its own normal contact of the profile on n × n pixels and the
  tangential contact with Coulomb discs and the Cerruti coupling,
  :func:`wearcheck.studies.fretting3d.bem_fretting` (stick radius
  √(A_stick/π)).

The BEM shares no contact or friction code with the MDR; if it finds the same
growth of the stick radius on the same profiles, the growth is not an
artefact of the MDR's 1D springs. Columns: c over Cattaneo–Mindlin's c0 for
the run (MDR history), the held-profile MDR cycle and the BEM, the BEM's
growth relative to its own unworn value (which cancels its pixel bias), the
BEM's depth rise (its rigid-body approach), and times. The machine is shared
(2 cores, several users): times are indicative.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from wearcheck import cases, mdr
from wearcheck.cases import reference as ref
from wearcheck.cases import reference_fretting as rf
from wearcheck.studies import fretting3d

R, FORCE, MU, K = 0.01, 30.0, 0.3, 0.1


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=129, help="BEM pixels per side (odd)")
    ap.add_argument("--elements", type=int, default=800)
    ap.add_argument("--increments", type=int, default=2,
                    help="BEM increments per quarter cycle")
    ap.add_argument("--quick", action="store_true", help="n = 65, N = 200, stages 0 and 800")
    args = ap.parse_args(argv)
    n, N = (65, 200) if args.quick else (args.n, args.elements)
    stages = [0, 800] if args.quick else [0, 10, 30, 100, 300, 800]
    E_star = 210e9 / (1 - 0.3**2)
    a = ref.hertz(E_star, R, force=FORCE)["contact_radius"]
    base = dict(indenter=dict(profile="paraboloid", radius=R, youngs_modulus=210e9,
                              poisson_ratio=0.3),
                loading=dict(control="force", force=FORCE),
                wear=dict(k=K, mu=MU, hardness=2e9), mdr=dict(elements=N))
    probe = cases.from_dict(dict(base, fretting=dict(amplitude=1e-9, cycles=1)))
    u0 = 0.5 * rf.gross_slip_displacement(MU, FORCE, probe.G_star, a)
    case = cases.from_dict(dict(base, fretting=dict(amplitude=u0, cycles=stages[-1],
                                                    increments=20, jump_tolerance=0.02,
                                                    stage_cycles=stages)))
    c0, c_max = rf.stick_radius_bounds(FORCE, case.E_star, case.G_star, MU, u0, R)
    print("# stick radius growth under force control: MDR and 3D BEM on the MDR's worn "
          "profiles (shared 2-core machine: times indicative)")
    t0 = time.perf_counter()
    run = mdr.solve(case)
    print(f"MDR run: N = {N}, k = {K}, {stages[-1]} cycles in {time.perf_counter() - t0:.1f} s; "
          f"c0 = {c0 / a:.4f} a (Cattaneo–Mindlin), c_max = {c_max / c0:.4f} c0; "
          f"BEM {n if n % 2 else n + 1}² pixels, box 2.4 a")
    h = run.history
    print(f"{'cycles':>6} {'c run/c0':>9} {'c MDR/c0':>9} {'c BEM/c0':>9} {'BEM growth':>10} "
          f"{'d/d0 MDR':>9} {'pixel/c0':>8} {'t BEM s':>7}")
    bem0 = None
    for k, cyc in enumerate(run.info["stage_cycles"]):
        f = run.f[k]
        m = fretting3d.mdr_fretting(case, f)
        t0 = time.perf_counter()
        b = fretting3d.bem_fretting(run.r, f, R, FORCE, case.E_star, case.G_star, MU, u0,
                                    m["contact_radius"], n=n, increments=args.increments)
        t_bem = time.perf_counter() - t0
        bem0 = bem0 or b["stick_radius"]
        i = int(np.searchsorted(h["cycles"], cyc))
        print(f"{cyc:>6d} {h['stick_radius'][i] / c0:>9.4f} {m['stick_radius'] / c0:>9.4f} "
              f"{b['stick_radius'] / c0:>9.4f} {b['stick_radius'] / bem0:>10.4f} "
              f"{h['depth'][i] / (a * a / R):>9.4f} {b['pixel'] / c0:>8.4f} {t_bem:>7.1f}")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
