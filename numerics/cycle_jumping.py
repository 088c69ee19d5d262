"""Error-controlled cycle jumping: a cycle-averaged rate integrated in the cycle count.

A cyclic process (fretting: one tangential cycle of a contact) changes a slowly
varying variable y (the worn profile) by W(y) per cycle, and over many cycles
y follows the ODE dy/dN = W(y) in the cycle count N. The integrator simulates a
cycle (W at the current state), then jumps over h cycles by the linearly
implicit (Rosenbrock–)Euler step

    y ← y + (I − hJ)⁻¹ h W,

J ≈ ∂W/∂y estimated from simulated cycles: one-sided differences, one cycle
per entry of y whose rate is not negligible. The step is stable at any length
where the rate decays — the wear rate's stiff grid-scale modes, and its
approach to a limit where W → 0, which kept forward-Euler jumps short — and
there it tends to the limit itself (h → ∞: a Newton step on W = 0).

The next simulated cycle checks the jump. Its local error is estimated as
(I − hJ)⁻¹ (h/2)(W(y_new) − W): the difference to the trapezoidal rule,
filtered through the step's own matrix where the rate is stiff (Hairer &
Wanner, Solving ODEs II, §IV.8). The estimates are carried through the
step's linearised dynamics, e ← (I − hJ)⁻¹ e + est — how the scheme itself
propagates an error of its state: damped where the contact damps it (a node
worn too little wears faster) — and e is the global error estimate against the
run that simulates every cycle. A jump may use LOCAL_SHARE of the room
tol·Y − |carried e| (max norm; Y = max|y − y(0)| the change so far), so
|e| <= tol·Y throughout. Where the linear model holds the estimates fall and
the jump grows by GROWTH per jump: the simulated cycles grow with log N once
the rate varies smoothly.

The Jacobian is estimated when a jump is rejected and there is none, or the
one in hand was taken at fewer than JACOBIAN_AGE of the current cycles (else
the jump is shortened), and when the carried error takes half the
tolerance without one. Entries whose rate becomes negligible leave it; entries
whose rate appears (a node coming into contact) enter it by their columns, one
cycle each, and — for a problem whose Jacobian is near-symmetric
(``Problem.symmetric``) — their rows from those columns. A jump whose whole
change 2h·max|W| fits its share is forward Euler.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from wearcheck.cases.errors import SolverError

#: factor on the jump the error estimate proposes (the estimate grows as h²)
SAFETY = 0.8
#: largest growth and shrinking of the jump from one jump to the next
GROWTH = 2.0
SHRINK = 0.2
#: entries of y whose rate is below ACTIVE·max|W| are outside the Jacobian
#: (in fretting the stick zone's round-off wear, 1e-17 of the slip annulus's)
ACTIVE = 1e-6
#: the differences' probe: PROBE times the largest change of the jump it is
#: taken for, at least PROBE_FLOOR times the problem's scale of y
PROBE = 1e-3
PROBE_FLOOR = 1e-6
#: share of the room left under the tolerance (tol·Y less the error carried
#: from earlier jumps) that one jump's local error may take
LOCAL_SHARE = 0.5
GLOBAL = False
#: a rejected jump estimates a new Jacobian when the one in hand was taken at
#: fewer than this fraction of the cycles at the jump's start
JACOBIAN_AGE = 0.1
#: what ``info["cycle_jumping"]["error_estimate"]`` means, in meta.json
ERROR_MEANING = (
    "estimated error of the integrated variable against the run that simulates every cycle, "
    "max norm over its largest change: the jumps' local error estimates carried through the "
    "scheme's linearised dynamics (first order); at most the tolerance. local_error_sum: "
    "the same estimates summed without that carrying (no damping counted)")


@dataclass
class Cycle:
    """One simulated cycle: the state after it, the rate W (change of y over the
    cycle) and whatever the problem keeps of it (``record``)."""

    state: object
    rate: np.ndarray
    record: object = None


class Problem:
    """A cyclic process as the integrator sees it; states are the problem's own objects."""

    #: ∂W/∂y is near-symmetric: an entry added to the Jacobian takes its row from
    #: its column (one cycle instead of one per entry)
    symmetric = False

    def cycle(self, state, n: int, probe: bool = False) -> Cycle:
        """Simulate cycle ``n`` (the one ending at cycle count n) from ``state``;
        ``probe``: for the Jacobian, nothing of it is kept. Must not modify ``state``."""
        raise NotImplementedError

    def advance(self, state, increment: np.ndarray, cycles: int, cycle: Cycle | None):
        """The state after ``cycles`` jumped cycles that change y by ``increment``;
        ``cycle`` is the simulated cycle the jump extrapolates (None for a probe,
        ``cycles`` = 0). Must not modify ``state``."""
        raise NotImplementedError

    def variable(self, state) -> np.ndarray:
        """The integrated variable y of ``state``."""
        raise NotImplementedError

    def scale(self, state) -> float:
        """A size of y (the smallest probe of the differences is PROBE_FLOOR of it)."""
        raise NotImplementedError


