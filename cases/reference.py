"""Analytic reference solutions of axisymmetric frictionless contact.

Closed forms (Hertz, truncated paraboloid, cone, power law, exact sphere) and
adaptive quadrature where no closed form exists. These share no code with the
solvers; tests and comparisons measure both solvers against them. Each function
takes SI values and returns SI values.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import scipy  # submodules load on first use (scipy is lazy): import wearcheck stays quick

from .errors import CaseError
from .profiles import slope


# -- Hertz (paraboloid f = r^2 / 2R) ---------------------------------------

def hertz(E_star, R, depth=None, force=None):
    """Contact radius, depth and force of a paraboloid; give depth or force."""
    if depth is not None:
        a = math.sqrt(R * depth)
    else:
        a = (3.0 * force * R / (4.0 * E_star)) ** (1.0 / 3.0)
    d = a**2 / R
    return dict(contact_radius=a, depth=d, force=4.0 / 3.0 * E_star * math.sqrt(R) * d**1.5)


def hertz_pressure(r, E_star, R, contact_radius):
    """p(r) = (2E*/(πR)) sqrt(a² - r²) inside the contact, 0 outside."""
    r = np.asarray(r, dtype=float)
    a = contact_radius
    return 2.0 * E_star / (math.pi * R) * np.sqrt(np.clip(a**2 - r**2, 0.0, None))


# -- truncated ("flattened") paraboloid, paper Eqs. 17-19 -------------------

def truncated_paraboloid(E_star, R, b, depth=None, force=None):
    """Contact radius, depth and force of f = 0 (r<b), (r²-b²)/2R (r>=b)."""
    if depth is not None:
        a = math.sqrt(0.5 * (b**2 + math.sqrt(b**4 + 4.0 * R**2 * depth**2)))
    else:
        def excess(a):
            return 2 * E_star / (3 * R) * math.sqrt(a**2 - b**2) * (2 * a**2 + b**2) - force
        hi = 2 * b + (3 * force * R / (4 * E_star)) ** (1 / 3)
        a = scipy.optimize.brentq(excess, b, hi, xtol=1e-15 * hi, rtol=1e-14)
    d = a / R * math.sqrt(a**2 - b**2)
    F = 2.0 * E_star / (3.0 * R) * math.sqrt(a**2 - b**2) * (2.0 * a**2 + b**2)
    return dict(contact_radius=a, depth=d, force=F)


def truncated_paraboloid_pressure(r, E_star, R, b, contact_radius):
    """p(r) by adaptive quadrature of paper Eq. 13 with Eq. 19.

    p(r) = (E*/(πR)) ∫_{max(r,b)}^a (2x² - b²) / (sqrt(x²-b²) sqrt(x²-r²)) dx.
    The substitutions x² = b² + t² (r < b) or x² = r² + u² (r > b) remove the
    inverse-square-root end singularity; p is infinite (logarithmically) at r = b.
    """
    a = contact_radius
    out = np.zeros(np.shape(r))
    for i, ri in np.ndenumerate(np.asarray(r, dtype=float)):
        if ri >= a:
            continue
        if ri == b:
            out[i] = np.inf
        elif ri < b:
            def g(t):
                x = math.sqrt(b * b + t * t)
                return (2 * x * x - b * b) / (x * math.sqrt(x * x - ri * ri))
            val, _ = scipy.integrate.quad(g, 0.0, math.sqrt(a * a - b * b), epsabs=0, epsrel=1e-12,
                                    limit=200)
            out[i] = val
        else:
            def h(u):
                x = math.sqrt(ri * ri + u * u)
                return (2 * x * x - b * b) / (x * math.sqrt(x * x - b * b))
            val, _ = scipy.integrate.quad(h, 0.0, math.sqrt(a * a - ri * ri), epsabs=0, epsrel=1e-12,
                                    limit=200)
            out[i] = val
    return E_star / (math.pi * R) * out


# -- elliptical Hertz (f = x²/2R1 + y²/2R2) --------------------------------

def hertz_elliptical(E_star, R1, R2, depth=None, force=None):
    """Hertz contact of an ellipsoid f = x²/2R1 + y²/2R2 on a half-space.

    The pressure p0 √(1 - (u/a)² - (v/b)²) on an ellipse with semi-axes a >= b
    (a along the larger radius) displaces the surface inside it by
    (p0 b/E*) [K(e) - (K - E)/e² · u²/a² - (E/(1-e²) - K)/e² · v²/a²],
    e² = 1 - b²/a², K, E the complete elliptic integrals (Johnson 1985, §3.9
    with 1/E* for both bodies). Matching the profile's curvatures gives

        R_small/R_large = (K - E) / (E/(1-e²) - K),
        d = p0 b K / E*,   a² = 2 R_large d (K - E)/(e² K),   F = (2/3) π a b p0.

    Returns semi_axis_x, semi_axis_y (along R1 and R2), depth, force, p0 and
    the equivalent contact radius √(a b).
    """
    big, small = max(R1, R2), min(R1, R2)
    ratio = small / big
    if ratio > 1.0 - 1e-8:
        # (nearly) a paraboloid of revolution: e² -> 0, where the equation
        # above cancels; the error of taking √(R1 R2) is O((1 - ratio)²)
        big = math.sqrt(R1 * R2)
        c = hertz(E_star, big, depth=depth, force=force)
        a = b = c["contact_radius"]
        p_max = 2.0 * E_star * a / (math.pi * big)
        e2 = 0.0
        d = c["depth"]
    else:
        def mismatch(e2):
            K, E = scipy.special.ellipk(e2), scipy.special.ellipe(e2)
            return (K - E) / (E / (1.0 - e2) - K) - ratio
        # the ratio falls from 1 (e → 0) to 0 (e → 1)
        # near e = 0 the ratio is 1 - (3/4)e² + ...: bracket below that
        e2 = scipy.optimize.brentq(mismatch, 0.1 * (1.0 - ratio), 1.0 - 1e-15, xtol=1e-16,
                             rtol=1e-15)
        K, E = scipy.special.ellipk(e2), scipy.special.ellipe(e2)
        if depth is None:
            # F ∝ d^(3/2): solve at a unit depth and scale
            unit = hertz_elliptical(E_star, R1, R2, depth=1.0)
            depth = (force / unit["force"]) ** (2.0 / 3.0)
        d = depth
        a = math.sqrt(2.0 * big * d * (K - E) / (e2 * K))
        b = a * math.sqrt(1.0 - e2)
        p_max = d * E_star / (b * K)
    F = 2.0 / 3.0 * math.pi * a * b * float(p_max)
    p_max = float(p_max)
    ax, ay = (a, b) if R1 >= R2 else (b, a)
    return dict(semi_axis_x=ax, semi_axis_y=ay, depth=d, force=F, max_pressure=p_max,
                eccentricity_squared=e2, contact_radius=math.sqrt(a * b))


# -- other profiles --------------------------------------------------------

def sphere(E_star, R, depth=None, force=None):
    """Exact sphere f = R - sqrt(R² - r²): g(x) = x atanh(x/R) (MDR, paper Eq. 2)."""
    def d_of(a):
        return a * math.atanh(a / R)

    def F_of(a):
        return E_star * ((a**2 + R**2) * math.atanh(a / R) - R * a)

    if depth is not None:
        a = scipy.optimize.brentq(lambda a: d_of(a) - depth, 0.0, R * (1 - 1e-15),
                            xtol=1e-16 * R, rtol=1e-14)
    else:
        a = scipy.optimize.brentq(lambda a: F_of(a) - force, 0.0, R * (1 - 1e-15),
                            xtol=1e-16 * R, rtol=1e-14)
    return dict(contact_radius=a, depth=d_of(a), force=F_of(a))


def cone(E_star, slope_angle, depth=None, force=None):
    """Cone f = r tan θ: g = (π/2)|x| tan θ, F = (2/π) E* d² / tan θ."""
    t = math.tan(slope_angle)
    if depth is None:
        depth = math.sqrt(force * math.pi * t / (2.0 * E_star))
    a = 2.0 * depth / (math.pi * t)
    return dict(contact_radius=a, depth=depth, force=E_star * a * depth)


def power_law_factor(n):
    """κ(n) in g(x) = κ c |x|^n for f = c r^n (MDR stretch factor)."""
    return math.sqrt(math.pi) * scipy.special.gamma(n / 2 + 1) / scipy.special.gamma(n / 2 + 0.5)


def power_law(E_star, c, n, depth=None, force=None):
    """f = c r^n: a = (d/(κc))^(1/n), F = 2E* a d n/(n+1)."""
    k = power_law_factor(n) * c
    if depth is None:
        # F = 2E* n/(n+1) κc a^(n+1)
        a = (force * (n + 1) / (2 * E_star * n * k)) ** (1.0 / (n + 1))
        depth = k * a**n
    a = (depth / k) ** (1.0 / n)
    return dict(contact_radius=a, depth=depth, force=2 * E_star * a * depth * n / (n + 1))


def mdr_transform_quad(indenter, x, table=None):
    """g(x) = x ∫_0^x f'(r)/sqrt(x²-r²) dr by quadrature (r = x sin φ makes it smooth)."""
    x = float(x)
    if x == 0.0:
        return 0.0
    val, _ = scipy.integrate.quad(lambda p: float(slope(indenter, x * math.sin(p), table)),
                            0.0, math.pi / 2, epsabs=0, epsrel=1e-11, limit=200)
    return x * val


