"""Node-to-node frictionless contact against a rigid plane: an LCP.

Find forces f >= 0 with gaps g = q + M f >= 0 and f·g = 0, where M = C (the
condensed compliance) or C + diag(D) (implicit wear), q = z + w − d. Under
force control d is an unknown fixed by Σ f = F.

The solver is a primal active-set method of Lawson–Hanson type for the
equivalent convex QP (min ½ fᵀMf + qᵀf, f >= 0), warm-started from a given
active set. Nodes are ordered by radius and contact regions grow from the
pole, so the active set is nearly always a prefix 0..m−1: its Cholesky factor
is the leading block of one factor of the whole M, computed once per M. Extra
active nodes outside the prefix are added by bordering the factor (O(m²) per
node), so the factor is never recomputed from scratch as the contact grows.
"""

from __future__ import annotations

import numpy as np
from scipy import linalg

from wearcheck.cases import SolverError


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
