"""How far a run slides and where it keeps its stages, with the solvers' run-length caps.

Shared by the solvers that step in ŝ (MDR, FEM, BEM): the checks are about the
case, so they live beside it rather than in each solver; :func:`stepping_plan`
turns them into the plan :mod:`numerics.stepping` runs.
"""

from __future__ import annotations

import math

from wearcheck.numerics import stepping

from .errors import CaseError, SolverError


def sliding_plan(case, step_hat: float, per_m: float, *, s_hat_cap: float, max_steps: int,
                 adaptive: bool) -> tuple[float, list[float], str]:
    """The sliding distance to stop at, the stage distances and the stop rule.

    Parameters
    ----------
    case : the case; step_hat : the (largest) step in ŝ (inf: none);
    per_m : ŝ per metre of sliding; s_hat_cap, max_steps : the solver's caps;
    adaptive : whether steps are chosen by the error control (no step cap).

    Returns
    -------
    s_end [m] (the cap when the run stops on the force), stage_s [m] (the stages
    at or before s_end), until ("force_fraction" or "distance").

    Raises
    ------
    CaseError
        a run past the caps, naming the key that sets its length.
    """
    sl = case.sliding
    s_end = case.end_distance
    if s_end is not None:
        key = "sliding.distance" if sl.until == "distance" else "sliding.cycles"
        if s_end * per_m > s_hat_cap:
            raise CaseError(f"key '{key}' = {getattr(sl, key.split('.')[1])!r}: ŝ = "
                            f"{s_end * per_m:.4g} exceeds the solver's cap of {s_hat_cap:g}"
                            + ("" if adaptive else " for fixed steps (use sliding.scheme = "
                               "\"adaptive\")"))
        expected = s_end * per_m / step_hat
        if expected > max_steps:
            raise CaseError(f"key 'sliding.step_hat' = {sl.step_hat!r}: the run would take "
                            f"{expected:.3g} steps (cap {max_steps}); raise the step"
                            + ("" if adaptive else " or use sliding.scheme = \"adaptive\""))
    else:
        s_end = s_hat_cap / per_m
    stage_s = [sh / per_m for sh in case.stages.s_hat]
    if case.end_distance is not None:
        stage_s = [s for s in stage_s if s <= s_end * (1 + 1e-12)]
    until = "force_fraction" if sl.until == "force_fraction" else "distance"
    return s_end, stage_s, until


def stepping_plan(case, step_hat: float, sc: dict, *,
                  control: str = "ladder") -> tuple[stepping.Plan, str]:
    """The plan of a case's wear run for :func:`numerics.stepping.run`, and its stop rule.

    Parameters
    ----------
    case : the case; step_hat : the step in ŝ (adaptive: the largest, inf for
    none); sc : :func:`cases.reference.scales` of the case; control : the
    adaptive scheme's step control ("ladder" or "continuous", the solver's choice).

    Raises
    ------
    CaseError
        a run past the scheme's caps (:func:`sliding_plan`).
    """
    sl = case.sliding
    per_m = sc["s_hat_per_m"]
    s_hat_cap, max_steps = stepping.caps(sl.scheme)
    s_end, stage_s, until = sliding_plan(case, step_hat, per_m, s_hat_cap=s_hat_cap,
                                         max_steps=max_steps,
                                         adaptive=sl.scheme == "adaptive")
    plan = stepping.Plan(
        scheme=sl.scheme, step=step_hat / per_m, end=s_end, per_m=per_m, stages=tuple(stage_s),
        force_fraction=sl.force_fraction if until == "force_fraction" else None,
        tolerance=sl.tolerance, force_scale=sc["F0"], depth_scale=sc["d0"], control=control,
        max_steps=max_steps, step_key=f"key 'sliding.step_hat' = {sl.step_hat!r}")
    return plan, until


def finish_history(case, history: dict, until: str, s_end: float, per_m: float) -> dict:
    """Check that a run stopping on the force did stop, and add the columns every
    ŝ-stepping solver writes: ``s_hat`` and ``cycles`` (NaN without a stroke).

    Raises
    ------
    SolverError
        the force did not fall below its fraction of F0 before the cap.
    """
    if until == "force_fraction" and history["s"][-1] >= s_end * (1 - 1e-12):
        raise SolverError(f"the force did not fall below {case.sliding.force_fraction} F0 "
                          f"within ŝ = {s_end * per_m:g}")
    history["s_hat"] = history["s"] * per_m
    cpm = case.cycles_per_metre
    history["cycles"] = history["s"] * (cpm if cpm is not None else math.nan)
    return history
