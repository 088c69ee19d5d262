"""Tangential (partial-slip) contact of the BEM, each against something independent.

Units are nondimensional (a = 1, E* = 1, R = 10): the closed forms are
written here, in the test, from Johnson (1985) §3.6 and §7.2 (Cattaneo,
Mindlin, Mindlin–Deresiewicz); none is imported from the code under test.
"""

import math

import numpy as np
import pytest
from scipy import integrate

from wearcheck.bem import tangential as T
from wearcheck.cases import SolverError

A, R, E_STAR, MU = 1.0, 10.0, 1.0, 0.3
P0 = 2.0 * E_STAR * A / (math.pi * R)


def grid(n, box=2.4):
    """Pixel centres of an n × n grid of side box·a centred on the tip."""
    dx = box * A / n
    x = (np.arange(n) - (n - 1) / 2) * dx
    X, Y = np.meshgrid(x, x, indexing="ij")
    return dx, X, Y


def hertz_pressure(X, Y):
    r2 = (X**2 + Y**2) / A**2
    return P0 * np.sqrt(np.clip(1.0 - r2, 0.0, None))


def moduli(nu):
    """G, G* of a half-space of E* = 1 and Poisson ratio ν (rigid counterface)."""
    G = E_STAR * (1.0 - nu) / 2.0
    return G, 4.0 * G / (2.0 - nu)


# -- the operator ------------------------------------------------------------

@pytest.mark.parametrize("x, y", [(0.0, 0.0), (1.0, 0.0), (2.0, 3.0), (-5.0, 1.0)])
def test_cerruti_rectangle_integrals_against_quadrature(x, y):
    # the closed forms against adaptive quadrature of the point-force kernels
    # over the unit pixel [-1/2, 1/2]²; the self pixel has an integrable 1/ρ
    # singularity, so quadrature there runs over the four quarters meeting at it
    ones, xx, yy, xy = T.rectangle_integrals(x, y, 0.5, 0.5)
    kernels = [lambda X, Y: 1 / math.hypot(X, Y), lambda X, Y: X * X / math.hypot(X, Y)**3,
               lambda X, Y: Y * Y / math.hypot(X, Y)**3, lambda X, Y: X * Y / math.hypot(X, Y)**3]
    cuts = sorted({-0.5, 0.5} | ({x} if -0.5 < x < 0.5 else set()))
    cuts_y = sorted({-0.5, 0.5} | ({y} if -0.5 < y < 0.5 else set()))
    for k, value in zip(kernels, (ones, xx, yy, xy)):
        q = 0.0
        for x0, x1 in zip(cuts[:-1], cuts[1:]):
            for y0, y1 in zip(cuts_y[:-1], cuts_y[1:]):
                q += integrate.dblquad(lambda yp, xp: k(x - xp, y - yp), x0, x1, y0, y1,
                                       epsabs=1e-12, epsrel=1e-10)[0]
        assert value == pytest.approx(q, rel=1e-7, abs=1e-10)
    # X²/ρ³ + Y²/ρ³ = 1/ρ
    assert xx + yy == pytest.approx(ones, rel=1e-12)


def test_equivalent_half_space_inverts_the_moduli():
    for nu in (0.0, 0.3, 0.5):
        G, G_star = moduli(nu)
        G2, nu2 = T.equivalent_half_space(E_STAR, G_star)
        assert (G2, nu2) == pytest.approx((G, nu), rel=1e-12, abs=1e-14)


