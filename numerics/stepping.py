"""The time stepper of the wear law, shared by every gross-slip solver.

The wear law dw/ds = K σ0 (p/σ0)^n is integrated in the sliding distance s.
A solver describes its discretisation as a :class:`Problem` — above all its
implicit step: from a state and a start profile, the state after a step of
length h with wear compliance c·h — and :func:`run` does the rest, the same
for every solver: the schemes (explicit and implicit Euler, variable-step
BDF2, step doubling with the deferred Richardson correction), the step
ladder 2^k ŝ or continuous step control, landing on stages, the run caps,
the stop rules and the time-error estimate (docs/time-stepping.md).

Distances are in metres; ``Plan.per_m`` (ŝ per metre) sets the ladder.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from wearcheck.cases.errors import CaseError, SolverError

SCHEMES = ("explicit", "implicit", "bdf2", "adaptive")
#: runaway guards. Fixed steps: ŝ and steps; adaptive steps grow as wear
#: slows, so those runs are capped in steps only (and ŝ < 1e9)
MAX_S_HAT = 1.0e4
MAX_STEPS = 2_000_000
ADAPTIVE_MAX_S_HAT = 1.0e9
ADAPTIVE_MAX_STEPS = 100_000
#: BDF2: largest ratio of consecutive steps (zero-stable below 1 + √2)
BDF2_MAX_RATIO = 2.0
#: BDF2's first (backward Euler) step as a fraction of its step, a power of
#: 1/2 so that the doubling ramp after it sums to one step: a full first step's
#: O(h²) local error would be the largest part of the run's time error
#: (docs/time-stepping.md)
BDF2_FIRST_STEP = 1.0 / 16.0
#: step doubling: the first step in ŝ; on the ladder the steps are 2^k ŝ
FIRST_STEP_HAT = 2.0 ** -7
#: ladder: the step doubles when the estimate is below this fraction of the
#: tolerance (it grows as h², fourfold per doubling)
GROW_BELOW = 0.2
#: continuous control: the step is set so that the estimate comes to this
#: fraction of the tolerance, growing at most MAX_GROWTH per step and falling
#: at most to 0.5 (0.2 after a rejection); 0.5 keeps the ladder's accuracy with
#: fewer steps (docs/time-stepping.md)
ERROR_TARGET = 0.5
MAX_GROWTH = 2.0
#: what ``info.time_error`` means, in meta.json
TIME_ERROR_MEANING = (
    "largest step-doubling estimate of a step's local error (force /F0, depth and central "
    "wear /max(d0, value)): the recorded states are backward-Euler states one step off the "
    "propagated second-order (Richardson-corrected) solution, so this estimates the global "
    "time error of the history (measured on paper.toml, MDR: 0.93e-4 at tolerance 1e-4; "
    "3.2e-5 at 1e-5)")


def caps(scheme: str) -> tuple[float, int]:
    """The run caps of a scheme: the longest run in ŝ and the most steps."""
    if scheme == "adaptive":
        return ADAPTIVE_MAX_S_HAT, ADAPTIVE_MAX_STEPS
    return MAX_S_HAT, MAX_STEPS


def bdf2_coefficients(h: float, h_prev: float | None) -> tuple[float, float, float]:
    """Variable-step BDF2: y_{n+1} = a y_n + b y_{n-1} + c h y'_{n+1}.

    With ω = h/h_prev: a = (1+ω)²/(1+2ω), b = -ω²/(1+2ω), c = (1+ω)/(1+2ω)
    (a + b = 1). ``h_prev=None`` (no history) gives backward Euler (1, 0, 1).
    """
    if h_prev is None:
        return 1.0, 0.0, 1.0
    w = h / h_prev
    return (1.0 + w) ** 2 / (1.0 + 2.0 * w), -w * w / (1.0 + 2.0 * w), (1.0 + w) / (1.0 + 2.0 * w)


@dataclass(slots=True)
class Substep:
    """What a solve is within its step, for the solver's guesses and factorisations.

    ``kind``: "step" (the one solve of a fixed-step scheme), or the three
    solves of a doubled step: "full" (one step of ``length``), "half" (its
    first half) and "second" (the second half, from the first). ``regular``:
    the step has the size the scheme keeps returning to (the ladder's or
    the fixed step; not shortened to land on a stage), so a factorisation
    for it is worth keeping. ``start``: the accepted state the step starts
    from; ``full`` and ``half``: the solves of the doubled step made so far.
    Not frozen: three are made a step, and a frozen dataclass's ``__init__``
    takes three times as long (docs/performance.md).
    """

    kind: str
    regular: bool
    s: float                 # distance at the start of the step [m]
    length: float            # the whole step [m] (both halves' step for "half", "second")
    start: object
    full: object = None
    half: object = None


class Regrid(Exception):
    """Raised by a solve when the discretisation must change before it can be
    solved (the MDR: the contact reached the edge of its domain); the stepper
    calls :meth:`Problem.regrid` with ``forced=True`` and retries the step."""


class Problem:
    """A solver's discretisation as the stepper sees it.

    Subclasses supply :meth:`implicit` (required), :meth:`profile` and
    :meth:`measures`, and as needed :meth:`explicit`, :meth:`accepted`,
    :meth:`regrid` and :meth:`outside`. States are the solver's own objects;
    the stepper reads them only through these methods.
    """

    def implicit(self, origin, base: np.ndarray, h: float, c: float, sub: Substep):
        """The state after a step of length h with wear compliance c·h.

        The new profile is ``base + c h · (wear speed at the new pressure)``
        (c = 1: backward Euler from ``base``; BDF2: ``base`` = a y_n + b
        y_{n-1}). ``origin`` is the state the solve starts from (its contact
        set and pressure are the guesses; ``base`` is its profile, or that
        profile plus the carried correction).
        """
        raise NotImplementedError

    def explicit(self, state, h: float, sub: Substep):
        """Forward Euler: the state after wearing ``state`` by its own pressure for h."""
        raise NotImplementedError(f"{type(self).__name__} has no explicit step")

    def profile(self, state) -> np.ndarray:
        """The integrated variable of ``state`` (the worn profile or the wear depth)."""
        raise NotImplementedError

    def measures(self, state) -> tuple[float, float, float]:
        """(force, depth, wear at the centre): what the stop rule and the error estimate read."""
        raise NotImplementedError

    def accepted(self, old, new, h: float) -> None:
        """Called after each accepted step from ``old`` to ``new`` of length h."""

    def regrid(self, state, carried: dict, forced: bool):
        """Change the discretisation before a step, or None to keep it.

        ``carried``: the stepper's arrays on the old grid, by name:
        "correction" (Richardson's, an increment of the profile) and
        "previous" (BDF2's previous profile), each possibly None. Returns
        (state, carried) on the new grid. ``forced``: a solve raised
        :class:`Regrid`; the problem must change or raise a SolverError.
        """
        return None

    def outside(self, state):
        """Where a negative Richardson correction is dropped (a slice of the
        profile), or None: nowhere."""
        return None


@dataclass(frozen=True)
class Plan:
    """What to run. Distances and steps in metres.

    ``step``: the fixed step, or for "adaptive" the largest step (inf: none);
    ``end``: stop there (a run stopped by the force: the cap); ``stages``:
    increasing distances where the run lands exactly; ``force_fraction``:
    stop at the first state with F < force_fraction·F(0) (None: run to
    ``end``); ``tolerance``: the local error allowed per step (adaptive),
    relative to ``force_scale`` F0 and ``depth_scale`` d0; ``control``:
    "ladder" (steps 2^k ŝ, one factorisation per step size) or "continuous";
    ``step_key``: how a refusal names the setting that fixed the step.
    """

    scheme: str
    step: float
    end: float
    per_m: float
    stages: tuple = ()
    force_fraction: float | None = None
    tolerance: float | None = None
    force_scale: float = 1.0
    depth_scale: float = 1.0
    control: str = "ladder"
    max_steps: int | None = None
    step_key: str = "key 'sliding.step_hat'"

    def __post_init__(self):
        if self.scheme not in SCHEMES:
            raise ValueError(f"scheme {self.scheme!r}: one of {SCHEMES}")
        if self.control not in ("ladder", "continuous"):
            raise ValueError(f"control {self.control!r}: \"ladder\" or \"continuous\"")
        if self.max_steps is None:
            object.__setattr__(self, "max_steps", caps(self.scheme)[1])


@dataclass
class Outcome:
    """A run's end: the last state, where it stopped, and the stepping's counts."""

    state: object
    s: float
    force_start: float
    steps: int = 0
    rejected_steps: int = 0
    largest_step: float = 0.0      # [m]
    time_error: float = 0.0        # the largest accepted estimate
    local_error_sum: float = 0.0
    extra: dict = field(default_factory=dict)

    def time_error_info(self, plan: Plan) -> dict:
        """``info.time_error`` of meta.json (step doubling only)."""
        return dict(estimate=self.time_error, local_error_sum=self.local_error_sum,
                    rejected_steps=self.rejected_steps,
                    largest_step_hat=self.largest_step * plan.per_m,
                    tolerance=plan.tolerance, meaning=TIME_ERROR_MEANING)


def _step_factor(err: float, tolerance: float, least: float) -> float:
    """The factor on the step that brings the estimate (~h²) to ERROR_TARGET·tolerance."""
    if err <= 0.0:
        return MAX_GROWTH
    return min(MAX_GROWTH, max(least, math.sqrt(ERROR_TARGET * tolerance / err)))


def _ladder_below(h: float, per_m: float) -> float:
    """The largest ladder step 2^k (in ŝ) below h [m], in metres."""
    return 2.0 ** math.floor(math.log2(0.5 * h * per_m)) / per_m


def _rounded_step(h: float, regular: float, per_m: float, ladder: bool) -> float:
    """A step onto a stage, ``h``, as the regular step or (``ladder``) the ladder
    step 2^k ŝ that it is but for the rounding of s.

    s sums the steps in metres, so a stage at a multiple of a ladder step (the
    paper case's) is reached only to round-off; taken as the step it is, the
    solve uses that step's kept factorisation (a step off the ladder is
    solved by GMRES, preconditioned by the nearest one), and s still lands
    on the stage exactly.
    """
    steps = (regular, 2.0 ** round(math.log2(h * per_m)) / per_m) if ladder else (regular,)
    for step in steps:
        if abs(h - step) <= 1e-9 * step:
            return step
    return h


def run(problem: Problem, state, plan: Plan, observe, progress=None) -> Outcome:
    """Step ``problem`` from ``state`` (the unworn contact at s = 0) as ``plan`` says.

    ``observe(state, s, stages)`` is called with every accepted state (and
    the first), ``stages`` the number of stages it completes (0 or more).
    ``progress(fraction, text)``, if given, is called as the run advances.
    Raises SolverError at the step cap or on non-finite values, CaseError
    when the first step shows that a fixed step would pass the step cap.
    """
    scheme = plan.scheme
    adaptive, bdf2 = scheme == "adaptive", scheme == "bdf2"
    continuous = adaptive and plan.control == "continuous"
    ladder = adaptive and not continuous
    h = plan.step
    tol = plan.tolerance
    per_m = plan.per_m
    ff = plan.force_fraction
    force_start = problem.measures(state)[0]
    out = Outcome(state=state, s=0.0, force_start=force_start)
    stages = list(plan.stages)

    def reached(s):
        n = 0
        while stages and stages[0] <= s * (1 + 1e-12) + 1e-300:
            stages.pop(0)
            n += 1
        return n

    def estimate(a, b):
        """The local error estimate between two solutions of one step."""
        Fa, da, wa = problem.measures(a)
        Fb, db, wb = problem.measures(b)
        d0 = plan.depth_scale
        return max(abs(Fa - Fb) / plan.force_scale, abs(da - db) / max(d0, abs(da)),
                   abs(wa - wb) / max(d0, abs(wa)))

    if not h > 0.0:
        raise CaseError(f"{plan.step_key}: the step in metres of sliding is {h!r} in floating "
                        "point; raise the step")
    h_cur = min(FIRST_STEP_HAT / per_m, h) if adaptive else h
    ramp = []
    if bdf2:
        # a short backward-Euler step, then doubling: h/16, h/16, h/8, h/4, h/2
        # reach s = h, so the regular steps stay aligned with stages at multiples of h
        ramp = [BDF2_FIRST_STEP * h]
        while sum(ramp) < h * (1 - 1e-9) and len(ramp) < 64:
            ramp.append(sum(ramp))
    # the wear compliance factor of the regular step (bdf2 at a constant step: 2/3)
    c_regular = bdf2_coefficients(h, h)[2] if bdf2 else 1.0
    previous = None      # bdf2: (y_{n-1}, h_{n-1})
    corr = None          # adaptive: Richardson's correction for the next step's start
    s = 0.0
    last_report = -1.0
    observe(state, s, reached(s))
    while True:
        force = problem.measures(state)[0]
        if ff is not None and s > 0.0 and force < ff * force_start:
            break
        if s >= plan.end:
            break
        if out.steps >= plan.max_steps:
            raise SolverError(f"the wear run took more than {plan.max_steps} steps; raise "
                              "sliding.step_hat or sliding.tolerance")
        moved = problem.regrid(state, _carried(corr, previous), forced=False)
        if moved is not None:
            state, corr, previous = _unpack(moved, previous)
        target = min(plan.end, stages[0]) if stages else plan.end
        hstep = h_cur if adaptive else h
        # land exactly on the next stage or the end, never a sliver of a step after it
        if target - s <= hstep * (1 + 1e-9):
            hn, s_new = _rounded_step(target - s, hstep, per_m, ladder), target
        elif (adaptive or bdf2) and target - s < 2.0 * hstep:
            # two equal steps onto the stage rather than a regular step and a
            # sliver: a sliver after a long step leaves a pressure maximum on the
            # outermost node in contact (adaptive), and BDF2's step ratios stay in [1/2, 2]
            hn = _rounded_step(0.5 * (target - s), hstep, per_m, ladder)
            s_new = s + hn
        else:
            hn, s_new = hstep, s + hstep
        if bdf2:
            # the step grows by at most BDF2_MAX_RATIO per step, also after a short one
            cap = math.inf if previous is None else BDF2_MAX_RATIO * previous[1]
            if ramp:
                cap = min(cap, ramp.pop(0))
            if hn > cap:
                hn, s_new = cap, s + cap
        y = problem.profile(state)
        try:
            if scheme == "explicit":
                new = problem.explicit(state, hn, Substep("step", hn == h, s, hn, state))
            elif adaptive:
                regular = hn == h_cur
                base = y if corr is None else y + corr
                sub = Substep("full", regular, s, hn, state)
                full = problem.implicit(state, base, hn, 1.0, sub)
                # (built directly: dataclasses.replace, twice a step, was a
                # visible share of a small run; docs/performance.md)
                sub = Substep("half", regular, s, hn, state, full=full)
                half = problem.implicit(state, base, 0.5 * hn, 1.0, sub)
                sub = Substep("second", regular, s, hn, state, full=full, half=half)
                two = problem.implicit(half, problem.profile(half), 0.5 * hn, 1.0, sub)
                err = estimate(two, full)
                if err > tol and hn > 1e-12 * max(s, hn):
                    out.rejected_steps += 1
                    if continuous:
                        h_cur = min(h_cur, hn * _step_factor(err, tol, 0.2))
                    else:
                        h_cur = 0.5 * hn if regular else min(h_cur, _ladder_below(hn, per_m))
                    continue
                # keep the backward-Euler state (monotone at the edge) and carry
                # Richardson's correction into the next step's start profile
                new = two
                corr = problem.profile(two) - problem.profile(full)
                where = problem.outside(two)
                if where is not None:
                    dropped = corr[where]
                    np.maximum(dropped, 0.0, out=dropped)
                out.time_error = max(out.time_error, err)
                out.local_error_sum += err
                out.largest_step = max(out.largest_step, hn)
                if continuous:
                    grown = min(hn * _step_factor(err, tol, 0.5), h)
                    h_cur = grown if regular else min(h_cur, max(grown, hn))
                elif regular and err < GROW_BELOW * tol and 2.0 * hn <= h:
                    h_cur = 2.0 * hn
            else:
                if previous is None:
                    c, base = 1.0, y
                else:
                    a, b, c = bdf2_coefficients(hn, previous[1])
                    base = a * y + b * previous[0]
                sub = Substep("step", c * hn == c_regular * h, s, hn, state)
                new = problem.implicit(state, base, hn, c, sub)
                if bdf2:
                    previous = (y, hn)
        except Regrid:
            moved = problem.regrid(state, _carried(corr, previous), forced=True)
            if moved is None:
                raise SolverError("the discretisation could not follow the contact") from None
            state, corr, previous = _unpack(moved, previous)
            continue
        force = problem.measures(new)[0]
        if not np.isfinite(problem.profile(new)).all() or not math.isfinite(force):
            raise SolverError("the wear run produced non-finite values; reduce sliding.step_hat")
        problem.accepted(state, new, hn)
        state, s = new, s_new
        out.steps += 1
        observe(state, s, reached(s))
        if out.steps == 1 and ff is not None and math.isfinite(h):
            _check_projected_steps(plan, s, force / force_start, scheme)
        if progress is not None:
            frac = s / plan.end if ff is None else (1.0 - force / force_start) / (1.0 - ff)
            if frac - last_report >= 0.01:
                last_report = frac
                progress(min(max(frac, 0.0), 1.0), f"F/F0 = {force / force_start:.3g}")
    out.state, out.s = state, s
    return out


def _carried(corr, previous) -> dict:
    return {"correction": corr, "previous": None if previous is None else previous[0]}


def _unpack(moved, previous):
    state, carried = moved
    if previous is not None:
        previous = (carried["previous"], previous[1])
    return state, carried["correction"], previous


def _check_projected_steps(plan: Plan, s: float, force_ratio: float, scheme: str) -> None:
    """Refuse a run stopped by the force whose step would take it past the step cap.

    Its length is not known before it runs; the first step's fall of the
    force projects it: the force falls fastest at the start (wear flattens
    the contact and slows itself), so s·(1 - ff)/(1 - F/F0) underestimates
    the distance to F = ff·F0 and the projected count does not refuse a run
    that would end under the cap. A force that has not fallen at all (a step
    below the resolution of floating point) projects no end; nor does a fall within
    round-off of the force (1e-12 of F0: the BEM's force moved by one ulp, 2e-16, in
    a step of 1e-300, which projected 4e15 steps), which no step can be told by.
    """
    fallen = (1.0 - force_ratio) / (1.0 - plan.force_fraction)
    if abs(1.0 - force_ratio) < 1e-12:
        fallen = 0.0
    projected = s / fallen / plan.step if fallen > 0.0 else math.inf
    if projected > plan.max_steps:
        what = "steps of at most" if scheme == "adaptive" else "steps of"
        step = f"{plan.step * plan.per_m:.4g} in ŝ"
        remedy = "; raise the step" + ("" if scheme == "adaptive" else
                                       " or use sliding.scheme = \"adaptive\"")
        if fallen > 0.0:
            raise CaseError(
                f"{plan.step_key}: the run would take about {projected:.3g} {what} {step} "
                f"to F < {plan.force_fraction:g} F0, projected from its first step (cap "
                f"{plan.max_steps}){remedy}")
        raise CaseError(
            f"{plan.step_key}: the force did not fall in a first step of {step} (too "
            f"short to move the solution in floating point), so the run cannot reach "
            f"F < {plan.force_fraction:g} F0 within its cap of {plan.max_steps} steps{remedy}")


def info(outcome: Outcome, plan: Plan) -> dict:
    """What meta.json records of the stepping: steps, and for step doubling the
    tolerance, rejections, largest step and ``time_error``."""
    out = dict(steps=outcome.steps)
    if plan.scheme == "adaptive":
        te = outcome.time_error_info(plan)
        out.update(tolerance=plan.tolerance, rejected_steps=outcome.rejected_steps,
                   largest_step_hat=te["largest_step_hat"], time_error=te)
    return out
