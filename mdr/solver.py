"""``mdr.solve(case)``: the MDR gross-slip wear run of one case."""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from wearcheck.cases import CaseError, RunResult, SolverError, profiles, programme, reference
from wearcheck.cases import validity
from wearcheck.cases.result import scar_radius

from . import contact, linalg, resolution, transforms, wear

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
#: runaway guards: fixed-step runs (ŝ, steps); adaptive runs take far fewer
#: steps per ŝ as wear slows, so they are capped in steps only (and ŝ < 1e9)
MAX_STEPS = 2_000_000
MAX_S_HAT = 1.0e4
ADAPTIVE_MAX_S_HAT = 1.0e9
ADAPTIVE_MAX_STEPS = 100_000
#: the domain grows (t = r² doubles, the grid keeps every other node) once
#: the contact edge passes this fraction of the nodes
GROW_AT = 0.8
#: adaptive scheme: first step in ŝ, and the ladder of steps 2^k ŝ it climbs
ADAPTIVE_FIRST_STEP_HAT = 2.0 ** -7
#: adaptive scheme: the step doubles when the error estimate is below this
#: fraction of the tolerance (the estimate grows as h², fourfold per doubling)
ADAPTIVE_GROW_BELOW = 0.2
#: grids solved iteratively (N > wear.DENSE_MAX): the step is set continuously so
#: the error estimate comes to this fraction of the tolerance, growing at most
#: ADAPTIVE_MAX_GROWTH per step (None: the ladder, as direct solves, whose steps
#: run at 0.2-0.8 of the tolerance). Paper case against a Richardson-extrapolated
#: time-converged history: N = 25600, 144 steps and max |ΔF/F0| 7.8e-5, against
#: 165 and 9.7e-5 on the ladder (3.5 against 4.1 s); at 0.6, 132 steps and
#: 9.3e-5. At 0.5 the accuracy is the ladder's or better, with 13 % fewer steps
ADAPTIVE_ERROR_TARGET = 0.5
ADAPTIVE_MAX_GROWTH = 2.0
#: the half steps' edges are guessed from the shares of the full step's edge
#: move they took of late when it moves at least this many nodes, else as its
#: midpoint and end (paper case: N = 800, 639 contact iterations with
#: midpoint and end, 677 with the shares always, 635 with this rule; N =
#: 25600, 1175 contact and 7387 GMRES iterations with midpoint and end, 870
#: and 5637 with the shares)
SHARE_MOVE = 4
#: iterative solves of an adaptive run: GMRES's relative residual as a share
#: of the run's tolerance (1e-7 at the default 1e-4), between wear.ACCURATE_RTOL
#: and ADAPTIVE_SOLVE_RTOL_MAX. The solves' error stays about 1 % of the time
#: error the run accepts: paper case, over the steps taken alike, 1.5e-7 in F/F0
#: and 9e-7 of the largest central wear at N = 102400 (1e-7 and 1.1e-6 at
#: 25600), where 1e-9 took 24.4 s, 5418 GMRES and 897 contact iterations and
#: this 17.6 s, 3228 and 975. Looser than 1e-7, the marginal edge node is
#: decided by the solver's noise (loose passes at 1e-5 cost 2.4 times the
#: contact iterations at N = 25600)
ADAPTIVE_SOLVE_SHARE = 1e-3
#: the matrix-free solves' GMRES iterations done in float32 (of gmres_iterations)
#: and their solves finished by float64 GMRES (mdr/linalg.py, iterative refinement)
_FLOAT32_COUNTERS = ("gmres_float32_iterations", "gmres_float64_fallbacks")
ADAPTIVE_SOLVE_RTOL_MAX = 1e-7
#: grids finer than this check the contact beyond a window against a
#: reference profile (wear.FarGap) instead of transforming the whole grid
FAR_GAP_FROM = 2048
#: which solution of a doubled step the adaptive scheme keeps (docs/time-stepping.md)
ADAPTIVE_ACCEPT = "deferred"
#: (Richardson's correction is carried everywhere but where it is negative on
#: the outermost contact node and beyond; see the comment where it is formed)


#: what the MDR result of an ellipsoid is (info["approximate"] and info["warning"])
ELLIPSOID_WARNING = ("the ellipsoid (radii R1, R2) is run as the paraboloid of "
                     "the equivalent radius √(R1 R2); MDR is exact only for bodies of "
                     "revolution (use the BEM for the ellipsoid as it is)")