def test_displacement_of_a_hertzian_shear_traction():
    # Johnson Eq. 3.92: q_x = q0 √(1 - r²/a²) gives inside the circle
    # u_x = π q0/(32 G a) [4(2-ν)a² - (4-3ν)x² - (4-ν)y²]: the x and y
    # curvatures differ by the Poisson coupling. Pixels carry q_x at their
    # centres; the error is the pixelisation of the edge, O(Δ) on u, so 1 % of
    # u_x(0) at a/32 pixels is checked on r <= 0.8 a.
    nu = 0.3
    G, _ = moduli(nu)
    n = 80
    dx, X, Y = grid(n, box=2.5)
    q = np.sqrt(np.clip(1.0 - (X**2 + Y**2) / A**2, 0.0, None))
    op = T.TangentialHalfSpace(n, dx, G, nu)
    ux, uy = op(q, np.zeros_like(q))
    exact = math.pi / (32 * G * A) * (4 * (2 - nu) * A**2 - (4 - 3 * nu) * X**2
                                      - (4 - nu) * Y**2)
    inner = X**2 + Y**2 <= (0.8 * A)**2
    err = np.max(np.abs(ux - exact)[inner]) / exact.max()
    assert err < 0.01, err
    # by symmetry u_y is odd in x and in y
    assert np.max(np.abs(uy + uy[::-1, :])) < 1e-12 * exact.max()


# -- Cattaneo–Mindlin at ν = 0 -----------------------------------------------

def cattaneo_mindlin_traction(r, c):
    """τ_x = μp0/a [√(a² - r²) - √(c² - r²)] (second term only inside c)."""
    return MU * P0 / A * (np.sqrt(np.clip(A**2 - r**2, 0, None))
                          - np.sqrt(np.clip(c**2 - r**2, 0, None)))


def solve_cm(n, amplitude_fraction=0.5, nu=0.0):
    dx, X, Y = grid(n)
    p = hertz_pressure(X, Y)
    G, G_star = moduli(nu)
    F = dx * dx * p.sum()
    u_star = 3 * MU * F / (4 * G_star * A)
    op = T.TangentialHalfSpace(n, dx, G, nu)
    st = T.solve(op, p, MU, amplitude_fraction * u_star, tol=1e-8)
    return dx, X, Y, p, F, u_star, st


def test_cattaneo_mindlin_stick_radius_and_traction_at_nu_zero():
    # ν = 0: no coupling, Cattaneo–Mindlin is exact. Pixels of a/25: the stick
    # radius (equivalent radius of the stick pixels) within 1.5 pixel of
    # c = a(1 - Q/μF)^(1/3) (the stick boundary is resolved to a pixel, the
    # area count scatters by its perimeter); the traction within 1 % of μp0
    # more than 1.5 pixels from the edges r = c, a (measured 0.2 %), within
    # 6 % on the pixels straddling them (the √ edges sampled at pixel centres:
    # measured 3.5, 3.9, 2.2 % at n = 30, 60, 120, not converging in max norm;
    # the RMS does, see the convergence test); Q(δ) against
    # Q = μF[1 - (1 - δ/u*)^(3/2)] within 1 %.
    n = 60
    dx, X, Y, p, F, u_star, st = solve_cm(n)
    Q = st.force[0]
    c_cm = A * (1 - Q / (MU * F)) ** (1 / 3)
    c_bem = math.sqrt(st.stick.sum() * dx * dx / math.pi)
    assert abs(c_bem - c_cm) < 1.5 * dx, (c_bem, c_cm)
    assert Q / (MU * F) == pytest.approx(1 - 0.5**1.5, rel=0.01)
    r = np.hypot(X, Y)
    err = np.abs(st.traction[0] - cattaneo_mindlin_traction(r, c_cm)) / (MU * P0)
    away = (np.abs(r - c_cm) > 1.5 * dx) & (r < A - 1.5 * dx)
    assert np.max(err[away]) < 0.01, np.max(err[away])
    assert np.max(err) < 0.06, np.max(err)
    # the friction law: nowhere above μp, no τ_y at ν = 0
    assert np.all(np.hypot(*st.traction) <= MU * p * (1 + 1e-12))
    assert np.max(np.abs(st.traction[1])) == 0.0
    # stick: no slip increment; slip: traction along the slip
    assert np.all(st.slip_increment[:, st.stick] == 0.0)
    slip = (p > 0) & ~st.stick
    along = np.sum(st.traction * st.slip_increment, axis=0)[slip]
    assert np.all(along >= 0.0)


