"""Coverage of the 95 % intervals when both rates are fitted (K_ball and K_flat together).

    python benchmarks/coverage_fit_track.py [DRAWS]

``tests/test_fit_track.py`` measures the coverage of K_flat alone (K_ball held)
over 100 draws; the 2-D profiles of a joint fit cost a few seconds a draw, too
much for the suite, so this script measures it: ``ball_on_flat_steel`` at 40²
(sliding.tolerance 1e-3), the ball's central wear and the track's depth at
10 to 300 cycles from a run at K_ball = 2e-15, K_flat = 1.3e-14, ± 2 % noise
per draw; five runs at ratios a factor 2 apart around 6.5 (not on the grid),
reused over the draws. Prints the running counts and the coverage of each rate.
"""

import math
import sys
import time
import warnings

import numpy as np

import wearcheck
from wearcheck import registry
from wearcheck.cases import reference
from wearcheck.comparisons.analysis import fitting
from wearcheck.studies import fit_track

warnings.simplefilter("ignore")
K_BALL, K_FLAT = 2e-15, 1.3e-14
CYCLES = np.geomspace(10.0, 300.0, 5)
S = 0.02 * CYCLES


def main(draws: int) -> None:
    case = wearcheck.load_case("ball_on_flat_steel", {"bem.grid": 40, "sliding.tolerance": 1e-3})
    run = registry.solve(case.derive({"wear.specific_rate": K_BALL,
                                      "counterface.specific_rate": K_FLAT,
                                      "sliding.until": "distance",
                                      "sliding.distance": float(S[-1]),
                                      "stages.s": [0.0] + list(S)}), "bem")
    h = run.history
    at = [int(np.flatnonzero(np.isclose(h["s"], s, rtol=1e-12))[0]) for s in S]
    truth = fit_track.curves_of({k: np.asarray(v)[at] for k, v in h.items()}).values
    sc = reference.scales(case)
    c = sc["E_star"] / sc["a0"]
    top, start = 2 * K_BALL * c * S[-1], 1e-3 * K_BALL * c * S[0]
    ratios = np.log(6.5) + np.log(2.0) * (np.arange(5) - 2.3)
    family = fitting.RatioCurves(ratios, tuple(fit_track.curves_of(registry.solve(case.derive(
        fit_track.forward_changes(case, K_BALL, r, top, start)), "bem").history)
        for r in ratios))
    lo, hi = math.log(1e-6 / (c * S[-1])), math.log(100 * top / (c * S[-1]))
    ball = flat = 0
    t = time.perf_counter()
    for seed in range(draws):
        rng = np.random.default_rng(seed)
        names = ("wear_center", "track_depth")
        y = np.concatenate([truth[q] * (1 + 0.02 * rng.standard_normal(len(S))) for q in names])
        sigma = np.concatenate([0.02 * truth[q] for q in names])
        data = fitting.Data(np.tile(S, 2), np.repeat(names, len(S)), y, sigma)
        found = fitting.fit_rates(family, data, c, ("ball", "flat"), 0.0, 0.0, lo, hi)
        a, b = found["intervals"]["ball"]
        ball += a is not None and b is not None and a <= math.log(K_BALL) <= b
        a, b = found["intervals"]["flat"]
        flat += a is not None and b is not None and a <= math.log(K_FLAT) <= b
        print(f"draw {seed}: K_ball {ball}/{seed + 1}, K_flat {flat}/{seed + 1}, "
              f"{time.perf_counter() - t:.1f} s", flush=True)
    print(f"coverage over {draws} draws: K_ball {ball}, K_flat {flat}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 100)
