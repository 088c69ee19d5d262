"""Closed forms of partial-slip (fretting) contact of a paraboloid.

Cattaneo–Mindlin (monotonic tangential loading under a constant normal load),
Mindlin–Deresiewicz (the hysteresis loop of an oscillating tangential load and
the energy it dissipates per cycle) and Popov's limiting profile of fretting
wear under a constant normal force. Written in MDR form (paraboloid
f = r²/2R, g = x²/R, effective moduli E*, G* of paper Eqs. 5-6). They share
no code with the solvers. SI units throughout.

Notation: F normal force, a contact radius, μ friction coefficient, Q
tangential force, u tangential displacement of the indenter (rigid-body),
u* = 3μF/(4G*a) the displacement at which gross slip sets in.
"""

from __future__ import annotations

import math

import numpy as np


# -- Cattaneo–Mindlin --------------------------------------------------------

def gross_slip_displacement(mu, force, G_star, contact_radius):
    """u* = 3μF/(4G*a): the tangential displacement at which the stick zone vanishes.

    Equal to μE*a²/(R G*) for a paraboloid under Hertz contact.
    """
    return 3.0 * mu * force / (4.0 * G_star * contact_radius)


def stick_radius(contact_radius, R, E_star, G_star, mu, amplitude):
    """Cattaneo–Mindlin stick radius under a displacement u0: c² = a² - R G* u0/(μE*).

    Returns 0 at and beyond gross slip (u0 >= u*).
    """
    c2 = contact_radius**2 - R * G_star * amplitude / (mu * E_star)
    return math.sqrt(c2) if c2 > 0.0 else 0.0


def stick_radius_from_force(contact_radius, tangential_force, mu, force):
    """Cattaneo–Mindlin stick radius under a tangential force: c/a = (1 - Q/μF)^(1/3)."""
    x = 1.0 - abs(tangential_force) / (mu * force)
    return contact_radius * x ** (1.0 / 3.0) if x > 0.0 else 0.0


def tangential_force(u, mu, force, u_star):
    """Initial (virgin) loading: Q = μF [1 - (1 - u/u*)^(3/2)], |u| <= u*; μF beyond."""
    u = np.asarray(u, dtype=float)
    x = np.clip(1.0 - np.abs(u) / u_star, 0.0, None)
    return np.sign(u) * mu * force * (1.0 - x**1.5)


def tangential_displacement(Q, mu, force, u_star):
    """Inverse of :func:`tangential_force`: u = u* [1 - (1 - Q/μF)^(2/3)], |Q| < μF."""
    Q = np.asarray(Q, dtype=float)
    return np.sign(Q) * u_star * (1.0 - (1.0 - np.abs(Q) / (mu * force)) ** (2.0 / 3.0))


# -- Mindlin–Deresiewicz ---------------------------------------------------------

def loop_force(u, amplitude, mu, force, u_star, branch):
    """Q(u) on the steady hysteresis loop between -u0 and u0 (u0 = amplitude < u*).

    branch "unloading": u runs from u0 down to -u0,
    Q = Q* - 2μF [1 - (1 - (u0 - u)/(2u*))^(3/2)];
    branch "reloading": u runs from -u0 up to u0, the loop's point reflection.
    Q* = Q(u0) of the virgin curve (Masing's rule: the branches are the virgin
    curve stretched by two).
    """
    u = np.asarray(u, dtype=float)
    Qs = float(tangential_force(amplitude, mu, force, u_star))
    if branch == "unloading":
        x = np.clip(1.0 - (amplitude - u) / (2.0 * u_star), 0.0, None)
        return Qs - 2.0 * mu * force * (1.0 - x**1.5)
    if branch == "reloading":
        x = np.clip(1.0 - (amplitude + u) / (2.0 * u_star), 0.0, None)
        return -Qs + 2.0 * mu * force * (1.0 - x**1.5)
    raise ValueError(f"branch must be 'unloading' or 'reloading', got {branch!r}")


def energy_per_cycle(force_amplitude, mu, force, u_star):
    """Energy dissipated per cycle of ±Q* (Mindlin–Deresiewicz), Q* < μF.

    W = (24/5) μF u* {1 - (1 - q)^(5/3) - (5q/6) [1 + (1 - q)^(2/3)]}, q = Q*/μF;
    for small q, W ≈ (4/27) u* Q*³/(μF)².
    """
    q = force_amplitude / (mu * force)
    if not 0.0 <= q <= 1.0:
        raise ValueError(f"Q*/μF = {q!r} must be in [0, 1] (partial slip)")
    return 4.8 * mu * force * u_star * (1.0 - (1.0 - q) ** (5.0 / 3.0)
                                        - 5.0 * q / 6.0 * (1.0 + (1.0 - q) ** (2.0 / 3.0)))


def energy_per_cycle_displacement(amplitude, mu, force, u_star):
    """Energy per cycle of a displacement amplitude u0 <= u* (Q* from the virgin curve)."""
    Qs = float(tangential_force(amplitude, mu, force, u_star))
    return energy_per_cycle(Qs, mu, force, u_star)


# -- Popov's limiting profile (constant normal force and amplitude) -----------

