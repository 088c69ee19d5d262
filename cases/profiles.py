"""The unworn indenter profile f(r) and its slope, as the case defines them.

The solvers evaluate the geometry through these functions, so that the case
means the same shape to each of them. The axisymmetric solvers see the
ellipsoid as the paraboloid of the equivalent radius √(R1 R2) (an
approximation); :func:`height_xy` gives the true surface over the plane.
"""

from __future__ import annotations

import numpy as np
import scipy  # submodules load on first use (scipy is lazy): import wearcheck stays quick

from .schema import Indenter


def equivalent_radius(indenter: Indenter) -> float:
    """√(R1 R2) of an ellipsoid: the paraboloid of the same Gaussian curvature."""
    return float(np.sqrt(indenter.radius * indenter.radius_y))


#: PCHIP interpolants of the tables seen last, by the identity of their radius
#: array (a case's table is built once and never changed): building one per
#: evaluation is a cost every recorded step of a run would pay (cases/validity.py;
#: docs/performance.md, "Measurements behind the code")
_INTERPOLANTS: dict = {}


def _table_interpolant(table):
    r, f = table
    hit = _INTERPOLANTS.get(id(r))
    if hit is not None and hit[0] is r and hit[1] is f:
        return hit[2]
    interpolant = scipy.interpolate.PchipInterpolator(r, f, extrapolate=True)
    if len(_INTERPOLANTS) >= 8:
        _INTERPOLANTS.clear()
    _INTERPOLANTS[id(r)] = (r, f, interpolant)   # (r, f) kept: their ids stay theirs
    return interpolant


def height(indenter: Indenter, r, table=None) -> np.ndarray:
    """Unworn profile height f(r) [m], f(0) = 0."""
    r = np.abs(np.asarray(r, dtype=float))
    kind = indenter.profile
    if kind == "paraboloid":
        return r**2 / (2.0 * indenter.radius)
    if kind == "sphere":
        R = indenter.radius
        rr = np.minimum(r, R)
        return R - np.sqrt(R**2 - rr**2)
    if kind == "truncated_paraboloid":
        b, R = indenter.flat_radius, indenter.radius
        return np.where(r < b, 0.0, (r**2 - b**2) / (2.0 * R))
    if kind == "cone":
        return r * np.tan(indenter.slope_angle)
    if kind == "power_law":
        return indenter.coefficient * r**indenter.exponent
    if kind == "ellipsoid":
        # the axisymmetric stand-in: a paraboloid of the equivalent radius √(R1 R2)
        return r**2 / (2.0 * equivalent_radius(indenter))
    if kind == "table":
        rt, ft = table
        out = _table_interpolant(table)(np.minimum(r, rt[-1]))
        # beyond the table: continue with the last slope (the profile keeps rising).
        # Only the gap outside the contact sees it: a contact or scar that
        # leaves the table stops the run (cases/validity.py), as that continuation
        # is a guess, not the measured body
        slope_end = _table_interpolant(table).derivative()(rt[-1])
        return np.where(r > rt[-1], ft[-1] + slope_end * (r - rt[-1]), out)
    raise ValueError(f"unknown profile {kind!r}")


def slope(indenter: Indenter, r, table=None) -> np.ndarray:
    """Slope f'(r) of the unworn profile."""
    r = np.abs(np.asarray(r, dtype=float))
    kind = indenter.profile
    if kind == "paraboloid":
        return r / indenter.radius
    if kind == "sphere":
        R = indenter.radius
        rr = np.minimum(r, R * (1 - 1e-15))
        return rr / np.sqrt(R**2 - rr**2)
    if kind == "truncated_paraboloid":
        return np.where(r < indenter.flat_radius, 0.0, r / indenter.radius)
    if kind == "cone":
        return np.full_like(r, np.tan(indenter.slope_angle))
    if kind == "power_law":
        n = indenter.exponent
        return indenter.coefficient * n * r ** (n - 1.0)
    if kind == "ellipsoid":
        return r / equivalent_radius(indenter)
    if kind == "table":
        rt, _ = table
        d = _table_interpolant(table).derivative()
        return d(np.minimum(r, rt[-1]))
    raise ValueError(f"unknown profile {kind!r}")


def height_xy(indenter: Indenter, x, y, table=None) -> np.ndarray:
    """Unworn surface height f(x, y) [m] over the plane, f(0, 0) = 0.

    Bodies of revolution are f(√(x² + y²)); the ellipsoid (paraboloidal
    approximation near its tip) is x²/2R1 + y²/2R2 with R1 = indenter.radius
    along x and R2 = indenter.radius_y along y.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if indenter.profile == "ellipsoid":
        return x**2 / (2.0 * indenter.radius) + y**2 / (2.0 * indenter.radius_y)
    return height(indenter, np.hypot(x, y), table)
