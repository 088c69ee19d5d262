"""What the uncoupled (elastically similar) model neglects: the BEM with ``bem.coupling``. Prints tables.

    python benchmarks/bench_coupling.py [--grid 128] [--ball-grid 256] [--tolerance 1e-5]
                                        [--static 64,128,256] [--quick]
                                        [--scaling-grid 64] [--only scaling]

Table 1, the closed form: a Hertz contact (force control) in gross slip with
the friction traction μp along +x coupled into the normal problem. The centre
of pressure moves to x_c = -3βμa/(2π) at first order in βμ
(docs/bem-tangential.md §6); columns: x_c over that, the force change at the
Hertz depth (second order) and the peak pressure, per grid.

Table 2, the wear runs: cases/paper.toml (depth control, to 1 % of the force)
and cases/ball_on_flat.toml (force control, 10^6 cycles), each run three
times on the same grid and time tolerance: uncoupled (β taken as 0, what
every solver does), coupled with one sliding direction (+x), and coupled
with reciprocating strokes. paper.toml has no stroke: its reciprocating run
sets sliding.stroke (the averaged model does not depend on its length);
ball_on_flat.toml's one-direction run slides the same distance without one.
Per stage: F/F0 uncoupled and the relative force change ΔF/F of each coupled
run; the centre of pressure x_c/a (the +x stroke's when reciprocating); the
largest pressure change over the stage's peak (all pixels, and inside 0.9 a:
the edge pixels move with the contact's shift); the largest change of the
wear depth over the stage's central wear, and the wear's antisymmetric part
(w - its mirror image in x)/2 over the same; the largest change of the
ring-averaged profile (what `compare` sees) over d (d0 under force control).

Table 3, the second order of reciprocating strokes: paper.toml with
reciprocating strokes at μ = 0.15, 0.3, 0.6 (βμ = 0.043, 0.086, 0.171; the
wear coefficient kμ/σ0 changes with μ, the run in ŝ does not) against one
uncoupled run. Per stage ΔF/F and the ring-averaged profile's change over d,
each divided by (βμ)²: the constants of the O((βμ)²) law, which collapse
when it holds; and the slope of log|ΔF/F| on log βμ.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import tomllib

import numpy as np

from wearcheck import bem, cases
from wearcheck.bem import contact, tangential
from wearcheck.bem.operator import HalfSpace
from wearcheck.cases import reference


def load() -> str:
    return "load average %.2f %.2f %.2f" % os.getloadavg()


def static_table(grids):
    """Hertz, force control, a = 1, R = 10, E* = 1: x_c against -3βμa/(2π)."""
    a, R, E = 1.0, 10.0, 1.0
    p0 = 2 * E * a / (math.pi * R)
    F = 2 * p0 * math.pi * a * a / 3
    d = a * a / R
    print("\n## Table 1: sliding Hertz contact, x_c against the first-order closed form")
    print("| grid | pixels/a | β | μ | βμ | x_c / (-3βμa/2π) | ΔF/F at the Hertz depth "
          "| p_max/p0 | sweeps' CG iterations |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n in grids:
        dx = 3.0 * a / n
        x = (np.arange(n) - n // 2) * dx
        X, Y = np.meshgrid(x, x, indexing="ij")
        h = (X**2 + Y**2) / (2 * R)
        op = HalfSpace(n, dx, E)
        kw = dict(p_scale=p0, g_scale=d, tol=1e-9)
        base = contact.solve(op, h, force=F, **kw)
        base_d = contact.solve(op, h, depth=d, **kw)
        for beta, mu in ((0.2857, 0.1), (0.2857, 0.3), (0.5, 0.5)):
            sh = tangential.ShearToNormal(n, dx, beta, E)
            c = contact.solve_coupled(op, sh, h, mu, force=F, p_init=base.pressure, **kw)
            cd = contact.solve_coupled(op, sh, h, mu, depth=d, p_init=base_d.pressure, **kw)
            xc = float(np.sum(X * c.pressure) / np.sum(c.pressure))
            pred = -3 * beta * mu * a / (2 * math.pi)
            print(f"| {n} | {a / dx:.1f} | {beta:g} | {mu:g} | {beta * mu:.4f} | {xc / pred:.5f} "
                  f"| {cd.force / base_d.force - 1:+.2e} | {c.pressure.max() / p0:.5f} "
                  f"| {c.iterations} |")


def paper_cases(grid, tol):
    raw = tomllib.loads(cases.shipped("paper").read_text())
    raw["bem"] = dict(grid=grid)
    raw["sliding"]["tolerance"] = tol
    one = dict(raw, bem=dict(grid=grid, coupling=True))
    rec = dict(one, sliding=dict(raw["sliding"], stroke=1e-3))
    return cases.from_dict(raw), cases.from_dict(one), cases.from_dict(rec)


def ball_cases(grid, tol):
    raw = tomllib.loads(cases.shipped("ball_on_flat").read_text())
    raw["bem"] = dict(raw.get("bem", {}), grid=grid)
    raw["sliding"]["tolerance"] = tol
    off = cases.from_dict(raw)
    rec = cases.from_dict(dict(raw, bem=dict(raw["bem"], coupling=True)))
    sl = {k: v for k, v in raw["sliding"].items() if k not in ("stroke", "cycles")}
    sl.update(until="distance", distance=off.end_distance)
    one = cases.from_dict(dict(raw, sliding=sl, stages=dict(s_hat=list(off.stages.s_hat)),
                               bem=dict(raw["bem"], coupling=True)))
    return off, one, rec


def mirror(field):
    """The field's mirror image x -> -x about the tip (pixel n//2); pixel 0 of even n kept."""
    n = field.shape[0]
    lo = 2 * (n // 2) - (n - 1)
    out = field.copy()
    out[lo:] = field[lo:][::-1]
    return out


def stage_rows(case, res):
    """Per stage: s_hat, F, a, pressure field, wear field, ring profile, x_c."""
    sc = reference.scales(case)
    h = res.history
    x = res.fields["x"]
    X, Y = np.meshgrid(x, x, indexing="ij")
    out = []
    for k, s in enumerate(res.stage_s):
        p = res.fields["pressure"][k]
        out.append(dict(s_hat=s * sc["s_hat_per_m"], F=float(np.interp(s, h["s"], h["force"])),
                        a=float(np.interp(s, h["s"], h["contact_radius"])), p=p,
                        w=res.fields["wear_depth"][k], f=res.f[k], rho=np.hypot(X, Y),
                        xc=float(np.sum(X * p) / np.sum(p))))
    return out


def dp(run, ref):
    """Largest pressure change over the stage's peak: all pixels (inside 0.9 a)."""
    change = np.abs(run["p"] - ref["p"]) / ref["p"].max()
    return f"{np.max(change):.3f} ({np.max(change[ref['rho'] < 0.9 * ref['a']]):.3f})"


def wear_table(name, trio):
    off_case = trio[0]
    sc = reference.scales(off_case)
    d = off_case.loading.depth if off_case.loading.control == "depth" else sc["d0"]
    runs, secs = [], []
    for case in trio:
        t0 = time.perf_counter()
        res = bem.solve(case)
        secs.append(time.perf_counter() - t0)
        runs.append(stage_rows(case, res))
    beta = cases.dundurs_beta(off_case.indenter, off_case.counterface)
    print(f"\n## Table 2: {name}, grid {off_case.bem.grid}, β = {beta:.4f}, μ = "
          f"{off_case.wear.mu:g}, βμ = {beta * off_case.wear.mu:.4f}, sliding.tolerance "
          f"{off_case.sliding.tolerance:g}; solve times uncoupled / one direction / "
          f"reciprocating {secs[0]:.1f} / {secs[1]:.1f} / {secs[2]:.1f} s")
    print("| ŝ | F/F0 (β = 0) | ΔF/F one dir. | ΔF/F recip. | x_c/a one dir. | x_c/a recip. "
          "| max Δp / p_max one (r < 0.9a) | max Δp / p_max recip. (r < 0.9a) "
          "| max Δw / w_c one | antisym. w / w_c one "
          "| max Δw / w_c recip. | max Δf_ring / d one | max Δf_ring / d recip. |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    n = off_case.bem.grid
    for k, ref in enumerate(runs[0]):
        one, rec = runs[1][k], runs[2][k]
        pmax = ref["p"].max()
        wc = ref["w"][n // 2, n // 2]
        cells = [f"{ref['s_hat']:.4g}", f"{ref['F'] / sc['F0']:.5f}",
                 f"{one['F'] / ref['F'] - 1:+.2e}", f"{rec['F'] / ref['F'] - 1:+.2e}",
                 f"{one['xc'] / ref['a']:+.4f}", f"{rec['xc'] / ref['a']:+.4f}",
                 dp(one, ref), dp(rec, ref)]
        if wc > 0:
            cells += [f"{np.max(np.abs(one['w'] - ref['w'])) / wc:.2e}",
                      f"{np.max(np.abs(one['w'] - mirror(one['w']))) / (2 * wc):.2e}",
                      f"{np.max(np.abs(rec['w'] - ref['w'])) / wc:.2e}"]
        else:
            cells += ["–", "–", "–"]
        cells += [f"{np.max(np.abs(one['f'] - ref['f'])) / d:.2e}",
                  f"{np.max(np.abs(rec['f'] - ref['f'])) / d:.2e}"]
        print("| " + " | ".join(cells) + " |")


def scaling_table(grid, tol, mus=(0.15, 0.3, 0.6)):
    """Reciprocating strokes on paper.toml at three βμ against one uncoupled run."""
    raw = tomllib.loads(cases.shipped("paper").read_text())
    raw["bem"] = dict(grid=grid)
    raw["sliding"]["tolerance"] = tol
    off = cases.from_dict(raw)
    runs = [stage_rows(off, bem.solve(off))]
    beta = cases.dundurs_beta(off.indenter, off.counterface)
    t0 = time.perf_counter()
    for mu in mus:
        rec = cases.from_dict(dict(raw, bem=dict(grid=grid, coupling=True),
                                   wear=dict(raw["wear"], mu=mu),
                                   sliding=dict(raw["sliding"], stroke=1e-3)))
        runs.append(stage_rows(rec, bem.solve(rec)))
    bm = [beta * mu for mu in mus]
    d = off.loading.depth
    print(f"\n## Table 3: paper.toml, reciprocating, grid {grid}, sliding.tolerance {tol:g}; "
          f"ΔF/F and max Δf_ring/d over (βμ)² at βμ = "
          + ", ".join(f"{b:.4f}" for b in bm)
          + f"; slope of log|ΔF/F| on log βμ ({time.perf_counter() - t0:.0f} s)")
    print("| ŝ | F/F0 (β = 0) | ΔF/F/(βμ)² | Δf_ring/d/(βμ)² | slope ΔF | slope Δf_ring |")
    print("|---|---|---|---|---|---|")
    sc = reference.scales(off)
    for k, ref in enumerate(runs[0]):
        dF = [r[k]["F"] / ref["F"] - 1 for r in runs[1:]]
        df = [float(np.max(np.abs(r[k]["f"] - ref["f"]))) / d for r in runs[1:]]

        def slope(v):
            v = np.abs(v)
            return f"{np.polyfit(np.log(bm), np.log(v), 1)[0]:.2f}" if np.all(v > 0) else "–"
        print(f"| {ref['s_hat']:.4g} | {ref['F'] / sc['F0']:.5f} | "
              + ", ".join(f"{x / b**2:+.3f}" for x, b in zip(dF, bm)) + " | "
              + ", ".join(f"{x / b**2:.3f}" for x, b in zip(df, bm))
              + f" | {slope(dF)} | {slope(df)} |")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=128, help="paper.toml's pixels per side")
    ap.add_argument("--ball-grid", type=int, default=256,
                    help="ball_on_flat.toml's pixels per side (its shipped value)")
    ap.add_argument("--tolerance", type=float, default=1e-5,
                    help="sliding.tolerance of every run (time error well below the effect)")
    ap.add_argument("--static", default="64,128,256", help="grids of table 1")
    ap.add_argument("--quick", action="store_true", help="grids 32/128, table 1 at 64 only")
    ap.add_argument("--scaling-grid", type=int, default=64, help="paper.toml's grid in table 3")
    ap.add_argument("--only", choices=("static", "wear", "scaling"),
                    help="print one table only")
    args = ap.parse_args(argv)
    grid, ball, static = args.grid, args.ball_grid, [int(g) for g in args.static.split(",")]
    if args.quick:
        grid, ball, static = 32, 128, [64]
    print("# Normal-tangential coupling in the BEM (" + load() + "; shared 2-core machine)")
    print("# " + " ".join(sys.argv))
    if args.only in (None, "static"):
        static_table(static)
    if args.only in (None, "wear"):
        wear_table("paper.toml", paper_cases(grid, args.tolerance))
        wear_table("ball_on_flat.toml", ball_cases(ball, args.tolerance))
    if args.only in (None, "scaling"):
        scaling_table(args.scaling_grid, args.tolerance)
    print("# " + load())


if __name__ == "__main__":
    main()
