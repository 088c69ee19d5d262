"""Gross-slip Reye–Archard wear of the pixel grid: the BEM's implicit wear step.

The state is the worn profile f = f0 + w on the pixels. Over a sliding
increment h each pixel wears by Δw = K p h, K = k μ/σ0 (pressure-driven
Archard wear, the same law as the MDR and FEM solvers), or by
Δw = K σ0 (p/σ0)^n h with a pressure exponent n (implicit steps then
iterate on the linearised law, :func:`implicit_state`).

- explicit Euler: w_{n+1} = w_n + h K p_n, then a static contact solve;
  stable for h K / λ_min(G) <= 2 (:func:`explicit_limit`).
- implicit step of wear compliance c h: p_{n+1} solves the contact problem
  with the operator G + c h K I on a start profile (f_n: backward Euler;
  a f_n + b f_{n-1}: the variable-step BDF2), then f_{n+1} = start + c h K p_{n+1}.

:class:`Wear` hands these to :mod:`numerics.stepping`, which runs every
scheme (the step control, stages, step doubling with the deferred
Richardson correction, BDF2's start, the caps) as for the MDR and FEM
(docs/time-stepping.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from wearcheck.cases import SolverError, wear_law
from wearcheck.cases.result import scar_radius
from wearcheck.numerics import stepping

from . import contact
from .operator import HalfSpace
from .tangential import ShearToNormal


@dataclass
class Coupling:
    """The friction traction τx = μp moving the surface normally (bodies not elastically similar).

    shear : the normal displacement of a traction along x (Dundurs' β in it).
    mu : friction coefficient; the traction on the worn body points along +x,
        the direction the counterface slides relative to it.
    reciprocating : strokes alternate +x, -x. The wear of a step is then the
        mean of the two strokes' (the stroke is short against the wear's time
        scale): the pressure of the -x stroke is the mirror image x -> -x of
        the +x stroke's on a profile symmetric in x, which the symmetric
        wear keeps (the unworn profiles are all symmetric in x). An implicit
        step solves the +x stroke's contact on base + σ·(stroke mean of p):
        the wear compliance acts on the stroke mean (:func:`contact.solve`
        ``stroke_mean``), so the step is backward Euler of the averaged law.
    """

    shear: ShearToNormal
    mu: float
    reciprocating: bool = False


def stroke_mean(model: "Model", field_: np.ndarray) -> np.ndarray:
    """The mean of a +x stroke's field and its mirror image (the -x stroke's); itself otherwise.

    :func:`contact.mirror_x` (for even n pixel 0 keeps its value: it carries
    no load, the contact may not reach the box's edge).
    """
    if not reciprocating(model):
        return field_
    return 0.5 * (field_ + contact.mirror_x(field_))


def reciprocating(model: "Model") -> bool:
    """Coupled with reciprocating strokes: the wear is the two strokes' mean."""
    return model.coupling is not None and model.coupling.reciprocating


@dataclass
class Model:
    """A discretised case: operator, unworn profile, wear rate, load, tolerances."""

    op: HalfSpace
    f0: np.ndarray             # (n, n) unworn heights at the pixel centres [m]
    wear_rate: float           # K = k μ / σ0 [1/Pa]
    depth: float | None
    force: float | None
    p_scale: float             # p0 [Pa]
    g_scale: float             # d (or d0) [m]
    tol: float = 1e-8
    maxiter: int = 5000
    centre: tuple[int, int] = (0, 0)
    exponent: float = 1.0      # n of the wear law dw/ds = K σ0 (p/σ0)^n
    hardness: float = 1.0      # σ0 [Pa]; enters only when exponent != 1
    coupling: Coupling | None = None   # bem.coupling: friction traction into the normal problem


@dataclass
class State:
    f: np.ndarray
    p: np.ndarray
    gap: np.ndarray
    depth: float
    force: float
    iterations: int
    residual: float
    stats: dict = field(default_factory=dict)
    displacement: np.ndarray | None = None   # G p, within displacement_error [m]
    displacement_error: float = 0.0


def wear_speed(model: Model, p: np.ndarray) -> np.ndarray:
    """dw/ds = K σ0 (p/σ0)^n (K p for n = 1, Reye–Archard): :func:`cases.wear_law.speed`.

    Reciprocating with coupling: averaged over the two strokes (:func:`stroke_mean`).
    """
    return stroke_mean(model, wear_law.speed(p, model.wear_rate, model.exponent,
                                             model.hardness))


def wear_speed_slope(model: Model, p: np.ndarray) -> np.ndarray:
    """d(dw/ds)/dp divided by K: n (p/σ0)^(n-1)."""
    return wear_law.slope(p, model.exponent, model.hardness)


def explicit_limit(op: HalfSpace, wear_rate: float) -> float:
    """Largest stable explicit Euler step [m of sliding]: 2 λ_min(G) / K.

    In contact, p = G_c⁻¹ (d - f) (depth control), so one step maps a
    perturbation δf to (I - h K G_c⁻¹) δf; stable while h K / λ_min(G_c) <= 2.
    λ_min(G_c) >= the symbol's minimum (:meth:`HalfSpace.smallest_eigenvalue`),
    about 0.52 Δ/E* for pixels of side Δ, so the limit falls with the pixel size.
    """
    return 2.0 * op.smallest_eigenvalue() / wear_rate


def in_contact(model: Model, p: np.ndarray) -> np.ndarray:
    """The loaded pixels: p above the solve's tolerance (p0 · tol).

    A free pixel may keep a pressure below tol · p0 at convergence (the
    complementarity residual allows it); it is not counted as in contact.
    """
    return p > model.tol * model.p_scale


def check_edge(p: np.ndarray) -> None:
    """The contact must stay inside the box: no load on its outermost pixels."""
    if np.any(p[0] > 0) or np.any(p[-1] > 0) or np.any(p[:, 0] > 0) or np.any(p[:, -1] > 0):
        raise SolverError("the contact has reached the edge of the BEM box (pressure on its "
                          "outermost pixels); raise bem.box")


def contact_state(model: Model, base: np.ndarray, sigma: float = 0.0,
                  p_init=None, displacement=None) -> State:
    """Contact of the profile ``base`` (+ wear compliance σ) under the model's load.

    The returned profile is base + σ p (the worn profile of an implicit step),
    base + σ·(stroke mean of p) when reciprocating with coupling: the +x
    stroke's contact is solved with the wear compliance on the stroke mean,
    so p is the +x stroke's pressure on the returned profile, which stays
    exactly symmetric in x (σ must be symmetric in x). ``displacement`` =
    (G p_init, its error bound) when known (:func:`contact.solve`).
    """
    u, error = displacement if displacement is not None else (None, 0.0)
    kw = dict(depth=model.depth, force=model.force, sigma=sigma, p_init=p_init,
              p_scale=model.p_scale, g_scale=model.g_scale, tol=model.tol,
              maxiter=model.maxiter, stroke_mean=reciprocating(model),
              displacement=u, displacement_error=error)
    if model.coupling is None:
        # the gap and displacement on the window only (the gap outside is
        # filled when a stage is stored, :func:`whole_gap`): no convolution
        # on the whole box per solve
        c = contact.solve(model.op, base, whole_box=False, **kw)
    else:
        c = contact.solve_coupled(model.op, model.coupling.shear, base, model.coupling.mu, **kw)
    check_edge(c.pressure)
    f = base + stroke_mean(model, sigma * c.pressure) if np.any(sigma) else base
    return State(f=f, p=c.pressure, gap=c.gap, depth=c.depth, force=c.force,
                 iterations=c.iterations, residual=c.residual, displacement=c.displacement,
                 displacement_error=c.displacement_error)


#: Newton iteration of a pressure exponent n != 1 (as the MDR's,
#: docs/time-stepping.md): relative change of p that ends it (at least ten
#: times the contact solve's tolerance), most iterations, undamped ones, the
#: floor of the pressure the slope is taken at, and the stall rule
NEWTON_TOL = 1e-7
NEWTON_MAX = 60
NEWTON_UNDAMPED = 8
NEWTON_FLOOR = 0.05
NEWTON_STALL = 1e-5
NEWTON_STALL_AFTER = 4


def implicit_state(model: Model, base: np.ndarray, eff: float, p_guess=None,
                   displacement=None) -> State:
    """One implicit step: the contact of ``base`` + eff·(wear speed at its end).

    eff is the step times the scheme's factor (h for backward Euler, c h for
    BDF2). n = 1: one contact solve with wear compliance eff·K. n != 1: the
    wear speed is linearised about the last iterate (Newton: per-pixel wear
    compliance eff K n (p_k/σ0)^(n-1), base shifted by eff (r(p_k) - r'(p_k)
    p_k)) until p settles; the profile is then base + eff r(p) (reciprocating
    with coupling: r(p) and its linearisation averaged over the two strokes,
    as :func:`contact_state`). ``displacement``: (G p_guess, its error
    bound) when known.
    """
    K = model.wear_rate
    if model.exponent == 1.0:
        return contact_state(model, base, eff * K, p_guess, displacement)
    p_k = contact_state(model, base, 0.0, p_guess).p if p_guess is None else p_guess
    tol = max(NEWTON_TOL, 10.0 * model.tol)
    iterations, changes = 0, []
    for it in range(NEWTON_MAX):
        # the slope vanishes as p -> 0 (n > 1): floored, or an edge pixel would
        # enter unworn and leave worn, iterate after iterate (any slope leaves
        # the fixed point p = p_k unchanged)
        slope = wear_speed_slope(model, np.maximum(p_k, NEWTON_FLOOR * np.max(p_k)))
        # reciprocating: the wear is the stroke mean S r(p), linearised with a
        # slope symmetric in x (S·diag(slope) is then symmetric, as the
        # solve needs; Newton's fixed point does not depend on the slope)
        slope = stroke_mean(model, slope)
        shift = eff * (wear_speed(model, p_k) - stroke_mean(model, K * slope * p_k))
        new = contact_state(model, base + shift, eff * K * slope, p_k)
        iterations += new.iterations
        change = float(np.max(np.abs(new.p - p_k))) / float(np.max(new.p))
        if change <= tol:
            break
        changes.append(change)
        if len(changes) > NEWTON_STALL_AFTER and change <= NEWTON_STALL and \
                min(changes[-NEWTON_STALL_AFTER:]) >= 0.5 * min(changes[:-NEWTON_STALL_AFTER]):
            break     # settled at the accuracy of the contact solves
        p_k = new.p if it < NEWTON_UNDAMPED else 0.5 * (p_k + new.p)
    else:
        raise SolverError(f"implicit wear step: the Newton iteration of the pressure exponent "
                          f"did not converge in {NEWTON_MAX} iterations (last change "
                          f"{change:.2e} of max p)")
    new.f = base + eff * wear_speed(model, new.p)
    new.iterations = iterations
    return new


class Wear(stepping.Problem):
    """The BEM's implicit wear step on its pixel grid, as :mod:`numerics.stepping` steps it.

    The whole step of a doubled step and its first half start from the
    pressure extrapolated linearly in s from the last two accepted states
    to their own end; the second half starts from the whole step's
    solution, which is at its end already. ``cg_iterations`` counts every
    solve's iterations. A guess's displacement G p is the same combination
    of the states' displacements (the pixels the extrapolation clips to
    zero added by direct sums), so a solve starts without a convolution.
    """

    def __init__(self, model: Model, start: State):
        self.model = model
        self.points = [(0.0, start)]     # the last two accepted states and their s
        self.cg_iterations = start.iterations

    def _guess(self, s):
        """The pressure extrapolated linearly to ``s`` from the last two accepted states,
        and (G p, its error bound), or None when unknown."""
        s1, last = self.points[-1]
        if len(self.points) < 2:
            return last.p, displacement_of(last)
        s0, before = self.points[0]
        ratio = (s - s1) / (s1 - s0)
        linear = last.p + ratio * (last.p - before.p)
        guess = np.maximum(linear, 0.0)
        if not np.any(guess > 0):
            return last.p, displacement_of(last)
        known, earlier = displacement_of(last), displacement_of(before)
        clipped = np.nonzero(linear < 0.0)
        if known is None or earlier is None or len(clipped[0]) > contact.MAX_DIRECT:
            return guess, None
        u = (1.0 + ratio) * known[0] - ratio * earlier[0]
        self.model.op.add_point_loads(u, clipped, -linear[clipped])
        return guess, (u, (1.0 + ratio) * known[1] + ratio * earlier[1])

    def implicit(self, origin, base, h, c, sub):
        # Each solve starts from a guess at its own end (the first half's was
        # extrapolated over the whole step until 2026-11-27). The second half
        # starting from the whole step's solution pulls the two solutions the
        # step doubling compares towards each other only within the solve's
        # tolerance: the error estimates moved by 2e-7 F0 rms against 1e-5
        # (docs/performance.md, BEM)
        if sub.kind == "second":
            p_guess, known = sub.full.p, displacement_of(sub.full)
        else:
            p_guess, known = self._guess(sub.s + h)
        new = implicit_state(self.model, base, c * h, p_guess, known)
        self.cg_iterations += new.iterations
        return new

    def explicit(self, state, h, sub):
        new = contact_state(self.model, state.f + h * wear_speed(self.model, state.p), 0.0,
                            state.p, displacement_of(state))
        self.cg_iterations += new.iterations
        return new

    def profile(self, state):
        return state.f

    def measures(self, state):
        i0, j0 = self.model.centre
        return state.force, state.depth, state.f[i0, j0] - self.model.f0[i0, j0]

    def accepted(self, old, new, h):
        self.points = [self.points[-1], (self.points[-1][0] + h, new)]


def whole_gap(model: Model, state: State) -> np.ndarray:
    """The state's gap on the whole box: where its solve left it unknown (NaN,
    outside the window), f - d + G p (no pressure there, so f is the solve's
    h and there is no wear compliance)."""
    gap = state.gap
    unknown = np.isnan(gap)
    if not np.any(unknown):
        return gap
    gap = gap.copy()
    gap[unknown] = (state.f - state.depth + model.op(state.p))[unknown]
    return gap


def displacement_of(state: State) -> tuple | None:
    """(G p, its error bound) of a state, when its solve returned them."""
    if state.displacement is None:
        return None
    return state.displacement, state.displacement_error


def run(model: Model, plan: stepping.Plan, progress=None, *, ring: tuple | None = None,
        watch=None) -> dict:
    """Step the wear from the unworn state as ``plan`` says.

    ``ring`` = (ring index per pixel, number of rings, radii) adds the
    ``scar_radius`` column (from the ring-averaged wear). Returns the history,
    the stages reached (s, f, p, gap, depth), counters (the stepping's of
    :func:`numerics.stepping.info`, ``cg_iterations``, ``F_start``).
    ``watch(s, contact_radius, scar_radius)`` is called at every recorded step
    (:class:`cases.validity.BodyWatch`).
    """
    area = model.op.spacing**2
    i0, j0 = model.centre
    state = contact_state(model, model.f0.copy())
    if not state.force > 0.0:
        raise SolverError("the unworn indenter carries no load")
    hist = {k: [] for k in ("s", "force", "depth", "contact_radius", "wear_center",
                            "wear_volume", "max_pressure", "cg_iterations",
                            "complementarity_residual", "scar_radius")}
    stages = []

    def record(st, s, reached):
        w = st.f - model.f0
        hist["s"].append(s)
        hist["force"].append(st.force)
        hist["depth"].append(st.depth)
        hist["contact_radius"].append(math.sqrt(np.count_nonzero(in_contact(model, st.p))
                                                * area / math.pi))
        hist["wear_center"].append(float(w[i0, j0]))
        hist["wear_volume"].append(float(np.sum(w)) * area)
        hist["max_pressure"].append(float(np.max(st.p)))
        hist["cg_iterations"].append(st.iterations)
        hist["complementarity_residual"].append(st.residual)
        hist["scar_radius"].append(ring_scar_radius(ring, w))
        if watch is not None:
            watch(s, hist["contact_radius"][-1], hist["scar_radius"][-1])
        if reached:
            gap = whole_gap(model, st)
        for _ in range(reached):
            stages.append((s, st.f.copy(), st.p.copy(), gap.copy(), st.depth))

    problem = Wear(model, state)
    outcome = stepping.run(problem, state, plan, record, progress)
    counters = dict(stepping.info(outcome, plan), cg_iterations=problem.cg_iterations,
                    F_start=outcome.force_start)
    return dict(history={k: np.asarray(v) for k, v in hist.items()}, stages=stages,
                counters=counters)


def ring_scar_radius(ring, w) -> float:
    """The scar radius of the wear ``w`` (n, n) from its ring averages; ``ring`` =
    (ring index per pixel, number of rings, ring radii), or None: NaN."""
    if ring is None:
        return math.nan
    index, rings, radii = ring
    inside = index < rings
    total = np.bincount(index[inside], w[inside], minlength=rings)
    count = np.maximum(np.bincount(index[inside], minlength=rings), 1)
    return scar_radius(radii, total / count)
