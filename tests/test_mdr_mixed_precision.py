"""Float32 Krylov iterations inside float64 iterative refinement (mdr/linalg.py gmres ``low``).

Checked against dense float64 algebra: the implicit step's matrix assembled
(compliance_matrix, built from the kernels independently of the FFT
transforms) and solved by numpy, and residuals measured in float64.
"""

import dataclasses

import numpy as np
import pytest

from wearcheck import cases, mdr
from wearcheck.mdr import linalg, solver, transforms, wear

from test_mdr_wear import make, u_star_of


@pytest.fixture(scope="module")
def system_3000():
    # a contact of ~3000 nodes on a grid above DENSE_MAX: the matrix-free
    # system (float32 Krylov iterations, the default mdr.krylov_precision), its
    # assembled matrix and a right-hand side of the step
    case = make(N=10000)
    model, sc = solver.build_model(case)
    st = wear.contact_state(model, model.f0.copy())
    system = wear.ImplicitSystem(model, 0.05 / sc["s_hat_per_m"])
    assert not system.nested and model.krylov_precision == "float32"
    n = st.m + 1
    A = wear.compliance_block(model, n)
    A[np.diag_indices(n)] += system.sigma
    b = st.depth - model.f0[:n]
    # |A⁻¹|₂ <= sqrt(|A⁻¹|₁ |A⁻¹|_inf) (Hölder), from numpy's inverse
    Ainv = np.linalg.inv(A)
    system.inverse_bound = np.sqrt(np.linalg.norm(Ainv, 1) * np.linalg.norm(Ainv, np.inf))
    # numpy's dense solve of A x = b, made once for the six tolerance/start tests
    system.dense_solution = np.linalg.solve(A, b)
    return system, A, b, st.p[:n]


@pytest.mark.parametrize("rtol", [1e-7, 1e-9, 1e-12])
@pytest.mark.parametrize("start", ["zero", "guess"])
def test_mixed_precision_solve_meets_the_float64_tolerance(system_3000, rtol, start):
    # the answer of float32 iterations must satisfy |b - A x| <= rtol |b| in
    # float64 with the assembled matrix (bound: rtol itself; the FFT and the
    # dense matrix differ by ~1e-15 relative, far below 1e-12), so its error
    # against numpy's dense solve is at most |A⁻¹| rtol |b|
    system, A, b, guess = system_3000
    assert 2500 < len(b) < 3500
    stats = {}
    x = system.solve(b, system.sigma, None if start == "zero" else guess, stats, rtol)
    assert x.dtype == np.float64
    assert np.linalg.norm(b - A @ x) <= rtol * np.linalg.norm(b)
    exact = system.dense_solution
    assert np.linalg.norm(x - exact) <= system.inverse_bound * rtol * np.linalg.norm(b)
    # every iteration was a float32 one: the inner precision did not fall back
    assert stats["gmres_float32_iterations"] == stats["gmres_iterations"] > 0
    assert stats.get("gmres_float64_fallbacks", 0) == 0


def test_float32_products_are_float32_and_accurate(system_3000):
    # the float32 operator: float32 in and out (an upcast anywhere would
    # silently make it a float64 product), within a few float32 roundings of
    # the float64 one relative to the product (measured 5e-8 to 1.1e-7;
    # bound 1e-6 = 17 eps32)
    system, A, b, guess = system_3000
    matvec32, precond32 = system._low(system.sigma, system.sigma)
    rng = np.random.default_rng(1)
    for v in (guess, rng.random(len(b)) * np.max(guess)):
        v32 = (v / np.linalg.norm(v)).astype(np.float32)
        y32 = matvec32(v32)
        assert y32.dtype == np.float32 and precond32(v32).dtype == np.float32
        y = system.matvec(v32.astype(float), system.sigma)
        assert np.linalg.norm(y32 - y) <= 1e-6 * np.linalg.norm(y)
    # the cached spectra are kept per precision
    g = rng.random(3000)
    f64 = transforms.from_1d_exact(g)
    f32 = transforms.from_1d_exact(g.astype(np.float32))
    assert f64.dtype == np.float64 and f32.dtype == np.float32
    assert np.max(np.abs(f32 - f64)) <= 1e-5 * np.max(np.abs(f64))
    np.testing.assert_array_equal(transforms.from_1d_exact(g), f64)


@pytest.mark.parametrize("n", [65, 66, 101, 3001, 4097])
def test_float32_toeplitz_products_by_half_length_transforms(n):
    # float32 products go through two complex FFTs of half the length with
    # the real/complex split folded into the kernel's factors: against the
    # float64 real-FFT product (and, for the smallest, a direct sum), to a few
    # float32 roundings (measured 6e-8 to 1.4e-7 up to n = 65537; bound 1e-6)
    rng = np.random.default_rng(n)
    kernel = transforms._kernel(transforms.abel_kernel_inverse_sum, n)
    x = rng.standard_normal(n)
    for product in (transforms.lower, transforms.upper):
        y64 = product(kernel, x, key="B")
        y32 = product(kernel, x.astype(np.float32), key="B")
        assert y32.dtype == np.float32
        assert np.linalg.norm(y32 - y64) <= 1e-6 * np.linalg.norm(y64)
    if n < 200:
        direct = np.array([kernel[:i + 1][::-1] @ x[:i + 1] for i in range(n)])
        np.testing.assert_allclose(transforms.lower(kernel, x, key="B"), direct,
                                   rtol=0, atol=1e-12 * np.max(np.abs(direct)))


