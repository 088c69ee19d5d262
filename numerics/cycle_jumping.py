"""Error-controlled cycle jumping: a cycle-averaged rate integrated in the cycle count.

A cyclic process (fretting: one tangential cycle of a contact) changes a slowly
varying variable y (the worn profile) by F(y) per cycle, and over many cycles y
follows the ODE dy/dN = F(y) in the cycle count N. The rate is known only by
simulating a cycle, and it is stiff: in fretting its Jacobian J = ∂F/∂y has
eigenvalues down to −1e-2 per cycle (a node worn too far unloads and wears
less: grid-scale modes relax within ~100 cycles, and so does a node coming
into contact) while the profile changes over 10⁴–10⁶ cycles. Forward-Euler
jumps are stable only while h·|λ| < 2 and kept the old jumps short.

The integrator takes steps of h cycles by ROS2 (Verwer, Spee, Blom &
Hundsdorfer, SIAM J. Sci. Comput. 20, 1999), a two-stage Rosenbrock method:

    (I − γhJ) k1 = F(y),   (I − γhJ) k2 = F(y + h k1) − 2 k1,
    y ← y + (3/2) h k1 + (1/2) h k2,          γ = 1 + 1/√2,

second order for any matrix J (a W-method: J may be an estimate, and old) and
L-stable: a stiff mode relaxes within the step, and as F → 0 the step tends
to the limit itself. Each step simulates two cycles, F(y) (kept) and the
stage. J is estimated from simulated cycles by one-sided differences, one
cycle per entry of y whose rate is not negligible; entries whose rate appears
(a node coming into contact) enter by their columns, one cycle each, and —
for a problem whose Jacobian is near-symmetric (``Problem.symmetric``) —
their rows from those columns; entries whose rate vanishes leave. A new
estimate is taken when a step is rejected and J is older than JACOBIAN_AGE of
the cycles so far. Until the first rejection the steps are explicit (Heun's).

Error control is against the run that simulates every cycle. The local error
estimate of a step is the difference to its embedded first-order solution,
(h/2)(k1 + k2); the estimates are carried through the scheme's own
linearised dynamics, e ← R(hJ) e + est (R the stability function: stiff
errors are damped as the contact damps them, a node worn too little wears
faster), and e is the global error estimate. A step may take LOCAL_SHARE of
the room tol·Y − max|e| (Y = max|y − y(0)|, the change so far), so max|e|
<= tol·Y throughout; a rejected step is retried shorter. The step grows by up
to GROWTH per step, so where the rate varies smoothly the cycles simulated
grow with log N. Steps land where a simulated cycle must end, and where the
problem's events (``Problem.events``: quantities crossing zero at a kink of F)
extrapolate to a crossing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wearcheck.cases.errors import SolverError

#: ROS2's γ (L-stable)
GAMMA = 1.0 + 1.0 / math.sqrt(2.0)
#: factor on the step the error estimate proposes (the estimate grows as h²)
SAFETY = 0.8
#: largest growth and shrinking of the step from one step to the next
GROWTH = 2.0
SHRINK = 0.2
#: share of the room tol·Y − max|e| that one step's local error may take
LOCAL_SHARE = 0.5
#: entries of y whose rate is below ACTIVE·max|F| are outside the Jacobian
#: (in fretting the stick zone's round-off wear, 1e-17 of the slip annulus's)
ACTIVE = 1e-6
#: the differences' probe: PROBE times the problem's scale of y, lowering y
#: (in fretting: pressing a node into contact rather than out of it)
PROBE = -1e-6
#: an entry whose rate changed by more than this fraction since its column of
#: the Jacobian was taken gets a new one (one cycle)
COLUMN_CHANGE = 0.5
#: a rejected step estimates a new Jacobian when the one in hand was taken
#: at fewer than this fraction of the cycles at the step's start
JACOBIAN_AGE = 0.5
#: what ``info["cycle_jumping"]["error_estimate"]`` means, in meta.json
ERROR_MEANING = (
    "estimated error of the integrated variable against the run that simulates every cycle, "
    "max norm over its largest change: the steps' local error estimates (their embedded "
    "first-order solutions') carried through the scheme's linearised dynamics; kept at most "
    "the tolerance. local_error_sum: the estimates' norms summed, nothing damped")


@dataclass
class Cycle:
    """One simulated cycle: the state after it, the rate F (change of y over the
    cycle) and whatever the problem keeps of it (``record``)."""

    state: object
    rate: np.ndarray
    record: object = None


class Problem:
    """A cyclic process as the integrator sees it; states are the problem's own objects."""

    def cycle(self, state, n: int, probe: bool = False) -> Cycle:
        """Simulate cycle ``n`` (the one ending at cycle count n) from ``state``;
        ``probe``: a stage or a difference of the integrator, nothing of it is
        kept. Must not modify ``state``."""
        raise NotImplementedError

    def advance(self, state, increment: np.ndarray, cycles: int, cycle: Cycle | None):
        """The state ``cycles`` cycles after ``state`` with y changed by ``increment``;
        ``cycle``: the simulated cycle from ``state`` (its sums per cycle), None
        for a stage or probe state (``cycles`` = 0). Must not modify ``state``."""
        raise NotImplementedError

    def variable(self, state) -> np.ndarray:
        """The integrated variable y of ``state``."""
        raise NotImplementedError

    def scale(self, state) -> float:
        """A size of y: the differences perturb y by PROBE of it."""
        raise NotImplementedError

    def events(self, cycle: Cycle) -> dict:
        """Quantities that cross zero where the rate has a kink (a node coming into
        contact, say), by a key that names the event, after a kept cycle; a step
        lands where the last two kept cycles put the nearest crossing."""
        return {}


