"""Linear algebra for the implicit wear step: nested-block LU and GMRES.

The implicit step's matrix on the contact nodes 0..n-1 is the leading n×n
block of one matrix of the whole grid, because its factors T⁻¹ (lower) and
P⁻¹ (upper) are triangular. An LU factorisation without pivoting has the
same nesting: the factors of a leading block are the leading blocks of the
factors. So one factorisation serves every contact set: BLAS solves the
leading block in place through its leading dimension (or, where scipy's
BLAS entry points are not reachable, a prefix of packed copies), and a
factorisation grows to a larger contact by bordering.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import threading

import numpy as np
from threadpoolctl import ThreadpoolController
from scipy.linalg import lu_factor, solve_triangular
from scipy.linalg.blas import dtpsv

from wearcheck.cases import SolverError


_blas_lock = threading.Lock()
_blas_users = 0
_blas_limiter = None
#: the process's thread pools, found once: finding them reads every loaded
#: library's path (threadpoolctl's threadpool_limits does it per call), a
#: share of a small run's time (docs/performance.md, "The paper case as users
#: run it"); the BLAS libraries are loaded with numpy and scipy.linalg, before
_blas_controller = None


@contextlib.contextmanager
def single_threaded_blas():
    """Run a block with every loaded BLAS limited to one thread (threadpoolctl).

    The solver's dense algebra is small (factorisations of at most ~2000²,
    triangular solves, matrix-vector products); threaded OpenBLAS spins
    against other processes on a shared machine, far slower under load
    (docs/performance.md, "Measurements behind the code"). Re-entrant and
    thread-safe: the first user in sets the
    limit, the last out restores the previous counts, so concurrent solves
    never restore each other's limit mid-run.
    """
    global _blas_users, _blas_limiter, _blas_controller
    with _blas_lock:
        if _blas_users == 0:
            if _blas_controller is None:
                _blas_controller = ThreadpoolController()
            _blas_limiter = _blas_controller.limit(limits=1, user_api="blas")
        _blas_users += 1
    try:
        yield
    finally:
        with _blas_lock:
            _blas_users -= 1
            if _blas_users == 0:
                _blas_limiter.restore_original_limits()
                _blas_limiter = None


def lu_nopivot(M: np.ndarray, block: int = 64) -> np.ndarray:
    """In-place blocked LU without pivoting; returns L (unit, strictly lower) and U in one array."""
    M = np.array(M, dtype=float, order="C")
    n = len(M)
    for k0 in range(0, n, block):
        k1 = min(k0 + block, n)
        for k in range(k0, k1):
            piv = M[k, k]
            if not abs(piv) > 0.0:
                raise SolverError("implicit wear step: zero pivot in the contact matrix")
            M[k + 1:, k] /= piv
            if k + 1 < k1:
                M[k + 1:, k + 1:k1] -= np.outer(M[k + 1:, k], M[k, k + 1:k1])
        if k1 < n:
            M[k0:k1, k1:] = solve_triangular(M[k0:k1, k0:k1], M[k0:k1, k1:], lower=True,
                                             unit_diagonal=True, check_finite=False)
            M[k1:, k1:] -= M[k1:, k0:k1] @ M[k0:k1, k1:]
    return M


def _cython_blas(name: str, signature):
    """A BLAS routine from scipy.linalg.cython_blas as a ctypes function, or None.

    scipy.linalg.blas's wrappers copy any array that is not contiguous, so a
    leading block of a larger matrix costs a copy per call; BLAS itself takes
    the block as it is (its leading dimension). The same capsules are what
    numba reaches scipy's BLAS through.
    """
    try:
        from scipy.linalg import cython_blas
        capsule = cython_blas.__pyx_capi__[name]
        api = ctypes.pythonapi
        api.PyCapsule_GetName.restype = ctypes.c_char_p
        api.PyCapsule_GetName.argtypes = [ctypes.py_object]
        api.PyCapsule_GetPointer.restype = ctypes.c_void_p
        api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
        address = api.PyCapsule_GetPointer(capsule, api.PyCapsule_GetName(capsule))
        return signature(address) if address else None
    except Exception:     # another scipy build or Python: the packed path below
        return None


def _dtrsv():
    p_int = ctypes.POINTER(ctypes.c_int)
    return _cython_blas("dtrsv", ctypes.CFUNCTYPE(
        None, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, p_int,
        ctypes.c_void_p, p_int, ctypes.c_void_p, p_int))


_DTRSV = _dtrsv()
_ONE = ctypes.c_int(1)


def _dtrsm():
    p_int, p_dbl = ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_double)
    return _cython_blas("dtrsm", ctypes.CFUNCTYPE(
        None, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, p_int, p_int,
        p_dbl, ctypes.c_void_p, p_int, ctypes.c_void_p, p_int))


_DTRSM = _dtrsm() if _DTRSV is not None else None


def _trsm_in_place(side: bytes, uplo: bytes, diag: bytes, a: np.ndarray, rows: int,
                   cols: int, b_offset: int) -> None:
    """B := op(A)⁻¹ B (side L) or B A⁻¹ (side R), all blocks inside one Fortran array.

    A is the array's leading block, B the rows×cols block starting at flat
    (column-major) element ``b_offset``; no copies (scipy's wrappers copy
    every strided block).
    """
    lda = ctypes.c_int(a.shape[0])
    one = ctypes.c_double(1.0)
    _DTRSM(side, uplo, b"N", diag, ctypes.byref(ctypes.c_int(rows)),
           ctypes.byref(ctypes.c_int(cols)), ctypes.byref(one), a.ctypes.data,
           ctypes.byref(lda), a.ctypes.data + 8 * b_offset, ctypes.byref(lda))


class Pivoted(Exception):
    """LAPACK's partial pivoting permuted a matrix that :class:`NestedLU` was given to
    factorise in its own storage (``overwrite``): that matrix is overwritten, so the
    factorisation without pivoting needs a fresh copy of it."""


class NestedLU:
    """LU of a matrix whose leading blocks are solved as often as the whole.

    ``solve(b)`` solves the leading len(b)×len(b) block: two triangular
    solves (BLAS trsv) on the leading block of the factors, in place with
    the factors' leading dimension, or, without access to BLAS's own entry
    points, on packed copies of the factors (BLAS tpsv). ``extend`` grows
    the factorisation to a larger leading block of the same matrix by
    bordering, so it can start at the size needed now.
    """

    def __init__(self, M: np.ndarray, limit: int | None = None, overwrite: bool = False):
        """``overwrite``: M (a square float64 array in Fortran order) may become the
        factors' storage, spared a copy; should LAPACK pivot it, :class:`Pivoted` is
        raised (M is then lost) and the caller factors a fresh copy without it."""
        self.n = 0
        self.limit = limit          # the largest size it may grow to (storage is capped there)
        own = overwrite and M.dtype == np.float64 and M.flags.f_contiguous \
            and M.flags.writeable and M.shape[0] == M.shape[1]
        self.lu = M if own else np.zeros((0, 0), order="F")
        self.extend(M[:0, :], M[:, :0], M)

    @staticmethod
    def _factor(M: np.ndarray, out: np.ndarray) -> None:
        """LU of M without pivoting, written to ``out`` (a Fortran-ordered block)."""
        # LAPACK's partial pivoting leaves these matrices (a compliance plus a
        # positive diagonal, or its Schur complements) unpermuted in practice;
        # use it when it does. In place where ``out`` is a whole array: the
        # first factorisation of a system is its largest matrix
        whole = out.flags.f_contiguous and out.base is None
        if whole and out is not M:
            out[...] = M
        lu, piv = lu_factor(out if whole else M, overwrite_a=whole, check_finite=False)
        if np.any(piv != np.arange(len(piv))):
            if out is M:
                raise Pivoted("LAPACK pivoted a matrix factorised in its own storage")
            lu = lu_nopivot(M)
        if lu is not out:
            out[...] = lu

    def extend(self, A12: np.ndarray, A21: np.ndarray, A22: np.ndarray) -> None:
        """Factor [[A11, A12], [A21, A22]] from the factors of A11 (the current matrix).

        U12 = L11⁻¹ A12, L21 = A21 U11⁻¹, and the Schur complement A22 - L21 U12
        factored: 2 n² k + k³ operations for k new rows, where factoring
        afresh costs (n + k)³ (LU without pivoting: the leading factors stay).
        """
        n, k = self.n, len(A22)
        m = n + k
        lu = self.lu
        if m > lu.shape[0]:
            size = m if n == 0 else int(1.25 * m) + 8
            if self.limit is not None:
                size = max(m, min(size, self.limit))
            grown = np.empty((size, size), order="F")
            grown[:n, :n] = lu[:n, :n]
            lu = grown
        if n and _DTRSM is not None:
            lu[:n, n:m] = A12
            lu[n:m, :n] = A21
            ld = lu.shape[0]
            # U12 = L11⁻¹ A12 and L21 = A21 U11⁻¹, in place in the factors' storage
            _trsm_in_place(b"L", b"L", b"U", lu, n, k, n * ld)
            _trsm_in_place(b"R", b"U", b"N", lu, k, n, n)
            S = A22 - lu[n:m, :n] @ lu[:n, n:m]
        elif n:
            F11 = lu[:n, :n]          # L11 below the diagonal, U11 on and above
            U12 = solve_triangular(F11, A12, lower=True, unit_diagonal=True, check_finite=False)
            L21 = solve_triangular(F11, A21.T, trans="T", lower=False,
                                   check_finite=False).T
            S = A22 - L21 @ U12
            lu[:n, n:m] = U12
            lu[n:m, :n] = L21
        else:
            S = A22
        self._factor(S, lu if m == lu.shape[0] and n == 0 else lu[n:m, n:m])
        if not np.all(np.isfinite(lu[n:m, :m])) or not np.all(np.isfinite(lu[:n, n:m])):
            raise SolverError("implicit wear step: the contact matrix factorisation failed")
        self.lu, self.n = lu, m
        self._last = None       # (b, L⁻¹ b) of the last solve (:meth:`solve`)
        # the factors' address and leading dimension for BLAS, read once per
        # growth (ndarray.ctypes is slow for a per-solve call; docs/performance.md)
        self._address, self._lda = lu.ctypes.data, ctypes.c_int(lu.shape[0])
        if _DTRSV is None:
            r, c = np.tril_indices(m)           # ordered by r, then c
            # column-major packed upper storage of U and of Lᵀ: column j holds rows 0..j
            self.U = np.ascontiguousarray(lu[c, r])
            self.Lt = np.ascontiguousarray(lu[r, c])
            self.Lt[np.cumsum(np.arange(1, m + 1)) - 1] = 1.0

    def _forward_kept(self, x: np.ndarray) -> int:
        """How many leading entries of the forward solve of ``x`` the last solve
        had (its right-hand side agreed there); they are written into ``x``."""
        last = self._last
        if last is None:
            return 0
        b0, y0 = last
        k = min(len(x), len(b0))
        if not k or not np.array_equal(x[:k], b0[:k]):
            return 0
        x[:k] = y0[:k]
        return k

    def solve(self, b: np.ndarray, keep: bool = False) -> np.ndarray:
        """Solve the leading len(b)×len(b) block. ``keep``: keep the forward
        solve for the next call, and use the last kept one where its right-hand
        side shares the leading entries (the contact iteration's solves; not
        worth its comparison where every right-hand side differs, as GMRES's
        preconditioning)."""
        n = len(b)
        if n > self.n:
            raise ValueError(f"NestedLU.solve: {n} unknowns, factored {self.n}")
        if _DTRSV is not None:
            x = np.array(b, dtype=float)     # a fresh contiguous copy, solved in place
            if n:
                lda, one = ctypes.byref(self._lda), ctypes.byref(_ONE)
                a, xp = self._address, x.ctypes.data
                # the forward solve y = L⁻¹ b is nested too: y[:k] depends on b[:k]
                # alone, so a right-hand side that shares its leading entries with
                # the last one's (the contact iteration's next set: the same gap,
                # a node or two more or fewer) keeps that part of y
                k = self._forward_kept(x) if keep else 0
                if k < n:
                    if k:
                        x[k:] -= self.lu[k:n, :k] @ x[:k]
                    _DTRSV(b"L", b"N", b"U", ctypes.byref(ctypes.c_int(n - k)),
                           a + 8 * k * (self._lda.value + 1), lda, xp + 8 * k, one)
                if keep:
                    self._last = (np.array(b, dtype=float), x.copy())
                _DTRSV(b"U", b"N", b"N", ctypes.byref(ctypes.c_int(n)), a, lda, xp, one)
            return x
        k = n * (n + 1) // 2
        y = dtpsv(n, self.Lt[:k], b, lower=0, trans=1, diag=1)
        return dtpsv(n, self.U[:k], y, lower=0)


#: an inner (low-precision) solve of :func:`gmres` is asked for at most this
#: relative reduction of the residual it is given: float32 reaches it with
#: room to spare (its products are accurate to ~1e-7; measured
#: docs/mixed-precision.md). A tolerance further away takes several outer passes
INNER_REDUCTION = 1e-4
#: share of the outer tolerance the last inner solve's Arnoldi residual may
#: take; the rest is left to the float32 error of its correction, which is
#: not re-checked: |r_true| <= |r_arnoldi| + γ eps32 |r| for an inner solve on
#: a residual r (eps32 = 2^-24), so the tolerance holds without a float64
#: product when γ eps32 <= (1 - INNER_SHARE) rtol|b|/|r|, which INNER_REDUCTION
#: guarantees up to γ = INNER_ERROR_BOUND = 168, well above the γ measured on
#: the shipped cases; a smaller share costs iterations (docs/mixed-precision.md;
#: docs/performance.md, "Measurements behind the code")
INNER_SHARE = 0.9
INNER_ERROR_BOUND = (1.0 - INNER_SHARE) * INNER_REDUCTION / float(np.finfo(np.float32).eps)
#: after a pass, the float64 residual is accepted at this share of the
#: tolerance, not just under it: a unit response (force control, started from
#: 0) landing just under the tolerance puts its error, multiplied by the depth,
#: into one step's p (docs/performance.md, "Measurements behind the code")
ACCEPT_SHARE = 0.5
#: outer passes of iterative refinement before the float64 GMRES takes over
REFINE_PASSES = 4
#: restarts an inner solve may take before it counts as stagnated
INNER_CYCLES = 3
#: if a list, every solve ended by a trusted pass appends (|r|/|b|, its Arnoldi
#: residual |r_arnoldi|/|r|, the true residual |b - A x|/|r| by a float64
#: product, the passes, the last pass's iterations), r the residual that pass
#: started from: a measurement hook for benchmarks and tests, off in runs (its
#: float64 product costs a tenth of a large run; docs/performance.md,
#: "Measurements behind the code")
REFINE_AUDIT = None


def _cycles(matvec, precond, b, x, tol, restart, maxiter, low):
    """Restarted right-preconditioned GMRES cycles in b's precision until |b - A x| <= tol.

    x None starts from 0 (no product for the first residual). Returns x, the
    last residual norm (the Arnoldi one where the last cycle ended on it),
    the iterations and whether tol was met. ``low``: an inner solve (non-finite
    products end it unconverged instead of raising).
    """
    n, dtype = len(b), b.dtype
    its = 0
    res = np.inf
    for _ in range(maxiter):
        r = b.copy() if x is None else b - matvec(x)
        beta = float(np.linalg.norm(r))
        res = beta
        if beta <= tol:
            return (np.zeros_like(b) if x is None else x), res, its, True
        if not np.isfinite(beta) and low:
            return x, np.inf, its, False
        V = np.empty((restart + 1, n), dtype=dtype)
        Z = np.empty((restart, n), dtype=dtype)
        # the Hessenberg matrix reduced to triangular R by Givens rotations as it
        # grows: the least-squares residual |g[j+1]| at every iteration without a
        # least-squares solve (numpy's lstsq per iteration was a fifth of a
        # pressure exponent's run at N = 100, its GMRES taking 5-6 iterations)
        R = np.zeros((restart, restart))
        cs, sn = [0.0] * restart, [0.0] * restart
        g = [0.0] * (restart + 1)
        g[0] = beta
        V[0] = r / beta
        k = 0
        for j in range(restart):
            its += 1
            Z[j] = precond(V[j])
            w = matvec(Z[j])
            if not np.all(np.isfinite(w)):
                if low:
                    return x, np.inf, its, False
                raise SolverError("implicit wear step: non-finite values in the iterative "
                                  "solve; the case's numbers may lie outside what it can "
                                  "represent")
            h = [0.0] * (j + 1)
            for i in range(j + 1):
                h[i] = float(w @ V[i])
                w -= h[i] * V[i]
            h_next = float(np.linalg.norm(w))
            for i in range(j):
                h[i], h[i + 1] = cs[i] * h[i] + sn[i] * h[i + 1], \
                    -sn[i] * h[i] + cs[i] * h[i + 1]
            rho = math.hypot(h[j], h_next)
            cs[j], sn[j] = (h[j] / rho, h_next / rho) if rho > 0.0 else (1.0, 0.0)
            h[j] = rho
            R[:j + 1, j] = h
            g[j], g[j + 1] = cs[j] * g[j], -sn[j] * g[j]
            res = abs(g[j + 1])
            k = j + 1
            if res <= tol or h_next == 0.0:
                break
            V[j + 1] = w / h_next
        if np.all(np.diag(R)[:k] != 0.0):
            y = solve_triangular(R[:k, :k], np.array(g[:k]), check_finite=False)
        else:       # a breakdown with a singular R: its least-squares solution
            y = np.linalg.lstsq(R[:k, :k], np.array(g[:k]), rcond=None)[0]
        step = y.astype(dtype) @ Z[:len(y)]
        x = step if x is None else x + step
        if res <= tol:
            # the Arnoldi residual is the true one (right preconditioning; MGS
            # over at most `restart` vectors): no product spent to re-check it
            return x, res, its, True
    return x, res, its, False


def _refine(matvec, low, b, x0, rtol, bnorm, restart, stats):
    """Iterative refinement: float64 residuals, float32 GMRES corrections.

    Returns (x, True) with |b - A x| <= rtol |b|, or (x, False), the best x
    so far, when the float32 corrections stop reducing the residual.
    """
    matvec32, precond32 = low
    x = np.zeros_like(b) if x0 is None else np.array(x0, dtype=float)
    r = b.copy() if x0 is None else b - matvec(x)
    rnorm = float(np.linalg.norm(r))
    for k in range(REFINE_PASSES):
        if rnorm <= (1.0 if k == 0 else ACCEPT_SHARE) * rtol * bnorm:
            return x, True
        eta = rtol * bnorm / rnorm
        final = eta >= INNER_REDUCTION
        # the last pass: the Arnoldi residual takes INNER_SHARE of the tolerance,
        # the float32 error of the correction (γ eps32 |r|, γ <= INNER_ERROR_BOUND)
        # the rest; an earlier one reduces what float32 surely can
        target = INNER_SHARE * eta if final else INNER_REDUCTION
        # unit right-hand side: float32's range holds any case's scale
        d, res, its, ok = _cycles(matvec32, precond32, (r / rnorm).astype(np.float32), None,
                                  target, restart, INNER_CYCLES, True)
        if stats is not None:
            stats["gmres_iterations"] = stats.get("gmres_iterations", 0) + its
            stats["gmres_float32_iterations"] = stats.get("gmres_float32_iterations", 0) + its
        if not ok:
            return x, False
        x = x + rnorm * d.astype(float)
        if final:
            if REFINE_AUDIT is not None:
                true = float(np.linalg.norm(b - matvec(x)))
                REFINE_AUDIT.append((rnorm / bnorm, res, true / rnorm, k + 1, its))
            return x, True
        new = b - matvec(x)
        newnorm = float(np.linalg.norm(new))
        if not newnorm <= 10.0 * INNER_REDUCTION * rnorm:
            # float32 stagnates (or the correction is worse than float32 allows)
            return (x if newnorm < rnorm else x - rnorm * d.astype(float)), False
        r, rnorm = new, newnorm
    return x, rnorm <= rtol * bnorm


def gmres(matvec, precond, b, x0=None, rtol=1e-11, restart=30, maxiter=10, stats=None,
          low=None):
    """Right-preconditioned restarted GMRES (modified Gram–Schmidt).

    Returns x with |b - A x| <= rtol |b|; raises SolverError otherwise.
    ``low = (matvec32, precond32)``: the same operator and preconditioner in
    float32; the Krylov iterations then run in float32 inside an iterative
    refinement whose residuals are float64 (:func:`_refine`), the float64
    iterations taking over where float32 stagnates.
    """
    bnorm = np.linalg.norm(b)
    if not np.isfinite(bnorm):
        raise SolverError("implicit wear step: non-finite right-hand side; the case's numbers "
                          "may lie outside what it can represent")
    if bnorm == 0.0:
        return np.zeros_like(b)
    if low is not None:
        x, ok = _refine(matvec, low, b, x0, rtol, bnorm, restart, stats)
        if ok:
            return x
        if stats is not None:
            stats["gmres_float64_fallbacks"] = stats.get("gmres_float64_fallbacks", 0) + 1
        x0 = x
    x = precond(b) if x0 is None else x0.copy()
    x, res, its, ok = _cycles(matvec, precond, b, x, rtol * bnorm, restart, maxiter, False)
    if not ok:
        r = b - matvec(x)
        if np.linalg.norm(r) > rtol * bnorm * 10:
            raise SolverError(f"implicit wear step: GMRES did not converge "
                              f"(residual {np.linalg.norm(r) / bnorm:.2e} after {its} iterations)")
    if stats is not None:
        stats["gmres_iterations"] = stats.get("gmres_iterations", 0) + its
    return x
