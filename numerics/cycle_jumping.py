"""Error-controlled cycle jumping: a cycle-averaged rate integrated in the cycle count.

A cyclic process (fretting: one tangential cycle of a contact) changes a slowly
varying variable y (the worn profile) by F(y) per cycle, and over many cycles y
follows the ODE dy/dN = F(y) in the cycle count N. The rate is known only by
simulating a cycle. It is stiff: its Jacobian has a spectral radius ρ of
1e-2 per cycle in fretting (a worn node unloads and wears less, a grid-scale
mode damped within ~100 cycles) against the slow change of the profile over
10⁴–10⁶ cycles, so forward-Euler jumps are stable only while hρ < 2.

The integrator takes steps of h cycles by the explicit Runge–Kutta–Chebyshev
method RKC2 (van der Houwen & Sommeijer 1980; Sommeijer, Shampine & Verwer,
J. Comput. Appl. Math. 88, 1998): s stages, each a simulated cycle from an
intermediate profile, stable for hρ <= 0.65 s², second order, damping every
mode whose eigenvalue is on the negative real axis — fretting's Jacobian is
symmetric to 0.5 %, so its spectrum is. The cost of a step grows as √(hρ)
and needs no Jacobian, only ρ, which a few cycles of nonlinear power
iteration estimate. Where the rate decays towards a limit, the whole change
2h·max|F| of a step eventually fits the error allowed, and a forward-Euler
step does (stable or not: its increment is that small).

A step from y_n over h cycles is checked by the next simulated cycle, the rate
F_{n+1} at its end (which starts the next step): the local error estimate is
(12(y_n − y_{n+1}) + 6h(F_n + F_{n+1}))/15, the RKC code's, for forward
Euler (h/2)(F_{n+1} − F_n). The estimates are summed as vectors, e (signed, no
damping counted), the first-order estimate of the global error against the
run that simulates every cycle. A step may take LOCAL_SHARE of the room
tol·Y − max|e| (Y = max|y − y(0)|, the change so far), so max|e| <= tol·Y
throughout; a rejected step is retried shorter. The steps grow by up to
GROWTH per step, so where the rate varies smoothly the cycles simulated grow
with log N.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wearcheck.cases.errors import SolverError

#: factor on the step the error estimate proposes (the estimate grows as h³)
SAFETY = 0.8
#: largest growth and shrinking of the step from one step to the next
GROWTH = 2.0
SHRINK = 0.2
#: share of the room tol·Y − max|e| that one step's local error may take
LOCAL_SHARE = 0.5
#: RKC's damping ε (stability interval 0.653 s² for ε = 2/13, the RKC code's)
DAMPING = 2.0 / 13.0
#: safety factor on the estimated spectral radius (nonlinear power iteration
#: approaches it from below: 4-7 % low after 8 iterations on fretting's Jacobians)
RADIUS_SAFETY = 1.2
#: power iterations: from an alternating start, and warm from the last estimate
POWER_COLD = 8
POWER_WARM = 3
#: the power iteration's probe: the largest entry of its perturbation, as a
#: fraction of the problem's scale of y
PROBE = 1e-6
#: most stages of one step (the step is shortened to keep within)
MAX_STAGES = 200
#: what ``info["cycle_jumping"]["error_estimate"]`` means, in meta.json
ERROR_MEANING = (
    "estimated error of the integrated variable against the run that simulates every cycle, "
    "max norm over its largest change: the steps' local error estimates summed as vectors "
    "(first order, no damping counted); kept at most the tolerance. local_error_sum: their "
    "norms summed")


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
        ``probe``: a stage or a probe of the integrator, nothing of it is kept.
        Must not modify ``state``."""
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
        """A size of y: the power iteration perturbs y by PROBE of it."""
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
    the simulated cycles (all of them: kept, stages, probes, rejected);
    ``tolerance_key``: how messages name the tolerance."""

    cycles: int
    tolerance: float
    landings: tuple = ()
    max_simulated: int = 200_000
    tolerance_key: str = "the jump tolerance"


def rkc_coefficients(s: int) -> dict:
    """RKC2's coefficients for s >= 2 stages (damping DAMPING).

    Returns arrays over j = 0..s: mu, nu, mu_tilde, gamma_tilde (entries j >= 2;
    mu_tilde[1] too) and ``beta``, the stability interval [−beta, 0] of hλ.
    Stage recursion: Y1 = Y0 + mu_tilde[1] h F0; Y_j = (1 − mu_j − nu_j) Y0 +
    mu_j Y_{j−1} + nu_j Y_{j−2} + mu_tilde_j h F(Y_{j−1}) + gamma_tilde_j h F0.
    """
    if s < 2:
        raise ValueError(f"RKC needs s >= 2 stages, got {s}")
    w0 = 1.0 + DAMPING / s**2
    t = w0 * w0 - 1.0
    arg = s * math.log(w0 + math.sqrt(t))
    w1 = math.sinh(arg) * t / (math.cosh(arg) * s * math.sqrt(t) - w0 * math.sinh(arg))
    T = np.zeros(s + 1)
    dT = np.zeros(s + 1)
    ddT = np.zeros(s + 1)
    T[0], T[1], dT[1] = 1.0, w0, 1.0
    for j in range(2, s + 1):
        T[j] = 2 * w0 * T[j - 1] - T[j - 2]
        dT[j] = 2 * T[j - 1] + 2 * w0 * dT[j - 1] - dT[j - 2]
        ddT[j] = 4 * dT[j - 1] + 2 * w0 * ddT[j - 1] - ddT[j - 2]
    b = np.zeros(s + 1)
    b[2:] = ddT[2:] / dT[2:] ** 2
    b[0] = b[1] = b[2]
    a = 1.0 - b * T
    mu = np.zeros(s + 1)
    nu = np.zeros(s + 1)
    mt = np.zeros(s + 1)
    gt = np.zeros(s + 1)
    mt[1] = b[1] * w1
    for j in range(2, s + 1):
        mu[j] = 2 * b[j] * w0 / b[j - 1]
        nu[j] = -b[j] / b[j - 2]
        mt[j] = 2 * b[j] * w1 / b[j - 1]
        gt[j] = -a[j - 1] * mt[j]
    beta = (w0 + 1.0) / w1          # where the stability polynomial leaves [−1, 1]
    return dict(mu=mu, nu=nu, mu_tilde=mt, gamma_tilde=gt, beta=beta)


def stages_for(h_rho: float) -> int:
    """The fewest RKC2 stages (>= 2) stable for h·ρ."""
    s = max(2, int(math.ceil(math.sqrt(max(h_rho, 0.0) / 0.653))))
    while rkc_coefficients(s)["beta"] < h_rho:
        s += 1
    return s


@dataclass
class Outcome:
    """A run's end and its counts (``info`` for meta.json)."""

    state: object
    cycles: int = 0
    rows: int = 0                  # simulated cycles kept (observed)
    simulated: int = 0             # all simulated cycles
    stage_cycles: int = 0          # of them: RKC stages
    radius_cycles: int = 0         # of them: power iterations for ρ
    steps: int = 0
    rkc_steps: int = 0
    rejected_steps: int = 0
    largest_step: int = 0          # cycles covered by a step
    most_stages: int = 0
    event_landings: int = 0        # steps cut to land at a kink
    spectral_radius: float = 0.0   # the last estimate [1/cycle]
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
                    stage_cycles=self.stage_cycles, radius_cycles=self.radius_cycles,
                    steps=self.steps, rkc_steps=self.rkc_steps,
                    rejected_steps=self.rejected_steps, largest_step=self.largest_step,
                    most_stages=self.most_stages, event_landings=self.event_landings,
                    spectral_radius=self.spectral_radius)


