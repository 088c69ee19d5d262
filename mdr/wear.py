"""Gross-slip Reye–Archard wear steps (paper Eqs. 1, 14-16; docs/theory.md §4, §7-8).

The state is the worn 3D profile f at the nodes. One step over a sliding
increment h raises it by Δf = K p S h, K = k μ/σ0, where S is the slip per
unit sliding: 1, or with the tangential correction what the springs'
reversal at each stroke end leaves of a stroke ℓ, 1 - T⁻¹[2μq/(G*ℓ)]
(:func:`mdr.tangential.reciprocating_slip`).

Explicit Euler uses the pressure at the start of the step. Implicit Euler
uses the pressure at its end: on the contact nodes 0..m it solves

    T⁻¹[q/E*] + h K S p = d - f_n,      q = P⁻¹ p,

the contact problem of the 3D compliance plus a diagonal wear compliance
(docs/theory.md §7-8). The variable-step BDF2 is the same problem with f_n replaced
by a f_n + b f_{n-1} and h by c h (:func:`numerics.stepping.bdf2_coefficients`).

T⁻¹ and P⁻¹ are triangular, so on the contact set only their leading blocks
enter: solved directly (mdr.linear_solver; "auto": up to DENSE_MAX nodes) one
Cholesky factorisation of the matrix's symmetric part (its rank-one rest by
Sherman–Morrison) serves every contact set (its factor's leading blocks),
started at the present contact and grown by bordering as the contact grows;
solved iteratively (finer grids) each operator is applied as one FFT
convolution and the step solved by GMRES with a coarse-grid preconditioner
(a handful of iterations whatever the grid: the operator's condition number
is about 1 + 2.4/Δŝ), each contact iteration starting from the last one's
pressure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.sparse.linalg import LinearOperator, eigs

from wearcheck.cases import SolverError, wear_law

from . import contact, linalg, tangential, transforms


@dataclass
class Model:
    """A discretised case: grid, unworn profile, material and load."""

    x: np.ndarray           # node radii (N+1), uniform in t = x²
    f0: np.ndarray          # unworn profile at the nodes
    E_star: float
    wear_rate: float        # K = k μ / σ0 [1/Pa]
    depth: float | None     # depth control
    force: float | None     # force control
    tangential: float = 0.0  # μ/G* with the tangential correction (L = μq/G*), else 0
    stroke: float | None = None  # reciprocating stroke ℓ (one way) [m], for the correction
    exponent: float = 1.0    # n of the wear law dw/ds = K σ0 (p/σ0)^n
    hardness: float = 1.0    # σ0 [Pa]; enters only when exponent != 1
    linear_solver: str = "auto"       # mdr.linear_solver (:func:`solves_directly`)
    krylov_precision: str = "float32"  # mdr.krylov_precision (:meth:`ImplicitSystem.solve`)

    def __post_init__(self):
        self.t = self.x**2                              # nodes in t = r²
        self.dt = float(self.t[-1] / (len(self.x) - 1))  # their spacing


@dataclass
class State:
    """The worn profile and its contact at one sliding distance.

    ``q`` (the line load, nodes 0..N) may be given as None with ``dt``: it is
    then formed from p on first use, P⁻¹p clipped at 0 (an implicit step's
    force comes from p itself; only the tangential correction needs q).
    """

    f: np.ndarray
    depth: float
    q: np.ndarray | None
    p: np.ndarray
    force: float
    contact_radius: float
    m: int
    slip: np.ndarray | None = None     # slip per unit sliding S of this state (None: 1)
    stats: dict = field(default_factory=dict)
    #: the reference of the contact checks of steps from this state (:class:`FarGap`)
    gap_reference: "FarGap | None" = field(default=None, repr=False, compare=False)
    dt: float | None = field(default=None, repr=False)


def _line_load_of(state: State) -> np.ndarray:
    q = state._q
    if q is None:
        n = state.m + 1
        q = np.zeros(len(state.p))
        q[:n] = np.maximum(transforms.line_load(state.p[:n], state.dt), 0.0)
        state._q = q
    return q


def _set_line_load(state: State, q) -> None:
    state._q = q


# (a property set after the dataclass is made: its __init__ assigns q through it)
State.q = property(_line_load_of, _set_line_load, doc="The line load q at the nodes (0..N).")


def wear_speed(model: Model, p: np.ndarray) -> np.ndarray:
    """dw/ds = K σ0 (p/σ0)^n (K p for n = 1, Reye–Archard): :func:`cases.wear_law.speed`."""
    return wear_law.speed(p, model.wear_rate, model.exponent, model.hardness)


def wear_speed_slope(model: Model, p: np.ndarray) -> np.ndarray:
    """d(dw/ds)/dp divided by K (the implicit step's factor on h K): n (p/σ0)^(n-1)."""
    return wear_law.slope(p, model.exponent, model.hardness)


def contact_state(model: Model, f: np.ndarray) -> State:
    """Normal contact of the profile f under the model's depth or force."""
    g = transforms.to_1d(f)
    c = contact.solve_normal(g, model.t, model.dt, model.E_star, model.depth, model.force)
    return State(f=f, depth=c["depth"], q=c["q"], p=c["p"], force=c["force"],
                 contact_radius=c["contact_radius"], m=c["m"], slip=slip_factor(model, c["q"]),
                 gap_reference=FarGap(f, g))


def slip_factor(model: Model, q: np.ndarray) -> np.ndarray | None:
    """Slip per unit sliding S(r) under the line load q (None: 1, no correction).

    With the tangential correction the springs reverse their deformation
    ±μq/G* at each stroke end and slide the rest of the stroke
    (:func:`mdr.tangential.reciprocating_slip`).
    """
    if model.tangential == 0.0:
        return None
    return tangential.reciprocating_slip(model.tangential * q, model.stroke)


def explicit_step(model: Model, state: State, h: float) -> State:
    """Forward Euler: wear by the pressure and slip at the start of the step."""
    S = 1.0 if state.slip is None else state.slip
    f = state.f + h * S * wear_speed(model, state.p)
    return contact_state(model, f)


#: largest grid factorised densely (nested Cholesky, exact) with mdr.linear_solver =
#: "auto"; finer grids use GMRES
DENSE_MAX = 2048
#: relative tolerance of the contact conditions (gap and line load, times d)
EDGE_TOL = 1e-9
#: GMRES tolerance of every pass of the contact iteration of fixed-step runs,
#: the floor of adaptive ones (solver.ADAPTIVE_SOLVE_SHARE; far below the
#: spatial error, docs/performance.md "Measurements behind the code"). Each pass starts
#: from the last iterate, so a loose pass while the set is found saves little
#: and, deciding the marginal edge node differently, costs extra passes
#: (docs/performance.md, "Measurements behind the code")
ACCURATE_RTOL = 1e-9
#: a nested factorisation too small for a contact set grows to at least this factor
NESTED_GROWTH = 1.1
#: nodes of the coarse grid that preconditions GMRES on finer grids, at most
#: a quarter of the grid's (the contact holds 40-80 % of the nodes, so the
#: coarse grid stays coarser than the contacts it preconditions also when a
#: small grid is solved iteratively)
COARSE_NODES = 256


def solves_directly(model: Model) -> bool:
    """Whether the implicit steps of ``model`` are factorised (mdr.linear_solver;
    "auto": up to DENSE_MAX nodes) rather than solved by GMRES."""
    if model.linear_solver == "auto":
        return len(model.x) - 1 <= DENSE_MAX
    return model.linear_solver == "direct"


def coarse_nodes(N: int) -> int:
    """Nodes of the coarse grid of the GMRES preconditioner on a grid of N elements."""
    return max(min(COARSE_NODES, N // 4), 2)


_UNIT_COMPLIANCE: dict = {}
_TRANSFERS: dict = {}


def compliance_block(model: Model, n: int, rows: slice = slice(None),
                     cols: slice = slice(None)) -> np.ndarray:
    """A fresh copy of the leading n×n block of the model's compliance matrix
    (Fortran-ordered), or of its part ``[rows, cols]``.

    The matrix is sqrt(Δt)/E* times one of the grid size alone, so that one
    is built once and shared by every grid a growing domain passes through and
    every step size of an adaptive run: building it costs as much as
    factorising. It is built twice as large as asked (at most the whole grid),
    since contacts grow: built at the size asked, a growing contact rebuilt
    it several times (docs/performance.md, "Measurements behind the code").
    A factorisation grown by bordering asks for the new rows and columns only.
    """
    unit = _grown("C", n, model, lambda size: transforms.compliance_matrix(size, 1.0, 1.0), len)
    return np.multiply(unit[:n, :n][rows, cols], math.sqrt(model.dt) / model.E_star, order="F")


def _grown(key: str, n: int, model: Model, build, size_of):
    """The cached unit matrix ``key`` of at least n nodes, built by ``build(size)``
    twice as large as asked (at most the grid) when it is missing or too small;
    ``size_of`` reads the size of what is cached."""
    have = _UNIT_COMPLIANCE.get(key)
    if have is None or size_of(have) < n:
        size = max(n, min(2 * max(n, size_of(have) if have is not None else 0), len(model.x)))
        have = _UNIT_COMPLIANCE[key] = build(size)
    return have


def _unit_split(model: Model, n: int):
    """The cached :func:`transforms.compliance_split` of at least n nodes (grown
    as :func:`compliance_block`'s matrix is: twice as large as asked, at most the grid)."""
    return _grown("split", n, model, transforms.compliance_split, lambda split: len(split[1]))


def symmetric_block(model: Model, n: int, rows: slice = slice(None),
                    cols: slice = slice(None)) -> np.ndarray:
    """A fresh Fortran-ordered copy of the leading n×n block of the symmetric part
    S of the model's compliance matrix C = S + u vᵀ (:func:`transforms.compliance_split`,
    scaled by sqrt(Δt)/E*), or of its part ``[rows, cols]``; only its upper triangle
    holds S."""
    S = _unit_split(model, n)[0]
    return np.multiply(S[:n, :n][rows, cols], math.sqrt(model.dt) / model.E_star, order="F")


def rank_one(model: Model, n: int) -> tuple[np.ndarray, np.ndarray]:
    """u, v of the compliance matrix C = S + u vᵀ on its leading n nodes (fresh arrays)."""
    _, u, v = _unit_split(model, n)
    return u[:n] * (math.sqrt(model.dt) / model.E_star), v[:n].copy()


def coarse_eigen(nc: int):
    """Eigenvalues and eigenvectors (λ, V, V⁻¹) of the unit compliance matrix of nc nodes.

    Cached per process. Measured at nc = 256: real eigenvalues in [0.022,
    27.6] (the matrix is a congruence L D Lᵀ but for its first row), cond(V)
    = 1.09, so the shifted solves through them are as accurate as an LU.
    """
    key = ("eigen", nc)
    out = _UNIT_COMPLIANCE.get(key)
    if out is None:
        lam, V = np.linalg.eig(transforms.compliance_matrix(nc, 1.0, 1.0))
        if np.any(lam.imag != 0.0) or np.any(lam.real <= 0.0):
            raise SolverError("the coarse compliance matrix has non-real or non-positive "
                              "eigenvalues; the preconditioner cannot use them")
        lam, V = lam.real, V.real
        out = _UNIT_COMPLIANCE[key] = (lam, V, np.linalg.inv(V))
    return out


class ImplicitSystem:
    """(T⁻¹ P⁻¹/E* + σ) p = r on the contact nodes, σ = h K S, for any contact set.

    Direct (:func:`solves_directly`): the nested Cholesky factorisation of the
    whole grid's matrix (:class:`linalg.NestedCholesky`) for the run's regular
    step, exact for every contact set. Iterative: GMRES, preconditioned by the
    same operator on a coarse t-uniform grid whose
    contact edge coincides with the fine one (linear interpolation in t
    between the grids) plus 1/σ on what the coarse grid cannot represent
    (grid-scale modes, where the wear compliance σ dominates the elastic one).
    Stage-landing steps (another σ) use the regular step's factors as a
    preconditioner.
    """

    def __init__(self, model: "Model", h: float, nodes: int | None = None,
                 rtol: float = ACCURATE_RTOL):
        N = len(model.x) - 1
        self.sigma = h * model.wear_rate
        self.rtol = rtol        # GMRES's relative residual in the contact iteration
        self.dt, self.E = model.dt, model.E_star
        self.nested = solves_directly(model)
        self.N = N
        self.model = model
        self.lu = None
        if self.nested:
            # factorise only the contact sets the run is likely to need; grow on demand
            self._factor(N + 1 if nodes is None else nodes)
        else:
            self.nc = coarse_nodes(N)
            self._eigen = coarse_eigen(self.nc)

    def _factor(self, n: int) -> None:
        # C + σI = (S + σI) + u vᵀ: the symmetric positive definite S + σI by
        # Cholesky, the rank-one term by Sherman–Morrison inside its solves
        # (linalg.NestedCholesky), half the operations of an LU of the whole
        n = min(n, self.N + 1)
        model = self.model
        if self.lu is None:
            A = symmetric_block(model, n)
            A[np.diag_indices(n)] += self.sigma
            # factorised in A's own storage (A is a fresh copy)
            self.lu = linalg.NestedCholesky(A, limit=self.N + 1, overwrite=True)
        else:
            # bordering: the factor of the smaller block stays (the paper case
            # at N = 800 factored 1.52e9 n³-units sized ahead and refactoring,
            # against 0.63e9 for the blocks its solves needed); only the new
            # columns of the matrix are formed
            k = self.lu.n
            old, new = slice(0, k), slice(k, n)
            A22 = symmetric_block(model, n, new, new)
            A22[np.diag_indices(n - k)] += self.sigma
            self.lu.extend(symmetric_block(model, n, old, new), A22)
        self.lu.rank_one(*rank_one(model, self.lu.n))

    def _nested_solve(self, r: np.ndarray, keep: bool = False) -> np.ndarray:
        if len(r) > self.lu.n:
            self._factor(max(len(r), int(NESTED_GROWTH * self.lu.n)))
        return self.lu.solve(r, keep)

    def matvec(self, p: np.ndarray, sigma) -> np.ndarray:
        return transforms.from_1d_exact(transforms.line_load(p, self.dt)) / self.E + sigma * p

    def _coarse_solve(self, rc: np.ndarray, n: int, sigma: float) -> np.ndarray:
        """(s A1 + σ) e = rc on the coarse grid spanning a contact of n nodes.

        The coarse grid spans the contact (Δt_c = n Δt / nc) and the matrix
        scales as sqrt(Δt)/E*, so every contact set and step size is the
        unit matrix A1 scaled and shifted: solved through A1's eigenvectors,
        computed once (an LU per contact set and step was a noticeable share
        of a large run; docs/performance.md, "Measurements behind the code").
        """
        lam, V, Vinv = self._eigen
        scale = math.sqrt(n * self.dt / self.nc) / self.E
        return V @ ((Vinv @ rc) / (scale * lam + sigma))

    def _transfer(self, n: int):
        """Linear interpolation in t from a coarse grid to a contact of n nodes.

        The coarse grid has nc + 1 nodes spanning the same contact
        (the last one, the contact edge, carries no pressure). Returns the
        coarse cell j of each fine node, its weights (1 - w, w) on the cell's
        ends, the sparse interpolation matrix P (built directly in compressed
        form) and the first fine node of each cell (None when a cell is empty,
        n < nc), which makes the transpose Pᵀ r two segment sums
        (np.add.reduceat), cheaper than building Pᵀ as a matrix or forming
        both with bincounts per GMRES iteration (docs/performance.md,
        "Measurements behind the code"). Cached per contact set.
        """
        cache = _TRANSFERS
        nc = self.nc
        out = cache.get((n, nc))
        if out is None:
            from scipy import sparse

            xi = np.arange(n) * (nc / n)          # fine node -> coarse coordinate
            j = xi.astype(np.int64)
            w1 = xi - j
            w0 = 1.0 - w1
            data = np.empty(2 * n)
            data[0::2], data[1::2] = w0, w1
            cols = np.empty(2 * n, dtype=np.int64)
            cols[0::2], cols[1::2] = j, j + 1
            P = sparse.csr_matrix((data, cols, np.arange(0, 2 * n + 1, 2)), shape=(n, nc + 1))
            starts = np.searchsorted(j, np.arange(nc)) if n >= nc else None
            if len(cache) >= 4:
                # the contact set of one GMRES solve is fixed; a few suffice, and
                # each holds 6n numbers (kept per system, they grew without bound:
                # docs/performance.md, "Measurements behind the code")
                cache.clear()     # (atomic: solves may run in threads)
            out = cache[(n, nc)] = (j, w0, w1, P, starts)
        return out

    def _restrict(self, r: np.ndarray) -> np.ndarray:
        """Pᵀ r on the coarse nodes 0..nc-1 (the edge node's entry dropped)."""
        nc = self.nc
        j, w0, w1, P, starts = self._transfer(len(r))
        if starts is None:
            return (np.bincount(j, r * w0, minlength=nc + 1) +
                    np.bincount(j + 1, r * w1, minlength=nc + 1))[:nc]
        rc = np.add.reduceat(r * w0, starts)
        rc[1:] += np.add.reduceat(r * w1, starts)[:-1]
        return rc

    def _twolevel(self, r: np.ndarray, sigma: float) -> np.ndarray:
        # the coarse solve where the coarse grid resolves r, 1/σ (the wear
        # compliance, dominant at grid scale) on the rest:
        # P A_c⁻¹ R r + (r - P R r)/σ, R = Pᵀ nc/n
        n, nc = len(r), self.nc
        if n <= nc:
            # a contact of fewer nodes than the coarse grid (a fine grid on a wide
            # domain): the coarse grid would be the finer one, and GMRES did not
            # converge in 300 iterations under it (paper case, N = 3000,
            # mdr.domain_factor >= 3.8, <= 104 nodes in the contact); the block
            # itself is small enough to factorise
            return self._block_solve(r, sigma)
        P = self._transfer(n)[3]
        rc = self._restrict(r) * (nc / n)
        ec = self._coarse_solve(rc, n, sigma)
        # the pressure vanishes at the contact edge: coarse node nc carries none
        return r / sigma + P @ np.r_[ec - rc / sigma, 0.0]

    def _block_solve(self, r: np.ndarray, sigma: float) -> np.ndarray:
        """(A_n + σ) e = r with the contact's own n×n block (n <= COARSE_NODES), LU cached."""
        from scipy.linalg import lu_factor, lu_solve
        n = len(r)
        cache = self.__dict__.setdefault("_blocks", {})
        lu = cache.get((n, sigma))
        if lu is None:
            A = compliance_block(self.model, n)
            A[np.diag_indices(n)] += sigma
            if len(cache) >= 8:
                cache.clear()
            lu = cache[(n, sigma)] = lu_factor(A, check_finite=False)
        return lu_solve(lu, np.asarray(r, dtype=float), check_finite=False)

    def unit_response(self, n, sigma, stats, rtol):
        """The solution p1 for a unit right-hand side on nodes 0..n-1 and its force F1.

        Force control: the same for every step with this system's own σ,
        cached per contact set.
        """
        def response():
            p1 = self.solve(np.ones(n), sigma, None, stats, rtol)
            return p1, _force_of(p1, self.N, self.dt, self.exact(sigma))

        if not self.exact(sigma):
            return response()
        cache = self.__dict__.setdefault("_unit", {})
        out = cache.get(n)
        if out is None:
            if len(cache) > 64:
                cache.clear()
            out = cache[n] = response()
        return out

    def exact(self, sigma) -> bool:
        """Whether :meth:`solve` with this sigma is a direct solve (no GMRES)."""
        if not self.nested:
            return False
        if not isinstance(sigma, np.ndarray):      # (not np.ndim: slow in this hot path)
            return sigma == self.sigma
        return bool(np.all(sigma == self.sigma))

    def solve(self, r, sigma, x0=None, stats=None, rtol=1e-9):
        """Solve on the contact nodes 0..len(r)-1; sigma is h K S there.

        rtol: GMRES's relative residual (1e-9: far below the spatial error;
        :data:`ACCURATE_RTOL`).
        """
        low = None
        if self.nested:
            if self.exact(sigma):
                return self._nested_solve(r, keep=True)
            precond = self._nested_solve
        else:
            s0 = float(np.mean(sigma))

            def precond(v):
                return self._twolevel(v, s0)
            if self.model.krylov_precision == "float32":
                low = self._low(sigma, s0)
        return linalg.gmres(lambda v: self.matvec(v, sigma), precond, r, x0=x0,
                            rtol=rtol, stats=stats, low=low)

    def _low(self, sigma, s0):
        """The operator and preconditioner in float32 (products, transforms and
        their cached kernel spectra; the coarse solve stays float64, it is small)."""
        sigma32 = np.float32(sigma) if np.ndim(sigma) == 0 else np.asarray(sigma, np.float32)
        scale = np.float32(1.0 / self.E)

        def matvec32(v):
            return transforms.from_1d_exact(transforms.line_load(v, self.dt)) * scale + \
                sigma32 * v

        def precond32(v):
            return self._twolevel(v, s0).astype(np.float32)
        return matvec32, precond32


#: the contact check computes the 1D profile exactly, by direct sums, on the
#: contact's last node and this many beyond it (a growing contact penetrates
#: there first: the contact iteration's sets grow by a node or two); beyond,
#: a bound against a reference clears the nodes (:class:`FarGap`)
EDGE_WINDOW = 8


class FarGap:
    """The contact condition beyond the contact, without the 1D profile of the whole grid.

    The contact iteration needs the 1D profile g = to_1d(f) beyond the contact
    (nodes n..N) only to see which nodes penetrate (d - g_i > tol·d), and at the
    contact's last node and the next for the contact radius. g is summed
    directly on the window n-1..M-1, M = n + EDGE_WINDOW
    (:func:`transforms.to_1d_rows`; to_1d is triangular, so these need f on
    0..M-1 only). Beyond it f differs from a reference profile f_ref, whose
    g_ref is known on the whole grid, by Δ = f - f_ref, and where Δ is zero
    from node M on, |to_1d(Δ)_i| <= b for every i >= M
    (:func:`transforms.far_bound`). When d - min_{i>=M} g_ref_i + b <= tol·d
    less half the tolerance's size tol·|d|/2 (room for the round-off of g_ref;
    a negative depth's threshold tol·d is below 0), no node beyond the window
    comes within the tolerance; otherwise g is computed on the whole grid and
    becomes the reference: a few full transforms a run instead of one per
    contact iteration (docs/performance.md, "The paper case as users run it").
    One per grid: :func:`contact_state` starts one with its own profile, and
    the states of implicit steps pass it on.
    """

    def __init__(self, f: np.ndarray | None = None, g: np.ndarray | None = None):
        # (f_ref, g_ref, min of g_ref over i..N or None), replaced as one (solves
        # may run in threads)
        self.reference = None if f is None else (np.array(f, dtype=float), g, None)

    def full(self, f: np.ndarray) -> np.ndarray:
        """g = to_1d(f) on the whole grid, kept as the reference."""
        g = transforms.to_1d(f)
        self.reference = (f.copy(), g, None)
        return g

    def clears(self, f: np.ndarray, M: int, d: float, tol: float) -> bool:
        """Whether the bound shows every node i >= M out of contact, by half the
        tolerance (d - g_i <= tol·d - tol·|d|/2)."""
        return self._clears(f, None, M, d, tol)

    def _clears(self, f, delta, M, d, tol) -> bool:
        # (delta: f - f_ref of this reference, or None)
        reference = self.reference
        if reference is None:
            return False
        f_ref, g_ref, g_min = reference
        if g_min is None:
            # (a list: one value is read per check)
            g_min = np.minimum.accumulate(g_ref[::-1])[::-1].tolist()
            self.reference = (f_ref, g_ref, g_min)
        if delta is None:
            delta = f - f_ref
        if np.count_nonzero(delta[M:]):
            return False
        # every node i >= M then has d - g_i <= tol·d less half the tolerance's
        # size: 0.5 tol d for d > 0, 1.5 tol d for a negative depth (whose
        # threshold tol·d lies below 0)
        limit = 0.5 * tol * d if d >= 0.0 else 1.5 * tol * d
        return d - g_min[M] + transforms.far_bound(delta[:M]) <= limit

    def check(self, f: np.ndarray, n: int, d: float, tol: float):
        """The nodes i >= n that penetrate (d - g_i > tol·d; as i - n), and g from
        node n-1 on (at least to node n), or None where the bound alone shows every
        node from n on out of contact (the contact set found: the window's sums
        are spared)."""
        N1 = len(f)
        reference = self.reference
        delta = None if reference is None else f - reference[0]
        if self._clears(f, delta, n, d, tol):
            return _NO_NODES, None
        M = min(n + EDGE_WINDOW, N1)
        if M == N1 or self._clears(f, delta, M, d, tol):
            g = transforms.to_1d_rows(f, n - 1, M)
        else:
            g = self.full(f)[n - 1:]
        return (d - g[1:] > tol * d).nonzero()[0], g


_NO_NODES = np.zeros(0, dtype=np.intp)


def implicit_step(model: Model, state: State, h: float, c: float = 1.0,
                  base: np.ndarray | None = None, m_guess: int | None = None,
                  system: ImplicitSystem | None = None, p_guess: np.ndarray | None = None,
                  far_gap: FarGap | None = None) -> State:
    """An implicit step of length h: wear by the pressure at the end of the step.

    The new profile is ``base + c h K S p`` with p the contact pressure of
    that profile: backward Euler from ``state`` (``base`` = state.f, c = 1),
    or the variable-step BDF2 step (``base`` = a f_n + b f_{n-1},
    :func:`numerics.stepping.bdf2_coefficients`). ``state``: the state the
    step starts from (its contact set and pressure start the solve). The slip
    factor S (tangential correction) is the end state's, as the scheme's wear
    rate at the end of the step is: the step is solved with the start state's
    S and again with the S of its result until S settles (SLIP_TOL; lagged by
    one step instead, S made BDF2 first order: docs/performance.md,
    "Measurements behind the code"). ``system`` must be built
    for c h when it is to be used directly.

    ``p_guess`` (nodes 0..N) starts the iterative solves of finer grids (the
    pressure at the start of the step if None); the result is the same to the
    solver's tolerance. ``far_gap`` (one per grid, kept across steps; None:
    the start state's) spares the full 1D transform of each contact iteration
    (:class:`FarGap`).

    With a pressure exponent n != 1 the wear speed K σ0 (p/σ0)^n is
    linearised about the last iterate (Newton): wear compliance c h K S n
    (p_k/σ0)^(n-1) and a shifted base, repeated until p settles.

    The contact set (nodes 0..m) is found by iterating: solve on a guess,
    grow it where the new 1D profile dips below the depth, shrink it where
    the line load turns negative.
    """
    # full slip everywhere (no tangential correction): a scalar, so the wear
    # compliance is one number and the regular step's factors solve it directly
    S = 1.0 if state.slip is None else state.slip
    if base is None:
        base = state.f
    hc = c * h
    system = system or ImplicitSystem(model, hc)
    m = max(state.m if m_guess is None else m_guess, 0)
    far_gap = far_gap or state.gap_reference or FarGap()
    total = {}
    for _ in range(SLIP_ITERATIONS):
        new = _implicit_step_with_slip(model, state, base, hc, S, system, m, p_guess, far_gap)
        new.gap_reference = far_gap
        for k, v in new.stats.items():
            total[k] = total.get(k, 0) + v
        if model.tangential == 0.0:
            break
        new.slip = slip_factor(model, new.q)
        change = float(np.max(np.abs(new.slip - S)))
        if change <= max(SLIP_TOL, 10.0 * system.rtol):
            break
        S, m, p_guess = new.slip, new.m, new.p
    else:
        raise SolverError(f"implicit wear step: the slip factor of the tangential correction "
                          f"did not settle in {SLIP_ITERATIONS} solves (last change "
                          f"{change:.2e}); reduce sliding.step_hat")
    new.stats = total
    return new


#: the implicit step's slip factor S (tangential correction) is iterated to the
#: end state's until it changes by at most SLIP_TOL, or 10 times the solve's
#: tolerance where that is looser (S is 1 - O(2u*/ℓ); 1e-9 is far below any
#: time error a step may have), in at most SLIP_ITERATIONS solves
SLIP_TOL = 1e-9
SLIP_ITERATIONS = 30


def _implicit_step_with_slip(model, state, base, hc, S, system, m, p_guess, far_gap) -> State:
    """The implicit step from ``base`` with wear compliance hc K S (Newton for n != 1)."""
    if model.exponent == 1.0:
        new = _implicit_solve(model, state, base, hc, S, system, m,
                              state.p if p_guess is None else p_guess, far_gap)
    else:
        p_k, total = state.p, {"gmres_iterations": 0, "contact_iterations": 0}
        ms, changes = [], []
        for it in range(NEWTON_MAX):
            # the slope at p -> 0 vanishes (n > 1): an edge node would then enter
            # the contact unworn and leave it worn, iterate after iterate. Any slope
            # leaves the fixed point p = p_k unchanged, so floor the pressure it is
            # taken at
            slope = wear_speed_slope(model, np.maximum(p_k, NEWTON_FLOOR * np.max(p_k)))
            shift = hc * S * (wear_speed(model, p_k) - model.wear_rate * slope * p_k)
            new = _implicit_solve(model, state, base + shift, hc, S * slope, system, m, p_k,
                                  far_gap)
            for k, v in new.stats.items():
                total[k] = total.get(k, 0) + v
            # converged on the nodes both iterates hold in contact: the outermost
            # node may toggle in and out (no nodal contact set satisfies the
            # conditions exactly there, as for the marginal node of the linear step)
            inner = min(m, new.m)
            change = np.max(np.abs(new.p[:inner] - p_k[:inner])) if inner > 0 else 0.0
            if change <= NEWTON_TOL * np.max(new.p):
                break
            changes.append(change / np.max(new.p))
            if len(changes) > NEWTON_STALL_AFTER and changes[-1] <= NEWTON_STALL and \
                    min(changes[-NEWTON_STALL_AFTER:]) >= 0.5 * min(changes[:-NEWTON_STALL_AFTER]):
                # settled at the accuracy of the linear solves (GMRES to 1e-9 of the
                # residual leaves p to ~1e-7 at n = 3-4): it no longer falls, and it is
                # far below the time error a step may have
                break
            ms.append(new.m)
            if len(ms) >= 6 and len(set(ms[-6:])) == 2 and max(ms[-6:]) - min(ms[-6:]) == 1 \
                    and new.m == max(ms[-6:]) and change <= NEWTON_MARGINAL * np.max(new.p):
                # a settled two-cycle over the outermost node (the marginal node of
                # the linear step): keep it in contact; the iterates differ by less
                # than the grid's own error at the edge
                break
            # the contact set can flip between iterates at the edge: damp after a few
            p_k = new.p if it < NEWTON_UNDAMPED else 0.5 * (p_k + new.p)
            m = new.m
        else:
            raise SolverError(f"implicit wear step: the Newton iteration of the pressure "
                              f"exponent did not converge in {NEWTON_MAX} iterations "
                              f"(last change {change / np.max(new.p):.2e} of max p)")
        # the converged profile by the wear law itself (not its linearisation)
        new.f = base + hc * S * wear_speed(model, new.p)
        new.stats = total
    return new


#: Newton iteration of the pressure exponent: relative change of p that ends it
NEWTON_TOL = 1e-7
NEWTON_MAX = 60
NEWTON_UNDAMPED = 8
NEWTON_FLOOR = 0.05
NEWTON_MARGINAL = 1e-3
#: a change of p below NEWTON_STALL (of max p) that has not halved over the last
#: NEWTON_STALL_AFTER iterations ends the iteration (a pressure exponent can
#: settle into a cycle above NEWTON_TOL: docs/performance.md, "Measurements
#: behind the code")
NEWTON_STALL = 1e-5
NEWTON_STALL_AFTER = 4


def _force_of(p: np.ndarray, N: int, dt: float, direct: bool) -> float:
    """Eq. 12 of the line load P⁻¹ p of a pressure on the leading nodes of a grid of N
    elements: a dot product with p (direct solves), or of the line load itself
    (GMRES: see the end of :func:`_implicit_solve`)."""
    if direct:
        return dt * float(transforms.pressure_force_weights(N)[:len(p)] @ p)
    return float(transforms.force_weights(N, dt)[:len(p)] @ transforms.line_load(p, dt))


def _implicit_solve(model, state, base, hc, S, system, m, p_guess, far_gap) -> State:
    """The linear complementarity problem of one implicit step, contact set included."""
    N = len(model.x) - 1
    E, K = model.E_star, model.wear_rate
    stats = {"gmres_iterations": 0, "contact_iterations": 0}
    seen = set()
    tried = []
    tol = EDGE_TOL
    marginal = None
    x0 = p_guess[:m + 1]
    d_last = state.depth
    while True:
        stats["contact_iterations"] += 1
        if m >= N - 1:
            raise contact.DomainOutgrown("the contact has reached the edge of the MDR domain "
                                         "during wear")
        n = m + 1
        sigma = hc * K * (S[:n] if isinstance(S, np.ndarray) else S)
        direct = system.exact(sigma)      # (a direct solve ignores the start x0)
        if not direct and len(x0) != n:
            # the last iterate's pressure, cut or extended by its edge value: the
            # sets of successive iterations differ by a node or two at the edge
            # (from the step's start pressure instead, each GMRES pass took
            # 8-10 iterations at N = 25600, now about half that)
            x0 = np.concatenate((x0[:n], np.full(max(n - len(x0), 0),
                                                 x0[-1] if len(x0) else 0.0)))
        rtol = system.rtol
        if model.force is None:
            d = model.depth
            p = system.solve(d - base[:n], sigma, x0, stats, rtol)
        else:
            # p = d p1 + p2 is linear in the unknown depth; the force fixes d
            p1, F1 = system.unit_response(n, sigma, stats, rtol)
            p2 = system.solve(-base[:n], sigma, None if direct else x0 - d_last * p1, stats,
                              rtol)
            F2 = _force_of(p2, N, model.dt, direct)
            d = (model.force - F2) / F1
            p = d * p1 + p2
            d_last = d
        x0 = p
        # the line load's edge value exactly: the triangular P⁻¹ has b[0] = 1 on its diagonal
        q_edge = 0.5 * math.pi * math.sqrt(model.dt) * p[m]
        tension = q_edge < -tol * E * d
        if tension and marginal != m:
            # too large a set: shrink it, without the 1D profile of the whole
            # grid (a full transform; at N = 102400 a third of the contact
            # iterations shrink)
            below = ()
        else:
            f = base.copy()
            f[:n] += sigma * p
            below, g = far_gap.check(f, n, d, tol)
        if len(below):
            m_new = n + int(below[-1])
        elif tension:
            m_new = transforms.last_loaded(p)
        else:
            break
        if marginal == m and m_new == m - 1 and \
                -q_edge < 1e-3 * np.max(transforms.line_load(p, model.dt)):
            # the marginal node: slightly tensile in contact, slightly
            # penetrating out of it; keep it in, its line load clipped to 0
            break
        # the edge iteration m -> m_new contracts geometrically: Aitken's
        # extrapolation of the last three iterates jumps close to its limit
        tried.append(m)
        if len(tried) >= 2:
            m0, m1, m2 = tried[-2], tried[-1], m_new
            denom = m2 - 2 * m1 + m0
            if (m1 - m0) * (m2 - m1) > 0 and denom != 0:
                jump = int(round(m0 - (m1 - m0) ** 2 / denom))
                if min(m1, m2) <= jump <= m2 + 4 * abs(m2 - m1) or \
                        max(m1, m2) >= jump >= m2 - 4 * abs(m2 - m1):
                    if jump not in tried:
                        m_new = jump
        if m_new in tried and abs(m_new - m) == 1 and marginal is None:
            # a two-cycle over one node: nodal contact conditions cannot
            # place the edge between nodes, so neither set satisfies them
            marginal = m_new = max(m, m_new)
        elif m_new in tried or stats["contact_iterations"] > 50:
            if m_new in tried and (m_new, m) not in seen:
                seen.add((m_new, m))
            else:
                raise SolverError(_unsettled(model, m, m_new))
        m = m_new
    pp = np.zeros(N + 1)
    pp[:n] = p
    # the line load P⁻¹ p of the pressure found, clipped at 0 (the 1D gap differs
    # from it by T of the solve's residual: round-off for a direct solve, ~1e-6
    # of max q late in a GMRES run). A direct solve forms it only when asked for
    # (State): where p >= 0 it is positive and the force is Eq. 12 of it, a dot
    # product with p. (A GMRES run keeps the force of the line load: one transform
    # among its solve's many, and its steps, continuous in length, follow the
    # force's round-off into the solver's tolerance.)
    if direct and p.min() >= 0.0:
        qq, force = None, _force_of(p, N, model.dt, True)
    else:
        qq = np.zeros(N + 1)
        qq[:n] = np.maximum(transforms.line_load(p, model.dt), 0.0)
        force = transforms.force(qq, model.dt)
    if g is None:       # (the check's bound alone found the set: g at the edge now)
        g = transforms.to_1d_rows(f, m, m + 2)
    return State(f=f, depth=float(d), q=qq, p=pp, force=force,
                 contact_radius=contact.radius_between(float(g[0]), float(g[1]), d,
                                                       model.t[m], model.t[m + 1]),
                 m=m, stats=stats, dt=model.dt)


def _unsettled(model: Model, m: int, m_new: int) -> str:
    """Why the contact set of an implicit step did not settle, and what to do."""
    text = f"implicit wear step: the contact set did not settle (nodes {m} <-> {m_new}"
    lo, hi = sorted((m, m_new))
    if hi - lo > max(UNSETTLED_NODES, UNSETTLED_SHARE * hi):
        # an edge that jumps far is no step size's doing: the set that grows to
        # take in a far penetrating ring is in tension in between, and the one
        # that sheds the tension leaves the ring penetrating
        a, b = (float(model.x[k]) for k in (lo, hi))
        return (f"{text}, edges r = {a:.4g} m and {b:.4g} m): the profile touches in two "
                f"separate regions (a ring or dip of the profile beyond the central "
                f"contact), which the MDR's contact of one radius cannot represent; check "
                f"indenter.profile (its table), or solve the case with the BEM (--solver bem)")
    return f"{text}); reduce sliding.step_hat"


#: an unsettled contact set whose edge jumps by more than this many nodes, and
#: this share of its nodes, is two separate regions of contact, not a step too long
UNSETTLED_NODES = 4
UNSETTLED_SHARE = 0.1


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
