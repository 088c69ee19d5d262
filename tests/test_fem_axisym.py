"""The axisymmetric elasticity form against exact solutions."""

import math

import numpy as np
import pytest
from skfem import (Basis, ElementTriP1, ElementTriP2, ElementVector, FacetBasis, MeshTri,
                   Functional, asm, condense, solve)

from wearcheck.fem.axisym import stiffness_form, traction_form

E, NU = 210e9, 0.3


def _solve(mesh, order, dirichlet, traction, facets):
    elem = ElementVector(ElementTriP2() if order == 2 else ElementTriP1())
    basis = Basis(mesh, elem, intorder=4)
    K = asm(stiffness_form(E, NU), basis)
    fb = FacetBasis(mesh, elem, facets=facets, intorder=4)
    b = asm(traction_form(*traction), fb)
    D = np.concatenate([basis.get_dofs(f).all(comp) for f, comp in dirichlet])
    return basis, solve(*condense(K, b, D=D))


@pytest.mark.parametrize("order", [1, 2])
def test_uniaxial_cylinder_exact(order):
    # A solid cylinder under uniform axial stress σ: u_r = -ν σ r / E,
    # u_z = σ z / E. Linear fields lie in the FE space, so the Galerkin
    # solution is exact; 1e-9 relative leaves room for round-off only. A
    # missing or wrong hoop term (u_r/r) changes u_r at O(1).
    Ra, L, sigma = 2.0, 3.0, 1e6
    mesh = MeshTri.init_tensor(np.linspace(0, Ra, 5), np.linspace(0, L, 7)).with_boundaries(
        {"axis": lambda x: x[0] < 1e-12, "bottom": lambda x: x[1] < 1e-12,
         "top": lambda x: x[1] > L - 1e-12})
    basis, u = _solve(mesh, order, [("axis", "u^1"), ("bottom", "u^2")],
                      (lambda x: 0 * x[0], lambda x: sigma + 0 * x[0]),
                      mesh.boundaries["top"])
    x = basis.doflocs
    exact = np.empty_like(u)
    exact[0::2] = -NU * sigma * x[0, 0::2] / E
    exact[1::2] = sigma * x[1, 1::2] / E
    assert np.max(np.abs(u - exact)) < 1e-9 * sigma * L / E


def _lame_error(n, order):
    # Thick-walled tube a <= r <= b under inner pressure, plane strain (u_z = 0
    # on both ends): u_r = (1+ν)/E [(1-2ν) C1 r + C2 / r].
    a, b, L, p = 1.0, 2.0, 0.5, 1e6
    C1, C2 = p * a**2 / (b**2 - a**2), p * a**2 * b**2 / (b**2 - a**2)
    mesh = MeshTri.init_tensor(np.linspace(a, b, n + 1), np.linspace(0, L, max(2, n // 4) + 1))
    mesh = mesh.with_boundaries({"inner": lambda x: x[0] < a + 1e-12,
                                 "ends": lambda x: (x[1] < 1e-12) | (x[1] > L - 1e-12)})
    basis, u = _solve(mesh, order, [("ends", "u^2")],
                      (lambda x: p + 0 * x[0], lambda x: 0 * x[0]), mesh.boundaries["inner"])

    @Functional
    def err2(w):
        r = w.x[0]
        ur = (1 + NU) / E * ((1 - 2 * NU) * C1 * r + C2 / r)
        return (w["u"][0] - ur) ** 2 + w["u"][1] ** 2

    scale = (1 + NU) / E * C2 / a
    return math.sqrt(err2.assemble(basis, u=basis.interpolate(u))) / scale


@pytest.mark.parametrize("order,rate", [(1, 2.0), (2, 3.0)])
def test_lame_tube_converges_at_optimal_rate(order, rate):
    # L2 error of a non-polynomial exact solution; the optimal rate is p + 1.
    # A slope within 0.3 of it over three halvings allows for pre-asymptotic
    # curvature; a wrong hoop term or weight would stall convergence at O(1).
    ns = np.array([8, 16, 32]) if order == 1 else np.array([4, 8, 16])
    errs = np.array([_lame_error(n, order) for n in ns])
    slope = -np.polyfit(np.log(ns), np.log(errs), 1)[0]
    assert abs(slope - rate) < 0.3, (slope, errs)
    assert errs[-1] < 1e-2
