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


def draw(directory: Path, case, m, run, hist, stages, judged=None) -> list[str]:
    """fig_profiles, fig_pressure (where the user gave them) and history; returns the PNG
    names. ``judged``: the history rows' relative differences
    (:func:`verification.row_differences`) for the history's difference panels."""
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
                   [st["s_hat_reference"] for st in pair["stages"]], judged=judged,
                   failed=failing_rows(pair))
    names.append("history.png")
    return names


#: the history panels: quantity, the value's label, the difference's label
PANELS = (("force", "F / F0", "ΔF / F"), ("contact_radius", "a / a0", "Δa / a"),
          ("wear_center", "w(0) / d", "Δw(0) / w(0)"),
          ("wear_volume", "V / (π a0² d)", "ΔV / V"), ("depth", "depth / d", "Δd / d"))
#: the difference panels show at most this many tolerances either side; a row beyond is
#: drawn at the edge as a triangle pointing out (a unit slip would flatten the band)
CLIP_TOLERANCES = 12.0


def failing_rows(pair) -> dict:
    """{quantity: sorted history row indices whose check failed}: the rows between the
    stages (``pair["rows"]["failed_rows"]``) and the stages' own rows."""
    out = {q: set(v) for q, v in (pair.get("rows") or {}).get("failed_rows", {}).items()}
    for st in pair["stages"]:
        for q, c in st["checks"].items():
            if q in verification.HISTORY_CHECKS and not c["passed"] and st.get("row") is not None:
                out.setdefault(q, set()).add(st["row"])
    return {q: sorted(v) for q, v in out.items()}


def history_figure(stem, ref_hist, hist, sc, depth, stage_s_hat, formats=("png", "pdf"),
                   judged=None, failed=None):
    """The history against ŝ (see :func:`history_axes`), saved as ``stem``.png/pdf."""
    plt = figures._pyplot()
    fig = history_axes(ref_hist, hist, sc, depth, stage_s_hat, judged=judged, failed=failed)
    out = figures._save(fig, stem, formats)
    plt.close(fig)
    return out


def history_axes(ref_hist, hist, sc, depth, stage_s_hat, *, judged=None, failed=None):
    """F/F0, a/a0, central wear / d, worn volume / (π a0² d) (and depth / d, where
    given) against ŝ: the reference's line, the user's rows as markers; below each,
    the rows' signed difference relative to the scale the check judges it against
    (``judged``: :func:`verification.row_differences`), in %, with the tolerance as a
    band, and the rows whose check failed (``failed``: {quantity: row indices}) as
    red crosses. On linear axes an 8 % force error looks like agreement; in the
    difference panel it lies outside the ±3 % band. Returns the matplotlib figure."""
    plt = figures._pyplot()
    units = verification.unit_scales(sc, depth)
    judged, failed = judged or {}, failed or {}
    panels = [p for p in PANELS if p[0] != "depth" or p[0] in hist]
    fig, axes = plt.subplots(2, len(panels), figsize=(3.4 * len(panels), 6.0),
                             layout="constrained", sharex="col",
                             gridspec_kw=dict(height_ratios=(3, 2)))
    per_m = sc["s_hat_per_m"]
    s_ref = np.asarray(ref_hist["s"], float) * per_m
    s_user = np.asarray(hist["s"], float) * per_m
    # a run over decades of sliding (a lab test to 10^6 cycles) on a logarithmic axis
    positive = s_ref[s_ref > 0]
    log = positive.size > 1 and positive[-1] / positive[0] > 1e4
    shown_ref = s_ref > 0 if log else np.ones(len(s_ref), bool)
    shown_user = s_user > 0 if log else np.ones(len(s_user), bool)
    for (top, low), (q, label, dlabel) in zip(axes.T, panels):
        if q in ref_hist:
            top.plot(s_ref[shown_ref], np.asarray(ref_hist[q], float)[shown_ref] / units[q],
                     color="C0", label="reference", **REFERENCE_STYLE)
        if q in hist:
            top.plot(s_user[shown_user], np.asarray(hist[q], float)[shown_user] / units[q],
                     color="C3", label="results", **RESULTS_STYLE)
        bad = np.asarray(failed.get(q, []), int)
        bad = bad[shown_user[bad]] if bad.size else bad
        if bad.size:
            top.plot(s_user[bad], np.asarray(hist[q], float)[bad] / units[q], ls="none",
                     marker="x", ms=5, color="red", mew=1.2, gid="failed",
                     label=f"failed ({bad.size} row(s))")
        top.set_ylabel(label)
        top.ticklabel_format(axis="y", useOffset=False)
        lo, hi = top.get_ylim()
        if hi - lo < 1e-3 * max(abs(lo), abs(hi)):
            # a constant (the depth of a displacement-controlled case): ±1 % of it, not
            # round-off spread over the axis with labels of ten digits
            mid = 0.5 * (lo + hi)
            top.set_ylim(mid - 0.01 * abs(mid), mid + 0.01 * abs(mid))
        top.legend(fontsize=7)
        _difference_panel(low, q, dlabel, s_user, shown_user, judged.get(q), bad)
        low.set_xlabel("ŝ" + (" (log)" if log else ""))
        for ax in (top, low):
            for s in stage_s_hat:
                if s > 0 or not log:
                    ax.axvline(s, color="0.85", lw=0.6, zorder=0)
            if log:
                ax.set_xscale("log")
            ax.grid(alpha=0.3)
    fig.suptitle("history: the reference (line), your rows (markers); below, each row's "
                 "difference relative to the scale its check judges it against, with the "
                 "tolerance band (failed rows: red ×)", fontsize=9)
    return fig


def _difference_panel(ax, q, label, s_user, shown, judged, bad):
    """The rows' relative difference in %, the tolerance band ±tol, failed rows marked."""
    if judged is None:
        ax.text(0.5, 0.5, "not given", transform=ax.transAxes, ha="center", va="center",
                color="0.5")
        ax.set_yticks([])
        return
    tol = 100.0 * judged["tolerance"]
    v = 100.0 * np.asarray(judged["value"], float)
    ok = shown & np.isfinite(v)
    cap = CLIP_TOLERANCES * tol
    ax.axhspan(-tol, tol, color="C2", alpha=0.15, lw=0, gid="tolerance",
               label=f"tolerance ±{tol:g} %")
    for y in (-tol, tol):
        ax.axhline(y, color="C2", lw=0.8, gid="tolerance_line")
    ax.axhline(0.0, color="0.4", lw=0.6)
    clipped = np.clip(v, -cap, cap)
    inside = ok & (np.abs(v) <= cap)
    ax.plot(s_user[inside], clipped[inside], color="C3", label="results", **RESULTS_STYLE)
    for sign, marker in ((1, "^"), (-1, "v")):
        out = ok & (sign * v > cap)
        if out.any():
            ax.plot(s_user[out], clipped[out], ls="none", marker=marker, ms=5, color="C3",
                    label=f"beyond ±{cap:g} %")
    if bad.size:
        ax.plot(s_user[bad], clipped[bad], ls="none", marker="x", ms=6, color="red", mew=1.2,
                gid="failed", label="failed")
    span = max(2.0 * tol, 1.15 * float(np.max(np.abs(clipped[ok]), initial=0.0)))
    ax.set_ylim(-span, span)
    ax.set_ylabel(label + " [%]")
    ax.legend(fontsize=6.5, loc="best")