@dataclass(frozen=True)
class Plan:
    """What to run: ``cycles`` in all; ``tolerance`` on the global error relative to
    the largest change of y (0: every cycle simulated); ``landings``: cycle counts
    at which a simulated cycle must end; ``max_simulated``: the runaway guard on
    the simulated cycles (all of them, the Jacobians' included);
    ``tolerance_key``: how messages name the tolerance."""

    cycles: int
    tolerance: float
    landings: tuple = ()
    max_simulated: int = 200_000
    tolerance_key: str = "the jump tolerance"


class Jacobian:
    """J ≈ ∂W/∂y on the entries ``index`` (taken at cycle count ``cycle``), and the
    solves with I − hJ of the step."""

    def __init__(self, index: np.ndarray, matrix: np.ndarray, cycle: int):
        self.index = np.asarray(index, dtype=int)
        self.matrix = matrix
        self.cycle = cycle
        self._lu = None

    def solve(self, h: float, x: np.ndarray) -> np.ndarray:
        """(I − hJ)⁻¹ x (non-finite where I − hJ is singular)."""
        from scipy.linalg import lu_factor, lu_solve

        if self._lu is None or self._lu[0] != h:
            A = np.eye(len(self.index)) - h * self.matrix
            with np.errstate(all="ignore"):
                try:
                    self._lu = (h, lu_factor(A, check_finite=False))
                except (ValueError, np.linalg.LinAlgError):
                    self._lu = (h, None)
        if self._lu[1] is None:
            return np.full_like(x, np.nan)
        with np.errstate(all="ignore"):
            return lu_solve(self._lu[1], x, check_finite=False)

    def restrict(self, keep: np.ndarray) -> None:
        """Keep the entries where ``keep`` (a mask over ``index``)."""
        self.index = self.index[keep]
        self.matrix = self.matrix[np.ix_(keep, keep)]
        self._lu = None

    def extend(self, entries: np.ndarray, columns: np.ndarray, symmetric: bool) -> None:
        """Add ``entries`` with their ``columns`` of ∂W/∂y (rows over the old index
        and the new entries); their rows from the columns if ``symmetric``, else zero."""
        n, k = len(self.index), len(entries)
        J = np.zeros((n + k, n + k))
        J[:n, :n] = self.matrix
        J[:, n:] = columns
        if symmetric:
            J[n:, :n] = columns[:n].T
        order = np.argsort(np.r_[self.index, entries], kind="stable")
        self.index = np.r_[self.index, entries][order]
        self.matrix = J[np.ix_(order, order)]
        self._lu = None


