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
from scipy.sparse.linalg import LinearOperator, eigs

from cases import SolverError

from . import contact, linalg, transforms


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


#: largest grid factorised densely; finer grids use it as a coarse-grid preconditioner
DENSE_MAX = 1024


class ImplicitSystem:
    """(T⁻¹ P⁻¹/E* + σ) p = r on the contact nodes, σ = h K S, for any contact set.

    Preconditioner: the nested LU of the same operator (σ = h K) on a grid of
    at most DENSE_MAX + 1 nodes — the grid itself when it is that small, so
    the preconditioner is the exact inverse; otherwise every k-th node, with
    linear interpolation in t between the grids and 1/σ on what the coarse
    grid cannot represent (grid-scale modes, where the wear compliance σ
    dominates the elastic one).
    """

    def __init__(self, model: "Model", h: float, nodes: int | None = None):
        N = len(model.x) - 1
        self.sigma = h * model.wear_rate
        self.dt, self.E = model.dt, model.E_star
        self.k = 1
        while N // self.k > DENSE_MAX:
            self.k *= 2
        self.nc_max = N // self.k + 1
        self.lu = None
        # factorise only the contact sets the run is likely to need; grow on demand
        self._factor(self.nc_max if nodes is None else -(-nodes // self.k) + 1)
        l = np.arange(self.k) / self.k
        self.w0, self.w1 = 1.0 - l, l

    def _factor(self, nc: int) -> None:
        nc = min(nc, self.nc_max)
        A = transforms.compliance_matrix(nc, self.k * self.dt, self.E)
        A[np.diag_indices(nc)] += self.sigma
        self.lu = linalg.NestedLU(A)

    def _coarse_solve(self, rc: np.ndarray) -> np.ndarray:
        if len(rc) > self.lu.n:
            self._factor(max(len(rc), int(1.5 * self.lu.n)))
        return self.lu.solve(rc)

    def matvec(self, p: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        return transforms.from_1d_exact(transforms.line_load(p, self.dt)) / self.E + sigma * p

    def _prolong(self, ec: np.ndarray, n: int) -> np.ndarray:
        e = (np.outer(ec[:-1], self.w0) + np.outer(ec[1:], self.w1)).ravel()
        return np.r_[e, ec[-1]][:n]

    def _restrict(self, r: np.ndarray, nc: int) -> np.ndarray:
        rp = np.zeros((nc - 1) * self.k + 1)
        rp[:len(r)] = r
        Rm = rp[:-1].reshape(nc - 1, self.k)
        rc = np.zeros(nc)
        rc[:-1] += Rm @ self.w0
        rc[1:] += Rm @ self.w1
        rc[-1] += rp[-1]
        return rc / self.k

    def precond(self, r: np.ndarray) -> np.ndarray:
        if self.k == 1:
            return self._coarse_solve(r)
        n = len(r)
        nc = -(-(n - 1) // self.k) + 1
        rc = self._restrict(r, nc)
        smooth = self._prolong(rc, n)
        return self._prolong(self._coarse_solve(rc), n) + (r - smooth) / self.sigma

    def solve(self, r, sigma, x0=None, stats=None):
        """Solve on the contact nodes 0..len(r)-1; sigma is h K S there."""
        exact = self.k == 1 and np.all(sigma == self.sigma)
        if exact:
            return self._coarse_solve(r)
        return linalg.gmres(lambda v: self.matvec(v, sigma), self.precond, r, x0=x0,
                            rtol=1e-9, stats=stats)


def implicit_step(model: Model, state: State, h: float, m_guess: int | None = None,
                  system: ImplicitSystem | None = None) -> State:
    """Backward Euler: wear by the pressure at the end of the step.

    The contact set (nodes 0..m) is found by iterating: solve on a guess,
    grow it where the new 1D profile dips below the depth, shrink it where
    the line load turns negative.
    """
    N = len(model.x) - 1
    E, K = model.E_star, model.wear_rate
    S = np.ones(N + 1) if state.slip is None else state.slip
    system = system or ImplicitSystem(model, h)
    m = max(state.m if m_guess is None else m_guess, 0)
    stats = {"gmres_iterations": 0, "contact_iterations": 0}
    seen = set()
    tol = 1e-9
    while True:
        stats["contact_iterations"] += 1
        if m >= N - 1:
            raise SolverError("the contact has reached the edge of the MDR domain during "
                              "wear; raise mdr.domain_factor")
        n = m + 1
        sigma = h * K * S[:n]
        x0 = state.p[:n]
        if model.force is None:
            d = model.depth
            p = system.solve(d - state.f[:n], sigma, x0, stats)
        else:
            # p = d p1 + p2 is linear in the unknown depth; the force fixes d
            p1 = system.solve(np.ones(n), sigma, None, stats)
            p2 = system.solve(-state.f[:n], sigma, x0 - state.depth * p1, stats)
            w = transforms.force_weights(N, model.dt)[:n]
            F1 = w @ transforms.line_load(p1, model.dt)
            F2 = w @ transforms.line_load(p2, model.dt)
            d = (model.force - F2) / F1
            p = d * p1 + p2
        q = transforms.line_load(p, model.dt)
        f = state.f.copy()
        f[:n] += sigma * p
        g = transforms.to_1d(f)
        below = np.flatnonzero(d - g[n:] > tol * d)
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
