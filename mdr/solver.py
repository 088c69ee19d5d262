"""``mdr.solve(case)``: the MDR gross-slip wear run of one case."""

from __future__ import annotations

import math
import time

import numpy as np

from wearcheck.cases import CaseError, RunResult, SolverError, profiles, reference

from . import linalg, transforms, wear

#: implicit Euler's default step in ŝ (sliding.step_hat = "auto"); see README/report:
#: on the paper case its time error in F/F0 is 7.7e-3 (0.077 Δŝ, first order)
IMPLICIT_STEP_HAT = 0.1
#: BDF2's default step in ŝ. On paper.toml at N = 800 (bench_mdr table 3, max
#: over the history): time error 6.6e-5 in F/F0 in 0.11 s, against 2.3e-4 in
#: 0.08 s at Δŝ = 0.1 and 2.8e-5 in 0.17 s at 0.025; the space error there is
#: 2.3e-5. Error ≈ 0.023 Δŝ² in the bulk of the run; at finer steps the first
#: tenths of ŝ (the Hertz start, not smooth in s) dominate and fall as Δŝ^1.2-1.5.
#: 0.1 keeps the issue's speed targets (N = 800 within 0.1 s, N = 102400 within
#: 30 s) at 1/30 of implicit Euler's time error; lower step_hat for more
BDF2_STEP_HAT = 0.1
#: largest ratio of consecutive BDF2 steps (zero-stable below 1 + √2)
BDF2_MAX_RATIO = 2.0
#: BDF2's first (backward Euler) step as a fraction of its step (a power of
#: 1/2, so the doubling ramp after it sums to one step); measured on
#: paper.toml (N = 800, Δŝ = 0.1): time error 9.9e-4 starting with a full
#: step, 2.2e-4 with 1/16 (then the BDF2 error proper, 0.022 Δŝ²), 2.3e-4 with 1/256
BDF2_FIRST_STEP = 1.0 / 16.0
#: runaway guards
MAX_STEPS = 2_000_000
MAX_S_HAT = 1.0e4


#: what the MDR result of an ellipsoid is (info["warning"])
ELLIPSOID_WARNING = ("approximate: the ellipsoid (radii R1, R2) is run as the paraboloid of "
                     "the equivalent radius √(R1 R2); MDR is exact only for bodies of "
                     "revolution (use the BEM for the ellipsoid as it is)")


def supports(case) -> str | None:
    """None: the MDR runs every axisymmetric profile, and the ellipsoid approximately."""
    return None


def build_model(case) -> tuple[wear.Model, dict]:
    """Grid, unworn profile and load of a case; the scales of reference.scales."""
    sc = reference.scales(case)
    N = case.mdr.elements
    L = case.mdr.domain_factor * math.sqrt(2.0) * sc["a0"]
    x = transforms.grid(N, L)
    f0 = profiles.height(case.indenter, x, case.table)
    tangential = (case.wear.mu / case.G_star) if case.wear.tangential_correction else 0.0
    model = wear.Model(x=x, f0=f0, E_star=case.E_star, wear_rate=case.wear_rate,
                       depth=case.loading.depth, force=case.loading.force,
                       tangential=tangential)
    return model, sc


def stability_limit_hat(model: wear.Model, s_hat_per_m: float) -> float:
    """Largest stable explicit step in ŝ: h λ_max <= 2."""
    return 2.0 / wear.stiffest_rate(model) * s_hat_per_m