@dataclass
class Outcome:
    """A run's end and its counts (``info`` for meta.json)."""

    state: object
    cycles: int = 0
    rows: int = 0                  # simulated cycles kept (observed)
    simulated: int = 0             # all simulated cycles: rows, rejected checks, Jacobians
    jacobians: int = 0             # full estimates
    jacobian_cycles: int = 0       # cycles spent on the Jacobian (estimates and entries added)
    jumps: int = 0
    rejected_jumps: int = 0
    implicit_jumps: int = 0
    largest_jump: int = 0          # cycles covered by a jump and its checking cycle
    error_sum: float = 0.0         # Σ accepted local error estimates (absolute, max norm)
    propagated_error: float = 0.0  # the global error estimate at the end (max norm)
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
                    jacobians=self.jacobians, jacobian_cycles=self.jacobian_cycles,
                    jumps=self.jumps, implicit_jumps=self.implicit_jumps,
                    rejected_jumps=self.rejected_jumps, largest_jump=self.largest_jump)


@dataclass
class _Jump:
    start: object          # the state the jump starts from (after a simulated cycle)
    n: int                 # its cycle count
    cycle: Cycle           # the simulated cycle whose rate it extrapolates
    origin: object         # the state that cycle started from
    h: int                 # cycles jumped
    allowed: float         # the local error it may make
    carried: np.ndarray    # the global error so far, carried over the jump
    delta: np.ndarray | None = None
    jacobian: Jacobian | None = None