@dataclass(frozen=True)
class Plan:
    """What to run: ``cycles`` in all; ``tolerance`` on the global error relative to
    the largest change of y (0: every cycle simulated); ``landings``: cycle counts
    at which a simulated cycle must end; ``max_simulated``: the runaway guard on
    the simulated cycles (all of them: kept, stages, differences, rejected);
    ``tolerance_key``: how messages name the tolerance."""

    cycles: int
    tolerance: float
    landings: tuple = ()
    max_simulated: int = 200_000
    tolerance_key: str = "the jump tolerance"


class Jacobian:
    """J ≈ ∂F/∂y on the entries ``index`` (estimated at cycle count ``cycle``) and
    the solves with I − γhJ."""

    def __init__(self, index: np.ndarray, matrix: np.ndarray, cycle: int, rates: np.ndarray):
        self.index = np.asarray(index, dtype=int)
        self.matrix = matrix
        self.cycle = cycle
        self.rates = np.asarray(rates, dtype=float)   # F at the entries when their columns were taken
        self._lu = None

    def solve(self, gh: float, x: np.ndarray) -> np.ndarray:
        """(I − gh·J)⁻¹ x (non-finite where the matrix is singular)."""
        from scipy.linalg import lu_factor, lu_solve

        if self._lu is None or self._lu[0] != gh:
            A = np.eye(len(self.index)) - gh * self.matrix
            with np.errstate(all="ignore"):
                try:
                    self._lu = (gh, lu_factor(A, check_finite=False))
                except (ValueError, np.linalg.LinAlgError):
                    self._lu = (gh, None)
        if self._lu[1] is None:
            return np.full_like(x, np.nan)
        with np.errstate(all="ignore"):
            return lu_solve(self._lu[1], x, check_finite=False)

    def restrict(self, keep: np.ndarray) -> None:
        """Keep the entries where ``keep`` (a mask over ``index``)."""
        self.index = self.index[keep]
        self.matrix = self.matrix[np.ix_(keep, keep)]
        self.rates = self.rates[keep]
        self._lu = None

    def replace(self, at: np.ndarray, columns: np.ndarray, rates: np.ndarray) -> None:
        """New ``columns`` for the entries at positions ``at`` of ``index``."""
        self.matrix[:, at] = columns
        self.rates[at] = rates
        self._lu = None

    def extend(self, entries: np.ndarray, columns: np.ndarray, rates: np.ndarray) -> None:
        """Add ``entries`` with their ``columns`` of ∂F/∂y (rows over the old index,
        then the new entries); their rows are zero but for the new block (the
        way the others' change drives theirs is left to the step, which is
        second order for any J, and no spurious growth enters J)."""
        n, k = len(self.index), len(entries)
        J = np.zeros((n + k, n + k))
        J[:n, :n] = self.matrix
        J[:, n:] = columns
        order = np.argsort(np.r_[self.index, entries], kind="stable")
        self.index = np.r_[self.index, entries][order]
        self.matrix = J[np.ix_(order, order)]
        self.rates = np.r_[self.rates, rates][order]
        self._lu = None


