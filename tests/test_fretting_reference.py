"""Fretting closed forms (cases.reference_fretting) against independent routes."""

import math

import numpy as np
import pytest
from scipy import integrate

from wearcheck.cases import reference as ref
from wearcheck.cases import reference_fretting as rf

E_STAR, G_STAR, R, F, MU = 230.77e9, 190.0e9, 0.01, 30.0, 0.3


def hertz():
    return ref.hertz(E_STAR, R, force=F)


def test_gross_slip_threshold_two_forms():
    # u* = 3μF/(4G*a) and μE*a²/(RG*) are the same number under Hertz contact
    h = hertz()
    a = h["contact_radius"]
    u_star = rf.gross_slip_displacement(MU, F, G_STAR, a)
    assert u_star == pytest.approx(MU * E_STAR * a * a / (R * G_STAR), rel=1e-12)
    # and the stick radius closes exactly there
    assert rf.stick_radius(a, R, E_STAR, G_STAR, MU, u_star * (1 - 1e-12)) < 1e-5 * a


@pytest.mark.parametrize("frac", [0.1, 0.5, 0.9])
def test_stick_radius_displacement_and_force_forms_agree(frac):
    # c² = a² - R G* u0/(μE*) against c/a = (1 - Q/μF)^(1/3) with Q from the virgin curve
    a = hertz()["contact_radius"]
    u_star = rf.gross_slip_displacement(MU, F, G_STAR, a)
    u0 = frac * u_star
    Q = float(rf.tangential_force(u0, MU, F, u_star))
    assert rf.stick_radius(a, R, E_STAR, G_STAR, MU, u0) == \
        pytest.approx(rf.stick_radius_from_force(a, Q, MU, F), rel=1e-12)
    assert float(rf.tangential_displacement(Q, MU, F, u_star)) == pytest.approx(u0, rel=1e-12)


@pytest.mark.parametrize("q", [0.05, 0.4, 0.95])
def test_energy_per_cycle_is_the_loop_area(q):
    # the closed form against quadrature of the area between the two branches
    a = hertz()["contact_radius"]
    u_star = rf.gross_slip_displacement(MU, F, G_STAR, a)
    Qs = q * MU * F
    u0 = float(rf.tangential_displacement(Qs, MU, F, u_star))
    # the work ∮ Q du: the reloading branch (u rising) lies above the unloading one
    area = integrate.quad(lambda u: rf.loop_force(u, u0, MU, F, u_star, "reloading")
                          - rf.loop_force(u, u0, MU, F, u_star, "unloading"),
                          -u0, u0, epsabs=0, epsrel=1e-12)[0]
    assert area == pytest.approx(rf.energy_per_cycle(Qs, MU, F, u_star), rel=1e-9)
    # the branches close the loop at the turning points
    assert float(rf.loop_force(u0, u0, MU, F, u_star, "reloading")) == pytest.approx(Qs, rel=1e-12)
    assert float(rf.loop_force(-u0, u0, MU, F, u_star, "unloading")) == \
        pytest.approx(-Qs, rel=1e-12)


def test_limiting_depth_carries_the_force():
    # 2E* ∫ (d∞ - g∞)_+ dx = F (paper Eq. 12 on the limiting 1D profile)
    a = hertz()["contact_radius"]
    c = 0.7 * a
    d = rf.limiting_depth(F, E_STAR, c, R)
    val = integrate.quad(lambda x: max(d - float(rf.limiting_profile_1d(x, R, c, d)), 0.0),
                         0.0, 2 * a, points=[c, math.sqrt(R * d)], epsabs=0, epsrel=1e-12)[0]
    assert 2 * E_STAR * val == pytest.approx(F, rel=1e-10)


