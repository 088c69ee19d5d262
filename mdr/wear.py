"""Gross-slip Reye–Archard wear steps (paper Eqs. 1, 14-16; physics.md §3-4).

The state is the worn 3D profile f at the nodes. One step over a sliding
increment h raises it by Δf = K p S h, K = k μ/σ0, where S is the slip per
unit sliding (1, or 1 - (μ/G*) T⁻¹[dq/ds] with the tangential correction).

Explicit Euler uses the pressure at the start of the step. Implicit Euler
uses the pressure at its end: on the contact nodes 0..m it solves

    T⁻¹[q/E*] + h K S p = d - f_n,      q = P⁻¹ p,

the contact problem of the 3D compliance plus a diagonal wear compliance
(physics.md §4). T⁻¹ and P⁻¹ are triangular, so on the contact set only their
leading blocks enter, and each is one FFT convolution with a fixed kernel;
the operator's condition number is about 1 + 2.4/Δŝ whatever the grid, so
GMRES needs a handful of iterations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.sparse.linalg import LinearOperator, eigs, gmres

from cases import SolverError

from . import contact, transforms


@dataclass
class Model:
    """A discretised case: grid, unworn profile, material and load."""

    x: np.ndarray           # node radii (N+1), uniform in t = x²
    f0: np.ndarray          # unworn profile at the nodes
    E_star: float
    wear_rate: float        # K = k μ / σ0 [1/Pa]
    depth: float | None     # depth control
    force: float | None     # force control
    tangential: float = 0.0  # μ/G* with the tangential correction, else 0

    @property
    def t(self) -> np.ndarray:
        return self.x**2

    @property
    def dt(self) -> float:
        return float(self.x[-1] ** 2 / (len(self.x) - 1))


@dataclass
class State:
    """The worn profile and its contact at one sliding distance."""

    f: np.ndarray
    depth: float
    q: np.ndarray
    p: np.ndarray
    force: float
    contact_radius: float
    m: int
    slip: np.ndarray | None = None     # slip factor S for the next step
    stats: dict = field(default_factory=dict)


def contact_state(model: Model, f: np.ndarray) -> State:
    """Normal contact of the profile f under the model's depth or force."""
    g = transforms.to_1d(f)
    c = contact.solve_normal(g, model.t, model.dt, model.E_star, model.depth, model.force)
    return State(f=f, depth=c["depth"], q=c["q"], p=c["p"], force=c["force"],
                 contact_radius=c["contact_radius"], m=c["m"])


def _slip(model: Model, old: State, new: State, h: float) -> np.ndarray | None:
    """Slip per unit sliding for the step after ``new`` (paper Eqs. 15-16, lagged one step).

    A 1D spring in gross slip carries μ q/G* of tangential deformation, so it
    slips h - (μ/G*) Δq over a step; Eq. 16 takes that to 3D.
    """
    if model.tangential == 0.0 or h <= 0.0:
        return None
    return 1.0 - model.tangential * transforms.from_1d_exact(new.q - old.q) / h


def explicit_step(model: Model, state: State, h: float) -> State:
    """Forward Euler: wear by the pressure at the start of the step."""
    S = 1.0 if state.slip is None else state.slip
    f = state.f + h * model.wear_rate * S * state.p
    new = contact_state(model, f)
    new.slip = _slip(model, state, new, h)
    return new


def _wear_operator(model: Model, n: int, hK_S: np.ndarray) -> LinearOperator:
    """p -> T⁻¹[P⁻¹ p]/E* + h K S p on the contact nodes 0..n-1."""
    dt, E = model.dt, model.E_star

    def matvec(p):
        p = np.ravel(p)
        return transforms.from_1d_exact(transforms.line_load(p, dt)) / E + hK_S * p

    return LinearOperator((n, n), matvec=matvec, dtype=float)


def _solve(op, rhs, x0, stats):
    it = [0]

    def count(_):
        it[0] += 1

    # rtol 1e-11: far below the spatial error (1e-5 at N = 800) and cheap here
    sol, info = gmres(op, rhs, x0=x0, rtol=1e-11, atol=0.0, restart=40, maxiter=20,
                      callback=count, callback_type="pr_norm")
    stats["gmres_iterations"] = stats.get("gmres_iterations", 0) + it[0]
    if info != 0:
        raise SolverError(f"implicit wear step: GMRES did not converge (info = {info}) on "
                          f"{len(rhs)} contact nodes")
    return sol


