"""What a ``wearcheck fit`` costs: n fixed (one MDR run, one at N/2) against n free (a scan).

    python benchmarks/bench_fit.py [--elements 400] [--exponents 1,1.25,...,4] [--workers 2]
                                   [--skip-free]

Makes a measurement sheet from an MDR run of ``ball_on_flat`` at K = 2.3e-15
m³/(N·m) (scar diameters at 1e2 ... 1e5 cycles, ± 2 %), then times, each in a
fresh process (imports and the Dask cluster's start included, as a user meets
them): one plain MDR run of the fit's length (the baseline), the fit with n
fixed, and the fit with n free on an embedded Dask cluster. Prints the wall
times, their ratios to the baseline, and the forward runs' own times.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

import harness

def fit_run(mode: str, sheet: str, elements: int, exponents: str, workers: int) -> dict:
    """One timed job in a fresh process (run by :func:`child`): ``mode`` baseline
    (one MDR run of the fit's length), fixed (n fixed) or free (n free); its
    ``wall`` includes importing wearcheck, as a user meets it."""
    import time
    import warnings
    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    import wearcheck
    case = wearcheck.load_case("ball_on_flat", {"mdr.elements": int(elements)})
    if mode == "baseline":
        from wearcheck.cases import reference
        from wearcheck.studies import fit as F
        data, _, _ = F.read_measurements(sheet, case)
        sc = reference.scales(case)
        start, top = F.plan(case, data, sc["E_star"] / sc["a0"], 1.0)
        r = wearcheck.solve(case.derive(F.forward_changes(case, 1.0, top, start)))
        out = dict(steps=r.info["steps"])
    else:
        keys = ["wear.specific_rate"] + (["wear.pressure_exponent"] if mode == "free" else [])
        ex = [float(v) for v in exponents.split(",")] if exponents else None
        res = wearcheck.fit(case, sheet, keys, exponents=ex, workers=int(workers))
        out = dict(parameters=res.parameters, runs=res.model["runs"],
                   resolution=res.model["resolution"])
    out["wall"] = time.perf_counter() - t0
    return out


def sheet(directory: Path, elements: int) -> Path:
    import wearcheck
    case = wearcheck.load_case("ball_on_flat", {"mdr.elements": elements})
    cycles = np.array([100.0, 300.0, 1e3, 3e3, 1e4, 3e4, 1e5])
    s = 2e-3 * cycles
    run = wearcheck.solve(case.derive({"wear.specific_rate": 2.3e-15,
                                       "sliding.until": "distance",
                                       "sliding.distance": float(s[-1]),
                                       "stages.s": [0.0] + list(s)}))
    h = run.history
    at = [int(np.flatnonzero(np.isclose(h["s"], x, rtol=1e-12))[0]) for x in s]
    D = 2e6 * h["scar_radius"][at]
    noisy = D * (1 + 0.02 * np.random.default_rng(0).standard_normal(len(D)))
    path = directory / "sheet.csv"
    path.write_text("cycles, D [um], ± D [um]\n" + "".join(
        f"{c:.0f}, {d:.2f}, {0.02 * t:.2f}\n" for c, d, t in zip(cycles, noisy, D)))
    return path


def child(mode, path, args) -> dict:
    return harness.call(f"{__file__}:fit_run", mode, str(path), args.elements,
                        args.exponents or "", args.workers,
                        env=dict(os.environ, MPLBACKEND="Agg"))[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--elements", type=int, default=400)
    ap.add_argument("--exponents", default=None)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--skip-free", action="store_true")
    args = ap.parse_args()
    print(f"{harness.load()}; mdr.elements = {args.elements}")
    with tempfile.TemporaryDirectory() as tmp:
        path = sheet(Path(tmp), args.elements)
        base = child("baseline", path, args)
        print(f"one MDR run of the fit's length: {base['wall']:.1f} s ({base['steps']} steps)")
        fixed = child("fixed", path, args)
        K = fixed["parameters"]["wear.specific_rate"]
        print(f"fit, n fixed: {fixed['wall']:.1f} s = {fixed['wall'] / base['wall']:.2f} x; "
              f"K = {K['value']:.4g} [{K['ci95'][0]:.4g}, {K['ci95'][1]:.4g}]; runs "
              + ", ".join(f"{r['seconds']:.1f} s" for r in fixed["runs"])
              + f", N/2 run {fixed['resolution']['seconds']:.1f} s")
        if not args.skip_free:
            t = time.perf_counter()
            free = child("free", path, args)
            runs = free["runs"]
            n = free["parameters"]["wear.pressure_exponent"]
            print(f"fit, n free: {free['wall']:.1f} s = {free['wall'] / base['wall']:.1f} x "
                  f"({len(runs)} exponents on {args.workers} workers); n = {n['value']:.3g} "
                  f"[{n['ci95'][0]:.3g}, {n['ci95'][1]:.3g}]; runs: "
                  + ", ".join(f"n={r['exponent']:g} {r['seconds']:.0f} s ({r['steps']} steps)"
                              for r in runs)
                  + f"; N/2 run {free['resolution']['seconds']:.1f} s")


if __name__ == "__main__":
    main()
