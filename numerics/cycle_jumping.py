"""Error-controlled cycle jumping: a cycle-averaged rate integrated in the cycle count.

A cyclic process (fretting: one tangential cycle of a contact) changes a slowly
varying variable y (the worn profile) by F(y) per cycle, and over many cycles y
follows the ODE dy/dN = F(y) in the cycle count N. The rate is known only by
simulating a cycle, and it is stiff: in fretting a node worn too far unloads
and wears less, so grid-scale modes of the profile relax within ~100 cycles
while the profile changes over 10⁴–10⁸ cycles, and the ratio grows without
bound as the wear rate decays towards the limit. Forward-Euler jumps are
stable only while h·|λ| < 2 and were held at 115–200 cycles there.

The integrator takes steps of h cycles by ROS2 (Verwer, Spee, Blom &
Hundsdorfer, SIAM J. Sci. Comput. 20, 1999), a two-stage Rosenbrock method:

    (I − γhJ) k1 = F(y),   (I − γhJ) k2 = F(y + h k1) − 2 k1,
    y ← y + (3/2) h k1 + (1/2) h k2,          γ = 1 + 1/√2,

second order for any matrix J (a W-method: J may be an approximation) and
L-stable: a stiff mode relaxes within the step, and as F → 0 the step tends
to the limit itself. J is the problem's own (``Problem.jacobian``; in
fretting the part of ∂F/∂y that is stiff, the wear's response to the
pressure, from the normal contact alone — no cycle is simulated for it),
taken afresh at every step. Each step simulates two cycles: the stage F(y +
h k1) and the cycle from the step's end, which is kept (a row of the
history) and starts the next step.

Error control is against the run that simulates every cycle. The local error
estimate of a step is its difference to the trapezoidal rule on the rates at
its ends, (3/2)h k1 + (1/2)h k2 − (h/2)(F(y) + F(y_new)), filtered through
(I − γhJ)⁻¹ where J acts (Shampine's filter: on stiff modes the trapezoidal
rule is no reference). The estimates are carried through the scheme's own
linearised dynamics, e ← R(hJ) e + est (R the stability function: stiff
errors are damped as the contact damps them), and max|e| + max|d| is the
global error estimate, d the map drift carried alike (below). A step may take
LOCAL_SHARE of the room tol·Y − max|R e| − max|R d| (Y = max|y − y(0)|, the
change so far), so max|e| + max|d| <= tol·Y throughout; a rejected
step is retried shorter. The step grows by up to GROWTH per step, so where the
rate varies smoothly the cycles simulated grow with log N. Steps land where
a simulated cycle must end (``Plan.landings``).

What is integrated is the ODE, not the map of the cycles y ← y + F(y): the
map follows dy/dN = log(I + J)/J · F ≈ F − ½JF, so on a mode of rate λ per
cycle the two part by about λ²N/2 (at most λ/2 of the change), which the
comparison with the trapezoidal rule does not see. Each step's share of it is
counted: ½(I − γhJ)⁻¹ J Δy (Δy the step's increment; ½λΔy where hλ is small,
fading as 1/(γh) on modes the step relaxes, where both solutions have
decayed), carried like the local estimates and held with them under the
tolerance (``map_drift_estimate``). It is known only where J is: entries
outside the Jacobian count none. Integrating F − ½JF instead was tried:
right on maps whose J is exact, but fretting's J is the rate's, not the
cycle's (a simulated cycle relaxes the stiff nodes within itself), and the
correction broke the shipped case near 10⁶ cycles, capped or not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wearcheck.cases.errors import SolverError

#: ROS2's γ (L-stable)
GAMMA = 1.0 + 1.0 / math.sqrt(2.0)
#: factor on the step the error estimate proposes (the estimate grows as h³)
SAFETY = 0.8
#: largest growth and shrinking of the step from one step to the next
GROWTH = 2.0
SHRINK = 0.2
#: share of the room tol·Y − max|e| that one step's local error may take
LOCAL_SHARE = 0.5
#: what ``info["cycle_jumping"]["error_estimate"]`` means, in meta.json
ERROR_MEANING = (
    "estimated error of the integrated variable against the run that simulates every cycle, "
    "max norm over its largest change so far, the largest over the run: the steps' local "
    "error estimates (against the trapezoidal rule, filtered where stiff) carried through the "
    "scheme's linearised dynamics, plus the averaged ODE's parting from the map of the cycles "
    "(map_drift_estimate, carried alike); kept at most the tolerance. final_error_estimate: "
    "the same at the last cycle (damped where the limit attracts; in fretting it misses "
    "errors along the limit's neutral directions). local_error_sum: the local estimates' "
    "norms summed, nothing damped")


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
        ``probe``: a stage of the integrator, nothing of it is kept. Must not
        modify ``state``."""
        raise NotImplementedError

    def advance(self, state, increment: np.ndarray, cycles: int, cycle: Cycle | None):
        """The state ``cycles`` cycles after ``state`` with y changed by ``increment``;
        ``cycle``: the simulated cycle from ``state`` (its sums per cycle), None
        for a stage state (``cycles`` = 0). Must not modify ``state``."""
        raise NotImplementedError

    def variable(self, state) -> np.ndarray:
        """The integrated variable y of ``state``."""
        raise NotImplementedError

    def admissible(self, before: Cycle, after: Cycle) -> bool:
        """Whether the kept cycle ``after`` (from a step's end) may follow the kept
        cycle ``before`` (from its start): a step whose end breaks a law of the
        process is retried at half the length, whatever its error estimate."""
        return True

    def jacobian(self, cycle: Cycle) -> tuple[np.ndarray, np.ndarray] | None:
        """(index, J): an approximation of ∂F/∂y on the entries ``index`` near the
        state of ``cycle`` (zero elsewhere), a :class:`SolveJacobian`, or None
        (explicit steps, Heun's)."""
        return None