def ellipsoid_warning(case) -> str:
    """ELLIPSOID_WARNING with what the stand-in costs at the start: its unworn force
    (depth control) or depth (force control) over the exact elliptical Hertz one."""
    ind, ld = case.indenter, case.loading
    load = {ld.control: getattr(ld, ld.control)}
    exact = reference.hertz_elliptical(case.E_star, ind.radius, ind.radius_y, **load)
    stand_in = reference.hertz(case.E_star, profiles.equivalent_radius(ind), **load)
    what = "force" if ld.control == "depth" else "depth"
    return (f"{ELLIPSOID_WARNING}; at R2/R1 = {ind.radius_y / ind.radius:.4g} its unworn {what} "
            f"is {stand_in[what] / exact[what]:.4g} of the exact (elliptical Hertz) one")


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
                       tangential=tangential, exponent=case.wear.pressure_exponent,
                       hardness=case.wear.hardness)
    return model, sc


def stability_limit_hat(model: wear.Model, s_hat_per_m: float, p_max: float | None = None) -> float:
    """Largest stable explicit step in ŝ: h λ_max <= 2.

    With a pressure exponent n the rate's derivative n (p/σ0)^(n-1) scales
    λ; ``p_max`` (the largest pressure of the run, the unworn one) bounds it.
    """
    lam = wear.stiffest_rate(model)
    if model.exponent != 1.0 and p_max is not None:
        lam *= float(wear.wear_speed_slope(model, np.array([p_max]))[0])
    return 2.0 / lam * s_hat_per_m


def grow_domain(model: wear.Model, profile, arrays=()) -> tuple[wear.Model, list]:
    """The model on a domain √2 wider (t = r² doubled), and ``arrays`` moved onto it.

    For an even N the new nodes inside the old domain are every other old
    node, so profiles are carried over exactly at the nodes (piecewise linear
    in t in between, as everywhere); beyond the old domain nothing is worn
    and an array takes its value at the old edge (profiles: the unworn one).
    ``profile(x)`` gives the unworn profile. ``arrays``: (array or None,
    kind) with kind "profile", "increment" (zero beyond) or "field" (the
    edge value beyond).
    """
    N = len(model.x) - 1
    x = transforms.grid(N, model.x[-1] * math.sqrt(2.0))
    f0 = profile(x)
    new = dataclasses.replace(model, x=x, f0=f0)
    out = []
    for a, kind in arrays:
        if a is None:
            out.append(None)
        elif kind == "profile":
            # worn = unworn + wear, the wear moved and zero beyond the old domain
            wear_depth = np.interp(new.t, model.t, a - model.f0, right=0.0)
            out.append(f0 + wear_depth)
        elif kind == "increment":   # a change of the profile: none beyond the old domain
            out.append(np.interp(new.t, model.t, a, right=0.0))
        else:
            out.append(np.interp(new.t, model.t, a))
    return new, out


class _Recorder:
    """History rows and stored stages of a run whose grid may grow."""

    def __init__(self, stage_s, watch=None):
        self.hist = {k: [] for k in ("s", "force", "depth", "contact_radius", "wear_center",
                                     "wear_volume", "scar_radius", "max_pressure")}
        self.stage_s = list(stage_s)
        self.stages = []      # (s, x, f, p)
        self.watch = watch    # watch(s, contact_radius, scar_radius) per recorded step

    def __call__(self, model, st, s):
        w = st.f - model.f0
        h = self.hist
        h["s"].append(s)
        h["force"].append(st.force)
        h["depth"].append(st.depth)
        h["contact_radius"].append(st.contact_radius)
        h["wear_center"].append(w[0])
        h["wear_volume"].append(transforms.volume(w, model.dt))
        h["scar_radius"].append(scar_radius(model.x, w))
        h["max_pressure"].append(float(np.max(st.p)))
        if self.watch is not None:
            self.watch(s, st.contact_radius, h["scar_radius"][-1])
        while self.stage_s and self.stage_s[0] <= s * (1 + 1e-12) + 1e-300:
            self.stages.append((s, model.x.copy(), st.f.copy(), st.p.copy()))
            self.stage_s.pop(0)

    def stage_arrays(self, profile, x):
        """Stages on one grid: the union of the stage grids (each exact on it).

        ``x``: the grid of a run that reached no stage (its arrays are 0 × len(x)).
        """
        if not self.stages:
            return np.zeros(0), x.copy(), np.zeros((0, len(x))), np.zeros((0, len(x)))
        grids = [x for _, x, _, _ in self.stages]
        if all(len(x) == len(grids[0]) and np.array_equal(x, grids[0]) for x in grids):
            r = grids[0]
        else:
            r = np.unique(np.concatenate(grids))
            # nodes that coincide up to round-off (sqrt of equal t) are one node
            keep = np.r_[True, np.diff(r) > 1e-12 * r[-1]]
            r = r[keep]
        f0 = profile(r)
        F, P = [], []
        for _, x, f, p in self.stages:
            t, tt = r**2, x**2
            F.append(f0 + np.interp(t, tt, f - profile(x), right=0.0))
            P.append(np.interp(t, tt, p, right=0.0))
        return np.array([st[0] for st in self.stages]), r, np.array(F), np.array(P)