def ros2(F0: np.ndarray, stage_rate, h: float, jac: Jacobian | None):
    """One ROS2 step of h: (increment, local error estimate), both vectors over y.

    ``stage_rate(y_increment)`` is F at y + y_increment. Entries outside the
    Jacobian take J = 0 there (Heun's rule); without one, every entry does.
    """
    def solve(x):
        x = x.copy()
        if jac is not None and len(jac.index):
            x[jac.index] = jac.solve(GAMMA * h, x[jac.index])
        return x

    k1 = solve(F0)
    if not np.all(np.isfinite(k1)):
        return None, None
    F2 = stage_rate(h * k1)
    k2 = solve(F2 - 2.0 * k1)
    return 1.5 * h * k1 + 0.5 * h * k2, 0.5 * h * (k1 + k2)


def ros2_propagate(e: np.ndarray, h: float, jac: Jacobian | None) -> np.ndarray:
    """R(hJ) e: the error e carried through a ROS2 step of the linearised problem."""
    if jac is None or not len(jac.index):
        return e.copy()
    S = jac.index
    x = e[S]
    k1 = jac.solve(GAMMA * h, jac.matrix @ x)
    k2 = jac.solve(GAMMA * h, jac.matrix @ (x + h * k1) - 2.0 * k1)
    out = e.copy()
    out[S] = x + 1.5 * h * k1 + 0.5 * h * k2
    return out


@dataclass
class Outcome:
    """A run's end and its counts (``info`` for meta.json)."""

    state: object
    cycles: int = 0
    rows: int = 0                  # simulated cycles kept (observed)
    simulated: int = 0             # all simulated cycles
    stage_cycles: int = 0          # of them: ROS2 stages
    jacobian_cycles: int = 0       # of them: differences for the Jacobian
    jacobians: int = 0             # full estimates
    steps: int = 0
    implicit_steps: int = 0
    rejected_steps: int = 0
    largest_step: int = 0          # cycles covered by a step
    event_landings: int = 0        # steps shortened to land at a kink
    error_sum: float = 0.0         # Σ max|est| of the accepted steps
    propagated_error: float = 0.0  # max|e| at the end
    largest_change: float = 0.0    # Y = max|y − y(0)| at the end
    tolerance: float = 0.0

    @property
    def error_estimate(self) -> float:
        Y = self.largest_change
        return self.propagated_error / Y if Y > 0 else 0.0

    def info(self) -> dict:
        Y = self.largest_change
        return dict(error_estimate=self.error_estimate, tolerance=self.tolerance,
                    meaning=ERROR_MEANING, local_error_sum=self.error_sum / Y if Y > 0 else 0.0,
                    simulated_cycles=self.simulated, recorded_cycles=self.rows,
                    stage_cycles=self.stage_cycles, jacobian_cycles=self.jacobian_cycles,
                    jacobians=self.jacobians, steps=self.steps,
                    implicit_steps=self.implicit_steps, rejected_steps=self.rejected_steps,
                    largest_step=self.largest_step, event_landings=self.event_landings)


@dataclass
class _Step:
    origin: object         # the state the step starts from
    n: int                 # its cycle count
    cycle: Cycle           # the simulated cycle from origin (its rate is F(y))
    h: int                 # cycles the step covers
    allowed: float         # the local error it may make
    carried: np.ndarray    # the global error so far, carried over the step
    increment: np.ndarray | None = None
    estimate: np.ndarray | None = None
    jacobian: Jacobian | None = None


