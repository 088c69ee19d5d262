"""How many MDR grid cells the unworn contact needs (mdr/resolution.py). Prints a table.

    python benchmarks/bench_mdr_resolution.py [--quick] [--only sphere,cone]

The grid has N cells uniform in t = r² on L = mdr.domain_factor·√2·a0, so the
unworn contact holds n0 = N/(2·domain_factor²) of them. For each profile the
MDR history at n0 = 1 … 128 cells (N varied at the default domain factor,
1.25) is compared with the same run at N = 6400 (n0 = 2048): the largest
difference over the run of F/F0 (depth control) or d/d0 (force control),
and the fitted order in n0 from n0 = 10 on. Part 2 varies the domain factor
at N = 800 on the paper case instead, to show that n0 alone sets the error.
The solver's refusal below MIN_CONTACT_CELLS is lifted here to measure below it.

Profiles (all worn in gross slip to F ≈ 0.25 F0 under depth control, the
paper case's sphere, depth and wear keys): sphere, truncated paraboloid
(b = a0/2), cone, power law f = c r⁴, and cases/ball_on_flat.toml (force
control) for 10⁴ cycles. MIN_CONTACT_CELLS is the smallest n0 at which every
row errs by less than 1 % (the compare default's force tolerance).
"""

from __future__ import annotations

import argparse
import os
import time
from unittest import mock

import numpy as np

import wearcheck
from wearcheck.mdr import resolution

DEPTH = {"sliding.force_fraction": 0.25, "stages.s_hat": [0.0]}
CASES = {
    "sphere": ("paper", DEPTH),
    "truncated": ("paper", {**DEPTH, "indenter.profile": "truncated_paraboloid",
                            "indenter.radius": 0.01, "indenter.flat_radius": 0.5e-4}),
    "cone": ("paper", {**DEPTH, "indenter.profile": "cone", "indenter.slope_angle": 0.0064}),
    "power_law": ("paper", {**DEPTH, "indenter.profile": "power_law",
                            "indenter.coefficient": 3.75e9, "indenter.exponent": 4.0}),
    "ball_on_flat": ("ball_on_flat", {"sliding.cycles": 1e4, "stages.cycles": [0.0]}),
}
CELLS = (1, 2, 3, 4, 6, 8, 10, 12, 16, 24, 32, 64, 128)
REFERENCE_N = 6400


def history(name, changes):
    """ŝ and F/F0 (depth control) or d/d0 (force control) of an MDR run, unchecked grid."""
    case = wearcheck.load_case(name, changes)
    with mock.patch.object(resolution, "check", lambda case: None):
        run = wearcheck.solve(case, "mdr")
    sc = run.scales
    s_hat = run.history["s"] * sc["s_hat_per_m"]
    y = run.history["force"] / sc["F0"] if case.loading.control == "depth" else \
        run.history["depth"] / sc["d0"]
    return s_hat, y


def error(run, ref) -> float:
    """Largest |Δy| over the sliding both runs cover (on 400 points, linear in ŝ)."""
    g = np.linspace(0.0, min(run[0][-1], ref[0][-1]), 400)
    return float(np.max(np.abs(np.interp(g, *run) - np.interp(g, *ref))))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the sphere only")
    parser.add_argument("--only", default="", help="comma-separated profiles: " + ",".join(CASES))
    args = parser.parse_args()
    names = [n for n in (args.only.split(",") if args.only else CASES) if n]
    if args.quick:
        names = ["sphere"]
    print(f"# load average {os.getloadavg()[0]:.2f}; MIN_CONTACT_CELLS = "
          f"{resolution.MIN_CONTACT_CELLS}")
    worst = {}
    for label in names:
        name, changes = CASES[label]
        t = time.perf_counter()
        ref = history(name, {**changes, "mdr.elements": REFERENCE_N})
        print(f"\n## {label} (reference N = {REFERENCE_N}, {time.perf_counter() - t:.1f} s, "
              f"ends at ŝ = {ref[0][-1]:.3g})")
        print("| cells n0 | N | max |Δ| |\n|---|---|---|")
        rows = []
        for n0 in CELLS:
            N = round(n0 * 2 * 1.25**2)
            e = error(history(name, {**changes, "mdr.elements": N}), ref)
            rows.append((N / 3.125, e))
            worst[n0] = max(worst.get(n0, 0.0), e)
            print(f"| {N / 3.125:.3g} | {N} | {e:.2e} |", flush=True)
        fit = [(c, e) for c, e in rows if c >= resolution.MIN_CONTACT_CELLS and e > 0]
        order = -np.polyfit(np.log([c for c, _ in fit]), np.log([e for _, e in fit]), 1)[0]
        print(f"order in n0 (fitted from {fit[0][0]:.3g} cells on): {order:.2f}")
    if "sphere" in names and not args.quick:
        ref = history("paper", {**DEPTH, "mdr.elements": REFERENCE_N})
        print("\n## sphere, N = 800, domain factor varied\n| domain_factor | cells n0 | max |Δ| |"
              "\n|---|---|---|")
        for factor in (1.25, 2.5, 5.0, 8.0, 10.0, 20.0, 40.0):
            e = error(history("paper", {**DEPTH, "mdr.domain_factor": factor}), ref)
            print(f"| {factor:g} | {800 / (2 * factor**2):.3g} | {e:.2e} |", flush=True)
    print("\nworst over the profiles: " + ", ".join(f"{n0}: {e:.2e}" for n0, e in worst.items()))
    ok = [n0 for n0 in CELLS if all(worst[m] < 0.01 for m in CELLS if m >= n0)]
    print(f"fewest cells with every profile within 1 %: {ok[0] if ok else 'none'}")


if __name__ == "__main__":
    main()
