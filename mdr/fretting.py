"""Fretting (partial-slip) Reye–Archard wear by the MDR, with cycle jumping.

The indenter oscillates tangentially, a triangle wave between +U and -U in
displacement (``fretting.amplitude``) or tangential force
(``fretting.force_amplitude``), under a normal depth or force held fixed. The
1D springs carry normal line load q_z = E*(d - g) (paper Eq. 10) and
tangential line load q_x = G* v with Coulomb friction and memory
(:mod:`mdr.tangential`). Per increment, where the surface slides, the local
law of paper Eq. 1 with the real slip

    Δf(r) = (k/σ0) |τ(r)| |Δslip(r)|,

τ from q_x by paper Eq. 13 and the slip from the 1D slip by Eq. 16, raises
the profile (explicitly: the increment's wear is small against the profile;
the normal contact is re-solved once the wear since the last solve exceeds
NORMAL_RESOLVE = 1e-7 of the depth, in gross slip after every increment). The
friction work is taken as (τ·Δslip)₊, which is |τ||Δslip| wherever the
surface slides under pressure: where the grid's 3D pressure is tensile
(round-off in an unloaded slip annulus) the two disagree in sign and nothing
wears; with |τ||Δslip| that noise seeded a growing grid-scale mode in the
limiting state. The energy dissipated is accumulated as ∫ (τ·Δslip)₊ dA with
the same quadrature as the worn volume, so V = (k/σ0) W holds to round-off.
A depth that falls under force control (a force that rises under depth
control) is a SolverError: wear only removes material. So is an increment
wear number Λ = (k/σ0) μ E* |Δslip|/Δr (the wear of an increment over the
elastic indentation of one grid cell) past WEAR_NUMBER_LIMIT, the explicit
wear's stability limit (docs/fretting.md §5): the increments per cycle do
not resolve the wear, and the error names the number that would.

Cycle jumping (:mod:`numerics.cycle_jumping`): the wear per cycle W(f), one
cycle (+U -> -U -> +U) simulated increment by increment, is the rate of an
ODE in the cycle count, integrated by L-stable ROS2 steps whose Jacobian is
the stiff part of ∂W/∂f, the wear's response to the pressure (wear per unit
pressure (k/σ0) μ s, s the 3D slip per cycle, times the normal contact's
∂p/∂f on the sliding nodes), computed from the normal contact alone. Each
step simulates two cycles (its stage and the cycle from its end, which is
recorded); the steps grow geometrically as the rate decays to Popov's limit.
The global error against the run that simulates every cycle is estimated and
held at ``fretting.jump_tolerance`` of the largest wear (``info
["cycle_jumping"]``, meta.json); ``tol = 0`` simulates every cycle. A step
puts the springs on the limits its wear lowered without wear: the slip by
which they followed their limits down is the jumped cycles', and in W
already (docs/fretting.md §4).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from wearcheck.cases import CaseError, RunResult, SolverError, profiles, reference, validity
from wearcheck.cases.result import scar_radius
from wearcheck.numerics import cycle_jumping

from . import contact, linalg, resolution, tangential, transforms

#: most simulated cycles a run may take (runaway guard)
MAX_SIMULATED_CYCLES = 200_000
#: wear per cycle, relative to the node that wears most, below which a node is
#: left out of the cycle jumps' Jacobian
WORN = 1e-9
#: wear (relative to the depth) after which the normal contact is solved again
#: within a cycle; below it the pressure lags by that fraction of p0
NORMAL_RESOLVE = 1e-7
#: largest relative fall of the depth (force control) or rise of the force
#: (depth control) from one recorded cycle to the next: wear only removes
#: material, so either would mean the explicit wear went unstable
MONOTONE_TOLERANCE = 1e-6
#: longest wall time a run that simulates every cycle (fretting.jump_tolerance = 0)
#: may be estimated to take, fretting.cycles × the measured cost of its first cycles,
#: before it is refused: ten minutes, a run one waits for at the terminal; the cycle
#: count is known up front, so the run stops after its first cycles instead of late
EVERY_CYCLE_SECONDS = 600.0
#: simulated cycles and seconds measured before the estimate is judged (the timer's
#: resolution and the first cycles' set-up kept small beside the measurement)
ESTIMATE_CYCLES, ESTIMATE_SECONDS = 5, 0.2
#: largest increment wear number (k/σ0) μ E* |Δslip|/Δr a run may reach: the
#: wear within a cycle is forward Euler, stable at the grid scale while
#: Λ β_max <= 2, β_max = 1.47 the largest eigenvalue of (Δr/E*) ∂p/∂f on the
#: grid (any N, any amplitude), so Λ <= 1.36; the damage sets in at 2.0-2.4 in
#: gross slip and at 2.5-4 in partial slip (docs/fretting.md, §5;
#: benchmarks/bench_fretting_increments.py)
WEAR_NUMBER_LIMIT = 1.3
#: grid cells a refusal of an unresolved slip annulus proposes, and the width
#: (in cells at the contact edge) below which the grid's own a - c is not
#: taken as the annulus's width (its estimate from the amplitude is)
ANNULUS_CELLS = 4.0
ANNULUS_MEASURED = 0.5
#: margin of the increments a refusal proposes: Λ grows by up to 1.5x from the
#: first cycles (where the check fires) to the run's end, and Λ·increments is
#: constant to 5 %
WEAR_NUMBER_GROWTH = 1.6


@dataclass
class Model:
    """Grid, unworn profile, materials, normal load and tangential programme."""

    x: np.ndarray
    f0: np.ndarray
    E_star: float
    G_star: float
    mu: float
    k_over_hardness: float          # k_wear / σ0 [1/Pa]
    depth: float | None             # normal depth control
    force: float | None             # normal force control
    amplitude: float | None         # tangential displacement amplitude U [m]
    force_amplitude: float | None   # tangential force amplitude Q* [N]
    increments: int = 40            # per cycle, a multiple of 4
    #: the normal transforms as matrices (:func:`_normal_operators`, built once)
    normal_operators: tuple | None = field(default=None, repr=False)

    def __post_init__(self):
        self.t = self.x**2
        self.dt = float(self.t[-1] / (len(self.x) - 1))
        self.weights = transforms.force_weights(len(self.x) - 1, self.dt)
        # node spacing in r (the last node repeats its segment's)
        self.h = np.diff(self.x, append=2 * self.x[-1] - self.x[-2])


@dataclass
class State:
    """Profile, normal contact, spring deformations and the indenter's position."""

    f: np.ndarray
    v: np.ndarray                   # tangential spring deformation [m]
    u: float = 0.0                  # indenter displacement [m]
    Q: float = 0.0                  # tangential force [N]
    normal: dict = field(default_factory=dict)
    L: np.ndarray | None = None     # spring limits μ q_z / G*
    unsolved: float = 0.0           # largest wear since the last normal solve [m]

    def copy(self) -> "State":
        return replace(self, f=self.f.copy(), v=self.v.copy(), normal=dict(self.normal),
                       L=self.L.copy())


