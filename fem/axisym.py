"""Axisymmetric linear elasticity in scikit-fem (no built-in form exists).

Coordinates x = (r, z), displacement u = (u_r, u_z). The strains are
ε_rr = ∂u_r/∂r, ε_zz = ∂u_z/∂z, ε_θθ = u_r/r (hoop strain), γ_rz = ∂u_r/∂z +
∂u_z/∂r, and every integral carries the weight 2πr, so forces are totals over
the full revolution [N]. Quadrature points are interior to the elements, so
r > 0 wherever u_r/r is evaluated.
"""

from __future__ import annotations

import math

import numpy as np
from skfem import BilinearForm, LinearForm


def lame(E, nu):
    """Lamé constants (λ, μ) from Young's modulus and Poisson's ratio."""
    return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


def strains(u, r):
    """(ε_rr, ε_zz, ε_θθ, γ_rz) of a vector field (skfem DiscreteField)."""
    return (u.grad[0, 0], u.grad[1, 1], u[0] / r, u.grad[0, 1] + u.grad[1, 0])


def stresses(eps, lam, mu):
    """(σ_rr, σ_zz, σ_θθ, σ_rz) from (ε_rr, ε_zz, ε_θθ, γ_rz), isotropic Hooke."""
    err, ezz, ett, grz = eps
    tr = err + ezz + ett
    return (lam * tr + 2 * mu * err, lam * tr + 2 * mu * ezz, lam * tr + 2 * mu * ett, mu * grz)


def stiffness_form(E, nu):
    """Bilinear form ∫ ε(v) : σ(u) 2πr dA of axisymmetric elasticity."""
    lam, mu = lame(E, nu)

    @BilinearForm
    def form(u, v, w):
        r = w.x[0]
        su = stresses(strains(u, r), lam, mu)
        ev = strains(v, r)
        return 2.0 * math.pi * r * (su[0] * ev[0] + su[1] * ev[1] + su[2] * ev[2]
                                    + su[3] * ev[3])

    return form


@LinearForm
def boundary_weight(v, w):
    """∫ φ_i 2πr ds on a facet basis: the 2πr-weighted nodal area (row sums)."""
    return 2.0 * math.pi * w.x[0] * v


@BilinearForm
def boundary_mass(u, v, w):
    """Consistent 2πr-weighted boundary mass ∫ φ_i φ_j 2πr ds."""
    return 2.0 * math.pi * w.x[0] * u * v


def traction_form(t_r, t_z):
    """Load ∫ (t_r v_r + t_z v_z) 2πr ds for callables t_r(x), t_z(x) [Pa]."""

    @LinearForm
    def form(v, w):
        r = w.x[0]
        return 2.0 * math.pi * r * (t_r(w.x) * v[0] + t_z(w.x) * v[1])

    return form


def stress_at_quadrature(basis, u, E, nu):
    """(4, Nt, Nq) stresses σ_rr, σ_zz, σ_θθ, σ_rz at the quadrature points."""
    lam, mu = lame(E, nu)
    field = basis.interpolate(u)
    r = basis.mapping.F(basis.X)[0]
    return np.array(stresses(strains(field, r), lam, mu))
