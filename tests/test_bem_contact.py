"""BEM static contact against closed forms (Hertz, elliptical Hertz, flattened
sphere), a fitted grid-convergence order, Tamaas, and its failure modes."""

import math
import tomllib

import numpy as np
import pytest

from wearcheck import bem, cases
from wearcheck.bem import contact, wear
from wearcheck.bem.operator import HalfSpace
from wearcheck.cases import CaseError, SolverError, reference


def static(name, grid, *extra):
    case = cases.load(cases.shipped(name), [f"bem.grid={grid}", *extra])
    return case, bem.solve(case), reference.scales(case)


def test_hertz_sphere():
    # hertz.toml at 64² pixels: Δ = 0.055 a0 (box 2.5 · √2 a0)
    case, res, sc = static("hertz", 64)
    dx = res.info["pixel"] / sc["a0"]
    h = res.history
    # force: the collocation error is O(Δ²) (fitted below); Δ² = 3e-3
    assert abs(h["force"][0] / sc["F0"] - 1) < dx**2
    # contact radius √(A/π) from whole pixels: within one pixel
    assert abs(h["contact_radius"][0] / sc["a0"] - 1) < dx
    # ring-averaged pressure inside 0.9 a against Hertz: within 2 Δ·p0
    # (the ring average of a curved field and the pixel collocation are O(Δ))
    inner = res.r < 0.9 * sc["a0"]
    p_ref = reference.hertz_pressure(res.r, case.E_star, case.indenter.radius, sc["a0"])
    assert np.max(np.abs(res.p[0] - p_ref)[inner]) / sc["p0"] < 2 * dx
    # the complementarity tolerance holds
    assert h["complementarity_residual"][0] < case.bem.tolerance


def test_force_control_gives_the_hertz_approach():
    raw = tomllib.loads(cases.shipped("hertz").read_text())
    raw["loading"] = dict(control="force", force=20.0)
    raw["bem"] = dict(grid=64)
    case = cases.from_dict(raw)
    res, sc = bem.solve(case), reference.scales(case)
    assert sc["d0"] == pytest.approx(reference.hertz(case.E_star, 0.01, force=20.0)["depth"])
    assert abs(res.history["depth"][0] / sc["d0"] - 1) < (res.info["pixel"] / sc["a0"])**2
    assert res.history["force"][0] == pytest.approx(case.loading.force, rel=1e-12)


def test_grid_convergence_order():
    # the Hertz force error against the closed form over five grids: the
    # pixel collocation is second order where p is smooth, the √ edge lowers
    # it (measured 1.80 over 24..256 pixels); asserted: order in [1.4, 2.6]
    grids = (48, 64, 96, 128, 192)
    errs, h = [], []
    for g in grids:
        _, res, sc = static("hertz", g)
        errs.append(abs(res.history["force"][0] / sc["F0"] - 1))
        h.append(res.info["pixel"] / sc["a0"])
    order = np.polyfit(np.log(h), np.log(errs), 1)[0]
    assert 1.4 < order < 2.6, order


