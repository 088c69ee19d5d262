"""The edge peak of paper Section 4: an interior local maximum of p(r) near the contact edge.

Pure functions: a pressure profile in, the peak's position and height out, and
a rule that says from runs at several resolutions whether the peak is a
converged feature or changes with the resolution.
"""

from __future__ import annotations

import math

import numpy as np

from . import metrics

#: the outer part of the contact searched for a peak, r/a >= OUTER
OUTER = 0.5
#: a local maximum counts as a peak when its prominence exceeds this fraction of max p
MIN_PROMINENCE = 1e-3
#: where the pressure just inside the edge is probed, r/a (Hertz: sqrt(1 - 0.98²) ≈ 0.2)
EDGE_PROBE = 0.98


def find_edge_peak(r, p, a, *, outer=OUTER, min_prominence=MIN_PROMINENCE) -> dict:
    """The most prominent interior local maximum of p(r) in outer·a <= r < a.

    A node i is a local maximum when p[i] > p[i-1] and p[i] >= p[i+1] (the node
    beyond the last one in contact has p = 0). Its prominence is p[i] minus the
    lowest pressure at r <= r[i] (the dip inward of it).

    Parameters
    ----------
    r : (M,) increasing radii [m]; p : (M,) pressure [Pa]; a : contact radius [m].
    outer : where the outer part of the contact starts, as a fraction of a.
    min_prominence : prominences below this fraction of max p are noise, not a peak.

    Returns
    -------
    dict: present, r_over_a, height (p_peak / p(0)), prominence (/ p(0)),
    prominence_of_max (/ max p), at_last_node (the peak is the outermost node in
    contact: not resolved by the grid), edge_height (p at r = EDGE_PROBE·a, linearly
    interpolated, / p(0): how abruptly p falls to zero at the edge), p_center [Pa].
    """
    r = np.asarray(r, float)
    p = np.asarray(p, float)
    none = dict(present=False, r_over_a=math.nan, height=math.nan, prominence=math.nan,
                prominence_of_max=0.0, at_last_node=False, edge_height=math.nan,
                p_center=float(p[0]))
    inside = np.flatnonzero((r < a) & (p > 0))
    if inside.size < 3 or a <= 0:
        return none
    last = inside[-1]
    if p[0] > 0:
        none["edge_height"] = float(np.interp(EDGE_PROBE * a, r, p) / p[0])
    pp = np.append(p[: last + 1], 0.0)  # zero beyond the last node in contact
    i = np.arange(1, last + 1)
    is_max = (pp[i] > pp[i - 1]) & (pp[i] >= pp[i + 1]) & (r[i] >= outer * a)
    cand = i[is_max]
    if cand.size == 0:
        return none
    dip = np.minimum.accumulate(pp)[cand]
    prom = pp[cand] - dip
    j = int(np.argmax(prom))
    ipk, pmax = int(cand[j]), float(np.max(pp))
    p_center = float(p[0])
    rel = (lambda v: v / p_center) if p_center > 0 else (lambda v: math.inf)
    return dict(present=bool(prom[j] >= min_prominence * pmax),
                r_over_a=float(r[ipk] / a), height=float(rel(pp[ipk])),
                prominence=float(rel(prom[j])), prominence_of_max=float(prom[j] / pmax),
                at_last_node=bool(ipk == last), edge_height=none["edge_height"],
                p_center=p_center)


def stage_peaks(r, p, a, **kw) -> list[dict]:
    """``find_edge_peak`` for each stage: p is (K, M), a is (K,)."""
    return [find_edge_peak(r, p[k], a[k], **kw) for k in range(len(a))]


def assess(levels: list[dict], *, position_tol=0.02, prominence_tol=0.2) -> list[dict]:
    """Whether each stage's peak is a converged feature, from runs at several resolutions.

    Parameters
    ----------
    levels : runs of one solver, each a dict with ``label``, ``spacing`` (grid
        spacing / a0, smaller is finer) and ``peaks`` (``stage_peaks`` output).
        The first level is the reference (the case as given).
    position_tol : allowed spread of the peak position r/a over the levels (plus
        one grid spacing of the coarsest level, the resolution of a position).
    prominence_tol : allowed relative spread of the peak's prominence.

    Returns
    -------
    one dict per stage: ``verdict`` ("no peak" | "converged" | "resolution-dependent"),
    ``reason`` and the per-level numbers. A peak seen at every level, at the same
    place and of the same prominence, is converged; one seen at some levels only,
    or moving, or growing or shrinking with the resolution, is resolution-dependent;
    a peak on the outermost node in contact at every level is not resolved by any
    grid and is reported as resolution-dependent.
    """
    K = min(len(lv["peaks"]) for lv in levels)
    out = []
    for k in range(K):
        pk = [lv["peaks"][k] for lv in levels]
        seen = [q["present"] for q in pk]
        row = dict(stage=k, levels=[dict(label=lv["label"], spacing=lv["spacing"], **q)
                                    for lv, q in zip(levels, pk)])
        if not any(seen):
            row.update(verdict="no peak", reason="no level shows an interior maximum")
        elif not all(seen):
            shown = [lv["label"] for lv, s in zip(levels, seen) if s]
            row.update(verdict="resolution-dependent",
                       reason="seen only at " + ", ".join(shown))
        else:
            pos = np.array([q["r_over_a"] for q in pk])
            prom = np.array([q["prominence_of_max"] for q in pk])
            coarse = max(lv["spacing"] for lv in levels)
            spread_pos = float(pos.max() - pos.min())
            spread_prom = float((prom.max() - prom.min()) / prom.max())
            if all(q["at_last_node"] for q in pk):
                row.update(verdict="resolution-dependent",
                           reason="the maximum sits on the outermost node in contact at "
                                  "every level (not resolved)")
            elif spread_pos > position_tol + coarse:
                row.update(verdict="resolution-dependent",
                           reason=f"position r/a moves by {spread_pos:.3f} between levels")
            elif spread_prom > prominence_tol:
                row.update(verdict="resolution-dependent",
                           reason=f"prominence changes by {100 * spread_prom:.0f}% between "
                                  "levels")
            else:
                row.update(verdict="converged",
                           reason=f"seen at every level; r/a within {spread_pos:.3f}, "
                                  f"prominence within {100 * spread_prom:.0f}%")
        out.append(row)
    return out


def peaks_of(result, sc) -> list[dict]:
    """The edge peak of each stage of one run (contact radius from its history)."""
    a = metrics.at_stages(result.history["s"], result.history["contact_radius"],
                          result.stage_s)
    peaks = stage_peaks(result.r, np.asarray(result.p), a)
    for q, s in zip(peaks, result.stage_s):
        q["s_hat"] = float(s * sc["s_hat_per_m"])
    return peaks