def test_limiting_profile_3d_is_eq3_of_the_1d_one():
    # f∞ closed form against quadrature of paper Eq. 3 (x = r sin φ)
    a = hertz()["contact_radius"]
    c = 0.7 * a
    d = rf.limiting_depth(F, E_STAR, c, R)
    b = math.sqrt(R * d)
    r = np.array([0.3 * c, c, 1.01 * c, 0.5 * (c + b), b, 1.3 * b])
    closed = rf.limiting_profile_3d(r, R, c, d)
    for ri, fi in zip(r, closed):
        kinks = [math.asin(min(k / ri, 1.0)) for k in (c, b)]
        q = integrate.quad(lambda p: float(rf.limiting_profile_1d(ri * math.sin(p), R, c, d)),
                           0.0, math.pi / 2, points=kinks, epsabs=0, epsrel=1e-12)[0]
        assert fi == pytest.approx(2 / math.pi * q, rel=1e-10)
    # inside the stick zone the unworn paraboloid is untouched
    assert closed[0] == pytest.approx((0.3 * c) ** 2 / (2 * R), rel=1e-14)


@pytest.mark.parametrize("frac", [0.1, 0.5, 0.9])
def test_stick_radius_bounds_meet_the_two_conditions(frac):
    # c_max: the depth bound and the edge condition c² = R(d - w_c) meet there
    a = hertz()["contact_radius"]
    u0 = frac * rf.gross_slip_displacement(MU, F, G_STAR, a)
    c0, c_max = rf.stick_radius_bounds(F, E_STAR, G_STAR, MU, u0, R)
    wc = rf.stick_compression(E_STAR, G_STAR, MU, u0)
    assert c0 == pytest.approx(rf.stick_radius(a, R, E_STAR, G_STAR, MU, u0), rel=1e-12)
    d = rf.depth_bound(F, E_STAR, R, c0, wc, c_max)
    assert rf.stick_radius_at_depth(d, R, E_STAR, G_STAR, MU, u0) == pytest.approx(c_max,
                                                                                   rel=1e-12)
    assert c0 < c_max < a
    # at the Hertz depth the edge condition is Cattaneo–Mindlin's c0, and the
    # depth bound at c = c0 is Popov's d∞(c0)
    assert rf.stick_radius_at_depth(a * a / R, R, E_STAR, G_STAR, MU, u0) == \
        pytest.approx(c0, rel=1e-12)
    assert rf.depth_bound(F, E_STAR, R, c0, wc, c0) == \
        pytest.approx(rf.limiting_depth(F, E_STAR, c0, R), rel=1e-12)


def test_stick_radius_bound_is_attained_by_its_extremal_profile():
    # the profile that attains c_max: x²/R on [0, c0], every spring of (c0, c]
    # loaded by exactly w_c (g = d - w_c), the annulus beyond c unloaded
    # (g = d); paper Eq. 12 by quadrature carries F at d = c²/R + w_c
    a = hertz()["contact_radius"]
    u0 = 0.5 * rf.gross_slip_displacement(MU, F, G_STAR, a)
    c0, c = rf.stick_radius_bounds(F, E_STAR, G_STAR, MU, u0, R)
    wc = rf.stick_compression(E_STAR, G_STAR, MU, u0)
    d = c * c / R + wc

    def g(x):
        return x * x / R if x <= c0 else (d - wc if x <= c else d)
    val = integrate.quad(lambda x: max(d - g(x), 0.0), 0.0, c, points=[c0],
                         epsabs=0, epsrel=1e-12)[0]
    assert 2 * E_STAR * val == pytest.approx(F, rel=1e-10)
    # the springs of (c0, c] lie on or above x²/R (an admissible worn profile)
    assert d - wc >= c * c / R * (1 - 1e-12)
    # u0 -> 0 leaves no room: c0 = c_max = a
    c0_small, c_small = rf.stick_radius_bounds(F, E_STAR, G_STAR, MU, 1e-9 * u0, R)
    assert c_small == pytest.approx(a, rel=1e-6) and c0_small == pytest.approx(a, rel=1e-6)