def limiting_depth(force, E_star, stick_radius, R):
    """Popov's d∞ = F/(2E*c) + c²/(3R): the depth once the slip annulus carries no pressure.

    Exact when the stick zone |x| <= c is unworn (depth control, or c = c0);
    under force control c grows, the springs between c0 and c wore before
    they stuck, and the limiting depth lies above this by their mean raise of
    the 1D profile over the stick zone (5e-5 of d at u0 = 0.5u*,
    docs/fretting.md §2).
    """
    c = stick_radius
    return force / (2.0 * E_star * c) + c * c / (3.0 * R)


def limiting_profile_1d(x, R, stick_radius, depth):
    """Popov's limiting 1D profile: x²/R for |x| <= c, d∞ for c < |x| <= √(R d∞), x²/R beyond."""
    x = np.abs(np.asarray(x, dtype=float))
    g = x * x / R
    b = math.sqrt(R * depth)
    return np.where((x > stick_radius) & (x <= b), depth, g)


def limiting_profile_3d(r, R, stick_radius, depth):
    """Paper Eq. 3 of :func:`limiting_profile_1d` in closed form.

    With J(x) = ∫_0^x ξ²/√(r² - ξ²) dξ = (r²/2) asin(x/r) - (x/2)√(r² - x²)
    and b = √(R d∞):
    f∞ = (2/π) {[J(min(r,c)) + J(r) - J(min(r,b))]/R + d∞ [asin(min(r,b)/r) - asin(min(r,c)/r)]},
    i.e. r²/2R inside c and [r² asin(c/r) - c√(r² - c²)]/(πR) + d∞(1 - (2/π) asin(c/r))
    for c < r <= b.
    """
    r = np.abs(np.asarray(r, dtype=float))
    c, b = stick_radius, math.sqrt(R * depth)
    out = np.empty_like(r)
    for i, ri in np.ndenumerate(r):
        if ri <= c:
            out[i] = ri * ri / (2.0 * R)
            continue

        def J(x):
            return 0.5 * ri * ri * math.asin(min(x / ri, 1.0)) \
                - 0.5 * x * math.sqrt(max(ri * ri - x * x, 0.0))
        rb = min(ri, b)
        out[i] = (2.0 / math.pi) * ((J(c) + J(ri) - J(rb)) / R
                                    + depth * (math.asin(min(rb / ri, 1.0)) - math.asin(c / ri)))
    return out


# -- the stick radius under force control (docs/fretting.md, §2.1) -------------

def stick_compression(E_star, G_star, mu, amplitude):
    """w_c = G* u0/(μE*): the least normal compression d - g(x) of a spring that sticks.

    A 1D spring slides in a cycle ±u0 unless its Coulomb limit μE*(d - g)/G*
    reaches u0.
    """
    return G_star * amplitude / (mu * E_star)


def stick_radius_at_depth(depth, R, E_star, G_star, mu, amplitude):
    """c = √(R (d - w_c)): the stick radius if the profile at the stick edge is unworn.

    An upper bound on the stick radius at depth d when wear never lowers the
    1D profile below x²/R (docs/fretting.md, §2.1); at the Hertz depth it is
    Cattaneo–Mindlin's c. Returns 0 when d <= w_c.
    """
    c2 = R * (depth - stick_compression(E_star, G_star, mu, amplitude))
    return math.sqrt(c2) if c2 > 0.0 else 0.0


def depth_bound(force, E_star, R, initial_stick_radius, compression, stick_radius):
    """Largest depth under force F while the stick zone is [0, c] (docs/fretting.md, §2.1).

    d <= [F/(2E*) + c0³/(3R) - w_c (c - c0)]/c0: the unworn core |x| <= c0
    carries E*(d - x²/R), every other sticking spring at least E* w_c, the
    slipping annulus nothing less than zero. c = c0 gives d∞ of Popov at c0.
    """
    c0, wc = initial_stick_radius, compression
    return (force / (2.0 * E_star) + c0**3 / (3.0 * R) - wc * (stick_radius - c0)) / c0


def stick_radius_bounds(force, E_star, G_star, mu, amplitude, R):
    """Bounds c0 <= c(t) <= c_max on the stick radius of fretting wear under constant F and u0.

    c0 is Cattaneo–Mindlin's stick radius of the unworn paraboloid (a stuck
    spring is never worn and the depth never falls under force control);
    c_max the positive root of (c0/R) c² + w_c c = F/(2E*) + c0³/(3R), which
    combines :func:`depth_bound` with c² <= R(d - w_c) at the stick edge.
    Derivation: docs/fretting.md, §2.1. Valid at every cycle, not only in
    the limiting state. Returns (c0, c_max); (0, 0) at and beyond gross slip.
    """
    a = (3.0 * force * R / (4.0 * E_star)) ** (1.0 / 3.0)
    c0 = stick_radius(a, R, E_star, G_star, mu, amplitude)
    if c0 == 0.0:
        return 0.0, 0.0
    wc = stick_compression(E_star, G_star, mu, amplitude)
    A, B, C = c0 / R, wc, force / (2.0 * E_star) + c0**3 / (3.0 * R)
    # the root of A c² + B c - C = 0 written without cancellation
    c_max = 2.0 * C / (B + math.sqrt(B * B + 4.0 * A * C))
    return c0, c_max
