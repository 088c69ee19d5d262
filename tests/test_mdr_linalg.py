"""Nested-block LU and GMRES of the implicit wear step, against numpy.linalg.solve."""

import numpy as np
import pytest

from wearcheck.mdr import linalg, transforms


@pytest.mark.parametrize("blas", ["trsv in place", "packed tpsv"])
def test_nested_lu_solves_every_leading_block(blas, monkeypatch):
    # the implicit step's matrix (compliance + wear compliance) and one that
    # LAPACK would pivot (large sub-diagonal), which takes the unpivoted path;
    # both ways of solving the leading blocks (BLAS reached directly, or the
    # packed copies used where it cannot be)
    if blas == "packed tpsv":
        monkeypatch.setattr(linalg, "_DTRSV", None)
        monkeypatch.setattr(linalg, "_DTRSM", None)
    else:
        assert linalg._DTRSV is not None, "scipy's BLAS entry points are not reachable"
    rng = np.random.default_rng(3)
    A = transforms.compliance_matrix(150, 1e-10, 2e11)
    A[np.diag_indices(150)] += 0.05 * A[0, 0]
    B = rng.random((150, 150)) + 150 * np.eye(150)
    B[1, 0] = 1000.0
    for M in (A, B):
        lu = linalg.NestedLU(M)
        for n in (150, 97, 3, 1):
            b = rng.random(n)
            np.testing.assert_allclose(lu.solve(b), np.linalg.solve(M[:n, :n], b),
                                       rtol=1e-10, atol=1e-12 * np.max(np.abs(b)))


def test_nested_lu_in_its_matrix_storage_solves_or_refuses_a_pivoted_matrix():
    # overwrite=True factorises M in M's own storage (no copy): the same leading
    # block solves as numpy's; a matrix LAPACK pivots is lost by then, so it is
    # refused (linalg.Pivoted) and the caller factors a copy the other way
    rng = np.random.default_rng(7)
    A = np.asfortranarray(transforms.compliance_matrix(120, 1e-10, 2e11))
    A[np.diag_indices(120)] += 0.05 * A[0, 0]
    ref = A.copy()
    lu = linalg.NestedLU(A, overwrite=True)
    assert lu.lu is A                      # factored where it was, not copied
    for n in (120, 61, 1):
        b = rng.random(n)
        np.testing.assert_allclose(lu.solve(b), np.linalg.solve(ref[:n, :n], b),
                                   rtol=1e-10, atol=1e-12 * np.max(np.abs(b)))
    B = np.asfortranarray(rng.random((50, 50)) + 50 * np.eye(50))
    B[1, 0] = 1000.0
    with pytest.raises(linalg.Pivoted):
        linalg.NestedLU(B, overwrite=True)


def test_implicit_system_falls_back_when_lapack_pivots(monkeypatch):
    # the implicit step's factorisation in place meets a pivoting LAPACK: it must
    # factor a fresh block without pivoting and solve as numpy does
    from wearcheck.mdr import wear
    model = wear.Model(x=transforms.grid(100, 1e-4), f0=np.zeros(101), E_star=1e11,
                       wear_rate=1e-13, depth=1e-6, force=None)
    real = linalg.lu_factor

    def pivoting(a, overwrite_a=False, check_finite=True):
        lu, piv = real(a, overwrite_a=overwrite_a, check_finite=check_finite)
        return lu, piv[::-1].copy()          # reported as pivoted
    monkeypatch.setattr(linalg, "lu_factor", pivoting)
    system = wear.ImplicitSystem(model, 1e-5, nodes=60)
    A = wear.compliance_block(model, 60)
    A[np.diag_indices(60)] += system.sigma
    b = np.random.default_rng(8).random(60)
    np.testing.assert_allclose(system.solve(b, system.sigma), np.linalg.solve(A, b),
                               rtol=1e-10, atol=1e-12 * np.max(np.abs(b)))


def test_nested_lu_keeps_the_forward_solve_of_a_shared_leading_part():
    # the contact iteration's next right-hand side is the last one cut or extended
    # (the same gap, a node or two more or fewer): the kept forward solve must
    # give numpy's solution of every such block, and a right-hand side that
    # differs anywhere in its leading part must not reuse it
    rng = np.random.default_rng(9)
    A = transforms.compliance_matrix(200, 1e-10, 2e11)
    A[np.diag_indices(200)] += 0.05 * A[0, 0]
    lu = linalg.NestedLU(A)
    b = rng.random(200)
    for n in (150, 153, 149, 149, 200, 1, 37):
        x = lu.solve(b[:n], keep=True)
        np.testing.assert_allclose(x, np.linalg.solve(A[:n, :n], b[:n]), rtol=1e-10, atol=1e-12)
    c = b.copy()
    c[5] += 1.0
    lu.solve(b[:120], keep=True)
    x = lu.solve(c[:130], keep=True)
    np.testing.assert_allclose(x, np.linalg.solve(A[:130, :130], c[:130]), rtol=1e-10, atol=1e-12)


def test_lu_without_pivoting_matches_numpy():
    rng = np.random.default_rng(4)
    M = rng.random((200, 200)) + 200 * np.eye(200)
    lu = linalg.lu_nopivot(M, block=16)
    L = np.tril(lu, -1) + np.eye(200)
    U = np.triu(lu)
    np.testing.assert_allclose(L @ U, M, rtol=1e-12, atol=1e-10)


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
def test_nested_lu_grown_by_bordering_solves_every_leading_block(blas, monkeypatch):
    # factored in pieces (100, then +30, +1, +119, +50 rows and columns), the
    # factors must solve every leading block as numpy does: the bordering is
    # an exact identity (LU without pivoting), so to round-off
    if blas == "copies":
        monkeypatch.setattr(linalg, "_DTRSM", None)
    rng = np.random.default_rng(6)
    A = transforms.compliance_matrix(300, 1e-10, 2e11)
    A[np.diag_indices(300)] += 0.05 * A[0, 0]
    lu = linalg.NestedLU(A[:100, :100])
    for n1 in (130, 131, 250, 300):
        n0 = lu.n
        lu.extend(A[:n0, n0:n1], A[n0:n1, :n0], A[n0:n1, n0:n1])
        for n in (n1, 129, 77, 1):
            b = rng.random(n)
            np.testing.assert_allclose(lu.solve(b), np.linalg.solve(A[:n, :n], b),
                                       rtol=1e-10, atol=1e-12 * np.max(np.abs(b)))
    with pytest.raises(ValueError):
        lu.solve(np.ones(301))


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