@dataclass(frozen=True)
class Plan:
    """What to run: ``cycles`` in all; ``tolerance`` on the global error relative to
    the largest change of y (0: every cycle simulated); ``landings``: cycle counts
    at which a simulated cycle must end; ``max_simulated``: the runaway guard on
    the simulated cycles (all of them: kept, stages, rejected);
    ``tolerance_key``: how messages name the tolerance."""

    cycles: int
    tolerance: float
    landings: tuple = ()
    max_simulated: int = 200_000
    tolerance_key: str = "the jump tolerance"


class Jacobian:
    """J on the entries ``index`` and the solves with I − γhJ (factorised once per h)."""

    def __init__(self, index: np.ndarray, matrix: np.ndarray):
        self.index = np.asarray(index, dtype=int)
        self.matrix = np.asarray(matrix, dtype=float)
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

    def filter(self, gh: float, x: np.ndarray) -> np.ndarray:
        """x with its entries on ``index`` replaced by (I − gh·J)⁻¹ x there."""
        x = np.array(x, dtype=float, copy=True)
        if len(self.index):
            x[self.index] = self.solve(gh, x[self.index])
        return x


class SolveJacobian:
    """J known by its solves only (a matrix-free approximation of ∂F/∂y, e.g. a
    contact's elastic response): :meth:`filter` is (I − gh·J)⁻¹ x on the whole
    variable; R(hJ) e (:func:`ros2_propagate`) is built from the same solves, as
    (I − gJ)⁻¹J = ((I − gJ)⁻¹ − I)/g. Return one from :meth:`Problem.jacobian`
    instead of (index, J)."""

    def filter(self, gh: float, x: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def propagate(self, e: np.ndarray, h: float) -> np.ndarray:
        g = GAMMA * h
        k1 = (self.filter(g, e) - e) / g
        z = e + h * k1
        k2 = (self.filter(g, z) - z) / g - 2.0 * self.filter(g, k1)
        return e + 1.5 * h * k1 + 0.5 * h * k2


def ros2(F0: np.ndarray, stage_rate, h: float, jac: Jacobian | None):
    """One ROS2 step of h cycles: the increment of y (None if not finite).

    ``stage_rate(y_increment)`` is F at y + y_increment. Entries outside the
    Jacobian take J = 0 there (Heun's rule); without one, every entry does.
    """
    def solve(x):
        return jac.filter(GAMMA * h, x) if jac is not None else np.array(x, dtype=float)

    k1 = solve(F0)
    if not np.all(np.isfinite(k1)):
        return None
    F2 = stage_rate(h * k1)
    k2 = solve(F2 - 2.0 * k1)
    increment = 1.5 * h * k1 + 0.5 * h * k2
    return increment if np.all(np.isfinite(increment)) else None


def ros2_propagate(e: np.ndarray, h: float, jac: Jacobian | None) -> np.ndarray:
    """R(hJ) e: the error e carried through a ROS2 step of the linearised problem."""
    if isinstance(jac, SolveJacobian):
        return jac.propagate(e, h)
    if jac is None or not len(jac.index):
        return e.copy()
    S = jac.index
    x = e[S]
    k1 = jac.solve(GAMMA * h, jac.matrix @ x)
    k2 = jac.solve(GAMMA * h, jac.matrix @ (x + h * k1) - 2.0 * k1)
    out = e.copy()
    out[S] = x + 1.5 * h * k1 + 0.5 * h * k2
    return out


def map_drift(increment: np.ndarray, h: float, jac) -> np.ndarray:
    """½(I − γhJ)⁻¹ J Δy: a step's share of the averaged ODE's parting from the map
    of the cycles (zero where J is not known).

    The map y ← y + F(y) follows the flow of F − ½JF + O(J²F), so over a step
    whose increment is Δy the ODE dy/dN = F gains about ½JΔy on it; filtered as
    the local estimate is, so that on modes the step relaxes (hλ ≫ 1, where
    both solutions have decayed) it fades as 1/(γh) instead of standing at λ/2.
    ``jac`` needs only ``filter``: (I − gJ)⁻¹J x = ((I − gJ)⁻¹x − x)/g.
    """
    if jac is None:
        return np.zeros_like(increment)
    g = GAMMA * h
    if isinstance(jac, Jacobian):
        out = np.zeros_like(increment)
        if len(jac.index):
            out[jac.index] = 0.5 * jac.solve(g, jac.matrix @ increment[jac.index])
        return out
    return (jac.filter(g, increment) - increment) / (2.0 * g)


@dataclass
class Outcome:
    """A run's end and its counts (``info`` for meta.json)."""

    state: object
    cycles: int = 0
    rows: int = 0                  # simulated cycles kept (observed)
    simulated: int = 0             # all simulated cycles
    second_stage_cycles: int = 0   # of them: for ROS2's second stage, F(y + h k1)
    steps: int = 0
    rejected_steps: int = 0
    inadmissible_steps: int = 0    # of them: rejected by Problem.admissible
    largest_step: int = 0          # cycles covered by a step
    error_sum: float = 0.0         # Σ max|est| of the accepted steps
    propagated_error: float = 0.0  # max|e| + max|d| at the end
    propagated_drift: float = 0.0  # max|d| at the end: the ODE's parting from the map
    largest_drift: float = 0.0     # max over the run of max|d|/Y
    largest_error: float = 0.0     # max over the run of (max|e| + max|d|)/Y (Y then)
    largest_change: float = 0.0    # Y = max|y − y(0)| at the end
    tolerance: float = 0.0

    @property
    def error_estimate(self) -> float:
        """The largest relative global error estimate of the run (held <= tolerance)."""
        return self.largest_error

    def info(self) -> dict:
        Y = self.largest_change
        return dict(error_estimate=self.error_estimate,
                    final_error_estimate=self.propagated_error / Y if Y > 0 else 0.0,
                    tolerance=self.tolerance, meaning=ERROR_MEANING,
                    local_error_sum=self.error_sum / Y if Y > 0 else 0.0,
                    map_drift_estimate=self.largest_drift,
                    final_map_drift_estimate=self.propagated_drift / Y if Y > 0 else 0.0,
                    scheme="ROS2 (L-stable Rosenbrock W-method, order 2)",
                    simulated_cycles=self.simulated, recorded_cycles=self.rows,
                    second_stage_cycles=self.second_stage_cycles, steps=self.steps,
                    rejected_steps=self.rejected_steps,
                    inadmissible_steps=self.inadmissible_steps, largest_step=self.largest_step)


def _factor(err: float, allowed: float, parting: float = 0.0) -> float:
    """The step's factor from its error estimate ``err``, which grows as h³ but for
    its part ``parting`` (the map drift), which grows as h."""
    if err <= 0.0:
        return GROWTH
    if not (allowed > 0.0 and math.isfinite(err)):
        return SHRINK
    f = SAFETY * (allowed / err) ** (1.0 / 3.0)
    if parting > 0.0:
        f = min(f, SAFETY * allowed / parting)
    return min(GROWTH, max(SHRINK, f))


def run(problem: Problem, state, plan: Plan, observe, progress=None) -> Outcome:
    """Integrate ``problem`` from ``state`` (cycle count 0) to ``plan.cycles``.

    ``observe(cycle, n)`` is called with every simulated cycle that is kept, in
    order (``n`` the cycle count at its end): the cycle from each accepted
    state. Stages and rejected steps are not kept. ``progress(fraction,
    text)`` as the run advances. Raises SolverError past ``plan.max_simulated``
    simulated cycles or on non-finite values.
    """
    tol = float(plan.tolerance)
    end = int(plan.cycles)
    landings = sorted({int(c) for c in plan.landings if 0 < c < end} | {end})
    y0 = np.array(problem.variable(state), dtype=float, copy=True)
    out = Outcome(state=state, tolerance=tol)
    error = np.zeros_like(y0)      # the global error estimate (signed, carried)
    drift = np.zeros_like(y0)      # of it: the averaged ODE's parting from the map
    h_ctrl = 2.0
    last_report = -1.0

    def simulate(st, count, probe=False):
        if out.simulated >= plan.max_simulated:
            raise SolverError(f"the cyclic run simulated more than {plan.max_simulated} cycles; "
                              f"raise {plan.tolerance_key} or lower the cycles")
        out.simulated += 1
        return problem.cycle(st, count, probe)

    def change(st):
        return float(np.max(np.abs(problem.variable(st) - y0)))

    # The progress fraction follows the cost: with jumps the cost grows with
    # the logarithm of the cycle count (docs/performance.md, "The cost in the
    # cycle count"), so the bar advances in log(1 + n); simulating every cycle
    # it grows with n.
    scale = (lambda n: math.log1p(n) / math.log1p(end)) if tol > 0.0 else (lambda n: n / end)

    def keep(cyc, count):
        nonlocal last_report
        out.rows += 1
        observe(cyc, count)
        if progress is not None and scale(count) - last_report >= 0.01:
            last_report = scale(count)
            progress(min(last_report, 1.0), f"cycle {count} of {end}")

    def attempt(origin, n_origin, cyc, h, jac):
        """The step of h cycles from ``origin``: (increment, state after it, the
        cycle from there, local error estimate), Nones where not finite."""
        def stage_rate(dy):
            out.second_stage_cycles += 1
            return simulate(problem.advance(origin, dy, 0, None), n_origin + 1, probe=True).rate

        F0 = cyc.rate
        increment = ros2(F0, stage_rate, h, jac)
        if increment is None:
            return None, None, None, None
        new = problem.advance(origin, increment, h, cyc)
        check = simulate(new, n_origin + h + 1)
        if not problem.admissible(cyc, check):
            out.inadmissible_steps += 1
            return increment, new, check, None
        est = increment - 0.5 * h * (F0 + check.rate)
        if jac is not None:
            est = jac.filter(GAMMA * h, est)
        return increment, new, check, est

    origin, n_origin = state, 0
    cyc = simulate(origin, 1)
    n = 1
    keep(cyc, n)
    while n < end:
        # cyc: the kept cycle from origin (count n_origin), ending at n = n_origin + 1
        h = 0
        Y = change(origin)
        if tol > 0.0 and Y > 0.0:
            # (from the unworn state no error is small enough: the first step is
            # taken from the first cycle's end)
            land = next(c for c in landings if c > n)
            h = min(int(h_ctrl), land - n_origin - 1)
        accepted = False
        if h >= 2:
            index_matrix = problem.jacobian(cyc)
            jac = (index_matrix if index_matrix is None or isinstance(index_matrix, SolveJacobian)
                   else Jacobian(*index_matrix))
        while h >= 2:
            carried = ros2_propagate(error, h, jac)
            carried_drift = ros2_propagate(drift, h, jac)
            allowed = LOCAL_SHARE * (tol * Y - float(np.max(np.abs(carried)))
                                     - float(np.max(np.abs(carried_drift))))
            increment, new, check, est = attempt(origin, n_origin, cyc, h, jac)
            local = float(np.max(np.abs(est))) if est is not None else math.inf
            step_drift = map_drift(increment, h, jac) if est is not None else None
            parting = float(np.max(np.abs(step_drift))) if est is not None else 0.0
            err = local + parting
            if not math.isfinite(err) or not (np.all(np.isfinite(carried))
                                              and np.all(np.isfinite(carried_drift))):
                err = math.inf
            if err <= allowed:
                accepted = True
                break
            out.rejected_steps += 1
            if est is None:
                h = h // 2
            else:
                h = min(int(h * _factor(err, allowed, parting)), h - 1)
            h_ctrl = max(2.0, h)
        if not accepted:
            # one cycle as simulated: its error is nil, the carried error unchanged
            origin, n_origin = cyc.state, n
            cyc = simulate(origin, n + 1)
            n += 1
            keep(cyc, n)
            continue
        out.steps += 1
        out.largest_step = max(out.largest_step, h)
        out.error_sum += local
        error = carried + est
        drift = carried_drift + step_drift
        f = _factor(err, allowed, parting)
        if h >= int(h_ctrl):
            h_ctrl = max(2.0, h_ctrl * f)
        else:                           # a step cut short to land does not lengthen the next
            h_ctrl = min(h_ctrl, max(2.0, h * f))
        origin, n_origin = new, n_origin + h
        cyc, n = check, n_origin + 1
        Y_new = max(change(origin), 1e-300)
        out.largest_error = max(out.largest_error, (float(np.max(np.abs(error)))
                                                    + float(np.max(np.abs(drift)))) / Y_new)
        out.largest_drift = max(out.largest_drift, float(np.max(np.abs(drift))) / Y_new)
        keep(cyc, n)
    out.state, out.cycles = cyc.state, n
    out.largest_change = change(cyc.state)
    out.propagated_drift = float(np.max(np.abs(drift)))
    out.propagated_error = float(np.max(np.abs(error))) + out.propagated_drift
    return out
