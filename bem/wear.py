"""Gross-slip Reye–Archard wear of the pixel grid (the BEM's time loop).

The state is the worn profile f = f0 + w on the pixels. Over a sliding
increment h each pixel wears by Δw = K p h, K = k μ/σ0 (pressure-driven
Archard wear, the same law as the MDR and FEM solvers), or by
Δw = K σ0 (p/σ0)^n h with a pressure exponent n (implicit steps then
iterate on the linearised law, :func:`implicit_state`).

- explicit Euler: w_{n+1} = w_n + h K p_n, then a static contact solve;
  stable for h K / λ_min(G) <= 2 (:func:`explicit_limit`).
- implicit Euler: p_{n+1} solves the contact problem with the operator
  G + h K I on the profile f_n (gap = f_n - d + (G + hK) p), then
  f_{n+1} = f_n + h K p_{n+1}.
- BDF2 (variable step): the same problem on a f_n + b f_{n-1} with wear
  compliance c h K (:func:`bdf2_coefficients`), started by a short backward
  Euler step and a doubling ramp as in the MDR.
- adaptive (as the MDR's): backward Euler with step doubling. Each step is
  solved once whole and as two halves; their difference (force /F0, depth
  and central wear /max(d0, value)) is the local error estimate; a step
  above ``tolerance`` is halved and retried, one below 0.2·tolerance lets
  the next step double (steps on the ladder 2^k ŝ from 2^-7). The two-half
  state is kept and Richardson's correction (two − whole) is carried into
  the next step's start profile ("deferred" correction).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from wearcheck.cases import SolverError, wear_law
from wearcheck.cases.result import scar_radius

from . import contact
from .operator import HalfSpace
from .tangential import ShearToNormal

#: BDF2: largest ratio of consecutive steps (zero-stable below 1 + √2)
BDF2_MAX_RATIO = 2.0
#: BDF2: first (backward Euler) step as a fraction of the step (as the MDR)
BDF2_FIRST_STEP = 1.0 / 16.0
#: adaptive scheme (as the MDR's): first step in ŝ, the ladder 2^k ŝ it climbs,
#: and the fraction of the tolerance below which the step doubles (the
#: estimate grows as h², fourfold per doubling)
ADAPTIVE_FIRST_STEP_HAT = 2.0 ** -7
ADAPTIVE_GROW_BELOW = 0.2


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


def wear_speed(model: Model, p: np.ndarray) -> np.ndarray:
    """dw/ds = K σ0 (p/σ0)^n (K p for n = 1, Reye–Archard): :func:`cases.wear_law.speed`.

    Reciprocating with coupling: averaged over the two strokes (:func:`stroke_mean`).
    """
    return stroke_mean(model, wear_law.speed(p, model.wear_rate, model.exponent,
                                             model.hardness))


def wear_speed_slope(model: Model, p: np.ndarray) -> np.ndarray:
    """d(dw/ds)/dp divided by K: n (p/σ0)^(n-1)."""
    return wear_law.slope(p, model.exponent, model.hardness)


def bdf2_coefficients(h: float, h_prev: float | None) -> tuple[float, float, float]:
    """Variable-step BDF2: f_{n+1} = a f_n + b f_{n-1} + c h f'_{n+1}; None: backward Euler."""
    if h_prev is None:
        return 1.0, 0.0, 1.0
    w = h / h_prev
    return (1.0 + w) ** 2 / (1.0 + 2.0 * w), -w * w / (1.0 + 2.0 * w), (1.0 + w) / (1.0 + 2.0 * w)


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
                  p_init=None) -> State:
    """Contact of the profile ``base`` (+ wear compliance σ) under the model's load.

    The returned profile is base + σ p (the worn profile of an implicit step),
    base + σ·(stroke mean of p) when reciprocating with coupling: the +x
    stroke's contact is solved with the wear compliance on the stroke mean,
    so p is the +x stroke's pressure on the returned profile, which stays
    exactly symmetric in x (σ must be symmetric in x).
    """
    kw = dict(depth=model.depth, force=model.force, sigma=sigma, p_init=p_init,
              p_scale=model.p_scale, g_scale=model.g_scale, tol=model.tol,
              maxiter=model.maxiter, stroke_mean=reciprocating(model))
    if model.coupling is None:
        c = contact.solve(model.op, base, **kw)
    else:
        c = contact.solve_coupled(model.op, model.coupling.shear, base, model.coupling.mu, **kw)
    check_edge(c.pressure)
    f = base + stroke_mean(model, sigma * c.pressure) if np.any(sigma) else base
    return State(f=f, p=c.pressure, gap=c.gap, depth=c.depth, force=c.force,
                 iterations=c.iterations, residual=c.residual)


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