@functools.lru_cache(maxsize=4)
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes and weights on [-1, 1], computed once per n (an n x n
    eigenproblem, slow for n = 800, and every reference.scales of a table case
    needs it; docs/performance.md, "Measurements behind the code")."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = w.flags.writeable = False
    return x, w


def general(E_star, indenter, table, depth=None, force=None):
    """Any profile with a monotonic g(x), by Gauss–Legendre quadrature and root finding.

    g(x) = x ∫_0^{π/2} f'(x sin φ) dφ (paper Eq. 2 after r = x sin φ), evaluated
    with a fixed rule: a tabulated profile's slope is only piecewise smooth, so an
    adaptive rule would subdivide at every knot.
    """
    phi, wphi = _gauss_legendre(800)
    phi, wphi = (phi + 1) * np.pi / 4, wphi * np.pi / 4
    t, wt = _gauss_legendre(400)
    t, wt = (t + 1) / 2, wt / 2

    def g(x):
        x = np.atleast_1d(np.asarray(x, dtype=float))
        return x * (slope(indenter, x[:, None] * np.sin(phi), table) @ wphi)

    def F_of(a):
        return 2.0 * E_star * a * float(wt @ (g(a)[0] - g(a * t)))

    hi = table[0][-1] if table is not None else 1.0
    if depth is not None:
        if g(hi)[0] < depth:
            raise CaseError(f"key 'loading.depth' = {depth!r}: deeper than the tabulated profile "
                            f"reaches (g at its last radius is {g(hi)[0]:.4g} m)")
        a = scipy.optimize.brentq(lambda x: g(x)[0] - depth, 0.0, hi, xtol=1e-14 * hi, rtol=1e-12)
    else:
        if F_of(hi) < force:
            raise CaseError(f"key 'loading.force' = {force!r}: larger than the tabulated profile "
                            "can carry within its last radius")
        a = scipy.optimize.brentq(lambda x: F_of(x) - force, 0.0, hi, xtol=1e-14 * hi, rtol=1e-12)
    return dict(contact_radius=a, depth=float(g(a)[0]), force=F_of(a))