def run(problem: Problem, state, plan: Plan, observe, progress=None) -> Outcome:
    """Integrate ``problem`` from ``state`` (cycle count 0) to ``plan.cycles``.

    ``observe(cycle, n)`` is called with every simulated cycle that is kept,
    in order (``n`` the cycle count at its end); the cycles that check a
    rejected jump and the Jacobian's are not kept. ``progress(fraction, text)``
    as the run advances. Raises SolverError past ``plan.max_simulated``
    simulated cycles or on non-finite values.
    """
    tol = float(plan.tolerance)
    end = int(plan.cycles)
    landings = sorted({int(c) for c in plan.landings if 0 < c < end} | {end})
    y0 = np.array(problem.variable(state), dtype=float, copy=True)
    out = Outcome(state=state, tolerance=tol)
    jac: Jacobian | None = None
    error = np.zeros_like(y0)      # the global error estimate, carried (signed)
    pending: _Jump | None = None
    h_ctrl = 1.0
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

    def active(W):
        top = float(np.max(np.abs(W)))
        return np.flatnonzero(np.abs(W) > ACTIVE * top) if top > 0 else np.arange(0)

    def carry(x, h):
        """x carried over a jump of h cycles by the scheme (unchanged outside J)."""
        x = x.copy()
        if jac is not None and len(jac.index):
            x[jac.index] = jac.solve(h, x[jac.index])
        return x

    def stale(n0):
        return jac is None or jac.cycle < JACOBIAN_AGE * n0

    def columns(origin, count, cyc, entries, h, rows):
        """∂W/∂y at ``origin`` for ``entries`` (rows ``rows``), one cycle each."""
        W = cyc.rate
        eps = max(PROBE * h * float(np.max(np.abs(W))), PROBE_FLOOR * problem.scale(origin))
        C = np.empty((len(rows), len(entries)))
        for k, i in enumerate(entries):
            d = np.zeros_like(W)
            d[i] = eps
            Wi = simulate(problem.advance(origin, d, 0, None), count, probe=True).rate
            C[:, k] = (Wi[rows] - W[rows]) / eps
        out.jacobian_cycles += len(entries)
        if not np.all(np.isfinite(C)):
            raise SolverError("the cycle jumps' Jacobian has non-finite entries")
        return C

    def estimate_jacobian(origin, count, cyc, h):
        """A new Jacobian at ``origin``, the state ``cyc`` (cycle ``count``) started from."""
        nonlocal jac
        S = active(cyc.rate)
        jac = Jacobian(S, columns(origin, count, cyc, S, h, S), count - 1)
        out.jacobians += 1

    def follow(origin, count, cyc, h):
        """Let the Jacobian's entries follow the active ones of ``cyc``."""
        S = active(cyc.rate)
        keep = np.isin(jac.index, S)
        if not keep.all():
            jac.restrict(keep)
        new = np.setdiff1d(S, jac.index)
        if len(new):
            rows = np.r_[jac.index, new]
            jac.extend(new, columns(origin, count, cyc, new, h, rows), problem.symmetric)

    def jump(start, n0, cyc, origin, h):
        """The jump of h cycles from ``start`` (its increment None if not finite)."""
        W = cyc.rate
        carried = carry(error, h)
        room = tol * change(start) - (float(np.max(np.abs(carried))) if GLOBAL else 0.0)
        j = _Jump(start=start, n=n0, cycle=cyc, origin=origin, h=h,
                  allowed=LOCAL_SHARE * room, carried=carried)
        delta = h * W
        if jac is not None and 2.0 * h * float(np.max(np.abs(W))) > j.allowed:
            # the whole change would not fit: the linearly implicit step
            S = jac.index
            delta[S] = jac.solve(h, h * W[S])
            j.jacobian = jac
        ok = np.all(np.isfinite(delta)) and np.all(np.isfinite(carried))
        j.delta = delta if ok else None
        return j

    def estimate(j: _Jump, W1):
        """The local error estimate (vector) of jump j from the rate W1 after it: the
        step less the trapezoidal rule's, filtered by the step's matrix."""
        est = j.delta - 0.5 * j.h * (j.cycle.rate + W1)
        if j.jacobian is not None:
            S = j.jacobian.index
            est[S] = j.jacobian.solve(j.h, est[S])
        return est

    def take(start, n0, cyc, origin, h):
        """Jump h cycles (fewer where the step is not finite) from ``start``: the
        pending jump, the state and the count after it."""
        while h >= 1:
            j = jump(start, n0, cyc, origin, h)
            if j.delta is not None:
                return j, problem.advance(start, j.delta, h, cyc), n0 + h
            out.rejected_jumps += 1
            h = int(SHRINK * h)
        return None, start, n0

    def factor(err, allowed):
        if err <= 0.0:
            return GROWTH
        if not (allowed > 0.0 and math.isfinite(err)):
            return SHRINK
        return min(GROWTH, max(SHRINK, SAFETY * math.sqrt(allowed / err)))

    while n < end:
        origin = state
        cyc = simulate(state, n + 1)
        if pending is not None:
            j = pending
            est = estimate(j, cyc.rate)
            err = float(np.max(np.abs(est)))
            if not err <= j.allowed:
                out.rejected_jumps += 1
                if stale(j.n):
                    estimate_jacobian(j.origin, j.n, j.cycle, j.h)
                    h = j.h
                else:
                    h = min(int(j.h * factor(err, j.allowed)), j.h - 1)
                h_ctrl = max(1.0, h)
                pending, state, n = take(j.start, j.n, j.cycle, j.origin, h)
                continue
            out.jumps += 1
            out.largest_jump = max(out.largest_jump, j.h + 1)
            out.implicit_jumps += j.jacobian is not None
            out.error_sum += err
            error = j.carried + est
            if j.h >= int(h_ctrl):
                h_ctrl *= factor(err, j.allowed)
            else:                       # a jump cut short to land does not lengthen the next
                h_ctrl = min(h_ctrl, max(1.0, j.h * factor(err, j.allowed)))
        pending = None
        state, n = cyc.state, n + 1
        out.rows += 1
        observe(cyc, n)
        if progress is not None and n / end - last_report >= 0.01:
            last_report = n / end
            progress(min(n / end, 1.0), f"cycle {n}")
        if tol <= 0.0 or n >= end:
            continue
        land = next(c for c in landings if c > n)
        h = min(int(h_ctrl), land - n - 1)
        if h < 1:
            continue
        if jac is not None:
            follow(origin, n, cyc, h)
        if stale(n) and float(np.max(np.abs(carry(error, h)))) > 0.5 * tol * change(state):
            # the error so far takes half the tolerance: a Jacobian, to carry it
            # through the dynamics that damp it
            estimate_jacobian(origin, n, cyc, h)
        pending, state, n = take(state, n, cyc, origin, h)
    out.state, out.cycles = state, n
    out.largest_change = change(state)
    out.propagated_error = float(np.max(np.abs(error)))
    return out
