"""The contact LCP solver against an independent method (scipy NNLS)."""

import numpy as np
import pytest
from scipy import linalg, optimize

from wearcheck.cases import SolverError
from wearcheck.numerics.superelement import PrefixCholesky, complementarity_residual, solve_lcp


def _problem(n=60, seed=0):
    # a compliance-like SPD matrix: smooth kernel plus a diagonal, nodes
    # ordered by radius; heights of a bumpy paraboloid so that the contact
    # set has holes (exercises the bordered, non-prefix factors)
    rng = np.random.default_rng(seed)
    x = np.linspace(0, 1, n)
    C = np.exp(-np.abs(x[:, None] - x[None, :]) / 0.2) / n + 1e-3 * np.eye(n) / n
    z = 0.5 * x**2 + 0.02 * np.sin(25 * x) ** 2 + 1e-3 * rng.random(n)
    return C, z


def _nnls_reference(C, q):
    # min ½fᵀCf + qᵀf, f >= 0  <=>  min |Lᵀf + L⁻¹q|², f >= 0 with C = L Lᵀ
    L = linalg.cholesky(C, lower=True)
    f, _ = optimize.nnls(L.T, -linalg.solve_triangular(L, q, lower=True), maxiter=50 * len(q))
    return f


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_depth_control_matches_nnls(seed):
    # Two different algorithms for the same strictly convex QP: the unique
    # minimiser agrees to round-off (1e-8 of the largest force), and the
    # returned gaps satisfy complementarity to the stated tolerance.
    C, z = _problem(seed=seed)
    d = 0.2
    res = solve_lcp(PrefixCholesky(C), z, depth=d, gap_scale=d, force_scale=1.0)
    ref = _nnls_reference(C, z - d)
    assert np.max(np.abs(res.f - ref)) < 1e-8 * ref.max()
    gap = z - d + C @ res.f
    assert np.allclose(res.gap, gap, rtol=0, atol=1e-12 * d)
    assert complementarity_residual(res.f, gap, res.f.max(), d) < 1e-9
    holes = np.setdiff1d(np.arange(res.active.max() + 1), res.active)
    assert len(holes) > 0  # the bumpy profile really has a non-prefix contact set


def test_warm_start_from_any_set_gives_the_same_solution():
    C, z = _problem()
    fac = PrefixCholesky(C)
    cold = solve_lcp(fac, z, depth=0.2, gap_scale=0.2, force_scale=1.0)
    for start in ([], [59], list(range(0, 60, 3)), list(range(60))):
        warm = solve_lcp(fac, z, depth=0.2, active=start, gap_scale=0.2, force_scale=1.0)
        assert np.max(np.abs(warm.f - cold.f)) < 1e-9 * cold.f.max()
    again = solve_lcp(fac, z, depth=0.2, active=cold.active, gap_scale=0.2, force_scale=1.0)
    assert again.iterations <= 2  # the right set: one solve, one check


def test_force_control_is_the_inverse_of_depth_control():
    # The total force of a depth-controlled solution, imposed, returns that
    # depth and those forces (1e-9): d is the multiplier of Σf = F.
    C, z = _problem(seed=3)
    fac = PrefixCholesky(C)
    dep = solve_lcp(fac, z, depth=0.15, gap_scale=0.15, force_scale=1.0)
    frc = solve_lcp(fac, z, force=dep.f.sum(), gap_scale=0.15, force_scale=1.0)
    assert abs(frc.depth - 0.15) < 1e-9 * 0.15
    assert np.max(np.abs(frc.f - dep.f)) < 1e-9 * dep.f.max()


def test_no_convergence_is_an_error():
    C, z = _problem()
    with pytest.raises(SolverError, match="did not converge"):
        solve_lcp(PrefixCholesky(C), z, depth=0.2, active=[0], gap_scale=0.2,
                  force_scale=1.0, max_iter=2)


def test_indefinite_compliance_is_an_error():
    with pytest.raises(SolverError, match="positive definite"):
        PrefixCholesky(np.array([[1.0, 2.0], [2.0, 1.0]]))