def test_force_control_reaches_the_force_and_the_stick_radius():
    # Q prescribed: c/a = (1 - Q/μF)^(1/3), within 1.5 pixel as above
    n = 48
    dx, X, Y = grid(n)
    p = hertz_pressure(X, Y)
    G, _ = moduli(0.0)
    F = dx * dx * p.sum()
    op = T.TangentialHalfSpace(n, dx, G, 0.0)
    Q = 0.8 * MU * F
    st = T.solve_force(op, p, MU, Q, force_rtol=1e-6)
    assert st.force[0] == pytest.approx(Q, abs=1e-6 * MU * F)
    c_bem = math.sqrt(st.stick.sum() * dx * dx / math.pi)
    assert abs(c_bem - A * 0.2 ** (1 / 3)) < 1.5 * dx
    with pytest.raises(SolverError, match="gross slip"):
        T.solve_force(op, p, MU, 1.01 * MU * F)


def mindlin_deresiewicz_energy(Q_star, F, u_star):
    """Loop area ∮ Q du of the Mindlin–Deresiewicz loop by quadrature of its branches.

    Virgin curve u_m(Q) = u*[1 - (1 - Q/μF)^(2/3)]; by Masing's rule the
    unloading branch is u = u0 - 2 u_m((Q* - Q)/2) and the reloading branch its
    point reflection, so the area is ∫ [u_unload(Q) - u_reload(Q)] dQ over ±Q*.
    """
    def um(q):
        return u_star * (1.0 - (1.0 - q / (MU * F)) ** (2.0 / 3.0))
    u0 = um(Q_star)

    def width(q):
        return (u0 - 2 * um((Q_star - q) / 2)) - (-u0 + 2 * um((Q_star + q) / 2))
    return integrate.quad(width, -Q_star, Q_star, epsabs=0, epsrel=1e-12)[0]


def test_energy_per_cycle_against_mindlin_deresiewicz_at_nu_zero():
    # ν = 0: the dissipation of the steady cycle ±u0 against the loop area of
    # Mindlin–Deresiewicz at the Q* the BEM reaches, within 3 % (the energy is
    # a small difference of Q(u) branches, ∝ (u0/u*)³ here; pixels of a/20).
    # Energy balance: over a closed cycle the stored elastic energy returns,
    # so the dissipation equals ∮Q dδ; the trapezoidal rule on 16 increments
    # per cycle misses O(h²) of the loop's curvature: 2 %.
    n = 48
    dx, X, Y = grid(n)
    p = hertz_pressure(X, Y)
    G, G_star = moduli(0.0)
    F = dx * dx * p.sum()
    u_star = 3 * MU * F / (4 * G_star * A)
    op = T.TangentialHalfSpace(n, dx, G, 0.0)
    cyc = T.reciprocating(op, p, MU, 0.5 * u_star, increments=4, tol=1e-8)
    Q_star = cyc.first_loading.force[0]
    W = mindlin_deresiewicz_energy(Q_star, F, u_star)
    assert cyc.energy_per_cycle == pytest.approx(W, rel=0.03)
    assert cyc.loop_work == pytest.approx(cyc.energy_per_cycle, rel=0.02)
    # the loop closes: the force at +u0 repeats after the cycle (Masing)
    assert cyc.force[-1] == pytest.approx(Q_star, rel=1e-4)
    # at ν = 0 the slip never turns, so the increments do not matter
    one = T.reciprocating(op, p, MU, 0.5 * u_star, increments=1, tol=1e-8)
    assert one.energy_per_cycle == pytest.approx(cyc.energy_per_cycle, rel=1e-4)


def test_energy_balance_with_poisson_coupling():
    # ν = 0.3: the slip directions turn a little, so increments matter; the
    # dissipation of the cycle still equals ∮Q dδ (no stored energy is left),
    # within 2 % at 4 increments per quarter cycle (trapezoidal rule, as above)
    n = 40
    dx, X, Y = grid(n)
    p = hertz_pressure(X, Y)
    G, G_star = moduli(0.3)
    F = dx * dx * p.sum()
    u_star = 3 * MU * F / (4 * G_star * A)
    op = T.TangentialHalfSpace(n, dx, G, 0.3)
    cyc = T.reciprocating(op, p, MU, 0.5 * u_star, increments=4, tol=1e-8)
    assert cyc.loop_work == pytest.approx(cyc.energy_per_cycle, rel=0.02)
    assert cyc.energy_per_cycle > 0.0


