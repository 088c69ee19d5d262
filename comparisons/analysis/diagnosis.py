"""What to change when a comparison fails: the setting most likely to fix its worst
check (pure: numbers in, a dict out).

Two discretisations separate a solver from its reference: space (each solver's
grid at the contact edge) and time (the sliding steps). Each run reports how fine
both are: its radii, from which the spacing at the stage's contact radius
follows (the BEM's pixel ``info.pixel``, the FEM's ``info.mesh.contact_spacing``,
the MDR's grid uniform in r²), and, when adaptive, the step-doubling estimate
of its time error (``info.time_error.estimate``, in F0 for the force); a run at
fixed first-order steps (implicit or explicit Euler) gets the estimate
:func:`first_order_time_error` from its own history. The rule, decided here and
stated in the report:

- the time steps are blamed when the larger time-error estimate of the pair,
  carried to the failing stage's scale, uses at least :data:`TIME_SHARE` of the
  check's tolerance (never at ŝ = 0, where nothing has slid);
- otherwise the grid of the solver with the fewest points across the stage's
  contact radius (its registry ``resolution_key`` with the case's value).

A solver that solved an approximation of the case (the MDR's equivalent sphere
for an ellipsoid) is named instead: no setting removes a model difference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import metrics

#: share of a check's tolerance a run's own time-error estimate must use for the
#: time steps to be named before the grids
TIME_SHARE = 0.5
#: the factor suggested for a resolution key, and the one for sliding.tolerance
REFINE_FACTOR = 2
TOLERANCE_FACTOR = 10


@dataclass(frozen=True)
class Resolution:
    """How finely one run of the pair resolved the failing stage.

    solver, title : its registry name and display name.
    key, value : its resolution setting ("bem.grid") and the case's value (None if
        it has none, e.g. a notebook solver).
    points_across : the stage's contact radius over the run's grid spacing there.
    time_error : the run's estimate of its time error: step doubling (adaptive
        runs), :func:`first_order_time_error` (fixed implicit or explicit Euler
        steps); None for BDF2's fixed steps.
    approximate : why the run solved an approximation of the case, or None.
    step_hat : the fixed step the run took (``info.step_hat``), or None.
    """

    solver: str
    title: str
    key: str | None
    value: object
    points_across: float
    time_error: float | None = None
    approximate: str | None = None
    step_hat: float | None = None


def points_across(r, a) -> float:
    """The contact radius ``a`` over the spacing of the radii ``r`` at r = a.

    The spacing is the local one (the MDR's grid is uniform in r², not in r):
    interpolated linearly between the midpoints of the sorted radii.
    """
    r = np.unique(np.asarray(r, float))
    if r.size < 2 or not np.isfinite(a) or a <= 0:
        return math.nan
    mid = 0.5 * (r[1:] + r[:-1])
    h = float(np.interp(a, mid, np.diff(r)))
    return a / h


def step_hat_used(result, s_hat_per_m) -> float:
    """The median sliding step of a run, in ŝ (NaN when it did not slide)."""
    ds = np.diff(np.asarray(result.history["s"], float))
    ds = ds[ds > 0]
    return float(np.median(ds) * s_hat_per_m) if ds.size else math.nan


def grid_spacing(result, a0) -> float:
    """Median spacing of a result's radii, relative to a0."""
    return float(np.median(np.diff(np.asarray(result.r, float))) / a0)


def worst_failure(stages) -> dict | None:
    """The failed check of a pair's stages that uses the largest share of its tolerance.

    {check, stage, s_hat, value, tolerance, used, scale, scale_from, unit, unworn},
    or None when every check passed.
    """
    worst = None
    for st in stages:
        for name, c in st["checks"].items():
            if c["passed"]:
                continue
            used = c["value"] / c["tolerance"] if np.isfinite(c["value"]) else math.inf
            if worst is None or used > worst["used"]:
                worst = dict(check=name, stage=st["index"], s_hat=st["s_hat_reference"],
                             value=c["value"], tolerance=c["tolerance"], used=used,
                             scale=c.get("scale"), scale_from=c.get("scale_from"),
                             unit=c.get("unit"), unworn=c.get("unworn"))
    return worst


def first_order_time_error(history, F0, d0) -> float:
    """Global time error of a fixed-step first-order run, estimated from its history.

    Euler's local error in a step h is h²/2 |y''|; summed over the steps without
    the damping that wear provides (so an upper estimate), it is
    Σ ½ |Δy_{n+1} − Δy_n| over the recorded steps. Taken for the force (/F0) and
    for the depth and central wear (/d0), the largest; NaN with fewer than three
    recorded steps. The same units as the step-doubling estimate of an adaptive run.
    """
    out = math.nan
    for name, scale in (("force", F0), ("depth", d0), ("wear_center", d0)):
        y = np.asarray(history.get(name, ()), float)
        y = y[np.isfinite(y)]
        if y.size >= 3 and scale > 0:
            e = 0.5 * float(np.abs(np.diff(y, 2)).sum()) / scale
            out = e if not np.isfinite(out) else max(out, e)
    return out


def time_share(error, failure) -> float:
    """The share of the failing check's tolerance a run's time-error estimate uses.

    The estimate is in F0 for the force (and, as the pressure follows the force,
    is taken so for the pressure): it is divided by the stage's scale there; for
    profile and contact radius it is relative already (depth and central wear
    over max(d0, value)). Zero at ŝ = 0; NaN without an estimate.
    """
    if failure["s_hat"] == 0.0:
        return 0.0
    if error is None or not np.isfinite(error):
        return math.nan
    relative = error
    if failure["unit"] in ("F0", "p0") and failure.get("scale"):
        relative = error / failure["scale"]
    return relative / failure["tolerance"]


def advise(failure: dict, runs: list[Resolution], *, scheme: str, tolerance: float,
           step_hat) -> dict:
    """The setting most likely to fix ``failure`` (from :func:`worst_failure`).

    Parameters
    ----------
    failure : the worst failed check of the pair.
    runs : the resolution of each run of the pair (reference and compared solver).
    scheme, tolerance, step_hat : the case's sliding.scheme, sliding.tolerance and
        sliding.step_hat.

    Returns
    -------
    dict: setting (dotted key or None), value (its current value), suggestion
    (a value to try, or None), solver, reason (one sentence), otherwise (the
    runner-up in words, or None), rule, and the measures (per solver:
    points_across, time_share).
    """
    measures = {r.solver: dict(points_across=r.points_across,
                               time_share=time_share(r.time_error, failure))
                for r in runs}
    out = dict(check=failure["check"], stage=failure["stage"], s_hat=failure["s_hat"],
               measures=measures, otherwise=None,
               rule=(f"the time steps when a run's own time-error estimate uses at least "
                     f"{TIME_SHARE:g} of the tolerance at the stage; else the grid with the "
                     "fewest points across the stage's contact radius"))
    approx = [r for r in runs if r.approximate]
    if approx:
        r = approx[0]
        return dict(out, setting=None, value=None, suggestion=None, solver=r.solver,
                    reason=f"{r.title} solved an approximation of the case ({r.approximate}); "
                           "no setting removes that difference")
    label = metrics.CHECK_BY_COLUMN[failure["check"]].label \
        if failure["check"] in metrics.CHECK_BY_COLUMN else failure["check"]
    where = f"stage {failure['stage']} (ŝ = {failure['s_hat']:.3g})"
    # at ŝ = 0 nothing has slid: the time steps cannot be the cause
    shares = [(measures[r.solver]["time_share"], r) for r in runs
              if failure["s_hat"] > 0.0 and np.isfinite(measures[r.solver]["time_share"])]
    timed = max(shares, key=lambda t: t[0], default=None)
    time_advice = None
    if timed is not None:
        share, r = timed
        reason = (f"{r.title}'s own time-error estimate uses {100 * share:.0f} % of the "
                  f"{label} tolerance at {where}")
        if scheme == "adaptive":
            time_advice = dict(setting="sliding.tolerance", value=tolerance,
                               suggestion=tolerance / TOLERANCE_FACTOR, solver=r.solver,
                               reason=reason)
        else:   # fixed steps: first order, the error halves with the step
            time_advice = dict(setting="sliding.step_hat", value=step_hat,
                               suggestion=(step_hat / REFINE_FACTOR
                                           if isinstance(step_hat, (int, float))
                                           else r.step_hat / REFINE_FACTOR
                                           if r.step_hat else None),
                               solver=r.solver, reason=reason)
    elif failure["s_hat"] > 0.0 and scheme != "adaptive":
        time_advice = dict(setting="sliding.step_hat", value=step_hat, suggestion=None,
                           solver=None, reason=f"the {scheme} scheme's fixed steps report no "
                                               "time-error estimate")
    gridded = [r for r in runs if np.isfinite(r.points_across)]
    grid_advice = None
    if gridded:
        r = min(gridded, key=lambda r: r.points_across)
        others = ", ".join(f"{o.title} {o.points_across:.0f}" for o in gridded if o is not r)
        reason = (f"{r.title} has {r.points_across:.1f} points across the contact radius at "
                  f"{where}" + (f" ({others})" if others else ""))
        if r.key is None:
            grid_advice = dict(setting=None, value=None, suggestion=None, solver=r.solver,
                               reason=reason + f"; {r.title} names no resolution setting")
        else:
            grid_advice = dict(setting=r.key, value=r.value, solver=r.solver, reason=reason,
                               suggestion=r.value * REFINE_FACTOR
                               if isinstance(r.value, int) else None)
    if time_advice is not None and timed is not None and timed[0] >= TIME_SHARE:
        first, second = time_advice, grid_advice
    else:
        first, second = grid_advice, time_advice
    if first is None:
        return dict(out, setting=None, value=None, suggestion=None, solver=None,
                    reason="no run reports a grid or a time-error estimate")
    return dict(out, **first, otherwise=_words(second) if second else None)


def _words(advice: dict) -> str:
    """An advice's setting, value and reason in one clause."""
    if advice.get("setting") is None:
        return advice["reason"]
    return f"{advice['setting']} (now {advice['value']!s}): {advice['reason']}"


def sentence(advice: dict) -> str:
    """The advice as the terminal and the report show it."""
    if advice.get("setting") is None:
        return "no setting to name: " + advice["reason"] + "."
    try_ = f"; try {advice['suggestion']:g}" if advice.get("suggestion") is not None else ""
    verb = "tighten" if advice["setting"] == "sliding.tolerance" else (
        "reduce" if advice["setting"] == "sliding.step_hat" else "raise")
    then = f" Next most likely: {advice['otherwise']}." if advice.get("otherwise") else ""
    return (f"{verb} {advice['setting']} (now {advice['value']!s}{try_}): "
            f"{advice['reason']}.{then}")
