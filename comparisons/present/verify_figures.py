"""The figures of a verification: the reference's curves (lines) and the user's results
(markers) at each judged stage, and the histories against ŝ."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wearcheck.comparisons.analysis import verification
from wearcheck.comparisons.present import figures

#: the reference's curves and the user's points
REFERENCE_STYLE = dict(ls="-", lw=1.4)
RESULTS_STYLE = dict(ls="none", marker="o", ms=3.2, mfc="none", mew=0.9)


def _run_stage(run, s) -> int | None:
    tol = verification.SAME_DISTANCE * max(float(np.max(run.stage_s, initial=0.0)), 1e-300)
    hit = np.flatnonzero(np.abs(np.asarray(run.stage_s, float) - s) <= tol)
    return int(hit[0]) if hit.size else None


def draw(directory: Path, case, m, run, hist, stages) -> list[str]:
    """fig_profiles, fig_pressure (where the user gave them) and history; returns the PNG names."""
    sc = m["scales"]
    a0, p0, d = sc["a0"], sc["p0"], m["profile_scale_depth"]
    pair = m["pairs"]["results"]
    by_s = {st["s"]: st for st in stages}
    prof, pres = [], []
    xmax = 0.0
    for st in pair["stages"]:
        user = by_s.get(st["s"])
        k = _run_stage(run, st["s"])
        if user is None or k is None:
            continue
        label = f"ŝ={st['s_hat_reference']:.3g}"
        r_ref = np.asarray(run.r, float) / a0
        xmax = max(xmax, float(np.max(user["r"])) / a0)
        for key, arr, scale, bucket in (("f", run.f, d, prof), ("p", run.p, p0, pres)):
            if user[key] is None:
                continue
            bucket.append(dict(label=label, series=[
                dict(x=r_ref, y=np.asarray(arr[k], float) / scale,
                     label=f"reference {label}", style=REFERENCE_STYLE),
                dict(x=np.asarray(user["r"]) / a0, y=np.asarray(user[key]) / scale,
                     label=f"results {label}", style=RESULTS_STYLE)]))
    names = []
    xlim = (0.0, xmax or None) if xmax else None
    if prof:
        figures.stage_figure(directory / "fig_profiles", prof, ylabel="f / d",
                             title="worn profiles (reference lines, results markers)",
                             xlim=xlim)
        names.append("fig_profiles.png")
    if pres:
        figures.stage_figure(directory / "fig_pressure", pres, ylabel="p / p0",
                             title="contact pressure (reference lines, results markers)",
                             xlim=xlim)
        names.append("fig_pressure.png")
    history_figure(directory / "history", run.history, hist, sc, d,
                   [st["s_hat_reference"] for st in pair["stages"]])
    names.append("history.png")
    return names


def history_figure(stem, ref_hist, hist, sc, depth, stage_s_hat, formats=("png", "pdf")):
    """F/F0, a/a0, central wear / d and worn volume / (π a0² d) against ŝ: the
    reference's line, the user's rows as markers (the quantities given)."""
    plt = figures._pyplot()
    units = verification.unit_scales(sc, depth)
    panels = [("force", "F / F0"), ("contact_radius", "a / a0"),
              ("wear_center", "w(0) / d"), ("wear_volume", "V / (π a0² d)")]
    fig, axes = plt.subplots(1, 4, figsize=(14.0, 3.6))
    per_m = sc["s_hat_per_m"]
    s_ref = np.asarray(ref_hist["s"], float) * per_m
    s_user = np.asarray(hist["s"], float) * per_m
    # a run over decades of sliding (a lab test to 10^6 cycles) on a logarithmic axis
    positive = s_ref[s_ref > 0]
    log = positive.size > 1 and positive[-1] / positive[0] > 1e4
    shown_ref = s_ref > 0 if log else np.ones(len(s_ref), bool)
    shown_user = s_user > 0 if log else np.ones(len(s_user), bool)
    for ax, (q, label) in zip(axes, panels):
        ax.plot(s_ref[shown_ref], np.asarray(ref_hist[q], float)[shown_ref] / units[q],
                color="C0", label="reference", **REFERENCE_STYLE)
        if q in hist:
            ax.plot(s_user[shown_user], np.asarray(hist[q], float)[shown_user] / units[q],
                    color="C3", label="results", **RESULTS_STYLE)
        for s in stage_s_hat:
            if s > 0 or not log:
                ax.axvline(s, color="0.85", lw=0.6, zorder=0)
        ax.set_xlabel("ŝ" + (" (log)" if log else ""))
        ax.set_ylabel(label)
        if log:
            ax.set_xscale("log")
        ax.grid(alpha=0.3)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.legend(fontsize=7)
    out = figures._save(fig, stem, formats)
    plt.close(fig)
    return out