def run(model: wear.Model, scheme: str, h: float, stage_s, until: str, s_end: float,
        force_fraction: float, progress=None, check_oscillation: bool = True) -> dict:
    """Step the wear from the unworn state; the numerics without case handling.

    h, stage_s, s_end in metres of sliding. Returns the history (arrays),
    the stages reached (s, f, p) and counters. ``check_oscillation=False``
    lets a test see what an unstable explicit run returns when nobody looks.
    """
    state = wear.contact_state(model, model.f0.copy())
    F_start = state.force
    if not F_start > 0.0:
        raise SolverError("the unworn indenter carries no load (no node in contact); "
                          "raise mdr.elements or the load")
    hist = {k: [] for k in ("s", "force", "depth", "contact_radius", "wear_center",
                            "wear_volume", "max_pressure")}
    stages_s, stages_f, stages_p = [], [], []
    stage_s = list(stage_s)
    counters = {"steps": 0, "gmres_iterations": 0, "contact_iterations": 0}
    if scheme == "explicit":
        step = wear.explicit_step
    else:
        # one factorisation for the run's regular step (BDF2: wear compliance
        # c h with c = 2/3 at a constant step); the first, stage-landing and
        # ratio-limited steps use it as a preconditioner
        # (depth control: the contact radius grows to about sqrt(2) a0, twice the
        # nodes of the start in t = r²; the factorisation grows if needed)
        h_sys = h if scheme == "implicit" else wear.bdf2_coefficients(h, h)[2] * h
        system = wear.ImplicitSystem(model, h_sys, nodes=int(2.2 * (state.m + 1)) + 16)
        m_prev = [state.m, state.m]

        def step(model, state, hn, previous=None):
            # the contact edge moves smoothly: extrapolate its last move
            guess = 2 * state.m - m_prev[-1]
            m_prev[:] = [m_prev[-1], state.m]
            return wear.implicit_step(model, state, hn, m_guess=guess, system=system,
                                      previous=previous)
    # BDF2's history: (f_{n-1}, h_{n-1}); None makes the next step backward Euler
    previous = None
    # BDF2 starts with a short backward-Euler step (its O(h²) local error would
    # otherwise be the largest part of the run's time error), then doubles the
    # step: h/16, h/16, h/8, h/4, h/2 reach s = h, so the regular steps stay
    # aligned with stages at multiples of h
    ramp = []
    if scheme == "bdf2":
        ramp = [BDF2_FIRST_STEP * h]
        while sum(ramp) < h * (1 - 1e-9):
            ramp.append(sum(ramp))
    dt = model.dt
    s = 0.0
    last_report = -1.0

    def record(st, s):
        w = st.f - model.f0
        hist["s"].append(s)
        hist["force"].append(st.force)
        hist["depth"].append(st.depth)
        hist["contact_radius"].append(st.contact_radius)
        hist["wear_center"].append(w[0])
        hist["wear_volume"].append(transforms.volume(w, dt))
        hist["max_pressure"].append(float(np.max(st.p)))
        while stage_s and stage_s[0] <= s * (1 + 1e-12) + 1e-300:
            stages_s.append(s)
            stages_f.append(st.f.copy())
            stages_p.append(st.p.copy())
            stage_s.pop(0)

    record(state, s)
    while True:
        if until == "force_fraction" and s > 0.0 and state.force < force_fraction * F_start:
            break
        if s >= s_end:
            break
        target = s_end
        if stage_s:
            target = min(target, stage_s[0])
        # land exactly on the next stage or the end (never a sliver of a step after it)
        if target - s <= h * (1 + 1e-9):
            hn, s_new = target - s, target
        elif scheme == "bdf2" and target - s < 2.0 * h:
            # BDF2: two equal steps onto the stage rather than a regular step and
            # a short one, so the step ratios around it stay within [1/2, 2]
            hn = 0.5 * (target - s)
            s_new = s + hn
        else:
            hn, s_new = h, s + h
        if scheme == "bdf2":
            # the step grows by at most BDF2_MAX_RATIO per step, also after a
            # short step (stages closer than h): zero-stable below 1 + √2
            cap = math.inf if previous is None else BDF2_MAX_RATIO * previous[1]
            if ramp:
                cap = min(cap, ramp.pop(0))
            if hn > cap:
                hn, s_new = cap, s + cap
        if scheme == "explicit":
            new = step(model, state, hn)
            if check_oscillation and wear.oscillation(new.p, new.m):
                raise SolverError(
                    f"explicit Euler: grid-scale oscillation of the pressure at ŝ step "
                    f"{counters['steps'] + 1}; the step is past the stability limit — "
                    "reduce sliding.step_hat or use sliding.scheme = \"implicit\"")
        else:
            new = step(model, state, hn, previous)
            if scheme == "bdf2":
                previous = (state.f, hn)
            for k in ("gmres_iterations", "contact_iterations"):
                counters[k] += new.stats.get(k, 0)
        if not np.all(np.isfinite(new.f)) or not math.isfinite(new.force):
            raise SolverError("the wear run produced non-finite values; reduce sliding.step_hat")
        state, s = new, s_new
        counters["steps"] += 1
        record(state, s)
        if counters["steps"] >= MAX_STEPS:
            raise SolverError(f"the wear run took more than {MAX_STEPS} steps; raise "
                              "sliding.step_hat or use sliding.scheme = \"implicit\"")
        if progress is not None:
            if until == "distance":
                frac = s / s_end
            else:
                frac = (1.0 - state.force / F_start) / (1.0 - force_fraction)
            if frac - last_report >= 0.01:
                last_report = frac
                progress(min(max(frac, 0.0), 1.0), f"F/F0 = {state.force / F_start:.3g}")
    counters.update(F_start=F_start)
    return dict(history={k: np.asarray(v) for k, v in hist.items()},
                stage_s=np.asarray(stages_s), f=np.asarray(stages_f), p=np.asarray(stages_p),
                counters=counters)


