"""What a counterface fit costs: ``wearcheck fit --fit counterface.specific_rate`` (K_ball
held) and with ``--fit wear.specific_rate`` too, against one BEM run.

    python benchmarks/bench_fit_track.py [--grid 80] [--workers 0]

Makes a G133 measurement sheet from a BEM run of ``ball_on_flat_steel`` at
K_ball = 2e-15, K_flat = 1.3e-14 m³/(N·m) (the ball's scar diameter, the
track's depth and width at 50 ... 2000 cycles, ± 2 %), then times, each in a
fresh process (imports included, as a user meets them): one BEM run of the
fit's length at the true rates (the baseline), the fit of K_flat with K_ball
held, and the fit of both. ``--workers N``: the runs on a Dask cluster of N
workers (0: one after another in the process). Prints the wall times, their
ratios to the baseline, the runs' own times and the rates found.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

import numpy as np

import harness

K_BALL, K_FLAT = 2e-15, 1.3e-14
CYCLES = np.array([50.0, 100.0, 250.0, 500.0, 1000.0, 2000.0])


def fit_run(mode: str, sheet: str, grid: int, workers: int) -> dict:
    """One timed job in a fresh process: ``mode`` baseline, flat (K_flat, K_ball held) or
    both."""
    import time
    import warnings
    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    import wearcheck
    case = wearcheck.load_case("ball_on_flat_steel", {"bem.grid": int(grid),
                                                      "wear.specific_rate": K_BALL})
    if mode == "baseline":
        s_max = 0.02 * CYCLES[-1]
        r = wearcheck.solve(case.derive({"counterface.specific_rate": K_FLAT,
                                         "sliding.until": "distance",
                                         "sliding.distance": 1.05 * s_max,
                                         "stages.s_hat": [0.0] + list(np.logspace(-3, 2.5, 12))}),
                            solver="bem")
        out = dict(steps=r.info["steps"])
    else:
        keys = ["counterface.specific_rate"] + (["wear.specific_rate"] if mode == "both" else [])
        res = wearcheck.fit(case, sheet, keys, workers=int(workers) or None)
        out = dict(parameters=res.parameters, runs=res.model["runs"], seconds=res.seconds,
                   resolution=res.model["resolution"], warnings=res.warnings)
    out["wall"] = time.perf_counter() - t0
    return out


def sheet(directory: Path, grid: int) -> Path:
    import warnings
    warnings.simplefilter("ignore")
    import wearcheck
    case = wearcheck.load_case("ball_on_flat_steel", {"bem.grid": grid})
    s = 0.02 * CYCLES
    run = wearcheck.solve(case.derive({"wear.specific_rate": K_BALL,
                                       "counterface.specific_rate": K_FLAT,
                                       "sliding.until": "distance",
                                       "sliding.distance": float(s[-1]),
                                       "stages.s": [0.0] + list(s)}), solver="bem")
    h = run.history
    at = [int(np.flatnonzero(np.isclose(h["s"], x, rtol=1e-12))[0]) for x in s]
    rng = np.random.default_rng(0)
    cols = {"D": 2e6 * h["scar_radius"][at], "track depth": 1e6 * h["track_depth"][at],
            "track width": 1e6 * h["track_width"][at]}
    lines = ["cycles, " + ", ".join(f"{n} [um], ± {n} [um]" for n in cols)]
    for i, c in enumerate(CYCLES):
        cells = [f"{c:.0f}"]
        for v in cols.values():
            cells += [f"{v[i] * (1 + 0.02 * rng.standard_normal()):.5g}", f"{0.02 * v[i]:.4g}"]
        lines.append(", ".join(cells))
    path = directory / "sheet.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def child(mode, path, args) -> dict:
    return harness.call(f"{__file__}:fit_run", mode, str(path), args.grid, args.workers,
                        env=dict(os.environ, MPLBACKEND="Agg"))[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=80)
    ap.add_argument("--workers", type=int, default=0)
    args = ap.parse_args()
    print(f"{harness.load()}; bem.grid = {args.grid}, workers = {args.workers or 'none'}")
    with tempfile.TemporaryDirectory() as tmp:
        path = sheet(Path(tmp), args.grid)
        base = child("baseline", path, args)
        print(f"one BEM run of the fit's length: {base['wall']:.1f} s ({base['steps']} steps)")
        for mode, what in (("flat", "K_flat (K_ball held)"), ("both", "K_ball and K_flat")):
            out = child(mode, path, args)
            params = "; ".join(f"{k} = {p['value']:.4g} [{p['ci95'][0]:.4g}, {p['ci95'][1]:.4g}]"
                               for k, p in out["parameters"].items())
            runs = out["runs"]
            print(f"fit of {what}: {out['wall']:.1f} s = {out['wall'] / base['wall']:.1f} x; "
                  f"{len(runs)} runs ({sum(r['seconds'] for r in runs):.1f} s: "
                  + ", ".join(f"{r['ratio']:.3g}: {r['seconds']:.1f} s" for r in runs)
                  + f"); {params}")
            check = out["resolution"]
            if isinstance(check, dict):
                print(f"  widths' check: {check['seconds']:.1f} s at bem.grid {check['grid']}, "
                      f"{check['quantity']} {100 * check['largest_change']:+.2g} %")
            for w in out["warnings"]:
                print(f"  note: {w}")


if __name__ == "__main__":
    main()
