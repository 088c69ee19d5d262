"""Frictionless normal contact of a body of revolution by the MDR (paper Eqs. 9-13).

Pure functions of nodal arrays on the t-uniform grid of :mod:`mdr.transforms`.
The 1D line load is q = E* (d - g) where positive, taken node by node and
linear in t between nodes; the contact radius is located between the last
loaded node and the next by linear interpolation of g in t (sub-grid).
"""

from __future__ import annotations

import math

import numpy as np

from wearcheck.cases import SolverError

from . import transforms


class DomainOutgrown(SolverError):
    """The contact reached the edge of the MDR grid; the solver grows the domain and retries."""


def line_load(g: np.ndarray, depth: float, E_star: float) -> np.ndarray:
    """Paper Eq. 10: q = E* (d - g) where positive, else 0 (nodal)."""
    return E_star * np.maximum(depth - g, 0.0)


def last_loaded(q: np.ndarray) -> int:
    """Index of the last node with q > 0 (-1 if none); the domain must reach beyond it."""
    loaded = np.flatnonzero(q > 0.0)
    m = int(loaded[-1]) if loaded.size else -1
    if m >= len(q) - 2:
        raise DomainOutgrown(
            "the contact has reached the edge of the MDR domain (contact radius ≈ domain "
            "radius); raise mdr.domain_factor")
    return m


def contact_radius(g: np.ndarray, depth: float, t: np.ndarray, m: int) -> float:
    """Paper Eq. 11, g(a) = d, between node m (g < d) and m+1 (g >= d), linear in t."""
    if m < 0:
        return 0.0
    return radius_between(g[m], g[m + 1], depth, t[m], t[m + 1])


def radius_between(g0: float, g1: float, depth: float, t0: float, t1: float) -> float:
    """:func:`contact_radius` from g and t at the last loaded node (g0, t0) and the next."""
    frac = (depth - g0) / (g1 - g0) if g1 > g0 else 1.0
    frac = min(max(frac, 0.0), 1.0)
    return math.sqrt(t0 + frac * (t1 - t0))


def depth_for_force(g: np.ndarray, force: float, E_star: float, weights: np.ndarray) -> float:
    """The depth d with E* Σ w_i (d - g_i)_+ = F (the discrete Eq. 12), solved exactly.

    F(d) is piecewise linear and increasing in d; its pieces start at the
    sorted nodal g values.
    """
    order = np.argsort(g, kind="stable")
    gs, ws = g[order], weights[order]
    W = np.cumsum(ws)
    G = np.cumsum(ws * gs)
    # force when d equals each sorted g value (all nodes below it loaded)
    F_at = E_star * (gs * W - G)
    k = int(np.searchsorted(F_at, force, side="right")) - 1
    k = min(max(k, 0), len(gs) - 1)
    return float((force / E_star + G[k]) / W[k])


def solve_normal(g: np.ndarray, t: np.ndarray, dt: float, E_star: float,
                 depth: float | None = None, force: float | None = None) -> dict:
    """Normal contact of a 1D profile g under a given depth or force.

    Returns depth, line_load q, pressure p (nodal), force, contact_radius and
    the index m of the last loaded node.
    """
    if depth is None:
        depth = depth_for_force(g, force, E_star, transforms.force_weights(len(g) - 1, dt))
    q = line_load(g, depth, E_star)
    m = last_loaded(q)
    return dict(depth=depth, q=q, p=transforms.pressure(q, dt), force=transforms.force(q, dt),
                contact_radius=contact_radius(g, depth, t, m), m=m)