def run(problem: Problem, state, plan: Plan, observe, progress=None) -> Outcome:
    """Integrate ``problem`` from ``state`` (cycle count 0) to ``plan.cycles``.

    ``observe(cycle, n)`` is called with every simulated cycle that is kept, in
    order (``n`` the cycle count at its end): the cycle from each accepted
    state. Stages, differences and rejected steps are not kept.
    ``progress(fraction, text)`` as the run advances. Raises SolverError past
    ``plan.max_simulated`` simulated cycles or on non-finite values.
    """
    tol = float(plan.tolerance)
    end = int(plan.cycles)
    landings = sorted({int(c) for c in plan.landings if 0 < c < end} | {end})
    y0 = np.array(problem.variable(state), dtype=float, copy=True)
    out = Outcome(state=state, tolerance=tol)
    error = np.zeros_like(y0)      # the global error estimate (signed, carried)
    jac: Jacobian | None = None
    pending: _Step | None = None
    seen = None                    # (count, events) of the last kept cycle
    h_ctrl = 2.0
    n = 0
    last_report = -1.0

    def simulate(st, count, probe=False):
        if out.simulated >= plan.max_simulated:
            raise SolverError(f"the cyclic run simulated more than {plan.max_simulated} cycles; "
                              f"raise {plan.tolerance_key} or lower the cycles")
        out.simulated += 1
        return problem.cycle(st, count, probe)

    def change(st):
        return float(np.max(np.abs(problem.variable(st) - y0)))

    def active(F):
        top = float(np.max(np.abs(F)))
        return np.flatnonzero(np.abs(F) > ACTIVE * top) if top > 0 else np.arange(0)

    def columns(origin, count, cyc, entries, rows):
        """∂F/∂y at ``origin`` for ``entries`` (over ``rows``), one cycle each."""
        F = cyc.rate
        eps = PROBE * problem.scale(origin)
        C = np.empty((len(rows), len(entries)))
        for k, i in enumerate(entries):
            d = np.zeros_like(F)
            d[i] = eps
            Fi = simulate(problem.advance(origin, d, 0, None), count, probe=True).rate
            C[:, k] = (Fi[rows] - F[rows]) / eps
        out.jacobian_cycles += len(entries)
        if not np.all(np.isfinite(C)):
            raise SolverError("the cycle jumps' Jacobian has non-finite entries")
        return C

    def estimate_jacobian(origin, count, cyc):
        nonlocal jac
        S = active(cyc.rate)
        jac = Jacobian(S, columns(origin, count, cyc, S, S), count - 1, cyc.rate[S])
        out.jacobians += 1

    def follow(origin, count, cyc):
        """Let the Jacobian's entries follow the active ones of ``cyc``: those whose
        rate vanished leave, new ones enter by their columns, and an entry whose
        rate changed by more than COLUMN_CHANGE since its column was taken (a
        node that came into contact since) gets its column anew."""
        F = cyc.rate
        S = active(F)
        keep = np.isin(jac.index, S)
        if not keep.all():
            jac.restrict(keep)
        old = np.flatnonzero(np.abs(F[jac.index] - jac.rates) > COLUMN_CHANGE * np.abs(jac.rates))
        if len(old):
            jac.replace(old, columns(origin, count, cyc, jac.index[old], jac.index),
                        F[jac.index[old]])
        new = np.setdiff1d(S, jac.index)
        if len(new):
            rows = np.r_[jac.index, new]
            jac.extend(new, columns(origin, count, cyc, new, rows), F[new])

    def step(origin, count, cyc, h):
        """The step of h cycles from ``origin``: the pending step and the state
        after it (None if the step is not finite)."""
        carried = ros2_propagate(error, h, jac)
        room = tol * change(origin) - float(np.max(np.abs(carried)))
        st = _Step(origin=origin, n=count, cycle=cyc, h=h, allowed=LOCAL_SHARE * room,
                   carried=carried, jacobian=jac)

        def stage_rate(dy):
            out.stage_cycles += 1
            return simulate(problem.advance(origin, dy, 0, None), count + 1, probe=True).rate

        st.increment, _ = ros2(cyc.rate, stage_rate, h, jac)
        if (st.increment is None or not np.all(np.isfinite(st.increment))
                or not np.all(np.isfinite(carried))):
            return st, None
        return st, problem.advance(origin, st.increment, h, cyc)

    def estimate(st, F1):
        """The local error estimate of step st from the rate F1 at its end: the
        step less the trapezoidal rule's, filtered through I − γhJ where stiff."""
        est = st.increment - 0.5 * st.h * (st.cycle.rate + F1)
        if st.jacobian is not None and len(st.jacobian.index):
            S = st.jacobian.index
            est[S] = st.jacobian.solve(GAMMA * st.h, est[S])
        return est

    def factor(err, allowed):
        if err <= 0.0:
            return GROWTH
        if not (allowed > 0.0 and math.isfinite(err)):
            return SHRINK
        return min(GROWTH, max(SHRINK, SAFETY * (allowed / err) ** (1.0 / 3.0)))

    def keep(cyc, count):
        nonlocal last_report
        out.rows += 1
        observe(cyc, count)
        if progress is not None and count / end - last_report >= 0.01:
            last_report = count / end
            progress(min(count / end, 1.0), f"cycle {count}")

    origin, n_origin = state, 0
    cyc = simulate(origin, 1)
    n = 1
    keep(cyc, n)
    while n < end:
        # cyc: the kept cycle from origin (count n_origin), ending at n = n_origin + 1
        h = 0
        if tol > 0.0 and change(origin) > 0.0:
            # (from the unworn state no error is small enough: the first step is
            # taken from the first cycle's)
            land = next(c for c in landings if c > n)
            h = min(int(h_ctrl), land - n_origin - 1)
            events = problem.events(cyc)
            if seen is not None:
                crossing = _next_crossing(seen, (n, events))
                if crossing is not None and crossing - n_origin < h:
                    # the kink at the step's end: the next step starts past it
                    h = max(2, int(math.floor(crossing)) - n_origin)
                    out.event_landings += 1
            seen = (n, events)
        if h >= 2 and jac is not None:
            follow(origin, n, cyc)
        accepted = False
        while h >= 2:
            st, new = step(origin, n_origin, cyc, h)
            check = simulate(new, n_origin + h + 1) if new is not None else None
            est = estimate(st, check.rate) if check is not None else None
            err = float(np.max(np.abs(est))) if est is not None else math.inf
            if err <= st.allowed:
                accepted = True
                break
            out.rejected_steps += 1
            if jac is None or jac.cycle < JACOBIAN_AGE * n_origin:
                estimate_jacobian(origin, n, cyc)
                continue
            h = min(int(h * factor(err, st.allowed)), h - 1)
            h_ctrl = max(2.0, h)
        if not accepted:
            origin, n_origin = cyc.state, n
            cyc = simulate(origin, n + 1)
            n += 1
            keep(cyc, n)
            continue
        out.steps += 1
        out.implicit_steps += st.jacobian is not None
        out.largest_step = max(out.largest_step, st.h)
        out.error_sum += err
        error = st.carried + est
        if st.h >= int(h_ctrl):
            h_ctrl = max(2.0, h_ctrl * factor(err, st.allowed))
        else:                           # a step cut short to land does not lengthen the next
            h_ctrl = min(h_ctrl, max(2.0, st.h * factor(err, st.allowed)))
        origin, n_origin = new, n_origin + st.h
        cyc, n = check, n_origin + 1
        keep(cyc, n)
    out.state, out.cycles = cyc.state, n
    out.largest_change = change(cyc.state)
    out.propagated_error = float(np.max(np.abs(error)))
    return out


def _next_crossing(before, after) -> float | None:
    """The earliest cycle count at which an event present in both (count, events)
    crosses zero, extrapolated linearly; None if none approaches zero."""
    (n0, e0), (n1, e1) = before, after
    best = None
    for key, v1 in e1.items():
        v0 = e0.get(key)
        if v0 is None or n1 <= n0 or v1 == 0.0 or abs(v1) >= abs(v0) or v0 * v1 < 0:
            continue
        at = n1 + v1 * (n1 - n0) / (v0 - v1)
        best = at if best is None else min(best, at)
    return best
