"""What ``wearcheck fit`` shows: the text it prints and its figure (measurements, the
fitted model, the lab formula and the residuals)."""

from __future__ import annotations

import math

import numpy as np

from wearcheck.extras import need
from wearcheck.comparisons.analysis.fitting import LABELS, lab_track_volume

#: how each quantity is drawn: label, unit shown and factor from SI
_SHOWN = {"scar_diameter": ("scar diameter D", "µm", 1e6),
          "ball_volume": ("ball volume V", "mm³", 1e9),
          "wear_center": ("central wear depth h", "µm", 1e6),
          "track_width": ("track width w", "µm", 1e6),
          "track_depth": ("track depth", "µm", 1e6),
          "track_area": ("track cross-section A", "µm²", 1e12),
          "track_volume": ("track volume", "mm³", 1e9)}


def _lab_line(quantity, K_lab, s, case):
    """The lab formula's quantity for V = K F s (inverting π D⁴/64R, π h²(3R − h)/3 ≈ π R h²,
    and the track's formulas, the width's and depth's numerically)."""
    R, F = case.indenter.radius, case.loading.force
    V = K_lab * F * np.asarray(s, float)
    if quantity == "scar_diameter":
        return (64.0 * R * V / math.pi) ** 0.25
    if quantity == "wear_center":
        return np.sqrt(V / (math.pi * R))
    if quantity in ("track_width", "track_depth"):
        # the formula's volume grows monotonically with w (δ) up to the ball's 2R (R)
        top = 2.0 * R if quantity == "track_width" else R
        grid = np.geomspace(top * 1e-7, top, 4000)
        return np.interp(V, lab_track_volume(quantity, grid, R, case.sliding), grid,
                         right=np.nan)
    if quantity == "track_area":
        return V / lab_track_volume("track_area", 1.0, R, case.sliding)
    return V


def figure(result, path=None, axes=None):
    """Draw one panel per measured quantity (log-log against sliding: data with error
    bars, the fitted model, the lab formula's line) and one of the residuals.

    ``axes``: a sequence of as many matplotlib Axes as quantities plus one, to draw
    into; without it a figure is made (and saved to ``path``). Returns the axes.
    """
    matplotlib = need("matplotlib", "drawing figures")
    if axes is None and path is not None:
        matplotlib.use("Agg", force=False)
    # lazy (a): matplotlib, the optional "plot" extra
    import matplotlib.pyplot as plt
    rows = result.measurements
    quantities = [q for q in _SHOWN if any(r["quantity"] == q for r in rows)]
    fig = None
    if axes is None:
        fig, axes = plt.subplots(1, len(quantities) + 1, figsize=(4.2 * (len(quantities) + 1), 3.8))
    case = result.case
    cycles = all(r["cycles"] is not None for r in rows) and case.cycles_per_metre is not None
    x_of = (lambda s: np.asarray(s) * case.cycles_per_metre) if cycles else (lambda s: s)
    xlabel = "cycles" if cycles else "sliding distance s [m]"
    s_curve, model = result.curve
    solver = result.model["solver"].upper()
    fitted = result.fitted_case
    for ax, q in zip(axes, quantities):
        track = q.startswith("track_")
        K = fitted.counterface_wear_rate if track else fitted.wear_rate
        label, unit, f = _SHOWN[q]
        mine = [r for r in rows if r["quantity"] == q]
        s = np.array([r["s"] for r in mine])
        y = np.array([r["measured"] for r in mine])
        err = [r["uncertainty"] for r in mine]
        ax.errorbar(x_of(s), y * f, yerr=None if err[0] is None else np.array(err) * f,
                    fmt="o", ms=4, color="k", label="measured")
        name = "K_flat" if track else "K"
        ax.plot(x_of(s_curve), model[q] * f, "-", color="C0",
                label=f"{solver}, {name} = {K:.3g} m³/(N·m)")
        K_lab = result.lab[q]["K"]
        ax.plot(x_of(s_curve), _lab_line(q, K_lab, s_curve, case) * f, "--", color="C1",
                label=f"lab formula, {name} = {K_lab:.3g}")
        ax.set(xscale="log", yscale="log", xlabel=xlabel, ylabel=f"{label} [{unit}]")
        ax.legend(fontsize=8)
    ax = axes[len(quantities)]
    weighted = rows[0]["uncertainty"] is not None
    for k, q in enumerate(quantities):
        mine = [r for r in rows if r["quantity"] == q]
        res = np.array([r["residual"] for r in mine]) * (1.0 if weighted else 100.0)
        ax.plot(x_of([r["s"] for r in mine]), res, "o", ms=4, color=f"C{k + 2}",
                label=_SHOWN[q][0])
    ax.axhline(0.0, color="0.5", lw=0.8)
    if weighted:
        for band in (-2.0, 2.0):
            ax.axhline(band, color="0.7", lw=0.8, ls=":")
    gof = result.goodness_of_fit
    verdict = {True: "fits", False: "does NOT fit", None: "fit not tested"}[gof["fits"]]
    ax.set(xscale="log", xlabel=xlabel,
           ylabel="(measured − model)/σ" if weighted else "ln(measured/model) [%]",
           title=f"residuals: {verdict} (p = {gof['p_value']:.2g})")
    ax.legend(fontsize=8)
    if fig is not None:
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=120)
            plt.close(fig)
    return axes


