"""Nested-block Cholesky and GMRES of the implicit wear step, against numpy.linalg.solve."""

import numpy as np
import pytest

from wearcheck.mdr import linalg, transforms


def implicit_matrix(n):
    """The implicit step's matrix C + σ (compliance_matrix, the triangular factors'
    product: independent of compliance_split) and its split S + σ, u, v."""
    C = transforms.compliance_matrix(n, 1.0, 1.0)
    S, u, v = transforms.compliance_split(n)
    sigma = 0.05 * C[0, 0]
    C[np.diag_indices(n)] += sigma
    S = S.copy(order="F")
    S[np.diag_indices(n)] += sigma
    return C, S, u, v


def spd_with_rank_one(n, rng):
    """A random symmetric positive definite matrix (upper triangle given, the lower
    one garbage: only the upper may be read) and a rank-one term."""
    X = rng.random((n, n))
    M = X @ X.T + n * np.eye(n)
    u, v = rng.random(n), rng.random(n)
    given = np.asfortranarray(np.triu(M) + np.tril(rng.random((n, n)) * 1e3, -1))
    return M + np.outer(u, v), given, u, v


@pytest.mark.parametrize("blas", ["trsv in place", "copies"])
def test_nested_cholesky_solves_every_leading_block(blas, monkeypatch):
    # the implicit step's matrix (compliance + wear compliance, as its symmetric
    # part and a rank-one term) and a random one with garbage below the
    # diagonal, against numpy's solve of the whole matrix's leading blocks; both
    # ways of solving (BLAS reached directly, or scipy's triangular solves on copies)
    if blas == "copies":
        monkeypatch.setattr(linalg, "_DTRSV", None)
        monkeypatch.setattr(linalg, "_DTRSM", None)
    else:
        assert linalg._DTRSV is not None, "scipy's BLAS entry points are not reachable"
    rng = np.random.default_rng(3)
    C, S, u, v = implicit_matrix(150)
    A, given, a, b_ = spd_with_rank_one(150, rng)
    for whole, M, uu, vv in ((C, S, u, v), (A, given, a, b_)):
        ch = linalg.NestedCholesky(M)
        ch.rank_one(uu, vv)
        for n in (150, 97, 3, 1):
            b = rng.random(n)
            # (tolerance: round-off times the condition numbers, below 1e3 here)
            np.testing.assert_allclose(ch.solve(b), np.linalg.solve(whole[:n, :n], b),
                                       rtol=1e-10, atol=1e-12 * np.max(np.abs(b)))
        # without the rank-one term: the symmetric matrix itself
        plain = linalg.NestedCholesky(M)
        Msym = np.triu(M) + np.triu(M, 1).T
        b = rng.random(80)
        np.testing.assert_allclose(plain.solve(b), np.linalg.solve(Msym[:80, :80], b),
                                   rtol=1e-10, atol=1e-12)


def test_nested_cholesky_in_its_matrix_storage_and_refusing_an_indefinite_matrix():
    # overwrite=True factorises M in M's own storage (no copy), solving the same
    # leading blocks as numpy; a matrix that is not positive definite is refused
    # (a SolverError naming the row), not returned as a factor
    from wearcheck.cases import SolverError
    rng = np.random.default_rng(7)
    C, S, u, v = implicit_matrix(120)
    ch = linalg.NestedCholesky(S, overwrite=True)
    assert ch.u is S                       # factored where it was, not copied
    ch.rank_one(u, v)
    for n in (120, 61, 1):
        b = rng.random(n)
        np.testing.assert_allclose(ch.solve(b), np.linalg.solve(C[:n, :n], b),
                                   rtol=1e-10, atol=1e-12 * np.max(np.abs(b)))
    B = np.asfortranarray(np.eye(50))
    B[30, 30] = -1.0
    with pytest.raises(SolverError, match="not positive definite.*row 31"):
        linalg.NestedCholesky(B)


def test_nested_cholesky_keeps_the_forward_solve_of_a_shared_leading_part():
    # the contact iteration's next right-hand side is the last one cut or extended
    # (the same gap, a node or two more or fewer): the kept forward solve must
    # give numpy's solution of every such block, and a right-hand side that
    # differs anywhere in its leading part must not reuse it
    rng = np.random.default_rng(9)
    C, S, u, v = implicit_matrix(200)
    ch = linalg.NestedCholesky(S)
    ch.rank_one(u, v)
    b = rng.random(200)
    for n in (150, 153, 149, 149, 200, 1, 37):
        x = ch.solve(b[:n], keep=True)
        np.testing.assert_allclose(x, np.linalg.solve(C[:n, :n], b[:n]), rtol=1e-10, atol=1e-12)
    c = b.copy()
    c[5] += 1.0
    ch.solve(b[:120], keep=True)
    x = ch.solve(c[:130], keep=True)
    np.testing.assert_allclose(x, np.linalg.solve(C[:130, :130], c[:130]), rtol=1e-10, atol=1e-12)


def test_gmres_reaches_its_tolerance():
    rng = np.random.default_rng(5)
    n = 120
    M = transforms.compliance_matrix(n, 1e-10, 2e11)
    M[np.diag_indices(n)] += 0.1 * M[0, 0]
    b = rng.random(n)
    d = 1.0 / np.diag(M)
    x = linalg.gmres(lambda v: M @ v, lambda v: d * v, b, rtol=1e-10, restart=10, maxiter=50)
    assert np.linalg.norm(M @ x - b) <= 1e-10 * np.linalg.norm(b) * 1.0001


@pytest.mark.parametrize("blas", ["trsm in place", "copies"])
def test_nested_cholesky_grown_by_bordering_solves_every_leading_block(blas, monkeypatch):
    # factored in pieces (100, then +30, +1, +119, +50 rows and columns), the
    # factor must solve every leading block as numpy does: the bordering is an
    # exact identity (the Cholesky factor of a leading block is the leading
    # block of the factor), so to round-off; the rank-one term set anew each time
    if blas == "copies":
        monkeypatch.setattr(linalg, "_DTRSM", None)
    rng = np.random.default_rng(6)
    C, S, u, v = implicit_matrix(300)
    ch = linalg.NestedCholesky(S[:100, :100])
    for n1 in (130, 131, 250, 300):
        n0 = ch.n
        ch.extend(S[:n0, n0:n1], S[n0:n1, n0:n1])
        ch.rank_one(u[:n1], v[:n1])
        for n in (n1, 129, 77, 1):
            b = rng.random(n)
            np.testing.assert_allclose(ch.solve(b), np.linalg.solve(C[:n, :n], b),
                                       rtol=1e-10, atol=1e-12 * np.max(np.abs(b)))
    with pytest.raises(ValueError):
        ch.solve(np.ones(301))


def test_gmres_reports_non_finite_products_itself(capfd):
    # an operator that overflows (youngs_modulus = 1e300 in a case) must end in
    # one SolverError, before LAPACK's least squares prints its own complaint
    from wearcheck.cases import SolverError
    b = np.ones(50)
    with pytest.raises(SolverError, match="non-finite"):
        linalg.gmres(lambda v: np.full_like(v, np.nan), lambda v: v, b)
    with pytest.raises(SolverError, match="non-finite"):
        linalg.gmres(lambda v: v, lambda v: v, np.full(5, np.inf))
    assert "DLASCL" not in capfd.readouterr().err
