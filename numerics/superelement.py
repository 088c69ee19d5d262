"""Node-to-node contact on a condensed compliance matrix, and its wear (pure arrays).

A body condensed onto its candidate contact nodes (the FEM's axisymmetric
sphere, a compliance computed by CalculiX) meets a rigid plane node to node:
find forces f >= 0 with gaps g = q + M f >= 0 and f·g = 0, where M = C (the
condensed compliance) or C + diag(D) (implicit wear), q = z + w − d. Under
force control d is an unknown fixed by Σ f = F (:func:`solve_lcp`).

The solver is a primal active-set method of Lawson–Hanson type for the
equivalent convex QP (min ½ fᵀMf + qᵀf, f >= 0), warm-started from a given
active set. Nodes are ordered by radius and contact regions grow from the
pole, so the active set is nearly always a prefix 0..m−1: its Cholesky factor
is the leading block of one factor of the whole M, computed once per M. Extra
active nodes outside the prefix are added by bordering the factor (O(m²) per
node), so the factor is never recomputed from scratch as the contact grows.

Wear (:class:`Superelement`, :func:`run`): each contact node carries a wear
depth w_i that widens its gap and grows as dw_i/ds = K σ0 (p_i/σ0)^n with
the nodal pressure p_i = f_i / A_i (A_i: lumped 2πr-weighted area). The
implicit step of wear compliance c·h is one LCP with M = C + diag(K c h/A)
(Newton on the linearised law for n != 1); :mod:`numerics.stepping` steps it
(docs/theory.md §7, §12; docs/time-stepping.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import linalg

from wearcheck.cases import SolverError, wear_law
from wearcheck.cases.result import scar_radius

from . import stepping

#: relative tolerance on the complementarity residual of every contact solve
LCP_TOL = 1e-9


class PrefixCholesky:
    """Cholesky factors of principal submatrices M_AA of one SPD matrix M."""

    def __init__(self, M: np.ndarray):
        self.M = M
        try:
            self.L = linalg.cholesky(M, lower=True)
        except linalg.LinAlgError:
            raise SolverError("the contact compliance matrix is not positive definite") from None
        self.borderings = 0
        self._prefix: dict[int, np.ndarray] = {}

    def _leading(self, m: int) -> np.ndarray:
        """The leading m×m block of L as a Fortran array (LAPACK would copy a
        strided view on every solve; the active set keeps its size for many
        steps, so a few recent blocks are kept)."""
        L11 = self._prefix.get(m)
        if L11 is None:
            if len(self._prefix) >= 4:
                self._prefix.pop(next(iter(self._prefix)))
            L11 = self._prefix[m] = np.asfortranarray(self.L[:m, :m])
        return L11

    def solver(self, A: np.ndarray):
        """A function b -> M_AA^{-1} b for the sorted index set A."""
        m = int(np.searchsorted(A - np.arange(len(A)), 1))  # length of the prefix 0..m-1
        L11 = self._leading(m)
        E = A[m:]
        if len(E) == 0:
            return lambda b: linalg.cho_solve((L11, True), b, check_finite=False)
        self.borderings += 1
        B = linalg.solve_triangular(L11, self.M[:m][:, E], lower=True, check_finite=False)
        S = self.M[np.ix_(E, E)] - B.T @ B
        try:
            L22 = linalg.cholesky(S, lower=True)
        except linalg.LinAlgError:
            raise SolverError("contact sub-matrix not positive definite (bordering)") from None

        def solve(b):
            y1 = linalg.solve_triangular(L11, b[:m], lower=True, check_finite=False)
            y2 = linalg.solve_triangular(L22, b[m:] - B.T @ y1, lower=True, check_finite=False)
            x2 = linalg.solve_triangular(L22, y2, lower=True, trans="T", check_finite=False)
            x1 = linalg.solve_triangular(L11, y1 - B @ x2, lower=True, trans="T",
                                         check_finite=False)
            return np.concatenate([x1, x2])

        return solve


class ContactResult:
    __slots__ = ("f", "gap", "depth", "active", "iterations", "residual")

    def __init__(self, f, gap, depth, active, iterations, residual):
        self.f, self.gap, self.depth = f, gap, depth
        self.active, self.iterations, self.residual = active, iterations, residual


def complementarity_residual(f, gap, force_scale, gap_scale) -> float:
    """max_i |min(f_i / force_scale, gap_i / gap_scale)|: zero exactly at a solution."""
    return float(np.max(np.abs(np.minimum(f / force_scale, gap / gap_scale)), initial=0.0))


def solve_lcp(factor: PrefixCholesky, z: np.ndarray, *, depth: float | None = None,
              force: float | None = None, active=None, gap_scale: float, force_scale: float,
              tol: float = 1e-9, max_iter: int | None = None) -> ContactResult:
    """Solve the contact LCP for the geometry z (heights incl. wear) [m].

    Give ``depth`` (depth control) or ``force`` (force control). Converged when
    f >= 0 and the complementarity residual (see
    :func:`complementarity_residual`) is below ``tol``; otherwise SolverError.
    """
    M = factor.M
    n = len(z)
    if max_iter is None:
        max_iter = 10 * n + 50
    force_control = force is not None

    def subsolve(A):
        """Forces on A (gap zero there) and the depth."""
        sol = factor.solver(A)
        if force_control:
            x = sol(np.column_stack([np.ones(len(A)), -z[A]]))
            d = (force - x[:, 1].sum()) / x[:, 0].sum()
            return x[:, 1] + d * x[:, 0], d
        return sol(depth - z[A]), depth

    def gaps(fA, A, d):
        # only columns up to the last active node enter (a view: no copy)
        k = int(A[-1]) + 1 if len(A) else 0
        f = np.zeros(k)
        f[A] = fA
        return z - d + M[:, :k] @ f

    A = np.array(sorted(set(np.asarray(active if active is not None else [], int).tolist())),
                 dtype=int)
    if len(A) == 0:
        # cold start: every node, then phase 1 drops those that would pull
        # (a few rounds, unlike growing from one node)
        A = np.arange(n)
    # phase 1: drop nodes that would pull (a warm start may be too large)
    it = 0
    while True:
        it += 1
        if len(A) == 0:
            fA, d = np.empty(0), depth
            break
        fA, d = subsolve(A)
        if np.all(fA >= 0):
            break
        A = A[fA >= 0]
    # phase 2: Lawson–Hanson: add violated nodes, step back when a force turns negative
    single = False
    while True:
        g = gaps(fA, A, d)
        inactive = np.ones(n, bool)
        inactive[A] = False
        viol = np.flatnonzero(inactive & (g < -tol * gap_scale))
        if len(viol) == 0:
            break
        it += 1
        if it > max_iter:
            raise SolverError(f"contact active-set method did not converge in {max_iter} "
                              f"iterations ({len(viol)} nodes still penetrate, worst gap "
                              f"{g[viol].min():.3e} m)")
        J = viol[[np.argmin(g[viol])]] if single else viol
        single = False
        Atry = np.union1d(A, J)
        fold = np.zeros(n)
        fold[A] = fA
        dold = d
        while True:
            fnew, dnew = subsolve(Atry)
            neg = fnew < 0
            if not np.any(neg):
                A, fA, d = Atry, fnew, dnew
                break
            fo = fold[Atry]
            ratio = fo[neg] / (fo[neg] - fnew[neg])
            alpha = float(np.min(ratio))
            if alpha <= 0.0:
                single = True  # degenerate: next time add one node only
            step = fo + alpha * (fnew - fo)
            fold[:] = 0.0
            fold[Atry] = step
            dold = dold + alpha * (dnew - dold)
            keep = step > 0.0
            keep[np.flatnonzero(neg)[np.argmin(ratio)]] = False  # the blocking node leaves
            Atry = Atry[keep]
            it += 1
            if it > max_iter:
                raise SolverError(f"contact active-set method did not converge in {max_iter} "
                                  "iterations (cycling while stepping back)")
            if len(Atry) == 0:
                if force_control:
                    raise SolverError("contact active-set method lost every contact node "
                                      "under force control")
                A, fA, d = Atry, np.empty(0), dold
                break
    f = np.zeros(n)
    f[A] = fA
    # g: the gaps of this (A, fA, d), computed at the top of the last pass
    res = complementarity_residual(f, g, force_scale, gap_scale)
    if not res <= tol * 10:
        raise SolverError(f"contact solution fails complementarity: residual {res:.3e} "
                          f"> {10 * tol:.1e}")
    return ContactResult(f=f, gap=g, depth=d, active=A, iterations=it, residual=res)


# -- wear of the condensed body ------------------------------------------------

def explicit_limit(C: np.ndarray, area: np.ndarray, rate: float) -> float:
    """Largest stable explicit Euler step Δs [m].

    The wear map δw ← (I − rate Δs A⁻¹ S) δw with S = C_AA⁻¹ is stable while
    rate Δs λ_max(A⁻¹ S) < 2. Over the whole candidate arc λ_max is an upper
    bound for any active subset (Schur complement), so the limit is safe.
    λ_max(A⁻¹ C⁻¹) = 1 / λ_min(A^½ C A^½), of order E*/h for node spacing h,
    i.e. Δs_max ≈ C h σ0 / (k μ E*) with C of order one (docs/theory.md §7; the
    constants measured: docs/performance.md, "Measurements behind the code").
    """
    sa = np.sqrt(area)
    lam_min = linalg.eigvalsh(sa[:, None] * C * sa[None, :], subset_by_index=[0, 0])[0]
    return 2.0 * lam_min / rate


def contact_radius(r: np.ndarray, f: np.ndarray, gap: np.ndarray) -> float:
    """Contact radius to sub-node accuracy.

    Between the last loaded node i and the next node the edge is found from
    the gaps of the first two free nodes j, j+1: near a smooth contact edge
    the gap grows like (r − a)^{3/2}, so gap^{2/3} is extrapolated linearly to
    zero; the result is clamped to [r_i, r_j].
    """
    loaded = np.flatnonzero(f > 0)
    if len(loaded) == 0:
        return 0.0
    i = loaded[-1]
    j = i + 1
    if j >= len(r):
        return float(r[i])
    if j + 1 >= len(r):
        return float(r[i])
    t1, t2 = np.cbrt(max(gap[j], 0.0)) ** 2, np.cbrt(max(gap[j + 1], 0.0)) ** 2
    if t2 <= t1:
        return float(r[i])
    a = r[j] - t1 * (r[j + 1] - r[j]) / (t2 - t1)
    return float(min(max(a, r[i]), r[j]))


@dataclass
class State:
    """The wear depth of the contact nodes and their contact."""

    w: np.ndarray
    contact: ContactResult


class Superelement(stepping.Problem):
    """The implicit wear step of a body condensed onto its contact nodes.

    C (n, n) compliance [m/N]; z (n,) unworn heights [m]; r, area (n,) radii
    [m] and lumped areas [m²]; rate K = k μ / σ0 [1/Pa]; ``control`` "depth"
    or "force" with its ``value``; ``center`` (n,) weights giving the wear at
    r = 0 as center @ w (default: node 0). ``exponent`` n and ``hardness``
    σ0: wear speed K σ0 (p/σ0)^n (implicit steps linearise it, Newton).
    Explicit steps stop when the pressure alternates with growing amplitude
    for ``oscillation_steps`` steps. ``arc_key``: the case key that lengthens
    the candidate arc (``fem.contact_factor``), named when the contact reaches
    its end.
    """

    def __init__(self, C, z, r, area, rate, *, control, value, gap_scale, force_scale,
                 pressure_scale, center=None, exponent=1.0, hardness=1.0,
                 oscillation_steps=5, arc_key=None):
        self.C, self.z, self.r, self.area, self.rate = C, z, r, area, rate
        self.kw = {control: value}
        self.gap_scale, self.force_scale = gap_scale, force_scale
        self.pressure_scale = pressure_scale
        self.center = np.eye(1, len(z))[0] if center is None else center
        self.exponent, self.hardness = exponent, hardness
        self.oscillation_steps = oscillation_steps
        self.arc_key = arc_key
        self.factors: dict[float, PrefixCholesky] = {}
        self.counts = dict(lcp_iterations=0, max_residual=0.0, refactorisations=0,
                           borderings=0)
        self._osc = None      # explicit: (p, its last change, alternation counts)

    def speed(self, p):
        """Wear speed dw/ds at nodal pressures p (:func:`cases.wear_law.speed`)."""
        return wear_law.speed(p, self.rate, self.exponent, self.hardness)

    def factor_for(self, eff: float) -> PrefixCholesky:
        """Factor of C + rate·eff/A (eff: the step times the scheme's c; 0: C).

        A new factor is needed only when c·Δs changes: constant steps share one;
        a stage off the step grid adds a few; a factor costs many steps
        (docs/performance.md, "Measurements behind the code"). A step equal
        to a factored one up to round-off (a landing
        on a stage one regular step away) uses its factor. Least recently used
        out: the running step's factor is used every step and must survive a
        landing's.
        """
        eff = next((k for k in self.factors if abs(k - eff) <= 1e-12 * eff), eff)
        fac = self.factors.pop(eff, None)
        if fac is None:
            if len(self.factors) >= 6:
                self.counts["borderings"] += self.factors.pop(next(iter(self.factors))).borderings
            fac = PrefixCholesky(self.C if eff == 0.0 else self.C + np.diag(self.rate * eff /
                                                                              self.area))
            self.counts["refactorisations"] += 1
        self.factors[eff] = fac
        return fac

    def contact(self, zz, fac, active, s=0.0) -> ContactResult:
        """The contact of the heights ``zz`` with the factor ``fac``."""
        res = solve_lcp(fac, zz, active=active, gap_scale=self.gap_scale,
                        force_scale=self.force_scale, tol=LCP_TOL, **self.kw)
        self.counts["lcp_iterations"] += res.iterations
        self.counts["max_residual"] = max(self.counts["max_residual"], res.residual)
        if res.f[-1] > 0:
            raise SolverError(
                f"the contact reached the end of the candidate arc (r = {self.r[-1]:.4g} m) "
                f"at s = {s:.4g} m: the scar outgrew the radius predicted when the mesh was "
                "built; " + (f"increase {self.arc_key}" if self.arc_key else
                             "lengthen the candidate arc"))
        return res

    def unworn(self) -> State:
        """The contact of the unworn body."""
        return State(np.zeros(len(self.z)), self.contact(self.z, self.factor_for(0.0), None))

    def implicit(self, origin, base, h, c, sub):
        """One LCP with compliance C + K c h/A from the wear ``base`` (Newton for n != 1)."""
        eff = c * h
        active = origin.contact.active
        if self.exponent == 1.0:
            res = self.contact(self.z + base, self.factor_for(eff), active, sub.s)
            return State(base + self.rate * eff * res.f / self.area, res)
        p_k = origin.contact.f / self.area
        for _ in range(30):
            slope = wear_law.slope(p_k, self.exponent, self.hardness)
            shift = eff * (self.speed(p_k) - self.rate * slope * p_k)
            fac = PrefixCholesky(self.C + np.diag(self.rate * eff * slope / self.area))
            self.counts["refactorisations"] += 1
            res = self.contact(self.z + base + shift, fac, active, sub.s)
            p = res.f / self.area
            change = np.max(np.abs(p - p_k))
            p_k, active = p, res.active
            if change <= 1e-9 * max(np.max(p), 1e-300):
                break
        else:
            raise SolverError("implicit wear step: the Newton iteration of the pressure "
                              "exponent did not converge in 30 iterations")
        return State(base + eff * self.speed(p_k), res)

    def explicit(self, state, h, sub):
        """Wear by the pressure at the start of the step, then the contact."""
        p_start = state.contact.f / self.area
        w = state.w + h * self.speed(p_start)
        res = self.contact(self.z + w, self.factor_for(0.0), state.contact.active, sub.s)
        p = res.f / self.area
        if self._osc is None:
            self._osc = (p_start, np.zeros(len(p)), np.zeros(len(p), dtype=int))
        p_prev, dp_prev, osc = self._osc
        dp = p - p_prev
        growing = (dp * dp_prev < 0) & (np.abs(dp) > np.abs(dp_prev)) & \
            (np.abs(dp) > 1e-3 * self.pressure_scale)
        osc = np.where(growing, osc + 1, 0)
        if np.any(osc >= self.oscillation_steps):
            i = int(np.argmax(osc))
            raise SolverError(
                f"explicit wear oscillates: the pressure at r = {self.r[i]:.4g} m alternates "
                f"with growing amplitude for {self.oscillation_steps} steps "
                f"(s = {sub.s + h:.4g} m); reduce sliding.step_hat or use sliding.scheme = "
                "\"implicit\"")
        self._osc = (p, dp, osc)
        return State(w, res)

    def profile(self, state):
        return state.w

    def measures(self, state):
        return float(state.contact.f.sum()), state.contact.depth, float(self.center @ state.w)


@dataclass
class WearRun:
    """History, stages and counts of a superelement wear run (SI)."""

    s: list = field(default_factory=list)
    force: list = field(default_factory=list)
    depth: list = field(default_factory=list)
    contact_radius: list = field(default_factory=list)
    wear_center: list = field(default_factory=list)
    wear_volume: list = field(default_factory=list)
    scar_radius: list = field(default_factory=list)
    stages: list = field(default_factory=list)  # (s, f, w, depth, gap)
    lcp_iterations: int = 0
    max_residual: float = 0.0
    refactorisations: int = 0
    borderings: int = 0
    steps: int = 0
    outcome: stepping.Outcome | None = None

    def record(self, s, f, gap, depth, w, stages=0, *, r, area, center) -> None:
        """Append the state at ``s`` (forces f, gaps, depth, wear w of the nodes at radii
        r with lumped areas ``area``; ``center @ w`` the wear at r = 0) to the history,
        and ``stages`` copies of it to the stages."""
        self.s.append(s)
        self.force.append(float(np.sum(f)))
        self.depth.append(depth)
        self.contact_radius.append(contact_radius(r, f, gap))
        self.wear_center.append(float(center @ w))
        self.wear_volume.append(float(area @ w))
        self.scar_radius.append(scar_radius(r, w))
        for _ in range(stages):
            self.stages.append((s, f.copy(), w.copy(), depth, gap.copy()))


def run(problem: Superelement, plan: stepping.Plan, progress=None, watch=None) -> WearRun:
    """Slide and wear ``problem`` as ``plan`` says; the history and the stored stages.

    ``watch(s, contact_radius, scar_radius)`` is called at every recorded step
    (:class:`cases.validity.BodyWatch`). Raises SolverError when the unworn
    body carries no force.
    """
    out = WearRun()
    r, area, center = problem.r, problem.area, problem.center

    def observe(state, s, stages):
        res = state.contact
        out.record(s, res.f, res.gap, res.depth, state.w, stages, r=r, area=area, center=center)
        if watch is not None:
            watch(s, out.contact_radius[-1], out.scar_radius[-1])

    start = problem.unworn()
    if not start.contact.f.sum() > 0:
        raise SolverError("the unworn sphere carries no force")
    outcome = stepping.run(problem, start, plan, observe, progress)
    counts = problem.counts
    counts["borderings"] += sum(f.borderings for f in problem.factors.values())
    problem.factors.clear()
    out.lcp_iterations, out.max_residual = counts["lcp_iterations"], counts["max_residual"]
    out.refactorisations, out.borderings = counts["refactorisations"], counts["borderings"]
    out.steps, out.outcome = outcome.steps, outcome
    return out