def solve_normal(model: Model, st: State) -> None:
    """Normal contact of the current profile; updates the spring limits.

    The transforms are causal (node i needs nodes 0..i), so after the first
    solve only a window reaching past the contact edge is transformed; a
    contact that reaches the window's end is solved again on the whole grid.
    """
    N1 = len(model.x)
    m_prev = st.normal.get("m")
    K = N1 if m_prev is None else min(N1, int(1.25 * (m_prev + 1)) + 16)
    while True:
        g = transforms.to_1d(st.f[:K])
        q = contact.line_load(g, model.depth, model.E_star) if model.depth is not None else None
        if q is None:
            depth = contact.depth_for_force(g, model.force, model.E_star, model.weights[:K])
            q = contact.line_load(g, depth, model.E_star)
        else:
            depth = model.depth
        loaded = np.flatnonzero(q > 0.0)
        m = int(loaded[-1]) if loaded.size else -1
        if m < K - 2 or K == N1:
            break
        K = N1
    m = contact.last_loaded(q) if K == N1 else m
    qq = np.zeros(N1)
    qq[:K] = q
    pp = np.zeros(N1)
    pp[:K] = transforms.pressure(q, model.dt)
    st.normal = dict(depth=float(depth), q=qq, p=pp, force=float(model.weights[:K] @ q),
                     contact_radius=contact.contact_radius(g, depth, model.t, m), m=m)
    st.L = tangential.limit(qq, model.mu, model.G_star)
    st.unsolved = 0.0


def initial_state(model: Model) -> State:
    st = State(f=model.f0.copy(), v=np.zeros_like(model.x))
    solve_normal(model, st)
    if not st.normal["force"] > 0.0:
        raise SolverError("the unworn indenter carries no load (no node in contact); "
                          "raise mdr.elements or the load")
    return st