class _EdgeGuess:
    """Guesses of the contact edge (last node) of an adaptive step's three solves.

    Each wrong guess costs a contact iteration (a solve). The extrapolation
    from the accepted states (``base``) misses the full step's edge, which
    runs ahead of the accepted (two half steps) ones by O(h): where the edge
    moves several nodes a step, the recent miss per unit step corrects it,
    and the half steps take the shares of the full step's move they took of
    late (paper case, N = 51200: 814 contact iterations, 1022 with the last
    step's lead of the full step's edge over the accepted one); where it moves
    a node or two (coarse grids), that lead, the midpoint and the full step's
    end do better (N = 800: 637 against 649; see SHARE_MOVE).
    """

    def __init__(self):
        self.share = [0.5, 0.5]      # the half steps' moves over the full step's, of late
        self.moves = [0.0, 0.0, 0.0]  # their decaying sums (half, second half, full)
        self.reset()

    def reset(self):
        """Forget the leads (the grid changed: nodes mean other radii)."""
        self.miss = 0.0              # the full step's edge beyond ``base``, per metre
        self.lead = 0                # the full step's edge beyond the accepted one, last step

    def full(self, m, base, h, h_last):
        if abs(base - m) >= SHARE_MOVE:
            return base + round(self.miss * h)
        return base + (round(self.lead * h / h_last) if h_last else 0)

    def half(self, m, full_m):
        move = full_m - m
        return m + (round(self.share[0] * move) if abs(move) >= SHARE_MOVE else move // 2)

    def two(self, m, half_m, full_m):
        move = full_m - m
        return half_m + round(self.share[1] * move) if abs(move) >= SHARE_MOVE else full_m

    def update(self, m, base, h, h_last, full_m, half_m, two_m):
        if h_last:
            self.miss = 0.7 * self.miss + 0.3 * (full_m - base) / h
        self.lead = full_m - two_m
        # ratios of decaying sums: a move of a node or two makes one step's ratio noise
        self.moves = [0.7 * a + b for a, b in zip(self.moves, (half_m - m, two_m - half_m,
                                                               full_m - m))]
        if self.moves[2] > 0:
            self.share = [self.moves[0] / self.moves[2], self.moves[1] / self.moves[2]]


def run(model: wear.Model, scheme: str, h: float, stage_s, until: str, s_end: float,
        force_fraction: float, progress=None, check_oscillation: bool = True, *,
        tolerance: float | None = None, scales: dict | None = None, profile=None,
        accept: str = "deferred", watch=None) -> dict:
    """Step the wear from the unworn state; the numerics without case handling.

    h, stage_s, s_end in metres of sliding (adaptive: h is the largest step,
    inf for none). Returns the history (arrays), the stages reached (s, r, f,
    p; on the union of the grids the run used) and counters.
    ``check_oscillation=False`` lets a test see what an unstable explicit run
    returns when nobody looks. ``profile(x)``, the unworn profile, lets the
    domain grow; without it a contact that reaches the domain's edge is an
    error. Adaptive: ``tolerance`` and ``scales`` (F0, d0, s_hat_per_m) set
    the error control, ``accept`` which solution of a step is kept:
    "deferred" (the two half steps, Richardson's correction 2·two − full
    added to the start of the next step), "euler" (the two half steps, no
    correction) or "extrapolated" (Richardson's profile, its contact solved
    afresh: not monotone at the edge). ``watch(s, contact_radius,
    scar_radius)`` is called at every recorded step (:class:`cases.validity.BodyWatch`).
    """
    state = wear.contact_state(model, model.f0.copy())
    F_start = state.force
    if not F_start > 0.0:
        raise SolverError("the unworn indenter carries no load (no node in contact); "
                          "raise mdr.elements or the load")
    rec = _Recorder(stage_s, watch)
    stage_s = rec.stage_s
    counters = {"steps": 0, "gmres_iterations": 0, "contact_iterations": 0,
                "domain_growths": 0}
    counters.update({k: 0 for k in _FLOAT32_COUNTERS})
    N = len(model.x) - 1
    adaptive = scheme == "adaptive"
    # direct solves reuse one factorisation per step size: their steps keep to
    # a ladder 2^k; iterative solves cost the same at any step
    continuous = adaptive and N > wear.DENSE_MAX and ADAPTIVE_ERROR_TARGET is not None
    systems: dict = {}
    m_prev = [state.m, state.m]
    p_prev = None     # the pressure one step back (on the current grid), for guesses
    edges = _EdgeGuess()
    # the 1D profile beyond the contact from a reference (fine grids: there the
    # full transform of each contact iteration cost as much as a GMRES pass)
    far_gap = wear.FarGap() if N > FAR_GAP_FROM else None
    h_last = None
    # (a pressure exponent's Newton iteration settles to the solves' accuracy:
    # it keeps the accurate solves)
    solve_rtol = wear.ACCURATE_RTOL if not adaptive or model.exponent != 1.0 else \
        min(max(ADAPTIVE_SOLVE_SHARE * tolerance, wear.ACCURATE_RTOL), ADAPTIVE_SOLVE_RTOL_MAX)

    def system_for(hc, exact=True):
        """The implicit system of wear compliance hc K (cached by hc; LRU of 6)."""
        sys_ = systems.pop(hc, None)
        if sys_ is None and not exact and systems:
            # an off-ladder step (a stage landing): the nearest factorisation preconditions
            near = min(systems, key=lambda k: abs(math.log(k / hc)))
            return systems[near]
        if sys_ is None:
            if len(systems) >= 6:
                systems.pop(next(iter(systems)))
            # depth control: the contact radius grows to about sqrt(2) a0, twice the
            # nodes of the start in t = r². The factorisation grows by bordering
            # where a contact set needs it, so an adaptive run's systems (each
            # used over a part of the run) start at about the present contact
            grow_by = 1.05 if adaptive else 2.2
            sys_ = wear.ImplicitSystem(model, hc, nodes=int(grow_by * (state.m + 1)) + 16,
                                       rtol=solve_rtol)
        systems[hc] = sys_
        return sys_

    def implicit(st, hn, previous=None, exact=True, guess=None, p_guess=None):
        hc = hn if previous is None else wear.bdf2_coefficients(hn, previous[1])[2] * hn
        if model.exponent != 1.0:
            # the Newton steps' wear compliance is hc K n (p/σ0)^(n-1) per node: a
            # factorisation at its typical size (a power of 2, so it is reused)
            # preconditions their GMRES solves well
            p_in = st.p[:st.m + 1]
            typical = float(wear.wear_speed_slope(model, np.array([np.mean(p_in)]))[0])
            hc = hc * 2.0 ** round(math.log2(max(typical, 1e-12)))
            exact = True
        return wear.implicit_step(model, st, hn, m_guess=guess, system=system_for(hc, exact),
                                  previous=previous, p_guess=p_guess, far_gap=far_gap)

    h_sys = None
    if scheme in ("implicit", "bdf2"):
        # one factorisation for the run's regular step (BDF2: wear compliance
        # c h with c = 2/3 at a constant step); the first, stage-landing and
        # ratio-limited steps use it as a preconditioner
        h_sys = h if scheme == "implicit" else wear.bdf2_coefficients(h, h)[2] * h
        system_for(h_sys)
    previous = None
    ramp = []
    if scheme == "bdf2":
        # BDF2 starts with a short backward-Euler step (its O(h²) local error would
        # otherwise be the largest part of the run's time error), then doubles the
        # step: h/16, h/16, h/8, h/4, h/2 reach s = h, so the regular steps stay
        # aligned with stages at multiples of h
        ramp = [BDF2_FIRST_STEP * h]
        while sum(ramp) < h * (1 - 1e-9):
            ramp.append(sum(ramp))
    corr = None     # adaptive: Richardson's correction for the next step's start
    if adaptive:
        per_m = scales["s_hat_per_m"]
        h_cur = min(ADAPTIVE_FIRST_STEP_HAT / per_m, h)
        F0, d0 = scales["F0"], scales["d0"]
        time_error = error_sum = 0.0
        counters.update(rejected_steps=0, largest_step_hat=0.0)
    s = 0.0
    last_report = -1.0
    max_steps = ADAPTIVE_MAX_STEPS if adaptive else MAX_STEPS

    def grow():
        nonlocal model, state, previous, systems, corr, p_prev, far_gap
        if profile is None:
            raise SolverError("the contact has reached the edge of the MDR domain; raise "
                              "mdr.domain_factor")
        arrays = [(state.f, "profile"), (state.slip, "field"),
                  (None if previous is None else previous[0], "profile"), (corr, "increment")]
        model, (f, slip, f_prev, corr) = grow_domain(model, profile, arrays)
        state = wear.contact_state(model, f)
        state.slip = slip
        if previous is not None:
            previous = (f_prev, previous[1])
        systems = {}
        p_prev = None
        edges.reset()
        if far_gap is not None:
            far_gap = wear.FarGap()
        if h_sys is not None:
            system_for(h_sys)
        m_prev[:] = [state.m, state.m]
        counters["domain_growths"] += 1

    def error_of(a, b):
        """Local error estimate between two solutions of one step (relative to the scales)."""
        return max(abs(a.force - b.force) / F0,
                   abs(a.depth - b.depth) / max(d0, abs(a.depth)),
                   abs(a.f[0] - b.f[0]) / max(d0, abs(a.f[0] - model.f0[0])))

    rec(model, state, s)
    while True:
        if until == "force_fraction" and s > 0.0 and state.force < force_fraction * F_start:
            break
        if s >= s_end:
            break
        if state.m >= GROW_AT * N and profile is not None:
            grow()
        target = s_end
        if stage_s:
            target = min(target, stage_s[0])
        hstep = h_cur if adaptive else h
        # land exactly on the next stage or the end (never a sliver of a step after it)
        if target - s <= hstep * (1 + 1e-9):
            hn, s_new = target - s, target
        elif adaptive and target - s < 2.0 * hstep:
            # two equal steps onto the stage rather than a regular step and a
            # sliver: a sliver after a long step leaves a pressure maximum on the
            # outermost node in contact (measured, prominence 0.006 p(0))
            hn = 0.5 * (target - s)
            s_new = s + hn
        elif scheme == "bdf2" and target - s < 2.0 * h:
            # BDF2: two equal steps onto the stage rather than a regular step and
            # a short one, so the step ratios around it stay within [1/2, 2]
            hn = 0.5 * (target - s)
            s_new = s + hn
        else:
            hn, s_new = hstep, s + hstep
        if scheme == "bdf2":
            # the step grows by at most BDF2_MAX_RATIO per step, also after a
            # short step (stages closer than h): zero-stable below 1 + √2
            cap = math.inf if previous is None else BDF2_MAX_RATIO * previous[1]
            if ramp:
                cap = min(cap, ramp.pop(0))
            if hn > cap:
                hn, s_new = cap, s + cap
        # the contact edge extrapolated linearly in s from the last step
        guess = state.m + (round((state.m - m_prev[-1]) * hn / h_last) if h_last else 0)
        try:
            if scheme == "explicit":
                new = wear.explicit_step(model, state, hn)
                if check_oscillation and wear.oscillation(new.p, new.m):
                    raise SolverError(
                        f"explicit Euler: grid-scale oscillation of the pressure at ŝ step "
                        f"{counters['steps'] + 1}; the step is past the stability limit — "
                        "reduce sliding.step_hat or use sliding.scheme = \"implicit\"")
            elif adaptive:
                # (a regular step: not shortened to land on a stage)
                regular = hn == h_cur
                start = state if corr is None else dataclasses.replace(state, f=state.f + corr)
                # the pressure extrapolated linearly in s starts the iterative
                # solves of fine grids (GMRES iterations of the full step's first
                # pass at N = 25600: 8-10 from the step's start pressure, 5-7 from this)
                p_guess = None if p_prev is None or not h_last else \
                    state.p + (state.p - p_prev) * (hn / h_last)
                full = implicit(start, hn, exact=regular,
                                guess=edges.full(state.m, guess, hn, h_last), p_guess=p_guess)
                # the half steps start from the full step's pressure (at their
                # end, and half way)
                half = implicit(start, 0.5 * hn, exact=regular,
                                guess=edges.half(state.m, full.m),
                                p_guess=0.5 * (state.p + full.p))
                two = implicit(half, 0.5 * hn, exact=regular,
                               guess=edges.two(state.m, half.m, full.m), p_guess=full.p)
                edges.update(state.m, guess, hn, h_last, full.m, half.m, two.m)
                err = error_of(two, full)
                for st in (full, half, two):
                    for k in ("gmres_iterations", "contact_iterations") + _FLOAT32_COUNTERS:
                        counters[k] += st.stats.get(k, 0)
                if err > tolerance and hn > 1e-12 * max(s, hn):
                    counters["rejected_steps"] += 1
                    if continuous:
                        h_cur = min(h_cur, hn * _step_factor(err, tolerance, 0.2))
                    else:
                        h_cur = 0.5 * hn if regular else min(h_cur, _ladder_below(hn, per_m))
                    continue
                if accept == "extrapolated":
                    new = wear.contact_state(model, 2.0 * two.f - full.f)
                    new.slip = two.slip
                elif accept == "deferred":
                    # keep the backward-Euler state (monotone at the edge) and carry
                    # Richardson's correction into the next step's start profile
                    new = two
                    corr = two.f - full.f
                    # no negative correction on the outermost contact node and
                    # beyond: it leaves that node less worn than its neighbours,
                    # a pressure maximum on it at tight tolerances (measured on
                    # paper.toml, N = 800, tolerance 1e-5: prominence 0.0024
                    # p(0) with it, none at any tolerance or N without; the
                    # global error is 9.3e-5 at 1e-4 (9.9e-5 with it), 3.2e-5
                    # at 1e-5 (1.4e-5 with it): docs/time-stepping.md)
                    corr[two.m:] = np.maximum(corr[two.m:], 0.0)
                else:
                    new = two
                time_error = max(time_error, err)
                error_sum += err
                counters["largest_step_hat"] = max(counters["largest_step_hat"], hn * per_m)
                if continuous:
                    grown = min(hn * _step_factor(err, tolerance, 0.5), h)
                    h_cur = grown if regular else min(h_cur, max(grown, hn))
                elif regular and err < ADAPTIVE_GROW_BELOW * tolerance and 2.0 * hn <= h:
                    h_cur = 2.0 * hn
            else:
                hc = hn if previous is None else wear.bdf2_coefficients(hn, previous[1])[2] * hn
                new = implicit(state, hn, previous, exact=hc == h_sys, guess=guess)
                if scheme == "bdf2":
                    previous = (state.f, hn)
                for k in ("gmres_iterations", "contact_iterations") + _FLOAT32_COUNTERS:
                    counters[k] += new.stats.get(k, 0)
        except contact.DomainOutgrown:
            if profile is None:
                raise SolverError("the contact has reached the edge of the MDR domain; raise "
                                  "mdr.domain_factor") from None
            grow()
            continue
        m_prev[:] = [m_prev[-1], state.m]
        p_prev = state.p
        if not np.all(np.isfinite(new.f)) or not math.isfinite(new.force):
            raise SolverError("the wear run produced non-finite values; reduce sliding.step_hat")
        state, s, h_last = new, s_new, hn
        counters["steps"] += 1
        rec(model, state, s)
        if counters["steps"] >= max_steps:
            raise SolverError(f"the wear run took more than {max_steps} steps; raise "
                              "sliding.step_hat or sliding.tolerance")
        if progress is not None:
            if until == "distance":
                frac = s / s_end
            else:
                frac = (1.0 - state.force / F_start) / (1.0 - force_fraction)
            if frac - last_report >= 0.01:
                last_report = frac
                progress(min(max(frac, 0.0), 1.0), f"F/F0 = {state.force / F_start:.3g}")
    counters.update(F_start=F_start, N=N, domain=float(model.x[-1]))
    if adaptive:
        counters["time_error"] = time_error
        counters["local_error_sum"] = error_sum
    stage_s_out, r, f, p = rec.stage_arrays(profile if profile is not None
                                            else (lambda x: np.interp(x, model.x, model.f0)),
                                            model.x)
    return dict(history={k: np.asarray(v) for k, v in rec.hist.items()},
                stage_s=stage_s_out, r=r, f=f, p=p,
                counters=counters)


def _step_factor(err: float, tolerance: float, least: float) -> float:
    """The step's factor that brings the error estimate (~h²) to ADAPTIVE_ERROR_TARGET·tolerance."""
    if err <= 0.0:
        return ADAPTIVE_MAX_GROWTH
    return min(ADAPTIVE_MAX_GROWTH, max(least, math.sqrt(ADAPTIVE_ERROR_TARGET * tolerance / err)))


def _ladder_below(h: float, per_m: float) -> float:
    """The largest ladder step 2^k (in ŝ) below h [m], in metres."""
    return 2.0 ** math.floor(math.log2(0.5 * h * per_m)) / per_m


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
    resolution.check(case)
    validity.check_planned(case)
    model, sc = build_model(case)
    per_m = sc["s_hat_per_m"]
    sl = case.sliding
    info = dict(solver="mdr", N=case.mdr.elements, domain_start=float(model.x[-1]),
                grid="uniform in r^2", scheme=sl.scheme,
                pressure_exponent=case.wear.pressure_exponent)
    adaptive = sl.scheme == "adaptive"
    if sl.scheme == "explicit":
        limit_hat = stability_limit_hat(model, per_m, p_max=1.5 * sc["p0"])
        info["stability_limit_hat"] = limit_hat
        step_hat = 0.5 * limit_hat if sl.step_hat == "auto" else sl.step_hat
        if step_hat > limit_hat:
            raise CaseError(
                f"key 'sliding.step_hat' = {sl.step_hat!r}: past the stability limit of "
                f"explicit Euler on this grid; the largest stable step is {limit_hat:.4g} "
                f"(N = {case.mdr.elements}); use a smaller step or sliding.scheme = "
                "\"implicit\"")
    elif adaptive:
        step_hat = math.inf if sl.step_hat == "auto" else sl.step_hat
        info["tolerance"] = sl.tolerance
    else:
        auto = IMPLICIT_STEP_HAT if sl.scheme == "implicit" else BDF2_STEP_HAT
        step_hat = auto if sl.step_hat == "auto" else sl.step_hat
    info["step_hat"] = float(step_hat) if math.isfinite(step_hat) else "unlimited"
    # approximate: False, or the reason (what comparisons report per solver)
    watch = validity.BodyWatch(case)
    info["approximate"] = False
    if case.indenter.profile == "ellipsoid":
        info["approximate"] = info["warning"] = ellipsoid_warning(case)
        info["equivalent_radius"] = profiles.equivalent_radius(case.indenter)
        validity.remark(watch.remarks, info["warning"])
    s_end, stage_s, until = programme.sliding_plan(
        case, step_hat, per_m, s_hat_cap=ADAPTIVE_MAX_S_HAT if adaptive else MAX_S_HAT,
        max_steps=MAX_STEPS, adaptive=adaptive)

    def profile(x):
        return profiles.height(case.indenter, x, case.table)

    out = run(model, sl.scheme, step_hat / per_m, stage_s, until, s_end, sl.force_fraction,
              progress, tolerance=sl.tolerance, scales=sc, profile=profile, accept=ADAPTIVE_ACCEPT,
              watch=watch)
    if watch.remarks:
        info["warnings"] = watch.remarks
    hist = programme.finish_history(case, out["history"], until, s_end, per_m)
    counters = out["counters"]
    info.update(counters)
    info["domain"] = counters.pop("domain")
    if adaptive:
        info["time_error"] = dict(
            estimate=info.pop("time_error"), local_error_sum=info.pop("local_error_sum"),
            meaning="largest step-doubling estimate of a step's local error (force /F0, depth "
                    "and central wear /max(d0, value)): the recorded states are backward-Euler "
                    "states one step off the propagated second-order (Richardson-corrected) "
                    "solution, so this estimates the global time error of the history "
                    "(measured on paper.toml: 0.93e-4 at tolerance 1e-4; 3.2e-5 at 1e-5)")
    if progress is not None:
        progress(1.0, "done")
    return RunResult(history=hist, stage_s=out["stage_s"], r=out["r"], f=out["f"], p=out["p"],
                     solve_seconds=time.perf_counter() - t0, info=info)
