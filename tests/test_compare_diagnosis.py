"""What ``wearcheck compare`` says to change when it fails: the rule on constructed
measures, then on real solvers made coarse in one setting at a time (the setting
named must be the one that was made coarse)."""

import math

import numpy as np
import pytest

import wearcheck
from wearcheck import registry
from wearcheck.comparisons.analysis import diagnosis
from wearcheck.studies import compare as compare_mod


def _failure(s_hat, check="force", scale=0.02, tolerance=0.03):
    unit = {"force": "F0", "pressure_interior_max": "p0"}.get(check, "d")
    return dict(check=check, stage=3, s_hat=s_hat, value=0.1, tolerance=tolerance,
                used=0.1 / tolerance, scale=scale, scale_from="stage", unit=unit,
                unworn=0.1 * scale)


def _runs(points=(400.0, 30.0), errors=(None, None)):
    return [diagnosis.Resolution("mdr", "MDR", "mdr.elements", 800, points[0], errors[0]),
            diagnosis.Resolution("bem", "BEM", "bem.grid", 128, points[1], errors[1])]


def test_points_across_a_uniform_and_an_r_squared_grid():
    # uniform spacing 0.01: a contact radius of 1 spans 100 spacings
    assert diagnosis.points_across(np.linspace(0.0, 2.0, 201), 1.0) == pytest.approx(100.0)
    # uniform in r² with step q: the local spacing at r = a is q/(2a), so a/h = 2a²/q
    # (midpoint interpolation of the spacing: error O(q/a²) relative, < 1e-3 here)
    q = 4.0 / 4000
    r = np.sqrt(np.arange(4001) * q)
    assert diagnosis.points_across(r, 1.0) == pytest.approx(2.0 / q, rel=1e-3)
    assert math.isnan(diagnosis.points_across(r[:1], 1.0))


def test_the_grid_with_fewest_points_across_is_named():
    advice = diagnosis.advise(_failure(5.0), _runs(), scheme="adaptive", tolerance=1e-4,
                              step_hat="auto")
    assert (advice["setting"], advice["value"], advice["suggestion"]) == ("bem.grid", 128, 256)
    assert "BEM has 30.0 points across the contact radius" in advice["reason"]
    text = diagnosis.sentence(advice)
    assert text.startswith("raise bem.grid (now 128; try 256): BEM has 30.0 points")


def test_the_time_steps_are_named_when_their_own_estimate_uses_half_the_tolerance():
    # force estimate 4e-4 F0 at a stage whose force is 0.02 F0: 2 % of the stage's
    # force, 2/3 of the 3 % tolerance (>= 1/2): the time steps, not the BEM's 30 points
    runs = _runs(errors=(1e-4, 4e-4))
    advice = diagnosis.advise(_failure(5.0), runs, scheme="adaptive", tolerance=1e-4,
                              step_hat="auto")
    assert advice["setting"] == "sliding.tolerance" and advice["value"] == 1e-4
    assert advice["suggestion"] == pytest.approx(1e-5)
    assert advice["measures"]["bem"]["time_share"] == pytest.approx(2 / 3)
    assert "bem.grid (now 128)" in advice["otherwise"]
    # a third of the tolerance: the grid again, the time steps as the runner-up
    runs = _runs(errors=(1e-4, 2e-4))
    advice = diagnosis.advise(_failure(5.0), runs, scheme="adaptive", tolerance=1e-4,
                              step_hat="auto")
    assert advice["setting"] == "bem.grid"
    assert advice["otherwise"].startswith("sliding.tolerance (now 0.0001)")
    # at ŝ = 0 nothing has slid: never the time steps, whatever the estimate
    advice = diagnosis.advise(_failure(0.0), _runs(errors=(1.0, 1.0)), scheme="adaptive",
                              tolerance=1e-4, step_hat="auto")
    assert advice["setting"] == "bem.grid" and advice["otherwise"] is None