def unworn_contact(case):
    """Contact radius, depth and force of the unworn profile under the case's load."""
    ind, E = case.indenter, case.E_star
    load = {case.loading.control: getattr(case.loading, case.loading.control)}
    kind = ind.profile
    if kind == "paraboloid":
        return hertz(E, ind.radius, **load)
    if kind == "sphere":
        return sphere(E, ind.radius, **load)
    if kind == "truncated_paraboloid":
        return truncated_paraboloid(E, ind.radius, ind.flat_radius, **load)
    if kind == "cone":
        return cone(E, ind.slope_angle, **load)
    if kind == "power_law":
        return power_law(E, ind.coefficient, ind.exponent, **load)
    if kind == "ellipsoid":
        # contact_radius: the equivalent radius √(a b) of the contact ellipse
        return hertz_elliptical(E, ind.radius, ind.radius_y, **load)
    return general(E, ind, case.table, **load)


def scales(case) -> dict:
    """Natural scales of a case (docs/theory.md §5), from its unworn contact.

    a0, d0, F0: contact radius, depth, force of the unworn profile (Hertz's for
    the paraboloid; for the ellipsoid a0 = √(a b) of its contact ellipse, so
    that p0 is its maximum pressure); p0 = 3 F0 / (2π a0²), Hertz's maximum pressure;
    ŝ = s_hat_per_m · s = k μ E* s / (σ0 a0).
    """
    c = unworn_contact(case)
    a0, F0 = c["contact_radius"], c["force"]
    return dict(
        E_star=case.E_star,
        G_star=case.G_star,
        a0=a0,
        d0=c["depth"],
        F0=F0,
        p0=3.0 * F0 / (2.0 * math.pi * a0**2),
        s_hat_per_m=case.wear_rate * case.E_star / a0,
    )


def complete_wear_profile(r, R, depth):
    """Fixed-depth limit of a worn paraboloid: max(r²/2R, d) (docs/theory.md §6)."""
    return np.maximum(np.asarray(r, dtype=float) ** 2 / (2.0 * R), depth)


# -- long runs under constant force (issue 11) -------------------------------