def implicit_state(model: Model, base: np.ndarray, eff: float, p_guess=None) -> State:
    """One implicit step: the contact of ``base`` + eff·(wear speed at its end).

    eff is the step times the scheme's factor (h for backward Euler, c h for
    BDF2). n = 1: one contact solve with wear compliance eff·K. n != 1: the
    wear speed is linearised about the last iterate (Newton: per-pixel wear
    compliance eff K n (p_k/σ0)^(n-1), base shifted by eff (r(p_k) - r'(p_k)
    p_k)) until p settles; the profile is then base + eff r(p) (reciprocating
    with coupling: r(p) and its linearisation averaged over the two strokes,
    as :func:`contact_state`).
    """
    K = model.wear_rate
    if model.exponent == 1.0:
        return contact_state(model, base, eff * K, p_guess)
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


def run(model: Model, scheme: str, h: float, stage_s, until: str, s_end: float,
        force_fraction: float, progress=None, *, tolerance: float | None = None,
        scales: dict | None = None, ring: tuple | None = None,
        max_steps: int = 2_000_000) -> dict:
    """Step the wear from the unworn state (h, stage_s, s_end in metres of sliding).

    Adaptive: h is the largest step (inf for none), ``tolerance`` and
    ``scales`` (F0, d0, s_hat_per_m) set the error control. ``ring`` =
    (ring index per pixel, number of rings, radii) adds the ``scar_radius``
    column (from the ring-averaged wear). Returns the history, the stages
    reached (s, f, p, gap, depth) and counters.
    """
    area = model.op.spacing**2
    i0, j0 = model.centre
    state = contact_state(model, model.f0.copy())
    F_start = state.force
    if not F_start > 0.0:
        raise SolverError("the unworn indenter carries no load")
    hist = {k: [] for k in ("s", "force", "depth", "contact_radius", "wear_center",
                            "wear_volume", "max_pressure", "cg_iterations",
                            "complementarity_residual", "scar_radius")}
    stages = []
    stage_s = list(stage_s)
    counters = {"steps": 0, "cg_iterations": state.iterations}

    def record(st, s):
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
        if ring is not None:
            index, rings, radii = ring
            inside = index < rings
            total = np.bincount(index[inside], w[inside], minlength=rings)
            count = np.maximum(np.bincount(index[inside], minlength=rings), 1)
            hist["scar_radius"].append(scar_radius(radii, total / count))
        else:
            hist["scar_radius"].append(math.nan)
        while stage_s and stage_s[0] <= s * (1 + 1e-12) + 1e-300:
            stages.append((s, st.f.copy(), st.p.copy(), st.gap.copy(), st.depth))
            stage_s.pop(0)

    ramp = []
    if scheme == "bdf2":
        ramp = [BDF2_FIRST_STEP * h]
        while sum(ramp) < h * (1 - 1e-9):
            ramp.append(sum(ramp))
    adaptive = scheme == "adaptive"
    corr = None              # adaptive: Richardson's correction for the next start
    if adaptive:
        per_m = scales["s_hat_per_m"]
        F0, d0 = scales["F0"], scales["d0"]
        h_cur = min(ADAPTIVE_FIRST_STEP_HAT / per_m, h)
        time_error = 0.0
        counters.update(rejected_steps=0, largest_step_hat=0.0)

    def backward_euler(start_f, p_guess, hn):
        return implicit_state(model, start_f, hn, p_guess)

    def error_of(a, b):
        """Local error estimate between two solutions of one step."""
        wa = a.f[i0, j0] - model.f0[i0, j0]
        return max(abs(a.force - b.force) / F0,
                   abs(a.depth - b.depth) / max(d0, abs(a.depth)),
                   abs(a.f[i0, j0] - b.f[i0, j0]) / max(d0, abs(wa)))

    previous = None          # BDF2: (f_{n-1}, h_{n-1})
    last = None              # (p_{n-1}, h_{n-1}) for the warm start's extrapolation
    s = 0.0
    last_report = -1.0
    record(state, s)
    while True:
        if until == "force_fraction" and s > 0.0 and state.force < force_fraction * F_start:
            break
        if s >= s_end:
            break
        target = s_end
        if stage_s:
            target = min(target, stage_s[0])
        hstep = h_cur if adaptive else h
        if target - s <= hstep * (1 + 1e-9):
            hn = target - s
        elif (scheme == "bdf2" or adaptive) and target - s < 2.0 * hstep:
            hn = 0.5 * (target - s)
        else:
            hn = hstep
        if scheme == "bdf2":
            cap = math.inf if previous is None else BDF2_MAX_RATIO * previous[1]
            if ramp:
                cap = min(cap, ramp.pop(0))
            hn = min(hn, cap)
        # warm start: the pressure extrapolated linearly from the last two steps
        guess = state.p
        if last is not None and scheme != "explicit":
            guess = np.maximum(state.p + (hn / last[1]) * (state.p - last[0]), 0.0)
            if not np.any(guess > 0):
                guess = state.p
        if scheme == "explicit":
            new = contact_state(model, state.f + hn * wear_speed(model, state.p), 0.0, guess)
        elif adaptive:
            on_ladder = hn == h_cur
            start = state.f if corr is None else state.f + corr
            full = backward_euler(start, guess, hn)
            half = backward_euler(start, guess, 0.5 * hn)
            two = backward_euler(half.f, half.p, 0.5 * hn)
            counters["cg_iterations"] += full.iterations + half.iterations
            err = error_of(two, full)
            if err > tolerance and hn > 1e-12 * max(s, hn):
                counters["rejected_steps"] += 1
                counters["cg_iterations"] += two.iterations
                h_cur = 0.5 * hn if on_ladder else min(
                    h_cur, 2.0 ** math.floor(math.log2(0.5 * hn * per_m)) / per_m)
                continue
            # keep the backward-Euler state (monotone at the edge) and carry
            # Richardson's correction into the next step's start profile
            new, corr = two, two.f - full.f
            time_error = max(time_error, err)
            counters["largest_step_hat"] = max(counters["largest_step_hat"], hn * per_m)
            if on_ladder and err < ADAPTIVE_GROW_BELOW * tolerance and 2.0 * hn <= h:
                h_cur = 2.0 * hn
        else:
            if scheme == "bdf2" and previous is not None:
                a, b, c = bdf2_coefficients(hn, previous[1])
                base, eff = a * state.f + b * previous[0], c * hn
            else:
                base, eff = state.f, hn
            new = implicit_state(model, base, eff, guess)
            if scheme == "bdf2":
                previous = (state.f, hn)
        if not np.all(np.isfinite(new.f)) or not math.isfinite(new.force):
            raise SolverError("the wear run produced non-finite values; reduce sliding.step_hat")
        last = (state.p, hn)
        state = new
        s = s + hn if target - s > hn * (1 + 1e-9) else target
        counters["steps"] += 1
        counters["cg_iterations"] += state.iterations
        record(state, s)
        if counters["steps"] >= max_steps:
            raise SolverError(f"the wear run took more than {max_steps} steps; raise "
                              "sliding.step_hat or sliding.tolerance")
        if progress is not None:
            frac = s / s_end if until == "distance" else \
                (1.0 - state.force / F_start) / (1.0 - force_fraction)
            if frac - last_report >= 0.01:
                last_report = frac
                progress(min(max(frac, 0.0), 1.0), f"F/F0 = {state.force / F_start:.3g}")
    counters["F_start"] = F_start
    if adaptive:
        counters["time_error"] = time_error
    return dict(history={k: np.asarray(v) for k, v in hist.items()}, stages=stages,
                counters=counters)
