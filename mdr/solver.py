"""``mdr.solve(case)``: the MDR gross-slip wear run of one case."""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from wearcheck.cases import CaseError, RunResult, SolverError, profiles, programme, reference
from wearcheck.cases import validity
from wearcheck.cases.result import scar_radii

from wearcheck.numerics import stepping

from . import contact, fretting, linalg, resolution, transforms, wear

#: implicit Euler's default step in ŝ (sliding.step_hat = "auto"): its time
#: error, first order in Δŝ, is docs/performance.md's ("Measurements behind the code")
IMPLICIT_STEP_HAT = 0.1
#: the largest |V/(K F s) − 1| at the end of a force-controlled run with n = 1 that
#: is taken as wear and not round-off: the grid's and the steps' own errors are far
#: below it (tests/test_mdr_archard_balance.py), a wear that round-off swallows far
#: past it (docs/performance.md, "Measurements behind the code")
ARCHARD_BALANCE_TOL = 0.02
#: BDF2's default step in ŝ, chosen for speed: on paper.toml its time error in
#: F/F0 is 1/30 of implicit Euler's at its default step, second order in the
#: bulk of the run (at finer steps the first tenths of ŝ, the Hertz start, not
#: smooth in s, dominate); lower step_hat for more accuracy. The errors and
#: times by step: docs/performance.md, "Measurements behind the code"
BDF2_STEP_HAT = 0.1
#: the domain grows (t = r² doubles, the grid keeps every other node) once
#: the contact edge passes this fraction of the nodes
GROW_AT = 0.8
#: the half steps' edges are guessed from the shares of the full step's edge
#: move they took of late when it moves at least this many nodes, else as its
#: midpoint and end: the fewest contact and GMRES iterations of the three rules
#: tried (docs/performance.md, "Measurements behind the code")
SHARE_MOVE = 4
#: iterative solves of an adaptive run: GMRES's relative residual as a share
#: of the run's tolerance (1e-7 at the default 1e-4), between wear.ACCURATE_RTOL
#: and ADAPTIVE_SOLVE_RTOL_MAX. The solves' error stays about 1 % of the time
#: error the run accepts, for less time than 1e-9; looser than 1e-7, the
#: marginal edge node is decided by the solver's noise and the contact
#: iterations multiply (docs/performance.md, "Measurements behind the code")
ADAPTIVE_SOLVE_SHARE = 1e-3
ADAPTIVE_SOLVE_RTOL_MAX = 1e-7
#: the matrix-free solves' GMRES iterations done in float32 (of gmres_iterations)
#: and their solves finished by float64 GMRES (mdr/linalg.py, iterative refinement)
_FLOAT32_COUNTERS = ("gmres_float32_iterations", "gmres_float64_fallbacks")
#: the solves' counters a run sums
_COUNTERS = ("gmres_iterations", "contact_iterations") + _FLOAT32_COUNTERS

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
                       tangential=tangential, stroke=case.sliding.stroke,
                       exponent=case.wear.pressure_exponent,
                       hardness=case.wear.hardness, linear_solver=case.mdr.linear_solver,
                       krylov_precision=case.mdr.krylov_precision)
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


#: the recorder derives its rows' columns at once every FLUSH_ROWS rows, or fewer
#: where the rows held would pass FLUSH_VALUES values (fine grids)
FLUSH_ROWS = 64
FLUSH_VALUES = 2 ** 21