def worn_sphere_asymptote(R, F, s, wear_coefficient, *, exponent=1.0, hardness=1.0,
                          profile="sphere"):
    """Long-run scar of a sphere worn under a constant force F (rigid-flat limit).

    The worn cap becomes a flat of radius b under a nearly uniform pressure
    F/(π b²). Wearing it at its centre, dh/ds = K_n (F/(π b²))^n with
    K_n = wear_coefficient · hardness^(1−n) (= kμ σ0^(−n); ``wear_coefficient``
    is K = kμ/σ0), h the height of the cap cut off.

    ``profile="sphere"``: the exact spherical cap, b² = 2Rh − h². With
    h = R(1 − cos θ) the integral ∫_0^h (2Rη − η²)^n dη is
    R^(2n+1) ∫_0^θ sin^(2n+1), i.e.

        (R^(2n+1)/2) B(n+1, ½) I_{(b/R)²}(n+1, ½) = K_n (F/π)^n s,

    I the regularised incomplete beta function; for n = 1 the cap's volume
    πh²(3R − h)/3 is K F s, Archard's law. ``profile="paraboloid"``
    (f = r²/2R, b² = 2Rh): b^(2(n+1)) = 2(n+1) R K_n (F/π)^n s, for n = 1
    b = (4 R K F s/π)^(1/4); the sphere's leading order, which it exceeds by
    (b/R)²/12 in b for n = 1 (5.3e-4 at b/R = 0.08).

    Returns scar_radius b [m], wear_center h [m] and wear_volume [m³] of the
    cap; NaN where the sphere's cap would pass the hemisphere (b = R).
    """
    n = float(exponent)
    Kn = wear_coefficient * hardness ** (1.0 - n)
    s = np.asarray(s, dtype=float)
    if profile == "paraboloid":
        b = (2.0 * (n + 1.0) * R * Kn * (F / math.pi) ** n * s) ** (1.0 / (2.0 * (n + 1.0)))
        return dict(scar_radius=b, wear_center=b**2 / (2.0 * R),
                    wear_volume=math.pi * b**4 / (4.0 * R))
    if profile != "sphere":
        raise ValueError(f"profile must be 'sphere' or 'paraboloid', got {profile!r}")
    y = 2.0 * Kn * (F / math.pi) ** n * s / (R ** (2.0 * n + 1.0) * scipy.special.beta(n + 1.0, 0.5))
    with np.errstate(invalid="ignore"):
        b = R * np.sqrt(np.where(y < 1.0, scipy.special.betaincinv(n + 1.0, 0.5,
                                                                    np.minimum(y, 1.0)), np.nan))
    # h = R - √(R² - b²) without cancellation at small b/R
    h = b**2 / (R + np.sqrt(R**2 - b**2))
    return dict(scar_radius=b, wear_center=h, wear_volume=math.pi * h**2 * (3.0 * R - h) / 3.0)


def predicted_scar_radius(case, s) -> float:
    """Radius the contact or scar can reach by sliding s [m], for sizing meshes.

    Depth control: √2·a0 (complete wear, docs/theory.md §6). Force control: the
    long-run asymptote started from the unworn radius,
    (a0^(2(n+1)) + 2(n+1) R K_n (F/π)^n s)^(1/(2(n+1))). Not a bound: early
    in a run the scar runs a few percent beyond it, later within a fraction of
    a percent (docs/performance.md, "Measurements behind the code"),
    so meshes and boxes sized on it keep a margin (``fem.contact_factor``,
    ``bem.box``). The paraboloid's law for every profile: for a sphere it is
    the larger by (b/R)²/12 (n = 1), a margin of the right sign, and the
    meshes and boxes of the shipped cases were measured with it.
    """
    a0 = scales(case)["a0"]
    if case.loading.control == "depth":
        return math.sqrt(2.0) * a0
    n = case.wear.pressure_exponent
    b = worn_sphere_asymptote(case.indenter.radius, case.loading.force, s, case.wear_rate,
                              exponent=n, hardness=case.wear.hardness,
                              profile="paraboloid")["scar_radius"]
    p = 2.0 * (n + 1.0)
    return float((a0**p + float(b) ** p) ** (1.0 / p))


def worn_crown(F, b, E_star):
    """Centre-to-edge height difference of a flat pressed by a uniform pressure.

    A uniform pressure q = F/(π b²) on a circle of radius b displaces the
    half-space surface by u(0) = 2 q b/E* at the centre and u(b) = 4 q b/(π E*)
    at the rim (Johnson, Contact Mechanics, §3.2), so u(0) − u(b) =
    2F(1 − 2/π)/(π b E*). Worn flat under load, the unloaded profile keeps
    this crown.
    """
    return 2.0 * F * (1.0 - 2.0 / math.pi) / (math.pi * b * E_star)