def test_traction_converges_with_the_pixel_size():
    # the RMS traction error against Cattaneo–Mindlin (ν = 0) over three grids;
    # the edges at r = c, a are √ singular in the derivative, sampled at pixel
    # centres: an order between 1 and 2 is expected; the fitted order must
    # exceed 0.8 and the finest error be below 1 % of μp0
    errs, hs = [], []
    for n in (24, 48, 96):
        dx, X, Y, p, F, u_star, st = solve_cm(n)
        c_cm = A * (1 - st.force[0] / (MU * F)) ** (1 / 3)
        exact = cattaneo_mindlin_traction(np.hypot(X, Y), c_cm)
        errs.append(math.sqrt(np.mean((st.traction[0] - exact)[p > 0] ** 2)) / (MU * P0))
        hs.append(dx)
    order = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert order > 0.8, (order, errs)
    assert errs[-1] < 0.01, errs


# -- against Tamaas ----------------------------------------------------------

def test_against_tamaas_polonsky_keer_tan():
    # Tamaas 2.9's PolonskyKeerTan solves normal and tangential contact
    # together on a PERIODIC box (its only option for tangential contact) with
    # the mean tractions given. At ν = 0.5 the normal and tangential problems
    # do not couple, so its pressure is the given pressure of ours, and the
    # Poisson coupling of the tangential problem is strongest. Our solve under
    # that pressure at the same Q: the stick pixels agree to one pixel and
    # the traction to 4 % of μ max p (measured 2.3 % at a/6.4 pixels, 1.6 % at
    # a/10.7, 1.1 % at a/16: the two discretisations, pixel-constant against
    # Fourier collocation, and the periodic images of a box of 5a differ by
    # that much); τ_y, the Poisson coupling, is ~6 % of μp0 in both.
    import tamaas as tm  # in the test extra: a missing one fails, never skips
    n, L, nu = 32, 5.0, 0.5
    model = tm.ModelFactory.createModel(tm.model_type.surface_2d, [L, L], [n, n])
    model.E, model.nu = E_STAR * (1 - nu**2), nu
    dx = L / n
    x = (np.arange(n) + 0.5) * dx - L / 2
    X, Y = np.meshgrid(x, x, indexing="ij")
    F = 2 * P0 * math.pi * A * A / 3
    Q = 0.6 * MU * F
    solver = tm.PolonskyKeerTan(model, -(X**2 + Y**2) / (2 * R), 1e-8, MU)
    solver.max_iter = 20000
    solver.solve([Q / L**2, 0.0, F / L**2])
    tr = np.array(model.traction)
    p = tr[..., 2]
    G, _ = moduli(nu)
    op = T.TangentialHalfSpace(n, dx, G, nu)
    st = T.solve_force(op, p, MU, Q)
    scale = MU * p.max()
    tm_stick = (p > 0) & (np.hypot(tr[..., 0], tr[..., 1]) < MU * p * (1 - 1e-4))
    assert np.sum(st.stick != tm_stick) <= 1
    assert np.max(np.abs(st.traction[0] - tr[..., 0])) < 0.04 * scale
    assert np.max(np.abs(st.traction[1] - tr[..., 1])) < 0.04 * scale
    assert np.max(np.abs(tr[..., 1])) > 0.03 * scale
    assert np.max(np.abs(st.traction[1])) > 0.03 * scale


# -- failures ----------------------------------------------------------------

def test_non_convergence_and_no_pressure_raise():
    n = 24
    dx, X, Y = grid(n)
    p = hertz_pressure(X, Y)
    op = T.TangentialHalfSpace(n, dx, 0.5, 0.0)
    with pytest.raises(SolverError, match="did not converge"):
        T.solve(op, p, MU, 0.01, maxiter=5, check_every=1)
    with pytest.raises(SolverError, match="no pixel"):
        T.solve(op, np.zeros_like(p), MU, 0.1)