def implicit_step(model: Model, state: State, h: float, m_guess: int | None = None) -> State:
    """Backward Euler: wear by the pressure at the end of the step.

    The contact set (nodes 0..m) is found by iterating: solve on a guess,
    grow it where the new 1D profile dips below the depth, shrink it where
    the line load turns negative.
    """
    N = len(model.x) - 1
    E, K = model.E_star, model.wear_rate
    S = np.ones(N + 1) if state.slip is None else state.slip
    m = state.m if m_guess is None else m_guess
    m = max(m, 0)
    stats = {"gmres_iterations": 0, "contact_iterations": 0}
    seen = set()
    tol = 1e-9
    while True:
        stats["contact_iterations"] += 1
        if m >= N - 1:
            raise SolverError("the contact has reached the edge of the MDR domain during "
                              "wear; raise mdr.domain_factor")
        n = m + 1
        op = _wear_operator(model, n, h * K * S[:n])
        x0 = state.p[:n]
        if model.force is None:
            d = model.depth
            p = _solve(op, d - state.f[:n], x0, stats)
        else:
            # p = d p1 + p2 is linear in the unknown depth; the force fixes d
            p1 = _solve(op, np.ones(n), None, stats)
            p2 = _solve(op, -state.f[:n], x0 - state.depth * p1 if x0.any() else None, stats)
            w = transforms.force_weights(N, model.dt)[:n]
            F1 = w @ transforms.line_load(p1, model.dt)
            F2 = w @ transforms.line_load(p2, model.dt)
            d = (model.force - F2) / F1
            p = d * p1 + p2
        q = transforms.line_load(p, model.dt)
        f = state.f.copy()
        f[:n] += h * K * S[:n] * p
        g = transforms.to_1d(f)
        scale = tol * max(d, 1e-300)
        below = np.flatnonzero(d - g[n:] > scale)
        if below.size:
            m_new = n + int(below[-1])
        elif q[m] < -tol * E * d:
            pos = np.flatnonzero(q > 0.0)
            m_new = int(pos[-1]) if pos.size else 0
        else:
            break
        if (m_new, m) in seen or stats["contact_iterations"] > 50:
            raise SolverError(f"implicit wear step: the contact set did not settle "
                              f"(nodes {m} <-> {m_new}); reduce sliding.step_hat")
        seen.add((m_new, m))
        m = m_new
    qq = np.zeros(N + 1)
    qq[:n] = np.maximum(q, 0.0)
    pp = np.zeros(N + 1)
    pp[:n] = p
    new = State(f=f, depth=float(d), q=qq, p=pp, force=transforms.force(qq, model.dt),
                contact_radius=contact.contact_radius(g, d, model.t, m), m=m, stats=stats)
    new.slip = _slip(model, state, new, h)
    if new.slip is not None:
        new.slip = np.asarray(new.slip)
    return new


# -- explicit Euler: stability ----------------------------------------------

def stiffest_rate(model: Model, n: int | None = None) -> float:
    """Largest eigenvalue of the wear rate operator δf -> K E* P T δf on nodes 0..n-1.

    Forward Euler is stable for steps h with h·λ < 2. The default set, the
    whole domain but its last node, bounds every contact set the run can have
    (the stiffest modes sit at the contact edge and stiffen with its radius).
    """
    N = len(model.x) - 1
    n = N if n is None else n
    dt = model.dt

    def matvec(v):
        v = np.ravel(v)
        q = np.zeros(n + 1)
        q[:n] = model.E_star * transforms.to_1d(v)
        return model.wear_rate * transforms.pressure(q, dt)[:n]

    op = LinearOperator((n, n), matvec=matvec, dtype=float)
    if n < 3:
        return float(np.max(np.abs(op.matmat(np.eye(n)))))
    vals = eigs(op, k=1, which="LM", return_eigenvectors=False, tol=1e-6,
                ncv=min(n, 40), maxiter=5000)
    return float(abs(vals[0]))


def oscillation(p: np.ndarray, m: int, run: int = 4, level: float = 1e-3) -> bool:
    """A grid-scale saw-tooth in the pressure on the contact nodes 0..m.

    True when ``run`` consecutive nodes alternate in slope with jumps above
    ``level`` times the peak pressure. A smooth pressure (even with the peak
    near the worn border) has isolated extrema only.
    """
    if m < run + 2:
        return False
    d = np.diff(p[:m + 1])
    big = np.abs(d) > level * np.max(np.abs(p[:m + 1]))
    alt = (d[1:] * d[:-1] < 0.0) & big[1:] & big[:-1]
    if not alt.any():
        return False
    # longest run of consecutive alternations
    edges = np.diff(np.concatenate([[0], alt.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return bool(np.max(ends - starts) >= run)
