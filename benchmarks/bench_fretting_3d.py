"""A 3D check of the MDR's fretting mapping with the BEM (issue 12, §5). Prints a table.

    python benchmarks/bench_fretting_3d.py [--n 129] [--increments 2] [--pixels 65,97,129]
                                           [--quick]

Table 1: the BEM's pixel convergence on the unworn sphere against the closed
forms written with G* (Cattaneo–Mindlin stick radius, Mindlin–Deresiewicz
energy per cycle, the force at +u0): exact at ν = 0, the size of Cattaneo–
Mindlin's approximation at ν = 0.3.

Table 2 (the comparison):
For ν = 0 and ν = 0.3 (cases/fretting.toml with indenter.poisson_ratio set,
rigid counterface, amplitude u0 = 0.18 µm held), the MDR fretting run to
10^5 cycles gives worn profiles after 0 (unworn), 10, 10^3, 10^5 cycles.
On each profile, under the same normal force and the cycle ±u0:

- MDR: the tangential springs over a ramp and one cycle, wear off (the
  profile held), :func:`wearcheck.studies.fretting3d.mdr_fretting`;
- BEM: normal contact on n × n pixels (box 2.4 a), tangential contact with
  Coulomb discs and the Cerruti coupling, :func:`wearcheck.studies.fretting3d.bem_fretting`.

Columns: stick radius (MDR; BEM equivalent √(A/π) and its half-widths along
x and y), stick-area difference, the largest difference of τx along the x
and y axes from MDR's τ(r) and the largest |τy| (in μ max p), energy per
cycle (MDR, BEM, difference), tangential force at +u0 (difference), solve
times. The machine is shared (2 cores, several users): times are indicative.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from wearcheck import mdr
from wearcheck.cases import load
from wearcheck.cases import reference_fretting as rf
from wearcheck.studies import fretting3d

ROOT = Path(__file__).resolve().parents[1]
STAGES = (0, 10, 1000, 100000)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=129, help="BEM pixels per side (odd)")
    ap.add_argument("--increments", type=int, default=2,
                    help="BEM increments per quarter cycle")
    ap.add_argument("--pixels", default="65,97,129",
                    help="pixels per side of table 1 (unworn sphere)")
    ap.add_argument("--quick", action="store_true", help="n = 65, stages 0 and 10")
    args = ap.parse_args(argv)
    n = 65 if args.quick else args.n
    stages = STAGES[:2] if args.quick else STAGES
    print("# 3D check of the MDR fretting mapping with the BEM "
          "(shared 2-core machine: times indicative)")
    pixels = [65] if args.quick else [int(v) for v in args.pixels.split(",")]
    pixel_convergence(pixels, args.increments)
    rows = []
    print("\n## MDR against BEM on the MDR's profiles (BEM on "
          f"{n if n % 2 else n + 1}² pixels)")
    for nu in (0.0, 0.3):
        case = load(ROOT / "cases" / "fretting.toml",
                    [f"indenter.poisson_ratio={nu}", f"fretting.cycles={stages[-1]}",
                     "fretting.stage_cycles=[" + ", ".join(map(str, stages)) + "]"])
        t0 = time.perf_counter()
        run = mdr.solve(case)
        t_run = time.perf_counter() - t0
        cycles = list(run.info["stage_cycles"])
        fr = case.fretting
        R, F = case.indenter.radius, case.loading.force
        u_star = run.info["gross_slip_displacement_unworn"]
        print(f"\nν = {nu}: E* = {case.E_star/1e9:.1f} GPa, G* = {case.G_star/1e9:.1f} GPa, "
              f"u0 = {fr.amplitude*1e6:.3f} µm = {fr.amplitude/u_star:.3f} u* (unworn); "
              f"MDR run to {cycles[-1]} cycles in {t_run:.1f} s")
        for k, cyc in enumerate(cycles):
            if cyc not in stages:
                continue
            f = run.f[k]
            t0 = time.perf_counter()
            m = fretting3d.mdr_fretting(case, f)
            t_mdr = time.perf_counter() - t0
            t0 = time.perf_counter()
            b = fretting3d.bem_fretting(run.r, f, R, F, case.E_star, case.G_star, case.wear.mu,
                                        fr.amplitude, m["contact_radius"], n=n,
                                        increments=args.increments)
            t_bem = time.perf_counter() - t0
            d = fretting3d.compare(m, b, case.wear.mu)
            a = m["contact_radius"]
            rows.append(dict(nu=nu, cycles=cyc, a=a, **d, t_mdr=t_mdr, t_bem=t_bem,
                             loop=b["loop_work"] / b["energy_per_cycle"],
                             a_bem=b["contact_radius"]))
            print_row(rows[-1], header=(k == 0 and nu == 0.0))
            sys.stdout.flush()
    print("\nc: stick radius over the MDR contact radius a of the stage; BEM c = √(A_stick/π),"
          "\ncx, cy its half-widths on the axes; Δτx: max |τx,BEM - τMDR(|x|)|"
          "\non the x / y axis over μ max p; rms: RMS of τx,BEM - τMDR(ρ) over the contact;"
          "\nτy: max |τy,BEM| over μ max p; W: energy per cycle; ΔQ: tangential force at +u0;"
          "\nloop: ∮Q dδ / W of the BEM (energy balance, trapezoidal rule on "
          f"{4 * args.increments} increments per cycle).")
    return rows


def pixel_convergence(pixels, increments):
    """Table 1: BEM on the unworn sphere against the closed forms with G*."""
    print("\n## BEM on the unworn sphere against Cattaneo–Mindlin / Mindlin–Deresiewicz "
          "(written with G*)")
    print(f"{'ν':>4} {'n':>4} {'Δ/a':>7} {'a_BEM/a':>8} {'c_BEM/c':>8} {'cx/c':>6} {'cy/c':>6} "
          f"{'Q/Q_CM':>8} {'W/W_MD':>8} {'τy/μp0':>7} {'t s':>6}")
    for nu in (0.0, 0.3):
        case = load(ROOT / "cases" / "fretting.toml", [f"indenter.poisson_ratio={nu}"])
        R, F, mu, u0 = (case.indenter.radius, case.loading.force, case.wear.mu,
                        case.fretting.amplitude)
        a = (3.0 * F * R / (4.0 * case.E_star)) ** (1.0 / 3.0)
        u_star = rf.gross_slip_displacement(mu, F, case.G_star, a)
        c = rf.stick_radius(a, R, case.E_star, case.G_star, mu, u0)
        Q = float(rf.tangential_force(u0, mu, F, u_star))
        W = rf.energy_per_cycle_displacement(u0, mu, F, u_star)
        r = np.linspace(0.0, 3.0 * a, 3001)
        for n in pixels:
            t0 = time.perf_counter()
            b = fretting3d.bem_fretting(r, r**2 / (2 * R), R, F, case.E_star, case.G_star, mu,
                                        u0, a, n=n, increments=increments)
            t = time.perf_counter() - t0
            p0 = 3 * F / (2 * math.pi * a * a)
            print(f"{nu:>4.1f} {b['n']:>4d} {b['pixel']/a:>7.4f} {b['contact_radius']/a:>8.4f} "
                  f"{b['stick_radius']/c:>8.4f} {b['stick_extent_x']/c:>6.3f} "
                  f"{b['stick_extent_y']/c:>6.3f} {b['tangential_force']/Q:>8.5f} "
                  f"{b['energy_per_cycle']/W:>8.5f} {b['tau_y_max']/(mu*p0):>7.4f} {t:>6.1f}")
            sys.stdout.flush()


def print_row(r, header=False):
    if header:
        print(f"{'ν':>4} {'cycles':>7} {'a µm':>7} {'c MDR':>7} {'c BEM':>7} {'cx':>6} "
              f"{'cy':>6} {'ΔA_st':>7} {'Δτx(x)':>7} {'Δτx(y)':>7} {'rms':>6} {'τy':>6} "
              f"{'W MDR nJ':>9} {'W BEM nJ':>9} {'ΔW':>7} {'ΔQ':>7} {'loop':>6} {'Δ/a':>6} "
              f"{'t MDR':>6} {'t BEM':>6}")
    a = r["a"]
    print(f"{r['nu']:>4.1f} {r['cycles']:>7d} {a*1e6:>7.2f} {r['stick_radius_mdr']/a:>7.4f} "
          f"{r['stick_radius_bem']/a:>7.4f} {r['stick_extent_x']/a:>6.3f} "
          f"{r['stick_extent_y']/a:>6.3f} {r['stick_area_rel']:>+7.2%} {r['tau_diff_x']:>7.3f} "
          f"{r['tau_diff_y']:>7.3f} {r['tau_rms']:>6.3f} {r['tau_y_max']:>6.3f} "
          f"{r['energy_mdr']*1e9:>9.4f} "
          f"{r['energy_bem']*1e9:>9.4f} {r['energy_rel']:>+7.2%} {r['force_rel']:>+7.2%} "
          f"{r['loop']:>6.3f} {r['pixel']/a:>6.4f} {r['t_mdr']:>6.2f} {r['t_bem']:>6.1f}")


if __name__ == "__main__":
    main()
