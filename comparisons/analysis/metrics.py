"""Differences between a solver's result and a reference solver's result of one case
(pure: arrays in, numbers out).

Solvers store their stages on different radii (MDR: its uniform grid; FEM: the
contact-node radii; BEM: rings one pixel wide). Differences are taken on the
compared solver's radii, with the reference's fields linearly interpolated onto
them.

Every difference is reported in the case's unworn scales (profiles by the depth
d, pressures by p0, forces by F0, contact radii by a0): those are the columns of
the tables. The verdict judges each stage against its own scale instead (see
:data:`CHECKS`): late in a wear run the force and the pressure are small
fractions of F0 and p0, and a tolerance in F0 could not fail there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Check:
    """One check that decides the verdict.

    The stage's difference ``column`` (in the unworn scale ``unit``) is divided
    by the stage's own scale (``scale``, in words), floored at ``floor`` (a
    [compare] key, in the same unworn unit), and must not exceed ``tolerance``
    (a [compare] key). ``label`` and ``difference`` name it in reports.
    """

    column: str
    tolerance: str
    floor: str
    unit: str
    scale: str
    label: str
    difference: str


#: the checks that decide the verdict; the scale each one is judged against
CHECKS = (
    Check("profile_contact_max", "profile_tolerance", "profile_floor", "d",
          "the reference's depth at the stage (the approach of the unworn tip, which "
          "includes the central wear), or its central wear if larger",
          "profile", "max |Δf| over the contact and its edge band"),
    Check("force", "force_tolerance", "force_floor", "F0",
          "the reference's normal force at the stage", "force", "|ΔF|"),
    Check("pressure_interior_max", "pressure_tolerance", "pressure_floor", "p0",
          "the reference's peak pressure at the stage (outside a band left out around a "
          "singularity)", "pressure", "max |Δp| in the interior"),
    Check("contact_radius", "contact_radius_tolerance", "contact_radius_floor", "a0",
          "the reference's contact radius at the stage", "contact radius", "|Δa|"),
)
#: the wear checks ``wearcheck verify`` adds where a user's history gives the quantity
#: (a solver's run is judged by CHECKS alone): lengths against the stage's own
#: value like the profile, the worn volume in V = π a0² d
WEAR_CHECKS = (
    Check("wear_center", "profile_tolerance", "profile_floor", "d",
          "the reference's central wear at the stage", "central wear", "|Δw(0)|"),
    Check("wear_volume", "profile_tolerance", "profile_floor", "V",
          "the reference's worn volume at the stage (V = π a0² d)", "worn volume", "|ΔV|"),
    Check("depth", "profile_tolerance", "profile_floor", "d",
          "the reference's depth at the stage", "depth", "|Δd|"),
)
#: the checks by their column
CHECK_BY_COLUMN = {c.column: c for c in CHECKS + WEAR_CHECKS}


def to_grid(r_src, y_src, r_dst) -> np.ndarray:
    """Linear interpolation of y(r_src) onto r_dst; NaN outside the range of r_src."""
    return np.interp(np.asarray(r_dst, float), np.asarray(r_src, float),
                     np.asarray(y_src, float), left=np.nan, right=np.nan)


def max_rms(diff) -> tuple[float, float, int]:
    """Max |diff|, RMS of diff over its finite entries, and their count (NaN, NaN, 0 if none)."""
    d = np.asarray(diff, float)
    d = d[np.isfinite(d)]
    if d.size == 0:
        return math.nan, math.nan, 0
    return float(np.max(np.abs(d))), float(np.sqrt(np.mean(d**2))), int(d.size)


def at_stages(history_s, values, stage_s) -> np.ndarray:
    """A history column (one value per step) read at the stage distances, linearly."""
    return np.interp(np.asarray(stage_s, float), np.asarray(history_s, float),
                     np.asarray(values, float))


def edge_masks(r, a_1, a_2, edge_band):
    """Masks of the contact interior and of its edge band on the radii r.

    Interior: r < (1 - edge_band) min(a_1, a_2), away from both solvers' edges.
    Edge band: (1 - edge_band) min(a_1, a_2) <= r <= (1 + edge_band) max(a_1, a_2).
    """
    r = np.asarray(r, float)
    inner = (1.0 - edge_band) * min(a_1, a_2)
    outer = (1.0 + edge_band) * max(a_1, a_2)
    return r < inner, (r >= inner) & (r <= outer)


def stage_differences(r, f_1, f_2, p_1, p_2, a_1, a_2, *, depth, p0, edge_band,
                      exclude=None) -> dict:
    """Profile and pressure differences of one stage, both given on the radii r.

    Parameters
    ----------
    r : (M,) radii [m]; f_*, p_* : (M,) profiles [m] and pressures [Pa] of the two
        solvers on r (NaN where one is not defined); a_* : contact radii [m].
    depth, p0 : the scales of profile and pressure.
    edge_band : fraction of the contact radius reported separately at the edge.
    exclude : optional (M,) mask of radii left out of the pressure interior
        (e.g. around a known singularity).

    Returns
    -------
    dict of max and RMS differences relative to depth and p0: the profile over
    all r and over the contact (r up to the edge band's outer end, where the
    profile is of the order of the depth; beyond it f grows as r² and its
    difference measures the solvers' grids, not their wear), the pressure in the
    interior and in the edge band.
    """
    df = (np.asarray(f_1, float) - np.asarray(f_2, float)) / depth
    dp = (np.asarray(p_1, float) - np.asarray(p_2, float)) / p0
    interior, edge = edge_masks(r, a_1, a_2, edge_band)
    contact = interior | edge | (np.asarray(r, float) <= min(a_1, a_2))
    if exclude is not None:
        interior = interior & ~np.asarray(exclude, bool)
    out = {}
    out["profile_max"], out["profile_rms"], out["profile_points"] = max_rms(df)
    (out["profile_contact_max"], out["profile_contact_rms"],
     out["profile_contact_points"]) = max_rms(df[contact])
    (out["pressure_interior_max"], out["pressure_interior_rms"],
     out["pressure_interior_points"]) = max_rms(dp[interior])
    out["pressure_edge_max"], out["pressure_edge_rms"], out["pressure_edge_points"] = \
        max_rms(dp[edge])
    return out


def stage_scale(own, floor) -> tuple[float, str]:
    """The scale a stage is judged against: its own magnitude, or ``floor`` where that
    is smaller (or undefined). Returns the scale and "stage" or "floor"."""
    if np.isfinite(own) and own > floor:
        return float(own), "stage"
    return float(floor), "floor"


def verdict(stage: dict, tolerances: dict, checks=CHECKS) -> dict:
    """Each check of one stage against its tolerance, relative to the stage's own scale.

    ``stage`` holds the differences in unworn units (the columns of :data:`CHECKS`)
    and ``stage_scales``, the stage's own magnitudes in the same units. Returns
    {column: {value, tolerance, scale, scale_from, unit, unworn, passed}}: value =
    unworn / scale, scale = max(the stage's magnitude, the floor), unworn the
    difference in the unworn unit. A NaN value (nothing to compare) fails: a check
    that compared nothing passes nothing. ``checks``: the checks to make (default
    :data:`CHECKS`).
    """
    out = {}
    for c in checks:
        column = float(stage[c.column])
        scale, source = stage_scale(stage["stage_scales"][c.column], tolerances[c.floor])
        value = column / scale
        tol = tolerances[c.tolerance]
        out[c.column] = dict(value=value, tolerance=tol, scale=scale, scale_from=source,
                             unit=c.unit, unworn=column,
                             passed=bool(np.isfinite(value) and value <= tol))
    return out


def peak_pressure(r, p, exclude_radius=None, exclude_width=0.0) -> float:
    """Largest pressure on the radii r, outside |r - exclude_radius| < exclude_width
    (a singular band whose grid values are not comparable); NaN if none is left."""
    r, p = np.asarray(r, float), np.asarray(p, float)
    keep = np.isfinite(p)
    if exclude_radius is not None:
        keep &= np.abs(r - exclude_radius) >= exclude_width
    return float(np.max(p[keep])) if keep.any() else math.nan


def compare_results(ref, other, *, s_hat_per_m, a0, F0, p0, depth, tolerances, edge_band,
                    exclude_radius=None, exclude_width=0.0) -> dict:
    """Compare a result with the reference's (``cases.RunResult``-like) stage by stage.

    Stage k of one result is the k-th requested ŝ; the stages both reached are
    compared. Forces, contact radii and depths at a stage are the history values
    read at the stage's sliding distance.

    Parameters
    ----------
    ref, other : the reference's and the compared solver's results: objects with
        history (dict), stage_s, r, f, p. Differences are other minus reference,
        on other's radii.
    s_hat_per_m, a0, F0, p0 : scales (``cases.reference.scales``).
    depth : profile scale d (the held depth, or the unworn depth d0 under force control).
    tolerances : the ``[compare]`` tolerances and floors as a dict.
    edge_band : fraction of the contact radius treated as edge.
    exclude_radius, exclude_width : optionally leave |r - exclude_radius| <
        exclude_width out of the pressure interior and of the peak pressure (a
        singularity at r = b).

    Returns
    -------
    dict with ``stages`` (list of per-stage dicts: the differences in unworn
    units, ``stage_scales`` and ``checks``), ``worst``, ``history`` (force and
    contact radius over the common sliding range) and ``passed``.
    """
    K = min(len(ref.stage_s), len(other.stage_s))
    h = ref.history
    a_m = at_stages(h["s"], h["contact_radius"], ref.stage_s)
    a_f = at_stages(other.history["s"], other.history["contact_radius"], other.stage_s)
    F_m = at_stages(h["s"], h["force"], ref.stage_s)
    F_f = at_stages(other.history["s"], other.history["force"], other.stage_s)
    d_m = at_stages(h["s"], h["depth"], ref.stage_s)
    w_m = at_stages(h["s"], h["wear_center"], ref.stage_s)
    r = np.asarray(other.r, float)
    stages = []
    for k in range(K):
        f_m = to_grid(ref.r, ref.f[k], r)
        p_m = to_grid(ref.r, ref.p[k], r)
        exclude = None
        if exclude_radius is not None:
            exclude = np.abs(r - exclude_radius) < exclude_width
        st = dict(index=k,
                  s_hat_reference=float(ref.stage_s[k] * s_hat_per_m),
                  s_hat_solver=float(other.stage_s[k] * s_hat_per_m),
                  force_reference=float(F_m[k] / F0), force_solver=float(F_f[k] / F0),
                  contact_radius_reference=float(a_m[k] / a0),
                  contact_radius_solver=float(a_f[k] / a0))
        st["force"] = abs(st["force_reference"] - st["force_solver"])
        st["contact_radius"] = abs(st["contact_radius_reference"] - st["contact_radius_solver"])
        st.update(stage_differences(r, f_m, other.f[k], p_m, other.p[k], a_m[k], a_f[k],
                                    depth=depth, p0=p0, edge_band=edge_band, exclude=exclude))
        st["stage_scales"] = dict(
            profile_contact_max=max(abs(float(d_m[k])), abs(float(w_m[k]))) / depth,
            force=abs(st["force_reference"]),
            pressure_interior_max=peak_pressure(ref.r, ref.p[k], exclude_radius,
                                                exclude_width) / p0,
            contact_radius=st["contact_radius_reference"])
        st["checks"] = verdict(st, tolerances)
        st["passed"] = all(c["passed"] for c in st["checks"].values())
        stages.append(st)
    hist = history_differences(ref.history, other.history, F0=F0, a0=a0)
    return dict(stages=stages, stages_compared=K, worst=worst(stages),
                stages_reached=dict(reference=len(ref.stage_s), solver=len(other.stage_s)),
                history=hist,
                passed=bool(K > 0 and all(st["passed"] for st in stages)))


#: relative tolerance on a solver's stage sliding distances against the requested ones.
#: The shared stepper lands every stage exactly (MDR, FEM and BEM store the requested
#: s bit for bit); 1e-6 leaves room for a result written to text with ~7 digits and
#: read back, and is far below any unit slip (1e-3, 1e3) or a few-percent scaling.
SLIDING_DISTANCE_RTOL = 1e-6


def sliding_distance_check(stage_s, history_s, requested_s, rtol=SLIDING_DISTANCE_RTOL) -> dict:
    """Whether a result's stages sit at the requested sliding distances.

    Each stored stage k must be at the requested s_k, to ``rtol`` of max(|s_k|, the
    last requested s) (so the ŝ = 0 stage is judged on the run's scale), and lie within
    the history's sliding range, to the same tolerance. Returns {passed, tolerance,
    value (the largest relative difference), stage, s_solver, s_requested, history_s_min,
    history_s_max, reason} with stage/reason naming the first mismatch (None if none).
    """
    stage_s = np.asarray(stage_s, float)
    req = np.asarray(requested_s, float)
    hs = np.asarray(history_s, float)
    K = min(len(stage_s), len(req))
    scale = float(np.max(np.abs(req))) if len(req) else 1.0
    scale = scale if scale > 0 else 1.0
    lo = float(np.nanmin(hs)) if hs.size else math.nan
    hi = float(np.nanmax(hs)) if hs.size else math.nan
    rel = np.abs(stage_s[:K] - req[:K]) / np.maximum(np.abs(req[:K]), scale)
    out = dict(tolerance=rtol, value=float(np.max(rel)) if K else 0.0, stage=None,
               s_solver=None, s_requested=None, history_s_min=lo, history_s_max=hi,
               reason=None)
    for k in range(K):
        s_k, r_k = float(stage_s[k]), float(req[k])
        bad = None
        if not (np.isfinite(s_k) and rel[k] <= rtol):
            bad = "stage"
        elif not (lo - rtol * scale <= s_k <= hi + rtol * scale):
            bad = "history"
        if bad:
            out.update(stage=k, s_solver=s_k, s_requested=r_k, reason=bad)
            break
    out["passed"] = out["stage"] is None
    return out


def worst(stages, checks=CHECKS) -> dict:
    """Per check, the stage using the largest fraction of its tolerance.

    {column: {stage, value, tolerance, used}} with used = value / tolerance (NaN
    if none); value is relative to that stage's scale, as in its check. A stage
    without a check (not judged there) is skipped.
    """
    out = {}
    for c in checks:
        rows = [(st["checks"][c.column]["value"], st["checks"][c.column]["tolerance"],
                 st["index"]) for st in stages if c.column in st["checks"]]
        rows = [r for r in rows if np.isfinite(r[0])]
        if not rows:
            out[c.column] = dict(stage=None, value=math.nan, tolerance=math.nan, used=math.nan)
            continue
        value, tol, k = max(rows, key=lambda r: r[0] / r[1])
        out[c.column] = dict(stage=k, value=value, tolerance=tol, used=value / tol)
    return out


def history_differences(h_1, h_2, *, F0, a0) -> dict:
    """Max differences of force (/F0) and contact radius (/a0) over the common sliding range.

    The second history is interpolated linearly onto the sliding distances of
    the first that lie inside its range.
    """
    s1, s2 = np.asarray(h_1["s"], float), np.asarray(h_2["s"], float)
    keep = (s1 >= s2.min()) & (s1 <= s2.max())
    out = dict(s_common_max=float(s1[keep].max()) if keep.any() else math.nan)
    for name, scale in (("force", F0), ("contact_radius", a0)):
        d = (np.asarray(h_1[name], float)[keep] - np.interp(s1[keep], s2, h_2[name])) / scale
        out[f"{name}_max"], out[f"{name}_rms"], _ = max_rms(d)
    return out
