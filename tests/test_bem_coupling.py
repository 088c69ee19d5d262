"""The BEM's normal–tangential coupling (bem.coupling), each part against something independent.

Units of the operator and contact tests are nondimensional (a = 1, E* = 1,
R = 10). The closed forms are written here from their derivations in
docs/bem-tangential.md §6 (Gauss's theorem for the displacement of a Hertzian
traction, reciprocity for the moment of the pressure); none is imported from
the code under test.
"""

import math
import tomllib

import numpy as np
import pytest
from scipy import integrate

from wearcheck import bem, cases
from wearcheck.bem import contact, wear
from wearcheck.bem import tangential as T
from wearcheck.bem.operator import HalfSpace
from wearcheck.cases import CaseError, SolverError, reference

A, R, E_STAR = 1.0, 10.0, 1.0
P0 = 2.0 * E_STAR * A / (math.pi * R)
F_HERTZ = 2.0 * P0 * math.pi * A * A / 3.0
BETA_STEEL = 0.4 / 1.4          # (1 - 2ν)/(2(1 - ν)), ν = 0.3, rigid counterface


def grid(n, box=3.0):
    """Pixel centres of an n × n grid of side box·a, pixel n//2 on the tip (as the BEM)."""
    dx = box * A / n
    x = (np.arange(n) - n // 2) * dx
    X, Y = np.meshgrid(x, x, indexing="ij")
    return dx, X, Y


# -- the operator ------------------------------------------------------------

@pytest.mark.parametrize("x, y", [(0.0, 0.0), (1.0, 0.0), (0.3, 0.2), (2.0, 3.0), (-5.0, 1.0)])
def test_x_over_rho2_pixel_integral_against_quadrature(x, y):
    # the closed form against adaptive quadrature over the unit pixel; the
    # self pixel's 1/ρ singularity is integrable, quadrature runs over the
    # quarters meeting at it (tolerance 1e-7: the quadrature's own accuracy)
    value = T.rectangle_integral_x_over_rho2(x, y, 0.5, 0.5)
    cuts = sorted({-0.5, 0.5} | ({x} if -0.5 < x < 0.5 else set()))
    cuts_y = sorted({-0.5, 0.5} | ({y} if -0.5 < y < 0.5 else set()))
    q = 0.0
    for x0, x1 in zip(cuts[:-1], cuts[1:]):
        for y0, y1 in zip(cuts_y[:-1], cuts_y[1:]):
            q += integrate.dblquad(lambda yp, xp: (x - xp) / ((x - xp)**2 + (y - yp)**2),
                                   x0, x1, y0, y1, epsabs=1e-12, epsrel=1e-10)[0]
    assert value == pytest.approx(q, rel=1e-7, abs=1e-10)


def hertz_traction_displacement(X, Y, beta):
    """u_z of τx = √(1 - r²/a²) (q0 = 1): β/(πE*) x M(r)/r², M(r) = ∫∫_{ρ<r} τ dA (Gauss)."""
    r2 = X**2 + Y**2
    inside = np.clip(1.0 - r2 / A**2, 0.0, None)
    M = 2.0 * math.pi * A**2 / 3.0 * (1.0 - inside**1.5)
    with np.errstate(invalid="ignore", divide="ignore"):
        return beta / (math.pi * E_STAR) * X * np.where(r2 > 0, M / r2, 0.0)


def test_shear_to_normal_against_the_hertz_traction_closed_form():
    # the normal displacement of a Hertzian shear traction, from Gauss's
    # theorem for the logarithmic potential (docs/bem-tangential.md §6):
    # max error over the peak 1.2 % at a/10.7 pixels, 0.47 % at a/21.3
    # (tolerances 1.5 % and 0.6 %), falling with the pixel size at order >= 1.2
    errors = []
    for n in (32, 64):
        dx, X, Y = grid(n)
        q = np.sqrt(np.clip(1.0 - (X**2 + Y**2) / A**2, 0.0, None))
        u = T.ShearToNormal(n, dx, BETA_STEEL, E_STAR)(q)
        exact = hertz_traction_displacement(X, Y, BETA_STEEL)
        errors.append(np.max(np.abs(u - exact)) / np.max(np.abs(exact)))
    assert errors[0] < 0.015 and errors[1] < 0.006
    assert math.log2(errors[0] / errors[1]) > 1.2


def test_shear_to_normal_against_tamaas():
    # Tamaas 2.9's Boussinesq–Cerruti operator (surface_2d, Fourier, PERIODIC)
    # on the Hertzian traction at ν = 0.3: the same sign (the surface ahead of
    # the traction sinks) and size. The difference inside 1.5 a is the
    # periodic images of Tamaas's box L, which fall as (a/L)²: measured 7.0 %
    # of the peak at L = 8a and 1.9 % at 16a (tolerances 2.5 % at 16a, and a
    # ratio within [3, 5.5] of the (a/L)² law's 4)
    import tamaas as tm  # in the test extra: a missing one fails, never skips
    nu = 0.3
    beta = (1 - 2 * nu) / (2 * (1 - nu))
    diffs = []
    for n, L in ((64, 8.0), (128, 16.0)):
        model = tm.ModelFactory.createModel(tm.model_type.surface_2d, [L, L], [n, n])
        model.E, model.nu = E_STAR * (1 - nu**2), nu
        dx = L / n
        x = np.arange(n) * dx - L / 2
        X, Y = np.meshgrid(x, x, indexing="ij")
        q = np.sqrt(np.clip(1 - (X**2 + Y**2) / A**2, 0, None))
        traction = np.zeros((n, n, 3))
        traction[..., 0] = q
        model.traction[...] = traction
        model.solveNeumann()
        uz_tamaas = np.array(model.displacement)[..., 2]
        uz = T.ShearToNormal(n, dx, beta, E_STAR)(q)
        near = X**2 + Y**2 < (1.5 * A)**2
        # ahead of the traction the surface moves into the solid: our gap
        # opens, Tamaas's u_z (along the compressive pressure) is positive
        assert np.sum(uz[X > 0.3]) > 0 and np.sum(uz_tamaas[X > 0.3]) > 0
        diffs.append(np.max(np.abs(uz - uz_tamaas)[near]) / np.max(np.abs(uz)))
    assert diffs[1] < 0.025
    assert 3.0 < diffs[0] / diffs[1] < 5.5


# -- the coupled contact -----------------------------------------------------

def centre_of_pressure_shift(beta, mu):
    """x_c = -3βμa/(2π): first order in βμ, by reciprocity with the tilted flat punch."""
    return -3.0 * beta * mu * A / (2.0 * math.pi)


def test_sliding_hertz_pressure_shift_against_the_closed_form():
    # Hertz under force control with τx = μp coupled: the centre of pressure
    # moves against the traction by 3βμa/(2π) at first order. At a/21 pixels
    # measured x_c over it 1.0013 (βμ = 0.029) and 0.9968 (βμ = 0.086):
    # the pixel error and the O((βμ)²) term (0.991 at βμ = 0.25); tolerance
    # 1 %. The force is held; the coupled problem is solved: its residual,
    # recomputed from scratch with G and C, below the tolerance.
    n = 64
    dx, X, Y = grid(n)
    h = (X**2 + Y**2) / (2 * R)
    op = HalfSpace(n, dx, E_STAR)
    tol = 1e-8
    kw = dict(p_scale=P0, g_scale=A * A / R, tol=tol)
    plain = contact.solve(op, h, force=F_HERTZ, **kw)
    for mu in (0.1, 0.3):
        shear = T.ShearToNormal(n, dx, BETA_STEEL, E_STAR)
        c = contact.solve_coupled(op, shear, h, mu, force=F_HERTZ, **kw)
        xc = np.sum(X * c.pressure) / np.sum(c.pressure)
        assert xc / centre_of_pressure_shift(BETA_STEEL, mu) == pytest.approx(1.0, abs=0.01)
        assert c.force == pytest.approx(F_HERTZ, rel=1e-12)
        gap = h - c.depth + op(c.pressure) + shear(mu * c.pressure)
        assert contact.complementarity_residual(c.pressure, gap, P0, A * A / R) < tol
        # the uncoupled solve is not a solution of the coupled problem
        gap_plain = h - plain.depth + op(plain.pressure) + shear(mu * plain.pressure)
        assert contact.complementarity_residual(plain.pressure, gap_plain, P0, A * A / R) > 100 * tol
    # at a held depth the force changes at second order only (F is even in
    # βμ: the mirror image x -> -x reverses the traction): ΔF/F fitted
    # against βμ = 0.029, 0.086, 0.25 on log-log has slope 2 (measured 1.98;
    # tolerance ±0.1) and ΔF/F < 0 (measured -1.04e-3 at βμ = 0.086)
    d_hertz = A * A / R
    base = contact.solve(op, h, depth=d_hertz, **kw)
    beta_mu, change = [], []
    for beta, mu in ((BETA_STEEL, 0.1), (BETA_STEEL, 0.3), (0.5, 0.5)):
        c = contact.solve_coupled(op, T.ShearToNormal(n, dx, beta, E_STAR), h, mu,
                                  depth=d_hertz, p_init=base.pressure, **kw)
        beta_mu.append(beta * mu)
        change.append(c.force / base.force - 1.0)
    assert all(c < 0 for c in change)
    assert np.polyfit(np.log(beta_mu), np.log(-np.array(change)), 1)[0] == \
        pytest.approx(2.0, abs=0.1)
    # β = 0: nothing is coupled
    zero = contact.solve_coupled(op, T.ShearToNormal(n, dx, 0.0, E_STAR), h, 0.3,
                                 force=F_HERTZ, **kw)
    assert np.allclose(zero.pressure, plain.pressure, rtol=0, atol=10 * tol * P0)


def test_coupled_solve_that_cannot_converge_says_why():
    # βμ = 1.5: the sweeps cannot contract; a SolverError naming the key and βμ
    n = 32
    dx, X, Y = grid(n)
    h = (X**2 + Y**2) / (2 * R)
    with pytest.raises(SolverError, match=r"bem\.coupling.*mu = 1\.5"):
        contact.solve_coupled(HalfSpace(n, dx, E_STAR), T.ShearToNormal(n, dx, 0.5, E_STAR),
                              h, 3.0, force=F_HERTZ, p_scale=P0, g_scale=A * A / R, tol=1e-8)


# -- wear with coupling ------------------------------------------------------

def paper(grid_=32, **bem_keys):
    raw = tomllib.loads(cases.shipped("paper").read_text())
    raw["bem"] = dict(grid=grid_, **bem_keys)
    return raw


def short(raw, s_hat, **sliding):
    """The case of ``raw`` slid to ŝ with stages at 0 and ŝ."""
    case = cases.from_dict(raw)
    per = reference.scales(case)["s_hat_per_m"]
    sl = {k: v for k, v in raw["sliding"].items() if k != "force_fraction"}
    sl.update(until="distance", distance=s_hat / per, **sliding)
    return cases.from_dict(dict(raw, sliding=sl, stages=dict(s_hat=[0.0, s_hat])))


def test_reciprocating_is_the_limit_of_alternating_strokes():
    # The reciprocating model wears by the mean of the two strokes' pressures.
    # Against strokes simulated one by one (backward Euler steps alternately
    # with the traction along +x and -x, each step one stroke): they differ
    # by O(stroke), halving with it (measured max |Δf| 3.6e-3, 1.8e-3 d at
    # ŝ = 3 for strokes of 0.05 and 0.025 in ŝ; here to ŝ = 1 with ratio in
    # [1.6, 2.4]); and the mean's profile is exactly symmetric in x
    raw = paper(32)
    case = cases.from_dict(raw)
    sc = reference.scales(case)
    x, dx, _ = bem.solver.grid(case, sc)
    n = len(x)
    X, Y = np.meshgrid(x, x, indexing="ij")
    f0 = cases.profiles.height_xy(case.indenter, X, Y)
    op = HalfSpace(n, dx, case.E_star)
    shear = T.ShearToNormal(n, dx, BETA_STEEL, case.E_star)
    common = dict(op=op, f0=f0, wear_rate=case.wear_rate, depth=case.loading.depth,
                  force=None, p_scale=sc["p0"], g_scale=case.loading.depth, tol=1e-8,
                  centre=(n // 2, n // 2))
    mean = wear.Model(**common, coupling=wear.Coupling(shear, case.wear.mu, True))
    strokes = [wear.Model(**common, coupling=wear.Coupling(shear, s * case.wear.mu, False))
               for s in (1.0, -1.0)]
    per = sc["s_hat_per_m"]

    def slide(models, step_hat, s_hat=1.0):
        f, p = f0.copy(), None
        for k in range(round(s_hat / step_hat)):
            st = wear.implicit_state(models[k % len(models)], f, step_hat / per, p)
            f, p = st.f, st.p
        return f

    diffs = []
    for step in (0.1, 0.05):
        f_mean, f_alt = slide([mean], step), slide(strokes, step)
        diffs.append(np.max(np.abs(f_mean - f_alt)) / case.loading.depth)
        assert np.array_equal(f_mean[1:], f_mean[1:][::-1])
    assert 1.6 < diffs[0] / diffs[1] < 2.4


@pytest.mark.parametrize("stroke", [None, 1e-3])
def test_coupled_wear_run_conserves_volume_and_solves_the_coupled_problem(stroke):
    # Backward Euler with coupling: the worn volume is K Σ h F exactly (the
    # stroke mean moves wear between mirror pixels and keeps its sum), every
    # step's coupled residual below the tolerance (recomputed here at the
    # stages with G and C from scratch); one direction shifts the unworn
    # pressure against the traction (x_c < 0) and wears asymmetrically,
    # reciprocating strokes wear symmetrically
    raw = paper(32, coupling=True)
    if stroke is not None:
        raw["sliding"]["stroke"] = stroke
    case = short(raw, 1.0, scheme="implicit", step_hat=0.1)
    res = bem.solve(case)
    info = res.info["coupling"]
    assert info["beta"] == pytest.approx(BETA_STEEL)
    assert ("reciprocating" in info["sliding"]) == (stroke is not None)
    h = res.history
    V = case.wear_rate * np.cumsum(np.diff(h["s"]) * h["force"][1:])
    assert np.allclose(h["wear_volume"][1:], V, rtol=1e-10, atol=0)
    tol = case.bem.tolerance
    assert np.all(h["complementarity_residual"] < tol)
    x = res.fields["x"]
    n = len(x)
    X = np.meshgrid(x, x, indexing="ij")[0]
    op = HalfSpace(n, res.info["pixel"], case.E_star)
    shear = T.ShearToNormal(n, res.info["pixel"], BETA_STEEL, case.E_star)
    d = case.loading.depth
    p0 = reference.scales(case)["p0"]
    for k in range(len(res.stage_s)):
        p, f = res.fields["pressure"][k], res.fields["profile"][k]
        gap = f - d + op(p) + shear(case.wear.mu * p)
        # an implicit step's contact is solved on the step's end profile
        # (reciprocating: the +x stroke's, with the wear on the stroke mean)
        assert contact.complementarity_residual(p, gap, p0, d) < 2 * tol
    p_unworn = res.fields["pressure"][0]
    assert np.sum(X * p_unworn) < 0
    w = res.fields["wear_depth"][-1]
    asym = np.max(np.abs(w[1:] - w[1:][::-1])) / np.max(w)
    assert asym == 0.0 if stroke is not None else asym > 1e-2


def test_coupling_key():
    # validated as the schema's other keys: a clear message naming the key
    raw = paper(32, coupling="yes")
    with pytest.raises(CaseError, match=r"bem\.coupling"):
        cases.from_dict(raw)
    # elastically similar bodies (the same steel both sides): nothing to couple
    raw = paper(32, coupling=True)
    raw["counterface"] = dict(rigid=False, youngs_modulus=210e9, poisson_ratio=0.3)
    case = short(raw, 0.1)
    assert cases.dundurs_beta(case.indenter, case.counterface) == 0.0
    assert "without effect" in bem.solve(case).info["coupling"]


def test_gross_slip_shift_against_tamaas_partial_slip_extrapolated():
    # Tamaas 2.9's PolonskyKeerTan solves normal and tangential contact
    # together with the Poisson coupling (periodic box, mean tractions
    # given). At ν = 0.3 it converges in partial slip up to Q ≈ 0.95 μF and
    # not beyond (asked for 0.99 μF its Q drifts: 0.95, 0.92, 0.77 μF after
    # 10³, 3·10³, 10⁴ iterations), so it does not reach gross slip. Near
    # Q = μF the stick zone's part of the moment of the pressure falls as
    # c³ ∝ 1 - Q/μF, linearly: Tamaas's centre of pressure at Q = 0.90 and
    # 0.95 μF extrapolated to μF against our gross-slip solve on the same
    # grid (a/8 pixels, box 8a): measured -0.0403 a against -0.0410 a
    # (1.8 %: Tamaas's periodic images, (a/L)² ~ 1.6 %, and the
    # extrapolation); tolerance 4 %. The uncoupled shift is 0.
    import tamaas as tm
    nu, mu, n, L = 0.3, 0.3, 64, 8.0
    beta = (1 - 2 * nu) / (2 * (1 - nu))
    dx = L / n
    x = np.arange(n) * dx - L / 2
    X, Y = np.meshgrid(x, x, indexing="ij")
    q_frac, centre = [], []
    for frac in (0.9, 0.95):
        model = tm.ModelFactory.createModel(tm.model_type.surface_2d, [L, L], [n, n])
        model.E, model.nu = E_STAR * (1 - nu**2), nu
        solver = tm.PolonskyKeerTan(model, -(X**2 + Y**2) / (2 * R), 1e-12, mu)
        solver.max_iter = 1500
        solver.solve([frac * mu * F_HERTZ / L**2, 0.0, F_HERTZ / L**2])
        tr = np.array(model.traction)
        q_frac.append(np.sum(tr[..., 0]) * dx * dx / (mu * F_HERTZ))
        centre.append(np.sum(X * tr[..., 2]) / np.sum(tr[..., 2]))
    slope = (centre[1] - centre[0]) / (q_frac[1] - q_frac[0])
    tamaas_gross = centre[1] + slope * (1.0 - q_frac[1])
    h = (X**2 + Y**2) / (2 * R)
    c = contact.solve_coupled(HalfSpace(n, dx, E_STAR), T.ShearToNormal(n, dx, beta, E_STAR),
                              h, mu, force=F_HERTZ, p_scale=P0, g_scale=A * A / R, tol=1e-8)
    ours = np.sum(X * c.pressure) / np.sum(c.pressure)
    assert ours == pytest.approx(tamaas_gross, rel=0.04)


def test_the_similarity_note_gives_the_case_its_first_order_shift():
    # the note every command prints names the coupling key and this case's
    # first-order shift 3βμ/(2π) (docs/bem-tangential.md §6.2), here for μ = 0.5
    raw = paper(32)
    raw["wear"]["mu"] = 0.5
    note = cases.from_dict(raw).warnings[0]
    assert "bem.coupling = true" in note
    assert f"{3 * BETA_STEEL * 0.5 / (2 * math.pi):.3f} contact radii" in note


def test_reciprocating_wear_changes_at_second_order_in_beta_mu():
    # Reciprocating strokes: the mirror image x -> -x maps the +x stroke at
    # βμ to the -x stroke and the stroke mean is even in βμ, so the worn
    # profile and the force differ from the uncoupled run at O((βμ)²)
    # (docs/theory.md §1). Paper case at 32² to ŝ = 1.5 (backward Euler,
    # Δŝ = 0.1) at βμ = 0.029, 0.057, 0.114: the changes of the profile and
    # of the force, fitted on log-log against βμ, have slope 2 (measured
    # 2.0005, tolerance ±0.05; the force 1.96, tolerance ±0.1: pixels entering
    # and leaving the contact make it the rougher measure), and
    # (max |Δf|/d)/(βμ)² is one constant (measured 0.1284 at all three to
    # 6e-4 of itself; tolerance 2 %). A first-order effect (slope 1, or a
    # constant halving per doubling) fails.
    raw = paper(32)
    case = cases.from_dict(raw)
    sc = reference.scales(case)
    x, dx, _ = bem.solver.grid(case, sc)
    n = len(x)
    X, Y = np.meshgrid(x, x, indexing="ij")
    f0 = cases.profiles.height_xy(case.indenter, X, Y)
    f0 -= f0[n // 2, n // 2]
    op = HalfSpace(n, dx, case.E_star)
    shear = T.ShearToNormal(n, dx, BETA_STEEL, case.E_star)
    common = dict(op=op, f0=f0, wear_rate=case.wear_rate, depth=case.loading.depth,
                  force=None, p_scale=sc["p0"], g_scale=case.loading.depth, tol=1e-10,
                  centre=(n // 2, n // 2))
    step = 0.1 / sc["s_hat_per_m"]

    def slide(coupling):
        model = wear.Model(**common, coupling=coupling)
        f, p = f0.copy(), None
        for _ in range(15):
            st = wear.implicit_state(model, f, step, p)
            f, p = st.f, st.p
        return f, st.force

    f_off, F_off = slide(None)
    beta_mu, df, dF = [], [], []
    for mu in (0.1, 0.2, 0.4):
        f, F = slide(wear.Coupling(shear, mu, reciprocating=True))
        beta_mu.append(BETA_STEEL * mu)
        df.append(np.max(np.abs(f - f_off)) / case.loading.depth)
        dF.append(abs(F / F_off - 1.0))
    slope_f = np.polyfit(np.log(beta_mu), np.log(df), 1)[0]
    slope_F = np.polyfit(np.log(beta_mu), np.log(dF), 1)[0]
    assert slope_f == pytest.approx(2.0, abs=0.05)
    assert slope_F == pytest.approx(2.0, abs=0.1)
    constants = np.array(df) / np.array(beta_mu)**2
    assert np.ptp(constants) < 0.02 * constants.mean()