def solve(case, progress=None) -> RunResult:
    """Run the MDR wear simulation of ``case`` (see the package docstring).

    BLAS runs single-threaded meanwhile (:func:`mdr.linalg.single_threaded_blas`).
    A case with a [fretting] section runs :func:`mdr.fretting.solve`.
    """
    if getattr(case, "fretting", None) is not None:
        from .fretting import solve as solve_fretting
        return solve_fretting(case, progress)
    with linalg.single_threaded_blas():
        return _solve(case, progress)


def _solve(case, progress=None) -> RunResult:
    t0 = time.perf_counter()
    model, sc = build_model(case)
    per_m = sc["s_hat_per_m"]
    sl = case.sliding
    info = dict(solver="mdr", N=case.mdr.elements, domain=float(model.x[-1]),
                grid="uniform in r^2", scheme=sl.scheme)
    limit_hat = None
    if sl.scheme == "explicit":
        limit_hat = stability_limit_hat(model, per_m)
        info["stability_limit_hat"] = limit_hat
        step_hat = 0.5 * limit_hat if sl.step_hat == "auto" else sl.step_hat
        if step_hat > limit_hat:
            raise CaseError(
                f"key 'sliding.step_hat' = {sl.step_hat!r}: past the stability limit of "
                f"explicit Euler on this grid; the largest stable step is {limit_hat:.4g} "
                f"(N = {case.mdr.elements}); use a smaller step or sliding.scheme = "
                "\"implicit\"")
    else:
        auto = IMPLICIT_STEP_HAT if sl.scheme == "implicit" else BDF2_STEP_HAT
        step_hat = auto if sl.step_hat == "auto" else sl.step_hat
    info["step_hat"] = float(step_hat)
    info["approximate"] = case.indenter.profile == "ellipsoid"
    if info["approximate"]:
        info["equivalent_radius"] = profiles.equivalent_radius(case.indenter)
        info["warning"] = ELLIPSOID_WARNING
    if sl.until == "distance":
        s_end = sl.distance
        if s_end * per_m > MAX_S_HAT:
            raise CaseError(f"key 'sliding.distance' = {s_end!r}: ŝ = {s_end * per_m:.4g} "
                            f"exceeds the solver's cap of {MAX_S_HAT:g}")
        expected = s_end * per_m / step_hat
        if expected > MAX_STEPS:
            raise CaseError(f"key 'sliding.step_hat' = {sl.step_hat!r}: the run would take "
                            f"{expected:.3g} steps (cap {MAX_STEPS}); raise the step")
    else:
        s_end = MAX_S_HAT / per_m
    stage_s = [sh / per_m for sh in case.stages.s_hat]
    if sl.until == "distance":
        stage_s = [s for s in stage_s if s <= s_end * (1 + 1e-12)]
    until = sl.until
    out = run(model, sl.scheme, step_hat / per_m, stage_s,
              "distance" if until == "distance" else "force_fraction",
              s_end, sl.force_fraction, progress)
    if until == "force_fraction" and out["history"]["s"][-1] >= s_end * (1 - 1e-12):
        raise SolverError(f"the force did not fall below {sl.force_fraction} F0 within "
                          f"ŝ = {MAX_S_HAT:g}")
    hist = out["history"]
    hist["s_hat"] = hist["s"] * per_m
    info.update(out["counters"])
    K = len(out["stage_s"])
    M = len(model.x)
    f = out["f"].reshape(K, M)
    p = out["p"].reshape(K, M)
    if progress is not None:
        progress(1.0, "done")
    return RunResult(history=hist, stage_s=out["stage_s"], r=model.x.copy(), f=f, p=p,
                     solve_seconds=time.perf_counter() - t0, info=info)
