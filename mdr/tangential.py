"""Tangential springs of the MDR with Coulomb friction and memory (Cattaneo–Mindlin in 1D).

Each 1D spring at x has tangential stiffness G*·Δx (paper Eq. 4) and carries
the line load q_x = G* v, v its elastic tangential deformation. It sticks
(v follows the indenter's displacement) until |q_x| reaches μ q_z, then
slides with q_x = ±μ q_z. In displacement units the limit is
L(x) = μ q_z(x)/G*. Pure functions of nodal arrays on the t-uniform grid of
:mod:`mdr.transforms`; the 3D fields follow by the same transforms as the
normal ones: shear traction τ from q_x by paper Eq. 13, relative slip from the
1D slip by paper Eq. 16 (= Eq. 3).
"""

from __future__ import annotations

import math

import numpy as np

from wearcheck.cases import SolverError

from . import transforms


def limit(q: np.ndarray, mu: float, G_star: float) -> np.ndarray:
    """L = μ q_z/G*: the largest elastic deformation a spring takes before it slides."""
    return (mu / G_star) * q


def step(v: np.ndarray, L: np.ndarray, du: float) -> tuple[np.ndarray, np.ndarray]:
    """One increment du of the indenter: new deformations and the 1D slip.

    v_new = clip(v + du, -L, L) also re-clips springs whose limit fell (worn
    normal load); slip = du - (v_new - v), zero where the spring sticks.
    """
    trial = v + du
    v_new = np.clip(trial, -L, L)
    # slip = du - (v_new - v) = trial - v_new, exactly zero on sticking springs
    return v_new, trial - v_new


def force(v: np.ndarray, G_star: float, weights: np.ndarray) -> float:
    """Tangential force Q = 2 ∫ G* v dx (paper Eq. 12 for q_x), exact for v linear in t."""
    return float(G_star * (weights @ v))


def displacement_for_force(v: np.ndarray, L: np.ndarray, target: float, G_star: float,
                           weights: np.ndarray) -> float:
    """The increment du with Q(clip(v + du, -L, L)) = target, solved exactly.

    Q(du) is piecewise linear and non-decreasing; its kinks are where springs
    reach their limits (du = L - v upwards, -L - v downwards).
    """
    Q0 = force(v, G_star, weights)
    if target == Q0:
        return 0.0
    up = target > Q0
    # the largest force the springs can carry in this direction
    Qmax = G_star * (weights @ (L if up else -L))
    if (up and target >= Qmax * (1 - 1e-12)) or (not up and target <= Qmax * (1 - 1e-12)):
        # the limit falls under wear (depth control) to just below Q*: four digits
        # read "8.955 N is beyond μF = 8.955 N", so the excess is stated
        raise SolverError(
            f"tangential force {abs(target):.7g} N is beyond the friction limit μF = "
            f"{abs(Qmax):.7g} N of the current normal load (by "
            f"{abs(target) / abs(Qmax) - 1:.2g} relative; gross slip under force control "
            "has no equilibrium); lower fretting.force_amplitude")
    sgn = 1.0 if up else -1.0
    # distances to saturation along the direction of loading, sorted
    b = sgn * (sgn * L - v)
    order = np.argsort(b, kind="stable")
    bs, ws = b[order], weights[order]
    # Q(du) with du = sgn*s: Q0 + sgn*G* [Σ_{b_i > s} w_i s + Σ_{b_i <= s} w_i b_i]
    free_w = ws.sum() - np.cumsum(ws)              # weight still sticking after k saturated
    Wb = np.cumsum(ws * bs)
    need = abs(target - Q0) / G_star
    # value at s = bs[k] (springs 0..k saturated): Wb[k] + free_w[k] bs[k]
    at = Wb + free_w * bs
    k = int(np.searchsorted(at, need, side="left"))
    if k == 0:
        s = need / ws.sum()
    else:
        s = bs[k - 1] + (need - at[k - 1]) / free_w[k - 1]
    return sgn * s


def stick_radius(slipped: np.ndarray, margin: np.ndarray, t: np.ndarray) -> float:
    """Radius of the region that did not slip, sub-grid.

    ``slipped``: nodes that slid (in the last stroke); ``margin``: a quantity
    positive on sticking nodes and crossing zero at the stick edge (L - U,
    U the half stroke), linear in t between nodes. The edge lies between the
    last node of the leading sticking run and the next.
    """
    if slipped[0]:
        return 0.0
    k = int(np.argmax(slipped)) if slipped.any() else len(slipped) - 1
    if not slipped.any():
        return math.sqrt(t[-1])
    j = k - 1
    m0, m1 = margin[j], margin[k]
    frac = m0 / (m0 - m1) if m0 > m1 else 1.0
    frac = min(max(frac, 0.0), 1.0)
    return math.sqrt(t[j] + frac * (t[k] - t[j]))


def shear_traction(v: np.ndarray, G_star: float, dt: float) -> np.ndarray:
    """τ(r) by paper Eq. 13 applied to q_x = G* v."""
    return transforms.pressure(G_star * v, dt)


def reciprocating_slip(L: np.ndarray, stroke: float) -> np.ndarray:
    """3D slip per unit sliding of reciprocating gross slip (docs/theory.md §4).

    At each stroke end a spring reverses its deformation from +L to -L before
    it slides again, so of a stroke ℓ (one way) it slides ℓ - 2L(x), and
    nothing where ℓ <= 2L (it sticks). Paper Eq. 16 takes the 1D slip to 3D,
    here by the exact inverse of the discrete Eq. 2 (exact on functions linear
    in t, constants included): S(r) = 1 - T⁻¹[min(2L/ℓ, 1)](r).
    """
    return 1.0 - transforms.from_1d_exact(np.minimum(2.0 * L / stroke, 1.0))


def slip_3d(slip_1d: np.ndarray) -> np.ndarray:
    """Relative 3D slip u^(0) - u^(3D)(r) from the 1D slip by paper Eq. 16 (= Eq. 3)."""
    return transforms.to_3d(slip_1d)
