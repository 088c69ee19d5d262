"""Linear algebra for the implicit wear step: nested-block Cholesky and GMRES.

The implicit step's matrix on the contact nodes 0..n-1 is the leading n×n
block of one matrix of the whole grid, because its factors T⁻¹ (lower) and
P⁻¹ (upper) are triangular; it is a symmetric positive definite matrix plus
a rank-one term (:func:`mdr.transforms.compliance_split`). A Cholesky
factorisation has the same nesting: the factor of a leading block is the
leading block of the factor. So one factorisation serves every contact set:
BLAS solves the leading block in place through its leading dimension (or,
where scipy's BLAS entry points are not reachable, through copies), the
rank-one term by Sherman–Morrison inside the solve, and a factorisation
grows to a larger contact by bordering.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import threading

import numpy as np
from threadpoolctl import ThreadpoolController
from scipy.linalg import solve_triangular
from scipy.linalg.lapack import dpotrf

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
    # dtrsv(uplo, trans, diag, n*, a*, lda*, x*, incx*), called with bytes, byref()s
    # and c_void_p pointers only: declared without argument types, ctypes passes
    # these as they are instead of converting each through its argtype's
    # from_param (half the cost of a call; a solve makes two)
    return _cython_blas("dtrsv", ctypes.CFUNCTYPE(None))


_DTRSV = _dtrsv()
_ONE = ctypes.c_int(1)


def _dtrsm():
    p_int, p_dbl = ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_double)
    return _cython_blas("dtrsm", ctypes.CFUNCTYPE(
        None, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, p_int, p_int,
        p_dbl, ctypes.c_void_p, p_int, ctypes.c_void_p, p_int))


_DTRSM = _dtrsm() if _DTRSV is not None else None


def _trsm_in_place(side: bytes, uplo: bytes, diag: bytes, a: np.ndarray, rows: int,
                   cols: int, b_offset: int, trans: bytes = b"N") -> None:
    """B := op(A)⁻¹ B (side L) or B op(A)⁻¹ (side R), all blocks inside one Fortran
    array; op(A) = A, or Aᵀ with ``trans`` b"T".

    A is the array's leading block, B the rows×cols block starting at flat
    (column-major) element ``b_offset``; no copies (scipy's wrappers copy
    every strided block).
    """
    lda = ctypes.c_int(a.shape[0])
    one = ctypes.c_double(1.0)
    _DTRSM(side, uplo, trans, diag, ctypes.byref(ctypes.c_int(rows)),
           ctypes.byref(ctypes.c_int(cols)), ctypes.byref(one), a.ctypes.data,
           ctypes.byref(lda), a.ctypes.data + 8 * b_offset, ctypes.byref(lda))


class NestedCholesky:
    """Cholesky factor of a symmetric positive definite matrix M whose leading blocks
    are solved as often as the whole, and of M plus a rank-one term.

    M = Uᵀ U with U upper triangular: the factor of a leading block is the
    leading block of U, so one factorisation serves every contact set, as an
    LU without pivoting would, at half its operations (``potrf``: n³/3 against
    ``getrf``'s 2n³/3; a bordering one ``trsm`` instead of two). Only the upper
    triangles of the matrices given are read. ``solve(b)`` solves the leading
    len(b)×len(b) block by two triangular solves (BLAS trsv) in place in the
    factor's storage; ``extend`` grows the factorisation by bordering.

    With :meth:`rank_one` (u, v) it solves M + u vᵀ instead, by Sherman–Morrison
    folded into the solve: with f = U⁻ᵀ u and g = U⁻ᵀ v (nested, like every
    forward solve), (M_n + u_n v_nᵀ)⁻¹ b = U_n⁻¹ (y - f_n (g_n·y)/(1 + g_n·f_n)),
    y = U_n⁻ᵀ b: two dot products and no further triangular solve per block.
    One solve at a time: it solves in a work vector of its own.
    """

    def __init__(self, M: np.ndarray, limit: int | None = None, overwrite: bool = False):
        """``overwrite``: M (a square float64 array in Fortran order) becomes the
        factor's storage, spared a copy."""
        self.n = 0
        self.limit = limit          # the largest size it may grow to (storage is capped there)
        own = overwrite and M.dtype == np.float64 and M.flags.f_contiguous \
            and M.flags.writeable and M.shape[0] == M.shape[1]
        self.u = M if own else np.zeros((0, 0), order="F")
        self.extend(M[:0, :], M)

    def extend(self, A12: np.ndarray, A22: np.ndarray) -> None:
        """Factor [[A11, A12], [A12ᵀ, A22]] from the factor of A11 (the current matrix).

        U12 = U11⁻ᵀ A12 and the Schur complement A22 - U12ᵀ U12 factored:
        n² k + k³/3 operations for k new rows, where factoring afresh costs
        (n + k)³/3.
        """
        n, k = self.n, len(A22)
        m = n + k
        U = self.u
        if m > U.shape[0]:
            size = m if n == 0 else int(1.25 * m) + 8
            if self.limit is not None:
                size = max(m, min(size, self.limit))
            grown = np.empty((size, size), order="F")
            grown[:n, :n] = U[:n, :n]
            U = grown
        if n:
            U[:n, n:m] = A12
            if _DTRSM is not None:
                _trsm_in_place(b"L", b"U", b"N", U, n, k, n * U.shape[0], trans=b"T")
            else:
                U[:n, n:m] = solve_triangular(U[:n, :n], A12, trans="T", lower=False,
                                              check_finite=False)
            U12 = U[:n, n:m]
            S = A22 - U12.T @ U12
        else:
            S = A22
        block = U if m == U.shape[0] and n == 0 else U[n:m, n:m]
        if block is not S:
            block[...] = S
        # in place where the block is a whole array (a system's first factorisation)
        c, info = dpotrf(block, lower=0, clean=0, overwrite_a=1)
        if info != 0:
            raise SolverError("implicit wear step: the contact matrix is not positive "
                              f"definite (Cholesky factorisation failed at row {n + info})")
        if not np.may_share_memory(c, block):
            block[...] = c
        if not np.all(np.isfinite(U[:m, n:m])):
            raise SolverError("implicit wear step: the contact matrix factorisation failed")
        self.u, self.n = U, m
        self._last = None       # (b, U⁻ᵀ b) of the last solve (:meth:`solve`)
        self._rank_one = None   # (f, g, 1 + cumsum(g f)) of :meth:`rank_one`, this size
        # the factor's address and leading dimension for BLAS, read once per growth,
        # and a work vector solved in place at a known address (ndarray.ctypes and
        # ctypes.byref cost microseconds per call, a share of a small run's solves;
        # docs/performance.md)
        self._address, self._lda = U.ctypes.data, ctypes.c_int(U.shape[0])
        self._work = np.empty(U.shape[0])
        self._work_address = self._work.ctypes.data
        self._size = ctypes.c_int(0)
        self._refs = (ctypes.byref(self._size), ctypes.byref(self._lda), ctypes.byref(_ONE))

    #: (the references of the last growth, the factor's and the work vector's
    #: addresses as ctypes pointers) for :meth:`solve`
    _pointers = None

    def _forward_kept(self, x: np.ndarray) -> int:
        """How many leading entries of the forward solve of ``x`` the last solve
        had (its right-hand side agreed there); they are written into ``x``."""
        last = self._last
        if last is None:
            return 0
        b0, y0 = last           # (b0: the bytes of the last right-hand side)
        k = min(len(x), len(y0))
        # compared as bytes: no array temporaries (a -0.0 for a 0.0 only recomputes)
        if not k or x[:k].tobytes() != b0[:8 * k]:
            return 0
        x[:k] = y0[:k]
        return k

    def forward(self, b: np.ndarray) -> np.ndarray:
        """y = U⁻ᵀ b on the leading len(b) nodes (nested: y[:k] depends on b[:k] alone)."""
        n = len(b)
        if _DTRSV is None:
            return solve_triangular(self.u[:n, :n], b, trans="T", lower=False,
                                    check_finite=False)
        y = np.array(b, dtype=float)
        if n:
            _DTRSV(b"U", b"T", b"N", ctypes.byref(ctypes.c_int(n)), ctypes.c_void_p(self._address),
                   ctypes.byref(self._lda), ctypes.c_void_p(y.ctypes.data), ctypes.byref(_ONE))
        return y

    def rank_one(self, u: np.ndarray, v: np.ndarray) -> None:
        """Solve M + u vᵀ from now on (u, v: the term on the factored nodes, len :attr:`n`;
        set again after each :meth:`extend`)."""
        f, g = self.forward(u), self.forward(v)
        denominator = 1.0 + np.cumsum(g * f)
        if not np.all(denominator != 0.0) or not np.all(np.isfinite(denominator)):
            raise SolverError("implicit wear step: the contact matrix is singular "
                              "(Sherman–Morrison denominator 0)")
        # (the denominators as floats: one is read per solve)
        self._rank_one = (f, g, denominator.tolist())

    def backward(self, y: np.ndarray) -> np.ndarray:
        """x = U⁻¹ y on the leading len(y) nodes (a fresh array)."""
        n = len(y)
        if _DTRSV is None:
            return solve_triangular(self.u[:n, :n], y, lower=False, check_finite=False)
        x = np.array(y, dtype=float)
        if n:
            _DTRSV(b"U", b"N", b"N", ctypes.byref(ctypes.c_int(n)), ctypes.c_void_p(self._address),
                   ctypes.byref(self._lda), ctypes.c_void_p(x.ctypes.data), ctypes.byref(_ONE))
        return x

    def solve(self, b: np.ndarray, keep: bool = False) -> np.ndarray:
        """Solve the leading len(b)×len(b) block. ``keep``: keep the forward
        solve for the next call, and use the last kept one where its right-hand
        side shares the leading entries (the contact iteration's solves; not
        worth its comparison where every right-hand side differs, as GMRES's
        preconditioning)."""
        n = len(b)
        if n > self.n:
            raise ValueError(f"NestedCholesky.solve: {n} unknowns, factored {self.n}")
        if _DTRSV is None:
            return self.backward(self._with_rank_one(self.forward(b)))
        if not n:
            return np.zeros(0)
        x = self._work[:n]
        x[...] = b                       # solved in place in the work vector
        size, lda, one = self._refs
        pointers = self._pointers
        if pointers is None or pointers[0] is not self._refs:
            # the factor's and the work vector's addresses as ctypes pointers, made
            # once per growth (extend makes new references)
            pointers = self._pointers = (self._refs, ctypes.c_void_p(self._address),
                                         ctypes.c_void_p(self._work_address))
        _, a, xp = pointers
        # the forward solve y = U⁻ᵀ b is nested: y[:k] depends on b[:k] alone,
        # so a right-hand side that shares its leading entries with the last
        # one's (the contact iteration's next set: the same gap, a node or two
        # more or fewer) keeps that part of y
        if keep:
            b_bytes = x.tobytes()
            k = self._forward_kept(x)
        else:
            k = 0
        if k < n:
            if k:
                x[k:] -= np.dot(x[:k], self.u[:k, k:n])
            self._size.value = n - k
            if k:
                _DTRSV(b"U", b"T", b"N", size,
                       ctypes.c_void_p(self._address + 8 * k * (self._lda.value + 1)), lda,
                       ctypes.c_void_p(self._work_address + 8 * k), one)
            else:
                _DTRSV(b"U", b"T", b"N", size, a, lda, xp, one)
        if keep:
            self._last = (b_bytes, x.copy())
        self._with_rank_one(x)
        self._size.value = n
        _DTRSV(b"U", b"N", b"N", size, a, lda, xp, one)
        return x.copy()

    def _with_rank_one(self, y: np.ndarray) -> np.ndarray:
        """y - f (g·y)/(1 + g·f) on y's nodes, in place (y itself without a rank-one term)."""
        if self._rank_one is not None and len(y):
            f, g, denominator = self._rank_one
            n = len(y)
            y -= f[:n] * (float(np.dot(g[:n], y)) / denominator[n - 1])
        return y


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
