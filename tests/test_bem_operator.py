"""BEM half-space operator: Love's coefficients, the DC-FFT convolution, its spectrum."""

import math

import numpy as np
import pytest
from scipy import integrate

from wearcheck.bem.operator import HalfSpace, influence_kernel, rectangle_displacement


def test_square_centre_closed_form():
    # Johnson (1985) §3.5: the centre of a square of side 2c under p sinks
    # (8/π) ln(1 + √2) c p / E*; round-off only
    c, p, E = 0.3, 2.0, 5.0
    u = p * rectangle_displacement(0.0, 0.0, c, c, E)
    assert u == pytest.approx(8.0 / math.pi * math.log(1 + math.sqrt(2)) * c * p / E, rel=1e-13)


@pytest.mark.parametrize("x, y", [(0.0, 0.0), (0.7, 0.2), (-1.9, 0.5), (0.5, 0.25),
                                  (3.0, -4.0), (-0.5, -0.8)])
def test_love_against_quadrature(x, y):
    # Boussinesq's 1/(π E* ρ) integrated over the rectangle numerically (the
    # integrand is split at the point where it is singular; quadrature to 1e-10)
    a, b, E = 0.5, 0.25, 1.0

    def inner(yp, xp):
        return 1.0 / math.hypot(x - xp, y - yp)
    xs = sorted({-a, a, *([x] if -a < x < a else [])})
    ys = sorted({-b, b, *([y] if -b < y < b else [])})
    total = 0.0
    for x0, x1 in zip(xs, xs[1:]):
        for y0, y1 in zip(ys, ys[1:]):
            val, _ = integrate.dblquad(inner, x0, x1, y0, y1, epsabs=1e-12, epsrel=1e-11)
            total += val
    assert rectangle_displacement(x, y, a, b, E) == pytest.approx(total / (math.pi * E),
                                                                  rel=1e-8)


@pytest.mark.parametrize("n", [7, 8])
def test_dcfft_equals_direct_sum(n):
    # the zero-padded FFT convolution is the non-periodic sum over the box,
    # to round-off: compare with the dense influence matrix, evaluated at
    # every offset (the kernel is evaluated on one quadrant and mirrored)
    dx, E = 0.1, 3.0
    op = HalfSpace(n, dx, E)
    c = (np.arange(n) * dx)
    X, Y = np.meshgrid(c, c, indexing="ij")
    G = rectangle_displacement(X.ravel()[:, None] - X.ravel()[None, :],
                               Y.ravel()[:, None] - Y.ravel()[None, :], dx / 2, dx / 2, E)
    p = np.random.default_rng(1).random((n, n))
    assert np.allclose(op(p).ravel(), G @ p.ravel(), rtol=1e-12, atol=0)
    # and the sparse direct sum used for clipped pixels
    u = np.zeros((n, n))
    idx = (np.array([0, 3, 6]), np.array([6, 2, 0]))
    op.add_point_loads(u, idx, np.array([1.0, 2.0, -0.5]))
    q = np.zeros((n, n))
    q[idx] = [1.0, 2.0, -0.5]
    assert np.allclose(u.ravel(), G @ q.ravel(), rtol=1e-12, atol=0)


def test_smallest_eigenvalue_bounds_the_box():
    # the explicit stability limit rests on λ_min(G on any pixel set) >= the
    # symbol's checkerboard value; dense eigenvalues of G on a 24 × 24 box:
    # above it, and within 1 % (the box's own λ_min approaches it as n grows:
    # measured 0.5898, 0.5832, 0.5818 at n = 8, 16, 24)
    n, dx, E = 24, 1.0, 1.0
    op = HalfSpace(n, dx, E)
    c = np.arange(n) * dx
    X, Y = np.meshgrid(c, c, indexing="ij")
    G = rectangle_displacement(X.ravel()[:, None] - X.ravel()[None, :],
                               Y.ravel()[:, None] - Y.ravel()[None, :], 0.5, 0.5, E)
    lam = np.linalg.eigvalsh(G)[0]
    bound = op.smallest_eigenvalue()
    assert bound <= lam <= 1.01 * bound


def test_kernel_layout():
    # offsets ±n never occur inside the box: that row and column are zero
    K = influence_kernel(4, 1.0, 1.0)
    assert K.shape == (8, 8) and np.all(K[4] == 0) and np.all(K[:, 4] == 0)
    assert K[1, 0] == pytest.approx(K[7, 0], rel=1e-14)
    assert K[0, 1] == pytest.approx(K[0, 7], rel=1e-14)
    assert K[1, 0] == pytest.approx(K[0, 1], rel=1e-14)