def test_float64_path_stays_callable(system_3000):
    # mdr.krylov_precision = "float64": no float32 iteration at all, same tolerance
    system, A, b, guess = system_3000
    system = wear.ImplicitSystem(dataclasses.replace(system.model, krylov_precision="float64"),
                                 system.sigma / system.model.wear_rate)
    stats = {}
    x = system.solve(b, system.sigma, guess, stats, 1e-9)
    assert np.linalg.norm(b - A @ x) <= 1e-9 * np.linalg.norm(b)
    assert stats["gmres_iterations"] > 0 and "gmres_float32_iterations" not in stats


def test_the_inner_residual_is_trusted_within_its_bound(monkeypatch):
    # the last float32 pass is not re-checked in float64: its true residual is
    # the Arnoldi one plus γ eps32 |r| with γ <= INNER_ERROR_BOUND (168). Audit
    # every refined solve of a small adaptive and fixed-step run on the
    # matrix-free path (and one with the tangential correction: σ per node):
    # each meets its tolerance in float64 and keeps γ in bound
    eps32 = float(np.finfo(np.float32).eps)
    # the tangential correction at a stroke of 5u*: S from 0.68 to 1, σ per node
    stroke = 5.0 * u_star_of(make(N=50, control="force"))
    for kw, rtol in ((dict(scheme="adaptive", tolerance=1e-4), 1e-7),
                     (dict(step_hat=0.15), wear.ACCURATE_RTOL),
                     (dict(step_hat=0.15, tangential=True, stroke=stroke), wear.ACCURATE_RTOL)):
        audit = []
        monkeypatch.setattr(linalg, "REFINE_AUDIT", audit)
        res = mdr.solve(make(N=300, s_hat=2.0, control="force", stages=(0.0, 1.0),
                             linear_solver="iterative", **kw))
        assert len(audit) > 20
        a = np.array(audit)
        assert np.all(a[:, 0] * a[:, 2] <= rtol)          # |b - A x| <= rtol |b|
        gamma = (a[:, 2] - a[:, 1]) / eps32
        assert np.max(gamma) <= linalg.INNER_ERROR_BOUND
        assert res.info["gmres_float32_iterations"] == res.info["gmres_iterations"] > 0
        assert res.info["gmres_float64_fallbacks"] == 0


def test_float64_takes_over_where_float32_cannot():
    # an operator float32 cannot represent well enough (condition 1e8: a
    # float32 copy of it solves to a relative error eps32 cond = 6): the
    # refinement's residual stops falling, float64 GMRES finishes from the
    # best iterate and meets the tolerance (1e-7: float64's own floor here is
    # eps64 cond = 1e-8)
    rng = np.random.default_rng(7)
    n = 200
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    M = (Q * np.logspace(0, -8, n)) @ Q.T
    Minv = (Q / np.logspace(0, -8, n)) @ Q.T
    M32, Minv32 = M.astype(np.float32), Minv.astype(np.float32)
    b = rng.random(n)
    stats = {}
    x = linalg.gmres(lambda v: M @ v, lambda v: Minv @ v, b, rtol=1e-7, stats=stats,
                     low=(lambda v: M32 @ v, lambda v: Minv32 @ v))
    assert np.linalg.norm(b - M @ x) <= 1e-7 * np.linalg.norm(b)
    assert stats["gmres_float64_fallbacks"] == 1
    assert stats["gmres_float32_iterations"] > 0
    assert stats["gmres_iterations"] > stats["gmres_float32_iterations"]


@pytest.mark.parametrize("rtol", [1e-7, 1e-12])
def test_the_implicit_system_falls_back_when_its_float32_solves_stall(system_3000, rtol,
                                                                       monkeypatch):
    # float32 corrections that cannot reduce the residual as asked (here an
    # inner operator with σ off by half, as float32 would be near cond = 1/eps32:
    # each pass leaves a third of the residual): float64 GMRES takes over and
    # the answer meets rtol against the assembled matrix
    system, A, b, guess = system_3000
    low = system._low
    monkeypatch.setattr(system, "_low", lambda sigma, s0: low(1.5 * sigma, s0), raising=False)
    stats = {}
    x = system.solve(b, system.sigma, guess, stats, rtol)
    assert np.linalg.norm(b - A @ x) <= rtol * np.linalg.norm(b)
    assert stats["gmres_float64_fallbacks"] == 1
    assert 0 < stats["gmres_float32_iterations"] < stats["gmres_iterations"]