def test_elliptical_hertz():
    # ellipsoid.toml unworn (R2/R1 = 3) at 96²: force and peak pressure against
    # the elliptic-integral solution, semi-axes from the loaded pixels on the
    # two axes (whole pixels: within one pixel each), and their ratio
    case, res, sc = static("ellipsoid", 96, 'sliding.until="distance"', "sliding.distance=0.0")
    ref = reference.unworn_contact(case)
    x = res.fields["x"]
    dx = x[1] - x[0]
    n = len(x)
    P = res.fields["pressure"][0]
    on = P > case.bem.tolerance * sc["p0"]
    ax = np.count_nonzero(on[:, n // 2]) * dx / 2
    ay = np.count_nonzero(on[n // 2, :]) * dx / 2
    b = min(ref["semi_axis_x"], ref["semi_axis_y"])
    assert abs(res.history["force"][0] / ref["force"] - 1) < (dx / b) ** 2
    assert abs(P.max() / ref["max_pressure"] - 1) < (dx / b) ** 2
    assert abs(ax - ref["semi_axis_x"]) < dx and abs(ay - ref["semi_axis_y"]) < dx
    ratio = ref["semi_axis_y"] / ref["semi_axis_x"]
    assert abs(ay / ax - ratio) < ratio * (dx / ax + dx / ay)
    # depth control at the given depth (the approach is the case's own)
    assert res.history["depth"][0] == case.loading.depth


def test_elliptical_hertz_reduces_to_hertz():
    # R1 = R2: the sphere's Hertz solution (independent closed form)
    c = reference.hertz_elliptical(1e11, 0.01, 0.01 * (1 + 1e-6), depth=1e-6)
    h = reference.hertz(1e11, 0.01, depth=1e-6)
    assert c["force"] == pytest.approx(h["force"], rel=1e-5)
    assert c["semi_axis_x"] == pytest.approx(h["contact_radius"], rel=1e-5)
    # and Johnson's approximation b/a ≈ (R_small/R_large)^(2/3) within 1 %
    e = reference.hertz_elliptical(1e11, 0.01, 0.03, depth=1e-6)
    assert e["semi_axis_x"] / e["semi_axis_y"] == pytest.approx((1 / 3) ** (2 / 3), rel=0.01)


def test_flattened_sphere():
    # truncated.toml (paper Eq. 17) at 64²: force and contact radius against
    # paper Eqs. 18-19 (closed form), the same bounds as the Hertz case
    case, res, sc = static("truncated", 64)
    dx = res.info["pixel"] / sc["a0"]
    assert abs(res.history["force"][0] / sc["F0"] - 1) < dx**2
    assert abs(res.history["contact_radius"][0] / sc["a0"] - 1) < dx


def _paraboloid_grid(n, box=3.0, R=0.01, d=1e-6, E=1e11):
    a0 = math.sqrt(R * d)
    dx = box * a0 / n
    x = (np.arange(n) - n // 2) * dx
    X, Y = np.meshgrid(x, x, indexing="ij")
    return X, Y, HalfSpace(n, dx, E), a0


def test_static_solve_matches_tamaas_on_a_worn_profile():
    import tamaas as tm  # in the test extra: a missing one fails, never skips
    tm.set_log_level(tm.LogLevel.error)
    # a worn paraboloid: flattened by wear to max(f, 0.3 d) plus a ripple
    n, R, d, E = 64, 0.01, 1e-6, 1e11
    X, Y, op, a0 = _paraboloid_grid(n, R=R, d=d, E=E)
    f = np.maximum((X**2 + Y**2) / (2 * R), 0.3 * d) \
        + 0.05 * d * np.cos(7 * X / a0) * np.exp(-(X**2 + Y**2) / a0**2)
    F = 10.0
    L = n * op.spacing
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [L, L], [n, n])
    model.E, model.nu = E, 0.0          # E* = E/(1 - ν²) = E
    tm.ModelFactory.registerNonPeriodic(model, "dcfft")
    # Tamaas's surface is the rigid body's height (contact where it is highest)
    solver = tm.PolonskyKeerRey(model, np.ascontiguousarray(-f), 1e-12,
                                tm.PolonskyKeerRey.pressure, tm.PolonskyKeerRey.pressure)
    solver.setIntegralOperator("dcfft")
    solver.solve(F / L**2)
    p_tm = np.array(model.traction).reshape(n, n)
    c = contact.solve(op, f, force=F, p_scale=1e9, g_scale=d, tol=1e-10)
    # both solve the same discrete problem to 1e-10-1e-12: the pressures agree
    # to 1e-7 of the peak (measured 6e-10)
    assert np.max(np.abs(c.pressure - p_tm)) < 1e-7 * np.max(p_tm)
    assert np.array_equal(c.pressure > 1e-8 * p_tm.max(), p_tm > 1e-8 * p_tm.max())


def test_not_converging_is_a_solver_error():
    X, Y, op, a0 = _paraboloid_grid(32)
    with pytest.raises(SolverError, match="did not converge"):
        contact.solve(op, (X**2 + Y**2) / 0.02, depth=1e-6, p_scale=1e9, g_scale=1e-6,
                      tol=1e-12, maxiter=2)


def test_contact_reaching_the_box_edge_is_refused():
    # depth 4 d in a box sized for d: the contact (2 a0) covers the box (1.5 a0)
    X, Y, op, a0 = _paraboloid_grid(32)
    f0 = (X**2 + Y**2) / 0.02
    model = wear.Model(op=op, f0=f0, wear_rate=1e-14, depth=4e-6, force=None, p_scale=1e9,
                       g_scale=1e-6)
    with pytest.raises(SolverError, match="edge of the BEM box"):
        wear.contact_state(model, f0)


def test_bad_settings_are_case_errors():
    with pytest.raises(CaseError, match="bem.grid"):
        bem.solve(cases.load(cases.shipped("hertz"), ["bem.grid=8"]))
    with pytest.raises(CaseError, match="bem.box"):
        cases.load(cases.shipped("hertz"), ["bem.box=2.0"])
    with pytest.raises(CaseError, match="bem.tolerance"):
        cases.load(cases.shipped("hertz"), ["bem.tolerance=0"])


def _worn(n):
    """A worn paraboloid with a ripple (as the Tamaas test) on n² pixels."""
    X, Y, op, a0 = _paraboloid_grid(n)
    d = 1e-6
    f = np.maximum((X**2 + Y**2) / 0.02, 0.3 * d) \
        + 0.05 * d * np.cos(7 * X / a0) * np.exp(-(X**2 + Y**2) / a0**2)
    return X, Y, op, f, d


def test_single_precision_operator():
    # G t with float32 transforms against float64: within 1e-6 of max |G t|
    # (measured 3-4e-7, the bound contact.SINGLE_ERROR = 2e-6 takes 5x that),
    # and really single precision (above 1e-9)
    rng = np.random.default_rng(1)
    X, Y, op, f, d = _worn(64)
    for t in (rng.standard_normal((64, 64)), np.sqrt(np.maximum(1 - (X**2 + Y**2) / 1e-8, 0))):
        exact = op(t)
        err = np.max(np.abs(op.single(t) - exact)) / np.max(np.abs(exact))
        assert 1e-9 < err < 1e-6
        assert err < contact.SINGLE_ERROR


@pytest.mark.parametrize("control", ["depth", "force"])
@pytest.mark.parametrize("tol", [1e-6, 2e-7, 1e-9])
def test_single_precision_directions_keep_the_tolerance(control, tol):
    # The solve with single-precision search directions ends only where the
    # residual recomputed from scratch in double precision is below tol: at
    # 1e-6 (the default bem.tolerance) and 2e-7 by its error bound (going on
    # in double where the bound is too large or the residual stalls); below
    # contact.SINGLE_MIN_TOL (1e-9) in double only. Its pressure is the
    # double-precision solve's to 50·tol of the peak (two solutions of
    # residual < tol; measured 4.5e-8 and 4.8e-8 of the peak at 1e-6 and
    # 2e-7). The returned displacement is G p within its stated error bound.
    X, Y, op, f, d = _worn(64)
    load = dict(depth=0.8 * d) if control == "depth" else dict(force=10.0)
    kw = dict(p_scale=1e9, g_scale=d, tol=tol, **load)
    fast = contact.solve(op, f, **kw)
    slow = contact.solve(op, f, single=False, **kw)
    assert (op.single_applications > 0) == (tol >= contact.SINGLE_MIN_TOL)
    gap = f - fast.depth + op(fast.pressure)
    assert contact.complementarity_residual(fast.pressure, gap, 1e9, d) < tol
    assert np.max(np.abs(fast.pressure - slow.pressure)) < 50 * tol * slow.pressure.max()
    true = op(fast.pressure)
    assert np.max(np.abs(fast.displacement - true)) <= fast.displacement_error \
        + 1e-12 * np.max(true)


def test_a_known_displacement_replaces_the_first_convolution():
    # A second solve on a slightly worn profile, started from the first's
    # pressure with its displacement: no double-precision convolution at all
    # (the first's displacement is carried with its error bound), the same
    # solution as a start without it (to 50·tol of the peak)
    X, Y, op, f, d = _worn(64)
    kw = dict(depth=0.8 * d, p_scale=1e9, g_scale=d, tol=1e-6)
    first = contact.solve(op, f, **kw)
    worn = f + 1e-3 * d * np.exp(-(X**2 + Y**2) / (0.5 * np.max(X))**2)
    before = op.applications
    again = contact.solve(op, worn, p_init=first.pressure, displacement=first.displacement,
                          displacement_error=first.displacement_error, **kw)
    assert op.applications == before
    plain = contact.solve(op, worn, p_init=first.pressure, window=False, **kw)
    assert op.applications == before + 1
    assert np.max(np.abs(again.pressure - plain.pressure)) < 50 * 1e-6 * plain.pressure.max()
    gap = worn - again.depth + op(again.pressure)
    assert contact.complementarity_residual(again.pressure, gap, 1e9, d) < 1e-6


def test_a_contact_that_outgrows_its_window_is_enlarged(monkeypatch):
    # Force control started from the pressure of a contact of half the
    # radius (an eighth of the force): the first window (that pressure's
    # pixels and a margin) cannot hold the new contact, pixels outside it
    # overlap, and the window is enlarged until none does. The result must
    # be the whole box's solve to 50·tol of the peak pressure (both meet the
    # complementarity tolerance 1e-6; as the warm-start test above), and its
    # complementarity residual on the whole box, with a fresh convolution,
    # below the tolerance.
    X, Y, op, a0 = _paraboloid_grid(96, box=8.0)
    R, E = 0.01, 1e11
    h = (X**2 + Y**2) / (2 * R)
    d0 = a0**2 / R
    W = 4.0 / 3.0 * E * math.sqrt(R) * d0**1.5
    kw = dict(p_scale=1e9, g_scale=d0, tol=1e-6)
    small = contact.solve(op, h, force=W / 8, **kw)
    windows = []
    window_of = contact.contact_window
    monkeypatch.setattr(contact, "contact_window",
                        lambda *a: windows.append(window_of(*a)) or windows[-1])
    grown = contact.solve(op, h, force=W, p_init=small.pressure,
                          displacement=small.displacement,
                          displacement_error=small.displacement_error, **kw)
    first = np.zeros(h.shape, dtype=bool)
    first[windows[0]] = True
    assert len(windows) >= 2 and windows[-1] is not None
    assert np.any(grown.pressure[~first] > 0)        # the enlargement was needed
    box = contact.solve(op, h, force=W, p_init=small.pressure, window=False, **kw)
    assert np.max(np.abs(grown.pressure - box.pressure)) < 50 * 1e-6 * box.pressure.max()
    gap = h - grown.depth + op(grown.pressure)
    assert contact.complementarity_residual(grown.pressure, gap, 1e9, d0) < 1e-6
    assert abs(grown.force - W) < 1e-9 * W


def test_the_window_solve_equals_the_box_solve_under_depth_control():
    # A depth-controlled solve on the worn profile with a contact small
    # against the box: the window (pixels with h < d and a margin) holds
    # every pixel that can touch, so the window's solve is the box's to
    # 50·tol of the peak (both meet tol = 1e-6), in fewer operator work:
    # its convolutions are on the window
    X, Y, op, a0 = _paraboloid_grid(96, box=8.0)
    d = 1e-6
    f = (X**2 + Y**2) / 0.02 + 0.05 * d * np.cos(7 * X / a0) * np.exp(-(X**2 + Y**2) / a0**2)
    kw = dict(depth=d, p_scale=1e9, g_scale=d, tol=1e-6)
    win = contact.solve(op, f, **kw)
    box = contact.solve(op, f, window=False, **kw)
    assert contact.contact_window(f < d, contact.WINDOW_MARGIN) is not None
    assert np.max(np.abs(win.pressure - box.pressure)) < 50 * 1e-6 * box.pressure.max()
    gap = f - d + op(win.pressure)
    assert contact.complementarity_residual(win.pressure, gap, 1e9, d) < 1e-6


def test_window_only_fields_equal_the_box_solve():
    # Depth control, the contact small against the box: with whole_box=False
    # the gap and displacement are the window's and NaN outside it, where no
    # pixel can touch (h >= d there: the window holds every pixel with h < d).
    # Pressure and approach must be the whole box's solve to 50·tol of the
    # peak (both meet tol = 1e-6), the kept displacement G p within its error
    # bound of a fresh double-precision convolution, and the gap outside,
    # completed as h - d + G p, non-negative. A second solve started from the
    # window-only displacement (its window is the same) must need no
    # convolution in double precision, as with a whole-box one.
    X, Y, op, a0 = _paraboloid_grid(96, box=8.0)
    d = 1e-6
    f = (X**2 + Y**2) / 0.02 + 0.05 * d * np.cos(7 * X / a0) * np.exp(-(X**2 + Y**2) / a0**2)
    kw = dict(depth=d, p_scale=1e9, g_scale=d, tol=1e-6)
    win = contact.solve(op, f, whole_box=False, **kw)
    box = contact.solve(op, f, window=False, **kw)
    known = np.isfinite(win.displacement)
    assert np.array_equal(known, np.isfinite(win.gap))
    assert 0 < np.count_nonzero(known) < known.size
    assert np.all(f[~known] >= d) and np.all(win.pressure[~known] == 0.0)
    assert np.max(np.abs(win.pressure - box.pressure)) < 50 * 1e-6 * box.pressure.max()
    true = op(win.pressure)
    assert np.max(np.abs(win.displacement - true)[known]) <= win.displacement_error \
        + 1e-12 * np.max(true)
    gap = f - d + true
    assert np.max(np.abs(win.gap - gap)[known]) < 1e-6 * d
    assert np.min(gap[~known]) >= 0.0
    assert contact.complementarity_residual(win.pressure, gap, 1e9, d) < 1e-6
    worn = f + 1e-3 * d * np.exp(-(X**2 + Y**2) / (0.5 * a0)**2)
    before = op.applications
    again = contact.solve(op, worn, p_init=win.pressure, displacement=win.displacement,
                          displacement_error=win.displacement_error, whole_box=False, **kw)
    assert op.applications == before
    gap = worn - d + op(again.pressure)
    assert contact.complementarity_residual(again.pressure, gap, 1e9, d) < 1e-6


def test_a_window_only_displacement_is_convolved_where_unknown():
    # A displacement known on a smaller window than the next solve's (NaN on
    # the rest): the solve must convolve rather than use it, and still meet
    # the tolerance on the whole box (a fresh convolution)
    X, Y, op, a0 = _paraboloid_grid(96, box=8.0)
    d = 1e-6
    f = (X**2 + Y**2) / 0.02
    kw = dict(p_scale=1e9, g_scale=d, tol=1e-6)
    small = contact.solve(op, f, depth=0.5 * d, whole_box=False, **kw)
    assert np.any(np.isnan(small.displacement))
    before = op.applications
    grown = contact.solve(op, f, depth=d, p_init=small.pressure,
                          displacement=small.displacement,
                          displacement_error=small.displacement_error, whole_box=False, **kw)
    assert op.applications > before
    gap = f - d + op(grown.pressure)
    assert contact.complementarity_residual(grown.pressure, gap, 1e9, d) < 1e-6


def test_force_control_fields_are_window_only_where_nothing_can_touch():
    # Force control: after the window's solve, pixels outside it with h < d
    # at the solved approach could touch; only when there are none may the
    # fields stay the window's (NaN outside). Started from an eighth of the
    # force (the window too small: the solve enlarges it) and from the
    # solution itself: wherever the fields are NaN, h >= d, and the pressure
    # is the whole box's solve to 50·tol of the peak (both meet 1e-6)
    X, Y, op, a0 = _paraboloid_grid(96, box=8.0)
    R, E = 0.01, 1e11
    h = (X**2 + Y**2) / (2 * R)
    d0 = a0**2 / R
    W = 4.0 / 3.0 * E * math.sqrt(R) * d0**1.5
    kw = dict(p_scale=1e9, g_scale=d0, tol=1e-6)
    box = contact.solve(op, h, force=W, window=False, **kw)
    for start in (contact.solve(op, h, force=W / 8, **kw), box):
        win = contact.solve(op, h, force=W, p_init=start.pressure,
                            displacement=start.displacement,
                            displacement_error=start.displacement_error, whole_box=False, **kw)
        unknown = np.isnan(win.gap)
        assert np.array_equal(unknown, np.isnan(win.displacement))
        assert np.all(h[unknown] >= win.depth)
        assert np.max(np.abs(win.pressure - box.pressure)) < 50 * 1e-6 * box.pressure.max()
        gap = h - win.depth + op(win.pressure)
        assert contact.complementarity_residual(win.pressure, gap, 1e9, d0) < 1e-6


def test_a_recomputed_displacement_restarts_the_directions():
    # A start whose displacement is off by 3e-5 d (stated as its error
    # bound): the solve meets the tolerance on the tracked displacement,
    # finds the bound too large, recomputes it in double precision and goes
    # on. The conjugate directions must restart there: continued across the
    # jump of the gap, a captured wear-step solve took 855 iterations
    # instead of 7 (here 148 against 9). Bound: 40 iterations (a cold start
    # here takes 13), and the residual on a fresh convolution below the
    # tolerance.
    X, Y, op, f, d = _worn(64)
    kw = dict(depth=0.8 * d, p_scale=1e9, g_scale=d, tol=1e-6)
    first = contact.solve(op, f, window=False, **kw)
    worn = f + 1e-3 * d * np.exp(-(X**2 + Y**2) / (0.5 * np.max(X))**2)
    error = 3e-5 * d * np.cos(3 * X / np.max(X)) * np.cos(2 * Y / np.max(X))
    c = contact.solve(op, worn, p_init=first.pressure, window=False,
                      displacement=op(first.pressure) + error,
                      displacement_error=3e-5 * d, **kw)
    assert c.iterations < 40
    gap = worn - c.depth + op(c.pressure)
    assert contact.complementarity_residual(c.pressure, gap, 1e9, d) < 1e-6