def increment(model: Model, st: State, target: float, acc: dict) -> None:
    """One load increment to the displacement or tangential force ``target``; wear by it."""
    if model.amplitude is not None:
        du = target - st.u
    else:
        du = tangential.displacement_for_force(st.v, st.L, target, model.G_star, model.weights)
    v_new, slip = tangential.step(st.v, st.L, du)
    st.v, st.u = v_new, st.u + du
    st.Q = tangential.force(v_new, model.G_star, model.weights)
    acc["slide"] += abs(du)
    m = st.normal["m"]
    sliding = np.abs(slip[:m + 1]) > 0.0
    if not sliding.any():
        return
    acc["slipped"] |= np.abs(slip) > 0.0
    # τ vanishes beyond the contact: the wear and the dissipation live on nodes 0..m
    n = m + 2
    tau = tangential.shear_traction(v_new[:n], model.G_star, model.dt)
    s3 = tangential.slip_3d(slip[:n])
    # Eq. 16 at r needs the 1D slip on [0, r] only: inside the first spring that
    # slid the 3D slip is exactly zero, and so is the wear. The FFT's product
    # integration leaves round-off there (1e-15 of the annulus's slip): a
    # simulated cycle rounds its wear away (below an ulp of the profile), a
    # cycle jump of h cycles lays h times it down, and at a stick edge whose
    # spring limit equals U to round-off that wear seeds a mode of the cycle
    # map that grows by ~4 % per cycle (docs/fretting.md §4, the stick edge on
    # a node)
    s3[:int(np.argmax(sliding))] = 0.0
    work = np.maximum(tau * s3, 0.0)                    # dissipation per area [J/m²]
    # the 3D slip of the nodes whose springs slid: the wear per unit pressure
    # (over (k/σ0) μ) of the cycle-averaged rate's Jacobian
    acc["slid"][:n] += np.where(np.abs(slip[:n]) > 0.0, np.abs(s3), 0.0)
    acc["energy"] += transforms.volume(work, model.dt)
    # the 1D springs' own dissipation, an independent sum (MDR energy equivalence)
    acc["energy_1d"] += float(model.weights[:n] @ (np.abs(model.G_star * v_new[:n])
                                                   * np.abs(slip[:n])))
    df = model.k_over_hardness * work
    worn = work > 0.0
    if worn.any():
        acc["largest_wear"] = max(acc["largest_wear"], float(np.max(df)))
        # the wear of the increment over the elastic indentation of one grid cell
        # under the local pressure, Δf E*/(p Δr) = (k/σ0) μ E* |Δslip|/Δr where the
        # surface slides (τ = μp): the explicit wear's stability number
        acc["wear_number"] = max(acc["wear_number"], model.k_over_hardness * model.mu
                                 * model.E_star * float(np.max(np.abs(s3[worn])
                                                               / model.h[:n][worn])))
    st.f = st.f.copy()
    st.f[:n] += df
    acc["wear"][:n] += df
    # the normal contact follows the worn profile; re-solving it after wear of
    # 1e-7 of the depth changes the pressure by about that fraction of p0
    st.unsolved += float(np.max(df))
    if st.unsolved > NORMAL_RESOLVE * st.normal["depth"]:
        solve_normal(model, st)


def targets(model: Model, start: float, end: float, n: int) -> np.ndarray:
    """n equal increments from start to end (excluded start, included end)."""
    return start + (end - start) * np.arange(1, n + 1) / n


def run_path(model: Model, st: State, path: np.ndarray, loop: bool = False) -> dict:
    """Drive the indenter through the targets of ``path``; the cycle's sums."""
    acc = dict(energy=0.0, energy_1d=0.0, slide=0.0, wear=np.zeros_like(st.f),
               slid=np.zeros_like(st.f), slipped=np.zeros(len(st.f), dtype=bool), largest_wear=0.0, wear_number=0.0)
    us, Qs = [st.u], [st.Q]
    u_lo = u_hi = st.u
    Q_amp = abs(st.Q)
    for k, target in enumerate(path):
        if k == len(path) // 2 and len(path) == model.increments:
            # the stick zone of the cycle is the part that did not slip in its last stroke
            acc["slipped"][:] = False
        increment(model, st, float(target), acc)
        u_lo, u_hi = min(u_lo, st.u), max(u_hi, st.u)
        Q_amp = max(Q_amp, abs(st.Q))
        if loop:
            us.append(st.u)
            Qs.append(st.Q)
        if not math.isfinite(st.Q) or not math.isfinite(st.normal["force"]):
            raise SolverError("the fretting run produced non-finite values")
    if st.unsolved > 0.0:
        solve_normal(model, st)   # what is recorded is the contact of the worn profile
    acc.update(Q_amp=Q_amp, u_amp=0.5 * (u_hi - u_lo))
    if loop:
        acc.update(loop_u=np.asarray(us), loop_Q=np.asarray(Qs))
    return acc


def cycle_path(model: Model) -> np.ndarray:
    amp = model.amplitude if model.amplitude is not None else model.force_amplitude
    h = model.increments // 2
    return np.concatenate([targets(model, amp, -amp, h), targets(model, -amp, amp, h)])