def test_fixed_steps_are_the_runner_up_and_an_approximation_is_named():
    advice = diagnosis.advise(_failure(5.0), _runs(), scheme="implicit", tolerance=1e-4,
                              step_hat=0.1)
    assert advice["setting"] == "bem.grid"
    assert advice["otherwise"].startswith("sliding.step_hat (now 0.1)")
    runs = [diagnosis.Resolution("mdr", "MDR", "mdr.elements", 800, 400.0,
                                 approximate="the equivalent sphere"), _runs()[1]]
    advice = diagnosis.advise(_failure(5.0), runs, scheme="adaptive", tolerance=1e-4,
                              step_hat="auto")
    assert advice["setting"] is None and "MDR solved an approximation" in advice["reason"]
    assert diagnosis.sentence(advice).startswith("no setting to name: ")


# -- real solvers, one setting made coarse at a time (mdr.elements: in
# test_compare.py, test_real_solvers_made_to_disagree_fail_with_exit_code_1) --------

# the paper case to ŝ = 1 (three stages), every solver fine except the one made coarse
SMALL = {"stages.s_hat": [0.0, 0.5, 1.0], "sliding.until": "distance",
         "sliding.distance": 0.03, "mdr.elements": 200, "fem.contact_nodes": 60,
         "bem.grid": 64}


@pytest.fixture(scope="module")
def small_mdr():
    return registry.get("mdr").solve(wearcheck.load_case("paper", SMALL))


@pytest.mark.parametrize("solver, key, value", [("fem", "fem.contact_nodes", 8),
                                                ("bem", "bem.grid", 16)])
def test_a_coarse_solver_fails_and_its_resolution_key_is_named(small_mdr, solver, key, value):
    # FEM with 8 contact nodes over 1.77 a0: ~5 across the contact radius (MDR ~180);
    # BEM with 16 pixels over its box of 3.5 a0: ~5 pixels across a0 (the fewest it
    # accepts is 4). Either makes a difference of several % at some stage.
    case = wearcheck.load_case("paper", {**SMALL, key: value})
    result = registry.get(solver).solve(case)
    m = compare_mod.analyse(case, {"mdr": small_mdr, solver: result})
    assert not m["passed"]
    d = m["diagnosis"]
    assert (d["setting"], d["value"], d["solver"]) == (key, value, solver)
    assert d["measures"][solver]["points_across"] < 8 < 100 < d["measures"]["mdr"][
        "points_across"]


def test_coarse_fixed_steps_are_named_and_the_suggested_step_passes():
    # The paper case to F = 0.01 F0 at backward Euler's default fixed steps: the MDR's
    # ŝ-step 0.1, the FEM's 0.02, both grids fine (MDR 200 springs, FEM 120 nodes): the
    # MDR's first-order time error decides the last stage's force. (The adaptive scheme
    # no longer fails at any allowed sliding.tolerance, 0.1 at most: its Richardson-
    # corrected histories agree to 3 % there.)
    base = {"mdr.elements": 200, "fem.contact_nodes": 120, "sliding.scheme": "implicit"}
    case = wearcheck.load_case("paper", base)
    results = {n: registry.get(n).solve(case) for n in ("mdr", "fem")}
    m = compare_mod.analyse(case, results)
    assert not m["passed"]
    d = m["diagnosis"]
    assert (d["setting"], d["value"], d["solver"]) == ("sliding.step_hat", "auto", "mdr")
    assert d["suggestion"] == pytest.approx(0.05)
    assert d["s_hat"] > 0 and d["measures"]["mdr"]["time_share"] >= 0.5
    # following the advice passes: both solvers at ŝ-steps of 0.05
    case = wearcheck.load_case("paper", {**base, "sliding.step_hat": d["suggestion"]})
    results = {n: registry.get(n).solve(case) for n in ("mdr", "fem")}
    assert compare_mod.analyse(case, results)["passed"]


@pytest.mark.parametrize("h", [0.1, 0.05, 0.02])
def test_the_first_order_estimate_bounds_backward_eulers_error(h):
    # y' = -y, y(0) = 1 on [0, 5] by backward Euler: the global error peaks near
    # h/(2e) at t = 1; the estimate Σ h²/2 |y''| ≈ h/2 (1 - e^-5) is an upper one,
    # within 3x (the ratio is e(1 - e^-5) ≈ 2.7 as h -> 0)
    n = round(5.0 / h)
    t = h * np.arange(n + 1)
    y = (1.0 + h) ** -np.arange(n + 1.0)
    actual = np.max(np.abs(y - np.exp(-t)))
    est = diagnosis.first_order_time_error({"force": y}, F0=1.0, d0=1.0)
    assert actual <= est <= 3.0 * actual