@dataclass
class _Step:
    origin: object         # the state the step starts from
    n: int                 # its cycle count
    rate: np.ndarray       # F at origin (the simulated cycle from it)
    cycle: Cycle           # that cycle
    h: int                 # cycles the step covers
    allowed: float         # the local error it may make
    stages: int = 1        # 1: forward Euler
    increment: np.ndarray | None = None


def run(problem: Problem, state, plan: Plan, observe, progress=None) -> Outcome:
    """Integrate ``problem`` from ``state`` (cycle count 0) to ``plan.cycles``.

    ``observe(cycle, n)`` is called with every simulated cycle that is kept, in
    order (``n`` the cycle count at its end): the cycle from each accepted
    state. Stages, probes and the cycles of rejected steps are not kept.
    ``progress(fraction, text)`` as the run advances. Raises SolverError past
    ``plan.max_simulated`` simulated cycles or on non-finite values.
    """
    tol = float(plan.tolerance)
    end = int(plan.cycles)
    landings = sorted({int(c) for c in plan.landings if 0 < c < end} | {end})
    y0 = np.array(problem.variable(state), dtype=float, copy=True)
    out = Outcome(state=state, tolerance=tol)
    error = np.zeros_like(y0)      # Σ local error estimates (signed)
    radius = None                  # (ρ, its vector, the count it was estimated at)
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

    def rate_at(origin, count, y_origin, y):
        """F at the profile y (a stage state built from ``origin``)."""
        return simulate(problem.advance(origin, y - y_origin, 0, None), count, probe=True).rate

    def estimate_radius(origin, count, F):
        """ρ by nonlinear power iteration on (F(y + εv) − F(y))/ε at ``origin``."""
        nonlocal radius
        y = problem.variable(origin)
        active = np.abs(F) > 1e-6 * float(np.max(np.abs(F)))
        v = radius[1] * active if radius is not None else np.zeros_like(F)
        iterations = POWER_WARM
        if not np.any(v):
            v = np.where(np.arange(len(F)) % 2 == 0, 1.0, -1.0) * active
            iterations = POWER_COLD
        rho = 0.0
        scale = PROBE * problem.scale(origin)
        for _ in range(iterations):
            top = float(np.max(np.abs(v)))
            if top == 0.0:
                break
            eps = scale / top
            u = (rate_at(origin, count, y, y + eps * v) - F) / eps
            out.radius_cycles += 1
            rho = float(np.linalg.norm(u) / np.linalg.norm(v))
            v = u * active
            if np.any(v):
                v = v / float(np.max(np.abs(v)))
        if not math.isfinite(rho):
            raise SolverError("the cycle jumps' spectral radius is not finite")
        radius = (RADIUS_SAFETY * rho, v, count)
        out.spectral_radius = radius[0]

    def step(origin, count, cyc, h):
        """The step of h cycles from ``origin`` (rate ``cyc.rate``): the pending
        step and the state after it (None if its increment is not finite)."""
        F0 = cyc.rate
        room = tol * change(origin) - float(np.max(np.abs(error)))
        st = _Step(origin=origin, n=count, rate=F0, cycle=cyc, h=h, allowed=LOCAL_SHARE * room)
        if 2.0 * h * float(np.max(np.abs(F0))) <= st.allowed or radius is None:
            st.increment = h * F0                       # forward Euler
        else:
            s = stages_for(h * radius[0])
            st.stages = s
            c = rkc_coefficients(s)
            y = problem.variable(origin)
            Y2 = y
            Y1 = y + c["mu_tilde"][1] * h * F0
            for j in range(2, s + 1):
                Fj = rate_at(origin, count + 1, y, Y1)
                out.stage_cycles += 1
                Yj = ((1 - c["mu"][j] - c["nu"][j]) * y + c["mu"][j] * Y1 + c["nu"][j] * Y2
                      + c["mu_tilde"][j] * h * Fj + c["gamma_tilde"][j] * h * F0)
                Y2, Y1 = Y1, Yj
            st.increment = Y1 - y
        if not np.all(np.isfinite(st.increment)):
            return st, None
        return st, problem.advance(origin, st.increment, h, cyc)

    def estimate(st: _Step, F1):
        """The local error estimate (vector) of step st from the rate F1 at its end."""
        if st.stages == 1:
            return 0.5 * st.h * (F1 - st.rate)
        return (-12.0 * st.increment + 6.0 * st.h * (st.rate + F1)) / 15.0

    def factor(err, allowed, order):
        if err <= 0.0:
            return GROWTH
        if not (allowed > 0.0 and math.isfinite(err)):
            return SHRINK
        return min(GROWTH, max(SHRINK, SAFETY * (allowed / err) ** (1.0 / order)))

    def take(origin, count, cyc, h):
        """Step h cycles (fewer while the step is not finite or needs too many
        stages) from ``origin``; the pending step, the state and count after it."""
        while h >= 2:
            if radius is not None and stages_for(h * radius[0]) > MAX_STAGES:
                h = int(0.9 * h * MAX_STAGES**2 / stages_for(h * radius[0]) ** 2)
                continue
            st, new = step(origin, count, cyc, h)
            if new is not None:
                return st, new, count + h
            out.rejected_steps += 1
            h = int(SHRINK * h)
        return None, cyc.state, count + 1

    origin, n_origin = state, 0
    while n < end:
        cyc = simulate(origin, n_origin + 1)
        if pending is not None:
            st = pending
            est = estimate(st, cyc.rate)
            err = float(np.max(np.abs(est)))
            order = 2 if st.stages == 1 else 3
            if not err <= st.allowed:
                out.rejected_steps += 1
                if st.stages > 1 and radius[2] < st.n:
                    # an unstable stage sequence looks like a large error: ρ afresh
                    estimate_radius(st.origin, st.n, st.rate)
                    h = st.h
                else:
                    h = min(int(st.h * factor(err, st.allowed, order)), st.h - 1)
                h_ctrl = max(2.0, h)
                pending, origin, n_origin = take(st.origin, st.n, st.cycle, h)
                n = n_origin
                continue
            out.steps += 1
            out.rkc_steps += st.stages > 1
            out.most_stages = max(out.most_stages, st.stages)
            out.largest_step = max(out.largest_step, st.h)
            out.error_sum += err
            error = error + est
            if st.h >= int(h_ctrl):
                h_ctrl *= factor(err, st.allowed, order)
            else:                       # a step cut short to land does not lengthen the next
                h_ctrl = min(h_ctrl, max(2.0, st.h * factor(err, st.allowed, order)))
        pending = None
        n = n_origin + 1
        out.rows += 1
        observe(cyc, n)
        if progress is not None and n / end - last_report >= 0.01:
            last_report = n / end
            progress(min(n / end, 1.0), f"cycle {n}")
        if tol <= 0.0 or n >= end:
            origin, n_origin = cyc.state, n
            continue
        land = next(c for c in landings if c > n)
        h = min(int(h_ctrl), land - n_origin - 1)
        events = problem.events(cyc)
        if seen is not None:
            crossing = _next_crossing(seen, (n, events))
            if crossing is not None:
                # the kink at the step's end: the next step starts past it
                h = min(h, max(2, int(math.floor(crossing)) - n_origin))
                out.event_landings += crossing - n_origin < h_ctrl
        seen = (n, events)
        if h >= 2 and (radius is None or n_origin > 2 * radius[2]):
            estimate_radius(origin, n_origin + 1, cyc.rate)
        pending, origin, n_origin = take(origin, n_origin, cyc, h)
    out.state, out.cycles = origin, n
    out.largest_change = change(origin)
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