def ramp_path(model: Model) -> np.ndarray:
    amp = model.amplitude if model.amplitude is not None else model.force_amplitude
    return targets(model, 0.0, amp, model.increments // 4)


def stick_radius(model: Model, st: State, acc: dict, ramp: bool) -> float:
    """Stick radius of the last stroke: the crossing of L - U, U the stroke's half travel."""
    U = acc["u_amp"] if not ramp else abs(st.u)
    margin = st.L - U
    # a spring without normal load cannot hold any tangential force: it
    # counts as slipping even in a stroke in which no loaded spring slid
    # (the limiting state, where the annulus is unloaded exactly)
    return tangential.stick_radius(acc["slipped"] | (st.L <= 0.0), margin, model.t)


HISTORY_KEYS = ("cycles", "s", "force", "depth", "contact_radius", "wear_center", "wear_volume",
                "scar_radius", "tangential_force_amplitude", "displacement_amplitude",
                "stick_radius", "dissipated_energy", "dissipated_energy_1d", "energy_per_cycle",
                "max_pressure")


@dataclass
class Point:
    """The run between two cycles: the contact's state and the run's totals."""

    st: State
    totals: dict                    # cycles, s, energy, energy_1d


class Cycles(cycle_jumping.Problem):
    """The fretting run as :mod:`numerics.cycle_jumping` sees it: a cycle is
    simulated increment by increment, the integrated variable is the profile f."""

    def __init__(self, model: Model, counters: dict, loop_cycles=()):
        self.model = model
        self.path = cycle_path(model)
        self.counters = counters
        self.loop_cycles = set(loop_cycles)

    def cycle(self, point, n, probe=False):
        model = self.model
        st = point.st.copy()
        acc = run_path(model, st, self.path, loop=not probe and n in self.loop_cycles)
        self.counters["total_increments"] += model.increments
        _check_resolution(model, acc, self.counters)
        totals = dict(point.totals, cycles=n)
        for key, name in (("s", "slide"), ("energy", "energy"), ("energy_1d", "energy_1d")):
            totals[key] += acc[name]
        return cycle_jumping.Cycle(state=Point(st, totals), rate=acc["wear"], record=acc)

    def advance(self, point, increment, cycles, cycle):
        model = self.model
        st = point.st.copy()
        # wear only removes material: every cycle's wear is >= 0 at every node, so
        # h cycles wear at least what their first one did (the kept cycle, whose
        # state is the recorded row). A step below that (round-off of the solves,
        # or an L-stable step's overshoot near the limit) is in error there, and
        # the bound only brings it nearer the every-cycle run; without it the
        # recorded depth fell by 2e-5 near 10⁶ cycles in the shipped case
        floor = cycle.rate if cycle is not None else 0.0
        increment = np.maximum(increment, floor)
        st.f = st.f + increment
        totals = dict(point.totals)
        if cycles:
            acc = cycle.record
            totals["cycles"] += cycles
            totals["s"] += cycles * acc["slide"]
            # the energy the jumped cycles dissipated is their worn volume over k/σ0
            # (paper Eq. 1 integrated): V = (k/σ0) W holds at every cycle, jumps included
            energy = (transforms.volume(increment, model.dt) / model.k_over_hardness
                      if model.k_over_hardness > 0 else cycles * acc["energy"])
            totals["energy"] += energy
            totals["energy_1d"] += (energy * acc["energy_1d"] / acc["energy"]
                                    if acc["energy"] > 0 else cycles * acc["energy_1d"])
        if not np.all(np.isfinite(st.f)):
            raise SolverError("cycle jumping produced non-finite values; lower "
                              "fretting.jump_tolerance")
        _settle_springs(model, st)
        return Point(st, totals)

    def variable(self, point):
        return point.st.f

    def admissible(self, before, after):
        """Wear only removes material: the depth does not fall under force control,
        the force does not rise under depth control (the check every recorded
        cycle passes, :func:`_check_monotone`). An L-stable step near the limit
        can break it by a spike of its increment at one node (to_1d's grid
        weights are not all positive); the step is retried shorter instead."""
        return not _moved_against_wear(self.model, before.state.st.normal,
                                       after.state.st.normal)

    def jacobian(self, cycle):
        """The wear's response to the pressure, the stiff part of ∂W/∂f.

        Where the surface slides, τ = μp and the wear per cycle is W = (k/σ0) μ p s,
        s the 3D slip per cycle; a profile change Δf changes p by P Δf (the
        normal contact's linear response on its contact set, force or depth
        held), so ∂W/∂f ≈ diag((k/σ0) μ s) P on the sliding nodes. This is what
        makes the problem stiff (a node worn too far unloads and wears less)
        and what stays as the wear vanishes in the limit (s does not); the
        slip's own change with the profile is left to the step, which is second
        order for any J (a W-method). No cycle is simulated for it.
        """
        model, st, acc = self.model, cycle.state.st, cycle.record
        m = st.normal["m"]
        # the sliding nodes that wear: the stick zone's round-off wear (1e-17 of
        # the annulus's) stays out, its increments those of Heun's rule
        W = acc["wear"][:m + 1]
        index = np.flatnonzero((acc["slid"][:m + 1] > 0.0) & (W > WORN * np.max(W)))
        if not len(index):
            return None
        P = _pressure_response(model, m, index)
        return index, (model.k_over_hardness * model.mu * acc["slid"][index])[:, None] * P


def run(model: Model, cycles: int, tol: float, stage_cycles, progress=None, watch=None) -> dict:
    """The fretting run from the unworn state; numerics without case handling.

    Returns history (arrays, one entry per simulated cycle kept and the
    initial ramp as cycle 0), stages (cycles, s, f, p, tau), loops (Q(u) of
    the simulated cycles at the stage cycles), counters and the cycle
    jumping's report (``jumping``, :meth:`numerics.cycle_jumping.Outcome.info`).
    ``watch(s, contact_radius, scar_radius, cycle)`` is called at every
    recorded cycle (:class:`cases.validity.BodyWatch`).
    """
    st = initial_state(model)
    hist = {k: [] for k in HISTORY_KEYS}
    stages = dict(cycles=[], s=[], f=[], p=[], tau=[])
    loops = dict(cycles=[], u=[], Q=[])
    stage_list = sorted(set(int(c) for c in stage_cycles if c <= cycles))
    stage_set = list(stage_list)
    counters = dict(total_increments=0, largest_wear_per_increment=0.0,
                    increment_wear_number=0.0)

    def record(point, acc, ramp=False):
        st, totals = point.st, point.totals
        n = st.normal
        if hist["cycles"]:
            _check_monotone(model, hist, n, totals["cycles"])
        w = st.f - model.f0
        hist["cycles"].append(totals["cycles"])
        hist["s"].append(totals["s"])
        hist["force"].append(n["force"])
        hist["depth"].append(n["depth"])
        hist["contact_radius"].append(n["contact_radius"])
        hist["wear_center"].append(w[0])
        hist["wear_volume"].append(transforms.volume(w, model.dt))
        hist["scar_radius"].append(scar_radius(model.x, w))
        hist["tangential_force_amplitude"].append(acc["Q_amp"])
        hist["displacement_amplitude"].append(acc["u_amp"] if not ramp else abs(st.u))
        hist["stick_radius"].append(stick_radius(model, st, acc, ramp))
        hist["dissipated_energy"].append(totals["energy"])
        hist["dissipated_energy_1d"].append(totals["energy_1d"])
        hist["energy_per_cycle"].append(acc["energy"])
        hist["max_pressure"].append(float(np.max(n["p"])))
        if watch is not None:
            watch(totals["s"], n["contact_radius"], hist["scar_radius"][-1],
                  cycle=totals["cycles"])
        while stage_set and stage_set[0] < totals["cycles"]:
            stage_set.pop(0)
        if stage_set and stage_set[0] == totals["cycles"]:
            stage_set.pop(0)
            stages["cycles"].append(totals["cycles"])
            stages["s"].append(totals["s"])
            stages["f"].append(st.f.copy())
            stages["p"].append(n["p"].copy())
            stages["tau"].append(tangential.shear_traction(st.v, model.G_star, model.dt))
            if "loop_u" in acc and not ramp:
                loops["cycles"].append(totals["cycles"])
                loops["u"].append(acc["loop_u"])
                loops["Q"].append(acc["loop_Q"])

    acc = run_path(model, st, ramp_path(model))
    counters["total_increments"] += model.increments // 4
    _check_resolution(model, acc, counters)
    _check_slip_resolved(model, st, acc)
    start = Point(st, dict(cycles=0, s=acc["slide"], energy=acc["energy"],
                           energy_1d=acc["energy_1d"]))
    record(start, acc, ramp=True)
    problem = Cycles(model, counters, loop_cycles=stage_list)
    plan = cycle_jumping.Plan(cycles=cycles, tolerance=tol, landings=tuple(stage_list),
                              max_simulated=MAX_SIMULATED_CYCLES,
                              tolerance_key="fretting.jump_tolerance")
    out = cycle_jumping.run(problem, start, plan,
                            lambda cyc, n: record(cyc.state, cyc.record), progress)
    counters.update(simulated_cycles=out.simulated, jumps=out.steps,
                    rejected_jumps=out.rejected_steps, largest_jump=max(out.largest_step, 1))
    return dict(history={k: np.asarray(v, dtype=float) for k, v in hist.items()},
                stages={k: np.asarray(v) for k, v in stages.items()},
                loops=loops, counters=counters, jumping=out.info())


def _every_cycle_estimate(fr, watch, clock=time.perf_counter):
    """``watch``, and for a run without cycle jumping its refusal after the first
    cycles when ``fr.cycles`` of them would take more than :data:`EVERY_CYCLE_SECONDS`.

    The cost per cycle is measured from the end of the initial ramp (cycle 0) over
    at least :data:`ESTIMATE_CYCLES` cycles and :data:`ESTIMATE_SECONDS`; every cycle
    costs the same grid and increments, so it projects to the run's end.
    """
    if fr.jump_tolerance != 0:
        return watch
    seen = {}

    def estimated(s, contact_radius, scar_radius, cycle=None):
        watch(s, contact_radius, scar_radius, cycle=cycle)
        now = clock()
        if "start" not in seen:
            seen["start"] = now
            return
        spent = now - seen["start"]
        if seen.get("judged") or cycle < ESTIMATE_CYCLES or spent < ESTIMATE_SECONDS:
            return
        seen["judged"] = True
        estimate = spent / cycle * fr.cycles
        if estimate > EVERY_CYCLE_SECONDS:
            largest = int(EVERY_CYCLE_SECONDS * cycle / spent)
            raise CaseError(
                f"key 'fretting.jump_tolerance' = {fr.jump_tolerance!r}: simulating every one "
                f"of fretting.cycles = {fr.cycles} cycles would take about {estimate:.3g} s "
                f"({spent / cycle * 1e3:.3g} ms per cycle, measured on the first {cycle}), more "
                f"than the {EVERY_CYCLE_SECONDS:g} s allowed without cycle jumping; give "
                f"fretting.jump_tolerance > 0 (the default is 0.02) or at most "
                f"about {largest} cycles")
    return estimated


def _check_resolution(model, acc, counters):
    """SolverError if the increments do not resolve the wear (docs/fretting.md, §5).

    The increment wear number Λ = (k/σ0) μ E* |Δslip|/Δr (largest over the
    nodes worn in an increment) is the wear of an increment over the elastic
    indentation p Δr/E* of one grid cell under the local pressure: the
    explicit wear's stability number, proportional to k, to the slip per
    increment (1/increments) and to N (Δr at the contact edge).
    """
    counters["largest_wear_per_increment"] = max(counters["largest_wear_per_increment"],
                                                 acc["largest_wear"])
    number = acc["wear_number"]
    counters["increment_wear_number"] = max(counters["increment_wear_number"], number)
    if number > WEAR_NUMBER_LIMIT:
        n = model.increments
        # Λ ∝ 1/increments, with the margin for its growth over the run
        need = 4 * math.ceil(WEAR_NUMBER_GROWTH * n * number / WEAR_NUMBER_LIMIT / 4)
        raise SolverError(
            f"fretting.increments = {n} does not resolve the wear within a cycle: the "
            f"increment wear number (k/σ0)·μE*·|Δslip|/Δr reached {number:.4g}, past "
            f"{WEAR_NUMBER_LIMIT:g}, the stability limit of the explicit wear on this grid; "
            f"fretting.increments = {need} would do (or lower wear.k or mdr.elements)")


def _check_slip_resolved(model, st, acc):
    """SolverError if the slip annulus of the first quarter cycle is under one grid cell.

    Any tangential load slides the edge of the unworn contact (the pressure
    falls to zero there), but an annulus a - c narrower than the cell at the
    contact edge holds no loaded node, or one barely loaded: the run
    dissipates and wears almost nothing, silently: the first cycle's energy
    against Mindlin–Deresiewicz falls short the more, the fewer cells the
    annulus holds (docs/performance.md, "Measurements behind the code";
    docs/fretting.md §2). The grid's own a and c (sub-grid crossings) measure
    the annulus.
    """
    m = st.normal["m"]
    if m < 0:
        return
    a = st.normal["contact_radius"]
    c = stick_radius(model, st, acc, ramp=True)
    cell = float(model.h[m])
    if a - c >= cell:
        return
    N = len(model.x) - 1
    amp, value = (("fretting.amplitude", model.amplitude) if model.amplitude is not None
                  else ("fretting.force_amplitude", model.force_amplitude))
    width, measured = a - c, True
    if width < ANNULUS_MEASURED * cell:
        # the grid's a and c are then mostly the sub-grid interpolation (their
        # difference even negative, e.g. -1.9e-7 m at an amplitude of 1e-30 m):
        # springs slide where μ q/G* < U, q falling as E* g'(a) (a - r) at the
        # edge, so a - c = G* U/(μ |q'(a)|), with U = Q/(2 a G*) while the
        # contact sticks (Mindlin's a Q/(3 μ F) for a paraboloid)
        q, x = st.normal["q"], model.x
        slope = (q[m - 1] - q[m]) / (x[m] - x[m - 1]) if m >= 1 else q[0] / x[1]
        U = model.amplitude if model.amplitude is not None else \
            model.force_amplitude / (2.0 * a * model.G_star)
        width, measured = model.G_star * U / (model.mu * slope), False
    said = (f"{width:.3g} m wide (a - c, a = {a:.4g} m)" if measured else
            f"narrower than the grid measures, about {width:.3g} m (G*U/(μ|q'(a)|), a = "
            f"{a:.4g} m)")
    # the cell at the edge scales as 1/N (t = r² uniform); with too few cells in
    # the annulus the first cycle's energy is low (docs/performance.md,
    # "Measurements behind the code"). The annulus grows in proportion to a
    # small amplitude.
    cells = width / cell
    need = 100 * math.ceil(N * ANNULUS_CELLS / cells / 100)
    remedy = f"raise {amp} to about {value * ANNULUS_CELLS / cells:.3g}"
    if need <= resolution.MAX_PROPOSED_ELEMENTS:
        remedy = f"mdr.elements = {need} would put {ANNULUS_CELLS:g} cells in it (or {remedy})"
    raise SolverError(
        f"key '{amp}' = {value!r}: mdr.elements = {N} does not resolve its slip annulus: it "
        f"is {said}, {cells:.2g} of the grid cell at the contact edge, so the run would "
        f"dissipate and wear almost nothing; {remedy}")


def _check_monotone(model, hist, normal, cycle):
    """SolverError if the normal load moved against the wear (docs/fretting.md, §3).

    Under force control Δd = (1/a) ∫_0^a Δf(r) r dr/√(a² - r²) >= 0 for any
    wear Δf >= 0; under depth control the force falls likewise.
    """
    if model.force is not None:
        prev, now, what = hist["depth"][-1], normal["depth"], "depth fell"
    else:
        prev, now, what = hist["force"][-1], normal["force"], "force rose"
    if _moved_against_wear(model, dict(depth=hist["depth"][-1], force=hist["force"][-1]),
                           normal):
        raise SolverError(
            f"the fretting run became unstable at cycle {cycle}: the {what} by "
            f"{abs(now / prev - 1):.2g} (relative) while wear can only remove material; "
            "raise fretting.increments, or lower fretting.jump_tolerance, wear.k or "
            "mdr.elements")


def _moved_against_wear(model, before: dict, after: dict) -> bool:
    """Whether the normal load moved against the wear from ``before`` to ``after``
    (normal contact dicts) by more than MONOTONE_TOLERANCE."""
    if model.force is not None:
        return after["depth"] < before["depth"] * (1.0 - MONOTONE_TOLERANCE)
    return after["force"] > before["force"] * (1.0 + MONOTONE_TOLERANCE)


def _normal_operators(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """The MDR's normal transforms as matrices on the grid (once per model): A with
    g = A f (paper Eq. 2, :func:`transforms.to_1d`) and B with p = B q (paper
    Eq. 13, :func:`transforms.pressure`), both linear."""
    if model.normal_operators is None:
        n = len(model.x)
        eye = np.eye(n)
        A = np.column_stack([transforms.to_1d(eye[:, j]) for j in range(n)])
        B = np.zeros((n, n))
        for j in range(n - 1):
            B[:, j] = transforms.pressure(eye[:, j], model.dt)
        model.normal_operators = (A, B)
    return model.normal_operators


def _pressure_response(model: Model, m: int, index: np.ndarray) -> np.ndarray:
    """∂p/∂f on the nodes ``index`` (rows and columns) for the contact set 0..m.

    q = E*(d − g) on 0..m; under force control d follows g by
    ∂d/∂g_i = w_i / Σ w (the discrete Eq. 12 with the force held), under depth
    control d is held.
    """
    A, B = _normal_operators(model)
    Bs = B[index, :m + 1]
    As = A[:m + 1, index]
    P = -(Bs @ As)
    if model.force is not None:
        w = model.weights[:m + 1]
        P += np.outer(Bs.sum(axis=1), w @ As) / w.sum()
    return model.E_star * P


def _settle_springs(model, st):
    """Solve the normal contact of a jumped profile and put the springs on its limits."""
    solve_normal(model, st)
    # The jumped cycles' wear lowered the limits L in the slip annulus, and each
    # of those cycles ended with its sliding springs at its own lowered limit.
    # The slip by which they followed the limits down, its wear, dissipation and
    # friction work, is part of every simulated cycle, so the jump's increment
    # holds it already: the springs are put on the new limits without wear, and
    # the next cycle starts where the cycle-by-cycle run's would. Left at the
    # old limits, the next cycle slid less by the limits' fall (docs/fretting.md, §4).
    Q_end = st.Q
    st.v = np.clip(st.v, -st.L, st.L)
    if model.amplitude is None:
        # tangential force control: every simulated cycle ends at Q*, its
        # springs reloaded onto the lowered limits by a little more travel of
        # the indenter; clipped alone, the next cycle started below Q*
        du = tangential.displacement_for_force(st.v, st.L, Q_end, model.G_star, model.weights)
        st.v, _ = tangential.step(st.v, st.L, du)
        st.u += du
    st.Q = tangential.force(st.v, model.G_star, model.weights)
    # The springs' memory is slaved to the profile: in the every-cycle run each
    # cycle starts from the state the last one left for nearly the same limits,
    # while after a jump the springs inside the stick edge still hold the state
    # of the old limits, and the first cycle from there slides and wears more:
    # without a correction the shipped case is biased at any tolerance
    # (docs/performance.md, "Measurements behind the code"). One cycle of the
    # springs alone, without wear, under the new limits puts every spring in the
    # state the periodic cycle gives them (Coulomb springs under fixed limits
    # shake down within one cycle; docs/fretting.md §4).
    _spring_cycle(model, st)


def _spring_cycle(model, st):
    """One cycle of the tangential springs under the current limits, without wear."""
    for target in cycle_path(model):
        if model.amplitude is not None:
            du = float(target) - st.u
        else:
            du = tangential.displacement_for_force(st.v, st.L, float(target), model.G_star,
                                                   model.weights)
        st.v, _ = tangential.step(st.v, st.L, du)
        st.u += du
    st.Q = tangential.force(st.v, model.G_star, model.weights)


# -- the case -------------------------------------------------------------------

def default_stage_cycles(cycles: int) -> list[int]:
    """0, 1, 10, 100, ... below ``cycles``, and ``cycles``."""
    out, c = [0], 1
    while c < cycles:
        out.append(c)
        c *= 10
    return out + [cycles]


def build_model(case) -> tuple[Model, dict]:
    """Grid (as the gross-slip solver's), unworn profile, materials and programme."""
    sc = reference.scales(case)
    N = case.mdr.elements
    L = case.mdr.domain_factor * math.sqrt(2.0) * sc["a0"]
    x = transforms.grid(N, L)
    fr = case.fretting
    model = Model(x=x, f0=profiles.height(case.indenter, x, case.table), E_star=case.E_star,
                  G_star=case.G_star, mu=case.wear.mu,
                  k_over_hardness=case.wear.k / case.wear.hardness,
                  depth=case.loading.depth, force=case.loading.force,
                  amplitude=fr.amplitude, force_amplitude=fr.force_amplitude,
                  increments=fr.increments)
    return model, sc


def solve(case, progress=None) -> RunResult:
    """Run the fretting case (``case.fretting`` set); see the module docstring.

    ``RunResult.history`` has one row per simulated cycle (cycle 0: the first
    quarter cycle from 0 to +U); ``stage_extra["tau"]`` the shear traction at
    the stages (at +U, the end of the stage's cycle); ``fields`` the loops
    Q(u_x) of the simulated cycles at the stage cycles (``loop_cycles`` (L,),
    ``loop_displacement`` and ``loop_tangential_force`` (L, increments + 1)).
    ``info["increment_wear_number"]`` is the largest Λ of the run (at most
    WEAR_NUMBER_LIMIT, else SolverError), ``info["largest_wear_per_increment"]``
    the largest wear of one increment [m].
    """
    with linalg.single_threaded_blas():
        return _solve(case, progress)


def _solve(case, progress=None) -> RunResult:
    t0 = time.perf_counter()
    resolution.check(case)
    model, sc = build_model(case)
    fr = case.fretting
    if fr.jump_tolerance == 0 and fr.cycles > MAX_SIMULATED_CYCLES:
        raise CaseError(f"key 'fretting.cycles' = {fr.cycles}: without cycle jumping "
                        f"(fretting.jump_tolerance = 0) at most {MAX_SIMULATED_CYCLES} cycles "
                        "are simulated; set a jump tolerance")
    stage_cycles = (default_stage_cycles(fr.cycles) if fr.stage_cycles is None
                    else [int(c) for c in fr.stage_cycles])
    watch = validity.BodyWatch(case)
    out = run(model, fr.cycles, fr.jump_tolerance, stage_cycles, progress,
              watch=_every_cycle_estimate(fr, watch))
    hist = out["history"]
    hist["s_hat"] = hist["s"] * sc["s_hat_per_m"]
    a0, F0 = sc["a0"], sc["F0"]
    u_star = 3.0 * case.wear.mu * F0 / (4.0 * case.G_star * a0)
    stg = out["stages"]
    K, M = len(stg["cycles"]), len(model.x)
    info = dict(solver="mdr", mode="fretting", N=case.mdr.elements, domain=float(model.x[-1]),
                grid="uniform in r^2", increments=fr.increments,
                jump_tolerance=fr.jump_tolerance, stage_cycles=stg["cycles"].tolist(),
                gross_slip_displacement_unworn=u_star, cycle_jumping=out["jumping"],
                increment_wear_number_limit=WEAR_NUMBER_LIMIT, **out["counters"])
    remarks = list(watch.remarks)
    if K and stg["cycles"][-1] < fr.cycles:
        # an explicit list that ends early (the shipped case's, run longer with
        # --set fretting.cycles=...): the final profile would be in no output
        remarks.append(f"the stored stages end at cycle {int(stg['cycles'][-1])} of "
                       f"fretting.cycles = {fr.cycles}: stages.npz holds no profile, "
                       "pressure or shear traction after it; add the last cycle to "
                       "fretting.stage_cycles (or leave the key out: its default ends "
                       "at the last cycle)")
    if remarks:
        info["warnings"] = remarks
    loops = out["loops"]
    fields = None
    if loops["cycles"]:
        fields = dict(loop_cycles=np.asarray(loops["cycles"], dtype=float),
                      loop_displacement=np.asarray(loops["u"]),
                      loop_tangential_force=np.asarray(loops["Q"]))
    if progress is not None:
        progress(1.0, "done")
    return RunResult(history=hist, stage_s=np.asarray(stg["s"], dtype=float),
                     r=model.x.copy(), f=np.asarray(stg["f"]).reshape(K, M),
                     p=np.asarray(stg["p"]).reshape(K, M),
                     solve_seconds=time.perf_counter() - t0, info=info, fields=fields,
                     stage_extra=dict(tau=np.asarray(stg["tau"]).reshape(K, M)))