def _g(v, spec=".4g"):
    if v is None:
        return ""
    return "inf" if isinstance(v, float) and math.isinf(v) else format(v, spec)


def text(result) -> str:
    """The text ``wearcheck fit`` prints: parameters, the lab formula, the residuals."""
    runs = result.model["runs"]
    against = ("the MDR, the ball alone" if result.model["solver"] == "mdr" else
               "the BEM, both bodies wearing (long-stroke model)")
    lines = [f"fit of {', '.join(result.keys)} to {len(result.measurements)} measurements "
             f"({result.source}) against {against}: {len(runs)} run(s), "
             f"{sum(r['seconds'] for r in runs):.3g} s of {result.seconds:.3g} s",
             "", f"{'parameter':<24} {'value':>11}  95 % interval"]
    for key, p in result.parameters.items():
        lo, hi = p["ci95"]
        unit = "" if p["unit"] == "1" else f" {p['unit']}"
        lines.append(f"{key:<24} {_g(p['value']):>11}  [{_g(lo)}, "
                     f"{_g(hi) if hi is not None else 'open'}]{unit}")
    lines.append(f"  ({result.interval_method})")
    for q, lab in result.lab.items():
        name = "K_flat" if q.startswith("track_") else "K"
        lines.append(f"lab formula from {LABELS[q][0]}: {name} = {_g(lab['K'])} m^3/(N m)  "
                     f"({lab['formula']})")
    gof = result.goodness_of_fit
    if gof["test"] == "chi2":
        test = (f"χ² = {_g(gof['statistic'])} for {gof['dof']} degrees of freedom "
                f"(χ²/ν = {_g(gof['reduced_chi2'], '.3g')})")
    else:
        test = ("no trend of the residuals with ln s tested (" + gof.get("note", "") + ")"
                if gof.get("note") else
                f"trend of the residuals with ln s: F = {_g(gof['statistic'])} on "
                f"{gof['dof'][0]}, {gof['dof'][1]} degrees of freedom")
    if gof["fits"] is None:
        lines.append(f"goodness of fit: not tested: too few measurements to test the model's "
                     f"fit: {gof['measurements']} points, {gof['parameters']} parameter(s) "
                     f"({test})")
    else:
        verdict = "the model fits" if gof["fits"] else "the model does NOT fit"
        out = gof["outliers"]
        if out["tested"]:
            test += (f"; outliers: largest |{out['statistic']}| "
                     f"{max(abs(v) for v in out['values']):.3g}, limit {out['limit']:.3g}")
        lines.append(f"goodness of fit: {test}, p = {_g(gof['p_value'], '.3g')}: {verdict}")
    weighted = result.measurements[0]["uncertainty"] is not None
    lines += ["", f"{'row':>4} {'cycles':>10} {'s [m]':>10} {'quantity':<22} {'measured':>11} "
                  f"{'±':>9} {'model':>11} {'residual':>9} {'lab K':>10}"]
    for m in result.measurements:
        res = f"{m['residual']:+.2f}" if weighted else f"{100 * m['residual']:+.2f}%"
        lines.append(f"{m['row']:>4} {_g(m['cycles']):>10} {_g(m['s']):>10} "
                     f"{LABELS[m['quantity']][0]:<22} {_g(m['measured']):>11} "
                     f"{_g(m['uncertainty'], '.3g'):>9} {_g(m['model']):>11} {res:>9} "
                     f"{_g(m['lab_K'], '.3g'):>10}")
    lines.append("(SI: m, m^2, m^3; residual (measured − model)/±" if weighted else
                 "(SI: m, m^2, m^3; residual ln(measured/model)")
    lines[-1] += "; lab K = V_lab/(F s) of each measurement)"
    return "\n".join(lines)