class _Recorder:
    """History rows and stored stages of a run whose grid may grow.

    A row holds its state's profile and pressure (each solve's own arrays, never
    changed after it) until :meth:`flush` derives the worn volume, scar radius,
    central wear and maximum pressure of the rows held, all on one grid, at once,
    and calls ``watch`` on them in order (``watch.rows`` where it has it): at a
    grid change, every :data:`FLUSH_ROWS` rows and at the end of the run (the
    per-row numpy calls were most of the recording's time; the unworn state is
    watched at once). A row past
    the body's end is refused at most that many rows after it; :func:`run`
    flushes before any error of the stepper, so the watch's refusal comes first,
    as when each row was watched at once.
    """

    def __init__(self, watch=None):
        self.hist = {k: [] for k in ("s", "force", "depth", "contact_radius", "wear_center",
                                     "wear_volume", "scar_radius", "max_pressure")}
        self.stages = []      # (s, x, f, p)
        self.watch = watch    # watch(s, contact_radius, scar_radius) per recorded step
        self.model = None     # the grid of the rows held
        self.held = []        # their (f, p)
        self.limit = FLUSH_ROWS

    def __call__(self, model, st, s, stages):
        """Record ``st`` at s on ``model``'s grid; it completes ``stages`` stages."""
        if model is not self.model:
            self.flush()
            self.model = model
            self.limit = max(1, min(FLUSH_ROWS, FLUSH_VALUES // len(model.x)))
        h = self.hist
        h["s"].append(s)
        h["force"].append(st.force)
        h["depth"].append(st.depth)
        h["contact_radius"].append(st.contact_radius)
        self.held.append((st.f, st.p))
        for _ in range(stages):
            self.stages.append((s, model.x.copy(), st.f.copy(), st.p.copy()))
        if len(self.held) >= self.limit or len(h["s"]) == 1:   # (the unworn state at once)
            self.flush()

    def flush(self):
        """Derive the held rows' columns and watch them."""
        held, model = self.held, self.model
        if not held:
            return
        self.held = []
        w = np.array([f for f, _ in held])
        w -= model.f0
        scar = scar_radii(model.x, w)
        h = self.hist
        h["wear_center"].extend(w[:, 0].tolist())
        h["wear_volume"].extend(transforms.volume(w, model.dt).tolist())
        h["scar_radius"].extend(scar.tolist())
        h["max_pressure"].extend(np.array([p for _, p in held]).max(axis=1).tolist())
        if self.watch is None:
            return
        n = len(held)
        s, a = h["s"][-n:], h["contact_radius"][-n:]
        rows = getattr(self.watch, "rows", None)
        if rows is not None:
            rows(s, a, scar)
        else:
            for args in zip(s, a, scar.tolist()):
                self.watch(*args)

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


class Wear(stepping.Problem):
    """The MDR's implicit wear step on its grid, as :mod:`numerics.stepping` steps it.

    What the stepper cannot know and this keeps between its calls: one
    implicit system per wear compliance (direct solves: a nested factorisation per step
    size of the ladder, the regular step's for fixed steps, the nearest one
    preconditioning a stage landing; GMRES grids: the coarse-grid
    preconditioner, the same at any step), the guesses of the contact edge
    and pressure from the accepted states (:meth:`accepted`), the far-gap
    reference, and the grid, which grows by √2 in r when the contact nears its
    edge (:meth:`regrid`; a solve whose contact reaches the edge raises
    :class:`numerics.stepping.Regrid`). ``profile(x)``, the unworn profile,
    lets the grid grow; without it a contact at the edge is an error.
    ``check_oscillation=False`` lets a test see what an unstable explicit run
    returns when nobody looks.
    """

    def __init__(self, model: wear.Model, start: wear.State, plan: stepping.Plan, *,
                 profile=None, check_oscillation: bool = True):
        self.model, self.unworn = model, profile
        self.check_oscillation = check_oscillation
        self.adaptive = plan.scheme == "adaptive"
        self.N = len(model.x) - 1
        self.counters = {"gmres_iterations": 0, "contact_iterations": 0, "domain_growths": 0}
        self.counters.update({k: 0 for k in _FLOAT32_COUNTERS})
        self.current = start      # the last accepted state
        self.m_prev = start.m     # the contact edge one accepted state back
        self.p_prev = None        # the pressure one accepted state back (this grid)
        self.h_last = None        # the last accepted step
        self.steps = 0
        self.edges = _EdgeGuess()
        self.systems: dict = {}
        # the regular steps' solves are direct (exact, started from no guess of p):
        # their pressure guesses are not formed
        self.direct = wear.solves_directly(model) and model.exponent == 1.0 \
            and model.tangential == 0.0
        # (a pressure exponent's Newton iteration settles to the solves' accuracy:
        # it keeps the accurate solves)
        self.solve_rtol = wear.ACCURATE_RTOL if not self.adaptive or model.exponent != 1.0 \
            else min(max(ADAPTIVE_SOLVE_SHARE * plan.tolerance, wear.ACCURATE_RTOL),
                     ADAPTIVE_SOLVE_RTOL_MAX)
        # one factorisation for the run's regular step (BDF2: wear compliance
        # c h with c = 2/3 at a constant step); the first, stage-landing and
        # ratio-limited steps use it as a preconditioner
        self.h_sys = None
        if plan.scheme in ("implicit", "bdf2"):
            c = 1.0 if plan.scheme == "implicit" else stepping.bdf2_coefficients(plan.step,
                                                                                 plan.step)[2]
            self.h_sys = c * plan.step
            self.system_for(self.h_sys)
        self._edge = None         # a doubled step's edge extrapolated from the accepted states

    def system_for(self, hc, exact=True):
        """The implicit system of wear compliance hc K (cached by hc; LRU of 6)."""
        systems = self.systems
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
            grow_by = 1.05 if self.adaptive else 2.2
            sys_ = wear.ImplicitSystem(self.model, hc,
                                       nodes=int(grow_by * (self.current.m + 1)) + 16,
                                       rtol=self.solve_rtol)
        systems[hc] = sys_
        return sys_

    def _edge_guess(self, h):
        """The contact edge extrapolated linearly in s from the last step."""
        st = self.current
        return st.m + (round((st.m - self.m_prev) * h / self.h_last) if self.h_last else 0)

    def _solve(self, origin, base, h, c, exact, guess, p_guess=None):
        model = self.model
        hc = c * h
        if model.exponent != 1.0:
            # the Newton steps' wear compliance is hc K n (p/σ0)^(n-1) per node: a
            # factorisation at its typical size (a power of 2, so it is reused)
            # preconditions their GMRES solves well
            p_in = origin.p[:origin.m + 1]
            typical = float(wear.wear_speed_slope(model, np.array([np.mean(p_in)]))[0])
            hc = hc * 2.0 ** round(math.log2(max(typical, 1e-12)))
            exact = True
        try:
            return wear.implicit_step(model, origin, h, c, base, m_guess=guess,
                                      system=self.system_for(hc, exact), p_guess=p_guess)
        except contact.DomainOutgrown:
            raise stepping.Regrid() from None

    def implicit(self, origin, base, h, c, sub):
        if sub.kind == "step":
            new = self._solve(origin, base, h, c, sub.regular, self._edge_guess(h))
            self._count(new)
            return new
        # a doubled step: the guesses of its three solves (_EdgeGuess)
        start, hn, edges = sub.start, sub.length, self.edges
        iterative = not (self.direct and sub.regular)
        if sub.kind == "full":
            self._edge = self._edge_guess(hn)
            # the pressure extrapolated linearly in s starts the iterative
            # solves of fine grids (GMRES iterations of the full step's first
            # pass at N = 25600: 8-10 from the step's start pressure, 5-7 from this)
            p_guess = None if self.p_prev is None or not self.h_last or not iterative else \
                start.p + (start.p - self.p_prev) * (hn / self.h_last)
            return self._solve(origin, base, h, c, sub.regular,
                               edges.full(start.m, self._edge, hn, self.h_last), p_guess)
        # the half steps start from the full step's pressure (at their end, and half way)
        full = sub.full
        if sub.kind == "half":
            return self._solve(origin, base, h, c, sub.regular, edges.half(start.m, full.m),
                               0.5 * (start.p + full.p) if iterative else None)
        two = self._solve(origin, base, h, c, sub.regular,
                          edges.two(start.m, sub.half.m, full.m), full.p)
        edges.update(start.m, self._edge, hn, self.h_last, full.m, sub.half.m, two.m)
        for st in (full, sub.half, two):
            self._count(st)
        return two

    def _count(self, st):
        for k in _COUNTERS:
            self.counters[k] += st.stats.get(k, 0)

    def explicit(self, state, h, sub):
        new = wear.explicit_step(self.model, state, h)
        if self.check_oscillation and wear.oscillation(new.p, new.m):
            raise SolverError(
                f"explicit Euler: grid-scale oscillation of the pressure at ŝ step "
                f"{self.steps + 1}; the step is past the stability limit — "
                "reduce sliding.step_hat or use sliding.scheme = \"implicit\"")
        return new

    def profile(self, state):
        return state.f

    def measures(self, state):
        return state.force, state.depth, state.f[0] - self.model.f0[0]

    def outside(self, state):
        # no negative Richardson correction on the outermost contact node and
        # beyond: it leaves that node less worn than its neighbours, a pressure
        # maximum on it at tight tolerances (docs/time-stepping.md)
        return slice(state.m, None)

    def accepted(self, old, new, h):
        self.m_prev, self.p_prev, self.h_last = old.m, old.p, h
        self.current = new
        self.steps += 1

    def regrid(self, state, carried, forced):
        """The domain √2 wider (t = r² doubled) when the contact passes GROW_AT of
        the nodes or reached the edge in a solve (``forced``)."""
        if self.unworn is None:
            if forced:
                raise SolverError("the contact has reached the edge of the MDR domain; raise "
                                  "mdr.domain_factor")
            return None
        if not forced and state.m < GROW_AT * self.N:
            return None
        arrays = [(state.f, "profile"), (state.slip, "field"), (carried["previous"], "profile"),
                  (carried["correction"], "increment")]
        self.model, (f, slip, f_prev, corr) = grow_domain(self.model, self.unworn, arrays)
        state = wear.contact_state(self.model, f)
        state.slip = slip
        self.current = state
        self.systems = {}
        self.p_prev = None
        self.edges.reset()
        if self.h_sys is not None:
            self.system_for(self.h_sys)
        self.m_prev = state.m
        self.counters["domain_growths"] += 1
        return state, {"correction": corr, "previous": f_prev}


def archard_balance(history: dict, K: float, force: float) -> float:
    """|V / (K F s) − 1| at the run's end: Archard's law (n = 1) under a constant force
    F wears the volume K·F·s exactly, whatever the profile; 0 for a run without sliding."""
    s, V = float(history["s"][-1]), float(history["wear_volume"][-1])
    return abs(V / (K * force * s) - 1.0) if s > 0.0 else 0.0


def wear_rate_key(case) -> tuple[str, float]:
    """The key the case gave K by, and its value: wear.k, or wear.specific_rate
    (the loader derives the other, :attr:`cases.Case.derived`)."""
    w = case.wear
    return ("wear.specific_rate", w.specific_rate) if "wear.k" in case.derived \
        else ("wear.k", w.k)


def check_archard_balance(case, history: dict) -> float | None:
    """Refuse (SolverError) a force-controlled run with n = 1 (and no tangential
    correction, whose slip factor wears less than K·F·s) whose volume at the end is
    not K·F·s within :data:`ARCHARD_BALANCE_TOL`: its wear was lost to round-off (a wear
    rate so small that each step's wear K·p·Δs falls below float64's resolution of the
    profile heights). Returns the balance's error (None where it does not apply)."""
    # with wear.tangential_correction each stroke end loses sliding to the tangential
    # springs' reversal (slip factor S < 1): the volume is K·F·∫S ds, not K·F·s
    if case.loading.control != "force" or case.wear.pressure_exponent != 1.0 \
            or case.wear.tangential_correction:
        return None
    K, F = case.wear_rate, case.loading.force
    error = archard_balance(history, K, F)
    if error > ARCHARD_BALANCE_TOL:
        key, value = wear_rate_key(case)
        s, V = float(history["s"][-1]), float(history["wear_volume"][-1])
        raise SolverError(
            f"key '{key}' = {value!r}: the worn volume at the end, {V:.4g} m³, is "
            f"{V / (K * F * s):.3g} of Archard's K·F·s = {K * F * s:.4g} m³ (K = {K:.4g} 1/Pa): "
            f"the wear of each step, K·p·Δs, is lost in the round-off of the profile heights "
            f"(float64, 1e-16 of them); a wear rate this small leaves the profile unworn to float64's "
            f"resolution: its volume is V = K·F·s by Archard's law alone")
    return error


def run(model: wear.Model, plan: stepping.Plan, progress=None, *, profile=None,
        check_oscillation: bool = True, watch=None) -> dict:
    """Step the wear from the unworn state as ``plan`` says; the numerics without case handling.

    Returns the history (arrays), the stages reached (s, r, f, p; on the
    union of the grids the run used), counters (the stepping's of
    :func:`numerics.stepping.info` and the solves') and ``outcome``, the
    stepper's :class:`numerics.stepping.Outcome`.
    ``profile`` and ``check_oscillation``: see :class:`Wear`. ``watch(s,
    contact_radius, scar_radius)`` is called at every recorded step
    (:class:`cases.validity.BodyWatch`).
    """
    state = wear.contact_state(model, model.f0.copy())
    if not state.force > 0.0:
        raise SolverError("the unworn indenter carries no load (no node in contact); "
                          "raise mdr.elements or the load")
    problem = Wear(model, state, plan, profile=profile, check_oscillation=check_oscillation)
    rec = _Recorder(watch)
    try:
        outcome = stepping.run(problem, state, plan,
                               lambda st, s, stages: rec(problem.model, st, s, stages), progress)
    except Exception:
        # the rows not yet watched first: one past the body's end is the run's refusal
        try:
            rec.flush()
        except Exception as refusal:
            raise refusal from None
        raise
    rec.flush()
    model = problem.model
    counters = dict(stepping.info(outcome, plan), **problem.counters)
    counters.update(F_start=outcome.force_start, N=problem.N, domain=float(model.x[-1]))
    stage_s, r, f, p = rec.stage_arrays(profile if profile is not None
                                        else (lambda x: np.interp(x, model.x, model.f0)),
                                        model.x)
    return dict(history={k: np.asarray(v) for k, v in rec.hist.items()},
                stage_s=stage_s, r=r, f=f, p=p, counters=counters)


def solve(case, progress=None) -> RunResult:
    """Run the MDR wear simulation of ``case`` (see the package docstring).

    BLAS runs single-threaded meanwhile (:func:`mdr.linalg.single_threaded_blas`).
    A case with a [fretting] section runs :func:`mdr.fretting.solve`.
    """
    if getattr(case, "fretting", None) is not None:
        return fretting.solve(case, progress)
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
    # direct solves reuse one factorisation per step size: their steps keep to
    # the ladder 2^k ŝ; iterative solves cost the same at any step
    control = "ladder" if wear.solves_directly(model) else "continuous"
    plan, until = programme.stepping_plan(case, step_hat, sc, control=control)

    def profile(x):
        return profiles.height(case.indenter, x, case.table)

    out = run(model, plan, progress, profile=profile, watch=watch)
    if watch.remarks:
        info["warnings"] = watch.remarks
    hist = programme.finish_history(case, out["history"], until, plan.end, per_m)
    balance = check_archard_balance(case, hist)
    if balance is not None:
        info["archard_balance_error"] = balance
    info.update(out["counters"])
    if progress is not None:
        progress(1.0, "done")
    return RunResult(history=hist, stage_s=out["stage_s"], r=out["r"], f=out["f"], p=out["p"],
                     solve_seconds=time.perf_counter() - t0, info=info)
